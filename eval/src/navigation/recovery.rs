//! The recovery sequence of a closed loop that made no progress (nav2's behaviours before it gives up): face
//! the goal and wait, mapping; back up; each followed by a plan.

use oeg::Pose2;
use sim::scenario::Navigation;

use super::controller::Command;

/// One behaviour of the recovery sequence: what a robot that made no progress does before it plans again.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Recovery {
    /// Turn on the spot to face the goal, then stand still, mapping, for `seconds`: the sensors look at the
    /// way again, and what blocked it may leave or be seen better (nav2's `Spin` and `Wait`).
    Look { seconds: f64 },
    /// Drive backwards this far at this speed: away from what the footprint may be pinned against, and
    /// farther from what the map could not decide, so the next plan sees more of it (nav2's `BackUp`).
    BackUp { distance_m: f64, speed_m_s: f64 },
}

impl Recovery {
    /// How long the behaviour lasts, begun at `pose`: a look's turn at `max_turn_rate` and its wait.
    pub(super) fn duration_s(self, pose: Pose2, goal: [f64; 2], max_turn_rate: f64) -> f64 {
        match self {
            Self::Look { seconds } => heading_error(pose, goal).abs() / max_turn_rate + seconds,
            Self::BackUp {
                distance_m,
                speed_m_s,
            } => distance_m / speed_m_s,
        }
    }

    /// The command at the estimated `pose`, for a tick of `dt` seconds.
    pub(super) fn command(self, pose: Pose2, goal: [f64; 2], max_turn_rate: f64, dt: f64) -> Command {
        match self {
            Self::Look { .. } => Command {
                speed_m_s: 0.0,
                turn_rate_rad_s: (heading_error(pose, goal) / dt).clamp(-max_turn_rate, max_turn_rate),
            },
            Self::BackUp { speed_m_s, .. } => Command {
                speed_m_s: -speed_m_s,
                turn_rate_rad_s: 0.0,
            },
        }
    }

    pub(super) fn describe(self) -> String {
        match self {
            Self::Look { seconds } => {
                format!("recovery: face the goal and wait {seconds} s, mapping, then plan again")
            }
            Self::BackUp {
                distance_m,
                speed_m_s,
            } => format!("recovery: back up {distance_m} m at {speed_m_s} m/s, then plan again"),
        }
    }

    pub(super) fn name(self) -> String {
        match self {
            Self::Look { seconds } => format!("face the goal and wait {seconds} s"),
            Self::BackUp { distance_m, .. } => format!("back up {distance_m} m"),
        }
    }
}

/// The turn from `pose`'s heading to the bearing of `goal`, radians in `(-pi, pi]`.
fn heading_error(pose: Pose2, goal: [f64; 2]) -> f64 {
    let bearing = (goal[1] - pose.y_m).atan2(goal[0] - pose.x_m);
    sim::drive::wrap_angle(bearing - pose.yaw_rad)
}

/// The recovery sequence, nav2's default behaviour tree where it applies: its `ClearEntireCostmap` has nothing
/// to clear (the map keeps no transient layer: every cell is evidence, forgotten only by new evidence); its
/// `Spin` becomes a turn to face the goal, since the sensors look ahead and the way is what must be seen
/// again; then its `Wait` and its `BackUp`, each followed by a plan. The robot is stuck only when it still
/// makes no progress after the last.
pub(super) fn recovery_sequence(n: &Navigation) -> Vec<Recovery> {
    let mut sequence = vec![Recovery::Look {
        seconds: n.recovery_wait_s,
    }];
    if n.backup_distance_m > 0.0 {
        sequence.push(Recovery::BackUp {
            distance_m: n.backup_distance_m,
            speed_m_s: n.backup_speed_m_s,
        });
    }
    sequence
}

pub(super) fn describe_sequence(sequence: &[Recovery]) -> String {
    sequence.iter().map(|r| r.name()).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use oeg::Pose2;

    use super::{Recovery, heading_error};

    fn pose(x_m: f64, y_m: f64, yaw_deg: f64) -> Pose2 {
        Pose2 {
            x_m,
            y_m,
            yaw_rad: yaw_deg.to_radians(),
        }
    }

    #[test]
    fn a_look_turns_the_short_way_to_face_the_goal_then_stands() {
        let goal = [0.0, 5.0];
        // Facing east, the goal due north: a quarter turn to the left.
        let p = pose(0.0, 0.0, 0.0);
        assert!((heading_error(p, goal) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // Facing 170 degrees with the goal at -170: 20 degrees to the left across the seam, not 340 right.
        let across = heading_error(pose(0.0, 0.0, 170.0), [-10.0, -10.0 * 10f64.to_radians().tan()]);
        assert!((across - 20f64.to_radians()).abs() < 1e-9, "{across}");
        let look = Recovery::Look { seconds: 5.0 };
        let rate = 1.0;
        // A tick of 0.1 s: the turn is capped at the robot's rate, and the robot does not drive.
        let c = look.command(p, goal, rate, 0.1);
        assert_eq!((c.speed_m_s, c.turn_rate_rad_s), (0.0, rate));
        // Nearly facing it: the last tick turns just the rest.
        let c = look.command(pose(0.0, 0.0, 89.0), goal, rate, 0.1);
        assert!((c.turn_rate_rad_s - 1f64.to_radians() / 0.1).abs() < 1e-9);
        // It lasts the turn at that rate and the wait.
        assert!((look.duration_s(p, goal, rate) - (std::f64::consts::FRAC_PI_2 + 5.0)).abs() < 1e-12);
    }

    #[test]
    fn a_back_up_drives_backwards_straight_for_its_distance() {
        let back = Recovery::BackUp {
            distance_m: 0.3,
            speed_m_s: 0.05,
        };
        let c = back.command(pose(1.0, 1.0, 30.0), [9.0, 9.0], 1.0, 0.1);
        assert_eq!((c.speed_m_s, c.turn_rate_rad_s), (-0.05, 0.0));
        assert!((back.duration_s(pose(0.0, 0.0, 0.0), [1.0, 0.0], 1.0) - 6.0).abs() < 1e-12);
    }
}
