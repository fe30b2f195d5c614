#!/usr/bin/env bash
# Sensor grids (docs/benchmarks.md, "Points"): an N-point work-plane grid (tgrid) in the
# tests' daylit room (gensky sky and sun through glass) at -ab 5, -I, traced by
#   rtrace -n 1, rtrace -n 2 (real Radiance, on oconv's octree; oconv's time not counted),
#   ttrace -n 1, ttrace -n 2,
#   a point job (tplan --points) run by one tpiece with 2 tile loops, merged and assembled;
# wall and CPU seconds; then the error of each against its own converged values at equal
# settings, and a sweep of -ad x -aa (equal error: each renderer's front, the CPU ttrace
# needs to reach rtrace's error along it).
# Errors are per-point relative differences to the renderer's own reference (-aa .05
# -ad 2048 -as 1024, one thread), averaged over the points.
#
# Usage: bash bench/points.sh
# Environment: N (points, default 10000), OPTS (default "-ab 5 -ad 512 -as 128 -aa .15"),
#   SWEEP (the -aa values of the sweep, default ".3 .2 .15 .1"), AD_SWEEP (its -ad values,
#   default "256 512 1024"), REPEAT (runs of each sweep
#   point, the smallest CPU kept; default 3),
#   REF_OPTS (default "-ab 5 -ad 2048 -as 1024 -aa .05"), KEEP (a directory that keeps
#   the grid, the references and the sweep table), REF_DIR (a KEEP directory of an earlier
#   run whose references are used again when its grid is the same; the caller keeps
#   their options the same), TT_EXTRA (options for ttrace alone, its reference and the
#   job included: TT_EXTRA="--amb-ss-own off").
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
NAME=points
NO_BUILD=1
# shellcheck source=bench/common.sh
source "$ROOT/bench/common.sh"
(cd "$ROOT" && cargo build --release --quiet --bins)
B=$ROOT/target/release
N=${N:-10000}
OPTS=${OPTS:-"-ab 5 -ad 512 -as 128 -aa .15"}
SWEEP=${SWEEP:-".3 .2 .15 .1"}
AD_SWEEP=${AD_SWEEP:-"256 512 1024"}
REPEAT=${REPEAT:-3}
REF_OPTS=${REF_OPTS:-"-ab 5 -ad 2048 -as 1024 -aa .05"}
TT_EXTRA=${TT_EXTRA:-}
work_dir
cp "$ROOT"/tests/scenes/daylight/*.rad "$TMP/"
cd "$TMP"
export RAYPATH=".:$RAYPATH"
oconv room.rad sky.rad >s.oct
# A 6 x 5 m room: the spacing that gives about N points at 0.8 m.
SP=$(awk -v n="$N" 'BEGIN { printf "%.5f", sqrt(30 / n) }')
"$B/tgrid" --rect 0 0 6 5 --spacing "$SP" --height 0.8 >grid.pts
NP=$(wc -l <grid.pts)
echo "points: $NP (spacing $SP m), options: $OPTS"

# run LABEL OUT CMD...: wall and CPU seconds (children's user + system) of CMD < grid.pts.
run() {
    local label=$1 out=$2
    shift 2
    local t0 t1
    t0=$(date +%s.%N)
    /usr/bin/time -f "%U %S" -o time.txt "$@" <grid.pts >"$out"
    t1=$(date +%s.%N)
    read -r u s <time.txt
    printf '%-34s %8.2f %8.2f\n' "$label" "$(echo "$t1 - $t0" | bc)" "$(echo "$u + $s" | bc)"
}
# shellcheck disable=SC2206
O=($OPTS)
# shellcheck disable=SC2206
R=($REF_OPTS)
# shellcheck disable=SC2206
X=($TT_EXTRA)
printf '%-34s %8s %8s\n' run wall-s CPU-s
run "rtrace -n 1" rt1.out rtrace -h -I "${O[@]}" s.oct
run "rtrace -n 2" rt2.out rtrace -n 2 -h -I "${O[@]}" s.oct
run "ttrace -n 1" tt1.out "$B/ttrace" -n 1 -h -I "${O[@]}" "${X[@]}" room.rad sky.rad
run "ttrace -n 2" tt2.out "$B/ttrace" -n 2 -h -I "${O[@]}" "${X[@]}" room.rad sky.rad
t0=$(date +%s.%N)
/usr/bin/time -f "%U %S" -o time.txt bash -c "
    '$B/tplan' --points grid.pts --workers 2 -o job -- -h -I ${OPTS} ${TT_EXTRA} room.rad sky.rad >/dev/null 2>&1 &&
    '$B/tpiece' job --threads 2 -q && '$B/tmerge' job >/dev/null 2>&1 &&
    '$B/tassemble' job -o job.out"
t1=$(date +%s.%N)
read -r u s <time.txt
printf '%-34s %8.2f %8.2f\n' "job: tpiece --threads 2" "$(echo "$t1 - $t0" | bc)" "$(echo "$u + $s" | bc)"

if [[ -n "${REF_DIR:-}" && -f "$REF_DIR/grid.pts" ]] && cmp -s grid.pts "$REF_DIR/grid.pts"; then
    # References kept by an earlier run (KEEP) of the same grid; their options are the
    # caller's to match.
    echo "references: from $REF_DIR"
    cp "$REF_DIR/rt.ref" "$REF_DIR/tt.ref" .
else
    echo "references ($REF_OPTS, one thread):"
    run "rtrace reference" rt.ref rtrace -h -I "${R[@]}" s.oct
    run "ttrace reference" tt.ref "$B/ttrace" -n 1 -h -I "${R[@]}" "${X[@]}" room.rad sky.rad
fi

# err TEST REF: mean per-point relative difference of the first component (points whose
# reference is below 1e-3 of the largest are left out).
err() {
    paste "$1" "$2" | awk '
        { t[NR] = $1; r[NR] = $4; if ($4 > top) top = $4 }
        END {
            for (i = 1; i <= NR; i++) if (r[i] > 1e-3 * top) { e += (t[i] > r[i] ? t[i] - r[i] : r[i] - t[i]) / r[i]; n++ }
            printf "%.5f", e / n
        }'
}
echo "error against each renderer's own reference, at equal settings:"
echo "  rtrace -n 1 $(err rt1.out rt.ref)   ttrace -n 1 $(err tt1.out tt.ref)   job $(err job.out tt.ref)"
echo "  ttrace against rtrace's reference: $(err tt.ref rt.ref) (the references' difference)"

# least_cpu OUT CMD...: the smallest CPU seconds (user + system) of $REPEAT runs of CMD <
# grid.pts, whose output (the same every run) goes to OUT.
least_cpu() {
    local out=$1 best="" u s c
    shift
    for _ in $(seq "$REPEAT"); do
        /usr/bin/time -f "%U %S" -o t.txt "$@" <grid.pts >"$out"
        read -r u s <t.txt
        c=$(echo "$u + $s" | bc)
        if [ -z "$best" ] || [ "$(echo "$c < $best" | bc)" = 1 ]; then best=$c; fi
    done
    echo "$best"
}

echo "sweep of -ad x -aa (one thread, the smallest CPU of $REPEAT runs): CPU-s and error of each"
printf '%-6s %-6s %10s %10s %10s %10s\n' -ad -aa rtrace-CPU rtrace-err ttrace-CPU ttrace-err | tee sweep.txt
for ad in $AD_SWEEP; do
    for aa in $SWEEP; do
        # shellcheck disable=SC2206
        S=($OPTS -ad "$ad" -aa "$aa")
        c1=$(least_cpu rs.out rtrace -h -I "${S[@]}" s.oct)
        c2=$(least_cpu ts.out "$B/ttrace" -n 1 -h -I "${S[@]}" "${X[@]}" room.rad sky.rad)
        printf '%-6s %-6s %10.2f %10s %10.2f %10s\n' "$ad" "$aa" "$c1" "$(err rs.out rt.ref)" \
            "$c2" "$(err ts.out tt.ref)" | tee -a sweep.txt
    done
done
# Equal error, as bench/ambient.sh does for pictures: each renderer's front (its runs that
# no cheaper run of it beats in error); for each point of rtrace's front, the CPU of
# ttrace's front at that error, interpolated linearly in log CPU and log error between the
# two front points that enclose it; the ratios where the fronts overlap and their median.
echo "at equal error (each renderer's front over the sweep; ttrace's CPU at rtrace's error):"
python3 - sweep.txt "$ROOT/bench" <<'PY'
import sys
sys.path.insert(0, sys.argv[2])
from fronts import pareto, time_at
rows = [l.split() for l in open(sys.argv[1]).read().splitlines()[1:] if l.strip()]
rf = pareto([(float(r[2]), float(r[3]), r[0], r[1]) for r in rows])
tf = pareto([(float(r[4]), float(r[5]), r[0], r[1]) for r in rows])
print("  rtrace's front: " + ", ".join(f"-ad {a} -aa {b} {100*e:.2f}% {c:.2f} s" for c, e, a, b in rf))
print("  ttrace's front: " + ", ".join(f"-ad {a} -aa {b} {100*e:.2f}% {c:.2f} s" for c, e, a, b in tf))
ratios = []
for c, e, ad, aa in rf:
    # ttrace's cheapest run already as accurate: its CPU is a bound.
    bound = e >= tf[0][1]
    t = tf[0][0] if bound else time_at(tf, e)
    if t is None:
        print(f"  rtrace -ad {ad} -aa {aa} ({100*e:.2f}%, {c:.2f} s): below ttrace's front")
        continue
    print(f"  rtrace -ad {ad} -aa {aa} ({100*e:.2f}%, {c:.2f} s): ttrace {'at most ' if bound else ''}{t:.2f} s, {c/t:.2f}x")
    if not bound:
        ratios.append(c / t)
if ratios:
    ratios.sort()
    m = len(ratios)
    med = ratios[m // 2] if m % 2 else (ratios[m // 2 - 1] + ratios[m // 2]) / 2
    print(f"  overlap: {m} point(s), median {med:.2f}x, min {ratios[0]:.2f}x, max {ratios[-1]:.2f}x")
else:
    print("  the fronts do not overlap")
PY
# KEEP=DIR keeps the grid, the references and the sweep's table.
if [[ -n "${KEEP:-}" ]]; then
    mkdir -p "$KEEP"
    cp grid.pts rt.ref tt.ref sweep.txt "$KEEP/"
fi
