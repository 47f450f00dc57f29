//! The clock: the robot moved along its drive (settled on the terrain) and the actors along their
//! waypoints, and the poses of the robot and its links, true and as odometry believes.

use crate::convert::to_pose;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};

use super::{ActorTrack, World};
use crate::drive::{PlanarPose, VelocityCommand};

impl ActorTrack {
    /// Position at `t_s`, or `None` when the actor is not in the scene.
    pub(super) fn position_at(&self, t_s: f64) -> Option<(f64, f64)> {
        crate::scenario::position_on(&self.waypoints, t_s)
    }
}

impl World {
    /// Simulated time, seconds.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// Moves the clock to `t_s` (not before the current time): the robot along its drive (or its velocity
    /// command, once one was given), draped on the terrain, its odometry drift, and the actors.
    pub fn advance_to(&mut self, t_s: f64) {
        let t_s = t_s.max(self.time_s);
        self.time_s = t_s;
        self.move_actors(t_s);
        let planar = if let Some(wheels) = self.wheels.as_mut() {
            let labels = &self.labels;
            wheels.advance_to(&mut self.physics, t_s, &|u| Self::name_of(labels, u));
            let pose = wheels.world_from_base(&self.physics);
            let mut now = crate::physics::planar(&pose);
            now.distance_m =
                self.planar.distance_m + (now.x_m - self.planar.x_m).hypot(now.y_m - self.planar.y_m);
            self.world_from_base = pose;
            now
        } else {
            let planar = match &self.command {
                Some(c) => c.pose_at(t_s),
                None => self.path.pose_at(t_s),
            };
            self.world_from_base = self.drape(planar.x_m, planar.y_m, planar.yaw_rad);
            planar
        };
        self.planar = planar;
        self.drift.advance(planar.distance_m);
        self.estimated_world_from_base = self.drift.apply(&self.world_from_base);
        if let Some(body) = self.physics.bodies.get_mut(self.robot_body) {
            body.set_position(to_pose(&self.world_from_base), true);
        }
        self.physics.detect_collisions(&(), &());
    }

    /// Puts each actor where it is at `t_s`, and takes out of the scene those not in it.
    fn move_actors(&mut self, t_s: f64) {
        for k in 0..self.actors.len() {
            let track = &self.actors[k];
            let present = track.position_at(t_s);
            let (body, collider, half) = (track.body, track.collider, track.half_height_m);
            if let Some((x, y)) = present {
                let z = self.ground_z(x, y).unwrap_or(0.0) + half;
                if let Some(b) = self.physics.bodies.get_mut(body) {
                    b.set_position(to_pose(&Isometry3::translation(x, y, z)), true);
                }
            }
            if let Some(c) = self.physics.colliders.get_mut(collider) {
                c.set_enabled(present.is_some());
            }
        }
    }

    /// The base pose at `(x, y, yaw)` resting on the terrain: height from the wheel contacts, pitch from the
    /// front and rear pairs, roll from the left and right pairs.
    pub(super) fn drape(&self, x: f64, y: f64, yaw: f64) -> Isometry3<f64> {
        let planar = Isometry3::from_parts(
            Translation3::new(x, y, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        );
        let ground = |p: &Point3<f64>| {
            let w = planar * p;
            self.ground_z(w.x, w.y).unwrap_or(0.0)
        };
        let c = &self.wheel_contacts;
        if c.len() != 4 {
            let z = self.ground_z(x, y).unwrap_or(0.0);
            return Isometry3::from_parts(
                Translation3::new(x, y, z),
                UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
            );
        }
        // Sorted front-left, front-right, rear-left, rear-right.
        let z: Vec<f64> = c.iter().map(ground).collect();
        let wheelbase = (c[0].x + c[1].x - c[2].x - c[3].x) / 2.0;
        let track = (c[0].y + c[2].y - c[1].y - c[3].y) / 2.0;
        let pitch = -(((z[0] + z[1]) - (z[2] + z[3])) / 2.0).atan2(wheelbase);
        let roll = (((z[0] + z[2]) - (z[1] + z[3])) / 2.0).atan2(track);
        let mean = z.iter().sum::<f64>() / 4.0;
        Isometry3::from_parts(
            Translation3::new(x, y, mean),
            UnitQuaternion::from_euler_angles(roll, pitch, yaw),
        )
    }

    /// From now on, the robot drives at `speed_m_s` (negative: backwards) turning at `turn_rate_rad_s`
    /// from where it is, instead of along its scripted path, until the next command: the simulator's side of
    /// a `cmd_vel`. A kinematic robot goes where it is sent, through obstacles too (contacts are the judge's
    /// to find); a robot on its wheels has its drive try, within its motors' limits, and goes where the
    /// physics takes it.
    pub fn command(&mut self, speed_m_s: f64, turn_rate_rad_s: f64) {
        if let Some(wheels) = self.wheels.as_mut() {
            wheels.command(speed_m_s, turn_rate_rad_s);
            return;
        }
        self.command = Some(VelocityCommand {
            since_s: self.time_s,
            from: self.planar,
            speed_m_s,
            turn_rate_rad_s,
        });
    }

    /// The robot's true planar pose now: position, heading and distance driven.
    pub fn planar_pose(&self) -> PlanarPose {
        self.planar
    }

    /// The time at which the scripted drive ends (the robot stands at its last waypoint), seconds.
    pub fn drive_end_s(&self) -> f64 {
        self.path.duration_s()
    }

    /// The robot's true pose, `world_from_base`.
    pub fn world_from_base(&self) -> Isometry3<f64> {
        self.world_from_base
    }

    /// The robot's estimated pose (true pose plus odometry drift).
    pub fn estimated_world_from_base(&self) -> Isometry3<f64> {
        self.estimated_world_from_base
    }

    /// `world_from_link` of a robot link at the current time (true pose).
    pub fn world_from_link(&self, link: &str) -> Option<Isometry3<f64>> {
        self.robot.base_from_link(link).map(|b| self.world_from_base * b)
    }

    /// `world_from_link` from the estimated pose.
    pub fn estimated_world_from_link(&self, link: &str) -> Option<Isometry3<f64>> {
        self.robot
            .base_from_link(link)
            .map(|b| self.estimated_world_from_base * b)
    }
}
