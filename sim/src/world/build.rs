//! Building the world from a loaded scenario: the terrain as a height field, the obstacles, the actors and
//! the robot.

use crate::convert::to_pose;
use crate::drive::{DrivePath, OdometryDrift};
use crate::error::{Result, SimError};
use crate::physics::PhysicsDrive;
use crate::robot::Shape;
use crate::scenario::{Actor, LoadedScenario, Obstacle, Scenario};
use crate::seed;
use crate::terrain::{self, HeightGrid};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};
use rand::RngExt;
use rapier3d::math::{Rotation, Vector};
use rapier3d::parry::utils::Array2;
use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle};

use super::clock::{Motion, move_actors};
use super::{
    ActorTrack, KIND_ACTOR, KIND_OBSTACLE, KIND_ROBOT, KIND_TERRAIN, OBSTACLE_FOOTING_M, World, tag,
};

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

        let terrain = terrain::build(s, &loaded.source).map_err(|e| scenario_error(e.to_string()))?;
        physics.insert(
            RigidBodyBuilder::fixed(),
            heightfield_collider(&terrain).user_data(tag(KIND_TERRAIN, 0)),
        );
        physics.detect_collisions(&(), &());

        let mut world = Self {
            physics,
            robot_body: RigidBodyHandle::invalid(),
            wheels: None,
            actors: Vec::new(),
            robot: loaded.robot.clone(),
            path: DrivePath::new(&s.robot.drive),
            command: None,
            planar: crate::drive::PlanarPose {
                x_m: 0.0,
                y_m: 0.0,
                yaw_rad: 0.0,
                distance_m: 0.0,
            },
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
        // Each actor where it is at the start, and those not yet in the scene out of it, before the robot settles
        // among them.
        let ground = world.ground_probe();
        move_actors(&mut world.physics, &world.actors, ground, 0.0, Motion::Place);
        match &loaded.wheeled {
            Some(model) => {
                let start = world.path.pose_at(0.0);
                let at = world.drape(start.x_m, start.y_m, start.yaw_rad);
                let d = &s.robot.drive;
                world.wheels = Some(PhysicsDrive::insert(
                    &mut world.physics,
                    model,
                    &at,
                    tag(KIND_ROBOT, 0),
                    &d.waypoints_xy_m,
                    d.speed_m_s,
                ));
            }
            None => world.insert_kinematic_robot(loaded),
        }
        world.advance_to(0.0);
        Ok(world)
    }

    /// The robot as one kinematic body carrying every collision shape of its URDF, placed at each tick.
    fn insert_kinematic_robot(&mut self, loaded: &LoadedScenario) {
        self.robot_body = self
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
                let body = self.robot_body;
                self.physics.insert_collider(collider, Some(body));
            }
        }
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
            } => vec![
                ramp_collider(index, [*length_m, *width_m, *height_m])?.position(yaw_pose(ground, *yaw_deg)),
            ],
            Obstacle::Bush {
                radius_m,
                height_m,
                num_parts,
                ..
            } => bush_colliders(s.seed, index, [cx, cy, ground], *radius_m, *height_m, *num_parts),
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
}

/// A ramp's wedge (`[length, width, height]` in metres), rising along its local +x, sealed below the ground
/// by the footing.
fn ramp_collider(
    index: usize,
    [length_m, width_m, height_m]: [f64; 3],
) -> std::result::Result<ColliderBuilder, String> {
    let (l, w, h) = ((length_m / 2.0) as f32, (width_m / 2.0) as f32, height_m as f32);
    let f = OBSTACLE_FOOTING_M as f32;
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
    ColliderBuilder::convex_hull(&points).ok_or_else(|| format!("ramp {index} has a degenerate shape"))
}

/// A bush: `num_parts` leafy boxes at random places, sizes, heights and yaws within its radius and height,
/// drawn from the stream `bush/<index>` of the scenario's seed, standing on the ground at `[x, y, ground]`.
fn bush_colliders(
    seed: u64,
    index: usize,
    [cx, cy, ground]: [f64; 3],
    radius_m: f64,
    height_m: f64,
    num_parts: u32,
) -> Vec<ColliderBuilder> {
    let mut rng = seed::stream(seed, &format!("bush/{index}"));
    (0..num_parts)
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
