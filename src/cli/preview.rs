//! `oeg preview`: a scenario's truth, drive and sensors, drawn before running it.

use std::path::PathBuf;

/// `oeg preview`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct PreviewArgs {
    /// A scenario file (.toml).
    scenario: PathBuf,
    /// Output folder.
    #[arg(long, default_value = "out/preview")]
    out: PathBuf,
    /// Also write each figure as SVG beside its PNG, for papers.
    #[arg(long)]
    svg: bool,
}

/// Draws the preview and names the files written.
pub(crate) fn run(args: &PreviewArgs) -> anyhow::Result<()> {
    for f in oeg_eval::jobs::preview::preview(
        &args.scenario,
        &args.out,
        oeg_eval::figures::ImageFormats { svg: args.svg },
    )? {
        say!("wrote {}", f.display());
    }
    Ok(())
}
