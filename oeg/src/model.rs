//! The OEG update rules (paper sections 3 and 4) as small pure functions, and the options that parameterise
//! them.
//!
//! Each function names the equation it implements. [`crate::Map::integrate`] strings them together as the
//! paper's Algorithm 1 does.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Default lower log-odds bound `L_min` (eq. 7): OctoMap's `clamping_thres_min` of 0.1192.
pub const DEFAULT_LOG_ODDS_MIN: f32 = -2.0;
/// Default upper log-odds bound `L_max` (eq. 7): OctoMap's `clamping_thres_max` of 0.971.
pub const DEFAULT_LOG_ODDS_MAX: f32 = 3.5;
/// Default occupancy threshold: a cell is occupied when `P(L)` exceeds it (OctoMap's default).
pub const DEFAULT_OCCUPIED_THRESHOLD: f32 = 0.5;
/// Default significance `k` of one measurement in eq. 10, in metres. Chosen so that a hit with a 3 cm range
/// error peaks at `p` = 0.9 and one with a 30 cm error (stereo at 3 m) at about 0.54: far, noisy readings count
/// less, as in the paper's Fig. 3.
pub const DEFAULT_SIGNIFICANCE_K_M: f32 = 0.03;
/// Default `p_min` of eq. 11, the occupancy probability of a sample the beam passed through (OctoMap's
/// `prob_miss` of 0.4).
pub const DEFAULT_P_MIN: f32 = 0.4;
/// Default upper clamp of eq. 10's result, which exceeds 1 for small range errors. 0.9 lets two confident hits
/// saturate `L_max`, close to OctoMap's `prob_hit` of 0.7 per hit.
pub const DEFAULT_P_MAX: f32 = 0.9;
/// Default `l_occ` of eq. 12: a sample is an elevation measurement when its `p` exceeds this.
pub const DEFAULT_ELEVATION_THRESHOLD: f32 = 0.5;
/// The inverse sensor model's Gaussian is evaluated within this many range errors of the hit; beyond it the
/// exponential is below 1.2 % and the sample takes `p_occ(l)`. Cells beyond `l_p + 3 dl` are not touched.
pub const GAUSSIAN_CUTOFF_SIGMAS: f32 = 3.0;

/// What a sample the beam passed through (not near the hit) says about a cell's elevation: eq. 12's "otherwise"
/// branch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FreeSpaceElevation {
    /// The paper: a free sample is the measurement `h = 0` (flat ground), fused like any other. When a scan turns
    /// an occupied cell free, the obstacle's elevation history is dropped first, so the cell restarts from the
    /// ground (the paper's Fig. 6: the elevation follows the occupancy once a person has left).
    #[default]
    Zero,
    /// A free sample leaves the elevation alone.
    Skip,
    /// A free sample at height `z` bounds the elevation from above: the beam passed there, so nothing stands
    /// higher. `mu` is lowered to at most `z` (the beam's highest point inside the cell, the conservative choice);
    /// the variance is kept.
    RayBound,
}

/// How an elevation measurement of a hit is fused with the cell's estimate.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ElevationFusion {
    /// The paper: every measurement is fused by eq. 8 and 9.
    #[default]
    Kalman,
    /// As elevation_mapping (Fankhauser et al.): a measurement more than `mahalanobis_threshold` standard
    /// deviations above the estimate is a higher surface and replaces it; one as far below is a lower surface
    /// (the ground under a board, the foot of a curb's face) and is ignored, but raises the variance by
    /// `multi_height_noise_m2` so that a surface that is really gone (a person who left) is eventually replaced
    /// by what is below it; others are fused by eq. 8 and 9. "The elevation is computed considering the higher
    /// point of the obstacle", across scans as within one.
    HighestSurface {
        /// Threshold in standard deviations of the difference (`sqrt(sigma^2 + s^2)`).
        mahalanobis_threshold: f32,
        /// A measurement this many standard deviations below the estimate is already a lower surface; `None`:
        /// `mahalanobis_threshold`. A smaller value keeps a cell at its highest surface when most of its hits
        /// lie lower (a push-broom laser climbing a curb's face, whose hits fall in the curb's first cells),
        /// at the price of a slight upward bias from noise.
        #[serde(default)]
        lower_threshold: Option<f32>,
        /// Variance added for each ignored lower measurement, m^2 (elevation_mapping's `multi_height_noise`).
        #[serde(default)]
        multi_height_noise_m2: f32,
    },
}

/// Fuses the elevation measurement `h` (variance `s2`) into `prior` under `rule` (see [`ElevationFusion`]).
pub fn fuse_elevation(
    rule: ElevationFusion,
    prior: Option<Elevation>,
    h_m: f32,
    s2_m2: f32,
    process_noise_var_m2: f32,
) -> Elevation {
    match (rule, prior) {
        (
            ElevationFusion::HighestSurface {
                mahalanobis_threshold,
                lower_threshold,
                multi_height_noise_m2,
            },
            Some(e),
        ) => {
            let spread = (e.var_m2 + process_noise_var_m2 + s2_m2).sqrt();
            if h_m - e.mean_m > mahalanobis_threshold * spread {
                Elevation {
                    mean_m: h_m,
                    var_m2: s2_m2,
                }
            } else if e.mean_m - h_m > lower_threshold.unwrap_or(mahalanobis_threshold) * spread {
                Elevation {
                    mean_m: e.mean_m,
                    var_m2: e.var_m2 + multi_height_noise_m2,
                }
            } else {
                kalman_fuse(prior, h_m, s2_m2, process_noise_var_m2)
            }
        }
        _ => kalman_fuse(prior, h_m, s2_m2, process_noise_var_m2),
    }
}

/// Which of one scan's hits in a cell make its elevation measurement (eq. 12's `z`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScanHitElevation {
    /// The paper (section 4: "the elevation is computed considering the higher point of the obstacle"): the
    /// highest hit of the scan, with its variance. Exact for a precise laser; with many noisy hits in a cell
    /// (a stereo camera's pixels) the highest is biased upwards by about two standard deviations.
    #[default]
    Highest,
    /// Every hit is an independent measurement, as elevation_mapping fuses each point: the scan's
    /// measurement is the hits' inverse-variance weighted mean, with variance `1 / sum(1 / s_i^2)`
    /// (sequential Kalman updates with the same result). Noise no longer biases it upwards; a cell that spans an
    /// obstacle's edge gets a height between its top and the ground.
    WeightedMean,
}

impl ScanHitElevation {
    /// Adds the hit `(z_m, var_m2)` to the scan's measurement `(z, var)` of a cell (`z = -inf`,
    /// `var = +inf` before the first hit).
    #[inline(always)]
    pub fn combine(self, (z, var): (f32, f32), z_m: f32, var_m2: f32) -> (f32, f32) {
        match self {
            Self::Highest => {
                if z_m > z {
                    (z_m, var_m2)
                } else {
                    (z, var)
                }
            }
            Self::WeightedMean => {
                if z == f32::NEG_INFINITY {
                    (z_m, var_m2)
                } else {
                    // One Kalman step with gain var / (var + var_m2).
                    let k = var / (var + var_m2);
                    (z + k * (z_m - z), var * var_m2 / (var + var_m2))
                }
            }
        }
    }
}

/// Whether a sample the beam passed through lowers a cell's occupancy (eq. 10's `p_min` branch).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FreeSpaceOccupancy {
    /// The paper: every free sample is evidence that the cell is free, at whatever height the beam passed.
    /// In a 2.5D cell this lets a beam passing high over a low obstacle (a push-broom laser's beams over a
    /// curb it saw a moment ago) erase it.
    #[default]
    Always,
    /// A free sample counts only where the beam passed no higher than the cell's elevation estimate (its
    /// highest point in the cell at most `mu`): a beam above an obstacle says nothing about it. Cells without
    /// an estimate are updated as in the paper. Moving obstacles (people) are still cleared: beams pass below
    /// their top. With [`FreeSpaceElevation::Zero`], an occupied cell keeps its elevation while free samples
    /// lower its occupancy, and restarts from the ground once it turns free.
    BelowElevation,
}

/// Whether a free sample passing at `beam_top_m` (its highest point in the cell) may update a cell whose
/// elevation estimate is `prior` under `rule`. (Samples deeper than `free_space_max_depth_m` below the
/// estimate were dropped before this: see [`ModelOptions::free_space_max_depth_m`].)
pub fn free_sample_informs(rule: FreeSpaceOccupancy, prior: Option<Elevation>, beam_top_m: f32) -> bool {
    match (rule, prior) {
        (FreeSpaceOccupancy::Always, _) | (FreeSpaceOccupancy::BelowElevation, None) => true,
        (FreeSpaceOccupancy::BelowElevation, Some(e)) => beam_top_m <= e.mean_m,
    }
}

/// The parameters of the map's update rules. `Default` gives the documented defaults above.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ModelOptions {
    /// `L_min` of eq. 7.
    pub log_odds_min: f32,
    /// `L_max` of eq. 7.
    pub log_odds_max: f32,
    /// A cell is occupied when its probability (eq. 3) exceeds this.
    pub occupied_threshold: f32,
    /// `k` of eq. 10, metres.
    pub significance_k_m: f32,
    /// `p_min` of eq. 11.
    pub p_min: f32,
    /// Upper clamp of eq. 10's result.
    pub p_max: f32,
    /// `l_occ` of eq. 12.
    pub elevation_threshold: f32,
    /// Eq. 12's free branch.
    pub free_space_elevation: FreeSpaceElevation,
    /// Whether free samples above a cell's elevation lower its occupancy.
    pub free_space_occupancy: FreeSpaceOccupancy,
    /// A free sample that passes more than this far below a cell's elevation estimate says nothing about the
    /// cell, in metres: the beam may have gone under an overhang (a board, a table) whose top the map holds.
    /// `None` (the paper): no limit. Moving obstacles are then removed by the hits on what is behind or under
    /// them (see [`ElevationFusion::HighestSurface`]'s `multi_height_noise_m2`) and by beams near their top.
    pub free_space_max_depth_m: Option<f32>,
    /// Which of a scan's hits in a cell make its elevation measurement.
    pub scan_hit_elevation: ScanHitElevation,
    /// How hit elevations are fused.
    pub elevation_fusion: ElevationFusion,
    /// Variance added to a cell's elevation variance before each fusion, m^2 per update. 0 (the paper) keeps
    /// eq. 9's ever-shrinking variance; a positive value lets a stubborn cell follow a moving obstacle. It is per
    /// update, not per second, because a cell stores no time stamp (three f32 per cell).
    pub process_noise_var_m2: f32,
    /// Height thresholding (paper section 6.2, Fig. 12): the parts of a beam higher than this, in world z
    /// metres, are ignored entirely, so overhangs the robot passes under never enter the map. `None` (the
    /// paper's base model) keeps everything; set it to the robot's height plus a margin.
    pub max_height_m: Option<f32>,
    /// Hits farther than this from the sensor are treated as no-return rays up to this range (OctoMap's
    /// `maxrange`). `None`: no limit.
    pub max_range_m: Option<f32>,
    /// How far a no-return ray clears, metres. `None`: the sensor's maximum range.
    pub no_return_clear_range_m: Option<f32>,
}

impl Default for ModelOptions {
    fn default() -> Self {
        Self {
            log_odds_min: DEFAULT_LOG_ODDS_MIN,
            log_odds_max: DEFAULT_LOG_ODDS_MAX,
            occupied_threshold: DEFAULT_OCCUPIED_THRESHOLD,
            significance_k_m: DEFAULT_SIGNIFICANCE_K_M,
            p_min: DEFAULT_P_MIN,
            p_max: DEFAULT_P_MAX,
            elevation_threshold: DEFAULT_ELEVATION_THRESHOLD,
            free_space_elevation: FreeSpaceElevation::Zero,
            free_space_occupancy: FreeSpaceOccupancy::Always,
            free_space_max_depth_m: None,
            scan_hit_elevation: ScanHitElevation::Highest,
            elevation_fusion: ElevationFusion::Kalman,
            process_noise_var_m2: 0.0,
            max_height_m: None,
            max_range_m: None,
            no_return_clear_range_m: None,
        }
    }
}

impl ModelOptions {
    /// Checks every option for sense.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the first bad option and its valid range.
    pub fn validate(&self) -> Result<()> {
        fn check(ok: bool, name: &'static str, message: String) -> Result<()> {
            if ok {
                Ok(())
            } else {
                Err(Error::setting(name, message))
            }
        }
        let o = self;
        check(
            o.log_odds_min.is_finite() && o.log_odds_min < 0.0,
            "log_odds_min",
            format!("must be a finite negative log-odds, got {}", o.log_odds_min),
        )?;
        check(
            o.log_odds_max.is_finite() && o.log_odds_max > 0.0,
            "log_odds_max",
            format!("must be a finite positive log-odds, got {}", o.log_odds_max),
        )?;
        check(
            o.occupied_threshold > 0.0 && o.occupied_threshold < 1.0,
            "occupied_threshold",
            format!("must be a probability in (0, 1), got {}", o.occupied_threshold),
        )?;
        check(
            o.significance_k_m.is_finite() && o.significance_k_m > 0.0,
            "significance_k_m",
            format!("must be a positive number of metres, got {}", o.significance_k_m),
        )?;
        check(
            o.p_min > 0.0 && o.p_min < 0.5,
            "p_min",
            format!("must be in (0, 0.5), got {}", o.p_min),
        )?;
        check(
            o.p_max > 0.5 && o.p_max < 1.0,
            "p_max",
            format!("must be in (0.5, 1), got {}", o.p_max),
        )?;
        check(
            o.elevation_threshold > 0.0 && o.elevation_threshold < 1.0,
            "elevation_threshold",
            format!("must be a probability in (0, 1), got {}", o.elevation_threshold),
        )?;
        if let ElevationFusion::HighestSurface {
            mahalanobis_threshold,
            lower_threshold,
            multi_height_noise_m2,
        } = o.elevation_fusion
        {
            if let Some(t) = lower_threshold {
                check(
                    t.is_finite() && t > 0.0,
                    "elevation_fusion",
                    format!("lower_threshold must be a positive number of standard deviations, got {t}"),
                )?;
            }
            check(
                multi_height_noise_m2.is_finite() && multi_height_noise_m2 >= 0.0,
                "elevation_fusion",
                format!("multi_height_noise_m2 must be a variance >= 0, got {multi_height_noise_m2}"),
            )?;
            check(
                mahalanobis_threshold.is_finite() && mahalanobis_threshold > 0.0,
                "elevation_fusion",
                format!(
                    "mahalanobis_threshold must be a positive number of standard deviations, got {mahalanobis_threshold}"
                ),
            )?;
        }
        check(
            o.process_noise_var_m2.is_finite() && o.process_noise_var_m2 >= 0.0,
            "process_noise_var_m2",
            format!("must be a variance >= 0, got {}", o.process_noise_var_m2),
        )?;
        if let Some(h) = o.max_height_m {
            check(
                h.is_finite(),
                "max_height_m",
                format!("must be a finite height in metres, got {h}"),
            )?;
        }
        if let Some(d) = o.free_space_max_depth_m {
            check(
                d.is_finite() && d >= 0.0,
                "free_space_max_depth_m",
                format!("must be a depth in metres >= 0, got {d}"),
            )?;
        }
        for (name, v) in [
            ("max_range_m", o.max_range_m),
            ("no_return_clear_range_m", o.no_return_clear_range_m),
        ] {
            if let Some(v) = v {
                check(
                    v.is_finite() && v > 0.0,
                    name,
                    format!("must be a positive range in metres, got {v}"),
                )?;
            }
        }
        Ok(())
    }
}

/// Eq. 3: the occupancy probability of log-odds `l`, `1 - 1 / (1 + e^l)`.
pub fn probability_from_log_odds(l: f32) -> f32 {
    1.0 - 1.0 / (1.0 + l.exp())
}

/// Eq. 6: the log-odds `log(p / (1 - p))` of one measurement's probability `p` (prior 0.5, so eq. 4's prior
/// term vanishes).
pub fn log_odds(p: f32) -> f32 {
    (p / (1.0 - p)).ln()
}

/// Eq. 5 with Yguel's clamping, eq. 7: `max(min(l + delta, l_max), l_min)`.
pub fn update_log_odds(l: f32, delta: f32, l_min: f32, l_max: f32) -> f32 {
    (l + delta).clamp(l_min, l_max)
}

/// Eq. 11: the occupancy probability of a sample at range `l` without the Gaussian bump: `p_min` up to the
/// measured range `l_p`, 0.5 (unknown) behind it.
pub fn p_occ(l: f32, l_p: f32, p_min: f32) -> f32 {
    if l <= l_p { p_min } else { 0.5 }
}

/// Eq. 10: the Gaussian inverse sensor model, the occupancy probability of a sample at range `l` on a beam that
/// measured `l_p` with range error `dl`:
/// `p_occ(l) + (k / (dl sqrt(2 pi)) + 0.5 - p_occ(l)) exp(-((l - l_p) / dl)^2 / 2)`.
///
/// The result can exceed 1 for small `dl`; [`clamp_probability`] bounds it before it becomes log-odds.
pub fn inverse_sensor_model(l: f32, l_p: f32, dl: f32, k: f32, p_min: f32) -> f32 {
    let base = p_occ(l, l_p, p_min);
    let z = (l - l_p) / dl;
    let peak = k / (dl * (2.0 * std::f32::consts::PI).sqrt());
    base + (peak + 0.5 - base) * (-0.5 * z * z).exp()
}

/// Bounds an inverse-sensor-model probability into `[p_min, p_max]`, inside the open interval (0, 1), so its
/// log-odds is finite.
pub fn clamp_probability(p: f32, p_min: f32, p_max: f32) -> f32 {
    p.clamp(p_min, p_max)
}

/// Eq. 12: the elevation measurement of a sample at height `z_m` with occupancy probability `p`: `z` when
/// `p > l_occ`, otherwise the paper's `0` (returned as `None` here; what a free sample does is
/// [`FreeSpaceElevation`]'s choice).
pub fn elevation_observation(p: f32, z_m: f32, l_occ: f32) -> Option<f32> {
    (p > l_occ).then_some(z_m)
}

/// An elevation estimate: the Gaussian `N(mean_m, var_m2)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Elevation {
    /// Mean `mu`, metres (world z).
    pub mean_m: f32,
    /// Variance `sigma^2`, m^2.
    pub var_m2: f32,
}

/// Eq. 8 and 9, the one-dimensional Kalman update of Pfaff et al.: fuses the measurement `h` with variance
/// `s2` into the prior `(mu, sigma^2)`:
/// `mu' = (s2 mu + sigma^2 h) / (sigma^2 + s2)`, `sigma'^2 = sigma^2 s2 / (sigma^2 + s2)`.
///
/// `process_noise_var_m2` is added to the prior variance first (0 in the paper). With no prior (`None`) the
/// measurement becomes the estimate.
pub fn kalman_fuse(prior: Option<Elevation>, h_m: f32, s2_m2: f32, process_noise_var_m2: f32) -> Elevation {
    match prior {
        None => Elevation {
            mean_m: h_m,
            var_m2: s2_m2,
        },
        Some(Elevation {
            mean_m: mu,
            var_m2: var,
        }) => {
            let var = var + process_noise_var_m2;
            let sum = var + s2_m2;
            if sum <= 0.0 {
                // Two exact estimates: keep the prior rather than divide by zero.
                return Elevation {
                    mean_m: mu,
                    var_m2: var,
                };
            }
            Elevation {
                mean_m: (s2_m2 * mu + var * h_m) / sum,
                var_m2: var * s2_m2 / sum,
            }
        }
    }
}

/// The ray-bound rule of [`FreeSpaceElevation::RayBound`]: a beam that passed through the cell at height
/// `beam_z_m` caps the elevation mean there.
pub fn ray_bound(prior: Elevation, beam_z_m: f32) -> Elevation {
    Elevation {
        mean_m: prior.mean_m.min(beam_z_m),
        var_m2: prior.var_m2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f32, b: f32, tol: f32) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn a_scans_hits_combine_as_the_highest_or_the_weighted_mean() {
        let none = (f32::NEG_INFINITY, f32::INFINITY);
        let highest = ScanHitElevation::Highest;
        let first = highest.combine(none, 0.1, 0.01);
        assert_eq!(first, (0.1, 0.01));
        assert_eq!(highest.combine(first, 0.3, 0.04), (0.3, 0.04));
        assert_eq!(highest.combine((0.3, 0.04), 0.1, 0.01), (0.3, 0.04));
        // Weighted mean: weights 1 / 0.01 and 1 / 0.03 -> (0.1 * 100 + 0.3 * 33.3) / 133.3 = 0.15, variance
        // 1 / 133.3 = 0.0075.
        let mean = ScanHitElevation::WeightedMean;
        let first = mean.combine(none, 0.1, 0.01);
        assert_eq!(first, (0.1, 0.01));
        let (z, var) = mean.combine(first, 0.3, 0.03);
        assert!(close(z, 0.15, 1e-6) && close(var, 0.0075, 1e-7), "{z} {var}");
    }

    #[test]
    fn eq3_and_eq6_are_inverse() {
        assert!(close(probability_from_log_odds(0.0), 0.5, 1e-7));
        // OctoMap's clamping bounds: -2 -> 0.1192, 3.5 -> 0.9707.
        assert!(close(probability_from_log_odds(-2.0), 0.119_203, 1e-5));
        assert!(close(probability_from_log_odds(3.5), 0.970_688, 1e-5));
        assert!(close(log_odds(0.7), 0.847_298, 1e-5));
        assert!(close(log_odds(0.4), -0.405_465, 1e-5));
        for p in [0.1_f32, 0.3, 0.5, 0.8, 0.95] {
            assert!(close(probability_from_log_odds(log_odds(p)), p, 1e-5));
        }
    }

    #[test]
    fn eq7_clamps_to_the_bounds() {
        assert_eq!(update_log_odds(3.0, 0.847, -2.0, 3.5), 3.5);
        assert_eq!(update_log_odds(-1.8, -0.405, -2.0, 3.5), -2.0);
        assert!(close(update_log_odds(0.0, 0.847, -2.0, 3.5), 0.847, 1e-6));
    }

    #[test]
    fn eq10_matches_hand_computed_values() {
        // At the hit: p_occ = p_min = 0.4, bump = k / (dl sqrt(2 pi)) = 0.03 / (0.03 * 2.506628) = 0.398942.
        let p = inverse_sensor_model(5.0, 5.0, 0.03, 0.03, 0.4);
        assert!(close(p, 0.4 + (0.398_942 + 0.5 - 0.4), 1e-5), "{p}");
        // One dl before the hit: 0.4 + 0.498942 * exp(-0.5) = 0.702627.
        let p = inverse_sensor_model(4.97, 5.0, 0.03, 0.03, 0.4);
        assert!(close(p, 0.702_627, 1e-4), "{p}");
        // One dl behind the hit, p_occ is 0.5: 0.5 + 0.398942 * exp(-0.5) = 0.741971.
        let p = inverse_sensor_model(5.03, 5.0, 0.03, 0.03, 0.4);
        assert!(close(p, 0.741_971, 1e-4), "{p}");
        // Far before the hit the Gaussian vanishes and p = p_min.
        assert!(close(inverse_sensor_model(1.0, 5.0, 0.03, 0.03, 0.4), 0.4, 1e-6));
        // The paper's Fig. 3: a larger range error lowers the peak.
        assert!(
            inverse_sensor_model(15.0, 15.0, 0.3, 0.03, 0.4)
                < inverse_sensor_model(10.0, 10.0, 0.2, 0.03, 0.4)
        );
    }

    #[test]
    fn eq11_switches_at_the_measured_range() {
        assert_eq!(p_occ(2.0, 2.0, 0.4), 0.4);
        assert_eq!(p_occ(2.01, 2.0, 0.4), 0.5);
    }

    #[test]
    fn eq12_gives_the_height_only_near_the_hit() {
        assert_eq!(elevation_observation(0.8, 0.31, 0.5), Some(0.31));
        assert_eq!(elevation_observation(0.4, 0.31, 0.5), None);
    }

    #[test]
    fn eq8_eq9_match_hand_computed_values() {
        // Prior N(1, 0.04), measurement 2 with 0.01: mu = (0.01 * 1 + 0.04 * 2) / 0.05 = 1.8, var = 0.008.
        let e = kalman_fuse(
            Some(Elevation {
                mean_m: 1.0,
                var_m2: 0.04,
            }),
            2.0,
            0.01,
            0.0,
        );
        assert!(
            close(e.mean_m, 1.8, 1e-6) && close(e.var_m2, 0.008, 1e-7),
            "{e:?}"
        );
        // Process noise inflates the prior first: var 0.03 + 0.01 = 0.04 -> same result.
        let e2 = kalman_fuse(
            Some(Elevation {
                mean_m: 1.0,
                var_m2: 0.03,
            }),
            2.0,
            0.01,
            0.01,
        );
        assert!(
            close(e2.mean_m, 1.8, 1e-6) && close(e2.var_m2, 0.008, 1e-7),
            "{e2:?}"
        );
        // No prior: the measurement is the estimate.
        let e3 = kalman_fuse(None, 0.2, 0.5, 0.0);
        assert_eq!(
            e3,
            Elevation {
                mean_m: 0.2,
                var_m2: 0.5
            }
        );
    }

    #[test]
    fn ray_bound_only_lowers() {
        let e = Elevation {
            mean_m: 1.2,
            var_m2: 0.01,
        };
        assert_eq!(ray_bound(e, 0.3).mean_m, 0.3);
        assert_eq!(ray_bound(e, 2.0).mean_m, 1.2);
        assert_eq!(ray_bound(e, 0.3).var_m2, 0.01);
    }

    #[test]
    fn the_highest_surface_wins_across_scans() {
        let rule = ElevationFusion::HighestSurface {
            mahalanobis_threshold: 3.0,
            lower_threshold: None,
            multi_height_noise_m2: 1e-4,
        };
        let curb = Some(Elevation {
            mean_m: 0.03,
            var_m2: 1e-6,
        });
        // Much higher: replaces.
        let higher = fuse_elevation(rule, curb, 0.05, 1e-6, 0.0);
        assert_eq!((higher.mean_m, higher.var_m2), (0.05, 1e-6));
        // Much lower: ignored, but the variance grows (multi-height noise).
        let prior = Some(Elevation {
            mean_m: 0.05,
            var_m2: 1e-6,
        });
        let kept = fuse_elevation(rule, prior, 0.0, 1e-4, 0.0);
        assert_eq!(kept.mean_m, 0.05);
        assert!((kept.var_m2 - (1e-6 + 1e-4)).abs() < 1e-9, "{kept:?}");
        // Close: fused as eq. 8-9.
        let near = fuse_elevation(rule, curb, 0.031, 1e-4, 0.0);
        assert_eq!(near, kalman_fuse(curb, 0.031, 1e-4, 0.0));
        // A lower threshold of 1 sigma: a face hit 2 sigma under a curb's top no longer pulls it down.
        let strict = ElevationFusion::HighestSurface {
            mahalanobis_threshold: 3.0,
            lower_threshold: Some(1.0),
            multi_height_noise_m2: 1e-4,
        };
        let top = Some(Elevation {
            mean_m: 0.05,
            var_m2: 0.0,
        });
        assert_eq!(
            fuse_elevation(rule, top, 0.03, 1e-4, 0.0).mean_m,
            kalman_fuse(top, 0.03, 1e-4, 0.0).mean_m
        );
        assert_eq!(fuse_elevation(strict, top, 0.03, 1e-4, 0.0).mean_m, 0.05);
        assert_eq!(
            fuse_elevation(strict, top, 0.045, 1e-4, 0.0),
            kalman_fuse(top, 0.045, 1e-4, 0.0)
        );
        // The paper's rule always fuses.
        assert_eq!(
            fuse_elevation(ElevationFusion::Kalman, curb, 0.05, 1e-4, 0.0),
            kalman_fuse(curb, 0.05, 1e-4, 0.0)
        );
    }

    #[test]
    fn free_samples_above_an_obstacle_say_nothing_about_it() {
        let curb = Some(Elevation {
            mean_m: 0.05,
            var_m2: 1e-4,
        });
        assert!(free_sample_informs(FreeSpaceOccupancy::Always, curb, 0.4));
        assert!(!free_sample_informs(
            FreeSpaceOccupancy::BelowElevation,
            curb,
            0.4
        ));
        assert!(free_sample_informs(
            FreeSpaceOccupancy::BelowElevation,
            curb,
            0.03
        ));
        assert!(free_sample_informs(FreeSpaceOccupancy::BelowElevation, None, 0.4));
    }

    #[test]
    fn options_are_validated() {
        assert!(ModelOptions::default().validate().is_ok());
        let bad = ModelOptions {
            p_min: 0.6,
            ..ModelOptions::default()
        };
        assert!(bad.validate().expect_err("p_min").to_string().contains("p_min"));
        let bad = ModelOptions {
            process_noise_var_m2: f32::NAN,
            ..ModelOptions::default()
        };
        assert!(bad.validate().is_err());
        let bad = ModelOptions {
            max_range_m: Some(-1.0),
            ..ModelOptions::default()
        };
        assert!(bad.validate().is_err());
        let bad = ModelOptions {
            free_space_max_depth_m: Some(-0.01),
            ..ModelOptions::default()
        };
        let message = bad.validate().expect_err("negative depth").to_string();
        assert!(message.contains("free_space_max_depth_m"), "{message}");
        let bad = ModelOptions {
            elevation_fusion: ElevationFusion::HighestSurface {
                mahalanobis_threshold: 3.0,
                lower_threshold: Some(f32::NAN),
                multi_height_noise_m2: 0.0,
            },
            ..ModelOptions::default()
        };
        let message = bad.validate().expect_err("NaN threshold").to_string();
        assert!(message.contains("lower_threshold"), "{message}");
    }
}
