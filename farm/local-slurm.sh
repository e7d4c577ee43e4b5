#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for the tests and for trying the farm scripts:
#
#   farm/local-slurm.sh start DIR    # munged, slurmctld and slurmd, all state and logs in DIR
#   export SLURM_CONF=DIR/slurm.conf # then sbatch, squeue, sinfo talk to it
#   farm/local-slurm.sh stop DIR     # stops exactly the daemons it started (by their pid files)
#
# Needs Debian's slurm-wlm and munge packages (slurmctld/slurmd 22.05, munge 0.5). Nothing is
# installed or changed outside DIR: the cluster has its own munge key and socket, its own ports
# (26817 and 26818 unless SLURMCTLD_PORT / SLURMD_PORT say otherwise) and runs as the current
# user. No systemd needed. A requeued job starts again after CRED_EXPIRE seconds (10 here;
# Slurm's default, on real clusters, is 120).
set -euo pipefail

usage() { echo "usage: $0 start|stop DIR" >&2; exit 2; }
[ $# -eq 2 ] || usage
action=$1
dir=$(mkdir -p "$2" && cd "$2" && pwd)
conf=$dir/slurm.conf

stop() {
    local pid_file pid
    # Jobs first (their steps would outlive the daemons), then an orderly shutdown; the pid
    # files below catch whatever is left.
    if [ -s "$dir/slurmctld.pid" ] && kill -0 "$(cat "$dir/slurmctld.pid")" 2>/dev/null; then
        SLURM_CONF=$conf timeout 10 scancel --user="$(id -un)" 2>/dev/null || true
        SLURM_CONF=$conf timeout 10 scontrol shutdown 2>/dev/null || true
    fi
    for pid_file in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munge/munged.pid"; do
        [ -s "$pid_file" ] || continue
        pid=$(cat "$pid_file")
        kill "$pid" 2>/dev/null || true
        # Wait for it to end (at most 10 s), then make sure.
        for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$pid" 2>/dev/null || true
        rm -f "$pid_file"
    done
}

start() {
    # Whatever fails from here on, the daemons already started are stopped again.
    trap stop ERR
    for tool in munged slurmctld slurmd sbatch sinfo; do
        command -v "$tool" >/dev/null || {
            echo "$0: $tool is not installed (apt-get install slurm-wlm munge)" >&2
            exit 3
        }
    done
    user=$(id -un)
    for port in "${SLURMCTLD_PORT:-26817}" "${SLURMD_PORT:-26818}"; do
        if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
            echo "$0: port $port is in use (another cluster?); choose others with SLURMCTLD_PORT and SLURMD_PORT" >&2
            exit 1
        fi
    done
    # munged insists that every folder on the way to its socket lets everyone through.
    chmod 755 "$dir"
    mkdir -p "$dir/munge" "$dir/state" "$dir/spool" "$dir/log"
    chmod 755 "$dir/munge"
    if [ ! -s "$dir/munge/munge.key" ]; then
        head -c 128 /dev/urandom > "$dir/munge/munge.key"
        chmod 600 "$dir/munge/munge.key"
    fi
    munged --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
        --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" \
        --seed-file="$dir/munge/munged.seed"

    # The node as slurmd sees it: its CPUs and memory.
    cpus=$(slurmd -C | sed -n 's/.*CPUs=\([0-9]*\).*/\1/p')
    memory=$(slurmd -C | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p')
    cat > "$conf" <<CONF
ClusterName=raylab
SlurmctldHost=localhost
SlurmctldPort=${SLURMCTLD_PORT:-26817}
SlurmdPort=${SLURMD_PORT:-26818}
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
# A requeued job waits cred_expire seconds before it starts again (120 by default).
AuthInfo=socket=$dir/munge/munge.socket,cred_expire=${CRED_EXPIRE:-10}
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
ReturnToService=2
# sbatch --wait returns about 2 s after the job ends.
SchedulerParameters=batch_sched_delay=0
MinJobAge=4
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=raylab Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
    slurmctld -c -f "$conf"
    slurmd -f "$conf" -N localhost
    # Ready when the node is idle (at most 30 s).
    for _ in $(seq 300); do
        if SLURM_CONF=$conf sinfo -h -o %t 2>/dev/null | grep -qx idle; then
            echo "$0: a one-node cluster runs in $dir (export SLURM_CONF=$conf)"
            return 0
        fi
        sleep 0.1
    done
    echo "$0: the node did not come up; logs in $dir/log" >&2
    stop
    exit 1
}

case $action in
    start) start ;;
    stop) stop ;;
    *) usage ;;
esac
