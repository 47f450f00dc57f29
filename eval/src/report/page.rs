//! `report.html`: a scenario run on one page, to open and share. The verdict first, then the decisions, the
//! map against the truth, the closed loop and what the sensors could see where the run has them, the tables
//! (metrics, obstacles, the plan check), the settings, and a link to every file of the run. Several models of
//! the same run (`--compare`) stand side by side.

use std::path::{Path, PathBuf};

use serde_json::Value;
use sim::scenario::Scenario;

use crate::error::{EvalError, Result};
use crate::judge::Evaluation;
use crate::judge::outcome::{Outcome, Safety};
use crate::navigation::NavigationLog;
use crate::output::html::{Page, escape, field, href, rows_to_html, table_html};
use crate::output::{unit_of, write_bytes};

/// The metrics' definitions: `docs/metrics.md`, built into the program so that the page carries them (it
/// needs no network and no copy of the repository).
const METRICS_DOC: &str = include_str!("../../../docs/metrics.md");

/// The definition of each metric key, from the table of `docs/metrics.md` (a row `| `key`, `key` | unit | definition |`).
pub(crate) fn metric_definitions() -> std::collections::BTreeMap<String, String> {
    let mut out = std::collections::BTreeMap::new();
    for line in METRICS_DOC.lines() {
        let cells: Vec<&str> = line.trim().trim_matches('|').split('|').map(str::trim).collect();
        let [keys, _unit, definition] = cells.as_slice() else {
            continue;
        };
        if !keys.starts_with('`') {
            continue;
        }
        for key in keys.split(',') {
            let key = key.trim().trim_matches('`');
            // The first table to define a key is the metrics' own (later tables reuse names).
            if !key.is_empty() {
                out.entry(key.to_string())
                    .or_insert_with(|| definition.replace('`', ""));
            }
        }
    }
    out
}

/// One model of the run: its scenario (with its map settings), its evaluation and its folder inside the run's
/// (empty for the run's own model).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ModelRun<'a> {
    /// The scenario as this model ran it.
    pub scenario: &'a Scenario,
    /// The judge's evaluation of its map.
    pub evaluation: &'a Evaluation,
    /// Its folder, relative to the run's (`""` or `"robust"`).
    pub dir: &'a str,
}

impl ModelRun<'_> {
    fn name(&self) -> &'static str {
        self.scenario.map.preset.name()
    }

    /// What this model's map made the robot do, and its regression bounds.
    pub(crate) fn outcome(&self) -> Outcome {
        let e = self.evaluation;
        Outcome::new(self.name(), &e.metrics, &self.scenario.expectations)
            .with_closed_by(e.plan.closed_by(&e.verdicts, &e.estimate))
    }

    fn file(&self, name: &str) -> String {
        if self.dir.is_empty() {
            name.to_string()
        } else {
            format!("{}/{name}", self.dir)
        }
    }
}

/// Everything the page shows.
#[derive(Debug, Clone)]
pub(crate) struct RunPage<'a> {
    /// The scenario file as given.
    pub scenario_file: &'a Path,
    /// The models, the run's own first.
    pub models: Vec<ModelRun<'a>>,
    /// Every `--set` of the run, in order.
    pub overrides: &'a [String],
    /// The external planner's command line, when the run used one.
    pub planner_command: Option<&'a [String]>,
    /// The closed loop's records, when the run navigated.
    pub navigation: Option<&'a NavigationLog>,
    /// What happened to the robot on its wheels, when it drove on them.
    pub physics: Option<crate::judge::PhysicsRecord<'a>>,
    /// The run's files, relative to its folder.
    pub files: Vec<PathBuf>,
}

/// Writes `report.html` into `out_dir` and returns its path.
///
/// # Errors
/// A table that cannot be written, or a failed write.
pub(crate) fn write_run_page(out_dir: &Path, run: &RunPage) -> Result<PathBuf> {
    let path = out_dir.join("report.html");
    let html = run_page(run).map_err(|message| EvalError::Input {
        path: path.clone(),
        message,
    })?;
    write_bytes(&path, html.as_bytes())?;
    Ok(path)
}

/// The page as HTML text, or what kept a table from being written.
fn run_page(run: &RunPage) -> std::result::Result<String, String> {
    let own = run.models.first().ok_or("a run page needs a model")?;
    let s = own.scenario;
    let mut page = Page::new(&format!("oeg run: {}", s.name));
    if !s.description.is_empty() {
        page.paragraph(&s.description);
    }
    verdict(&mut page, run);
    decisions(&mut page, run);
    if let Some(log) = run.navigation {
        closed_loop(&mut page, log, &run.files)?;
    }
    if let Some(record) = &run.physics {
        super::physics::page_section(&mut page, record);
    }
    if run.files.iter().any(|f| f == Path::new("observability.png")) {
        page.heading("observability", "What the sensors could see");
        page.paragraph(
            "Per cell, whether a ray ended on it (its step could be measured) or crossed the band between a \
             step and the robot's height (its clearance could be measured); truly blocked cells that no ray \
             could tell about are blind. The blind band per distance is in blind_band.csv.",
        );
        page.figures(&[(
            "observability.png".into(),
            "What the sensors could see, and the blind cells".into(),
        )]);
    }
    metrics(&mut page, run)?;
    for m in &run.models {
        page.heading(
            &format!("obstacles-{}", m.name()),
            &format!("Obstacles ({} model)", m.name()),
        );
        page.raw(&rows_to_html(&m.evaluation.obstacles, &[]).map_err(|e| e.to_string())?);
    }
    plan_check(&mut page, run)?;
    settings(&mut page, run)?;
    page.heading("files", "Files");
    let links: Vec<(String, String)> = run
        .files
        .iter()
        .map(|f| (href(f), f.display().to_string()))
        .collect();
    page.links(&links);
    Ok(page.finish())
}

/// The verdict: per model, whether the robot would have driven safely on its map and how its wrong cells split
/// ([`Outcome`]); then the scenario's expectations, named as the regression bounds they are, for every model.
fn verdict(page: &mut Page, run: &RunPage) {
    let outcomes: Vec<Outcome> = run.models.iter().map(ModelRun::outcome).collect();
    let mut html = String::from(
        "<div class=\"verdict neutral\" id=\"verdict\">\n<p><b>Would the robot have driven safely on this \
         map?</b> The path planned on the map from the start to the goal, checked against the truth, and the \
         map's wrong cells.</p>\n<ul>\n",
    );
    for o in &outcomes {
        let class = match o.safety {
            Safety::Safe => "safe",
            Safety::Unsafe => "unsafe",
            Safety::NoPath => "nopath",
        };
        html.push_str(&format!(
            "<li><b>{model}</b>: <span class=\"badge {class}\">{word}</span> planned path: {path}.",
            model = escape(&o.model),
            word = escape(&o.safety.name().to_uppercase()),
            path = escape(&o.path_text()),
        ));
        if let Some(drive) = o.drive_text() {
            html.push_str(&format!(" Closed loop: {}.", escape(&drive)));
        }
        html.push_str(&format!(" Cells: {}.</li>\n", escape(&o.cells_text())));
    }
    html.push_str("</ul>\n</div>\n");
    page.raw(&html);
    if outcomes.iter().all(|o| o.bounds.is_empty()) {
        page.paragraph("The scenario sets no expectations (regression bounds): nothing to pass or fail.");
        return;
    }
    page.heading("bounds", "Regression bounds");
    page.paragraph(
        "The scenario's expectations are regression bounds, set from a measured run with a margin: they catch a \
         change in the results, they do not say the map is right. The run's exit status follows the first \
         model's; a compared model is checked against the same bounds and shown, not enforced.",
    );
    let mut list = String::from("<ul class=\"bounds\">\n");
    for o in &outcomes {
        let class = if o.failed_bounds().next().is_some() {
            "fail"
        } else {
            "pass"
        };
        list.push_str(&format!(
            "<li><b>{}</b>: <span class=\"{class}-text\">{}</span></li>\n",
            escape(&o.model),
            escape(&o.bounds_text())
        ));
    }
    list.push_str("</ul>\n");
    page.raw(&list);
    let mut header = vec!["expectation".to_string(), "required".to_string()];
    header.extend(outcomes.iter().map(|o| format!("{} measured", o.model)));
    let rows: Vec<Vec<String>> = outcomes[0]
        .bounds
        .iter()
        .enumerate()
        .map(|(k, first)| {
            let mut row = vec![first.metric.clone(), first.required.clone()];
            row.extend(outcomes.iter().map(|o| {
                o.bounds.get(k).map_or("-".into(), |r| {
                    format!(
                        "{}{}",
                        field(&r.measured.to_string()),
                        if r.passed { "" } else { " FAIL" }
                    )
                })
            }));
            row
        })
        .collect();
    page.raw(&format!(
        "<details><summary>Every bound</summary>\n{}</details>\n",
        table_html(&header, &rows)
    ));
}

/// The decisions of every model side by side, then each model's map, truth and error side by side.
fn decisions(page: &mut Page, run: &RunPage) {
    page.heading("decisions", "Decisions");
    page.paragraph(
        "Every cell's decision judged against the truth: right, unsafe (mapped drivable where the robot cannot \
         go), over-cautious (mapped blocked where it can) or uncertain; with the drive, the obstacles and the \
         path planned on the map.",
    );
    let figures: Vec<(String, String)> = run
        .models
        .iter()
        .map(|m| {
            (
                m.file("decisions.png"),
                format!(
                    "{} model: {} unsafe, {} over-cautious, {} uncertain cells",
                    m.name(),
                    m.evaluation.metrics.unsafe_cells,
                    m.evaluation.metrics.overcautious_cells,
                    m.evaluation.metrics.uncertain_cells
                ),
            )
        })
        .collect();
    page.figures(&figures);
    page.heading("map", "The map against the truth");
    for (k, m) in run.models.iter().enumerate() {
        let name = m.name();
        let mut figures = vec![(m.file("elevation.png"), format!("{name} model: mapped elevation"))];
        // The truth is the same for every model: shown once, in the first row.
        if k == 0 {
            figures.push(("truth_elevation.png".into(), "true elevation".into()));
        }
        figures.push((
            m.file("elevation_error.png"),
            format!(
                "{name} model: map - truth (RMSE {:.3} m)",
                m.evaluation.metrics.elevation_rmse_m
            ),
        ));
        figures.push((
            m.file("traversability.png"),
            format!("{name} model: the map's decisions"),
        ));
        figures.push((
            m.file("occupancy.png"),
            format!("{name} model: occupancy probability"),
        ));
        figures.push((
            m.file("variance.png"),
            format!("{name} model: elevation variance"),
        ));
        // Three a row.
        for row in figures.chunks(3) {
            page.figures(row);
        }
    }
}

/// A closed-loop run: the outcome, the events and the maps at the events.
fn closed_loop(page: &mut Page, log: &NavigationLog, files: &[PathBuf]) -> std::result::Result<(), String> {
    let n = &log.summary;
    page.heading("navigation", "Closed loop");
    page.paragraph(&format!(
        "Outcome: {} after {:.1} s; driven {:.2} m{}; {} replans; the trajectory and some of the plans are on \
         the decisions image above.",
        n.outcome.name(),
        n.time_s,
        n.driven_length_m,
        n.length_ratio
            .map(|r| format!(" ({r:.2} times the truth's shortest path)"))
            .unwrap_or_default(),
        n.replans
    ));
    page.raw(&rows_to_html(&n.events, &[]).map_err(|e| e.to_string())?);
    // The event images (`events/<index>_<kind>.png`, the index the event's row above).
    let figures: Vec<(String, String)> = files
        .iter()
        .filter(|f| f.starts_with("events") && f.extension().is_some_and(|e| e == "png"))
        .map(|f| {
            let name = f
                .file_stem()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            (href(f), format!("event {}", name.replacen('_', ": ", 1)))
        })
        .collect();
    if !figures.is_empty() {
        page.paragraph("The map's decisions at the first events:");
        page.figures(&figures);
    }
    Ok(())
}

/// Every metric, one column per model, with its unit.
fn metrics(page: &mut Page, run: &RunPage) -> std::result::Result<(), String> {
    page.heading("metrics", "Metrics");
    page.paragraph(
        "Each metric with its unit and its definition (from the testbed's docs/metrics.md, carried by this page).",
    );
    let values = metric_objects(run)?;
    let definitions = metric_definitions();
    let mut header = vec!["metric".to_string(), "unit".to_string()];
    header.extend(run.models.iter().map(|m| m.name().to_string()));
    header.push("definition".to_string());
    let rows: Vec<Vec<String>> = values[0]
        .keys()
        .map(|key| {
            let mut row = vec![key.clone(), unit_of(key).unwrap_or("").to_string()];
            row.extend(values.iter().map(|v| value_text(v.get(key))));
            row.push(definitions.get(key).cloned().unwrap_or_default());
            row
        })
        .collect();
    page.raw(&table_html(&header, &rows));
    Ok(())
}

/// Every model's metrics as JSON objects, in the models' order.
fn metric_objects(run: &RunPage) -> std::result::Result<Vec<serde_json::Map<String, Value>>, String> {
    run.models
        .iter()
        .map(|m| match serde_json::to_value(&m.evaluation.metrics) {
            Ok(Value::Object(o)) => Ok(o),
            _ => Err("the metrics are not an object".to_string()),
        })
        .collect()
}

/// A JSON value as a table cell.
pub(super) fn value_text(v: Option<&Value>) -> String {
    match v {
        None | Some(Value::Null) => "-".into(),
        Some(Value::String(s)) => s.clone(),
        Some(Value::Number(n)) => field(&n.to_string()),
        Some(other) => other.to_string(),
    }
}

/// The planner check of every model.
fn plan_check(page: &mut Page, run: &RunPage) -> std::result::Result<(), String> {
    page.heading("plan", "Plan check");
    page.paragraph(
        "A* from the start to the goal on the map's decisions, with the robot's inflation, against the same \
         search on the truth, and on the truth as far as the rays reached it (a drivable cell no ray ended on nor \
         crossed above a step's height counts as never observed); the path's cells near a truly blocked cell are \
         unsafe. The path is in plan.csv.",
    );
    let keys = [
        "plan_found",
        "truth_plan_found",
        "observable_truth_plan_found",
        "plan_length_ratio",
        "plan_unsafe_cells",
        "plan_blind_cells",
    ];
    let values = metric_objects(run)?;
    let mut header = vec!["".to_string()];
    header.extend(run.models.iter().map(|m| m.name().to_string()));
    let rows: Vec<Vec<String>> = keys
        .iter()
        .filter(|k| values.iter().any(|v| v.contains_key(**k)))
        .map(|k| {
            let mut row = vec![(*k).to_string()];
            row.extend(values.iter().map(|v| value_text(v.get(*k))));
            row
        })
        .collect();
    page.table(&header, &rows);
    Ok(())
}

/// The settings the run used: the scenario file, its seed, every model's preset and options, every `--set`.
fn settings(page: &mut Page, run: &RunPage) -> std::result::Result<(), String> {
    let s = run.models[0].scenario;
    page.heading("settings", "Settings");
    let mut rows = vec![
        vec![
            "scenario file".to_string(),
            run.scenario_file.display().to_string(),
        ],
        vec!["seed".to_string(), s.seed.to_string()],
        vec![
            "region [m]".to_string(),
            format!(
                "({}, {}) to ({}, {})",
                s.map.min_xy_m[0], s.map.min_xy_m[1], s.map.max_xy_m[0], s.map.max_xy_m[1]
            ),
        ],
        vec!["resolution [m]".to_string(), s.map.resolution_m.to_string()],
        vec![
            "models".to_string(),
            run.models.iter().map(|m| m.name()).collect::<Vec<_>>().join(", "),
        ],
        vec![
            "--set".to_string(),
            if run.overrides.is_empty() {
                "(none)".to_string()
            } else {
                run.overrides.join("  ")
            },
        ],
    ];
    if let Some(command) = run.planner_command {
        rows.push(vec![
            "planner command".to_string(),
            crate::navigation::external::shown_command(command),
        ]);
    }
    page.table(&["setting", "value"], &rows);
    for m in &run.models {
        let options = serde_json::to_string_pretty(&(&m.scenario.map.model, &m.scenario.map.traversability))
            .map_err(|e| e.to_string())?;
        page.raw(&format!(
            "<p>The {} model's options and traversability rule, after its preset and every <code>--set</code>:</p>\n<pre>{}</pre>",
            escape(m.name()),
            escape(&options)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_metric_has_a_definition_carried_by_the_page() {
        let definitions = metric_definitions();
        for name in crate::judge::metrics::metric_names() {
            assert!(
                definitions.get(&name).is_some_and(|d| !d.is_empty()),
                "docs/metrics.md defines no `{name}`"
            );
        }
        assert!(definitions["coverage"].contains("num_observed_cells / num_cells"));
    }
}
