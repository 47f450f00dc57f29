//! One file per command: its arguments (clap's derive) and the few lines that call the job in `oeg_eval` and
//! print what it did.

pub(crate) mod check_path;
pub(crate) mod demo;
pub(crate) mod inspect;
pub(crate) mod map;
pub(crate) mod plan;
pub(crate) mod preview;
pub(crate) mod record;
pub(crate) mod run;
pub(crate) mod score;
pub(crate) mod suite;
pub(crate) mod sweep;
pub(crate) mod validate;

/// A command's answer that is not success and not an error, with its own exit status (`oeg plan`'s "no
/// path" is 3): `main` prints the message and exits with the code.
#[derive(Debug)]
pub(crate) struct Status {
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
fn fail_on_expectations(failed: &[oeg_eval::judge::expectations::FailedExpectation]) -> anyhow::Result<()> {
    if failed.is_empty() {
        return Ok(());
    }
    for f in failed {
        eprintln!("expectation failed: {f}");
    }
    anyhow::bail!("{} of the scenario's expectations failed", failed.len())
}
