//! The map's input: one scan, a sensor origin and its rays, in the world frame.

use nalgebra::{Point3, Vector3};

use crate::error::{Error, Result};
use crate::sensor::SensorModel;

/// Whether a ray ended on a surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RayKind {
    /// The ray hit something at its end point.
    Hit,
    /// The sensor got no return along this direction (out of range, dropout, sky): the ray only clears, never
    /// marks anything occupied.
    NoReturn,
}

/// One ray of a scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Hit or no return.
    pub kind: RayKind,
    /// For a hit, the end point minus the scan's origin, world axes, metres; for a no return, the direction
    /// (any length).
    pub offset_in_world: Vector3<f32>,
    /// This ray's range error (one standard deviation, metres), or `None` to use the scan's sensor model.
    pub range_sigma_m: Option<f32>,
}

impl Ray {
    /// A hit at `offset_in_world` from the scan's origin.
    pub fn hit(offset_in_world: Vector3<f32>) -> Self {
        Self {
            kind: RayKind::Hit,
            offset_in_world,
            range_sigma_m: None,
        }
    }

    /// A reading with no return along `direction_in_world`.
    pub fn no_return(direction_in_world: Vector3<f32>) -> Self {
        Self {
            kind: RayKind::NoReturn,
            offset_in_world: direction_in_world,
            range_sigma_m: None,
        }
    }

    /// The same ray with its own range error, overriding the sensor model.
    pub fn with_range_sigma_m(self, range_sigma_m: f32) -> Self {
        Self {
            range_sigma_m: Some(range_sigma_m),
            ..self
        }
    }
}

/// One scan: every ray a sensor produced from one origin at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// The sensor's origin, world frame, metres.
    pub origin_in_world: Point3<f64>,
    /// The rays, relative to the origin.
    pub rays: Vec<Ray>,
    /// The sensor model for rays that carry no range error of their own.
    pub sensor: SensorModel,
    /// Time of the scan, seconds (informational; the map does not use it).
    pub stamp_s: f64,
    /// The world z of the ground under the robot that carried the sensor, metres, where it is known (a
    /// simulated run, a log recorded with it): height thresholding
    /// ([`crate::ModelOptions::max_height_m`]) measures from it, as elevation_mapping's height limits
    /// measure in the robot's frame, so a robot that climbs a slope keeps mapping the ground ahead. `None`
    /// (real data without a robot's pose): the threshold is world z.
    pub ground_z_m: Option<f64>,
}

impl Scan {
    /// An empty scan from `origin_in_world`.
    pub fn new(origin_in_world: Point3<f64>, sensor: SensorModel) -> Self {
        Self {
            origin_in_world,
            rays: Vec::new(),
            sensor,
            stamp_s: 0.0,
            ground_z_m: None,
        }
    }

    /// Adds a hit at the world point `p_in_world`.
    pub fn push_hit(&mut self, p_in_world: Point3<f64>) {
        self.rays
            .push(Ray::hit((p_in_world - self.origin_in_world).cast::<f32>()));
    }

    /// Number of hit rays.
    pub fn num_hits(&self) -> usize {
        self.rays.iter().filter(|r| r.kind == RayKind::Hit).count()
    }

    /// Checks that every number in the scan can be used: a finite origin, finite ray vectors, no zero-length
    /// no-return direction, range errors finite and >= 0, and a valid sensor model.
    ///
    /// # Errors
    /// [`Error::InvalidScan`] naming the first bad ray and its index.
    pub fn validate(&self) -> Result<()> {
        if !self.origin_in_world.iter().all(|v| v.is_finite()) {
            return Err(Error::InvalidScan(format!(
                "origin {:?} is not finite",
                self.origin_in_world
            )));
        }
        self.sensor.validate()?;
        for (index, ray) in self.rays.iter().enumerate() {
            let v = ray.offset_in_world;
            if !v.iter().all(|c| c.is_finite()) {
                return Err(Error::InvalidScan(format!(
                    "ray {index} has a non-finite vector {v:?}"
                )));
            }
            if ray.kind == RayKind::NoReturn && v.norm_squared() == 0.0 {
                return Err(Error::InvalidScan(format!(
                    "no-return ray {index} has no direction"
                )));
            }
            if let Some(s) = ray.range_sigma_m
                && !(s.is_finite() && s >= 0.0)
            {
                return Err(Error::InvalidScan(format!(
                    "ray {index} has range error {s}, expected >= 0 m"
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_names_the_bad_ray() {
        let mut scan = Scan::new(Point3::new(0.0, 0.0, 1.0), SensorModel::laser());
        scan.push_hit(Point3::new(1.0, 0.0, 0.0));
        assert!(scan.validate().is_ok());
        scan.rays.push(Ray::hit(Vector3::new(f32::NAN, 0.0, 0.0)));
        let err = scan.validate().expect_err("NaN ray");
        assert!(err.to_string().contains("ray 1"), "{err}");
        scan.rays[1] = Ray::no_return(Vector3::zeros());
        assert!(scan.validate().is_err());
        scan.rays[1] = Ray::hit(Vector3::x()).with_range_sigma_m(-0.1);
        assert!(scan.validate().is_err());
        scan.rays.pop();
        scan.origin_in_world.x = f64::INFINITY;
        assert!(scan.validate().is_err());
    }
}
