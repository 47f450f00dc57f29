//! Progress of long work on standard error: a bar with the time left on a terminal, and under CI or into a
//! log file (standard error is not a terminal) a plain line at most every [`PLAIN_INTERVAL`] with the same
//! figures, so a 36-minute run says how far it is wherever it runs. A caller that can be interrupted (the
//! Python package on Ctrl-C) cancels the work through the same counter ([`Progress::cancel`]).

use std::io::IsTerminal as _;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How often a plain progress line is printed when standard error is not a terminal.
pub const PLAIN_INTERVAL: Duration = Duration::from_secs(30);

/// How progress is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// A bar redrawn in place (a terminal).
    Bar,
    /// A line every [`PLAIN_INTERVAL`] (CI, a log file).
    Lines,
    /// Nothing (library callers, tests, nested work).
    Hidden,
}

/// A progress counter of `len` steps shown on standard error (see the module).
#[derive(Debug, Clone)]
pub struct Progress {
    bar: ProgressBar,
    mode: Mode,
    unit: Arc<std::sync::Mutex<String>>,
    started: Instant,
    /// Milliseconds after `started` of the last plain line.
    last_line_ms: Arc<AtomicU64>,
    /// Set by [`Progress::cancel`], shared by every clone.
    cancelled: Arc<AtomicBool>,
    /// Every position the counter reached, in order (tests read how work was counted).
    #[cfg(test)]
    pub(crate) steps: Arc<std::sync::Mutex<Vec<u64>>>,
}

impl Progress {
    /// A counter of `len` steps, `unit` naming them ("scans"), with the time left.
    pub fn new(len: u64, unit: &str) -> Self {
        let mode = if std::io::stderr().is_terminal() {
            Mode::Bar
        } else {
            Mode::Lines
        };
        Self::with_mode(len, unit, mode)
    }

    /// A counter that never shows (for library callers and tests).
    pub fn hidden() -> Self {
        Self::with_mode(0, "", Mode::Hidden)
    }

    fn with_mode(len: u64, unit: &str, mode: Mode) -> Self {
        let target = if mode == Mode::Bar {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        let bar = ProgressBar::with_draw_target(Some(len), target);
        let progress = Self {
            bar,
            mode,
            unit: Arc::new(std::sync::Mutex::new(unit.to_string())),
            started: Instant::now(),
            last_line_ms: Arc::new(AtomicU64::new(0)),
            cancelled: Arc::new(AtomicBool::new(false)),
            #[cfg(test)]
            steps: Arc::default(),
        };
        progress.style();
        progress
    }

    /// The bar's look: the time left only once a step is done (before that there is nothing to estimate it
    /// from, and a bar that says "ETA 0s" or "ETA 69m" at its start misleads).
    fn style(&self) {
        let unit = self.unit();
        let eta = if self.bar.position() > 0 {
            "ETA {eta}"
        } else {
            "ETA after the first step"
        };
        let template = if self.bar.length().unwrap_or(0) == 0 {
            // No total known (yet): the count alone.
            format!("{{spinner}} [{{elapsed_precise}}] {{pos}} {unit} {{msg}}")
        } else {
            format!("{{spinner}} [{{elapsed_precise}}] {{bar:40}} {{pos}}/{{len}} {unit}, {eta} {{msg}}")
        };
        if let Ok(style) = ProgressStyle::with_template(&template) {
            self.bar.set_style(style);
        }
    }

    fn unit(&self) -> String {
        self.unit.lock().map(|u| u.clone()).unwrap_or_default()
    }

    /// Counts in another unit from now on (a closed loop counts simulated time, not scans).
    pub fn set_unit(&self, unit: &str) {
        if let Ok(mut u) = self.unit.lock() {
            *u = unit.to_string();
        }
        self.style();
    }

    /// Asks the work counted here (and by every clone) to stop: it ends at its next step with
    /// [`crate::error::EvalError::Cancelled`], leaving no output behind.
    pub fn cancel(&self) {
        self.cancelled.store(true, Ordering::Relaxed);
    }

    /// `Err(Cancelled)` once [`Progress::cancel`] was called: long loops check it at every step.
    ///
    /// # Errors
    /// The work was cancelled.
    pub fn check_cancelled(&self) -> crate::error::Result<()> {
        if self.cancelled.load(Ordering::Relaxed) {
            Err(crate::error::EvalError::Cancelled)
        } else {
            Ok(())
        }
    }

    /// Set the number of steps.
    pub fn set_length(&self, len: u64) {
        let had = self.bar.length().unwrap_or(0) > 0;
        self.bar.set_length(len);
        if had != (len > 0) && self.mode == Mode::Bar {
            self.style();
        }
    }

    /// Advance by `n` steps.
    pub fn inc(&self, n: u64) {
        let first = self.bar.position() == 0;
        self.bar.inc(n);
        self.after_step(first);
    }

    /// Move to step `pos` (a closed loop's simulated time).
    pub fn set_position(&self, pos: u64) {
        let first = self.bar.position() == 0;
        self.bar.set_position(pos);
        self.after_step(first);
    }

    /// The time left appears with the first step done; a plain line is due every [`PLAIN_INTERVAL`].
    fn after_step(&self, first: bool) {
        #[cfg(test)]
        if let Ok(mut steps) = self.steps.lock() {
            steps.push(self.bar.position());
        }
        if first && self.bar.position() > 0 && self.mode == Mode::Bar {
            self.style();
        }
        if self.mode == Mode::Lines {
            let now_ms = self.started.elapsed().as_millis() as u64;
            let last = self.last_line_ms.load(Ordering::Relaxed);
            let due = now_ms.saturating_sub(last) >= PLAIN_INTERVAL.as_millis() as u64;
            // One thread prints each line, however many advance the counter at once.
            if due
                && self
                    .last_line_ms
                    .compare_exchange(last, now_ms, Ordering::Relaxed, Ordering::Relaxed)
                    .is_ok()
            {
                eprintln!("{}", self.line());
            }
        }
    }

    /// The plain line: `progress: 120/400 scans (30 %), 0:01:05 elapsed, about 0:02:31 left`.
    fn line(&self) -> String {
        let (pos, len) = (self.bar.position(), self.bar.length().unwrap_or(0));
        let elapsed = self.started.elapsed();
        let message = self.bar.message();
        let message = if message.is_empty() {
            String::new()
        } else {
            format!(" ({message})")
        };
        if len == 0 || pos > len {
            // The total is not known: the count and the time, no share and no time left.
            return format!(
                "progress: {pos} {}, {} elapsed{message}",
                self.unit(),
                hms(elapsed)
            );
        }
        let left = if pos > 0 && len >= pos {
            hms(elapsed.mul_f64((len - pos) as f64 / pos as f64))
        } else {
            "unknown (until the first step is done)".into()
        };
        let percent = (100 * pos).checked_div(len).unwrap_or(0);
        format!(
            "progress: {pos}/{len} {} ({percent} %), {} elapsed, about {left} left{message}",
            self.unit(),
            hms(elapsed),
        )
    }

    /// Show a short message after the bar (and in the plain lines).
    pub fn message(&self, msg: String) {
        self.bar.set_message(msg);
    }

    /// Remove the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// `h:mm:ss`.
fn hms(d: Duration) -> String {
    let s = d.as_secs();
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_run_says_how_far_it_is_and_the_time_left_without_a_terminal() {
        let p = Progress::with_mode(400, "scans", Mode::Lines);
        p.bar.set_position(100);
        let line = p.line();
        assert!(
            line.starts_with("progress: 100/400 scans (25 %), 0:00:00 elapsed, about "),
            "{line}"
        );
        assert!(line.ends_with(" left"), "{line}");
        assert_eq!(hms(Duration::from_secs(2 * 3600 + 3 * 60 + 4)), "2:03:04");
        let none = Progress::with_mode(400, "scans", Mode::Lines);
        assert!(
            none.line()
                .contains("about unknown (until the first step is done) left"),
            "{}",
            none.line()
        );
    }
}
