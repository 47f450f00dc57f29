//! The check of `[robot.physics]`: each value in a range a wheeled robot's simulation can mean.

use super::super::load::KeySeg;
use super::super::physics::PhysicsSettings;
use super::Checker;
use crate::error::Result;

/// Largest physics time step, seconds: a wheel of a few centimetres' radius at walking speed moves more than
/// its contact patch in a longer step.
pub(crate) const MAX_TIME_STEP_S: f64 = 0.05;
/// Smallest physics time step, seconds: below it a run of the longest duration takes days.
pub(crate) const MIN_TIME_STEP_S: f64 = 1e-4;
/// Most solver iterations per step.
pub(crate) const MAX_SOLVER_ITERATIONS: u32 = 64;
/// Largest friction coefficient: beyond it no material pair exists and the solver's cone is meaningless.
pub(crate) const MAX_FRICTION: f64 = 5.0;
/// Largest wheel torque, N m, and wheel speed, rad/s: far beyond any wheeled mobile robot.
pub(crate) const MAX_WHEEL_TORQUE_NM: f64 = 10_000.0;
/// See [`MAX_WHEEL_TORQUE_NM`].
pub(crate) const MAX_WHEEL_SPEED_RAD_S: f64 = 1_000.0;

impl Checker<'_> {
    /// `[robot.physics]`.
    pub(super) fn validate_physics(&self, p: &PhysicsSettings) -> Result<()> {
        use KeySeg::Key as K;
        let at = |key| [K("robot"), K("physics"), K(key)];
        let within = |v: f64, lo: f64, hi: f64, key: &'static str, what: &str| {
            self.check(v.is_finite() && (lo..=hi).contains(&v), &at(key), || {
                format!("expected {what} from {lo} to {hi}, got {v}")
            })
        };
        within(
            p.time_step_s,
            MIN_TIME_STEP_S,
            MAX_TIME_STEP_S,
            "time_step_s",
            "a time step in seconds",
        )?;
        self.check(
            (1..=MAX_SOLVER_ITERATIONS).contains(&p.solver_iterations),
            &at("solver_iterations"),
            || {
                format!(
                    "expected from 1 to {MAX_SOLVER_ITERATIONS} solver iterations, got {}",
                    p.solver_iterations
                )
            },
        )?;
        within(
            p.wheel_friction,
            0.0,
            MAX_FRICTION,
            "wheel_friction",
            "a friction coefficient",
        )?;
        within(
            p.body_friction,
            0.0,
            MAX_FRICTION,
            "body_friction",
            "a friction coefficient",
        )?;
        if let Some(t) = p.wheel_torque_nm {
            self.check(
                t.is_finite() && t > 0.0 && t <= MAX_WHEEL_TORQUE_NM,
                &at("wheel_torque_nm"),
                || format!("expected a positive torque in N m of at most {MAX_WHEEL_TORQUE_NM}, got {t}"),
            )?;
        }
        if let Some(w) = p.max_wheel_speed_rad_s {
            self.check(
                w.is_finite() && w > 0.0 && w <= MAX_WHEEL_SPEED_RAD_S,
                &at("max_wheel_speed_rad_s"),
                || {
                    format!(
                        "expected a positive wheel speed in rad/s of at most {MAX_WHEEL_SPEED_RAD_S}, got {w}"
                    )
                },
            )?;
        }
        within(p.stall_time_s, 0.1, 600.0, "stall_time_s", "a time in seconds")?;
        within(
            p.stall_distance_m,
            0.0,
            10.0,
            "stall_distance_m",
            "a distance in metres",
        )?;
        Ok(())
    }
}
