//! The built-in planner while navigating: its options, and a plan on the map.

use oeg::{CellIndex, Plan, Traversability};

use super::NavigationInputs;
use crate::error::{EvalError, Result};

/// The built-in planner's path from cell `a` to cell `b` on `decisions`, ending at `goal` itself (`None`: no
/// path).
pub(super) fn plan(
    inputs: &NavigationInputs<'_>,
    window: &oeg::GridWindow,
    decisions: &[Traversability],
    (a, b): (CellIndex, CellIndex),
    goal: (f64, f64),
) -> Result<Option<Vec<(f64, f64)>>> {
    let options = planner_options(inputs);
    let plan = oeg::plan(window, decisions, a, b, &options).map_err(|e| EvalError::Input {
        path: inputs.scenario.name.clone().into(),
        message: format!("planner: {e}"),
    })?;
    Ok(plan.map(|p| path_points(&p, window.geometry(), goal)))
}

/// The planner's options while navigating: the scenario's `[planner]` options, with `[navigation]`'s
/// `unknown`, and by default an inflation of the footprint's circumscribed radius (nav2's rule: less lets a
/// turning robot's corners reach what the planner kept its centre away from) and half a cell's diagonal.
/// The inflation is measured between cell centres, but the footprint meets a cell's square, which reaches
/// half a diagonal beyond its centre: without that half diagonal, a path whose centre keeps out of every
/// inflation still runs the footprint's corners into the squares of the cells it inflates, and the
/// collision guard, which watches the footprint against the squares, stops the robot on its own plan.
pub fn planner_options(inputs: &NavigationInputs<'_>) -> oeg::PlannerOptions {
    let planner = &inputs.scenario.planner;
    let half_diagonal = inputs.truth.window.resolution_m() * std::f64::consts::FRAC_1_SQRT_2;
    oeg::PlannerOptions {
        unknown: inputs.settings.unknown,
        optimistic_beyond_m: Some(inputs.settings.decide_within()),
        inflation_radius_m: planner.inflation_radius_m.unwrap_or_else(|| {
            oeg::DEFAULT_INFLATION_RADIUS_M.max(inputs.footprint.circumscribed_radius_m()) + half_diagonal
        }),
        ..planner.options()
    }
}

/// The path through a plan's cell centres, ending at the goal itself.
fn path_points(plan: &Plan, geometry: &oeg::GridGeometry, goal: (f64, f64)) -> Vec<(f64, f64)> {
    let mut points: Vec<(f64, f64)> = plan.cells.iter().map(|c| geometry.cell_center(*c)).collect();
    if let Some(last) = points.last_mut() {
        *last = goal;
    }
    points
}
