"""The Python package against the Rust command line: the same inputs give the same bytes and counts, bad
input raises a named Python exception, and the examples run."""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, Dict, List, Tuple

import numpy as np
import pytest

import oeg
from _cli import ROOT, oeg_binary, run_cli

SHARED_DATA = ROOT.parent / "shared" / "data"


def floor_and_box(step_m: float = 0.04) -> np.ndarray:
    """Points every `step_m` on a floor at z = 0 (x 0.5..4, y -1.5..1.5) and on the top of a 0.2 m box (x 2..2.4,
    y -0.2..0.2), seen from (0, 0, 0.5)."""
    x, y = np.meshgrid(np.arange(0.5, 4.0, step_m), np.arange(-1.5, 1.5, step_m))
    floor = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    on_box = (floor[:, 0] >= 2.0) & (floor[:, 0] <= 2.4) & (np.abs(floor[:, 1]) <= 0.2)
    floor[on_box, 2] = 0.2
    return floor


@pytest.fixture
def mapped() -> oeg.Map:
    m = oeg.Map(0.1, model="robust")
    m.integrate([0.0, 0.0, 0.5], floor_and_box())
    return m


def test_save_and_load_round_trip_every_layer_and_the_memory(mapped: oeg.Map, tmp_path: Path) -> None:
    path = tmp_path / "map.oeg"
    mapped.save(path)
    loaded = oeg.load(path)
    assert loaded.num_scans == mapped.num_scans == 1
    # The loaded map holds the cells without the integration's scratch buffers.
    assert 0 < loaded.memory_bytes() <= mapped.memory_bytes()
    assert loaded.model == mapped.model
    for name in oeg.LAYERS:
        a, b = mapped.layer(name), loaded.layer(name)
        assert a.extent == b.extent
        np.testing.assert_array_equal(a.values, b.values)
    # Saving the loaded map gives the same bytes.
    again = tmp_path / "again.oeg"
    loaded.save(again)
    assert again.read_bytes() == path.read_bytes()


def test_layers_have_imshow_orientation_and_units(mapped: oeg.Map) -> None:
    elevation = mapped.layer("elevation_m")
    x0, x1, y0, y1 = elevation.extent
    rows, cols = elevation.values.shape
    assert elevation.values.dtype == np.float32
    assert (x1 - x0) == pytest.approx(cols * 0.1) and (y1 - y0) == pytest.approx(rows * 0.1)
    # The box at x 2.0..2.4, y -0.2..0.2 stands 0.2 m above the floor, in the row of y = 0.
    row, col = int((0.0 - y0) / 0.1), int((2.2 - x0) / 0.1)
    assert elevation.values[row, col] == pytest.approx(0.2, abs=0.05)
    assert abs(float(np.nanmedian(elevation.values[:, : int((1.5 - x0) / 0.1)]))) < 0.02
    decisions = mapped.traversability()
    assert decisions.values.dtype == np.uint8
    assert oeg.DECISIONS[int(decisions.values[row, col])] == "blocked"
    # A robot that climbs 0.3 m drives over it.
    climber = mapped.traversability(robot={"max_step_m": 0.3})
    assert oeg.DECISIONS[int(climber.values[row, col])] != "blocked"


def test_layer_counts_equal_oeg_inspect_on_the_same_map(mapped: oeg.Map, tmp_path: Path) -> None:
    path = tmp_path / "map.oeg"
    mapped.save(path)
    text = run_cli("inspect", str(path))

    def count(label: str) -> int:
        found = re.search(rf"^\s*{label}:\s+(\d+)", text, re.MULTILINE)
        assert found, f"{label} not in {text}"
        return int(found.group(1))

    codes = oeg.load(path).traversability().values
    assert count("observed cells") == mapped.num_observed_cells() == int((codes != 0).sum())
    assert count("free") == int((codes == 1).sum())
    assert count("traversable") == int((codes == 2).sum())
    assert count("blocked") == int((codes == 3).sum())


def test_a_map_from_python_is_the_same_bytes_as_oeg_map_on_the_same_scans(tmp_path: Path) -> None:
    # `oeg demo` maps its own scan graph at 5 cm with max_height_m 0.5 and keeps the graph beside the map.
    out = tmp_path / "demo"
    run_cli("demo", "--out", str(out))
    m = oeg.Map(0.05, model={"max_height_m": 0.5})
    for scan in oeg.read_graph(out / "demo.graph"):
        assert scan.points.shape[1] == 3 and not scan.no_return.any()
        m.integrate_scan(scan)
    mine = tmp_path / "mine.oeg"
    m.save(mine)
    assert mine.read_bytes() == (out / "map.oeg").read_bytes()


def test_run_scenario_gives_the_metrics_of_oeg_run_bit_for_bit(tmp_path: Path) -> None:
    scene = ROOT / "tests" / "scenes" / "decisions.toml"
    cli_out, py_out = tmp_path / "cli", tmp_path / "py"
    # A 3 s drive misses the scene's expectations: both sides report the same metrics anyway.
    run_cli("run", str(scene), "--set", "duration_s=3.0", "--out", str(cli_out), check=False)
    result = oeg.run_scenario(scene, {"duration_s": 3.0}, out=py_out)
    assert (py_out / "metrics.json").read_bytes() == (cli_out / "metrics.json").read_bytes()
    assert result.metrics == json.loads((cli_out / "metrics.json").read_text())
    assert result.out_dir == py_out
    assert len(result.obstacles) > 0
    # Without `out`, nothing is left behind and the metrics are the same.
    again = oeg.run_scenario(scene, ["duration_s=3.0"])
    assert again.out_dir is None and again.metrics == result.metrics


def test_scoring_the_testbeds_own_map_gives_the_counts_of_oeg_run(tmp_path: Path) -> None:
    scene = ROOT / "tests" / "scenes" / "decisions.toml"
    short = {"duration_s": 3.0}
    run = oeg.run_scenario(scene, short, out=tmp_path / "run")
    truth = oeg.truth(scene, short)
    assert truth.has_observability and truth.scenario == "decisions"
    # The map's layers over the truth's region, as another mapper would export them.
    m = oeg.load(tmp_path / "run" / "map.oeg")
    x0, x1, y0, y1 = truth.extent
    h = truth.resolution_m / 2
    region = (x0 + h, y0 + h, x1 - h, y1 - h)
    decisions, extent = m.traversability(robot=truth.robot, region=region)
    assert extent == pytest.approx(truth.extent)
    layer = {n: m.layer(n, region).values for n in ("elevation_m", "variance_m2", "occupancy_probability")}
    s = oeg.score(
        truth,
        decisions,
        origin=truth.origin,
        resolution_m=truth.resolution_m,
        elevation=layer["elevation_m"],
        variance=layer["variance_m2"],
        occupancy=layer["occupancy_probability"],
    )
    for key, value in run.metrics.items():
        if key.startswith("doubt_"):
            # Arrays say what the map decided, not why.
            assert s.metrics[key] is None, key
            continue
        expected = 0 if key in ("map_bytes", "num_scans", "num_rays") else value
        assert s.metrics[key] == expected, key
    assert s.metrics["num_scored_cells"] > 1000
    # The per-obstacle table is the run's, row for row.
    columns = ["name", "sensor_returns", "num_observed_cells", "unsafe_cells", "blind_cells", "decision"]
    assert s.obstacles[columns].values.tolist() == run.obstacles[columns].values.tolist()
    assert set(s.plan["path"]) == {"map", "truth"}
    # The truth's layers agree with the verdicts: every scored truly blocked cell is right, unsafe or uncertain.
    t = truth.layers()
    assert t["truly_blocked"].shape == decisions.shape == t["observed_step"].shape
    scored = (decisions != 0) & ~np.isnan(t["elevation_m"])
    blocked = int((t["truly_blocked"] & scored).sum())
    mx = s.metrics
    assert blocked == mx["right_blocked_cells"] + mx["unsafe_cells"] + mx["uncertain_truly_blocked_cells"]
    assert set(np.unique(t["truth_class"])) <= set(oeg.TRUTH_CLASSES)


def test_a_coarse_map_is_resampled_and_bad_arrays_raise_named_exceptions() -> None:
    truth = oeg.truth(ROOT / "tests" / "scenes" / "decisions.toml", observability=False)
    assert not truth.has_observability and "observed_step" not in truth.layers()
    # One blocked 1 m cell over the start: the 20 x 20 truth cells under it are scored, nothing else.
    one = oeg.score(truth, np.array([[3]], dtype=np.uint8), origin=(-0.5, -0.5), resolution_m=1.0)
    assert one.metrics["num_scored_cells"] == 400
    assert one.metrics["right_blocked_cells"] + one.metrics["overcautious_cells"] == 400
    assert one.obstacles["sensor_returns"].isna().all()
    codes = np.ones((2, 2), dtype=np.int64)
    with pytest.raises(TypeError, match="integer codes"):
        oeg.score(truth, codes.astype(np.float32), origin=(0, 0), resolution_m=0.05)
    with pytest.raises(ValueError, match="decision code 7 at element 1"):
        oeg.score(truth, np.array([[1, 7]]), origin=(0, 0), resolution_m=0.05)
    with pytest.raises(ValueError, match=r"elevation: shape \(1, 4\)"):
        oeg.score(truth, codes, origin=(0, 0), resolution_m=0.05, elevation=np.zeros((1, 4)))
    with pytest.raises(ValueError, match="variances: -1"):
        oeg.score(truth, codes, origin=(0, 0), resolution_m=0.05, elevation=np.zeros((2, 2)), variance=-np.ones((2, 2)))
    with pytest.raises(ValueError, match="resolution 0"):
        oeg.score(truth, codes, origin=(0, 0), resolution_m=0.0)
    with pytest.raises(FileNotFoundError):
        oeg.truth(ROOT / "no_such.toml")


def test_a_python_planner_drives_a_closed_loop_and_its_exceptions_are_events(tmp_path: Path) -> None:
    scene = ROOT / "tests" / "scenes" / "nav_blind.toml"
    calls: List[Tuple[float, float]] = []

    def straight(layers: Dict[str, Any], start: Tuple[float, float], goal: Tuple[float, float]) -> np.ndarray:
        decisions = layers["decisions"]
        assert decisions.dtype == np.uint8 and decisions.shape == layers["elevation_m"].shape
        x0, x1, y0, y1 = layers["extent"]
        assert x0 <= start[0] <= x1 and y0 <= goal[1] <= y1
        calls.append(start)
        return np.array([start, goal])

    # Planning at every replanning time ("when_invalid" asks the planner again only once the path is blocked).
    settings = {"duration_s": 6.0, "navigation.replan": "periodic"}
    result = oeg.run_scenario(scene, settings, out=tmp_path / "ok", planner=straight)
    assert len(calls) >= 2, "replanned on the way"
    navigation = json.loads((tmp_path / "ok" / "navigation.json").read_text())
    assert navigation["planner"] == "callback"
    assert "nav_reached" in result.metrics

    def broken(layers: Dict[str, Any], start: Tuple[float, float], goal: Tuple[float, float]) -> None:
        raise ValueError("no map for me")

    oeg.run_scenario(scene, {"duration_s": 3.0}, out=tmp_path / "broken", planner=broken)
    with open(tmp_path / "broken" / "events.csv", newline="") as f:
        events = list(csv.DictReader(f))
    failed = [e for e in events if e["kind"] == "planner_failed"]
    assert failed and "ValueError: no map for me" in failed[0]["message"], events


def test_long_calls_release_the_gil() -> None:
    scene = ROOT / "tests" / "scenes" / "decisions.toml"
    worker = threading.Thread(target=oeg.run_scenario, args=(scene, {"duration_s": 3.0}))
    ticks = 0
    worker.start()
    while worker.is_alive():
        ticks += 1
        time.sleep(0.001)
    worker.join()
    # The run takes seconds; with the GIL held this thread would not have run at all meanwhile.
    assert ticks > 100, ticks


def test_ctrl_c_interrupts_a_run_with_keyboard_interrupt_and_leaves_nothing(tmp_path: Path) -> None:
    out = tmp_path / "out"
    # Python turns Ctrl-C into KeyboardInterrupt only where SIGINT was not ignored when it started (a job put
    # in the background by a non-interactive shell ignores it): the child installs the handler an interactive
    # session has.
    code = (
        "import signal, sys, oeg\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "print('started', flush=True)\n"
        "try:\n"
        "    oeg.run_scenario(sys.argv[1], out=sys.argv[2])\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted', flush=True)\n"
        "    sys.exit(3)\n"
    )
    child = subprocess.Popen(
        [sys.executable, "-c", code, str(ROOT / "scenarios" / "default.toml"), str(out)],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert child.stdout is not None and child.stdout.readline().strip() == "started"
    time.sleep(2.0)
    interrupted_at = time.monotonic()
    child.send_signal(signal.SIGINT)
    stdout, _ = child.communicate(timeout=60)
    assert child.returncode == 3 and "interrupted" in stdout, stdout
    assert time.monotonic() - interrupted_at < 10.0
    assert not out.exists(), "a cancelled run leaves no output folder"


def test_plan_returns_a_path_through_cell_centres(mapped: oeg.Map) -> None:
    path = oeg.plan(mapped, (1.0, -1.0), (3.5, 1.0), {"planner.inflation_radius_m": 0.1})
    assert path is not None and path.shape[1] == 2 and len(path) > 5
    assert np.allclose(path[0], (1.05, -0.95)) and np.allclose(path[-1], (3.55, 1.05))
    # Nothing reaches a goal far outside what was seen when unknown cells are avoided.
    assert oeg.plan(mapped, (1.0, 0.0), (30.0, 0.0), {"planner.unknown": "avoid"}) is None


@pytest.mark.parametrize(
    "points, error",
    [
        (np.zeros((5, 3), dtype=np.int64), TypeError),
        (np.zeros((5, 2)), TypeError),
        (np.zeros(5), TypeError),
        ([[1.0, 2.0, 3.0]], TypeError),
        (np.array([[1.0, 0.0, 0.0], [np.nan, 0.0, 0.0]]), ValueError),
        (np.array([[1.0, 0.0, np.inf]], dtype=np.float32), ValueError),
    ],
)
def test_bad_points_raise_a_named_python_exception(points: object, error: type) -> None:
    m = oeg.Map(0.1)
    with pytest.raises(error, match="points_xyz"):
        m.integrate([0.0, 0.0, 0.5], points)  # type: ignore[arg-type]
    assert m.num_scans == 0


def test_bad_arguments_and_files_raise_named_exceptions(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="preset"):
        oeg.Map(0.1, model="best")
    with pytest.raises(ValueError, match="no_such_key"):
        oeg.Map(0.1, model={"no_such_key": 1.0})
    with pytest.raises(ValueError):
        oeg.Map(-1.0)
    m = oeg.Map(0.1)
    with pytest.raises(ValueError, match="origin_xyz"):
        m.integrate([0.0, 0.0], np.zeros((1, 3)))
    with pytest.raises(ValueError, match="no_return"):
        m.integrate([0.0, 0.0, 0.5], np.ones((3, 3)), no_return=np.zeros(2, dtype=bool))
    with pytest.raises(ValueError, match="range_variance_m2"):
        m.integrate([0.0, 0.0, 0.5], np.ones((1, 3)), range_variance_m2=np.array([-1.0]))
    with pytest.raises(ValueError, match="layer"):
        m.layer("height")
    with pytest.raises(ValueError, match="observed nothing"):
        m.layer("elevation_m")
    missing = tmp_path / "missing.oeg"
    for call in (
        lambda: oeg.load(missing),
        lambda: oeg.read_graph(missing),
        lambda: oeg.read_pcd(missing),
        lambda: oeg.run_scenario(missing),
        lambda: oeg.load_sweep(tmp_path),
    ):
        with pytest.raises(FileNotFoundError, match="missing|runs.jsonl"):
            call()
    corrupt = tmp_path / "corrupt.oeg"
    corrupt.write_bytes(b"OEGMAP\x00\x01" + bytes(40))
    with pytest.raises(oeg.OegError, match="corrupt.oeg"):
        oeg.load(corrupt)
    scene = ROOT / "tests" / "scenes" / "decisions.toml"
    with pytest.raises(TypeError, match="duration_s"):
        oeg.run_scenario(scene, {"duration_s": [3.0]})  # type: ignore[dict-item]
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 'x'\nno_such_key = 1\n")
    with pytest.raises(oeg.OegError, match="bad.toml"):
        oeg.run_scenario(bad)


def test_no_return_rays_clear_and_per_ray_variances_weigh_the_estimate() -> None:
    points = np.array([[2.0, 0.0, 0.0], [2.0, 0.5, 0.0]])
    m = oeg.Map(0.1)
    stats = m.integrate([0.0, 0.0, 0.5], points, no_return=np.array([False, True]))
    assert stats == {"num_rays": 2, "num_cell_visits": stats["num_cell_visits"], "num_scans": 1}
    precise, vague = oeg.Map(0.1), oeg.Map(0.1)
    precise.integrate([0.0, 0.0, 0.5], points[:1], range_variance_m2=np.array([1e-6]))
    vague.integrate([0.0, 0.0, 0.5], points[:1], range_variance_m2=np.array([1e-2]))
    region = (1.95, -0.05, 2.05, 0.05)
    assert np.nanmax(precise.layer("variance_m2", region).values) < np.nanmax(vague.layer("variance_m2", region).values)


def test_float32_and_float64_points_give_the_same_map() -> None:
    points = floor_and_box(0.1)
    a, b = oeg.Map(0.1), oeg.Map(0.1)
    a.integrate([0.0, 0.0, 0.5], points.astype(np.float32).astype(np.float64))
    b.integrate([0.0, 0.0, 0.5], points.astype(np.float32))
    np.testing.assert_array_equal(a.layer("elevation_m").values, b.layer("elevation_m").values)
    # A Fortran-ordered copy reads the same.
    c = oeg.Map(0.1)
    c.integrate([0.0, 0.0, 0.5], np.asfortranarray(points.astype(np.float32)))
    np.testing.assert_array_equal(a.layer("elevation_m").values, c.layer("elevation_m").values)


def test_load_sweep_reads_the_rows_of_oeg_sweep_run(tmp_path: Path) -> None:
    out = tmp_path / "sweep"
    run_cli("sweep", "run", str(ROOT / "sweeps" / "smoke.toml"), "--out", str(out))
    rows = oeg.load_sweep(out)
    lines = [l for l in (out / "runs.jsonl").read_text().splitlines() if l.strip()]
    assert len(rows) == len(lines) > 0
    assert "elevation_rmse_m" in rows.columns


@pytest.mark.skipif(not SHARED_DATA.is_dir(), reason=f"{SHARED_DATA} is absent: the real-data checks need it")
def test_real_scans_map_from_python() -> None:
    scans = oeg.read_graph(SHARED_DATA / "spherical_scan.graph")
    m = oeg.Map(0.1)
    for s in scans:
        m.integrate_scan(s)
    assert m.num_observed_cells() > 500
    cloud = oeg.read_pcd(SHARED_DATA / "office1.pcd")
    assert cloud.points.shape[1] == 3


EXAMPLES = sorted((ROOT / "python" / "examples").glob("*.py"))


@pytest.mark.parametrize("example", EXAMPLES, ids=[e.stem for e in EXAMPLES])
def test_the_examples_run(example: Path, tmp_path: Path) -> None:
    env = dict(os.environ, MPLBACKEND="Agg", OEG_EXAMPLE_OUT=str(tmp_path), OEG_EXAMPLE_QUICK="1")
    args = [sys.executable, str(example)]
    if example.stem == "sweep_metric":
        sweep = tmp_path / "sweep"
        run_cli("sweep", "run", str(ROOT / "sweeps" / "smoke.toml"), "--out", str(sweep))
        args.append(str(sweep))
    done = subprocess.run(args, capture_output=True, text=True, cwd=ROOT, env=env)
    assert done.returncode == 0, done.stdout + done.stderr
    if example.stem in ("map_real_scans", "sweep_metric") and "skipped" not in done.stdout:
        assert any(p.suffix == ".png" for p in tmp_path.iterdir()), done.stdout


def test_the_examples_pass_mypy_strict() -> None:
    if shutil.which("mypy") is None and not _has_module("mypy"):
        pytest.skip("mypy is not installed")
    files: List[str] = [str(e) for e in EXAMPLES] + [str(ROOT / "python" / "oeg")]
    done = subprocess.run([sys.executable, "-m", "mypy", "--strict", *files], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stdout + done.stderr


def _has_module(name: str) -> bool:
    import importlib.util

    return importlib.util.find_spec(name) is not None


def test_a_scan_too_large_for_memory_raises_memory_error() -> None:
    overcommit = Path("/proc/sys/vm/overcommit_memory")
    if overcommit.exists() and overcommit.read_text().strip() == "1":
        pytest.skip("the kernel grants every allocation (vm.overcommit_memory = 1): it cannot refuse one")
    # A view of 10^11 points that costs no memory itself: reading it in would need 2.4 TB.
    points = np.broadcast_to(np.zeros(3, dtype=np.float32), (10**11, 3))
    m = oeg.Map(resolution_m=0.1)
    with pytest.raises(MemoryError, match="points_xyz"):
        m.integrate(np.zeros(3), points)
    assert m.num_scans == 0


def test_ctrl_c_stops_a_long_scan_with_keyboard_interrupt_and_leaves_the_map_as_it_was() -> None:
    # As above: the handler an interactive session has, whatever SIGINT's disposition in this process.
    code = (
        "import signal, sys, numpy as np, oeg\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "m = oeg.Map(resolution_m=0.05)\n"
        "angles = np.linspace(0, 2 * np.pi, 8_000_000, dtype=np.float64)\n"
        "points = np.stack([20 * np.cos(angles), 20 * np.sin(angles), np.zeros_like(angles)], axis=1)\n"
        "print('started', flush=True)\n"
        "try:\n"
        "    m.integrate(np.array([0.0, 0.0, 0.5]), points)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted', m.num_scans, m.memory_bytes() < 10_000_000, flush=True)\n"
        "    sys.exit(3)\n"
    )
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert child.stdout is not None and child.stdout.readline().strip() == "started"
    time.sleep(2.0)
    interrupted_at = time.monotonic()
    child.send_signal(signal.SIGINT)
    stdout, _ = child.communicate(timeout=120)
    assert child.returncode == 3, stdout
    assert "interrupted 0" in stdout, stdout
    assert time.monotonic() - interrupted_at < 5.0
