#!/usr/bin/env bash
# Direct light (-ab 0): speed at equal error, tpict against rpict.
#
# For every scene, each renderer renders a reference at `-ps 1 -ss 16 -ds REF_DS` (fine
# source partitions, 16 specular samples, every pixel) and then a grid of settings
# (-ps in PS_LIST × -ds in DS_LIST, otherwise the defaults). Every picture is reduced with
# `pfilt -1 -r 1 -x RED -y RED` and read as brightness (`pvalue -b`); its error is the
# relative RMS against the same renderer's reference,
#     sqrt(mean(((b − ref) / max(ref, FLOOR·mean(ref)))²)),
# so each renderer is judged against its own converged picture (the two renderers' source
# models differ slightly). The CPU time (user + sys) is the minimum of REPEAT runs, both
# renderers single-threaded (`tpict -n 1`).
#
# Speed at equal error: tpict's settings form a frontier (the cheapest picture for each error:
# points no cheaper picture beats); tpict's CPU at rpict's error is interpolated on it (log-log).
# `ratio@default` is rpict's CPU at its default settings ÷ tpict's CPU at the same error;
# `median ratio` is the median of that ratio over rpict's own frontier points that lie within
# tpict's range of errors. A `>` marks a lower bound: rpict's error is above every tpict
# error, so tpict's cheapest picture is used.
#
# Environment:
#   RES=512  RED=128        picture size and reduced size
#   SCENES="spheres ..."    subset of: spheres curved glassy mirrors aniso examp daffodil
#   PS_LIST="1 2 4 8 16"    -ps settings
#   DS_LIST="default .1 .05" -ds settings ("default": the renderer's own)
#   REF_DS=.02 REF_SS=16    the references' -ds and -ss
#   REPEAT=2                runs per timing (the minimum is kept)
#   FLOOR=.01               error floor (fraction of the reference's mean)
#   TSV=FILE                also write every run as tab-separated values
#   TESSERA_RADIANCE_BIN, NO_BUILD, TPICT   as for bench/run.sh
#
# Usage: bench/direct_error.sh   (see docs/benchmarks.md)
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
RES=${RES:-512}
RED=${RED:-128}
SCENES=${SCENES:-"spheres curved glassy mirrors aniso examp daffodil"}
PS_LIST=${PS_LIST:-"1 2 4 8 16"}
DS_LIST=${DS_LIST:-"default .1 .05"}
REF_DS=${REF_DS:-.02}
REF_SS=${REF_SS:-16}
REPEAT=${REPEAT:-2}
FLOOR=${FLOOR:-.01}

NAME=direct_error
# shellcheck source=bench/common.sh
source "$ROOT/bench/common.sh"

work_dir

# Scenes: scene_def in bench/common.sh.

# cpu_of OUT cmd... : run REPEAT times with stdout to OUT; prints the minimum user+sys.
cpu_of() {
    local out=$1 best="" c
    shift
    for ((k = 0; k < REPEAT; k++)); do
        local TIMEFORMAT='%U %S'
        { time "$@" >"$out" 2>"$TMP/err"; } 2>"$TMP/time" || {
            echo "$NAME: failed: $*" >&2
            cat "$TMP/err" >&2
            exit 1
        }
        c=$(awk '{ printf "%.3f", $1 + $2 }' "$TMP/time")
        best=$(awk -v a="$c" -v b="$best" 'BEGIN { print (b == "" || a < b) ? a : b }')
    done
    echo "$best"
}


printf '%s: %s; %sx%s -> %sx%s, -ab 0; references -ps 1 -ss %s -ds %s; Radiance in %s\n' \
    "$NAME" "$("$TPICT" -version 2>/dev/null | head -1)" "$RES" "$RES" "$RED" "$RED" \
    "$REF_SS" "$REF_DS" "$RADBIN" >&2

RUNS="$TMP/runs.tsv"
: >"$RUNS"
for s in $SCENES; do
    def=$(scene_def "$s") || { echo "$NAME: unknown scene $s" >&2; exit 1; }
    IFS='|' read -r dir files view av <<<"$def"
    sdir="$ROOT/tests/scenes/$dir"
    read -r -a farr <<<"$files"
    oct="$TMP/$s.oct"
    (cd "$sdir" && oconv "${farr[@]}" >"$oct")
    cd "$sdir"
    common=(-vf "$view" -x "$RES" -y "$RES" -ab 0 -av "$av" "$av" "$av")
    ref=(-ps 1 -ss "$REF_SS" -ds "$REF_DS")
    rpict "${common[@]}" "${ref[@]}" "$oct" >"$TMP/rref.hdr"
    "$TPICT" "${common[@]}" "${ref[@]}" "${farr[@]}" >"$TMP/tref.hdr"
    bright "$TMP/rref.hdr" "$TMP/rref.b"
    bright "$TMP/tref.hdr" "$TMP/tref.b"
    for ps in $PS_LIST; do
        for ds in $DS_LIST; do
            opts=(-ps "$ps")
            [[ $ds != default ]] && opts+=(-ds "$ds")
            rc=$(cpu_of "$TMP/r.hdr" rpict "${common[@]}" "${opts[@]}" "$oct")
            tc=$(cpu_of "$TMP/t.hdr" "$TPICT" -n 1 "${common[@]}" "${opts[@]}" "${farr[@]}")
            bright "$TMP/r.hdr" "$TMP/r.b"
            bright "$TMP/t.hdr" "$TMP/t.b"
            re=$(relrms "$TMP/r.b" "$TMP/rref.b")
            te=$(relrms "$TMP/t.b" "$TMP/tref.b")
            printf '%s\trpict\t%s\t%s\t%s\t%s\n' "$s" "$ps" "$ds" "$rc" "$re" >>"$RUNS"
            printf '%s\ttpict\t%s\t%s\t%s\t%s\n' "$s" "$ps" "$ds" "$tc" "$te" >>"$RUNS"
            echo "$NAME: $s -ps $ps -ds $ds: rpict ${rc}s err $re, tpict ${tc}s err $te" >&2
        done
    done
    cd "$ROOT"
done
[[ -n "${TSV:-}" ]] && { printf 'scene\trenderer\tps\tds\tcpu_s\terr\n'; cat "$RUNS"; } >"$TSV"

# --- Speed at equal error, per scene ---------------------------------------------------------
echo
echo "| scene | rpict default: cpu s | error | tpict default: cpu s | error | tpict cpu at rpict's default error | ratio@default | median ratio (n) |"
echo "|---|---|---|---|---|---|---|---|"
awk -F'\t' '
    function frontier(sc, who,   i, j, n, tmp) {
        # Points of (sc, who) sorted by CPU; keep those with a lower error than every cheaper one.
        n = 0
        for (i = 1; i <= N; i++) if (S[i] == sc && W[i] == who) { n++; fc[n] = C[i]; fe[n] = E[i] }
        for (i = 2; i <= n; i++) for (j = i; j > 1 && (fc[j] < fc[j-1] || (fc[j] == fc[j-1] && fe[j] < fe[j-1])); j--) {
            tmp = fc[j]; fc[j] = fc[j-1]; fc[j-1] = tmp; tmp = fe[j]; fe[j] = fe[j-1]; fe[j-1] = tmp
        }
        FN = 0
        for (i = 1; i <= n; i++) if (FN == 0 || fe[i] < FE[FN]) { FN++; FC[FN] = fc[i]; FE[FN] = fe[i] }
    }
    # CPU of the frontier (FC, FE) at error e: -1 below its range; LOW set when above it.
    function cpu_at(e,   i, t) {
        LOW = 0
        if (e >= FE[1]) { LOW = (e > FE[1]); return FC[1] }
        if (e < FE[FN]) return -1
        for (i = 1; i < FN; i++) if (e <= FE[i] && e >= FE[i+1]) {
            if (FE[i] == FE[i+1] || FC[i] <= 0 || FC[i+1] <= 0) return FC[i+1]
            t = (log(e) - log(FE[i])) / (log(FE[i+1]) - log(FE[i]))
            return exp(log(FC[i]) + t * (log(FC[i+1]) - log(FC[i])))
        }
        return -1
    }
    { N++; S[N] = $1; W[N] = $2; P[N] = $3; D[N] = $4; C[N] = $5; E[N] = $6; if (!($1 in seen)) { seen[$1] = 1; order[++NS] = $1 } }
    END {
        for (k = 1; k <= NS; k++) {
            sc = order[k]; rdc = rde = tdc = tde = ""
            for (i = 1; i <= N; i++) if (S[i] == sc && P[i] == 4 && D[i] == "default") {
                if (W[i] == "rpict") { rdc = C[i]; rde = E[i] } else { tdc = C[i]; tde = E[i] }
            }
            # rpict frontier points
            frontier(sc, "rpict"); rn = FN
            for (i = 1; i <= FN; i++) { RC[i] = FC[i]; RE[i] = FE[i] }
            frontier(sc, "tpict")
            at = cpu_at(rde); mark = LOW ? ">" : ""
            ratio = (at > 0) ? sprintf("%s%.2f", mark, rdc / at) : "-"
            atxt = (at > 0) ? sprintf("%.3f", at) : "-"
            m = 0
            for (i = 1; i <= rn; i++) { a = cpu_at(RE[i]); if (a > 0 && !LOW) r[++m] = RC[i] / a }
            for (i = 2; i <= m; i++) for (j = i; j > 1 && r[j] < r[j-1]; j--) { t = r[j]; r[j] = r[j-1]; r[j-1] = t }
            med = m ? (m % 2 ? r[(m + 1) / 2] : (r[m/2] + r[m/2 + 1]) / 2) : 0
            printf "| %s | %.3f | %.2f%% | %.3f | %.2f%% | %s | %s | %s |\n", sc, rdc, 100 * rde, tdc, 100 * tde, atxt, ratio, m ? sprintf("%.2f (%d)", med, m) : "- (0)"
            if (at > 0) { lg += log(rdc / at); ng++ }
        }
        if (ng) printf "\ngeometric mean of ratio@default over %d scenes: %.2f (target >= 3)\n", ng, exp(lg / ng)
    }' "$RUNS"
