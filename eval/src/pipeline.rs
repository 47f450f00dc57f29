//! The one pipeline every scenario job shares: load a scenario with its overrides, simulate the drive and the
//! sensors, integrate the scans into one map per model, compute the truth, judge the map ([`crate::judge`]) and
//! write the run's report ([`crate::report`]). `oeg run` and `oeg suite` run it whole; `oeg sweep` and
//! `oeg preview` call its stages.

use std::path::{Path, PathBuf};
use std::time::Instant;

use oeg::{GridGeometry, Map, MapConfig, RobotProfile};
use serde::Serialize;
use sim::sensors::PoseSource;
use sim::truth::{DEFAULT_SAMPLES_PER_SIDE, TruthRaster};
use sim::world::Actors;
use sim::{Simulation, scenario};

use crate::error::{EvalError, Result};
use crate::judge::metrics::{self, FailedExpectation, Metrics};
use crate::judge::{Evaluation, evaluate};
use crate::output::{Staged, create_dir, write_json};
use crate::progress::Progress;
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
    // The file alone first, so that its own errors name its lines; then the overrides, each named if it breaks
    // the scenario.
    let mut loaded = scenario::load_str(path, &text)?;
    if !options.overrides.is_empty() {
        let doc: toml::Table = toml::from_str(&text).map_err(|e| EvalError::Input {
            path: path.clone(),
            message: format!("not valid TOML: {}", e.message()),
        })?;
        loaded = crate::settings::resolve_with(&doc, &options.overrides, |doc| {
            scenario::load_doc(path, &text, doc).map_err(|e| SettingError::invalid(scenario_message(&e)))
        })
        .map_err(|e| EvalError::Input {
            path: path.clone(),
            message: e.to_string(),
        })?;
    }
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

/// The scenario's map region as cells.
pub fn region_of(s: &scenario::Scenario, geometry: &GridGeometry) -> Result<oeg::CellRegion> {
    let eps = s.map.resolution_m * 1e-6;
    Ok(geometry.region_covering(
        (s.map.min_xy_m[0], s.map.min_xy_m[1]),
        (s.map.max_xy_m[0] - eps, s.map.max_xy_m[1] - eps),
    )?)
}

/// Wall times of a simulation shared by several maps.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SimulatedTiming {
    /// Simulating the drive and the sensors, seconds.
    pub simulation_wall_time_s: f64,
    /// Integrating the scans, seconds, summed over the maps.
    pub map_wall_time_s: f64,
    /// Rays simulated.
    pub num_rays: u64,
}

/// Simulates `loaded` once and integrates every scan, at the estimated pose, into one map per entry of
/// `maps` (the map settings of runs that share this simulation: they differ only in the map's model,
/// resolution or rule). The simulation is returned at the end of its drive.
///
/// # Errors
/// A world or map that cannot be built, or a scan the map rejects.
pub fn simulate_and_map(
    loaded: &scenario::LoadedScenario,
    maps: &[&scenario::MapSettings],
    progress: &Progress,
) -> Result<(Simulation, Vec<Map>, SimulatedTiming)> {
    let s = &loaded.scenario;
    let mut simulation = Simulation::new(loaded)?;
    let mut built = maps
        .iter()
        .map(|m| {
            Map::new(MapConfig {
                resolution_m: m.resolution_m,
                model: m.model,
                memory_limit_bytes: oeg::DEFAULT_MEMORY_LIMIT_BYTES,
            })
        })
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let models: Vec<oeg::SensorModel> = simulation.sensors().iter().map(|x| x.map_model()).collect();
    progress.set_length(simulation.num_scans_total());
    let mut simulation_s = 0.0;
    let mut map_s = vec![0.0; built.len()];
    let mut last_tick = -1i64;
    loop {
        let t0 = Instant::now();
        let Some(scan) = simulation.next_scan() else { break };
        simulation_s += t0.elapsed().as_secs_f64();
        let stamp_s = scan.stamp_s;
        let scan = scan.to_scan(PoseSource::Estimated, models[scan.sensor_index]);
        // The maps are independent: with several, each scan goes into all of them at once (a map's integration
        // is one thread, so the other cores would idle). The results do not depend on it.
        let integrate = |(map, seconds): (&mut Map, &mut f64)| {
            let t1 = Instant::now();
            let r = map.integrate(&scan).map(|_| ());
            *seconds += t1.elapsed().as_secs_f64();
            r
        };
        if built.len() > 1 {
            use rayon::prelude::*;
            built
                .par_iter_mut()
                .zip(map_s.par_iter_mut())
                .map(integrate)
                .collect::<std::result::Result<Vec<()>, _>>()?;
        } else {
            built.iter_mut().zip(map_s.iter_mut()).try_for_each(integrate)?;
        }
        progress.inc(1);
        // The progress line is refreshed once per simulation tick (`tick_s`).
        let tick = (stamp_s / s.tick_s).floor() as i64;
        if tick != last_tick {
            last_tick = tick;
            progress.message(format!(
                "t = {:.1} / {:.0} s, {:.2} M rays/s",
                stamp_s,
                s.duration_s,
                simulation.num_rays() as f64 / simulation_s.max(1e-9) / 1e6
            ));
        }
    }
    progress.finish();
    // The truth is taken at the end of the run: a person who left must have left the map too.
    simulation.world_mut().advance_to(s.duration_s);
    let timing = SimulatedTiming {
        simulation_wall_time_s: simulation_s,
        map_wall_time_s: map_s.iter().sum(),
        num_rays: simulation.num_rays(),
    };
    Ok((simulation, built, timing))
}

/// The truth over the scenario's map region on `geometry`'s cells, people left out, from the world at the end
/// of the run.
///
/// # Errors
/// A region that does not fit the grid.
pub fn truth_of(s: &scenario::Scenario, world: &sim::World, geometry: &GridGeometry) -> Result<TruthRaster> {
    let region = region_of(s, geometry)?;
    Ok(TruthRaster::compute(
        world,
        geometry,
        region,
        profile_of(s)?,
        Actors::Excluded,
        DEFAULT_SAMPLES_PER_SIDE,
    ))
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
    let staged = Staged::begin(&out_dir)?;
    // The compared model: the scenario as if its `[map]` said `preset = "<preset>"` (its own `[map.model]` keys,
    // such as height thresholding, still apply), through the same door as `--set map.preset=<preset>`.
    let compared: Option<(oeg::MapPreset, scenario::Scenario)> = match options.compare {
        None => None,
        Some(preset) => {
            let mut with_preset = options.clone();
            with_preset
                .overrides
                .push(format!("map.preset={}", preset.name()));
            Some((preset, load(&with_preset)?.scenario))
        }
    };
    let mut settings = vec![&s.map];
    if let Some((_, c)) = &compared {
        settings.push(&c.map);
    }
    let (simulation, maps, sim_timing) = simulate_and_map(&loaded, &settings, progress)?;
    let mut maps = maps.into_iter();
    let map = maps.next().ok_or_else(|| EvalError::Input {
        path: options.scenario.clone(),
        message: "the simulation built no map".into(),
    })?;
    let truth_start = Instant::now();
    let geometry = *map.geometry();
    let truth = truth_of(s, simulation.world(), &geometry)?;
    let truth_wall_time_s = truth_start.elapsed().as_secs_f64();
    let evaluation = evaluate(s, &map, &truth, simulation.obstacle_returns())?;

    let stage = staged.dir();
    let mut files = write_report(stage, s, &map, &truth, &evaluation)?;
    let mut compared_metrics = None;
    if let (Some((preset, c)), Some(other)) = (&compared, maps.next()) {
        let other_eval = evaluate(c, &other, &truth, simulation.obstacle_returns())?;
        let dir = stage.join(preset.name());
        create_dir(&dir)?;
        files.extend(write_report(&dir, c, &other, &truth, &other_eval)?);
        files.extend(write_comparison(
            stage,
            [(s, &evaluation), (c, &other_eval)],
            &geometry,
        )?);
        compared_metrics = Some((*preset, other_eval.metrics));
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
    };
    let timing_path = stage.join("timing.json");
    write_json(&timing_path, &timing)?;
    files.push(timing_path);
    let files = files.iter().map(|f| staged.final_path(f)).collect();
    staged.commit()?;
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
        compared: compared_metrics,
        out_dir,
        files,
    })
}
