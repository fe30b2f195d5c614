#!/usr/bin/env bash
# The fuzz campaign (docs/robustness.md, "Fuzzing"): runs every target of tests/fuzz.rs for
# SECONDS each, one after another, under a memory limit so that an unbounded allocation is
# a finding too (the process aborts; the input it was running is kept).
# Usage: bash bench/fuzz.sh [SECONDS (default 600)] [TARGET ...]
# The target special-files runs bench/fuzz_special.sh (special files in a job directory).
# Environment: SEED (default: the clock), MEM_KB (virtual memory limit, default 8000000).
# Findings (inputs that panicked, hung for more than 10 s or aborted) are saved under
# target/fuzz-findings/; copy each into tests/fuzz-regressions/ with a test that refuses it.
set -uo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SECS=${1:-600}
shift || true
TARGETS=${*:-"scene options view rgbe exr amblog radambient manifest task-names cal octree mesh obj special-files"}
SEED=${SEED:-$(date +%s%3N)}
MEM_KB=${MEM_KB:-8000000}
cd "$ROOT" || exit 1
cargo build --release --test fuzz >&2 || exit 1
BIN=$(cargo test --release --test fuzz --no-run --message-format=json 2>/dev/null |
    sed -n 's/.*"executable":"\([^"]*fuzz-[^"]*\)".*/\1/p' | tail -1)
[[ -x "$BIN" ]] || { echo "fuzz.sh: no fuzz binary found" >&2; exit 1; }
# A private copy: rebuilding the tree during a long campaign does not change what runs.
COPY=$(mktemp "$ROOT/target/fuzz-bin.XXXXXX")
trap 'rm -f "$COPY"' EXIT
cp "$BIN" "$COPY" && chmod +x "$COPY" && BIN=$COPY
FIND=$ROOT/target/fuzz-findings
mkdir -p "$FIND"
status=0
for t in $TARGETS; do
    if [[ $t == special-files ]]; then
        # Special files in a job directory, against the tools themselves.
        SEED=$SEED MEM_KB=$MEM_KB bash "$ROOT/bench/fuzz_special.sh" "$SECS" || status=1
        continue
    fi
    out=$( (ulimit -v "$MEM_KB"; "$BIN" --seconds "$SECS" --target "$t" --seed "$SEED") 2>&1)
    rc=$?
    line=$(grep "^fuzz $t " <<<"$out" | tail -1)
    if [[ $rc -ne 0 ]]; then
        status=1
        keep="$FIND/$t-abort-$SEED.bin"
        [[ -f "$FIND/$t-current.bin" ]] && mv "$FIND/$t-current.bin" "$keep"
        echo "fuzz $t: exit $rc; last input kept as $keep"
        grep -v "^fuzz $t " <<<"$out" | tail -5
    fi
    [[ -n "$line" ]] && echo "$line"
done
exit $status
