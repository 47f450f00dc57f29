//! Sensor settings as written in scenario files, their presets, and their resolution into a checked
//! [`SensorSpec`].
//!
//! A `[[sensors]]` entry names a kind, a mount and optionally a preset; any parameter written in the file
//! overrides the preset's. Parameters that do not apply to the kind are errors.

use serde::Deserialize;

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

/// A preset's values: the same fields as a file entry, all given.
struct Preset {
    name: &'static str,
    kind: SensorKind,
    rate_hz: f64,
    min_range_m: f64,
    max_range_m: f64,
    fov_deg: f64,
    step_deg: f64,
    vertical_angles_deg: &'static [f64],
    image_size_px: [u32; 2],
    hfov_deg: f64,
    pixel_stride: u32,
    baseline_m: f64,
    range_sigma_m: f64,
    disparity_sigma_px: f64,
    hole_probability: f64,
}

const VLP16_ANGLES: [f64; 16] = [
    -15.0, -13.0, -11.0, -9.0, -7.0, -5.0, -3.0, -1.0, 1.0, 3.0, 5.0, 7.0, 9.0, 11.0, 13.0, 15.0,
];

const BASE: Preset = Preset {
    name: "",
    kind: SensorKind::Laser2d,
    rate_hz: 10.0,
    min_range_m: 0.1,
    max_range_m: 80.0,
    fov_deg: 180.0,
    step_deg: 0.5,
    vertical_angles_deg: &[],
    image_size_px: [0, 0],
    hfov_deg: 60.0,
    pixel_stride: 1,
    baseline_m: 0.12,
    range_sigma_m: 0.0,
    disparity_sigma_px: 0.0,
    hole_probability: 0.0,
};

/// Every preset, the kind's default first. Sources: SICK LMS 291 and LMS1xx datasheets (180 degrees, 0.25/0.5/1
/// degree steps, up to 75 Hz, 80 m, statistical error 12 mm), Velodyne VLP-16 (16 channels, 2 degrees apart
/// over +-15 degrees, 0.2 degree azimuth step at 10 Hz, 100 m, +-3 cm), the paper's simple stereo rig (Fig. 4:
/// depth error 0.032 m at 1 m), Kinect v1 (640 x 480, 57 degrees, 0.5 to 4.5 m).
const PRESETS: &[Preset] = &[
    Preset {
        name: "sick_lms291",
        kind: SensorKind::Laser2d,
        rate_hz: 75.0,
        range_sigma_m: 0.012,
        ..BASE
    },
    // The paper's data set (section 6.2): LMS 291-S14 scanners sweeping 90 degrees.
    Preset {
        name: "sick_lms291_90",
        kind: SensorKind::Laser2d,
        rate_hz: 75.0,
        fov_deg: 90.0,
        range_sigma_m: 0.012,
        ..BASE
    },
    Preset {
        name: "vlp16",
        kind: SensorKind::Lidar3d,
        rate_hz: 10.0,
        min_range_m: 0.5,
        max_range_m: 100.0,
        fov_deg: 360.0,
        step_deg: 0.2,
        vertical_angles_deg: &VLP16_ANGLES,
        range_sigma_m: 0.03,
        ..BASE
    },
    // A cheap rig: 320 x 240, 12 cm baseline, focal 240 px; a 0.92 px disparity error gives the paper's
    // 0.032 z^2 m depth error.
    Preset {
        name: "paper_stereo",
        kind: SensorKind::Stereo,
        rate_hz: 5.0,
        min_range_m: 0.3,
        max_range_m: 8.0,
        image_size_px: [320, 240],
        hfov_deg: 67.38,
        pixel_stride: 2,
        baseline_m: 0.12,
        disparity_sigma_px: 0.9216,
        hole_probability: 0.05,
        ..BASE
    },
    // A good matcher: 0.1 px.
    Preset {
        name: "stereo_vga",
        kind: SensorKind::Stereo,
        rate_hz: 10.0,
        min_range_m: 0.3,
        max_range_m: 15.0,
        image_size_px: [640, 480],
        hfov_deg: 66.0,
        pixel_stride: 4,
        baseline_m: 0.12,
        disparity_sigma_px: 0.1,
        hole_probability: 0.02,
        ..BASE
    },
    Preset {
        name: "kinect_like",
        kind: SensorKind::DepthCamera,
        rate_hz: 10.0,
        min_range_m: 0.5,
        max_range_m: 4.5,
        image_size_px: [640, 480],
        hfov_deg: 57.0,
        pixel_stride: 4,
        hole_probability: 0.02,
        ..BASE
    },
];

/// The names of the presets of `kind`, default first.
pub fn preset_names(kind: SensorKind) -> Vec<&'static str> {
    PRESETS
        .iter()
        .filter(|p| p.kind == kind)
        .map(|p| p.name)
        .collect()
}

/// A problem with a sensor entry: the key (relative to the entry) and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecError {
    /// Key path inside the entry (`["noise", "dropout_probability"]`).
    pub key: Vec<&'static str>,
    /// What is wrong and what was expected.
    pub message: String,
}

fn err(key: &[&'static str], message: String) -> SpecError {
    SpecError {
        key: key.to_vec(),
        message,
    }
}

impl SensorMount {
    /// Resolves the entry against its preset and checks every value.
    ///
    /// # Errors
    /// The first bad value, with its key.
    pub fn resolve(&self) -> Result<SensorSpec, SpecError> {
        let kind = self.kind;
        let preset = match &self.preset {
            None => PRESETS.iter().find(|p| p.kind == kind),
            Some(name) => PRESETS.iter().find(|p| p.name == name),
        }
        .ok_or_else(|| {
            err(
                &["preset"],
                format!(
                    "unknown preset; presets for {}: {}",
                    kind.name(),
                    preset_names(kind).join(", ")
                ),
            )
        })?;
        if preset.kind != kind {
            return Err(err(
                &["preset"],
                format!(
                    "preset `{}` is a {}, not a {}",
                    preset.name,
                    preset.kind.name(),
                    kind.name()
                ),
            ));
        }
        // Keys that do not apply to the kind.
        let is_camera = matches!(kind, SensorKind::Stereo | SensorKind::DepthCamera);
        let foreign: [(&'static str, bool, bool); 8] = [
            (
                "fov_deg",
                self.fov_deg.is_some(),
                matches!(kind, SensorKind::Laser2d | SensorKind::Lidar3d),
            ),
            ("step_deg", self.step_deg.is_some(), kind == SensorKind::Laser2d),
            (
                "vertical_angles_deg",
                self.vertical_angles_deg.is_some(),
                kind == SensorKind::Lidar3d,
            ),
            (
                "azimuth_step_deg",
                self.azimuth_step_deg.is_some(),
                kind == SensorKind::Lidar3d,
            ),
            ("image_size_px", self.image_size_px.is_some(), is_camera),
            (
                "hfov_deg",
                self.hfov_deg.is_some() || self.focal_px.is_some(),
                is_camera,
            ),
            ("pixel_stride", self.pixel_stride.is_some(), is_camera),
            (
                "baseline_m",
                self.baseline_m.is_some(),
                kind == SensorKind::Stereo,
            ),
        ];
        for (key, given, applies) in foreign {
            if given && !applies {
                return Err(err(&[key], format!("does not apply to a {} sensor", kind.name())));
            }
        }
        let n = &self.noise;
        let noise_foreign: [(&'static str, bool, bool); 5] = [
            (
                "range_sigma_m",
                n.range_sigma_m.is_some(),
                matches!(kind, SensorKind::Laser2d | SensorKind::Lidar3d),
            ),
            (
                "range_sigma_per_m",
                n.range_sigma_per_m.is_some(),
                matches!(kind, SensorKind::Laser2d | SensorKind::Lidar3d),
            ),
            (
                "disparity_sigma_px",
                n.disparity_sigma_px.is_some(),
                kind == SensorKind::Stereo,
            ),
            (
                "axial_noise_scale",
                n.axial_noise_scale.is_some(),
                kind == SensorKind::DepthCamera,
            ),
            ("hole_probability", n.hole_probability.is_some(), is_camera),
        ];
        for (key, given, applies) in noise_foreign {
            if given && !applies {
                return Err(err(
                    &["noise", key],
                    format!("does not apply to a {} sensor", kind.name()),
                ));
            }
        }

        let positive = |v: f64, key: &'static str, what: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(err(&[key], format!("expected a positive {what}, got {v}")))
            }
        };
        let rate_hz = positive(self.rate_hz.unwrap_or(preset.rate_hz), "rate_hz", "rate in Hz")?;
        if rate_hz > MAX_RATE_HZ {
            return Err(err(
                &["rate_hz"],
                format!("expected a rate up to {MAX_RATE_HZ} Hz, got {rate_hz}"),
            ));
        }
        let max_range_m = positive(
            self.max_range_m.unwrap_or(preset.max_range_m),
            "max_range_m",
            "range in metres",
        )?;
        let min_range_m = self.min_range_m.unwrap_or(preset.min_range_m);
        if !(min_range_m.is_finite() && min_range_m >= 0.0 && min_range_m < max_range_m) {
            return Err(err(
                &["min_range_m"],
                format!("expected a range >= 0 and below max_range_m {max_range_m}, got {min_range_m}"),
            ));
        }
        let beams = match kind {
            SensorKind::Laser2d => {
                let fov = self.fov_deg.unwrap_or(preset.fov_deg);
                if !(fov.is_finite() && fov > 0.0 && fov <= 360.0) {
                    return Err(err(
                        &["fov_deg"],
                        format!("expected a field of view in (0, 360] degrees, got {fov}"),
                    ));
                }
                let step = positive(
                    self.step_deg.unwrap_or(preset.step_deg),
                    "step_deg",
                    "angle in degrees",
                )?;
                if fov / step > 100_000.0 {
                    return Err(err(
                        &["step_deg"],
                        format!("{fov} / {step} gives more than 100000 beams"),
                    ));
                }
                BeamPattern::Fan {
                    fov_rad: fov.to_radians(),
                    step_rad: step.to_radians(),
                }
            }
            SensorKind::Lidar3d => {
                let fov = self.fov_deg.unwrap_or(preset.fov_deg);
                if !(fov.is_finite() && fov > 0.0 && fov <= 360.0) {
                    return Err(err(
                        &["fov_deg"],
                        format!("expected an azimuth coverage in (0, 360] degrees, got {fov}"),
                    ));
                }
                let step = positive(
                    self.azimuth_step_deg.unwrap_or(preset.step_deg),
                    "azimuth_step_deg",
                    "angle in degrees",
                )?;
                let angles = self
                    .vertical_angles_deg
                    .clone()
                    .unwrap_or_else(|| preset.vertical_angles_deg.to_vec());
                if angles.is_empty()
                    || angles.len() > 1024
                    || angles.iter().any(|a| !(a.is_finite() && a.abs() <= 90.0))
                {
                    return Err(err(
                        &["vertical_angles_deg"],
                        "expected 1 to 1024 elevations within [-90, 90] degrees".into(),
                    ));
                }
                if fov / step * angles.len() as f64 > 10_000_000.0 {
                    return Err(err(
                        &["azimuth_step_deg"],
                        "more than 10 million beams per scan".into(),
                    ));
                }
                BeamPattern::Sweep {
                    elevations_rad: angles.iter().map(|a| a.to_radians()).collect(),
                    fov_rad: fov.to_radians(),
                    step_rad: step.to_radians(),
                }
            }
            SensorKind::Stereo | SensorKind::DepthCamera => {
                let [w, h] = self.image_size_px.unwrap_or(preset.image_size_px);
                if !(1..=20_000).contains(&w) || !(1..=20_000).contains(&h) {
                    return Err(err(
                        &["image_size_px"],
                        format!("expected 1 to 20000 pixels per side, got [{w}, {h}]"),
                    ));
                }
                let focal_px = match (self.focal_px, self.hfov_deg) {
                    (Some(f), _) => positive(f, "focal_px", "focal length in pixels")?,
                    (None, hfov) => {
                        let hfov = hfov.unwrap_or(preset.hfov_deg);
                        if !(hfov.is_finite() && hfov > 0.0 && hfov < 180.0) {
                            return Err(err(
                                &["hfov_deg"],
                                format!("expected a field of view in (0, 180) degrees, got {hfov}"),
                            ));
                        }
                        f64::from(w) / 2.0 / (hfov.to_radians() / 2.0).tan()
                    }
                };
                let stride = self.pixel_stride.unwrap_or(preset.pixel_stride);
                if stride == 0 || stride > w.max(h) {
                    return Err(err(
                        &["pixel_stride"],
                        format!("expected 1 to {} pixels, got {stride}", w.max(h)),
                    ));
                }
                let pattern = BeamPattern::Pinhole {
                    width_px: w,
                    height_px: h,
                    focal_px,
                    stride,
                };
                if pattern.rays_per_scan() > MAX_RAYS_PER_SCAN {
                    return Err(err(
                        &["pixel_stride"],
                        format!(
                            "a {w} x {h} image at stride {stride} casts {} rays per frame, over the limit of \
                             {MAX_RAYS_PER_SCAN}; use a larger stride or a smaller image",
                            pattern.rays_per_scan()
                        ),
                    ));
                }
                pattern
            }
        };
        let probability = |v: Option<f64>, key: &'static str| {
            let v = v.unwrap_or(0.0);
            if v.is_finite() && (0.0..=1.0).contains(&v) {
                Ok(v)
            } else {
                Err(err(
                    &["noise", key],
                    format!("expected a probability in [0, 1], got {v}"),
                ))
            }
        };
        let non_negative = |v: f64, key: &'static str| {
            if v.is_finite() && v >= 0.0 {
                Ok(v)
            } else {
                Err(err(&["noise", key], format!("expected a value >= 0, got {v}")))
            }
        };
        let range = match kind {
            SensorKind::Laser2d | SensorKind::Lidar3d => RangeNoise::Linear {
                sigma_m: non_negative(n.range_sigma_m.unwrap_or(preset.range_sigma_m), "range_sigma_m")?,
                per_m: non_negative(n.range_sigma_per_m.unwrap_or(0.0), "range_sigma_per_m")?,
            },
            SensorKind::Stereo => {
                let sigma_d = non_negative(
                    n.disparity_sigma_px.unwrap_or(preset.disparity_sigma_px),
                    "disparity_sigma_px",
                )?;
                let baseline = positive(
                    self.baseline_m.unwrap_or(preset.baseline_m),
                    "baseline_m",
                    "baseline in metres",
                )?;
                let BeamPattern::Pinhole { focal_px, .. } = beams else {
                    unreachable!("cameras have pinhole beams")
                };
                RangeNoise::Disparity {
                    coefficient_per_m: sigma_d / (focal_px * baseline),
                }
            }
            SensorKind::DepthCamera => RangeNoise::Axial {
                scale: non_negative(n.axial_noise_scale.unwrap_or(1.0), "axial_noise_scale")?,
            },
        };
        let noise = Noise {
            range,
            bias_sigma_m: non_negative(n.bias_sigma_m.unwrap_or(0.0), "bias_sigma_m")?,
            dropout_probability: probability(n.dropout_probability, "dropout_probability")?,
            spurious_probability: probability(n.spurious_probability, "spurious_probability")?,
            mixed_pixel_probability: probability(n.mixed_pixel_probability, "mixed_pixel_probability")?,
            angular_jitter_rad: non_negative(n.angular_jitter_deg.unwrap_or(0.0), "angular_jitter_deg")?
                .to_radians(),
            hole_probability: probability(
                n.hole_probability.or(Some(preset.hole_probability)),
                "hole_probability",
            )?,
        };
        Ok(SensorSpec {
            name: self.name.clone(),
            kind,
            preset: preset.name,
            mount_link: self.mount_link.clone(),
            xyz_m: self.xyz_m,
            rpy_rad: self.rpy_deg.map(f64::to_radians),
            rate_hz,
            min_range_m,
            max_range_m,
            beams,
            noise,
        })
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn mount(kind: SensorKind) -> SensorMount {
        SensorMount {
            name: "s".into(),
            kind,
            mount_link: "base_link".into(),
            xyz_m: [0.0; 3],
            rpy_deg: [0.0; 3],
            preset: None,
            rate_hz: None,
            min_range_m: None,
            max_range_m: None,
            fov_deg: None,
            step_deg: None,
            vertical_angles_deg: None,
            azimuth_step_deg: None,
            image_size_px: None,
            hfov_deg: None,
            focal_px: None,
            pixel_stride: None,
            baseline_m: None,
            noise: NoiseSettings::default(),
        }
    }

    #[test]
    fn presets_fill_what_the_file_leaves_out() {
        let spec = mount(SensorKind::Laser2d).resolve().expect("valid");
        assert_eq!(spec.preset, "sick_lms291");
        assert_eq!(spec.rate_hz, 75.0);
        assert!(
            matches!(spec.beams, BeamPattern::Fan { fov_rad, .. } if (fov_rad - std::f64::consts::PI).abs() < 1e-12)
        );
        let spec = SensorMount {
            preset: Some("vlp16".into()),
            ..mount(SensorKind::Lidar3d)
        }
        .resolve()
        .expect("valid");
        assert!(
            matches!(&spec.beams, BeamPattern::Sweep { elevations_rad, .. } if elevations_rad.len() == 16)
        );
    }

    #[test]
    fn the_paper_stereo_preset_gives_the_papers_depth_error() {
        let spec = SensorMount {
            preset: Some("paper_stereo".into()),
            ..mount(SensorKind::Stereo)
        }
        .resolve()
        .expect("valid");
        // On the optical axis: 0.032 z^2.
        for z in [1.0, 2.0, 3.0] {
            let s = spec.noise.range_sigma_m(z, 1.0);
            assert!((s - 0.032 * z * z).abs() < 2e-4, "{z}: {s}");
        }
    }

    #[test]
    fn bad_settings_are_errors_with_their_key() {
        let bad = SensorMount {
            fov_deg: Some(-10.0),
            ..mount(SensorKind::Laser2d)
        }
        .resolve()
        .expect_err("fov");
        assert_eq!(bad.key, vec!["fov_deg"]);
        let bad = SensorMount {
            step_deg: Some(0.0),
            ..mount(SensorKind::Laser2d)
        }
        .resolve()
        .expect_err("step");
        assert_eq!(bad.key, vec!["step_deg"]);
        let noise = NoiseSettings {
            range_sigma_m: Some(f64::NAN),
            ..NoiseSettings::default()
        };
        let bad = SensorMount {
            noise,
            ..mount(SensorKind::Laser2d)
        }
        .resolve()
        .expect_err("nan");
        assert_eq!(bad.key, vec!["noise", "range_sigma_m"]);
        let noise = NoiseSettings {
            dropout_probability: Some(1.5),
            ..NoiseSettings::default()
        };
        let bad = SensorMount {
            noise,
            ..mount(SensorKind::Laser2d)
        }
        .resolve()
        .expect_err("probability");
        assert_eq!(bad.key, vec!["noise", "dropout_probability"]);
        let bad = SensorMount {
            baseline_m: Some(0.1),
            ..mount(SensorKind::Laser2d)
        }
        .resolve()
        .expect_err("foreign");
        assert!(bad.message.contains("does not apply to a laser2d"), "{bad:?}");
        let bad = SensorMount {
            preset: Some("vlp16".into()),
            ..mount(SensorKind::Stereo)
        }
        .resolve()
        .expect_err("kind");
        assert!(bad.message.contains("is a lidar3d"), "{bad:?}");
        let bad = SensorMount {
            preset: Some("nope".into()),
            ..mount(SensorKind::Stereo)
        }
        .resolve()
        .expect_err("unknown");
        assert!(bad.message.contains("paper_stereo"), "{bad:?}");
    }
}
