//! `oeg sweep bench`: what a study costs, and what sharing simulations saves. Runs the whole plan into
//! temporary folders, alternately with shared simulations and with one simulation per run, and prints the
//! median wall times, runs per hour and the speed-up (the median of the pairwise ratios, so that a machine whose
//! speed drifts during the measurement still gives a fair ratio).

use std::path::PathBuf;
use std::time::Instant;

use super::execute::{ExecuteOptions, run};
use super::plan::SweepPlan;
use crate::error::{EvalError, Result};
use crate::progress::Progress;

/// The measured figures.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchFigures {
    /// Runs in the plan.
    pub num_runs: usize,
    /// Simulations when shared.
    pub num_shared_simulations: usize,
    /// Wall seconds of each repetition with shared simulations.
    pub shared_s: Vec<f64>,
    /// Wall seconds of each repetition with one simulation per run (empty without the comparison).
    pub each_s: Vec<f64>,
}

/// The median of `v` (NaN when empty).
pub fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.to_vec();
    s.sort_by(f64::total_cmp);
    match s.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => s[n / 2],
        n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}

impl BenchFigures {
    /// Runs per hour with shared simulations (median repetition).
    pub fn runs_per_hour(&self) -> f64 {
        self.num_runs as f64 * 3600.0 / median(&self.shared_s)
    }

    /// The figures as lines of text: each way's median, minimum and maximum, runs per hour, the speed-up.
    pub fn lines(&self) -> Vec<String> {
        let spread = |v: &[f64]| {
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            format!("median {:.2} s (min {lo:.2}, max {hi:.2})", median(v))
        };
        let mut out = vec![format!(
            "shared simulations ({}): {}; {:.0} runs per hour",
            self.num_shared_simulations,
            spread(&self.shared_s),
            self.runs_per_hour()
        )];
        if !self.each_s.is_empty() {
            out.push(format!(
                "one simulation per run ({}): {}; {:.0} runs per hour",
                self.num_runs,
                spread(&self.each_s),
                self.num_runs as f64 * 3600.0 / median(&self.each_s)
            ));
            out.push(format!(
                "speed-up of sharing: {:.2}x (median of the pairwise ratios)",
                self.speed_up()
            ));
        }
        out
    }

    /// The median of the pairwise ratios one-simulation-per-run over shared.
    pub fn speed_up(&self) -> f64 {
        let ratios: Vec<f64> = self
            .each_s
            .iter()
            .zip(&self.shared_s)
            .map(|(e, s)| e / s)
            .collect();
        median(&ratios)
    }
}

/// Runs the plan `repeat` times each way (shared first, then one simulation per run, in turn).
///
/// # Errors
/// A failed run of the plan or a temporary folder that cannot be removed.
pub fn bench(plan: &SweepPlan, jobs: usize, repeat: usize, compare: bool) -> Result<BenchFigures> {
    let mut figures = BenchFigures {
        num_runs: plan.runs.len(),
        num_shared_simulations: plan.num_groups(),
        shared_s: Vec::new(),
        each_s: Vec::new(),
    };
    for k in 0..repeat.max(1) {
        for simulate_each in [false, true] {
            if simulate_each && !compare {
                continue;
            }
            let dir: PathBuf = std::env::temp_dir().join(format!(
                "oeg-sweep-bench-{}-{k}-{}",
                std::process::id(),
                u8::from(simulate_each)
            ));
            let _ = std::fs::remove_dir_all(&dir);
            let options = ExecuteOptions {
                out_dir: dir.clone(),
                shard: None,
                jobs,
                simulate_each,
            };
            let start = Instant::now();
            let result = run(plan, &options, &Progress::hidden());
            let seconds = start.elapsed().as_secs_f64();
            std::fs::remove_dir_all(&dir).map_err(|source| EvalError::Io { path: dir, source })?;
            result?;
            if simulate_each {
                figures.each_s.push(seconds);
            } else {
                figures.shared_s.push(seconds);
            }
        }
    }
    Ok(figures)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_are_medians_and_pairwise_ratios() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        let f = BenchFigures {
            num_runs: 6,
            num_shared_simulations: 1,
            shared_s: vec![10.0, 12.0, 11.0],
            each_s: vec![20.0, 18.0, 33.0],
        };
        // Ratios 2.0, 1.5, 3.0: median 2.0 (not 23 / 11).
        assert!((f.speed_up() - 2.0).abs() < 1e-12);
        assert!((f.runs_per_hour() - 6.0 * 3600.0 / 11.0).abs() < 1e-9);
        assert_eq!(f.lines().len(), 3);
    }
}
