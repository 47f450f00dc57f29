//! `oeg sweep merge`: shard outputs back into one set of rows, checked to cover the plan exactly once.

use std::path::{Path, PathBuf};

use serde_json::Value as Json;

use super::rows::{read_plan, read_record, row_path, write_row_tables};
use crate::error::{EvalError, Result};
use crate::output::{Staged, write_bytes};

/// What a merge found.
#[derive(Debug, Clone, PartialEq)]
pub struct MergeSummary {
    /// Runs in the plan, all present once.
    pub num_runs: usize,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// The run ids of a `plan.json`, in plan order.
pub fn plan_ids(plan: &Json) -> Vec<String> {
    plan["runs"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|r| r["id"].as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default()
}

/// The axis keys of a `plan.json`.
pub fn plan_axes(plan: &Json) -> Vec<String> {
    plan["axes"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|x| x["key"].as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default()
}

/// Merges the finished runs of `dirs` (outputs of `oeg sweep run`, one per shard) into `out`: `plan.json`,
/// `runs.csv`, `runs.jsonl`, `obstacles.csv`.
///
/// # Errors
/// Folders of different plans, and a plan not covered exactly once: every missing and duplicated run is
/// named.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<MergeSummary> {
    let Some(first) = dirs.first() else {
        return Err(EvalError::CommandLine {
            message: "expected at least one folder to merge".into(),
        });
    };
    let plan = read_plan(first)?;
    let ids = plan_ids(&plan);
    for d in &dirs[1..] {
        if plan_ids(&read_plan(d)?) != ids {
            return Err(EvalError::Input {
                path: d.join("plan.json"),
                message: format!(
                    "holds another plan than {}: the shards of one study are run from the same sweep file with the \
                     same --set; merge only those",
                    first.join("plan.json").display()
                ),
            });
        }
    }
    let mut rows = Vec::with_capacity(ids.len());
    let (mut missing, mut duplicated) = (Vec::new(), Vec::new());
    for id in &ids {
        let mut found: Vec<(&PathBuf, (Json, Vec<Json>))> = Vec::new();
        for d in dirs {
            if let Some(record) = read_record(&row_path(d, id), id)? {
                found.push((d, record));
            }
        }
        match found.len() {
            0 => missing.push(id.clone()),
            1 => rows.extend(found.into_iter().map(|(_, r)| r)),
            _ => duplicated.push(format!(
                "{id} (in {})",
                found
                    .iter()
                    .map(|(d, _)| d.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        }
    }
    if !missing.is_empty() || !duplicated.is_empty() {
        let mut problems = Vec::new();
        if !missing.is_empty() {
            problems.push(format!(
                "{} missing run(s): {}",
                missing.len(),
                missing.join(", ")
            ));
        }
        if !duplicated.is_empty() {
            problems.push(format!(
                "{} duplicated run(s): {}",
                duplicated.len(),
                duplicated.join("; ")
            ));
        }
        return Err(EvalError::Input {
            path: first.clone(),
            message: format!(
                "the folders do not cover the plan of {} runs exactly once: {}",
                ids.len(),
                problems.join("; ")
            ),
        });
    }
    let inputs: Vec<&Path> = dirs.iter().map(PathBuf::as_path).collect();
    let staged = Staged::begin(out, &inputs)?;
    let write = || -> Result<Vec<PathBuf>> {
        let plan_path = staged.dir().join("plan.json");
        let mut bytes = serde_json::to_vec_pretty(&plan).unwrap_or_default();
        bytes.push(b'\n');
        write_bytes(&plan_path, &bytes)?;
        let mut files = vec![plan_path];
        let folder = super::folder::SweepFolder::fresh(staged.dir())?;
        files.extend(write_row_tables(&plan_axes(&plan), &rows, &folder)?);
        Ok(files)
    };
    let files = staged.explained(write())?;
    let files = files.iter().map(|f| staged.final_path(f)).collect();
    staged.commit()?;
    Ok(MergeSummary {
        num_runs: ids.len(),
        files,
    })
}
