//! The blind band: on the geometry alone, for each range from the robot, the heights at which the sensors'
//! rays pass within the robot's height band on flat ground, and the largest vertical gap between them. A board
//! thinner than the gap at a range can hide in it (`blind_band.csv`).

use nalgebra::{Point3, Vector3};
use oeg::RobotProfile;
use serde::Serialize;

use crate::sensors::SimSensor;
use crate::world::World;

/// One row of `blind_band.csv`: the sensors' rays at one range from the robot, on flat ground.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlindBandRow {
    /// Horizontal distance from the robot's base, metres.
    pub range_m: f64,
    /// Distinct ray heights within the band between a step and the robot's height at this range.
    pub rays_in_band: u64,
    /// The largest vertical gap between rays (or a band edge) within the band, metres: a board thinner than
    /// this can hide in it.
    pub largest_gap_m: f64,
    /// The gap's lower edge, metres above the ground.
    pub gap_from_m: f64,
    /// The gap's upper edge, metres above the ground.
    pub gap_to_m: f64,
}

/// The heights above the ground, metres, at which the rays of `sensors` (mounted on the robot as `world`
/// holds it now) pass at `range_m` from the robot's base, over flat ground at the base's height; sorted, a
/// ray that meets the ground before the range left out.
pub fn ray_heights_at(sensors: &[SimSensor], world: &World, range_m: f64) -> Vec<f64> {
    let rays = rays_of(sensors, world);
    let mut h = heights_at(&rays, &world.world_from_base(), range_m);
    h.sort_by(f64::total_cmp);
    h
}

type RayLine = (Point3<f64>, Vector3<f64>);

fn rays_of(sensors: &[SimSensor], world: &World) -> Vec<RayLine> {
    sensors
        .iter()
        .filter_map(|s| {
            let world_from_sensor = world.world_from_link(&s.spec.mount_link)? * s.link_from_sensor;
            let origin = Point3::from(world_from_sensor.translation.vector);
            Some(
                s.directions()
                    .iter()
                    .map(|d| (origin, world_from_sensor.rotation * d))
                    .collect::<Vec<_>>(),
            )
        })
        .flatten()
        .collect()
}

fn heights_at(rays: &[RayLine], base: &nalgebra::Isometry3<f64>, range: f64) -> Vec<f64> {
    let ground = base.translation.z;
    rays.iter()
        .filter_map(|(o, d)| {
            let horizontal = d.x.hypot(d.y);
            if horizontal < 1e-9 {
                return None;
            }
            // The horizontal distance from the base to the ray's point at range: the sensor's offset from the
            // base is small beside a range, and is taken along the ray.
            let offset = ((o.x - base.translation.x) * d.x + (o.y - base.translation.y) * d.y) / horizontal;
            let along = range - offset;
            if along <= 0.0 {
                return None;
            }
            let h = o.z - ground + d.z / horizontal * along;
            // A ray that met the ground before this range does not reach it.
            (h >= 0.0).then_some(h)
        })
        .collect()
}

/// The blind band of `sensors` mounted on the robot as `world` holds it now (its pose at the time), over
/// flat ground at the base's height: for each range from `step_m` to `max_range_m`, the heights at which the
/// rays pass ([`ray_heights_at`]), and the largest gap between them within `[max_step_m, height_m]` above
/// the ground.
pub fn blind_band(
    sensors: &[SimSensor],
    world: &World,
    profile: &RobotProfile,
    step_m: f64,
    max_range_m: f64,
) -> Vec<BlindBandRow> {
    let base = world.world_from_base();
    let rays = rays_of(sensors, world);
    let (lo, hi) = (f64::from(profile.max_step_m), f64::from(profile.height_m));
    let num = (max_range_m / step_m).floor() as usize;
    (1..=num)
        .map(|k| {
            let range = k as f64 * step_m;
            let mut heights: Vec<f64> = heights_at(&rays, &base, range)
                .into_iter()
                .filter(|h| (lo..=hi).contains(h))
                .collect();
            heights.sort_by(f64::total_cmp);
            heights.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
            let rays_in_band = heights.len() as u64;
            let mut edges = vec![lo];
            edges.extend(&heights);
            edges.push(hi);
            let (from, to) = edges
                .windows(2)
                .map(|w| (w[0], w[1]))
                .max_by(|a, b| (a.1 - a.0).total_cmp(&(b.1 - b.0)))
                .unwrap_or((lo, hi));
            let round = |v: f64| (v * 1e6).round() / 1e6;
            BlindBandRow {
                range_m: round(range),
                rays_in_band,
                largest_gap_m: round(to - from),
                gap_from_m: round(from),
                gap_to_m: round(to),
            }
        })
        .collect()
}
