//! The scenario file's schema: what `serde` reads from TOML. `docs/scenario-format.md` documents every key.
//!
//! Frames follow REP-103: x forward, y left, z up, metres. Angles in files are degrees (keys end in `_deg`).

use std::collections::BTreeMap;
use std::path::PathBuf;

use oeg::{ModelOptions, TraversabilityRule};

use super::scene::{Actor, Obstacle, Terrain};
use super::sensors::SensorMount;
use serde::Deserialize;

/// A whole scenario: a place, a robot, its sensors and drive, and what the run must achieve.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name, used for the output folder.
    pub name: String,
    /// What the scenario shows.
    #[serde(default)]
    pub description: String,
    /// The one source of randomness; split into named sub-streams.
    pub seed: u64,
    /// Simulated duration, seconds.
    pub duration_s: f64,
    /// Reporting step, seconds: progress is refreshed once per tick. The world is moved to each sensor scan's
    /// time, whatever the tick.
    #[serde(default = "default_tick_s")]
    pub tick_s: f64,
    /// The map's region and model.
    pub map: MapSettings,
    /// The robot, its drive and odometry.
    pub robot: RobotSettings,
    /// The run's planner check: where it plans from and to, and how it reads the map.
    #[serde(default)]
    pub planner: PlannerSettings,
    /// A closed-loop run after the drive (`None`: the drive alone).
    #[serde(default)]
    pub navigation: Option<super::navigation::Navigation>,
    /// The ground.
    #[serde(default)]
    pub terrain: Terrain,
    /// Static obstacles.
    #[serde(default)]
    pub obstacles: Vec<Obstacle>,
    /// Moving actors (people).
    #[serde(default)]
    pub actors: Vec<Actor>,
    /// Sensors on the robot.
    #[serde(default)]
    pub sensors: Vec<SensorMount>,
    /// Thresholds on the run's metrics, by metric name.
    #[serde(default)]
    pub expectations: BTreeMap<String, Expectation>,
}

/// Default simulation tick: 0.1 s (10 Hz).
pub const DEFAULT_TICK_S: f64 = 0.1;

fn default_tick_s() -> f64 {
    DEFAULT_TICK_S
}

/// The region mapped and evaluated, and the map model.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapSettings {
    /// Min-x, min-y corner of the region, metres.
    #[serde(deserialize_with = "crate::scenario::exact::array")]
    pub min_xy_m: [f64; 2],
    /// Max-x, max-y corner, metres.
    #[serde(deserialize_with = "crate::scenario::exact::array")]
    pub max_xy_m: [f64; 2],
    /// Cell size, metres.
    pub resolution_m: f64,
    /// The named model the options start from (`paper`, the default, `static` or `robust`:
    /// `oeg::MapPreset`). The keys given in `model` and `traversability` replace the preset's.
    #[serde(default)]
    pub preset: oeg::MapPreset,
    /// The `[map.model]` keys as the file gives them (`oeg::ModelOptions`' names; every one optional).
    #[serde(default, rename = "model")]
    pub model_keys: oeg::ModelKeys,
    /// `[map] traversability` as the file gives it: the step rule, unless the preset's.
    #[serde(default, rename = "traversability")]
    pub traversability_key: Option<TraversabilityRule>,
    /// The model's options, resolved when the scenario is loaded ([`MapSettings::resolve`]): the preset's for
    /// the scenario's robot, with `[map.model]`'s keys over them.
    #[serde(skip)]
    pub model: ModelOptions,
    /// The step rule, resolved with the options: `[map] traversability`, or the preset's.
    #[serde(skip)]
    pub traversability: TraversabilityRule,
}

impl MapSettings {
    /// The model as the file chooses it: the preset, and the keys and the rule it gives over the preset's.
    pub fn choice(&self) -> oeg::ModelChoice {
        oeg::ModelChoice {
            preset: self.preset,
            keys: self.model_keys,
            traversability: self.traversability_key,
        }
    }

    /// Resolves [`MapSettings::model`] and [`MapSettings::traversability`] from the file's choice for `robot`
    /// ([`oeg::ModelChoice::resolve`], the one rule). The loader calls it; so does a change of preset
    /// ([`crate::LoadedScenario::with_preset`]).
    pub fn resolve(&mut self, robot: &oeg::RobotProfile) {
        let model = self.choice().resolve(robot);
        self.model = model.options;
        self.traversability = model.rule;
    }

    /// The map's window onto a grid of `geometry` (the resolution, [`MapSettings::resolution_m`], checked by
    /// the caller): the cells of the region from `min_xy_m` (included) to `max_xy_m` (excluded),
    /// [`oeg::GridWindow::covering`]. A loaded scenario holds its own, [`crate::LoadedScenario::window`].
    ///
    /// # Errors
    /// A region that is empty or beyond the grid's index range.
    pub fn window_on(&self, geometry: oeg::GridGeometry) -> oeg::Result<oeg::GridWindow> {
        oeg::GridWindow::covering(
            geometry,
            (self.min_xy_m[0], self.min_xy_m[1]),
            (self.max_xy_m[0], self.max_xy_m[1]),
        )
    }
}

/// The run's planner check: a path on the map and on the truth, from a start to a goal. Every field optional.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlannerSettings {
    /// Where the planner starts, `[x, y]` metres; default the drive's first waypoint. The cells within the
    /// footprint radius count as drivable (see `oeg::plan`).
    #[serde(default, deserialize_with = "crate::scenario::exact::option")]
    pub start_xy_m: Option<[f64; 2]>,
    /// Where it plans to, `[x, y]` metres; default the drive's last waypoint.
    #[serde(deserialize_with = "crate::scenario::exact::option")]
    pub goal_xy_m: Option<[f64; 2]>,
    /// The robot's centre keeps at least this far from blocked cells, metres; default
    /// `oeg::DEFAULT_INFLATION_RADIUS_M` (0.25).
    pub inflation_radius_m: Option<f64>,
    /// The robot's own radius, metres: the cells under it at the start count as drivable; default
    /// `oeg::DEFAULT_FOOTPRINT_RADIUS_M` (0.25).
    pub footprint_radius_m: Option<f64>,
    /// Cells the map never observed; default `avoid`.
    pub unknown: oeg::UnknownCells,
    /// Cells the map cannot judge (`uncertain`); default `blocked`.
    pub uncertain: oeg::UncertainCells,
    /// The extra cost, in cell lengths, of crossing a cell the map cannot decide where a closed loop plans
    /// optimistically (beyond `[navigation] decide_within_m`); default `oeg::DEFAULT_DOUBT_COST` (4).
    pub doubt_cost: Option<f64>,
    /// The band beyond the inflation radius over which entering a cell costs more the nearer it lies to a
    /// blocked cell, metres; default `oeg::DEFAULT_INFLATION_COST_WIDTH_M` (0.30); 0: no cost.
    pub inflation_cost_width_m: Option<f64>,
    /// How fast that cost decays, per metre; default `oeg::DEFAULT_COST_SCALING_FACTOR` (10, nav2's).
    pub cost_scaling_factor: Option<f64>,
}

impl PlannerSettings {
    /// The planner's options.
    pub fn options(&self) -> oeg::PlannerOptions {
        oeg::PlannerOptions {
            inflation_radius_m: self.inflation_radius_m.unwrap_or(oeg::DEFAULT_INFLATION_RADIUS_M),
            footprint_radius_m: self.footprint_radius_m.unwrap_or(oeg::DEFAULT_FOOTPRINT_RADIUS_M),
            unknown: self.unknown,
            uncertain: self.uncertain,
            optimistic_beyond_m: None,
            doubt_cost: self.doubt_cost.unwrap_or(oeg::DEFAULT_DOUBT_COST),
            inflation_cost_width_m: self
                .inflation_cost_width_m
                .unwrap_or(oeg::DEFAULT_INFLATION_COST_WIDTH_M),
            cost_scaling_factor: self
                .cost_scaling_factor
                .unwrap_or(oeg::DEFAULT_COST_SCALING_FACTOR),
        }
    }

    /// The start and the goal for a drive through `waypoints` (`None` without waypoints); `goal` replaces
    /// the last waypoint as the default goal (a closed-loop run's).
    pub fn ends(&self, waypoints: &[[f64; 2]], goal: Option<[f64; 2]>) -> Option<([f64; 2], [f64; 2])> {
        Some((
            self.start_xy_m.or_else(|| waypoints.first().copied())?,
            self.goal_xy_m.or(goal).or_else(|| waypoints.last().copied())?,
        ))
    }
}

/// The robot.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSettings {
    /// The URDF file, relative to the scenario file.
    pub urdf: PathBuf,
    /// The URDF link that is the robot's base (its pose is the robot's pose).
    #[serde(default = "default_base_link")]
    pub base_link: String,
    /// Largest step the robot climbs, metres (decisions: `oeg::RobotProfile::max_step_m`, whose type and
    /// default, `oeg::DEFAULT_MAX_STEP_M`, it has).
    #[serde(default = "default_max_step")]
    pub max_step_m: f32,
    /// Robot height, metres (decisions: it passes under higher structures; `oeg::RobotProfile::height_m`).
    #[serde(default = "default_height")]
    pub height_m: f32,
    /// Steepest grade the robot climbs, rise over run (decisions: with `max_step_m` it sets the contact
    /// distance of a step, `max_step_m / max_grade`; `oeg::RobotProfile::max_grade`).
    #[serde(default = "default_max_grade")]
    pub max_grade: f32,
    /// A physics study's measured limits (the JSON `bash scripts/physics-limits.sh` writes), relative to the
    /// scenario file: when given, `max_step_m` is the climb limit measured at `[robot.physics] wheel_friction`
    /// and `height_m` the lowest underside passed, and the scenario may set neither.
    #[serde(default)]
    pub limits_from: Option<PathBuf>,
    /// Top speed, m/s: the Pioneer 3-AT's datasheet gives 0.7 (closed-loop runs).
    #[serde(default = "default_max_speed")]
    pub max_speed_m_s: f64,
    /// Top turn rate, degrees per second: the Pioneer 3-AT's datasheet gives 140 (closed-loop runs).
    #[serde(default = "default_max_turn_rate")]
    pub max_turn_rate_deg_s: f64,
    /// The path it drives (a drive of one waypoint places the robot there).
    pub drive: Drive,
    /// Odometry drift of the estimated pose.
    #[serde(default)]
    pub odometry: Odometry,
    /// What the URDF does not say, for a drive on the wheels (`[robot.drive] mode = "physics"`).
    #[serde(default)]
    pub physics: super::physics::PhysicsSettings,
}

fn default_base_link() -> String {
    "base_link".into()
}

/// The decision profile's defaults, from their one home: `oeg::RobotProfile::default()`.
fn default_max_step() -> f32 {
    oeg::RobotProfile::default().max_step_m
}

fn default_height() -> f32 {
    oeg::RobotProfile::default().height_m
}

fn default_max_grade() -> f32 {
    oeg::RobotProfile::default().max_grade
}

/// Default top speed, m/s (Pioneer 3-AT datasheet).
pub const DEFAULT_MAX_SPEED_M_S: f64 = 0.7;
/// Default top turn rate, degrees per second (Pioneer 3-AT datasheet).
pub const DEFAULT_MAX_TURN_RATE_DEG_S: f64 = 140.0;

fn default_max_speed() -> f64 {
    DEFAULT_MAX_SPEED_M_S
}

fn default_max_turn_rate() -> f64 {
    DEFAULT_MAX_TURN_RATE_DEG_S
}

impl RobotSettings {
    /// The robot as the decisions see it (the truth's and the map's): one type, `oeg::RobotProfile`.
    pub fn profile(&self) -> oeg::RobotProfile {
        oeg::RobotProfile {
            max_step_m: self.max_step_m,
            height_m: self.height_m,
            max_grade: self.max_grade,
        }
    }
}

/// The drive: straight segments between waypoints at a constant speed; the robot turns on the spot at each
/// waypoint and stops at the last.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Drive {
    /// Waypoints `[x, y]`, metres; the first is the start.
    #[serde(deserialize_with = "crate::scenario::exact::each")]
    pub waypoints_xy_m: Vec<[f64; 2]>,
    /// Speed along the path, m/s.
    pub speed_m_s: f64,
    /// Heading at the start, degrees from +x; default: towards the second waypoint.
    #[serde(default)]
    pub start_yaw_deg: Option<f64>,
    /// Placed on the path (the default) or driven on its wheels.
    #[serde(default)]
    pub mode: super::physics::DriveMode,
}

/// Odometry drift: the estimated pose is the true pose plus a random walk whose standard deviation grows with
/// the square root of the distance driven. Zero by default (perfect localisation).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Odometry {
    /// Position drift, metres per square root of metre driven (per axis).
    pub xy_sigma_m_per_sqrt_m: f64,
    /// Heading drift, degrees per square root of metre driven.
    pub yaw_sigma_deg_per_sqrt_m: f64,
}

/// A threshold on one metric: the run fails when the value is below `min` or above `max`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Expectation {
    /// Smallest acceptable value.
    #[serde(default)]
    pub min: Option<f64>,
    /// Largest acceptable value.
    #[serde(default)]
    pub max: Option<f64>,
}

/// Where a scenario came from: resolves the paths it mentions.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioSource {
    /// The scenario file.
    pub path: PathBuf,
    /// Its text, for error positions.
    pub text: String,
}

impl ScenarioSource {
    /// A path from the scenario, relative to the scenario file's folder.
    pub fn resolve(&self, relative: &std::path::Path) -> PathBuf {
        self.path
            .parent()
            .map_or_else(|| relative.to_path_buf(), |dir| dir.join(relative))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_robot_s_decision_defaults_are_the_profile_s() {
        let robot: RobotSettings = toml::from_str(
            "urdf = \"robot.urdf\"\n[drive]\nwaypoints_xy_m = [[0.0, 0.0]]\nspeed_m_s = 0.5\n",
        )
        .expect("a robot with its decision keys left out");
        assert_eq!(robot.profile(), oeg::RobotProfile::default());
    }
}
