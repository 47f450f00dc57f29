//! The simulation stage every scenario job shares: the drive (scripted or closed loop) and its sensors, each
//! scan into one map per model, and the planner a closed loop asks.

use std::path::Path;
use std::time::Instant;

use oeg::Map;
use sim::truth::TruthRaster;
use sim::{Simulation, scenario};

use super::{RunOptions, truth_of};
use crate::error::{EvalError, Result};
use crate::mapping::{Mapping, SimulatedTiming};
use crate::navigation::external::ExternalPlanner;
use crate::navigation::{NavigationInputs, NavigationLog, PlannerSource, navigate};
use crate::progress::Progress;
use crate::recording::Recording;

/// Simulates `loaded` once and integrates every scan, at the estimated pose, into one map per entry of
/// `maps` (one map per entry, as a sweep shares a simulation). The simulation is returned at the end of its drive.
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
            observability: mapping.observability.finished(),
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
        observability: mapping.observability.finished(),
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
