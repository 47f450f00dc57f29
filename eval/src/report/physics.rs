//! A drive on the wheels' files: `physics.json` (the robot's resolved physical parameters, the figures and
//! the events by name) and `physics.csv` (the sampled state: pose, roll and pitch, commanded and achieved
//! motion, wheel slip, distance from the scripted path).

use std::path::{Path, PathBuf};

use serde::Serialize;
use sim::physics::{PhysicsEvent, PhysicsSample, WheeledModel};

use crate::error::Result;
use crate::judge::{PhysicsMetrics, PhysicsRecord};
use crate::output::{CsvRow, write_json, write_table};

impl CsvRow for PhysicsSample {
    const COLUMNS: &'static [&'static str] = &[
        "time_s",
        "x_m",
        "y_m",
        "z_m",
        "yaw_deg",
        "roll_deg",
        "pitch_deg",
        "commanded_speed_m_s",
        "commanded_turn_rate_deg_s",
        "speed_m_s",
        "turn_rate_deg_s",
        "slip_left",
        "slip_right",
        "path_error_m",
    ];
}

/// The robot as the physics drove it: what the URDF and `[robot.physics]` resolved to.
#[derive(Debug, Clone, Serialize)]
struct RobotPhysics {
    mass_kg: f64,
    wheel_radius_m: f64,
    wheel_torque_nm: f64,
    tip_roll_limit_deg: f64,
    tip_pitch_limit_deg: f64,
    time_step_s: f64,
    solver_iterations: u32,
    wheel_friction: f64,
    body_friction: f64,
}

/// `physics.json`.
#[derive(Debug, Clone, Serialize)]
struct PhysicsSummary<'a> {
    robot: RobotPhysics,
    figures: PhysicsMetrics,
    events: &'a [PhysicsEvent],
}

/// Writes `physics.json` and `physics.csv` for a drive of `model` on its wheels.
///
/// # Errors
/// A failed write.
pub(crate) fn write_physics(
    out_dir: &Path,
    model: &WheeledModel,
    record: &PhysicsRecord<'_>,
) -> Result<Vec<PathBuf>> {
    let settings = model.settings();
    let (roll, pitch) = model.tip_limits_deg();
    let summary = PhysicsSummary {
        robot: RobotPhysics {
            mass_kg: model.mass_kg(),
            wheel_radius_m: model.wheel_radius_m(),
            wheel_torque_nm: model.wheel_torque_nm(),
            tip_roll_limit_deg: roll,
            tip_pitch_limit_deg: pitch,
            time_step_s: settings.time_step_s,
            solver_iterations: settings.solver_iterations,
            wheel_friction: settings.wheel_friction,
            body_friction: settings.body_friction,
        },
        figures: PhysicsMetrics::of(record),
        events: record.events,
    };
    let json = out_dir.join("physics.json");
    write_json(&json, &summary)?;
    let csv = out_dir.join("physics.csv");
    write_table(&csv, record.samples)?;
    Ok(vec![json, csv])
}
