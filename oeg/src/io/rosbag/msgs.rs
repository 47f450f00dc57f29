//! The ROS 2 messages a bag's range data and poses come in, hand-written: each decoded from CDR field by field
//! (no ROS installation), and those the writer needs encoded, with the message definitions a bag's schemas
//! carry (`ros2msg`, as `ros2 bag record` writes them).

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

use super::cdr::{CdrError, CdrReader, CdrResult, CdrWriter};
use crate::io::unit_quaternion;

/// `sensor_msgs/PointCloud2`.
pub(crate) const POINT_CLOUD2: &str = "sensor_msgs/msg/PointCloud2";
/// `sensor_msgs/LaserScan`.
pub(crate) const LASER_SCAN: &str = "sensor_msgs/msg/LaserScan";
/// `tf2_msgs/TFMessage`.
pub(crate) const TF_MESSAGE: &str = "tf2_msgs/msg/TFMessage";
/// `nav_msgs/Odometry`.
pub(crate) const ODOMETRY: &str = "nav_msgs/msg/Odometry";
/// `grid_map_msgs/GridMap`.
pub(crate) const GRID_MAP: &str = "grid_map_msgs/msg/GridMap";
/// `nav_msgs/OccupancyGrid`.
pub(crate) const OCCUPANCY_GRID: &str = "nav_msgs/msg/OccupancyGrid";

/// Whether a schema's name (`package/msg/Name`, or `package/Name` as ROS 1 and some tools write it) is `kind`.
pub(crate) fn is_type(name: &str, kind: &str) -> bool {
    name == kind || name == kind.replace("/msg/", "/")
}

/// `std_msgs/Header`: the stamp in nanoseconds since the epoch, and the frame.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Header {
    pub(crate) stamp_ns: i64,
    pub(crate) frame_id: String,
}

impl Header {
    pub(super) fn read(r: &mut CdrReader) -> CdrResult<Self> {
        let sec = r.i32("header.stamp.sec")?;
        let nanosec = r.u32("header.stamp.nanosec")?;
        Ok(Self {
            stamp_ns: i64::from(sec) * 1_000_000_000 + i64::from(nanosec),
            frame_id: frame_name(&r.string("header.frame_id")?),
        })
    }

    pub(crate) fn write(&self, w: &mut CdrWriter) {
        self.write_stamp(w);
        w.string(&self.frame_id);
    }

    /// The stamp alone, as `builtin_interfaces/Time`.
    pub(crate) fn write_stamp(&self, w: &mut CdrWriter) {
        w.i32(self.stamp_ns.div_euclid(1_000_000_000) as i32);
        w.u32(self.stamp_ns.rem_euclid(1_000_000_000) as u32);
    }
}

/// A frame's name as tf2 uses it: without a leading `/` (ROS 1 wrote one).
pub(crate) fn frame_name(name: &str) -> String {
    name.trim_start_matches('/').to_string()
}

/// `sensor_msgs/LaserScan`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LaserScan {
    pub(crate) header: Header,
    pub(crate) angle_min: f32,
    pub(crate) angle_increment: f32,
    pub(crate) range_min: f32,
    pub(crate) range_max: f32,
    pub(crate) ranges: Vec<f32>,
}

impl LaserScan {
    pub(crate) fn decode(data: &[u8]) -> CdrResult<Self> {
        let mut r = CdrReader::new(data)?;
        let header = Header::read(&mut r)?;
        let angle_min = r.f32("angle_min")?;
        r.f32("angle_max")?;
        let angle_increment = r.f32("angle_increment")?;
        r.f32("time_increment")?;
        r.f32("scan_time")?;
        let range_min = r.f32("range_min")?;
        let range_max = r.f32("range_max")?;
        let ranges = r.f32s("ranges")?;
        for (v, name) in [
            (angle_min, "angle_min"),
            (angle_increment, "angle_increment"),
            (range_min, "range_min"),
            (range_max, "range_max"),
        ] {
            if !v.is_finite() {
                return Err(CdrError {
                    field: name.into(),
                    message: format!("{v}, where a finite number is expected"),
                });
            }
        }
        if !(range_max > 0.0 && range_min <= range_max) {
            return Err(CdrError {
                field: "range_max".into(),
                message: format!("{range_max} m with range_min {range_min} m: an empty range"),
            });
        }
        Ok(Self {
            header,
            angle_min,
            angle_increment,
            range_min,
            range_max,
            ranges,
        })
    }
}

/// One edge of the transform tree: `parent_from_child` at the header's stamp (the header's frame is the parent).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TransformStamped {
    pub(crate) header: Header,
    pub(crate) child_frame_id: String,
    pub(crate) transform: Isometry3<f64>,
}

impl TransformStamped {
    fn read(r: &mut CdrReader, field: &str) -> CdrResult<Self> {
        let header = Header::read(r)?;
        let child_frame_id = frame_name(&r.string(&format!("{field}.child_frame_id"))?);
        let transform = read_pose(r, &format!("{field}.transform"))?;
        Ok(Self {
            header,
            child_frame_id,
            transform,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        w.string(&self.child_frame_id);
        write_pose(w, &self.transform);
    }
}

/// A translation (`x y z`, float64) and a rotation (`x y z w`, float64), as `geometry_msgs/Transform` and
/// `geometry_msgs/Pose` both are; the rotation normalised, a zero or non-finite one refused.
fn read_pose(r: &mut CdrReader, field: &str) -> CdrResult<Isometry3<f64>> {
    let mut v = [0.0; 7];
    for (k, x) in v.iter_mut().enumerate() {
        *x = r.f64(field)?;
        if !x.is_finite() {
            return Err(CdrError {
                field: field.into(),
                message: format!("component {k} is {x}, where a finite number is expected"),
            });
        }
    }
    // A rotation that is unit to rounding is taken as written, so that a pose survives a bag bit for bit;
    // another is normalised as every reader of the project does.
    let q = Quaternion::new(v[6], v[3], v[4], v[5]);
    let rotation = if (q.norm_squared() - 1.0).abs() <= 4.0 * f64::EPSILON {
        UnitQuaternion::new_unchecked(q)
    } else {
        unit_quaternion(v[6], v[3], v[4], v[5]).ok_or_else(|| CdrError {
            field: format!("{field}.rotation"),
            message: "a zero quaternion".into(),
        })?
    };
    Ok(Isometry3::from_parts(
        Translation3::new(v[0], v[1], v[2]),
        rotation,
    ))
}

pub(crate) fn write_pose(w: &mut CdrWriter, pose: &Isometry3<f64>) {
    let (t, q) = (pose.translation.vector, pose.rotation.quaternion());
    for x in [t.x, t.y, t.z, q.i, q.j, q.k, q.w] {
        w.f64(x);
    }
}

/// `tf2_msgs/TFMessage`.
pub(crate) fn decode_tf(data: &[u8]) -> CdrResult<Vec<TransformStamped>> {
    let mut r = CdrReader::new(data)?;
    // A transform is at least its stamp, two string lengths and seven float64s.
    let n = r.sequence_len("transforms", 16 + 56)?;
    (0..n)
        .map(|k| TransformStamped::read(&mut r, &format!("transforms[{k}]")))
        .collect()
}

pub(crate) fn encode_tf(transforms: &[TransformStamped]) -> Vec<u8> {
    let mut w = CdrWriter::new();
    w.len(transforms.len());
    for t in transforms {
        t.write(&mut w);
    }
    w.finish()
}

/// `nav_msgs/Odometry`'s pose as a transform: the child frame (the robot) in the header's frame. The
/// covariance and the twist are not read.
pub(crate) fn decode_odometry(data: &[u8]) -> CdrResult<TransformStamped> {
    let mut r = CdrReader::new(data)?;
    TransformStamped::read(&mut r, "pose.pose")
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;

    #[test]
    fn a_transform_reads_back_as_written() {
        let t = TransformStamped {
            header: Header {
                stamp_ns: -5,
                frame_id: "map".into(),
            },
            child_frame_id: "base_link".into(),
            transform: Isometry3::new(Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.0, 0.0, 0.5)),
        };
        let back = decode_tf(&encode_tf(std::slice::from_ref(&t))).expect("decodes");
        assert_eq!(back.len(), 1);
        assert_eq!(back[0].header, t.header);
        assert!((back[0].transform.to_homogeneous() - t.transform.to_homogeneous()).norm() < 1e-12);
    }
}
