//! The simulated world: a Rapier world (z up, gravity -z) holding the terrain, the obstacles, the moving
//! actors and the robot, a clock that moves the robot along its drive and the actors along their waypoints, and
//! one ray cast that every sensor and the ground truth go through.
//!
//! Nothing here integrates dynamics: every body is fixed or kinematic, placed at each tick, and the query
//! structures are refreshed with Rapier's collision detection (`PhysicsWorld::detect_collisions`).

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::RngExt;
use rapier3d::math::{Rotation, Vector};
use rapier3d::parry::utils::Array2;
use rapier3d::prelude::{
    Collider, ColliderBuilder, ColliderHandle, PhysicsWorld, QueryFilter, Ray, RigidBodyBuilder,
    RigidBodyHandle,
};

use crate::convert::{from_pose, point_to_vector, to_pose, to_vector};
use crate::drive::{DrivePath, OdometryDrift};
use crate::error::{Result, SimError};
use crate::robot::{RobotModel, Shape};
use crate::scenario::{Actor, LoadedScenario, Obstacle, Scenario};
use crate::seed;
use crate::terrain::{self, HeightGrid};

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

impl ActorTrack {
    /// Position at `t_s`, or `None` when the actor is not in the scene.
    fn position_at(&self, t_s: f64) -> Option<(f64, f64)> {
        let first = self.waypoints.first()?;
        let last = self.waypoints.last()?;
        if t_s < first[0] || t_s > last[0] {
            return None;
        }
        for w in self.waypoints.windows(2) {
            if t_s <= w[1][0] {
                let f = (t_s - w[0][0]) / (w[1][0] - w[0][0]);
                return Some((
                    w[0][1] + f * (w[1][1] - w[0][1]),
                    w[0][2] + f * (w[1][2] - w[0][2]),
                ));
            }
        }
        Some((last[1], last[2]))
    }
}

/// The simulated world of one scenario.
pub struct World {
    physics: PhysicsWorld,
    robot_body: RigidBodyHandle,
    actors: Vec<ActorTrack>,
    robot: RobotModel,
    path: DrivePath,
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
    /// Builds the world of a loaded scenario, at time 0.
    ///
    /// # Errors
    /// [`SimError::Scenario`] if the terrain image cannot be read or a ramp's shape is degenerate.
    pub fn new(loaded: &LoadedScenario) -> Result<Self> {
        let s = &loaded.scenario;
        let scenario_error = |message: String| SimError::Scenario {
            path: loaded.source.path.clone(),
            position: None,
            message,
        };
        let mut physics = PhysicsWorld::new();
        physics.gravity = Vector::new(0.0, 0.0, -9.81);

        let terrain = terrain::build(s, &loaded.source).map_err(scenario_error)?;
        physics.insert(
            RigidBodyBuilder::fixed(),
            heightfield_collider(&terrain).user_data(tag(KIND_TERRAIN, 0)),
        );
        physics.detect_collisions(&(), &());

        let mut world = Self {
            physics,
            robot_body: RigidBodyHandle::invalid(),
            actors: Vec::new(),
            robot: loaded.robot.clone(),
            path: DrivePath::new(&s.robot.drive),
            drift: OdometryDrift::new(s.robot.odometry, seed::stream(s.seed, "odometry")),
            wheel_contacts: loaded.robot.wheel_contacts(),
            time_s: 0.0,
            world_from_base: Isometry3::identity(),
            estimated_world_from_base: Isometry3::identity(),
            terrain_top_m: terrain.heights_m.iter().copied().fold(f64::MIN, f64::max) + 1.0,
            terrain_span_m: terrain.heights_m.iter().copied().fold(f64::MIN, f64::max)
                - terrain.heights_m.iter().copied().fold(f64::MAX, f64::min)
                + 2.0,
            terrain,
            labels: s.obstacles.iter().enumerate().map(|(k, o)| o.label(k)).collect(),
        };
        for (k, o) in s.obstacles.iter().enumerate() {
            world.insert_obstacle(s, k, o).map_err(scenario_error)?;
        }
        for (
            k,
            Actor::Person {
                waypoints,
                radius_m,
                height_m,
                ..
            },
        ) in s.actors.iter().enumerate()
        {
            let half = (height_m / 2.0 - radius_m).max(0.0);
            let (body, collider) = world.physics.insert(
                RigidBodyBuilder::kinematic_position_based(),
                ColliderBuilder::capsule_z(half as f32, *radius_m as f32).user_data(tag(KIND_ACTOR, k)),
            );
            world.actors.push(ActorTrack {
                body,
                collider,
                waypoints: waypoints.clone(),
                half_height_m: height_m / 2.0,
            });
        }
        world.robot_body = world
            .physics
            .insert_body(RigidBodyBuilder::kinematic_position_based());
        for link in loaded.robot.links() {
            for (link_from_shape, shape) in &link.shapes {
                let base_from_shape = link.base_from_link * link_from_shape;
                let builder = match shape {
                    Shape::Cuboid { half_extents_m: h } => {
                        ColliderBuilder::cuboid(h.x as f32, h.y as f32, h.z as f32)
                    }
                    Shape::Sphere { radius_m } => ColliderBuilder::ball(*radius_m as f32),
                    Shape::Capsule { radius_m, length_m } => {
                        ColliderBuilder::capsule_z((length_m / 2.0) as f32, *radius_m as f32)
                    }
                    Shape::Cylinder { radius_m, length_m } => {
                        // Rapier's cylinder runs along its local y; URDF's along z.
                        ColliderBuilder::cylinder((length_m / 2.0) as f32, *radius_m as f32)
                    }
                };
                let mut pose = to_pose(&base_from_shape);
                if matches!(shape, Shape::Cylinder { .. }) {
                    pose.rotation =
                        (pose.rotation * Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2)).normalize();
                }
                let collider = builder.position(pose).user_data(tag(KIND_ROBOT, 0));
                let body = world.robot_body;
                world.physics.insert_collider(collider, Some(body));
            }
        }
        world.advance_to(0.0);
        Ok(world)
    }

    fn insert_obstacle(
        &mut self,
        s: &Scenario,
        index: usize,
        o: &Obstacle,
    ) -> std::result::Result<(), String> {
        let [cx, cy] = o.center_xy_m();
        let ground = self.ground_z(cx, cy).unwrap_or(0.0);
        let data = tag(KIND_OBSTACLE, index);
        let yaw_pose = |z: f64, yaw_deg: f64| {
            to_pose(&Isometry3::from_parts(
                Translation3::new(cx, cy, z),
                UnitQuaternion::from_euler_angles(0.0, 0.0, yaw_deg.to_radians()),
            ))
        };
        let colliders: Vec<ColliderBuilder> = match o {
            Obstacle::Box {
                size_m,
                yaw_deg,
                base_m,
                ..
            } => {
                // Standing on the ground: extended below it by the footing; the top stays where the file says.
                let footing = if *base_m == 0.0 { OBSTACLE_FOOTING_M } else { 0.0 };
                let (hx, hy, hz) = (size_m[0] / 2.0, size_m[1] / 2.0, (size_m[2] + footing) / 2.0);
                let top = ground + base_m + size_m[2];
                vec![
                    ColliderBuilder::cuboid(hx as f32, hy as f32, hz as f32)
                        .position(yaw_pose(top - hz, *yaw_deg)),
                ]
            }
            Obstacle::Cylinder {
                radius_m,
                height_m,
                base_m,
                ..
            } => {
                // No footing: parry casts rays on cylinders with GJK, and a cylinder reaching below the ground
                // was measured to let grazing rays through its wall near the ground (trees_no_threshold).
                let mut pose = yaw_pose(ground + base_m + height_m / 2.0, 0.0);
                pose.rotation = Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2);
                vec![ColliderBuilder::cylinder((height_m / 2.0) as f32, *radius_m as f32).position(pose)]
            }
            Obstacle::Ramp {
                length_m,
                width_m,
                height_m,
                yaw_deg,
                ..
            } => {
                let (l, w, h) = ((length_m / 2.0) as f32, (width_m / 2.0) as f32, *height_m as f32);
                let f = OBSTACLE_FOOTING_M as f32;
                // The wedge, sealed below the ground by the footing.
                let points = [
                    Vector::new(-l, -w, 0.0),
                    Vector::new(-l, w, 0.0),
                    Vector::new(l, -w, h),
                    Vector::new(l, w, h),
                    Vector::new(-l, -w, -f),
                    Vector::new(-l, w, -f),
                    Vector::new(l, -w, -f),
                    Vector::new(l, w, -f),
                ];
                let hull = ColliderBuilder::convex_hull(&points)
                    .ok_or_else(|| format!("ramp {index} has a degenerate shape"))?;
                vec![hull.position(yaw_pose(ground, *yaw_deg))]
            }
            Obstacle::Bush {
                radius_m,
                height_m,
                num_parts,
                ..
            } => {
                let mut rng = seed::stream(s.seed, &format!("bush/{index}"));
                (0..*num_parts)
                    .map(|_| {
                        let r = radius_m * rng.random_range(0.0f64..1.0).sqrt();
                        let a = rng.random_range(0.0..std::f64::consts::TAU);
                        let hx = radius_m * rng.random_range(0.15..0.35);
                        let hy = radius_m * rng.random_range(0.15..0.35);
                        let hz = height_m * rng.random_range(0.2..0.5);
                        let z = if height_m - hz > hz {
                            rng.random_range(hz..height_m - hz)
                        } else {
                            height_m / 2.0
                        };
                        let yaw = rng.random_range(0.0..360.0);
                        let pose = to_pose(&Isometry3::from_parts(
                            Translation3::new(cx + r * a.cos(), cy + r * a.sin(), ground + z),
                            UnitQuaternion::from_euler_angles(0.0, 0.0, f64::to_radians(yaw)),
                        ));
                        ColliderBuilder::cuboid(hx as f32, hy as f32, hz as f32).position(pose)
                    })
                    .collect()
            }
            Obstacle::Overhang {
                size_m,
                clearance_m,
                yaw_deg,
                ..
            } => {
                let h = size_m.map(|v| v / 2.0);
                vec![
                    ColliderBuilder::cuboid(h[0] as f32, h[1] as f32, h[2] as f32)
                        .position(yaw_pose(ground + clearance_m + h[2], *yaw_deg)),
                ]
            }
        };
        for c in colliders {
            self.physics.insert(RigidBodyBuilder::fixed(), c.user_data(data));
        }
        Ok(())
    }

    /// Simulated time, seconds.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// Moves the clock to `t_s` (not before the current time): the robot along its drive, draped on the
    /// terrain, its odometry drift, and the actors.
    pub fn advance_to(&mut self, t_s: f64) {
        let t_s = t_s.max(self.time_s);
        self.time_s = t_s;
        let planar = self.path.pose_at(t_s);
        self.world_from_base = self.drape(planar.x_m, planar.y_m, planar.yaw_rad);
        self.drift.advance(planar.distance_m);
        self.estimated_world_from_base = self.drift.apply(&self.world_from_base);
        if let Some(body) = self.physics.bodies.get_mut(self.robot_body) {
            body.set_position(to_pose(&self.world_from_base), true);
        }
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
        self.physics.detect_collisions(&(), &());
    }

    /// The base pose at `(x, y, yaw)` resting on the terrain: height from the wheel contacts, pitch from the
    /// front and rear pairs, roll from the left and right pairs.
    fn drape(&self, x: f64, y: f64, yaw: f64) -> Isometry3<f64> {
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
        let mut filter = QueryFilter::default().exclude_rigid_body(self.robot_body);
        if actors == Actors::Excluded {
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
        // Start just above the terrain: Rapier works in f32, and a start far above would cost precision.
        let from = self.terrain_top_m;
        let ray = Ray::new(
            point_to_vector(&Point3::new(x, y, from)),
            Vector::new(0.0, 0.0, -1.0),
        );
        let only_terrain = |_: ColliderHandle, c: &Collider| kind_of(c) == KIND_TERRAIN;
        let filter = QueryFilter::default().predicate(&only_terrain);
        let (_, toi) = self
            .physics
            .cast_ray(&ray, self.terrain_span_m as f32, true, filter)?;
        Some(from - f64::from(toi))
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

/// Rapier's heightfield for a grid: its heights are local y and its rows run along local z, so it is turned
/// +90 degrees about x (local z becomes world -y: row 0 is the max-y edge) and centred on the grid.
fn heightfield_collider(grid: &HeightGrid) -> ColliderBuilder {
    let (nx, ny) = (grid.num_x, grid.num_y);
    let mut data = Vec::with_capacity(nx * ny);
    // Column-major: column = x index, row = (ny - 1 - y index).
    for i in 0..nx {
        for row in 0..ny {
            let j = ny - 1 - row;
            data.push(grid.heights_m[j * nx + i] as f32);
        }
    }
    let extent_x = (nx - 1) as f64 * grid.cell_m;
    let extent_y = (ny - 1) as f64 * grid.cell_m;
    let center = Point3::new(
        grid.origin_xy_m[0] + extent_x / 2.0,
        grid.origin_xy_m[1] + extent_y / 2.0,
        0.0,
    );
    let pose = Isometry3::from_parts(
        Translation3::from(center.coords),
        UnitQuaternion::from_euler_angles(std::f64::consts::FRAC_PI_2, 0.0, 0.0),
    );
    ColliderBuilder::heightfield(
        Array2::new(ny, nx, data),
        Vector::new(extent_x as f32, 1.0, extent_y as f32),
    )
    .position(to_pose(&pose))
}
