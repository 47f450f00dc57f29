//! The drive on the wheels' keys of `metrics.json` (`phys_*`): what physically happened, from the events and
//! samples of `sim::physics`. Absent (not null) for a kinematic drive, so a kinematic run's `metrics.json` is
//! what it was before the robot could drive on its wheels.

use serde::Serialize;
use sim::physics::{PhysicsEvent, PhysicsEventKind, PhysicsSample};

/// A drive on the wheels: its events and its sampled state.
#[derive(Debug, Clone, Copy)]
pub struct PhysicsRecord<'a> {
    /// What happened, by name.
    pub events: &'a [PhysicsEvent],
    /// The state every `sim::physics::SAMPLE_PERIOD_S`.
    pub samples: &'a [PhysicsSample],
}

impl<'a> PhysicsRecord<'a> {
    /// The record of a world whose robot drives on its wheels (`None`: a kinematic drive).
    pub fn of(world: &'a sim::World) -> Option<Self> {
        Some(Self {
            events: world.physics_events()?,
            samples: world.physics_samples()?,
        })
    }
}

/// The physics figures of `metrics.json`, each absent for a kinematic drive. Flattened into
/// [`crate::judge::Metrics`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct PhysicsMetrics {
    /// Times a part of the body (not a wheel) started touching an obstacle or a person.
    #[serde(rename = "phys_contacts", skip_serializing_if = "Option::is_none")]
    pub contacts: Option<u64>,
    /// Times the body started touching the ground (high-centred on a step or a crest).
    #[serde(rename = "phys_ground_contacts", skip_serializing_if = "Option::is_none")]
    pub ground_contacts: Option<u64>,
    /// Stalls: commanded to move, no progress for `stall_time_s`.
    #[serde(rename = "phys_stalls", skip_serializing_if = "Option::is_none")]
    pub stalls: Option<u64>,
    /// Whether the robot tipped over.
    #[serde(rename = "phys_tipped_over", skip_serializing_if = "Option::is_none")]
    pub tipped_over: Option<bool>,
    /// Whether the scripted drive reached its last waypoint.
    #[serde(rename = "phys_goal_reached", skip_serializing_if = "Option::is_none")]
    pub goal_reached: Option<bool>,
    /// When it did, seconds: null when it did not (the inner `None`), absent for a kinematic drive.
    #[serde(rename = "phys_goal_time_s", skip_serializing_if = "Option::is_none")]
    pub goal_time_s: Option<Option<f64>>,
    /// The largest distance of the base from the scripted path while the robot followed it, metres.
    #[serde(rename = "phys_max_path_error_m", skip_serializing_if = "Option::is_none")]
    pub max_path_error_m: Option<f64>,
    /// The largest roll and pitch of the base, degrees.
    #[serde(rename = "phys_max_roll_deg", skip_serializing_if = "Option::is_none")]
    pub max_roll_deg: Option<f64>,
    /// See `phys_max_roll_deg`.
    #[serde(rename = "phys_max_pitch_deg", skip_serializing_if = "Option::is_none")]
    pub max_pitch_deg: Option<f64>,
    /// The mean absolute difference between the commanded and the achieved speed, m/s, over the samples.
    #[serde(rename = "phys_mean_speed_error_m_s", skip_serializing_if = "Option::is_none")]
    pub mean_speed_error_m_s: Option<f64>,
    /// The mean absolute wheel slip over the samples where the robot was commanded to move.
    #[serde(rename = "phys_mean_wheel_slip", skip_serializing_if = "Option::is_none")]
    pub mean_wheel_slip: Option<f64>,
}

impl PhysicsMetrics {
    /// Every figure present and zero (`false`): the shape of a drive on the wheels' keys.
    pub const ZERO: Self = Self {
        contacts: Some(0),
        ground_contacts: Some(0),
        stalls: Some(0),
        tipped_over: Some(false),
        goal_reached: Some(false),
        goal_time_s: Some(Some(0.0)),
        max_path_error_m: Some(0.0),
        max_roll_deg: Some(0.0),
        max_pitch_deg: Some(0.0),
        mean_speed_error_m_s: Some(0.0),
        mean_wheel_slip: Some(0.0),
    };

    /// The figures of a drive on the wheels.
    pub fn of(record: &PhysicsRecord<'_>) -> Self {
        let count = |f: &dyn Fn(&PhysicsEventKind) -> bool| {
            record.events.iter().filter(|e| f(&e.kind)).count() as u64
        };
        let touched = |ground: bool| move |k: &PhysicsEventKind| matches!(k, PhysicsEventKind::Contact { with, .. } if (with == "ground") == ground);
        let goal_time_s = record
            .events
            .iter()
            .find(|e| e.kind == PhysicsEventKind::GoalReached)
            .map(|e| e.time_s);
        let samples = record.samples;
        let max = |f: &dyn Fn(&PhysicsSample) -> f64| samples.iter().map(f).fold(0.0, f64::max);
        let moving: Vec<&PhysicsSample> = samples
            .iter()
            .filter(|s| s.commanded_speed_m_s.abs() > 1e-3)
            .collect();
        let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        let speed_errors: Vec<f64> = samples
            .iter()
            .map(|s| (s.commanded_speed_m_s - s.speed_m_s).abs())
            .collect();
        let slips: Vec<f64> = moving
            .iter()
            .map(|s| (s.slip_left.abs() + s.slip_right.abs()) / 2.0)
            .collect();
        Self {
            contacts: Some(count(&touched(false))),
            ground_contacts: Some(count(&touched(true))),
            stalls: Some(count(&|k| matches!(k, PhysicsEventKind::Stall { .. }))),
            tipped_over: Some(count(&|k| matches!(k, PhysicsEventKind::TipOver { .. })) > 0),
            goal_reached: Some(goal_time_s.is_some()),
            goal_time_s: Some(goal_time_s),
            max_path_error_m: Some(max(&|s| s.path_error_m.unwrap_or(0.0))),
            max_roll_deg: Some(max(&|s| s.roll_deg.abs())),
            max_pitch_deg: Some(max(&|s| s.pitch_deg.abs())),
            mean_speed_error_m_s: mean(&speed_errors),
            mean_wheel_slip: mean(&slips),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t: f64, commanded: f64, speed: f64, slip: f64, roll: f64) -> PhysicsSample {
        PhysicsSample {
            time_s: t,
            x_m: 0.0,
            y_m: 0.0,
            z_m: 0.0,
            yaw_deg: 0.0,
            roll_deg: roll,
            pitch_deg: -2.0 * roll,
            commanded_speed_m_s: commanded,
            commanded_turn_rate_deg_s: 0.0,
            speed_m_s: speed,
            turn_rate_deg_s: 0.0,
            slip_left: slip,
            slip_right: -slip,
            path_error_m: Some(roll / 100.0),
        }
    }

    fn event(t: f64, kind: PhysicsEventKind) -> PhysicsEvent {
        PhysicsEvent {
            time_s: t,
            x_m: 1.0,
            y_m: 2.0,
            kind,
        }
    }

    #[test]
    fn the_figures_count_the_events_and_summarize_the_samples() {
        let contact = |with: &str| PhysicsEventKind::Contact {
            with: with.into(),
            link: "chassis".into(),
        };
        let events = [
            event(1.0, contact("board")),
            event(1.5, contact("ground")),
            event(2.0, PhysicsEventKind::Stall { wheel_slip: 0.9 }),
            event(3.0, contact("person 0")),
        ];
        let samples = [sample(0.0, 0.5, 0.4, 0.2, 1.0), sample(0.05, 0.0, 0.0, 0.0, -3.0)];
        let m = PhysicsMetrics::of(&PhysicsRecord {
            events: &events,
            samples: &samples,
        });
        assert_eq!(
            (m.contacts, m.ground_contacts, m.stalls),
            (Some(2), Some(1), Some(1))
        );
        assert_eq!(
            (m.tipped_over, m.goal_reached, m.goal_time_s),
            (Some(false), Some(false), Some(None))
        );
        assert_eq!((m.max_roll_deg, m.max_pitch_deg), (Some(3.0), Some(6.0)));
        assert_eq!(m.max_path_error_m, Some(0.01));
        assert!((m.mean_speed_error_m_s.expect("samples") - 0.05).abs() < 1e-12);
        // Slip over the samples commanded to move only.
        assert_eq!(m.mean_wheel_slip, Some(0.2));
        // A drive on the wheels that did not arrive writes its arrival time as null, for a stable column.
        let json = serde_json::to_value(m).expect("json");
        assert!(json["phys_goal_time_s"].is_null() && json.get("phys_goal_time_s").is_some());
    }

    #[test]
    fn a_kinematic_run_writes_no_physics_key() {
        let json = serde_json::to_string(&PhysicsMetrics::default()).expect("json");
        assert_eq!(json, "{}");
        let zero = serde_json::to_value(PhysicsMetrics::ZERO).expect("json");
        assert_eq!(zero.as_object().map(|o| o.len()), Some(11));
    }
}
