#!/usr/bin/env bash
# The README's quick start: render the demo scene through the batch pipeline on this machine
#   tplan -> N tpiece workers in parallel -> tmerge -> tassemble -> tstat
# Usage: bash demo/batch.sh [WORKERS (default 4)] [OUTPUT (default demo.hdr; .exr/.png work)]
# The job directory is demo-job/ (replaced if it is an earlier demo job).
set -euo pipefail
cd "$(dirname "$0")/.."
N="${1:-4}"
OUT="${2:-demo.hdr}"
JOB="${TESSERA_DEMO_JOB:-demo-job}"
case "$N" in '' | *[!0-9]* | 0) echo "batch.sh: WORKERS must be a positive integer" >&2; exit 2 ;; esac
echo "batch.sh: building the toolkit (cargo build --release; a few minutes the first time)" >&2
cargo build --release --bins
B="$PWD/target/release"
export RAYPATH=demo
if [ -e "$JOB" ]; then
  if [ -f "$JOB/manifest.json" ] && [ -d "$JOB/tasks" ]; then
    rm -rf "$JOB"
  else
    echo "batch.sh: $JOB exists and is not a Tessera job; not touching it" >&2
    exit 1
  fi
fi
"$B/tplan" --workers "$N" -o "$JOB" -- \
  -vf demo/demo.vf -x 640 -y 480 -ab 1 -av .02 .02 .02 demo/demo.rad
pids=()
for i in $(seq 1 "$N"); do
  "$B/tpiece" "$JOB" --worker-id "local-$i" --threads 1 --amb-flush auto -q &
  pids+=("$!")
done
status=0
for p in "${pids[@]}"; do wait "$p" || status=1; done
[ "$status" = 0 ] || { echo "batch.sh: a worker failed" >&2; exit 1; }
"$B/tmerge" "$JOB"
rm -f "$OUT"
"$B/tassemble" "$JOB" -o "$OUT"
"$B/tstat" "$JOB"
echo "batch.sh: wrote $OUT"
