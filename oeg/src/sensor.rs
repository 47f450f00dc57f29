//! Range-dependent measurement error of the sensors the map knows: the `dl` of eq. 10 and the `sigma_t` of the
//! elevation measurement (section 4.2).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Default statistical range error of a laser scanner, metres: SICK's LMS1xx datasheet gives 12 mm.
pub const DEFAULT_LASER_SIGMA_M: f32 = 0.012;
/// Default coefficient `c` of the stereo model `sigma = c * l^2`, 1/m: the paper's Fig. 4 (0.032, 0.13 and 0.28 m
/// at 1, 2 and 3 m).
pub const DEFAULT_STEREO_COEFFICIENT_PER_M: f32 = 0.032;
/// Default maximum range of a sensor when none is given, metres (the SICK LMS 291's 80 m).
pub const DEFAULT_MAX_RANGE_M: f32 = 80.0;

/// How a sensor's range error grows with the measured range `l`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RangeNoiseModel {
    /// A laser range finder: `sigma(l) = sigma_m + sigma_per_m * l`.
    Laser {
        /// Range error at zero range, metres.
        sigma_m: f32,
        /// Growth of the range error per metre of range.
        sigma_per_m: f32,
    },
    /// A stereo camera: `sigma(l) = coefficient_per_m * l^2` (depth error grows with the square of depth).
    Stereo {
        /// The coefficient `c`, 1/m.
        coefficient_per_m: f32,
    },
}

impl RangeNoiseModel {
    /// A laser scanner with the SICK-class default error and no growth with range.
    pub const fn laser() -> Self {
        Self::Laser {
            sigma_m: DEFAULT_LASER_SIGMA_M,
            sigma_per_m: 0.0,
        }
    }

    /// The paper's stereo rig (Fig. 4).
    pub const fn stereo() -> Self {
        Self::Stereo {
            coefficient_per_m: DEFAULT_STEREO_COEFFICIENT_PER_M,
        }
    }

    /// The range error (one standard deviation, metres) of a reading at range `range_m`.
    pub fn sigma_m(&self, range_m: f32) -> f32 {
        match *self {
            Self::Laser { sigma_m, sigma_per_m } => sigma_m + sigma_per_m * range_m,
            Self::Stereo { coefficient_per_m } => coefficient_per_m * range_m * range_m,
        }
    }
}

/// Smallest range error the map uses, metres: keeps eq. 10 and the Kalman gain finite for a reading at (almost)
/// zero range or a model with zero error.
pub const MIN_RANGE_SIGMA_M: f32 = 1e-3;

/// What the map needs to know about the sensor that produced a scan.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorModel {
    /// The range error model, used for rays that carry no error of their own.
    pub noise: RangeNoiseModel,
    /// The sensor's maximum range, metres: how far a no-return ray clears by default.
    pub max_range_m: f32,
}

impl SensorModel {
    /// A laser scanner with the default error and range.
    pub const fn laser() -> Self {
        Self {
            noise: RangeNoiseModel::laser(),
            max_range_m: DEFAULT_MAX_RANGE_M,
        }
    }

    /// The paper's stereo camera with a 10 m maximum depth.
    pub const fn stereo() -> Self {
        Self {
            noise: RangeNoiseModel::stereo(),
            max_range_m: 10.0,
        }
    }

    /// The range error used by the map for a reading at `range_m`, never below [`MIN_RANGE_SIGMA_M`].
    pub fn sigma_m(&self, range_m: f32) -> f32 {
        self.noise.sigma_m(range_m).max(MIN_RANGE_SIGMA_M)
    }

    /// Checks the parameters for sense.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the bad parameter.
    pub fn validate(&self) -> Result<()> {
        let ok = |v: f32| v.is_finite() && v >= 0.0;
        match self.noise {
            RangeNoiseModel::Laser { sigma_m, sigma_per_m } if !ok(sigma_m) || !ok(sigma_per_m) => {
                return Err(Error::setting(
                    "sensor.noise",
                    format!("laser sigma_m and sigma_per_m must be >= 0, got {sigma_m} and {sigma_per_m}"),
                ));
            }
            RangeNoiseModel::Stereo { coefficient_per_m } if !ok(coefficient_per_m) => {
                return Err(Error::setting(
                    "sensor.noise",
                    format!("stereo coefficient_per_m must be >= 0, got {coefficient_per_m}"),
                ));
            }
            _ => {}
        }
        if !(self.max_range_m.is_finite() && self.max_range_m > 0.0) {
            return Err(Error::setting(
                "sensor.max_range_m",
                format!("must be a positive range in metres, got {}", self.max_range_m),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stereo_default_reproduces_the_papers_figure_4() {
        let m = RangeNoiseModel::stereo();
        for (l, expected) in [(1.0, 0.032), (2.0, 0.128), (3.0, 0.288)] {
            assert!((m.sigma_m(l) - expected).abs() < 1e-6);
        }
        // The paper quotes 0.13 and 0.28 m, rounded.
        assert!((m.sigma_m(2.0) - 0.13).abs() < 0.005 && (m.sigma_m(3.0) - 0.28).abs() < 0.01);
    }

    #[test]
    fn laser_error_grows_linearly() {
        let m = RangeNoiseModel::Laser {
            sigma_m: 0.01,
            sigma_per_m: 0.002,
        };
        assert!((m.sigma_m(10.0) - 0.03).abs() < 1e-6);
    }

    #[test]
    fn the_error_has_a_floor() {
        assert_eq!(SensorModel::stereo().sigma_m(0.0), MIN_RANGE_SIGMA_M);
    }

    #[test]
    fn bad_parameters_are_rejected() {
        let bad = SensorModel {
            noise: RangeNoiseModel::Stereo {
                coefficient_per_m: f32::NAN,
            },
            max_range_m: 5.0,
        };
        assert!(bad.validate().is_err());
        let bad = SensorModel {
            max_range_m: 0.0,
            ..SensorModel::laser()
        };
        assert!(bad.validate().is_err());
        assert!(SensorModel::laser().validate().is_ok());
    }
}
