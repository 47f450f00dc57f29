//! `oeg sweep report`: `summary.csv` (each metric's mean and 95 % interval per axis value and line) and plots
//! (each metric against each numeric axis, one line per preset or categorical value; the psychometric curves
//! of the obstacle decisions).
//!
//! Intervals: Student's t over the runs (replicates) for means of counts and errors; Wilson's score interval
//! for rates (`plan_found`, the pooled obstacle decision error of the psychometric curves). Where the runs of
//! one point also differ in another numeric axis, the point pools them (a marginal mean).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::Value as Json;

use super::folder::SweepFolder;
use super::stats::{Summary, mean_interval, rate_interval};
use crate::error::{EvalError, Result};
use crate::figures::chart::{Chart, Point, Series};
use crate::figures::{ImageFormats, save_with};

pub use super::summarized::{METRICS, OPTIONAL_METRICS};

/// One row of `summary.csv`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SummaryRow {
    /// The axis along which the point lies (`all` without axes).
    pub axis: String,
    /// The axis value.
    pub value: String,
    /// The line: the values of the categorical axes (presets, scenarios), or `all`.
    pub line: String,
    /// The metric.
    pub metric: String,
    /// `student_t` or `wilson`.
    pub interval: &'static str,
    /// Runs (or obstacles) in the point.
    pub n: usize,
    /// Mean, or rate.
    pub mean: Option<f64>,
    /// Sample standard deviation.
    pub std: Option<f64>,
    /// Lower end of the 95 % interval.
    pub ci95_low: Option<f64>,
    /// Upper end.
    pub ci95_high: Option<f64>,
}

impl crate::output::CsvRow for SummaryRow {
    const COLUMNS: &'static [&'static str] = &[
        "axis",
        "value",
        "line",
        "metric",
        "interval",
        "n",
        "mean",
        "std",
        "ci95_low",
        "ci95_high",
    ];
}

struct Axis {
    key: String,
    numeric: bool,
    values: Vec<Json>,
}

fn read_rows(path: &Path) -> Result<Vec<Json>> {
    let bytes = oeg_files::read_bounded(path, super::rows::MAX_TABLE_BYTES)?;
    let text = String::from_utf8_lossy(&bytes);
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(k, l)| {
            serde_json::from_str(l).map_err(|e| EvalError::Input {
                path: path.to_path_buf(),
                message: format!("line {}: not a row: {e}", k + 1),
            })
        })
        .collect()
}

fn read_obstacles(path: &Path) -> Result<Vec<BTreeMap<String, String>>> {
    let bytes = oeg_files::read_bounded(path, super::rows::MAX_TABLE_BYTES)?;
    let mut r = csv::Reader::from_reader(bytes.as_slice());
    r.deserialize()
        .map(|row| {
            row.map_err(|e| EvalError::Input {
                path: path.to_path_buf(),
                message: e.to_string(),
            })
        })
        .collect()
}

/// A cell as text: strings bare, everything else as JSON.
fn text(v: &Json) -> String {
    match v {
        Json::String(s) => s.clone(),
        Json::Null => String::new(),
        other => other.to_string(),
    }
}

fn number(v: &Json) -> f64 {
    match v {
        Json::Number(n) => n.as_f64().unwrap_or(f64::NAN),
        Json::Bool(b) => f64::from(u8::from(*b)),
        Json::String(s) => s.parse().unwrap_or(f64::NAN),
        _ => f64::NAN,
    }
}

/// What a report covers and wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportSummary {
    /// Runs of the plan with a row (finished, `ok` or `error`).
    pub num_covered: usize,
    /// Runs in the plan.
    pub num_planned: usize,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// Checks the rows against the plan: every row a run of the plan, once. Returns how many runs they cover.
fn check_coverage(dir: &Path, plan: &Json, rows: &[Json]) -> Result<usize> {
    let ids = super::merge::plan_ids(plan);
    let plan_path = dir.join("plan.json");
    if ids.is_empty() {
        return Err(EvalError::Input {
            path: plan_path,
            message: "the plan lists no runs; expected the plan.json of `oeg sweep run` or `oeg sweep merge`"
                .into(),
        });
    }
    let planned: std::collections::BTreeSet<&str> = ids.iter().map(String::as_str).collect();
    let mut seen = std::collections::BTreeSet::new();
    let rows_path = dir.join("runs.jsonl");
    for (k, row) in rows.iter().enumerate() {
        let at = |message: String| EvalError::Input {
            path: rows_path.clone(),
            message: format!("row {}: {message}", k + 1),
        };
        let id = row["id"]
            .as_str()
            .ok_or_else(|| at("expected a row of `oeg sweep` with its run `id`".into()))?;
        if !planned.contains(id) {
            return Err(at(format!(
                "run {id} is not in {} (the folder mixes two plans); run the sweep again into a new folder",
                plan_path.display()
            )));
        }
        if !seen.insert(id) {
            return Err(at(format!("run {id} appears twice")));
        }
    }
    Ok(seen.len())
}

/// Writes `summary.csv` and the plots of a sweep's output folder (from `oeg sweep run` or `oeg sweep merge`).
/// A folder whose rows do not cover the whole plan (a shard, an unfinished run) is refused unless `partial`;
/// then every plot's title says which part of the plan it shows.
///
/// # Errors
/// Not a sweep's folder (`SweepFolder::open`), missing or malformed `plan.json`, `runs.jsonl` or
/// `obstacles.csv`, a plan with no runs, rows of another plan, an incomplete study without `partial`, or a
/// failed write.
pub fn report(dir: &Path, partial: bool, figures: ImageFormats) -> Result<ReportSummary> {
    let folder = SweepFolder::open(dir)?;
    let study = Study::read(&folder, dir, partial)?;
    let plots = dir.join("plots");
    folder.create_dir(&plots)?;
    let mut summary = Vec::new();
    let mut files = study.metric_plots(&folder, &plots, &mut summary, figures)?;
    files.extend(study.decision_plots(&folder, &plots, &mut summary, figures)?);
    let path = dir.join("summary.csv");
    folder.write_table(&path, &summary)?;
    // The same summary as Markdown, for a study's results page.
    let md_path = dir.join("summary.md");
    let md = crate::output::markdown_rows(&summary, &[]).map_err(|e| EvalError::Input {
        path: md_path.clone(),
        message: e.to_string(),
    })?;
    folder.write_bytes(&md_path, md.as_bytes())?;
    let html_path = dir.join("report.html");
    let html = study.page(dir, &files, &summary).map_err(|e| EvalError::Input {
        path: html_path.clone(),
        message: e.to_string(),
    })?;
    folder.write_bytes(&html_path, html.as_bytes())?;
    files.insert(0, html_path);
    files.insert(0, md_path);
    files.insert(0, path);
    Ok(ReportSummary {
        num_covered: study.num_covered,
        num_planned: study.num_planned,
        files,
    })
}

/// A study's rows as the report reads them.
struct Study {
    /// The sweep's name, with the part of the plan it covers when partial.
    name: String,
    /// The plan's axes, and the base scenario as a categorical axis when there are several.
    axes: Vec<Axis>,
    /// The rows of the runs that finished without error.
    ok: Vec<Json>,
    /// One row per obstacle and run.
    obstacles: Vec<BTreeMap<String, String>>,
    /// Runs of the plan the rows cover.
    num_covered: usize,
    /// Runs of the plan.
    num_planned: usize,
}

impl Study {
    /// `report.html`: the study's summary table and every plot, with links to its files.
    fn page(
        &self,
        dir: &Path,
        plots: &[PathBuf],
        summary: &[SummaryRow],
    ) -> std::result::Result<String, crate::output::TableError> {
        use crate::output::html::{Page, href, rows_to_html};
        let mut page = Page::new(&format!("oeg sweep: {}", self.name));
        page.paragraph(&format!(
            "{} of the plan's {} runs have a row; {} finished without error. Means with their 95 % intervals \
             per axis value; the plots show the same.",
            self.num_covered,
            self.num_planned,
            self.ok.len()
        ));
        page.heading("plots", "Plots");
        let figures: Vec<(String, String)> = plots
            .iter()
            .filter_map(|p| p.strip_prefix(dir).ok())
            .filter(|p| p.extension().is_some_and(|e| e == "png"))
            .map(|p| {
                let caption = p
                    .file_stem()
                    .map(|n| n.to_string_lossy().replace('_', " "))
                    .unwrap_or_default();
                (href(p), caption)
            })
            .collect();
        page.figures(&figures);
        page.heading("summary", "Summary");
        page.raw(&rows_to_html(summary, &[])?);
        page.heading("files", "Files");
        let mut links = vec![
            ("summary.csv".to_string(), "summary.csv".to_string()),
            ("summary.md".to_string(), "summary.md".to_string()),
        ];
        for name in ["plan.json", "runs.csv", "runs.jsonl", "obstacles.csv"] {
            if dir.join(name).is_file() {
                links.push((name.to_string(), name.to_string()));
            }
        }
        page.links(&links);
        Ok(page.finish())
    }

    /// Reads the plan, the rows and the obstacles, and checks that the rows cover the plan (unless
    /// `partial`).
    fn read(folder: &SweepFolder, dir: &Path, partial: bool) -> Result<Self> {
        for file in ["plan.json", "runs.jsonl", "obstacles.csv"] {
            folder.check(&dir.join(file))?;
        }
        let plan = super::rows::read_plan(dir)?;
        let rows: Vec<Json> = read_rows(&dir.join("runs.jsonl"))?;
        let num_planned = super::merge::plan_ids(&plan).len();
        let num_covered = check_coverage(dir, &plan, &rows)?;
        if num_covered < num_planned && !partial {
            return Err(EvalError::Input {
                path: dir.to_path_buf(),
                message: format!(
                    "covers {num_covered} of the plan's {num_planned} runs: finish it (`oeg sweep run` again with \
                     the same file and --out), merge every shard (`oeg sweep merge`), or give --partial to \
                     summarise the finished runs as a partial study"
                ),
            });
        }
        let obstacles = read_obstacles(&dir.join("obstacles.csv"))?;
        let mut name = plan["sweep"].as_str().unwrap_or("sweep").to_string();
        if num_covered < num_planned {
            name = format!("{name} (partial: {num_covered} of {num_planned} runs)");
        }
        let mut axes: Vec<Axis> = plan["axes"]
            .as_array()
            .map(|a| {
                a.iter()
                    .map(|x| Axis {
                        key: x["key"].as_str().unwrap_or_default().to_string(),
                        numeric: x["numeric"].as_bool().unwrap_or(false),
                        values: x["values"].as_array().cloned().unwrap_or_default(),
                    })
                    .collect()
            })
            .unwrap_or_default();
        // Several base scenarios are a categorical axis of their own.
        let mut scenarios: Vec<Json> = rows.iter().map(|r| r["scenario"].clone()).collect();
        scenarios.dedup();
        scenarios.sort_by_key(text);
        scenarios.dedup();
        if scenarios.len() > 1 {
            axes.push(Axis {
                key: "scenario".into(),
                numeric: false,
                values: scenarios,
            });
        }
        let ok = rows.into_iter().filter(|r| r["status"] == "ok").collect();
        Ok(Self {
            name,
            axes,
            ok,
            obstacles,
            num_covered,
            num_planned,
        })
    }

    /// The line a row belongs to: its value on every categorical axis but `except` (`all` without any).
    fn line_of(&self, get: &dyn Fn(&str) -> String, except: &str) -> String {
        let parts: Vec<String> = self
            .axes
            .iter()
            .filter(|a| !a.numeric && a.key != except)
            .map(|a| format!("{}={}", a.key, get(&a.key)))
            .collect();
        if parts.is_empty() {
            "all".into()
        } else {
            parts.join(", ")
        }
    }

    /// The finished runs grouped by (line, value on `axis`).
    fn points_along(&self, axis: Option<&Axis>) -> BTreeMap<(String, String), Vec<&Json>> {
        let mut by: BTreeMap<(String, String), Vec<&Json>> = BTreeMap::new();
        for r in &self.ok {
            let value = axis.map_or_else(|| "all".to_string(), |a| text(&r[&a.key]));
            let line = self.line_of(&|k| text(&r[k]), axis.map_or("", |a| a.key.as_str()));
            by.entry((line, value)).or_default().push(r);
        }
        by
    }

    /// Each metric's summary along each axis, and its plot against each numeric axis.
    fn metric_plots(
        &self,
        folder: &SweepFolder,
        plots: &Path,
        summary: &mut Vec<SummaryRow>,
        figures: ImageFormats,
    ) -> Result<Vec<PathBuf>> {
        let mut files = Vec::new();
        let axis_list: Vec<Option<&Axis>> = if self.axes.is_empty() {
            vec![None]
        } else {
            self.axes.iter().map(Some).collect()
        };
        for axis in axis_list {
            let groups = self.points_along(axis);
            let optional = OPTIONAL_METRICS.into_iter().filter(|(metric, _, is_rate)| {
                groups
                    .values()
                    .any(|runs| summarize(runs, metric, *is_rate).n > 0)
            });
            for (metric, label, is_rate) in METRICS.into_iter().chain(optional) {
                let mut lines: BTreeMap<String, Vec<Point>> = BTreeMap::new();
                for ((line, value), runs) in &groups {
                    let s = summarize(runs, metric, is_rate);
                    summary.push(SummaryRow {
                        axis: axis.map_or_else(|| "all".into(), |a| a.key.clone()),
                        value: value.clone(),
                        line: line.clone(),
                        metric: metric.into(),
                        interval: if is_rate { "wilson" } else { "student_t" },
                        n: s.n,
                        mean: finite(s.mean),
                        std: finite(s.std),
                        ci95_low: finite(s.low),
                        ci95_high: finite(s.high),
                    });
                    if let Some(a) = axis.filter(|a| a.numeric) {
                        let x = a
                            .values
                            .iter()
                            .find(|v| text(v) == *value)
                            .map_or(f64::NAN, number);
                        lines.entry(line.clone()).or_default().push(Point {
                            x,
                            y: s.mean,
                            low: s.low,
                            high: s.high,
                        });
                    }
                }
                if let Some(a) = axis.filter(|a| a.numeric) {
                    let series = lines
                        .into_iter()
                        .map(|(label, mut points)| {
                            points.sort_by(|p, q| p.x.total_cmp(&q.x));
                            Series { label, points }
                        })
                        .collect();
                    let chart = Chart {
                        title: format!("{}: {label}", self.name),
                        x_label: with_unit(&a.key),
                        y_label: label.into(),
                        series,
                        note: if is_rate {
                            "band: 95 % Wilson interval".into()
                        } else {
                            "band: 95 % t interval over runs".into()
                        },
                    };
                    files.extend(save_with(
                        &plots.join(format!("{metric}_vs_{}.png", file_safe(&a.key))),
                        &chart.draw(),
                        figures,
                        |p, b| folder.write_bytes(p, b),
                    )?);
                }
            }
        }
        Ok(files)
    }

    /// The psychometric curves of the obstacle decisions: the error rate against the distance from the
    /// threshold, one curve per line, for steps and for clearances.
    fn decision_plots(
        &self,
        folder: &SweepFolder,
        plots: &Path,
        summary: &mut Vec<SummaryRow>,
        figures: ImageFormats,
    ) -> Result<Vec<PathBuf>> {
        let mut files = Vec::new();
        for (decides, threshold, bin_m) in [
            ("step", "height - max step", 0.005),
            ("clearance", "clearance - robot height", 0.01),
        ] {
            let Some(series) = self.decision_series(decides, bin_m, summary) else {
                continue;
            };
            let chart = Chart {
                title: format!("{}: {decides} decisions", self.name),
                x_label: format!("{threshold} [cm] (bins of {:.1} cm)", bin_m * 100.0),
                y_label: "decision error rate".into(),
                series,
                note: "band: 95 % Wilson interval".into(),
            };
            files.extend(save_with(
                &plots.join(format!("psychometric_{decides}.png")),
                &chart.draw(),
                figures,
                |p, b| folder.write_bytes(p, b),
            )?);
        }
        Ok(files)
    }

    /// The error rate of the seen obstacles that decide `decides`, binned by their distance from the
    /// threshold (`bin_m`), per line; `None` when no obstacle decides it.
    fn decision_series(
        &self,
        decides: &str,
        bin_m: f64,
        summary: &mut Vec<SummaryRow>,
    ) -> Option<Vec<Series>> {
        let chosen: Vec<&BTreeMap<String, String>> = self
            .obstacles
            .iter()
            .filter(|o| {
                o.get("decides").is_some_and(|d| d == decides)
                    && o.get("decision").is_some_and(|d| d != "unseen")
            })
            .collect();
        if chosen.is_empty() {
            return None;
        }
        let mut lines: BTreeMap<String, BTreeMap<i64, (usize, usize)>> = BTreeMap::new();
        for o in &chosen {
            let d: f64 = o
                .get("threshold_distance_m")
                .and_then(|v| v.parse().ok())
                .unwrap_or(f64::NAN);
            if !d.is_finite() {
                continue;
            }
            let line = self.line_of(&|k| o.get(k).cloned().unwrap_or_default(), "");
            let bin = (d / bin_m).round() as i64;
            let e = lines.entry(line).or_default().entry(bin).or_default();
            e.0 += usize::from(o.get("decision").is_some_and(|v| v != "right"));
            e.1 += 1;
        }
        let mut series = Vec::new();
        for (line, bins) in lines {
            let mut points = Vec::new();
            for (bin, (wrong, n)) in bins {
                let s = rate_interval(wrong, n);
                let x_cm = bin as f64 * bin_m * 100.0;
                summary.push(SummaryRow {
                    axis: format!("{decides}_threshold_distance_cm"),
                    value: format!("{x_cm:.1}"),
                    line: line.clone(),
                    metric: "obstacle_decision_error".into(),
                    interval: "wilson",
                    n,
                    mean: finite(s.mean),
                    std: finite(s.std),
                    ci95_low: finite(s.low),
                    ci95_high: finite(s.high),
                });
                points.push(Point {
                    x: x_cm,
                    y: s.mean,
                    low: s.low,
                    high: s.high,
                });
            }
            series.push(Series { label: line, points });
        }
        Some(series)
    }
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

fn summarize(runs: &[&Json], metric: &str, is_rate: bool) -> Summary {
    let values: Vec<f64> = runs.iter().map(|r| number(&r[metric])).collect();
    if is_rate {
        let known: Vec<f64> = values.into_iter().filter(|v| v.is_finite()).collect();
        let hits = known.iter().filter(|v| **v > 0.5).count();
        rate_interval(hits, known.len())
    } else {
        mean_interval(&values)
    }
}

/// An axis label with the unit its key's suffix names ([`crate::output::unit_of`]).
fn with_unit(key: &str) -> String {
    crate::output::unit_of(key).map_or_else(|| key.to_string(), |unit| format!("{key} [{unit}]"))
}

/// A key as a file name part: `sensors.*.noise.range_sigma_m` -> `sensors_all_noise_range_sigma_m`.
fn file_safe(key: &str) -> String {
    key.replace('*', "all")
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
