#!/usr/bin/env bash
# One copy of the scene per node (docs/benchmarks.md, "The scene image"): P single-thread
# workers on one job, each mapping the job's scene image (JOB/scene.img, the default) or
# building the scene itself (tpiece --no-scene-image), and one worker with P tile loops:
# wall seconds, the node's memory while they run (the largest sum over the workers of the
# proportional set size, PSS, which counts a page shared by k processes as 1/k in each:
# the node's real use; and of the resident size, RSS, which counts it in each) and one
# worker's start-up (a one-tile 1x1 job, best of 3).
#
# Usage: bash bench/sceneimage.sh
# Environment: SCENE (files, default the demo; "mesh": 18 placements of a 51,200-triangle
#   OBJ height field made here), VIEW (default -vf demo/demo.vf),
#   RES="-x 128 -y 128", OPTS="-ab 1 -aa .15 -ad 256 -as 64 -ar 64 -ps 1",
#   WORKERS="1 2" (at most the cores).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
CORES=$(nproc)
SCENE=${SCENE:-"$ROOT/demo/demo.rad"}
VIEW=${VIEW:-"-vf $ROOT/demo/demo.vf"}
RES=${RES:-"-x 128 -y 128"}
OPTS=${OPTS:-"-ab 1 -aa .15 -ad 256 -as 64 -ar 64 -ps 1"}
WORKERS=${WORKERS:-"1 2"}
(cd "$ROOT" && cargo build --release --quiet --bins)
B=$ROOT/target/release
export RAYPATH="$ROOT/demo:${RAYPATH:-.}"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
if [ "$SCENE" = mesh ]; then
    python3 - "$TMP" << 'EOF'
import math, sys
d, n = sys.argv[1], 160
with open(f"{d}/terrain.obj", "w") as f:
    for j in range(n + 1):
        for i in range(n + 1):
            x, y = i / n * 4, j / n * 4
            f.write(f"v {x:.6f} {y:.6f} {0.3 * math.sin(3 * x) * math.cos(2 * y) + 0.3:.6f}\n")
    f.write("usemtl grey\n")
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            f.write(f"f {a} {a + 1} {a + n + 2}\nf {a} {a + n + 2} {a + n + 1}\n")
with open(f"{d}/mesh.rad", "w") as f:
    f.write("void plastic grey 0 0 5 .5 .5 .5 0 0\nvoid light bright 0 0 3 1000 1000 1000\n")
    f.write("bright sphere sun 0 0 4 10 10 30 2\n")
    for k in range(18):
        f.write(f"void mesh m{k} 5 terrain.obj -t {k // 3 * 4.2} {k % 3 * 4.2} 0\n0\n0\n")
    f.write("grey polygon floor 0 0 12 -5 -5 0 30 -5 0 30 20 0 -5 20 0\n")
EOF
    SCENE="$TMP/mesh.rad"
    export RAYPATH="$TMP:$RAYPATH"
    VIEW="-vp 12 -12 14 -vd 0 1 -0.8 -vu 0 0 1 -vh 60 -vv 45"
fi
# shellcheck disable=SC2206
RARGS=($VIEW $RES $OPTS)
# shellcheck disable=SC2206
SFILES=($SCENE)

# watch PIDS...: until all have ended, every 20 ms, the sums of their PSS and RSS (kB);
# prints the largest sums (MB) and the CPU seconds of their last sample.
watch() {
    local maxp=0 maxr=0 cpu=0 hz
    hz=$(getconf CLK_TCK)
    while :; do
        local alive=0 p=0 r=0 c=0
        for pid in "$@"; do
            [ -r "/proc/$pid/smaps_rollup" ] || continue
            alive=1
            read -r pp rr < <(awk '/^Pss:/ { p = $2 } /^Rss:/ { r = $2 } END { print p + 0, r + 0 }' \
                "/proc/$pid/smaps_rollup" 2> /dev/null || echo "0 0")
            cc=$(awk '{ print $14 + $15 }' "/proc/$pid/stat" 2> /dev/null || echo 0)
            p=$((p + pp))
            r=$((r + rr))
            c=$((c + cc))
        done
        [ "$alive" = 1 ] || break
        [ "$p" -gt "$maxp" ] && maxp=$p
        [ "$r" -gt "$maxr" ] && maxr=$r
        [ "$c" -gt "$cpu" ] && cpu=$c
        sleep 0.02
    done
    awk -v p="$maxp" -v r="$maxr" -v c="$cpu" -v hz="$hz" \
        'BEGIN { printf "%.1f %.1f %.2f\n", p / 1024, r / 1024, c / hz }'
}

echo "bench/sceneimage.sh: $CORES cores; scene ${SFILES[*]}; ${RARGS[*]}"
# Start-up: a one-tile job of a 1x1 picture.
one="$TMP/one"
"$B/tplan" --tiles 1 -o "$one" -- "${RARGS[@]/$RES/}" -x 1 -y 1 "${SFILES[@]}" 2> /dev/null
for mode in image build; do
    flag=()
    [ "$mode" = build ] && flag=(--no-scene-image)
    best=
    for _ in 1 2 3; do
        rm -rf "$TMP/o" && cp -r "$one" "$TMP/o"
        s=$(date +%s.%N)
        "$B/tpiece" "$TMP/o" --threads 1 -q "${flag[@]}"
        t=$(echo "$(date +%s.%N) - $s" | bc)
        if [ -z "$best" ] || [ "$(echo "$t < $best" | bc)" = 1 ]; then best=$t; fi
    done
    printf 'start-up (%s): %.3f s\n' "$mode" "$best"
done
printf 'image size: %s bytes\n' "$(stat -c %s "$one/scene.img")"
echo
printf '%-40s %3s %8s %8s %9s %9s\n' run P wall-s CPU-s "PSS MB" "RSS MB"
for P in $WORKERS; do
    if [ "$P" -gt "$CORES" ]; then
        echo "(P = $P skipped: $CORES cores)"
        continue
    fi
    job="$TMP/job-$P"
    "$B/tplan" --workers "$P" -o "$job" -- "${RARGS[@]}" "${SFILES[@]}" 2> /dev/null
    for mode in image build threads; do
        rm -rf "$TMP/j" && cp -r "$job" "$TMP/j"
        pids=()
        s=$(date +%s.%N)
        case $mode in
            threads)
                "$B/tpiece" "$TMP/j" --worker-id w1 --threads "$P" -q &
                pids+=("$!")
                label="1 x tpiece --threads $P"
                ;;
            *)
                flag=()
                [ "$mode" = build ] && flag=(--no-scene-image)
                for i in $(seq 1 "$P"); do
                    "$B/tpiece" "$TMP/j" --worker-id "w$i" --threads 1 -q "${flag[@]}" &
                    pids+=("$!")
                done
                label="$P x tpiece --threads 1 ($mode)"
                ;;
        esac
        read -r pss rss cpu < <(watch "${pids[@]}")
        for p in "${pids[@]}"; do wait "$p"; done
        w=$(echo "$(date +%s.%N) - $s" | bc)
        printf '%-40s %3d %8.2f %8.2f %9.1f %9.1f\n' "$label" "$P" "$w" "$cpu" "$pss" "$rss"
    done
done
