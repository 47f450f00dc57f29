"""Search the lasers' pitch with Optuna's ask-and-tell interface over `oeg run`: fewer cells the map gets
wrong (unsafe) and fewer cells no ray could tell about (blind), two objectives at once.

    pip install optuna
    python python/examples/optuna_lidar_pitch.py [SCENARIO.toml] [--trials 12]

Each trial is one `oeg.run_scenario` of the default scenario with both 2D lasers pitched down by the same
angle (their mounts' `rpy_deg`), scored by the run's `unsafe_cells` and `blind_cells`. The package holds no
search machinery: Optuna asks for a pitch, the testbed runs it, Optuna is told the two counts. Prints the
Pareto front.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import List

import optuna

import oeg


def main() -> int:
    root = Path(__file__).resolve().parents[2]
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scenario", nargs="?", default=str(root / "scenarios" / "default.toml"))
    parser.add_argument("--trials", type=int, default=12)
    args = parser.parse_args()
    quick = bool(os.environ.get("OEG_EXAMPLE_QUICK"))
    trials = 3 if quick else args.trials

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(
        directions=["minimize", "minimize"], sampler=optuna.samplers.TPESampler(seed=2026)
    )
    for _ in range(trials):
        trial = study.ask()
        pitch = trial.suggest_float("laser_pitch_deg", 5.0, 45.0)
        overrides: List[str] = [
            f"sensors.0.rpy_deg=[0.0, {pitch}, 15.0]",
            f"sensors.1.rpy_deg=[0.0, {pitch}, -15.0]",
        ]
        if quick:
            overrides.append("duration_s=3.0")
        metrics = oeg.run_scenario(args.scenario, overrides).metrics
        unsafe, blind = int(metrics["unsafe_cells"]), int(metrics["blind_cells"])
        study.tell(trial, [unsafe, blind])
        print(f"trial {trial.number}: pitch {pitch:5.1f} deg -> {unsafe} unsafe, {blind} blind cells")
    print("Pareto front (pitch, unsafe, blind):")
    for t in sorted(study.best_trials, key=lambda t: t.params["laser_pitch_deg"]):
        print(f"  {t.params['laser_pitch_deg']:5.1f} deg  {t.values[0]:6.0f}  {t.values[1]:6.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
