//! Metrics of a map against the truth (`docs/metrics.md` defines every key), and the check of a scenario's
//! expectations. Pure functions of the map and the truth raster.

use std::collections::BTreeMap;

use serde::Serialize;
use sim::truth::TruthRaster;

use crate::judge::estimate::Estimate;
pub use crate::judge::navigation_metrics::NavMetrics;
pub use crate::judge::physics_metrics::PhysicsMetrics;
use crate::judge::verdict::{TruthClass, Verdict, Verdicts};

/// `metrics.json`: one flat object, snake_case keys with units in their names. Deterministic for the same
/// scenario and seed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Metrics {
    /// Scenario name.
    pub scenario: String,
    /// Seed of the run.
    pub seed: u64,
    /// Cells in the scenario's map region.
    pub num_cells: u64,
    /// Region cells the map observed.
    pub num_observed_cells: u64,
    /// `num_observed_cells / num_cells`.
    pub coverage: f64,
    /// Observed region cells with an elevation estimate and a true elevation: the elevation metrics' cells.
    pub num_elevation_cells: u64,
    /// Root mean square of `mu - true elevation`, metres.
    pub elevation_rmse_m: f64,
    /// Mean absolute error, metres.
    pub elevation_mae_m: f64,
    /// Mean error (positive: the map is too high), metres.
    pub elevation_bias_m: f64,
    /// 95th percentile of the absolute error, metres.
    pub elevation_p95_abs_err_m: f64,
    /// Fraction of cells whose true elevation lies within 2 sigma of `mu` (0.95 for a calibrated map).
    pub elevation_within_2sigma: f64,
    /// Mean of `(P(occupied) - truly blocked)^2` over the scored cells.
    pub occupancy_brier: f64,
    /// Observed cells on the terrain: the decision metrics' cells (`oeg_eval::verdict`). The six counts below
    /// partition them.
    pub num_scored_cells: u64,
    /// Truly drivable, mapped drivable (free or traversable).
    pub right_drivable_cells: u64,
    /// Truly blocked (a step, or a structure lower than the robot), mapped blocked.
    pub right_blocked_cells: u64,
    /// Truly a step, mapped drivable: where the robot would drive into something. Must be zero.
    pub unsafe_step_cells: u64,
    /// Under a structure lower than the robot, mapped drivable. Must be zero.
    pub unsafe_clearance_cells: u64,
    /// Truly drivable, mapped blocked: where the robot would refuse a drivable cell.
    pub overcautious_step_cells: u64,
    /// Under a structure the robot passes under, mapped blocked.
    pub overcautious_clearance_cells: u64,
    /// Mapped uncertain: the map says it cannot tell (a step or clearance within `kappa` sigma of its
    /// threshold). The planner treats them as blocked by default.
    pub uncertain_cells: u64,
    /// `unsafe_step_cells + unsafe_clearance_cells`.
    pub unsafe_cells: u64,
    /// `overcautious_step_cells + overcautious_clearance_cells`.
    pub overcautious_cells: u64,
    /// Of the unsafe step cells, those no ray of the sensors ended on: no map of these readings could have
    /// known (`sim::observability`).
    pub blind_step_cells: u64,
    /// Of the unsafe clearance cells, those where no ray ended inside the band between a step and the robot's
    /// height: no ray reached the structure.
    pub blind_clearance_cells: u64,
    /// `blind_step_cells + blind_clearance_cells`.
    pub blind_cells: u64,
    /// `unsafe_cells - blind_cells`: the unsafe cells a ray could have told about, the map's own.
    pub unsafe_observable_cells: u64,
    /// Of the uncertain cells, those truly blocked.
    pub uncertain_truly_blocked_cells: u64,
    /// The cells the map could not decide by what it could not tell ([`oeg::Doubt`]), `doubt_<doubt>_cells`,
    /// one key per doubt: the scored uncertain cells, and the observed cells on the terrain it left unknown
    /// (`frontier`, `no_height`; not scored). Null when the map does not say why (another mapper's arrays).
    #[serde(flatten)]
    pub doubts: BTreeMap<String, Option<u64>>,
    /// Scored cells under a structure (a gap higher than a step within 3 m above the ground).
    pub num_clearance_cells: u64,
    /// DynamicMap's SA adapted to cells (`judge::ghosts`): of the truly blocked cells a ray could have
    /// told about and no actor passed through, the fraction mapped blocked or uncertain (null: none).
    pub static_accuracy: f64,
    /// DynamicMap's DA: of the cells an actor covered and left (truly drivable, scored, not uncertain only for
    /// the sensors' resolution), the fraction mapped drivable at the end (null: no such cell).
    pub dynamic_accuracy: f64,
    /// DynamicMap's AA, `sqrt(static_accuracy * dynamic_accuracy)` (null when either is).
    pub associated_accuracy: f64,
    /// The cells behind `dynamic_accuracy`.
    pub num_dynamic_cells: u64,
    /// Bytes the map holds.
    pub map_bytes: u64,
    /// Scans integrated.
    pub num_scans: u64,
    /// Rays integrated.
    pub num_rays: u64,
    /// Whether the planner found a path on the map from its start to its goal (by default the drive's first and
    /// last waypoints).
    pub plan_found: bool,
    /// Length of the map's path, metres (null when there is none).
    pub plan_length_m: f64,
    /// Cells of the map's path within the planner's inflation radius of a truly blocked cell: where the robot
    /// would touch an obstacle. The number that must be zero.
    pub plan_unsafe_cells: u64,
    /// Of the unsafe path cells, those whose near truly blocked cells no ray could have told about.
    pub plan_blind_cells: u64,
    /// Whether a path exists on the truth.
    pub truth_plan_found: bool,
    /// Whether a path exists on the truth through the cells the sensors reached (a drivable cell that no ray
    /// ended on nor crossed above a step's height counts as unknown); null without an observability truth (a
    /// replayed log).
    pub observable_truth_plan_found: Option<bool>,
    /// Length of the truth's path, metres (null when there is none).
    pub truth_plan_length_m: f64,
    /// `plan_length_m / truth_plan_length_m`: the detour the map's decisions cost (1 = none; null when either
    /// path is missing).
    pub plan_length_ratio: f64,
    /// The closed loop's figures (`nav_*`; null for a run without `[navigation]`).
    #[serde(flatten)]
    pub nav: NavMetrics,
    /// The drive on the wheels' figures (`phys_*`; absent for a kinematic drive).
    #[serde(flatten)]
    pub phys: PhysicsMetrics,
    /// Whether every expectation of the scenario holds.
    pub expectations_passed: bool,
    /// Number of expectations that failed.
    pub num_expectations_failed: u64,
}

/// The cells the map could not decide by doubt, keyed `doubt_<doubt>_cells`: the scored uncertain cells, and
/// the observed cells on the terrain left unknown. Counts when the estimate says why, nulls when it does not.
fn doubt_counts(estimate: &Estimate, verdicts: &Verdicts) -> BTreeMap<String, Option<u64>> {
    let known = !estimate.doubts.is_empty();
    let mut counts: BTreeMap<oeg::Doubt, u64> = oeg::Doubt::ALL.iter().map(|d| (*d, 0)).collect();
    let cells = estimate
        .doubts
        .iter()
        .zip(&verdicts.verdict)
        .zip(&verdicts.truth)
        .zip(&verdicts.mapped);
    for (((doubt, verdict), truth), mapped) in cells {
        let counted = *verdict == Verdict::Uncertain
            || (*mapped == oeg::Traversability::Unknown && *truth != TruthClass::OffTerrain);
        if let (Some(d), true) = (doubt, counted) {
            *counts.entry(*d).or_default() += 1;
        }
    }
    counts
        .into_iter()
        .map(|(d, n)| (format!("doubt_{}_cells", d.name()), known.then_some(n)))
        .collect()
}

/// What the observed cells say against the truth: how many there are, the occupancy's squared errors (over the
/// cells with a probability, on the terrain), and each elevation estimate's error with how many lie within two
/// standard deviations.
struct CellErrors {
    observed: u64,
    brier_sum: f64,
    num_brier: u64,
    errors: Vec<f64>,
    within: u64,
}

impl CellErrors {
    fn of(estimate: &Estimate, truth: &TruthRaster, verdicts: &Verdicts) -> Self {
        let mut e = Self {
            observed: 0,
            brier_sum: 0.0,
            num_brier: 0,
            errors: Vec::new(),
            within: 0,
        };
        for (k, t) in truth.cells.iter().enumerate() {
            if !estimate.observed[k] {
                continue;
            }
            e.observed += 1;
            if t.elevation_m.is_nan() {
                continue;
            }
            let p = estimate.occupancy(k);
            if !p.is_nan() {
                let o = if verdicts.truth[k].is_blocked() { 1.0 } else { 0.0 };
                e.brier_sum += (p - o) * (p - o);
                e.num_brier += 1;
            }
            if let Some((elevation, var)) = estimate.elevation(k) {
                let err = elevation - f64::from(t.elevation_m);
                e.errors.push(err);
                if err.abs() <= 2.0 * var.sqrt() {
                    e.within += 1;
                }
            }
        }
        e
    }
}

/// Computes every metric except the expectation and plan fields: the elevation against the truth, and the
/// decisions from the verdict raster.
pub fn compute(
    scenario: &str,
    seed: u64,
    estimate: &Estimate,
    truth: &TruthRaster,
    verdicts: &Verdicts,
) -> Metrics {
    let CellErrors {
        observed,
        brier_sum,
        num_brier,
        errors,
        within,
    } = CellErrors::of(estimate, truth, verdicts);
    let counts = verdicts.counts();
    let doubts = doubt_counts(estimate, verdicts);
    let n = errors.len() as f64;
    let (rmse, mae, bias, p95, within_2sigma) = if errors.is_empty() {
        (f64::NAN, f64::NAN, f64::NAN, f64::NAN, f64::NAN)
    } else {
        let mut abs: Vec<f64> = errors.iter().map(|e| e.abs()).collect();
        abs.sort_by(f64::total_cmp);
        (
            (errors.iter().map(|e| e * e).sum::<f64>() / n).sqrt(),
            abs.iter().sum::<f64>() / n,
            errors.iter().sum::<f64>() / n,
            percentile(&abs, 0.95),
            within as f64 / n,
        )
    };
    let num_cells = truth.window.num_cells();
    Metrics {
        scenario: scenario.to_string(),
        seed,
        num_cells,
        num_observed_cells: observed,
        coverage: observed as f64 / num_cells.max(1) as f64,
        num_elevation_cells: errors.len() as u64,
        elevation_rmse_m: rmse,
        elevation_mae_m: mae,
        elevation_bias_m: bias,
        elevation_p95_abs_err_m: p95,
        elevation_within_2sigma: within_2sigma,
        occupancy_brier: if num_brier > 0 {
            brier_sum / num_brier as f64
        } else {
            f64::NAN
        },
        num_scored_cells: counts.num_scored_cells,
        right_drivable_cells: counts.right_drivable_cells,
        right_blocked_cells: counts.right_blocked_cells,
        unsafe_step_cells: counts.unsafe_step_cells,
        unsafe_clearance_cells: counts.unsafe_clearance_cells,
        overcautious_step_cells: counts.overcautious_step_cells,
        overcautious_clearance_cells: counts.overcautious_clearance_cells,
        uncertain_cells: counts.uncertain_cells,
        unsafe_cells: counts.unsafe_cells(),
        overcautious_cells: counts.overcautious_cells(),
        blind_step_cells: counts.blind_step_cells,
        blind_clearance_cells: counts.blind_clearance_cells,
        blind_cells: counts.blind_cells(),
        unsafe_observable_cells: counts.unsafe_cells() - counts.blind_cells(),
        uncertain_truly_blocked_cells: counts.uncertain_truly_blocked_cells,
        doubts,
        num_clearance_cells: counts.num_clearance_cells,
        static_accuracy: f64::NAN,
        dynamic_accuracy: f64::NAN,
        associated_accuracy: f64::NAN,
        num_dynamic_cells: 0,
        map_bytes: estimate.totals.map_bytes,
        num_scans: estimate.totals.num_scans,
        num_rays: estimate.totals.num_rays,
        plan_found: false,
        plan_length_m: f64::NAN,
        plan_unsafe_cells: 0,
        plan_blind_cells: 0,
        truth_plan_found: false,
        observable_truth_plan_found: None,
        truth_plan_length_m: f64::NAN,
        plan_length_ratio: f64::NAN,
        nav: NavMetrics::default(),
        phys: PhysicsMetrics::default(),
        expectations_passed: true,
        num_expectations_failed: 0,
    }
}

/// The value at fraction `q` of sorted values (nearest rank).
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1]
}

/// The metrics as name -> number (booleans as 0 / 1), for expectations.
pub fn numeric(metrics: &Metrics) -> BTreeMap<String, f64> {
    let value = serde_json::to_value(metrics).unwrap_or_default();
    let mut out = BTreeMap::new();
    if let Some(obj) = value.as_object() {
        for (k, v) in obj {
            if let Some(x) = v.as_f64() {
                out.insert(k.clone(), x);
            } else if let Some(b) = v.as_bool() {
                out.insert(k.clone(), f64::from(u8::from(b)));
            } else if v.is_null() {
                out.insert(k.clone(), f64::NAN);
            }
        }
    }
    out
}

/// The names of every metric an expectation may name.
pub fn metric_names() -> Vec<String> {
    numeric(&compute_empty()).into_keys().collect()
}

/// A safe run's metrics for tests: a path found on the map and the truth, no closed loop.
#[cfg(test)]
pub(crate) fn test_metrics() -> Metrics {
    Metrics {
        plan_found: true,
        truth_plan_found: true,
        plan_length_m: 10.0,
        truth_plan_length_m: 10.0,
        plan_length_ratio: 1.0,
        nav: NavMetrics::default(),
        phys: PhysicsMetrics::default(),
        ..compute_empty()
    }
}

fn compute_empty() -> Metrics {
    Metrics {
        scenario: String::new(),
        seed: 0,
        num_cells: 0,
        num_observed_cells: 0,
        coverage: 0.0,
        num_elevation_cells: 0,
        elevation_rmse_m: 0.0,
        elevation_mae_m: 0.0,
        elevation_bias_m: 0.0,
        elevation_p95_abs_err_m: 0.0,
        elevation_within_2sigma: 0.0,
        occupancy_brier: 0.0,
        num_scored_cells: 0,
        right_drivable_cells: 0,
        right_blocked_cells: 0,
        unsafe_step_cells: 0,
        unsafe_clearance_cells: 0,
        overcautious_step_cells: 0,
        overcautious_clearance_cells: 0,
        uncertain_cells: 0,
        unsafe_cells: 0,
        overcautious_cells: 0,
        blind_step_cells: 0,
        blind_clearance_cells: 0,
        blind_cells: 0,
        unsafe_observable_cells: 0,
        uncertain_truly_blocked_cells: 0,
        doubts: BTreeMap::new(),
        num_clearance_cells: 0,
        static_accuracy: f64::NAN,
        dynamic_accuracy: f64::NAN,
        associated_accuracy: f64::NAN,
        num_dynamic_cells: 0,
        map_bytes: 0,
        num_scans: 0,
        num_rays: 0,
        plan_found: false,
        plan_length_m: 0.0,
        plan_unsafe_cells: 0,
        plan_blind_cells: 0,
        truth_plan_found: false,
        observable_truth_plan_found: None,
        truth_plan_length_m: 0.0,
        plan_length_ratio: 0.0,
        nav: NavMetrics::ZERO,
        phys: PhysicsMetrics::ZERO,
        expectations_passed: true,
        num_expectations_failed: 0,
    }
}

#[cfg(test)]
mod tests;
