//! What the planner reads of the map's decisions: the cells under the robot cleared (footprint clearing), and
//! the cells the map cannot decide beyond the stopping distance taken as drivable at a cost.

use super::{PlannerOptions, SIDE_COST};
use crate::geometry::{CellIndex, CellRegion, GridWindow};
use crate::traversability::Traversability;

/// `decisions` as [`plan`] reads them, with the cost of entering each cell beyond its length: the cells under the
/// robot at the start drivable and the unknown cells under it at the goal ([`clear_footprint`]), and the cells the
/// map cannot decide beyond [`PlannerOptions::optimistic_beyond_m`] drivable at a cost ([`optimistic_beyond`]).
pub(super) fn as_planned(
    window: &GridWindow,
    decisions: &[Traversability],
    start: CellIndex,
    goal: CellIndex,
    options: &PlannerOptions,
) -> (Vec<Traversability>, Vec<u32>) {
    let (region, resolution_m) = (window.region(), window.resolution_m());
    let mut decisions = decisions.to_vec();
    let r = options.footprint_radius_m.min(options.inflation_radius_m) / resolution_m + 1e-9;
    clear_footprint(region, &mut decisions, start, r, true);
    clear_footprint(region, &mut decisions, goal, r, false);
    let mut extra = vec![0; decisions.len()];
    optimistic_beyond(region, resolution_m, &mut decisions, &mut extra, start, options);
    (decisions, extra)
}

/// [`PlannerOptions::optimistic_beyond_m`]: the cells the map cannot decide beyond that distance from `start`
/// become drivable in `decisions`, each with its doubt added to `extra` (A*'s cost of entering it), if it is on.
fn optimistic_beyond(
    region: &CellRegion,
    resolution_m: f64,
    decisions: &mut [Traversability],
    extra: &mut [u32],
    start: CellIndex,
    options: &PlannerOptions,
) {
    let Some(beyond) = options.optimistic_beyond_m.map(|m| m / resolution_m) else {
        return;
    };
    // At most 1,000 cell lengths (the options' check): far within a u32.
    let doubt = (options.doubt_cost * SIDE_COST as f64).round() as u32;
    for (k, (t, e)) in decisions.iter_mut().zip(extra).enumerate() {
        if !matches!(t, Traversability::Uncertain | Traversability::Unknown) {
            continue;
        }
        let c = region.cell_at(
            (k % region.num_x as usize) as u32,
            (k / region.num_x as usize) as u32,
        );
        let (di, dj) = (f64::from(c.i - start.i), f64::from(c.j - start.j));
        if di * di + dj * dj > beyond * beyond {
            *t = Traversability::Free;
            *e = e.saturating_add(doubt);
        }
    }
}

/// Marks drivable the cells within `radius_cells` (centre to centre) of `centre` that are unknown, or also
/// blocked when `clear_blocked`: the robot's own footprint.
fn clear_footprint(
    region: &CellRegion,
    decisions: &mut [Traversability],
    centre: CellIndex,
    radius_cells: f64,
    clear_blocked: bool,
) {
    let rc = radius_cells
        .floor()
        .min(f64::from(region.num_x.max(region.num_y))) as i64;
    for dj in -rc..=rc {
        for di in -rc..=rc {
            let c = CellIndex::new(
                (i64::from(centre.i) + di) as i32,
                (i64::from(centre.j) + dj) as i32,
            );
            let Some(k) = region.offset(c) else { continue };
            let inside = ((di * di + dj * dj) as f64) <= radius_cells * radius_cells;
            let clearable = decisions[k] == Traversability::Unknown
                || (clear_blocked
                    && matches!(decisions[k], Traversability::Blocked | Traversability::Uncertain));
            if inside && clearable {
                decisions[k] = Traversability::Free;
            }
        }
    }
}
