//! The scripted drive on the wheels: a pure-pursuit follower of the drive's waypoints, segment by segment, that
//! drives to each waypoint and turns on the spot there, as the kinematic drive does; between waypoints it
//! only steers.

use crate::drive::PlanarPose;

/// The follower's lookahead along the path, metres: nav2's Regulated Pure Pursuit `lookahead_dist`.
pub(crate) const LOOKAHEAD_M: f64 = crate::scenario::DEFAULT_LOOKAHEAD_M;
/// The last waypoint counts as reached this close, metres: within a wheel's radius of the scripted end.
pub(crate) const ARRIVAL_M: f64 = 0.1;
/// Heading error beyond which the robot turns on the spot before it drives on, radians (15 degrees): the
/// kinematic drive turns on the spot at each waypoint, and a skid-steer robot that drives off with a larger
/// error swings wide of its path.
const TURN_IN_PLACE_RAD: f64 = 15.0 * std::f64::consts::PI / 180.0;
/// Heading error below which a turn on the spot is done, radians (5 degrees): the hysteresis keeps the robot
/// from switching between turning and driving at the threshold.
const TURN_DONE_RAD: f64 = 5.0 * std::f64::consts::PI / 180.0;
/// Gain of the turn towards the lookahead point, 1/s.
const HEADING_GAIN_PER_S: f64 = 2.0;
/// The deceleration with which the robot comes to each waypoint, m/s²: the Pioneer's controller default
/// (ARIA's `TransDecel`, 300 mm/s²). Faster, a skid-steer robot slides on past the corner it turns at.
pub(crate) const DECELERATION_M_S2: f64 = 0.3;

/// Where the follower is on its waypoints.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct WaypointFollower {
    waypoints: Vec<[f64; 2]>,
    speed_m_s: f64,
    /// The segment the robot was last nearest to.
    segment: usize,
    arrived: bool,
    /// Turning on the spot, until the heading error is below [`TURN_DONE_RAD`].
    turning: bool,
    /// Whether the robot may still turn on the spot on this segment: at its start only. Mid-segment, an
    /// obstacle that pushes the robot off its heading (a curb met at an angle) is driven through with pure
    /// pursuit, as a driver would, not answered with a turn on the spot against it.
    at_segment_start: bool,
}

impl WaypointFollower {
    pub(crate) fn new(waypoints: &[[f64; 2]], speed_m_s: f64) -> Self {
        Self {
            waypoints: waypoints.to_vec(),
            speed_m_s,
            segment: 0,
            arrived: waypoints.len() < 2,
            turning: false,
            at_segment_start: true,
        }
    }

    /// Whether the robot has reached the last waypoint.
    pub(crate) fn arrived(&self) -> bool {
        self.arrived
    }

    /// The commanded speed (m/s) and turn rate (rad/s) from `pose`, limited to `max_turn_rate_rad_s`.
    pub(crate) fn command(&mut self, pose: &PlanarPose, max_turn_rate_rad_s: f64) -> (f64, f64) {
        let Some(last) = self.waypoints.last().copied() else {
            return (0.0, 0.0);
        };
        if self.arrived || (pose.x_m - last[0]).hypot(pose.y_m - last[1]) < ARRIVAL_M {
            self.arrived = true;
            return (0.0, 0.0);
        }
        // Advance past segments whose end the robot has passed (projection beyond the segment).
        while self.segment + 2 < self.waypoints.len() {
            let (a, b) = (self.waypoints[self.segment], self.waypoints[self.segment + 1]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len2 = dx * dx + dy * dy;
            let t = if len2 > 0.0 {
                ((pose.x_m - a[0]) * dx + (pose.y_m - a[1]) * dy) / len2
            } else {
                1.0
            };
            let to_end = (pose.x_m - b[0]).hypot(pose.y_m - b[1]);
            if t >= 1.0 || to_end < ARRIVAL_M {
                self.segment += 1;
                self.at_segment_start = true;
            } else {
                break;
            }
        }
        let target = self.lookahead_point(pose);
        let heading = (target[1] - pose.y_m).atan2(target[0] - pose.x_m);
        let error = wrap(heading - pose.yaw_rad);
        let turn = (HEADING_GAIN_PER_S * error).clamp(-max_turn_rate_rad_s, max_turn_rate_rad_s);
        if self.at_segment_start {
            self.turning = error.abs()
                > if self.turning {
                    TURN_DONE_RAD
                } else {
                    TURN_IN_PLACE_RAD
                };
            if self.turning {
                return (0.0, turn);
            }
            self.at_segment_start = false;
        }
        // Pure pursuit: the arc through the lookahead point, at the cruise speed, slowed to stop at the
        // segment's end.
        let end = self.waypoints[self.segment + 1];
        let to_end = (pose.x_m - end[0]).hypot(pose.y_m - end[1]);
        let speed = self
            .speed_m_s
            .min((2.0 * DECELERATION_M_S2 * to_end).sqrt().max(0.05));
        let distance = (target[0] - pose.x_m).hypot(target[1] - pose.y_m).max(1e-6);
        let curvature = 2.0 * error.sin() / distance;
        (
            speed,
            (speed * curvature).clamp(-max_turn_rate_rad_s, max_turn_rate_rad_s),
        )
    }

    /// The point [`LOOKAHEAD_M`] ahead of the robot's projection onto its current segment, never past the
    /// segment's end: the robot drives to each waypoint and turns there, as the kinematic drive does.
    fn lookahead_point(&self, pose: &PlanarPose) -> [f64; 2] {
        let (a, b) = (self.waypoints[self.segment], self.waypoints[self.segment + 1]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = dx.hypot(dy);
        if len <= 0.0 {
            return b;
        }
        let along = ((pose.x_m - a[0]) * dx + (pose.y_m - a[1]) * dy) / len;
        let f = ((along + LOOKAHEAD_M) / len).clamp(0.0, 1.0);
        [a[0] + f * dx, a[1] + f * dy]
    }
}

/// An angle in (-pi, pi].
pub(crate) fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let w = a.rem_euclid(t);
    if w > std::f64::consts::PI { w - t } else { w }
}

/// The distance from `(x, y)` to the polyline through `waypoints`, metres (to the point for one waypoint).
pub(crate) fn distance_to_path(waypoints: &[[f64; 2]], x: f64, y: f64) -> f64 {
    if waypoints.len() == 1 {
        return (x - waypoints[0][0]).hypot(y - waypoints[0][1]);
    }
    waypoints
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len2 = dx * dx + dy * dy;
            let t = if len2 > 0.0 {
                (((x - a[0]) * dx + (y - a[1]) * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (x - a[0] - t * dx).hypot(y - a[1] - t * dy)
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f64, y: f64, yaw_deg: f64) -> PlanarPose {
        PlanarPose {
            x_m: x,
            y_m: y,
            yaw_rad: yaw_deg.to_radians(),
            distance_m: 0.0,
        }
    }

    #[test]
    fn it_drives_along_a_straight_path_and_stops_at_its_end() {
        let mut f = WaypointFollower::new(&[[0.0, 0.0], [3.0, 0.0]], 0.5);
        let (v, w) = f.command(&at(1.0, 0.0, 0.0), 2.0);
        assert!((v - 0.5).abs() < 1e-12 && w.abs() < 1e-12, "{v} {w}");
        // Left of the path, it turns right, back towards it.
        let (_, w) = f.command(&at(1.0, 0.2, 0.0), 2.0);
        assert!(w < 0.0);
        assert_eq!(f.command(&at(2.95, 0.0, 0.0), 2.0), (0.0, 0.0));
        assert!(f.arrived());
    }

    #[test]
    fn it_turns_on_the_spot_at_a_corner() {
        let mut f = WaypointFollower::new(&[[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]], 0.5);
        let (v, w) = f.command(&at(2.0, 0.0, 0.0), 2.0);
        assert_eq!(v, 0.0);
        assert!(w > 0.0, "left turn at the corner: {w}");
    }

    #[test]
    fn angles_wrap_and_distances_reach_the_polyline() {
        assert!((wrap(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
        assert!((wrap(-0.5) + 0.5).abs() < 1e-12);
        let path = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]];
        assert!((distance_to_path(&path, 1.0, 0.3) - 0.3).abs() < 1e-12);
        assert!((distance_to_path(&path, 2.5, 1.0) - 0.5).abs() < 1e-12);
    }
}
