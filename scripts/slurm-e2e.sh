#!/usr/bin/env bash
# End-to-end test of the Slurm recipe (deploy/slurm) on a single-node Slurm of its own:
# installs Debian's slurmctld, slurmd, slurm-client and munge when they are missing (root),
# starts munged (unless one runs), slurmctld and slurmd without systemd on ports of its
# own, runs a 4-task shard array of a transmission-error run and the dependent merge job,
# then the retry recipe (a lost shard listed by `merge --missing` and resubmitted alone),
# and checks both merged reports against one `rvtol run` byte for byte. Stops every daemon
# it started, whatever happens.
#
# Usage: scripts/slurm-e2e.sh [RVTOL_BINARY]   (default: target/release/rvtol, built)
set -euo pipefail
cd "$(dirname "$0")/.."
started=$(date +%s)
say() { echo "slurm-e2e: $*"; }

if ! command -v sbatch >/dev/null || ! command -v slurmctld >/dev/null \
    || ! command -v slurmd >/dev/null || ! command -v munged >/dev/null; then
    say "installing slurmctld slurmd slurm-client munge"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null
    apt-get install -y -qq --no-install-recommends slurmctld slurmd slurm-client munge >/dev/null
fi

rvtol=${1:-}
if [[ -z "$rvtol" ]]; then
    cargo build --release --locked -q -p rvtol --bin rvtol
    rvtol=$PWD/target/release/rvtol
fi
rvtol=$(realpath "$rvtol")
scenario=$PWD/scenarios/rv40e-transmission.json
samples=20000
shards=4

work=$(mktemp -d /tmp/rvtol-slurm-e2e.XXXXXX)
chmod 755 "$work"
pids=()
cleanup() {
    local status=$?
    for pid in "${pids[@]}"; do
        kill "$pid" 2>/dev/null || true
    done
    for pid in "${pids[@]}"; do
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$pid" 2>/dev/null || true
    done
    if (( status != 0 )); then
        for log in "$work"/*.log "$work"/out/*.out; do
            [[ -f "$log" ]] && { echo "--- $log"; tail -n 20 "$log"; }
        done
    fi
    rm -rf "$work"
    exit "$status"
}
trap cleanup EXIT
trap 'exit 143' INT TERM HUP

# munge: the key the package made, else one of our own; our own daemon unless one answers.
if ! munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1; then
    mkdir -p /run/munge /var/lib/munge /var/log/munge /etc/munge
    if [[ ! -s /etc/munge/munge.key ]]; then
        dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
    fi
    chown -R munge:munge /etc/munge /run/munge /var/lib/munge /var/log/munge 2>/dev/null || true
    chmod 0700 /etc/munge; chmod 0400 /etc/munge/munge.key
    rm -f /run/munge/munged.pid
    runuser -u munge -- munged --force 2>"$work/munged.log" || munged --force 2>>"$work/munged.log"
    for _ in $(seq 50); do [[ -s /run/munge/munged.pid ]] && break; sleep 0.1; done
    pids+=("$(cat /run/munge/munged.pid)")
    munge -n </dev/null | unmunge >/dev/null
fi

node=rvtol-e2e
mkdir -p "$work/state" "$work/spool" "$work/out"
cat > "$work/slurm.conf" <<CONF
ClusterName=rvtol-e2e
SlurmctldHost=$(hostname -s)(127.0.0.1)
MailProg=/bin/true
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
MpiDefault=none
ReturnToService=2
SlurmdTimeout=30
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=e2e Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$work/slurm.conf

slurmctld -D -i -f "$SLURM_CONF" >"$work/slurmctld.out" 2>&1 &
pids+=("$!")
slurmd -D -N "$node" -f "$SLURM_CONF" >"$work/slurmd.out" 2>&1 &
pids+=("$!")
for _ in $(seq 150); do
    sinfo -h -N -o '%t' 2>/dev/null | grep -qE '^(idle|mix|alloc)' && break
    sleep 0.2
done
sinfo -h -N -o '%N %t' | grep -qE 'idle|mix|alloc' || { say "the node did not come up"; sinfo; exit 1; }
say "Slurm up ($(sinfo -V)) after $(( $(date +%s) - started )) s"

export RVTOL=$rvtol SCENARIO=$scenario RVTOL_SHARDS=$shards
export RVTOL_ARGS="--samples $samples --threads 1"
wait_for() {  # job id: waits until Slurm no longer lists it (at most five minutes)
    for _ in $(seq 1500); do
        [[ -z "$(squeue -h -j "$1" 2>/dev/null)" ]] && return 0
        sleep 0.2
    done
    say "job $1 still queued after five minutes"; squeue; return 1
}

# The recipe: the array, and the merge after it.
export OUT=$work/out/run
cd "$work/out"
array=$(sbatch --parsable --array=0-$((shards - 1)) --export=ALL "$OLDPWD/deploy/slurm/rvtol-shards.sbatch")
merge=$(sbatch --parsable --dependency=afterok:"$array" --kill-on-invalid-dep=yes --export=ALL \
    "$OLDPWD/deploy/slurm/rvtol-merge.sbatch")
say "shard array $array, merge job $merge"
wait_for "$merge"
cd "$OLDPWD"
[[ -s "$OUT/report.json" ]] || { say "the merge job wrote no report"; exit 1; }

"$rvtol" run "$scenario" --samples "$samples" --json "$work/single.json" --quiet > "$work/single.txt"
cmp "$OUT/report.json" "$work/single.json"
cmp "$OUT/report.txt" "$work/single.txt"
say "merged report of $shards shards = one process's, byte for byte"

# The retry recipe: a shard lost (its node died), found by merge --missing, resubmitted.
rm "$OUT/shard-2.part" "$OUT/report.json"
missing=$("$rvtol" merge --missing "$OUT"/shard-*.part)
[[ "$missing" == "2" ]] || { say "merge --missing said '$missing', expected 2"; exit 1; }
cd "$work/out"
retry=$(sbatch --parsable --array="$missing" --export=ALL "$OLDPWD/deploy/slurm/rvtol-shards.sbatch")
merge=$(sbatch --parsable --dependency=afterok:"$retry" --kill-on-invalid-dep=yes --export=ALL \
    "$OLDPWD/deploy/slurm/rvtol-merge.sbatch")
wait_for "$merge"
cd "$OLDPWD"
cmp "$OUT/report.json" "$work/single.json"
say "shard $missing resubmitted alone: merged report again byte for byte"
say "passed in $(( $(date +%s) - started )) s"
