//! `oeg suite`: run many scenarios, print a table, write `suite.csv`, `suite.json` and `suite.html`, and fail if any
//! scenario fails its expectations. Several scenarios run at once (`jobs`): a run's ray casts and truth use
//! every thread, but its map integration is one thread, so a second scenario fills the idle cores. A scenario's
//! results do not depend on it (the same bytes on any thread count).

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::error::{EvalError, Result};
use crate::judge::outcome::Safety;
use crate::output::{CsvRow, Staged, write_json, write_markdown_rows, write_table};
use crate::pipeline::{RunOptions, run_scenario};
use crate::progress::Progress;

/// One row of the suite's table (`suite.csv`, `suite.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SuiteRow {
    /// Scenario name (or the file, if it could not be read).
    pub scenario: String,
    /// The scenario file.
    pub file: String,
    /// The scenario's regression bounds (its expectations): `pass`, `fail`, or `error` (the run could not
    /// complete). Bounds set from a measured run catch a change; they do not say the map is right.
    pub status: String,
    /// What the map made the robot do: `safe`, `unsafe` (the planned path near a truly blocked cell, or a
    /// closed-loop contact) or `no path` (`Safety`); empty for a run that could not complete.
    pub safety: String,
    /// Coverage of the map region. The metrics are empty for a row with status `error`: the run measured
    /// nothing (an empty CSV field, `null` in JSON).
    pub coverage: Option<f64>,
    /// Elevation RMSE, metres.
    pub elevation_rmse_m: Option<f64>,
    /// Unsafe step cells.
    pub unsafe_step_cells: Option<u64>,
    /// Over-cautious step cells.
    pub overcautious_step_cells: Option<u64>,
    /// Unsafe clearance cells.
    pub unsafe_clearance_cells: Option<u64>,
    /// Over-cautious clearance cells.
    pub overcautious_clearance_cells: Option<u64>,
    /// The planner check: the map's path length over the truth's (1 = no detour; empty when the map or the
    /// truth has no path, or the run failed).
    pub plan_length_ratio: Option<f64>,
    /// Cells of the map's path near a true obstacle.
    pub plan_unsafe_cells: Option<u64>,
    /// Unsafe cells a ray could have told about: the map's own.
    pub unsafe_observable_cells: Option<u64>,
    /// Unsafe cells no ray could have told about.
    pub blind_cells: Option<u64>,
    /// A closed-loop run: whether it reached its goal (empty without `[navigation]`).
    pub nav_reached: Option<bool>,
    /// A closed-loop run: contacts with truly blocked cells.
    pub nav_contacts: Option<u64>,
    /// A closed-loop run: of its contacts, those with a cell a ray could have told about before.
    pub nav_contacts_observable: Option<u64>,
    /// Wall time of the run, seconds.
    pub wall_time_s: f64,
    /// Failed expectations, or the error, `; `-separated.
    pub problems: String,
}

impl CsvRow for SuiteRow {
    const COLUMNS: &'static [&'static str] = &[
        "scenario",
        "file",
        "status",
        "safety",
        "coverage",
        "elevation_rmse_m",
        "unsafe_step_cells",
        "overcautious_step_cells",
        "unsafe_clearance_cells",
        "overcautious_clearance_cells",
        "plan_length_ratio",
        "plan_unsafe_cells",
        "unsafe_observable_cells",
        "blind_cells",
        "nav_reached",
        "nav_contacts",
        "nav_contacts_observable",
        "wall_time_s",
        "problems",
    ];
}

/// The scenario files named by `paths`: files as given, folders' `*.toml` files sorted by name. A file named
/// twice (by the same path or another, or through a folder) runs once, where it was first named.
///
/// # Errors
/// A path that does not exist or a folder that cannot be read, and two different files with the same name
/// (their outputs would share `<out>/<name>/`).
pub fn expand(paths: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut files: Vec<PathBuf> = std::fs::read_dir(p)
                .map_err(|source| EvalError::Io {
                    path: p.clone(),
                    source,
                })?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| f.extension().is_some_and(|e| e == "toml"))
                .collect();
            files.sort();
            out.extend(files);
        } else if p.is_file() {
            out.push(p.clone());
        } else {
            return Err(EvalError::Input {
                path: p.clone(),
                message: "no such scenario file or folder".into(),
            });
        }
    }
    if out.is_empty() {
        return Err(EvalError::CommandLine {
            message: "no scenario files found".into(),
        });
    }
    // Each file once, as first named, with its canonical path.
    let mut unique: Vec<(PathBuf, PathBuf)> = Vec::new();
    for file in out {
        let real = std::fs::canonicalize(&file).map_err(|source| EvalError::Io {
            path: file.clone(),
            source,
        })?;
        if unique.iter().any(|(r, _)| *r == real) {
            continue;
        }
        if let Some((_, first)) = unique.iter().find(|(_, f)| f.file_stem() == file.file_stem()) {
            return Err(EvalError::Input {
                path: file.clone(),
                message: format!(
                    "has the same name as {}, and each scenario's results go to <out>/{}/: rename one",
                    first.display(),
                    file.file_stem().unwrap_or_default().to_string_lossy()
                ),
            });
        }
        unique.push((real, file));
    }
    Ok(unique.into_iter().map(|(_, file)| file).collect())
}

/// Runs every scenario into `out_dir/<name>/`, up to `jobs` at once on a pool of `jobs` threads (1: one
/// after another on the current threads), and writes `suite.csv` and `suite.json` into `out_dir`, rows in the
/// order of the files.
///
/// # Errors
/// Bad paths, a thread pool that cannot start, or a failed write; a scenario that fails or errors is a row,
/// not an error.
pub fn suite(
    paths: &[PathBuf],
    out_dir: &Path,
    overrides: &[String],
    jobs: usize,
    figures: crate::figures::ImageFormats,
) -> Result<Vec<SuiteRow>> {
    use rayon::prelude::*;
    let files = expand(paths)?;
    let inputs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let staged = Staged::begin(out_dir, &inputs)?;
    let stage = staged.dir();
    let rows: Vec<SuiteRow> = if jobs <= 1 {
        files
            .iter()
            .map(|f| run_one(f, stage, overrides, figures))
            .collect()
    } else {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(jobs)
            .build()
            .map_err(|e| EvalError::CommandLine {
                message: format!("cannot start {jobs} threads for --jobs: {e}"),
            })?;
        pool.install(|| {
            files
                .par_iter()
                .with_max_len(1)
                .map(|f| run_one(f, stage, overrides, figures))
                .collect()
        })
    };
    let write = || -> Result<()> {
        write_table(&stage.join("suite.csv"), &rows)?;
        write_json(&stage.join("suite.json"), &rows)?;
        // The table as Markdown for a results page, without what varies from run to run (the wall time).
        write_markdown_rows(&stage.join("suite.md"), &rows, &["file", "wall_time_s"])?;
        let page = suite_page(&files, &rows, stage);
        crate::output::write_bytes(&stage.join("suite.html"), page.as_bytes())
    };
    staged.explained(write())?;
    staged.commit()?;
    Ok(rows)
}

/// The run's folder of a scenario file in the suite's folder: its file stem.
fn run_dir(file: &Path) -> String {
    file.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// `suite.html`: one row per scenario with its status, key metrics and the thumbnail of its decisions, each
/// linking to the run's own page (a run that could not complete has neither).
fn suite_page(files: &[PathBuf], rows: &[SuiteRow], stage: &Path) -> String {
    use crate::output::html::{Page, escape, field, href};
    let passed = rows.iter().filter(|r| r.status == "pass").count();
    let count_of = |word: &str| rows.iter().filter(|r| r.safety == word).count();
    let (safe, unsafe_runs, no_path) = (count_of("safe"), count_of("unsafe"), count_of("no path"));
    let errors = rows.iter().filter(|r| r.status == "error").count();
    let mut page = Page::new("oeg suite");
    let class = if unsafe_runs > 0 || errors > 0 {
        "fail"
    } else if no_path > 0 {
        "neutral"
    } else {
        "pass"
    };
    page.raw(&format!(
        "<div class=\"verdict {class}\" id=\"verdict\"><p><b>Would the robot have driven safely?</b> {}</p>\
         <p>Regression bounds (each scenario's expectations, set from a measured run with a margin: they catch a \
         change, they do not say the map is right): {}.</p></div>",
        escape(&format!(
            "{safe} of {n} scenarios safe, {unsafe_runs} unsafe (the planned path near a truly blocked cell, or \
             a closed-loop contact), {no_path} with no path{}.",
            if errors > 0 {
                format!(", {errors} could not run")
            } else {
                String::new()
            },
            n = rows.len()
        )),
        escape(&format!("{passed} of {} scenarios within their bounds", rows.len()))
    ));
    page.raw("<p>The same rows as suite.csv (<a href=\"suite.csv\">suite.csv</a>, <a href=\"suite.json\">suite.json</a>).</p>");
    let header = [
        "decisions",
        "scenario",
        "drive",
        "regression bounds",
        "coverage",
        "elevation RMSE [m]",
        "unsafe step cells",
        "unsafe clearance cells",
        "over-cautious cells (step + clearance)",
        "plan length ratio",
        "plan unsafe cells",
        "unsafe cells a ray could have told about",
        "blind cells",
        "closed loop",
        "problems",
    ];
    let mut table = String::from("<table>\n<thead><tr>");
    for h in header {
        table.push_str(&format!("<th>{}</th>", escape(h)));
    }
    table.push_str("</tr></thead>\n<tbody>\n");
    let num = |v: Option<f64>| field(&v.map(|v| v.to_string()).unwrap_or_default());
    let count = |v: Option<u64>| v.map_or("-".to_string(), |v| v.to_string());
    for (file, r) in files.iter().zip(rows) {
        let dir = run_dir(file);
        let report = Path::new(&dir).join("report.html");
        let image = Path::new(&dir).join("decisions.png");
        let (thumb, name) = if stage.join(&report).is_file() && stage.join(&image).is_file() {
            (
                format!(
                    "<a href=\"{r}\"><img class=\"thumb\" src=\"{i}\" alt=\"decisions of {n}\"></a>",
                    r = escape(&href(&report)),
                    i = escape(&href(&image)),
                    n = escape(&r.scenario)
                ),
                format!(
                    "<a href=\"{}\">{}</a>",
                    escape(&href(&report)),
                    escape(&r.scenario)
                ),
            )
        } else {
            ("-".to_string(), escape(&r.scenario))
        };
        let overcautious = match (r.overcautious_step_cells, r.overcautious_clearance_cells) {
            (Some(a), Some(b)) => (a + b).to_string(),
            _ => "-".into(),
        };
        let closed_loop = match (r.nav_reached, r.nav_contacts) {
            (Some(reached), contacts) => format!(
                "{}, {} contacts ({} observable)",
                if reached { "reached" } else { "not reached" },
                count(contacts),
                count(r.nav_contacts_observable)
            ),
            (None, _) => "-".into(),
        };
        let cells = [
            num(r.coverage),
            num(r.elevation_rmse_m),
            count(r.unsafe_step_cells),
            count(r.unsafe_clearance_cells),
            overcautious,
            num(r.plan_length_ratio),
            count(r.plan_unsafe_cells),
            count(r.unsafe_observable_cells),
            count(r.blind_cells),
        ];
        table.push_str(&format!(
            "<tr><td>{thumb}</td><td>{name}</td><td><span class=\"badge {safety_class}\">{safety}</span></td>\
             <td class=\"{status}-text\">{status}</td>{cells}<td>{nav}</td><td>{problems}</td></tr>\n",
            safety_class = match r.safety.as_str() {
                "safe" => "safe",
                "unsafe" => "unsafe",
                _ => "nopath",
            },
            safety = escape(if r.safety.is_empty() { "-" } else { &r.safety }),
            status = escape(&r.status),
            cells = cells
                .iter()
                .map(|c| format!("<td class=\"num\">{}</td>", escape(c)))
                .collect::<String>(),
            nav = escape(&closed_loop),
            problems = escape(&r.problems),
        ));
    }
    table.push_str("</tbody>\n</table>\n");
    page.raw(&table);
    page.finish()
}

/// Runs one scenario of the suite into `out_dir/<file stem>/` and prints its table line as it finishes.
fn run_one(
    file: &Path,
    out_dir: &Path,
    overrides: &[String],
    figures: crate::figures::ImageFormats,
) -> SuiteRow {
    let start = Instant::now();
    let stem = run_dir(file);
    let options = RunOptions {
        scenario: file.to_path_buf(),
        out_dir: Some(out_dir.join(&stem)),
        seed: None,
        overrides: overrides.to_vec(),
        compare: None,
        planner_command: None,
        allow_scenario_command: false,
        mcap: false,
        figures,
        planner_callback: None,
    };
    let row = match run_scenario(&options, &Progress::hidden()) {
        Ok(r) => SuiteRow {
            scenario: r.metrics.scenario.clone(),
            file: file.display().to_string(),
            status: if r.failed.is_empty() { "pass" } else { "fail" }.into(),
            safety: Safety::of(&r.metrics).name().into(),
            coverage: Some(r.metrics.coverage),
            elevation_rmse_m: Some(r.metrics.elevation_rmse_m),
            unsafe_step_cells: Some(r.metrics.unsafe_step_cells),
            overcautious_step_cells: Some(r.metrics.overcautious_step_cells),
            unsafe_clearance_cells: Some(r.metrics.unsafe_clearance_cells),
            overcautious_clearance_cells: Some(r.metrics.overcautious_clearance_cells),
            plan_length_ratio: Some(r.metrics.plan_length_ratio).filter(|v| v.is_finite()),
            plan_unsafe_cells: Some(r.metrics.plan_unsafe_cells),
            unsafe_observable_cells: Some(r.metrics.unsafe_observable_cells),
            blind_cells: Some(r.metrics.blind_cells),
            nav_reached: r.metrics.nav.reached,
            nav_contacts: r.metrics.nav.contacts,
            nav_contacts_observable: r.metrics.nav.contacts_observable,
            wall_time_s: start.elapsed().as_secs_f64(),
            problems: r
                .failed
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join("; "),
        },
        Err(e) => SuiteRow {
            scenario: stem,
            file: file.display().to_string(),
            status: "error".into(),
            safety: String::new(),
            coverage: None,
            elevation_rmse_m: None,
            unsafe_step_cells: None,
            overcautious_step_cells: None,
            unsafe_clearance_cells: None,
            overcautious_clearance_cells: None,
            plan_length_ratio: None,
            plan_unsafe_cells: None,
            unsafe_observable_cells: None,
            blind_cells: None,
            nav_reached: None,
            nav_contacts: None,
            nav_contacts_observable: None,
            wall_time_s: start.elapsed().as_secs_f64(),
            problems: e.to_string(),
        },
    };
    eprintln!("{}", table_line(&row));
    row
}

/// The table's header.
pub fn table_header() -> String {
    format!(
        "{:<26} {:>7} {:>6} {:>9} {:>9} {:>8} {:>8} {:>8} {:>8} {:>6} {:>8}",
        "scenario",
        "drive",
        "bounds",
        "coverage",
        "rmse [m]",
        "unsafe",
        "cautious",
        "unsafe-c",
        "caut.-c",
        "path",
        "time [s]"
    )
}

/// One row of the table; `-` where a failed run measured nothing.
pub fn table_line(r: &SuiteRow) -> String {
    let real = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{v:.3}"));
    let count = |v: Option<u64>| v.map_or_else(|| "-".to_string(), |v| v.to_string());
    let path = if r.status == "error" {
        "-".to_string()
    } else {
        r.plan_length_ratio
            .map_or_else(|| "none".to_string(), |v| format!("{v:.2}"))
    };
    format!(
        "{:<26} {:>7} {:>6} {:>9} {:>9} {:>8} {:>8} {:>8} {:>8} {:>6} {:>8.1}",
        r.scenario,
        if r.safety.is_empty() { "-" } else { &r.safety },
        r.status,
        real(r.coverage),
        real(r.elevation_rmse_m),
        count(r.unsafe_step_cells),
        count(r.overcautious_step_cells),
        count(r.unsafe_clearance_cells),
        count(r.overcautious_clearance_cells),
        path,
        r.wall_time_s
    )
}
