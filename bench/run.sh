#!/usr/bin/env bash
# Benchmark tpict against Radiance's rpict at direct-only settings (-ab 0).
#
# For every test scene, at the default -ps/-pj and at -ps 1, measures the wall and CPU
# (user+sys) time of `tpict -n 1`, `tpict -n 2` and `rpict` (oconv is timed separately:
# tpict reads the .rad files directly), the rays each traced (from the final `-t` report
# line, or from `--stats FILE` when tpict writes one) and prints a table of the ratios.
# Every timing is the minimum over REPEAT runs.
#
# Environment:
#   RES=512                 picture size (-x RES -y RES)
#   REPEAT=3                runs per measurement (the minimum is reported)
#   SCENES="spheres ..."    subset of: spheres curved glassy mirrors aniso examp daffodil
#   PS_LIST="default 1"     -ps settings ("default" = tpict's/rpict's own defaults)
#   TESSERA_RADIANCE_BIN    folder holding rpict and oconv (else PATH, else pyradiance)
#   TSV=FILE                also write the raw numbers as tab-separated values
#   NO_BUILD=1              skip `cargo build --release`
#   TPICT=path              benchmark this tpict binary instead (implies NO_BUILD)
#
# Usage: bench/run.sh            (from anywhere; see docs/benchmarks.md)
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
RES=${RES:-512}
REPEAT=${REPEAT:-3}
SCENES=${SCENES:-"spheres curved glassy mirrors aniso examp daffodil"}
PS_LIST=${PS_LIST:-"default 1"}

NAME=bench
# shellcheck source=bench/common.sh
source "$ROOT/bench/common.sh"

work_dir

# Scenes: scene_def in bench/common.sh.

# time_cmd OUT ERR cmd... : run cmd with stdout to OUT, stderr to ERR; prints "wall cpu".
time_cmd() {
    local out=$1 err=$2
    shift 2
    local tf="$TMP/time.$$"
    local TIMEFORMAT='%R %U %S'
    { time "$@" >"$out" 2>"$err"; } 2>"$tf"
    awk '{ printf "%.3f %.3f\n", $1, $2 + $3 }' "$tf"
}

# best_of N cmd... : minimum wall and minimum CPU over N runs ("wall cpu"); the last run's
# stderr stays in $TMP/last.err.
best_of() {
    local n=$1
    shift
    local bw="" bc="" w c
    for ((k = 0; k < n; k++)); do
        rm -f "$TMP/out.hdr" "$TMP/stats.json"
        read -r w c < <(time_cmd "$TMP/out.hdr" "$TMP/last.err" "$@")
        [[ -s "$TMP/out.hdr" ]] || { echo "bench: no picture from: $*" >&2; cat "$TMP/last.err" >&2; exit 1; }
        bw=$(awk -v a="$w" -v b="$bw" 'BEGIN { print (b == "" || a < b) ? a : b }')
        bc=$(awk -v a="$c" -v b="$bc" 'BEGIN { print (b == "" || a < b) ? a : b }')
    done
    echo "$bw $bc"
}

# Rays of the last run: `--stats` file if tpict wrote one with a "rays" field, else the last
# "N rays" report line on stderr.
last_rays() {
    local r=""
    if [[ -s "$TMP/stats.json" ]]; then
        r=$(grep -o '"rays"[^0-9]*[0-9]*' "$TMP/stats.json" | grep -o '[0-9]*$' | head -1 || true)
    fi
    if [[ -z "$r" ]]; then
        r=$(grep -o '[0-9]* rays' "$TMP/last.err" | tail -1 | awk '{ print $1 }' || true)
    fi
    echo "${r:-0}"
}

ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (b > 0) printf "%.2f", a / b; else print "-" }'; }

printf 'bench: %s, %sx%s, -ab 0, best of %s, %s cores, Radiance in %s\n' \
    "$("$TPICT" -version 2>/dev/null | head -1)" "$RES" "$RES" "$REPEAT" "$(nproc)" "$RADBIN" >&2

HDR="scene|ps|oconv s|rpict wall|rpict cpu|tpict1 wall|tpict1 cpu|wall ratio|cpu ratio|tpict2 wall|1->2 speed-up|tpict Mrays/s|rpict rays|tpict rays"
ROWS=()
[[ -n "${TSV:-}" ]] && echo "$HDR" | tr '|' '\t' >"$TSV"
for s in $SCENES; do
    def=$(scene_def "$s") || { echo "bench: unknown scene $s" >&2; exit 1; }
    IFS='|' read -r dir files view av <<<"$def"
    sdir="$ROOT/tests/scenes/$dir"
    read -r -a farr <<<"$files"
    oct="$TMP/$s.oct"
    # oconv must run in the scene's folder (relative includes, !genbox, ...).
    read -r ow _ < <(cd "$sdir" && time_cmd "$oct" "$TMP/oconv.err" oconv "${farr[@]}")
    for ps in $PS_LIST; do
        common=(-vf "$view" -x "$RES" -y "$RES" -ab 0 -av "$av" "$av" "$av")
        [[ $ps != default ]] && common+=(-ps "$ps")
        cd "$sdir"
        read -r rw rc < <(best_of "$REPEAT" "$RADBIN/rpict" -t 86400 "${common[@]}" "$oct")
        rrays=$(last_rays)
        read -r t1w t1c < <(best_of "$REPEAT" "$TPICT" -n 1 -t 86400 --stats "$TMP/stats.json" "${common[@]}" "${farr[@]}")
        trays=$(last_rays)
        read -r t2w _ < <(best_of "$REPEAT" "$TPICT" -n 2 "${common[@]}" "${farr[@]}")
        cd "$ROOT"
        mrs=$(awk -v r="$trays" -v t="$t1w" 'BEGIN { if (t > 0) printf "%.2f", r / t / 1e6; else print "-" }')
        row="$s|$ps|$ow|$rw|$rc|$t1w|$t1c|$(ratio "$rw" "$t1w")|$(ratio "$rc" "$t1c")|$t2w|$(ratio "$t1w" "$t2w")|$mrs|$rrays|$trays"
        ROWS+=("$row")
        echo "bench: $row" >&2
        [[ -n "${TSV:-}" ]] && echo "$row" | tr '|' '\t' >>"$TSV"
    done
done

# --- Table (Markdown) and geometric means ---------------------------------------------------
echo
echo "| ${HDR//|/ | } |"
echo "|$(echo "$HDR" | awk -F'|' '{ for (i = 1; i <= NF; i++) printf "---|" }')"
for r in "${ROWS[@]}"; do echo "| ${r//|/ | } |"; done
printf '%s\n' "${ROWS[@]}" | awk -F'|' '
    { n++; w += log($8); c += log($9); s += log($11) }
    END {
        if (n) printf "\ngeometric means over %d runs: rpict/tpict wall %.2f, cpu %.2f; tpict 1->2 threads speed-up %.2f\n", n, exp(w/n), exp(c/n), exp(s/n)
        print "targets: tpict >= 3x faster than rpict single-threaded; >= 1.9x speed-up from 1 to 2 threads"
    }'
