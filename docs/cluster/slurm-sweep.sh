#!/usr/bin/env bash
# One shard of a sweep per task of a Slurm job array. Submit from the repository root, with the output folder on
# storage every node sees:
#
#   SWEEP=sweeps/laser_noise.toml OUT=/shared/oeg/laser_noise \
#       sbatch --array=1-8 --export=ALL docs/cluster/slurm-sweep.sh
#
# `oeg sweep run` reads its shard from SLURM_ARRAY_TASK_ID within SLURM_ARRAY_TASK_MIN..MAX, so any array
# (1-8, 0-7, 10-17) splits the plan into as many shards as it has tasks, each run in exactly one. A task that is
# killed or requeued resumes where it stopped. Then merge and report, once every task has finished:
#
#   sbatch --dependency=afterok:<array job id> --export=ALL --wrap \
#       "oeg sweep merge $OUT/shard-* --out $OUT/merged && oeg sweep report $OUT/merged"
#
#SBATCH --job-name=oeg-sweep
#SBATCH --cpus-per-task=2
#SBATCH --output=oeg-sweep-%A_%a.out
#SBATCH --requeue
set -euo pipefail
: "${SWEEP:?set SWEEP to a sweep file}" "${OUT:?set OUT to the output folder}"
OEG=${OEG:-oeg}
exec "$OEG" sweep run "$SWEEP" --out "$OUT/shard-${SLURM_ARRAY_TASK_ID:?not in a job array}" \
    --jobs "${SLURM_CPUS_PER_TASK:-1}"
