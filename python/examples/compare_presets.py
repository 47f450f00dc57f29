"""Run a scenario with the paper's model and the recommended one, and compare their decisions.

    python python/examples/compare_presets.py [SCENARIO.toml]

Each run is ``oeg run`` with ``--set map.preset=...``; the table lists the metrics that decide whether the
robot would drive where it must not (unsafe) or refuse where it could (over-cautious).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any, Dict, List

import oeg

KEYS = ["unsafe_cells", "overcautious_cells", "uncertain_cells", "elevation_rmse_m", "plan_found"]


def main() -> int:
    root = Path(__file__).resolve().parents[2]
    scenario = Path(sys.argv[1]) if len(sys.argv) > 1 else root / "scenarios" / "default.toml"
    overrides: Dict[str, oeg.SettingValue] = {}
    if os.environ.get("OEG_EXAMPLE_QUICK"):
        overrides["duration_s"] = 3.0
    rows: List[Dict[str, Any]] = []
    for preset in ["paper", "robust"]:
        result = oeg.run_scenario(scenario, {**overrides, "map.preset": preset})
        rows.append({"preset": preset, **{k: result.metrics[k] for k in KEYS}})
        if result.failed:
            print(f"{preset}: {len(result.failed)} expectation(s) failed: {result.failed[0]}")
    width = max(len(k) for k in KEYS)
    print(f"{scenario.name}")
    print(" " * width + "".join(f"{r['preset']:>12}" for r in rows))
    for k in KEYS:
        print(f"{k:<{width}}" + "".join(f"{str(r[k]):>12}" for r in rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
