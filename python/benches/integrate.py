"""The Python binding's cost per scan: integrating the shared real scans from Python against the same scans
integrated by the Rust command line (`oeg map`, whose timing.json gives its integration time), in one run.

    python python/benches/integrate.py [SCAN.graph] [--resolution 0.1] [--repeats 5]

Both sides integrate the same rays into the same model (the defaults of `oeg map`); the Python side's time
covers its `Map.integrate` calls only (the arrays are read beforehand, as a user's would be). Prints the
medians and the overhead per scan. Without the file and without ../shared/data it says so and exits.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import oeg

ROOT = Path(__file__).resolve().parents[2]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("graph", nargs="?", default=str(ROOT.parent / "shared" / "data" / "3dtk_frames.graph"))
    parser.add_argument("--resolution", type=float, default=0.1)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    graph = Path(args.graph)
    if not graph.is_file():
        print(f"skipped: {graph} is absent")
        return 0
    binary = Path(os.environ.get("OEG_BIN", ROOT / "target" / "release" / "oeg"))
    scans = oeg.read_graph(graph)
    rays = sum(len(s.points) for s in scans)

    python_s, rust_s = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.repeats):
            m = oeg.Map(args.resolution)
            started = time.perf_counter()
            for s in scans:
                m.integrate(s.origin, s.points, no_return=s.no_return)
            python_s.append(time.perf_counter() - started)
            out = Path(tmp) / f"run{k}"
            subprocess.run(
                [str(binary), "map", str(graph), "--resolution", str(args.resolution), "--out", str(out)],
                check=True,
                capture_output=True,
            )
            rust_s.append(json.loads((out / "timing.json").read_text())["integrate_wall_time_s"])
    py, rs = statistics.median(python_s), statistics.median(rust_s)
    print(f"{graph.name}: {len(scans)} scans, {rays} rays, {args.resolution} m cells, median of {args.repeats}")
    print(f"  Rust (oeg map, integration):  {rs:.3f} s  ({rays / rs / 1e6:.2f} M rays/s)")
    print(f"  Python (Map.integrate calls): {py:.3f} s  ({rays / py / 1e6:.2f} M rays/s)")
    print(f"  ratio Python / Rust: {py / rs:.3f}; difference {(py - rs) / len(scans) * 1e3:.3f} ms per scan")
    # The fixed cost of one call: a scan of one ray, integrated many times (array checks, the GIL's release
    # and the scan's set-up, with almost no ray to trace).
    m, one, calls = oeg.Map(args.resolution), np.array([[1.0, 0.0, 0.0]]), 20000
    started = time.perf_counter()
    for _ in range(calls):
        m.integrate((0.0, 0.0, 0.5), one)
    per_call = (time.perf_counter() - started) / calls
    print(f"  one call with a 1-ray scan: {per_call * 1e6:.1f} us ({calls} calls)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
