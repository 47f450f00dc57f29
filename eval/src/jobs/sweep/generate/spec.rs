//! The `[generate]` table as `serde` reads it, with its documented defaults.

use std::path::PathBuf;

use serde::Deserialize;

/// Uniform `[min, max]`.
pub(crate) type Range = [f64; 2];
/// Uniform integer `[min, max]`.
pub(crate) type Count = [u32; 2];

/// The `[generate]` table.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GenerateSpec {
    /// The scenario that gives the robot, its sensors, the map model and resolution, the terrain (relative to
    /// the sweep file).
    pub base: PathBuf,
    /// Where the robot stops, metres along x from the start.
    #[serde(default = "d_drive")]
    pub drive_length_m: f64,
    /// Driving speed, m/s.
    #[serde(default = "d_speed")]
    pub speed_m_s: f64,
    /// Where the obstacle field begins, metres along x.
    #[serde(default = "d_field_start")]
    pub field_start_m: f64,
    /// Length of the field along x, metres.
    #[serde(default = "d_field_length")]
    pub field_length_m: f64,
    /// Half the field's width, metres.
    #[serde(default = "d_half_width")]
    pub field_half_width_m: f64,
    /// Half the width of the lane kept free where the robot drives, metres.
    #[serde(default = "d_lane")]
    pub lane_half_width_m: f64,
    /// Seconds the sensors keep scanning after the robot stops and the last person left.
    #[serde(default = "d_settle")]
    pub settle_s: f64,
    /// How far past the field's far end the goal lies, metres (kept free of obstacles; the map region reaches
    /// a metre beyond it).
    #[serde(default = "d_goal_beyond")]
    pub goal_beyond_m: f64,
    /// Closed loop: after its drive the robot navigates to the goal (`[navigation]`), for at most
    /// `navigation_time_s`.
    #[serde(default)]
    pub navigate: bool,
    /// A closed-loop run's time limit after the drive, seconds.
    #[serde(default = "d_navigation_time")]
    pub navigation_time_s: f64,
    /// Curbs: boxes across the drive at a random yaw and offset to the cell grid.
    pub curbs: Option<Curbs>,
    /// Boards and table tops at a clearance near the robot's height.
    pub boards: Option<Boards>,
    /// Walls of random height, some lower than the sensors.
    pub walls: Option<Walls>,
    /// Bushes.
    pub bushes: Option<Bushes>,
    /// Ramps.
    pub ramps: Option<Ramps>,
    /// People who walk through, or who stand in front of the robot for a while and leave.
    pub people: Option<People>,
}

fn d_drive() -> f64 {
    3.0
}
fn d_speed() -> f64 {
    0.4
}
fn d_field_start() -> f64 {
    1.5
}
fn d_field_length() -> f64 {
    5.0
}
fn d_half_width() -> f64 {
    2.5
}
fn d_lane() -> f64 {
    0.6
}
fn d_goal_beyond() -> f64 {
    0.5
}
fn d_navigation_time() -> f64 {
    60.0
}
fn d_settle() -> f64 {
    2.0
}

/// `[generate.curbs]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Curbs {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Height, metres (default 2 to 5 cm, around the 3.5 cm step).
    #[serde(default = "d_curb_h")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub height_m: Range,
    /// Length across the drive, metres.
    #[serde(default = "d_curb_len")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub length_m: Range,
    /// Depth along the drive, metres.
    #[serde(default = "d_curb_depth")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub depth_m: Range,
    /// Yaw to the drive, degrees (0: the face square to the drive).
    #[serde(default = "d_curb_yaw")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub yaw_deg: Range,
}
fn d_curb_h() -> Range {
    [0.02, 0.05]
}
fn d_curb_len() -> Range {
    [0.8, 1.6]
}
fn d_curb_depth() -> Range {
    [0.25, 0.45]
}
fn d_curb_yaw() -> Range {
    [-45.0, 45.0]
}

/// `[generate.boards]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Boards {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Free gap under the board, metres (default 0.38 to 0.54: around the robot's 0.46 m).
    #[serde(default = "d_board_clear")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub clearance_m: Range,
    /// Length, metres.
    #[serde(default = "d_board_len")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub length_m: Range,
    /// Width, metres.
    #[serde(default = "d_board_width")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub width_m: Range,
    /// Thickness, metres.
    #[serde(default = "d_board_thick")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub thickness_m: Range,
    /// Yaw, degrees.
    #[serde(default = "d_any_yaw")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub yaw_deg: Range,
}
fn d_board_clear() -> Range {
    [0.38, 0.54]
}
fn d_board_len() -> Range {
    [0.5, 1.0]
}
fn d_board_width() -> Range {
    [0.6, 1.2]
}
fn d_board_thick() -> Range {
    [0.02, 0.05]
}
fn d_any_yaw() -> Range {
    [-90.0, 90.0]
}

/// `[generate.walls]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Walls {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Height, metres (default 0.1 to 1.2: some below the sensors).
    #[serde(default = "d_wall_h")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub height_m: Range,
    /// Length, metres.
    #[serde(default = "d_wall_len")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub length_m: Range,
    /// Thickness, metres.
    #[serde(default = "d_wall_thick")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub thickness_m: Range,
    /// Yaw, degrees.
    #[serde(default = "d_any_yaw")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub yaw_deg: Range,
}
fn d_wall_h() -> Range {
    [0.1, 1.2]
}
fn d_wall_len() -> Range {
    [1.0, 2.0]
}
fn d_wall_thick() -> Range {
    [0.1, 0.2]
}

/// `[generate.bushes]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bushes {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Radius, metres.
    #[serde(default = "d_bush_r")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub radius_m: Range,
    /// Height, metres.
    #[serde(default = "d_bush_h")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub height_m: Range,
}
fn d_bush_r() -> Range {
    [0.3, 0.7]
}
fn d_bush_h() -> Range {
    [0.4, 1.2]
}

/// `[generate.ramps]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ramps {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Height at the high end, metres.
    #[serde(default = "d_ramp_h")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub height_m: Range,
    /// Length, metres.
    #[serde(default = "d_ramp_len")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub length_m: Range,
    /// Width, metres.
    #[serde(default = "d_ramp_width")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub width_m: Range,
    /// Yaw, degrees.
    #[serde(default = "d_ramp_yaw")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub yaw_deg: Range,
}
fn d_ramp_h() -> Range {
    [0.05, 0.2]
}
fn d_ramp_len() -> Range {
    [0.8, 1.5]
}
fn d_ramp_width() -> Range {
    [0.6, 1.2]
}
fn d_ramp_yaw() -> Range {
    [-180.0, 180.0]
}

/// `[generate.people]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct People {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Probability that a person stands still in front of the robot (else walks through the field).
    #[serde(default = "d_half")]
    pub stand_probability: f64,
    /// How long a standing person stands, seconds.
    #[serde(default = "d_stand")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub stand_s: Range,
    /// Probability that the robot is standing (stopped at the end of its drive) when a person stands in front
    /// of it; otherwise it is still driving towards them.
    #[serde(default = "d_half")]
    pub robot_standing_probability: f64,
    /// Walking speed, m/s.
    #[serde(default = "d_walk")]
    pub walk_speed_m_s: f64,
}
fn d_half() -> f64 {
    0.5
}
fn d_stand() -> Range {
    [2.0, 6.0]
}
fn d_walk() -> f64 {
    1.0
}
