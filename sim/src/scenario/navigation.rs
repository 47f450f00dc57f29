//! `[navigation]`: a closed-loop run. After the scripted drive (a drive of one waypoint only places the robot
//! there), the robot plans on the map it has built so far, follows the plan with a pure-pursuit controller,
//! keeps mapping, and plans again, until it reaches the goal, is stuck, or runs out of time.
//! `docs/scenario-format.md` documents every key; defaults follow nav2's where it has one.

use serde::Deserialize;

/// Default replanning period, seconds: nav2's default behaviour tree replans at 1 Hz.
pub const DEFAULT_REPLAN_PERIOD_S: f64 = 1.0;
/// Default goal tolerance, metres: nav2's `SimpleGoalChecker.xy_goal_tolerance`.
pub const DEFAULT_GOAL_TOLERANCE_M: f64 = 0.25;
/// Default pure-pursuit lookahead, metres: nav2's Regulated Pure Pursuit `lookahead_dist`.
pub const DEFAULT_LOOKAHEAD_M: f64 = 0.6;
/// Default cruise speed, m/s.
pub const DEFAULT_NAVIGATION_SPEED_M_S: f64 = 0.4;
/// Default stuck window, seconds: nav2's `SimpleProgressChecker.movement_time_allowance`.
pub const DEFAULT_STUCK_TIME_S: f64 = 10.0;
/// Default stuck radius, metres: nav2's `SimpleProgressChecker.required_movement_radius`.
pub const DEFAULT_STUCK_RADIUS_M: f64 = 0.5;
/// Default wall-time limit of one call of an external planner, seconds.
pub const DEFAULT_PLANNER_TIMEOUT_S: f64 = 10.0;

/// Which planner plans at each replanning time.
#[derive(Debug, Clone, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlannerKind {
    /// The built-in A* (`oeg::plan`) with the scenario's `[planner]` options.
    #[default]
    Astar,
    /// An external program (`docs/planner-protocol.md`): `command` in this table, allowed with
    /// `--allow-scenario-command`, or `--planner-command` on the command line.
    External,
}

/// A closed-loop run.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Navigation {
    /// Where the robot must go, `[x, y]` metres, world frame, inside the map region.
    #[serde(deserialize_with = "crate::scenario::exact::array")]
    pub goal_xy_m: [f64; 2],
    /// Seconds the robot may navigate after the scripted drive; default: until `duration_s`.
    #[serde(default)]
    pub time_limit_s: Option<f64>,
    /// Seconds between plans, simulated time.
    #[serde(default = "default_replan")]
    pub replan_period_s: f64,
    /// The goal counts as reached when the estimated position is this close, metres.
    #[serde(default = "default_goal_tolerance")]
    pub goal_tolerance_m: f64,
    /// Pure-pursuit lookahead along the path, metres.
    #[serde(default = "default_lookahead")]
    pub lookahead_m: f64,
    /// Cruise speed, m/s; at most the robot's `max_speed_m_s`.
    #[serde(default = "default_speed")]
    pub speed_m_s: f64,
    /// The robot is stuck when it has not moved `stuck_radius_m` in this many seconds.
    #[serde(default = "default_stuck_time")]
    pub stuck_time_s: f64,
    /// See `stuck_time_s`, metres.
    #[serde(default = "default_stuck_radius")]
    pub stuck_radius_m: f64,
    /// What the planner makes of never-observed cells while navigating; default `drivable` (nav2's
    /// `allow_unknown: true`: a robot plans through what it has not seen yet, and replans when it sees it).
    /// The other options come from `[planner]`, but for the inflation, which defaults to the footprint's
    /// circumscribed radius.
    #[serde(default = "default_unknown")]
    pub unknown: oeg::UnknownCells,
    /// `astar` (default) or `external`.
    #[serde(default)]
    pub planner: PlannerKind,
    /// The external planner's command line (program first). A scenario's command runs only with
    /// `--allow-scenario-command`.
    #[serde(default)]
    pub command: Option<Vec<String>>,
    /// Wall-time limit of one external planner call, seconds.
    #[serde(default = "default_planner_timeout")]
    pub planner_timeout_s: f64,
}

fn default_unknown() -> oeg::UnknownCells {
    oeg::UnknownCells::Drivable
}
fn default_replan() -> f64 {
    DEFAULT_REPLAN_PERIOD_S
}
fn default_goal_tolerance() -> f64 {
    DEFAULT_GOAL_TOLERANCE_M
}
fn default_lookahead() -> f64 {
    DEFAULT_LOOKAHEAD_M
}
fn default_speed() -> f64 {
    DEFAULT_NAVIGATION_SPEED_M_S
}
fn default_stuck_time() -> f64 {
    DEFAULT_STUCK_TIME_S
}
fn default_stuck_radius() -> f64 {
    DEFAULT_STUCK_RADIUS_M
}
fn default_planner_timeout() -> f64 {
    DEFAULT_PLANNER_TIMEOUT_S
}
