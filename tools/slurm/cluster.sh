#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for tests: Debian's slurm-wlm and munge
# (installed with apt-get when missing), one node with every core, one partition `debug`,
# no cgroups and no accounting. Needs root.
# Usage: tools/slurm/cluster.sh start | stop
set -euo pipefail
state=/var/tmp/uncoil-slurm
case "${1:-}" in
  start)
    if ! command -v slurmctld > /dev/null || ! command -v munged > /dev/null; then
      (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge) > /dev/null
    fi
    host=$(hostname -s)
    cpus=$(nproc)
    mem=$(awk '/MemTotal/ { print int($2 / 1024 * 0.9) }' /proc/meminfo)
    mkdir -p "$state/ctld" "$state/d" /etc/slurm /run/munge /var/log/munge /var/lib/munge
    cat > /etc/slurm/slurm.conf <<EOF
ClusterName=uncoil-test
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/d
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
    if [ ! -s /etc/munge/munge.key ]; then
      mkdir -p /etc/munge
      dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
    fi
    chown -R munge:munge /etc/munge /run/munge /var/log/munge /var/lib/munge
    chmod 0400 /etc/munge/munge.key
    pgrep -x munged > /dev/null || runuser -u munge -- munged
    pgrep -x slurmctld > /dev/null || slurmctld
    pgrep -x slurmd > /dev/null || slurmd
    # Wait for the node to take jobs.
    for _ in $(seq 60); do
      if sinfo -h -o '%T' 2>/dev/null | grep -qx idle; then
        exit 0
      fi
      sleep 1
    done
    echo "error: the Slurm node did not come up; see $state/*.log" >&2
    sinfo >&2 || true
    exit 1
    ;;
  stop)
    pkill -x slurmd || true
    pkill -x slurmctld || true
    pkill -x munged || true
    ;;
  *)
    echo "usage: $0 start | stop" >&2
    exit 2
    ;;
esac
