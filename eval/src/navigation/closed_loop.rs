//! The closed loop as a type with its steps: the goal checker, the progress checker with its recovery
//! sequence, the planner at its replanning rate and the controller at every tick, as nav2's behaviour tree
//! runs them; and the summary of the run when the loop ends.

use oeg::{Pose2, Traversability};
use sim::scenario::Replanning;

use super::commitment;
use super::contact::ContactWatch;
use super::controller::{Command, PurePursuit};
use super::guard::{Guard, guard_command};
use super::record::{Event, EventKind, NavigationSummary, Outcome, PlannedPath};
use super::recovery::{Recovery, describe_sequence, recovery_sequence};
use super::{
    MAX_KEPT_PLAN_POINTS, NavigationInputs, NavigationLog, PlanBudget, PlannerSource, Recorder, Replan,
    estimated_pose, replan, round, step_to, truth_shortest_path,
};
use crate::error::Result;
use crate::mapping::Mapping;
use crate::progress::Progress;

/// Runs the scripted drive, then navigates to the goal until it is reached, the robot is stuck, or the time
/// runs out. Every map of `mapping` integrates every scan; the robot plans on the first.
///
/// # Errors
/// A scan a map rejects, or a map file for an external planner that cannot be written.
pub fn navigate(
    mapping: &mut Mapping,
    inputs: &NavigationInputs<'_>,
    progress: &Progress,
) -> Result<NavigationLog> {
    let s = inputs.scenario;
    let mut watch = ContactWatch::new(s, inputs.truth, inputs.footprint);
    let mut log = Recorder::default();
    // Progress counts simulated seconds: a closed loop's scans do not say how far it is from its goal.
    mapping.count_simulated_time = true;
    progress.set_unit("s simulated");
    progress.set_length(s.duration_s.ceil() as u64);
    drive_scripted(mapping, inputs, &mut log, &mut watch, progress)?;

    let mut closed = ClosedLoop::new(inputs, mapping);
    // The bar's end is the time limit: the robot may reach its goal sooner, never later.
    progress.set_length(closed.end.ceil() as u64);
    let outcome = closed.run(mapping, &mut log, &mut watch, progress)?;
    let world = mapping.simulation.world_mut();
    world.command(0.0, 0.0);
    if outcome == Outcome::Reached {
        world.goal_reached();
    }
    if let Some(row) = log.trajectory.last_mut() {
        row.planner_state = match outcome {
            Outcome::Reached => "reached",
            Outcome::Stuck => "stuck",
            Outcome::TimeLimit => "time_limit",
        };
    }
    closed.summarize(mapping, log, &watch, outcome)
}

/// The scripted drive before the loop, one tick at a time, so that the trajectory and the watch see all of it.
fn drive_scripted(
    mapping: &mut Mapping,
    inputs: &NavigationInputs<'_>,
    log: &mut Recorder,
    watch: &mut ContactWatch<'_>,
    progress: &Progress,
) -> Result<()> {
    let s = inputs.scenario;
    let dt = s.tick_s;
    // A kinematic drive ends at its scheduled time; one on the wheels when the physics gets it to its last
    // waypoint, within the scenario's duration.
    let world = mapping.simulation.world();
    let drive_end = if world.drives_on_wheels() {
        s.duration_s
    } else {
        world.drive_end_s().min(s.duration_s)
    };
    let ticks = (drive_end / dt).ceil() as u64;
    for k in 1..=ticks {
        if mapping.simulation.world().scripted_drive_over() {
            break;
        }
        let t = (k as f64 * dt).min(drive_end);
        step_to(mapping, t, progress)?;
        log.sample(mapping, Command::default(), "scripted", None);
        log.watch(watch, mapping);
    }
    Ok(())
}

/// A closed loop under way: the plan the controller follows, the recovery under way, the progress checker's
/// anchor and the counts the summary reports.
struct ClosedLoop<'i, 'a> {
    inputs: &'i NavigationInputs<'a>,
    controller: PurePursuit,
    guard: Guard,
    /// Whether the guard held the robot still at the last tick (a stop is an event when it begins).
    guard_stopped: bool,
    guard_stops: u64,
    /// Where and when the loop started.
    start: sim::drive::PlanarPose,
    t0: f64,
    /// The time limit, simulated seconds.
    end: f64,
    /// The tick, seconds.
    dt: f64,
    /// The path the controller follows, its place on it, and the plan it came from (its index in the log).
    path: Vec<(f64, f64)>,
    progress_index: usize,
    plan_index: Option<u64>,
    /// The plan last given to the world as the path the robot follows (`Some(None)`: none), so that a robot
    /// on its wheels reports its distance from the plan it is following.
    reference_plan: Option<Option<u64>>,
    /// The planner's state as the trajectory records it.
    state: &'static str,
    /// Whether the last replanning found a path (a no-path event is logged when that changes).
    had_path: bool,
    /// The progress checker: where the robot last made progress, and when.
    anchor: (f64, f64),
    anchor_t: f64,
    next_replan: f64,
    planner_wall_time_s: f64,
    wall_time_dependent: bool,
    plan_budget: PlanBudget,
    replans: u64,
    no_path_replans: u64,
    failures: u64,
    /// The recovery sequence (nav2's, before it gives up): the behaviour under way and until when, and how
    /// many of the sequence's behaviours were tried since the robot last made progress.
    sequence: Vec<Recovery>,
    recovering: Option<(Recovery, f64)>,
    tried: usize,
}

impl<'i, 'a> ClosedLoop<'i, 'a> {
    /// The loop from the robot's pose at the end of the scripted drive.
    fn new(inputs: &'i NavigationInputs<'a>, mapping: &Mapping) -> Self {
        let (s, n) = (inputs.scenario, inputs.settings);
        let start = mapping.simulation.world().planar_pose();
        let t0 = mapping.simulation.world().time_s();
        let end = n
            .time_limit_s
            .map_or(s.duration_s, |l| (t0 + l).min(s.duration_s));
        Self {
            inputs,
            controller: PurePursuit {
                lookahead_m: n.lookahead_m,
                speed_m_s: n.speed_m_s,
                max_turn_rate_rad_s: s.robot.max_turn_rate_deg_s.to_radians(),
            },
            guard: Guard {
                time_s: n.guard_time_s,
                footprint: inputs.footprint,
            },
            guard_stopped: false,
            guard_stops: 0,
            start,
            t0,
            end,
            dt: s.tick_s,
            path: Vec::new(),
            progress_index: 0,
            plan_index: None,
            reference_plan: None,
            state: "following",
            had_path: true,
            anchor: (start.x_m, start.y_m),
            anchor_t: t0,
            next_replan: t0,
            planner_wall_time_s: 0.0,
            wall_time_dependent: false,
            plan_budget: PlanBudget::new(MAX_KEPT_PLAN_POINTS),
            replans: 0,
            no_path_replans: 0,
            failures: 0,
            sequence: recovery_sequence(n),
            recovering: None,
            tried: 0,
        }
    }

    /// Ticks until the goal is reached, the robot is stuck or the time runs out.
    fn run(
        &mut self,
        mapping: &mut Mapping,
        log: &mut Recorder,
        watch: &mut ContactWatch<'_>,
        progress: &Progress,
    ) -> Result<Outcome> {
        let mut k = 0u64;
        loop {
            let t = self.t0 + k as f64 * self.dt;
            let estimated = estimated_pose(mapping);
            if let Some(outcome) = self.check(mapping, log, t, estimated)? {
                return Ok(outcome);
            }
            if self.recovering.is_none() && t >= self.next_replan - 1e-9 {
                self.replan(mapping, log, t, estimated)?;
            }
            k += 1;
            self.tick(
                mapping,
                log,
                watch,
                estimated,
                (self.t0 + k as f64 * self.dt).min(self.end),
                progress,
            )?;
        }
    }

    /// The checks before a tick at `t`: the goal checker (on the estimated pose, as a robot's), the end of a
    /// recovery, the progress checker (which starts the next recovery, or gives up) and the time limit.
    fn check(
        &mut self,
        mapping: &Mapping,
        log: &mut Recorder,
        t: f64,
        estimated: Pose2,
    ) -> Result<Option<Outcome>> {
        let (s, n) = (self.inputs.scenario, self.inputs.settings);
        if (estimated.x_m - n.goal_xy_m[0]).hypot(estimated.y_m - n.goal_xy_m[1]) <= n.goal_tolerance_m {
            log.event(
                mapping,
                EventKind::Reached,
                "the estimated position is within the goal tolerance",
            );
            return Ok(Some(Outcome::Reached));
        }
        if let Some((_, until)) = self.recovering
            && t >= until - 1e-9
        {
            // The behaviour is over: plan again now, and give the progress checker a fresh window.
            self.recovering = None;
            self.next_replan = t;
            let now = mapping.simulation.world().planar_pose();
            (self.anchor, self.anchor_t) = ((now.x_m, now.y_m), t);
        }
        if self.recovering.is_none() && t - self.anchor_t >= n.stuck_time_s - 1e-9 {
            let Some(behaviour) = self.sequence.get(self.tried).copied() else {
                log.event(
                    mapping,
                    EventKind::Stuck,
                    &format!(
                        "moved less than {} m in {} s, after the recovery sequence ({})",
                        n.stuck_radius_m,
                        n.stuck_time_s,
                        describe_sequence(&self.sequence)
                    ),
                );
                return Ok(Some(Outcome::Stuck));
            };
            self.tried += 1;
            let e = log.event(mapping, EventKind::Recovery, &behaviour.describe());
            log.snapshot(mapping, self.inputs, e)?;
            let turn_rate = s.robot.max_turn_rate_deg_s.to_radians();
            self.recovering = Some((
                behaviour,
                t + behaviour.duration_s(estimated, n.goal_xy_m, turn_rate),
            ));
            (self.path, self.plan_index, self.state) = (Vec::new(), None, "recovery");
        }
        if t >= self.end - 1e-9 {
            log.event(mapping, EventKind::TimeLimit, "the time limit ran out");
            return Ok(Some(Outcome::TimeLimit));
        }
        Ok(None)
    }

    /// Plans from the estimated pose at `t` and takes the result: a path to follow, no path (logged when the
    /// last replanning had one), or the planner's failure.
    fn replan(&mut self, mapping: &Mapping, log: &mut Recorder, t: f64, estimated: Pose2) -> Result<()> {
        self.next_replan += self.inputs.settings.replan_period_s;
        let mode = self.inputs.settings.replan;
        let ahead = &self.path[self.progress_index.min(self.path.len())..];
        let (window, decisions) = super::map_decisions(mapping, self.inputs)?;
        let from = (estimated.x_m, estimated.y_m);
        let committed = mode != Replanning::Periodic
            && self.state == "following"
            && !ahead.is_empty()
            && commitment::path_still_valid(self.inputs, &window, &decisions, from, ahead)?;
        if committed && mode == Replanning::WhenInvalid {
            return Ok(());
        }
        self.replans += 1;
        let wall = std::time::Instant::now();
        let result = replan(mapping, self.inputs, estimated, (&window, &decisions))?;
        self.planner_wall_time_s += wall.elapsed().as_secs_f64();
        if committed {
            // `when_shorter`: the path ahead is still allowed; a new one replaces it only if clearly shorter.
            let rest = commitment::path_length_m(from, ahead);
            let shorter = matches!(&result, Replan::Path(points)
                if commitment::clearly_shorter(commitment::path_length_m(from, points), rest));
            if !shorter {
                return Ok(());
            }
        }
        match result {
            Replan::Path(points) => {
                self.plan_index = Some(log.plans.len() as u64);
                log.plans.push(PlannedPath {
                    time_s: round(t),
                    points: self.plan_budget.keep(&points),
                });
                (self.path, self.progress_index, self.state, self.had_path) = (points, 0, "following", true);
            }
            Replan::NoPath { closed_by } => {
                self.no_path_replans += 1;
                if self.had_path {
                    let e = log.event(
                        mapping,
                        EventKind::NoPath,
                        "no path on the map from the estimated pose to the goal",
                    );
                    log.summary_events[e].closed_by = closed_by;
                    log.snapshot(mapping, self.inputs, e)?;
                }
                (self.path, self.plan_index, self.state, self.had_path) =
                    (Vec::new(), None, "no_path", false);
            }
            Replan::Failed { message, timed_out } => {
                self.failures += 1;
                self.wall_time_dependent |= timed_out;
                let e = log.event(mapping, EventKind::PlannerFailed, &message);
                log.snapshot(mapping, self.inputs, e)?;
                (self.path, self.plan_index, self.state) = (Vec::new(), None, "planner_failed");
            }
        }
        Ok(())
    }

    /// One tick to `t_next`: the recovery's or the controller's command, the world and the maps moved on,
    /// the trajectory sampled, the judge's watch, and the progress checker's anchor moved on progress.
    fn tick(
        &mut self,
        mapping: &mut Mapping,
        log: &mut Recorder,
        watch: &mut ContactWatch<'_>,
        estimated: Pose2,
        t_next: f64,
        progress: &Progress,
    ) -> Result<()> {
        let (s, n) = (self.inputs.scenario, self.inputs.settings);
        let command = match self.recovering {
            Some((behaviour, _)) => behaviour.command(
                estimated,
                n.goal_xy_m,
                s.robot.max_turn_rate_deg_s.to_radians(),
                self.dt,
            ),
            None => self
                .controller
                .command(estimated, &self.path, &mut self.progress_index),
        };
        let guarded = guard_command(
            &self.guard,
            &mapping.maps[0],
            self.inputs.truth.window.region(),
            &self.inputs.truth.profile,
            s.map.traversability,
            estimated,
            command,
        )?;
        let command = guarded.command;
        if guarded.stopped() && !self.guard_stopped {
            self.guard_stops += 1;
            if let Some(cell) = guarded.limited_by {
                let (x, y) = mapping.maps[0].geometry().cell_center(cell);
                let e = log.event(
                    mapping,
                    EventKind::GuardStop,
                    &format!(
                        "the collision guard stopped the robot short of a cell its map calls blocked at \
                         ({x:.3}, {y:.3}) m"
                    ),
                );
                log.summary_events[e].mapped_as = Traversability::Blocked.name().to_string();
            }
        }
        self.guard_stopped = guarded.stopped();
        let world = mapping.simulation.world_mut();
        if self.reference_plan != Some(self.plan_index) {
            world.set_reference_path(&self.path);
            self.reference_plan = Some(self.plan_index);
        }
        world.command(command.speed_m_s, command.turn_rate_rad_s);
        step_to(mapping, t_next, progress)?;
        log.sample(mapping, command, self.state, self.plan_index);
        if let Some(e) = log.watch(watch, mapping) {
            log.snapshot(mapping, self.inputs, e)?;
        }
        let now = mapping.simulation.world().planar_pose();
        if self.recovering.is_none()
            && (now.x_m - self.anchor.0).hypot(now.y_m - self.anchor.1) >= n.stuck_radius_m
        {
            // Progress: the sequence starts afresh at the next stall.
            (self.anchor, self.anchor_t, self.tried) = ((now.x_m, now.y_m), t_next, 0);
        }
        Ok(())
    }

    /// The run's log and summary once the loop ended with `outcome`: the closest approach the watch saw
    /// among the events, the drive against the truth's shortest path, the counts.
    fn summarize(
        self,
        mapping: &Mapping,
        mut log: Recorder,
        watch: &ContactWatch<'_>,
        outcome: Outcome,
    ) -> Result<NavigationLog> {
        let (s, n, inputs) = (self.inputs.scenario, self.inputs.settings, self.inputs);
        if let Some((d, time_s, pose, cell)) = watch.closest {
            log.summary_events.push(Event {
                time_s: round(time_s),
                kind: EventKind::ClosestApproach,
                x_m: round(pose.x_m),
                y_m: round(pose.y_m),
                yaw_deg: round(pose.yaw_rad.to_degrees()),
                obstacle: watch.obstacle_of(cell),
                distance_m: Some(round(d)),
                observable: None,
                mapped_as: String::new(),
                closed_by: String::new(),
                message: "the closest the footprint came to a truly blocked cell".into(),
            });
            log.summary_events.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        }
        let start = self.start;
        let end_pose = mapping.simulation.world().planar_pose();
        let driven = end_pose.distance_m - start.distance_m;
        let truth_path = truth_shortest_path(inputs, (start.x_m, start.y_m))?;
        let reached = outcome == Outcome::Reached;
        let count_contacts = |observable: Option<bool>| {
            log.summary_events
                .iter()
                .filter(|e| {
                    e.kind == EventKind::Contact && observable.is_none_or(|o| e.observable == Some(o))
                })
                .count() as u64
        };
        let (contacts, contacts_observable) = (count_contacts(None), count_contacts(Some(true)));
        let count_mapped = |classes: &[&str]| {
            log.summary_events
                .iter()
                .filter(|e| e.kind == EventKind::Contact && classes.contains(&e.mapped_as.as_str()))
                .count() as u64
        };
        let summary = NavigationSummary {
            scenario: s.name.clone(),
            seed: s.seed,
            outcome,
            reached,
            planner: match inputs.planner {
                PlannerSource::Builtin => "astar",
                PlannerSource::External(_) => "external",
                PlannerSource::Callback(_) => "callback",
            },
            start_xy_m: [round(start.x_m), round(start.y_m)],
            goal_xy_m: n.goal_xy_m,
            start_time_s: round(self.t0),
            time_s: round(mapping.simulation.world().time_s() - self.t0),
            driven_length_m: round(driven),
            truth_shortest_path_m: truth_path.map(round),
            length_ratio: truth_path.filter(|_| reached).map(|p| round(driven / p)),
            final_distance_to_goal_m: round(
                (end_pose.x_m - n.goal_xy_m[0]).hypot(end_pose.y_m - n.goal_xy_m[1]),
            ),
            replans: self.replans,
            guard_stops: self.guard_stops,
            no_path_replans: self.no_path_replans,
            planner_failures: self.failures,
            contacts,
            contacts_observable,
            contacts_blind: contacts - contacts_observable,
            contacts_mapped_blocked: count_mapped(&["blocked"]),
            contacts_mapped_undecided: count_mapped(&["uncertain", "unknown"]),
            contacts_mapped_drivable: count_mapped(&["traversable", "free"]),
            closest_approach_m: watch.closest.map(|c| round(c.0)),
            footprint_m: [
                round(inputs.footprint.min_x_m),
                round(inputs.footprint.max_x_m),
                round(inputs.footprint.min_y_m),
                round(inputs.footprint.max_y_m),
            ],
            wall_time_dependent: self.wall_time_dependent,
            plan_points_dropped: self.plan_budget.dropped,
            events: log.summary_events,
        };
        Ok(NavigationLog {
            trajectory: log.trajectory,
            plans: log.plans,
            summary,
            snapshots: log.snapshots,
            planner_wall_time_s: self.planner_wall_time_s,
        })
    }
}
