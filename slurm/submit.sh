#!/usr/bin/env bash
# Submit a Tessera job directory to SLURM: an array of N render workers (render.sbatch) and
# an assembly job (assemble.sbatch) that runs after all of them, whatever their exit status.
#
#   slurm/submit.sh JOBDIR [N] [extra sbatch options...]
#
#   JOBDIR   made by `tplan -o JOBDIR`; must be on a file system the compute nodes share
#   N        number of array tasks (workers), default 4 (or TESSERA_WORKERS)
#   extra    options given to both sbatch calls, e.g. --partition=batch --time=2:00:00
#
# Prints one line on stdout:  render_job=<id> assemble_job=<id>
# Logs: JOBDIR/logs/render-<jobid>_<task>.log and JOBDIR/logs/assemble-<jobid>.log.
#
# Environment (optional):
#   TESSERA_OUTPUT           picture the assembly writes (default JOBDIR/out/frame.hdr;
#                            use a %04d pattern for every frame of a multi-frame job)
#   TESSERA_BIN              folder holding tpiece, tmerge, tassemble, tstat (else PATH)
#   TESSERA_WORKERS          default for N
#   TESSERA_CPUS_PER_TASK    CPUs per render task = tpiece --threads. Unset (the default):
#                            each render task takes a whole node (--exclusive) and runs
#                            one tpiece with a tile loop per CPU, so N = nodes and each
#                            node holds the scene once (docs/batch.md, "Workers, threads
#                            and nodes"); set it (e.g. 1) to pack several workers per node
#   TESSERA_ARRAY_LIMIT      at most this many render tasks at once (sbatch --array=...%M)
#   TESSERA_AMB_FLUSH        passed to tpiece --amb-flush
#   TESSERA_PARTIAL=1        tassemble --partial
#   TESSERA_FORCE=1          tassemble --force (replace an existing picture)
#   TESSERA_SBATCH_TIMEOUT   seconds allowed for one sbatch call (default 120)
# The batch jobs inherit this environment (sbatch's default --export=ALL), which is how
# TESSERA_BIN, PATH and RAYPATH reach them; the job directory and output are passed as
# arguments. They run in the directory submit.sh was started from, so relative scene paths
# given to tplan resolve as they did there.
set -euo pipefail

PROG="submit.sh"
die() {
  echo "$PROG: error: $*" >&2
  exit 1
}
usage() {
  echo "usage: $PROG JOBDIR [N] [extra sbatch options...]" >&2
  exit 2
}

[ $# -ge 1 ] || usage
case "$1" in -h | --help) usage ;; esac
JOBDIR="$1"
shift
N="${TESSERA_WORKERS:-4}"
if [ $# -ge 1 ] && [[ "$1" =~ ^[0-9]+$ ]]; then
  N="$1"
  shift
fi
if ! [[ "$N" =~ ^[0-9]+$ ]] || [ "$N" -lt 1 ]; then
  die "N must be a positive number of workers, not '$N'"
fi

[ -d "$JOBDIR" ] || die "job directory '$JOBDIR' not found (create it with: tplan ... -o $JOBDIR -- ...)"
JOBDIR="$(cd "$JOBDIR" && pwd -P)"
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)"
RENDER="$HERE/render.sbatch"
ASSEMBLE="$HERE/assemble.sbatch"
if [ ! -r "$RENDER" ] || [ ! -r "$ASSEMBLE" ]; then
  die "render.sbatch / assemble.sbatch not found next to $0"
fi
command -v sbatch >/dev/null || die "sbatch not found on PATH (is this a SLURM submit host?)"

OUTPUT="${TESSERA_OUTPUT:-$JOBDIR/out/frame.hdr}"
case "$OUTPUT" in
  /*) ;;
  *) OUTPUT="$PWD/$OUTPUT" ;;
esac

if [ -n "${TESSERA_BIN:-}" ]; then
  for t in tpiece tmerge tassemble tstat; do
    [ -x "$TESSERA_BIN/$t" ] || die "TESSERA_BIN=$TESSERA_BIN has no executable $t"
  done
elif ! command -v tpiece >/dev/null; then
  echo "$PROG: warning: tpiece is not on PATH here; the compute nodes must have it (or set TESSERA_BIN)" >&2
fi

LOGS="$JOBDIR/logs"
mkdir -p "$LOGS" || die "cannot create $LOGS"

ARRAY="0-$((N - 1))"
if [ -n "${TESSERA_ARRAY_LIMIT:-}" ]; then
  ARRAY="$ARRAY%${TESSERA_ARRAY_LIMIT}"
fi
SBATCH_S="${TESSERA_SBATCH_TIMEOUT:-120}"

# sbatch --parsable prints "id" or "id;cluster".
submit() {
  local out
  out="$(timeout "$SBATCH_S" sbatch --parsable "$@")" || return 1
  out="${out%%;*}"
  [[ "$out" =~ ^[0-9]+$ ]] || {
    echo "$PROG: unexpected sbatch output: $out" >&2
    return 1
  }
  printf '%s\n' "$out"
}

if [ -n "${TESSERA_CPUS_PER_TASK:-}" ]; then
  PLACEMENT=(--cpus-per-task="$TESSERA_CPUS_PER_TASK")
else
  PLACEMENT=(--exclusive)
fi
RENDER_JOB="$(submit --array="$ARRAY" \
  "${PLACEMENT[@]}" \
  --output="$LOGS/render-%A_%a.log" \
  "$@" "$RENDER" "$JOBDIR")" || die "sbatch of the render array failed"

if ! ASSEMBLE_JOB="$(submit --dependency="afterany:$RENDER_JOB" \
  --output="$LOGS/assemble-%j.log" \
  "$@" "$ASSEMBLE" "$JOBDIR" "$OUTPUT")"; then
  timeout "$SBATCH_S" scancel "$RENDER_JOB" || true
  die "sbatch of the assembly job failed; cancelled render array $RENDER_JOB (finished tiles are kept in $JOBDIR)"
fi

echo "$PROG: render array $RENDER_JOB ($N tasks), assembly $ASSEMBLE_JOB -> $OUTPUT; logs in $LOGS" >&2
echo "render_job=$RENDER_JOB assemble_job=$ASSEMBLE_JOB"
