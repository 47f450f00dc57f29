"""Types of the native module ``oeg._oeg`` (the Rust half of the package). Use the wrappers in ``oeg``."""

from typing import Any, Callable, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

Extent = Tuple[float, float, float, float]
ScanArrays = Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.bool_]]

class OegError(Exception):
    """A map, scenario or data file the testbed refused: the message names the file, the place and what was
    expected."""

class Map:
    """The native map; :class:`oeg.Map` wraps it."""

    def __init__(
        self, resolution_m: float, model: Optional[Any] = None, memory_limit_bytes: Optional[int] = None
    ) -> None: ...
    @property
    def resolution_m(self) -> float:
        """Cell size, metres."""
    @property
    def num_scans(self) -> int:
        """Scans integrated so far."""
    @property
    def model(self) -> Dict[str, Any]:
        """The model options."""
    def integrate(
        self,
        origin_xyz: Any,
        points_xyz: Any,
        no_return: Optional[Any] = None,
        range_variance_m2: Optional[Any] = None,
        sensor: str = "laser",
    ) -> Tuple[int, int, int]:
        """Integrates one scan; returns rays, cell visits and scans so far."""
    def layer(
        self, name: str, region: Optional[Tuple[float, float, float, float]] = None
    ) -> Tuple[npt.NDArray[np.float32], Extent]:
        """One layer as a ``(num_y, num_x)`` array and its extent."""
    def traversability(
        self, robot: Optional[Dict[str, Any]] = None, region: Optional[Tuple[float, float, float, float]] = None
    ) -> Tuple[npt.NDArray[np.uint8], Extent]:
        """The decision codes as a ``(num_y, num_x)`` array and its extent."""
    def memory_bytes(self) -> int:
        """Bytes the map holds."""
    def num_observed_cells(self) -> int:
        """Cells observed at least once."""
    def observed_extent(self) -> Optional[Extent]:
        """The observed cells' extent."""
    def save(self, path: str) -> None:
        """Writes the map file atomically."""

class Truth:
    """A scenario's truth; :class:`oeg.Truth` wraps it."""

    @property
    def scenario(self) -> str:
        """The scenario's name."""
    @property
    def resolution_m(self) -> float:
        """Cell size, metres."""
    @property
    def extent(self) -> Extent:
        """The region's extent, metres."""
    @property
    def has_observability(self) -> bool:
        """Whether the observability layers exist."""
    @property
    def robot(self) -> Dict[str, Any]:
        """The robot's decision profile."""
    def layers(self) -> Dict[str, npt.NDArray[Any]]:
        """The truth's layers as ``(num_y, num_x)`` arrays."""

def truth(path: str, overrides: Any, seed: Optional[int] = None, observability: bool = True) -> Truth:
    """The truth of a scenario."""

def score(
    truth: Truth,
    decisions: npt.NDArray[np.int64],
    origin: Tuple[float, float],
    resolution_m: float,
    elevation: Optional[npt.NDArray[np.float64]] = None,
    variance: Optional[npt.NDArray[np.float64]] = None,
    occupancy: Optional[npt.NDArray[np.float64]] = None,
) -> Tuple[Dict[str, Any], List[Dict[str, Any]], List[Dict[str, Any]]]:
    """Scores another mapper's arrays; returns the metrics, the obstacles' rows and the plan's rows."""

def load(path: str, memory_limit_bytes: Optional[int] = None) -> Map:
    """Loads a map file."""

def read_graph(path: str) -> List[ScanArrays]:
    """Reads an OctoMap scan graph."""

def read_pcd(
    path: str, origin_xyz: Optional[Any] = None, frame: Optional[str] = None, invalid: Optional[str] = None
) -> ScanArrays:
    """Reads a PCD file as one scan."""

def plan(
    map: Map, start: Tuple[float, float], goal: Tuple[float, float], settings: Optional[Dict[str, Any]] = None
) -> Optional[npt.NDArray[np.float64]]:
    """Plans on a map; ``None`` when no path exists."""

def run_scenario(
    path: str,
    overrides: Any,
    out: Optional[str] = None,
    seed: Optional[int] = None,
    compare: Optional[str] = None,
    planner: Optional[Callable[..., Any]] = None,
) -> Tuple[Dict[str, Any], List[Dict[str, Any]], List[str], str]:
    """Runs a scenario; returns its metrics, its obstacles' rows, the failed expectations and the output folder."""
