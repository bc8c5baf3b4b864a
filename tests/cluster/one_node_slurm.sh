#!/usr/bin/env bash
# A one-node SLURM for the tests: munged, slurmctld and slurmd on this host, their config,
# state and logs under one folder.
#
#   one_node_slurm.sh start DIR   # idempotent; prints the SLURM_CONF to export
#   one_node_slurm.sh stop DIR    # stops what `start DIR` started, nothing else
#
# Several test processes may share one DIR: each start counts a user, each stop one less,
# and the last stop stops the daemons. Where no /etc/slurm/slurm.conf exists it is linked to
# DIR's (Snakemake's jobstep plugin drops SLURM_CONF from the environment of the steps it
# starts with srun, which then read the default path), and the link removed again.
# Needs root and Debian's slurm-wlm and munge (apt-get install -y slurm-wlm munge); exits 3
# saying what is missing otherwise. No accounting storage (sacct does not work: the
# Snakemake SLURM plugin is given --slurm-status-command squeue), so MinJobAge keeps
# finished jobs visible to squeue long after the plugin's first status query. The node
# declares CPUS cores whatever the host has (config_overrides): the tests' jobs are small.
set -euo pipefail
cmd=${1:-}; dir=${2:-}
[[ -n $cmd && -n $dir ]] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }
CPUS=${CPUS:-8}

ETC=/etc/slurm/slurm.conf

alive() { [[ -f $1 ]] && kill -0 "$(cat "$1")" 2>/dev/null; }
users() { cat "$dir/users" 2>/dev/null || echo 0; }

stop() {
    for pid in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munged.pid"; do
        if alive "$pid"; then kill "$(cat "$pid")"; fi
        rm -f "$pid"
    done
    if [[ -L $ETC && $(readlink "$ETC") == "$dir/slurm.conf" ]]; then rm -f "$ETC"; fi
    echo 0 > "$dir/users"
}

if [[ $cmd == stop ]]; then
    [[ -d $dir ]] || exit 0
    dir=$(cd "$dir" && pwd)
    exec 9>"$dir/.lock"; flock 9
    left=$(( $(users) - 1 ))
    if (( left > 0 )); then echo "$left" > "$dir/users"; else stop; fi
    exit 0
fi
[[ $cmd == start ]] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }

for bin in munged slurmctld slurmd sbatch squeue; do
    command -v "$bin" >/dev/null || { echo "no $bin here (apt-get install -y slurm-wlm munge)" >&2; exit 3; }
done
[[ $(id -u) == 0 ]] || { echo "needs root (slurmd runs jobs as their users)" >&2; exit 3; }

mkdir -p "$dir"/{state,spool}
dir=$(cd "$dir" && pwd)
conf=$dir/slurm.conf
exec 9>"$dir/.lock"; flock 9
if alive "$dir/slurmctld.pid" && alive "$dir/slurmd.pid"; then
    echo $(( $(users) + 1 )) > "$dir/users"
    echo "$conf"
    exit 0
fi
stop                                    # a half-started one from before

# munge: one daemon per host; start it only where none runs, and say so in munged.pid
if ! pgrep -x munged >/dev/null; then
    [[ -f /etc/munge/munge.key ]] || { mungekey --create --keyfile=/etc/munge/munge.key; chown munge: /etc/munge/munge.key; }
    install -d -o munge -g munge -m 0755 /run/munge
    runuser -u munge -- munged 9>&-
    for _ in $(seq 50); do pgrep -x munged >/dev/null && break; sleep 0.1; done
    pgrep -xn munged > "$dir/munged.pid"
fi

port() { python3 -c 'import socket; s = socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])'; }
host=$(hostname -s)
cat > "$conf" <<EOF
ClusterName=ballaststudy-test
SlurmctldHost=$host
SlurmctldPort=$(port)
SlurmdPort=$(port)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
MinJobAge=600
SlurmdParameters=config_overrides
NodeName=$host CPUs=$CPUS RealMemory=16000 State=UNKNOWN
PartitionName=standard Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$conf
if [[ ! -e $ETC ]]; then mkdir -p "$(dirname "$ETC")"; ln -sfn "$conf" "$ETC"; fi
slurmctld -f "$conf" 9>&-      # the daemons must not hold the lock
slurmd -f "$conf" 9>&-
for _ in $(seq 100); do
    if sinfo -h -o %t 2>/dev/null | grep -qx idle; then
        echo 1 > "$dir/users"
        echo "$conf"
        exit 0
    fi
    sleep 0.1
done
echo "slurm did not come up: see $dir/slurmctld.log and $dir/slurmd.log" >&2
stop
exit 1
