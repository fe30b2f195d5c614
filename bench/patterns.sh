#!/usr/bin/env bash
# Speed of pattern-heavy scenes (docs/benchmarks.md, "Patterns and functions"): every
# surface of tests/scenes/patterns/{patterns,datapat}.rad carries a function or data
# pattern, texture or mixture. CPU seconds (user+sys, best of REPEAT) of `tpict -n 1`
# against `oconv` + `rpict` at the same settings, at -ab 0 and -ab 1, and the mean
# luminance of each picture.
# Usage: bash bench/patterns.sh   Environment: RES=1024, REPEAT=3, AB="0 1", PS="4 1"
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
NAME=patterns
source "$ROOT/bench/common.sh"
RES=${RES:-1024}
REPEAT=${REPEAT:-3}
AB=${AB:-"0 1"}
PS=${PS:-"4 1"}
work_dir
cd "$ROOT/tests/scenes/patterns"
best() { # best CMD...: smallest user+sys of REPEAT runs (stdout to $TMP/out.hdr)
    local b=""
    for _ in $(seq "$REPEAT"); do
        /usr/bin/time -f "%U %S" -o "$TMP/t" "$@" >"$TMP/out.hdr" 2>/dev/null
        local c
        c=$(awk '{ printf "%.3f", $1 + $2 }' "$TMP/t")
        if [[ -z $b ]] || awk -v a="$c" -v b="$b" 'BEGIN { exit !(a < b) }'; then b=$c; fi
    done
    echo "$b"
}
mean() { pvalue -h -H -d -b "$1" | awk '{ s += $1; n++ } END { printf "%.5f", s / n }'; }
printf 'scene\tps\tab\trpict_cpu_s\ttpict_cpu_s\tratio\trpict_mean\ttpict_mean\n'
for s in patterns datapat; do
  for ps in $PS; do
    for ab in $AB; do
        opts=(-vf patterns.vf -x "$RES" -y "$RES" -ps "$ps" -ab "$ab" -av .05 .05 .05)
        rc=$(best sh -c "oconv $s.rad > $TMP/s.oct && rpict ${opts[*]} $TMP/s.oct")
        rm=$(mean "$TMP/out.hdr")
        tc=$(best "$TPICT" -n 1 "${opts[@]}" "$s.rad")
        tm=$(mean "$TMP/out.hdr")
        ratio=$(awk -v a="$tc" -v b="$rc" 'BEGIN { printf "%.2f", a / b }')
        printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$s" "$ps" "$ab" "$rc" "$tc" "$ratio" "$rm" "$tm"
    done
  done
done
