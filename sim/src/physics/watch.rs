//! What the drive watches after each step: the body's contacts, the tip-over and the stall, and the samples.

use nalgebra::Isometry3;
use rapier3d::prelude::PhysicsWorld;

use super::follow::{self, distance_to_path};
use super::{
    CONTACT_GAP_S, PhysicsDrive, PhysicsEvent, PhysicsEventKind, PhysicsSample, STALL_FRACTION, STILL_M_S,
    STILL_RAD_S, planar,
};
use crate::convert::to_point;
use crate::drive::PlanarPose;

/// The progress watch of a stall: where and when the robot last made progress.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Watch {
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

impl PhysicsDrive {
    /// After a step: contacts of the body, the tip-over and stall watches, and every `sample_every`-th step a
    /// sample.
    pub(super) fn watch(&mut self, physics: &PhysicsWorld, name_of: &dyn Fn(u128) -> String) {
        let t = self.time_s();
        let pose = self.world_from_base(physics);
        let p = planar(&pose);
        self.watch_contacts(physics, name_of, t, &p);
        let (roll, pitch, _) = pose.rotation.euler_angles();
        self.watch_tip_over(t, &p, roll, pitch);
        let (slip_left, slip_right) = self.slips(physics);
        self.watch_stall(t, &p, (slip_left + slip_right) / 2.0);
        if self.steps.is_multiple_of(self.sample_every) {
            self.sample(physics, t, &pose, (slip_left, slip_right));
        }
    }

    /// Each new touch of a body part with something else is an event.
    fn watch_contacts(
        &mut self,
        physics: &PhysicsWorld,
        name_of: &dyn Fn(u128) -> String,
        t: f64,
        p: &PlanarPose,
    ) {
        let gap_steps = (CONTACT_GAP_S / self.dt_s).round() as u64;
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
                let last = self.last_touch.insert(key, self.steps);
                if last.is_some_and(|l| self.steps - l <= gap_steps) {
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
    }

    /// Roll or pitch past its stability angle, once.
    fn watch_tip_over(&mut self, t: f64, p: &PlanarPose, roll: f64, pitch: f64) {
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
    }

    /// Commanded to move and no progress for `stall_time_s`, once per stall.
    fn watch_stall(&mut self, t: f64, p: &PlanarPose, slip: f64) {
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
                    w.slip_sum += slip;
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
    }

    /// A sample of the state now.
    fn sample(
        &mut self,
        physics: &PhysicsWorld,
        t: f64,
        pose: &Isometry3<f64>,
        (slip_left, slip_right): (f64, f64),
    ) {
        let p = planar(pose);
        let (roll, pitch, _) = pose.rotation.euler_angles();
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
            path_error_m: (!self.reference.is_empty())
                .then(|| distance_to_path(&self.reference, p.x_m, p.y_m)),
        });
    }
}
