//! Fixtures shared by the unit tests: truth cells and rasters (the metrics, the planner check, the CSV tables)
//! and scratch folders (the output, lock and sweep-folder rules).

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
        window: oeg::GridWindow::new(oeg::GridGeometry::new(1.0).expect("resolution"), region),
        profile: RobotProfile::default(),
        time_s: 0.0,
        actors: Actors::Excluded,
        cells,
    }
}

/// A row of `wrong_cells.csv` with a missing elevation and structure gap.
pub(crate) fn wrong_cell() -> crate::judge::wrong_cells::WrongCell {
    crate::judge::wrong_cells::WrongCell {
        x_m: 1.0,
        y_m: 2.0,
        error: "unsafe",
        mapped: "free",
        occupancy_probability: 0.2,
        elevation_m: None,
        elevation_std_m: Some(0.01),
        true_elevation_m: 0.3,
        true_ground_m: 0.0,
        true_step_m: 0.3,
        true_step_blocked: true,
        true_structure_gap_m: None,
        blind: false,
    }
}

/// A fresh, empty folder under the system's temporary folder for one test, named by `group`, `name` and this
/// process.
pub(crate) fn scratch_dir(group: &str, name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("oeg-{group}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    crate::output::create_dir(&dir).expect("scratch folder");
    dir
}
