//! nav2's path validity check (`IsPathValid`), made every tick: whether the path the controller follows now
//! runs, near the robot, where the planner would no longer go.

use oeg::{GridWindow, Pose2, UnknownCells};

use super::{NavigationInputs, planner_options};
use crate::error::Result;
use crate::mapping::Mapping;

/// Whether the path ahead (`path` from the controller's place on it) runs, within the distance where the map
/// decides for real ([`sim::scenario::Navigation::decide_within`]), within the inflation radius of a cell the
/// map now calls an obstacle (blocked, or uncertain where the planner counts those as blocked): the map learnt
/// of it since the plan was made, and the robot must plan again now rather than at the next period. Cells never
/// observed are left to the periodic replanning, which plans through them optimistically beyond that
/// distance. The path's points within the footprint radius of the robot are the planner's own start (it
/// counts the cells under the robot as drivable, so that it can plan out) and are not asked about.
pub(super) fn path_blocked_ahead(
    mapping: &Mapping,
    inputs: &NavigationInputs<'_>,
    path: &[(f64, f64)],
    from: Pose2,
) -> Result<bool> {
    let options = oeg::PlannerOptions {
        unknown: UnknownCells::Drivable,
        optimistic_beyond_m: None,
        ..planner_options(inputs)
    };
    let near = inputs.settings.decide_within();
    let distance = |p: &(f64, f64)| (p.0 - from.x_m).hypot(p.1 - from.y_m);
    let ahead: Vec<(f64, f64)> = path
        .iter()
        .take_while(|p| distance(p) <= near)
        .filter(|p| distance(p) > options.footprint_radius_m)
        .copied()
        .collect();
    if ahead.is_empty() {
        return Ok(false);
    }
    let map = &mapping.maps[0];
    let geometry = *map.geometry();
    // The window around the path ahead, with the inflation radius (and a cell) as margin: every cell that can
    // close a point of it lies inside.
    let margin = options.inflation_radius_m + geometry.resolution_m();
    let (mut lo, mut hi) = (
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for p in &ahead {
        (lo, hi) = ((lo.0.min(p.0), lo.1.min(p.1)), (hi.0.max(p.0), hi.1.max(p.1)));
    }
    let region = geometry.region_covering((lo.0 - margin, lo.1 - margin), (hi.0 + margin, hi.1 + margin))?;
    let decisions = map
        .traversability_layer(region, &inputs.truth.profile, inputs.scenario.map.traversability)?
        .values;
    let forbidden = oeg::forbidden_mask(&GridWindow::new(geometry, region), &decisions, &options)?;
    Ok(ahead.iter().any(|p| {
        geometry
            .cell_of(p.0, p.1)
            .and_then(|c| region.offset(c))
            .is_some_and(|k| forbidden[k])
    }))
}
