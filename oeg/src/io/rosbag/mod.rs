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
mod msgs;
mod tf;
mod write;

use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::{Path, PathBuf};

use mcap::records::Record;
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use self::msgs::{LASER_SCAN, LaserScan, ODOMETRY, POINT_CLOUD2, PointCloud2, TF_MESSAGE, is_type};
use self::tf::TfTree;
pub use self::write::{BagTransform, BagWriter, CloudPrecision};
use super::read_file;
use crate::error::{Error, Result};
use crate::scan::{Ray, Scan};
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
}

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
}

/// A channel of the bag, as its schema and channel records say.
struct Channel {
    topic: String,
    /// The message type, `package/msg/Name`.
    kind: String,
    encoding: String,
}

/// What each message of the bag is, by channel.
#[derive(Default)]
struct Channels {
    schemas: HashMap<u16, String>,
    channels: HashMap<u16, Channel>,
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
    let files = bag_files(path)?;
    let mut data = Vec::with_capacity(files.len());
    let mut left = limit_bytes;
    for f in &files {
        let bytes = read_file(f, left)?;
        left = left.saturating_sub(bytes.len() as u64);
        data.push((f.clone(), bytes));
    }
    parse_files(path, &data, options, limit_bytes)
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
    for (file, bytes) in data {
        for_each_message(
            file,
            bytes,
            limit_bytes,
            &mut channels,
            &mut |c, header, message| {
                first_log_ns = first_log_ns.min(header.log_time);
                let index = bump(&mut counts, header.channel_id);
                add_transforms(&mut tree, c, options, header.log_time, message)
                    .map_err(|e| message_error(file, c, index, &e))
            },
        )?;
    }
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
                "the transforms name neither `map` nor `odom`: choose the map frame (`input.bag_map_frame` of \
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
        },
    };
    counts.clear();
    for (file, bytes) in data {
        for_each_message(
            file,
            bytes,
            limit_bytes,
            &mut Channels::default(),
            &mut |c, header, message| {
                let index = bump(&mut counts, header.channel_id);
                if !ranges.contains(&c.topic) {
                    return Ok(());
                }
                reader
                    .message(c, index, header.log_time, message)
                    .map_err(|e| message_error(file, c, index, &e))
            },
        )?;
    }
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

/// The bag's files: the `.mcap` itself, or a folder's `metadata.yaml`'s `relative_file_paths`.
fn bag_files(path: &Path) -> Result<Vec<PathBuf>> {
    if !path.is_dir() {
        return Ok(vec![path.to_path_buf()]);
    }
    let metadata = path.join("metadata.yaml");
    let text = oeg_files::read_text(&metadata)?;
    let files = relative_file_paths(&text);
    if files.is_empty() {
        return Err(Error::parse(
            &metadata,
            "no `relative_file_paths` entries: is this a rosbag2 folder's metadata?",
        ));
    }
    Ok(files.into_iter().map(|f| path.join(f)).collect())
}

/// The entries of `relative_file_paths:` in a rosbag2 `metadata.yaml`, in block (`- a.mcap`) or flow
/// (`[a.mcap, b.mcap]`) style. The rest of the file is not read: the bag's own records say what it holds.
fn relative_file_paths(text: &str) -> Vec<String> {
    let unquote = |s: &str| s.trim().trim_matches(|c| c == '"' || c == '\'').to_string();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        let Some(rest) = line.trim_start().strip_prefix("relative_file_paths:") else {
            continue;
        };
        let indent = line.len() - line.trim_start().len();
        let rest = rest.trim();
        if let Some(flow) = rest.strip_prefix('[') {
            return flow
                .trim_end_matches(']')
                .split(',')
                .map(unquote)
                .filter(|s| !s.is_empty())
                .collect();
        }
        return lines
            .take_while(|l| {
                let t = l.trim_start();
                t.starts_with("- ") && l.len() - t.len() >= indent
            })
            .map(|l| unquote(&l.trim_start()[2..]))
            .collect();
    }
    Vec::new()
}

/// Calls `f` with every message of the file, chunks decompressed, with its channel.
fn for_each_message(
    file: &Path,
    bytes: &[u8],
    limit_bytes: u64,
    channels: &mut Channels,
    f: &mut dyn FnMut(&Channel, &mcap::records::MessageHeader, &[u8]) -> std::result::Result<(), Error>,
) -> Result<()> {
    let container = |e: mcap::McapError| Error::parse(file, format!("not a readable MCAP file: {e}"));
    for record in mcap::read::LinearReader::new(bytes).map_err(container)? {
        match record.map_err(container)? {
            Record::Chunk { header, data } => {
                let records = decompress(file, &header, &data, limit_bytes)?;
                for inner in mcap::read::LinearReader::sans_magic(&records) {
                    visit(file, inner.map_err(container)?, channels, f)?;
                }
            }
            other => visit(file, other, channels, f)?,
        }
    }
    Ok(())
}

fn visit(
    file: &Path,
    record: Record,
    channels: &mut Channels,
    f: &mut dyn FnMut(&Channel, &mcap::records::MessageHeader, &[u8]) -> std::result::Result<(), Error>,
) -> Result<()> {
    match record {
        Record::Schema { header, .. } => {
            channels.schemas.insert(header.id, header.name);
        }
        Record::Channel(c) => {
            let kind = channels.schemas.get(&c.schema_id).cloned().unwrap_or_default();
            channels.channels.insert(
                c.id,
                Channel {
                    topic: c.topic,
                    kind,
                    encoding: c.message_encoding,
                },
            );
        }
        Record::Message { header, data } => {
            let Some(c) = channels.channels.get(&header.channel_id) else {
                return Err(Error::parse(
                    file,
                    format!(
                        "a message on channel {} before that channel's record (a corrupt or truncated file?)",
                        header.channel_id
                    ),
                ));
            };
            f(c, &header, &data)?;
        }
        _ => {}
    }
    Ok(())
}

/// A chunk's records, decompressed (none, zstd or lz4) and checked against its declared size and CRC.
fn decompress(
    file: &Path,
    header: &mcap::records::ChunkHeader,
    data: &[u8],
    limit_bytes: u64,
) -> Result<Vec<u8>> {
    let size = header.uncompressed_size;
    let at = format!(
        "a chunk ({} compression, {size} bytes uncompressed)",
        header.compression
    );
    if size > limit_bytes {
        return Err(Error::parse(
            file,
            format!("{at}: over the memory limit of {limit_bytes} bytes"),
        ));
    }
    // Grown as it decodes: a lying size within the limit allocates no more than the data makes.
    let mut out = Vec::with_capacity((size as usize).min(data.len().saturating_mul(4)));
    let read = match header.compression.as_str() {
        "" => {
            out.extend_from_slice(data);
            Ok(out.len())
        }
        "zstd" => ruzstd::decoding::StreamingDecoder::new(data)
            .map_err(|e| std::io::Error::other(e.to_string()))
            .and_then(|d| d.take(size + 1).read_to_end(&mut out)),
        "lz4" => lz4_flex::frame::FrameDecoder::new(data)
            .take(size + 1)
            .read_to_end(&mut out),
        other => {
            return Err(Error::parse(
                file,
                format!("{at}: unknown compression `{other}` (expected none, zstd or lz4)"),
            ));
        }
    };
    read.map_err(|e| Error::parse(file, format!("{at}: corrupt compressed data: {e}")))?;
    if out.len() as u64 != size {
        return Err(Error::parse(
            file,
            format!(
                "{at}: decompresses to {} bytes, not the {size} it declares",
                out.len()
            ),
        ));
    }
    if header.uncompressed_crc != 0 && crc32fast::hash(&out) != header.uncompressed_crc {
        return Err(Error::parse(
            file,
            format!("{at}: its CRC does not match (corrupt)"),
        ));
    }
    Ok(out)
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

/// A header's stamp, or the log time for a zero stamp (tf2's "latest").
fn stamp_or_log_time(stamp_ns: i64, log_time: u64) -> i64 {
    if stamp_ns == 0 {
        i64::try_from(log_time).unwrap_or(i64::MAX)
    } else {
        stamp_ns
    }
}

fn topic_list(channels: &Channels, counts: &BTreeMap<u16, u64>) -> Vec<(String, String, u64)> {
    let mut topics: BTreeMap<(String, String), u64> = BTreeMap::new();
    for (id, c) in &channels.channels {
        *topics.entry((c.topic.clone(), c.kind.clone())).or_default() += counts.get(id).copied().unwrap_or(0);
    }
    topics.into_iter().map(|((t, k), n)| (t, k, n)).collect()
}

/// The range topics to map: those asked for, each checked, or every one of a range type.
fn range_topics(path: &Path, options: &BagOptions, channels: &Channels) -> Result<Vec<String>> {
    let is_range = |kind: &str| is_type(kind, POINT_CLOUD2) || is_type(kind, LASER_SCAN);
    let listed = || {
        let mut all: Vec<String> = channels
            .channels
            .values()
            .map(|c| format!("{} ({})", c.topic, c.kind))
            .collect();
        all.sort();
        all.dedup();
        all.join(", ")
    };
    for t in options.topics.iter().chain(&options.odometry_topics) {
        if !channels.channels.values().any(|c| &c.topic == t) {
            return Err(Error::parse(
                path,
                format!("no topic `{t}` in the bag; it holds {}", listed()),
            ));
        }
    }
    let mut topics = Vec::new();
    for c in channels.channels.values() {
        let chosen = if options.topics.is_empty() {
            is_range(&c.kind)
        } else {
            options.topics.contains(&c.topic)
        };
        if !chosen || topics.contains(&c.topic) {
            continue;
        }
        if !is_range(&c.kind) {
            return Err(Error::parse(
                path,
                format!(
                    "topic `{}` is a {}, not a PointCloud2 or LaserScan",
                    c.topic, c.kind
                ),
            ));
        }
        if c.encoding != "cdr" {
            return Err(Error::parse(
                path,
                format!("topic `{}` is encoded as `{}`, not CDR", c.topic, c.encoding),
            ));
        }
        topics.push(c.topic.clone());
    }
    if topics.is_empty() {
        return Err(Error::parse(
            path,
            format!(
                "no PointCloud2 or LaserScan topic in the bag; it holds {}",
                listed()
            ),
        ));
    }
    Ok(topics)
}

/// The second pass: each selected range message as a scan in the map frame.
struct ScanReader<'a> {
    options: &'a BagOptions,
    tree: &'a TfTree,
    map_frame: &'a str,
    first_log_ns: u64,
    bag: Bag,
}

impl ScanReader<'_> {
    fn message(
        &mut self,
        c: &Channel,
        index: u64,
        log_time: u64,
        data: &[u8],
    ) -> std::result::Result<(), String> {
        let o = self.options;
        let since_start_s = log_time.saturating_sub(self.first_log_ns) as f64 * 1e-9;
        let in_range =
            o.start_s.is_none_or(|s| since_start_s >= s) && o.end_s.is_none_or(|e| since_start_s <= e);
        if !in_range || index % u64::from(o.stride) != 0 {
            self.bag.num_not_selected += 1;
            return Ok(());
        }
        let (header, scan) = if is_type(&c.kind, POINT_CLOUD2) {
            let cloud = PointCloud2::decode(data).map_err(|e| e.to_string())?;
            let points = cloud.points().map_err(|e| e.to_string())?;
            (cloud.header, Readings::Points(points))
        } else {
            let laser = LaserScan::decode(data).map_err(|e| e.to_string())?;
            let readings = laser_readings(&laser);
            (laser.header, readings)
        };
        let stamp_ns = stamp_or_log_time(header.stamp_ns, log_time);
        let tolerance_ns = (o.tf_tolerance_s * 1e9).round() as i64;
        let pose = match self
            .tree
            .lookup(self.map_frame, &header.frame_id, stamp_ns, tolerance_ns)
        {
            Ok(p) => p,
            Err(reason) => {
                self.skip(
                    &c.topic,
                    format!(
                        "no transform from `{}` to `{}`: {reason}",
                        header.frame_id, self.map_frame
                    ),
                );
                return Ok(());
            }
        };
        let origin = Point3::from(pose.translation.vector);
        let mut out = Scan::new(origin, o.cloud_sensor);
        out.stamp_s = stamp_ns as f64 * 1e-9;
        match scan {
            Readings::Points(points) => {
                out.rays.reserve(points.len());
                for p in points {
                    out.push_hit(pose * Point3::from(p));
                }
            }
            Readings::Laser { range_max, rays } => {
                out.sensor = SensorModel {
                    max_range_m: range_max,
                    ..o.laser_sensor
                };
                out.rays.reserve(rays.len());
                for (v, hit) in rays {
                    if hit {
                        out.push_hit(pose * Point3::from(v));
                    } else {
                        out.rays.push(Ray::no_return((pose.rotation * v).cast::<f32>()));
                    }
                }
            }
        }
        if out.rays.is_empty() {
            self.skip(&c.topic, "no valid reading".into());
            return Ok(());
        }
        self.bag.scans.push(BagScan {
            topic: c.topic.clone(),
            index,
            scan: out,
        });
        Ok(())
    }

    fn skip(&mut self, topic: &str, reason: String) {
        // Counted by topic and the reason's kind (its text up to the first colon's detail).
        let kind = |r: &str| r.split(": ").take(1).collect::<String>();
        match self
            .bag
            .skipped
            .iter_mut()
            .find(|s| s.topic == topic && kind(&s.reason) == kind(&reason))
        {
            Some(s) => s.count += 1,
            None => self.bag.skipped.push(BagSkip {
                topic: topic.to_string(),
                reason,
                count: 1,
            }),
        }
    }
}

/// A range message's readings in its own frame.
enum Readings {
    Points(Vec<Vector3<f64>>),
    /// Each beam's vector (its reading, or its unit direction for a no-return) and whether it hit.
    Laser {
        range_max: f32,
        rays: Vec<(Vector3<f64>, bool)>,
    },
}

fn laser_readings(laser: &LaserScan) -> Readings {
    let rays = laser
        .ranges
        .iter()
        .enumerate()
        .filter_map(|(k, &r)| {
            let angle = f64::from(laser.angle_min) + k as f64 * f64::from(laser.angle_increment);
            let dir = Vector3::new(angle.cos(), angle.sin(), 0.0);
            if r.is_nan() || r < laser.range_min {
                None
            } else if r > laser.range_max {
                Some((dir, false))
            } else {
                Some((dir * f64::from(r), true))
            }
        })
        .collect();
    Readings::Laser {
        range_max: laser.range_max,
        rays,
    }
}

#[cfg(test)]
mod tests {
    use super::relative_file_paths;

    #[test]
    fn the_metadata_lists_its_files_in_either_style() {
        let block = "rosbag2_bagfile_information:\n  relative_file_paths:\n    - run_0.mcap\n    - 'run_1.mcap'\n  \
                     starting_time:\n    nanoseconds_since_epoch: 0\n";
        assert_eq!(relative_file_paths(block), ["run_0.mcap", "run_1.mcap"]);
        let flow = "rosbag2_bagfile_information:\n  relative_file_paths: [a.mcap, \"b.mcap\"]\n";
        assert_eq!(relative_file_paths(flow), ["a.mcap", "b.mcap"]);
        assert!(relative_file_paths("version: 5\n").is_empty());
    }
}
