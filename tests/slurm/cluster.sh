#!/usr/bin/env bash
# A real single-node SLURM cluster (munged + slurmctld + slurmd from Debian's packages) for
# Tessera's CI and for trying the batch scripts on one machine. Needs root; no systemd.
#
#   tests/slurm/cluster.sh install   apt-get install the packages (skipped when present)
#   tests/slurm/cluster.sh start     write the config, start the daemons, wait until the node is idle
#   tests/slurm/cluster.sh stop      cancel all jobs, stop the daemons this script started
#   tests/slurm/cluster.sh env       print `export SLURM_CONF=...` (use: eval "$(... env)")
#   tests/slurm/cluster.sh status    show the daemons, sinfo and squeue; exit 0 only when up
#
# Every subcommand is idempotent. Only processes whose pid this script recorded are signalled,
# and only after /proc/PID/comm confirms the name (pid reuse). Every SLURM client call runs
# under `timeout`, every wait has a wall-clock deadline.
#
# Environment (all optional):
#   SLURM_CI_DIR             config, state, spool, logs and pid files (default /tmp/tessera-slurm)
#   SLURM_CI_TIMEOUT         seconds to wait for a daemon or for the queue to drain (default 60)
#   SLURM_CI_CLIENT_TIMEOUT  seconds for one SLURM client command (default 20)
#   SLURM_CI_CTLD_PORT       slurmctld port (default 6817)
#   SLURM_CI_SLURMD_PORT     slurmd port (default 6818)
set -euo pipefail

DIR="${SLURM_CI_DIR:-/tmp/tessera-slurm}"
WAIT_S="${SLURM_CI_TIMEOUT:-60}"
CLIENT_S="${SLURM_CI_CLIENT_TIMEOUT:-20}"
CTLD_PORT="${SLURM_CI_CTLD_PORT:-6817}"
SLURMD_PORT="${SLURM_CI_SLURMD_PORT:-6818}"
CONF="$DIR/slurm.conf"
RUN="$DIR/run"
LOG="$DIR/log"
PACKAGES=(slurmctld slurmd slurm-client munge)
MUNGE_SOCKET=/run/munge/munge.socket.2
MUNGE_KEY=/etc/munge/munge.key
PROG="$(basename "$0")"

export SLURM_CONF="$CONF"
# The daemons and runuser live in sbin, which a plain user's PATH (or env -i) may lack.
export PATH="$PATH:/usr/sbin:/sbin"

say() { printf '%s: %s\n' "$PROG" "$*" >&2; }
die() {
  say "error: $*"
  exit 1
}

now_ms() { date +%s%3N; }
took() { # took START_MS -> "1.23s"
  local ms=$(($(now_ms) - $1))
  printf '%d.%02ds' $((ms / 1000)) $((ms % 1000 / 10))
}

need_root() {
  [ "$(id -u)" = 0 ] || die "'$1' must run as root (it installs packages and starts daemons as root)"
}

# A SLURM (or munge) client command, never allowed to hang.
client() { timeout "$CLIENT_S" "$@"; }

short_host() {
  local h
  h="$(uname -n)"
  printf '%s\n' "${h%%.*}"
}

# our_pid NAME PIDFILE: print the pid in PIDFILE if that process is alive (not a zombie) and
# its /proc/PID/comm is NAME; fail otherwise.
our_pid() {
  local name="$1" file="$2" pid comm stat rest
  [ -r "$file" ] || return 1
  read -r pid <"$file" || [ -n "${pid:-}" ] || return 1
  [[ "$pid" =~ ^[0-9]+$ ]] || return 1
  comm="$(cat "/proc/$pid/comm" 2>/dev/null)" || return 1
  [ "$comm" = "$name" ] || return 1
  stat="$(cat "/proc/$pid/stat" 2>/dev/null)" || return 1
  rest="${stat##*) }"
  [ "${rest%% *}" != Z ] || return 1
  printf '%s\n' "$pid"
}

# Run a daemon that forks into the background: stdio on /dev/null and no inherited
# descriptors beyond 0-2, so it never holds a CI pipe open.
detached() {
  (
    local fd
    for fd in /proc/self/fd/*; do
      fd="${fd##*/}"
      if [ "$fd" -gt 2 ]; then
        exec {fd}>&- 2>/dev/null || true
      fi
    done
    exec "$@" </dev/null >/dev/null 2>&1
  )
}

# wait_until DESCRIPTION SECONDS COMMAND...: poll COMMAND every 0.25 s until it succeeds.
wait_until() {
  local what="$1" limit="$2"
  shift 2
  local deadline=$((SECONDS + limit))
  while ! "$@"; do
    if [ "$SECONDS" -ge "$deadline" ]; then
      say "timed out after ${limit}s waiting for $what"
      return 1
    fi
    sleep 0.25
  done
}

# signal_and_wait NAME PIDFILE: SIGTERM our process, SIGKILL it if it outlives the deadline.
signal_and_wait() {
  local name="$1" file="$2" pid
  pid="$(our_pid "$name" "$file")" || return 0
  say "stopping $name (pid $pid)"
  kill -TERM "$pid" 2>/dev/null || true
  if ! wait_until "$name to exit" 15 not_alive "$name" "$file"; then
    if pid="$(our_pid "$name" "$file")"; then
      kill -KILL "$pid" 2>/dev/null || true
    fi
    wait_until "$name to exit after SIGKILL" 5 not_alive "$name" "$file" || true
  fi
}

not_alive() { ! our_pid "$1" "$2" >/dev/null; }

tail_logs() {
  local f
  for f in "$LOG/slurmctld.log" "$LOG/slurmd.log"; do
    if [ -s "$f" ]; then
      say "last lines of $f:"
      tail -n 25 "$f" >&2 || true
    fi
  done
}

# --- install ----------------------------------------------------------------------------------

packages_missing() {
  local p status
  for p in "${PACKAGES[@]}"; do
    status="$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)"
    if [ "$status" != "install ok installed" ]; then
      printf '%s\n' "$p"
    fi
  done
}

POLICY_RC=/usr/sbin/policy-rc.d
POLICY_RC_OURS=0
remove_policy_rc() {
  if [ "$POLICY_RC_OURS" = 1 ]; then
    rm -f "$POLICY_RC"
    POLICY_RC_OURS=0
  fi
}

ensure_munge_key() {
  [ -s "$MUNGE_KEY" ] && return 0
  say "creating $MUNGE_KEY"
  install -d -o munge -g munge -m 0700 "$(dirname "$MUNGE_KEY")"
  if ! mungekey --create --keyfile="$MUNGE_KEY" >/dev/null 2>&1; then
    dd if=/dev/urandom of="$MUNGE_KEY" bs=1024 count=1 status=none
  fi
  chown munge:munge "$MUNGE_KEY"
  chmod 0600 "$MUNGE_KEY"
}

cmd_install() {
  need_root install
  local t0 missing
  t0="$(now_ms)"
  mapfile -t missing < <(packages_missing)
  if [ "${#missing[@]}" -eq 0 ]; then
    say "packages already installed: ${PACKAGES[*]}"
  else
    say "installing ${missing[*]}"
    command -v apt-get >/dev/null || die "apt-get not found: this script supports Debian/Ubuntu only"
    # No package may start a daemon (there is no init system here anyway).
    if [ ! -e "$POLICY_RC" ]; then
      printf '#!/bin/sh\nexit 101\n' >"$POLICY_RC"
      chmod 0755 "$POLICY_RC"
      POLICY_RC_OURS=1
      trap remove_policy_rc EXIT
    fi
    timeout 600 apt-get update -qq || die "apt-get update failed"
    DEBIAN_FRONTEND=noninteractive timeout 900 apt-get install -y -qq --no-install-recommends \
      "${PACKAGES[@]}" >/dev/null || die "apt-get install ${PACKAGES[*]} failed"
    remove_policy_rc
    mapfile -t missing < <(packages_missing)
    [ "${#missing[@]}" -eq 0 ] || die "still missing after apt-get install: ${missing[*]}"
  fi
  getent passwd munge >/dev/null || die "user 'munge' missing (the munge package creates it)"
  ensure_munge_key
  say "install done ($(took "$t0"))"
}

# --- start ------------------------------------------------------------------------------------

munge_works() { client munge -n </dev/null 2>/dev/null | client unmunge >/dev/null 2>&1; }

start_munge() {
  if munge_works; then
    if our_pid munged "$RUN/munged.pid" >/dev/null; then
      say "munged already running (started by this script)"
    else
      say "using the munged already answering on $MUNGE_SOCKET (will not stop it)"
    fi
    return 0
  fi
  ensure_munge_key
  install -d -o munge -g munge -m 0755 /run/munge
  # munged refuses to run as root ("Logfile is insecure"): run it as its own user.
  detached runuser -u munge -- /usr/sbin/munged --force ||
    die "munged failed to start (see /var/log/munge/munged.log)"
  wait_until "munged to answer" "$WAIT_S" munge_works ||
    die "munged does not answer (see /var/log/munge/munged.log)"
  local pid
  pid="$(our_pid munged /run/munge/munged.pid)" ||
    die "munged answers but /run/munge/munged.pid does not name a munged process"
  # Our own record: only a munged listed here is ever stopped by this script.
  printf '%s\n' "$pid" >"$RUN/munged.pid"
  say "munged started (pid $pid)"
}

write_config() {
  local host="$1" topo="" mem_kb real_mb line
  # Topology as slurmd detects it (so slurmd never sees a mismatch).
  line="$(slurmd -C 2>/dev/null | head -n 1 || true)"
  local f
  for f in $line; do
    case "$f" in
      CPUs=* | Boards=* | SocketsPerBoard=* | CoresPerSocket=* | ThreadsPerCore=*) topo="$topo $f" ;;
    esac
  done
  [ -n "$topo" ] || topo=" CPUs=$(nproc)"
  # 90% of MemTotal: more than slurmd sees would drain the node ("Low RealMemory").
  mem_kb="$(awk '/^MemTotal:/ {print $2}' /proc/meminfo)"
  real_mb=$((mem_kb * 9 / 10 / 1024))
  cat >"$CONF.tmp" <<EOF
# Written by Tessera's tests/slurm/cluster.sh: one node, no cgroups, no accounting, runs as root.
ClusterName=tessera
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$RUN/slurmctld.pid
SlurmdPidFile=$RUN/slurmd.pid
SlurmctldLogFile=$LOG/slurmctld.log
SlurmdLogFile=$LOG/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$LOG/jobcomp.log
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0
DependencyParameters=kill_invalid_depend
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
KillWait=5
Waittime=0
MinJobAge=3600
NodeName=$host NodeAddr=127.0.0.1$topo RealMemory=$real_mb State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  mv "$CONF.tmp" "$CONF"
}

ctld_up() { client scontrol ping 2>/dev/null | grep -q 'is UP'; }

node_state() { client sinfo -h -n "$1" -o %T 2>/dev/null | head -n 1; }

node_ready() {
  case "$(node_state "$1")" in
    idle | mixed | allocated | completing) return 0 ;;
    *) return 1 ;;
  esac
}

cmd_start() {
  need_root start
  local t0 host
  t0="$(now_ms)"
  for b in slurmctld slurmd sinfo scontrol munged munge unmunge; do
    command -v "$b" >/dev/null || [ -x "/usr/sbin/$b" ] ||
      die "$b not found: run '$0 install' first"
  done
  host="$(short_host)"
  mkdir -p "$DIR/state" "$DIR/spool" "$LOG" "$RUN"
  start_munge

  if our_pid slurmctld "$RUN/slurmctld.pid" >/dev/null && our_pid slurmd "$RUN/slurmd.pid" >/dev/null; then
    say "slurmctld and slurmd already running"
  else
    # Half a cluster (one daemon died): restart both from a consistent state.
    signal_and_wait slurmd "$RUN/slurmd.pid"
    signal_and_wait slurmctld "$RUN/slurmctld.pid"
    # A fresh cluster each time: no jobs or node states left over from an earlier run
    # (after a crash they would be recovered as running).
    rm -rf "$DIR/state" "$DIR/spool"
    mkdir -p "$DIR/state" "$DIR/spool"
    write_config "$host"
    # -i: start even when the state files are missing or unreadable.
    detached slurmctld -i || { tail_logs; die "slurmctld failed to start"; }
    if ! wait_until "slurmctld to answer 'scontrol ping'" "$WAIT_S" ctld_up; then
      tail_logs
      cmd_stop_quiet
      die "slurmctld did not come up (is port $CTLD_PORT free?)"
    fi
    detached slurmd -N "$host" || { tail_logs; cmd_stop_quiet; die "slurmd failed to start"; }
  fi
  if ! wait_until "node $host to be idle" "$WAIT_S" node_ready "$host"; then
    local st
    st="$(node_state "$host")"
    case "$st" in
      down* | drain* | fail*)
        say "node $host is '$st': resuming it"
        client scontrol update NodeName="$host" State=RESUME || true
        ;;
    esac
    if ! wait_until "node $host to be idle" 10 node_ready "$host"; then
      tail_logs
      cmd_stop_quiet
      die "node $host is '$(node_state "$host")', not idle"
    fi
  fi
  client sinfo >&2 || true
  say "cluster up ($(took "$t0")); clients need: $(cmd_env)"
}

# --- stop -------------------------------------------------------------------------------------

queue_empty() {
  local out
  out="$(client squeue -h -o %i 2>&1)" || return 1
  [ -z "$out" ]
}

cancel_all_jobs() {
  local ids
  # %F: an array's base job id (or the job id), so one scancel covers all tasks.
  ids="$(client squeue -h -o %F 2>/dev/null | sort -u | tr '\n' ' ')" || return 0
  if [ -n "${ids// /}" ]; then
    say "cancelling jobs: $ids"
    # shellcheck disable=SC2086 # word splitting of the id list is intended
    client scancel $ids || true
    wait_until "the queue to drain" "$WAIT_S" queue_empty || true
  fi
}

cmd_stop_quiet() {
  local ctld
  if ctld="$(our_pid slurmctld "$RUN/slurmctld.pid")"; then
    cancel_all_jobs
    say "scontrol shutdown (slurmctld pid $ctld)"
    client scontrol shutdown >/dev/null 2>&1 || true
    wait_until "slurmctld and slurmd to exit" 20 both_gone || true
  fi
  signal_and_wait slurmd "$RUN/slurmd.pid"
  signal_and_wait slurmctld "$RUN/slurmctld.pid"
  reap_stepds
  signal_and_wait munged "$RUN/munged.pid"
  rm -f "$RUN/munged.pid"
}

both_gone() { not_alive slurmctld "$RUN/slurmctld.pid" && not_alive slurmd "$RUN/slurmd.pid"; }

# slurmstepd processes of THIS cluster: they hold our slurmd.log open. Normally none are left
# (jobs are cancelled first), but when slurmctld died they keep waiting for it.
our_stepds() {
  local p fd comm
  for p in /proc/[0-9]*; do
    comm=""
    { read -r comm <"$p/comm"; } 2>/dev/null || continue
    [ "$comm" = slurmstepd ] || continue
    for fd in "$p"/fd/*; do
      if [ "$(readlink "$fd" 2>/dev/null)" = "$LOG/slurmd.log" ]; then
        printf '%s\n' "${p#/proc/}"
        break
      fi
    done
  done
}

# All descendants of the given pids (their job scripts and what those started).
descendants() {
  local -A kids=()
  local p stat rest ppid
  for p in /proc/[0-9]*; do
    stat=""
    { read -r stat <"$p/stat"; } 2>/dev/null || continue
    rest="${stat##*) }"
    rest="${rest#* }"
    ppid="${rest%% *}"
    kids[$ppid]+="${p#/proc/} "
  done
  local queue=("$@") next
  while [ "${#queue[@]}" -gt 0 ]; do
    next="${queue[0]}"
    queue=("${queue[@]:1}")
    for p in ${kids[$next]:-}; do
      printf '%s\n' "$p"
      queue+=("$p")
    done
  done
}

no_stepds() { [ -z "$(our_stepds)" ]; }

# A finished step's slurmstepd lingers ~1 s; one whose slurmctld died waits for it forever
# and ignores SIGTERM. Their jobs' processes get SIGTERM, the slurmstepds SIGKILL.
reap_stepds() {
  wait_until "slurmstepd processes to exit" 3 no_stepds 2>/dev/null && return 0
  local stepds pids
  mapfile -t stepds < <(our_stepds)
  [ "${#stepds[@]}" -gt 0 ] || return 0
  mapfile -t pids < <(descendants "${stepds[@]}")
  say "stopping leftover slurmstepd ${stepds[*]} and their jobs' processes: ${pids[*]:-none}"
  if [ "${#pids[@]}" -gt 0 ]; then
    kill -TERM "${pids[@]}" 2>/dev/null || true
    sleep 1
    # Whatever is still below them (looked up again: pids that exited are not reused here).
    mapfile -t pids < <(descendants "${stepds[@]}")
    if [ "${#pids[@]}" -gt 0 ]; then
      kill -KILL "${pids[@]}" 2>/dev/null || true
    fi
  fi
  kill -KILL "${stepds[@]}" 2>/dev/null || true
  wait_until "slurmstepd processes to exit" 5 no_stepds || true
}

cmd_stop() {
  need_root stop
  local t0
  t0="$(now_ms)"
  if [ ! -d "$RUN" ]; then
    say "not running (no $RUN)"
    return 0
  fi
  cmd_stop_quiet
  say "stopped ($(took "$t0"))"
}

# --- env, status ------------------------------------------------------------------------------

cmd_env() { printf 'export SLURM_CONF=%q\n' "$CONF"; }

cmd_status() {
  local up=0 name pid
  for name in munged slurmctld slurmd; do
    if pid="$(our_pid "$name" "$RUN/$name.pid")"; then
      echo "$name: running (pid $pid)"
    elif [ "$name" = munged ] && munge_works; then
      echo "munged: running (not started by this script)"
    else
      echo "$name: not running"
      [ "$name" = munged ] || up=1
    fi
  done
  echo "SLURM_CONF=$CONF"
  if [ "$up" = 0 ] && ctld_up; then
    client sinfo || true
    client squeue || true
    return 0
  fi
  return 3
}

case "${1:-}" in
  install) cmd_install ;;
  start) cmd_start ;;
  stop) cmd_stop ;;
  env) cmd_env ;;
  status) cmd_status ;;
  *)
    echo "usage: $PROG install|start|stop|env|status" >&2
    exit 2
    ;;
esac
