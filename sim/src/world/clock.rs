//! The clock: the robot moved along its drive (settled on the terrain) and the actors along their
//! waypoints, and the poses of the robot and its links, true and as odometry believes.

use crate::convert::to_pose;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};

use rapier3d::prelude::PhysicsWorld;

use super::queries::GroundProbe;
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
        let ground = self.ground_probe();
        let planar = if let Some(wheels) = self.wheels.as_mut() {
            // On its wheels the robot meets the actors in the physics: each moves to where it is at the end of
            // every physics step, with the velocity that takes it there, rather than jumping a tick at a time.
            let (labels, actors) = (&self.labels, &self.actors);
            wheels.advance_to(
                &mut self.physics,
                t_s,
                &|u| Self::name_of(labels, u),
                &mut |physics, step_end_s| move_actors(physics, actors, ground, step_end_s, Motion::Step),
            );
            let pose = wheels.world_from_base(&self.physics);
            let mut now = crate::physics::planar(&pose);
            now.distance_m =
                self.planar.distance_m + (now.x_m - self.planar.x_m).hypot(now.y_m - self.planar.y_m);
            self.world_from_base = pose;
            now
        } else {
            move_actors(&mut self.physics, &self.actors, ground, t_s, Motion::Place);
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

    /// The path a closed loop's commands follow from now on (its plan; empty while it has none): a robot on its
    /// wheels reports its distance from it in every sample, the difference between the commanded and the
    /// achieved path. A kinematic robot keeps no physics log.
    pub fn set_reference_path(&mut self, path: &[(f64, f64)]) {
        if let Some(wheels) = self.wheels.as_mut() {
            wheels.set_reference(path);
        }
    }

    /// A closed loop's navigator reached its goal: a robot on its wheels logs it as its goal-reached event,
    /// at the time and place it is now (its scripted drive logs its own at its last waypoint). A kinematic
    /// robot keeps no physics log.
    pub fn goal_reached(&mut self) {
        if let Some(wheels) = self.wheels.as_mut() {
            wheels.goal_reached(self.planar.x_m, self.planar.y_m);
        }
    }

    /// The robot's true planar pose now: position, heading and distance driven.
    pub fn planar_pose(&self) -> PlanarPose {
        self.planar
    }

    /// The time at which the kinematic scripted drive ends (the robot stands at its last waypoint), seconds.
    /// A robot on its wheels takes the time the physics gives it: [`World::scripted_drive_over`].
    pub fn drive_end_s(&self) -> f64 {
        self.path.duration_s()
    }

    /// Whether the scripted drive is over: for a kinematic robot, its time has passed; for a robot on its
    /// wheels, it reached the last waypoint or a velocity command replaced the script.
    pub fn scripted_drive_over(&self) -> bool {
        match &self.wheels {
            Some(wheels) => wheels.scripted_drive_over(),
            None => self.time_s >= self.drive_end_s(),
        }
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

    /// The ground under the robot in the frame of its link `link`: the mean of its wheels' contact points, so
    /// that a sensor on that link knows, in every pose, how high the ground under the robot is. `None` for a
    /// robot without wheels or without that link.
    pub fn ground_in_link(&self, link: &str) -> Option<Point3<f64>> {
        if self.wheel_contacts.is_empty() {
            return None;
        }
        let mean = self
            .wheel_contacts
            .iter()
            .fold(nalgebra::Vector3::zeros(), |sum, c| sum + c.coords)
            / self.wheel_contacts.len() as f64;
        self.robot
            .base_from_link(link)
            .map(|b| b.inverse_transform_point(&Point3::from(mean)))
    }

    /// Where the robot stands now as odometry believes ([`crate::robot::stance_at`] at the estimated pose), for
    /// the map's [`oeg::Map::integrate_stance`]. `None` for a robot without wheels or collision shapes.
    pub fn estimated_stance(&self) -> Option<oeg::Stance> {
        crate::robot::stance_at(
            &self.wheel_contacts,
            self.robot.footprint(),
            &self.estimated_world_from_base,
        )
    }

    /// `world_from_link` from the estimated pose.
    pub fn estimated_world_from_link(&self, link: &str) -> Option<Isometry3<f64>> {
        self.robot
            .base_from_link(link)
            .map(|b| self.estimated_world_from_base * b)
    }
}

/// How an actor gets to where it is next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Motion {
    /// Placed there at once: a kinematic robot meets nothing in the physics.
    Place,
    /// Moved there over the next physics step, with the velocity that takes it there, so that a robot on its
    /// wheels meets it as a moving body.
    Step,
}

/// Puts each actor where it is at `t_s`, standing on the ground `ground` finds under it, and takes out of the
/// scene those not in it.
pub(super) fn move_actors(
    physics: &mut PhysicsWorld,
    actors: &[ActorTrack],
    ground: GroundProbe,
    t_s: f64,
    motion: Motion,
) {
    for track in actors {
        let present = track.position_at(t_s);
        // An actor that enters the scene is placed: moved there over one step, it would sweep across it.
        let entering = physics
            .colliders
            .get(track.collider)
            .is_some_and(|c| !c.is_enabled());
        if let Some((x, y)) = present {
            let z = ground.z(physics, x, y).unwrap_or(0.0) + track.half_height_m;
            if let Some(b) = physics.bodies.get_mut(track.body) {
                let pose = to_pose(&Isometry3::translation(x, y, z));
                if motion == Motion::Place || entering {
                    b.set_position(pose, true);
                } else {
                    b.set_next_kinematic_position(pose);
                }
            }
        }
        if let Some(c) = physics.colliders.get_mut(track.collider) {
            c.set_enabled(present.is_some());
        }
    }
}
