//! A sensor resolved from its entry and preset: everything the simulation needs, checked.

use super::SensorKind;

/// Beam geometry of a resolved sensor.
#[derive(Debug, Clone, PartialEq)]
pub enum BeamPattern {
    /// A fan in the sensor's x-y plane.
    Fan {
        /// Field of view, radians.
        fov_rad: f64,
        /// Angle between beams, radians.
        step_rad: f64,
    },
    /// Channels swept in azimuth.
    Sweep {
        /// Elevations, radians.
        elevations_rad: Vec<f64>,
        /// Azimuth coverage, radians.
        fov_rad: f64,
        /// Azimuth step, radians.
        step_rad: f64,
    },
    /// A pinhole camera looking along the sensor's +x.
    Pinhole {
        /// Image width, pixels.
        width_px: u32,
        /// Image height, pixels.
        height_px: u32,
        /// Focal length, pixels.
        focal_px: f64,
        /// Pixel stride.
        stride: u32,
    },
}

impl BeamPattern {
    /// Whether a sweep covers the full circle (then it does not repeat its first azimuth).
    pub fn is_full_circle(&self) -> bool {
        matches!(self, Self::Sweep { fov_rad, .. } if (fov_rad - std::f64::consts::TAU).abs() < 1e-9)
    }

    /// Azimuths of a fan or a sweep, from `-fov / 2` (from 0 for a full-circle sweep) every step; 0 for a
    /// camera.
    pub fn num_azimuths(&self) -> usize {
        match self {
            Self::Fan { fov_rad, step_rad }
            | Self::Sweep {
                fov_rad, step_rad, ..
            } => (fov_rad / step_rad + 1e-9).floor() as usize + usize::from(!self.is_full_circle()),
            Self::Pinhole { .. } => 0,
        }
    }

    /// Rays cast per scan ([`crate::sensors::beam_directions`] casts exactly these).
    pub fn rays_per_scan(&self) -> u64 {
        match self {
            Self::Fan { .. } => self.num_azimuths() as u64,
            Self::Sweep { elevations_rad, .. } => (self.num_azimuths() * elevations_rad.len()) as u64,
            Self::Pinhole {
                width_px,
                height_px,
                stride,
                ..
            } => u64::from(width_px.div_ceil(*stride)) * u64::from(height_px.div_ceil(*stride)),
        }
    }
}

impl SensorSpec {
    /// Scans in a run of `duration_s` seconds: one at time 0, then one every `1 / rate_hz`.
    pub fn num_scans(&self, duration_s: f64) -> u64 {
        (duration_s * self.rate_hz + 1e-9).floor() as u64 + 1
    }
}

/// The most rays one scan of any sensor may cast: 10 million (a camera frame of 10 million rays holds about
/// 400 MB while it is cast).
pub const MAX_RAYS_PER_SCAN: u64 = 10_000_000;
/// The highest scan rate, Hz.
pub const MAX_RATE_HZ: f64 = 1_000.0;

/// How the range error grows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RangeNoise {
    /// `sigma = sigma_m + per_m * range` (lasers).
    Linear {
        /// At zero range, metres.
        sigma_m: f64,
        /// Per metre.
        per_m: f64,
    },
    /// Depth error `z^2 sigma_d / (f b)` (stereo), applied along the optical axis.
    Disparity {
        /// `sigma_d / (f b)`, 1/m.
        coefficient_per_m: f64,
    },
    /// Depth error `scale (0.0012 + 0.0019 (z - 0.4)^2)` (structured light).
    Axial {
        /// Scale of the model.
        scale: f64,
    },
}

/// Resolved, checked noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Range (or depth) error.
    pub range: RangeNoise,
    /// Bias standard deviation, metres.
    pub bias_sigma_m: f64,
    /// Dropout probability.
    pub dropout_probability: f64,
    /// Spurious-return probability.
    pub spurious_probability: f64,
    /// Mixed-pixel probability at edges.
    pub mixed_pixel_probability: f64,
    /// Direction error, radians.
    pub angular_jitter_rad: f64,
    /// Hole probability (cameras).
    pub hole_probability: f64,
}

/// A sensor resolved from its entry and preset: everything the simulation needs, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorSpec {
    /// Name.
    pub name: String,
    /// Kind.
    pub kind: SensorKind,
    /// The preset used.
    pub preset: &'static str,
    /// Mount link.
    pub mount_link: String,
    /// Offset from the link, metres.
    pub xyz_m: [f64; 3],
    /// Rotation from the link, radians.
    pub rpy_rad: [f64; 3],
    /// Scans per second.
    pub rate_hz: f64,
    /// Minimum range, metres.
    pub min_range_m: f64,
    /// Maximum range, metres.
    pub max_range_m: f64,
    /// Beam geometry.
    pub beams: BeamPattern,
    /// Noise.
    pub noise: Noise,
}

impl Noise {
    /// The range error (one standard deviation, metres) of a reading at `range_m` along a beam whose
    /// forward component (cosine to the optical axis) is `forward`.
    pub fn range_sigma_m(&self, range_m: f64, forward: f64) -> f64 {
        match self.range {
            RangeNoise::Linear { sigma_m, per_m } => sigma_m + per_m * range_m,
            RangeNoise::Disparity { coefficient_per_m } => {
                let z = range_m * forward;
                coefficient_per_m * z * z / forward.max(1e-6)
            }
            RangeNoise::Axial { scale } => {
                let z = range_m * forward;
                scale * (0.0012 + 0.0019 * (z - 0.4) * (z - 0.4)) / forward.max(1e-6)
            }
        }
    }
}
