#!/usr/bin/env bash
# Scaling of one frame on one node (docs/benchmarks.md, "Scaling"): for P = 1, 2, 4, 8, 16
# (up to this machine's cores), the same frame rendered by
#   tpict -n 1, tpict -n P,
#   a job on tplan's default plan for P workers, run by P single-thread workers
#     (tpiece --threads 1, P processes mapping the job's scene image: one copy of the
#     geometry in the page cache),
#   the same with --no-scene-image (P processes that each read and build the scene),
#   the same job run by one worker with P tile loops (tpiece --threads P: one copy),
# with wall seconds, CPU seconds, speed-up and efficiency against tpict -n 1, the job's
# T_idle and T_sync (tstat, summed over workers, wall-s per thread), the sum of the
# processes' peak resident sizes (MB, which counts shared pages in every process) and the
# node's peak proportional set size (PSS MB: the largest sum over the workers, sampled
# every 20 ms, of their PSS, which counts a page shared by k processes as 1/k in each).
# Then the tile-plan simulation (bench/tilesim --sweep) for 2 to 256 workers on the tile
# costs of a one-worker run of the same frame (--tile-size 16x16), frame costs scaled to
# 0.1-1000 CPU-s.
#
# At the largest P it also renders the job on `tplan --tiles N` plans for each N of
# TILES_LIST, by one worker with P loops (the default configuration), and ends with the
# figures issue 29 asks for: the default plan against tpict -n P and against the best
# --tiles plan, one worker with P loops against P single-thread workers, and what each
# loop beyond the first adds to the node's memory.
#
# Usage: bash bench/scaling.sh [OUTDIR (default: a temporary directory)]
# Environment: WORKERS="1 2 4 8 16" (cut to the cores), SCENE (files, default the demo),
#   VIEW (default -vf demo/demo.vf), RES="-x 320 -y 240",
#   OPTS="-ab 2 -aa .15 -ad 512 -as 128 -ar 64 -av .02 .02 .02 -ps 1",
#   TILES_LIST="1 4 16 32 64 128 256 512 1024" ("" for none; 1 and 4: where splitting
#   among the loops decides), PMAX_REPEAT=3 (runs at the largest P, and of each --tiles
#   plan; the summary takes the fastest of each),
#   SIM_WORKERS="2,4,8,16,32,64,128,256", SPLIT (tilesim --split of the node sweep, default
#   tpiece's 0.05,0.05,0.05), SYNC (per-tile seconds for the simulation,
#   default tplan's 0.8 ms), STARTUP (seconds added to every simulated worker, default the
#   measured start-up of a worker: a job of one tile minus its tile's CPU),
#   NO_BUILD=1 (use the binaries in BIN, default target/release, as they are: a machine
#   without cargo), NO_SIM=1 (measure only: costs.json and startup.txt go to OUTDIR for
#   `cargo bench --bench tilesim -- OUTDIR/costs.json --sweep --startup S` elsewhere).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
CORES=$(nproc)
WORKERS=${WORKERS:-"1 2 4 8 16"}
SCENE=${SCENE:-"$ROOT/demo/demo.rad"}
VIEW=${VIEW:-"-vf $ROOT/demo/demo.vf"}
RES=${RES:-"-x 320 -y 240"}
OPTS=${OPTS:-"-ab 2 -aa .15 -ad 512 -as 128 -ar 64 -av .02 .02 .02 -ps 1"}
TILES_LIST=${TILES_LIST-"1 4 16 32 64 128 256 512 1024"}
PMAX_REPEAT=${PMAX_REPEAT:-3}
SIM_WORKERS=${SIM_WORKERS:-"2,4,8,16,32,64,128,256"}
SPLIT=${SPLIT:-0.05,0.05,0.05}
if [ -z "${NO_BUILD:-}" ]; then
    (cd "$ROOT" && cargo build --release --quiet --bins)
fi
B=${BIN:-$ROOT/target/release}
for t in tpict tplan tpiece tstat tassemble; do
    [ -x "$B/$t" ] || { echo "bench/scaling.sh: no $B/$t" >&2; exit 1; }
done
export RAYPATH="$ROOT/demo:${RAYPATH:-.}"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
OUT=${1:-$TMP/out}
mkdir -p "$OUT"
# shellcheck disable=SC2206
RARGS=($VIEW $RES $OPTS)
# shellcheck disable=SC2206
SFILES=($SCENE)

# timed NAME cmd...: run cmd, append "wall user sys maxrss_kb" of it to $TMP/NAME.t
timed() {
    local name=$1
    shift
    /usr/bin/time -a -o "$TMP/$name.t" -f "%e %U %S %M" "$@"
}

# sums NAME: "wall(max) cpu(sum) mem_mb(sum)" of the processes timed under NAME
sums() {
    awk '{ if ($1 > w) w = $1; c += $2 + $3; m += $4 } END { printf "%.2f %.2f %.0f\n", w, c, m / 1024 }' "$TMP/$1.t"
}

row() { # label P wall cpu mem idle sync [pss]
    awk -v l="$1" -v p="$2" -v w="$3" -v c="$4" -v m="$5" -v i="$6" -v s="$7" -v q="${8:--}" -v b="$BASE" \
        'BEGIN { printf "%-52s %3d %8.2f %8.2f %7.2f %5.0f%% %7s %7s %7.0f %7s\n", l, p, w, c, b / w, 100 * b / w / p, i, s, m, q }'
}

# descendants PID: the PIDs of every process below PID.
descendants() {
    local kid
    for kid in $(cat "/proc/$1/task/$1/children" 2> /dev/null); do
        echo "$kid"
        descendants "$kid"
    done
}

# pss_watch PARENTS...: until every parent has ended, every 20 ms, the sum of the PSS of
# the tpiece processes below them (the background jobs run /usr/bin/time, which runs
# tpiece); prints the largest sum in MB.
pss_watch() {
    local max=0
    while :; do
        local alive=0 sum=0
        for parent in "$@"; do
            [ -d "/proc/$parent" ] || continue
            alive=1
            for kid in $(descendants "$parent"); do
                [ "$(cat "/proc/$kid/comm" 2> /dev/null)" = tpiece ] || continue
                kb=$(awk '/^Pss:/ { print $2 }' "/proc/$kid/smaps_rollup" 2> /dev/null || echo 0)
                sum=$((sum + ${kb:-0}))
            done
        done
        [ "$alive" = 1 ] || break
        [ "$sum" -gt "$max" ] && max=$sum
        sleep 0.02
    done
    awk -v m="$max" 'BEGIN { printf "%.1f\n", m / 1024 }'
}

job_stats() { # JOB -> "t_idle t_sync"
    "$B/tstat" "$1" --json | python3 -c 'import json,sys; a=json.load(sys.stdin)["aggregate"]; print("%.2f %.3f" % (a["t_idle"], a["t_sync"]))'
}

echo "bench/scaling.sh: $CORES cores; scene ${SFILES[*]}; ${RARGS[*]}"
rm -f "$TMP"/*.t
timed one "$B/tpict" -n 1 "${RARGS[@]}" "${SFILES[@]}" > "$TMP/one.hdr"
read -r BASE BASE_CPU BASE_MEM < <(sums one)
printf '%-52s %3s %8s %8s %7s %6s %7s %7s %7s %7s\n' run P wall-s CPU-s speedup eff T_idle T_sync MB PSS-MB
row "tpict -n 1" 1 "$BASE" "$BASE_CPU" "$BASE_MEM" - -
PMAX=0
for P in $WORKERS; do [ "$P" -le "$CORES" ] && [ "$P" -gt "$PMAX" ] && PMAX=$P; done
for P in $WORKERS; do
    if [ "$P" -gt "$CORES" ]; then
        echo "(P = $P skipped: $CORES cores)"
        continue
    fi
    reps=1
    [ "$P" = "$PMAX" ] && reps=$PMAX_REPEAT
    for _ in $(seq 1 "$reps"); do
        rm -f "$TMP"/*.t
        timed tp "$B/tpict" -n "$P" "${RARGS[@]}" "${SFILES[@]}" > /dev/null
        read -r w c m < <(sums tp)
        row "tpict -n $P" "$P" "$w" "$c" "$m" - -
        w_tp=$w c_tp=$c m_tp=$m
        for mode in processes built threads; do
            job="$TMP/job-$P-$mode"
            rm -rf "$job"
            # One worker of P loops gets the plan made for it (tplan --threads P).
            threads=1
            [ "$mode" = threads ] && threads=$P
            "$B/tplan" --workers "$P" --threads "$threads" -o "$job" -- "${RARGS[@]}" "${SFILES[@]}" 2> "$TMP/plan.err"
            tiles=$(grep -o '[0-9]* tiles,' "$TMP/plan.err" | grep -o '[0-9]*')
            pids=()
            if [ "$mode" != threads ]; then
                flag=()
                [ "$mode" = built ] && flag=(--no-scene-image)
                for i in $(seq 1 "$P"); do
                    timed "$mode" "$B/tpiece" "$job" --worker-id "w$i" --threads 1 -q "${flag[@]}" &
                    pids+=("$!")
                done
            else
                timed "$mode" "$B/tpiece" "$job" --worker-id w1 --threads "$P" -q &
                pids+=("$!")
            fi
            pss=$(pss_watch "${pids[@]}")
            for p in "${pids[@]}"; do wait "$p"; done
            read -r w c m < <(sums "$mode")
            read -r idle sync < <(job_stats "$job")
            case $mode in
                processes) label="$P x tpiece --threads 1" ;;
                built) label="$P x tpiece --threads 1 --no-scene-image" ;;
                *) label="tpiece --threads $P" ;;
            esac
            row "$label ($tiles tiles)" "$P" "$w" "$c" "$m" "$idle" "$sync" "$pss"
            echo "$P $mode $tiles $w $c $m $pss" >> "$TMP/rows"
            "$B/tassemble" "$job" --force -o "$OUT/job-$P-$mode.hdr" 2> /dev/null
            rm -rf "$job"
        done
        echo "$P tpict $w_tp $c_tp $m_tp" >> "$TMP/tpict"
    done
done

# The default configuration (one worker, P loops) on --tiles plans, at the largest P run.
if [ "$PMAX" -gt 0 ]; then
    for n in $(for _ in $(seq 1 "$PMAX_REPEAT"); do echo $TILES_LIST; done); do
        job="$TMP/job-tiles-$n"
        rm -rf "$job"
        "$B/tplan" --workers "$PMAX" --tiles "$n" -o "$job" -- "${RARGS[@]}" "${SFILES[@]}" 2> "$TMP/plan.err"
        tiles=$(grep -o '[0-9]* tiles,' "$TMP/plan.err" | grep -o '[0-9]*')
        rm -f "$TMP"/tiles.t
        timed tiles "$B/tpiece" "$job" --worker-id w1 --threads "$PMAX" -q
        read -r w c m < <(sums tiles)
        read -r idle sync < <(job_stats "$job")
        row "tpiece --threads $PMAX, tplan --tiles $n ($tiles tiles)" "$PMAX" "$w" "$c" "$m" "$idle" "$sync"
        echo "$n $tiles $w" >> "$TMP/tilesrows"
        rm -rf "$job"
    done
    # What issue 29 asks, at P = PMAX.
    echo
    awk -v p="$PMAX" -v base="$BASE" '
        FILENAME ~ /rows$/ && $1 == p && (!($2 in w) || $4 < w[$2]) { w[$2] = $4; t[$2] = $3 }
        FILENAME ~ /tpict$/ && $1 == p && (tp == "" || $3 < tp) { tp = $3 }
        FILENAME ~ /tilesrows$/ && (!($1 in tw) || $3 < tw[$1]) { tw[$1] = $3; tt[$1] = $2 }
        END {
            for (n in tw) if (best == "" || tw[n] < best) { best = tw[n]; bt = tt[n] }
            printf "at P = %d: default plan (%d tiles), one worker with %d loops: %.2f s wall\n", p, t["threads"], p, w["threads"]
            printf "  against tpict -n %d (%.2f s): %.3f (at most 1 asked)\n", p, tp, w["threads"] / tp
            if (best != "") printf "  against the best --tiles plan (%d tiles, %.2f s): %.3f (at most 1.05 asked)\n", bt, best, w["threads"] / best
            printf "  against %d single-thread workers (%.2f s): %.3f (at most 1.05 asked)\n", p, w["processes"], w["threads"] / w["processes"]
        }' "$TMP/rows" "$TMP/tpict" $( [ -f "$TMP/tilesrows" ] && echo "$TMP/tilesrows" )
fi
# Memory per extra loop: one worker with P loops against one with one loop (PSS, MB).
awk '$2 == "threads" && (!($1 in q) || $7 < q[$1]) { q[$1] = $7 } END {
        if (!(1 in q)) exit
        for (p in q) if (p + 0 > 1 && q[1] > 0)
            printf "  one worker, %d loops: PSS %.1f MB, %.1f%% of the first loop'"'"'s per extra loop (at most 10%% asked)\n", p, q[p], 100 * (q[p] - q[1]) / (p - 1) / q[1]
    }' "$TMP/rows" | sort -n -k3

# The tile plan simulation on measured costs.
job="$TMP/costs"
"$B/tplan" --tile-size 16x16 -o "$job" -- "${RARGS[@]}" "${SFILES[@]}" 2> /dev/null
rm -f "$TMP"/*.t
timed costs "$B/tpiece" "$job" --threads 1 -q
"$B/tstat" "$job" --costs 0 > "$OUT/costs.json"
# A worker's start-up: a one-tile job of a 1x1 picture of the same scene.
one="$TMP/startup"
"$B/tplan" --tiles 1 -o "$one" -- "${RARGS[@]/$RES/}" -x 1 -y 1 "${SFILES[@]}" 2> /dev/null || true
STARTUP=${STARTUP:-}
if [ -z "$STARTUP" ] && [ -d "$one" ]; then
    rm -f "$TMP"/*.t
    timed startup "$B/tpiece" "$one" --threads 1 -q
    # The worker's wall time less its tile's (one pixel, which at -ab 2 still makes the
    # ambient values that pixel needs).
    tile_s=$("$B/tstat" "$one" --costs 0 | python3 -c 'import json, sys; print(sum(t["seconds"] for t in json.load(sys.stdin)["tiles"]))')
    STARTUP=$(awk -v t="$tile_s" '{ s = $1 - t; printf "%.3f\n", (s > 0 ? s : 0) }' "$TMP/startup.t")
fi
STARTUP=${STARTUP:-0}
echo "$STARTUP" > "$OUT/startup.txt"
if [ -n "${NO_SIM:-}" ]; then
    echo
    echo "costs: $OUT/costs.json, worker start-up $STARTUP s (NO_SIM: simulate elsewhere with"
    echo "  cargo bench --bench tilesim -- $OUT/costs.json --sweep --startup $STARTUP)"
    exit 0
fi
SYNCARG=()
if [ -n "${SYNC:-}" ]; then SYNCARG=(--sync-cost "$SYNC"); fi
echo
echo "tilesim --sweep on $OUT/costs.json (start-up $STARTUP s)"
(cd "$ROOT" && cargo bench --quiet --bench tilesim -- "$OUT/costs.json" --sweep \
    --workers "$SIM_WORKERS" --startup "$STARTUP" "${SYNCARG[@]}")
# The default configuration: workers of 16 loops (tplan --threads 16), splitting as tpiece
# does, with cells of the frame's -ps.
PS=$(awk '{ for (i = 1; i < NF; i++) if ($i == "-ps") p = $(i + 1) } END { print p ? p : 4 }' <<< "$OPTS")
echo
echo "tilesim --sweep, workers of 16 loops (tplan --threads 16, tpiece's splitting, -ps $PS)"
(cd "$ROOT" && cargo bench --quiet --bench tilesim -- "$OUT/costs.json" --sweep \
    --workers "$SIM_WORKERS" --startup "$STARTUP" "${SYNCARG[@]}" \
    --split "$SPLIT" --loops 16 --ps "$PS")
