//! Recorded sensor logs (`.oeglog`), version 1: every scan of a run, so the same data can be replayed through
//! different map settings. The framing is the map file's ([`oeg_files::FramedWriter`], [`oeg_files::read_container_prefix`]). Little-endian throughout:
//!
//! ```text
//! 8    magic "OEGLOG\r\n"
//! 4    u32 format version (1)
//! 4    u32 header length H
//! H    header, UTF-8 JSON (LogHeader: scenario, seed, duration, sensors with their map models, and where the
//!      robot stood at the start)
//! then records, each starting with a u8 tag:
//!   1 = scan:  u32 sensor index, u64 scan index, f64 stamp_s,
//!              7 f64 true world_from_sensor (tx ty tz qw qx qy qz), 7 f64 estimated world_from_sensor,
//!              u32 ray count, then per ray: u8 kind (0 hit, 1 no return), 3 f32 vector in the sensor frame
//!              (hit: end point, metres; no return: unit direction), f32 range error (metres)
//!   0 = end:   u64 scan count, u64 FNV-1a-64 checksum of every byte before the checksum
//! ```

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use oeg::RayKind;
use oeg_files::unit_quaternion;
use oeg_files::{FramedWriter, check_container_checksum, read_container_prefix};
use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError};
use crate::sensors::{PoseSource, SensorRay, SensorScan};

/// The farthest a sensor's `ground_in_sensor_m` may lie from it along any axis, metres: the ground is under the
/// robot that carries the sensor.
pub const MAX_GROUND_IN_SENSOR_M: f64 = 100.0;

/// The file's first eight bytes.
pub const MAGIC: &[u8; 8] = b"OEGLOG\r\n";
/// The format version written and read.
pub const FORMAT_VERSION: u32 = 1;
const RAY_BYTES: usize = 1 + 4 * 4;
const SCAN_FIXED_BYTES: usize = 4 + 8 + 8 + 14 * 8 + 4;

/// One sensor as the log describes it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LogSensor {
    /// Name.
    pub name: String,
    /// Kind (`laser2d`, `lidar3d`, `stereo`, `depth_camera`).
    pub kind: String,
    /// Preset used.
    pub preset: String,
    /// Scans per second.
    pub rate_hz: f64,
    /// What the map assumes for rays without their own error, and how far no-returns clear.
    pub map_model: oeg::SensorModel,
    /// The ground under the robot in the sensor's frame, metres ([`SensorScan::ground_in_sensor`]); absent
    /// for a robot without wheels, and from logs written before it was recorded (their maps threshold heights
    /// in world z).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_in_sensor_m: Option<[f64; 3]>,
}

/// The log's JSON header.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LogHeader {
    /// Scenario name.
    pub scenario: String,
    /// Seed of the run.
    pub seed: u64,
    /// Simulated duration, seconds.
    pub duration_s: f64,
    /// Sensors, by index.
    pub sensors: Vec<LogSensor>,
    /// Where the robot stood at the start, for the maps that take the ground under it as a measurement
    /// (`oeg::Map::integrate_stance`); absent from a log of a robot without wheels, and from logs written
    /// before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stance: Option<LogStance>,
}

/// The robot at the start of a run as the log records it: its wheels and footprint in its base frame, and its
/// base's pose, true and estimated (`tx ty tz qw qx qy qz`, as a scan's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LogStance {
    /// The wheels' ground contact points in the base frame, metres.
    pub wheel_contacts_m: Vec<[f64; 3]>,
    /// The footprint in the base frame: min x, max x, min y, max y, metres.
    pub footprint_m: [f64; 4],
    /// The true `world_from_base` at the start.
    pub true_world_from_base: [f64; 7],
    /// The estimated `world_from_base` at the start.
    pub estimated_world_from_base: [f64; 7],
}

impl LogStance {
    /// The record of a robot with `wheel_contacts` and `footprint` whose base starts at `true_pose`, believed
    /// at `estimated_pose`.
    pub fn new(
        wheel_contacts: &[Point3<f64>],
        footprint: oeg::Footprint,
        true_pose: &Isometry3<f64>,
        estimated_pose: &Isometry3<f64>,
    ) -> Self {
        let seven = |p: &Isometry3<f64>| {
            let (t, q) = (p.translation.vector, p.rotation.quaternion());
            [t.x, t.y, t.z, q.w, q.i, q.j, q.k]
        };
        Self {
            wheel_contacts_m: wheel_contacts.iter().map(|c| [c.x, c.y, c.z]).collect(),
            footprint_m: [
                footprint.min_x_m,
                footprint.max_x_m,
                footprint.min_y_m,
                footprint.max_y_m,
            ],
            true_world_from_base: seven(true_pose),
            estimated_world_from_base: seven(estimated_pose),
        }
    }

    /// The stance at the pose `source` chooses ([`crate::robot::stance_at`]); `None` for a robot without
    /// wheels or with an empty footprint.
    ///
    /// # Errors
    /// A message for a pose that is not finite or has a zero rotation.
    pub fn stance(&self, source: PoseSource) -> std::result::Result<Option<oeg::Stance>, &'static str> {
        let v = match source {
            PoseSource::True => self.true_world_from_base,
            PoseSource::Estimated => self.estimated_world_from_base,
        };
        let rotation = unit_quaternion(v[3], v[4], v[5], v[6])
            .filter(|_| v.iter().all(|x| x.is_finite()))
            .ok_or("the stance's pose is not finite or has a zero rotation")?;
        let pose = Isometry3::from_parts(Translation3::new(v[0], v[1], v[2]), rotation);
        let contacts: Vec<Point3<f64>> = self.wheel_contacts_m.iter().map(|c| Point3::from(*c)).collect();
        let [min_x_m, max_x_m, min_y_m, max_y_m] = self.footprint_m;
        let footprint = oeg::Footprint {
            min_x_m,
            max_x_m,
            min_y_m,
            max_y_m,
        };
        Ok(crate::robot::stance_at(&contacts, footprint, &pose))
    }
}

/// A whole log read back.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorLog {
    /// Header.
    pub header: LogHeader,
    /// Scans in recorded order.
    pub scans: Vec<SensorScan>,
}

/// Writes a log scan by scan, atomically ([`FramedWriter`]): an abandoned writer leaves no partial log and no
/// temporary file behind, and only a regular file is ever replaced.
pub struct LogWriter {
    path: PathBuf,
    out: FramedWriter,
    num_scans: u64,
}

impl std::fmt::Debug for LogWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LogWriter")
            .field("path", &self.path)
            .field("num_scans", &self.num_scans)
            .finish()
    }
}

impl LogWriter {
    /// Starts a log at `path`.
    ///
    /// # Errors
    /// [`SimError::Map`] naming the file: it cannot be created, or it is not a regular file (a device, a FIFO).
    pub fn create(path: &Path, header: &LogHeader) -> Result<Self> {
        let json = serde_json_bytes(header);
        Ok(Self {
            path: path.to_path_buf(),
            out: FramedWriter::create(path, MAGIC, FORMAT_VERSION, &json)?,
            num_scans: 0,
        })
    }

    /// Appends one scan.
    ///
    /// # Errors
    /// [`SimError::Map`] naming the file.
    pub fn push(&mut self, scan: &SensorScan) -> Result<()> {
        let mut buf = Vec::with_capacity(1 + SCAN_FIXED_BYTES + scan.rays.len() * RAY_BYTES);
        buf.push(1u8);
        buf.extend_from_slice(&(scan.sensor_index as u32).to_le_bytes());
        buf.extend_from_slice(&scan.scan_index.to_le_bytes());
        buf.extend_from_slice(&scan.stamp_s.to_le_bytes());
        for pose in [&scan.world_from_sensor, &scan.estimated_world_from_sensor] {
            let t = pose.translation.vector;
            let q = pose.rotation.quaternion();
            for v in [t.x, t.y, t.z, q.w, q.i, q.j, q.k] {
                buf.extend_from_slice(&v.to_le_bytes());
            }
        }
        buf.extend_from_slice(&(scan.rays.len() as u32).to_le_bytes());
        for r in &scan.rays {
            buf.push(u8::from(r.kind == RayKind::NoReturn));
            for v in [
                r.vector_in_sensor.x,
                r.vector_in_sensor.y,
                r.vector_in_sensor.z,
                r.range_sigma_m,
            ] {
                buf.extend_from_slice(&v.to_le_bytes());
            }
        }
        self.out.write(&buf)?;
        self.num_scans += 1;
        Ok(())
    }

    /// Writes the end record and moves the log into place.
    ///
    /// # Errors
    /// [`SimError::Map`] naming the file.
    pub fn finish(mut self) -> Result<u64> {
        self.out.write(&[0u8])?;
        self.out.write(&self.num_scans.to_le_bytes())?;
        self.out.finish()?;
        Ok(self.num_scans)
    }
}

fn serde_json_bytes(header: &LogHeader) -> Vec<u8> {
    // A struct of strings and numbers always serialises.
    serde_json::to_vec(header).unwrap_or_default()
}

/// The largest log read (it is read whole): 64 GiB, hours of a 3D lidar. A larger file, or a device or a pipe
/// that runs past it, is refused rather than read until memory runs out.
pub const MAX_LOG_BYTES: u64 = 64 << 30;

/// Reads a log.
///
/// # Errors
/// [`SimError::Io`] if it cannot be read or is larger than [`MAX_LOG_BYTES`]; [`SimError::Log`] (naming the file and byte) for a wrong magic
/// number or version, a malformed header, a truncated record, a bad ray kind, a non-finite number, a scan
/// count that disagrees with the records, or a checksum mismatch.
pub fn read_log(path: &Path) -> Result<SensorLog> {
    let data = oeg_files::read_bounded(path, MAX_LOG_BYTES).map_err(|e| match e {
        oeg_files::FileError::Io { source, .. } => SimError::Io {
            path: path.to_path_buf(),
            source,
        },
        other => SimError::Log {
            path: path.to_path_buf(),
            message: other.to_string(),
        },
    })?;
    parse_log(path, &data)
}

/// Reads a log from its bytes (`path` names it in errors).
///
/// # Errors
/// As [`read_log`], but for reading the file.
pub fn parse_log(path: &Path, data: &[u8]) -> Result<SensorLog> {
    let prefix = read_container_prefix(path, data, MAGIC, &[FORMAT_VERSION], "an OEG sensor log")?;
    let mut r = LogReader {
        path,
        data,
        pos: prefix.body_start,
    };
    let header: LogHeader =
        serde_json::from_slice(prefix.header).map_err(|e| r.fail(16, format!("malformed header: {e}")))?;
    for sensor in &header.sensors {
        if let Some(g) = sensor.ground_in_sensor_m
            && g.iter().any(|v| v.abs() > MAX_GROUND_IN_SENSOR_M)
        {
            return Err(r.fail(
                16,
                format!(
                    "sensor {}: ground_in_sensor_m {g:?} lies more than {MAX_GROUND_IN_SENSOR_M} m from the \
                     sensor; expected the ground under the robot that carries it",
                    sensor.name
                ),
            ));
        }
    }
    let mut scans = Vec::new();
    loop {
        let at = r.pos;
        match r.take(1, "a record tag")?[0] {
            0 => {
                let count = u64_at(r.take(8, "the scan count")?);
                if count != scans.len() as u64 {
                    return Err(r.fail(
                        at,
                        format!(
                            "the end record counts {count} scans, the log holds {}",
                            scans.len()
                        ),
                    ));
                }
                check_container_checksum(path, data, r.pos)?;
                return Ok(SensorLog { header, scans });
            }
            1 => {
                let mut scan = r.scan_record(at, header.sensors.len())?;
                scan.ground_in_sensor = header.sensors[scan.sensor_index]
                    .ground_in_sensor_m
                    .map(Point3::from);
                scans.push(scan);
            }
            other => return Err(r.fail(at, format!("unknown record tag {other}"))),
        }
    }
}

fn u32_at(b: &[u8]) -> u32 {
    u32::from_le_bytes([b[0], b[1], b[2], b[3]])
}

fn u64_at(b: &[u8]) -> u64 {
    u64::from_le_bytes(b[..8].try_into().unwrap_or([0; 8]))
}

fn f64_at(b: &[u8]) -> f64 {
    f64::from_le_bytes(b[..8].try_into().unwrap_or([0; 8]))
}

fn f32_at(b: &[u8]) -> f32 {
    f32::from_le_bytes([b[0], b[1], b[2], b[3]])
}

/// The log's body, read from `pos` on; every error names the file and the byte.
struct LogReader<'a> {
    path: &'a Path,
    data: &'a [u8],
    pos: usize,
}

impl<'a> LogReader<'a> {
    fn fail(&self, at: usize, message: String) -> SimError {
        SimError::Log {
            path: self.path.to_path_buf(),
            message: format!("at byte {at}: {message}"),
        }
    }

    /// The next `n` bytes, which hold `what`.
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        let data = self.data;
        if data.len() - self.pos < n {
            return Err(self.fail(
                self.pos,
                format!(
                    "the log is truncated: expected {n} bytes for {what}, found {}",
                    data.len() - self.pos
                ),
            ));
        }
        let s = &data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    /// A scan record (its tag, at byte `at`, already read) of one of `num_sensors` sensors: its fixed part, both
    /// poses and its rays, each checked.
    fn scan_record(&mut self, at: usize, num_sensors: usize) -> Result<SensorScan> {
        let fixed = self.take(SCAN_FIXED_BYTES, "a scan record")?;
        let sensor_index = u32_at(&fixed[0..4]) as usize;
        if sensor_index >= num_sensors {
            return Err(self.fail(
                at,
                format!("scan of sensor {sensor_index}, but the header lists {num_sensors}"),
            ));
        }
        let scan_index = u64_at(&fixed[4..12]);
        let stamp_s = f64_at(&fixed[12..20]);
        let mut poses = [Isometry3::identity(); 2];
        for (k, pose) in poses.iter_mut().enumerate() {
            let v: Vec<f64> = (0..7).map(|n| f64_at(&fixed[20 + (k * 7 + n) * 8..])).collect();
            let rotation = unit_quaternion(v[3], v[4], v[5], v[6])
                .filter(|_| v.iter().all(|x| x.is_finite()))
                .ok_or_else(|| self.fail(at, "a scan pose is not finite or has a zero rotation".into()))?;
            *pose = Isometry3::from_parts(Translation3::new(v[0], v[1], v[2]), rotation);
        }
        let num_rays = u32_at(&fixed[SCAN_FIXED_BYTES - 4..]) as usize;
        if num_rays.saturating_mul(RAY_BYTES) > self.data.len() - self.pos {
            return Err(self.fail(
                at,
                format!("a scan declares {num_rays} rays, more than the log holds: truncated"),
            ));
        }
        let bytes = self.take(num_rays * RAY_BYTES, "the rays")?;
        let mut rays = Vec::with_capacity(num_rays);
        for (n, r) in bytes.chunks_exact(RAY_BYTES).enumerate() {
            let kind = match r[0] {
                0 => RayKind::Hit,
                1 => RayKind::NoReturn,
                other => {
                    return Err(self.fail(
                        at,
                        format!("ray {n} has kind {other}, expected 0 (hit) or 1 (no return)"),
                    ));
                }
            };
            let v = Vector3::new(f32_at(&r[1..]), f32_at(&r[5..]), f32_at(&r[9..]));
            let sigma = f32_at(&r[13..]);
            if !(v.iter().all(|x| x.is_finite()) && sigma.is_finite() && sigma >= 0.0) {
                return Err(self.fail(at, format!("ray {n} holds a non-finite number")));
            }
            rays.push(SensorRay {
                kind,
                vector_in_sensor: v,
                range_sigma_m: sigma,
                true_range_m: f32::NAN,
                true_hit_actor: false,
            });
        }
        let [world_from_sensor, estimated_world_from_sensor] = poses;
        Ok(SensorScan {
            sensor_index,
            scan_index,
            stamp_s,
            world_from_sensor,
            estimated_world_from_sensor,
            ground_in_sensor: None,
            rays,
        })
    }
}
