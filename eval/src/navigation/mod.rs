//! Closed-loop navigation (`[navigation]` in a scenario): the robot plans on the map it has *now*, drives a
//! little, maps, and plans again, as nav2 runs a robot: a planner at a replanning rate, a controller (pure
//! pursuit, `controller`) at the simulation's tick, a goal checker and a progress checker.
//!
//! At every tick the sensors scan the world at the robot's true pose and the maps integrate the scans at the
//! estimated pose (odometry drift as in a scripted drive); at every replanning time the planner plans from
//! the estimated pose to the goal on the run's map, the built-in A* or an external program ([`external`]);
//! the controller's command moves the robot in the world, settled on the terrain. The judge watches the true
//! footprint against the truth (`contact`); nothing the robot decides reads the truth.

mod builtin;
mod closed_loop;
mod commitment;
pub(crate) mod contact;
pub(crate) mod controller;
mod diagnosis;
pub mod external;
mod guard;
pub(crate) mod record;
mod recovery;

use oeg::{CellIndex, Footprint, Plan, Pose2, Traversability};

use crate::judge::verdict::TruthClass;
use sim::scenario::{Navigation, Scenario};
use sim::truth::TruthRaster;

use crate::error::{EvalError, Result};
use crate::mapping::Mapping;
use crate::progress::Progress;
pub use builtin::planner_options;
pub use closed_loop::navigate;
pub use contact::APPROACH_WINDOW_M;
use contact::ContactWatch;
use controller::Command;
use external::ExternalPlanner;
use record::{Event, EventKind, NavigationSummary, PlannedPath, TrajectoryRow};

/// The most map snapshots kept for event images.
pub const MAX_SNAPSHOTS: usize = 6;
/// Exit status by which an external planner says that no path exists (`docs/planner-protocol.md`).
pub const NO_PATH_EXIT_CODE: i32 = 3;

/// Which planner plans.
#[derive(Debug, Clone, PartialEq)]
pub enum PlannerSource {
    /// The built-in A* with the scenario's `[planner]` options.
    Builtin,
    /// An external program.
    External(ExternalPlanner),
    /// A planner in the caller's own process (a Python function given to the Python package).
    Callback(SharedPlanner),
}

/// A planner in the caller's own process, such as a Python function given to the Python package's
/// `run_scenario`. It sees what an external planner sees, without files.
pub trait PlannerCallback: Send + Sync {
    /// Plans from `request.start` to `request.goal`: `Ok(Some(points))` a path of world points in metres,
    /// `Ok(None)` no path, `Err(message)` a failure, which is an event of the run as an external planner's is.
    ///
    /// # Errors
    /// The planner's own failure, as a message.
    fn plan(&self, request: &PlanRequest<'_>) -> std::result::Result<Option<Vec<(f64, f64)>>, String>;
}

/// What a [`PlannerCallback`] is given at each replanning time.
#[derive(Debug, Clone, Copy)]
pub struct PlanRequest<'a> {
    /// The map built so far.
    pub map: &'a oeg::Map,
    /// The region planned over (the scenario's map region).
    pub region: oeg::CellRegion,
    /// The map's decisions over `region`, row-major from its min corner.
    pub decisions: &'a [Traversability],
    /// The estimated position, world x and y, metres.
    pub start: (f64, f64),
    /// The goal, world x and y, metres.
    pub goal: (f64, f64),
    /// The region's extent, `[x_min, x_max, y_min, y_max]` in metres: the path must stay inside.
    pub extent: external::Extent,
}

/// A shared [`PlannerCallback`]; two are equal when they are the same object.
#[derive(Clone)]
pub struct SharedPlanner(pub std::sync::Arc<dyn PlannerCallback>);

impl std::fmt::Debug for SharedPlanner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("SharedPlanner(..)")
    }
}

impl PartialEq for SharedPlanner {
    fn eq(&self, other: &Self) -> bool {
        std::sync::Arc::ptr_eq(&self.0, &other.0)
    }
}

/// The map's decisions at an event's time, for its image.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// The event.
    pub event: Event,
    /// The decisions over the truth's region, row-major.
    pub decisions: Vec<Traversability>,
}

/// The most points of planned paths a closed-loop run keeps (16 MB): later plans keep their time, not their
/// points (`plans.csv` then lacks their rows, and `navigation.json` counts them in `plan_points_dropped`).
pub const MAX_KEPT_PLAN_POINTS: u64 = 1_000_000;

/// The points of planned paths a run keeps: every plan is kept with its time, its points only while the total
/// stays within the budget, so a long run that replans often holds a bounded log.
#[derive(Debug, Clone, Copy)]
struct PlanBudget {
    left: u64,
    dropped: u64,
}

impl PlanBudget {
    fn new(points: u64) -> Self {
        Self {
            left: points,
            dropped: 0,
        }
    }

    /// The points of a plan to keep: all of them within the budget, none past it.
    fn keep(&mut self, points: &[(f64, f64)]) -> Vec<(f64, f64)> {
        let n = points.len() as u64;
        if n <= self.left {
            self.left -= n;
            points.to_vec()
        } else {
            // Spent: this plan and every later one keep no points, so `plans.csv` holds the run's first plans.
            self.left = 0;
            self.dropped += n;
            Vec::new()
        }
    }
}

/// Everything a closed-loop run recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct NavigationLog {
    /// The robot at every tick.
    pub trajectory: Vec<TrajectoryRow>,
    /// Every plan made.
    pub plans: Vec<PlannedPath>,
    /// The summary, with the events.
    pub summary: NavigationSummary,
    /// The map at the first events' times.
    pub snapshots: Vec<Snapshot>,
    /// Wall time spent in the planner, seconds (not deterministic: it goes to `timing.json`).
    pub planner_wall_time_s: f64,
}

/// What the loop needs besides the simulation and the maps.
#[derive(Debug, Clone, Copy)]
pub struct NavigationInputs<'a> {
    /// The scenario.
    pub scenario: &'a Scenario,
    /// Its `[navigation]`.
    pub settings: &'a Navigation,
    /// The robot's footprint from its URDF.
    pub footprint: Footprint,
    /// The truth over the map region (the static world; the judge's, never the robot's).
    pub truth: &'a TruthRaster,
    /// The planner.
    pub planner: &'a PlannerSource,
}

/// What one replanning gave.
enum Replan {
    Path(Vec<(f64, f64)>),
    NoPath { closed_by: String },
    Failed { message: String, timed_out: bool },
}

/// Takes the scans up to `t_s` and moves the world there.
fn step_to(mapping: &mut Mapping, t_s: f64, progress: &Progress) -> Result<()> {
    mapping.feed_until(t_s, progress)?;
    mapping.simulation.world_mut().advance_to(t_s);
    Ok(())
}

fn estimated_pose(mapping: &Mapping) -> Pose2 {
    let p = mapping.simulation.world().estimated_world_from_base();
    Pose2 {
        x_m: p.translation.x,
        y_m: p.translation.y,
        yaw_rad: p.rotation.euler_angles().2,
    }
}

fn true_pose(mapping: &Mapping) -> Pose2 {
    let p = mapping.simulation.world().planar_pose();
    Pose2 {
        x_m: p.x_m,
        y_m: p.y_m,
        yaw_rad: p.yaw_rad,
    }
}

/// Metres and degrees in the outputs, rounded to the micrometre (as every CSV of the testbed).
fn round(v: f64) -> f64 {
    crate::output::round_m(v)
}

/// The cell of a point, clamped into the window (a point on its max edge lies in the cell beyond).
fn clamped_cell(window: &oeg::GridWindow, (x, y): (f64, f64)) -> Option<CellIndex> {
    let (lo, hi) = (window.region().min, window.region().max());
    let c = window.geometry().cell_of(x, y)?;
    let inside = c.i >= lo.i - 1 && c.i <= hi.i + 1 && c.j >= lo.j - 1 && c.j <= hi.j + 1;
    inside.then(|| CellIndex::new(c.i.clamp(lo.i, hi.i), c.j.clamp(lo.j, hi.j)))
}

/// The run's map decided over the scenario's window (the truth's window, whose cells the robot never reads):
/// what a replanning time plans on and checks the path ahead against.
fn map_decisions(
    mapping: &Mapping,
    inputs: &NavigationInputs<'_>,
) -> Result<(oeg::GridWindow, Vec<Traversability>)> {
    let map = &mapping.maps[0];
    let window = oeg::GridWindow::new(*map.geometry(), *inputs.truth.window.region());
    let decisions = map
        .traversability_layer(
            *window.region(),
            &inputs.truth.profile,
            inputs.scenario.map.traversability,
        )?
        .values;
    Ok((window, decisions))
}

/// Plans on the run's map, decided as `decisions` over `window`, from the estimated pose.
fn replan(
    mapping: &Mapping,
    inputs: &NavigationInputs<'_>,
    from: Pose2,
    (window, decisions): (&oeg::GridWindow, &[Traversability]),
) -> Result<Replan> {
    let s = inputs.scenario;
    let map = &mapping.maps[0];
    let region = *window.region();
    let goal = (inputs.settings.goal_xy_m[0], inputs.settings.goal_xy_m[1]);
    let result = match inputs.planner {
        PlannerSource::Builtin => {
            let (Some(a), Some(b)) = (
                clamped_cell(window, (from.x_m, from.y_m)),
                clamped_cell(window, goal),
            ) else {
                return Ok(Replan::Failed {
                    message: format!(
                        "the estimated position ({:.3}, {:.3}) m lies outside the map region",
                        from.x_m, from.y_m
                    ),
                    timed_out: false,
                });
            };
            builtin::plan(inputs, window, decisions, (a, b), goal)?
        }
        PlannerSource::External(planner) => {
            let mut files = oeg::planner_files(
                map,
                region,
                &inputs.truth.profile,
                s.map.traversability,
                planner_options(inputs).uncertain,
            )?;
            // The map itself too, for planners that read this project's format (`oeg plan`).
            files.push(("map.oeg".into(), oeg::map_to_bytes(map)));
            let extent = external::extent_of(window);
            match planner.call(&files, (from.x_m, from.y_m), goal, extent)? {
                Ok(points) => Some(points),
                Err(f)
                    if f.kind == "exit"
                        && f.message.contains(&format!("exit status: {NO_PATH_EXIT_CODE}")) =>
                {
                    None
                }
                Err(f) => {
                    return Ok(Replan::Failed {
                        timed_out: f.kind == "timeout",
                        message: f.message,
                    });
                }
            }
        }
        PlannerSource::Callback(planner) => {
            let extent = external::extent_of(window);
            let request = PlanRequest {
                map,
                region,
                decisions,
                start: (from.x_m, from.y_m),
                goal,
                extent,
            };
            let checked = planner.0.plan(&request).and_then(|path| match path {
                Some(points) if points.is_empty() => Err("the planner returned an empty path".to_string()),
                Some(points) => points
                    .iter()
                    .enumerate()
                    .find_map(|(k, p)| external::point_problem(*p, extent).map(|m| format!("point {k}: {m}")))
                    .map_or(Ok(Some(points)), Err),
                None => Ok(None),
            });
            match checked {
                Ok(path) => path,
                Err(message) => {
                    return Ok(Replan::Failed {
                        message,
                        timed_out: false,
                    });
                }
            }
        }
    };
    Ok(match result {
        Some(points) => Replan::Path(points),
        None => Replan::NoPath {
            closed_by: diagnosis::closed_by(map, decisions, inputs, window, from, goal)?,
        },
    })
}

/// The length of the built-in planner's path on the truth from `from` to the goal, metres.
fn truth_shortest_path(inputs: &NavigationInputs<'_>, from: (f64, f64)) -> Result<Option<f64>> {
    Ok(truth_plan(inputs, from)?.map(|p| p.length_m))
}

/// The built-in planner's path on the truth from `from` to the goal.
fn truth_plan(inputs: &NavigationInputs<'_>, from: (f64, f64)) -> Result<Option<Plan>> {
    let truth = inputs.truth;
    let goal = (inputs.settings.goal_xy_m[0], inputs.settings.goal_xy_m[1]);
    let (Some(a), Some(b)) = (
        clamped_cell(&truth.window, from),
        clamped_cell(&truth.window, goal),
    ) else {
        return Ok(None);
    };
    let decisions = crate::judge::verdict::Verdicts::from_classes(
        truth,
        vec![Traversability::Unknown; truth.cells.len()],
    )
    .truth_decisions();
    let options = planner_options(inputs);
    oeg::plan(&truth.window, &decisions, a, b, &options).map_err(|e| EvalError::Input {
        path: inputs.scenario.name.clone().into(),
        message: format!("planner: {e}"),
    })
}

/// The records as the loop writes them.
#[derive(Default)]
struct Recorder {
    trajectory: Vec<TrajectoryRow>,
    plans: Vec<PlannedPath>,
    summary_events: Vec<Event>,
    snapshots: Vec<Snapshot>,
}

impl Recorder {
    fn sample(&mut self, mapping: &Mapping, command: Command, state: &'static str, plan: Option<u64>) {
        let world = mapping.simulation.world();
        let t = true_pose(mapping);
        let e = estimated_pose(mapping);
        self.trajectory.push(TrajectoryRow {
            time_s: round(world.time_s()),
            true_x_m: round(t.x_m),
            true_y_m: round(t.y_m),
            true_yaw_deg: round(t.yaw_rad.to_degrees()),
            estimated_x_m: round(e.x_m),
            estimated_y_m: round(e.y_m),
            estimated_yaw_deg: round(e.yaw_rad.to_degrees()),
            speed_m_s: round(command.speed_m_s),
            turn_rate_deg_s: round(command.turn_rate_rad_s.to_degrees()),
            planner_state: state,
            plan,
        });
    }

    /// Records an event at the robot's true pose now; returns its index.
    fn event(&mut self, mapping: &Mapping, kind: EventKind, message: &str) -> usize {
        let p = true_pose(mapping);
        self.summary_events.push(Event {
            time_s: round(mapping.simulation.world().time_s()),
            kind,
            x_m: round(p.x_m),
            y_m: round(p.y_m),
            yaw_deg: round(p.yaw_rad.to_degrees()),
            obstacle: String::new(),
            distance_m: None,
            observable: None,
            mapped_as: String::new(),
            closed_by: String::new(),
            message: message.to_string(),
        });
        self.summary_events.len() - 1
    }

    /// Checks the true footprint now; a contact that begins is an event (its index returned).
    fn watch(&mut self, watch: &mut ContactWatch<'_>, mapping: &Mapping) -> Option<usize> {
        let time_s = mapping.simulation.world().time_s();
        let contact = watch.check(time_s, true_pose(mapping))?;
        let e = self.event(
            mapping,
            EventKind::Contact,
            "the footprint entered a truly blocked cell",
        );
        self.summary_events[e].obstacle = contact.obstacle;
        self.summary_events[e].distance_m = Some(0.0);
        // Observable: a ray of the scans so far could have told about one of the cells entered.
        let o = mapping.observability.observed();
        let observable = contact.cells.iter().any(|c| {
            o.window
                .region()
                .offset(*c)
                .filter(|_| o.window == *watch.window())
                .is_some_and(|k| TruthClass::of(watch.truth(), k).could_be_told(o, k))
        });
        self.summary_events[e].observable = Some(observable);
        self.summary_events[e].mapped_as = diagnosis::mapped_as(
            &mapping.maps[0],
            &contact.cells,
            &watch.truth().profile,
            watch.rule(),
        );
        Some(e)
    }

    /// Keeps the map's decisions for the image of event `event` (the first [`MAX_SNAPSHOTS`] only).
    fn snapshot(&mut self, mapping: &Mapping, inputs: &NavigationInputs<'_>, event: usize) -> Result<()> {
        if self.snapshots.len() >= MAX_SNAPSHOTS {
            return Ok(());
        }
        let decisions = mapping.maps[0]
            .traversability_layer(
                *inputs.truth.window.region(),
                &inputs.truth.profile,
                inputs.scenario.map.traversability,
            )?
            .values;
        let event = self.summary_events[event].clone();
        self.snapshots.push(Snapshot { event, decisions });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::PlanBudget;

    #[test]
    fn plans_past_the_budget_keep_their_time_not_their_points() {
        let mut budget = PlanBudget::new(5);
        assert_eq!(budget.keep(&[(0.0, 0.0); 3]).len(), 3);
        assert_eq!(budget.keep(&[(1.0, 1.0); 2]).len(), 2, "exactly the budget");
        assert!(budget.keep(&[(2.0, 2.0)]).is_empty(), "past it");
        assert!(budget.keep(&[(3.0, 3.0); 4]).is_empty());
        assert_eq!(budget.dropped, 5);
        let mut budget = PlanBudget::new(5);
        assert!(budget.keep(&[(0.0, 0.0); 6]).is_empty());
        assert!(
            budget.keep(&[(1.0, 1.0)]).is_empty(),
            "once spent, no later plan keeps points"
        );
    }
}
