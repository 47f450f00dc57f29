//! The wheeled robot as Rapier bodies and joints: dimforge's `rapier3d-urdf` reads the URDF's links, masses,
//! inertias, collision shapes and joints; this module checks that a drive on the wheels can use them, finds
//! the wheels, and resolves the motors' limits that a URDF leaves out.

use std::path::Path;

use nalgebra::Vector3;
use rapier3d::prelude::{ColliderBuilder, RigidBodyBuilder};
use rapier3d_urdf::{UrdfLoaderOptions, UrdfRobot, urdf_rs};

use crate::error::{Result, SimError};
use crate::robot::{RobotModel, Shape};
use crate::scenario::{PhysicsSettings, RobotSettings};

/// Standard gravity, m/s².
pub(crate) const GRAVITY_M_S2: f64 = 9.81;

/// One driven wheel.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct WheelSpec {
    /// The joint's index in the loaded robot's joints.
    pub(crate) joint: usize,
    /// The wheel link's index in the loaded robot's links.
    pub(crate) link: usize,
    /// The joint's name, for messages.
    pub(crate) name: String,
    /// +1 on the left (positive y in the base frame), -1 on the right.
    pub(crate) side: f64,
    /// +1 when the joint turns about the base's +y, -1 about its -y: a wheel rolling forward at `w` rad/s
    /// turns at `spin * w` about its joint axis.
    pub(crate) spin: f64,
    /// The wheel centre in the base frame, metres.
    pub(crate) center_in_base: Vector3<f64>,
}

/// The robot, ready to be put into a physics world: its Rapier parts, its wheels and its drive's limits.
#[derive(Debug, Clone)]
pub struct WheeledModel {
    pub(crate) parts: UrdfRobot,
    /// The index of the base link among `parts.links`.
    pub(crate) base: usize,
    pub(crate) wheels: Vec<WheelSpec>,
    /// Wheel radius, metres.
    pub(crate) radius_m: f64,
    /// Distance between the left and the right wheels' mid-planes, metres.
    pub(crate) track_m: f64,
    /// Total mass, kg.
    pub(crate) mass_kg: f64,
    /// Each wheel motor's torque limit, N m.
    pub(crate) torque_nm: f64,
    /// Each wheel's speed limit, rad/s.
    pub(crate) max_wheel_speed_rad_s: f64,
    /// Roll past which the robot falls on its side: the static stability angle over the wheels' contact
    /// line, from the centre of mass (radians).
    pub(crate) roll_limit_rad: f64,
    /// Pitch past which it falls over its front or rear axle, radians.
    pub(crate) pitch_limit_rad: f64,
    pub(crate) settings: PhysicsSettings,
    /// Each of `parts.links`' URDF name.
    pub(crate) link_names: Vec<String>,
    pub(crate) max_speed_m_s: f64,
    pub(crate) max_turn_rate_rad_s: f64,
}

impl WheeledModel {
    /// The robot of the URDF document `text` (read from `path`, which names it in errors), with the base link
    /// and limits of `settings`; `model` is the same document as the rest of the simulation reads it.
    ///
    /// # Errors
    /// [`SimError::Urdf`] naming the element when a link that moves has no mass or inertia, the wheel joints
    /// are missing, not turning joints, not turning about the base's y axis, or without a cylinder, or when
    /// the robot has wheels on one side only.
    pub fn from_urdf(path: &Path, text: &str, settings: &RobotSettings, model: &RobotModel) -> Result<Self> {
        let err = |message: String| SimError::Urdf {
            path: path.to_path_buf(),
            message,
        };
        let physics = &settings.physics;
        let options = UrdfLoaderOptions {
            // The base link is a frame without a body: squeezing it away would fix its child to the world.
            squeeze_empty_fixed_links: false,
            rigid_body_blueprint: RigidBodyBuilder::dynamic().can_sleep(false),
            collider_blueprint: ColliderBuilder::default().density(0.0),
            ..UrdfLoaderOptions::default()
        };
        let (parts, urdf) = UrdfRobot::from_str(text, options, path.parent().unwrap_or(Path::new(".")))
            .map_err(|e| err(format!("not a URDF a physics drive can load: {e}")))?;
        let link_name = |k: usize| urdf.links[parts.links[k].urdf_link_index].name.as_str();
        let base = (0..parts.links.len())
            .find(|k| link_name(*k) == settings.base_link)
            .ok_or_else(|| {
                err(format!(
                    "has no link named `{}` (the base link)",
                    settings.base_link
                ))
            })?;

        let mass_kg = check_masses(&parts, &urdf).map_err(err)?;

        let wheels = find_wheels(&parts, &urdf, physics, model).map_err(err)?;
        let radius_m = wheel_radius(&wheels, &parts, &urdf, model).map_err(err)?;
        let left = wheels.iter().filter(|w| w.side > 0.0).map(|w| w.center_in_base.y);
        let right = wheels.iter().filter(|w| w.side < 0.0).map(|w| w.center_in_base.y);
        let mean = |v: Vec<f64>| v.iter().sum::<f64>() / v.len().max(1) as f64;
        let track_m = mean(left.collect()) - mean(right.collect());

        let (roll_limit_rad, pitch_limit_rad) = tip_limits(&urdf, model, &wheels, mass_kg, track_m);
        let limit = |f: fn(&urdf_rs::JointLimit) -> f64| {
            let v: Vec<f64> = wheels
                .iter()
                .map(|w| f(&urdf.joints[parts.joints[w.joint].urdf_joint_index].limit))
                .collect();
            v.iter()
                .all(|x| *x > 0.0 && x.is_finite())
                .then(|| v.iter().copied().fold(f64::MAX, f64::min))
        };
        let torque_nm = physics
            .wheel_torque_nm
            .or_else(|| limit(|l| l.effort))
            .unwrap_or_else(|| {
                default_torque_nm(&wheels, radius_m, mass_kg, f64::from(settings.max_grade), physics)
            });
        let max_wheel_speed_rad_s = physics
            .max_wheel_speed_rad_s
            .or_else(|| limit(|l| l.velocity))
            .unwrap_or(settings.max_speed_m_s / radius_m);
        let link_names = (0..parts.links.len()).map(|k| link_name(k).to_string()).collect();
        Ok(Self {
            link_names,
            parts,
            base,
            wheels,
            radius_m,
            track_m,
            mass_kg,
            torque_nm,
            max_wheel_speed_rad_s,
            roll_limit_rad,
            pitch_limit_rad,
            settings: physics.clone(),
            max_speed_m_s: settings.max_speed_m_s,
            max_turn_rate_rad_s: settings.max_turn_rate_deg_s.to_radians(),
        })
    }

    /// The `[robot.physics]` settings it was built with.
    pub fn settings(&self) -> &PhysicsSettings {
        &self.settings
    }

    /// Each wheel motor's torque limit, N m.
    pub fn wheel_torque_nm(&self) -> f64 {
        self.torque_nm
    }

    /// Wheel radius, metres.
    pub fn wheel_radius_m(&self) -> f64 {
        self.radius_m
    }

    /// Total mass, kg.
    pub fn mass_kg(&self) -> f64 {
        self.mass_kg
    }

    /// The static stability angles, roll and pitch, degrees: past them the robot tips over.
    pub fn tip_limits_deg(&self) -> (f64, f64) {
        (
            self.roll_limit_rad.to_degrees(),
            self.pitch_limit_rad.to_degrees(),
        )
    }
}

/// The static stability angles, roll and pitch (radians): the centre of mass at rest, from each link's
/// `<inertial>`, over the wheels' contact lines.
fn tip_limits(
    urdf: &urdf_rs::Robot,
    model: &RobotModel,
    wheels: &[WheelSpec],
    mass_kg: f64,
    track_m: f64,
) -> (f64, f64) {
    // The centre of mass at rest, in the base frame.
    let mut com = Vector3::zeros();
    for l in &urdf.links {
        let Some(base_from_link) = model.base_from_link(&l.name) else {
            continue;
        };
        let o = &l.inertial.origin.xyz;
        com += (base_from_link * nalgebra::Point3::new(o[0], o[1], o[2])).coords * l.inertial.mass.value;
    }
    com /= mass_kg;
    let height = (com.z).max(1e-3);
    let (front, rear) = wheels.iter().fold((f64::MIN, f64::MAX), |(f, r), w| {
        (f.max(w.center_in_base.x), r.min(w.center_in_base.x))
    });
    let roll_limit_rad = (track_m / 2.0 - com.y.abs()).max(0.0).atan2(height);
    let pitch_limit_rad = (front - com.x).min(com.x - rear).max(0.0).atan2(height);
    (roll_limit_rad, pitch_limit_rad)
}

/// The wheel torque a URDF without `effort` limits gets, N m: what the data sheet's two ratings ask of the
/// motors, whichever is more. The robot climbs its `max_grade`: `m g r sin(atan(grade)) / n` on `n` wheels. It
/// turns on the spot: its wheels at distances `d_i` from the centre, `y_i` from the centre line, each loaded
/// with `m g / n`, slide sideways against friction `mu`, a moment of `mu m g / n * sum(d_i)` that the wheels'
/// pushes must beat, `tau / r * sum(|y_i|)`; [`TURN_HEADROOM`] times that, so the robot turns at a rate and
/// does not just creep round.
fn default_torque_nm(
    wheels: &[WheelSpec],
    radius_m: f64,
    mass_kg: f64,
    grade: f64,
    physics: &PhysicsSettings,
) -> f64 {
    let n = wheels.len() as f64;
    let load = mass_kg * GRAVITY_M_S2 / n;
    let climb = load * radius_m * grade.atan().sin();
    let reach: f64 = wheels
        .iter()
        .map(|w| w.center_in_base.x.hypot(w.center_in_base.y))
        .sum();
    let lever: f64 = wheels.iter().map(|w| w.center_in_base.y.abs()).sum();
    let turn = TURN_HEADROOM * radius_m * physics.wheel_friction * load * reach / lever;
    climb.max(turn)
}

/// How far the default wheel torque exceeds the least that turns the robot on the spot.
pub(crate) const TURN_HEADROOM: f64 = 1.5;

/// The robot's total mass, kg, once every link's mass is a number of kilograms and every link that moves
/// against its parent carries its own mass and inertia.
fn check_masses(parts: &UrdfRobot, urdf: &urdf_rs::Robot) -> std::result::Result<f64, String> {
    if let Some(l) = urdf
        .links
        .iter()
        .find(|l| !(l.inertial.mass.value.is_finite() && l.inertial.mass.value >= 0.0))
    {
        return Err(format!(
            "link `{}` has a mass of {} kg: a mass is a number of kilograms, 0 or more",
            l.name, l.inertial.mass.value
        ));
    }
    for j in &parts.joints {
        let joint = &urdf.joints[j.urdf_joint_index];
        if joint.joint_type == urdf_rs::JointType::Fixed {
            continue;
        }
        let link = &urdf.links[parts.links[j.link2].urdf_link_index];
        check_inertial(
            link,
            &format!("joined by the {:?} joint `{}`", joint.joint_type, joint.name),
        )?;
    }
    let mass_kg: f64 = urdf.links.iter().map(|l| l.inertial.mass.value).sum();
    if !(mass_kg.is_finite() && mass_kg > 0.0) {
        return Err(
            "has no mass: a physics drive needs `<inertial>` with a positive `<mass>` on its body and wheels"
                .into(),
        );
    }
    Ok(mass_kg)
}

/// A link's `<inertial>`: a positive, finite mass and positive principal moments.
fn check_inertial(link: &urdf_rs::Link, role: &str) -> std::result::Result<(), String> {
    let i = &link.inertial;
    if !(i.mass.value.is_finite() && i.mass.value > 0.0) {
        return Err(format!(
            "link `{}` ({role}) has no mass: a physics drive needs its `<inertial>` with a positive `<mass>`",
            link.name
        ));
    }
    let moments = [i.inertia.ixx, i.inertia.iyy, i.inertia.izz];
    if !moments.iter().all(|m| m.is_finite() && *m > 0.0) {
        return Err(format!(
            "link `{}` ({role}) has no inertia: a physics drive needs its `<inertia>` with positive ixx, iyy \
             and izz, got {moments:?}",
            link.name
        ));
    }
    Ok(())
}

/// The wheel joints: those `physics.wheel_joints` names, or every continuous joint; each a turning joint about
/// the base's y axis, with wheels on both sides.
fn find_wheels(
    parts: &UrdfRobot,
    urdf: &urdf_rs::Robot,
    physics: &PhysicsSettings,
    model: &RobotModel,
) -> std::result::Result<Vec<WheelSpec>, String> {
    let joint_of = |k: usize| &urdf.joints[parts.joints[k].urdf_joint_index];
    let chosen: Vec<usize> =
        match &physics.wheel_joints {
            Some(names) => {
                names
                    .iter()
                    .map(|n| {
                        (0..parts.joints.len()).find(|k| joint_of(*k).name == *n).ok_or_else(|| {
                    format!("`[robot.physics] wheel_joints` names `{n}`, which is not a joint of the URDF")
                })
                    })
                    .collect::<std::result::Result<_, _>>()?
            }
            None => (0..parts.joints.len())
                .filter(|k| joint_of(*k).joint_type == urdf_rs::JointType::Continuous)
                .collect(),
        };
    let mut wheels = Vec::with_capacity(chosen.len());
    for k in chosen {
        let joint = joint_of(k);
        if !matches!(
            joint.joint_type,
            urdf_rs::JointType::Continuous | urdf_rs::JointType::Revolute
        ) {
            return Err(format!(
                "joint `{}` is a {:?} joint: a wheel turns on a `continuous` or `revolute` joint",
                joint.name, joint.joint_type
            ));
        }
        let link = parts.joints[k].link2;
        let child = &urdf.links[parts.links[link].urdf_link_index].name;
        let parent_pose = model.base_from_link(&joint.parent.link).unwrap_or_default();
        let base_from_child = model.base_from_link(child).ok_or_else(|| {
            format!(
                "joint `{}` moves link `{child}`, which is not connected to the base",
                joint.name
            )
        })?;
        let a = joint.axis.xyz.0;
        let axis = parent_pose.rotation
            * crate::robot::rotation_from_rpy(joint.origin.rpy.0)
            * Vector3::new(a[0], a[1], a[2]);
        let axis = axis.try_normalize(1e-9).unwrap_or_else(Vector3::zeros);
        if axis.y.abs() < 1.0 - 1e-3 {
            return Err(format!(
                "joint `{}` turns about {:?} in the base frame: a skid-steer wheel turns about the base's y axis",
                joint.name,
                [axis.x, axis.y, axis.z]
            ));
        }
        let center = base_from_child.translation.vector;
        if center.y.abs() < 1e-6 {
            return Err(format!(
                "wheel joint `{}` lies on the base's centre line (y = 0): a skid-steer wheel is on the left or the right",
                joint.name
            ));
        }
        wheels.push(WheelSpec {
            joint: k,
            link,
            name: joint.name.clone(),
            side: center.y.signum(),
            spin: axis.y.signum(),
            center_in_base: center,
        });
    }
    let sides = (
        wheels.iter().any(|w| w.side > 0.0),
        wheels.iter().any(|w| w.side < 0.0),
    );
    if sides != (true, true) {
        return Err(format!(
            "has {} wheel joints, not on both sides: a skid-steer drive needs wheels on the left and the right \
             (`continuous` joints, or `[robot.physics] wheel_joints`)",
            wheels.len()
        ));
    }
    Ok(wheels)
}

/// The wheels' common radius: each wheel link's cylinder (or sphere), all the same within a millimetre.
fn wheel_radius(
    wheels: &[WheelSpec],
    parts: &UrdfRobot,
    urdf: &urdf_rs::Robot,
    model: &RobotModel,
) -> std::result::Result<f64, String> {
    let mut radii = Vec::with_capacity(wheels.len());
    for w in wheels {
        let name = &urdf.links[parts.links[w.link].urdf_link_index].name;
        let r = model
            .link(name)
            .and_then(|l| {
                l.shapes.iter().find_map(|(_, s)| match s {
                    Shape::Cylinder { radius_m, .. } | Shape::Sphere { radius_m } => Some(*radius_m),
                    _ => None,
                })
            })
            .ok_or_else(|| {
                format!(
                    "wheel link `{name}` (joint `{}`) has no cylinder collision",
                    w.name
                )
            })?;
        radii.push(r);
    }
    let (lo, hi) = radii
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), r| (a.min(*r), b.max(*r)));
    if hi - lo > 1e-3 {
        return Err(format!(
            "the wheels' radii differ, from {lo} to {hi} m: a skid-steer drive turns wheels of one size"
        ));
    }
    Ok(hi)
}
