//! A scenario's `[expectations]`: which names and ranges make sense (`oeg validate` asks), and each bound
//! checked against a run's metrics.

use std::collections::BTreeMap;

use crate::judge::metrics::{Metrics, metric_names, numeric};

/// One failed expectation.
#[derive(Debug, Clone, PartialEq)]
pub struct FailedExpectation {
    /// Metric name.
    pub metric: String,
    /// Measured value.
    pub measured: f64,
    /// What was required, as text (`>= 0.9`, `<= 0`).
    pub required: String,
}

impl std::fmt::Display for FailedExpectation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} = {} (required {})",
            self.metric, self.measured, self.required
        )
    }
}

/// The values a metric can take: fractions and flags lie in [0, 1], the elevation bias is any number, every
/// other metric (counts, errors, lengths, ratios) is at least 0.
pub fn metric_domain(name: &str) -> (f64, f64) {
    match name {
        "coverage"
        | "elevation_within_2sigma"
        | "occupancy_brier"
        | "plan_found"
        | "truth_plan_found"
        | "observable_truth_plan_found"
        | "nav_reached"
        | "nav_stuck"
        | "phys_tipped_over"
        | "phys_goal_reached"
        | "expectations_passed" => (0.0, 1.0),
        "elevation_bias_m" => (f64::NEG_INFINITY, f64::INFINITY),
        _ => (0.0, f64::INFINITY),
    }
}

/// What is wrong with a scenario's `[expectations]`, as `(metric, message)`: a name that is no metric, or a
/// range the metric can never meet (outside [`metric_domain`]). `oeg validate` and `oeg run` both ask.
pub fn expectation_problem(
    expectations: &BTreeMap<String, sim::scenario::Expectation>,
) -> Option<(String, String)> {
    let known = metric_names();
    for (name, e) in expectations {
        if !known.contains(name) {
            return Some((
                name.clone(),
                format!("`{name}` is not a metric; metrics: {}", known.join(", ")),
            ));
        }
        let (lo, hi) = metric_domain(name);
        let impossible = e.min.is_some_and(|m| m > hi) || e.max.is_some_and(|m| m < lo);
        if impossible {
            let range = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| v.to_string());
            return Some((
                name.clone(),
                format!(
                    "`{name}` takes values in [{lo}, {hi}], so [{}, {}] can never be met",
                    range(e.min),
                    range(e.max)
                ),
            ));
        }
    }
    None
}

/// One bound of one expectation, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct ExpectationResult {
    /// Metric name.
    pub metric: String,
    /// Measured value.
    pub measured: f64,
    /// What was required, as text (`>= 0.9`, `<= 0`).
    pub required: String,
    /// Whether the measured value meets it. A NaN metric (nothing to measure) fails any bound.
    pub passed: bool,
}

/// Every bound of `expectations` checked against the metrics, in the expectations' order (min before max).
pub fn expectation_results(
    metrics: &Metrics,
    expectations: &BTreeMap<String, sim::scenario::Expectation>,
) -> Vec<ExpectationResult> {
    let values = numeric(metrics);
    let mut results = Vec::new();
    for (name, e) in expectations {
        let measured = values.get(name).copied().unwrap_or(f64::NAN);
        // NaN compares as neither: it fails both kinds of bound.
        if let Some(min) = e.min {
            results.push(ExpectationResult {
                metric: name.clone(),
                measured,
                required: format!(">= {min}"),
                passed: measured
                    .partial_cmp(&min)
                    .is_some_and(|o| o != std::cmp::Ordering::Less),
            });
        }
        if let Some(max) = e.max {
            results.push(ExpectationResult {
                metric: name.clone(),
                measured,
                required: format!("<= {max}"),
                passed: measured
                    .partial_cmp(&max)
                    .is_some_and(|o| o != std::cmp::Ordering::Greater),
            });
        }
    }
    results
}

/// Checks `expectations` against the metrics ([`expectation_results`]), records the outcome in them, and
/// returns the failures.
pub fn check_expectations(
    metrics: &mut Metrics,
    expectations: &BTreeMap<String, sim::scenario::Expectation>,
) -> Vec<FailedExpectation> {
    let failed: Vec<FailedExpectation> = expectation_results(metrics, expectations)
        .into_iter()
        .filter(|r| !r.passed)
        .map(|r| FailedExpectation {
            metric: r.metric,
            measured: r.measured,
            required: r.required,
        })
        .collect();
    metrics.num_expectations_failed = failed.len() as u64;
    metrics.expectations_passed = failed.is_empty();
    failed
}
