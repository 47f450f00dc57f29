//! The planner's inflation: where the robot's centre may not be, and what entering a cell near an obstacle
//! costs (costmap_2d's inflation layer: a lethal radius, then a cost decaying with the distance).

use super::distance::squared_distances;
use super::{INFLATED_CELL_COST, PlannerOptions, SIDE_COST, UncertainCells, UnknownCells};
use crate::geometry::{CellIndex, CellRegion, GridWindow};
use crate::traversability::Traversability;

/// What the planner's inflation grows from and how far every cell lies from it.
pub(super) struct Inflation {
    /// The cells the robot's centre may not enter whatever the radius: the obstacles, and unknown cells
    /// under [`UnknownCells::Avoid`].
    forbidden: Vec<bool>,
    /// The squared distance, in cells centre to centre, from every cell to the nearest obstacle; `None`
    /// when there is none or neither the inflation nor its cost reaches a neighbour.
    squared_distances: Option<Vec<f64>>,
    resolution_m: f64,
}

impl Inflation {
    /// The inflation of `decisions` under `options`.
    pub(super) fn of(window: &GridWindow, decisions: &[Traversability], options: &PlannerOptions) -> Self {
        let (region, resolution_m) = (window.region(), window.resolution_m());
        let obstacle: Vec<bool> = decisions.iter().map(|t| grows_inflation(*t, options)).collect();
        let forbidden = decisions
            .iter()
            .zip(&obstacle)
            .map(|(t, o)| *o || (*t == Traversability::Unknown && options.unknown == UnknownCells::Avoid))
            .collect();
        // Exact squared distances (in cells, centre to centre) to the nearest obstacle: linear in the
        // region's size whatever the radius, so a large radius at a fine resolution costs no more than a
        // small one.
        let reach = (options.inflation_radius_m + options.inflation_cost_width_m) / resolution_m;
        let squared_distances = (reach + 1e-9 >= 1.0 && obstacle.iter().any(|o| *o))
            .then(|| squared_distances(&obstacle, region.num_x as usize, region.num_y as usize));
        Self {
            forbidden,
            squared_distances,
            resolution_m,
        }
    }

    /// Where the robot's centre may not be with the inflation `radius_m`.
    pub(super) fn forbidden(&self, radius_m: f64) -> Vec<bool> {
        let r = radius_m / self.resolution_m + 1e-9;
        match &self.squared_distances {
            Some(d2) if r >= 1.0 => self
                .forbidden
                .iter()
                .zip(d2)
                .map(|(f, d)| *f || *d <= r * r)
                .collect(),
            _ => self.forbidden.clone(),
        }
    }

    /// Adds to `extra` the cost of entering each cell beyond the inflation radius and within
    /// [`PlannerOptions::inflation_cost_width_m`] of it, in A*'s units: [`INFLATED_CELL_COST`] cell lengths
    /// at the radius, decaying by [`PlannerOptions::cost_scaling_factor`].
    pub(super) fn add_costs(&self, extra: &mut [u32], options: &PlannerOptions) {
        let Some(d2) = self
            .squared_distances
            .as_ref()
            .filter(|_| options.inflation_cost_width_m > 0.0)
        else {
            return;
        };
        let radius = options.inflation_radius_m / self.resolution_m + 1e-9;
        let reach = radius + options.inflation_cost_width_m / self.resolution_m;
        for (e, d2) in extra.iter_mut().zip(d2) {
            if *d2 > radius * radius && *d2 <= reach * reach {
                let beyond_m = (d2.sqrt() - radius) * self.resolution_m;
                let cost = INFLATED_CELL_COST * (-options.cost_scaling_factor * beyond_m).exp();
                *e = e.saturating_add((cost * SIDE_COST as f64).round() as u32);
            }
        }
    }
}

/// Whether the inflation grows from a cell of class `t`.
fn grows_inflation(t: Traversability, options: &PlannerOptions) -> bool {
    match t {
        Traversability::Blocked => true,
        Traversability::Uncertain => options.uncertain == UncertainCells::Blocked,
        Traversability::Unknown => options.unknown == UnknownCells::Inflate,
        Traversability::Free | Traversability::Traversable => false,
    }
}

/// The clearance a robot standing inside the inflation at `start` may keep: the distance from the start
/// cell's centre to the nearest cell the inflation grows from, less half a cell; `None` when the start lies
/// outside every inflation or on such a cell itself.
pub(super) fn start_clearance(
    region: &CellRegion,
    resolution_m: f64,
    decisions: &[Traversability],
    start: CellIndex,
    options: &PlannerOptions,
) -> Option<f64> {
    let reach = (options.inflation_radius_m / resolution_m)
        .ceil()
        .min(f64::from(region.num_x.max(region.num_y))) as i32;
    let mut nearest = f64::INFINITY;
    for dj in -reach..=reach {
        for di in -reach..=reach {
            let c = CellIndex::new(start.i.saturating_add(di), start.j.saturating_add(dj));
            if region
                .offset(c)
                .is_some_and(|k| grows_inflation(decisions[k], options))
            {
                nearest = nearest.min(f64::from(di).hypot(f64::from(dj)) * resolution_m);
            }
        }
    }
    let clearance = nearest - resolution_m / 2.0;
    (nearest <= options.inflation_radius_m && clearance > 0.0).then_some(clearance)
}

#[cfg(test)]
mod tests;
