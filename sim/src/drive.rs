//! The drive: where the robot is on its path at a time, and the odometry drift of its estimated pose.

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use rand_distr::{Distribution, Normal};

use crate::scenario::{Drive, Odometry};
use crate::seed::Stream;

/// The planar part of a pose on the path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanarPose {
    /// Position, metres.
    pub x_m: f64,
    /// Position, metres.
    pub y_m: f64,
    /// Heading from +x, radians.
    pub yaw_rad: f64,
    /// Distance driven since the start, metres.
    pub distance_m: f64,
}

/// The path: straight segments between waypoints at a constant speed. The robot turns on the spot at each
/// waypoint (instantly) and stops at the last one.
#[derive(Debug, Clone, PartialEq)]
pub struct DrivePath {
    waypoints: Vec<[f64; 2]>,
    /// Distance from the start to each waypoint.
    cumulative_m: Vec<f64>,
    speed_m_s: f64,
    start_yaw_rad: f64,
}

impl DrivePath {
    /// The path of a validated drive.
    pub fn new(drive: &Drive) -> Self {
        let mut cumulative_m = vec![0.0];
        for w in drive.waypoints_xy_m.windows(2) {
            let d = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
            cumulative_m.push(cumulative_m.last().copied().unwrap_or(0.0) + d);
        }
        let first_heading = drive
            .waypoints_xy_m
            .windows(2)
            .find(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) > 0.0)
            .map_or(0.0, |w| (w[1][1] - w[0][1]).atan2(w[1][0] - w[0][0]));
        Self {
            waypoints: drive.waypoints_xy_m.clone(),
            cumulative_m,
            speed_m_s: drive.speed_m_s,
            start_yaw_rad: drive.start_yaw_deg.map_or(first_heading, f64::to_radians),
        }
    }

    /// Length of the path, metres.
    pub fn length_m(&self) -> f64 {
        self.cumulative_m.last().copied().unwrap_or(0.0)
    }

    /// How long the drive takes, seconds.
    pub fn duration_s(&self) -> f64 {
        self.length_m() / self.speed_m_s
    }

    /// The waypoints.
    pub fn waypoints(&self) -> &[[f64; 2]] {
        &self.waypoints
    }

    /// The pose at time `t_s` (clamped to the start and the end of the path).
    pub fn pose_at(&self, t_s: f64) -> PlanarPose {
        let s = (self.speed_m_s * t_s.max(0.0)).min(self.length_m());
        let mut yaw = self.start_yaw_rad;
        for (k, w) in self.waypoints.windows(2).enumerate() {
            let (a, b) = (self.cumulative_m[k], self.cumulative_m[k + 1]);
            if b - a <= 0.0 {
                continue;
            }
            yaw = (w[1][1] - w[0][1]).atan2(w[1][0] - w[0][0]);
            if s <= b {
                let f = (s - a) / (b - a);
                return PlanarPose {
                    x_m: w[0][0] + f * (w[1][0] - w[0][0]),
                    y_m: w[0][1] + f * (w[1][1] - w[0][1]),
                    yaw_rad: yaw,
                    distance_m: s,
                };
            }
        }
        let last = self.waypoints.last().copied().unwrap_or([0.0, 0.0]);
        PlanarPose {
            x_m: last[0],
            y_m: last[1],
            yaw_rad: yaw,
            distance_m: s,
        }
    }
}

/// A velocity command held from a time on (a ROS `cmd_vel`): the robot drives an arc of constant speed and
/// turn rate from the pose it had when the command was given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityCommand {
    /// When the command was given, seconds.
    pub since_s: f64,
    /// The pose then.
    pub from: PlanarPose,
    /// Forward speed, m/s; negative: the robot backs up.
    pub speed_m_s: f64,
    /// Turn rate, radians per second, counter-clockwise.
    pub turn_rate_rad_s: f64,
}

impl VelocityCommand {
    /// The pose at `t_s` (not before the command): the exact arc of a unicycle.
    pub fn pose_at(&self, t_s: f64) -> PlanarPose {
        let dt = (t_s - self.since_s).max(0.0);
        let (v, w, p) = (self.speed_m_s, self.turn_rate_rad_s, self.from);
        let yaw = p.yaw_rad + w * dt;
        let (dx, dy) = if (w * dt).abs() < 1e-9 {
            let mid = p.yaw_rad + w * dt / 2.0;
            (v * dt * mid.cos(), v * dt * mid.sin())
        } else {
            let r = v / w;
            (
                r * (yaw.sin() - p.yaw_rad.sin()),
                -r * (yaw.cos() - p.yaw_rad.cos()),
            )
        };
        PlanarPose {
            x_m: p.x_m + dx,
            y_m: p.y_m + dy,
            yaw_rad: wrap_angle(yaw),
            distance_m: p.distance_m + v.abs() * dt,
        }
    }
}

/// An angle in `(-pi, pi]`.
pub fn wrap_angle(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let w = a.rem_euclid(two_pi);
    if w > std::f64::consts::PI { w - two_pi } else { w }
}

/// The odometry drift: a random walk in x, y and yaw whose steps have a standard deviation proportional to the
/// square root of the distance driven in the step.
#[derive(Debug, Clone)]
pub struct OdometryDrift {
    settings: Odometry,
    rng: Stream,
    /// Accumulated error: x, y (metres), yaw (radians).
    pub error: [f64; 3],
    last_distance_m: f64,
}

impl OdometryDrift {
    /// No drift yet.
    pub fn new(settings: Odometry, rng: Stream) -> Self {
        Self {
            settings,
            rng,
            error: [0.0; 3],
            last_distance_m: 0.0,
        }
    }

    /// Adds the drift of driving up to `distance_m` along the path.
    pub fn advance(&mut self, distance_m: f64) {
        let step = (distance_m - self.last_distance_m).max(0.0);
        self.last_distance_m = distance_m;
        let root = step.sqrt();
        let sigmas = [
            self.settings.xy_sigma_m_per_sqrt_m * root,
            self.settings.xy_sigma_m_per_sqrt_m * root,
            self.settings.yaw_sigma_deg_per_sqrt_m.to_radians() * root,
        ];
        for (e, s) in self.error.iter_mut().zip(sigmas) {
            // Zero sigma draws nothing, so a drift-free run consumes no random numbers.
            if s > 0.0
                && let Ok(n) = Normal::new(0.0, s)
            {
                *e += n.sample(&mut self.rng);
            }
        }
    }

    /// The estimated pose: the true pose with the drift added to x, y and yaw.
    pub fn apply(&self, world_from_base: &Isometry3<f64>) -> Isometry3<f64> {
        let t = world_from_base.translation.vector;
        let (roll, pitch, yaw) = world_from_base.rotation.euler_angles();
        Isometry3::from_parts(
            Translation3::new(t.x + self.error[0], t.y + self.error[1], t.z),
            UnitQuaternion::from_euler_angles(roll, pitch, yaw + self.error[2]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drive() -> Drive {
        Drive {
            waypoints_xy_m: vec![[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]],
            speed_m_s: 1.0,
            start_yaw_deg: None,
            mode: crate::scenario::DriveMode::Kinematic,
        }
    }

    #[test]
    fn the_path_is_followed_at_speed_and_ends_at_the_last_waypoint() {
        let p = DrivePath::new(&drive());
        assert_eq!(p.length_m(), 7.0);
        let a = p.pose_at(2.0);
        assert_eq!((a.x_m, a.y_m, a.yaw_rad, a.distance_m), (2.0, 0.0, 0.0, 2.0));
        let b = p.pose_at(5.0);
        assert!((b.x_m - 4.0).abs() < 1e-12 && (b.y_m - 1.0).abs() < 1e-12);
        assert!((b.yaw_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let end = p.pose_at(100.0);
        assert_eq!((end.x_m, end.y_m, end.distance_m), (4.0, 3.0, 7.0));
    }

    #[test]
    fn a_held_command_drives_an_arc_and_a_straight_line() {
        let from = PlanarPose {
            x_m: 1.0,
            y_m: 2.0,
            yaw_rad: 0.0,
            distance_m: 3.0,
        };
        let straight = VelocityCommand {
            since_s: 10.0,
            from,
            speed_m_s: 0.5,
            turn_rate_rad_s: 0.0,
        };
        let p = straight.pose_at(12.0);
        assert_eq!((p.x_m, p.y_m, p.yaw_rad, p.distance_m), (2.0, 2.0, 0.0, 4.0));
        // A quarter circle of radius 1 m.
        let arc = VelocityCommand {
            turn_rate_rad_s: std::f64::consts::FRAC_PI_2,
            speed_m_s: std::f64::consts::FRAC_PI_2,
            ..straight
        };
        let q = arc.pose_at(11.0);
        assert!(
            (q.x_m - 2.0).abs() < 1e-12 && (q.y_m - 3.0).abs() < 1e-12,
            "{q:?}"
        );
        assert!((q.yaw_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // Turning on the spot moves nothing.
        let spin = VelocityCommand {
            speed_m_s: 0.0,
            turn_rate_rad_s: 1.0,
            ..straight
        };
        let r = spin.pose_at(14.0);
        assert_eq!((r.x_m, r.y_m, r.distance_m), (1.0, 2.0, 3.0));
        assert!((r.yaw_rad - wrap_angle(4.0)).abs() < 1e-12 && r.yaw_rad < 0.0);
    }

    #[test]
    fn drift_grows_with_distance_and_is_seeded() {
        let settings = Odometry {
            xy_sigma_m_per_sqrt_m: 0.05,
            yaw_sigma_deg_per_sqrt_m: 1.0,
        };
        let run = |seed| {
            let mut d = OdometryDrift::new(settings, crate::seed::stream(seed, "odometry"));
            for k in 1..=100 {
                d.advance(f64::from(k) * 0.1);
            }
            d.error
        };
        assert_eq!(run(1), run(1));
        assert_ne!(run(1), run(2));
        let mut none = OdometryDrift::new(Odometry::default(), crate::seed::stream(1, "odometry"));
        none.advance(10.0);
        assert_eq!(none.error, [0.0; 3]);
    }
}
