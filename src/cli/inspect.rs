//! `oeg inspect`: a saved map's header and statistics.

use std::io::Write as _;
use std::path::PathBuf;

/// `oeg inspect`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct InspectArgs {
    /// A map file written by `oeg map` (map.oeg).
    map: PathBuf,
}

/// Prints the map's header and statistics.
pub(crate) fn run(args: &InspectArgs) -> anyhow::Result<()> {
    let text = oeg_eval::jobs::inspect::inspect(&args.map)?;
    let _ = write!(std::io::stdout(), "{text}");
    Ok(())
}
