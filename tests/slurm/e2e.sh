#!/usr/bin/env bash
# CI check: the demo scene rendered as a SLURM array job on a real single-node cluster
# (tests/slurm/cluster.sh) matches a single-process tpict render of the same view and options.
#
#   tests/slurm/cluster.sh install          # once (root; apt-get)
#   TESSERA_BIN=$PWD/target/release tests/slurm/e2e.sh
#
# Steps: start the cluster (stopped again on exit), tplan a 160x120 job, slurm/submit.sh it
# with 4 workers, wait (wall-clock deadline), check the assembled picture and compare it with
# `tpict` under the tests' tolerance (tests/slurm/picdiff.py: relative RMS <= 10% after
# halving both pictures, max <= 1.5, mean luminance within 2%); then a point job (a tgrid
# sensor grid, tplan --points, ttrace -I at -ab 0) through the same scripts, whose records
# must be byte-identical to one ttrace run.
#
# Environment:
#   TESSERA_BIN           folder with tplan, tpiece, tmerge, tassemble, tstat, tpict
#                         (default: target/release of this checkout)
#   TESSERA_RADIANCE_BIN  folder with Radiance's getinfo, pfilt, pvalue when not on PATH
#   TESSERA_E2E_TIMEOUT   seconds allowed from submission to both jobs done (default 180)
#   SLURM_CI_*            see tests/slurm/cluster.sh
set -euo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd -P)"
cd "$REPO"
PROG="e2e.sh"
WORKERS=4
DEADLINE_S="${TESSERA_E2E_TIMEOUT:-180}"
OPTS=(-vf demo/demo.vf -x 320 -y 240 -ab 1 -av .02 .02 .02)
SCENE=demo/demo.rad

now_ms() { date +%s%3N; }
secs() { # secs START_MS [END_MS] -> "1.23"
  local ms=$((${2:-$(now_ms)} - $1))
  printf '%d.%02d' $((ms / 1000)) $((ms % 1000 / 10))
}
T_ALL="$(now_ms)"
TIMINGS=()
timing() { TIMINGS+=("$(printf '%-28s %7ss' "$1" "$2")"); }

die() {
  echo "$PROG: FAIL: $*" >&2
  exit 1
}

# --- tools --------------------------------------------------------------------------------
BIN="${TESSERA_BIN:-$REPO/target/release}"
[ -d "$BIN" ] || die "TESSERA_BIN=$BIN is not a folder (build with: cargo build --release)"
BIN="$(cd "$BIN" && pwd -P)"
for t in tplan tpiece tmerge tassemble tstat tpict ttrace tgrid; do
  [ -x "$BIN/$t" ] || die "$BIN/$t missing (build with: cargo build --release)"
done
export TESSERA_BIN="$BIN"

if ! command -v pvalue >/dev/null; then
  for d in "${TESSERA_RADIANCE_BIN:-}" /opt/radvenv/lib/python3.11/site-packages/pyradiance/bin; do
    if [ -n "$d" ] && [ -x "$d/pvalue" ]; then
      PATH="$d:$PATH"
      break
    fi
  done
fi
for t in getinfo pfilt pvalue python3 timeout; do
  command -v "$t" >/dev/null || die "$t not found on PATH (Radiance: set TESSERA_RADIANCE_BIN)"
done
# The demo scene's !xform commands find their files through RAYPATH.
export RAYPATH="$REPO/demo:${RAYPATH:-.}"

WORK="$(mktemp -d "${TMPDIR:-/tmp}/tessera-slurm-e2e.XXXXXX")"
JOB="$WORK/job"
PICTURE="$WORK/out/demo.hdr"
REFERENCE="$WORK/reference.hdr"
CLUSTER="$REPO/tests/slurm/cluster.sh"

diagnostics() {
  echo "== diagnostics (work folder kept: $WORK)" >&2
  if [ -n "${RENDER_JOB:-}" ]; then
    timeout 20 squeue --states=all -j "$RENDER_JOB,$ASSEMBLE_JOB" -o '%i %j %T %r %e' >&2 || true
  fi
  local f
  for f in "$JOB"/logs/*.log; do
    [ -e "$f" ] || continue
    echo "--- $f" >&2
    tail -n 40 "$f" >&2 || true
  done
  bash "$CLUSTER" status >&2 || true
  if [ -n "${SLURM_CONF:-}" ]; then
    f="$(dirname "$SLURM_CONF")/log/slurmctld.log"
    if [ -s "$f" ]; then
      echo "--- $f" >&2
      tail -n 20 "$f" >&2 || true
    fi
  fi
}

on_exit() {
  local rc=$?
  trap - EXIT
  [ "$rc" = 0 ] || diagnostics
  local t
  t="$(now_ms)"
  bash "$CLUSTER" stop || echo "$PROG: warning: cluster.sh stop failed" >&2
  timing "cluster stop" "$(secs "$t")"
  timing "total" "$(secs "$T_ALL")"
  echo "== timings"
  printf '%s\n' "${TIMINGS[@]}"
  if [ "$rc" = 0 ]; then
    rm -rf "$WORK"
    echo "$PROG: passed"
  else
    echo "$PROG: FAILED (exit $rc)" >&2
  fi
  exit "$rc"
}
trap on_exit EXIT

# --- cluster ------------------------------------------------------------------------------
echo "== start the SLURM cluster"
t="$(now_ms)"
eval "$(bash "$CLUSTER" env)"
bash "$CLUSTER" start
timing "cluster start" "$(secs "$t")"

# --- plan and submit ------------------------------------------------------------------------
echo "== tplan ($WORKERS workers)"
t="$(now_ms)"
# Many tiles (80 per worker): the default plan gives this cheap frame a handful, and task 0
# must hold a claim long enough to be requeued mid-render.
"$BIN/tplan" --workers "$WORKERS" --tiles $((80 * WORKERS)) --lease 10 -o "$JOB" -- "${OPTS[@]}" "$SCENE"
[ -d "$JOB" ] || die "tplan did not create $JOB"
timing "tplan" "$(secs "$t")"

echo "== submit"
t_submit="$(now_ms)"
# Four single-CPU workers on the two-CPU node, so that task 0 can be requeued while the
# others render (the default, one exclusive node per task, would run them one by one).
ids="$(TESSERA_CPUS_PER_TASK=1 TESSERA_OUTPUT="$PICTURE" bash slurm/submit.sh "$JOB" "$WORKERS")" || die "slurm/submit.sh failed"
echo "$ids"
re='render_job=([0-9]+) assemble_job=([0-9]+)'
[[ "$ids" =~ $re ]] || die "cannot parse submit.sh output: $ids"
RENDER_JOB="${BASH_REMATCH[1]}"
ASSEMBLE_JOB="${BASH_REMATCH[2]}"

# --- requeue one task while it renders ---------------------------------------------------
# As SLURM does on node failure or preemption (the tasks are submitted with --requeue): task
# 0 is killed mid-render and queued again under the same array index; its new run takes
# over its predecessor's tile at once (same worker id), or, while it waits for a CPU, the
# other tasks re-claim that tile after the lease (10 s here: the node has 2 CPUs, so the
# requeued task may only start when the others end); the picture must come out whole.
echo "== requeue task ${RENDER_JOB}_0 while it renders"
t="$(now_ms)"
deadline=$((SECONDS + DEADLINE_S))
while :; do
  st="$(timeout 20 squeue -h -j "${RENDER_JOB}_0" -o %T 2>/dev/null || true)"
  if [ "$st" = RUNNING ] && compgen -G "$JOB/tasks/*.claim.${RENDER_JOB}-0.*" >/dev/null; then
    break
  fi
  case "$st" in
    COMPLETED | FAILED | CANCELLED) die "task ${RENDER_JOB}_0 ended ($st) before it could be requeued" ;;
  esac
  [ "$SECONDS" -lt "$deadline" ] || die "task ${RENDER_JOB}_0 never held a tile"
  sleep 0.1
done
timeout 20 scontrol requeue "${RENDER_JOB}_0" || die "scontrol requeue ${RENDER_JOB}_0 failed"
# SLURM holds a requeued job back (reason BeginTime) for a while: release it.
for _ in $(seq 1 100); do
  st="$(timeout 20 squeue -h -j "${RENDER_JOB}_0" -o '%T %r' 2>/dev/null || true)"
  case "$st" in
    "PENDING BeginTime"*)
      timeout 20 scontrol update JobId="${RENDER_JOB}_0" StartTime=now && break
      ;;
    RUNNING* | COMPLETED*) break ;;
  esac
  sleep 0.1
done
timing "requeue" "$(secs "$t")"

# --- wait ---------------------------------------------------------------------------------
# squeue prints nothing both when the jobs are gone and when it fails (slurmctld down), so
# its exit status decides; only "Invalid job id" (record purged) means gone.
wait_jobs() { # wait_jobs JOBIDS (comma-separated)
  echo "== wait for jobs $1, at most ${DEADLINE_S}s"
  local deadline=$((SECONDS + DEADLINE_S)) last="" q now rc
  while :; do
    if q="$(timeout 20 squeue -h -j "$1" -o '%i %T' 2>&1)"; then
      [ -n "$q" ] || break
    else
      rc=$?
      case "$q" in
        *"Invalid job id"*) break ;;
        *) die "squeue failed (exit $rc): $q" ;;
      esac
    fi
    now="$(echo "$q" | tr '\n' ' ')"
    if [ "$now" != "$last" ]; then
      echo "  $((SECONDS - deadline + DEADLINE_S))s: $now"
      last="$now"
    fi
    [ "$SECONDS" -lt "$deadline" ] || die "jobs not done after ${DEADLINE_S}s: $now"
    sleep 1
  done
}
wait_jobs "$RENDER_JOB,$ASSEMBLE_JOB"
timing "submit -> jobs done" "$(secs "$t_submit")"

states="$(timeout 20 squeue --states=all -h -j "$RENDER_JOB,$ASSEMBLE_JOB" -o '%i %T %e')" ||
  die "squeue --states=all failed"
echo "$states"
assemble_state="$(timeout 20 squeue --states=all -h -j "$ASSEMBLE_JOB" -o %T)" ||
  die "squeue --states=all -j $ASSEMBLE_JOB failed"
[ "$assemble_state" = COMPLETED ] || die "assembly job $ASSEMBLE_JOB is $assemble_state, not COMPLETED"
while read -r id state _; do
  [ "$state" = COMPLETED ] || die "render task $id is $state"
done < <(timeout 20 squeue --states=all -h -j "$RENDER_JOB" -o '%i %T')

# The requeued task ran twice (its log is appended to) and its second run finished.
LOG0="$JOB/logs/render-${RENDER_JOB}_0.log"
grep -q 'restart 1' "$LOG0" || die "task ${RENDER_JOB}_0 was not restarted (see $LOG0)"
echo "task ${RENDER_JOB}_0 was requeued and ran again:"
grep 'render.sbatch:' "$LOG0"

echo "== assembly log"
cat "$JOB"/logs/assemble-"$ASSEMBLE_JOB".log
[ -s "$PICTURE" ] || die "assembled picture $PICTURE missing or empty"
getinfo -d "$PICTURE"

# --- compare with a single-process render ---------------------------------------------------
echo "== reference: tpict ${OPTS[*]} $SCENE"
t="$(now_ms)"
"$BIN/tpict" "${OPTS[@]}" "$SCENE" >"$REFERENCE" || die "tpict failed"
timing "tpict reference" "$(secs "$t")"

echo "== compare"
t="$(now_ms)"
python3 tests/slurm/picdiff.py "$PICTURE" "$REFERENCE" ||
  die "the SLURM picture differs from tpict's beyond the tests' tolerance"
timing "compare" "$(secs "$t")"

# --- a point job through the same scripts ---------------------------------------------------
# A sensor grid (tgrid) as a job over rays (tplan --points), run by slurm/submit.sh
# unchanged; at -ab 0 its records are byte-identical to one ttrace run.
echo "== point job: tgrid, tplan --points, slurm/submit.sh; against one ttrace -I run"
t="$(now_ms)"
"$BIN/tgrid" --rect -1.5 -1.5 1.5 1.5 --spacing 0.1 --height 0.5 >"$WORK/points.txt"
PJOB="$WORK/pjob"
"$BIN/tplan" --points "$WORK/points.txt" --chunk 100 --workers 2 -o "$PJOB" -- -I -h- -ab 0 "$SCENE"
ids="$(TESSERA_CPUS_PER_TASK=1 TESSERA_OUTPUT="$WORK/out/points.dat" bash slurm/submit.sh "$PJOB" 2)" ||
  die "slurm/submit.sh failed on the point job"
echo "$ids"
[[ "$ids" =~ $re ]] || die "cannot parse submit.sh output: $ids"
RENDER_JOB="${BASH_REMATCH[1]}"
ASSEMBLE_JOB="${BASH_REMATCH[2]}"
JOB="$PJOB"
wait_jobs "$RENDER_JOB,$ASSEMBLE_JOB"
assemble_state="$(timeout 20 squeue --states=all -h -j "$ASSEMBLE_JOB" -o %T)" ||
  die "squeue --states=all -j $ASSEMBLE_JOB failed"
[ "$assemble_state" = COMPLETED ] || die "point assembly job $ASSEMBLE_JOB is $assemble_state"
"$BIN/ttrace" -I -h- -ab 0 "$SCENE" <"$WORK/points.txt" >"$WORK/points.ref" || die "ttrace failed"
cmp "$WORK/out/points.dat" "$WORK/points.ref" ||
  die "the point job's records differ from ttrace's"
echo "$(wc -l <"$WORK/points.ref") records, byte-identical to ttrace's"
timing "point job" "$(secs "$t")"
