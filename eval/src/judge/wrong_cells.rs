//! Every cell whose decision the map got wrong (`wrong_cells.csv`), with what the map held and what the truth
//! says, so a user can see why: a board top never seen, a curb edge averaged with the road, a person not yet
//! cleared.

use serde::Serialize;
use sim::truth::TruthRaster;

use crate::judge::estimate::Estimate;
use crate::judge::verdict::{Verdict, Verdicts};

/// One row of `wrong_cells.csv`. Empty fields are values that do not exist (no elevation estimate, no
/// structure over the cell).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct WrongCell {
    /// Cell centre, world x, metres.
    pub x_m: f64,
    /// Cell centre, world y, metres.
    pub y_m: f64,
    /// `unsafe` (truly blocked, mapped drivable), `over_cautious` (truly drivable, mapped blocked) or
    /// `uncertain` (the map could not tell).
    pub error: &'static str,
    /// The map's class: `free`, `traversable` or `blocked`.
    pub mapped: &'static str,
    /// The map's occupancy probability.
    pub occupancy_probability: f32,
    /// The map's elevation mean, metres.
    pub elevation_m: Option<f32>,
    /// The map's elevation standard deviation, metres.
    pub elevation_std_m: Option<f32>,
    /// The truth: highest surface below the robot's height, metres.
    pub true_elevation_m: f32,
    /// The truth: mean ground height, metres.
    pub true_ground_m: f32,
    /// The truth: largest rise of the surface within the robot's contact distance, metres.
    pub true_step_m: f32,
    /// The truth: whether that rise is a step the robot cannot climb.
    pub true_step_blocked: bool,
    /// The truth: smallest free gap under a structure over the cell, metres.
    pub true_structure_gap_m: Option<f32>,
    /// Truly blocked, and no ray could have told (the observability truth: no ray ended on the step cell, or
    /// inside the band under the structure, on it): an `unsafe` cell so counts in `blind_cells`, not in
    /// `unsafe_observable_cells`. False in a run without an observability truth (a replayed log).
    pub blind: bool,
}

/// The observed cells of the truth's region whose decision is wrong (verdict `unsafe` or `over_cautious`) or
/// that the map could not judge (`uncertain`), row-major from the region's min corner, read from the run's
/// verdict raster.
pub(crate) fn wrong_cells(estimate: &Estimate, truth: &TruthRaster, verdicts: &Verdicts) -> Vec<WrongCell> {
    let geometry = *estimate.window.geometry();
    let mut rows = Vec::new();
    for (k, cell) in truth.window.region().cells().enumerate() {
        let error = match verdicts.verdict[k] {
            Verdict::Unsafe => "unsafe",
            Verdict::OverCautious => "over_cautious",
            Verdict::Uncertain => "uncertain",
            _ => continue,
        };
        let t = &truth.cells[k];
        // The map's layers are f32: the file keeps their precision.
        let e = estimate.elevation(k).map(|(e, var)| (e as f32, var as f32));
        let (x_m, y_m) = geometry.cell_center(cell);
        rows.push(WrongCell {
            x_m: crate::output::round_m(x_m),
            y_m: crate::output::round_m(y_m),
            error,
            mapped: verdicts.mapped[k].name(),
            occupancy_probability: estimate.occupancy[k],
            elevation_m: e.map(|(e, _)| e),
            elevation_std_m: e.and_then(|(_, var)| (!var.is_nan()).then(|| var.sqrt())),
            true_elevation_m: t.elevation_m,
            true_ground_m: t.ground_m,
            true_step_m: t.step_m,
            true_step_blocked: t.step_blocked,
            true_structure_gap_m: (!t.structure_gap_m.is_nan()).then_some(t.structure_gap_m),
            blind: verdicts.unobservable[k],
        });
    }
    rows
}

impl crate::output::CsvRow for WrongCell {
    const COLUMNS: &'static [&'static str] = &[
        "x_m",
        "y_m",
        "error",
        "mapped",
        "occupancy_probability",
        "elevation_m",
        "elevation_std_m",
        "true_elevation_m",
        "true_ground_m",
        "true_step_m",
        "true_step_blocked",
        "true_structure_gap_m",
        "blind",
    ];
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_missing_value_is_an_empty_field() {
        let ours =
            String::from_utf8(crate::output::csv_table(&[crate::test_support::wrong_cell()]).expect("csv"))
                .expect("utf8");
        assert_eq!(
            ours.lines().nth(1),
            Some("1.0,2.0,unsafe,free,0.2,,0.01,0.3,0.0,0.3,true,,false")
        );
    }
}
