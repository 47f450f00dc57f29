//! Pure pursuit (Coulter, "Implementation of the Pure Pursuit Path Tracking Algorithm", CMU-RI-TR-92-01), as
//! nav2's Regulated Pure Pursuit runs it: steer along the arc through the point one lookahead ahead on the
//! path; turn on the spot first when that point lies more than 45 degrees off the heading; slow down over the
//! last lookahead before the goal; never exceed the robot's turn rate (the speed drops so the arc is kept).

use oeg::Pose2;

/// Heading error above which the robot turns on the spot (nav2's `rotate_to_heading_min_angle`, 0.785 rad).
pub(crate) const ROTATE_IN_PLACE_RAD: f64 = std::f64::consts::FRAC_PI_4;
/// The slowest approach speed, as a fraction of the cruise speed.
const MIN_APPROACH_FRACTION: f64 = 0.25;

/// The controller's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PurePursuit {
    /// Distance along the path to the point steered at, metres.
    pub lookahead_m: f64,
    /// Cruise speed, m/s.
    pub speed_m_s: f64,
    /// The robot's top turn rate, radians per second.
    pub max_turn_rate_rad_s: f64,
}

/// A velocity command.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Command {
    /// Forward speed, m/s.
    pub speed_m_s: f64,
    /// Turn rate, radians per second, counter-clockwise.
    pub turn_rate_rad_s: f64,
}

impl PurePursuit {
    /// The command that follows `path` (world points, start first) from `pose`. `progress` is the index of
    /// the path segment reached so far: the closest point is searched from there on, so the robot never
    /// steers back to a part of the path it has passed.
    pub(crate) fn command(&self, pose: Pose2, path: &[(f64, f64)], progress: &mut usize) -> Command {
        let Some(&last) = path.last() else {
            return Command::default();
        };
        let target = self.lookahead_point(pose, path, progress);
        let (s, c) = pose.yaw_rad.sin_cos();
        let (dx, dy) = (target.0 - pose.x_m, target.1 - pose.y_m);
        // The target in the robot's frame.
        let (fx, fy) = (c * dx + s * dy, -s * dx + c * dy);
        let alpha = fy.atan2(fx);
        if fx.hypot(fy) < 1e-9 {
            return Command::default();
        }
        if alpha.abs() > ROTATE_IN_PLACE_RAD {
            return Command {
                speed_m_s: 0.0,
                turn_rate_rad_s: self.max_turn_rate_rad_s.copysign(alpha),
            };
        }
        let curvature = 2.0 * fy / (fx * fx + fy * fy);
        let to_goal = (last.0 - pose.x_m).hypot(last.1 - pose.y_m);
        let approach = (to_goal / self.lookahead_m).clamp(MIN_APPROACH_FRACTION, 1.0);
        let mut speed = self.speed_m_s * approach;
        if (speed * curvature).abs() > self.max_turn_rate_rad_s {
            speed = self.max_turn_rate_rad_s / curvature.abs();
        }
        Command {
            speed_m_s: speed,
            turn_rate_rad_s: speed * curvature,
        }
    }

    /// The point one lookahead along the path from the point of it closest to `pose` (the path's end when
    /// less is left).
    fn lookahead_point(&self, pose: Pose2, path: &[(f64, f64)], progress: &mut usize) -> (f64, f64) {
        if path.len() == 1 {
            return path[0];
        }
        let start = (*progress).min(path.len() - 2);
        let (mut best, mut best_d, mut best_t) = (start, f64::INFINITY, 0.0);
        for k in start..path.len() - 1 {
            let (t, d) = project((pose.x_m, pose.y_m), path[k], path[k + 1]);
            if d < best_d {
                (best, best_d, best_t) = (k, d, t);
            }
        }
        *progress = best;
        let (a, b) = (path[best], path[best + 1]);
        let mut left = self.lookahead_m;
        let mut from = (a.0 + best_t * (b.0 - a.0), a.1 + best_t * (b.1 - a.1));
        for k in best..path.len() - 1 {
            let to = path[k + 1];
            let seg = (to.0 - from.0).hypot(to.1 - from.1);
            if seg >= left {
                let f = left / seg;
                return (from.0 + f * (to.0 - from.0), from.1 + f * (to.1 - from.1));
            }
            left -= seg;
            from = to;
        }
        path[path.len() - 1]
    }
}

/// Where `p` projects on segment `a`-`b`: the fraction along it, and the distance.
fn project(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (t, (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy))
}

#[cfg(test)]
mod tests {
    use super::*;

    const CONTROLLER: PurePursuit = PurePursuit {
        lookahead_m: 0.6,
        speed_m_s: 0.4,
        max_turn_rate_rad_s: 1.0,
    };

    fn at(x_m: f64, y_m: f64, yaw_deg: f64) -> Pose2 {
        Pose2 {
            x_m,
            y_m,
            yaw_rad: yaw_deg.to_radians(),
        }
    }

    #[test]
    fn on_a_straight_path_it_drives_straight_at_cruise_speed() {
        let path = [(0.0, 0.0), (5.0, 0.0)];
        let c = CONTROLLER.command(at(1.0, 0.0, 0.0), &path, &mut 0);
        assert_eq!(c.speed_m_s, 0.4);
        assert!(c.turn_rate_rad_s.abs() < 1e-12);
    }

    #[test]
    fn it_steers_back_onto_the_path_and_turns_on_the_spot_when_facing_away() {
        let path = [(0.0, 0.0), (5.0, 0.0)];
        // 0.2 m to the left of the path: turns right (clockwise).
        let c = CONTROLLER.command(at(1.0, 0.2, 0.0), &path, &mut 0);
        assert!(c.turn_rate_rad_s < 0.0 && c.speed_m_s > 0.0, "{c:?}");
        // Facing backwards: turns on the spot at the top rate.
        let back = CONTROLLER.command(at(1.0, 0.0, 170.0), &path, &mut 0);
        assert_eq!(back.speed_m_s, 0.0);
        assert_eq!(back.turn_rate_rad_s.abs(), 1.0);
    }

    #[test]
    fn it_slows_near_the_goal_and_keeps_the_turn_rate_limit() {
        let path = [(0.0, 0.0), (1.0, 0.0)];
        let near = CONTROLLER.command(at(0.85, 0.0, 0.0), &path, &mut 0);
        assert!((near.speed_m_s - 0.1).abs() < 1e-12, "{near:?}");
        // A sharp arc: the turn rate is capped, the speed drops to keep the arc.
        let slow = PurePursuit {
            max_turn_rate_rad_s: 0.2,
            ..CONTROLLER
        };
        let c = slow.command(at(0.0, 0.0, 0.0), &[(0.0, 0.0), (0.3, 0.3), (0.3, 2.0)], &mut 0);
        assert!(
            (c.turn_rate_rad_s - 0.2).abs() < 1e-12 && c.speed_m_s < 0.4,
            "{c:?}"
        );
    }

    #[test]
    fn progress_never_runs_back_along_the_path() {
        // A U-turn: the closest point to (1, 0.9) would be on the first leg, but progress is on the second.
        let path = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (0.0, 1.0)];
        let mut progress = 2;
        let target = CONTROLLER.lookahead_point(at(1.0, 0.9, 180.0), &path, &mut progress);
        assert_eq!(progress, 2);
        assert!(
            (target.0 - 0.4).abs() < 1e-9 && (target.1 - 1.0).abs() < 1e-9,
            "{target:?}"
        );
    }
}
