//! A run as an MCAP recording for Foxglove (`oeg run --mcap`): the robot's true and estimated pose, each
//! sensor's scans, the map's layers at a fixed rate, the truth once, the planned paths and the events, each at
//! its simulated time. Messages are JSON in Foxglove's well-known schemas (`foxglove.FrameTransform`,
//! `foxglove.PointCloud`, `foxglove.Grid`, `foxglove.PosesInFrame`, `foxglove.Log`), written with the `mcap`
//! crate without compression. Topics and frames: `docs/mcap.md`.

use std::collections::BTreeMap;
use std::io::Cursor;

use nalgebra::Isometry3;
use oeg::{GridWindow, LayerKind, Map, RobotProfile, TraversabilityRule};
use serde_json::{Value, json};

/// The frame every message is placed in: the scenario's world, metres, z up.
pub(crate) const WORLD_FRAME: &str = "world";
/// The robot's true base frame.
pub(crate) const BASE_FRAME: &str = "base_link";
/// The robot's base frame where odometry believes it is (the pose the map integrates at).
pub(crate) const ESTIMATED_BASE_FRAME: &str = "base_link_estimated";
/// The map's layers are recorded once per this many seconds of simulated time, and at the end.
pub(crate) const DEFAULT_GRID_PERIOD_S: f64 = 1.0;

pub(crate) use crate::error::RecordingError;

/// The schema of the robot's state on its wheels (`/physics`): the columns of `physics.csv`.
const PHYSICS_SCHEMA: &str = "oeg.PhysicsState";

/// The Foxglove schemas used, as JSON schemas (the fields this recording writes, with their types), by name.
pub(crate) fn schemas() -> BTreeMap<&'static str, Value> {
    let time = json!({"type": "object", "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}},
        "required": ["sec", "nsec"]});
    let vector3 = json!({"type": "object", "properties": {
        "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}},
        "required": ["x", "y", "z"]});
    let quaternion = json!({"type": "object", "properties": {
        "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}, "w": {"type": "number"}},
        "required": ["x", "y", "z", "w"]});
    let pose = json!({"type": "object", "properties": {"position": vector3, "orientation": quaternion},
        "required": ["position", "orientation"]});
    let fields = json!({"type": "array", "items": {"type": "object", "properties": {
        "name": {"type": "string"},
        "offset": {"type": "integer", "minimum": 0},
        "type": {"type": "integer", "minimum": 0, "maximum": 8}},
        "required": ["name", "offset", "type"]}});
    let data = json!({"type": "string", "contentEncoding": "base64"});
    let mut out = BTreeMap::new();
    let number = json!({"type": "number"});
    let mut physics = serde_json::Map::new();
    physics.insert("timestamp".into(), time.clone());
    for name in <sim::physics::PhysicsSample as crate::output::CsvRow>::COLUMNS {
        let field = if *name == "path_error_m" {
            json!({"type": ["number", "null"]})
        } else {
            number.clone()
        };
        physics.insert((*name).into(), field);
    }
    out.insert(
        PHYSICS_SCHEMA,
        json!({"title": PHYSICS_SCHEMA, "type": "object", "properties": physics, "required": ["timestamp"]}),
    );
    out.insert(
        "foxglove.FrameTransform",
        json!({"title": "foxglove.FrameTransform", "type": "object", "properties": {
            "timestamp": time, "parent_frame_id": {"type": "string"}, "child_frame_id": {"type": "string"},
            "translation": vector3, "rotation": quaternion},
            "required": ["timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"]}),
    );
    out.insert(
        "foxglove.PointCloud",
        json!({"title": "foxglove.PointCloud", "type": "object", "properties": {
            "timestamp": time, "frame_id": {"type": "string"}, "pose": pose,
            "point_stride": {"type": "integer", "minimum": 0}, "fields": fields, "data": data},
            "required": ["timestamp", "frame_id", "pose", "point_stride", "fields", "data"]}),
    );
    out.insert(
        "foxglove.Grid",
        json!({"title": "foxglove.Grid", "type": "object", "properties": {
            "timestamp": time, "frame_id": {"type": "string"}, "pose": pose,
            "column_count": {"type": "integer", "minimum": 0},
            "cell_size": {"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}},
                "required": ["x", "y"]},
            "row_stride": {"type": "integer", "minimum": 0}, "cell_stride": {"type": "integer", "minimum": 0},
            "fields": fields, "data": data},
            "required": ["timestamp", "frame_id", "pose", "column_count", "cell_size", "row_stride",
                "cell_stride", "fields", "data"]}),
    );
    out.insert(
        "foxglove.PosesInFrame",
        json!({"title": "foxglove.PosesInFrame", "type": "object", "properties": {
            "timestamp": time, "frame_id": {"type": "string"}, "poses": {"type": "array", "items": pose}},
            "required": ["timestamp", "frame_id", "poses"]}),
    );
    out.insert(
        "foxglove.Log",
        json!({"title": "foxglove.Log", "type": "object", "properties": {
            "timestamp": time, "level": {"type": "integer", "minimum": 0, "maximum": 5},
            "message": {"type": "string"}, "name": {"type": "string"}, "file": {"type": "string"},
            "line": {"type": "integer", "minimum": 0}},
            "required": ["timestamp", "level", "message", "name", "file", "line"]}),
    );
    out
}

/// Foxglove's log levels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogLevel {
    /// Information: a plan, the goal reached.
    Info = 2,
    /// A warning: no path, the closest approach.
    Warning = 3,
    /// An error: a contact with a truly blocked cell, stuck, a planner's failure.
    Error = 4,
}

fn stamp(t_s: f64) -> Value {
    let ns = nanos(t_s);
    json!({"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000})
}

fn nanos(t_s: f64) -> u64 {
    (t_s.max(0.0) * 1e9).round() as u64
}

fn planar_pose_json(x: f64, y: f64, z: f64) -> Value {
    json!({"position": {"x": x, "y": y, "z": z}, "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}})
}

/// A recording being written into memory; [`Recording::finish`] gives the file's bytes.
pub struct Recording {
    writer: mcap::Writer<Cursor<Vec<u8>>>,
    schemas: BTreeMap<&'static str, u16>,
    channels: BTreeMap<String, (u16, u32)>,
    window: GridWindow,
    grid_period_s: f64,
    next_grid_s: f64,
    last_pose_s: f64,
}

impl std::fmt::Debug for Recording {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recording")
            .field("channels", &self.channels.keys().collect::<Vec<_>>())
            .finish_non_exhaustive()
    }
}

impl Recording {
    /// A recording of the map over `window`, its layers every `grid_period_s` of simulated time.
    ///
    /// # Errors
    /// The writer's header cannot be written.
    pub fn new(window: GridWindow, grid_period_s: f64) -> Result<Self, RecordingError> {
        let writer = mcap::WriteOptions::new()
            .compression(None)
            .profile("")
            .library(concat!("oeg ", env!("CARGO_PKG_VERSION")))
            .create(Cursor::new(Vec::new()))?;
        Ok(Self {
            writer,
            schemas: BTreeMap::new(),
            channels: BTreeMap::new(),
            window,
            grid_period_s,
            next_grid_s: 0.0,
            last_pose_s: f64::NEG_INFINITY,
        })
    }

    /// Writes one message on `topic` (its channel made on first use) at `t_s`.
    fn write(
        &mut self,
        topic: &str,
        schema: &'static str,
        t_s: f64,
        message: &Value,
    ) -> Result<(), RecordingError> {
        if !self.channels.contains_key(topic) {
            let schema_id = match self.schemas.get(schema) {
                Some(id) => *id,
                None => {
                    let body = schemas()
                        .remove(schema)
                        .ok_or_else(|| RecordingError(format!("no schema {schema}")))?;
                    let bytes = serde_json::to_vec(&body).map_err(|e| RecordingError(e.to_string()))?;
                    let id = self.writer.add_schema(schema, "jsonschema", &bytes)?;
                    self.schemas.insert(schema, id);
                    id
                }
            };
            let id = self
                .writer
                .add_channel(schema_id, topic, "json", &BTreeMap::new())?;
            self.channels.insert(topic.to_string(), (id, 0));
        }
        let (channel_id, sequence) = self
            .channels
            .get_mut(topic)
            .map(|c| (c.0, &mut c.1))
            .ok_or_else(|| RecordingError(format!("no channel {topic}")))?;
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: *sequence,
            log_time: nanos(t_s),
            publish_time: nanos(t_s),
        };
        *sequence += 1;
        let data = serde_json::to_vec(message).map_err(|e| RecordingError(e.to_string()))?;
        self.writer.write_to_known_channel(&header, &data)?;
        Ok(())
    }

    /// The robot's true and estimated base poses at `t_s` (`/tf`), at most once per `min_period_s`.
    ///
    /// # Errors
    /// A failed write.
    pub fn poses(
        &mut self,
        t_s: f64,
        truth: &Isometry3<f64>,
        estimated: &Isometry3<f64>,
        min_period_s: f64,
    ) -> Result<(), RecordingError> {
        if t_s < self.last_pose_s + min_period_s - 1e-9 {
            return Ok(());
        }
        self.last_pose_s = t_s;
        for (child, iso) in [(BASE_FRAME, truth), (ESTIMATED_BASE_FRAME, estimated)] {
            let (t, q) = (iso.translation.vector, iso.rotation.coords);
            let message = json!({"timestamp": stamp(t_s), "parent_frame_id": WORLD_FRAME, "child_frame_id": child,
                "translation": {"x": t.x, "y": t.y, "z": t.z},
                "rotation": {"x": q.x, "y": q.y, "z": q.z, "w": q.w}});
            self.write("/tf", "foxglove.FrameTransform", t_s, &message)?;
        }
        Ok(())
    }

    /// The robot's poses now (at most once per `min_pose_period_s`) and one scan of `sensor` at its stamp: what
    /// a run and `oeg record` write for every scan.
    ///
    /// # Errors
    /// A failed write.
    pub fn sensor_scan(
        &mut self,
        world: &sim::World,
        sensor: &str,
        scan: &oeg::Scan,
        min_pose_period_s: f64,
    ) -> Result<(), RecordingError> {
        self.poses(
            scan.stamp_s,
            &world.world_from_base(),
            &world.estimated_world_from_base(),
            min_pose_period_s,
        )?;
        self.scan(scan.stamp_s, sensor, scan)
    }

    /// One scan's returns as a point cloud in the world frame, where the map placed them (at the estimated
    /// pose), on `/scans/<sensor>`.
    ///
    /// # Errors
    /// A failed write.
    pub fn scan(&mut self, t_s: f64, sensor: &str, scan: &oeg::Scan) -> Result<(), RecordingError> {
        let mut data = Vec::with_capacity(scan.rays.len() * 12);
        let o = scan.origin_in_world;
        for ray in &scan.rays {
            if let oeg::RayKind::Hit = ray.kind {
                let d = ray.offset_in_world;
                for v in [o.x + f64::from(d.x), o.y + f64::from(d.y), o.z + f64::from(d.z)] {
                    data.extend_from_slice(&(v as f32).to_le_bytes());
                }
            }
        }
        let message = json!({"timestamp": stamp(t_s), "frame_id": WORLD_FRAME,
            "pose": planar_pose_json(0.0, 0.0, 0.0), "point_stride": 12,
            "fields": [{"name": "x", "offset": 0, "type": 7}, {"name": "y", "offset": 4, "type": 7},
                {"name": "z", "offset": 8, "type": 7}],
            "data": crate::output::base64(&data)});
        self.write(&format!("/scans/{sensor}"), "foxglove.PointCloud", t_s, &message)
    }

    /// A grid over the recording's window on `topic`, one field `name` of 4-byte floats or bytes per cell.
    fn grid(&mut self, topic: &str, t_s: f64, name: &str, cells: GridCells) -> Result<(), RecordingError> {
        let (r, resolution_m) = (*self.window.region(), self.window.resolution_m());
        let (cell_stride, numeric_type, data) = match cells {
            GridCells::F32(values) => (
                4,
                7,
                values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>(),
            ),
            GridCells::U8(values) => (1, 1, values),
        };
        let (origin_x, origin_y) = self.window.min_corner_m();
        let message = json!({"timestamp": stamp(t_s), "frame_id": WORLD_FRAME,
            "pose": planar_pose_json(origin_x, origin_y, 0.0), "column_count": r.num_x,
            "cell_size": {"x": resolution_m, "y": resolution_m},
            "row_stride": cell_stride * r.num_x, "cell_stride": cell_stride,
            "fields": [{"name": name, "offset": 0, "type": numeric_type}],
            "data": crate::output::base64(&data)});
        self.write(topic, "foxglove.Grid", t_s, &message)
    }

    /// The map's layers (`/map/elevation`, `/map/occupancy_probability`, `/map/variance`, `/map/decisions`) when
    /// a grid period has passed since the last, or always when `force` (the end of the run).
    ///
    /// # Errors
    /// A failed write, or a raster over the map's memory limit.
    pub fn map_layers(
        &mut self,
        t_s: f64,
        map: &Map,
        profile: &RobotProfile,
        rule: TraversabilityRule,
        force: bool,
    ) -> Result<(), RecordingError> {
        if !force && t_s + 1e-9 < self.next_grid_s {
            return Ok(());
        }
        self.next_grid_s = (t_s / self.grid_period_s).floor() * self.grid_period_s + self.grid_period_s;
        for (topic, kind, name) in [
            ("/map/elevation", LayerKind::ElevationM, "elevation_m"),
            (
                "/map/occupancy_probability",
                LayerKind::OccupancyProbability,
                "occupancy_probability",
            ),
            ("/map/variance", LayerKind::VarianceM2, "variance_m2"),
        ] {
            let layer = map
                .layer(kind, *self.window.region())
                .map_err(|e| RecordingError(e.to_string()))?;
            self.grid(topic, t_s, name, GridCells::F32(layer.values))?;
        }
        let decisions = map
            .traversability_layer(*self.window.region(), profile, rule)
            .map_err(|e| RecordingError(e.to_string()))?;
        let codes = decisions.values.iter().map(|t| *t as u8).collect();
        self.grid("/map/decisions", t_s, "decision", GridCells::U8(codes))
    }

    /// The truth's elevation and truly blocked cells, once (`/truth/elevation`, `/truth/truly_blocked`).
    ///
    /// # Errors
    /// A failed write.
    pub fn truth(&mut self, truth: &sim::truth::TruthRaster) -> Result<(), RecordingError> {
        let elevation = truth.cells.iter().map(|c| c.elevation_m).collect();
        self.grid("/truth/elevation", 0.0, "elevation_m", GridCells::F32(elevation))?;
        let blocked = (0..truth.cells.len())
            .map(|k| u8::from(truth.truly_blocked(k)))
            .collect();
        self.grid(
            "/truth/truly_blocked",
            0.0,
            "truly_blocked",
            GridCells::U8(blocked),
        )
    }

    /// A planned path (`/plan`) at `t_s`, world points at the map's surface level.
    ///
    /// # Errors
    /// A failed write.
    pub fn path(&mut self, t_s: f64, points_m: &[(f64, f64)]) -> Result<(), RecordingError> {
        let poses: Vec<Value> = points_m
            .iter()
            .map(|(x, y)| planar_pose_json(*x, *y, 0.0))
            .collect();
        let message = json!({"timestamp": stamp(t_s), "frame_id": WORLD_FRAME, "poses": poses});
        self.write("/plan", "foxglove.PosesInFrame", t_s, &message)
    }

    /// An event of the run as a log message (`/events`).
    ///
    /// # Errors
    /// A failed write.
    pub fn event(&mut self, t_s: f64, level: LogLevel, message: &str) -> Result<(), RecordingError> {
        let message = json!({"timestamp": stamp(t_s), "level": level as u8, "message": message,
            "name": "oeg", "file": "", "line": 0});
        self.write("/events", "foxglove.Log", t_s, &message)
    }

    /// The robot's state on its wheels at one time (`/physics`): the fields of `physics.csv`, to plot.
    ///
    /// # Errors
    /// A failed write.
    pub fn physics_state(&mut self, sample: &sim::physics::PhysicsSample) -> Result<(), RecordingError> {
        let mut message = serde_json::to_value(sample).map_err(|e| RecordingError(e.to_string()))?;
        if let Some(object) = message.as_object_mut() {
            object.insert("timestamp".into(), stamp(sample.time_s));
        }
        self.write("/physics", PHYSICS_SCHEMA, sample.time_s, &message)
    }

    /// The finished file.
    ///
    /// # Errors
    /// The summary and footer cannot be written.
    pub fn finish(mut self) -> Result<Vec<u8>, RecordingError> {
        self.writer.finish()?;
        Ok(self.writer.into_inner().into_inner())
    }
}

/// One grid layer's values, row-major from the region's min corner.
enum GridCells {
    F32(Vec<f32>),
    U8(Vec<u8>),
}
