//! `oeg record`: a scenario's scans, recorded.

use std::path::PathBuf;

use clap::ValueEnum;
use oeg_eval::jobs::record::{self, RecordFormat};
use oeg_eval::progress::Progress;

/// `oeg record`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct RecordArgs {
    /// A scenario file (.toml).
    scenario: PathBuf,
    /// The file to write (.oeglog, .graph with --format graph, .mcap with --format mcap), or the folder of a
    /// ROS 2 bag with --format rosbag2 or of a DynamicMap sequence with --format dynamicmap.
    #[arg(long)]
    out: PathBuf,
    /// log: the testbed's sensor log (both poses, no-returns, range errors); graph: OctoMap's scan graph
    /// (estimated pose, hits only) for other mappers; mcap: a recording for Foxglove (both poses, each
    /// sensor's returns, the truth's grid; docs/mcap.md); rosbag2: a ROS 2 bag (each sensor's scans as
    /// PointCloud2 with range errors and no-returns, the poses as /tf and /tf_static;
    /// docs/guide.md#from-your-robots-logs); dynamicmap: the
    /// DynamicMap benchmark's unified format (a folder: pcd/ frames in the world frame with each point's label,
    /// 1 for a moving actor, and gt_cloud.pcd).
    #[arg(long, value_enum, default_value_t = FormatArg::Log)]
    format: FormatArg,
    /// Replace the scenario's seed.
    #[arg(long)]
    seed: Option<u64>,
}

/// The formats `oeg record` writes.
#[derive(ValueEnum, Clone, Copy, Debug)]
#[value(rename_all = "snake_case")]
enum FormatArg {
    Log,
    Graph,
    Mcap,
    Rosbag2,
    Dynamicmap,
}

/// Records the scans and says what was written.
pub(crate) fn run(args: &RecordArgs) -> anyhow::Result<()> {
    let format = match args.format {
        FormatArg::Log => RecordFormat::Log,
        FormatArg::Graph => RecordFormat::Graph,
        FormatArg::Mcap => RecordFormat::Mcap,
        FormatArg::Rosbag2 => RecordFormat::Rosbag2,
        FormatArg::Dynamicmap => RecordFormat::DynamicMap,
    };
    let progress = Progress::new(0, "scans");
    let r = record::record(&args.scenario, &args.out, format, args.seed, &progress)?;
    say!(
        "recorded {} scans, {} rays in {:.2} s ({:.2} M simulated rays/s){}; wrote {}",
        r.num_scans,
        r.num_rays,
        r.wall_time_s,
        r.rays_per_s / 1e6,
        if r.num_rays_left_out > 0 {
            format!(
                ", {} no-return rays left out (a graph or a DynamicMap frame holds hits only)",
                r.num_rays_left_out
            )
        } else {
            String::new()
        },
        r.path.display()
    );
    Ok(())
}
