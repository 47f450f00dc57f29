"""Map the shared real scans (an OctoMap scan graph) and plot the map's layers with matplotlib.

    python python/examples/map_real_scans.py [SCAN.graph]

Writes ``real_scans_layers.png`` into $OEG_EXAMPLE_OUT (default: the current folder). Without a file and
without ``../shared/data`` beside the project, it says so and does nothing.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import oeg


def main() -> int:
    default = Path(__file__).resolve().parents[3] / "shared" / "data" / "spherical_scan.graph"
    path = Path(sys.argv[1]) if len(sys.argv) > 1 else default
    if not path.is_file():
        print(f"skipped: {path} is absent (give an OctoMap .graph file)")
        return 0
    scans = oeg.read_graph(path)
    if os.environ.get("OEG_EXAMPLE_QUICK"):
        scans = scans[:3]
    m = oeg.Map(0.1, model="robust")
    rays = sum(m.integrate_scan(s)["num_rays"] for s in scans)
    print(f"{path.name}: {len(scans)} scans, {rays} rays, {m.num_observed_cells()} cells, {m.memory_bytes()} bytes")

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5), constrained_layout=True)
    for ax, (name, label, cmap) in zip(
        axes,
        [
            ("elevation_m", "elevation [m]", "viridis"),
            ("variance_m2", "elevation variance [m²]", "inferno"),
            ("occupancy_probability", "P(occupied)", "Greys"),
        ],
    ):
        layer = m.layer(name)
        image = ax.imshow(layer.values, origin="lower", extent=layer.extent, cmap=cmap)
        ax.set(title=name, xlabel="x [m]", ylabel="y [m]")
        fig.colorbar(image, ax=ax, label=label)
    decisions = m.traversability()
    blocked = float(np.mean(decisions.values == 3))
    fig.suptitle(f"{path.name} at 0.1 m, robust model: {blocked:.1%} of the region blocked")
    out = Path(os.environ.get("OEG_EXAMPLE_OUT", ".")) / "real_scans_layers.png"
    fig.savefig(out, dpi=100)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
