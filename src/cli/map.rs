//! `oeg map`: a map from recorded range data.

use std::path::PathBuf;

use oeg::MapConfig;
use oeg::PcdOptions;
use oeg_eval::jobs::map::{MapJob, MapReport};
use oeg_eval::progress::Progress;

/// `oeg map`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct MapArgs {
    /// Input files: .graph (OctoMap scan graph), .pcd (ascii, binary or binary_compressed), .oeglog (a
    /// sensor log of `oeg record`), a ROS 2 bag (its .mcap file or its folder), a KITTI sequence's folder
    /// (velodyne/, poses, calib.txt) or a DynamicMap sequence's folder (pcd/, world-frame frames).
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Cell size in metres (the setting map.resolution_m).
    #[arg(long)]
    pub resolution: f64,
    /// Output folder (created if needed).
    #[arg(long)]
    pub out: PathBuf,
    /// A setting by its scenario key (repeatable), e.g. --set map.model.max_height_m=0.5 or
    /// --set input.pcd_frame=optical: map.model.* (every model option), map.traversability, robot.max_step_m,
    /// robot.height_m, input.graph_sensor (laser|stereo), input.pcd_sensor (laser|stereo), input.pcd_frame
    /// (as_is|optical), input.pcd_points (sensor|world), input.pcd_invalid (drop|no_return), input.log_pose (estimated|true), input.bag.topics
    /// (["/points"]), input.bag.map_frame, input.bag.odometry, input.bag.start_s, input.bag.end_s,
    /// input.bag.stride, input.bag.tf_tolerance_s, input.bag.cloud_sensor, input.bag.ground_frame. Every key: docs/guide.md#settings-one-door.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub overrides: Vec<String>,
    /// Also write the files a planner reads over the observed region, in `planner/`: the decisions as a nav2
    /// map (PGM and YAML) and every layer as `.npy` (docs/planner-protocol.md). Dense: their size follows the
    /// region's extent.
    #[arg(long)]
    pub planner_files: bool,
    /// Also write each figure as SVG beside its PNG, for papers: lines and text as vectors, the map's cells
    /// as an image inside it.
    #[arg(long)]
    pub svg: bool,
    /// Memory limit of the map in MiB.
    #[arg(long, default_value_t = oeg::DEFAULT_MEMORY_LIMIT_BYTES >> 20)]
    pub memory_limit_mib: u64,
}

impl MapArgs {
    /// The job these arguments ask for, its settings resolved.
    pub(crate) fn job(&self) -> anyhow::Result<MapJob> {
        let settings = oeg_eval::settings::map_settings(self.resolution, &self.overrides)?;
        Ok(MapJob {
            inputs: self.inputs.clone(),
            out_dir: self.out.clone(),
            config: MapConfig {
                resolution_m: settings.map.resolution_m,
                model: settings.map.model,
                memory_limit_bytes: self.memory_limit_mib.saturating_mul(1 << 20),
            },
            graph_sensor: settings.input.graph_sensor.model(),
            pcd: PcdOptions {
                frame: settings.input.pcd_frame,
                points: settings.input.pcd_points,
                invalid_points: settings.input.pcd_invalid,
                sensor: settings.input.pcd_sensor.model(),
            },
            log_pose: settings.input.log_pose,
            bag: settings.input.bag.options(),
            profile: settings.robot,
            rule: settings.map.traversability,
            keep_inputs: false,
            planner_files: self.planner_files,
            figures: oeg_eval::figures::ImageFormats { svg: self.svg },
        })
    }
}

/// One line on the map and one per file written.
pub(crate) fn print_report(report: &MapReport) {
    let s = &report.summary;
    say!(
        "mapped {} scans, {} rays at {} m: {} cells observed ({} free, {} traversable, {} blocked), {} bytes; \
         integration {:.3} s ({:.2} M rays/s)",
        s.num_scans,
        s.num_rays,
        s.resolution_m,
        s.num_cells_observed,
        s.num_cells_free,
        s.num_cells_traversable,
        s.num_cells_blocked,
        s.map_bytes,
        report.timing.integrate_wall_time_s,
        report.timing.integrate_rays_per_s / 1e6
    );
    if let Some(h) = s.max_height_m {
        let (with, all) = (s.num_scans_with_ground, s.num_scans);
        if with == all {
            say!("height threshold {h} m over the ground under the robot at every scan");
        } else if with == 0 {
            say!(
                "height threshold {h} m over z = 0: no scan says where the ground under the robot was (a bag \
                 without `input.bag.ground_frame`, a scan graph, a point cloud)"
            );
        } else {
            say!(
                "height threshold {h} m over the ground under the robot at {with} of {all} scans, over z = 0 at the others"
            );
        }
    }
    for (bag, skip) in &report.skipped {
        say!(
            "skipped {} messages of {} in {}: {}",
            skip.count,
            skip.topic,
            bag.display(),
            skip.reason
        );
    }
    for f in &report.files {
        say!("wrote {}", f.display());
    }
}

/// Maps the inputs and says what was written.
pub(crate) fn run(args: &MapArgs) -> anyhow::Result<()> {
    let report = oeg_eval::jobs::map::run(&args.job()?, &Progress::new(0, "scans"))?;
    print_report(&report);
    Ok(())
}
