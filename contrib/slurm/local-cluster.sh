#!/usr/bin/env bash
# A one-node Slurm "cluster" on this machine, for trying contrib/slurm and for CI: starts
# munged, slurmctld and slurmd (as root, without systemd) with state under DIR, and prints the
# SLURM_CONF to export. `local-cluster.sh stop DIR` stops them by PID.
#   usage: local-cluster.sh start DIR | stop DIR
# Needs Debian's slurm-wlm and munge (apt-get install --no-install-recommends slurm-wlm munge).
set -euo pipefail
action=${1:?start or stop}; dir=${2:?a folder for the state of the cluster}
if [ "$action" = stop ]; then
    for daemon in slurmd slurmctld munged; do
        [ -f "$dir/$daemon.pid" ] && kill "$(cat "$dir/$daemon.pid")" 2>/dev/null || true
    done
    exit 0
fi
mkdir -p "$dir/state" "$dir/spool" "$dir/log" /run/munge
chown munge: /run/munge
host=$(hostname -s)
cat > "$dir/slurm.conf" <<CONF
ClusterName=hmdist
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MinJobAge=0
ReturnToService=2
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$dir/slurm.conf"
# Each daemon in the foreground as a background job, its PID kept.
su -s /bin/sh munge -c "exec /usr/sbin/munged --foreground" > "$dir/log/munged.log" 2>&1 &
echo $! > "$dir/munged.pid"
for _ in $(seq 50); do [ -S /run/munge/munge.socket.2 ] && break; sleep 0.1; done
/usr/sbin/slurmctld -D -i > "$dir/log/slurmctld.out" 2>&1 &
echo $! > "$dir/slurmctld.pid"
/usr/sbin/slurmd -D > "$dir/log/slurmd.out" 2>&1 &
echo $! > "$dir/slurmd.pid"
for _ in $(seq 150); do
    if sinfo -h -o %t 2>/dev/null | grep -qx idle; then
        echo "export SLURM_CONF=$SLURM_CONF"
        exit 0
    fi
    sleep 0.2
done
echo "local-cluster.sh: the node did not come up idle; logs in $dir/log" >&2
tail -n 20 "$dir"/log/* >&2 || true
exit 1
