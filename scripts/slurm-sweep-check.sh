#!/usr/bin/env bash
# Checks that a sweep sharded over a real Slurm job array merges to the rows of a local run.
#
# Run as root from the repository root (it is not part of .ci/run):
#
#   sudo bash scripts/slurm-sweep-check.sh
#
# 1. installs slurm-wlm and munge from the distribution when they are missing;
# 2. starts a private one-node cluster: its own munged and Slurm daemons, configuration, state, sockets and
#    ports, all under $WORK (default /tmp/oeg-slurm-check), found by Slurm's commands through SLURM_CONF;
# 3. builds `oeg` and submits sweeps/smoke.toml as an array of 3 tasks (`sbatch --array=1-3 --wait`);
# 4. merges the shards and checks that the merged runs.csv equals a local `oeg sweep run` of the same file,
#    byte for byte but for the wall-time column;
# 5. with OEG_PYTHON set to a Python that has the `oeg` package and submitit, runs
#    python/examples/submitit_sweep.py against the same cluster;
# 6. stops the daemons it started, by their process ids, however the script ends.
#
# It never writes /etc/slurm or /etc/munge and never signals a daemon it did not start, so it is safe on a
# machine that runs Slurm for real: the private cluster listens on its own ports (SLURMCTLD_PORT, default
# 16817, and SLURMD_PORT, 16818) and its own munge socket.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
SWEEP=sweeps/smoke.toml
WORK=${WORK:-/tmp/oeg-slurm-check}
CTLD_PORT=${SLURMCTLD_PORT:-16817}
SLURMD_PORT=${SLURMD_PORT:-16818}

if [ "$(id -u)" -ne 0 ]; then
    echo "run as root: slurmd launches the array's tasks, and munged and the Slurm daemons start here" >&2
    exit 2
fi

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    echo "== installing slurm-wlm and munge"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq slurm-wlm munge >/dev/null
fi

# Everything the private cluster writes, and the daemons it started (stopped by pid on exit).
rm -rf "$WORK"
mkdir -p "$WORK"/{etc,munge,state,spool,log,run}
PIDS=()
stop_daemons() {
    for pid in "${PIDS[@]}"; do
        kill "$pid" 2>/dev/null || true
    done
    for pid in "${PIDS[@]}"; do
        for _ in $(seq 1 50); do
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.1
        done
        kill -9 "$pid" 2>/dev/null || true
    done
}
trap stop_daemons EXIT
trap 'exit 130' INT TERM
# The pid a daemon wrote into its pid file, once it has.
pid_of() {
    for _ in $(seq 1 100); do
        if [ -s "$1" ]; then
            cat "$1"
            return 0
        fi
        sleep 0.1
    done
    echo "no pid file $1" >&2
    return 1
}

echo "== starting a private munged ($WORK/munge)"
dd if=/dev/urandom of="$WORK/munge/munge.key" bs=1 count=1024 status=none
chmod 0400 "$WORK/munge/munge.key"
chmod 0700 "$WORK/munge"
MUNGE_SOCKET="$WORK/munge/munge.socket"
munged --force --key-file="$WORK/munge/munge.key" --socket="$MUNGE_SOCKET" \
    --pid-file="$WORK/munge/munged.pid" --log-file="$WORK/log/munged.log" --seed-file="$WORK/munge/seed"
PIDS+=("$(pid_of "$WORK/munge/munged.pid")")
munge --socket="$MUNGE_SOCKET" -n | unmunge --socket="$MUNGE_SOCKET" >/dev/null

echo "== configuring a private one-node Slurm cluster ($WORK/etc/slurm.conf)"
HOST=$(hostname -s)
CPUS=$(nproc)
MEM_MB=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 512))
export SLURM_CONF="$WORK/etc/slurm.conf"
cat > "$SLURM_CONF" <<CONF
ClusterName=oegcheck
SlurmctldHost=$HOST
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$MUNGE_SOCKET
CredType=cred/munge
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/run/slurmctld.pid
SlurmdPidFile=$WORK/run/slurmd.pid
SlurmctldLogFile=$WORK/log/slurmctld.log
SlurmdLogFile=$WORK/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
NodeName=$HOST CPUs=$CPUS RealMemory=$MEM_MB State=UNKNOWN
PartitionName=check Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
# No cgroup.conf: slurmd detects the machine's cgroups itself (Debian 12's Slurm 22.05 has no "disabled"
# cgroup plugin).
slurmctld -c -f "$SLURM_CONF" || { tail -20 "$WORK/log/slurmctld.log"; exit 1; }
PIDS+=("$(pid_of "$WORK/run/slurmctld.pid")")
slurmd -c -f "$SLURM_CONF" || { tail -20 "$WORK/log/slurmd.log"; exit 1; }
PIDS+=("$(pid_of "$WORK/run/slurmd.pid")")
for _ in $(seq 1 30); do
    if sinfo -h -o %T 2>/dev/null | grep -qE 'idle|mixed'; then break; fi
    scontrol update nodename="$HOST" state=resume >/dev/null 2>&1 || true
    sleep 1
done
sinfo

echo "== building oeg"
cargo build --release --quiet
OEG="$ROOT/target/release/oeg"

mkdir -p "$WORK/out"
echo "== submitting $SWEEP as an array of 3 tasks"
SWEEP="$ROOT/$SWEEP" OUT="$WORK/out" OEG="$OEG" sbatch --wait --array=1-3 --cpus-per-task=1 \
    --output="$WORK/out/slurm-%A_%a.out" --export=ALL --chdir="$ROOT" docs/cluster/slurm-sweep.sh
cat "$WORK"/out/slurm-*.out

echo "== merging the shards, and a local run of the same file"
"$OEG" sweep merge "$WORK"/out/shard-1 "$WORK"/out/shard-2 "$WORK"/out/shard-3 --out "$WORK/out/merged"
"$OEG" sweep run "$SWEEP" --out "$WORK/out/local"

strip_wall_time() {
    python3 - "$1" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1], newline="")))
wall = rows[0].index("wall_time_s")
for r in rows:
    print(",".join(r[:wall] + r[wall + 1:]))
PY
}
if cmp -s <(strip_wall_time "$WORK/out/merged/runs.csv") <(strip_wall_time "$WORK/out/local/runs.csv"); then
    echo "OK: the 3 Slurm shards merge to the local run's $(($(wc -l < "$WORK/out/local/runs.csv") - 1)) rows (wall time aside)"
else
    diff <(strip_wall_time "$WORK/out/merged/runs.csv") <(strip_wall_time "$WORK/out/local/runs.csv") | head -20
    echo "FAILED: the merged rows differ from the local run's" >&2
    exit 1
fi

if [ -n "${OEG_PYTHON:-}" ]; then
    echo "== python/examples/submitit_sweep.py against the same cluster"
    OEG_BIN="$OEG" "$OEG_PYTHON" python/examples/submitit_sweep.py --out "$WORK/out/submitit"
fi
