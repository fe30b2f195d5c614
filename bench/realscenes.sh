#!/usr/bin/env bash
# tpict against oconv + rpict on three realistic scenes of our own, at the options lighting
# designers use (issue 26; docs/benchmarks.md, "Real-style scenes"):
#
#   office    a daylit office: gensky sun and sky through a glazed window, two ies2rad
#             LED panels, desks (genbox), six OBJ chairs (obj2mesh meshes), a wood-grain
#             floor and a plaster pattern (.cal functions), a glass partition; ~400 surfaces
#   interior  a lecture hall: 1,680 seats of genbox parts in xform arrays (~20,000
#             polygons), 24 ies2rad downlights, patterned carpet and walls
#   exterior  a park: a gensurf terrain of 20,000 triangles, 2,000 instances of two frozen
#             tree octrees (a cone trunk and 400 leaves each: 800,000 surfaces expanded),
#             genbox buildings with gensky sun and sky
#
# For each scene and each -ab in AB_LIST, one single-threaded render by each renderer
# (tpict -n 1 on the .rad files; oconv once, then rpict): CPU seconds (user + system),
# the ratio rpict ÷ tpict (above 1: tpict is faster) without and with oconv's CPU, and
# each one's peak resident memory (rpict's: the larger of oconv's and rpict's). Each run is taken REPS
# times; the table shows the fastest (memory: the largest).
#
# Environment:
#   SCENES="office interior exterior"   AB_LIST="1 2"   REPS=1
#   RES=256          picture width (the height follows the view)
#   OPTS="-ad 512 -as 128 -aa .15 -ar 64 -dt .07 -ps 1 -pj 0"   the shared render options
#   KEEP=DIR         build the scenes in DIR and keep them (default: a temporary folder)
#   BUILD_ONLY=1     with KEEP: only build the scenes (NAME.rad, NAME.view with the view's
#                    options, NAME.vf as a view file), e.g. for bench/ambient.sh's SCENE_DIR
#   TSV=FILE         also write the figures as tab-separated values
#   NO_BUILD=1 / TPICT=path   as bench/run.sh
#
# Usage: bash bench/realscenes.sh
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
NAME=realscenes
# shellcheck source=bench/common.sh
source "$ROOT/bench/common.sh"

SCENES=${SCENES:-"office interior exterior"}
AB_LIST=${AB_LIST:-"1 2"}
REPS=${REPS:-1}
RES=${RES:-256}
OPTS=${OPTS:-"-ad 512 -as 128 -aa .15 -ar 64 -dt .07 -ps 1 -pj 0"}

if [[ -n "${KEEP:-}" ]]; then
    mkdir -p "$KEEP"
    W=$(cd "$KEEP" && pwd)
    TMP=$W
else
    work_dir
    W=$TMP
fi
cd "$W"

# A synthetic LM-63 photometry (cosine-like falloff), made here: 3,400 lm, 0.6 m square.
ies_file() {
    {
        echo "IESNA:LM-63-1995"
        echo "[TEST] tessera bench/realscenes.sh"
        echo "TILT=NONE"
        echo "1 $1 1 10 1 1 2 $2 $2 0"
        echo "1.0 1.0 $3"
        echo "0 10 20 30 40 50 60 70 80 90"
        echo "0"
        awk -v lm="$1" 'BEGIN { for (i = 0; i <= 9; i++) { a = i * 10 * 3.14159265 / 180;
            c = cos(a); printf "%.1f ", lm / 3.0 * c * c ^ 0.4 } print "" }'
    } >"$4"
}

make_office() {
    [[ -f office.rad ]] && return
    ies_file 3400 0.6 32 panel.ies
    ies2rad -dm -t default -o panel panel.ies
    cat >wood.cal <<'EOF'
{ wood grain along x: rings in y-z, perturbed by noise }
grain = .5 + .5 * sin(40 * sqrt(Py * Py + (Pz + 3) * (Pz + 3)) + 3 * noise3(Px * 2, Py, Pz));
wr = .55 + .15 * grain; wg = .40 + .12 * grain; wb = .25 + .08 * grain;
plaster = 1 + .06 * noise3(Px * 8, Py * 8, Pz * 8);
EOF
    # A chair: seat, back and four legs as boxes, triangulated.
    awk 'function box(x0, y0, z0, x1, y1, z1,   i) {
            printf "v %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\n", x0,y0,z0, x1,y0,z0, x1,y1,z0, x0,y1,z0;
            printf "v %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\n", x0,y0,z1, x1,y0,z1, x1,y1,z1, x0,y1,z1;
            b = n; n += 8;
            f(b+1,b+4,b+3,b+2); f(b+5,b+6,b+7,b+8); f(b+1,b+2,b+6,b+5);
            f(b+2,b+3,b+7,b+6); f(b+3,b+4,b+8,b+7); f(b+4,b+1,b+5,b+8) }
         function f(a, b, c, d) { printf "f %d %d %d\nf %d %d %d\n", a, b, c, a, c, d }
         BEGIN { n = 0; print "usemtl chair_mat";
            box(0, 0, .42, .45, .45, .46); box(0, .41, .46, .45, .45, .9);
            box(0, 0, 0, .04, .04, .42); box(.41, 0, 0, .45, .04, .42);
            box(0, .41, 0, .04, .45, .42); box(.41, .41, 0, .45, .45, .42) }' >chair.obj
    obj2mesh chair.obj chair.rtm
    {
        echo "void plastic wall_paint 0 0 5 .75 .73 .7 0 0"
        echo "void brightfunc plaster_pat 2 plaster wood.cal 0 0"
        echo "plaster_pat plastic plaster 0 0 5 .8 .78 .74 0 0"
        echo "void colorfunc wood_pat 4 wr wg wb wood.cal 0 0"
        echo "wood_pat plastic wood_floor 0 0 5 1 1 1 .02 .05"
        echo "void plastic ceiling_white 0 0 5 .85 .85 .85 0 0"
        echo "void plastic desk_top 0 0 5 .6 .5 .35 .01 .1"
        echo "void metal desk_leg 0 0 5 .5 .5 .52 .9 .05"
        echo "void plastic chair_mat 0 0 5 .15 .2 .35 .01 .08"
        echo "void glass window_glass 0 0 3 .86 .86 .86"
        echo "void trans partition 0 0 7 .7 .75 .8 .02 .05 .6 .2"
        # The room, 8 x 6 x 3 m, window wall at y = 0 with a 4 x 1.6 m opening.
        echo "plaster polygon wall_east 0 0 12 8 0 0 8 6 0 8 6 3 8 0 3"
        echo "plaster polygon wall_west 0 0 12 0 0 0 0 0 3 0 6 3 0 6 0"
        echo "plaster polygon wall_north 0 0 12 0 6 0 0 6 3 8 6 3 8 6 0"
        echo "wall_paint polygon sill 0 0 12 0 0 0 8 0 0 8 0 .9 0 0 .9"
        echo "wall_paint polygon lintel 0 0 12 0 0 2.5 8 0 2.5 8 0 3 0 0 3"
        echo "wall_paint polygon jamb_w 0 0 12 0 0 .9 2 0 .9 2 0 2.5 0 0 2.5"
        echo "wall_paint polygon jamb_e 0 0 12 6 0 .9 8 0 .9 8 0 2.5 6 0 2.5"
        echo "window_glass polygon pane 0 0 12 2 0 .9 6 0 .9 6 0 2.5 2 0 2.5"
        echo "wood_floor polygon floor 0 0 12 0 0 0 0 6 0 8 6 0 8 0 0"
        echo "ceiling_white polygon ceiling 0 0 12 0 0 3 8 0 3 8 6 3 0 6 3"
        echo "partition polygon glass_wall 0 0 12 5 4.6 0 5 6 0 5 6 2.2 5 4.6 2.2"
        # Desks with legs, in two rows.
        for i in 0 1 2; do for j in 0 1; do
            x=$(awk -v i=$i 'BEGIN { print .6 + i * 1.5 }'); y=$(awk -v j=$j 'BEGIN { print 1.2 + j * 2.2 }')
            echo "!genbox desk_top top$i$j 1.2 .7 .03 | xform -t $x $y .72"
            for lx in 0 1.14; do for ly in 0 .64; do
                echo "!genbox desk_leg leg$i$j$lx$ly .04 .04 .72 | xform -t $(awk -v x=$x -v l=$lx 'BEGIN{print x+l}') $(awk -v y=$y -v l=$ly 'BEGIN{print y+l}') 0"
            done; done
            echo "void mesh chair$i$j 5 chair.rtm -t $(awk -v x=$x 'BEGIN{print x+.35}') $(awk -v y=$y 'BEGIN{print y+.75}') 0 0 0"
        done; done
        echo "!xform -t 2 2 3 -a 2 -t 3 0 0 panel.rad"
        echo "!gensky 3 21 10 -a 42 -o -71 -m -75 +s"
        echo "skyfunc glow sky_glow 0 0 4 .9 .9 1.15 0"
        echo "sky_glow source sky 0 0 4 0 0 1 180"
        echo "skyfunc glow ground_glow 0 0 4 1.4 .9 .6 0"
        echo "ground_glow source ground 0 0 4 0 0 -1 180"
        echo "void plastic ground_mat 0 0 5 .2 .22 .18 0 0"
        echo "ground_mat polygon outside 0 0 12 -30 -30 -.01 40 -30 -.01 40 -.2 -.01 -30 -.2 -.01"
    } >office.rad
    echo "-vp 7.7 2.4 1.5 -vd -1 .12 -.15 -vu 0 0 1 -vh 75 -vv 56" >office.view
}

make_interior() {
    [[ -f interior.rad ]] && return
    ies_file 1800 0.2 18 down.ies
    ies2rad -dm -t default -o down down.ies
    cat >carpet.cal <<'EOF'
{ carpet: a two-scale noise and a woven check }
cpt = .8 + .15 * noise3(Px * 20, Py * 20, 0) + .05 * if(sin(Px * 30) * sin(Py * 30), 1, -1);
stripe = 1 + .1 * if(sin(Pz * 6), 1, -1);
EOF
    # A seat model (its parts made once, as a modeller would export them).
    {
        echo "void plastic seat_fabric 0 0 5 .45 .1 .12 0 0"
        echo "void plastic seat_frame 0 0 5 .1 .1 .1 .02 .05"
        genbox seat_fabric cushion .5 .45 .08 | xform -t 0 0 .42
        genbox seat_fabric backrest .5 .06 .5 | xform -t 0 .42 .5
        genbox seat_frame arm .04 .45 .25 | xform -t -.04 0 .42
        genbox seat_frame post .04 .04 .42 | xform -t .23 .2 0
    } >seat.rad
    {
        echo "void brightfunc carpet_pat 2 cpt carpet.cal 0 0"
        echo "carpet_pat plastic carpet 0 0 5 .3 .3 .35 0 0"
        echo "void brightfunc stripe_pat 2 stripe carpet.cal 0 0"
        echo "stripe_pat plastic hall_wall 0 0 5 .7 .68 .62 0 0"
        echo "void plastic hall_ceiling 0 0 5 .8 .8 .8 0 0"
        echo "void plastic stage_wood 0 0 5 .5 .35 .2 .02 .08"
        echo "!genbox hall_wall hall 30 24 8 -i"
        echo "carpet polygon hall_floor 0 0 12 .01 .01 .005 29.99 .01 .005 29.99 23.99 .005 .01 23.99 .005"
        echo "!genbox stage_wood stage 20 4 .8 | xform -t 5 .5 0"
        # 1,680 seats: 40 rows of 42, each row a step higher.
        echo "!xform -a 42 -t .6 0 0 -a 40 -t 0 .45 .1 -t 2.2 5.2 0 seat.rad"
        echo "!xform -t 3 3 7.99 -a 6 -t 4.8 0 0 -a 4 -t 0 5.5 0 down.rad"
    } >interior.rad
    echo "-vp 15 4 3 -vd 0 1 -.1 -vu 0 0 1 -vh 80 -vv 60" >interior.view
}

make_exterior() {
    [[ -f exterior.rad ]] && return
    for k in 1 2; do
        awk -v seed=$k 'BEGIN { srand(seed * 17);
            print "void plastic bark 0 0 5 .25 .18 .12 0 0";
            printf "void plastic leaf 0 0 5 %.2f %.2f .08 0 0\n", .12 + .05 * seed, .3 + .05 * seed;
            print "bark cone trunk 0 0 8 0 0 0 0 0 4 .25 .12";
            for (i = 0; i < 400; i++) {
                r = 2.2 * rand() ^ .5; a = 6.2832 * rand(); z = 3 + 3 * rand();
                x = r * cos(a); y = r * sin(a); s = .35;
                printf "leaf polygon l%d 0 0 9 %g %g %g %g %g %g %g %g %g\n", i,
                    x, y, z, x + s * rand(), y + s * rand(), z + s * (rand() - .5),
                    x - s * rand(), y + s * rand(), z + s * rand() }
        }' >tree$k.rad
        oconv -f tree$k.rad >tree$k.oct
    done
    {
        echo "!gensky 6 21 15 -a 42 -o -71 -m -75 +s"
        echo "skyfunc glow sky_glow 0 0 4 .9 .9 1.15 0"
        echo "sky_glow source sky 0 0 4 0 0 1 180"
        echo "void plastic grass 0 0 5 .18 .28 .1 0 0"
        echo "!gensurf grass terrain '200*s-100' '200*t-100' '1.5*sin(s*9)*cos(t*7)-1.5' 100 100"
        echo "void plastic facade 0 0 5 .6 .55 .5 0 .02"
        echo "void glass bldg_glass 0 0 3 .6 .65 .7"
        for b in 0 1 2 3 4; do
            echo "!genbox facade bldg$b 12 10 $((10 + b * 4)) | xform -t $((b * 30 - 70)) 70 -2"
            echo "bldg_glass polygon win$b 0 0 12 $((b * 30 - 69)) 69.99 1 $((b * 30 - 59)) 69.99 1 $((b * 30 - 59)) 69.99 8 $((b * 30 - 69)) 69.99 8"
        done
        awk 'BEGIN { srand(3);
            for (i = 0; i < 2000; i++) {
                x = 180 * rand() - 90; y = 130 * rand() - 90;
                printf "void instance tree%d 9 tree%d.oct -rz %d -s %.2f -t %.2f %.2f %.2f 0 0\n",
                    i, 1 + i % 2, 360 * rand(), .8 + .5 * rand(), x, y,
                    1.5 * sin((x + 100) / 200 * 9) * cos((y + 100) / 200 * 7) - 1.6 }
        }'
    } >exterior.rad
    echo "-vp 0 -95 6 -vd 0 1 -.08 -vu 0 0 1 -vh 70 -vv 45" >exterior.view
}

# measure OUT cmd...: "cpu MB" of one run (user + system seconds, peak resident MB).
measure() {
    local out=$1
    shift
    /usr/bin/time -f "%U %S %M" -o "$W/time.txt" "$@" >"$out" 2>>"$W/err.txt" || {
        echo "$NAME: failed: $*" >&2
        tail -5 "$W/err.txt" >&2
        exit 1
    }
    awk '{ printf "%.2f %.0f\n", $1 + $2, $3 / 1024 }' "$W/time.txt"
}

# best CPU over REPS runs, largest memory: best OUT cmd...
best() {
    local out=$1 c m bc="" bm=0
    shift
    for ((k = 0; k < REPS; k++)); do
        read -r c m < <(measure "$out" "$@")
        bc=$(awk -v a="$c" -v b="$bc" 'BEGIN { print (b == "" || a < b) ? a : b }')
        bm=$(awk -v a="$m" -v b="$bm" 'BEGIN { print (a > b) ? a : b }')
    done
    echo "$bc $bm"
}

if [[ -n "${BUILD_ONLY:-}" ]]; then
    [[ -n "${KEEP:-}" ]] || { echo "$NAME: BUILD_ONLY needs KEEP=DIR" >&2; exit 1; }
    for s in $SCENES; do
        "make_$s"
        echo "rview $(cat "$s.view")" >"$s.vf"
    done
    echo "$NAME: built $SCENES in $W" >&2
    exit 0
fi
[[ -n "${TSV:-}" ]] && printf 'scene\tab\ttpict_cpu\trpict_cpu\toconv_cpu\tratio\ttpict_mb\trpict_mb\n' >"$TSV"
printf '%-9s %3s %9s %9s %9s %6s %6s %8s %8s %6s\n' scene ab "tpict" "rpict" "+oconv" ratio "+oconv" "tpict MB" "rpict MB" "MB ×"
for s in $SCENES; do
    "make_$s"
    # shellcheck disable=SC2046
    view=$(cat "$s.view")
    read -r oc om < <(best "$s.oct" oconv "$s.rad")
    for ab in $AB_LIST; do
        # shellcheck disable=SC2086
        read -r tc tm < <(best "$s-t$ab.hdr" "$TPICT" -n 1 -ab "$ab" $OPTS $view -x "$RES" -y "$RES" "$s.rad")
        # shellcheck disable=SC2086
        read -r rc rm < <(best "$s-r$ab.hdr" rpict -ab "$ab" $OPTS $view -x "$RES" -y "$RES" "$s.oct")
        rcpu=$(awk -v a="$rc" -v b="$oc" 'BEGIN { printf "%.2f", a + b }')
        rmb=$((rm > om ? rm : om))
        ratio=$(awk -v r="$rcpu" -v t="$tc" 'BEGIN { printf "%.2f", r / t }')
        mx=$(awk -v r="$rmb" -v t="$tm" 'BEGIN { printf "%.2f", t / r }')
        ralone=$(awk -v r="$rc" -v t="$tc" 'BEGIN { printf "%.2f", r / t }')
        printf '%-9s %3s %9s %9s %9s %6s %6s %8s %8s %6s\n' "$s" "$ab" "$tc" "$rc" "$rcpu" "$ralone" "$ratio" "$tm" "$rmb" "$mx"
        [[ -n "${TSV:-}" ]] && printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$s" "$ab" "$tc" "$rc" "$oc" "$ralone" "$tm" "$rmb" >>"$TSV"
    done
done
echo "(CPU: user + system seconds, one thread; +oconv: rpict's with oconv's; ratio: rpict ÷ tpict"
echo " without and with oconv; MB: peak resident memory, rpict's the larger of oconv's and"
echo " rpict's; settings: $OPTS, $RES px wide)"
