#!/usr/bin/env bash
# Sensor grids (docs/benchmarks.md, "Points"): an N-point work-plane grid (tgrid) in the
# tests' daylit room (gensky sky and sun through glass) at -ab 5, -I, traced by
#   rtrace -n 1, rtrace -n 2 (real Radiance, on oconv's octree; oconv's time not counted),
#   ttrace -n 1, ttrace -n 2,
#   a point job (tplan --points) run by one tpiece with 2 tile loops, merged and assembled;
# wall and CPU seconds; then the error of each against its own converged values at equal
# settings, and a sweep of -aa (equal error: the CPU each needs to reach the other's error).
# Errors are per-point relative differences to the renderer's own reference (-aa .05
# -ad 2048 -as 1024, one thread), averaged over the points.
#
# Usage: bash bench/points.sh
# Environment: N (points, default 10000), OPTS (default "-ab 5 -ad 512 -as 128 -aa .15"),
#   SWEEP (the -aa values of the sweep, default ".3 .2 .15 .1"),
#   REF_OPTS (default "-ab 5 -ad 2048 -as 1024 -aa .05").
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
REF_OPTS=${REF_OPTS:-"-ab 5 -ad 2048 -as 1024 -aa .05"}
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
printf '%-34s %8s %8s\n' run wall-s CPU-s
run "rtrace -n 1" rt1.out rtrace -h -I "${O[@]}" s.oct
run "rtrace -n 2" rt2.out rtrace -n 2 -h -I "${O[@]}" s.oct
run "ttrace -n 1" tt1.out "$B/ttrace" -n 1 -h -I "${O[@]}" room.rad sky.rad
run "ttrace -n 2" tt2.out "$B/ttrace" -n 2 -h -I "${O[@]}" room.rad sky.rad
t0=$(date +%s.%N)
/usr/bin/time -f "%U %S" -o time.txt bash -c "
    '$B/tplan' --points grid.pts --workers 2 -o job -- -h -I ${OPTS} room.rad sky.rad >/dev/null 2>&1 &&
    '$B/tpiece' job --threads 2 -q && '$B/tmerge' job >/dev/null 2>&1 &&
    '$B/tassemble' job -o job.out"
t1=$(date +%s.%N)
read -r u s <time.txt
printf '%-34s %8.2f %8.2f\n' "job: tpiece --threads 2" "$(echo "$t1 - $t0" | bc)" "$(echo "$u + $s" | bc)"

echo "references ($REF_OPTS, one thread):"
run "rtrace reference" rt.ref rtrace -h -I "${R[@]}" s.oct
run "ttrace reference" tt.ref "$B/ttrace" -n 1 -h -I "${R[@]}" room.rad sky.rad

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

echo "sweep of -aa (one thread): CPU-s and error of each"
printf '%-8s %10s %10s %10s %10s\n' -aa rtrace-CPU rtrace-err ttrace-CPU ttrace-err
for aa in $SWEEP; do
    # shellcheck disable=SC2206
    S=($OPTS -aa "$aa")
    /usr/bin/time -f "%U %S" -o t1.txt rtrace -h -I "${S[@]}" s.oct <grid.pts >rs.out
    /usr/bin/time -f "%U %S" -o t2.txt "$B/ttrace" -n 1 -h -I "${S[@]}" room.rad sky.rad <grid.pts >ts.out
    read -r u1 s1 <t1.txt
    read -r u2 s2 <t2.txt
    printf '%-8s %10.2f %10s %10.2f %10s\n' "$aa" "$(echo "$u1 + $s1" | bc)" "$(err rs.out rt.ref)" \
        "$(echo "$u2 + $s2" | bc)" "$(err ts.out tt.ref)"
done
