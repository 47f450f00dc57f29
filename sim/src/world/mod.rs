//! The simulated world: a Rapier world (z up, gravity -z) holding the terrain, the obstacles, the moving
//! actors and the robot, a clock that moves the robot along its drive and the actors along their waypoints, and
//! one ray cast that every sensor and the ground truth go through.
//!
//! Nothing here integrates dynamics: every body is fixed or kinematic, placed at each tick, and the query
//! structures are refreshed with Rapier's collision detection (`PhysicsWorld::detect_collisions`).

mod build;
mod clock;
mod queries;

use nalgebra::{Isometry3, Point3};
use rapier3d::prelude::{Collider, ColliderHandle, PhysicsWorld, RigidBodyHandle};

use crate::drive::{DrivePath, OdometryDrift, PlanarPose, VelocityCommand};
use crate::physics::{PhysicsDrive, PhysicsEvent, PhysicsSample};
use crate::robot::RobotModel;
use crate::terrain::HeightGrid;

/// How far boxes and ramps standing on the ground reach below it, metres: on uneven terrain their footprint
/// stays sealed against the ground instead of floating over its dips. Cylinders stand on the ground at their
/// centre's height.
pub const OBSTACLE_FOOTING_M: f64 = 0.5;

const KIND_TERRAIN: u32 = 0;
const KIND_OBSTACLE: u32 = 1;
const KIND_ACTOR: u32 = 2;
const KIND_ROBOT: u32 = 3;

fn tag(kind: u32, index: usize) -> u128 {
    (u128::from(kind) << 32) | index as u128
}

fn kind_of(c: &Collider) -> u32 {
    (c.user_data >> 32) as u32
}

/// What a ray hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HitKind {
    /// The ground.
    Terrain,
    /// Static obstacle number `index` of the scenario.
    Obstacle {
        /// Index in the scenario's `obstacles`.
        index: usize,
    },
    /// Moving actor number `index`.
    Actor {
        /// Index in the scenario's `actors`.
        index: usize,
    },
}

/// A ray's first hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// Where, world frame.
    pub point_in_world: Point3<f64>,
    /// How far from the ray's origin, metres.
    pub distance_m: f64,
    /// What.
    pub kind: HitKind,
}

/// Whether moving actors take part in a query.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Actors {
    /// Rays hit the actors present at the current time (sensors).
    Included,
    /// Rays pass through every actor (the static truth).
    Excluded,
}

/// How a ray treats an origin inside a shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RayStart {
    /// A ray starting inside a shape hits it at distance 0 (the truth's "inside a solid").
    InsideHits,
    /// A ray starting inside a shape leaves it and reports its exit (what a sensor behind a window sees is
    /// not this; sensors start outside shapes).
    InsideExits,
}

#[derive(Debug, Clone)]
struct ActorTrack {
    body: RigidBodyHandle,
    collider: ColliderHandle,
    waypoints: Vec<[f64; 3]>,
    half_height_m: f64,
}

/// The simulated world of one scenario.
pub struct World {
    physics: PhysicsWorld,
    /// The kinematic robot's one body (invalid when the robot drives on its wheels).
    robot_body: RigidBodyHandle,
    /// The robot on its wheels (`[robot.drive] mode = "physics"`), or `None`: placed on its path.
    wheels: Option<PhysicsDrive>,
    actors: Vec<ActorTrack>,
    robot: RobotModel,
    path: DrivePath,
    /// The velocity command the robot follows instead of its path, once one was given.
    command: Option<VelocityCommand>,
    /// The robot's planar pose now.
    planar: PlanarPose,
    drift: OdometryDrift,
    wheel_contacts: Vec<Point3<f64>>,
    time_s: f64,
    world_from_base: Isometry3<f64>,
    estimated_world_from_base: Isometry3<f64>,
    terrain: HeightGrid,
    /// Above the terrain's highest point, metres: where ground queries start.
    terrain_top_m: f64,
    /// The terrain's height range plus margins, metres: how far ground queries reach.
    terrain_span_m: f64,
    labels: Vec<String>,
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("time_s", &self.time_s)
            .field("num_colliders", &self.physics.colliders.len())
            .field("world_from_base", &self.world_from_base)
            .finish_non_exhaustive()
    }
}

impl World {
    /// The robot model.
    pub fn robot(&self) -> &RobotModel {
        &self.robot
    }

    /// The drive path.
    pub fn path(&self) -> &DrivePath {
        &self.path
    }

    /// The terrain grid.
    pub fn terrain(&self) -> &HeightGrid {
        &self.terrain
    }

    /// The label of obstacle `index`.
    pub fn obstacle_label(&self, index: usize) -> Option<&str> {
        self.labels.get(index).map(String::as_str)
    }

    /// Where each actor is now (`None`: not in the scene).
    pub fn actor_positions(&self) -> Vec<Option<(f64, f64)>> {
        self.actors.iter().map(|a| a.position_at(self.time_s)).collect()
    }

    /// Number of colliders in the Rapier world.
    pub fn num_colliders(&self) -> usize {
        self.physics.colliders.len()
    }

    /// Whether the robot drives on its wheels (`[robot.drive] mode = "physics"`).
    pub fn drives_on_wheels(&self) -> bool {
        self.wheels.is_some()
    }

    /// What happened to the robot on its wheels so far, by name (`None`: the robot is kinematic).
    pub fn physics_events(&self) -> Option<&[PhysicsEvent]> {
        self.wheels.as_ref().map(PhysicsDrive::events)
    }

    /// The robot's state on its wheels, sampled every [`crate::physics::SAMPLE_PERIOD_S`] (`None`: the robot
    /// is kinematic).
    pub fn physics_samples(&self) -> Option<&[PhysicsSample]> {
        self.wheels.as_ref().map(PhysicsDrive::samples)
    }

    /// The name of what a collider's `user_data` tags: an obstacle's label, `person <k>`, `ground` or `robot`.
    fn name_of(labels: &[String], user_data: u128) -> String {
        let index = (user_data & 0xffff_ffff) as usize;
        match (user_data >> 32) as u32 {
            KIND_TERRAIN => "ground".to_string(),
            KIND_OBSTACLE => labels
                .get(index)
                .cloned()
                .unwrap_or_else(|| format!("obstacle {index}")),
            KIND_ACTOR => format!("person {index}"),
            _ => "robot".to_string(),
        }
    }
}
