#!/usr/bin/env bash
# A one-node SLURM cluster on this machine, to try the SLURM profile (CI does the same).
# Needs Debian's packages and root (no systemd needed):
#   apt-get install -y slurmctld slurmd slurm-client munge
#
#   workflow/profiles/slurm/one_node_cluster.sh up     # start munged (if none answers), slurmctld, slurmd
#   workflow/profiles/slurm/one_node_cluster.sh down   # stop exactly the daemons `up` started (by pid)
#
# `up` writes /etc/slurm/slurm.conf (where every SLURM command, also srun inside a job, looks;
# the plugin drops SLURM_* variables such as SLURM_CONF in jobs) and refuses to overwrite one it did
# not write; `down` removes it.  State and logs go to ICOSIM_SLURM_DIR (default /tmp/icosim-slurm).
# The cluster: this machine's CPU count (nproc) and memory (free -m, less 512 MB for the system),
# one partition `debug` (the default), accounting off (so `sacct` knows no job: the case the
# profile must survive), no cgroups (containers); daemons and jobs run as root.
set -euo pipefail
DIR=${ICOSIM_SLURM_DIR:-/tmp/icosim-slurm}
CONF=/etc/slurm/slurm.conf
MARK="# written by workflow/profiles/slurm/one_node_cluster.sh"

stop_pid() { # stop_pid NAME PIDFILE: TERM the recorded pid, wait up to 20 s, then KILL
    local name=$1 file=$2 pid
    [[ -s $file ]] || return 0
    pid=$(cat "$file")
    if kill -0 "$pid" 2>/dev/null; then
        kill "$pid"
        for _ in $(seq 40); do kill -0 "$pid" 2>/dev/null || break; sleep 0.5; done
        kill -0 "$pid" 2>/dev/null && kill -9 "$pid"
        echo "stopped $name (pid $pid)"
    fi
    rm -f "$file"
}

down() {
    # jobs first: a job's slurmstepd outlives slurmd, so cancel every job and wait until none is left
    if [[ -s $DIR/slurmctld.pid ]] && kill -0 "$(cat "$DIR/slurmctld.pid")" 2>/dev/null; then
        squeue -h -o %i 2>/dev/null | xargs -r scancel 2>/dev/null || true
        for _ in $(seq 60); do
            [[ -z $(squeue -h -t PENDING,RUNNING,COMPLETING,SUSPENDED -o %i 2>/dev/null) ]] && break
            sleep 0.5
        done
    fi
    stop_pid slurmd "$DIR/slurmd.pid"
    stop_pid slurmctld "$DIR/slurmctld.pid"
    stop_pid munged "$DIR/munged.started.pid" # only if `up` started it
    if [[ -f $CONF ]] && head -1 "$CONF" | grep -qF "$MARK"; then rm -f "$CONF"; fi
}

up() {
    for exe in munged slurmctld slurmd sinfo sbatch squeue; do
        command -v "$exe" >/dev/null || {
            echo "$exe not found: apt-get install -y slurmctld slurmd slurm-client munge" >&2
            exit 1
        }
    done
    if [[ -s $DIR/slurmctld.pid ]] && kill -0 "$(cat "$DIR/slurmctld.pid")" 2>/dev/null; then
        echo "a cluster started by $0 is running already (pid $(cat "$DIR/slurmctld.pid")): '$0 down' first" >&2
        exit 1
    fi
    if [[ -f $CONF ]] && ! head -1 "$CONF" | grep -qF "$MARK"; then
        echo "$CONF exists and was not written by $0: not touching this machine's SLURM" >&2
        exit 1
    fi
    rm -rf "$DIR/state" "$DIR/spool" # a fresh cluster: no jobs of an earlier one
    mkdir -p "$DIR/state" "$DIR/spool" "$(dirname "$CONF")"
    # munge: a key (the Debian package makes one; make it if not), a daemon answering on the
    # default socket (reuse a running one; else start one as user munge and record its pid)
    if [[ ! -s /etc/munge/munge.key ]]; then
        mkdir -p /etc/munge
        dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
        chown munge:munge /etc/munge/munge.key && chmod 400 /etc/munge/munge.key
    fi
    if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
        install -d -o munge -g munge -m 755 /run/munge
        install -d -o munge -g munge -m 700 /var/log/munge /var/lib/munge
        runuser -u munge -- munged --pid-file=/run/munge/munged.pid
        cp /run/munge/munged.pid "$DIR/munged.started.pid"
        for _ in $(seq 20); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break; sleep 0.5; done
    fi
    local host cpus mem
    host=$(hostname -s)
    cpus=$(nproc)
    mem=$(($(free -m | awk '/^Mem:/ {print $2}') - 512))
    cat >"$CONF" <<EOF
$MARK on $(date -u +%FT%TZ)
ClusterName=icosim
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/slurmctld.pid
SlurmdPidFile=$DIR/slurmd.pid
SlurmctldLogFile=$DIR/slurmctld.log
SlurmdLogFile=$DIR/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
SchedulerType=sched/backfill
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
ReturnToService=2
# a finished job stays visible to squeue for 300 s (SLURM's default, stated): the profile's squeue
# status query needs this to be at least 3 x its first poll interval
MinJobAge=300
KillWait=5
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
    slurmctld -f "$CONF"
    slurmd -f "$CONF"
    # wait for the node to register and be idle
    local state=""
    for _ in $(seq 60); do
        state=$(sinfo -h -o %T 2>/dev/null | head -1)
        [[ $state == idle ]] && break
        sleep 0.5
    done
    if [[ $state != idle ]]; then
        echo "node not idle after 30 s (state '$state'); logs in $DIR" >&2
        tail -5 "$DIR/slurmctld.log" "$DIR/slurmd.log" >&2 || true
        down
        exit 1
    fi
    echo "one-node cluster up ($CONF): $host, $cpus CPUs, $mem MB, partition debug (default); accounting off"
}

case ${1:-} in
up) up ;;
down) down ;;
*)
    echo "usage: $0 up|down   (state and logs in ICOSIM_SLURM_DIR, default /tmp/icosim-slurm)" >&2
    exit 2
    ;;
esac
