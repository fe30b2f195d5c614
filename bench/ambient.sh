#!/usr/bin/env bash
# Speed against error for the indirect (ambient) calculation: tpict vs Radiance's rpict.
#
# For every scene and every -ab level:
#   1. two converged references with pure Monte Carlo sampling (no irradiance cache):
#        rpict -aa 0 -ad REF_AD -as 0   and   tpict -aa 0 -ad REF_AD -as 0
#      their agreement (relative RMS, mean luminance) goes to references.tsv;
#      the reference used for the sweep is the average of the two, reduced like the runs.
#   2. a sweep over -aa x -ad x -as for both renderers, single-threaded (tpict -n 1),
#      recording CPU time (user+sys, /usr/bin/time) and the error against the reference.
# Pictures are RES x RES with -ps 1 -pj 0 (no pixel-sampling noise), then reduced with
# `pfilt -1 -r 1 -x RED -y RED`. The error is the relative RMS of per-pixel brightness
# (pvalue -b): sqrt(mean(((b - ref) / max(ref, FLOOR*mean(ref)))^2)), like radcompare's
# per-pixel relative difference, with a floor so near-black pixels do not dominate.
# Each run's error is also recorded against each renderer's own reference alone.
#
# Environment:
#   SCENES="spheres curved glassy mirrors"   AB_LIST="1"   RES=128   RED=64
#   SCENE_DIR=tests/scenes  where each scene's NAME.rad and view file NAME.vf are (e.g. the
#                          real-style scenes: KEEP=DIR BUILD_ONLY=1 bash bench/realscenes.sh)
#   AA_LIST="0.3 0.2 0.15 0.1"  AD_LIST="128 512 1024"  AS_LIST="0 128"
#                          (AA_LIST="" renders only the references, e.g. to fill REF_DIR)
#   REF_AD=2048            divisions of the references
#   EXTRA=""               more options for every picture (references and runs), e.g.
#                          "-st 1": rough specular reflections go into the ambient term
#                          instead of being sampled, which takes their per-pixel noise (which
#                          no -a option reduces) out of the error (docs/benchmarks.md)
#   REF_EXTRA=""           more options for both references, e.g. "-lw 1e-8": the ray weight
#                          limit caps the divisions of an ambient value at 0.5/lw (rpict, tpict),
#                          and below an uncached sample ray (weight 0.5/REF_AD) it also drops
#                          weak reflections (a 6% mirror-like plastic, a pane's Fresnel
#                          reflection) that cached pictures keep: use a limit far below
#                          0.5/REF_AD times the weakest such coefficient (docs/benchmarks.md)
#   REF_DIR=dir            keep the reference pictures there and reuse them when present
#                          (named by scene, -ab, RES, REF_AD, EXTRA and REF_EXTRA; delete
#                          to re-render)
#   FLOOR=0.01             relative floor of the error denominator (x mean reference)
#   OUT=docs/benchmarks/ambient   where runs.tsv and references.tsv go (TAG=x -> runs-x.tsv)
#   TESSERA_RADIANCE_BIN   folder holding rpict, oconv, pfilt, pvalue
#   NO_BUILD=1 / TPICT=path
#   REPEAT=1               runs of each setting; the CPU time recorded is the smallest (the
#                          pictures, and so the errors, are the same every time)
#   AS_MAX_FRACTION=0.5    combinations with -as > AS_MAX_FRACTION x -ad are skipped (by
#                          default super-sampling more than half the divisions)
#   RENDERERS="rpict tpict"  which renderers the sweep runs (e.g. RENDERERS=tpict to measure
#                          a change of tpict against an earlier sweep's rpict rows)
#
# Usage: bench/ambient.sh   then   python3 bench/plot_ambient.py   (see docs/benchmarks.md)
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
SCENES=${SCENES:-"spheres curved glassy mirrors"}
AB_LIST=${AB_LIST:-"1"}
RES=${RES:-128}
RED=${RED:-64}
AA_LIST=${AA_LIST-"0.3 0.2 0.15 0.1"}
AD_LIST=${AD_LIST:-"128 512 1024"}
AS_LIST=${AS_LIST:-"0 128"}
REF_AD=${REF_AD:-2048}
REPEAT=${REPEAT:-1}
AS_MAX_FRACTION=${AS_MAX_FRACTION:-0.5}
RENDERERS=${RENDERERS:-"rpict tpict"}
REF_DIR=${REF_DIR:-}
SCENE_DIR=${SCENE_DIR:-"$ROOT/tests/scenes"}
[[ $SCENE_DIR == /* ]] || SCENE_DIR="$PWD/$SCENE_DIR"
REF_EXTRA=${REF_EXTRA:-}
EXTRA=${EXTRA:-}
FLOOR=${FLOOR:-0.01}
OUT=${OUT:-"$ROOT/docs/benchmarks/ambient"}
TAG=${TAG:-}
[[ $OUT == /* ]] || OUT="$PWD/$OUT"
mkdir -p "$OUT"
RUNS="$OUT/runs${TAG:+-$TAG}.tsv"
REFS="$OUT/references${TAG:+-$TAG}.tsv"

NAME=ambient
# shellcheck source=bench/common.sh
source "$ROOT/bench/common.sh"
[[ -x /usr/bin/time ]] || { echo "ambient: /usr/bin/time (GNU time) needed" >&2; exit 1; }

work_dir

# cpu_run OUT cmd... : run cmd (stdout to OUT); prints CPU seconds (user+sys).
cpu_run() {
    local out=$1
    shift
    /usr/bin/time -f "%U %S" -o "$TMP/time" "$@" >"$out" 2>"$TMP/err" || {
        echo "ambient: failed: $*" >&2
        cat "$TMP/err" >&2
        exit 1
    }
    [[ -s "$out" ]] || { echo "ambient: no picture from: $*" >&2; exit 1; }
    awk '{ printf "%.2f\n", $1 + $2 }' "$TMP/time"
}

mean_of() { awk '{ s += $1 } END { printf "%.6g\n", s / NR }' "$1"; }

printf 'ambient: %s; %sx%s -> %sx%s; Radiance in %s; %s cores\n' \
    "$("$TPICT" -version 2>/dev/null | head -1)" "$RES" "$RES" "$RED" "$RED" "$RADBIN" "$(nproc)" >&2

printf 'scene\tab\trpict_ref_cpu\ttpict_ref_cpu\trpict_ref_mean\ttpict_ref_mean\trelrms_tpict_vs_rpict\trelrms_rpict_vs_tpict\n' >"$REFS"
printf 'scene\tab\trenderer\taa\tad\tas\tcpu_s\terr_avgref\terr_rpictref\terr_tpictref\tmean\n' >"$RUNS"

for s in $SCENES; do
    sdir=$SCENE_DIR
    oct="$TMP/$s.oct"
    (cd "$sdir" && oconv "$s.rad" >"$oct")
    for ab in $AB_LIST; do
        # shellcheck disable=SC2206
        common=(-vf "$s.vf" -x "$RES" -y "$RES" -ps 1 -pj 0 -ab "$ab" $EXTRA)
        cd "$sdir"
        # --- references ---
        # References at the runs' resolution: with -pj 0 both sample the same pixel centres
        # (other points would add the runs' sub-pixel aliasing, not ambient error).
        refc=(-vf "$s.vf" -x "$RES" -y "$RES" -ps 1 -pj 0 -ab "$ab" -aa 0 -ad "$REF_AD" -as 0)
        # shellcheck disable=SC2206
        refc+=($EXTRA $REF_EXTRA)
        key="$s-ab$ab-$RES-ad$REF_AD$(echo "$EXTRA $REF_EXTRA" | tr -d ' ')"
        if [[ -n $REF_DIR && -s "$REF_DIR/$key-rref.hdr" && -s "$REF_DIR/$key-tref.hdr" ]]; then
            cp "$REF_DIR/$key-rref.hdr" "$TMP/rref.hdr"
            cp "$REF_DIR/$key-tref.hdr" "$TMP/tref.hdr"
            read -r rc tc <"$REF_DIR/$key-cpu"
            echo "ambient: reusing references $REF_DIR/$key-*" >&2
        else
            rc=$(cpu_run "$TMP/rref.hdr" rpict "${refc[@]}" "$oct")
            tc=$(cpu_run "$TMP/tref.hdr" "$TPICT" -n 1 "${refc[@]}" "$s.rad")
            if [[ -n $REF_DIR ]]; then
                mkdir -p "$REF_DIR"
                cp "$TMP/rref.hdr" "$REF_DIR/$key-rref.hdr"
                cp "$TMP/tref.hdr" "$REF_DIR/$key-tref.hdr"
                echo "$rc $tc" >"$REF_DIR/$key-cpu"
            fi
        fi
        bright "$TMP/rref.hdr" "$TMP/rref.b"
        bright "$TMP/tref.hdr" "$TMP/tref.b"
        # The average is taken of the reduced brightness, in floating point: averaging the
        # pictures with pcomb re-encodes every pixel as RGBE, and a mean that falls halfway
        # between two mantissa steps is rounded up (+0.1% over the picture).
        paste "$TMP/rref.b" "$TMP/tref.b" | awk '{ printf "%.7e\n", ($1 + $2) / 2 }' >"$TMP/aref.b"
        row="$s	$ab	$rc	$tc	$(mean_of "$TMP/rref.b")	$(mean_of "$TMP/tref.b")	$(relrms "$TMP/tref.b" "$TMP/rref.b")	$(relrms "$TMP/rref.b" "$TMP/tref.b")"
        echo "$row" >>"$REFS"
        echo "ambient: reference $row" >&2
        # --- sweep ---
        for aa in $AA_LIST; do
            for ad in $AD_LIST; do
                for as in $AS_LIST; do
                    awk -v a="$as" -v d="$ad" -v f="$AS_MAX_FRACTION" 'BEGIN { exit !(a <= f * d) }' ||
                        continue
                    amb=(-aa "$aa" -ad "$ad" -as "$as")
                    for r in $RENDERERS; do
                        c=""
                        for ((rep = 0; rep < REPEAT; rep++)); do
                            if [[ $r == rpict ]]; then
                                ci=$(cpu_run "$TMP/run.hdr" rpict "${common[@]}" "${amb[@]}" "$oct")
                            else
                                ci=$(cpu_run "$TMP/run.hdr" "$TPICT" -n 1 "${common[@]}" "${amb[@]}" "$s.rad")
                            fi
                            c=$(awk -v a="$c" -v b="$ci" 'BEGIN { print (a == "" || b + 0 < a + 0) ? b : a }')
                        done
                        bright "$TMP/run.hdr" "$TMP/run.b"
                        row="$s	$ab	$r	$aa	$ad	$as	$c	$(relrms "$TMP/run.b" "$TMP/aref.b")	$(relrms "$TMP/run.b" "$TMP/rref.b")	$(relrms "$TMP/run.b" "$TMP/tref.b")	$(mean_of "$TMP/run.b")"
                        echo "$row" >>"$RUNS"
                        echo "ambient: $row" >&2
                    done
                done
            done
        done
        cd "$ROOT"
    done
done
echo "ambient: wrote $RUNS and $REFS" >&2
