//! The one pipeline every scenario job shares: load a scenario with its overrides, simulate the drive and the
//! sensors, integrate the scans into one map per model, compute the truth, judge the map ([`crate::judge`]) and
//! write the run's report (`report`). `oeg run` and `oeg suite` run it whole; `oeg sweep` and
//! `oeg preview` call its stages.

mod run;
mod simulate;

use std::path::PathBuf;

use oeg::RobotProfile;
use sim::scenario;
use sim::truth::{DEFAULT_SAMPLES_PER_SIDE, TruthRaster};
use sim::world::Actors;

use crate::error::{EvalError, Result};
use crate::judge::expectations::expectation_problem;
use crate::progress::Progress;
use crate::settings::SettingError;

pub use run::{RunReport, RunTiming, run_scenario};
pub use simulate::{Simulated, planner_source, simulate, simulate_and_map};

/// What to run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// The scenario file.
    pub scenario: PathBuf,
    /// Output folder; default `out/<scenario name>`.
    pub out_dir: Option<PathBuf>,
    /// Replaces the scenario's seed.
    pub seed: Option<u64>,
    /// `key=value` overrides (see `settings::overrides`).
    pub overrides: Vec<String>,
    /// Also maps the same sensor log as if the scenario's `[map]` said `preset = "<preset>"` (its own
    /// `[map.model]` keys still apply), and writes that report into `<out>/<preset>/` with a side-by-side
    /// comparison (`comparison.csv`, `decisions_comparison.png`).
    pub compare: Option<oeg::MapPreset>,
    /// The external planner of a closed-loop run, from the command line (`--planner-command`): it replaces
    /// the scenario's planner.
    pub planner_command: Option<Vec<String>>,
    /// Whether the scenario's own `[navigation] command` may run (`--allow-scenario-command`). A scenario
    /// file someone sent never runs a program without it.
    pub allow_scenario_command: bool,
    /// Write `recording.mcap` for Foxglove (`--mcap`, `docs/mcap.md`).
    pub mcap: bool,
    /// The files each figure is written as (`--svg` adds an SVG beside each PNG).
    pub figures: crate::figures::ImageFormats,
    /// A closed-loop run's planner in the caller's process (the Python package's `planner=`): it replaces
    /// the scenario's planner and any command.
    pub planner_callback: Option<crate::navigation::SharedPlanner>,
}

/// Loads a scenario with `--set` overrides and a seed override applied.
///
/// # Errors
/// A bad override, or a scenario that (after the overrides) is invalid.
pub fn load(options: &RunOptions) -> Result<scenario::LoadedScenario> {
    let path = &options.scenario;
    let text = oeg_files::read_text(path)?;
    let mut loaded = if options.overrides.is_empty() {
        scenario::load_str(path, &text)?
    } else {
        // The scenario is read once, with the overrides; only when that fails is the file read alone, so
        // that its own errors name its lines, and otherwise the override that breaks it is named.
        let with_overrides = toml::from_str::<toml::Table>(&text).ok().map(|doc| {
            crate::settings::resolve_with(&doc, &options.overrides, |doc| {
                scenario::load_doc(path, &text, doc).map_err(|e| SettingError::invalid(scenario_message(&e)))
            })
        });
        match with_overrides {
            Some(Ok(loaded)) => loaded,
            failed => {
                // A file that does not read on its own (TOML included) is named at its line first.
                scenario::load_str(path, &text)?;
                let message = match failed {
                    Some(Err(e)) => e.to_string(),
                    _ => "not valid TOML".into(),
                };
                return Err(EvalError::Input {
                    path: path.clone(),
                    message,
                });
            }
        }
    };
    if let Some(seed) = options.seed {
        loaded.scenario.seed = seed;
    }
    check_expectations(&loaded, &text)?;
    Ok(loaded)
}

/// Refuses `[expectations]` that name no metric or can never be met, at their place in the file's `text`.
///
/// # Errors
/// [`EvalError::At`] naming the file, line and column.
pub fn check_expectations(loaded: &scenario::LoadedScenario, text: &str) -> Result<()> {
    match expectation_problem(&loaded.scenario.expectations) {
        None => Ok(()),
        Some((name, message)) => {
            // The place in the file, when the file (not a `--set`) holds the expectation as it was checked.
            let in_file = toml::from_str::<toml::Table>(text)
                .ok()
                .and_then(|doc| doc.get("expectations")?.get(&name).cloned())
                .and_then(|v| v.try_into::<scenario::Expectation>().ok())
                .is_some_and(|e| Some(&e) == loaded.scenario.expectations.get(&name));
            let at = [
                scenario::KeySeg::Key("expectations"),
                scenario::KeySeg::Key(&name),
            ];
            Err(EvalError::At {
                path: loaded.source.path.clone(),
                position: in_file.then(|| scenario::position_of(text, &at)).flatten(),
                message: format!("expectations.{name}: {message}"),
            })
        }
    }
}

/// A scenario error's message without its `file:line:column` (which would point into a rewritten text).
pub fn scenario_message(e: &sim::SimError) -> String {
    match e {
        sim::SimError::Scenario { message, .. } => message.clone(),
        other => other.to_string(),
    }
}

/// The truth over the scenario's map window ([`scenario::LoadedScenario::window`]), people left out, from the
/// world at the end of the run, with [`DEFAULT_SAMPLES_PER_SIDE`] samples per cell side.
///
/// # Errors
/// `progress` cancelled.
pub fn truth_of(
    loaded: &scenario::LoadedScenario,
    world: &sim::World,
    progress: &Progress,
) -> Result<TruthRaster> {
    truth_sampled(loaded, world, DEFAULT_SAMPLES_PER_SIDE, progress)
}

/// [`truth_of`] with `samples_per_side` samples per cell side; `progress`'s cancellation is checked at every
/// band of the computation.
///
/// # Errors
/// `progress` cancelled.
pub fn truth_sampled(
    loaded: &scenario::LoadedScenario,
    world: &sim::World,
    samples_per_side: u32,
    progress: &Progress,
) -> Result<TruthRaster> {
    TruthRaster::compute(
        world,
        &loaded.window,
        profile_of(&loaded.scenario)?,
        Actors::Excluded,
        samples_per_side,
        &|| progress.check_cancelled().is_ok(),
    )
    .map_err(|_| EvalError::Cancelled)
}

/// The robot's decision profile of a scenario.
///
/// # Errors
/// A step or height that makes no sense.
pub fn profile_of(s: &scenario::Scenario) -> Result<RobotProfile> {
    let profile = s.robot.profile();
    profile.validate()?;
    Ok(profile)
}
