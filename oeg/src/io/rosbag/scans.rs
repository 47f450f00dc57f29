//! The second pass over a bag: its range messages, chosen by topic, time and stride, as scans in the map frame.

use std::path::Path;

use nalgebra::{Isometry3, Point3, Vector3};

use super::cloud::{CloudReading, PointCloud2};
use super::container::{Channel, Channels};
use super::msgs::{LASER_SCAN, LaserScan, POINT_CLOUD2, is_type};
use super::tf::TfTree;
use super::{Bag, BagOptions, BagScan, BagSkip};
use crate::error::{Error, Result};
use crate::scan::{Ray, Scan};
use crate::sensor::SensorModel;

/// A header's stamp, or the log time for a zero stamp (tf2's "latest").
pub(super) fn stamp_or_log_time(stamp_ns: i64, log_time: u64) -> i64 {
    if stamp_ns == 0 {
        i64::try_from(log_time).unwrap_or(i64::MAX)
    } else {
        stamp_ns
    }
}

/// The range topics to map: those asked for, each checked, or every one of a range type.
pub(super) fn range_topics(path: &Path, options: &BagOptions, channels: &Channels) -> Result<Vec<String>> {
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
pub(super) struct ScanReader<'a> {
    pub(super) options: &'a BagOptions,
    pub(super) tree: &'a TfTree,
    pub(super) map_frame: &'a str,
    pub(super) first_log_ns: u64,
    pub(super) bag: Bag,
}

impl ScanReader<'_> {
    /// Maps one message of channel `c` (its `index` on the topic), or counts why not; a message that does not
    /// decode is an error, in words.
    pub(super) fn message(
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
        if !in_range || !index.is_multiple_of(u64::from(o.stride)) {
            self.bag.num_not_selected += 1;
            return Ok(());
        }
        let (header, scan) = if is_type(&c.kind, POINT_CLOUD2) {
            let cloud = PointCloud2::decode(data).map_err(|e| e.to_string())?;
            let readings = cloud.readings().map_err(|e| e.to_string())?;
            (cloud.header, Readings::Cloud(readings))
        } else {
            let laser = LaserScan::decode(data).map_err(|e| e.to_string())?;
            let readings = laser_readings(&laser);
            (laser.header, readings)
        };
        let stamp_ns = stamp_or_log_time(header.stamp_ns, log_time);
        let Some((pose, ground_z_m)) = self.place(&c.topic, &header.frame_id, stamp_ns) else {
            return Ok(());
        };
        let origin = Point3::from(pose.translation.vector);
        let mut out = Scan::new(origin, o.cloud_sensor);
        out.stamp_s = stamp_ns as f64 * 1e-9;
        out.ground_z_m = ground_z_m;
        match scan {
            Readings::Cloud(readings) => {
                // A cloud's rays that returned nothing clear to their own length, the sensor's range.
                if let Some(range_m) = readings
                    .iter()
                    .filter(|r| !r.hit)
                    .map(|r| r.point.norm() as f32)
                    .reduce(f32::max)
                {
                    out.sensor.max_range_m = range_m;
                }
                out.rays.reserve(readings.len());
                for r in readings {
                    // Rotated in float64 and stored in float32, as `oeg run` places a simulated scan's rays.
                    let offset = (pose.rotation * r.point).cast::<f32>();
                    let ray = if r.hit {
                        Ray::hit(offset)
                    } else {
                        Ray::no_return(offset)
                    };
                    out.rays.push(Ray {
                        range_sigma_m: r.range_sigma_m,
                        ..ray
                    });
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

    /// The sensor's pose in the map frame at `stamp_ns`, and the height of the ground under the robot there
    /// where the bag holds [`BagOptions::ground_frame`]; `None` (the message skipped, and counted) without
    /// either transform.
    fn place(&mut self, topic: &str, frame_id: &str, stamp_ns: i64) -> Option<(Isometry3<f64>, Option<f64>)> {
        let tolerance_ns = (self.options.tf_tolerance_s * 1e9).round() as i64;
        let pose = match self.tree.lookup(self.map_frame, frame_id, stamp_ns, tolerance_ns) {
            Ok(p) => p,
            Err(reason) => {
                let reason = format!("no transform from `{frame_id}` to `{}`: {reason}", self.map_frame);
                self.skip(topic, reason);
                return None;
            }
        };
        let Some(ground) = self.bag.ground_frame.clone() else {
            return Some((pose, None));
        };
        match self.tree.lookup(self.map_frame, &ground, stamp_ns, tolerance_ns) {
            Ok(p) => Some((pose, Some(p.translation.vector.z))),
            Err(reason) => {
                let reason = format!(
                    "no transform from `{ground}` (the ground under the robot) to `{}`: {reason}",
                    self.map_frame
                );
                self.skip(topic, reason);
                None
            }
        }
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
    Cloud(Vec<CloudReading>),
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
