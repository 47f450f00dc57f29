//! `[input]` of `oeg map`: how each kind of file becomes scans.

use serde::Deserialize;

/// A range-error model of rays read from files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RangeModel {
    /// Laser scanner, 12 mm range error (SICK class).
    Laser,
    /// Stereo camera, 0.032 l^2 range error (the paper's Fig. 4).
    Stereo,
}

impl RangeModel {
    /// The map crate's sensor model.
    pub fn model(self) -> oeg::SensorModel {
        match self {
            Self::Laser => oeg::SensorModel::laser(),
            Self::Stereo => oeg::SensorModel {
                noise: oeg::RangeNoiseModel::stereo(),
                ..oeg::SensorModel::stereo()
            },
        }
    }
}

/// `[input]` of `oeg map`: how files become scans.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct InputSettings {
    /// Range-error model of scan-graph rays (`laser`).
    pub graph_sensor: RangeModel,
    /// Range-error model of PCD rays (`stereo`).
    pub pcd_sensor: RangeModel,
    /// Frame of PCD points: `as_is`, or `optical` (x right, y down, z forward).
    pub pcd_frame: oeg::PcdFrame,
    /// Where PCD points are: `sensor` (placed by `VIEWPOINT`) or `world` (already placed, `VIEWPOINT` the
    /// sensor's pose, as the DynamicMap benchmark writes them).
    pub pcd_points: oeg::PcdPoints,
    /// NaN points of an organized PCD: `drop`, or `no_return` rays along their pixel.
    pub pcd_invalid: oeg::InvalidPoints,
    /// Pose of sensor-log scans: `estimated` or `true`.
    pub log_pose: sim::sensors::PoseSource,
    /// How a ROS 2 bag becomes scans (`input.bag.*`).
    pub bag: BagInput,
}

/// `[input.bag]` of `oeg map`: a ROS 2 bag's topics, frames and time range ([`oeg::BagOptions`]).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BagInput {
    /// The `PointCloud2` and `LaserScan` topics to map; empty: every one.
    pub topics: Vec<String>,
    /// The map frame; none: `map`, else `odom`.
    pub map_frame: Option<String>,
    /// `nav_msgs/Odometry` topics whose poses join the transform tree.
    pub odometry: Vec<String>,
    /// Seconds after the bag's first message to start at.
    pub start_s: Option<f64>,
    /// Seconds after the bag's first message to end at.
    pub end_s: Option<f64>,
    /// Every how many range messages of a topic one is mapped.
    pub stride: u32,
    /// How far a scan's stamp may lie outside its transforms, seconds.
    pub tf_tolerance_s: f64,
    /// Range-error model of `PointCloud2` points (`laser`).
    pub cloud_sensor: RangeModel,
    /// The frame on the ground under the robot that height thresholds are measured from (`base_footprint`).
    pub ground_frame: String,
}

impl Default for BagInput {
    fn default() -> Self {
        let o = oeg::BagOptions::default();
        Self {
            topics: o.topics,
            map_frame: o.map_frame,
            odometry: o.odometry_topics,
            start_s: o.start_s,
            end_s: o.end_s,
            stride: o.stride,
            tf_tolerance_s: o.tf_tolerance_s,
            cloud_sensor: RangeModel::Laser,
            ground_frame: o.ground_frame,
        }
    }
}

impl BagInput {
    /// The reader's options.
    pub fn options(&self) -> oeg::BagOptions {
        oeg::BagOptions {
            topics: self.topics.clone(),
            map_frame: self.map_frame.clone(),
            odometry_topics: self.odometry.clone(),
            start_s: self.start_s,
            end_s: self.end_s,
            stride: self.stride,
            tf_tolerance_s: self.tf_tolerance_s,
            cloud_sensor: self.cloud_sensor.model(),
            laser_sensor: oeg::SensorModel::laser(),
            ground_frame: self.ground_frame.clone(),
        }
    }
}

impl Default for InputSettings {
    fn default() -> Self {
        Self {
            graph_sensor: RangeModel::Laser,
            pcd_sensor: RangeModel::Stereo,
            pcd_frame: oeg::PcdFrame::default(),
            pcd_points: oeg::PcdPoints::default(),
            pcd_invalid: oeg::InvalidPoints::default(),
            log_pose: sim::sensors::PoseSource::Estimated,
            bag: BagInput::default(),
        }
    }
}
