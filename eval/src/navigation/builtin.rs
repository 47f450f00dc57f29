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

/// Whether the rest of a path, from the robot at `from`, is still one the planner allows on `decisions` (nav2's
/// `IsPathValid`, which its tree `navigate_w_replanning_only_if_path_becomes_invalid` asks before it plans
/// again): within `[navigation] decide_within_m` of the robot no point lies where the planner keeps the robot's
/// centre out (a blocked cell's inflation, or an undecided cell the options avoid); beyond it no point lies on a
/// cell the map calls blocked (the planner plans through what it cannot decide there). Points under the
/// robot's own footprint are not asked: the robot is already there.
pub(super) fn path_still_valid(
    inputs: &NavigationInputs<'_>,
    window: &oeg::GridWindow,
    decisions: &[Traversability],
    from: (f64, f64),
    path: &[(f64, f64)],
) -> Result<bool> {
    let forbidden =
        oeg::forbidden_mask(window, decisions, &planner_options(inputs)).map_err(|e| EvalError::Input {
            path: inputs.scenario.name.clone().into(),
            message: format!("planner: {e}"),
        })?;
    let near = Reach {
        decide_within_m: inputs.settings.decide_within(),
        footprint_m: inputs.footprint.circumscribed_radius_m(),
    };
    Ok(path_allowed(window, decisions, &forbidden, from, path, near))
}

/// How far from the robot a path's points are asked what (see [`path_still_valid`]).
#[derive(Debug, Clone, Copy)]
struct Reach {
    decide_within_m: f64,
    footprint_m: f64,
}

/// [`path_still_valid`] on a computed forbidden mask. A point outside the window makes the path invalid.
fn path_allowed(
    window: &oeg::GridWindow,
    decisions: &[Traversability],
    forbidden: &[bool],
    from: (f64, f64),
    path: &[(f64, f64)],
    reach: Reach,
) -> bool {
    path.iter().all(|&(x, y)| {
        let Some(k) = super::clamped_cell(window, (x, y)).and_then(|c| window.region().offset(c)) else {
            return false;
        };
        let d = (x - from.0).hypot(y - from.1);
        if d <= reach.footprint_m {
            true
        } else if d <= reach.decide_within_m {
            !forbidden[k]
        } else {
            decisions[k] != Traversability::Blocked
        }
    })
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

#[cfg(test)]
mod tests {
    use oeg::{CellIndex, CellRegion, GridGeometry, GridWindow, Traversability};

    use super::{Reach, path_allowed};

    const REACH: Reach = Reach {
        decide_within_m: 1.0,
        footprint_m: 0.35,
    };

    /// A 4 m strip of 0.1 m cells along x, one cell wide, all drivable.
    fn strip() -> (GridWindow, Vec<Traversability>) {
        let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(39, 0)).expect("region");
        let window = GridWindow::new(GridGeometry::new(0.1).expect("resolution"), region);
        (window, vec![Traversability::Traversable; 40])
    }

    fn along(from_m: f64, to_m: f64) -> Vec<(f64, f64)> {
        (0..)
            .map(|k| from_m + 0.05 + 0.1 * f64::from(k))
            .take_while(|x| *x < to_m)
            .map(|x| (x, 0.05))
            .collect()
    }

    #[test]
    fn a_path_stays_valid_until_the_map_forbids_a_point_ahead() {
        let (window, mut decisions) = strip();
        let path = along(0.0, 4.0);
        let free = vec![false; 40];
        assert!(path_allowed(
            &window,
            &decisions,
            &free,
            (0.05, 0.05),
            &path,
            REACH
        ));
        // Near: a point where the planner keeps the centre out (here an undecided cell it avoids) invalidates.
        let mut forbidden = free.clone();
        forbidden[7] = true;
        assert!(!path_allowed(
            &window,
            &decisions,
            &forbidden,
            (0.05, 0.05),
            &path,
            REACH
        ));
        // Beyond `decide_within_m` the planner plans through what it cannot decide: still valid.
        let mut forbidden = free.clone();
        forbidden[25] = true;
        decisions[25] = Traversability::Uncertain;
        assert!(path_allowed(
            &window,
            &decisions,
            &forbidden,
            (0.05, 0.05),
            &path,
            REACH
        ));
        // A cell the map now calls blocked invalidates wherever it lies ahead.
        decisions[25] = Traversability::Blocked;
        assert!(!path_allowed(
            &window,
            &decisions,
            &forbidden,
            (0.05, 0.05),
            &path,
            REACH
        ));
    }

    #[test]
    fn what_lies_under_the_robot_or_behind_the_path_is_not_asked() {
        let (window, mut decisions) = strip();
        let mut forbidden = vec![false; 40];
        // The robot at 1.05 m stands in an inflation (cell 11, under its footprint) and the path behind it is
        // not the path ahead.
        forbidden[11] = true;
        decisions[2] = Traversability::Blocked;
        let ahead = along(1.0, 4.0);
        assert!(path_allowed(
            &window,
            &decisions,
            &forbidden,
            (1.05, 0.05),
            &ahead,
            REACH
        ));
        // A point outside the window is not a path the planner could have made.
        let mut outside = ahead.clone();
        outside.push((9.0, 0.05));
        assert!(!path_allowed(
            &window,
            &decisions,
            &forbidden,
            (1.05, 0.05),
            &outside,
            REACH
        ));
    }
}
