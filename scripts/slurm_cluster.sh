#!/usr/bin/env bash
# A one-node Slurm cluster on the loopback address, in a folder of its own, for the batch tests
# (tests/app/batch_cli_test.cc): munged and slurmctld and slurmd with a slurm.conf written
# here, no cgroups, no accounting database. Needs Debian's slurm-wlm and munge (scripts/test.sh
# installs them) and root (slurmd starts jobs as their user).
#   scripts/slurm_cluster.sh start DIR   starts it; `export SLURM_CONF=DIR/slurm.conf` then
#                                        points sbatch, squeue and scancel at it
#   scripts/slurm_cluster.sh stop DIR    stops it
# The daemons' Unix sockets (slurmd's spool, munge's) live in a short folder of their own under
# /tmp, named in DIR/sockets: a socket's path is limited to 108 bytes, and a test's folder is long.
set -euo pipefail
action=$1
dir=$(realpath -m "$2")

stop() {
  for daemon in slurmd slurmctld munged; do
    [ -f "$dir/$daemon.pid" ] && kill "$(cat "$dir/$daemon.pid")" 2>/dev/null || true
  done
  sleep 0.5
  for daemon in slurmd slurmctld munged; do
    [ -f "$dir/$daemon.pid" ] && kill -9 "$(cat "$dir/$daemon.pid")" 2>/dev/null || true
    rm -f "$dir/$daemon.pid"
  done
  if [ -f "$dir/sockets" ]; then
    rm -rf "$(cat "$dir/sockets")"
    rm -f "$dir/sockets"
  fi
}

if [ "$action" = stop ]; then
  stop
  exit 0
fi
[ "$action" = start ] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }
for tool in slurmctld slurmd munged sbatch; do
  command -v "$tool" >/dev/null || { echo "slurm_cluster: $tool is missing (apt-get install slurm-wlm munge)" >&2; exit 77; }
done
[ "$(id -u)" -eq 0 ] || { echo "slurm_cluster: slurmd needs root" >&2; exit 77; }
mkdir -p "$dir/state" "$dir/log" "$dir/munge"
chmod 700 "$dir/munge"
sockets=$(mktemp -d /tmp/slurm.XXXXXX)
echo "$sockets" > "$dir/sockets"
mkdir -p "$sockets/spool"
dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$dir/munge/munge.key"
# Ports above the usual 6817/6818, chosen from the folder's name so that two runs do not meet.
base=$(( 20000 + $(printf '%s' "$dir" | cksum | cut -d' ' -f1) % 20000 ))
cpus=$(nproc)
memory_mib=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 * 8 / 10 ))
cat > "$dir/slurm.conf" <<CONF
ClusterName=shutterlab-test
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$base
SlurmdPort=$(( base + 1 ))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$sockets/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$sockets/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
# The main scheduler every second (not 60 s), so a dependent job starts as soon as its array ends.
SchedulerParameters=sched_interval=1,bf_interval=1
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
MpiDefault=none
ReturnToService=2
SlurmdTimeout=30
InactiveLimit=0
KillWait=5
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory_mib State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
munged --socket="$sockets/munge.socket" --key-file="$dir/munge/munge.key" \
  --pid-file="$dir/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/seed" \
  --force
export SLURM_CONF=$dir/slurm.conf
slurmctld -f "$dir/slurm.conf"
slurmd -f "$dir/slurm.conf"
for _ in $(seq 100); do
  if sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then
    echo "slurm_cluster: up in $dir (SLURM_CONF=$dir/slurm.conf)"
    exit 0
  fi
  sleep 0.2
done
echo "slurm_cluster: the node did not come up; $dir/log holds the daemons' logs" >&2
tail -5 "$dir/log/"*.log >&2 || true
stop
exit 1
