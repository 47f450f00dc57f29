//! Writing a ROS 2 bag: a folder with one MCAP file (profile `ros2`, CDR messages, `ros2msg` schemas) and the
//! `metadata.yaml` that `ros2 bag info` and the Python `rosbags` package open it by.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Vector3};

use super::cdr::CdrWriter;
use super::cloud::PointCloud2;
use super::msgs::{self, GRID_MAP, Header, OCCUPANCY_GRID, POINT_CLOUD2, TF_MESSAGE, TransformStamped};
use super::schemas;
use crate::error::{Error, Result};
use crate::io::write_atomically;

/// One transform for [`BagWriter::transforms`]: `parent_from_child` at `stamp_ns`.
#[derive(Debug, Clone, PartialEq)]
pub struct BagTransform {
    /// The parent frame.
    pub parent: String,
    /// The child frame.
    pub child: String,
    /// Nanoseconds since the epoch (ignored on `/tf_static`'s latched stamp: written as given).
    pub stamp_ns: i64,
    /// `parent_from_child`.
    pub transform: Isometry3<f64>,
}

/// The type of a written cloud's coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CloudPrecision {
    /// FLOAT32, as lidar drivers write them (12 bytes a point).
    Float32,
    /// FLOAT64 (24 bytes a point): coordinates kept to the bit.
    Float64,
}

/// The grid of a raster written to a bag ([`BagWriter::grid_map`], [`BagWriter::occupancy_grid`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BagRaster {
    /// The frame.
    pub frame: String,
    /// Nanoseconds since the epoch.
    pub stamp_ns: i64,
    /// World x and y of the lower-left corner of cell `[0, 0]`, metres.
    pub origin_xy_m: [f64; 2],
    /// Cell size, metres.
    pub resolution_m: f64,
    /// Rows (along y).
    pub rows: usize,
    /// Columns (along x).
    pub cols: usize,
}

impl BagRaster {
    fn header(&self) -> Header {
        Header {
            stamp_ns: self.stamp_ns,
            frame_id: self.frame.clone(),
        }
    }
}

/// A ROS 2 bag being written, held in memory until [`BagWriter::finish`] writes it whole.
pub struct BagWriter {
    folder: PathBuf,
    writer: mcap::Writer<Cursor<Vec<u8>>>,
    schemas: BTreeMap<&'static str, u16>,
    /// By topic: the channel, its type and its messages so far.
    channels: BTreeMap<String, (u16, &'static str, u64)>,
    first_ns: Option<i64>,
    last_ns: i64,
}

impl std::fmt::Debug for BagWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BagWriter")
            .field("folder", &self.folder)
            .finish_non_exhaustive()
    }
}

impl BagWriter {
    /// A bag that [`BagWriter::finish`] will write into `folder` (created if needed) as `<name>_0.mcap`
    /// (`name` the folder's) and `metadata.yaml`.
    ///
    /// # Errors
    /// [`Error::Parse`] if the folder has no name to give the file.
    pub fn new(folder: &Path) -> Result<Self> {
        if folder.file_name().is_none() {
            return Err(Error::parse(
                folder,
                "a bag's folder needs a name (its MCAP file is named after it)",
            ));
        }
        let writer = mcap::WriteOptions::new()
            .compression(None)
            .profile("ros2")
            .library("oeg")
            .create(Cursor::new(Vec::new()))
            .map_err(|e| mcap_error(folder, &e))?;
        Ok(Self {
            folder: folder.to_path_buf(),
            writer,
            schemas: BTreeMap::new(),
            channels: BTreeMap::new(),
            first_ns: None,
            last_ns: 0,
        })
    }

    fn channel(&mut self, topic: &str, kind: &'static str) -> Result<u16> {
        if let Some((id, k, _)) = self.channels.get(topic) {
            if *k != kind {
                return Err(Error::parse(
                    &self.folder,
                    format!("topic {topic} is a {k}, not a {kind}"),
                ));
            }
            return Ok(*id);
        }
        let schema = match self.schemas.get(kind) {
            Some(id) => *id,
            None => {
                let id = self
                    .writer
                    .add_schema(kind, "ros2msg", schemas::schema_text(kind).as_bytes())
                    .map_err(|e| mcap_error(&self.folder, &e))?;
                self.schemas.insert(kind, id);
                id
            }
        };
        // The ROS 2 profile's channel metadata: the QoS the topic was offered with, which `ros2 bag play`
        // offers again.
        let metadata = BTreeMap::from([("offered_qos_profiles".to_string(), offered_qos(topic))]);
        let id = self
            .writer
            .add_channel(schema, topic, "cdr", &metadata)
            .map_err(|e| mcap_error(&self.folder, &e))?;
        self.channels.insert(topic.to_string(), (id, kind, 0));
        Ok(id)
    }

    fn write(&mut self, topic: &str, kind: &'static str, stamp_ns: i64, data: &[u8]) -> Result<()> {
        let id = self.channel(topic, kind)?;
        let entry = self.channels.get_mut(topic).map(|c| &mut c.2);
        let sequence = entry.map_or(0, |n| {
            *n += 1;
            *n
        });
        let log_time = u64::try_from(stamp_ns).unwrap_or(0);
        self.first_ns = Some(self.first_ns.map_or(stamp_ns, |f| f.min(stamp_ns)));
        self.last_ns = self.last_ns.max(stamp_ns);
        let header = mcap::records::MessageHeader {
            channel_id: id,
            sequence: sequence as u32,
            log_time,
            publish_time: log_time,
        };
        self.writer
            .write_to_known_channel(&header, data)
            .map_err(|e| mcap_error(&self.folder, &e))
    }

    /// A `sensor_msgs/PointCloud2` of `points` (in `frame`, x y z of `precision`) on `topic`.
    ///
    /// # Errors
    /// [`Error::Parse`] if `topic` already carries another type.
    pub fn cloud(
        &mut self,
        topic: &str,
        frame: &str,
        stamp_ns: i64,
        points: &[Vector3<f64>],
        precision: CloudPrecision,
    ) -> Result<()> {
        self.cloud_with_fields(topic, frame, stamp_ns, (points, precision), &[])
    }

    /// [`BagWriter::cloud`] with FLOAT32 fields after x y z, one value a point each, such as
    /// [`crate::CLOUD_RANGE_SIGMA_FIELD`] and [`crate::CLOUD_CLEAR_FIELDS`].
    ///
    /// # Errors
    /// [`Error::Parse`] if `topic` already carries another type, or a field has not one value a point.
    pub fn cloud_with_fields(
        &mut self,
        topic: &str,
        frame: &str,
        stamp_ns: i64,
        (points, precision): (&[Vector3<f64>], CloudPrecision),
        fields: &[(&str, &[f32])],
    ) -> Result<()> {
        if let Some((name, values)) = fields.iter().find(|(_, v)| v.len() != points.len()) {
            return Err(Error::parse(
                &self.folder,
                format!(
                    "field `{name}` of a cloud on {topic} has {} values for {} points",
                    values.len(),
                    points.len()
                ),
            ));
        }
        let header = Header {
            stamp_ns,
            frame_id: frame.to_string(),
        };
        let float64 = precision == CloudPrecision::Float64;
        let data = PointCloud2::encode(&header, points, float64, fields);
        self.write(topic, POINT_CLOUD2, stamp_ns, &data)
    }

    /// A `tf2_msgs/TFMessage` of `transforms` on `topic` (`/tf`, or `/tf_static` for transforms that hold at
    /// every time), logged at `stamp_ns`.
    ///
    /// # Errors
    /// [`Error::Parse`] if `topic` already carries another type.
    pub fn transforms(&mut self, topic: &str, stamp_ns: i64, transforms: &[BagTransform]) -> Result<()> {
        let stamped: Vec<TransformStamped> = transforms
            .iter()
            .map(|t| TransformStamped {
                header: Header {
                    stamp_ns: t.stamp_ns,
                    frame_id: t.parent.clone(),
                },
                child_frame_id: t.child.clone(),
                transform: t.transform,
            })
            .collect();
        self.write(topic, TF_MESSAGE, stamp_ns, &msgs::encode_tf(&stamped))
    }

    /// A `grid_map_msgs/GridMap` of `layers` on `topic`: arrays of `raster.rows` x `raster.cols`, row 0 the min-y
    /// row and column 0 the min-x column (the layout [`crate::read_grid_map`] reads back), written as grid_map
    /// does (column-major, the circular buffer at its start).
    ///
    /// # Errors
    /// [`Error::Parse`] if `topic` already carries another type, or a layer is not `rows x cols` values.
    pub fn grid_map(&mut self, topic: &str, raster: &BagRaster, layers: &[(&str, &[f32])]) -> Result<()> {
        let (rows, cols) = (raster.rows, raster.cols);
        if let Some((name, _)) = layers.iter().find(|(_, v)| v.len() != rows * cols) {
            return Err(Error::parse(
                &self.folder,
                format!("layer {name} is not {rows} x {cols} values"),
            ));
        }
        let mut w = CdrWriter::new();
        raster.header().write(&mut w);
        let r = raster.resolution_m;
        let (length_x, length_y) = (cols as f64 * r, rows as f64 * r);
        w.f64(r);
        w.f64(length_x);
        w.f64(length_y);
        let centre = Isometry3::translation(
            raster.origin_xy_m[0] + length_x / 2.0,
            raster.origin_xy_m[1] + length_y / 2.0,
            0.0,
        );
        msgs::write_pose(&mut w, &centre);
        w.len(layers.len());
        for (name, _) in layers {
            w.string(name);
        }
        w.len(0);
        w.len(layers.len());
        // grid_map's (i, j) runs from the +x, +y corner: i along -x (its rows), j along -y (its columns).
        let (n_i, n_j) = (cols, rows);
        for (_, values) in layers {
            w.len(2);
            for (label, size, stride) in [("column_index", n_j, n_i * n_j), ("row_index", n_i, n_i)] {
                w.string(label);
                w.u32(size as u32);
                w.u32(stride as u32);
            }
            w.u32(0);
            let mut stored = Vec::with_capacity(n_i * n_j);
            for j in 0..n_j {
                for i in 0..n_i {
                    stored.push(values[(n_j - 1 - j) * cols + (n_i - 1 - i)]);
                }
            }
            w.f32s(&stored);
        }
        w.u16(0);
        w.u16(0);
        self.write(topic, GRID_MAP, raster.stamp_ns, &w.finish())
    }

    /// A `nav_msgs/OccupancyGrid` of `occupancy` (0 to 100, -1 unknown; `rows x cols`, row 0 the min-y row) on
    /// `topic`.
    ///
    /// # Errors
    /// [`Error::Parse`] if `topic` already carries another type, or `occupancy` is not `rows x cols` values.
    pub fn occupancy_grid(&mut self, topic: &str, raster: &BagRaster, occupancy: &[i8]) -> Result<()> {
        if occupancy.len() != raster.rows * raster.cols {
            return Err(Error::parse(
                &self.folder,
                format!("{topic}: not {} x {} cells", raster.rows, raster.cols),
            ));
        }
        let mut w = CdrWriter::new();
        let header = raster.header();
        header.write(&mut w);
        header.write_stamp(&mut w);
        w.f32(raster.resolution_m as f32);
        w.u32(raster.cols as u32);
        w.u32(raster.rows as u32);
        let origin = Isometry3::translation(raster.origin_xy_m[0], raster.origin_xy_m[1], 0.0);
        msgs::write_pose(&mut w, &origin);
        w.bytes(&occupancy.iter().map(|v| *v as u8).collect::<Vec<u8>>());
        self.write(topic, OCCUPANCY_GRID, raster.stamp_ns, &w.finish())
    }

    /// Writes the bag: `<folder>/<name>_0.mcap` and `<folder>/metadata.yaml`, each whole or not at all.
    /// Returns the MCAP file's path.
    ///
    /// # Errors
    /// A failed write, naming the file.
    pub fn finish(mut self) -> Result<PathBuf> {
        self.writer.finish().map_err(|e| mcap_error(&self.folder, &e))?;
        let name = self
            .folder
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        let file = format!("{name}_0.mcap");
        let metadata = self.metadata(&file);
        let bytes = self.writer.into_inner().into_inner();
        std::fs::create_dir_all(&self.folder).map_err(|source| Error::Io {
            path: self.folder.clone(),
            source,
        })?;
        let mcap_path = self.folder.join(&file);
        write_atomically(&mcap_path, &bytes)?;
        write_atomically(&self.folder.join("metadata.yaml"), metadata.as_bytes())?;
        Ok(mcap_path)
    }

    /// rosbag2's `metadata.yaml` (version 5, MCAP storage).
    fn metadata(&self, file: &str) -> String {
        let start = self.first_ns.unwrap_or(0);
        let duration = self.last_ns - start;
        let total: u64 = self.channels.values().map(|c| c.2).sum();
        let mut topics = String::new();
        for (topic, (_, kind, n)) in &self.channels {
            // The profile as one double-quoted YAML string, as rosbag2 writes it.
            let qos = offered_qos(topic).replace('\n', "\\n");
            topics.push_str(&format!(
                "    - topic_metadata:\n        name: {topic}\n        type: {kind}\n        serialization_format: cdr\n        \
                 offered_qos_profiles: \"{qos}\"\n      message_count: {n}\n"
            ));
        }
        format!(
            "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  duration:\n    nanoseconds: \
             {duration}\n  starting_time:\n    nanoseconds_since_epoch: {start}\n  message_count: {total}\n  \
             topics_with_message_count:\n{topics}  compression_format: \"\"\n  compression_mode: \"\"\n  \
             relative_file_paths:\n    - {file}\n  files:\n    - path: {file}\n      starting_time:\n        \
             nanoseconds_since_epoch: {start}\n      duration:\n        nanoseconds: {duration}\n      \
             message_count: {total}\n"
        )
    }
}

/// The QoS a topic is offered with, as rosbag2's list of profiles in YAML (its `rmw_qos_profile_t` numbers):
/// reliable, keeping the last 10 messages, and volatile, except `/tf_static`, which is transient local with a
/// depth of 1, as tf2's static broadcaster offers it (tf2's static listener asks for transient local, which a
/// volatile offer cannot give: played back so, a bag's static transforms would reach nobody). Deadline,
/// lifespan and lease are 0, the middleware's default (none).
fn offered_qos(topic: &str) -> String {
    let (depth, durability) = if topic == "/tf_static" { (1, 1) } else { (10, 2) };
    format!(
        "- history: 1\n  depth: {depth}\n  reliability: 1\n  durability: {durability}\n  deadline:\n    sec: 0\n    \
         nsec: 0\n  lifespan:\n    sec: 0\n    nsec: 0\n  liveliness: 1\n  liveliness_lease_duration:\n    sec: 0\n    \
         nsec: 0\n  avoid_ros_namespace_conventions: false"
    )
}

fn mcap_error(folder: &Path, e: &mcap::McapError) -> Error {
    Error::parse(folder, format!("writing the bag: {e}"))
}
