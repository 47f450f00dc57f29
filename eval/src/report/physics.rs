//! A drive on the wheels' files: `physics.json` (the robot's resolved physical parameters, the figures and
//! the events by name) and `physics.csv` (the sampled state: pose, roll and pitch, commanded and achieved
//! motion, wheel slip, distance from the scripted path), and its section of the report page.

use std::path::{Path, PathBuf};

use serde::Serialize;
use sim::physics::{PhysicsEvent, PhysicsSample, WheeledModel};

use crate::error::Result;
use crate::judge::{PhysicsMetrics, PhysicsRecord};
use crate::output::html::{Page, table_html};
use crate::output::{CsvRow, write_json, write_table};
use serde_json::Value;

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

/// Writes `physics.json` and `physics.csv` when the scenario's robot drove on its wheels in `world` (none for
/// a kinematic drive).
///
/// # Errors
/// A failed write.
pub(crate) fn write_physics(
    out_dir: &Path,
    loaded: &sim::LoadedScenario,
    world: &sim::World,
) -> Result<Vec<PathBuf>> {
    match (&loaded.wheeled, PhysicsRecord::of(world)) {
        (Some(model), Some(record)) => write_files(out_dir, model, &record),
        _ => Ok(Vec::new()),
    }
}

/// `physics.json` and `physics.csv` of a drive of `model` on its wheels.
fn write_files(out_dir: &Path, model: &WheeledModel, record: &PhysicsRecord<'_>) -> Result<Vec<PathBuf>> {
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

/// What happened to the robot on its wheels: the figures in words and the events by name.
pub(super) fn page_section(page: &mut Page, record: &PhysicsRecord<'_>) {
    let m = PhysicsMetrics::of(record);
    page.heading("physics", "On its wheels");
    let count = |v: Option<u64>| v.unwrap_or(0);
    page.paragraph(&format!(
        "The robot drove on its wheels in the physics world: {}; {} body contacts with obstacles or people, \
         {} with the ground, {} stalls{}; largest roll {:.1} deg and pitch {:.1} deg; at most {:.3} m off the \
         scripted path. The sampled state is in physics.csv, the events and the robot's physical parameters \
         in physics.json.",
        match m.goal_time_s.flatten() {
            Some(t) => format!("the goal reached at {t:.1} s"),
            None => "the goal not reached".to_string(),
        },
        count(m.contacts),
        count(m.ground_contacts),
        count(m.stalls),
        if m.tipped_over == Some(true) { ", and it tipped over" } else { "" },
        m.max_roll_deg.unwrap_or(0.0),
        m.max_pitch_deg.unwrap_or(0.0),
        m.max_path_error_m.unwrap_or(0.0),
    ));
    if !record.events.is_empty() {
        let rows: Vec<Vec<String>> = record
            .events
            .iter()
            .map(|e| {
                let kind = serde_json::to_value(&e.kind).unwrap_or(Value::Null);
                let name = kind.get("kind").and_then(Value::as_str).unwrap_or("").to_string();
                let detail = kind
                    .as_object()
                    .map(|o| {
                        o.iter()
                            .filter(|(k, _)| k.as_str() != "kind")
                            .map(|(k, v)| format!("{k}: {}", super::page::value_text(Some(v))))
                            .collect::<Vec<_>>()
                            .join(", ")
                    })
                    .unwrap_or_default();
                vec![
                    format!("{:.2}", e.time_s),
                    name,
                    format!("({:.2}, {:.2})", e.x_m, e.y_m),
                    detail,
                ]
            })
            .collect();
        let header: Vec<String> = ["time_s", "event", "where (m)", "detail"]
            .map(String::from)
            .to_vec();
        page.raw(&table_html(&header, &rows));
    }
}
