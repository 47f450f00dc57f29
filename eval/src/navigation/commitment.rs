//! When the navigator keeps the path it follows: whether the path ahead is still valid on the map (nav2's
//! `IsPathValid`), and whether a new one is worth switching to ([`sim::scenario::Replanning`]).

use oeg::Traversability;
use sim::scenario::SWITCH_SHORTER_FRACTION;

use super::NavigationInputs;
use super::builtin::planner_options;
use crate::error::{EvalError, Result};

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

/// [`path_still_valid`] on a computed forbidden mask. A point outside the window makes the path invalid. A
/// segment longer than [`SPARSE_SEGMENT_CELLS`] cells (an external planner's waypoints) is asked every half
/// cell along it; the built-in planner's paths step from cell to cell and are asked at their points.
fn path_allowed(
    window: &oeg::GridWindow,
    decisions: &[Traversability],
    forbidden: &[bool],
    from: (f64, f64),
    path: &[(f64, f64)],
    reach: Reach,
) -> bool {
    let allowed = |(x, y): (f64, f64)| {
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
    };
    let cell = window.geometry().resolution_m();
    let along = |(a, b): ((f64, f64), (f64, f64))| {
        let length = (b.0 - a.0).hypot(b.1 - a.1);
        let steps = if length > SPARSE_SEGMENT_CELLS * cell {
            (2.0 * length / cell).ceil() as usize
        } else {
            1
        };
        (1..=steps).all(|k| {
            let t = k as f64 / steps as f64;
            allowed((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)))
        })
    };
    path.first().is_none_or(|&p| allowed(p)) && path.windows(2).map(|w| (w[0], w[1])).all(along)
}

/// Segments longer than this many cells are asked along their length ([`path_allowed`]).
const SPARSE_SEGMENT_CELLS: f64 = 3.0;

/// The length of a path from `from` through its points, metres.
pub(super) fn path_length_m(from: (f64, f64), path: &[(f64, f64)]) -> f64 {
    path.iter()
        .scan(from, |last, &p| {
            let step = (p.0 - last.0).hypot(p.1 - last.1);
            *last = p;
            Some(step)
        })
        .sum()
}

/// Whether a new path of `new_m` metres is worth leaving a still valid one of `rest_m` for
/// ([`Replanning::WhenShorter`]).
pub(super) fn clearly_shorter(new_m: f64, rest_m: f64) -> bool {
    new_m < (1.0 - SWITCH_SHORTER_FRACTION) * rest_m
}

#[cfg(test)]
mod tests {
    use oeg::{CellIndex, CellRegion, GridGeometry, GridWindow, Traversability};

    use super::{Reach, clearly_shorter, path_allowed, path_length_m};

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

    /// [`path_allowed`] on `window` with [`REACH`].
    fn allowed(
        window: &GridWindow,
        decisions: &[Traversability],
        forbidden: &[bool],
        from: (f64, f64),
        path: &[(f64, f64)],
    ) -> bool {
        path_allowed(window, decisions, forbidden, from, path, REACH)
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
        assert!(allowed(&window, &decisions, &free, (0.05, 0.05), &path));
        // Near: a point where the planner keeps the centre out (here an undecided cell it avoids) invalidates.
        let mut forbidden = free.clone();
        forbidden[7] = true;
        assert!(!allowed(&window, &decisions, &forbidden, (0.05, 0.05), &path));
        // Beyond `decide_within_m` the planner plans through what it cannot decide: still valid.
        let mut forbidden = free.clone();
        forbidden[25] = true;
        decisions[25] = Traversability::Uncertain;
        assert!(allowed(&window, &decisions, &forbidden, (0.05, 0.05), &path));
        // A cell the map now calls blocked invalidates wherever it lies ahead.
        decisions[25] = Traversability::Blocked;
        assert!(!allowed(&window, &decisions, &forbidden, (0.05, 0.05), &path));
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
        assert!(allowed(&window, &decisions, &forbidden, (1.05, 0.05), &ahead));
        // An external planner's two waypoints are asked along the segment between them.
        let mut blocked = decisions.clone();
        blocked[30] = Traversability::Blocked;
        assert!(!allowed(
            &window,
            &blocked,
            &forbidden,
            (1.05, 0.05),
            &[(1.05, 0.05), (3.95, 0.05)]
        ));
        assert!(allowed(
            &window,
            &decisions,
            &forbidden,
            (1.05, 0.05),
            &[(1.05, 0.05), (3.95, 0.05)]
        ));
        // A point outside the window is not a path the planner could have made.
        let mut outside = ahead.clone();
        outside.push((9.0, 0.05));
        assert!(!allowed(&window, &decisions, &forbidden, (1.05, 0.05), &outside));
    }

    #[test]
    fn a_path_is_as_long_as_the_way_from_the_robot_through_its_points() {
        assert_eq!(path_length_m((0.0, 0.0), &[]), 0.0);
        assert_eq!(path_length_m((0.0, 0.0), &[(3.0, 4.0)]), 5.0);
        assert_eq!(path_length_m((1.0, 0.0), &[(1.0, 2.0), (4.0, 6.0)]), 7.0);
    }

    #[test]
    fn a_valid_path_is_left_only_for_one_a_tenth_shorter() {
        // Two ways round an obstacle that take turns being a little shorter: the robot keeps its own.
        assert!(!clearly_shorter(9.8, 10.0));
        assert!(!clearly_shorter(9.05, 10.0), "less than a tenth is not enough");
        assert!(clearly_shorter(8.9, 10.0));
        assert!(!clearly_shorter(12.0, 10.0));
    }
}
