//! ROS 2 bags (rosbag2 with MCAP storage, the default since ROS 2 Iron): range data in, and the testbed's scans
//! out.
//!
//! **Reading** ([`read_bag`]): a bag's `.mcap` file, or its folder with `metadata.yaml` (its
//! `relative_file_paths`, in order). Chunks may be uncompressed, zstd or lz4 (decoded in pure Rust). Messages
//! are CDR: `sensor_msgs/PointCloud2` (the fields `x`, `y`, `z` by name, FLOAT32 or FLOAT64; padding and other
//! fields skipped; NaN points of a cloud that is not dense left out) and `sensor_msgs/LaserScan` (a reading
//! within `[range_min, range_max]` a hit, one beyond `range_max` or infinite a no-return ray that clears to
//! `range_max`, NaN and readings under `range_min` left out) become scans; `tf2_msgs/TFMessage` on `/tf` and
//! `/tf_static`, and optionally `nav_msgs/Odometry` (its pose as the transform from its frame to its child),
//! make the transform tree. Each scan's frame is looked up in the map frame at the message's stamp (its log
//! time when the stamp is zero, as tf2 takes time 0 to mean "latest"): stamped transforms are interpolated,
//! and the tree is walked through every intermediate frame. A scan whose transform is missing, or outside the
//! stamped transforms by more than the tolerance, is skipped and counted with the reason ([`BagSkip`]). The
//! cloud's frame is the sensor's: its origin is where the rays start.
//!
//! **Writing** ([`BagWriter`]): clouds as `PointCloud2` and transforms as `TFMessage`, with the message
//! definitions in the schemas, so that `ros2 bag info`, Foxglove and the Python `rosbags` package read it.
//!
//! Every size is checked before it is allocated: a chunk's uncompressed size against the memory limit, a
//! message's counts against its bytes, a cloud's `width * height * point_step` against its data.

mod cdr;
mod cloud;
mod container;
mod grid_map;
mod msgs;
mod scans;
mod schemas;
mod tf;
mod write;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use self::cloud::{CLOUD_CLEAR_FIELDS, CLOUD_RANGE_SIGMA_FIELD};
use self::container::{Channel, Channels, for_each_message, read_bag_files, topic_list};
pub use self::grid_map::{GridMapLayers, MAX_GRID_MAP_CELLS, parse_grid_map, read_grid_map};
use self::msgs::{ODOMETRY, TF_MESSAGE, is_type};
use self::scans::{ScanReader, range_topics, stamp_or_log_time};
use self::tf::TfTree;
pub use self::write::{BagRaster, BagTransform, BagWriter, CloudPrecision};
use crate::error::{Error, Result};
use crate::scan::Scan;
use crate::sensor::SensorModel;

/// How a bag becomes scans. The defaults map every `PointCloud2` and `LaserScan` topic in the frame `map`, or
/// `odom` when the transforms name no `map`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BagOptions {
    /// The range topics to map; empty: every `PointCloud2` and `LaserScan` topic.
    pub topics: Vec<String>,
    /// The frame the map is built in; none: `map`, else `odom`.
    pub map_frame: Option<String>,
    /// `nav_msgs/Odometry` topics whose poses join the transform tree (frame -> child frame); none by default.
    pub odometry_topics: Vec<String>,
    /// Seconds after the bag's first message (by log time) before which messages are skipped.
    pub start_s: Option<f64>,
    /// Seconds after the bag's first message after which messages are skipped.
    pub end_s: Option<f64>,
    /// Every how many messages of a range topic one is mapped (1: all).
    pub stride: u32,
    /// How far a scan's stamp may lie outside its stamped transforms, seconds, and the nearest be used (tf2
    /// does not extrapolate: 0).
    pub tf_tolerance_s: f64,
    /// The range error of `PointCloud2` points (a lidar's, by default).
    pub cloud_sensor: SensorModel,
    /// The range error of `LaserScan` readings; its range is each message's `range_max`.
    pub laser_sensor: SensorModel,
    /// The frame whose origin lies on the ground under the robot, REP 120's `base_footprint` (the default):
    /// where the bag's transforms hold it, each scan's height threshold is measured from that origin's height
    /// in the map frame at the scan's stamp ([`Scan::ground_z_m`]), as `oeg run` measures it from the ground
    /// under the robot's wheels, and a scan without that transform is skipped like one without its sensor's.
    /// A bag without the frame thresholds in the map frame's z.
    pub ground_frame: String,
}

/// The default [`BagOptions::ground_frame`]: REP 120's frame on the ground under the robot.
pub const DEFAULT_GROUND_FRAME: &str = "base_footprint";

impl Default for BagOptions {
    fn default() -> Self {
        Self {
            topics: Vec::new(),
            map_frame: None,
            odometry_topics: Vec::new(),
            start_s: None,
            end_s: None,
            stride: 1,
            tf_tolerance_s: 0.0,
            cloud_sensor: SensorModel::laser(),
            laser_sensor: SensorModel::laser(),
            ground_frame: DEFAULT_GROUND_FRAME.into(),
        }
    }
}

/// One scan of a bag, with where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct BagScan {
    /// The topic.
    pub topic: String,
    /// The message's place on its topic, from 0, in the bag's order.
    pub index: u64,
    /// The scan, in the map frame; its `stamp_s` is the message's stamp, seconds since the epoch.
    pub scan: Scan,
}

/// Messages of a range topic that were not mapped, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BagSkip {
    /// The topic.
    pub topic: String,
    /// Why, the first message's reason in words.
    pub reason: String,
    /// How many messages.
    pub count: u64,
}

/// A bag's range data as scans, and what was left out.
#[derive(Debug, Clone, PartialEq)]
pub struct Bag {
    /// The frame the scans are in.
    pub map_frame: String,
    /// Every topic with its type and message count, as the bag's channels name them.
    pub topics: Vec<(String, String, u64)>,
    /// The scans, in the bag's order.
    pub scans: Vec<BagScan>,
    /// Range messages skipped for a missing transform or no valid reading, by topic and reason.
    pub skipped: Vec<BagSkip>,
    /// Range messages outside the time range or the stride.
    pub num_not_selected: u64,
    /// The frame the scans' height thresholds are measured from ([`BagOptions::ground_frame`]), or `None`
    /// where the bag's transforms do not hold it (the map frame's z).
    pub ground_frame: Option<String>,
}

/// Reads a bag's range data into scans in the map frame ([`BagOptions`]).
///
/// # Errors
/// [`Error::Io`] for a file that cannot be read; [`Error::Parse`] naming the file, and the topic, the
/// message's index and the field where a message is at fault, for a corrupt container or chunk, a message that
/// does not decode, a transform tree with a cycle, or options that name what the bag does not hold.
pub fn read_bag(path: &Path, options: &BagOptions) -> Result<Bag> {
    read_bag_within(path, options, crate::DEFAULT_MEMORY_LIMIT_BYTES)
}

/// [`read_bag`], with at most `limit_bytes` of memory for a file and a decompressed chunk.
///
/// # Errors
/// As [`read_bag`], and [`Error::Parse`] for a file or chunk over the limit.
pub fn read_bag_within(path: &Path, options: &BagOptions, limit_bytes: u64) -> Result<Bag> {
    check_options(path, options)?;
    parse_files(path, &read_bag_files(path, limit_bytes)?, options, limit_bytes)
}

/// [`read_bag_within`] for one MCAP file's bytes, `data`, named `path` in errors.
///
/// # Errors
/// As [`read_bag`].
pub fn parse_bag(path: &Path, data: &[u8], options: &BagOptions, limit_bytes: u64) -> Result<Bag> {
    check_options(path, options)?;
    parse_files(path, &[(path.to_path_buf(), data.to_vec())], options, limit_bytes)
}

/// The bag at `path` from its files' bytes, in order.
fn parse_files(
    path: &Path,
    data: &[(PathBuf, Vec<u8>)],
    options: &BagOptions,
    limit_bytes: u64,
) -> Result<Bag> {
    // First pass: the channels, the transform tree and the bag's first log time.
    let mut channels = Channels::default();
    let mut tree = TfTree::default();
    let mut first_log_ns = u64::MAX;
    let mut counts: BTreeMap<u16, u64> = BTreeMap::new();
    for_each_message(
        data,
        limit_bytes,
        &mut channels,
        &mut |file, c, header, message| {
            first_log_ns = first_log_ns.min(header.log_time);
            let index = bump(&mut counts, header.channel_id);
            add_transforms(&mut tree, c, options, header.log_time, message)
                .map_err(|e| message_error(file, c, index, &e))
        },
    )?;
    tree.finish();
    let topics = topic_list(&channels, &counts);
    let ranges = range_topics(path, options, &channels)?;
    let map_frame = match &options.map_frame {
        Some(f) => f.clone(),
        None if tree.has_frame("map") => "map".into(),
        None if tree.has_frame("odom") => "odom".into(),
        None => {
            return Err(Error::parse(
                path,
                "the transforms name neither `map` nor `odom`: choose the map frame (`input.bag.map_frame` of \
                 `oeg map`, `BagOptions::map_frame`)",
            ));
        }
    };
    if !tree.has_frame(&map_frame) {
        return Err(Error::parse(
            path,
            format!(
                "the map frame `{map_frame}` is not in the transforms, which name {}",
                tree.frames()
            ),
        ));
    }
    // Second pass: the scans.
    let ground_frame = tree
        .has_frame(&options.ground_frame)
        .then(|| options.ground_frame.clone());
    let mut reader = ScanReader {
        options,
        tree: &tree,
        map_frame: &map_frame,
        first_log_ns,
        bag: Bag {
            map_frame: map_frame.clone(),
            topics,
            scans: Vec::new(),
            skipped: Vec::new(),
            num_not_selected: 0,
            ground_frame,
        },
    };
    counts.clear();
    for_each_message(
        data,
        limit_bytes,
        &mut Channels::default(),
        &mut |file, c, header, message| {
            let index = bump(&mut counts, header.channel_id);
            if !ranges.contains(&c.topic) {
                return Ok(());
            }
            reader
                .message(c, index, header.log_time, message)
                .map_err(|e| message_error(file, c, index, &e))
        },
    )?;
    Ok(reader.bag)
}

fn bump(counts: &mut BTreeMap<u16, u64>, channel: u16) -> u64 {
    let n = counts.entry(channel).or_default();
    *n += 1;
    *n - 1
}

fn message_error(file: &Path, c: &Channel, index: u64, e: &str) -> Error {
    Error::parse(
        file,
        format!("topic {} ({}), message {index}: {e}", c.topic, c.kind),
    )
}

fn check_options(path: &Path, o: &BagOptions) -> Result<()> {
    let bad = |what: String| Err(Error::parse(path, format!("bag options: {what}")));
    if o.stride == 0 {
        return bad("stride must be at least 1".into());
    }
    if !(o.tf_tolerance_s.is_finite() && o.tf_tolerance_s >= 0.0) {
        return bad(format!("tf_tolerance_s must be >= 0 s, got {}", o.tf_tolerance_s));
    }
    for (name, v) in [("start_s", o.start_s), ("end_s", o.end_s)] {
        if v.is_some_and(|v| !v.is_finite()) {
            return bad(format!("{name} must be a finite number of seconds"));
        }
    }
    o.cloud_sensor.validate().and(o.laser_sensor.validate())
}

/// Adds a message's transforms to the tree, when it carries any.
fn add_transforms(
    tree: &mut TfTree,
    c: &Channel,
    options: &BagOptions,
    log_time: u64,
    message: &[u8],
) -> std::result::Result<(), String> {
    let transforms = if is_type(&c.kind, TF_MESSAGE) {
        msgs::decode_tf(message).map_err(|e| e.to_string())?
    } else if is_type(&c.kind, ODOMETRY) && options.odometry_topics.contains(&c.topic) {
        vec![msgs::decode_odometry(message).map_err(|e| e.to_string())?]
    } else {
        return Ok(());
    };
    let is_static = c.topic.ends_with("tf_static");
    for t in transforms {
        let stamp = (!is_static).then(|| stamp_or_log_time(t.header.stamp_ns, log_time));
        tree.add(&t.header.frame_id, &t.child_frame_id, stamp, t.transform)?;
    }
    Ok(())
}
