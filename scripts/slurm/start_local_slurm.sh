#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for trying and testing the Slurm sweeps
# (Makefile.analysis SCHEDULER=slurm): munged, slurmctld and slurmd on localhost. Run as root;
# needs Debian's slurm-wlm and munge. Idempotent: does nothing if the node is already up.
#   bash scripts/slurm/start_local_slurm.sh        start (or check) the cluster
#   bash scripts/slurm/start_local_slurm.sh stop   stop the daemons it started
set -euo pipefail
state=/var/lib/budjam-slurm
conf=/etc/slurm/slurm.conf

stop() {
  for daemon in slurmd slurmctld munged; do
    [[ -f $state/$daemon.pid ]] && kill "$(cat "$state/$daemon.pid")" 2>/dev/null || true
    rm -f "$state/$daemon.pid"
  done
}
if [[ ${1:-} == stop ]]; then stop; exit 0; fi

[[ $(id -u) == 0 ]] || { echo "start_local_slurm: run as root" >&2; exit 2; }
for p in slurmctld slurmd munged sbatch; do
  command -v "$p" >/dev/null || { echo "start_local_slurm: $p missing (apt-get install slurm-wlm munge)" >&2; exit 2; }
done
if sinfo -h -o %T 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then exit 0; fi
marker="# Written by scripts/slurm/start_local_slurm.sh"
if [[ -s $conf ]] && [[ $(head -n 1 "$conf") != "$marker"* ]]; then
  echo "start_local_slurm: $conf is another Slurm configuration: not replacing it" >&2
  exit 2
fi

mkdir -p "$state" /etc/munge /var/log/munge /run/munge /var/spool/slurmctld /var/spool/slurmd /etc/slurm
chown munge:munge /etc/munge /var/log/munge /run/munge 2>/dev/null || true
if [[ ! -s /etc/munge/munge.key ]]; then
  dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
  chown munge:munge /etc/munge/munge.key 2>/dev/null || true
  chmod 400 /etc/munge/munge.key
fi
if ! munge -n </dev/null >/dev/null 2>&1; then
  runuser -u munge -- munged --force --pid-file=/run/munge/munged.pid 2>/dev/null || munged --force
  cp /run/munge/munged.pid "$state/munged.pid" 2>/dev/null || true
fi

cpus=$(nproc)
mem=$(($(awk '/MemTotal/ { print int($2 / 1024) }' /proc/meminfo) * 8 / 10))
cat > "$conf" <<CONF
$marker: one node, this machine.
ClusterName=budjam-local
SlurmctldHost=localhost
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
JobRequeue=1
ReturnToService=2
MaxArraySize=100000
NodeName=localhost NodeHostname=$(hostname) CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF

slurmctld
slurmd -N localhost
for _ in $(seq 1 60); do
  if sinfo -h -o %T 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then exit 0; fi
  scontrol update nodename=localhost state=resume >/dev/null 2>&1 || true
  sleep 1
done
echo "start_local_slurm: the node did not come up (logs: $state/slurmctld.log, $state/slurmd.log)" >&2
exit 1
