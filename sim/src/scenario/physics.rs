//! `[robot.drive] mode` and `[robot.physics]`: the robot driven on its wheels in Rapier instead of placed on its
//! path. The URDF gives the bodies, masses, inertias and joints; this table is the documented extension for
//! what a URDF does not say (friction, motors, the skid-steer drive, the time step and the solver), each
//! default taken from the Pioneer 3-AT's data sheet, from Rapier's own defaults, or derived from them as
//! `docs/scenario-format.md` explains.

use serde::Deserialize;

/// How the robot moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DriveMode {
    /// The robot is placed on its path at each tick, draped on the terrain: it goes where it is sent, through
    /// obstacles too (contacts are the judge's to find).
    #[default]
    Kinematic,
    /// The robot is a Rapier multibody from its URDF, its wheels turned by velocity motors: it climbs what its
    /// wheels can climb, stalls against what they cannot, and stops against what its body meets.
    Physics,
}

/// Default physics time step, seconds: 1/120 s. The curb-climbing limit of the default robot is the same at
/// 1/120, 1/240 and 1/480 s (`docs/physics.md`), so a finer step buys nothing.
pub const DEFAULT_TIME_STEP_S: f64 = 1.0 / 120.0;
/// Default solver iterations per step: Rapier's own default (`IntegrationParameters::num_solver_iterations`).
pub const DEFAULT_SOLVER_ITERATIONS: u32 = 4;
/// Default friction coefficient of a wheel on the ground and on obstacles: rubber on dry concrete, 0.6 to
/// 0.85 in engineering tables; the upper end for a pneumatic tyre.
pub const DEFAULT_WHEEL_FRICTION: f64 = 0.8;
/// Default friction coefficient of the robot's body on what it touches: Rapier's default collider friction.
pub const DEFAULT_BODY_FRICTION: f64 = 0.5;
/// Default time without progress after which a commanded robot counts as stalled, seconds.
pub const DEFAULT_STALL_TIME_S: f64 = 2.0;
/// Default progress that ends a stall watch, metres: a tenth of the wheel radius of the Pioneer 3-AT, less
/// than a wheel creeps when it spins against a step.
pub const DEFAULT_STALL_DISTANCE_M: f64 = 0.01;

/// `[robot.physics]`: what the URDF does not say. Read only when `[robot.drive] mode = "physics"`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PhysicsSettings {
    /// Fixed physics time step, seconds; default [`DEFAULT_TIME_STEP_S`].
    pub time_step_s: f64,
    /// Solver iterations per step; default [`DEFAULT_SOLVER_ITERATIONS`].
    pub solver_iterations: u32,
    /// Friction coefficient of the wheels (the ground's is 1: the contact's coefficient is the wheel's);
    /// default [`DEFAULT_WHEEL_FRICTION`].
    pub wheel_friction: f64,
    /// Friction coefficient of the body's parts; default [`DEFAULT_BODY_FRICTION`].
    pub body_friction: f64,
    /// Largest torque of each wheel's motor, N m. Default: the URDF's `effort` limit of the wheel joints, or
    /// else the torque with which the robot, of its URDF mass, just holds its `max_grade` on its driven
    /// wheels (a motor sized for the data sheet's grade): `m g r sin(atan(max_grade)) / wheels`.
    pub wheel_torque_nm: Option<f64>,
    /// Fastest wheel speed, rad/s. Default: the URDF's `velocity` limit of the wheel joints, or else the
    /// robot's `max_speed_m_s` over the wheel radius.
    pub max_wheel_speed_rad_s: Option<f64>,
    /// The wheel joints, each `continuous` or `revolute` about the link's y axis: left wheels at positive y
    /// in the base frame, right at negative. Default: every `continuous` joint of the URDF.
    pub wheel_joints: Option<Vec<String>>,
    /// Seconds without progress, while commanded to drive or turn, after which the robot is stalled; default
    /// [`DEFAULT_STALL_TIME_S`]. Progress is the distance a wheel's contact covers (the base's displacement and
    /// its heading's change times half the track), and there is none when it stays under the larger of
    /// [`PhysicsSettings::stall_distance_m`] and a quarter of what the commands asked.
    pub stall_time_s: f64,
    /// See `stall_time_s`, metres; default [`DEFAULT_STALL_DISTANCE_M`].
    pub stall_distance_m: f64,
}

impl Default for PhysicsSettings {
    fn default() -> Self {
        Self {
            time_step_s: DEFAULT_TIME_STEP_S,
            solver_iterations: DEFAULT_SOLVER_ITERATIONS,
            wheel_friction: DEFAULT_WHEEL_FRICTION,
            body_friction: DEFAULT_BODY_FRICTION,
            wheel_torque_nm: None,
            max_wheel_speed_rad_s: None,
            wheel_joints: None,
            stall_time_s: DEFAULT_STALL_TIME_S,
            stall_distance_m: DEFAULT_STALL_DISTANCE_M,
        }
    }
}
