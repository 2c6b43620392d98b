#!/bin/bash
# A one-node Slurm cluster on this machine (127.0.0.1), without systemd, for CI and for
# trying the job scripts out: `start` installs Debian's slurm-wlm and munge if they are
# missing, writes slurm.conf into a state folder, starts munged, slurmctld and slurmd and
# waits until the node is idle; `stop` ends the daemons it started, by their PIDs; `install`
# only installs the packages.
#
#   scripts/slurm/local-cluster.sh install|start|stop|status|env
#
# As root. The clients need SLURM_CONF pointing at the state folder's slurm.conf:
# `eval "$(scripts/slurm/local-cluster.sh env)"` sets it.
#
# Environment: CLTRACE_SLURM_STATE, the state folder (/tmp/cltrace-slurm); CLTRACE_SLURM_PORT,
# slurmctld's port, slurmd's is the next (6817); CLTRACE_SLURM_GPUS, stand-in GPUs the node
# offers as gres (2): stand-in device files, so that `--gres=gpu:N` is scheduled and Slurm sets
# CUDA_VISIBLE_DEVICES; the renders still run on whatever OpenCL device there is.
set -euo pipefail

STATE=${CLTRACE_SLURM_STATE:-/tmp/cltrace-slurm}
CONF=$STATE/slurm.conf
PORT=${CLTRACE_SLURM_PORT:-6817}
GPUS=${CLTRACE_SLURM_GPUS:-2}
# Seconds to wait for each daemon, and for the node to become idle.
WAIT=${CLTRACE_SLURM_WAIT:-30}
export SLURM_CONF=$CONF

die() { echo "local-cluster: $*" >&2; exit 1; }
note() { echo "local-cluster: $*" >&2; }

# The PID recorded in $STATE/NAME.pid if that process is alive and runs the program NAME (a
# recycled PID must not be taken for the daemon).
running_pid() {
    local pid
    pid=$(cat "$STATE/$1.pid" 2>/dev/null) || return 1
    [[ $pid =~ ^[0-9]+$ ]] || return 1
    [[ $(cat "/proc/$pid/comm" 2>/dev/null) == "$1" ]] || return 1
    echo "$pid"
}

# Waits up to $WAIT seconds for the command to succeed; otherwise fails with MESSAGE and the
# tail of LOG.
wait_for() {
    local message=$1 log=$2
    shift 2
    local deadline=$((SECONDS + WAIT))
    until "$@" >/dev/null 2>&1; do
        if ((SECONDS >= deadline)); then
            note "$message after ${WAIT} s"
            [[ -f $log ]] && tail -n 20 "$log" >&2
            exit 1
        fi
        sleep 0.2
    done
}

install_packages() {
    local missing=0 tool
    for tool in munged slurmctld slurmd sbatch; do
        command -v "$tool" >/dev/null || missing=1
    done
    ((missing)) || return 0
    note "installing slurm-wlm and munge"
    local apt=(env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm munge)
    # A fresh machine has no package lists yet; update only when the install needs it.
    if ! "${apt[@]}" >/dev/null; then
        if ! apt-get update -qq || ! "${apt[@]}" >/dev/null; then
            die "cannot install slurm-wlm and munge"
        fi
    fi
}

munge_works() { munge -n </dev/null | unmunge >/dev/null; }

start_munge() {
    if munge_works 2>/dev/null; then
        # Someone else's munged: use it, and leave it running at `stop`.
        [[ -n $(running_pid munged) ]] || note "munged is already running: using it"
        return 0
    fi
    # munged refuses to run as root and checks that its folders belong to its user.
    local dir
    for dir in /etc/munge /var/lib/munge /var/log/munge /run/munge; do
        mkdir -p "$dir"
        chown munge:munge "$dir"
    done
    chmod 0700 /etc/munge /var/log/munge
    chmod 0755 /run/munge
    if [[ ! -s /etc/munge/munge.key ]]; then
        runuser -u munge -- mungekey --create --keyfile=/etc/munge/munge.key
    fi
    rm -f /run/munge/munged.pid
    runuser -u munge -- munged || die "munged did not start (see /var/log/munge/munged.log)"
    wait_for "munged wrote no PID file" /var/log/munge/munged.log test -s /run/munge/munged.pid
    cp /run/munge/munged.pid "$STATE/munged.pid"
    wait_for "munge does not answer" /var/log/munge/munged.log munge_works
}

write_conf() {
    local host node
    host=$(hostname -s)
    # The node's CPUs, sockets, cores, threads and memory as slurmd sees them; a node that
    # claims more than slurmd finds is drained.
    node=$(slurmd -C | head -n 1)
    [[ $node == NodeName=$host\ * ]] || die "unexpected 'slurmd -C' output: $node"
    mkdir -p "$STATE/ctld" "$STATE/spool" "$STATE/dev"
    local gres_types="" node_gres=""
    : >"$STATE/gres.conf"
    if ((GPUS > 0)); then
        local i
        # Slurm wants device files; these are /dev/null's (1:3) under other names.
        for ((i = 0; i < GPUS; i++)); do
            [[ -c $STATE/dev/gpu$i ]] || { rm -f "$STATE/dev/gpu$i"; mknod -m 0666 "$STATE/dev/gpu$i" c 1 3; }
        done
        gres_types="GresTypes=gpu"
        node_gres="Gres=gpu:$GPUS"
        echo "Name=gpu File=$STATE/dev/gpu[0-$((GPUS - 1))]" >"$STATE/gres.conf"
    fi
    cat >"$CONF" <<CONF
# Written by scripts/slurm/local-cluster.sh: a one-node cluster on 127.0.0.1.
ClusterName=cltrace
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
AuthType=auth/munge
CredType=cred/munge
# The jobs (and the daemons) run as root here.
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/spool
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/slurmctld.log
SlurmdLogFile=$STATE/slurmd.log
# No cgroups on this kind of machine.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
# Cores, not whole nodes: the tasks of an array run side by side.
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
# Without it, a job whose dependency can no longer be met (a failed render task) stays
# pending forever instead of being cancelled.
DependencyParameters=kill_invalid_depend
# No accounting daemon: sacct does not work, scontrol show job does (for MinJobAge seconds).
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
KillWait=5
$gres_types
$node NodeAddr=127.0.0.1 $node_gres State=UNKNOWN
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
}

node_idle() {
    local state
    state=$(sinfo -h -n "$(hostname -s)" -o %t 2>/dev/null) || return 1
    [[ $state == idle ]]
}

start() {
    ((EUID == 0)) || die "run as root: munged runs as the munge user, the Slurm daemons as root"
    mkdir -p "$STATE"
    if running_pid slurmctld >/dev/null && running_pid slurmd >/dev/null; then
        note "already running (SLURM_CONF=$CONF)"
        return 0
    fi
    install_packages
    start_munge
    write_conf
    if ! running_pid slurmctld >/dev/null; then
        rm -f "$STATE/slurmctld.pid"
        # -c: a fresh start, without the jobs of an earlier run.
        slurmctld -c -f "$CONF" || die "slurmctld did not start (see $STATE/slurmctld.log)"
        wait_for "slurmctld did not start" "$STATE/slurmctld.log" running_pid slurmctld
    fi
    if ! running_pid slurmd >/dev/null; then
        rm -f "$STATE/slurmd.pid"
        slurmd -f "$CONF" || die "slurmd did not start (see $STATE/slurmd.log)"
        wait_for "slurmd did not start" "$STATE/slurmd.log" running_pid slurmd
    fi
    wait_for "the node did not become idle (sinfo: $(sinfo -h -o '%t %E' 2>&1 | head -n 1))" \
        "$STATE/slurmd.log" node_idle
    note "up: slurmctld $(running_pid slurmctld), slurmd $(running_pid slurmd) (SLURM_CONF=$CONF)"
}

# Ends the daemon recorded in $STATE/NAME.pid: SIGTERM, then SIGKILL after $WAIT seconds.
stop_daemon() {
    local pid
    if pid=$(running_pid "$1"); then
        kill -TERM "$pid" 2>/dev/null || true
        local deadline=$((SECONDS + WAIT))
        while kill -0 "$pid" 2>/dev/null; do
            if ((SECONDS >= deadline)); then
                note "$1 ($pid) ignored SIGTERM for ${WAIT} s: killing it"
                kill -KILL "$pid" 2>/dev/null || true
                break
            fi
            sleep 0.1
        done
    fi
    rm -f "$STATE/$1.pid"
}

stop() {
    # slurmd first, so that slurmctld does not see its node go away as a failure.
    stop_daemon slurmd
    stop_daemon slurmctld
    stop_daemon munged
}

status() {
    local name pid
    for name in munged slurmctld slurmd; do
        if pid=$(running_pid "$name"); then echo "$name: running ($pid)"; else echo "$name: not started here"; fi
    done
    if [[ -f $CONF ]] && running_pid slurmctld >/dev/null; then sinfo; fi
}

case "${1:-}" in
install) install_packages ;;
start) start ;;
stop) stop ;;
status) status ;;
env) printf 'export SLURM_CONF=%q\n' "$CONF" ;;
*)
    echo "usage: $0 install|start|stop|status|env" >&2
    exit 2
    ;;
esac
