//! An entry resolved against its preset, step by step: the preset, the keys that apply to the kind, the rate
//! and ranges, the beams, the noise. Every value is checked; the first bad one is an error naming its key.

use super::presets::{PRESETS, Preset, preset_names};
use super::spec::{BeamPattern, MAX_RATE_HZ, MAX_RAYS_PER_SCAN, Noise, RangeNoise, SensorSpec};
use super::{SensorKind, SensorMount};

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

/// `v` when it is finite and positive.
fn positive(v: f64, key: &'static str, what: &str) -> Result<f64, SpecError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(err(&[key], format!("expected a positive {what}, got {v}")))
    }
}

/// A noise probability (absent: 0) when it lies in [0, 1].
fn probability(v: Option<f64>, key: &'static str) -> Result<f64, SpecError> {
    let v = v.unwrap_or(0.0);
    if v.is_finite() && (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(err(
            &["noise", key],
            format!("expected a probability in [0, 1], got {v}"),
        ))
    }
}

/// A noise magnitude when it is finite and not negative.
fn non_negative(v: f64, key: &'static str) -> Result<f64, SpecError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(err(&["noise", key], format!("expected a value >= 0, got {v}")))
    }
}

impl SensorMount {
    /// Resolves the entry against its preset and checks every value.
    ///
    /// # Errors
    /// The first bad value, with its key.
    pub fn resolve(&self) -> Result<SensorSpec, SpecError> {
        let preset = self.preset_entry()?;
        self.check_keys_apply()?;
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
        let beams = match self.kind {
            SensorKind::Laser2d => self.fan(preset)?,
            SensorKind::Lidar3d => self.sweep(preset)?,
            SensorKind::Stereo | SensorKind::DepthCamera => self.pinhole(preset)?,
        };
        let noise = self.noise(preset, &beams)?;
        Ok(SensorSpec {
            name: self.name.clone(),
            kind: self.kind,
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

    /// The named preset, or the kind's first; it must be of the entry's kind.
    fn preset_entry(&self) -> Result<&'static Preset, SpecError> {
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
        Ok(preset)
    }

    /// Refuses keys the file gives that do not apply to the kind (a `baseline_m` on a laser).
    fn check_keys_apply(&self) -> Result<(), SpecError> {
        let kind = self.kind;
        let is_laser = matches!(kind, SensorKind::Laser2d | SensorKind::Lidar3d);
        let is_camera = matches!(kind, SensorKind::Stereo | SensorKind::DepthCamera);
        let keys: [(&'static str, bool, bool); 8] = [
            ("fov_deg", self.fov_deg.is_some(), is_laser),
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
        for (key, given, applies) in keys {
            if given && !applies {
                return Err(err(&[key], format!("does not apply to a {} sensor", kind.name())));
            }
        }
        let n = &self.noise;
        let noise_keys: [(&'static str, bool, bool); 5] = [
            ("range_sigma_m", n.range_sigma_m.is_some(), is_laser),
            ("range_sigma_per_m", n.range_sigma_per_m.is_some(), is_laser),
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
        for (key, given, applies) in noise_keys {
            if given && !applies {
                return Err(err(
                    &["noise", key],
                    format!("does not apply to a {} sensor", kind.name()),
                ));
            }
        }
        Ok(())
    }

    /// A 2D laser's fan.
    fn fan(&self, preset: &Preset) -> Result<BeamPattern, SpecError> {
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
        Ok(BeamPattern::Fan {
            fov_rad: fov.to_radians(),
            step_rad: step.to_radians(),
        })
    }

    /// A 3D lidar's channels swept in azimuth.
    fn sweep(&self, preset: &Preset) -> Result<BeamPattern, SpecError> {
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
        Ok(BeamPattern::Sweep {
            elevations_rad: angles.iter().map(|a| a.to_radians()).collect(),
            fov_rad: fov.to_radians(),
            step_rad: step.to_radians(),
        })
    }

    /// A camera's pixel grid, within [`MAX_RAYS_PER_SCAN`].
    fn pinhole(&self, preset: &Preset) -> Result<BeamPattern, SpecError> {
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
        Ok(pattern)
    }

    /// The noise: the kind's range error model, then the effects every kind shares.
    fn noise(&self, preset: &Preset, beams: &BeamPattern) -> Result<Noise, SpecError> {
        let n = &self.noise;
        let range = match self.kind {
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
        Ok(Noise {
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
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::sensors::NoiseSettings;

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
