//! One file per command: its arguments (clap's derive) and the few lines that call the job in `oeg_eval` and
//! print what it did.

pub mod check_path;
pub mod demo;
pub mod inspect;
pub mod map;
pub mod plan;
pub mod preview;
pub mod record;
pub mod run;
pub mod score;
pub mod suite;
pub mod sweep;
pub mod validate;

/// A command's answer that is not success and not an error, with its own exit status (`oeg plan`'s "no
/// path" is 3): `main` prints the message and exits with the code.
#[derive(Debug)]
pub struct Status {
    /// The exit status.
    pub code: u8,
    /// What to print.
    pub message: String,
}

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Status {}

/// Prints each failed expectation and fails, so that the command exits non-zero (after its files are written).
fn fail_on_expectations(failed: &[oeg_eval::judge::metrics::FailedExpectation]) -> anyhow::Result<()> {
    if failed.is_empty() {
        return Ok(());
    }
    for f in failed {
        eprintln!("expectation failed: {f}");
    }
    anyhow::bail!("{} of the scenario's expectations failed", failed.len())
}
