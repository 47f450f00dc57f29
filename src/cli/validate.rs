//! `oeg validate`: check scenario files.

use std::path::PathBuf;

use oeg_eval::jobs::preview;

/// `oeg validate`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct ValidateArgs {
    /// Scenario files (.toml).
    #[arg(required = true)]
    scenarios: Vec<PathBuf>,
}

/// Prints one line per file; fails if any is invalid.
pub(crate) fn run(args: &ValidateArgs) -> anyhow::Result<()> {
    let mut num_bad = 0;
    for path in &args.scenarios {
        match preview::validate(path) {
            Ok(loaded) => say!("{}", preview::describe(&loaded)),
            Err(e) => {
                num_bad += 1;
                eprintln!("error: {e}");
            }
        }
    }
    if num_bad > 0 {
        anyhow::bail!("{num_bad} of {} scenario files are invalid", args.scenarios.len());
    }
    Ok(())
}
