//! What a run found, in the testbed's own terms, kept apart from the scenario's regression bounds: whether the
//! robot would have driven safely on the map (the planned path, and the closed-loop drive where there is one),
//! and how the map's wrong cells split (unsafe where a ray could have told, unsafe where none could, uncertain,
//! over-cautious). The report's first box, `oeg run`'s standard output and the suite's tables all read it.
//!
//! The expectations of a scenario are regression bounds set from a measured run with a margin: they catch a
//! change, they do not say the map is right. A map can meet every bound and still hold unsafe cells; the
//! outcome says so first.

use std::collections::BTreeMap;

use crate::judge::expectations::{ExpectationResult, expectation_results};
use crate::judge::metrics::Metrics;
use crate::output::html::field;

/// How a drive on the map ends, judged against the truth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Safety {
    /// The planned path kept clear of every truly blocked cell, and the closed-loop drive (if any) made no
    /// contact.
    Safe,
    /// The planned path passed near a truly blocked cell, or the closed-loop drive touched one.
    Unsafe,
    /// Nothing was driven: the map has no path (the closed loop, if any, made no contact but did not reach).
    NoPath,
}

impl Safety {
    /// The word for tables and CSV: `safe`, `unsafe` or `no path`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Safe => "safe",
            Self::Unsafe => "unsafe",
            Self::NoPath => "no path",
        }
    }

    /// Of one run's metrics.
    pub fn of(m: &Metrics) -> Self {
        let contacts = m.nav.contacts.unwrap_or(0);
        if m.plan_unsafe_cells > 0 || contacts > 0 {
            Self::Unsafe
        } else if !m.plan_found || m.nav.reached == Some(false) {
            Self::NoPath
        } else {
            Self::Safe
        }
    }
}

/// One model's outcome: what its map made the robot do, and its regression bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// The model's name (`paper`, `robust`).
    pub model: String,
    /// Safe, unsafe or no path.
    pub safety: Safety,
    /// Every bound of the scenario's expectations against this model's metrics.
    pub bounds: Vec<ExpectationResult>,
    metrics: Metrics,
    /// With no path on the map, the cells that closed the way, in words
    /// ([`crate::judge::plan_check::PlanCheck::closed_by`]).
    closed_by: Option<String>,
}

impl Outcome {
    /// The outcome of `model`'s metrics, with the scenario's expectations checked against them.
    pub fn new(
        model: &str,
        metrics: &Metrics,
        expectations: &BTreeMap<String, sim::scenario::Expectation>,
    ) -> Self {
        Self {
            model: model.to_string(),
            safety: Safety::of(metrics),
            bounds: expectation_results(metrics, expectations),
            metrics: metrics.clone(),
            closed_by: None,
        }
    }

    /// The outcome with the cells that closed the way when there is no path
    /// ([`crate::judge::plan_check::PlanCheck::closed_by`]), which [`Outcome::path_text`] then names.
    pub fn with_closed_by(self, closed_by: Option<String>) -> Self {
        Self { closed_by, ..self }
    }

    /// The bounds that do not hold.
    pub fn failed_bounds(&self) -> impl Iterator<Item = &ExpectationResult> {
        self.bounds.iter().filter(|r| !r.passed)
    }

    /// The planned path, in words: `safe (14.00 m, 1.00 times the truth's)`, `UNSAFE: 16 path cells ...`,
    /// `none (the truth has one)`.
    pub fn path_text(&self) -> String {
        let m = &self.metrics;
        if !m.plan_found {
            let text = match (m.truth_plan_found, m.observable_truth_plan_found) {
                (true, Some(false)) => {
                    "no path on the map (the truth has one, none through what the rays reached)"
                }
                (true, _) => "no path on the map (the truth has one)",
                (false, _) => "no path on the map, nor on the truth",
            };
            return match &self.closed_by {
                Some(closed_by) => format!("{text}: {closed_by}"),
                None => text.into(),
            };
        }
        let ratio = if m.plan_length_ratio.is_finite() {
            format!(", {:.2} times the truth's", m.plan_length_ratio)
        } else {
            String::new()
        };
        if m.plan_unsafe_cells == 0 {
            format!("safe ({:.2} m{ratio})", m.plan_length_m)
        } else {
            format!(
                "UNSAFE: {} path cells within the robot's radius of a truly blocked cell ({} of them blind)",
                m.plan_unsafe_cells, m.plan_blind_cells
            )
        }
    }

    /// The closed-loop drive, in words, when the run had one: `reached the goal in 41.2 s, no contact`.
    pub fn drive_text(&self) -> Option<String> {
        let m = &self.metrics;
        let reached = m.nav.reached?;
        let contacts = m.nav.contacts.unwrap_or(0);
        let end = if reached {
            "reached the goal"
        } else if m.nav.stuck == Some(true) {
            "did NOT reach the goal (stuck)"
        } else {
            "did NOT reach the goal"
        };
        let touch = match contacts {
            0 => "no contact".to_string(),
            1 => "1 CONTACT with a truly blocked cell".to_string(),
            n => format!("{n} CONTACTS with truly blocked cells"),
        };
        Some(format!(
            "{end} in {:.1} s, {touch}",
            m.nav.time_s.unwrap_or(f64::NAN)
        ))
    }

    /// The map's wrong cells, in words: `847 unsafe (415 observable, 432 blind), 0 uncertain, 4074
    /// over-cautious`.
    pub fn cells_text(&self) -> String {
        let m = &self.metrics;
        format!(
            "{} unsafe ({} a ray could have told about, {} blind), {} uncertain, {} over-cautious of {} scored cells",
            m.unsafe_cells,
            m.unsafe_observable_cells,
            m.blind_cells,
            m.uncertain_cells,
            m.overcautious_cells,
            m.num_scored_cells
        )
    }

    /// The regression bounds, in words: `all 9 hold`, `1 of 9 fail: plan_length_ratio = 1.032 (required <=
    /// 1.02)`, or `none set`.
    pub fn bounds_text(&self) -> String {
        let failed: Vec<String> = self
            .failed_bounds()
            .map(|r| {
                format!(
                    "{} = {} (required {})",
                    r.metric,
                    field(&r.measured.to_string()),
                    r.required
                )
            })
            .collect();
        match (self.bounds.len(), failed.len()) {
            (0, _) => "none set".into(),
            (n, 0) => format!("all {n} hold"),
            (n, f) => format!("{f} of {n} FAIL: {}", failed.join("; ")),
        }
    }

    /// The outcome in a few lines for a terminal: the drive, the cells, the bounds.
    pub fn lines(&self) -> Vec<String> {
        let mut lines = vec![format!(
            "{} model: {}; planned path {}",
            self.model,
            self.safety.name().to_uppercase(),
            self.path_text()
        )];
        if let Some(drive) = self.drive_text() {
            lines.push(format!("  closed loop: {drive}"));
        }
        lines.push(format!("  cells: {}", self.cells_text()));
        lines.push(format!("  regression bounds: {}", self.bounds_text()));
        lines
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::judge::metrics::test_metrics;
    use sim::scenario::Expectation;

    fn bound(max: f64) -> BTreeMap<String, Expectation> {
        BTreeMap::from([(
            "plan_length_ratio".to_string(),
            Expectation {
                min: None,
                max: Some(max),
            },
        )])
    }

    #[test]
    fn an_unsafe_path_is_unsafe_whatever_the_bounds_say() {
        let mut m = test_metrics();
        m.plan_unsafe_cells = 16;
        m.plan_blind_cells = 3;
        let o = Outcome::new("paper", &m, &bound(10.0));
        assert_eq!(o.safety, Safety::Unsafe);
        assert_eq!(o.bounds_text(), "all 1 hold");
        assert!(o.lines()[0].starts_with("paper model: UNSAFE; planned path UNSAFE: 16 path cells"));
        assert!(o.path_text().contains("3 of them blind"));
    }

    #[test]
    fn a_contact_makes_a_closed_loop_unsafe_and_a_failed_bound_is_named() {
        let mut m = test_metrics();
        m.nav.reached = Some(true);
        m.nav.contacts = Some(1);
        m.plan_length_ratio = 1.032;
        let o = Outcome::new("robust", &m, &bound(1.02));
        assert_eq!(o.safety, Safety::Unsafe);
        assert!(o.drive_text().expect("a closed loop").contains("1 CONTACT"));
        assert_eq!(
            o.bounds_text(),
            "1 of 1 FAIL: plan_length_ratio = 1.032 (required <= 1.02)"
        );
    }

    #[test]
    fn no_path_and_an_unreached_goal_are_no_path() {
        let mut m = test_metrics();
        m.plan_found = false;
        assert_eq!(Safety::of(&m), Safety::NoPath);
        let mut m = test_metrics();
        m.nav.reached = Some(false);
        m.nav.contacts = Some(0);
        assert_eq!(Safety::of(&m), Safety::NoPath);
        assert_eq!(Safety::of(&test_metrics()), Safety::Safe);
    }

    #[test]
    fn no_path_names_the_cells_that_closed_the_way_and_a_path_ignores_them() {
        let closed_by =
            "closed by 1 cell the map cannot decide (1 frontier); the truth: 1 drivable, 0 blocked";
        let mut m = test_metrics();
        m.plan_found = false;
        m.truth_plan_found = true;
        let o = Outcome::new("robust", &m, &bound(10.0)).with_closed_by(Some(closed_by.into()));
        assert_eq!(
            o.path_text(),
            format!("no path on the map (the truth has one): {closed_by}")
        );
        assert_eq!(
            Outcome::new("robust", &m, &bound(10.0)).path_text(),
            "no path on the map (the truth has one)"
        );
        m.observable_truth_plan_found = Some(false);
        assert_eq!(
            Outcome::new("robust", &m, &bound(10.0)).path_text(),
            "no path on the map (the truth has one, none through what the rays reached)"
        );
        let found =
            Outcome::new("robust", &test_metrics(), &bound(10.0)).with_closed_by(Some(closed_by.into()));
        assert!(!found.path_text().contains("closed by"), "{}", found.path_text());
    }
}
