//! Sensor entries of a scenario file (`[[sensors]]`): the schema as written, the presets with their sources
//! (`presets`), and their resolution (`resolve`) into a checked [`SensorSpec`] (`spec`).
//!
//! An entry names a kind, a mount and optionally a preset; any parameter written in the file overrides the
//! preset's. Parameters that do not apply to the kind are errors.

mod presets;
mod resolve;
mod spec;

use serde::Deserialize;

pub use presets::preset_names;
pub use resolve::SpecError;
pub use spec::{BeamPattern, MAX_RATE_HZ, MAX_RAYS_PER_SCAN, Noise, RangeNoise, SensorSpec};

/// The kinds of simulated sensor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SensorKind {
    /// A 2D laser scanner: one fan of beams in its x-y plane (tilt it for a push-broom).
    Laser2d,
    /// A multi-beam 3D lidar: channels at fixed elevations, swept in azimuth.
    Lidar3d,
    /// A stereo camera: a pinhole grid of rays, depth noise from disparity noise.
    Stereo,
    /// A structured-light depth camera (Kinect class): a pinhole grid, the Nguyen et al. axial noise model.
    DepthCamera,
}

impl SensorKind {
    /// The name used in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Laser2d => "laser2d",
            Self::Lidar3d => "lidar3d",
            Self::Stereo => "stereo",
            Self::DepthCamera => "depth_camera",
        }
    }
}

/// A sensor entry of a scenario file. Every parameter is optional; missing ones come from the preset (or the
/// kind's default preset).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorMount {
    /// Unique name.
    pub name: String,
    /// What it is.
    pub kind: SensorKind,
    /// The URDF link it is fixed to.
    pub mount_link: String,
    /// Offset from the link, metres (link frame).
    #[serde(default)]
    #[serde(deserialize_with = "crate::scenario::exact::array")]
    pub xyz_m: [f64; 3],
    /// Roll, pitch, yaw from the link, degrees (URDF convention: fixed axes x, then y, then z).
    #[serde(default)]
    #[serde(deserialize_with = "crate::scenario::exact::array")]
    pub rpy_deg: [f64; 3],
    /// A named preset (see `docs/scenario-format.md`); default: the kind's first preset.
    #[serde(default)]
    pub preset: Option<String>,
    /// Scans per second.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// Closer returns are lost (no return), metres.
    #[serde(default)]
    pub min_range_m: Option<f64>,
    /// Farther surfaces give no return, metres.
    #[serde(default)]
    pub max_range_m: Option<f64>,
    /// Laser: field of view of the fan; lidar: azimuth coverage. Degrees.
    #[serde(default)]
    pub fov_deg: Option<f64>,
    /// Laser: angle between beams, degrees.
    #[serde(default)]
    pub step_deg: Option<f64>,
    /// Lidar: elevation of each channel, degrees.
    #[serde(default)]
    pub vertical_angles_deg: Option<Vec<f64>>,
    /// Lidar: azimuth between firings, degrees.
    #[serde(default)]
    pub azimuth_step_deg: Option<f64>,
    /// Cameras: image width and height, pixels.
    #[serde(default)]
    #[serde(deserialize_with = "crate::scenario::exact::option")]
    pub image_size_px: Option<[u32; 2]>,
    /// Cameras: horizontal field of view, degrees (or give `focal_px`).
    #[serde(default)]
    pub hfov_deg: Option<f64>,
    /// Cameras: focal length, pixels (overrides `hfov_deg`).
    #[serde(default)]
    pub focal_px: Option<f64>,
    /// Cameras: cast one ray every `pixel_stride` pixels in each direction (speed).
    #[serde(default)]
    pub pixel_stride: Option<u32>,
    /// Stereo: baseline, metres.
    #[serde(default)]
    pub baseline_m: Option<f64>,
    /// The noise; every kind off when its parameter is 0.
    #[serde(default)]
    pub noise: NoiseSettings,
}

/// Noise settings: each parameter overrides the preset's.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NoiseSettings {
    /// Lasers: range noise standard deviation at zero range, metres.
    pub range_sigma_m: Option<f64>,
    /// Lasers: growth of the range noise per metre of range.
    pub range_sigma_per_m: Option<f64>,
    /// Stereo: disparity noise standard deviation, pixels (`sigma_z = z^2 sigma_d / (f b)`).
    pub disparity_sigma_px: Option<f64>,
    /// Depth camera: scale of the Nguyen axial model `0.0012 + 0.0019 (z - 0.4)^2` m (1 = the model, 0 = off).
    pub axial_noise_scale: Option<f64>,
    /// Standard deviation of a range bias drawn once per sensor, metres.
    pub bias_sigma_m: Option<f64>,
    /// Probability that a beam returns nothing (a no-return reading, never a hit at maximum range).
    pub dropout_probability: Option<f64>,
    /// Probability that a beam returns a false hit at a uniformly random range before the true one.
    pub spurious_probability: Option<f64>,
    /// Probability that a beam at a depth edge returns a mixed range between the two surfaces.
    pub mixed_pixel_probability: Option<f64>,
    /// Standard deviation of the beam direction's error, degrees.
    pub angular_jitter_deg: Option<f64>,
    /// Cameras: probability that a pixel has no depth (matching failed, no texture).
    pub hole_probability: Option<f64>,
}
