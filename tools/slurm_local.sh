#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for testing `mjtether sweep --slurm` (as root,
# Debian's slurm-wlm and munge):
#
#   tools/slurm_local.sh start DIR   # munged, slurmctld, slurmd on localhost; all state in DIR
#   export SLURM_CONF=DIR/slurm.conf # for sbatch, squeue, sinfo
#   tools/slurm_local.sh stop DIR    # stops the three daemons by their pid files
#
# Everything (munge key and socket, slurm.conf, spool, state, logs, pid files) lives in DIR, so
# no system-wide configuration or daemon is touched. `start` returns when the node is idle.
set -euo pipefail
cmd=${1:-}
dir=${2:-}
if [[ -z $cmd || -z $dir ]]; then
  echo "usage: $0 start|stop DIR" >&2
  exit 2
fi

stop() {
  for d in slurmd slurmctld munged; do
    if [[ -s $dir/$d.pid ]]; then
      pid=$(cat "$dir/$d.pid")
      kill "$pid" 2>/dev/null || true
      for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
      kill -9 "$pid" 2>/dev/null || true
      rm -f "$dir/$d.pid"
    fi
  done
}

if [[ $cmd == stop ]]; then
  stop
  exit 0
fi
[[ $cmd == start ]] || { echo "$0: unknown command $cmd" >&2; exit 2; }
if [[ $(id -u) != 0 ]]; then
  echo "$0: run as root (slurmd runs the jobs as root here)" >&2
  exit 2
fi
for p in munged mungekey slurmctld slurmd sinfo; do
  command -v "$p" >/dev/null || { echo "$0: $p not found: apt-get install slurm-wlm munge" >&2; exit 2; }
done
mkdir -p "$dir"
chmod 700 "$dir"
dir=$(cd "$dir" && pwd)
mkdir -p "$dir/spool" "$dir/state"

# munge: its own key and socket in DIR.
[[ -f $dir/munge.key ]] || mungekey -c -k "$dir/munge.key" >/dev/null
munged --key-file="$dir/munge.key" --socket="$dir/munge.socket" --pid-file="$dir/munged.pid" \
  --log-file="$dir/munged.log" --seed-file="$dir/munged.seed" --force

host=$(hostname -s)
cat > "$dir/slurm.conf" <<CONF
ClusterName=mjtether
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge.socket
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
ReturnToService=2
SlurmctldPort=${SLURMCTLD_PORT:-6817}
SlurmdPort=${SLURMD_PORT:-6818}
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmdSpoolDir=$dir/spool
StateSaveLocation=$dir/state
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$dir/slurm.conf
slurmctld -f "$dir/slurm.conf" -i
slurmd -f "$dir/slurm.conf"
for _ in $(seq 60); do
  if [[ $(sinfo -h -o %t 2>/dev/null) == idle ]]; then
    echo "slurm: node $host idle ($(nproc) CPUs); export SLURM_CONF=$dir/slurm.conf"
    exit 0
  fi
  sleep 0.5
done
echo "$0: the node did not become idle in 30 s; logs in $dir" >&2
sinfo >&2 || true
tail -5 "$dir/slurmctld.log" "$dir/slurmd.log" >&2 || true
stop
exit 1
