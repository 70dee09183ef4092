#!/usr/bin/env bash
# Starts a single-node Slurm on this machine (Debian's slurm-wlm and munge),
# for trying farm/slurm/lmanim-array.sbatch without a cluster: one node
# named after this host with all its cores, one partition `local`, state in
# STATE_DIR (default /tmp/lmanim-slurm); up to four jobs share a core, so
# a few chunks run at once even on a small machine. Needs root; installs the two
# packages when they are missing. `local-slurm.sh stop` stops it again.
set -euo pipefail
state=${STATE_DIR:-/tmp/lmanim-slurm}

stop() {
    pkill -x slurmctld || true
    pkill -x slurmd || true
    while pgrep -x slurmctld >/dev/null || pgrep -x slurmd >/dev/null; do sleep 0.2; done
}
if [ "${1:-}" = stop ]; then
    stop
    exit 0
fi

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq slurm-wlm munge >/dev/null
fi

# munge authenticates the daemons to each other.
if [ ! -s /etc/munge/munge.key ]; then
    mungekey --create --force
fi
chown -R munge:munge /etc/munge
mkdir -p /run/munge && chown munge:munge /run/munge
pgrep -x munged >/dev/null || runuser -u munge -- munged

host=$(hostname -s)
cpus=$(nproc)
memory=$(awk '/MemTotal/ { print int($2 / 1024 * 0.9) }' /proc/meminfo)
mkdir -p "$state"/spool "$state"/ctld /etc/slurm
cat > /etc/slurm/slurm.conf <<CONF
ClusterName=lmanim
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
NodeName=$host CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=FORCE:4
CONF
# No cgroups: processes are tracked by their parent (containers often
# have no writable cgroup tree).
rm -f /etc/slurm/cgroup.conf

# Daemons of an earlier start may hold an older configuration.
stop
slurmctld
slurmd
# Wait until the node takes jobs.
for _ in $(seq 30); do
    if sinfo --noheader --states=idle,mixed,allocated 2>/dev/null | grep -q local; then
        exit 0
    fi
    scontrol update nodename="$host" state=resume >/dev/null 2>&1 || true
    sleep 1
done
echo "local-slurm.sh: the node did not come up; see $state/*.log" >&2
exit 1
