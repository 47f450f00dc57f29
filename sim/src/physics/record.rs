//! What a drive on the wheels reports: its events by name, with time and place, and its sampled state.

use serde::Serialize;

/// What happened to the robot, by name.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PhysicsEventKind {
    /// A part of the robot's body (not a wheel) touched an obstacle, a person or the ground.
    Contact {
        /// What it touched: the obstacle's label, `person <k>`, or `ground`.
        with: String,
        /// The robot's link that touched it.
        link: String,
    },
    /// The robot was commanded to drive or turn and made no progress for `stall_time_s`: less than
    /// `stall_distance_m` or a quarter of what its commands asked.
    Stall {
        /// The wheels' mean slip over the stall, from 0 (rolling) to 1 (spinning in place).
        wheel_slip: f64,
    },
    /// Roll or pitch passed its static stability angle.
    TipOver {
        /// Roll at the time, degrees.
        roll_deg: f64,
        /// Pitch at the time, degrees.
        pitch_deg: f64,
    },
    /// The scripted drive reached its last waypoint, or a closed loop its goal.
    GoalReached,
}

/// One event with its time and place.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PhysicsEvent {
    /// Simulated time, seconds.
    pub time_s: f64,
    /// Where, world frame, metres: the contact point, or the robot's base.
    pub x_m: f64,
    /// See `x_m`.
    pub y_m: f64,
    /// What.
    #[serde(flatten)]
    pub kind: PhysicsEventKind,
}

/// The robot's state at one time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PhysicsSample {
    /// Simulated time, seconds.
    pub time_s: f64,
    /// Base position, world frame, metres.
    pub x_m: f64,
    /// See `x_m`.
    pub y_m: f64,
    /// See `x_m`.
    pub z_m: f64,
    /// Heading, roll and pitch of the base, degrees.
    pub yaw_deg: f64,
    /// See `yaw_deg`.
    pub roll_deg: f64,
    /// See `yaw_deg`.
    pub pitch_deg: f64,
    /// The commanded speed, m/s, and turn rate, degrees per second.
    pub commanded_speed_m_s: f64,
    /// See `commanded_speed_m_s`.
    pub commanded_turn_rate_deg_s: f64,
    /// The achieved speed along the base's heading, m/s, and turn rate, degrees per second.
    pub speed_m_s: f64,
    /// See `speed_m_s`.
    pub turn_rate_deg_s: f64,
    /// The left and the right wheels' mean slip: `(w r - v) / max(|w r|, |v|)`, 0 when rolling, 1 when
    /// spinning in place, negative when dragged.
    pub slip_left: f64,
    /// See `slip_left`.
    pub slip_right: f64,
    /// Distance from the path the drive follows, metres: the scripted waypoints, or a closed loop's plan
    /// (`None` while it has none).
    pub path_error_m: Option<f64>,
}
