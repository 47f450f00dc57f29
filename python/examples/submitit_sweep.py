"""Run a sweep's shards as a Slurm job array with submitit, then merge them: the study under the scheduler a
group already uses, with no scheduler code in the package.

    pip install submitit
    python python/examples/submitit_sweep.py [SWEEP.toml] [--shards 3] [--out out/submitit]

Each array task runs `oeg sweep run SWEEP --shard I/N` (the command line, so tasks need only the `oeg`
binary, $OEG_BIN or target/release/oeg); `oeg sweep merge` then joins the shards. Where Slurm is reachable
(`sinfo` answers; `scripts/slurm-sweep-check.sh` starts a private one-node cluster and runs this example
against it), submitit submits to it; elsewhere submitit's local executor runs the same tasks as
processes on this machine, and the example says which it used.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
from pathlib import Path

import submitit

ROOT = Path(__file__).resolve().parents[2]


def run_shard(oeg_bin: str, sweep: str, shard: int, shards: int, out: str) -> str:
    """One array task: one shard of the plan into `out/shard-I`."""
    folder = f"{out}/shard-{shard}"
    subprocess.run(
        [oeg_bin, "sweep", "run", sweep, "--shard", f"{shard}/{shards}", "--out", folder, "--jobs", "1"],
        check=True,
    )
    return folder


def slurm_answers() -> bool:
    """Whether a Slurm controller answers (`sinfo` succeeds), not only whether its commands are installed."""
    if shutil.which("sinfo") is None:
        return False
    try:
        return subprocess.run(["sinfo", "-h"], capture_output=True, timeout=10).returncode == 0
    except subprocess.TimeoutExpired:
        return False


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("sweep", nargs="?", default=str(ROOT / "sweeps" / "smoke.toml"))
    parser.add_argument("--shards", type=int, default=3)
    parser.add_argument("--out", default=os.environ.get("OEG_EXAMPLE_OUT", "out") + "/submitit")
    args = parser.parse_args()
    oeg_bin = os.environ.get("OEG_BIN", str(ROOT / "target" / "release" / "oeg"))
    out = Path(args.out).resolve()
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)

    cluster = "slurm" if slurm_answers() else "local"
    executor = submitit.AutoExecutor(folder=out / "logs", cluster=cluster)
    executor.update_parameters(timeout_min=30, cpus_per_task=1, name="oeg-sweep")
    if cluster == "slurm":
        executor.update_parameters(slurm_array_parallelism=args.shards)
    shards = list(range(1, args.shards + 1))
    jobs = executor.map_array(
        run_shard,
        [oeg_bin] * len(shards),
        [args.sweep] * len(shards),
        shards,
        [args.shards] * len(shards),
        [str(out)] * len(shards),
    )
    print(f"submitted {len(jobs)} shard(s) to {cluster}: {', '.join(j.job_id for j in jobs)}")
    folders = [j.result() for j in jobs]
    merged = out / "merged"
    subprocess.run([oeg_bin, "sweep", "merge", *folders, "--out", str(merged)], check=True, capture_output=True)
    rows = sum(1 for line in (merged / "runs.jsonl").read_text().splitlines() if line.strip())
    print(f"merged {len(folders)} shards into {merged}: {rows} runs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
