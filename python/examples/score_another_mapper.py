"""Score a map made by another mapper with the testbed's truth, beside the testbed's own map.

    python python/examples/score_another_mapper.py [SCENARIO.toml]

1. ``oeg record --format graph`` writes the scenario's scans as an OctoMap scan graph (what another mapper reads).
2. A deliberately simple mapper, written here in numpy, builds a 0.1 m grid: the highest and lowest hit per cell,
   blocked where they differ by more than the robot's step (a "height range" rule, common in quick elevation
   maps), free elsewhere, unknown where nothing hit.
3. ``oeg.score`` resamples it onto the truth's 0.05 m grid and judges it as ``oeg run`` judges the OEG, and the
   testbed's own run gives the OEG's figures to compare.

The ``oeg`` program comes from ``$OEG_BIN``, the ``PATH`` or the workspace's release build.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any, Dict, Optional, Tuple

import numpy as np
import numpy.typing as npt

import oeg

KEYS = ["num_scored_cells", "unsafe_cells", "blind_cells", "overcautious_cells", "plan_found", "plan_unsafe_cells"]
RESOLUTION_M = 0.1


def oeg_program(root: Path) -> Optional[str]:
    for candidate in [os.environ.get("OEG_BIN", ""), shutil.which("oeg") or "", str(root / "target/release/oeg")]:
        if candidate and Path(candidate).is_file():
            return candidate
    return None


def height_range_map(
    scans: list[oeg.Scan], max_step_m: float
) -> Tuple[npt.NDArray[np.int64], npt.NDArray[np.float64], Tuple[float, float]]:
    """The other mapper: per 0.1 m cell, the highest and lowest hit; returns decision codes, elevations and
    the origin of cell [0, 0]."""
    hits = np.concatenate([s.points[~s.no_return] for s in scans])
    origin = (float(np.floor(hits[:, 0].min())), float(np.floor(hits[:, 1].min())))
    cols = ((hits[:, 0] - origin[0]) // RESOLUTION_M).astype(np.int64)
    rows = ((hits[:, 1] - origin[1]) // RESOLUTION_M).astype(np.int64)
    shape = (int(rows.max()) + 1, int(cols.max()) + 1)
    top = np.full(shape, -np.inf)
    bottom = np.full(shape, np.inf)
    np.maximum.at(top, (rows, cols), hits[:, 2])
    np.minimum.at(bottom, (rows, cols), hits[:, 2])
    seen = np.isfinite(top)
    codes = np.where(seen, np.where(top - bottom > max_step_m, 3, 1), 0)
    return codes, np.where(seen, top, np.nan), origin


def main() -> int:
    root = Path(__file__).resolve().parents[2]
    default = "curb_staircase.toml" if os.environ.get("OEG_EXAMPLE_QUICK") else "default.toml"
    scenario = Path(sys.argv[1]) if len(sys.argv) > 1 else root / "scenarios" / default
    program = oeg_program(root)
    if program is None:
        print("skipped: no oeg program (cargo build --release, or set OEG_BIN)")
        return 0
    with tempfile.TemporaryDirectory(prefix="oeg-score-") as tmp:
        graph = Path(tmp) / "scans.graph"
        subprocess.run([program, "record", str(scenario), "--format", "graph", "--out", str(graph)], check=True)
        scans = oeg.read_graph(graph)
    truth = oeg.truth(scenario)
    codes, elevation, origin = height_range_map(scans, truth.robot["max_step_m"])
    theirs = oeg.score(truth, codes, origin=origin, resolution_m=RESOLUTION_M, elevation=elevation)
    ours = oeg.run_scenario(scenario)
    rows: Dict[str, Dict[str, Any]] = {"height range": theirs.metrics, "OEG (oeg run)": ours.metrics}
    width = max(len(k) for k in KEYS)
    print(f"{scenario.name}: {len(scans)} scans; the other mapper's grid is {codes.shape[0]} x {codes.shape[1]} cells")
    print(" " * width + "".join(f"{name:>16}" for name in rows))
    for k in KEYS:
        print(f"{k:<{width}}" + "".join(f"{str(m[k]):>16}" for m in rows.values()))
    table = theirs.obstacles
    records = table.to_dict("records") if hasattr(table, "to_dict") else table  # a DataFrame, or dicts without pandas
    unsafe = [str(r["name"]) for r in records if r["decision"] == "unsafe"]
    print(f"obstacles the height-range map lets the robot into: {', '.join(unsafe) or 'none'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
