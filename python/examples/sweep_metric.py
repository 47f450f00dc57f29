"""Load a sweep's rows and plot one metric against an axis, with its 95 % t interval over the seeds.

    python python/examples/sweep_metric.py SWEEP_DIR [METRIC] [AXIS]

SWEEP_DIR is a folder of ``oeg sweep run`` (for example ``oeg sweep run sweeps/smoke.toml --out out/smoke``).
Writes ``sweep_metric.png`` into $OEG_EXAMPLE_OUT (default: the current folder).
"""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path

import matplotlib.pyplot as plt

import oeg

# Two-sided 95 % quantiles of Student's t for 1 to 10 degrees of freedom; 1.96 beyond.
T95 = [12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228]


def main() -> int:
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    rows = oeg.load_sweep(sys.argv[1])
    metric = sys.argv[2] if len(sys.argv) > 2 else "elevation_rmse_m"
    axes = [c for c in rows.columns if "." in c and rows[c].nunique() > 1]
    axis = sys.argv[3] if len(sys.argv) > 3 else axes[0]
    line = "preset" if "preset" in rows.columns else None
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    for name, group in rows.groupby(line) if line else [("all", rows)]:
        stats = group.groupby(axis)[metric].agg(["mean", "std", "count"]).sort_index()
        half = [
            (T95[int(n) - 2] if 2 <= n <= 11 else 1.96) * s / math.sqrt(n) if n > 1 else 0.0
            for s, n in zip(stats["std"], stats["count"])
        ]
        x = stats.index.to_numpy(dtype=float)
        ax.plot(x, stats["mean"], marker="o", label=str(name))
        ax.fill_between(x, stats["mean"] - half, stats["mean"] + half, alpha=0.25)
    ax.set(xlabel=axis, ylabel=metric, title=f"{metric}: mean and 95 % t interval over runs")
    ax.legend(title=line or "")
    out = Path(os.environ.get("OEG_EXAMPLE_OUT", ".")) / "sweep_metric.png"
    fig.savefig(out, dpi=100)
    print(f"{len(rows)} runs; wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
