"""The Occupancy-Elevation Grid (OEG) and its simulation-backed testbed, from numpy and pandas.

The map, the readers, the planner and the testbed are the project's Rust crates; this package converts
arrays and results and holds no model logic of its own. Long calls release the GIL.

Units are SI and in the names: metres (``_m``), square metres (``_m2``). Arrays of a map's layers have one
row per y (row 0 the minimum y) and one column per x, so that::

    values, extent = m.layer("elevation_m")
    plt.imshow(values, origin="lower", extent=extent)

draws them north up in world metres.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from . import _oeg
from ._oeg import OegError

__all__ = [
    "DECISIONS",
    "LAYERS",
    "Layer",
    "Map",
    "OegError",
    "RunResult",
    "Scan",
    "Score",
    "TRUTH_CLASSES",
    "Truth",
    "load",
    "load_sweep",
    "plan",
    "read_graph",
    "read_pcd",
    "run_scenario",
    "score",
    "truth",
]

__version__: str = _oeg.__version__

PathLike = Union[str, "os.PathLike[str]"]
Extent = Tuple[float, float, float, float]
Region = Tuple[float, float, float, float]
SettingValue = Union[bool, int, float, str]
#: A closed-loop run's planner: ``planner(layers, start, goal)`` returns a ``(k, 2)`` path or ``None``.
Planner = Callable[[Dict[str, Any], Tuple[float, float], Tuple[float, float]], Any]

#: The layers :meth:`Map.layer` returns, with their units.
LAYERS: Dict[str, str] = {
    "occupancy_probability": "probability in [0, 1], NaN where never observed",
    "log_odds": "occupancy log-odds, NaN where never observed",
    "elevation_m": "elevation mean, metres, NaN where there is no estimate",
    "variance_m2": "elevation variance, square metres, NaN where there is no estimate",
    "std_dev_m": "elevation standard deviation, metres, NaN where there is no estimate",
}

#: The codes of :meth:`Map.traversability`, as the planner files' ``decisions.npy`` uses them.
DECISIONS: Dict[int, str] = {
    0: "unknown",
    1: "free",
    2: "traversable",
    3: "blocked",
    4: "uncertain",
}


#: The codes of a truth's ``truth_class`` layer.
TRUTH_CLASSES: Dict[int, str] = {
    0: "off_terrain",
    1: "drivable",
    2: "passable_under",
    3: "step",
    4: "too_low",
}


class Scan(NamedTuple):
    """One scan as arrays, world frame, metres."""

    #: The sensor's origin, shape ``(3,)``.
    origin: npt.NDArray[np.float64]
    #: One point per ray, shape ``(n, 3)``; a no-return ray's point is the origin plus its unit direction.
    points: npt.NDArray[np.float64]
    #: ``True`` for rays with no return, shape ``(n,)``.
    no_return: npt.NDArray[np.bool_]


class Layer(NamedTuple):
    """A 2D array of a map's cells with its extent for ``matplotlib.pyplot.imshow(extent=...)``."""

    #: Shape ``(num_y, num_x)``, row 0 the minimum y: draw with ``origin="lower"``.
    values: npt.NDArray[Any]
    #: ``(x_min, x_max, y_min, y_max)`` in metres.
    extent: Extent


class RunResult(NamedTuple):
    """What :func:`run_scenario` returns."""

    #: ``metrics.json`` as a dict (every key in the project's ``docs/metrics.md``), ``None`` where it writes
    #: ``null``.
    metrics: Dict[str, Any]
    #: ``obstacles.csv``'s rows: a pandas DataFrame when pandas is installed, else a list of dicts.
    obstacles: Any
    #: The scenario's expectations that failed, each with its measured and required value.
    failed: List[str]
    #: The output folder, or ``None`` when the run wrote into a temporary one.
    out_dir: Optional[Path]


class Map:
    """The Occupancy-Elevation Grid: per cell an occupancy probability, an elevation and its variance.

    Args:
        resolution_m: Cell size in metres.
        model: A preset's name (``"paper"``, ``"static"`` or ``"robust"``), or a dict in the scenario
            file's spelling: ``preset`` and ``traversability`` of ``[map]``, every other key of
            ``[map.model]`` (for example ``{"preset": "robust", "max_height_m": 0.5}``).
        memory_limit_bytes: The map's memory limit (default 4 GiB); a map or raster beyond it raises
            :class:`OegError`.

    Raises:
        ValueError: An unknown preset or key, or a value out of range, named.
    """

    def __init__(
        self,
        resolution_m: float,
        model: Union[str, Mapping[str, SettingValue], None] = None,
        memory_limit_bytes: Optional[int] = None,
    ) -> None:
        self._map = _oeg.Map(resolution_m, dict(model) if isinstance(model, Mapping) else model, memory_limit_bytes)

    @classmethod
    def _wrap(cls, native: _oeg.Map) -> "Map":
        m = cls.__new__(cls)
        m._map = native
        return m

    @property
    def resolution_m(self) -> float:
        """Cell size, metres."""
        return self._map.resolution_m

    @property
    def num_scans(self) -> int:
        """Scans integrated so far."""
        return self._map.num_scans

    @property
    def model(self) -> Dict[str, Any]:
        """Every model option, as the scenario files and the map file's header spell them."""
        return dict(self._map.model)

    def integrate(
        self,
        origin_xyz: Union[Sequence[float], npt.NDArray[np.floating[Any]]],
        points_xyz: npt.NDArray[np.floating[Any]],
        no_return: Optional[npt.NDArray[np.bool_]] = None,
        range_variance_m2: Optional[npt.NDArray[np.floating[Any]]] = None,
        sensor: str = "laser",
    ) -> Dict[str, int]:
        """Integrates one scan (the paper's sections 4 and 5), with the GIL released.

        Args:
            origin_xyz: The sensor's origin, world frame, metres.
            points_xyz: ``float32`` or ``float64``, shape ``(n, 3)``: each ray's end point in the world frame,
                or for a no-return ray any point along its direction. Read in place when C-contiguous,
                copied once otherwise; every point must be finite.
            no_return: ``bool``, shape ``(n,)``: rays with no return, which clear and never mark occupied.
            range_variance_m2: ``float32`` or ``float64``, shape ``(n,)``: each hit's range variance
                (square metres), instead of the sensor model's.
            sensor: The range-error model of rays without their own variance: ``"laser"`` (12 mm) or
                ``"stereo"`` (the paper's Fig. 4).

        Returns:
            ``{"num_rays": ..., "num_cell_visits": ..., "num_scans": ...}``.

        Raises:
            TypeError: A wrong dtype or shape, named with what was expected.
            ValueError: A point that is not finite (its row named), a variance that is not positive.
            MemoryError: The points do not fit in memory once read.
            KeyboardInterrupt: Ctrl-C, within a few milliseconds; the map is as it was before the scan.
        """
        rays, visits, scans = self._map.integrate(origin_xyz, points_xyz, no_return, range_variance_m2, sensor)
        return {"num_rays": rays, "num_cell_visits": visits, "num_scans": scans}

    def integrate_scan(self, scan: Scan, sensor: str = "laser") -> Dict[str, int]:
        """Integrates a :class:`Scan` from :func:`read_graph` or :func:`read_pcd`."""
        return self.integrate(scan.origin, scan.points, no_return=scan.no_return, sensor=sensor)

    def layer(self, name: str, region: Optional[Region] = None) -> Layer:
        """One layer over ``region`` (``(x_min, y_min, x_max, y_max)`` in metres; default: the observed region).

        Args:
            name: One of :data:`LAYERS`.

        Returns:
            A ``float32`` array (a copy: the map stores cells in tiles) and its extent.
        """
        values, extent = self._map.layer(name, region)
        return Layer(values, extent)

    def traversability(
        self, robot: Optional[Mapping[str, SettingValue]] = None, region: Optional[Region] = None
    ) -> Layer:
        """Each cell's decision for a robot (codes in :data:`DECISIONS`), ``uint8``.

        Args:
            robot: ``[robot]`` keys of a scenario (``max_step_m`` 0.035, ``height_m`` 0.46, ...).
            region: As for :meth:`layer`.
        """
        values, extent = self._map.traversability(dict(robot) if robot is not None else None, region)
        return Layer(values, extent)

    def memory_bytes(self) -> int:
        """Bytes the map holds: its cells, and after integrating the scratch buffers kept for the next scan."""
        return self._map.memory_bytes()

    def num_observed_cells(self) -> int:
        """Cells observed at least once."""
        return self._map.num_observed_cells()

    def observed_extent(self) -> Optional[Extent]:
        """``(x_min, x_max, y_min, y_max)`` of the observed cells, or ``None`` before any scan."""
        return self._map.observed_extent()

    def save(self, path: PathLike) -> None:
        """Writes the map file (``map.oeg``, the project's ``docs/map-file-format.md``) atomically."""
        self._map.save(os.fspath(path))


def load(path: PathLike, memory_limit_bytes: Optional[int] = None) -> Map:
    """Loads a map file written by :meth:`Map.save`, ``oeg map`` or ``oeg run``.

    Raises:
        FileNotFoundError: The file does not exist.
        OegError: A corrupt or truncated file, named with the byte offset.
    """
    return Map._wrap(_oeg.load(os.fspath(path), memory_limit_bytes))


def read_graph(path: PathLike) -> List[Scan]:
    """Reads an OctoMap scan graph (``.graph``): one :class:`Scan` per node, points in the world frame."""
    return [Scan(*s) for s in _oeg.read_graph(os.fspath(path))]


def read_pcd(
    path: PathLike,
    origin_xyz: Optional[Sequence[float]] = None,
    frame: Optional[str] = None,
    invalid: Optional[str] = None,
) -> Scan:
    """Reads a PCD file as one :class:`Scan`.

    Args:
        origin_xyz: The sensor's origin in the world frame, when the file's viewpoint is not it.
        frame: ``"as_is"`` (default) or ``"optical"`` (x right, y down, z forward).
        invalid: NaN points of an organized cloud: ``"drop"`` (default) or ``"no_return"``.
    """
    return Scan(*_oeg.read_pcd(os.fspath(path), origin_xyz, frame, invalid))


def plan(
    map: Map,
    start: Tuple[float, float],
    goal: Tuple[float, float],
    settings: Optional[Mapping[str, SettingValue]] = None,
) -> Optional[npt.NDArray[np.float64]]:
    """Plans a path on the map as ``oeg plan`` does, with the GIL released.

    Args:
        start, goal: World x and y, metres.
        settings: ``oeg plan``'s keys: ``planner.inflation_radius_m``,
            ``planner.inflation_cost_width_m``, ``planner.cost_scaling_factor``, ``planner.unknown``,
            ``planner.uncertain``, ``robot.max_step_m``, ``robot.height_m``, ``map.traversability`` (the
            paper's absolute step rule unless given) and ``map.preset`` (its step rule: ``"robust"`` judges a
            map as ``oeg run`` judges that preset's maps).

    Returns:
        The path through the cell centres, shape ``(k, 2)``, or ``None`` when the goal cannot be reached.
    """
    return _oeg.plan(map._map, start, goal, dict(settings) if settings is not None else None)


def _overrides(
    overrides: Union[Mapping[str, SettingValue], Sequence[str], None],
) -> Union[Dict[str, SettingValue], List[str]]:
    """A dict for the native side to spell as TOML, or the `KEY=VALUE` strings as they are."""
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        return dict(overrides)
    return [str(o) for o in overrides]


def run_scenario(
    path: PathLike,
    overrides: Union[Mapping[str, SettingValue], Sequence[str], None] = None,
    out: Optional[PathLike] = None,
    seed: Optional[int] = None,
    compare: Optional[str] = None,
    planner: Optional[Planner] = None,
) -> RunResult:
    """Runs a scenario as ``oeg run`` does, with the GIL released, and returns its metrics.

    Ctrl-C stops the run at its next scan and raises ``KeyboardInterrupt``; nothing is left in ``out``.

    Args:
        overrides: Scenario values by their dotted keys, as ``--set`` takes them:
            ``{"map.preset": "robust", "sensors.0.noise.range_sigma_m": 0.02}`` or ``["map.preset=robust"]``.
        out: The output folder; by default a temporary folder, removed before returning.
        seed: Replaces the scenario's seed.
        compare: Also map with this preset, as ``--compare``.
        planner: A closed-loop run's planner, replacing the scenario's: whenever the run plans
            (``[navigation] replan``) it is called as ``planner(layers, start, goal)``. ``layers`` holds the map over the scenario's region as
            ``(num_y, num_x)`` arrays (row 0 the minimum y): ``decisions`` (``uint8``, :data:`DECISIONS`),
            ``elevation_m``, ``variance_m2`` and ``occupancy_probability`` (``float32``), and ``extent``
            ``(x_min, x_max, y_min, y_max)``; ``start`` and ``goal`` are ``(x, y)`` in metres. It returns the
            path as a ``(k, 2)`` array or a list of ``(x, y)`` inside the extent, or ``None`` when there is no
            path. An exception it raises, or a path off the map, is a ``planner_failed`` event of the run.

    Raises:
        FileNotFoundError: The scenario does not exist.
        OegError: A malformed scenario or override, named with its line and column.
    """
    if out is not None:
        m, o, failed, out_dir = _oeg.run_scenario(
            os.fspath(path), _overrides(overrides), os.fspath(out), seed, compare, planner
        )
        return RunResult(dict(m), _records(o), failed, Path(out_dir))
    with tempfile.TemporaryDirectory(prefix="oeg-run-") as tmp:
        m, o, failed, _ = _oeg.run_scenario(
            os.fspath(path), _overrides(overrides), os.path.join(tmp, "run"), seed, compare, planner
        )
    return RunResult(dict(m), _records(o), failed, None)


def load_sweep(path: PathLike) -> Any:
    """A sweep's rows (``runs.jsonl`` of ``oeg sweep run`` or ``merge``) as a pandas DataFrame.

    Raises:
        ImportError: pandas is not installed.
        FileNotFoundError: The folder holds no ``runs.jsonl``.
        OegError: A row that is not JSON, named with its line.
    """
    import pandas as pd  # type: ignore[import-untyped, unused-ignore]

    rows_path = Path(path) / "runs.jsonl"
    if not rows_path.is_file():
        raise FileNotFoundError(f"{rows_path}: no such file (is {path} a folder of `oeg sweep run`?)")
    rows = []
    with open(rows_path, encoding="utf-8") as f:
        for number, line in enumerate(f, start=1):
            if not line.strip():
                continue
            try:
                rows.append(json.loads(line))
            except json.JSONDecodeError as e:
                raise OegError(f"{rows_path}:{number}: not a JSON row: {e.msg}") from None
    return pd.DataFrame.from_records(rows)


class Truth:
    """A scenario's truth, as ``oeg run`` judges a map against it: computed from the simulated world alone.

    Made by :func:`truth`; pass it to :func:`score` to judge several maps without computing it again.
    """

    def __init__(self, native: _oeg.Truth) -> None:
        self._truth = native

    @property
    def scenario(self) -> str:
        """The scenario's name."""
        return self._truth.scenario

    @property
    def resolution_m(self) -> float:
        """Cell size, metres: the scenario's ``map.resolution_m``."""
        return self._truth.resolution_m

    @property
    def extent(self) -> Extent:
        """``(x_min, x_max, y_min, y_max)`` of the scenario's map region, metres."""
        return self._truth.extent

    @property
    def origin(self) -> Tuple[float, float]:
        """World ``(x, y)`` of the lower-left corner of cell ``[0, 0]``, metres."""
        x0, _, y0, _ = self._truth.extent
        return (x0, y0)

    @property
    def has_observability(self) -> bool:
        """Whether the ``observed_*`` layers exist (the scenario's scripted drive was simulated)."""
        return self._truth.has_observability

    @property
    def robot(self) -> Dict[str, Any]:
        """The robot's decision profile: ``max_step_m``, ``height_m``, ``max_grade``."""
        return dict(self._truth.robot)

    def layers(self) -> Dict[str, npt.NDArray[Any]]:
        """The truth as ``(num_y, num_x)`` arrays, row 0 the minimum y (``imshow(origin="lower")``).

        * ``elevation_m`` (``float32``): the highest surface below the robot's height, NaN off the terrain;
        * ``ground_m``: the ground's height; ``step_m``: the largest rise within the robot's contact distance;
        * ``clearance_m``: the free gap under a structure over the cell, NaN where there is none;
        * ``step_blocked``, ``truly_blocked`` (``bool``): a step the robot cannot climb; a cell it truly cannot
          enter (a step, or a structure lower than the robot);
        * ``truth_class`` (``uint8``, :data:`TRUTH_CLASSES`);
        * with observability: ``observed_step`` (a ray ended on the cell), ``observed_clearance`` (a ray
          crossed or ended in the band between a step and the robot's height), ``observed_band_hit`` (a ray
          ended in that band).

        Each call copies the arrays out of the truth.
        """
        layers: Dict[str, npt.NDArray[Any]] = self._truth.layers()
        return layers


class Score(NamedTuple):
    """What :func:`score` returns: what ``oeg run`` reports for its own map."""

    #: The keys of ``metrics.json`` (``docs/metrics.md``); ``map_bytes``, ``num_scans`` and ``num_rays`` are 0.
    metrics: Dict[str, Any]
    #: ``obstacles.csv``'s rows: a pandas DataFrame when pandas is installed, else a list of dicts.
    obstacles: Any
    #: ``plan.csv``'s rows, the map's path and the truth's: a DataFrame, else a list of dicts.
    plan: Any


def truth(
    scenario: PathLike,
    overrides: Union[Mapping[str, SettingValue], Sequence[str], None] = None,
    seed: Optional[int] = None,
    observability: bool = True,
) -> Truth:
    """The truth of a scenario over its map region, at its ``map.resolution_m``.

    Args:
        overrides: Scenario values by their dotted keys, as :func:`run_scenario` takes them.
        seed: Replaces the scenario's seed.
        observability: Simulate the scenario's scripted drive with its sensors (the same rays ``oeg run`` and
            ``oeg record`` cast with this seed) to know what they could see: the ``observed_*`` layers, the blind
            counts and each obstacle's sensor returns. A closed-loop scenario has none: its rays depend on the
            map that steered it. Ctrl-C stops it with ``KeyboardInterrupt``.

    Raises:
        FileNotFoundError: The scenario does not exist.
        OegError: A malformed scenario or override.
    """
    return Truth(_oeg.truth(os.fspath(scenario), _overrides(overrides), seed, observability))


def _records(rows: List[Dict[str, Any]]) -> Any:
    try:
        import pandas as pd  # type: ignore[import-untyped, unused-ignore]
    except ImportError:
        return rows
    return pd.DataFrame.from_records(rows)


def score(
    scenario_or_truth: Union[PathLike, Truth],
    decisions: Any,
    origin: Tuple[float, float],
    resolution_m: float,
    elevation: Optional[Any] = None,
    variance: Optional[Any] = None,
    occupancy: Optional[Any] = None,
) -> Score:
    """Judges a map made by any mapper against a scenario's truth, as ``oeg run`` judges its own.

    The arrays are ``(rows, cols)``, row 0 the minimum y and column 0 the minimum x, cell ``[r, c]`` covering
    ``x`` from ``origin[0] + c * resolution_m`` and ``y`` from ``origin[1] + r * resolution_m``. They are
    resampled onto the truth's grid by the rule of ``docs/scoring.md``: a truth cell takes the user's cells
    whose centres lie in it (or, when none does, the cell under its centre), their most restrictive decision,
    their mean elevation, the variance of the mixture of their Gaussians and their mean occupancy.

    Args:
        scenario_or_truth: A scenario file, whose :func:`truth` is computed with observability, or a
            :class:`Truth`.
        decisions: Integer codes, :data:`DECISIONS` (0 unknown, 1 free, 2 traversable, 3 blocked, 4
            uncertain), of any integer or bool dtype. Cells with code 0 are not scored.
        origin: World ``(x, y)`` of the lower-left corner of cell ``[0, 0]``, metres.
        resolution_m: The arrays' cell size, metres.
        elevation: Elevations, metres, NaN for none (the elevation metrics).
        variance: Elevation variances, square metres, NaN for none (``elevation_within_2sigma``).
        occupancy: Occupancy probabilities, NaN for none (``occupancy_brier``).

    Raises:
        TypeError: An array of the wrong kind (float decisions, non-numeric layers).
        ValueError: Arrays of different shapes, unknown codes, a negative variance, a bad grid.
    """
    t = scenario_or_truth if isinstance(scenario_or_truth, Truth) else truth(scenario_or_truth)
    codes = np.asarray(decisions)
    if codes.ndim != 2 or codes.dtype.kind not in "biu":
        raise TypeError(
            f"decisions: expected a 2D array of integer codes, got dtype {codes.dtype} and shape {codes.shape}"
        )

    def floats(name: str, a: Optional[Any]) -> Optional[npt.NDArray[np.float64]]:
        if a is None:
            return None
        values = np.asarray(a)
        if values.ndim != 2 or values.dtype.kind not in "biuf":
            raise TypeError(f"{name}: expected a 2D numeric array, got dtype {values.dtype} and shape {values.shape}")
        return np.ascontiguousarray(values, dtype=np.float64)

    m, o, p = _oeg.score(
        t._truth,
        np.ascontiguousarray(codes, dtype=np.int64),
        (float(origin[0]), float(origin[1])),
        float(resolution_m),
        floats("elevation", elevation),
        floats("variance", variance),
        floats("occupancy", occupancy),
    )
    return Score(dict(m), _records(o), _records(p))
