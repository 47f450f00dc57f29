//! Queries of the world at the current time: the one ray cast every sensor and the truth go through, the
//! ground height, the robot's collider poses.

use crate::convert::{from_pose, point_to_vector, to_vector};
use nalgebra::{Isometry3, Point3, Vector3};
use rapier3d::math::Vector;
use rapier3d::prelude::{Collider, ColliderHandle, PhysicsWorld, QueryFilter, Ray};

use super::{
    Actors, HitKind, KIND_ACTOR, KIND_OBSTACLE, KIND_ROBOT, KIND_TERRAIN, RayHit, RayStart, World, kind_of,
};

impl World {
    /// Casts a ray from `origin` along `direction` (any length) up to `max_range_m`, ignoring the robot.
    pub fn cast_ray(
        &self,
        origin: &Point3<f64>,
        direction: &Vector3<f64>,
        max_range_m: f64,
        actors: Actors,
        start: RayStart,
    ) -> Option<RayHit> {
        let norm = direction.norm();
        if !norm.is_finite() || norm <= 0.0 || !origin.iter().all(|v| v.is_finite()) {
            return None;
        }
        let dir = direction / norm;
        let ray = Ray::new(point_to_vector(origin), to_vector(&dir));
        let skip_actors = |_: ColliderHandle, c: &Collider| kind_of(c) != KIND_ACTOR;
        // The robot on its wheels is many bodies: its colliders are skipped by their tag.
        let skip_robot = |_: ColliderHandle, c: &Collider| {
            let kind = kind_of(c);
            kind != KIND_ROBOT && (actors == Actors::Included || kind != KIND_ACTOR)
        };
        let mut filter = QueryFilter::default().exclude_rigid_body(self.robot_body);
        if self.wheels.is_some() {
            filter = filter.predicate(&skip_robot);
        } else if actors == Actors::Excluded {
            filter = filter.predicate(&skip_actors);
        }
        let (handle, toi) =
            self.physics
                .cast_ray(&ray, max_range_m as f32, start == RayStart::InsideHits, filter)?;
        let collider = self.physics.colliders.get(handle)?;
        let index = (collider.user_data & 0xffff_ffff) as usize;
        let kind = match kind_of(collider) {
            KIND_TERRAIN => HitKind::Terrain,
            KIND_OBSTACLE => HitKind::Obstacle { index },
            _ => HitKind::Actor { index },
        };
        let distance_m = f64::from(toi);
        Some(RayHit {
            point_in_world: origin + dir * distance_m,
            distance_m,
            kind,
        })
    }

    /// The terrain's height at `(x, y)` (obstacles and actors ignored), or `None` off the terrain.
    pub fn ground_z(&self, x: f64, y: f64) -> Option<f64> {
        self.ground_probe().z(&self.physics, x, y)
    }

    /// What [`World::ground_z`] needs of the world besides its physics, to ask while the physics is borrowed.
    pub(super) fn ground_probe(&self) -> GroundProbe {
        GroundProbe {
            top_m: self.terrain_top_m,
            span_m: self.terrain_span_m,
        }
    }

    /// Every robot collider's world pose, for checks and drawings.
    pub fn robot_collider_poses(&self) -> Vec<Isometry3<f64>> {
        self.physics
            .colliders
            .iter()
            .filter(|(_, c)| kind_of(c) == KIND_ROBOT)
            .map(|(_, c)| from_pose(c.position()))
            .collect()
    }
}

/// The terrain's vertical extent, for a ray straight down onto it.
#[derive(Debug, Clone, Copy)]
pub(super) struct GroundProbe {
    top_m: f64,
    span_m: f64,
}

impl GroundProbe {
    /// The terrain's height at `(x, y)` in `physics`, or `None` off the terrain.
    pub(super) fn z(self, physics: &PhysicsWorld, x: f64, y: f64) -> Option<f64> {
        // Start just above the terrain: Rapier works in f32, and a start far above would cost precision.
        let ray = Ray::new(
            point_to_vector(&Point3::new(x, y, self.top_m)),
            Vector::new(0.0, 0.0, -1.0),
        );
        let only_terrain = |_: ColliderHandle, c: &Collider| kind_of(c) == KIND_TERRAIN;
        let filter = QueryFilter::default().predicate(&only_terrain);
        let (_, toi) = physics.cast_ray(&ray, self.span_m as f32, true, filter)?;
        Some(self.top_m - f64::from(toi))
    }
}
