//! The robot on its wheels (`[robot.drive] mode = "physics"`): a Rapier multibody from the URDF ([`model`]),
//! its wheels turned by velocity motors with the torque and speed limits of `[robot.physics]`, stepped at a
//! fixed time step, and watched for what happened: contacts of its body, stalls, tip-overs and arrival.
//!
//! The drive is skid-steer: the left wheels turn at `(v - w b / 2) / r`, the right at `(v + w b / 2) / r`,
//! for a speed `v`, a turn rate `w`, a track `b` and a wheel radius `r`. A skid-steer robot turns with slip,
//! so the no-slip kinematics turn it slower than asked; the drive closes a loop on the turn rate the body
//! achieves (proportional and integral), and every sample reports the commanded and the achieved motion.

mod follow;
mod model;

pub use model::WheeledModel;

use std::collections::BTreeSet;

use nalgebra::{Isometry3, Vector3};
use rapier3d::prelude::{
    CoefficientCombineRule, ColliderHandle, JointAxis, MultibodyJointHandle, PhysicsWorld, RigidBodyHandle,
};
use rapier3d_urdf::UrdfMultibodyOptions;
use serde::Serialize;

use crate::convert::{from_pose, to_point, to_pose};
use crate::drive::PlanarPose;
use follow::{WaypointFollower, distance_to_path};

/// How often the drive records a sample of its state, seconds (20 Hz).
pub const SAMPLE_PERIOD_S: f64 = 0.05;
/// How long the robot settles on the ground, motors holding, before the run's clock starts, seconds.
pub const SETTLE_S: f64 = 0.5;
/// How far above the ground the robot is put before it settles, metres: its wheels start clear of it.
const DROP_M: f64 = 0.005;
/// Proportional gain of the turn-rate loop (dimensionless) and its integral gain, 1/s.
const TURN_KP: f64 = 1.0;
const TURN_KI_PER_S: f64 = 2.0;
/// The integral's bound, rad/s (anti-windup): a turn on the spot asks for up to twice the turn rate the
/// no-slip kinematics give; the bound adds at most a radian a second to that.
const TURN_INTEGRAL_MAX_RAD_S: f64 = 1.0;
/// The motors' velocity-servo gain (Rapier's motor damping): stiff, so a wheel turns at its target speed
/// unless its torque limit binds.
const MOTOR_GAIN: f32 = 1000.0;
/// A robot that covers less than this fraction of what its commands asked (and no more than `stall_distance_m`)
/// over `stall_time_s` is stalled: pushing against a step, spinning its wheels, or dithering against an edge.
const STALL_FRACTION: f64 = 0.25;
/// Commands below these are standing still, m/s and rad/s.
const STILL_M_S: f64 = 1e-3;
const STILL_RAD_S: f64 = 1e-2;

/// What happened to the robot, by name.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PhysicsEventKind {
    /// A part of the robot's body (not a wheel) touched an obstacle, a person or the ground.
    Contact {
        /// What it touched: the obstacle's label, `person <k>`, or `ground`.
        with: String,
        /// The robot's link that touched it.
        link: String,
    },
    /// The robot was commanded to drive or turn and made no progress for `stall_time_s`: less than
    /// `stall_distance_m` or a quarter of what its commands asked.
    Stall {
        /// The wheels' mean slip over the stall, from 0 (rolling) to 1 (spinning in place).
        wheel_slip: f64,
    },
    /// Roll or pitch passed its static stability angle.
    TipOver {
        /// Roll at the time, degrees.
        roll_deg: f64,
        /// Pitch at the time, degrees.
        pitch_deg: f64,
    },
    /// The scripted drive reached its last waypoint.
    GoalReached,
}

/// One event with its time and place.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PhysicsEvent {
    /// Simulated time, seconds.
    pub time_s: f64,
    /// Where, world frame, metres: the contact point, or the robot's base.
    pub x_m: f64,
    /// See `x_m`.
    pub y_m: f64,
    /// What.
    #[serde(flatten)]
    pub kind: PhysicsEventKind,
}

/// The robot's state at one time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PhysicsSample {
    /// Simulated time, seconds.
    pub time_s: f64,
    /// Base position, world frame, metres.
    pub x_m: f64,
    /// See `x_m`.
    pub y_m: f64,
    /// See `x_m`.
    pub z_m: f64,
    /// Heading, roll and pitch of the base, degrees.
    pub yaw_deg: f64,
    /// See `yaw_deg`.
    pub roll_deg: f64,
    /// See `yaw_deg`.
    pub pitch_deg: f64,
    /// The commanded speed, m/s, and turn rate, degrees per second.
    pub commanded_speed_m_s: f64,
    /// See `commanded_speed_m_s`.
    pub commanded_turn_rate_deg_s: f64,
    /// The achieved speed along the base's heading, m/s, and turn rate, degrees per second.
    pub speed_m_s: f64,
    /// See `speed_m_s`.
    pub turn_rate_deg_s: f64,
    /// The left and the right wheels' mean slip: `(w r - v) / max(|w r|, |v|)`, 0 when rolling, 1 when
    /// spinning in place, negative when dragged.
    pub slip_left: f64,
    /// See `slip_left`.
    pub slip_right: f64,
    /// Distance from the scripted path, metres (`None` once a command replaced it).
    pub path_error_m: Option<f64>,
}

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

/// The progress watch of a stall: where and when the robot last made progress.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Watch {
    since_s: f64,
    x_m: f64,
    y_m: f64,
    yaw_rad: f64,
    /// The distance the commands since `since_s` asked a wheel's contact to cover, metres.
    commanded_m: f64,
    slip_sum: f64,
    samples: u32,
    reported: bool,
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
    scripted: Vec<[f64; 2]>,
    commanded: (f64, f64),
    turn_integral: f64,
    watch: Option<Watch>,
    touching: BTreeSet<(usize, u128)>,
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
            scripted: waypoints.to_vec(),
            commanded: (0.0, 0.0),
            turn_integral: 0.0,
            watch: None,
            touching: BTreeSet::new(),
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
    /// wheels before each step and watching the robot after it; `name_of` names a collider's `user_data`.
    pub(crate) fn advance_to(
        &mut self,
        physics: &mut PhysicsWorld,
        t_s: f64,
        name_of: &dyn Fn(u128) -> String,
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

    /// After a step: contacts of the body, the tip-over and stall watches, and every `sample_every`-th step a
    /// sample.
    fn watch(&mut self, physics: &PhysicsWorld, name_of: &dyn Fn(u128) -> String) {
        let t = self.time_s();
        let pose = self.world_from_base(physics);
        let p = planar(&pose);
        // Contacts: each new touch of a body part with something else is an event.
        let mut now = BTreeSet::new();
        for (k, (handle, link)) in self.body_colliders.iter().enumerate() {
            for pair in physics.contact_pairs_with(*handle) {
                if !pair.has_any_active_contact() {
                    continue;
                }
                let other = if pair.collider1 == *handle {
                    pair.collider2
                } else {
                    pair.collider1
                };
                let Some(other_collider) = physics.colliders.get(other) else {
                    continue;
                };
                let key = (k, other_collider.user_data);
                now.insert(key);
                if self.touching.contains(&key) {
                    continue;
                }
                let at = pair
                    .find_deepest_contact()
                    .and_then(|(_, c)| {
                        physics
                            .colliders
                            .get(pair.collider1)
                            .map(|c1| to_point(c1.position().transform_point(c.local_p1)))
                    })
                    .unwrap_or_else(|| nalgebra::Point3::new(p.x_m, p.y_m, 0.0));
                self.events.push(PhysicsEvent {
                    time_s: t,
                    x_m: at.x,
                    y_m: at.y,
                    kind: PhysicsEventKind::Contact {
                        with: name_of(other_collider.user_data),
                        link: link.clone(),
                    },
                });
            }
        }
        self.touching = now;

        let (roll, pitch, _) = pose.rotation.euler_angles();
        if !self.tipped && (roll.abs() > self.roll_limit_rad || pitch.abs() > self.pitch_limit_rad) {
            self.tipped = true;
            self.events.push(PhysicsEvent {
                time_s: t,
                x_m: p.x_m,
                y_m: p.y_m,
                kind: PhysicsEventKind::TipOver {
                    roll_deg: roll.to_degrees(),
                    pitch_deg: pitch.to_degrees(),
                },
            });
        }

        let (slip_left, slip_right) = self.slips(physics);
        // Commanded to move: to drive, or to turn on the spot. Progress is the distance a wheel's contact
        // covers: the base's displacement and the heading's change times half the track.
        let moving = self.commanded.0.abs() >= STILL_M_S || self.commanded.1.abs() >= STILL_RAD_S;
        let fresh = Watch {
            since_s: t,
            x_m: p.x_m,
            y_m: p.y_m,
            yaw_rad: p.yaw_rad,
            commanded_m: 0.0,
            slip_sum: 0.0,
            samples: 0,
            reported: false,
        };
        let half_track = self.track_m / 2.0;
        let asked = (self.commanded.0.abs() + self.commanded.1.abs() * half_track) * self.dt_s;
        match (&mut self.watch, moving) {
            (_, false) => self.watch = None,
            (None, true) => self.watch = Some(fresh),
            (Some(w), true) => {
                let progress = (p.x_m - w.x_m).hypot(p.y_m - w.y_m)
                    + follow::wrap(p.yaw_rad - w.yaw_rad).abs() * half_track;
                w.commanded_m += asked;
                if progress > self.stall_distance_m.max(STALL_FRACTION * w.commanded_m) {
                    *w = fresh;
                } else {
                    w.slip_sum += (slip_left + slip_right) / 2.0;
                    w.samples += 1;
                    if !w.reported && t - w.since_s >= self.stall_time_s {
                        w.reported = true;
                        let wheel_slip = w.slip_sum / f64::from(w.samples.max(1));
                        self.events.push(PhysicsEvent {
                            time_s: t,
                            x_m: p.x_m,
                            y_m: p.y_m,
                            kind: PhysicsEventKind::Stall { wheel_slip },
                        });
                    }
                }
            }
        }

        if self.steps.is_multiple_of(self.sample_every) {
            let (speed, turn) = self.twist(physics);
            self.samples.push(PhysicsSample {
                time_s: t,
                x_m: p.x_m,
                y_m: p.y_m,
                z_m: pose.translation.z,
                yaw_deg: p.yaw_rad.to_degrees(),
                roll_deg: roll.to_degrees(),
                pitch_deg: pitch.to_degrees(),
                commanded_speed_m_s: self.commanded.0,
                commanded_turn_rate_deg_s: self.commanded.1.to_degrees(),
                speed_m_s: speed,
                turn_rate_deg_s: turn.to_degrees(),
                slip_left,
                slip_right,
                path_error_m: matches!(self.target, Target::Waypoints(_))
                    .then(|| distance_to_path(&self.scripted, p.x_m, p.y_m)),
            });
        }
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
