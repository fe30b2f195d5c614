#!/usr/bin/env bash
# The job-directory part of the fuzz campaign (docs/robustness.md, "Special files"): for
# SECONDS, copy a small finished job, replace one of its files or folders, chosen at random,
# by a special file (a FIFO, a symbolic link to /dev/zero, to /dev/urandom or out of the
# job, a folder, an empty file, a file cut short), sometimes remove a tile so that workers
# have work, and run one of tpiece, tmerge, tassemble and tstat on it under a 20 s timeout
# and a virtual memory limit. A run that times out (a hang), panics or dies of a signal is a
# finding: its case is written to target/fuzz-findings/special-files-SEED.txt.
# Usage: bash bench/fuzz_special.sh [SECONDS (default 600)]
# Environment: SEED (default: the clock), MEM_KB (default 8000000).
set -uo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SECS=${1:-600}
SEED=${SEED:-$(date +%s)}
MEM_KB=${MEM_KB:-8000000}
cd "$ROOT" || exit 1
cargo build --release --bins >&2 || exit 1
T=$ROOT/target/release
WORK=$(mktemp -d)
trap 'chmod -R u+w "$WORK" 2>/dev/null; rm -rf "$WORK"' EXIT
FIND=$ROOT/target/fuzz-findings
mkdir -p "$FIND"
LOG=$FIND/special-files-$SEED.txt
: >"$LOG"

# A small finished job of the demo scene (-ab 1: logs and a merged store exist).
(cd demo && RAYPATH=. "$T/tplan" -o "$WORK/base" --tiles 6 --workers 2 -- \
    -vf demo.vf -x 48 -y 32 -ab 1 -ad 32 -as 0 demo.rad) >/dev/null 2>&1 || exit 1
"$T/tpiece" "$WORK/base" --threads 1 -q >/dev/null 2>&1 || exit 1
"$T/tmerge" "$WORK/base" >/dev/null 2>&1 || exit 1

RANDOM=$((SEED % 32768))
kinds=(fifo zero urandom outside folder empty cut)
tools=(tpiece tmerge tassemble tstat)
runs=0 hangs=0 panics=0 signals=0 refused=0
end=$((SECONDS + SECS))
while ((SECONDS < end)); do
    j=$WORK/j
    chmod -R u+w "$j" 2>/dev/null
    rm -rf "$j" "$WORK/out.hdr"
    cp -a "$WORK/base" "$j"
    mapfile -t paths < <(find "$j" -mindepth 1 | sort)
    target=${paths[RANDOM % ${#paths[@]}]}
    kind=${kinds[RANDOM % ${#kinds[@]}]}
    case $kind in
    cut)
        if [[ -f $target ]]; then
            size=$(stat -c %s "$target")
            truncate -s $((size > 0 ? RANDOM % size : 0)) "$target"
        fi
        ;;
    *)
        rm -rf "$target"
        case $kind in
        fifo) mkfifo "$target" ;;
        zero) ln -s /dev/zero "$target" ;;
        urandom) ln -s /dev/urandom "$target" ;;
        outside) ln -s /etc/passwd "$target" ;;
        folder) mkdir -p "$target" ;;
        empty) : >"$target" ;;
        esac
        ;;
    esac
    # Half the time, work for the workers: a tile to render again.
    if ((RANDOM % 2)); then
        tile=$(find "$j/tiles" -maxdepth 1 -name '*.tile' -type f 2>/dev/null | head -1)
        if [[ -n $tile ]]; then
            name=$(basename "$tile" .tile)
            rm -f "$tile" && mv "$j/tasks/$name.done" "$j/tasks/$name.todo" 2>/dev/null
        fi
    fi
    tool=${tools[RANDOM % ${#tools[@]}]}
    case $tool in
    tpiece) args=("$j" --threads 1 -q --no-wait) ;;
    tmerge) args=("$j") ;;
    tassemble) args=("$j" -o "$WORK/out.hdr") ;;
    tstat) args=("$j") ;;
    esac
    out=$( (ulimit -v "$MEM_KB"; timeout -s KILL 20 "$T/$tool" "${args[@]}") 2>&1 </dev/null)
    rc=$?
    runs=$((runs + 1))
    what="${target#"$j"/} as $kind, $tool"
    if ((rc == 137)); then
        hangs=$((hangs + 1))
        echo "hang: $what" >>"$LOG"
    elif grep -q "panicked" <<<"$out"; then
        panics=$((panics + 1))
        echo "panic: $what: $(grep -m1 panicked <<<"$out")" >>"$LOG"
    elif ((rc > 128)); then
        signals=$((signals + 1))
        echo "signal $((rc - 128)): $what" >>"$LOG"
    elif ((rc != 0)); then
        refused=$((refused + 1))
    fi
done
echo "fuzz special-files: $runs cases, $refused refused with an error, $panics panics," \
    "$hangs hangs, $signals signals (seed $SEED)"
[[ $((panics + hangs + signals)) -eq 0 ]]
