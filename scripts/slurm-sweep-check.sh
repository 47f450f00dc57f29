#!/usr/bin/env bash
# Checks that a sweep sharded over a real Slurm job array merges to the rows of a local run.
#
# For a fresh Debian machine, run as root from the repository root (it installs packages and starts
# services; it is not part of .ci/run):
#
#   sudo bash scripts/slurm-sweep-check.sh
#
# 1. installs slurm-wlm and munge from the distribution and starts a one-node cluster on localhost;
# 2. builds `oeg` and submits sweeps/smoke.toml as an array of 3 tasks (`sbatch --array=1-3 --wait`);
# 3. merges the shards and checks that the merged runs.csv equals a local `oeg sweep run` of the same file,
#    byte for byte but for the wall-time column.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
SWEEP=sweeps/smoke.toml
WORK=${WORK:-/tmp/oeg-slurm-check}

if [ "$(id -u)" -ne 0 ]; then
    echo "run as root: it installs slurm-wlm and munge and starts their daemons" >&2
    exit 2
fi

echo "== installing slurm-wlm and munge"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq slurm-wlm munge >/dev/null

echo "== starting munge"
mkdir -p /etc/munge /var/run/munge /var/lib/munge /var/log/munge
if [ ! -s /etc/munge/munge.key ]; then
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
fi
chown -R munge:munge /etc/munge /var/run/munge /var/lib/munge /var/log/munge
chmod 0400 /etc/munge/munge.key
pgrep -x munged >/dev/null || su -s /bin/sh munge -c /usr/sbin/munged
munge -n | unmunge >/dev/null

echo "== configuring a one-node Slurm cluster"
HOST=$(hostname -s)
CPUS=$(nproc)
MEM_MB=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 512 ))
CONF_DIR=/etc/slurm
[ -d /etc/slurm-llnl ] && [ ! -d /etc/slurm ] && CONF_DIR=/etc/slurm-llnl
mkdir -p "$CONF_DIR" /var/spool/slurmctld /var/spool/slurmd /var/log/slurm
chown -R slurm:slurm /var/spool/slurmctld /var/log/slurm 2>/dev/null || true
cat > "$CONF_DIR/slurm.conf" <<CONF
ClusterName=oegcheck
SlurmctldHost=$HOST
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/var/run/slurmctld.pid
SlurmdPidFile=/var/run/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
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
pkill -x slurmctld 2>/dev/null || true
pkill -x slurmd 2>/dev/null || true
sleep 1
slurmctld -c || { tail -20 /var/log/slurm/slurmctld.log; exit 1; }
slurmd -c || { tail -20 /var/log/slurm/slurmd.log; exit 1; }
for _ in $(seq 1 30); do
    if sinfo -h -o %T 2>/dev/null | grep -qE 'idle|mixed'; then break; fi
    scontrol update nodename="$HOST" state=resume >/dev/null 2>&1 || true
    sleep 1
done
sinfo

echo "== building oeg"
cargo build --release --quiet
OEG="$ROOT/target/release/oeg"

rm -rf "$WORK"
mkdir -p "$WORK"
echo "== submitting $SWEEP as an array of 3 tasks"
SWEEP="$ROOT/$SWEEP" OUT="$WORK" OEG="$OEG" sbatch --wait --array=1-3 --cpus-per-task=1 \
    --output="$WORK/slurm-%A_%a.out" --export=ALL --chdir="$ROOT" docs/cluster/slurm-sweep.sh
cat "$WORK"/slurm-*.out

echo "== merging the shards, and a local run of the same file"
"$OEG" sweep merge "$WORK"/shard-1 "$WORK"/shard-2 "$WORK"/shard-3 --out "$WORK/merged"
"$OEG" sweep run "$SWEEP" --out "$WORK/local"

strip_wall_time() {
    python3 - "$1" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1], newline="")))
wall = rows[0].index("wall_time_s")
for r in rows:
    print(",".join(r[:wall] + r[wall + 1:]))
PY
}
if cmp -s <(strip_wall_time "$WORK/merged/runs.csv") <(strip_wall_time "$WORK/local/runs.csv"); then
    echo "OK: the 3 Slurm shards merge to the local run's $(($(wc -l < "$WORK/local/runs.csv") - 1)) rows (wall time aside)"
else
    diff <(strip_wall_time "$WORK/merged/runs.csv") <(strip_wall_time "$WORK/local/runs.csv") | head -20
    echo "FAILED: the merged rows differ from the local run's" >&2
    exit 1
fi
