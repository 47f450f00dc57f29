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

import csv
import io
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
    "load",
    "load_sweep",
    "plan",
    "read_graph",
    "read_pcd",
    "run_scenario",
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

    #: ``metrics.json`` as a dict (every key in the project's ``docs/metrics.md``).
    metrics: Dict[str, Any]
    #: ``obstacles.csv``: a pandas DataFrame when pandas is installed, else a list of dicts of strings.
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
        options: Dict[str, Any] = json.loads(self._map.model)
        return options

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
        settings: ``oeg plan``'s keys: ``planner.inflation_radius_m``, ``planner.unknown``,
            ``robot.max_step_m``, ``robot.height_m``, ``map.traversability``.

    Returns:
        The path through the cell centres, shape ``(k, 2)``, or ``None`` when the goal cannot be reached.
    """
    return _oeg.plan(map._map, start, goal, dict(settings) if settings is not None else None)


def _overrides(overrides: Union[Mapping[str, SettingValue], Sequence[str], None]) -> List[str]:
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        out = []
        for key, value in overrides.items():
            if isinstance(value, bool):
                literal = "true" if value else "false"
            elif isinstance(value, (int, float)):
                literal = repr(value)
            elif isinstance(value, str):
                literal = json.dumps(value)
            else:
                raise TypeError(f"{key}: expected a bool, int, float or str, got {type(value).__name__}")
            out.append(f"{key}={literal}")
        return out
    return [str(o) for o in overrides]


def _table(text: str) -> Any:
    try:
        import pandas as pd  # type: ignore[import-untyped, unused-ignore]
    except ImportError:
        return list(csv.DictReader(io.StringIO(text)))
    return pd.read_csv(io.StringIO(text))


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
        planner: A closed-loop run's planner, replacing the scenario's: at every replanning time it is called
            as ``planner(layers, start, goal)``. ``layers`` holds the map over the scenario's region as
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
        return RunResult(json.loads(m), _table(o), failed, Path(out_dir))
    with tempfile.TemporaryDirectory(prefix="oeg-run-") as tmp:
        m, o, failed, _ = _oeg.run_scenario(
            os.fspath(path), _overrides(overrides), os.path.join(tmp, "run"), seed, compare, planner
        )
    return RunResult(json.loads(m), _table(o), failed, None)


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
