//! A scenario run's report, written into its (staged) output folder: the map, its layer images, the comparison
//! images, `plan.csv`, `obstacles.csv`, `wrong_cells.csv`, `metrics.json`, and with a compared model
//! `comparison.csv` (and the same table as `comparison.md`) and `decisions_comparison.png`; and the page that
//! shows them all, `report.html` ([`page`]).

pub(crate) mod page;
mod physics;

pub(crate) use physics::write_physics;

use std::path::{Path, PathBuf};

use oeg::{GridGeometry, Map};
use serde::Serialize;
use sim::scenario;
use sim::truth::TruthRaster;

use crate::error::Result;
use crate::figures::{ImageFormats, comparison, save, write_layer_images};
use crate::judge::Evaluation;
use crate::navigation::NavigationLog;
use crate::navigation::record::{Event, PlanPointRow};
use crate::output::{write_bytes, write_json, write_markdown_rows, write_table};

/// Writes one map's report into `out_dir`: the map, its layer images, the comparison images, `plan.csv`,
/// `obstacles.csv`, `wrong_cells.csv` and `metrics.json` (last).
///
/// # Errors
/// A failed write.
pub(crate) fn write_report(
    out_dir: &Path,
    s: &scenario::Scenario,
    map: &Map,
    truth: &TruthRaster,
    evaluation: &Evaluation,
    overlay: Option<&comparison::Overlay>,
    formats: ImageFormats,
) -> Result<Vec<PathBuf>> {
    let profile = truth.profile;
    let mut files = Vec::new();
    let map_path = out_dir.join("map.oeg");
    write_bytes(&map_path, &oeg::map_to_bytes(map))?;
    files.push(map_path);
    files.extend(write_layer_images(
        map,
        out_dir,
        &profile,
        s.map.traversability,
        Some(*truth.window.region()),
        formats,
    )?);
    files.extend(comparison::write(
        out_dir, s, map, truth, evaluation, overlay, formats,
    )?);
    files.extend(write_tables(out_dir, truth, evaluation)?);
    let metrics_path = out_dir.join("metrics.json");
    write_json(&metrics_path, &evaluation.metrics)?;
    files.push(metrics_path);
    Ok(files)
}

/// The judgement's tables, for any map: `plan.csv`, `obstacles.csv` and `wrong_cells.csv` (`oeg run`'s
/// report and `oeg score`).
///
/// # Errors
/// A failed write.
pub(crate) fn write_tables(
    out_dir: &Path,
    truth: &TruthRaster,
    evaluation: &Evaluation,
) -> Result<Vec<PathBuf>> {
    let geometry = *evaluation.estimate.window.geometry();
    let plan = out_dir.join("plan.csv");
    write_table(
        &plan,
        &crate::judge::plan_check::rows(&evaluation.plan, &geometry),
    )?;
    let obstacles = out_dir.join("obstacles.csv");
    write_table(&obstacles, &evaluation.obstacles)?;
    let wrong = out_dir.join("wrong_cells.csv");
    write_table(
        &wrong,
        &crate::judge::wrong_cells::wrong_cells(&evaluation.estimate, truth, &evaluation.verdicts),
    )?;
    Ok(vec![plan, obstacles, wrong])
}

impl crate::output::CsvRow for ComparisonRow {
    const COLUMNS: &'static [&'static str] = &[
        "model",
        "unsafe_cells",
        "overcautious_cells",
        "uncertain_cells",
        "plan_found",
        "plan_unsafe_cells",
        "plan_length_ratio",
        "elevation_within_2sigma",
        "elevation_rmse_m",
    ];
}

/// One row of `comparison.csv`: one model's decisions on the same sensor log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct ComparisonRow {
    /// The model: the preset, with the scenario's own `[map.model]` keys over it.
    pub model: String,
    /// Unsafe cells (step and clearance).
    pub unsafe_cells: u64,
    /// Over-cautious cells.
    pub overcautious_cells: u64,
    /// Uncertain cells.
    pub uncertain_cells: u64,
    /// Whether the planner found a path on the map.
    pub plan_found: bool,
    /// Path cells within the inflation radius of a truly blocked cell.
    pub plan_unsafe_cells: u64,
    /// The map's path length over the truth's (null when either is missing).
    pub plan_length_ratio: Option<f64>,
    /// Fraction of cells whose true elevation lies within 2 sigma.
    pub elevation_within_2sigma: f64,
    /// Elevation RMSE, metres.
    pub elevation_rmse_m: f64,
}

/// `comparison.csv` and `decisions_comparison.png`: the two models' decisions side by side.
pub(crate) fn write_comparison(
    out_dir: &Path,
    runs: [(&scenario::Scenario, &Evaluation); 2],
    geometry: &GridGeometry,
    formats: ImageFormats,
) -> Result<Vec<PathBuf>> {
    let rows: Vec<ComparisonRow> = runs
        .iter()
        .map(|(s, e)| {
            let m = &e.metrics;
            ComparisonRow {
                model: s.map.preset.name().to_string(),
                unsafe_cells: m.unsafe_cells,
                overcautious_cells: m.overcautious_cells,
                uncertain_cells: m.uncertain_cells,
                plan_found: m.plan_found,
                plan_unsafe_cells: m.plan_unsafe_cells,
                plan_length_ratio: m.plan_length_ratio.is_finite().then_some(m.plan_length_ratio),
                elevation_within_2sigma: m.elevation_within_2sigma,
                elevation_rmse_m: m.elevation_rmse_m,
            }
        })
        .collect();
    let csv_path = out_dir.join("comparison.csv");
    write_table(&csv_path, &rows)?;
    // The same table as Markdown: the README's status table is this file of the default run.
    let md_path = out_dir.join("comparison.md");
    write_markdown_rows(&md_path, &rows, &[])?;
    let figures: Vec<crate::figures::Figure> = runs
        .iter()
        .zip(&rows)
        .map(|((s, e), r)| {
            comparison::decisions_figure(s, geometry, e, &format!("{}: {}", s.name, r.model), None)
        })
        .collect();
    let canvases: Vec<&crate::figures::Canvas> = figures.iter().map(|f| f.canvas()).collect();
    let mut files = vec![csv_path, md_path];
    files.extend(save(
        &out_dir.join("decisions_comparison.png"),
        &crate::figures::Canvas::side_by_side(&canvases, 24),
        formats,
    )?);
    Ok(files)
}

/// The most planned paths drawn on a closed-loop run's decisions image (evenly spread over the run).
pub(crate) const MAX_DRAWN_PLANS: usize = 5;

/// What a closed-loop run draws on its decisions image: the true trajectory and up to [`MAX_DRAWN_PLANS`]
/// of its plans, the first and the last among them.
pub(crate) fn overlay_of(log: &NavigationLog) -> comparison::Overlay {
    let n = log.plans.len();
    let picks: Vec<usize> = if n <= MAX_DRAWN_PLANS {
        (0..n).collect()
    } else {
        (0..MAX_DRAWN_PLANS)
            .map(|k| k * (n - 1) / (MAX_DRAWN_PLANS - 1))
            .collect()
    };
    comparison::Overlay {
        trajectory: log.trajectory.iter().map(|r| (r.true_x_m, r.true_y_m)).collect(),
        plans: picks.into_iter().map(|k| log.plans[k].points.clone()).collect(),
    }
}

/// Writes a closed-loop run's files: `navigation.json`, `events.csv`, `trajectory.csv`, `plans.csv`, and
/// the map's decisions at the first events' times (`events/<index>_<kind>.png`, the index its row in
/// `events.csv`).
///
/// # Errors
/// A failed write.
pub(crate) fn write_navigation(
    out_dir: &Path,
    s: &scenario::Scenario,
    truth: &TruthRaster,
    log: &NavigationLog,
    formats: ImageFormats,
) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let path = out_dir.join("navigation.json");
    write_json(&path, &log.summary)?;
    files.push(path);
    let path = out_dir.join("events.csv");
    write_table(&path, &log.summary.events)?;
    files.push(path);
    let path = out_dir.join("trajectory.csv");
    write_table(&path, &log.trajectory)?;
    files.push(path);
    let rows: Vec<PlanPointRow> = log
        .plans
        .iter()
        .enumerate()
        .flat_map(|(k, p)| {
            p.points
                .iter()
                .enumerate()
                .map(move |(step, (x, y))| PlanPointRow {
                    plan: k as u64,
                    time_s: p.time_s,
                    step: step as u64,
                    x_m: crate::output::round_m(*x),
                    y_m: crate::output::round_m(*y),
                })
        })
        .collect();
    let path = out_dir.join("plans.csv");
    write_table(&path, &rows)?;
    files.push(path);
    if !log.snapshots.is_empty() {
        let dir = out_dir.join("events");
        crate::output::create_dir(&dir)?;
        // Events are numbered in time order in `events.csv`; the snapshots name their event there.
        for snap in &log.snapshots {
            let event = &snap.event;
            let index = log.summary.events.iter().position(|e| e == event).unwrap_or(0);
            let name = event.kind.name();
            let fig = comparison::event_figure(
                s,
                truth,
                &snap.decisions,
                event_at(log, event),
                &format!("{}: {name} at t = {:.1} s", s.name, event.time_s),
            );
            files.extend(save(
                &dir.join(format!("{index:02}_{name}.png")),
                fig.canvas(),
                formats,
            )?);
        }
    }
    Ok(files)
}

/// The trajectory up to an event, and the event's place.
fn event_at(log: &NavigationLog, event: &Event) -> (Vec<(f64, f64)>, (f64, f64)) {
    (
        log.trajectory
            .iter()
            .take_while(|r| r.time_s <= event.time_s + 1e-9)
            .map(|r| (r.true_x_m, r.true_y_m))
            .collect(),
        (event.x_m, event.y_m),
    )
}

/// Writes what the sensors could see: `observability.png` (per cell, whether a ray ended on it and whether
/// one crossed its band between a step and the robot's height, with the blind cells: truly blocked, and no
/// ray could have told) and `blind_band.csv` (per range, the largest gap between rays within that band).
///
/// # Errors
/// A failed write.
pub(crate) fn write_observability(
    out_dir: &Path,
    s: &scenario::Scenario,
    observability: &sim::observability::Observability,
    verdicts: &crate::judge::verdict::Verdicts,
    blind_band: &[sim::observability::BlindBandRow],
    formats: ImageFormats,
) -> Result<Vec<PathBuf>> {
    let fig = comparison::observability_figure(s, observability, verdicts);
    let mut files = save(&out_dir.join("observability.png"), fig.canvas(), formats)?;
    let path = out_dir.join("blind_band.csv");
    write_table(&path, blind_band)?;
    files.push(path);
    Ok(files)
}

impl crate::output::CsvRow for sim::observability::BlindBandRow {
    const COLUMNS: &'static [&'static str] = &[
        "range_m",
        "rays_in_band",
        "largest_gap_m",
        "gap_from_m",
        "gap_to_m",
    ];
}
