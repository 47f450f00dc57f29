//! Fixtures shared by the unit tests of the metrics and the planner check.

use oeg::{CellRegion, RobotProfile};
use sim::truth::{CellTruth, TruthRaster};
use sim::world::Actors;

/// A truth cell on flat ground at 0 whose highest surface is `elevation_m`, with no structure over it unless
/// `structure_gap_m` is finite.
pub(crate) fn truth_cell(elevation_m: f32, step_blocked: bool, structure_gap_m: f32) -> CellTruth {
    CellTruth {
        elevation_m,
        ground_m: 0.0,
        step_m: elevation_m,
        step_blocked,
        structure_gap_m,
    }
}

/// A truth raster of 1 m cells over `region` for the paper's Pioneer 3-AT, people left out.
pub(crate) fn truth_raster(region: CellRegion, cells: Vec<CellTruth>) -> TruthRaster {
    TruthRaster {
        region,
        resolution_m: 1.0,
        profile: RobotProfile::default(),
        time_s: 0.0,
        actors: Actors::Excluded,
        cells,
    }
}
