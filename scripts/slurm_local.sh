#!/usr/bin/env bash
# A one-machine Slurm cluster from Debian's packages (munge, slurmctld,
# slurmd, slurm-client), for the sweep tests and for trying `millcharge sweep
# run --slurm` without a cluster. Everything lives in DIR: its own munge key
# and socket, slurm.conf, state, spool, logs and pid files; nothing in /etc
# or /run is touched.
#
#   scripts/slurm_local.sh start DIR   start munged, slurmctld and slurmd; wait
#                                      until the node takes jobs; print the line
#                                      `export SLURM_CONF=DIR/slurm.conf`
#   scripts/slurm_local.sh stop DIR    cancel DIR's jobs, stop the daemons
#
# The clients (sbatch, squeue, scancel, scontrol) find this cluster through
# SLURM_CONF. It needs root: slurmd starts each job as its user. It fails
# with a message and status 1 when it cannot start the cluster; it never
# pretends to have one.
set -euo pipefail

usage() { echo "usage: $0 start|stop DIR" >&2; exit 2; }
[ $# -eq 2 ] || usage
action=$1
dir=$2
fail() { echo "slurm_local: $*" >&2; exit 1; }

pid_of() { [ -s "$1" ] && cat "$1" || true; }

# Stops the process whose id is in pid file $1 (one this script started):
# SIGTERM, then SIGKILL after $2 seconds.
stop_pid() {
  local pid
  pid=$(pid_of "$1")
  [ -n "$pid" ] || return 0
  kill -TERM "$pid" 2>/dev/null || { rm -f "$1"; return 0; }
  for _ in $(seq 1 $(( $2 * 10 ))); do
    kill -0 "$pid" 2>/dev/null || { rm -f "$1"; return 0; }
    sleep 0.1
  done
  kill -KILL "$pid" 2>/dev/null || true
  rm -f "$1"
}

logs() {
  for f in "$dir"/log/*.log; do
    [ -f "$f" ] || continue
    echo "---- $f (last lines)" >&2
    tail -n 15 "$f" >&2
  done
}

# A TCP port nothing listens on (two clusters, or a system Slurm on the
# default 6817/6818, must not collide).
free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

start() {
  [ "$(id -u)" -eq 0 ] || fail "needs root: slurmd starts each job as its user (run as root, as CI does)"
  local missing=()
  for cmd in munged mungekey slurmctld slurmd sbatch squeue scontrol scancel python3; do
    command -v "$cmd" >/dev/null || missing+=("$cmd")
  done
  [ ${#missing[@]} -eq 0 ] ||
    fail "missing ${missing[*]}: install Debian's munge, slurmctld, slurmd and slurm-client (bash scripts/setup.sh does)"
  [ ! -e "$dir/slurm.conf" ] || fail "$dir already holds a cluster (stop it first: $0 stop $dir)"

  mkdir -p "$dir"
  dir=$(cd "$dir" && pwd)
  # munged wants the key private, and the socket's folders open to all
  # (execute) but writable by no one else.
  mkdir -p "$dir/munge" "$dir/socket" "$dir/state" "$dir/spool" "$dir/log" "$dir/run"
  chmod 0755 "$dir" "$dir/socket"
  chmod 0700 "$dir/munge"
  mungekey --create --keyfile="$dir/munge/munge.key" >/dev/null 2>&1 ||
    fail "mungekey could not create $dir/munge/munge.key"
  chmod 0600 "$dir/munge/munge.key"
  munged --socket="$dir/socket/munge.socket" --key-file="$dir/munge/munge.key" \
    --pid-file="$dir/run/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munged.seed" ||
    { logs; fail "munged did not start (log above)"; }

  local cpus mem_mb ctl_port node_port
  cpus=$(nproc)
  # Half the memory: a node that reports less than its slurm.conf is drained.
  mem_mb=$(awk '/^MemTotal:/ { print int($2 / 1024 / 2) }' /proc/meminfo)
  ctl_port=$(free_port)
  node_port=$(free_port)
  [ "$ctl_port" != "$node_port" ] || node_port=$(free_port)
  cat >"$dir/slurm.conf" <<EOF
# One-machine cluster of scripts/slurm_local.sh (temporary).
ClusterName=millcharge-local
SlurmctldHost=localhost
SlurmctldPort=$ctl_port
SlurmdPort=$node_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/socket/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# No cgroups, no accounting: processes are tracked by their parent ids.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
MailProg=/bin/true
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SlurmdParameters=config_overrides
ReturnToService=2
# SIGTERM on scancel and at the time limit, SIGKILL KillWait seconds later:
# a millcharge run writes its checkpoint in between.
KillWait=30
MinJobAge=600
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF="$dir/slurm.conf"
  slurmctld -f "$SLURM_CONF" || { logs; fail "slurmctld did not start (logs above)"; }
  slurmd -f "$SLURM_CONF" -N localhost || { logs; fail "slurmd did not start (logs above)"; }

  # Ready when the node is idle.
  local state=""
  for _ in $(seq 1 300); do
    state=$(scontrol show node localhost 2>/dev/null | sed -n 's/.*State=\([A-Z+_]*\).*/\1/p' | head -n 1) || true
    [ "$state" = "IDLE" ] && break
    sleep 0.1
  done
  if [ "$state" != "IDLE" ]; then
    logs
    scontrol show node localhost >&2 || true
    fail "the node did not become idle within 30 s (state '${state:-unknown}'; logs above)"
  fi
  echo "export SLURM_CONF=$dir/slurm.conf"
}

stop() {
  [ -d "$dir" ] || fail "$dir: no such folder"
  dir=$(cd "$dir" && pwd)
  if [ -f "$dir/slurm.conf" ] && [ -s "$dir/run/slurmctld.pid" ]; then
    export SLURM_CONF="$dir/slurm.conf"
    # The jobs first, so that no run is left behind when slurmd goes.
    scancel --full --quiet --user=root 2>/dev/null || true
    for _ in $(seq 1 150); do
      [ -z "$(squeue --noheader 2>/dev/null)" ] && break
      sleep 0.2
    done
  fi
  stop_pid "$dir/run/slurmd.pid" 10
  stop_pid "$dir/run/slurmctld.pid" 10
  stop_pid "$dir/run/munged.pid" 5
  rm -f "$dir/slurm.conf"
}

case "$action" in
  start) start ;;
  stop) stop ;;
  *) usage ;;
esac
