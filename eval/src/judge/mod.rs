//! A map judged against the truth: the verdict raster, and everything read from it (the metrics, the planner
//! check, the per-obstacle decisions, the expectations).
//!
//! The judge reads a map only through an [`estimate::Estimate`], what the map says about each cell of the
//! truth's region: the testbed's own map and another mapper's arrays are judged by the same code
//! ([`evaluate`], [`score`]).
//!
//! The modules depend one way: [`estimate`], [`verdict`] <- [`metrics`], `ghosts`, [`plan_check`],
//! `obstacles`, `wrong_cells` <- [`Evaluation`] <- the figures and the report.

pub mod estimate;
pub mod expectations;
pub(crate) mod ghosts;
pub mod metrics;
pub mod navigation_metrics;
pub(crate) mod obstacles;
pub(crate) mod outcome;
pub mod physics_metrics;
pub mod plan_check;
pub mod verdict;
pub(crate) mod wrong_cells;

use oeg::Map;
use sim::scenario;
use sim::sensors::ObstacleReturns;
use sim::truth::TruthRaster;

use crate::error::Result;
use crate::judge::estimate::Estimate;
use crate::judge::verdict::Verdicts;
use expectations::FailedExpectation;
use metrics::Metrics;
use navigation_metrics::NavMetrics;
pub use physics_metrics::{PhysicsMetrics, PhysicsRecord};

/// A map judged against the truth: metrics (with the planner check and the expectations), per-obstacle
/// decisions.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// The metrics.
    pub metrics: Metrics,
    /// Expectations that failed.
    pub failed: Vec<FailedExpectation>,
    /// The planner check.
    pub plan: plan_check::PlanCheck,
    /// Per-obstacle decisions.
    pub obstacles: Vec<obstacles::ObstacleDecision>,
    /// The verdict raster every one of the above was read from.
    pub verdicts: Verdicts,
    /// What the map said about each cell, which the verdicts judged.
    pub estimate: Estimate,
}

/// What the run's sensors and robot did, beside the map: the judge reads it with the truth.
#[derive(Debug, Clone, Copy)]
pub struct Sensed<'a> {
    /// The readings each obstacle gave the sensors (whether it was seen at all); `None` when unknown.
    pub returns: Option<&'a ObstacleReturns>,
    /// What the sensors' rays could have told, cell by cell (`None`: a replayed log).
    pub observability: Option<&'a sim::observability::Observability>,
    /// A closed-loop run's figures (the `nav_*` metrics, which the expectations may name).
    pub navigation: Option<&'a NavigationFigures>,
    /// A drive on the wheels' events and samples (the `phys_*` metrics; `None`: a kinematic drive).
    pub physics: Option<PhysicsRecord<'a>>,
}

/// Judges `map` against `truth` under the scenario's decisions, with what the run `sensed`.
///
/// # Errors
/// A planner check that cannot run (a start or goal outside the region).
pub fn evaluate(
    s: &scenario::Scenario,
    map: &Map,
    truth: &TruthRaster,
    sensed: &Sensed<'_>,
) -> Result<Evaluation> {
    let estimate = Estimate::of_map(map, truth, s.map.traversability)?;
    score(s, estimate, truth, sensed)
}

/// Judges what a map says, `estimate` (the testbed's map or another mapper's arrays), against `truth`, with
/// what the run `sensed`.
///
/// # Errors
/// A planner check that cannot run (a start or goal outside the region).
pub fn score(
    s: &scenario::Scenario,
    estimate: Estimate,
    truth: &TruthRaster,
    sensed: &Sensed<'_>,
) -> Result<Evaluation> {
    let verdicts =
        Verdicts::from_classes(truth, estimate.decisions.clone()).with_observability(sensed.observability);
    let mut metrics = metrics::compute(&s.name, s.seed, &estimate, truth, &verdicts);
    let plan = plan_check::check(s, &verdicts)?;
    record_plan(&mut metrics, &plan);
    record_ghosts(
        &mut metrics,
        &ghosts::count(s, &verdicts, &estimate.doubts, sensed.observability),
    );
    if let Some(n) = sensed.navigation {
        record_navigation(&mut metrics, n);
    }
    if let Some(p) = &sensed.physics {
        metrics.phys = PhysicsMetrics::of(p);
    }
    let failed = expectations::check_expectations(&mut metrics, &applicable(&s.expectations, &estimate));
    let obstacles = obstacles::decisions(s, &estimate, truth, &verdicts, sensed.returns);
    Ok(Evaluation {
        metrics,
        failed,
        plan,
        obstacles,
        verdicts,
        estimate,
    })
}

/// The expectations a map can be held to: none on a layer it does not have at all (a nav2 map has decisions
/// only, so its elevation and occupancy metrics are not measured, not failed).
fn applicable(
    expectations: &std::collections::BTreeMap<String, scenario::Expectation>,
    estimate: &Estimate,
) -> std::collections::BTreeMap<String, scenario::Expectation> {
    let has = |layer: &[f32]| layer.iter().any(|v| !v.is_nan());
    let (elevation, occupancy) = (has(&estimate.elevation_m), has(&estimate.occupancy));
    expectations
        .iter()
        .filter(|(name, _)| {
            let needs_elevation = name.starts_with("elevation_") || name.as_str() == "num_elevation_cells";
            (elevation || !needs_elevation) && (occupancy || name.as_str() != "occupancy_brier")
        })
        .map(|(name, e)| (name.clone(), *e))
        .collect()
}

/// A closed-loop run's figures, as the judge records them (the `nav_*` metrics).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavigationFigures {
    /// Whether the goal was reached.
    pub reached: bool,
    /// Seconds navigated.
    pub time_s: f64,
    /// Driven over the truth's shortest path (reached runs only).
    pub length_ratio: Option<f64>,
    /// Plans asked for.
    pub replans: u64,
    /// Stops of the collision guard.
    pub guard_stops: u64,
    /// Replanning times without a path.
    pub no_path_replans: u64,
    /// Failed planner calls.
    pub planner_failures: u64,
    /// Contacts with truly blocked cells.
    pub contacts: u64,
    /// Of them, contacts with a cell a ray could have told about before.
    pub contacts_observable: u64,
    /// Of them, by what the robot's map called the cells entered: blocked, undecided, drivable.
    pub contacts_mapped: [u64; 3],
    /// Closest approach to a truly blocked cell, metres.
    pub closest_approach_m: Option<f64>,
    /// Whether the robot ended stuck.
    pub stuck: bool,
}

/// Records a closed-loop run's figures in the metrics (the `nav_*` keys).
pub fn record_navigation(metrics: &mut Metrics, n: &NavigationFigures) {
    metrics.nav = NavMetrics::of(n);
}

/// Fills SA, DA and AA from their counts (NaN, written as null, where undefined).
pub fn record_ghosts(metrics: &mut Metrics, ghosts: &ghosts::GhostCounts) {
    metrics.static_accuracy = ghosts.static_accuracy().unwrap_or(f64::NAN);
    metrics.dynamic_accuracy = ghosts.dynamic_accuracy().unwrap_or(f64::NAN);
    metrics.associated_accuracy = ghosts.associated_accuracy().unwrap_or(f64::NAN);
    metrics.num_dynamic_cells = ghosts.num_dynamic_cells;
}

/// Records the planner check in the metrics (the `plan_*` keys).
pub fn record_plan(metrics: &mut Metrics, check: &plan_check::PlanCheck) {
    let length = |p: &Option<oeg::Plan>| p.as_ref().map_or(f64::NAN, |p| p.length_m);
    metrics.plan_found = check.map_plan.is_some();
    metrics.plan_length_m = length(&check.map_plan);
    metrics.plan_unsafe_cells = check.unsafe_cells.len() as u64;
    metrics.plan_blind_cells = check.blind_cells.len() as u64;
    metrics.truth_plan_found = check.truth_plan.is_some();
    metrics.observable_truth_plan_found = check.observable_truth_plan_found;
    metrics.truth_plan_length_m = length(&check.truth_plan);
    metrics.plan_length_ratio = metrics.plan_length_m / metrics.truth_plan_length_m;
}
