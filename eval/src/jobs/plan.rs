//! `oeg plan`: a path on a saved map (real data or a run's `map.oeg`), written as `plan.json`, `path.csv` and
//! `plan.png`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use oeg::{CellIndex, CellRegion, RobotProfile, TraversabilityRule};
use oeg::{PlannerOptions, UnknownCells};
use serde::Serialize;

use crate::error::{EvalError, Result};
use crate::judge::plan_check::{closing_words, count_reasons, map_reason, polyline};

/// `oeg plan`: a path on a saved map (real data or a run's `map.oeg`).
#[derive(Debug, Clone)]
pub struct PlanJob {
    /// The map file.
    pub map: PathBuf,
    /// Start, world x and y, metres.
    pub from_xy_m: (f64, f64),
    /// Goal, world x and y, metres.
    pub to_xy_m: (f64, f64),
    /// Output folder.
    pub out_dir: PathBuf,
    /// How the planner reads the map.
    pub options: PlannerOptions,
    /// The robot, for the decisions.
    pub profile: RobotProfile,
    /// The step rule.
    pub rule: TraversabilityRule,
    /// The files the figure is written as (`--svg` adds an SVG beside the PNG).
    pub figures: crate::figures::ImageFormats,
}

/// `plan.json` of `oeg plan`: one object, flat but for `traversability` (the rule, as a scenario writes it) and
/// `closed_by` (counts by reason).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanSummary {
    /// Whether a path was found.
    pub plan_found: bool,
    /// Its length through the cell centres, metres (null when there is none).
    pub plan_length_m: f64,
    /// Cells of the path.
    pub num_path_cells: u64,
    /// Start, world x, metres.
    pub from_x_m: f64,
    /// Start, world y, metres.
    pub from_y_m: f64,
    /// Goal, world x, metres.
    pub to_x_m: f64,
    /// Goal, world y, metres.
    pub to_y_m: f64,
    /// The planner's inflation radius, metres.
    pub inflation_radius_m: f64,
    /// The planner's rule for unknown cells.
    pub unknown: UnknownCells,
    /// The robot's step limit, metres.
    pub max_step_m: f32,
    /// The step rule the map's cells were judged by (`map.traversability`, or the preset's).
    pub traversability: TraversabilityRule,
    /// Why there is no path (null when there is one): the start or goal cell blocked, uncertain, never
    /// observed or within the inflation radius of a blocked cell, or no connection between them.
    pub no_path_reason: Option<String>,
    /// With no connection, the cells the map cannot decide that closed the way ([`oeg::closing_cells`]), by
    /// reason: the doubt of an uncertain or unknown cell (`frontier`, `imprecise`, ...,
    /// [`oeg::Doubt::name`]) or `never_observed`; listed one by one in `closing.csv`. Empty otherwise, and
    /// when the map's blocked cells alone close the way.
    pub closed_by: BTreeMap<&'static str, u64>,
}

/// A plan on a map, with the decisions it was planned on.
#[derive(Debug, Clone)]
pub struct MapPlan {
    /// The decisions over the planning region: the map's observed region, grown to hold the start and goal.
    pub classes: oeg::Raster<oeg::Traversability>,
    /// The path, or why the goal cannot be reached.
    pub plan: std::result::Result<oeg::Plan, oeg::NoPath>,
    /// With no connection, the cells that closed the way ([`oeg::closing_cells`]); empty otherwise.
    pub closing: Vec<CellIndex>,
}

/// Plans on `map` from `from` to `to` (world x and y, metres) over its observed region, grown to hold both;
/// `name` names the map in errors.
///
/// # Errors
/// A point that is not finite or off the grid, invalid options, or decisions beyond the memory limit.
pub fn plan_on_map(
    map: &oeg::Map,
    name: &std::path::Path,
    (from, to): ((f64, f64), (f64, f64)),
    options: &PlannerOptions,
    profile: &RobotProfile,
    rule: TraversabilityRule,
) -> Result<MapPlan> {
    let geometry = *map.geometry();
    let point_error = |what: &str, (x, y): (f64, f64)| EvalError::Input {
        path: name.to_path_buf(),
        message: format!("the {what} ({x}, {y}) m is not a finite point on the map's grid"),
    };
    let start = geometry
        .cell_of(from.0, from.1)
        .ok_or_else(|| point_error("start", from))?;
    let goal = geometry
        .cell_of(to.0, to.1)
        .ok_or_else(|| point_error("goal", to))?;
    let ends = CellRegion::from_corners(
        CellIndex::new(start.i.min(goal.i), start.j.min(goal.j)),
        CellIndex::new(start.i.max(goal.i), start.j.max(goal.j)),
    )
    .ok_or_else(|| point_error("start", from))?;
    let window = oeg::GridWindow::new(geometry, map.observed_region().map_or(ends, |r| r.union(&ends)));
    let region = *window.region();
    let (width_m, height_m) = window.size_m();
    // The search's arrays, beside the decisions' raster (which the map counts itself), within the map's limit.
    let needed = region
        .num_cells()
        .saturating_mul(oeg::PLANNER_BYTES_PER_CELL)
        .saturating_add(map.memory_bytes());
    let limit = map.config().memory_limit_bytes;
    if needed > limit {
        return Err(EvalError::Input {
            path: name.to_path_buf(),
            message: format!(
                "planning from ({}, {}) to ({}, {}) m searches {} cells ({:.0} m x {:.0} m with the map), which \
                 needs {needed} bytes, over the memory limit of {limit} bytes; plan between points nearer the map",
                from.0,
                from.1,
                to.0,
                to.1,
                region.num_cells(),
                width_m,
                height_m,
            ),
        });
    }
    let classes = map.traversability_layer(region, profile, rule)?;
    let plan = oeg::plan_or_why(&classes.window, &classes.values, start, goal, options).map_err(|e| {
        EvalError::Input {
            path: name.to_path_buf(),
            message: format!("planner: {e}"),
        }
    })?;
    let closing = match plan {
        Err(oeg::NoPath::NoConnection) => {
            oeg::closing_cells(&classes.window, &classes.values, start, goal, options)
                .map_err(|e| EvalError::Input {
                    path: name.to_path_buf(),
                    message: format!("planner: {e}"),
                })?
                .unwrap_or_default()
        }
        _ => Vec::new(),
    };
    Ok(MapPlan {
        classes,
        plan,
        closing,
    })
}

/// A cell that closed the way, as `closing.csv` lists it.
#[derive(Serialize)]
struct ClosingRow {
    x_m: f64,
    y_m: f64,
    class: &'static str,
    reason: &'static str,
}

/// The cells of `closing` with why the map could not decide each ([`map_reason`]).
fn closing_rows(map: &oeg::Map, closing: &[CellIndex], job: &PlanJob) -> Vec<ClosingRow> {
    closing
        .iter()
        .map(|&cell| {
            let (x_m, y_m) = map.geometry().cell_center(cell);
            ClosingRow {
                x_m: crate::output::round_m(x_m),
                y_m: crate::output::round_m(y_m),
                class: map.traversability(cell, &job.profile, job.rule).name(),
                reason: map_reason(map, cell, &job.profile, job.rule),
            }
        })
        .collect()
}

/// Plans on a saved map and writes `plan.json`, `path.csv` (one row per path cell: `step,x_m,y_m`) and
/// `plan.png` (the traversability classes with the path, the start and the goal) into the output folder. The
/// planning region is the map's observed region, grown to hold the start and the goal.
///
/// # Errors
/// The map cannot be read, a point is not finite, the options are invalid, or a write fails.
pub fn run_job(job: &PlanJob) -> Result<(PlanSummary, Vec<PathBuf>)> {
    let staged = crate::output::Staged::begin(&job.out_dir, &[&job.map])?;
    let map = oeg::load_map(&job.map)?;
    let geometry = *map.geometry();
    let MapPlan {
        classes,
        plan,
        closing,
    } = plan_on_map(
        &map,
        &job.map,
        (job.from_xy_m, job.to_xy_m),
        &job.options,
        &job.profile,
        job.rule,
    )?;
    let closing = closing_rows(&map, &closing, job);
    let closed_by = count_reasons(closing.iter().map(|row| row.reason));
    let no_path_reason = plan.as_ref().err().map(|why| {
        let why = why.describe(&job.options);
        match closing_words(&closed_by) {
            Some(words) => format!("{why}; {words}, listed in closing.csv"),
            None => why,
        }
    });
    let plan = plan.ok();
    let summary = PlanSummary {
        plan_found: plan.is_some(),
        plan_length_m: plan.as_ref().map_or(f64::NAN, |p| p.length_m),
        num_path_cells: plan.as_ref().map_or(0, |p| p.cells.len() as u64),
        from_x_m: job.from_xy_m.0,
        from_y_m: job.from_xy_m.1,
        to_x_m: job.to_xy_m.0,
        to_y_m: job.to_xy_m.1,
        inflation_radius_m: job.options.inflation_radius_m,
        unknown: job.options.unknown,
        max_step_m: job.profile.max_step_m,
        traversability: job.rule,
        no_path_reason,
        closed_by,
    };
    let work = || -> Result<_> {
        let mut files = Vec::new();
        let path_csv = staged.dir().join("path.csv");
        crate::output::write_csv(
            &path_csv,
            &["step", "x_m", "y_m"],
            plan.iter()
                .flat_map(|p| polyline(p, &geometry))
                .enumerate()
                .map(|(step, (x, y))| (step, x, y)),
        )?;
        files.push(path_csv);
        if !closing.is_empty() {
            let closing_csv = staged.dir().join("closing.csv");
            crate::output::write_csv(&closing_csv, &["x_m", "y_m", "class", "reason"], &closing)?;
            files.push(closing_csv);
        }
        let title = match &plan {
            Some(p) => format!("Path planned on the map: {:.2} m", p.length_m),
            None => "No path on the map (plan.json says why)".to_string(),
        };
        let mut fig = crate::figures::traversability_figure(&classes, &title);
        if let Some(p) = &plan {
            fig.polyline(&polyline(p, &geometry), crate::figures::PLAN);
        }
        fig.marker(job.from_xy_m.0, job.from_xy_m.1, crate::figures::DRIVE);
        fig.marker(job.to_xy_m.0, job.to_xy_m.1, crate::figures::PLAN);
        files.extend(crate::figures::save(
            &staged.dir().join("plan.png"),
            fig.canvas(),
            job.figures,
        )?);
        let json = staged.dir().join("plan.json");
        crate::output::write_json(&json, &summary)?;
        files.push(json);
        Ok(files)
    };
    let files = staged.explained(work())?;
    let files = files.iter().map(|f| staged.final_path(f)).collect();
    staged.commit()?;
    Ok((summary, files))
}
