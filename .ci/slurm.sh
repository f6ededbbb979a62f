#!/usr/bin/env bash
# CI stage: the workflow through a real SLURM (profiles/slurm, snakemake-executor-plugin-slurm)
# on a single-node cluster on localhost, against a local run of the small test config (.test/config/config.yaml).
#
#   bash .ci/slurm.sh          (called by .ci/run after pytest; about 2 minutes)
#
# It installs Debian's slurmctld, slurmd and munge if they are missing, starts its own
# munged, slurmctld and slurmd (private socket, ports, state and config under a temporary
# folder; no accounting), runs .test/config/config.yaml with --profile profiles/slurm under a
# hard timeout, checks that the jobs went through SLURM and that every table equals a local
# run's, and stops the three daemons it started (by their PIDs) and nothing else.
# It skips, exit 0 with a message, where it cannot run: not root, or no apt-get / package
# registry to install SLURM from. BOUNCING_BALL_SLURM_SIMULATE=nonroot or =noapt (SLURM
# taken as missing, apt-get failing) takes those skip paths on purpose, to check them.
set -euo pipefail

REPO=$(cd "$(dirname "$0")/.." && pwd)
START=$SECONDS
say() { echo "[slurm stage $((SECONDS - START))s] $*"; }
skip() {
    echo "SLURM stage SKIPPED: $*"
    echo "SLURM stage SKIPPED: the cluster path (profiles/slurm) was not tested on this machine"
    exit 0
}

SIMULATE=${BOUNCING_BALL_SLURM_SIMULATE:-}
if [ "$(id -u)" -ne 0 ] || [ "$SIMULATE" = nonroot ]; then
    skip "not root (uid $(id -u)${SIMULATE:+, simulated}): installing SLURM and starting its daemons needs root"
fi

# The library of this checkout, also inside the SLURM jobs (sbatch exports the environment).
export PYTHONPATH="$REPO${PYTHONPATH:+:$PYTHONPATH}"
PYTHON=$(command -v python)

# --- install -------------------------------------------------------------------------
missing=()
for program in munged slurmctld slurmd sbatch squeue scontrol; do
    command -v "$program" >/dev/null || missing+=("$program")
done
APT_GET=apt-get
if [ "$SIMULATE" = noapt ]; then
    # as if SLURM were missing and apt-get could not reach a package registry
    missing+=("(simulated)")
    APT_GET=false
fi
if [ ${#missing[@]} -gt 0 ]; then
    if ! command -v apt-get >/dev/null; then
        skip "SLURM is not installed (missing: ${missing[*]}) and there is no apt-get to install it"
    fi
    say "installing slurmctld, slurmd, munge (missing: ${missing[*]})"
    created_policy=0
    if [ ! -e /usr/sbin/policy-rc.d ]; then
        # keep the packages' scripts from starting daemons of their own
        printf '#!/bin/sh\nexit 101\n' >/usr/sbin/policy-rc.d
        chmod +x /usr/sbin/policy-rc.d
        created_policy=1
    fi
    installed=0
    if timeout 300 $APT_GET update -q >/tmp/bouncing-ball-slurm-apt.log 2>&1 &&
        DEBIAN_FRONTEND=noninteractive timeout 300 $APT_GET install -y -q --no-install-recommends \
            slurmctld slurmd munge slurm-client >>/tmp/bouncing-ball-slurm-apt.log 2>&1; then
        installed=1
    fi
    if [ "$created_policy" = 1 ]; then rm -f /usr/sbin/policy-rc.d; fi
    if [ "$installed" = 0 ]; then
        tail -5 /tmp/bouncing-ball-slurm-apt.log || true
        skip "apt-get could not install slurmctld, slurmd and munge (no package registry?); log: /tmp/bouncing-ball-slurm-apt.log"
    fi
fi
say "$(slurmctld -V)"

# --- a private single-node cluster ---------------------------------------------------
WORK=$(mktemp -d /tmp/bouncing-ball-slurm.XXXXXX)
mkdir -p "$WORK/munge" "$WORK/state" "$WORK/spool" "$WORK/log"
chmod 700 "$WORK/munge"
PIDS=()
cleanup() {
    status=$?
    if [ -n "${SLURM_CONF:-}" ] && [ ${#PIDS[@]} -gt 0 ]; then
        # jobs still known to our controller (a failed or timed-out run): cancel them
        jobs=$(timeout 10 squeue -h -o %A 2>/dev/null || true)
        if [ -n "$jobs" ]; then
            say "cancelling leftover jobs: $(echo $jobs)"
            timeout 10 scancel $jobs || true
            sleep 2
        fi
    fi
    for pid in "${PIDS[@]}"; do
        kill -TERM "$pid" 2>/dev/null || true
    done
    for pid in "${PIDS[@]}"; do
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
        kill -KILL "$pid" 2>/dev/null || true
        wait "$pid" 2>/dev/null || true
    done
    [ ${#PIDS[@]} -gt 0 ] && say "stopped the daemons this stage started (PIDs ${PIDS[*]})"
    [ -n "${WROTE_CONF:-}" ] && rm -f "$SLURM_CONF"
    if [ "$status" -ne 0 ]; then
        for log in "$WORK"/log/*.log; do
            [ -f "$log" ] && { echo "--- last lines of $log"; tail -20 "$log"; }
        done
        echo "SLURM stage FAILED (exit $status); its files are kept in $WORK"
    else
        rm -rf "$WORK"
    fi
    exit "$status"
}
trap cleanup EXIT

free_port() { "$PYTHON" -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
CTLD_PORT=$(free_port)
SLURMD_PORT=$(free_port)
while [ "$SLURMD_PORT" = "$CTLD_PORT" ]; do SLURMD_PORT=$(free_port); done
HOST=$(hostname -s)
NODE=bbnode
# the node as slurmd sees it (CPUs, RealMemory): a larger claim would drain the node
read -r CPUS MEMORY < <(slurmd -C | sed -n 's/.* CPUs=\([0-9]*\) .* RealMemory=\([0-9]*\).*/\1 \2/p')

# The config at SLURM's default path: the plugin's job step (snakemake-executor-plugin-
# slurm-jobstep) calls srun without SLURM_CONF, so a config elsewhere is not found inside
# the jobs. Written only where no other config is, removed on exit.
MARK="# written by bouncing-ball's .ci/slurm.sh"
export SLURM_CONF=/etc/slurm/slurm.conf
if [ -e "$SLURM_CONF" ] && ! head -1 "$SLURM_CONF" | grep -qF "$MARK"; then
    skip "$SLURM_CONF exists and is not this stage's: this machine has a SLURM of its own, left untouched"
fi
mkdir -p /etc/slurm
WROTE_CONF=1
cat >"$SLURM_CONF" <<EOF
$MARK: one node, no accounting, all state under $WORK
ClusterName=bouncingball
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$WORK/munge/munge.socket
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/log/slurmctld.log
SlurmdLogFile=$WORK/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
MpiDefault=none
ReturnToService=2
# finished jobs stay visible to squeue this long: at least 3 times the plugin's
# initial status delay (2 s below), or it falls back to sacct
MinJobAge=300
NodeName=$NODE NodeHostname=$HOST NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=$MEMORY State=UNKNOWN
PartitionName=ci Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF

head -c 1024 /dev/urandom >"$WORK/munge/munge.key"
chmod 400 "$WORK/munge/munge.key"
munged --foreground --force --key-file="$WORK/munge/munge.key" \
    --socket="$WORK/munge/munge.socket" --pid-file="$WORK/munge/munged.pid" \
    --seed-file="$WORK/munge/munged.seed" --log-file="$WORK/log/munged.log" >"$WORK/log/munged.out" 2>&1 &
PIDS+=($!)
for _ in $(seq 50); do
    munge -n -S "$WORK/munge/munge.socket" 2>/dev/null | unmunge -S "$WORK/munge/munge.socket" >/dev/null 2>&1 && break
    sleep 0.2
done
munge -n -S "$WORK/munge/munge.socket" | unmunge -S "$WORK/munge/munge.socket" >/dev/null
slurmctld -D -c -f "$SLURM_CONF" >"$WORK/log/slurmctld.out" 2>&1 &
PIDS+=($!)
slurmd -D -N "$NODE" -f "$SLURM_CONF" >"$WORK/log/slurmd.out" 2>&1 &
PIDS+=($!)
if ! timeout 60 bash -c 'until sinfo -h -N -o %t 2>/dev/null | grep -qx idle; do sleep 0.5; done'; then
    sinfo -N -l || true
    echo "the SLURM node did not become idle within 60 s"
    exit 1
fi
say "cluster up: munged, slurmctld, slurmd (PIDs ${PIDS[*]}), node $NODE, $CPUS CPUs, $MEMORY MB"
sinfo -N -o "%N %t %c %m"

# --- the small test config, locally and through SLURM ----------------------------------
TARGETS=(simulation solver fits tables)
copy() {
    mkdir -p "$1"
    cp -r "$REPO/Snakefile" "$REPO/workflow" "$REPO/scripts" "$REPO/config" "$REPO/profiles" "$1/"
    cp "$REPO/.test/config/config.yaml" "$1/config/config.yaml"
}
copy "$WORK/local"
copy "$WORK/cluster"

say "local run"
(cd "$WORK/local" && timeout --kill-after=15 300 "$PYTHON" -m snakemake --cores 2 "${TARGETS[@]}") \
    >"$WORK/log/local-run.log" 2>&1 || { tail -30 "$WORK/log/local-run.log"; exit 1; }

say "SLURM run: snakemake --profile profiles/slurm with the settings of a cluster without accounting"
# Site settings of this cluster on the command line (they win over the profile): no
# accounting, so squeue for job states and no account. The test config's 5 shards are 3
# SLURM jobs (batches of at most 2 shards: simulation.shards_per_job).
set +e
(cd "$WORK/cluster" && timeout --kill-after=15 300 "$PYTHON" -m snakemake --profile profiles/slurm \
    --slurm-status-command squeue --slurm-init-seconds-before-status-checks 2 \
    --slurm-no-account --slurm-keep-successful-logs \
    --jobs 4 --latency-wait 5 \
    "${TARGETS[@]}") >"$WORK/log/slurm-run.log" 2>&1
status=$?
set -e
if [ "$status" -ne 0 ]; then
    tail -40 "$WORK/log/slurm-run.log"
    [ "$status" -eq 124 ] && echo "the SLURM run did not finish within 300 s"
    exit 1
fi
say "SLURM run done"

# --- checks ---------------------------------------------------------------------------
"$PYTHON" "$REPO/.ci/slurm_check.py" "$WORK/local" "$WORK/cluster" "$WORK/log/slurm-run.log"
say "SLURM stage passed"
