#!/usr/bin/env bash
# The seed paper's batch experiments on this machine (docs/benchmarks.md, "Batch toolkit"):
#  1. workers 1, 2, 4, 8, 16 on one job (--amb-flush auto; time-sharing 2 cores): aggregate CPU time and
#     extensive ambient computations vs workers (the seed's Fig. 7/8);
#  2. the N_A sweep (--amb-flush 1, 5, 20, 122, auto) at 16 workers (the seed's Fig. 6);
#  3. the one-worker job's measured tile costs replayed by bench/tilesim for P = 1..256.
# Every job has the same plan (made for 16 workers) and the demo scene at -ab 2.
# Usage: bash bench/batch.sh [OUTDIR (default docs/benchmarks-batch)]
# Environment: WORKERS="1 2 4 8 16", NA_LIST="1 5 20 122 auto", NA_WORKERS=16,
#              RES="-x 320 -y 240", AMB="-ab 2 -ad 512 -as 128 -aa .15 -ar 64", REPEAT=1
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=${1:-$ROOT/docs/benchmarks-batch}
WORKERS=${WORKERS:-"1 2 4 8 16"}
NA_LIST=${NA_LIST:-"1 5 20 122 auto"}
NA_WORKERS=${NA_WORKERS:-16}
RES=${RES:-"-x 320 -y 240"}
AMB=${AMB:-"-ab 2 -ad 512 -as 128 -aa .15 -ar 64"}
REPEAT=${REPEAT:-1}
mkdir -p "$OUT"
(cd "$ROOT" && cargo build --release --quiet --bins)
B=$ROOT/target/release
export RAYPATH=$ROOT/demo
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# run_job NAME WORKERS NA -> appends a row to $OUT/runs.tsv, keeps tstat JSON
run_job() {
    local name=$1 n=$2 na=$3 job="$TMP/$1"
    # shellcheck disable=SC2086
    "$B/tplan" --workers 16 -o "$job" -- -vf "$ROOT/demo/demo.vf" $RES $AMB "$ROOT/demo/demo.rad" 2>/dev/null
    local t0 t1 pids=()
    t0=$(date +%s.%N)
    for i in $(seq 1 "$n"); do
        "$B/tpiece" "$job" --worker-id "w$i" --threads 1 --amb-flush "$na" -q &
        pids+=("$!")
    done
    for p in "${pids[@]}"; do wait "$p"; done
    t1=$(date +%s.%N)
    "$B/tstat" "$job" --json > "$OUT/$name.json"
    python3 - "$OUT/$name.json" "$n" "$na" "$t0" "$t1" "$name" >> "$OUT/runs.tsv" <<'PY'
import json, sys
st = json.load(open(sys.argv[1]))
a = st["aggregate"]
n, na, t0, t1, name = sys.argv[2], sys.argv[3], float(sys.argv[4]), float(sys.argv[5]), sys.argv[6]
print("\t".join(str(x) for x in [name, n, na, round(t1 - t0, 3), round(a["cpu_seconds"], 3),
      a["new_values"], a["shared_in"], round(a["t_spec"], 3), round(a["t_amb"], 3),
      round(a["t_idle"], 3), round(a["t_sync"], 4), a["tiles_done"]]))
PY
    tail -1 "$OUT/runs.tsv" >&2
    if [ "$n" = 1 ] && [ ! -f "$OUT/costs.json" ]; then
        "$B/tstat" "$job" --costs 0 > "$OUT/costs.json"
    fi
    rm -rf "$job"
}

printf 'name\tworkers\tamb_flush\twall_s\tcpu_s\tnew_values\tshared_in\tt_spec\tt_amb\tt_idle\tt_sync\ttiles\n' > "$OUT/runs.tsv"
rm -f "$OUT/costs.json"
for r in $(seq 1 "$REPEAT"); do
    for n in $WORKERS; do run_job "workers-$n-r$r" "$n" auto; done
    for na in $NA_LIST; do run_job "na-$na-r$r" "$NA_WORKERS" "$na"; done
done
(cd "$ROOT" && cargo bench --quiet --bench tilesim -- "$OUT/costs.json" --json "$OUT/tilesim.json") | tee "$OUT/tilesim.txt"
python3 "$ROOT/bench/plot_batch.py" "$OUT"
python3 "$ROOT/bench/plot_tilesim.py" "$OUT/tilesim.json" "$OUT/tilesim.png" || true
echo "results in $OUT"
