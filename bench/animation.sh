#!/usr/bin/env bash
# A walkthrough of the demo scene (docs/animation.md, "Figures"): FRAMES frames along a
# keyframed path (tplan --path), rendered as one job by one worker with a constant -aa and
# with time-varying accuracy (-ax, the seed paper's constant step; -axg, the geometric step it
# proposed; -axm, moving-direction accuracy; -axt, a per-frame CPU budget of BUDGET seconds). Per-frame CPU and new ambient values come from tstat --json; the error of the
# last frames is measured against a high-accuracy render of the same views.
# Usage: bash bench/animation.sh [OUTDIR (default docs/benchmarks/animation)]
# Environment: FRAMES=60, BUDGET=0.12, TILES=80, RES="-x 160 -y 120", AMB="-ab 1 -ad 512 -as 128 -ar 64",
#              MODES (name:options;...), REF="-aa .03 -ad 2048 -as 1024",
#              MID (frames along the path whose error is measured; default every frame
#              before the last LAST), LAST=5
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=${1:-$ROOT/docs/benchmarks/animation}
FRAMES=${FRAMES:-60}
RES=${RES:-"-x 160 -y 120"}
AMB=${AMB:-"-ab 1 -ad 512 -as 128 -ar 64"}
BUDGET=${BUDGET:-0.12}
MODES=${MODES:-"constant:-aa .1;ax:-ax .5 .1 .0075;axg:-axg .5 .1 .93;axm:-aa .1 -axm 2 5;axt:-aa .1 -axt $BUDGET .5 .1"}
REF=${REF:-"-aa .03 -ad 2048 -as 1024"}
LAST=${LAST:-5}
# Tiles per frame: -axm decides per tile, so the frames are cut finer than the default plan
# for one worker would.
TILES=${TILES:-80}
MID=${MID:-$(seq -s ' ' 0 $((FRAMES - LAST - 1)))}
NAME=animation
NO_BUILD=1
# shellcheck source=bench/common.sh
source "$ROOT/bench/common.sh"
(cd "$ROOT" && cargo build --release --quiet --bins)
B=$ROOT/target/release
mkdir -p "$OUT"
work_dir
cat > "$TMP/keys.vf" <<'KEYS'
-vtv -vp 7.6 .35 2.1 -vd -5.2 4.6 -1.5 -vu 0 0 1 -vh 80 -vv 60
-vp 6.2 2.4 1.7 -vd -1 .25 -.25
-vp 4.6 4.6 1.7 -vd -.7 -1 -.2
-vp 2.2 4.9 1.6 -vd .3 -1 -.25
KEYS
cd "$ROOT/demo"
IFS=';' read -ra modes <<<"$MODES"
for m in "${modes[@]}"; do
    name=${m%%:*}
    opts=${m#*:}
    job=$TMP/$name
    # shellcheck disable=SC2086
    "$B/tplan" --workers 1 --tiles "$TILES" --path "$TMP/keys.vf" --path-frames "$FRAMES" -o "$job" -- \
        $RES $AMB $opts demo.rad 2>/dev/null
    /usr/bin/time -f "%U %S %e" -o "$TMP/$name.time" "$B/tpiece" "$job" --threads 1 -q
    "$B/tstat" "$job" --json > "$OUT/$name.json"
    "$B/tassemble" "$job" --force --all-frames -o "$TMP/$name-%03d.hdr" 2>/dev/null
    [[ $name == ax ]] && "$B/tassemble" "$job" --contact-sheet "$OUT/sheet-$name.png" --thumb-width 64 2>/dev/null
    echo "$name: $(cat "$TMP/$name.time") (user sys wall s)" >&2
done
# References: the MID frames' and the last LAST frames' views at high accuracy.
first=${modes[0]%%:*}
ERRF="$MID $(seq -s ' ' $((FRAMES - LAST)) $((FRAMES - 1)))"
for k in $ERRF; do
    view=$(getinfo < "$TMP/$first-$(printf %03d "$k").hdr" | sed -n 's/^VIEW= *//p' | tail -1)
    # shellcheck disable=SC2086
    "$B/tpict" -n 2 $view $RES $AMB $REF -o "$TMP/ref-$(printf %03d "$k").hdr" demo.rad 2>/dev/null
done
# The relative RMS error of each mode's last frames (pictures reduced 8×).
for m in "${modes[@]}"; do
    name=${m%%:*}
    : > "$OUT/$name-error.txt"
    for k in $ERRF; do
        f=$(printf %03d "$k")
        # Reduced 8× first (Radiance's test-suite practice), so that pixel jitter does not count.
        pfilt -1 -x /8 -y /8 "$TMP/$name-$f.hdr" | pvalue -h -H -b -d > "$TMP/a.txt"
        pfilt -1 -x /8 -y /8 "$TMP/ref-$f.hdr" | pvalue -h -H -b -d > "$TMP/b.txt"
        paste "$TMP/a.txt" "$TMP/b.txt" | awk -v k="$k" '{d=$1-$2; s+=d*d; r+=$2*$2; m+=$2; n++}
            END {printf "%d %.5f\n", k, sqrt(s/n)/(m/n)}' >> "$OUT/$name-error.txt"
    done
done
# Flicker: a still camera, STILL frames, per-frame seeds (rpict's way) against --same-seeds;
# temporal noise = RMS of the difference of consecutive frames over their mean, per pixel.
STILL=${STILL:-8}
line=$(head -1 "$TMP/keys.vf")
for i in $(seq 1 "$STILL"); do echo "rview $line"; done > "$TMP/still.vf"
: > "$OUT/flicker.txt"
for seeds in per-frame same; do
    extra=""
    [[ $seeds == same ]] && extra="--same-seeds"
    job=$TMP/still-$seeds
    # shellcheck disable=SC2086
    "$B/tplan" --workers 1 --frames "$TMP/still.vf" -o "$job" -- $RES $AMB -aa .1 $extra \
        demo.rad 2>/dev/null
    "$B/tpiece" "$job" --threads 1 -q
    "$B/tassemble" "$job" --force --all-frames -o "$TMP/still-$seeds-%03d.hdr" 2>/dev/null
    for k in $(seq 1 $((STILL - 1))); do
        pvalue -h -H -b -d "$TMP/still-$seeds-$(printf %03d $((k - 1))).hdr" > "$TMP/a.txt"
        pvalue -h -H -b -d "$TMP/still-$seeds-$(printf %03d "$k").hdr" > "$TMP/b.txt"
        paste "$TMP/a.txt" "$TMP/b.txt" | awk '{d=$1-$2; s+=d*d; m+=($1+$2)/2; n++}
            END {printf "%.5f\n", sqrt(s/n)/(m/n)}'
    done | awk -v s="$seeds" '{t+=$1; n++} END {printf "%s %.5f\n", s, t/n}' >> "$OUT/flicker.txt"
done
python3 "$ROOT/bench/plot_animation.py" "$OUT" "$MODES" "$MID"
echo "temporal noise of a still camera (RMS of consecutive-frame differences / mean):"
cat "$OUT/flicker.txt"
