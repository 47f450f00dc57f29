//! What a closed-loop run records: the trajectory (`trajectory.csv`), the events (`events.csv`, and in
//! `navigation.json`), the plans, and the summary (`navigation.json`).

use serde::Serialize;

/// One row of `trajectory.csv`: the robot at one control step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrajectoryRow {
    /// Simulated time, seconds.
    pub time_s: f64,
    /// True position, metres.
    pub true_x_m: f64,
    /// True position, metres.
    pub true_y_m: f64,
    /// True heading from +x, degrees.
    pub true_yaw_deg: f64,
    /// Estimated (odometry) position, metres.
    pub estimated_x_m: f64,
    /// Estimated position, metres.
    pub estimated_y_m: f64,
    /// Estimated heading, degrees.
    pub estimated_yaw_deg: f64,
    /// Commanded speed over the step that ends here, m/s.
    pub speed_m_s: f64,
    /// Commanded turn rate over that step, degrees per second.
    pub turn_rate_deg_s: f64,
    /// `scripted` (the drive before navigation), `following`, `no_path`, `planner_failed`, `reached`,
    /// `stuck` or `time_limit`.
    pub planner_state: &'static str,
    /// The plan followed (its index in `plans.csv`), empty while there is none.
    pub plan: Option<u64>,
}

impl crate::output::CsvRow for TrajectoryRow {
    const COLUMNS: &'static [&'static str] = &[
        "time_s",
        "true_x_m",
        "true_y_m",
        "true_yaw_deg",
        "estimated_x_m",
        "estimated_y_m",
        "estimated_yaw_deg",
        "speed_m_s",
        "turn_rate_deg_s",
        "planner_state",
        "plan",
    ];
}

/// What happened.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    /// The footprint entered a truly blocked cell (the start of a contact).
    Contact,
    /// The closest the footprint came to a truly blocked cell over the run.
    ClosestApproach,
    /// No path on the map at a replanning time (after one was found, or the first time).
    NoPath,
    /// The collision guard stopped the robot short of a cell its map calls blocked (the start of a stop).
    GuardStop,
    /// The external planner failed: it could not start, exited non-zero, timed out or wrote a bad path.
    PlannerFailed,
    /// The robot did not move `stuck_radius_m` in `stuck_time_s`, and began the next behaviour of the
    /// recovery sequence (the message says which).
    Recovery,
    /// The robot did not move `stuck_radius_m` in `stuck_time_s` after the whole recovery sequence.
    Stuck,
    /// The estimated position came within the goal tolerance.
    Reached,
    /// The time limit ran out.
    TimeLimit,
}

impl EventKind {
    /// The name written in `events.csv` and `navigation.json`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Contact => "contact",
            Self::ClosestApproach => "closest_approach",
            Self::NoPath => "no_path",
            Self::GuardStop => "guard_stop",
            Self::PlannerFailed => "planner_failed",
            Self::Recovery => "recovery",
            Self::Stuck => "stuck",
            Self::Reached => "reached",
            Self::TimeLimit => "time_limit",
        }
    }
}

/// One row of `events.csv`: an event with its time and the robot's true pose.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Event {
    /// Simulated time, seconds.
    pub time_s: f64,
    /// What happened.
    pub kind: EventKind,
    /// True position, metres.
    pub x_m: f64,
    /// True position, metres.
    pub y_m: f64,
    /// True heading, degrees.
    pub yaw_deg: f64,
    /// The obstacle touched or approached (`terrain` for a step of the ground), empty otherwise.
    pub obstacle: String,
    /// Distance from the footprint to the nearest truly blocked cell, metres (contacts: 0), empty otherwise.
    pub distance_m: Option<f64>,
    /// A contact: whether a ray could have told, before it, about a truly blocked cell the footprint entered
    /// (the observability truth of the scans so far: a step a ray ended on, a structure lower than the robot a
    /// ray ended in the band of). `false`: blind, no sensor could have warned. Empty for other events.
    pub observable: Option<bool>,
    /// A contact: what the map the robot navigated by called the truly blocked cells it entered, at that
    /// moment, the most restrictive of their classes: `blocked` (the map knew; the navigator drove in),
    /// `uncertain` or `unknown` (the map could not decide), `traversable` or `free` (the map called them
    /// drivable: a false clearance). Empty for other events.
    pub mapped_as: String,
    /// Cells that closed the way (a `no_path`): blocked, uncertain, never observed.
    pub closed_by: String,
    /// What the event means, in words (a planner failure's message names the file and line).
    pub message: String,
}

impl crate::output::CsvRow for Event {
    const COLUMNS: &'static [&'static str] = &[
        "time_s",
        "kind",
        "x_m",
        "y_m",
        "yaw_deg",
        "obstacle",
        "distance_m",
        "observable",
        "mapped_as",
        "closed_by",
        "message",
    ];
}

/// One row of `plans.csv`: a point of a plan made at a replanning time.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct PlanPointRow {
    /// The plan's index.
    pub plan: u64,
    /// When it was made, seconds.
    pub time_s: f64,
    /// Position along the plan, 0 at its start.
    pub step: u64,
    /// World x, metres.
    pub x_m: f64,
    /// World y, metres.
    pub y_m: f64,
}

impl crate::output::CsvRow for PlanPointRow {
    const COLUMNS: &'static [&'static str] = &["plan", "time_s", "step", "x_m", "y_m"];
}

/// A plan made at a replanning time.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedPath {
    /// When, seconds.
    pub time_s: f64,
    /// World points, start first.
    pub points: Vec<(f64, f64)>,
}

/// How the run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The goal was reached.
    Reached,
    /// The robot was stuck.
    Stuck,
    /// The time ran out.
    TimeLimit,
}

impl Outcome {
    /// The name written in `navigation.json`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Reached => "reached",
            Self::Stuck => "stuck",
            Self::TimeLimit => "time_limit",
        }
    }
}

/// `navigation.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NavigationSummary {
    /// Scenario name.
    pub scenario: String,
    /// Seed of the run.
    pub seed: u64,
    /// How the run ended.
    pub outcome: Outcome,
    /// Whether the goal was reached.
    pub reached: bool,
    /// `astar` or `external`.
    pub planner: &'static str,
    /// Where navigation started (the drive's end), metres.
    pub start_xy_m: [f64; 2],
    /// The goal, metres.
    pub goal_xy_m: [f64; 2],
    /// When navigation started, seconds.
    pub start_time_s: f64,
    /// Seconds from the start of navigation to its end.
    pub time_s: f64,
    /// Length the robot truly drove while navigating, metres.
    pub driven_length_m: f64,
    /// Length of the shortest path on the truth from the start to the goal (the built-in A*, its inflation),
    /// metres; null when the truth has none.
    pub truth_shortest_path_m: Option<f64>,
    /// `driven_length_m / truth_shortest_path_m` (null unless reached).
    pub length_ratio: Option<f64>,
    /// True distance from the robot to the goal at the end, metres.
    pub final_distance_to_goal_m: f64,
    /// Plans asked for.
    pub replans: u64,
    /// Times the collision guard stopped the robot short of a cell its map calls blocked ([`EventKind::GuardStop`]).
    pub guard_stops: u64,
    /// Replanning times with no path on the map.
    pub no_path_replans: u64,
    /// Planner calls that failed.
    pub planner_failures: u64,
    /// Contacts: times the footprint entered truly blocked cells.
    pub contacts: u64,
    /// Of the contacts, those with a cell a ray could have told about before it ([`Event::observable`]).
    pub contacts_observable: u64,
    /// Of the contacts, the blind ones: no ray could have told about any cell the footprint entered.
    pub contacts_blind: u64,
    /// Of the contacts, those with a cell the robot's map called blocked at that moment
    /// ([`Event::mapped_as`]): the navigator drove into what its map forbade.
    pub contacts_mapped_blocked: u64,
    /// Of the contacts, those with no cell called blocked and one the map could not decide (uncertain or
    /// never observed).
    pub contacts_mapped_undecided: u64,
    /// Of the contacts, those whose cells the map called drivable: a false clearance of the map.
    pub contacts_mapped_drivable: u64,
    /// The smallest distance from the footprint to a truly blocked cell, metres (null: none within
    /// [`crate::navigation::APPROACH_WINDOW_M`]).
    pub closest_approach_m: Option<f64>,
    /// The robot's footprint from its URDF, base frame, metres: `[min_x, max_x, min_y, max_y]`.
    pub footprint_m: [f64; 4],
    /// Whether an external planner's time-out (wall time) shaped the run: such a run is not reproducible
    /// byte for byte.
    pub wall_time_dependent: bool,
    /// Points of planned paths not kept, past [`crate::navigation::MAX_KEPT_PLAN_POINTS`] (absent when none).
    #[serde(skip_serializing_if = "is_zero")]
    pub plan_points_dropped: u64,
    /// Every event, in time order.
    pub events: Vec<Event>,
}

impl NavigationSummary {
    /// The figures the judge records as metrics.
    pub fn figures(&self) -> crate::judge::NavigationFigures {
        crate::judge::NavigationFigures {
            reached: self.reached,
            time_s: self.time_s,
            length_ratio: self.length_ratio,
            replans: self.replans,
            guard_stops: self.guard_stops,
            no_path_replans: self.no_path_replans,
            planner_failures: self.planner_failures,
            contacts: self.contacts,
            contacts_observable: self.contacts_observable,
            contacts_mapped: [
                self.contacts_mapped_blocked,
                self.contacts_mapped_undecided,
                self.contacts_mapped_drivable,
            ],
            closest_approach_m: self.closest_approach_m,
            stuck: self.outcome == Outcome::Stuck,
        }
    }
}

/// Whether a count is zero (a key written only when it says something).
fn is_zero(n: &u64) -> bool {
    *n == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_the_serialized_ones() {
        for kind in [
            EventKind::Contact,
            EventKind::ClosestApproach,
            EventKind::NoPath,
            EventKind::GuardStop,
            EventKind::PlannerFailed,
            EventKind::Stuck,
            EventKind::Reached,
            EventKind::TimeLimit,
        ] {
            assert_eq!(serde_json::to_value(kind).ok(), Some(kind.name().into()));
        }
        for outcome in [Outcome::Reached, Outcome::Stuck, Outcome::TimeLimit] {
            assert_eq!(serde_json::to_value(outcome).ok(), Some(outcome.name().into()));
        }
    }
}
