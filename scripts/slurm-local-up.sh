#!/usr/bin/env bash
# A single-node Slurm on this machine for the opt-in Slurm tests (docs/slurm.md; the recipe of
# engineering.md §5): munge + slurmctld + slurmd on localhost, no systemd or cgroups.
# Idempotent: exits 0 with a working `sinfo` if the daemons already run. Root (or sudo) needed.
# Exit 2 when Slurm cannot be installed here (the caller reports the tests as skipped).
set -euo pipefail
SUDO=""
[ "$(id -u)" = 0 ] || SUDO="sudo"

if command -v sinfo >/dev/null 2>&1 && sinfo -h -o %a 2>/dev/null | grep -q up; then
  exit 0
fi
if ! command -v slurmctld >/dev/null 2>&1; then
  $SUDO apt-get update -qq >/dev/null 2>&1 || true
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    slurm-wlm munge >/dev/null 2>&1 || { echo "slurm-local-up: cannot install slurm-wlm" >&2; exit 2; }
fi

$SUDO mkdir -p /run/munge && $SUDO chown munge:munge /run/munge
pgrep -x munged >/dev/null || $SUDO runuser -u munge -- /usr/sbin/munged
munge -n | unmunge >/dev/null

$SUDO mkdir -p /var/spool/slurmctld /var/spool/slurmd /var/log/slurm /etc/slurm
$SUDO chown slurm:slurm /var/spool/slurmctld /var/log/slurm
H=$(hostname -s)
CPUS=$(nproc)
$SUDO tee /etc/slurm/slurm.conf >/dev/null <<CONF
ClusterName=local
SlurmctldHost=${H}(127.0.0.1)
SlurmUser=slurm
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SchedulerParameters=sched_min_interval=0,bf_interval=1
MaxArraySize=10001
MaxJobCount=20000
NodeName=${H} NodeAddr=127.0.0.1 CPUs=${CPUS} State=UNKNOWN
PartitionName=debug Nodes=${H} Default=YES MaxTime=INFINITE State=UP
CONF
pgrep -x slurmctld >/dev/null || $SUDO slurmctld
pgrep -x slurmd >/dev/null || $SUDO slurmd
for _ in $(seq 1 30); do
  if sinfo -h -o %a 2>/dev/null | grep -q up; then
    exit 0
  fi
  sleep 1
done
echo "slurm-local-up: the daemons did not come up (see /var/log/slurm/)" >&2
exit 2
