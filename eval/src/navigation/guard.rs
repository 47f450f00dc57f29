//! The collision guard: nav2's Collision Monitor with its `approach` action, on the robot's own map. Every
//! command, the controller's or a recovery's, is carried forward for `[navigation] guard_time_s` with the
//! robot's footprint; when the footprint would enter a cell the map calls blocked, the command is scaled down
//! so that the entry would come no sooner than that, and the robot stops short of the cell.
//!
//! The planner keeps the robot's centre away from what the map forbade when it planned; the guard covers what
//! the plan cannot: cells the map learnt of since (the controller follows a plan up to a period old), and the
//! footprint's corners where the path runs close (a plan out of an inflated start, pure pursuit cutting a
//! corner). It reads the map only, never the truth: a guard that stops the robot reports what the map said.
//!
//! It keeps the robot out of what the sensors saw, blocked cells, and of nothing else. A cell the map cannot
//! decide (uncertain) is the planner's to keep away from, with its inflation and its near rule, and the
//! robot's to look at again: a guard that also stopped for uncertain cells pinned the robot beside them, a
//! corner that may not turn past a doubt and a back that may not leave it, and ended runs stuck on cells the
//! truth calls drivable.

use oeg::{CellIndex, Footprint, GridWindow, Pose2, Traversability};

use super::controller::Command;
use crate::error::Result;

/// Longest step of the guard's simulation, seconds (nav2's `simulation_time_step` default); it is shortened
/// so that no point of the footprint moves more than half a cell in one step.
const MAX_STEP_S: f64 = 0.1;
/// At most this many simulated poses a command (a guard time of 60 s at the longest step).
const MAX_STEPS: usize = 600;

/// The guard's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Guard {
    /// How far ahead a command is carried, seconds; 0: no guard.
    pub time_s: f64,
    /// The robot's footprint.
    pub footprint: Footprint,
}

/// What the guard made of a command.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Guarded {
    /// The command to send: the one given, or it scaled down.
    pub command: Command,
    /// The blocked cell the footprint would have entered first, when the command was scaled down.
    pub limited_by: Option<CellIndex>,
}

impl Guarded {
    /// Whether the guard stopped the robot (the footprint's next step would have entered the cell).
    pub(super) fn stopped(&self) -> bool {
        self.limited_by.is_some() && self.command == Command::default()
    }
}

impl Guard {
    /// Whether the map's class of a cell forbids the footprint to enter it: blocked only (see the module).
    fn forbids(class: Traversability) -> bool {
        class == Traversability::Blocked
    }

    /// `command` at the estimated `pose`, guarded on `decisions` (the map's classes over `window`, which
    /// holds every cell the footprint can reach within the guard time: [`Guard::reach`]). Cells under the
    /// footprint now are not asked about: the robot may always drive out of where it stands.
    pub(super) fn limit(
        &self,
        window: &GridWindow,
        decisions: &[Traversability],
        pose: Pose2,
        command: Command,
    ) -> Guarded {
        let unchanged = Guarded {
            command,
            limited_by: None,
        };
        let Some((steps, dt)) = self.steps(window.resolution_m(), command) else {
            return unchanged;
        };
        let region = window.region();
        let mut under_now = self.footprint.cells_under(window, pose);
        under_now.sort_unstable_by_key(|c| (c.j, c.i));
        for k in 1..=steps {
            let at = carried(pose, command, k as f64 * dt);
            let entered = self.footprint.cells_under(window, at).into_iter().find(|c| {
                under_now
                    .binary_search_by_key(&(c.j, c.i), |u| (u.j, u.i))
                    .is_err()
                    && region.offset(*c).is_some_and(|o| Self::forbids(decisions[o]))
            });
            if let Some(cell) = entered {
                // The last free pose is `k - 1` steps ahead: drive so as to reach it no sooner than the guard
                // time (nav2's approach: the velocity times the collision time over `time_before_collision`).
                let ratio = (k - 1) as f64 * dt / self.time_s;
                return Guarded {
                    command: Command {
                        speed_m_s: command.speed_m_s * ratio,
                        turn_rate_rad_s: command.turn_rate_rad_s * ratio,
                    },
                    limited_by: Some(cell),
                };
            }
        }
        unchanged
    }

    /// The simulated steps of `command` over the guard time: how many, and how long each; `None` when there
    /// is nothing to guard (no guard time, or a robot standing still).
    fn steps(&self, resolution_m: f64, command: Command) -> Option<(usize, f64)> {
        let point_speed =
            command.speed_m_s.abs() + command.turn_rate_rad_s.abs() * self.footprint.circumscribed_radius_m();
        if self.time_s <= 0.0 || point_speed <= 0.0 {
            return None;
        }
        let step = MAX_STEP_S.min(0.5 * resolution_m / point_speed);
        let steps = ((self.time_s / step).ceil() as usize).clamp(1, MAX_STEPS);
        Some((steps, self.time_s / steps as f64))
    }

    /// The lower and upper world corners of a box that holds everything the footprint can cover within the
    /// guard time from `pose` under `command`, with a cell of margin: the window [`Guard::limit`] needs.
    fn reach(&self, pose: Pose2, command: Command, resolution_m: f64) -> ((f64, f64), (f64, f64)) {
        let travel = command.speed_m_s.abs() * self.time_s;
        let r = self.footprint.circumscribed_radius_m() + travel + resolution_m;
        ((pose.x_m - r, pose.y_m - r), (pose.x_m + r, pose.y_m + r))
    }
}

/// The pose `pose` reaches after `t` seconds of `command` (a unicycle: exact arcs).
fn carried(pose: Pose2, command: Command, t: f64) -> Pose2 {
    let (v, w) = (command.speed_m_s, command.turn_rate_rad_s);
    let yaw = pose.yaw_rad + w * t;
    let (dx, dy) = if (w * t).abs() < 1e-9 {
        (v * t * pose.yaw_rad.cos(), v * t * pose.yaw_rad.sin())
    } else {
        (
            v / w * (yaw.sin() - pose.yaw_rad.sin()),
            -v / w * (yaw.cos() - pose.yaw_rad.cos()),
        )
    };
    Pose2 {
        x_m: pose.x_m + dx,
        y_m: pose.y_m + dy,
        yaw_rad: yaw,
    }
}

/// The guard over the map the robot plans on: its classes around the robot, then [`Guard::limit`].
///
/// # Errors
/// A region the map cannot decide over (beyond the map's limits).
pub(super) fn guard_command(
    guard: &Guard,
    map: &oeg::Map,
    bounds: &oeg::CellRegion,
    profile: &oeg::RobotProfile,
    rule: oeg::TraversabilityRule,
    pose: Pose2,
    command: Command,
) -> Result<Guarded> {
    let geometry = *map.geometry();
    if guard.steps(geometry.resolution_m(), command).is_none() {
        return Ok(Guarded {
            command,
            limited_by: None,
        });
    }
    let (lo, hi) = guard.reach(pose, command, geometry.resolution_m());
    // Only the scenario's region is decided: beyond it the map holds nothing the robot may meet.
    let Some(region) = geometry
        .region_covering(lo, hi)
        .ok()
        .and_then(|r| r.intersection(bounds))
    else {
        return Ok(Guarded {
            command,
            limited_by: None,
        });
    };
    let decisions = map.traversability_layer(region, profile, rule)?.values;
    Ok(guard.limit(&GridWindow::new(geometry, region), &decisions, pose, command))
}

#[cfg(test)]
mod tests {
    use oeg::GridGeometry;

    use super::*;

    const FOOTPRINT: Footprint = Footprint {
        min_x_m: -0.3,
        max_x_m: 0.3,
        min_y_m: -0.25,
        max_y_m: 0.25,
    };

    fn guard() -> Guard {
        Guard {
            time_s: 2.0,
            footprint: FOOTPRINT,
        }
    }

    /// A 4 x 4 m window of 0.05 m cells from (-2, -2), every cell `Free` but for a band `x` in `[x0, x0 + 0.1)`
    /// of `class`.
    fn wall_at(x0: f64, class: Traversability) -> (GridWindow, Vec<Traversability>) {
        let window = GridWindow::covering(
            GridGeometry::new(0.05).expect("a resolution"),
            (-2.0, -2.0),
            (1.999, 1.999),
        )
        .expect("a window");
        let decisions = window
            .region()
            .cells()
            .map(|c| {
                let (x, _) = window.geometry().cell_center(c);
                if (x0..x0 + 0.1).contains(&x) {
                    class
                } else {
                    Traversability::Free
                }
            })
            .collect();
        (window, decisions)
    }

    const AHEAD: Command = Command {
        speed_m_s: 0.4,
        turn_rate_rad_s: 0.0,
    };
    const AT_ORIGIN: Pose2 = Pose2 {
        x_m: 0.0,
        y_m: 0.0,
        yaw_rad: 0.0,
    };

    #[test]
    fn far_from_what_the_map_forbids_the_command_passes_unchanged() {
        // 0.4 m/s for 2 s carries the front (0.3 m) to 1.1 m: a wall from 1.2 m is out of reach.
        let (window, decisions) = wall_at(1.2, Traversability::Blocked);
        let g = guard().limit(&window, &decisions, AT_ORIGIN, AHEAD);
        assert_eq!(
            g,
            Guarded {
                command: AHEAD,
                limited_by: None
            }
        );
    }

    #[test]
    fn it_slows_on_the_approach_in_proportion_to_the_time_left_and_stops_short() {
        // The front reaches the wall at 0.7 m after 1 s: the speed is about halved.
        let (window, decisions) = wall_at(0.7, Traversability::Blocked);
        let g = guard().limit(&window, &decisions, AT_ORIGIN, AHEAD);
        let cell = g.limited_by.expect("the wall limits the command");
        assert!(window.geometry().cell_center(cell).0 > 0.7, "{cell:?}");
        assert!(
            (0.4..=0.5).contains(&(g.command.speed_m_s / AHEAD.speed_m_s)),
            "{g:?}"
        );
        // Nose against it: stopped, and the guarded step never enters the wall.
        let (window, decisions) = wall_at(0.31, Traversability::Blocked);
        let g = guard().limit(&window, &decisions, AT_ORIGIN, AHEAD);
        assert!(g.stopped(), "{g:?}");
        // Driving on, a robot that slows as the guard says never enters: 200 ticks of 0.1 s from 1 m away.
        let (window, decisions) = wall_at(1.0, Traversability::Blocked);
        let mut pose = AT_ORIGIN;
        for _ in 0..200 {
            let g = guard().limit(&window, &decisions, pose, AHEAD);
            pose = carried(pose, g.command, 0.1);
        }
        assert!(pose.x_m + FOOTPRINT.max_x_m <= 1.0 && pose.x_m > 0.6, "{pose:?}");
    }

    #[test]
    fn only_blocked_cells_stop_it() {
        for class in [
            Traversability::Uncertain,
            Traversability::Unknown,
            Traversability::Traversable,
        ] {
            let (window, decisions) = wall_at(0.31, class);
            let g = guard().limit(&window, &decisions, AT_ORIGIN, AHEAD);
            assert_eq!(g.limited_by, None, "{class:?}");
        }
        let (window, decisions) = wall_at(0.31, Traversability::Blocked);
        assert!(guard().limit(&window, &decisions, AT_ORIGIN, AHEAD).stopped());
    }

    #[test]
    fn it_lets_the_robot_back_out_of_what_it_stands_on_and_guards_reversing_and_turning() {
        // A blocked band under the robot's nose: backing away is free, driving on is stopped.
        let (window, decisions) = wall_at(0.2, Traversability::Blocked);
        let back = Command {
            speed_m_s: -0.05,
            turn_rate_rad_s: 0.0,
        };
        assert_eq!(
            guard().limit(&window, &decisions, AT_ORIGIN, back).limited_by,
            None
        );
        // Nothing ahead, a wall just behind: backing up is stopped.
        let (window, decisions) = wall_at(-0.41, Traversability::Blocked);
        assert!(guard().limit(&window, &decisions, AT_ORIGIN, back).stopped());
        // Turning on the spot beside a wall the corners would sweep into (the corners lie 0.39 m out).
        let (window, decisions) = wall_at(0.32, Traversability::Blocked);
        let spin = Command {
            speed_m_s: 0.0,
            turn_rate_rad_s: 1.0,
        };
        let g = guard().limit(&window, &decisions, AT_ORIGIN, spin);
        assert!(g.stopped(), "{g:?}");
    }

    #[test]
    fn a_zero_guard_time_or_a_standing_robot_is_not_guarded() {
        let (window, decisions) = wall_at(0.31, Traversability::Blocked);
        let off = Guard {
            time_s: 0.0,
            ..guard()
        };
        assert_eq!(off.limit(&window, &decisions, AT_ORIGIN, AHEAD).limited_by, None);
        let still = Command::default();
        assert_eq!(
            guard().limit(&window, &decisions, AT_ORIGIN, still).limited_by,
            None
        );
    }

    #[test]
    fn carried_poses_follow_the_arc() {
        let quarter = Command {
            speed_m_s: 1.0,
            turn_rate_rad_s: 1.0,
        };
        let p = carried(AT_ORIGIN, quarter, std::f64::consts::FRAC_PI_2);
        assert!((p.x_m - 1.0).abs() < 1e-9 && (p.y_m - 1.0).abs() < 1e-9, "{p:?}");
    }
}
