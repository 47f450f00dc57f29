//! The planner check (`plan.csv` and the `plan_*` metrics): would a planner using this map send the robot
//! somewhere it cannot go, or refuse a way that is open? The run plans from the drive's first waypoint to its
//! last (or the scenario's `[planner]` start and goal) on the final map, checks every cell of that path
//! against the truth, and plans on the truth too, for the path the robot could have had.

use oeg::{Plan, PlannerOptions, UnknownCells};

use oeg::{CellIndex, GridWindow, Traversability};
use serde::Serialize;
use sim::scenario::Scenario;

use std::collections::BTreeMap;

use crate::error::{EvalError, Result};
use crate::judge::estimate::Estimate;
use crate::judge::verdict::Verdicts;

/// The outcome of the planner check.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanCheck {
    /// The path planned on the map, if there is one.
    pub map_plan: Option<Plan>,
    /// The path planned on the truth (every cell known), if there is one.
    pub truth_plan: Option<Plan>,
    /// Whether the truth has a path through what the sensors reached ([`Verdicts::observable_truth_decisions`]:
    /// a drivable cell that no ray ended on nor crossed above a step's height is unknown); `None` without an
    /// observability truth. Where it has none, a map's path would have to cross cells of which the sensors
    /// told nothing but, at most, a grazing ray below a step's height.
    pub observable_truth_plan_found: Option<bool>,
    /// Cells of the map's path whose centre lies within the inflation radius of a truly blocked cell: where
    /// the robot following the map's path would touch an obstacle.
    pub unsafe_cells: Vec<CellIndex>,
    /// Of the unsafe cells, those whose truly blocked cells within the inflation radius no ray could have
    /// told about ([`Verdicts::unobservable`]): blind, not the map's fault.
    pub blind_cells: Vec<CellIndex>,
    /// With no path on the map, the cells the map could not decide that closed the way
    /// ([`oeg::closing_cells`]); empty otherwise, and when the map's blocked cells alone close it.
    pub closing: Vec<CellIndex>,
}

impl PlanCheck {
    /// With no path on the map and cells that closed the way ([`PlanCheck::closing`]), those cells in words: by
    /// why the map could not decide them (`estimate`'s doubts, or `never_observed`), by what the truth calls
    /// them and, with an observability truth, how many of the drivable ones no ray reached, as in `closed by 3
    /// cells the map cannot decide (1 never_observed, 2 step_band); the truth: 3 drivable (1 no ray reached), 0
    /// blocked`. `None` otherwise.
    pub fn closed_by(&self, verdicts: &Verdicts, estimate: &Estimate) -> Option<String> {
        if self.map_plan.is_some() {
            return None;
        }
        let (mut truly_blocked, mut unreached) = (0, 0);
        let cells = self.closing.iter().filter_map(|c| verdicts.offset(*c));
        let reasons = count_reasons(cells.map(|k| {
            let blocked = verdicts.truth[k].is_blocked();
            truly_blocked += u64::from(blocked);
            unreached += u64::from(!blocked && verdicts.unreached(k));
            match estimate.doubts.get(k).copied().flatten() {
                Some(doubt) => doubt.name(),
                None if estimate.observed.get(k) == Some(&false) => "never_observed",
                // Another mapper's arrays say no reason: the class.
                None => verdicts.mapped[k].name(),
            }
        }));
        let total: u64 = reasons.values().sum();
        let unreached = match verdicts.reached {
            Some(_) => format!(" ({unreached} no ray reached)"),
            None => String::new(),
        };
        closing_words(&reasons).map(|words| {
            format!(
                "{words}; the truth: {} drivable{unreached}, {truly_blocked} blocked",
                total - truly_blocked
            )
        })
    }
}

/// Why `map` could not decide `cell`, one that closed the way: its doubt ([`oeg::Doubt::name`]), or
/// `never_observed` (the class's name for a cell with neither, which a closing cell is not).
pub(crate) fn map_reason(
    map: &oeg::Map,
    cell: CellIndex,
    profile: &oeg::RobotProfile,
    rule: oeg::TraversabilityRule,
) -> &'static str {
    match map.doubt(cell, profile, rule) {
        Some(doubt) => doubt.name(),
        None => match map.traversability(cell, profile, rule) {
            Traversability::Unknown => "never_observed",
            class => class.name(),
        },
    }
}

/// How many of the cells that closed the way the map left undecided for each reason ([`oeg::Doubt::name`], or
/// `never_observed`), in the reasons' order.
pub(crate) fn count_reasons(reasons: impl Iterator<Item = &'static str>) -> BTreeMap<&'static str, u64> {
    let mut counts = BTreeMap::new();
    for reason in reasons {
        *counts.entry(reason).or_insert(0) += 1;
    }
    counts
}

/// The cells that closed the way, counted by reason ([`count_reasons`]), in words: `closed by 3 cells the map
/// cannot decide (2 frontier, 1 step_band)`; `None` for none.
pub(crate) fn closing_words(reasons: &BTreeMap<&'static str, u64>) -> Option<String> {
    let total: u64 = reasons.values().sum();
    let cells = match total {
        0 => return None,
        1 => "cell",
        _ => "cells",
    };
    let reasons: Vec<String> = reasons.iter().map(|(why, n)| format!("{n} {why}")).collect();
    Some(format!(
        "closed by {total} {cells} the map cannot decide ({})",
        reasons.join(", ")
    ))
}

/// Plans on the map and on the truth from the drive's first waypoint to its last.
///
/// # Errors
/// A planner input the scenario's validation should have caught (a waypoint outside the region, bad
/// options), reported against the scenario.
pub fn check(s: &Scenario, verdicts: &Verdicts) -> Result<PlanCheck> {
    let window = &verdicts.window;
    let (geometry, region) = (window.geometry(), *window.region());
    let missing = || EvalError::Input {
        path: s.name.clone().into(),
        message: "the planner needs a start and a goal inside the map region (the drive's first and last \
                  waypoints, or [planner] start_xy_m and goal_xy_m)"
            .into(),
    };
    let (from, to) = s
        .planner
        .ends(
            &s.robot.drive.waypoints_xy_m,
            s.navigation.as_ref().map(|n| n.goal_xy_m),
        )
        .ok_or_else(missing)?;
    // A point on the region's max edge (valid in a scenario) lies in the cell just outside: take the edge cell.
    let (lo, hi) = (region.min, region.max());
    let cell_of = |[x, y]: [f64; 2]| {
        geometry
            .cell_of(x, y)
            .map(|c| CellIndex::new(c.i.clamp(lo.i, hi.i), c.j.clamp(lo.j, hi.j)))
            .ok_or_else(missing)
    };
    let (start, goal) = (cell_of(from)?, cell_of(to)?);
    let planner_error = |e: oeg::Error| EvalError::Input {
        path: s.name.clone().into(),
        message: format!("planner: {e}"),
    };
    let options = s.planner.options();
    let map_plan = oeg::plan(window, &verdicts.mapped, start, goal, &options).map_err(planner_error)?;
    let truly = verdicts.truth_decisions();
    let truth_plan = oeg::plan(window, &truly, start, goal, &options).map_err(planner_error)?;
    let observable_truth_plan_found = if truth_plan.is_none() {
        // Without a path on the truth there is none through less of it.
        verdicts.reached.as_ref().map(|_| false)
    } else {
        verdicts
            .observable_truth_decisions(&truly)
            .map(|told| oeg::plan(window, &told, start, goal, &options).map(|p| p.is_some()))
            .transpose()
            .map_err(planner_error)?
    };
    let unsafe_cells = match &map_plan {
        Some(p) => unsafe_path_cells(p, window, &truly, &options).map_err(planner_error)?,
        None => Vec::new(),
    };
    let blind_cells = blind_path_cells(&unsafe_cells, verdicts, options.inflation_radius_m);
    let closing = match &map_plan {
        Some(_) => Vec::new(),
        None => oeg::closing_cells(window, &verdicts.mapped, start, goal, &options)
            .map_err(planner_error)?
            .unwrap_or_default(),
    };
    Ok(PlanCheck {
        map_plan,
        truth_plan,
        observable_truth_plan_found,
        unsafe_cells,
        blind_cells,
        closing,
    })
}

/// The unsafe path cells all of whose truly blocked cells within `radius_m` are unobservable.
fn blind_path_cells(unsafe_cells: &[CellIndex], verdicts: &Verdicts, radius_m: f64) -> Vec<CellIndex> {
    let res = verdicts.window.resolution_m();
    let reach = (radius_m / res).ceil() as i32;
    let r2 = (radius_m / res).powi(2) + 1e-9;
    unsafe_cells
        .iter()
        .filter(|c| {
            let mut near = (-reach..=reach)
                .flat_map(|dj| (-reach..=reach).map(move |di| (di, dj)))
                .filter_map(|(di, dj)| {
                    let inside = f64::from(di * di + dj * dj) <= r2;
                    let k = verdicts.offset(CellIndex::new(c.i + di, c.j + dj))?;
                    (inside && verdicts.truth[k].is_blocked()).then_some(k)
                });
            near.all(|k| verdicts.unobservable[k])
        })
        .copied()
        .collect()
}

/// The cells of `plan` whose centre lies within the inflation radius of a blocked cell of the truth's
/// decisions `truly` (row-major over `window`): where the robot following the path would touch an obstacle.
///
/// # Errors
/// As [`oeg::forbidden_mask`].
pub fn unsafe_path_cells(
    plan: &Plan,
    window: &GridWindow,
    truly: &[Traversability],
    options: &PlannerOptions,
) -> oeg::Result<Vec<CellIndex>> {
    let region = window.region();
    let forbidden = oeg::forbidden_mask(
        window,
        truly,
        &PlannerOptions {
            unknown: UnknownCells::Drivable,
            ..*options
        },
    )?;
    Ok(plan
        .cells
        .iter()
        .filter(|c| region.offset(**c).is_some_and(|k| forbidden[k]))
        .copied()
        .collect())
}

impl crate::output::CsvRow for PlanRow {
    const COLUMNS: &'static [&'static str] = &["path", "step", "x_m", "y_m", "unsafe_cell", "blind_cell"];
}

/// One row of `plan.csv`: a cell of a planned path.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanRow {
    /// `map` (planned on the map) or `truth` (planned on the truth).
    pub path: &'static str,
    /// Position along the path, 0 at the start.
    pub step: u64,
    /// Cell centre, world x, metres.
    pub x_m: f64,
    /// Cell centre, world y, metres.
    pub y_m: f64,
    /// Whether the cell lies within the inflation radius of a truly blocked cell (always false on the truth's
    /// path).
    pub unsafe_cell: bool,
    /// Whether it is unsafe and no ray could have told about the truly blocked cells near it.
    pub blind_cell: bool,
}

/// The rows of `plan.csv`: the map's path, then the truth's.
pub fn rows(check: &PlanCheck, geometry: &oeg::GridGeometry) -> Vec<PlanRow> {
    let mut rows = Vec::new();
    for (name, plan) in [("map", &check.map_plan), ("truth", &check.truth_plan)] {
        let Some(plan) = plan else { continue };
        for (step, (c, (x_m, y_m))) in plan.cells.iter().zip(polyline(plan, geometry)).enumerate() {
            rows.push(PlanRow {
                path: name,
                step: step as u64,
                x_m,
                y_m,
                unsafe_cell: name == "map" && check.unsafe_cells.contains(c),
                blind_cell: name == "map" && check.blind_cells.contains(c),
            });
        }
    }
    rows
}

/// The path's cell centres as world points, rounded to the micrometre (`crate::output::round_m`): the
/// images' polyline and the CSV files' rows.
pub fn polyline(plan: &Plan, geometry: &oeg::GridGeometry) -> Vec<(f64, f64)> {
    plan.cells
        .iter()
        .map(|c| {
            let (x, y) = geometry.cell_center(*c);
            (crate::output::round_m(x), crate::output::round_m(y))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{truth_cell, truth_raster};
    use oeg::{CellRegion, Map, MapConfig, RobotProfile, TraversabilityRule};

    #[test]
    fn a_path_through_a_wall_the_map_missed_is_unsafe_and_the_truth_goes_around() {
        // 1 m cells, 7 x 5; the truth has a wall at x = 3 m from y = 0 to 3 m, the map (all free) misses it.
        let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(6, 4)).expect("region");
        let window = GridWindow::new(oeg::GridGeometry::new(1.0).expect("resolution"), region);
        let truth = truth_raster(
            region,
            region
                .cells()
                .map(|c| {
                    let wall = c.i == 3 && c.j <= 3;
                    truth_cell(if wall { 0.2 } else { 0.0 }, wall, f32::NAN)
                })
                .collect(),
        );
        let truly = Verdicts::from_classes(&truth, vec![Traversability::Unknown; truth.cells.len()])
            .truth_decisions();
        let options = PlannerOptions {
            inflation_radius_m: 0.0,
            unknown: UnknownCells::Drivable,
            ..PlannerOptions::default()
        };
        let (s, g) = (CellIndex::new(0, 0), CellIndex::new(6, 0));
        let truth_plan = oeg::plan(&window, &truly, s, g, &options)
            .expect("valid")
            .expect("around the wall");
        assert!(
            truth_plan.cells.contains(&CellIndex::new(3, 4)),
            "over the top of the wall"
        );
        // The map: nothing observed; with unknown cells drivable it goes straight through the wall.
        let map = Map::new(MapConfig::new(1.0)).expect("map");
        let mapped = map
            .traversability_layer(region, &RobotProfile::default(), TraversabilityRule::Absolute)
            .expect("raster")
            .values;
        assert!(mapped.iter().all(|t| *t == Traversability::Unknown));
        let straight = oeg::plan(&window, &mapped, s, g, &options)
            .expect("valid")
            .expect("straight");
        assert!((straight.length_m - 6.0).abs() < 1e-9);
        let unsafe_cells = unsafe_path_cells(&straight, &window, &truly, &options).expect("valid");
        assert_eq!(unsafe_cells, [CellIndex::new(3, 0)]);
        assert_eq!(
            unsafe_path_cells(&truth_plan, &window, &truly, &options).expect("valid"),
            [],
            "the truth's own path is safe"
        );
        let check = PlanCheck {
            map_plan: Some(straight),
            truth_plan: Some(truth_plan),
            observable_truth_plan_found: None,
            unsafe_cells,
            blind_cells: Vec::new(),
            closing: Vec::new(),
        };
        let geometry = oeg::GridGeometry::new(1.0).expect("geometry");
        let csv = String::from_utf8(crate::output::csv_table(&rows(&check, &geometry)).expect("csv"))
            .expect("utf8");
        let mut lines = csv.lines();
        assert_eq!(lines.next(), Some("path,step,x_m,y_m,unsafe_cell,blind_cell"));
        assert_eq!(lines.next(), Some("map,0,0.5,0.5,false,false"));
        assert!(csv.contains("map,3,3.5,0.5,true,false\n"), "{csv}");
        assert!(csv.lines().any(|l| l.starts_with("truth,0,")));
    }

    #[test]
    fn the_closing_cells_say_how_many_drivable_ones_no_ray_reached() {
        // Three closing cells: drivable and never observed, drivable on the frontier, and a truly blocked one.
        let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(2, 0)).expect("region");
        let window = GridWindow::new(oeg::GridGeometry::new(1.0).expect("resolution"), region);
        let flat = truth_cell(0.0, false, f32::NAN);
        let truth = truth_raster(region, vec![flat, flat, truth_cell(0.2, true, f32::NAN)]);
        let mut verdicts = Verdicts::from_classes(&truth, vec![Traversability::Unknown; 3]);
        let estimate = Estimate {
            window,
            decisions: vec![Traversability::Unknown; 3],
            doubts: vec![None, Some(oeg::Doubt::Frontier), None],
            observed: vec![false, true, false],
            elevation_m: vec![f32::NAN; 3],
            variance_m2: vec![f32::NAN; 3],
            occupancy: vec![f32::NAN; 3],
            totals: crate::judge::estimate::MapTotals::default(),
        };
        let check = PlanCheck {
            map_plan: None,
            truth_plan: None,
            observable_truth_plan_found: None,
            unsafe_cells: Vec::new(),
            blind_cells: Vec::new(),
            closing: region.cells().collect(),
        };
        let words =
            "closed by 3 cells the map cannot decide (1 frontier, 2 never_observed); the truth: 2 drivable";
        assert_eq!(
            check.closed_by(&verdicts, &estimate),
            Some(format!("{words}, 1 blocked")),
            "without an observability truth nothing is said of the rays"
        );
        // The blocked cell no ray reached is counted as blocked, not as unreached.
        verdicts.reached = Some(vec![false, true, false]);
        assert_eq!(
            check.closed_by(&verdicts, &estimate),
            Some(format!("{words} (1 no ray reached), 1 blocked"))
        );
    }

    #[test]
    fn the_cells_that_closed_the_way_are_counted_by_reason() {
        assert_eq!(closing_words(&count_reasons(std::iter::empty())), None);
        assert_eq!(
            closing_words(&count_reasons(["step_band"].into_iter())).as_deref(),
            Some("closed by 1 cell the map cannot decide (1 step_band)")
        );
        let reasons = count_reasons(["frontier", "step_band", "frontier"].into_iter());
        assert_eq!(reasons, BTreeMap::from([("frontier", 2), ("step_band", 1)]));
        assert_eq!(
            closing_words(&reasons).as_deref(),
            Some("closed by 3 cells the map cannot decide (2 frontier, 1 step_band)")
        );
    }
}
