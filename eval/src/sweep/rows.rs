//! A sweep's rows: one per run (`runs.csv`, `runs.jsonl`) and one per obstacle and run (`obstacles.csv`), built
//! from a run's evaluation, kept as `runs/<id>/row.json` (the finished-run marker) and gathered into tables in
//! plan order. Columns are documented in `docs/sweep-format.md`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::{Map as JsonMap, Value as Json};

use super::plan::{Plan, Run, to_json};
use crate::error::{EvalError, Result};
use crate::output::write_bytes;

/// What one run of a shared simulation produced.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The map judged against the truth.
    pub evaluation: crate::evaluation::Evaluation,
    /// The robot's step, metres.
    pub max_step_m: f64,
    /// The robot's height, metres.
    pub height_m: f64,
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
        .filter(|d| d.sensor_returns == 0)
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
                (o.height_m, "clearance")
            } else {
                (o.max_step_m, "step")
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
/// A `row.json` that cannot be read.
pub fn read_rows(out: &Path, runs: &[&Run]) -> Result<Vec<(Json, Vec<Json>)>> {
    let mut rows = Vec::new();
    for r in runs {
        let path = row_path(out, &r.id);
        if let Some(record) = read_record(&path)? {
            rows.push(record);
        }
    }
    Ok(rows)
}

/// A `row.json`: `None` when it does not exist.
///
/// # Errors
/// A file that is not a row.
pub fn read_record(path: &Path) -> Result<Option<(Json, Vec<Json>)>> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => {
            return Err(EvalError::Io {
                path: path.to_path_buf(),
                source,
            });
        }
    };
    let mut record: Json = serde_json::from_slice(&bytes).map_err(|e| EvalError::Input {
        path: path.to_path_buf(),
        message: format!("not a run's row: {e}"),
    })?;
    let obstacles = record["obstacles"].as_array().cloned().unwrap_or_default();
    let row = record["row"].take();
    if !row.is_object() {
        return Err(EvalError::Input {
            path: path.to_path_buf(),
            message: "not a run's row: no `row` object".into(),
        });
    }
    Ok(Some((row, obstacles)))
}

/// Writes `runs.csv`, `runs.jsonl` and `obstacles.csv` of the finished `runs` into `out`.
///
/// # Errors
/// A row that cannot be read, or a failed write.
pub fn write_tables(plan: &Plan, runs: &[&Run], out: &Path) -> Result<Vec<PathBuf>> {
    let rows = read_rows(out, runs)?;
    let axis_keys: Vec<String> = plan.sweep.axes.iter().map(|a| a.key.clone()).collect();
    write_row_tables(&axis_keys, &rows, out)
}

/// Writes the tables of `rows` (from [`read_rows`]) into `out`.
///
/// # Errors
/// A failed write.
pub fn write_row_tables(
    axis_keys: &[String],
    rows: &[(Json, Vec<Json>)],
    out: &Path,
) -> Result<Vec<PathBuf>> {
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
        &runs_csv,
        rows.iter().map(|(r, _)| r),
        &lead,
        &["status", "error"],
        &["wall_time_s"],
    )?;
    let runs_jsonl = out.join("runs.jsonl");
    write_bytes(&runs_jsonl, &jsonl)?;
    let obstacles_csv = out.join("obstacles.csv");
    let mut obstacle_lead = lead.clone();
    obstacle_lead.extend(
        ["obstacle", "name", "kind", "decides"]
            .iter()
            .map(|s| (*s).to_string()),
    );
    write_json_rows(
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
    crate::output::write_csv(path, &columns, records)
}
