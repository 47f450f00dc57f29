//! The robot's decision limits from a physics study's measured ones (`[robot] limits_from`): the truth and the
//! map then judge steps and clearances by what the simulated robot was seen to climb and pass, not by the
//! paper's figures.
//!
//! The file is the one `bash scripts/physics-limits.sh` writes (`docs/results/physics_limits.json`):
//!
//! ```json
//! { "climb_limit_m": [ { "wheel_friction": 0.8, "limit_m": 0.025 } ], "clearance_m": 0.47 }
//! ```
//!
//! `max_step_m` becomes the climb limit measured at the scenario's own wheel friction
//! (`[robot.physics] wheel_friction`), and `height_m` the lowest board underside passed in every run.

use serde::Deserialize;

use super::check::Checker;
use super::load::KeySeg;
use super::schema::Scenario;
use crate::error::Result;

/// The largest limit the file may hold, metres: a climb limit or a clearance above it is no measurement of a
/// wheeled robot.
const MAX_LIMIT_M: f64 = 10.0;
/// How near a measured friction must be to the scenario's to be its measurement.
const FRICTION_TOLERANCE: f64 = 1e-6;

/// The measured limits, as the study writes them (other keys, such as the commit, are read past).
#[derive(Debug, Deserialize)]
struct MeasuredLimits {
    climb_limit_m: Vec<ClimbLimit>,
    clearance_m: Option<f64>,
}

/// The climb limit at one wheel friction; `None` when no curb of the study was climbed in half the runs.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ClimbLimit {
    wheel_friction: f64,
    limit_m: Option<f64>,
}

/// Sets `scenario.robot`'s `max_step_m` and `height_m` from the file `[robot] limits_from` names, when it
/// names one. `stated(key)` says whether the scenario itself sets `robot.<key>`: a limit set twice is an error.
///
/// # Errors
/// [`crate::SimError::Scenario`] at `robot.limits_from` when the file cannot be read, is not the study's JSON,
/// has no measurement at the scenario's wheel friction, or holds a limit that is not a positive length; or when
/// the scenario also sets `max_step_m` or `height_m`.
pub(super) fn apply(
    checker: &Checker<'_>,
    scenario: &mut Scenario,
    stated: impl Fn(&str) -> bool,
) -> Result<()> {
    let Some(relative) = scenario.robot.limits_from.clone() else {
        return Ok(());
    };
    let at = [KeySeg::Key("robot"), KeySeg::Key("limits_from")];
    let error = |message: String| checker.error(&at, message);
    if let Some(key) = ["max_step_m", "height_m"].into_iter().find(|k| stated(k)) {
        return Err(error(format!(
            "`robot.{key}` is set too: `limits_from` sets it from the study, so set one or the other"
        )));
    }
    let path = checker.source.resolve(&relative);
    let file = |message: String| error(format!("{}: {message}", path.display()));
    let text = crate::error::read_text(&path).map_err(|e| error(e.to_string()))?;
    let limits: MeasuredLimits = serde_json::from_str(&text).map_err(|e| {
        file(format!(
            "line {}, column {}: {e}; expected the JSON `bash scripts/physics-limits.sh` writes, with \
             `climb_limit_m` (a list of {{\"wheel_friction\", \"limit_m\"}}) and `clearance_m`",
            e.line(),
            e.column()
        ))
    })?;
    let friction = scenario.robot.physics.wheel_friction;
    let entry = limits
        .climb_limit_m
        .iter()
        .find(|c| (c.wheel_friction - friction).abs() <= FRICTION_TOLERANCE)
        .ok_or_else(|| {
            let measured: Vec<String> = limits
                .climb_limit_m
                .iter()
                .map(|c| c.wheel_friction.to_string())
                .collect();
            file(format!(
                "no climb limit measured at the scenario's wheel friction {friction} (`robot.physics.\
                 wheel_friction`); the study measured {}",
                if measured.is_empty() {
                    "none".to_string()
                } else {
                    measured.join(", ")
                }
            ))
        })?;
    let step = measured_length(
        entry.limit_m,
        &format!("climb_limit_m at wheel friction {friction}"),
    )
    .map_err(file)?;
    let clearance = measured_length(limits.clearance_m, "clearance_m").map_err(file)?;
    scenario.robot.max_step_m = step as f32;
    scenario.robot.height_m = clearance as f32;
    Ok(())
}

/// A measured limit as a length: present, finite, positive and at most [`MAX_LIMIT_M`].
fn measured_length(value: Option<f64>, what: &str) -> std::result::Result<f64, String> {
    match value {
        None => Err(format!(
            "`{what}` is null: the study measured no limit there, so it cannot set the robot's limit"
        )),
        Some(v) if v.is_finite() && v > 0.0 && v <= MAX_LIMIT_M => Ok(v),
        Some(v) => Err(format!(
            "`{what}` is {v}; expected a length in metres, above 0 and at most {MAX_LIMIT_M}"
        )),
    }
}

/// Whether `doc` (a scenario's TOML) sets `robot.<key>`.
pub(super) fn stated_in(doc: &toml::Table, key: &str) -> bool {
    doc.get("robot")
        .and_then(|r| r.as_table())
        .is_some_and(|r| r.contains_key(key))
}

/// As [`stated_in`], for a document parsed with its places.
pub(super) fn stated_in_parsed(doc: &toml::de::DeTable<'_>, key: &str) -> bool {
    doc.iter()
        .find(|(k, _)| k.get_ref() == "robot")
        .is_some_and(|(_, v)| match v.get_ref() {
            toml::de::DeValue::Table(t) => t.iter().any(|(k, _)| k.get_ref() == key),
            _ => false,
        })
}
