//! A sweep's rows: one per run (`runs.csv`, `runs.jsonl`) and one per obstacle and run (`obstacles.csv`), built
//! from a run's evaluation, kept as `runs/<id>/row.json` (the finished-run marker) and gathered into tables in
//! plan order. Columns are documented in `docs/sweep-format.md`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::{Map as JsonMap, Value as Json};

use super::folder::SweepFolder;
use super::plan::{Run, SweepPlan, to_json};
use crate::error::{EvalError, Result};

/// What one run of a shared simulation produced.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The map judged against the truth.
    pub evaluation: crate::judge::Evaluation,
    /// The robot's step, metres.
    pub max_step_m: f32,
    /// The robot's height, metres.
    pub height_m: f32,
}

/// The finished-run marker of a run.
pub fn row_path(out: &Path, id: &str) -> PathBuf {
    out.join("runs").join(id).join("row.json")
}

/// Seconds to the millisecond.
pub fn round3(v: f64) -> f64 {
    (v * 1e3).round() / 1e3
}

/// `id`, `scenario`, `replicate`, `seed` and the axis values.
pub fn lead_columns(run: &Run) -> JsonMap<String, Json> {
    let mut row = JsonMap::new();
    row.insert("id".into(), Json::from(run.id.clone()));
    row.insert("scenario".into(), Json::from(run.scenario.clone()));
    row.insert("replicate".into(), Json::from(run.replicate));
    row.insert("seed".into(), Json::from(run.seed));
    for (k, v) in &run.axis_values {
        row.insert(k.clone(), to_json(v));
    }
    row
}

/// Every metric of `metrics.json` (but the scenario name and seed, already in the row) and the obstacle
/// decision counts.
pub fn metric_columns(row: &mut JsonMap<String, Json>, o: &Outcome) {
    if let Ok(Json::Object(m)) = serde_json::to_value(&o.evaluation.metrics) {
        for (k, v) in m {
            if k != "scenario" && k != "seed" {
                row.insert(k, v);
            }
        }
    }
    let (mut right, mut unsafe_, mut cautious, mut uncertain, mut unseen) = (0u64, 0u64, 0u64, 0u64, 0u64);
    for d in &o.evaluation.obstacles {
        match d.decision {
            "right" => right += 1,
            "unsafe" => unsafe_ += 1,
            "overcautious" => cautious += 1,
            "uncertain" => uncertain += 1,
            _ => unseen += 1,
        }
    }
    row.insert("obstacles_right".into(), Json::from(right));
    row.insert("obstacles_unsafe".into(), Json::from(unsafe_));
    row.insert("obstacles_overcautious".into(), Json::from(cautious));
    row.insert("obstacles_uncertain".into(), Json::from(uncertain));
    row.insert("obstacles_unseen".into(), Json::from(unseen));
    // Obstacles no reading ever came from: invisible to the sensor set, whatever the map does.
    let never_returned = o
        .evaluation
        .obstacles
        .iter()
        .filter(|d| d.sensor_returns == Some(0))
        .count();
    row.insert("obstacles_never_returned".into(), Json::from(never_returned));
    // Uncertain obstacles are not errors: the map said it could not tell.
    let judged = right + unsafe_ + cautious;
    let rate = if judged > 0 {
        Json::from((unsafe_ + cautious) as f64 / judged as f64)
    } else {
        Json::Null
    };
    row.insert("obstacle_decision_error_rate".into(), rate);
}

/// The run's obstacles with the distance of each to its threshold: height minus the robot's step, or an
/// overhang's clearance minus the robot's height.
pub fn obstacle_rows(run: &Run, o: &Outcome) -> Vec<Json> {
    o.evaluation
        .obstacles
        .iter()
        .map(|d| {
            let (threshold, decides) = if d.kind == "overhang" {
                (f64::from(o.height_m), "clearance")
            } else {
                (f64::from(o.max_step_m), "step")
            };
            let mut row = lead_columns(run);
            row.insert("obstacle".into(), Json::from(d.index));
            row.insert("name".into(), Json::from(d.name.clone()));
            row.insert("kind".into(), Json::from(d.kind.clone()));
            row.insert("decides".into(), Json::from(decides));
            row.insert("height_m".into(), Json::from(d.height_m));
            row.insert(
                "threshold_distance_m".into(),
                Json::from(((d.height_m - threshold) * 1e6).round() / 1e6),
            );
            row.insert("sensor_returns".into(), Json::from(d.sensor_returns));
            row.insert("num_observed_cells".into(), Json::from(d.num_observed_cells));
            row.insert("unsafe_cells".into(), Json::from(d.unsafe_cells));
            row.insert("overcautious_cells".into(), Json::from(d.overcautious_cells));
            row.insert("true_decision".into(), Json::from(d.true_decision));
            row.insert("mapped_decision".into(), Json::from(d.mapped_decision));
            row.insert("uncertain_cells".into(), Json::from(d.uncertain_cells));
            row.insert("decision".into(), Json::from(d.decision));
            Json::Object(row)
        })
        .collect()
}

/// The finished rows of `runs`, in their order: `(row, obstacle rows)`.
///
/// # Errors
/// A `row.json` that cannot be read or is not its run's ([`read_record`]).
pub fn read_rows(out: &Path, runs: &[&Run]) -> Result<Vec<(Json, Vec<Json>)>> {
    let mut rows = Vec::new();
    for r in runs {
        if let Some(record) = read_record(&row_path(out, &r.id), &r.id)? {
            rows.push(record);
        }
    }
    Ok(rows)
}

/// The largest table or plan a sweep folder's files are read up to (`plan.json`, `runs.jsonl`): 100,000 runs
/// take a few hundred megabytes.
pub const MAX_TABLE_BYTES: u64 = 1 << 30;

/// A sweep folder's `plan.json`.
///
/// # Errors
/// A missing or unreadable file, over [`MAX_TABLE_BYTES`], or not a JSON object.
pub fn read_plan(dir: &Path) -> Result<Json> {
    let path = dir.join("plan.json");
    let bytes = oeg_files::read_bounded(&path, MAX_TABLE_BYTES)?;
    match serde_json::from_slice(&bytes) {
        Ok(plan @ Json::Object(_)) => Ok(plan),
        Ok(_) => Err(EvalError::Input {
            path,
            message: "not a plan written by `oeg sweep run`: expected a JSON object".into(),
        }),
        Err(e) => Err(EvalError::Input {
            path,
            message: format!("not a plan written by `oeg sweep run`: {e}"),
        }),
    }
}

/// The largest `row.json` read (a run's row and its obstacles take a few kilobytes; 10,000 obstacles about
/// 10 MB).
pub const MAX_ROW_BYTES: u64 = 64 << 20;

/// A run's `row.json` (`runs/<id>/row.json`): `None` when it does not exist.
///
/// # Errors
/// A file that is not the row of run `id`: not JSON, not an object with a `row` object (whose `id` is `id` and
/// whose `status` is `ok` or `error`) and an `obstacles` list of objects; a copied row names another run.
pub fn read_record(path: &Path, id: &str) -> Result<Option<(Json, Vec<Json>)>> {
    let bytes = match oeg_files::read_bounded(path, MAX_ROW_BYTES) {
        Ok(b) => b,
        Err(oeg_files::FileError::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
            return Ok(None);
        }
        Err(e) => return Err(e.into()),
    };
    let record: Json = serde_json::from_slice(&bytes).map_err(|e| EvalError::Input {
        path: path.to_path_buf(),
        message: format!("not a run's row: {e}"),
    })?;
    parse_record(&record, id)
        .map(Some)
        .map_err(|message| EvalError::Input {
            path: path.to_path_buf(),
            message: format!(
                "{message}; this run's folder was changed by hand: remove {} to run it again",
                path.parent().unwrap_or(path).display()
            ),
        })
}

/// A run's record (`runs/<id>/row.json`) that is not one: what is wrong with it (the reader names the file).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct RecordError {
    /// What is wrong and what was expected.
    pub message: String,
}

impl From<String> for RecordError {
    fn from(message: String) -> Self {
        Self { message }
    }
}

impl From<&str> for RecordError {
    fn from(message: &str) -> Self {
        Self {
            message: message.to_string(),
        }
    }
}

/// The checks of [`read_record`] on parsed JSON.
///
/// # Errors
/// [`RecordError`]: not an object with `row` (of run `id`, with a status) and `obstacles`.
pub fn parse_record(record: &Json, id: &str) -> std::result::Result<(Json, Vec<Json>), RecordError> {
    let Json::Object(record) = record else {
        return Err(RecordError::from(format!(
            "expected a run's row, an object with `row` and `obstacles`, got {}",
            kind_of(record)
        )));
    };
    let row = match record.get("row") {
        Some(row @ Json::Object(_)) => row.clone(),
        Some(other) => {
            return Err(RecordError::from(format!(
                "`row`: expected an object, got {}",
                kind_of(other)
            )));
        }
        None => return Err("not a run's row: no `row`".into()),
    };
    match row.get("id") {
        Some(Json::String(found)) if found == id => {}
        Some(Json::String(found)) => {
            return Err(RecordError::from(format!(
                "holds the row of run {found}, not of run {id} (a copied row)"
            )));
        }
        _ => return Err("`row.id`: expected the run's id".into()),
    }
    match row.get("status").and_then(Json::as_str) {
        Some("ok" | "error") => {}
        _ => return Err("`row.status`: expected \"ok\" or \"error\"".into()),
    }
    let obstacles = match record.get("obstacles") {
        None => Vec::new(),
        Some(Json::Array(list)) if list.iter().all(Json::is_object) => list.clone(),
        Some(_) => return Err("`obstacles`: expected a list of objects".into()),
    };
    Ok((row, obstacles))
}

fn kind_of(v: &Json) -> &'static str {
    match v {
        Json::Null => "null",
        Json::Bool(_) => "a boolean",
        Json::Number(_) => "a number",
        Json::String(_) => "a string",
        Json::Array(_) => "a list",
        Json::Object(_) => "an object",
    }
}

/// Writes `runs.csv`, `runs.jsonl` and `obstacles.csv` of the finished `runs` into `out`.
///
/// # Errors
/// A row that cannot be read, or a failed write.
pub fn write_tables(plan: &SweepPlan, runs: &[&Run], folder: &SweepFolder) -> Result<Vec<PathBuf>> {
    let rows = read_rows(folder.root(), runs)?;
    let axis_keys: Vec<String> = plan.sweep.axes.iter().map(|a| a.key.clone()).collect();
    write_row_tables(&axis_keys, &rows, folder)
}

/// Writes the tables of `rows` (from [`read_rows`]) into `out`.
///
/// # Errors
/// A failed write.
pub fn write_row_tables(
    axis_keys: &[String],
    rows: &[(Json, Vec<Json>)],
    folder: &SweepFolder,
) -> Result<Vec<PathBuf>> {
    let out = folder.root();
    let lead: Vec<String> = ["id", "scenario", "replicate", "seed"]
        .iter()
        .map(|s| (*s).to_string())
        .chain(axis_keys.iter().cloned())
        .collect();
    let mut jsonl = Vec::new();
    for (row, _) in rows {
        jsonl.extend(serde_json::to_vec(row).unwrap_or_default());
        jsonl.push(b'\n');
    }
    let runs_csv = out.join("runs.csv");
    write_json_rows(
        folder,
        &runs_csv,
        rows.iter().map(|(r, _)| r),
        &lead,
        &["status", "error"],
        &["wall_time_s"],
    )?;
    let runs_jsonl = out.join("runs.jsonl");
    folder.write_bytes(&runs_jsonl, &jsonl)?;
    let obstacles_csv = out.join("obstacles.csv");
    let mut obstacle_lead = lead.clone();
    obstacle_lead.extend(
        ["obstacle", "name", "kind", "decides"]
            .iter()
            .map(|s| (*s).to_string()),
    );
    write_json_rows(
        folder,
        &obstacles_csv,
        rows.iter().flat_map(|(_, o)| o.iter()),
        &obstacle_lead,
        &[],
        &[],
    )?;
    Ok(vec![runs_csv, runs_jsonl, obstacles_csv])
}

/// Writes JSON objects as a CSV table at `path`: `lead` columns first, then `then`, the rest sorted, `last` at
/// the end. Null is an empty cell; nested values are written as JSON.
fn write_json_rows<'a>(
    folder: &SweepFolder,
    path: &Path,
    rows: impl Iterator<Item = &'a Json> + Clone,
    lead: &[String],
    then: &[&str],
    last: &[&str],
) -> Result<()> {
    let mut rest: BTreeMap<&str, ()> = BTreeMap::new();
    for r in rows.clone() {
        if let Json::Object(m) = r {
            for k in m.keys() {
                rest.insert(k, ());
            }
        }
    }
    let mut columns: Vec<&str> = lead.iter().map(String::as_str).collect();
    columns.extend(then.iter().copied());
    for k in rest.keys() {
        if !columns.contains(k) && !last.contains(k) {
            columns.push(k);
        }
    }
    columns.extend(last.iter().copied());
    let records = rows.map(|r| {
        columns
            .iter()
            .map(|c| match &r[*c] {
                Json::Null => String::new(),
                Json::String(s) => s.clone(),
                other => other.to_string(),
            })
            .collect::<Vec<String>>()
    });
    folder.write_csv(path, &columns, records)
}
