#!/usr/bin/env bash
# End-to-end test of the workflow on a real SLURM cluster (profiles/slurm).
#
# On a fresh Debian 12 machine, as root, from any directory:
#   .ci/slurm_e2e.sh [extra snakemake options for the SLURM run]
#
# 1. Installs Debian's slurm-wlm and munge if absent, creates a munge key if
#    absent, starts munged, writes a single-node /etc/slurm/slurm.conf for this
#    machine (node `hostname -s`, CPUs = nproc, RealMemory = MemTotal minus a
#    margin, one default partition) and starts slurmctld and slurmd; waits until
#    the node is idle.  No accounting database: job states come from `squeue`,
#    which keeps finished jobs for MinJobAge = 1 h (the executor plugin's
#    --slurm-status-command squeue); the job completion log is a text file.
# 2. Copies the repository's tracked files twice into a work directory and runs
#    the same subset of the ci study in both: once with local execution
#    (`snakemake --cores N`, in the background) and, at the same time, once
#    through `snakemake --profile profiles/slurm` with the cluster-specific
#    settings on the command line (below).
# 3. Compares the databases of the two runs (.ci/compare_runs.py): the same grid
#    points and rays, the same converged ones, deflections within 1e-9 relative
#    (NaN at the same places), prints the SLURM job ids of the run and the SLURM
#    version, and exits non-zero on any failure or mismatch.
#
# The subset: config/ci.yaml (a whole config) plus an overlay written
# below, and these targets:
#   results/simulated_space/paper.parquet          simulate_row (grouped) + assemble_space
#                                                  (paper space cut to 3 x 3 x 2 probes = 18 points,
#                                                  6 rows)
#   results/simulated_space/scale_free/neo_hookean.parquet
#                                                  simulate_ray_bundle (grouped) + assemble_scale_free_space
#                                                  (X1h/X1d cut to 0.001 and 0.1: 4 bundles; the
#                                                  6 mm ray at 0.001 stops early, so a NaN tail is compared)
#   results/simulated_space/scale_free/geometry/neo_hookean.parquet and
#   .../geometry/strain_stiffening.parquet         simulate_geometry_bundle (grouped) + assemble_geometry_space
#                                                  (a 5 x 5 grid of t_d/a, t_h/a: 5 neo-Hookean jobs of
#                                                  10 rays and 5 stiffening jobs of 30, two SLURM jobs)
#   results/figures/fig4_single_probe.png          simulate_test_curve, identification_test_curves,
#                                                  identification_runs (one identification study) and
#                                                  one figure (test point moved inside the cut space)
#
# Cluster-specific settings, from the environment (defaults for the cluster this
# script builds):
#   SLURM_ACCOUNT=...      slurm_account of every job (default: none; the plugin then
#                          tries to guess one and proceeds without; leave it unset on
#                          the cluster built here: the plugin checks a given account
#                          with sacctmgr/sshare, which need an accounting database)
#   SLURM_PARTITION=...    slurm_partition of every job (default: the partition written here, "ci")
#   SLURM_E2E_CORES=N      cores of one bundle (group) job, snakemake --cores (default: nproc)
#   SLURM_E2E_MEM_MB=M     memory of one bundle job, snakemake --resources mem_mb=M, and
#                          cap of every job's mem_mb (default: min(2000 x cores, node memory))
#   SLURM_E2E_GROUP_COMPONENTS="fe_curves=3 fe_rays=2 fe_geometry=5"
#                          grid rows / ray bundles / geometry jobs per cluster job
#                          (profile: 8, 16 and 8)
#   SLURM_E2E_SETUP=0      use the running cluster as it is: install, configure and start
#                          nothing (and use the plugin's default status command, sacct)
#   SLURM_E2E_STATUS_COMMAND=sacct|squeue   override the status command
#   SLURM_E2E_WORKDIR=DIR  where the two copies go (default: a new temporary directory,
#                          removed after a success; on a multi-node cluster it must be
#                          on a shared file system)
#   SLURM_E2E_KEEP=1       keep the work directory and leave the daemons this script
#                          started running
# Takes about 5 minutes on 2 cores (plus the apt-get install on a fresh machine).
# Any arguments are passed to the SLURM run's snakemake, e.g.
#   .ci/slurm_e2e.sh --slurm-qos short
set -euo pipefail

cd "$(dirname "$0")/.."
REPO=$(pwd)
T0=$SECONDS
say() { printf '\n=== %s (%ds)\n' "$*" "$((SECONDS - T0))"; }
die() { printf 'slurm_e2e: %s\n' "$*" >&2; exit 1; }

SETUP=${SLURM_E2E_SETUP:-1}
PARTITION_NAME=ci                  # the partition this script writes into slurm.conf
CONF=/etc/slurm/slurm.conf
MARK="# written by skinsuction .ci/slurm_e2e.sh"
STATE=/var/lib/slurm-e2e
LOGDIR=/var/log/slurm
STARTED_PIDS=()

cleanup() {
    local rc=$?
    # the local run, if the script stops before it ended
    if [[ -n ${LOCAL_PID:-} ]]; then
        kill "$(cat "$WORK/local.pid" 2>/dev/null)" "$LOCAL_PID" 2>/dev/null || true
    fi
    if [[ ${SLURM_E2E_KEEP:-0} != 1 ]]; then
        # stop only the daemons this script started, by their pid
        local i
        for ((i = ${#STARTED_PIDS[@]} - 1; i >= 0; i--)); do
            kill "${STARTED_PIDS[i]}" 2>/dev/null || true
        done
        if [[ $rc == 0 && -n ${WORK:-} && -z ${SLURM_E2E_WORKDIR:-} ]]; then rm -rf "$WORK"; fi
    fi
    exit "$rc"
}
trap cleanup EXIT

pid_alive() { [[ -s $1 ]] && kill -0 "$(cat "$1")" 2>/dev/null; }

# ------------------------------------------------------------------ the cluster
if [[ $SETUP == 1 ]]; then
    [[ $(id -u) == 0 ]] || die "run as root to set up the cluster (or SLURM_E2E_SETUP=0)"
    say "SLURM and munge"
    if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null ||
        ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -q
        apt-get install -y -q slurm-wlm munge
    fi

    # munge: a key (once), then the daemon as user munge
    if [[ ! -s /etc/munge/munge.key ]]; then
        mkdir -p /etc/munge
        if command -v mungekey >/dev/null; then
            mungekey --create --keyfile=/etc/munge/munge.key --force
        else
            dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
        fi
    fi
    chown munge:munge /etc/munge/munge.key && chmod 0400 /etc/munge/munge.key
    if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
        mkdir -p /run/munge /var/log/munge /var/lib/munge
        chown munge:munge /run/munge /var/log/munge /var/lib/munge
        chmod 0755 /run/munge
        runuser -u munge -- /usr/sbin/munged
        for _ in $(seq 50); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break; sleep 0.2; done
        munge -n | unmunge >/dev/null || die "munged does not answer"
        [[ -s /run/munge/munged.pid ]] && STARTED_PIDS+=("$(cat /run/munge/munged.pid)")
    fi

    # slurm.conf for this machine (never overwrites one this script did not write)
    NODE=$(hostname -s)
    CPUS=$(nproc)
    MEM_TOTAL_MB=$(($(awk '/^MemTotal:/ {print $2}' /proc/meminfo) / 1024))
    MARGIN_MB=$((MEM_TOTAL_MB / 10 > 512 ? MEM_TOTAL_MB / 10 : 512))
    NODE_MEM_MB=$((MEM_TOTAL_MB - MARGIN_MB))
    if [[ -e $CONF ]] && ! grep -qF "$MARK" "$CONF"; then
        die "$CONF exists and was not written by this script: leaving it alone (SLURM_E2E_SETUP=0 uses it)"
    fi
    mkdir -p /etc/slurm "$STATE/slurmctld" "$STATE/slurmd" "$LOGDIR"
    cat >"$CONF" <<EOF
$MARK: a single node, no accounting database
ClusterName=skinsuction-ci
SlurmctldHost=$NODE(127.0.0.1)
SlurmUser=root
AuthType=auth/munge
StateSaveLocation=$STATE/slurmctld
SlurmdSpoolDir=$STATE/slurmd
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$LOGDIR/slurmctld.log
SlurmdLogFile=$LOGDIR/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
ReturnToService=2
# finished jobs stay visible to squeue for an hour: the workflow's status checks
# (--slurm-status-command squeue) and the job id listing below rely on it
MinJobAge=3600
JobAcctGatherType=jobacct_gather/linux
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$LOGDIR/jobcomp.log
DefMemPerCPU=1000
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=$NODE_MEM_MB State=UNKNOWN
PartitionName=$PARTITION_NAME Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF
    say "slurmctld and slurmd on $NODE: $CPUS CPUs, $NODE_MEM_MB MB"
    # daemons left by an earlier run of this script: restart them with this configuration
    for pidfile in "$STATE/slurmd.pid" "$STATE/slurmctld.pid"; do
        if pid_alive "$pidfile"; then
            kill "$(cat "$pidfile")"
            for _ in $(seq 50); do pid_alive "$pidfile" || break; sleep 0.2; done
        fi
    done
    slurmctld -c
    for _ in $(seq 50); do pid_alive "$STATE/slurmctld.pid" && scontrol ping >/dev/null 2>&1 && break; sleep 0.2; done
    if ! pid_alive "$STATE/slurmctld.pid"; then
        tail -n 30 "$LOGDIR/slurmctld.log" || true
        die "slurmctld did not start"
    fi
    STARTED_PIDS+=("$(cat "$STATE/slurmctld.pid")")
    slurmd
    for _ in $(seq 50); do pid_alive "$STATE/slurmd.pid" && break; sleep 0.2; done
    if ! pid_alive "$STATE/slurmd.pid"; then
        tail -n 30 "$LOGDIR/slurmd.log" || true
        die "slurmd did not start"
    fi
    STARTED_PIDS+=("$(cat "$STATE/slurmd.pid")")
    state=
    for _ in $(seq 60); do
        state=$(sinfo -h -N -n "$NODE" -o %t 2>/dev/null || true)
        [[ $state == idle ]] && break
        sleep 1
    done
    if [[ $state != idle ]]; then
        sinfo -N -l || true
        tail -n 30 "$LOGDIR/slurmctld.log" "$LOGDIR/slurmd.log" || true
        die "node $NODE is '$state', not idle"
    fi
    sinfo
    DEFAULT_STATUS=squeue
    DEFAULT_PARTITION=$PARTITION_NAME
else
    NODE_MEM_MB=$(sinfo -h -o %m | tr -dc "0-9\n" | sort -n | head -n 1)
    NODE_MEM_MB=${NODE_MEM_MB:-16000}
    DEFAULT_STATUS=
    DEFAULT_PARTITION=
fi
SLURM_VERSION=$(sinfo --version)
echo "$SLURM_VERSION"

# ------------------------------------------------------------ the two copies
WORK=${SLURM_E2E_WORKDIR:-$(mktemp -d "${TMPDIR:-/tmp}/skinsuction-slurm-e2e.XXXXXX")}
mkdir -p "$WORK"
WORK=$(cd "$WORK" && pwd)
say "two copies of the tracked files in $WORK"
for run in local slurm; do
    rm -rf "${WORK:?}/$run" && mkdir -p "$WORK/$run"
    git -C "$REPO" ls-files -z | tar --null -T - --ignore-failed-read -cf - 2>/dev/null |
        tar -xf - -C "$WORK/$run"
    [[ -f $WORK/$run/Snakefile ]] || die "copy to $WORK/$run failed"
done

# the subset (see the header): ci study, smaller paper space, 2 X1h/X1d nodes
OVERLAY=$WORK/e2e_subset.yaml
cat >"$OVERLAY" <<'EOF'
spaces:
  paper:
    x1d: [0.0235, 0.046, 0.0685]        # MPa; all 18 points converge in a second or two
    x1h: [0.00066, 0.00111, 0.00156]
identification:
  target: {x1d: 0.035, x1h: 0.0009}     # inside the cut space
scale_free_space:
  ratio: [0.001, 0.1]                   # the 6 mm ray at 0.001 stops early (NaN tail)
  geometry:                             # 5 x 5 nodes x 2 X1h/X1d = 50 rays in 5 jobs
    t_d_over_a: [0.3, 0.45, 0.7, 1.0, 1.5]
    t_h_over_a: [0.5, 1.0, 2.0, 4.0, 8.0]
    causes:                             # x 3 stiffening nodes (ci.yaml): 150 rays in 5 jobs
      names: [strain_stiffening]
      t_d_over_a: [0.3, 0.45, 0.7, 1.0, 1.5]
      t_h_over_a: [0.5, 1.0, 2.0, 4.0, 8.0]
EOF
CONFIG_ARGS=(--configfile config/ci.yaml "$OVERLAY")  # ci.yaml: whole_config
TARGETS=(
    results/simulated_space/paper.parquet
    results/simulated_space/scale_free/neo_hookean.parquet
    results/simulated_space/scale_free/geometry/neo_hookean.parquet
    results/simulated_space/scale_free/geometry/strain_stiffening.parquet
    results/figures/fig4_single_probe.png
)
DATABASES=(results/simulated_space/paper.parquet results/simulated_space/scale_free/neo_hookean.parquet
           results/simulated_space/scale_free/geometry/neo_hookean.parquet
           results/simulated_space/scale_free/geometry/strain_stiffening.parquet)

# --------------------------------------------------------------- local run
# in the background, beside the SLURM run (which leaves cores idle while it
# polls and while single-core jobs run); both are checked below
say "local run: snakemake --cores $(nproc) (in the background)"
(
    t=$SECONDS
    cd "$WORK/local"
    snakemake --cores "$(nproc)" "${CONFIG_ARGS[@]}" -- "${TARGETS[@]}" &
    echo $! >"$WORK/local.pid"
    wait $!
    echo $((SECONDS - t)) >"$WORK/local.seconds"
) >"$WORK/local.log" 2>&1 &
LOCAL_PID=$!

# ----------------------------------------------------------------- SLURM run
# Cluster-specific settings on the command line, the rest from the profile: its
# default-resources plus account and partition, its set-resources with mem_mb
# capped at what one job may get here, bundle size from --cores/--resources.
CORES=${SLURM_E2E_CORES:-$(nproc)}
MEM_MB=${SLURM_E2E_MEM_MB:-$((2000 * CORES < NODE_MEM_MB ? 2000 * CORES : NODE_MEM_MB))}
GROUP_COMPONENTS=${SLURM_E2E_GROUP_COMPONENTS:-fe_curves=3 fe_rays=2 fe_geometry=5}
PARTITION=${SLURM_PARTITION:-$DEFAULT_PARTITION}
STATUS=${SLURM_E2E_STATUS_COMMAND:-$DEFAULT_STATUS}
mapfile -t RES_ARGS < <(
    cd "$WORK/slurm" && python - "$MEM_MB" "${SLURM_ACCOUNT:-}" "$PARTITION" <<'EOF'
import sys

import yaml

cap, account, partition = int(sys.argv[1]), sys.argv[2], sys.argv[3]
profile = yaml.safe_load(open("profiles/slurm/config.yaml", encoding="utf-8"))
default = dict(profile.get("default-resources") or {})
if account:
    default["slurm_account"] = account
if partition:
    default["slurm_partition"] = partition
if isinstance(default.get("mem_mb"), int):
    default["mem_mb"] = min(default["mem_mb"], cap)
print("--default-resources")
for k, v in default.items():
    print(f"{k}={v!r}" if isinstance(v, str) else f"{k}={v}")
print("--set-resources")
for rule, res in (profile.get("set-resources") or {}).items():
    for k, v in res.items():
        if k == "mem_mb" and isinstance(v, int):
            v = min(v, cap)
        print(f"{rule}:{k}={v!r}" if isinstance(v, str) else f"{rule}:{k}={v}")
EOF
)
[[ ${#RES_ARGS[@]} -gt 2 ]] || die "could not read profiles/slurm/config.yaml"
read -r -a GROUP_ARGS <<<"$GROUP_COMPONENTS"
SLURM_ARGS=(
    --profile profiles/slurm "${CONFIG_ARGS[@]}"
    --cores "$CORES" --resources "mem_mb=$MEM_MB"
    "${RES_ARGS[@]}"
    --group-components "${GROUP_ARGS[@]}"
    --slurm-init-seconds-before-status-checks 5
)
[[ -n $STATUS ]] && SLURM_ARGS+=(--slurm-status-command "$STATUS")
SLURM_ARGS+=("$@")
say "SLURM run: snakemake ${SLURM_ARGS[*]}"
t=$SECONDS
if ! (cd "$WORK/slurm" && snakemake "${SLURM_ARGS[@]}" -- "${TARGETS[@]}") >"$WORK/slurm.log" 2>&1; then
    tail -n 80 "$WORK/slurm.log"
    find "$WORK/slurm/.snakemake/slurm_logs" -name '*.log' -exec tail -n 20 {} + 2>/dev/null || true
    [[ $SETUP == 1 ]] && tail -n 20 "$LOGDIR/slurmctld.log"
    die "the SLURM run failed (log: $WORK/slurm.log)"
fi
SLURM_S=$((SECONDS - t))
grep -E "steps \(100%\) done" "$WORK/slurm.log" | tail -n 1
echo "SLURM run: ${SLURM_S}s"
if ! wait "$LOCAL_PID"; then
    LOCAL_PID=
    tail -n 60 "$WORK/local.log"
    die "the local run failed (log: $WORK/local.log)"
fi
LOCAL_PID=
LOCAL_S=$(cat "$WORK/local.seconds")
grep -E "steps \(100%\) done" "$WORK/local.log" | tail -n 1
echo "local run: ${LOCAL_S}s"

# ------------------------------------------------------- the SLURM job ids
say "SLURM jobs of the run"
RUN_ID=$(sed -n 's/.*SLURM run ID: \([^ ]*\).*/\1/p' "$WORK/slurm.log" | head -n 1)
SUBMITTED=$(grep "has been submitted with SLURM jobid" "$WORK/slurm.log" || true)
mapfile -t JOBIDS < <(sed -n 's/.*SLURM jobid \([0-9_]*\).*/\1/p' <<<"$SUBMITTED")
[[ ${#JOBIDS[@]} -gt 0 ]] || die "no job was submitted to SLURM"
echo "job name (SLURM run ID): $RUN_ID"
echo "SLURM job ids: ${JOBIDS[*]}"
# state, elapsed time and rule or group (the plugin's job comment) of each job
if ! squeue --states=all -h --name "$RUN_ID" -o '%.8i %.10T %.10M  %k' | sort -n | grep .; then
    sacct -X --name "$RUN_ID" -o JobID,State,Elapsed,JobName%40 || true
fi
# every rule of the subset went through SLURM (the log path names the rule or group)
for what in group_fe_curves_simulate_row group_fe_rays_simulate_ray_bundle \
    group_fe_geometry_simulate_geometry_bundle rule_assemble_geometry_space \
    rule_assemble_space rule_assemble_scale_free_space rule_simulate_test_curve \
    rule_identification_test_curves rule_identification_runs rule_fig4_single_probe; do
    n=$(grep -c "slurm_logs/$what/" <<<"$SUBMITTED" || true)
    printf '  %-36s %2d SLURM job(s)\n' "$what" "$n"
    [[ $n -gt 0 ]] || die "no SLURM job ran $what"
done

# ------------------------------------------------------------- comparison
say "comparison of the databases"
python "$REPO/.ci/compare_runs.py" "$WORK/local" "$WORK/slurm" "${DATABASES[@]}" --rtol 1e-9

say "done"
echo "$SLURM_VERSION; SLURM run ${SLURM_S}s (${#JOBIDS[@]} SLURM jobs), local run beside it ${LOCAL_S}s, total $((SECONDS - T0))s"
