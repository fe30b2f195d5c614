#!/usr/bin/env bash
# The seed paper's batch experiments on this machine (docs/benchmarks.md, "Batch toolkit"):
#  1. workers 1, 2, 4, 8, 16 on one job (--amb-flush auto; time-sharing 2 cores): aggregate CPU time and
#     extensive ambient computations vs workers (the seed's Fig. 7/8);
#  2. the N_A sweep (--amb-flush 1, 5, 20, 122, auto) at 16 workers (the seed's Fig. 6);
#  3. measured tile costs replayed by bench/tilesim for P = 1..256, from three jobs:
#     16 workers sharing a cold cache (costs-16w.json: each tile's CPU time as it happened
#     with 16 workers), one worker with a cold cache (costs-1w-cold.json: the first tiles
#     also pay the cache warm-up of the whole picture), one worker whose job was seeded
#     with the 16-worker job's merged store (costs-1w-warm.json: steady state).
# Every job has the same plan (made for 16 workers) and the demo scene at -ab 2.
# Usage: bash bench/batch.sh [OUTDIR (default docs/benchmarks/batch)]
# Environment: WORKERS="1 2 4 8 16", NA_LIST="1 5 20 122 auto", NA_WORKERS=16,
#              RES="-x 320 -y 240", AMB="-ab 2 -ad 512 -as 128 -aa .15 -ar 64", REPEAT=1,
#              COSTS_RES="-x 640 -y 480" (the cost jobs), COSTS=0 skips them, TILES=1280
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=${1:-$ROOT/docs/benchmarks/batch}
WORKERS=${WORKERS:-"1 2 4 8 16"}
NA_LIST=${NA_LIST:-"1 5 20 122 auto"}
NA_WORKERS=${NA_WORKERS:-16}
RES=${RES:-"-x 320 -y 240"}
AMB=${AMB:-"-ab 2 -ad 512 -as 128 -aa .15 -ar 64"}
REPEAT=${REPEAT:-1}
COSTS_RES=${COSTS_RES:-"-x 640 -y 480"}
# 80 tiles per worker for 16 workers: tplan's default estimates this scene's pixels far
# cheaper than they are at these settings (docs/batch.md, "The tile plan").
TILES=${TILES:-1280}
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
    "$B/tplan" --workers 16 --tiles "$TILES" -o "$job" -- -vf "$ROOT/demo/demo.vf" $RES $AMB "$ROOT/demo/demo.rad" 2>/dev/null
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
    rm -rf "$job"
}

# costs_job NAME WORKERS [STORE] -> $OUT/costs-NAME.json (and the job's merged store)
costs_job() {
    local name=$1 n=$2 store=${3:-} job="$TMP/costs-$1" seed=()
    [ -n "$store" ] && seed=(--ambient "$store")
    # shellcheck disable=SC2086
    "$B/tplan" --workers 16 --tiles "$TILES" "${seed[@]}" -o "$job" -- -vf "$ROOT/demo/demo.vf" $COSTS_RES $AMB "$ROOT/demo/demo.rad" 2>/dev/null
    local pids=()
    for i in $(seq 1 "$n"); do
        "$B/tpiece" "$job" --worker-id "c$i" --threads 1 -q &
        pids+=("$!")
    done
    for p in "${pids[@]}"; do wait "$p"; done
    "$B/tmerge" "$job" 2>/dev/null
    "$B/tstat" "$job" --costs 0 > "$OUT/costs-$name.json"
    cp "$job/merged/$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["store"])' "$job/merged/store.json")" "$TMP/store-$name.log"
}

if [ -n "$WORKERS$NA_LIST" ]; then
    printf 'name\tworkers\tamb_flush\twall_s\tcpu_s\tnew_values\tshared_in\tt_spec\tt_amb\tt_idle\tt_sync\ttiles\n' > "$OUT/runs.tsv"
    for r in $(seq 1 "$REPEAT"); do
        for n in $WORKERS; do run_job "workers-$n-r$r" "$n" auto; done
        for na in $NA_LIST; do run_job "na-$na-r$r" "$NA_WORKERS" "$na"; done
    done
    python3 "$ROOT/bench/plot_batch.py" "$OUT"
fi
if [ "${COSTS:-1}" = 1 ]; then
    costs_job 16w 16
    costs_job 1w-cold 1
    costs_job 1w-warm 1 "$TMP/store-16w.log"
    for c in 16w 1w-cold 1w-warm; do
        (cd "$ROOT" && cargo bench --quiet --bench tilesim -- "$OUT/costs-$c.json" --tiles-per-worker 80 --json "$OUT/tilesim-$c.json") | tee "$OUT/tilesim-$c.txt"
        python3 "$ROOT/bench/plot_tilesim.py" "$OUT/tilesim-$c.json" "$OUT/tilesim-$c.png" || true
    done
fi
echo "results in $OUT"
