#![doc = include_str!("../README.md")]

pub mod cell;
pub mod error;
pub mod geometry;
pub mod integrate;
pub mod io;
pub mod layers;
pub mod map;
pub mod model;
pub mod planner;
pub mod scan;
pub mod sensor;
pub mod storage;
pub mod traversability;
pub mod traversal;

pub use cell::{Ceiling, Cell, SeenFrom};
pub use error::{Error, Result};
pub use geometry::{CellIndex, CellRegion, GridGeometry};
pub use layers::{Layer, LayerKind, Raster, TraversabilityCounts};
pub use map::{DEFAULT_MEMORY_LIMIT_BYTES, IntegrationStats, Map, MapConfig};
pub use model::{
    Elevation, ElevationFusion, FreeSpaceElevation, FreeSpaceOccupancy, HitHeight, MapPreset, ModelOptions,
    OverheadHits, ScanHitElevation,
};
pub use planner::{Plan, PlannerOptions, UncertainCells, UnknownCells};
pub use scan::{Ray, RayKind, Scan};
pub use sensor::{RangeNoiseModel, SensorModel};
pub use traversability::{RobotProfile, Traversability, TraversabilityRule};
