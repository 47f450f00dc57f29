//! `oeg sweep run`: the plan's runs in parallel, resumable and shardable.
//!
//! Layout of the output folder (the rows and tables are [`super::rows`]'s):
//! * `plan.json`: the whole plan (every run's id, axis values and seed);
//! * `runs/<id>/`: `scenario.toml` (the resolved scenario, a plain scenario file), `metrics.json`,
//!   `obstacles.csv`, and last `row.json`, written atomically: a run is finished once its `row.json` exists;
//! * `runs.csv`, `runs.jsonl`, `obstacles.csv`: every finished run of this shard in plan order, rebuilt from the
//!   `row.json` files at the end of each invocation.
//!
//! Killed at any moment and started again with the same command, it runs only what has no `row.json`, and ends
//! with the same rows. Runs that share a simulation (they differ only in the map's model, rule or resolution,
//! the planner or the expectations) are simulated once and mapped once per setting.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::Value as Json;

use super::folder::SweepFolder;
use super::plan::{Run, SweepPlan};
use super::rows::{Outcome, lead_columns, metric_columns, obstacle_rows, round3, row_path, write_tables};
use crate::error::{EvalError, Result};
use crate::progress::Progress;

/// How to run a plan.
#[derive(Debug, Clone)]
pub struct ExecuteOptions {
    /// The output folder.
    pub out_dir: PathBuf,
    /// `(i, n)`: run only shard `i` of `n` (1-based).
    pub shard: Option<(usize, usize)>,
    /// Simulations at once.
    pub jobs: usize,
    /// Simulate every run on its own, even where runs could share a simulation (to measure what sharing
    /// saves).
    pub simulate_each: bool,
}

/// What an invocation did.
#[derive(Debug, Clone, PartialEq)]
pub struct ExecuteSummary {
    /// Runs of this shard.
    pub num_selected: usize,
    /// Of those, finished by an earlier invocation.
    pub num_already_done: usize,
    /// Run now.
    pub num_run: usize,
    /// Simulations run now.
    pub num_simulations: usize,
    /// Rows with status `error`.
    pub num_errors: usize,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// A shard that cannot be used: `--shard` or a cluster's variable, named in the message with its value.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct ShardError {
    /// What is wrong, with the option or variable at fault and what was expected.
    pub message: String,
}

fn shard_error(message: impl Into<String>) -> ShardError {
    ShardError {
        message: message.into(),
    }
}

/// Parses `--shard i/n` (1-based).
///
/// # Errors
/// A message saying what was expected.
pub fn parse_shard(text: &str) -> std::result::Result<(usize, usize), ShardError> {
    let parsed = text
        .split_once('/')
        .and_then(|(i, n)| Some((i.trim().parse::<usize>().ok()?, n.trim().parse::<usize>().ok()?)));
    match parsed {
        Some((i, n)) if n >= 1 && (1..=n).contains(&i) => Ok((i, n)),
        Some((i, n)) => Err(shard_error(format!(
            "shard {i} of {n}: expected i/n with 1 <= i <= n (shards count from 1)"
        ))),
        None => Err(shard_error(format!("expected i/n, such as 2/5, got `{text}`"))),
    }
}

/// The shard from a cluster's environment when `--shard` is absent: a Slurm job array
/// (`SLURM_ARRAY_TASK_ID` within `SLURM_ARRAY_TASK_MIN` .. `SLURM_ARRAY_TASK_MAX`), or a Kubernetes Indexed
/// Job (`JOB_COMPLETION_INDEX`, from 0, with `shards` given by `--shards`).
///
/// # Errors
/// A variable that is not a number, or a task outside its array's bounds.
pub fn shard_from_env(
    get: impl Fn(&str) -> Option<String>,
    shards: Option<usize>,
) -> std::result::Result<Option<(usize, usize)>, ShardError> {
    let number = |name: &str| -> std::result::Result<Option<usize>, ShardError> {
        get(name)
            .map(|v| {
                v.trim()
                    .parse::<usize>()
                    .map_err(|_| shard_error(format!("{name}={v}: expected a whole number")))
            })
            .transpose()
    };
    if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
        let (Some(min), Some(max)) = (number("SLURM_ARRAY_TASK_MIN")?, number("SLURM_ARRAY_TASK_MAX")?)
        else {
            return Err(shard_error(
                "SLURM_ARRAY_TASK_ID is set without SLURM_ARRAY_TASK_MIN and _MAX",
            ));
        };
        if !(min..=max).contains(&id) {
            return Err(shard_error(format!(
                "SLURM_ARRAY_TASK_ID={id} lies outside the array {min}-{max}"
            )));
        }
        return Ok(Some((id - min + 1, max - min + 1)));
    }
    if let Some(index) = number("JOB_COMPLETION_INDEX")? {
        let Some(n) = shards else {
            return Err(shard_error(
                "JOB_COMPLETION_INDEX is set: give the job's completions as --shards N",
            ));
        };
        if index >= n {
            return Err(shard_error(format!(
                "JOB_COMPLETION_INDEX={index} with --shards {n}: expected an index below {n}"
            )));
        }
        return Ok(Some((index + 1, n)));
    }
    Ok(None)
}

/// Runs the plan (or one shard of it) into `options.out_dir`.
///
/// # Errors
/// An output folder holding another plan, a thread pool that cannot start, or a failed write. A run whose
/// simulation or map fails is a row with status `error`, not an error.
pub fn run(plan: &SweepPlan, options: &ExecuteOptions, progress: &Progress) -> Result<ExecuteSummary> {
    use rayon::prelude::*;
    let out = &options.out_dir;
    let folder = SweepFolder::claim(out)?;
    folder.create_dir(&out.join("runs"))?;
    check_same_plan(plan, out)?;
    let plan_path = out.join("plan.json");
    folder.write_json(&plan_path, &plan.listing())?;
    let selected: Vec<&Run> = match options.shard {
        Some((i, n)) => plan.shard(i, n),
        None => plan.runs.iter().collect(),
    };
    // Every finished row is checked before any work: one that is not its run's is an error now, not after
    // the other runs.
    let mut pending: Vec<&Run> = Vec::new();
    for r in &selected {
        let row = row_path(out, &r.id);
        folder.check(&row)?;
        if super::rows::read_record(&row, &r.id)?.is_none() {
            pending.push(r);
        }
    }
    // A pending run's folder holds no finished row: whatever a killed invocation left there goes.
    for r in &pending {
        folder.remove_dir(&out.join("runs").join(&r.id))?;
    }
    // Groups in plan order; each is one simulation. Found through an index, not a scan of the groups: a plan
    // of 100,000 runs would otherwise take quadratic time here.
    let mut groups: Vec<(String, Vec<&Run>)> = Vec::new();
    let mut index: std::collections::BTreeMap<&str, usize> = std::collections::BTreeMap::new();
    for r in &pending {
        let key = if options.simulate_each { &r.id } else { &r.group };
        match index.get(key.as_str()) {
            Some(&k) => groups[k].1.push(r),
            None => {
                index.insert(key, groups.len());
                groups.push((key.clone(), vec![r]));
            }
        }
    }
    progress.set_length(pending.len() as u64);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.jobs.max(1))
        .build()
        .map_err(|e| EvalError::CommandLine {
            message: format!("cannot start {} threads for --jobs: {e}", options.jobs),
        })?;
    let errors: Vec<usize> = pool.install(|| {
        groups
            .par_iter()
            .with_max_len(1)
            .map(|(_, runs)| run_group(runs, &folder, progress))
            .collect::<Result<Vec<usize>>>()
    })?;
    progress.finish();
    let files = write_tables(plan, &selected, &folder)?;
    Ok(ExecuteSummary {
        num_selected: selected.len(),
        num_already_done: selected.len() - pending.len(),
        num_run: pending.len(),
        num_simulations: groups.len(),
        num_errors: errors.iter().sum(),
        files: std::iter::once(plan_path).chain(files).collect(),
    })
}

/// Refuses a folder that holds another plan's runs: its rows would be mixed with this plan's.
fn check_same_plan(plan: &SweepPlan, out: &Path) -> Result<()> {
    let path = out.join("plan.json");
    if !path.exists() {
        return Ok(());
    }
    let old = super::rows::read_plan(out)?;
    if super::merge::plan_ids(&old) != super::merge::plan_ids(&plan.listing()) {
        return Err(EvalError::Input {
            path,
            message:
                "this folder holds the runs of another plan (the sweep file changed); give another --out, or \
                      remove the folder to start again"
                    .into(),
        });
    }
    Ok(())
}

/// One simulation, mapped once per run; writes each run's files, `row.json` last, and counts each run on
/// `progress` as its row is written. Returns the error rows.
fn run_group(runs: &[&Run], folder: &SweepFolder, progress: &Progress) -> Result<usize> {
    let out = folder.root();
    let start = Instant::now();
    let loaded: Vec<std::result::Result<sim::LoadedScenario, String>> =
        runs.iter().map(|r| r.load().map_err(|e| e.to_string())).collect();
    let first = loaded.iter().find_map(|l| l.as_ref().ok());
    let results: Vec<std::result::Result<Outcome, String>> = match first.ok_or_else(|| {
        loaded
            .iter()
            .find_map(|l| l.as_ref().err().cloned())
            .unwrap_or_default()
    }) {
        Ok(first) => simulate_group(first, &loaded).unwrap_or_else(|e| vec![Err(e); runs.len()]),
        Err(e) => vec![Err(e); runs.len()],
    };
    let shared_s = start.elapsed().as_secs_f64();
    let mut num_errors = 0;
    for (run, result) in runs.iter().zip(results) {
        let dir = out.join("runs").join(&run.id);
        folder.create_dir(&dir)?;
        folder.write_bytes(&dir.join("scenario.toml"), run.scenario_text().as_bytes())?;
        let mut row = lead_columns(run);
        let obstacles = match result {
            Ok(o) => {
                folder.write_json(&dir.join("metrics.json"), &o.evaluation.metrics)?;
                folder.write_table(&dir.join("obstacles.csv"), &o.evaluation.obstacles)?;
                row.insert("status".into(), Json::from("ok"));
                row.insert("error".into(), Json::from(""));
                metric_columns(&mut row, &o);
                obstacle_rows(run, &o)
            }
            Err(message) => {
                num_errors += 1;
                row.insert("status".into(), Json::from("error"));
                row.insert("error".into(), Json::from(message));
                Vec::new()
            }
        };
        // The shared simulation's time split over its runs: the column adds up to the study's time.
        row.insert(
            "wall_time_s".into(),
            Json::from(round3(shared_s / runs.len() as f64)),
        );
        let record = serde_json::json!({ "row": row, "obstacles": obstacles });
        folder.write_json(&row_path(out, &run.id), &record)?;
        progress.inc(1);
    }
    Ok(num_errors)
}

/// Simulates the group's first valid scenario and judges one map per run.
fn simulate_group(
    first: &sim::LoadedScenario,
    loaded: &[std::result::Result<sim::LoadedScenario, String>],
) -> std::result::Result<Vec<std::result::Result<Outcome, String>>, String> {
    let settings: Vec<&sim::scenario::MapSettings> = loaded
        .iter()
        .map(|l| l.as_ref().map_or(&first.scenario.map, |l| &l.scenario.map))
        .collect();
    if first
        .scenario
        .navigation
        .as_ref()
        .is_some_and(|n| n.planner != sim::scenario::PlannerKind::Astar)
    {
        return Err(
            "an external planner runs in `oeg run` only (with --planner-command); a sweep plans with \
                    the built-in A*"
                .into(),
        );
    }
    let simulated = crate::pipeline::simulate(
        first,
        &settings,
        &crate::navigation::PlannerSource::Builtin,
        None,
        &Progress::hidden(),
    )
    .map_err(|e| e.to_string())?;
    let (simulation, maps) = (&simulated.simulation, &simulated.maps);
    let figures = simulated.navigation.as_ref().map(|n| n.summary.figures());
    // One truth per window (runs that differ only in the model share it); a closed-loop run's was taken
    // before its loop.
    let mut truths: Vec<sim::truth::TruthRaster> = Vec::new();
    if let Some((truth, _)) = &simulated.truth {
        truths.push(truth.clone());
    }
    let outcomes = loaded
        .iter()
        .zip(maps)
        .map(|(l, map)| {
            let l = l.as_ref().map_err(Clone::clone)?;
            let s = &l.scenario;
            let k = match truths.iter().position(|t| t.window == l.window) {
                Some(k) => k,
                None => {
                    let truth = crate::pipeline::truth_of(l, simulation.world(), &Progress::hidden())
                        .map_err(|e| e.to_string())?;
                    truths.push(truth);
                    truths.len() - 1
                }
            };
            let truth = &truths[k];
            let evaluation = crate::judge::evaluate(
                s,
                map,
                truth,
                &crate::judge::Sensed {
                    returns: Some(simulation.obstacle_returns()),
                    observability: Some(&simulated.observability),
                    navigation: figures.as_ref(),
                    physics: crate::judge::PhysicsRecord::of(simulation.world()),
                },
            )
            .map_err(|e| e.to_string())?;
            Ok(Outcome {
                evaluation,
                max_step_m: s.robot.max_step_m,
                height_m: s.robot.height_m,
            })
        })
        .collect::<Vec<_>>();
    Ok(outcomes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn progress_counts_each_run_as_its_row_is_written_shared_simulations_included() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let sweep = crate::jobs::sweep::Sweep::load(&root.join("sweeps/smoke.toml")).expect("smoke");
        let plan = SweepPlan::new(sweep).expect("plan");
        let options = ExecuteOptions {
            out_dir: crate::test_support::scratch_dir("sweep", "progress").join("out"),
            shard: None,
            jobs: 1,
            simulate_each: false,
        };
        let progress = Progress::hidden();
        let summary = run(&plan, &options, &progress).expect("run");
        // Groups of two runs share each simulation; the counter still moves one run at a time.
        assert!(summary.num_simulations < summary.num_run, "{summary:?}");
        let steps = progress.steps.lock().expect("steps").clone();
        let expected: Vec<u64> = (1..=summary.num_run as u64).collect();
        assert_eq!(steps, expected);
        let _ = std::fs::remove_dir_all(&options.out_dir);
    }

    #[test]
    fn shards_are_parsed_from_one() {
        assert_eq!(parse_shard("2/5"), Ok((2, 5)));
        assert_eq!(parse_shard("1/1"), Ok((1, 1)));
        for bad in ["0/3", "4/3", "1/0", "x/3", "3"] {
            let e = parse_shard(bad).expect_err(bad);
            assert!(e.message.contains("expected"), "{bad}: {e}");
        }
    }

    #[test]
    fn cluster_variables_give_the_shard() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |k: &str| pairs.iter().find(|(n, _)| *n == k).map(|(_, v)| (*v).to_string())
        };
        const SLURM: [(&str, &str); 3] = [
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_MIN", "4"),
            ("SLURM_ARRAY_TASK_MAX", "6"),
        ];
        assert_eq!(shard_from_env(env(&SLURM), None), Ok(Some((2, 3))));
        assert_eq!(
            shard_from_env(env(&[("JOB_COMPLETION_INDEX", "0")]), Some(3)),
            Ok(Some((1, 3)))
        );
        assert!(shard_from_env(env(&[("JOB_COMPLETION_INDEX", "3")]), Some(3)).is_err());
        assert!(shard_from_env(env(&[("JOB_COMPLETION_INDEX", "0")]), None).is_err());
        assert!(shard_from_env(env(&[("SLURM_ARRAY_TASK_ID", "1")]), None).is_err());
        assert_eq!(shard_from_env(env(&[]), None), Ok(None));
    }
}
