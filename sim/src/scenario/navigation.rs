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
/// Default wait of the recovery sequence, seconds: nav2's `Wait` behaviour in its default behaviour tree.
pub const DEFAULT_RECOVERY_WAIT_S: f64 = 5.0;
/// Default back-up distance of the recovery sequence, metres: nav2's `BackUp` in its default behaviour tree.
pub const DEFAULT_BACKUP_DISTANCE_M: f64 = 0.3;
/// Default back-up speed of the recovery sequence, m/s (nav2's default tree backs up at 0.05 m/s; a tenth of
/// the robot's cruise speed).
pub const DEFAULT_BACKUP_SPEED_M_S: f64 = 0.05;
/// Default look-ahead of the collision guard, seconds: nav2's Collision Monitor `time_before_collision` (its
/// `approach` action's default).
pub const DEFAULT_GUARD_TIME_S: f64 = 2.0;
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

/// How much shorter a new path must be than the rest of the path being followed for
/// [`Replanning::WhenShorter`] to switch to it: a tenth.
pub const SWITCH_SHORTER_FRACTION: f64 = 0.1;

/// When the navigator takes a new path, at each replanning time (nav2's navigation behaviour trees).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Replanning {
    /// It plans and takes the new path every time (nav2's default tree,
    /// `navigate_to_pose_w_replanning_and_recovery`). As the map firms up, two near-equal ways round an
    /// obstacle can take turns being the shorter, and the robot swings between them.
    Periodic,
    /// It plans only when the path ahead is no longer one the planner allows on the map, or there is none
    /// (nav2's `navigate_w_replanning_only_if_path_becomes_invalid`, its `IsPathValid` condition). A first path
    /// planned through unseen space is kept even once a much shorter one shows.
    #[default]
    WhenInvalid,
    /// It plans every time, and keeps the path ahead while it stays valid unless the new one is shorter than
    /// its rest by more than [`SWITCH_SHORTER_FRACTION`]: committed to its way, yet taking a clearly better
    /// one. On the randomized closed-loop study it let a robust map's robot into a cell its map had just
    /// blocked once in 100 runs, where `WhenInvalid` touched none (`docs/results/safe_and_live.md`).
    WhenShorter,
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
    /// When a replanning time's path replaces the one being followed.
    #[serde(default)]
    pub replan: Replanning,
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
    /// Cells the map cannot decide (uncertain, or never observed) farther than this from the robot, metres,
    /// are planned through at `[planner] doubt_cost` each (nav2's `allow_unknown`, for uncertain cells too):
    /// the robot drives closer and looks again. Nearer ones decide as `[planner] uncertain` and `unknown` say.
    /// Default ([`Navigation::decide_within`]): what the robot may cover before its next plan takes effect, one
    /// replanning period at cruise speed plus the controller's lookahead (1.0 m with the defaults).
    #[serde(default)]
    pub decide_within_m: Option<f64>,
    /// Seconds the recovery sequence waits (see [`Navigation`]'s recovery), default
    /// [`DEFAULT_RECOVERY_WAIT_S`].
    #[serde(default = "default_recovery_wait")]
    pub recovery_wait_s: f64,
    /// Metres the recovery sequence backs up, default [`DEFAULT_BACKUP_DISTANCE_M`]; 0: it does not.
    #[serde(default = "default_backup_distance")]
    pub backup_distance_m: f64,
    /// Speed of the back-up, m/s, default [`DEFAULT_BACKUP_SPEED_M_S`].
    #[serde(default = "default_backup_speed")]
    pub backup_speed_m_s: f64,
    /// The collision guard's look-ahead, seconds (nav2's Collision Monitor, `approach` action): every command,
    /// the controller's or a recovery's, is carried forward this long with the footprint, and slowed so that
    /// the footprint enters no cell the map calls blocked sooner than this; the robot stops short of one.
    /// Default [`DEFAULT_GUARD_TIME_S`]; 0: no guard.
    #[serde(default = "default_guard_time")]
    pub guard_time_s: f64,
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

impl Navigation {
    /// [`Navigation::decide_within_m`], or its default: `lookahead_m + speed_m_s * replan_period_s`.
    pub fn decide_within(&self) -> f64 {
        self.decide_within_m
            .unwrap_or(self.lookahead_m + self.speed_m_s * self.replan_period_s)
    }
}

fn default_recovery_wait() -> f64 {
    DEFAULT_RECOVERY_WAIT_S
}
fn default_backup_distance() -> f64 {
    DEFAULT_BACKUP_DISTANCE_M
}
fn default_backup_speed() -> f64 {
    DEFAULT_BACKUP_SPEED_M_S
}
fn default_guard_time() -> f64 {
    DEFAULT_GUARD_TIME_S
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

#[cfg(test)]
mod tests {
    use super::Navigation;

    fn navigation(extra: &str) -> Navigation {
        toml::from_str(&format!("goal_xy_m = [5.0, 0.0]\n{extra}")).expect("valid")
    }

    #[test]
    fn cells_decide_within_one_replanning_period_at_cruise_speed_plus_the_lookahead() {
        // The defaults: 0.6 m of lookahead and 1 s at 0.4 m/s.
        assert!((navigation("").decide_within() - 1.0).abs() < 1e-12);
        assert!((navigation("speed_m_s = 0.8\nreplan_period_s = 2.0").decide_within() - 2.2).abs() < 1e-12);
        assert_eq!(navigation("decide_within_m = 3.5").decide_within(), 3.5);
    }
}
