//! The robot on its wheels (`[robot.drive] mode = "physics"`): a Rapier multibody from the URDF ([`WheeledModel`]),
//! its wheels turned by velocity motors with the torque and speed limits of `[robot.physics]`, stepped at a
//! fixed time step, and watched for what happened: contacts of its body, stalls, tip-overs and arrival.
//!
//! The drive is skid-steer: the left wheels turn at `(v - w b / 2) / r`, the right at `(v + w b / 2) / r`,
//! for a speed `v`, a turn rate `w`, a track `b` and a wheel radius `r`. A skid-steer robot turns with slip,
//! so the no-slip kinematics turn it slower than asked; the drive closes a loop on the turn rate the body
//! achieves (proportional and integral), and every sample reports the commanded and the achieved motion.

mod follow;
mod model;
mod record;
mod watch;

pub use model::WheeledModel;
pub use record::{PhysicsEvent, PhysicsEventKind, PhysicsSample};

use std::collections::{BTreeMap, BTreeSet};

use nalgebra::{Isometry3, Vector3};
use rapier3d::prelude::{
    CoefficientCombineRule, ColliderHandle, JointAxis, MotorModel, MultibodyJointHandle, PhysicsWorld,
    RigidBodyHandle,
};
use rapier3d_urdf::UrdfMultibodyOptions;

use crate::convert::{from_pose, to_point, to_pose};
use crate::drive::PlanarPose;
use follow::WaypointFollower;
use watch::Watch;

/// How often the drive records a sample of its state, seconds (20 Hz).
pub const SAMPLE_PERIOD_S: f64 = 0.05;
/// How long the robot settles on the ground, motors holding, before the run's clock starts, seconds.
pub const SETTLE_S: f64 = 0.5;
/// A body part that touches the same thing again within this many seconds continues its contact, seconds.
pub const CONTACT_GAP_S: f64 = 0.5;
/// How far above the ground the robot is put before it settles, metres: its wheels start clear of it.
const DROP_M: f64 = 0.005;
/// Proportional gain of the turn-rate loop (dimensionless) and its integral gain, 1/s.
const TURN_KP: f64 = 1.0;
const TURN_KI_PER_S: f64 = 2.0;
/// The integral's bound, rad/s (anti-windup): a turn on the spot asks for up to twice the turn rate the
/// no-slip kinematics give; the bound adds at most a radian a second to that.
const TURN_INTEGRAL_MAX_RAD_S: f64 = 1.0;
/// The motors' velocity-servo gain, N m per rad/s (Rapier's motor damping under its force-based motor model):
/// stiff, so a wheel turns at its target speed unless its torque limit binds; at the default torque limit the
/// wheel lags its target by about 5 mrad/s (0.6 mm/s at the rim). Rapier's default, acceleration-based
/// model scales the gain by the joint's effective inertia instead, and a standing robot crept down a 20 %
/// slope at 2 cm/s under it.
const MOTOR_GAIN: f32 = 1000.0;
/// A robot that covers less than this fraction of what its commands asked (and no more than `stall_distance_m`)
/// over `stall_time_s` is stalled: pushing against a step, spinning its wheels, or dithering against an edge.
const STALL_FRACTION: f64 = 0.25;
/// Commands below these are standing still, m/s and rad/s.
const STILL_M_S: f64 = 1e-3;
const STILL_RAD_S: f64 = 1e-2;

/// What the drive follows.
#[derive(Debug, Clone, PartialEq)]
enum Target {
    /// The scripted waypoints.
    Waypoints(WaypointFollower),
    /// A velocity command (a closed loop's `cmd_vel`).
    Command { speed_m_s: f64, turn_rate_rad_s: f64 },
}

#[derive(Debug, Clone)]
struct Wheel {
    joint: MultibodyJointHandle,
    body: RigidBodyHandle,
    side: f64,
    spin: f64,
}

/// The robot driven on its wheels, in a physics world it was put into.
#[derive(Debug, Clone)]
pub(crate) struct PhysicsDrive {
    base: RigidBodyHandle,
    wheels: Vec<Wheel>,
    /// The robot's colliders that are not wheels, with their link's name.
    body_colliders: Vec<(ColliderHandle, String)>,
    radius_m: f64,
    track_m: f64,
    torque_nm: f32,
    max_wheel_speed_rad_s: f64,
    max_speed_m_s: f64,
    max_turn_rate_rad_s: f64,
    roll_limit_rad: f64,
    pitch_limit_rad: f64,
    stall_time_s: f64,
    stall_distance_m: f64,
    dt_s: f64,
    steps: u64,
    sample_every: u64,
    target: Target,
    /// The path the drive is asked to follow: the scripted waypoints, then a closed loop's plan (empty while
    /// it has none). Every sample reports the distance from it.
    reference: Vec<[f64; 2]>,
    commanded: (f64, f64),
    turn_integral: f64,
    watch: Option<Watch>,
    /// Each (body collider, partner) pair's last step in contact: a touch that resumes within
    /// [`CONTACT_GAP_S`] is the same contact (a body that bounces on what it leans against).
    last_touch: BTreeMap<(usize, u128), u64>,
    tipped: bool,
    events: Vec<PhysicsEvent>,
    samples: Vec<PhysicsSample>,
}

impl PhysicsDrive {
    /// Puts `model` into `physics` at `world_from_base` (lifted clear of the ground), tags its colliders with
    /// `user_data`, and lets it settle on its wheels for [`SETTLE_S`]; it then follows `waypoints` at
    /// `speed_m_s`.
    pub(crate) fn insert(
        physics: &mut PhysicsWorld,
        model: &WheeledModel,
        world_from_base: &Isometry3<f64>,
        user_data: u128,
        waypoints: &[[f64; 2]],
        speed_m_s: f64,
    ) -> Self {
        let settings = &model.settings;
        physics.integration_parameters.dt = settings.time_step_s as f32;
        physics.integration_parameters.num_solver_iterations = settings.solver_iterations as usize;
        let mut parts = model.parts.clone();
        let lifted = Isometry3::translation(0.0, 0.0, DROP_M) * world_from_base;
        parts.append_transform(&to_pose(&lifted));
        let wheel_links: BTreeSet<usize> = model.wheels.iter().map(|w| w.link).collect();
        for (k, link) in parts.links.iter_mut().enumerate() {
            for c in &mut link.colliders {
                c.collider.user_data = user_data;
                if wheel_links.contains(&k) {
                    // The ground and the obstacles keep Rapier's friction of 1 under this rule: the contact's
                    // coefficient is the wheel's.
                    c.collider.set_friction(settings.wheel_friction as f32);
                    c.collider
                        .set_friction_combine_rule(CoefficientCombineRule::Multiply);
                } else {
                    c.collider.set_friction(settings.body_friction as f32);
                    c.collider
                        .set_friction_combine_rule(CoefficientCombineRule::Multiply);
                }
            }
        }
        let link_names = &model.link_names;
        let handles = parts.insert_using_multibody_joints(
            &mut physics.bodies,
            &mut physics.colliders,
            &mut physics.multibody_joints,
            UrdfMultibodyOptions::DISABLE_SELF_CONTACTS,
        );
        let wheels = model
            .wheels
            .iter()
            .filter_map(|w| {
                Some(Wheel {
                    joint: handles.joints[w.joint].joint?,
                    body: handles.links[w.link].body,
                    side: w.side,
                    spin: w.spin,
                })
            })
            .collect();
        let body_colliders = handles
            .links
            .iter()
            .enumerate()
            .filter(|(k, _)| !wheel_links.contains(k))
            .flat_map(|(k, l)| l.colliders.iter().map(move |c| (c.handle, k)))
            .map(|(h, k)| (h, link_names[k].clone()))
            .collect();
        let dt_s = f64::from(physics.integration_parameters.dt);
        let mut drive = Self {
            base: handles.links[model.base].body,
            wheels,
            body_colliders,
            radius_m: model.radius_m,
            track_m: model.track_m,
            torque_nm: model.torque_nm as f32,
            max_wheel_speed_rad_s: model.max_wheel_speed_rad_s,
            max_speed_m_s: model.max_speed_m_s,
            max_turn_rate_rad_s: model.max_turn_rate_rad_s,
            roll_limit_rad: model.roll_limit_rad,
            pitch_limit_rad: model.pitch_limit_rad,
            stall_time_s: settings.stall_time_s,
            stall_distance_m: settings.stall_distance_m,
            dt_s,
            steps: 0,
            sample_every: ((SAMPLE_PERIOD_S / dt_s).round() as u64).max(1),
            target: Target::Command {
                speed_m_s: 0.0,
                turn_rate_rad_s: 0.0,
            },
            reference: waypoints.to_vec(),
            commanded: (0.0, 0.0),
            turn_integral: 0.0,
            watch: None,
            last_touch: BTreeMap::new(),
            tipped: false,
            events: Vec::new(),
            samples: Vec::new(),
        };
        for _ in 0..(SETTLE_S / dt_s).round() as u64 {
            drive.set_wheels(physics, 0.0, 0.0);
            physics.step();
        }
        drive.target = Target::Waypoints(WaypointFollower::new(waypoints, speed_m_s));
        drive
    }

    /// Simulated time of the drive, seconds.
    pub(crate) fn time_s(&self) -> f64 {
        self.steps as f64 * self.dt_s
    }

    /// From now on, drive at `speed_m_s` turning at `turn_rate_rad_s` (within the robot's limits).
    pub(crate) fn command(&mut self, speed_m_s: f64, turn_rate_rad_s: f64) {
        self.target = Target::Command {
            speed_m_s,
            turn_rate_rad_s,
        };
    }

    /// Whether the scripted drive is over: the last waypoint reached, or a command given instead.
    pub(crate) fn scripted_drive_over(&self) -> bool {
        match &self.target {
            Target::Waypoints(f) => f.arrived(),
            Target::Command { .. } => true,
        }
    }

    /// The path the commands follow from now on (a closed loop's plan; empty: none), for the samples' distance
    /// from it.
    pub(crate) fn set_reference(&mut self, path: &[(f64, f64)]) {
        self.reference = path.iter().map(|&(x, y)| [x, y]).collect();
    }

    /// Logs the goal as reached at `(x_m, y_m)` now, once: a closed loop's goal, which the drive does not know.
    pub(crate) fn goal_reached(&mut self, x_m: f64, y_m: f64) {
        if !self
            .events
            .iter()
            .any(|e| e.kind == PhysicsEventKind::GoalReached)
        {
            self.events.push(PhysicsEvent {
                time_s: self.time_s(),
                x_m,
                y_m,
                kind: PhysicsEventKind::GoalReached,
            });
        }
    }

    /// The base's pose now.
    pub(crate) fn world_from_base(&self, physics: &PhysicsWorld) -> Isometry3<f64> {
        physics
            .bodies
            .get(self.base)
            .map_or_else(Isometry3::identity, |b| from_pose(b.position()))
    }

    /// The events so far.
    pub(crate) fn events(&self) -> &[PhysicsEvent] {
        &self.events
    }

    /// The samples so far.
    pub(crate) fn samples(&self) -> &[PhysicsSample] {
        &self.samples
    }

    /// Steps the physics until `t_s` (the steps whose end is at most half a step past it), controlling the
    /// wheels before each step and watching the robot after it; `name_of` names a collider's `user_data`, and
    /// `before_step` moves the rest of the world (the actors) to where it is at the step's end.
    pub(crate) fn advance_to(
        &mut self,
        physics: &mut PhysicsWorld,
        t_s: f64,
        name_of: &dyn Fn(u128) -> String,
        before_step: &mut dyn FnMut(&mut PhysicsWorld, f64),
    ) {
        while (self.steps + 1) as f64 * self.dt_s <= t_s + self.dt_s / 2.0 {
            let pose = planar(&self.world_from_base(physics));
            let (speed, turn) = match &mut self.target {
                Target::Waypoints(f) => {
                    let was = f.arrived();
                    let c = f.command(&pose, self.max_turn_rate_rad_s);
                    if f.arrived() && !was {
                        self.events.push(PhysicsEvent {
                            time_s: self.time_s(),
                            x_m: pose.x_m,
                            y_m: pose.y_m,
                            kind: PhysicsEventKind::GoalReached,
                        });
                    }
                    c
                }
                Target::Command {
                    speed_m_s,
                    turn_rate_rad_s,
                } => (*speed_m_s, *turn_rate_rad_s),
            };
            let speed = speed.clamp(-self.max_speed_m_s, self.max_speed_m_s);
            let turn = turn.clamp(-self.max_turn_rate_rad_s, self.max_turn_rate_rad_s);
            self.commanded = (speed, turn);
            let (_, achieved_turn) = self.twist(physics);
            let error = turn - achieved_turn;
            if (turn.abs() < STILL_RAD_S && speed.abs() < STILL_M_S) || turn * self.turn_integral < 0.0 {
                // Standing, or turning the other way: what was integrated no longer applies.
                self.turn_integral = 0.0;
            } else {
                self.turn_integral = (self.turn_integral + TURN_KI_PER_S * error * self.dt_s)
                    .clamp(-TURN_INTEGRAL_MAX_RAD_S, TURN_INTEGRAL_MAX_RAD_S);
            }
            let turn_cmd = turn + TURN_KP * error + self.turn_integral;
            self.set_wheels(physics, speed, turn_cmd);
            before_step(physics, (self.steps + 1) as f64 * self.dt_s);
            physics.step();
            self.steps += 1;
            self.watch(physics, name_of);
        }
    }

    /// Sets the wheel motors for a speed and a turn rate by the skid-steer kinematics, scaled down together
    /// when a wheel would pass its speed limit.
    fn set_wheels(&mut self, physics: &mut PhysicsWorld, speed_m_s: f64, turn_rad_s: f64) {
        let half = turn_rad_s * self.track_m / 2.0;
        let (left, right) = (
            (speed_m_s - half) / self.radius_m,
            (speed_m_s + half) / self.radius_m,
        );
        let scale = (left.abs().max(right.abs()) / self.max_wheel_speed_rad_s).max(1.0);
        for w in &self.wheels {
            let target = if w.side > 0.0 { left } else { right } / scale;
            if let Some((multibody, link)) = physics.multibody_joints.get_mut(w.joint)
                && let Some(l) = multibody.link_mut(link)
            {
                l.joint
                    .data
                    .set_motor_model(JointAxis::AngX, MotorModel::ForceBased)
                    .set_motor_velocity(JointAxis::AngX, (w.spin * target) as f32, MOTOR_GAIN)
                    .set_motor_max_force(JointAxis::AngX, self.torque_nm);
            }
        }
    }

    /// The base's speed along its heading (m/s) and turn rate about the world's z (rad/s).
    fn twist(&self, physics: &PhysicsWorld) -> (f64, f64) {
        let Some(b) = physics.bodies.get(self.base) else {
            return (0.0, 0.0);
        };
        let v = to_point(b.linvel()).coords;
        let heading = from_pose(b.position()).rotation * Vector3::x();
        (v.dot(&heading), f64::from(b.angvel().z))
    }

    /// Each side's mean wheel slip.
    fn slips(&self, physics: &PhysicsWorld) -> (f64, f64) {
        let Some(base) = physics.bodies.get(self.base) else {
            return (0.0, 0.0);
        };
        let base_rot = from_pose(base.position()).rotation;
        let lateral = base_rot * Vector3::y();
        let heading = base_rot * Vector3::x();
        let base_w = to_point(base.angvel()).coords;
        let (mut sum, mut n) = ([0.0; 2], [0u32; 2]);
        for w in &self.wheels {
            let Some(b) = physics.bodies.get(w.body) else {
                continue;
            };
            let spin = (to_point(b.angvel()).coords - base_w).dot(&lateral);
            let surface = spin * self.radius_m;
            let ground = to_point(b.linvel()).coords.dot(&heading);
            let slip = (surface - ground) / surface.abs().max(ground.abs()).max(1e-3);
            let k = usize::from(w.side < 0.0);
            sum[k] += slip;
            n[k] += 1;
        }
        (sum[0] / f64::from(n[0].max(1)), sum[1] / f64::from(n[1].max(1)))
    }
}

/// The planar part of a pose: position and heading (the heading of the base's x axis in the ground plane).
pub(crate) fn planar(pose: &Isometry3<f64>) -> PlanarPose {
    let x = pose.rotation * Vector3::x();
    PlanarPose {
        x_m: pose.translation.x,
        y_m: pose.translation.y,
        yaw_rad: x.y.atan2(x.x),
        distance_m: 0.0,
    }
}
