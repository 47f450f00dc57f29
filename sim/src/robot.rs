//! The robot, from its URDF (read with urdf-rs): links, their fixed poses in the base frame, their collision
//! shapes, and the derived facts the testbed needs (height, wheel contact points).
//!
//! Joints are taken at position zero: wheels spin about their own axis, which changes no collision shape, and
//! every other joint of the robot is fixed.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use crate::error::{Result, SimError};

/// A collision shape of a link, in the link's frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// A box with these half extents.
    Cuboid {
        /// Half extents, metres.
        half_extents_m: Vector3<f64>,
    },
    /// A cylinder along the shape frame's z axis.
    Cylinder {
        /// Radius, metres.
        radius_m: f64,
        /// Length, metres.
        length_m: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius, metres.
        radius_m: f64,
    },
    /// A capsule along z (`length_m` between the centres of its caps).
    Capsule {
        /// Radius, metres.
        radius_m: f64,
        /// Length of the cylindrical part, metres.
        length_m: f64,
    },
}

impl Shape {
    /// The shape's x-y bounding box placed at `pose`: `[min_x, max_x, min_y, max_y]`, metres (exact for
    /// boxes, spheres, cylinders and capsules at any angle).
    fn plan_extent(&self, pose: &Isometry3<f64>) -> [f64; 4] {
        let c = pose.translation.vector;
        let (hx, hy) = match self {
            Self::Cuboid { half_extents_m: h } => {
                let r = pose.rotation.to_rotation_matrix();
                let m = r.matrix();
                (
                    m[(0, 0)].abs() * h.x + m[(0, 1)].abs() * h.y + m[(0, 2)].abs() * h.z,
                    m[(1, 0)].abs() * h.x + m[(1, 1)].abs() * h.y + m[(1, 2)].abs() * h.z,
                )
            }
            Self::Sphere { radius_m } => (*radius_m, *radius_m),
            Self::Cylinder { radius_m, length_m } | Self::Capsule { radius_m, length_m } => {
                // Along a world axis e: the axis ends at |a.e| h/2, and the rim (cylinder) or the cap
                // (capsule) adds r sqrt(1 - (a.e)^2) or r.
                let axis = pose.rotation * Vector3::z();
                let half = length_m / 2.0;
                let side = |a: f64| match self {
                    Self::Capsule { .. } => *radius_m,
                    _ => radius_m * (1.0 - a * a).max(0.0).sqrt(),
                };
                (
                    axis.x.abs() * half + side(axis.x),
                    axis.y.abs() * half + side(axis.y),
                )
            }
        };
        [c.x - hx, c.x + hx, c.y - hy, c.y + hy]
    }

    /// The highest z of the shape placed at `pose`.
    fn top_z(&self, pose: &Isometry3<f64>) -> f64 {
        let corners: Vec<Point3<f64>> = match self {
            Self::Cuboid { half_extents_m: h } => (0..8)
                .map(|k| {
                    Point3::new(
                        if k & 1 == 0 { -h.x } else { h.x },
                        if k & 2 == 0 { -h.y } else { h.y },
                        if k & 4 == 0 { -h.z } else { h.z },
                    )
                })
                .collect(),
            Self::Sphere { radius_m } => return pose.translation.z + radius_m,
            Self::Cylinder { radius_m, length_m } | Self::Capsule { radius_m, length_m } => {
                // The two end-cap centres, then the cap rim's highest point around the axis.
                let axis = pose.rotation * Vector3::z();
                let half = length_m / 2.0;
                let rim = radius_m * (1.0 - axis.z * axis.z).max(0.0).sqrt();
                let extra = if matches!(self, Self::Capsule { .. }) {
                    *radius_m
                } else {
                    rim
                };
                let ends = [
                    pose * Point3::new(0.0, 0.0, half),
                    pose * Point3::new(0.0, 0.0, -half),
                ];
                return ends.iter().map(|p| p.z).fold(f64::MIN, f64::max) + extra;
            }
        };
        corners.iter().map(|c| (pose * c).z).fold(f64::MIN, f64::max)
    }
}

/// One link: its pose in the base frame and its collision shapes.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// The link's name.
    pub name: String,
    /// `base_from_link`.
    pub base_from_link: Isometry3<f64>,
    /// Collision shapes with `link_from_shape`.
    pub shapes: Vec<(Isometry3<f64>, Shape)>,
}

/// The robot as the simulation uses it.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotModel {
    /// The URDF file.
    pub path: PathBuf,
    /// The robot's name in the URDF.
    pub name: String,
    /// The base link's name.
    pub base_link: String,
    links: BTreeMap<String, Link>,
}

/// URDF rpy (fixed axes x, then y, then z) as a rotation.
pub fn rotation_from_rpy(rpy: [f64; 3]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2])
}

fn pose_of(p: &urdf_rs::Pose) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(p.xyz[0], p.xyz[1], p.xyz[2]),
        rotation_from_rpy(p.rpy.0),
    )
}

impl RobotModel {
    /// Loads `path` and resolves every link's pose relative to `base_link`.
    ///
    /// # Errors
    /// [`SimError::Io`] for a missing file, [`SimError::Urdf`] for malformed XML, a missing base link, a link
    /// not connected to the base, a mesh collision (not supported: use primitives), or a non-positive size.
    pub fn load(path: &Path, base_link: &str) -> Result<Self> {
        let text = crate::error::read_text(path)?;
        Self::from_urdf_text(path, &text, base_link)
    }

    /// The robot of a URDF document already read (`path` names it in errors).
    ///
    /// # Errors
    /// As [`RobotModel::load`], but for reading the file.
    pub fn from_urdf_text(path: &Path, text: &str, base_link: &str) -> Result<Self> {
        let urdf = urdf_rs::read_from_string(text).map_err(|e| SimError::Urdf {
            path: path.to_path_buf(),
            message: format!("not a valid URDF: {e}"),
        })?;
        Self::from_urdf(path, &urdf, base_link)
    }

    fn from_urdf(path: &Path, urdf: &urdf_rs::Robot, base_link: &str) -> Result<Self> {
        let err = |message: String| SimError::Urdf {
            path: path.to_path_buf(),
            message,
        };
        let by_name: BTreeMap<&str, &urdf_rs::Link> =
            urdf.links.iter().map(|l| (l.name.as_str(), l)).collect();
        if !by_name.contains_key(base_link) {
            let names: Vec<&str> = by_name.keys().copied().collect();
            return Err(err(format!(
                "has no link named `{base_link}` (the base link); its links are: {}",
                names.join(", ")
            )));
        }
        // Walk the joint tree from the base.
        let mut poses: BTreeMap<String, Isometry3<f64>> = BTreeMap::new();
        poses.insert(base_link.to_string(), Isometry3::identity());
        let mut frontier = vec![base_link.to_string()];
        while let Some(parent) = frontier.pop() {
            let base_from_parent = poses[&parent];
            for j in urdf.joints.iter().filter(|j| j.parent.link == parent) {
                if !by_name.contains_key(j.child.link.as_str()) {
                    return Err(err(format!(
                        "joint `{}` names a child link `{}` that does not exist",
                        j.name, j.child.link
                    )));
                }
                if poses
                    .insert(j.child.link.clone(), base_from_parent * pose_of(&j.origin))
                    .is_some()
                {
                    return Err(err(format!(
                        "link `{}` has more than one parent joint",
                        j.child.link
                    )));
                }
                frontier.push(j.child.link.clone());
            }
        }
        let mut links = BTreeMap::new();
        for l in &urdf.links {
            let Some(base_from_link) = poses.get(&l.name) else {
                return Err(err(format!(
                    "link `{}` is not connected to the base link `{base_link}` by joints",
                    l.name
                )));
            };
            let mut shapes = Vec::new();
            for c in &l.collision {
                let shape = match &c.geometry {
                    urdf_rs::Geometry::Box { size } => Shape::Cuboid {
                        half_extents_m: Vector3::new(size[0], size[1], size[2]) / 2.0,
                    },
                    urdf_rs::Geometry::Cylinder { radius, length } => Shape::Cylinder {
                        radius_m: *radius,
                        length_m: *length,
                    },
                    urdf_rs::Geometry::Sphere { radius } => Shape::Sphere { radius_m: *radius },
                    urdf_rs::Geometry::Capsule { radius, length } => Shape::Capsule {
                        radius_m: *radius,
                        length_m: *length,
                    },
                    urdf_rs::Geometry::Mesh { filename, .. } => {
                        return Err(err(format!(
                            "link `{}` has a mesh collision ({filename}); only box, cylinder, sphere and capsule are supported",
                            l.name
                        )));
                    }
                };
                let sizes_ok = match &shape {
                    Shape::Cuboid { half_extents_m } => {
                        half_extents_m.iter().all(|v| *v > 0.0 && v.is_finite())
                    }
                    Shape::Cylinder { radius_m, length_m } | Shape::Capsule { radius_m, length_m } => {
                        *radius_m > 0.0 && *length_m >= 0.0 && radius_m.is_finite() && length_m.is_finite()
                    }
                    Shape::Sphere { radius_m } => *radius_m > 0.0 && radius_m.is_finite(),
                };
                if !sizes_ok {
                    return Err(err(format!(
                        "link `{}` has a collision shape with a non-positive size",
                        l.name
                    )));
                }
                shapes.push((pose_of(&c.origin), shape));
            }
            links.insert(
                l.name.clone(),
                Link {
                    name: l.name.clone(),
                    base_from_link: *base_from_link,
                    shapes,
                },
            );
        }
        Ok(Self {
            path: path.to_path_buf(),
            name: urdf.name.clone(),
            base_link: base_link.to_string(),
            links,
        })
    }

    /// The link called `name`.
    pub fn link(&self, name: &str) -> Option<&Link> {
        self.links.get(name)
    }

    /// Every link's name, sorted.
    pub fn link_names(&self) -> Vec<&str> {
        self.links.keys().map(String::as_str).collect()
    }

    /// Every link, sorted by name.
    pub fn links(&self) -> impl Iterator<Item = &Link> {
        self.links.values()
    }

    /// `base_from_link` of a link.
    pub fn base_from_link(&self, name: &str) -> Option<Isometry3<f64>> {
        self.link(name).map(|l| l.base_from_link)
    }

    /// The robot's height: the highest point of its collision geometry above the base frame's origin (the
    /// ground, for a base link on the ground).
    pub fn height_m(&self) -> f64 {
        self.links()
            .flat_map(|l| {
                l.shapes
                    .iter()
                    .map(move |(pose, s)| s.top_z(&(l.base_from_link * pose)))
            })
            .fold(0.0, f64::max)
    }

    /// The space its body fills over its footprint, above its wheels' contact points: from the lowest point of
    /// its collision geometry other than its wheels (the chassis' ground clearance) to its highest. `None` for
    /// a robot without wheels or without a body besides them.
    pub fn body_span(&self) -> Option<oeg::BodySpan> {
        let contacts = self.wheel_contacts();
        if contacts.is_empty() {
            return None;
        }
        let ground = contacts.iter().map(|c| c.z).sum::<f64>() / contacts.len() as f64;
        // Every shape is symmetric about its centre: its lowest point lies as far below it as its highest above.
        let underside = self
            .links()
            .flat_map(|l| l.shapes.iter().map(move |(pose, s)| (l.base_from_link * pose, s)))
            .filter(|(pose, s)| !is_wheel(pose, s))
            .map(|(pose, s)| 2.0 * pose.translation.z - s.top_z(&pose))
            .reduce(f64::min)?;
        Some(oeg::BodySpan {
            underside_m: (underside - ground).max(0.0) as f32,
            height_m: (self.height_m() - ground) as f32,
        })
    }

    /// The footprint: the rectangle in the base frame that bounds every collision shape, wheels included
    /// (a zero rectangle for a robot without collision shapes).
    pub fn footprint(&self) -> oeg::Footprint {
        let extents: Vec<[f64; 4]> = self
            .links()
            .flat_map(|l| {
                l.shapes
                    .iter()
                    .map(move |(pose, s)| s.plan_extent(&(l.base_from_link * pose)))
            })
            .collect();
        if extents.is_empty() {
            return oeg::Footprint {
                min_x_m: 0.0,
                max_x_m: 0.0,
                min_y_m: 0.0,
                max_y_m: 0.0,
            };
        }
        let low = |k: usize| extents.iter().map(|e| e[k]).fold(f64::INFINITY, f64::min);
        let high = |k: usize| extents.iter().map(|e| e[k]).fold(f64::NEG_INFINITY, f64::max);
        oeg::Footprint {
            min_x_m: low(0),
            max_x_m: high(1),
            min_y_m: low(2),
            max_y_m: high(3),
        }
    }

    /// The wheels' ground contact points in the base frame: the lowest point of every cylinder whose axis is
    /// horizontal (sorted front-left, front-right, rear-left, rear-right by x then y).
    pub fn wheel_contacts(&self) -> Vec<Point3<f64>> {
        let mut contacts: Vec<Point3<f64>> = self
            .links()
            .flat_map(|l| l.shapes.iter().map(move |(pose, s)| (l.base_from_link * pose, s)))
            .filter_map(|(pose, s)| match s {
                Shape::Cylinder { radius_m, .. } if is_wheel(&pose, s) => Some(Point3::new(
                    pose.translation.x,
                    pose.translation.y,
                    pose.translation.z - radius_m,
                )),
                _ => None,
            })
            .collect();
        contacts.sort_by(|a, b| b.x.total_cmp(&a.x).then(b.y.total_cmp(&a.y)));
        contacts
    }
}

/// Whether a collision shape at `pose` (base frame) is a wheel: a cylinder whose axis is horizontal.
fn is_wheel(pose: &Isometry3<f64>, shape: &Shape) -> bool {
    matches!(shape, Shape::Cylinder { .. }) && (pose.rotation * Vector3::z()).z.abs() < 1e-6
}

/// Where a robot stands at `world_from_base`: its wheels' contact points (`wheel_contacts`, base frame) in the
/// world, and its footprint there, with a contact's height error [`oeg::DEFAULT_STANCE_SIGMA_M`]. `None` for a
/// robot without wheels or with an empty footprint.
pub fn stance_at(
    wheel_contacts: &[Point3<f64>],
    footprint: oeg::Footprint,
    world_from_base: &Isometry3<f64>,
) -> Option<oeg::Stance> {
    if wheel_contacts.is_empty() || footprint.length_m() <= 0.0 || footprint.width_m() <= 0.0 {
        return None;
    }
    let (_, _, yaw_rad) = world_from_base.rotation.euler_angles();
    Some(oeg::Stance {
        contacts: wheel_contacts.iter().map(|c| world_from_base * c).collect(),
        footprint,
        pose: oeg::Pose2 {
            x_m: world_from_base.translation.x,
            y_m: world_from_base.translation.y,
            yaw_rad,
        },
        sigma_m: oeg::DEFAULT_STANCE_SIGMA_M,
    })
}

#[cfg(test)]
#[allow(clippy::disallowed_methods, reason = "tests write their inputs directly")]
mod tests;
