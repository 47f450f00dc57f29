//! `oeg run`'s whole pipeline in stages: load, simulate, judge, write.

use std::path::{Path, PathBuf};
use std::time::Instant;

use oeg::{GridGeometry, Map};
use serde::Serialize;
use sim::scenario;
use sim::truth::TruthRaster;

use super::simulate::{Simulated, planner_source, simulate};
use super::{RunOptions, load, truth_of};
use crate::error::{EvalError, Result};
use crate::judge::expectations::FailedExpectation;
use crate::judge::metrics::Metrics;
use crate::judge::{Evaluation, Sensed, evaluate};
use crate::mapping::SimulatedTiming;
use crate::navigation::{NavigationLog, PlannerSource};
use crate::output::{Staged, create_dir, write_json};
use crate::progress::Progress;
use crate::recording::{DEFAULT_GRID_PERIOD_S, LogLevel, Recording};
use crate::report::page::{ModelRun, RunPage, write_run_page};
use crate::report::{write_comparison, write_report};

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

/// The recording's last parts: the truth once, a drive on the wheels' states and events, the planned paths
/// (every replan of a closed loop at its time, else the plan on the final map at the end) and the events of a
/// closed loop, as log messages.
fn finish_recording(
    mut recording: Recording,
    truth: &TruthRaster,
    evaluation: &Evaluation,
    sim: &Simulated,
    geometry: &GridGeometry,
) -> Result<Vec<u8>> {
    let (navigation, world) = (sim.navigation.as_ref(), sim.simulation.world());
    let end_s = world.time_s();
    recording.truth(truth)?;
    if let Some(record) = crate::judge::PhysicsRecord::of(world) {
        for sample in record.samples {
            recording.physics_state(sample)?;
        }
        for e in record.events {
            use sim::physics::PhysicsEventKind as K;
            let (level, what) = match &e.kind {
                K::Contact { with, link } => (LogLevel::Error, format!("contact: {link} touched {with}")),
                K::TipOver { roll_deg, pitch_deg } => (
                    LogLevel::Error,
                    format!("tip-over: roll {roll_deg:.1} deg, pitch {pitch_deg:.1} deg"),
                ),
                K::Stall { wheel_slip } => (
                    LogLevel::Warning,
                    format!("stall: no progress, wheel slip {wheel_slip:.2}"),
                ),
                K::GoalReached => (LogLevel::Info, "goal reached".to_string()),
            };
            let text = format!("{what} at ({:.2}, {:.2}) m", e.x_m, e.y_m);
            recording.event(e.time_s, level, &text)?;
        }
    }
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
                    | EventKind::GuardStop
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

/// Runs a scenario end to end and writes its report, in stages: [`load`], `simulate_run` (the drive, the
/// sensors and the maps), `judge_run` (the truth and the verdicts), `write_run` (the report, the recording,
/// the comparison, the timing and the page). The output folder is written all or nothing.
///
/// # Errors
/// A bad scenario or override, or a failed write. Failed expectations are not errors: they are in the report.
pub fn run_scenario(options: &RunOptions, progress: &Progress) -> Result<RunReport> {
    let total_start = Instant::now();
    let loaded = load(options)?;
    let out_dir = options
        .out_dir
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&loaded.scenario.name));
    // The output folder is checked (and its staging made) before the work: a folder this job may not write
    // costs nothing.
    let inputs = loaded.files();
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    let staged = Staged::begin(&out_dir, &inputs)?;
    // The work, its errors naming a file where it would be in the output folder, not in the staging that is
    // removed when the job fails.
    let work = || -> Result<_> {
        let run = simulate_run(&loaded, options, &staged, progress)?;
        let judged = judge_run(&loaded, run, progress)?;
        write_run(&loaded, options, staged.dir(), judged, total_start)
    };
    let mut report = staged.explained(work())?;
    report.files = report.files.iter().map(|f| staged.final_path(f)).collect();
    report.out_dir = out_dir;
    staged.commit()?;
    Ok(report)
}

/// A run after its simulation: the maps, and what else the drive left.
struct RunSimulated {
    /// The compared model's scenario, if `--compare` asked for one.
    compared: Option<(oeg::MapPreset, scenario::Scenario)>,
    /// Where an external planner's files go (in the staging).
    planner_dir: PathBuf,
    /// The simulation, the maps (the run's own first), the closed loop's log and truth.
    simulated: Simulated,
}

/// The simulation stage: the compared model resolved, the planner and the recording set up, then the drive
/// (scripted or closed loop) with its sensors feeding one map per model.
fn simulate_run(
    loaded: &scenario::LoadedScenario,
    options: &RunOptions,
    staged: &Staged,
    progress: &Progress,
) -> Result<RunSimulated> {
    let s = &loaded.scenario;
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
    let planner_dir = staged.dir().join("planner");
    let planner = planner_source(s, options, &planner_dir, &staged.final_path(&planner_dir))?;
    if matches!(planner, PlannerSource::External(_)) {
        create_dir(&planner_dir)?;
    }
    let recording = if options.mcap {
        Some(Recording::new(loaded.window, DEFAULT_GRID_PERIOD_S)?)
    } else {
        None
    };
    let simulated = simulate(loaded, &settings, &planner, recording, progress)?;
    Ok(RunSimulated {
        compared,
        planner_dir,
        simulated,
    })
}

/// A run after its judge: each model's map against the truth.
struct RunJudged {
    run: RunSimulated,
    /// The run's own map and its evaluation.
    map: Map,
    evaluation: Evaluation,
    /// The compared model's map and evaluation, with its preset and scenario.
    compared: Option<(oeg::MapPreset, scenario::Scenario, Map, Evaluation)>,
    /// The truth, and the seconds it took.
    truth: TruthRaster,
    truth_wall_time_s: f64,
}

/// The judging stage: the truth (a closed loop took it before its loop), then each model's map judged against
/// it with what the sensors could see; the robot decided with the run's own map.
fn judge_run(
    loaded: &scenario::LoadedScenario,
    mut run: RunSimulated,
    progress: &Progress,
) -> Result<RunJudged> {
    let s = &loaded.scenario;
    let sim = &mut run.simulated;
    let mut maps = std::mem::take(&mut sim.maps).into_iter();
    let map = maps.next().ok_or_else(|| EvalError::Input {
        path: loaded.source.path.clone(),
        message: "the simulation built no map".into(),
    })?;
    let (truth, truth_wall_time_s) = match sim.truth.take() {
        Some(t) => t,
        None => {
            let truth_start = Instant::now();
            let truth = truth_of(loaded, sim.simulation.world(), progress)?;
            (truth, truth_start.elapsed().as_secs_f64())
        }
    };
    let figures = sim.navigation.as_ref().map(|n| n.summary.figures());
    let sensed = Sensed {
        returns: Some(sim.simulation.obstacle_returns()),
        observability: Some(&sim.observability),
        navigation: figures.as_ref(),
        physics: crate::judge::PhysicsRecord::of(sim.simulation.world()),
    };
    let evaluation = evaluate(s, &map, &truth, &sensed)?;
    let compared = match (run.compared.take(), maps.next()) {
        (Some((preset, c)), Some(other)) => {
            let other_eval = evaluate(&c, &other, &truth, &sensed)?;
            Some((preset, c, other, other_eval))
        }
        _ => None,
    };
    Ok(RunJudged {
        run,
        map,
        evaluation,
        compared,
        truth,
        truth_wall_time_s,
    })
}

/// The writing stage, into the staging folder `stage`: each model's report, the closed loop's records, what
/// the sensors could see, the planner's files, the recording, the comparison, `timing.json`, and last the page
/// that links them all. The report's folder and files are the staging's, until the staging is committed.
fn write_run(
    loaded: &scenario::LoadedScenario,
    options: &RunOptions,
    stage: &Path,
    judged: RunJudged,
    total_start: Instant,
) -> Result<RunReport> {
    let s = &loaded.scenario;
    let RunJudged {
        run,
        map,
        evaluation,
        compared,
        truth,
        truth_wall_time_s,
    } = judged;
    let RunSimulated {
        planner_dir,
        simulated: mut sim,
        ..
    } = run;
    let navigation = sim.navigation.as_ref();
    let formats = options.figures;
    let overlay = navigation.map(crate::report::overlay_of);
    let mut files = write_report(stage, s, &map, &truth, &evaluation, overlay.as_ref(), formats)?;
    if let Some(log) = navigation {
        files.extend(crate::report::write_navigation(stage, s, &truth, log, formats)?);
    }
    files.extend(crate::report::write_physics(
        stage,
        loaded,
        sim.simulation.world(),
    )?);
    files.extend(crate::report::write_observability(
        stage,
        s,
        &sim.observability,
        &evaluation.verdicts,
        &sim.blind_band,
        formats,
    )?);
    if planner_dir.is_dir() {
        files.push(planner_dir);
    }
    let geometry = *map.geometry();
    if let Some(recording) = sim.recording.take() {
        let path = stage.join("recording.mcap");
        let bytes = finish_recording(recording, &truth, &evaluation, &sim, &geometry)?;
        crate::output::write_bytes(&path, &bytes)?;
        files.push(path);
    }
    if let Some((preset, c, other, other_eval)) = &compared {
        // The compared model maps the same scans; the robot decided with the run's own map.
        let dir = stage.join(preset.name());
        create_dir(&dir)?;
        files.extend(write_report(&dir, c, other, &truth, other_eval, None, formats)?);
        files.extend(write_comparison(
            stage,
            [(s, &evaluation), (c, other_eval)],
            &geometry,
            formats,
        )?);
    }
    let timing = run_timing(
        &sim.timing,
        &map,
        1 + usize::from(compared.is_some()),
        truth_wall_time_s,
        total_start,
        navigation,
    );
    let timing_path = stage.join("timing.json");
    write_json(&timing_path, &timing)?;
    files.push(timing_path);
    // The page that shows the run, last: it links every file above.
    let compared_run = compared.as_ref().map(|(preset, c, _, e)| (*preset, c, e));
    let (page, outcomes) = write_page(stage, options, s, &evaluation, compared_run, &sim, &files)?;
    files.push(page);
    let Evaluation {
        metrics,
        failed,
        obstacles,
        ..
    } = evaluation;
    Ok(RunReport {
        metrics,
        timing,
        failed,
        obstacles,
        compared: compared.map(|(preset, _, _, e)| (preset, e.metrics)),
        outcomes,
        out_dir: stage.to_path_buf(),
        files,
    })
}

/// Writes `report.html`, the page that shows the run's models (`compared`: the compared model's preset,
/// scenario and evaluation) and links `files`; returns it and what each model's map made the robot do.
fn write_page(
    stage: &Path,
    options: &RunOptions,
    s: &scenario::Scenario,
    evaluation: &Evaluation,
    compared: Option<(oeg::MapPreset, &scenario::Scenario, &Evaluation)>,
    sim: &Simulated,
    files: &[PathBuf],
) -> Result<(PathBuf, Vec<crate::judge::outcome::Outcome>)> {
    let mut models = vec![ModelRun {
        scenario: s,
        evaluation,
        dir: "",
    }];
    if let Some((preset, c, e)) = compared {
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
        navigation: sim.navigation.as_ref(),
        physics: crate::judge::PhysicsRecord::of(sim.simulation.world()),
        files: files
            .iter()
            .filter_map(|f| f.strip_prefix(stage).ok().map(Path::to_path_buf))
            .collect(),
    };
    let path = write_run_page(stage, &page)?;
    Ok((path, page.models.iter().map(ModelRun::outcome).collect()))
}

/// `timing.json`'s figures: the simulation's and the maps' wall times (`num_maps` maps of the same rays), the
/// truth's, the whole run's since `total_start`, and a closed loop's planner time.
fn run_timing(
    sim: &SimulatedTiming,
    map: &Map,
    num_maps: usize,
    truth_wall_time_s: f64,
    total_start: Instant,
    navigation: Option<&NavigationLog>,
) -> RunTiming {
    let num_rays = sim.num_rays as f64;
    let (simulation_s, map_s) = (sim.simulation_wall_time_s, sim.map_wall_time_s);
    RunTiming {
        simulation_wall_time_s: simulation_s,
        simulation_rays_per_s: num_rays / simulation_s.max(1e-9),
        map_wall_time_s: map_s,
        map_rays_per_s: map.totals().num_rays as f64 * num_maps as f64 / map_s.max(1e-9),
        truth_wall_time_s,
        total_wall_time_s: total_start.elapsed().as_secs_f64(),
        threads: rayon::current_num_threads() as u64,
        planner_wall_time_s: navigation.map(|n| n.planner_wall_time_s),
    }
}
