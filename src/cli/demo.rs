//! `oeg demo`: the built-in demonstration scans, mapped.

use std::path::PathBuf;

use oeg_eval::progress::Progress;

use super::map::{MapArgs, print_report};

/// `oeg demo`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "out/demo")]
    out: PathBuf,
}

/// Maps the demonstration scans at 5 cm and says what was written.
pub(crate) fn run(args: &DemoArgs) -> anyhow::Result<()> {
    let map_args = MapArgs {
        inputs: Vec::new(),
        resolution: 0.05,
        out: args.out.clone(),
        overrides: vec!["map.model.max_height_m=0.5".into()],
        planner_files: true,
        svg: false,
        memory_limit_mib: oeg::DEFAULT_MEMORY_LIMIT_BYTES >> 20,
    };
    let report = oeg_eval::jobs::map::demo::run(map_args.job()?, &Progress::new(0, "scans"))?;
    print_report(&report);
    say!(
        "kept the scans as {} (synthetic scans of a scene with a 3 cm and a 5 cm curb and a board at 0.35 m)",
        args.out.join("demo.graph").display()
    );
    Ok(())
}
