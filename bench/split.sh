#!/usr/bin/env bash
# Splitting a tile in progress, measured: two single-thread workers render the office of
# bench/device.sh (512x355, `-ab 2 -aa .15 -ad 512 -as 128 -ar 64 -dt .07 -ps 1`) on plans
# of 1 and 3 tiles, with splitting and with `tplan --no-split`; per run the wall seconds,
# the pieces made, ΣT_idle and Σ CPU (tstat). docs/benchmarks.md, "Scaling and the default
# plan".
#   bash bench/split.sh [SCENEDIR]     # SCENEDIR from `bench/device.sh --prepare`; else
#                                      # one is prepared in a temporary directory
# Environment: REPEAT (default 2), RES (default "-x 512 -y 512"), PLANS (default
# "1 3"), NO_BUILD=1 and BIN (binaries, default target/release).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
[ -n "${NO_BUILD:-}" ] || (cd "$ROOT" && cargo build --release --bins -q)
BIN=$(cd "${BIN:-$ROOT/target/release}" && pwd)
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
if [ -n "${1:-}" ]; then
    dir=$(cd "$1" && pwd)
else
    dir="$TMP/scene"
    bash "$ROOT/bench/device.sh" --prepare "$dir" >/dev/null
fi
cd "$dir"
export RAYPATH="$dir:${RAYPATH:-.}"
OPTS="-ab 2 -aa .15 -ad 512 -as 128 -ar 64 -dt .07 -ps 1"
echo "bench/split.sh: two workers, office $(echo ${RES:--x 512 -y 512}) $OPTS"
for rep in $(seq "${REPEAT:-2}"); do
    for tiles in ${PLANS:-1 3}; do
        for split in "" --no-split; do
            job="$TMP/job"
            rm -rf "$job"
            # shellcheck disable=SC2086
            "$BIN/tplan" --tiles "$tiles" --workers 2 $split -o "$job" -- \
                $(cat office.view) ${RES:--x 512 -y 512} $OPTS office.rad >/dev/null 2>&1 ||
                { echo "bench/split.sh: tplan failed" >&2; exit 1; }
            s=$(date +%s.%N)
            "$BIN/tpiece" "$job" --worker-id a --threads 1 -q &
            "$BIN/tpiece" "$job" --worker-id b --threads 1 -q
            wait
            e=$(date +%s.%N)
            "$BIN/tstat" "$job" --json | python3 -c '
import json, sys
d = json.load(sys.stdin); a = d["aggregate"]
print("--tiles %s %-11s %2d tiles %2d pieces  wall %6.2f s  idle %5.2f s  CPU %6.2f s" % (
    sys.argv[1], sys.argv[2], d["tiles"], d["pieces"], float(sys.argv[3]),
    a["t_idle"], a["cpu_seconds"]))' "$tiles" "${split:-(split)}" "$(echo "$e - $s" | bc)"
        done
    done
done
