//! The one pipeline every scenario job shares: load a scenario with its overrides, simulate the drive and the
//! sensors, integrate the scans into one map per model, compute the truth, judge the map ([`crate::judge`]) and
//! write the run's report ([`crate::report`]). `oeg run` and `oeg suite` run it whole; `oeg sweep` and
//! `oeg preview` call its stages.

use std::path::{Path, PathBuf};
use std::time::Instant;

use oeg::{GridGeometry, Map, RobotProfile};
use serde::Serialize;
use sim::truth::{DEFAULT_SAMPLES_PER_SIDE, TruthRaster};
use sim::world::Actors;
use sim::{Simulation, scenario};

use crate::error::{EvalError, Result};
use crate::judge::metrics::{self, FailedExpectation, Metrics};
use crate::judge::{Evaluation, Sensed, evaluate};
use crate::mapping::{Mapping, SimulatedTiming};
use crate::navigation::external::ExternalPlanner;
use crate::navigation::{NavigationInputs, NavigationLog, PlannerSource, navigate};
use crate::output::{Staged, create_dir, write_json};
use crate::progress::Progress;
use crate::recording::{DEFAULT_GRID_PERIOD_S, LogLevel, Recording};
use crate::report::page::{ModelRun, RunPage, write_run_page};
use crate::report::{write_comparison, write_report};
use crate::settings::SettingError;

/// What to run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// The scenario file.
    pub scenario: PathBuf,
    /// Output folder; default `out/<scenario name>`.
    pub out_dir: Option<PathBuf>,
    /// Replaces the scenario's seed.
    pub seed: Option<u64>,
    /// `key=value` overrides (see [`crate::settings::overrides`]).
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

/// `timing.json`: wall times, kept apart from the metrics because they vary from run to run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunTiming {
    /// Simulating the drive and the sensors, seconds.
    pub simulation_wall_time_s: f64,
    /// Simulated rays per second of simulation time.
    pub simulation_rays_per_s: f64,
    /// Integrating the scans into the map, seconds.
    pub map_wall_time_s: f64,
    /// Rays integrated per second of map time.
    pub map_rays_per_s: f64,
    /// Computing the truth raster, seconds.
    pub truth_wall_time_s: f64,
    /// The whole run, seconds.
    pub total_wall_time_s: f64,
    /// Threads available to the parallel parts (ray casts, truth).
    pub threads: u64,
    /// A closed-loop run's time in its planner, seconds (absent without `[navigation]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub planner_wall_time_s: Option<f64>,
}

/// What a run produced.
#[derive(Debug, Clone)]
pub struct RunReport {
    /// The metrics written.
    pub metrics: Metrics,
    /// The timing written.
    pub timing: RunTiming,
    /// Expectations that failed.
    pub failed: Vec<FailedExpectation>,
    /// Per-obstacle decisions (also in `obstacles.csv`).
    pub obstacles: Vec<crate::judge::obstacles::ObstacleDecision>,
    /// The compared preset's metrics, if [`RunOptions::compare`] asked for one.
    pub compared: Option<(oeg::MapPreset, Metrics)>,
    /// What each model's map made the robot do, and its regression bounds: the run's own model first.
    pub outcomes: Vec<crate::judge::outcome::Outcome>,
    /// The output folder.
    pub out_dir: PathBuf,
    /// Every file written.
    pub files: Vec<PathBuf>,
}

/// Loads a scenario with `--set` overrides and a seed override applied.
///
/// # Errors
/// A bad override, or a scenario that (after the overrides) is invalid.
pub fn load(options: &RunOptions) -> Result<scenario::LoadedScenario> {
    let path = &options.scenario;
    let text = oeg::read_text(path)?;
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
    match metrics::expectation_problem(&loaded.scenario.expectations) {
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

/// Simulates `loaded` once and integrates every scan, at the estimated pose, into one map per entry of
/// `maps` (see [`Mapping::new`]). The simulation is returned at the end of its drive.
///
/// # Errors
/// A world or map that cannot be built, or a scan the map rejects.
pub fn simulate_and_map(
    loaded: &scenario::LoadedScenario,
    maps: &[&scenario::MapSettings],
    recording: Option<Recording>,
    progress: &Progress,
) -> Result<Mapping> {
    let s = &loaded.scenario;
    let mut mapping = Mapping::new(loaded, maps)?;
    start_recording(&mut mapping, loaded, maps, recording);
    progress.set_length(mapping.simulation.num_scans_total());
    mapping.feed_until(s.duration_s, progress)?;
    progress.finish();
    // The truth is taken at the end of the run: a person who left must have left the map too.
    mapping.simulation.world_mut().advance_to(s.duration_s);
    Ok(mapping)
}

/// A simulated run: the simulation at its end, the maps, the wall times, and for a closed-loop run its truth
/// (taken before the loop, on the first map's grid) and its log.
#[derive(Debug)]
pub struct Simulated {
    /// The simulation at the end of the run.
    pub simulation: Simulation,
    /// One map per entry of the map settings.
    pub maps: Vec<Map>,
    /// Wall times.
    pub timing: SimulatedTiming,
    /// A closed-loop run's truth and the seconds it took.
    pub truth: Option<(TruthRaster, f64)>,
    /// A closed-loop run's log.
    pub navigation: Option<NavigationLog>,
    /// What the sensors' rays could have told, over the map region on the first map's grid.
    pub observability: sim::observability::Observability,
    /// The sensors' blind band at the start.
    pub blind_band: Vec<sim::observability::BlindBandRow>,
    /// The recording, when the run records one: the poses, the scans and the first map's layers so far.
    pub recording: Option<Recording>,
}

/// Hands `recording` to the mapping, to draw the first map's decisions for the scenario's robot.
fn start_recording(
    mapping: &mut Mapping,
    loaded: &scenario::LoadedScenario,
    maps: &[&scenario::MapSettings],
    recording: Option<Recording>,
) {
    if let Some(r) = recording {
        let rule = maps
            .first()
            .map_or(loaded.scenario.map.traversability, |m| m.traversability);
        mapping.record(r, loaded.scenario.robot.profile(), rule);
    }
}

/// Simulates `loaded` and maps it into one map per entry of `maps`: the scripted drive, or with
/// `[navigation]` the drive and then the closed loop, planning with `planner` on the first map.
///
/// # Errors
/// A world or map that cannot be built, a scan the map rejects, a planner's map file that cannot be
/// written.
pub fn simulate(
    loaded: &scenario::LoadedScenario,
    maps: &[&scenario::MapSettings],
    planner: &PlannerSource,
    recording: Option<Recording>,
    progress: &Progress,
) -> Result<Simulated> {
    let s = &loaded.scenario;
    let Some(settings) = &s.navigation else {
        let mut mapping = simulate_and_map(loaded, maps, recording, progress)?;
        let recording = mapping.take_recording()?;
        let timing = mapping.timing();
        return Ok(Simulated {
            recording,
            simulation: mapping.simulation,
            maps: mapping.maps,
            timing,
            truth: None,
            navigation: None,
            observability: mapping.observability,
            blind_band: mapping.blind_band,
        });
    };
    let mut mapping = Mapping::new(loaded, maps)?;
    start_recording(&mut mapping, loaded, maps, recording);
    progress.set_length(mapping.simulation.num_scans_total());
    let truth_start = Instant::now();
    // The static world's truth (people and the robot left out) is the same at any time: it is taken before
    // the loop, so the judge can watch the robot's footprint against it at every step.
    let truth = truth_of(loaded, mapping.simulation.world(), progress)?;
    let truth_s = truth_start.elapsed().as_secs_f64();
    let inputs = NavigationInputs {
        scenario: s,
        settings,
        footprint: loaded.robot.footprint(),
        truth: &truth,
        planner,
    };
    let log = navigate(&mut mapping, &inputs, progress)?;
    progress.finish();
    let recording = mapping.take_recording()?;
    let timing = mapping.timing();
    Ok(Simulated {
        recording,
        simulation: mapping.simulation,
        maps: mapping.maps,
        timing,
        truth: Some((truth, truth_s)),
        navigation: Some(log),
        observability: mapping.observability,
        blind_band: mapping.blind_band,
    })
}

/// The planner a closed-loop run uses: `--planner-command`, else the scenario's (its command only when
/// allowed), exchanging files in `dir`, which messages name as `shown_dir` (where it is once the run is in place).
///
/// # Errors
/// [`EvalError::Input`] naming the scenario when it asks for an external planner without a command, or for
/// its own command without `--allow-scenario-command`.
pub fn planner_source(
    s: &scenario::Scenario,
    options: &RunOptions,
    dir: &Path,
    shown_dir: &Path,
) -> Result<PlannerSource> {
    let Some(n) = &s.navigation else {
        return Ok(PlannerSource::Builtin);
    };
    let external = |command: Vec<String>| {
        PlannerSource::External(ExternalPlanner {
            command,
            timeout: std::time::Duration::from_secs_f64(n.planner_timeout_s),
            dir: dir.to_path_buf(),
            shown_dir: shown_dir.to_path_buf(),
        })
    };
    if let Some(planner) = &options.planner_callback {
        return Ok(PlannerSource::Callback(planner.clone()));
    }
    if let Some(command) = &options.planner_command {
        return Ok(external(command.clone()));
    }
    match (&n.planner, &n.command) {
        (scenario::PlannerKind::Astar, _) => Ok(PlannerSource::Builtin),
        (scenario::PlannerKind::External, None) => Err(EvalError::Input {
            path: options.scenario.clone(),
            message:
                "navigation.planner = \"external\" needs a command: give one with --planner-command, or \
                      [navigation] command with --allow-scenario-command"
                    .into(),
        }),
        (scenario::PlannerKind::External, Some(command)) if !options.allow_scenario_command => {
            Err(EvalError::Input {
                path: options.scenario.clone(),
                message: format!(
                    "the scenario asks to run the command {} as its planner; a scenario file never runs a program \
                 unless allowed: pass --allow-scenario-command to run it, or give your own with --planner-command",
                    crate::navigation::external::shown_command(command)
                ),
            })
        }
        (scenario::PlannerKind::External, Some(command)) => Ok(external(command.clone())),
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

/// The recording's last parts: the truth once, the planned paths (every replan of a closed loop at its time,
/// else the plan on the final map at the end) and the events of a closed loop, as log messages.
fn finish_recording(
    mut recording: Recording,
    truth: &TruthRaster,
    evaluation: &Evaluation,
    navigation: Option<&NavigationLog>,
    geometry: &GridGeometry,
    end_s: f64,
) -> Result<Vec<u8>> {
    recording.truth(truth)?;
    match navigation {
        Some(log) => {
            for p in &log.plans {
                recording.path(p.time_s, &p.points)?;
            }
            for e in &log.summary.events {
                use crate::navigation::record::EventKind;
                let level = match e.kind {
                    EventKind::Contact | EventKind::Stuck | EventKind::PlannerFailed => LogLevel::Error,
                    EventKind::NoPath
                    | EventKind::Recovery
                    | EventKind::ClosestApproach
                    | EventKind::TimeLimit => LogLevel::Warning,
                    EventKind::Reached => LogLevel::Info,
                };
                let place = format!(
                    "{} at ({:.2}, {:.2}) m: {}",
                    e.kind.name(),
                    e.x_m,
                    e.y_m,
                    e.message
                );
                recording.event(e.time_s, level, &place)?;
            }
        }
        None => {
            if let Some(p) = &evaluation.plan.map_plan {
                recording.path(end_s, &crate::judge::plan_check::polyline(p, geometry))?;
            }
        }
    }
    Ok(recording.finish()?)
}

/// Runs a scenario end to end and writes its report.
///
/// # Errors
/// A bad scenario or override, or a failed write. Failed expectations are not errors: they are in the report.
pub fn run_scenario(options: &RunOptions, progress: &Progress) -> Result<RunReport> {
    let total_start = Instant::now();
    let loaded = load(options)?;
    let s = &loaded.scenario;
    let out_dir = options
        .out_dir
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&s.name));
    // The output folder is checked (and its staging made) before the work: a folder this job may not write
    // costs nothing.
    let inputs = loaded.files();
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    let staged = Staged::begin(&out_dir, &inputs)?;
    // The work, its errors naming a file where it would be in the output folder, not in the staging that is
    // removed when the job fails.
    let work = || -> Result<_> {
        // The compared model: the scenario as if its `[map]` said `preset = "<preset>"` (its own `[map.model]`
        // keys, such as height thresholding, still apply), resolved from the document already read.
        let compared: Option<(oeg::MapPreset, scenario::Scenario)> = match options.compare {
            None => None,
            Some(preset) => Some((preset, loaded.with_preset(preset)?.scenario)),
        };
        let mut settings = vec![&s.map];
        if let Some((_, c)) = &compared {
            settings.push(&c.map);
        }
        let stage = staged.dir();
        let planner_dir = stage.join("planner");
        let planner = planner_source(s, options, &planner_dir, &staged.final_path(&planner_dir))?;
        if matches!(planner, PlannerSource::External(_)) {
            create_dir(&planner_dir)?;
        }
        let recording = if options.mcap {
            Some(Recording::new(loaded.window, DEFAULT_GRID_PERIOD_S)?)
        } else {
            None
        };
        let Simulated {
            simulation,
            maps,
            timing: sim_timing,
            truth,
            navigation,
            observability,
            blind_band,
            recording,
        } = simulate(&loaded, &settings, &planner, recording, progress)?;
        let mut maps = maps.into_iter();
        let map = maps.next().ok_or_else(|| EvalError::Input {
            path: options.scenario.clone(),
            message: "the simulation built no map".into(),
        })?;
        let geometry = *map.geometry();
        let (truth, truth_wall_time_s) = match truth {
            Some(t) => t,
            None => {
                let truth_start = Instant::now();
                let truth = truth_of(&loaded, simulation.world(), progress)?;
                (truth, truth_start.elapsed().as_secs_f64())
            }
        };
        let figures = navigation.as_ref().map(|n| n.summary.figures());
        let sensed = Sensed {
            returns: Some(simulation.obstacle_returns()),
            observability: Some(&observability),
            navigation: figures.as_ref(),
        };
        let evaluation = evaluate(s, &map, &truth, &sensed)?;
        let overlay = navigation.as_ref().map(crate::report::overlay_of);

        let formats = options.figures;
        let mut files = write_report(stage, s, &map, &truth, &evaluation, overlay.as_ref(), formats)?;
        if let Some(log) = &navigation {
            files.extend(crate::report::write_navigation(stage, s, &truth, log, formats)?);
        }
        files.extend(crate::report::write_observability(
            stage,
            s,
            &observability,
            &evaluation.verdicts,
            &blind_band,
            formats,
        )?);
        if planner_dir.is_dir() {
            files.push(planner_dir.clone());
        }
        if let Some(recording) = recording {
            let path = stage.join("recording.mcap");
            let end_s = simulation.world().time_s();
            let bytes = finish_recording(
                recording,
                &truth,
                &evaluation,
                navigation.as_ref(),
                &geometry,
                end_s,
            )?;
            crate::output::write_bytes(&path, &bytes)?;
            files.push(path);
        }
        let mut compared_eval = None;
        if let (Some((preset, c)), Some(other)) = (&compared, maps.next()) {
            // The compared model maps the same scans; the robot decided with the run's own map.
            let other_eval = evaluate(c, &other, &truth, &sensed)?;
            let dir = stage.join(preset.name());
            create_dir(&dir)?;
            files.extend(write_report(&dir, c, &other, &truth, &other_eval, None, formats)?);
            files.extend(write_comparison(
                stage,
                [(s, &evaluation), (c, &other_eval)],
                &geometry,
                formats,
            )?);
            compared_eval = Some((*preset, c, other_eval));
        }
        let num_rays = sim_timing.num_rays as f64;
        let (simulation_s, map_s) = (sim_timing.simulation_wall_time_s, sim_timing.map_wall_time_s);
        let timing = RunTiming {
            simulation_wall_time_s: simulation_s,
            simulation_rays_per_s: num_rays / simulation_s.max(1e-9),
            map_wall_time_s: map_s,
            map_rays_per_s: map.totals().num_rays as f64 * settings.len() as f64 / map_s.max(1e-9),
            truth_wall_time_s,
            total_wall_time_s: total_start.elapsed().as_secs_f64(),
            threads: rayon::current_num_threads() as u64,
            planner_wall_time_s: navigation.as_ref().map(|n| n.planner_wall_time_s),
        };
        let timing_path = stage.join("timing.json");
        write_json(&timing_path, &timing)?;
        files.push(timing_path);
        // The page that shows the run, last: it links every file above.
        let mut models = vec![ModelRun {
            scenario: s,
            evaluation: &evaluation,
            dir: "",
        }];
        if let Some((preset, c, e)) = &compared_eval {
            models.push(ModelRun {
                scenario: c,
                evaluation: e,
                dir: preset.name(),
            });
        }
        let page = RunPage {
            scenario_file: &options.scenario,
            models,
            overrides: &options.overrides,
            planner_command: options.planner_command.as_deref(),
            navigation: navigation.as_ref(),
            files: files
                .iter()
                .filter_map(|f| f.strip_prefix(stage).ok().map(Path::to_path_buf))
                .collect(),
        };
        files.push(write_run_page(stage, &page)?);
        let outcomes: Vec<_> = page.models.iter().map(ModelRun::outcome).collect();
        let Evaluation {
            metrics,
            failed,
            obstacles,
            ..
        } = evaluation;
        Ok((
            files,
            metrics,
            failed,
            obstacles,
            compared_eval.map(|(preset, _, e)| (preset, e.metrics)),
            outcomes,
            timing,
        ))
    };
    let (files, metrics, failed, obstacles, compared, outcomes, timing) = staged.explained(work())?;
    let files = files.iter().map(|f| staged.final_path(f)).collect();
    staged.commit()?;
    Ok(RunReport {
        metrics,
        timing,
        failed,
        obstacles,
        compared,
        outcomes,
        out_dir,
        files,
    })
}
