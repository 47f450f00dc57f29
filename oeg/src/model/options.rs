//! The options that parameterise the update rules, with their documented defaults, and their validation.

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
/// Default half width of a cell's surface band, in standard deviations ([`FreeSpaceOccupancy::SurfaceBand`]):
/// 3, the Gaussian's 99.7 % bound.
pub const DEFAULT_SURFACE_BAND_SIGMAS: f32 = 3.0;
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
    /// A free sample leaves the elevation alone, but a cell that free samples turn free forgets its elevation
    /// (the obstacle is gone; nothing is assumed about the ground, unlike [`Self::Zero`]'s `h = 0`). The
    /// recommended preset's rule: with [`FreeSpaceOccupancy::SurfaceBand`] only beams through the surface
    /// turn a cell free.
    Forget,
}

/// How an elevation measurement of a hit is fused with the cell's estimate.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ElevationFusion {
    /// The paper: every measurement is fused by eq. 8 and 9.
    #[default]
    Kalman,
    /// Eq. 8's mean, and eq. 9's variance plus the disagreement between the estimate and the measurement that
    /// their variances do not explain ([`crate::model::fuse_with_disagreement`]). Measurements that agree
    /// within their noise shrink the variance as eq. 9 does; one that disagrees (a spurious return, a person
    /// arriving or leaving, the face of a curb) raises it by as much as it disagrees, so the estimate says how
    /// sure it is.
    Disagreement,
    /// The top surface of the cell: a measurement within `surface_band_sigmas` standard deviations of the
    /// estimate (of `sqrt(sigma^2 + s^2)`) is the same surface and is fused by eq. 8 and 9; one above the band
    /// pulls the estimate up as [`Self::Disagreement`] does, keeping the disagreement as variance (a higher
    /// surface is confirmed by the next hits, a spurious return outvoted by them); one below it is a lower level
    /// (the ground under a table or a board) and leaves it as it is ([`crate::model::fuse_top_surface`]). A
    /// surface comes down only when beams pass through its band ([`FreeSpaceOccupancy::SurfaceBand`]: a hit
    /// below a contradicted surface replaces it). The recommended preset's rule.
    TopSurface,
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
    /// The inverse-variance weighted mean of the hits (as [`Self::WeightedMean`]), with a variance that also
    /// holds how far the surface itself spreads within the cell: the excess of the hits' sample variance over
    /// their noise ([`crate::model::spread_variance`]). A cell that spans an edge, or a column (a person) hit
    /// at many heights, is then as uncertain as its surface is spread; noise is not taken for spread.
    MeanWithSpread,
    /// [`Self::MeanWithSpread`] over the hits of the highest level in the cell only: a hit more than
    /// `surface_band_sigmas` standard deviations (of their noise) above the hits so far starts the level
    /// afresh, one as far below them is a lower level (the ground seen under a table whose edge the same scan
    /// hit) and is left out ([`crate::model::surface_level`]). The recommended preset's rule.
    HighestLevel,
}

/// Where a hit's elevation measurement is taken (eq. 12's `z`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HitHeight {
    /// The paper (eq. 12): every sample within 3 sigma of the measured range whose probability (eq. 10) exceeds
    /// `l_occ` measures the cell's elevation at the beam's own height there. A beam that slopes down onto the
    /// ground then reports the cells just before its end above the ground, by up to `3 sigma_r |dir_z|` (1.5 cm
    /// for a 12 mm laser looking 25 degrees down): a bias that no amount of fusion removes.
    #[default]
    BeamSample,
    /// Only the cell that holds the measured end point gets a height, the end point's, as
    /// elevation_mapping files each point in its own cell; the other samples within 3 sigma count for the
    /// occupancy only. The range error then moves the height by `sigma_r |dir_z|`, which
    /// [`ModelOptions::vertical_variance`] accounts for, and no more.
    Endpoint,
}

impl HitHeight {
    /// Whether this is the paper's rule (left out of serialized options, so that files written before the
    /// option existed, and the paper's, keep their bytes).
    pub fn is_paper(&self) -> bool {
        *self == Self::BeamSample
    }
}

/// What a hit more than the surface band above a cell's surface is (eq. 12's `z` when the cell already holds
/// a lower surface).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OverheadHits {
    /// The paper: a measurement of the cell's one surface, fused by [`ElevationFusion`].
    #[default]
    Surface,
    /// A structure over the surface (a board or a table top over the ground, a person who stepped onto it):
    /// the hit goes to the cell's ceiling ([`crate::Ceiling`], [`crate::model::update_ceiling`]), the
    /// lowest structure seen over the surface, and leaves the surface alone. One height per cell cannot hold a
    /// board seen now and then over ground seen all the time: fused into the surface, the board's rare top hits
    /// are outvoted by the ground under it. A ceiling is cleared by beams through its band, as a surface is;
    /// the robot is blocked where the clearance under it lies between its step and its height
    /// ([`crate::traversability::ceiling_decision`]). The recommended preset's rule.
    Ceiling,
}

impl OverheadHits {
    /// Whether this is the paper's rule (left out of serialized options, so that the paper's files keep their
    /// bytes).
    pub fn is_paper(&self) -> bool {
        *self == Self::Surface
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
    /// A free sample counts only where the beam passes through the band in which the top of the cell's surface
    /// is believed to be: up to `surface_band_sigmas` standard deviations below `mu`, and not above it (see
    /// [`crate::model::band_contradicts`]). A beam far below the surface (under a board or a
    /// table) or above it (over a curb or a low wall, or skimming the ground it lands on next) says nothing
    /// about it. Cells without an estimate are updated as in the paper. In the same scan, a hit below a
    /// contradicted surface replaces it (the surface has gone down: a person who left).
    SurfaceBand,
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
    /// Where a hit's elevation is measured: the paper's beam samples or the end point.
    #[serde(skip_serializing_if = "HitHeight::is_paper")]
    pub hit_height: HitHeight,
    /// Which of a scan's hits in a cell make its elevation measurement.
    pub scan_hit_elevation: ScanHitElevation,
    /// What a hit above the band of a cell's surface is: the surface, or a structure over it.
    #[serde(skip_serializing_if = "OverheadHits::is_paper")]
    pub overhead_hits: OverheadHits,
    /// How hit elevations are fused.
    pub elevation_fusion: ElevationFusion,
    /// Variance added to a cell's elevation variance before each fusion, m^2 per update. 0 (the paper) keeps
    /// eq. 9's ever-shrinking variance; a positive value lets a stubborn cell follow a moving obstacle. It is per
    /// update, not per second, because a cell stores no time stamp (three f32 per cell).
    pub process_noise_var_m2: f32,
    /// Whether a hit's elevation variance is its range variance projected onto the vertical
    /// ([`crate::model::vertical_variance`]) rather than the range variance itself (the paper, `false`). Under
    /// it, a hit in a cell that holds a surface is weighted by the range error its beam has where it meets that
    /// surface: a sensor whose error grows with range (stereo) reports less error for a reading that fell short
    /// and more for one that went long, and weighted by what they report the short readings pull the surface up.
    pub vertical_variance: bool,
    /// Half the width of a cell's surface band, in standard deviations of its elevation
    /// ([`FreeSpaceOccupancy::SurfaceBand`]).
    pub surface_band_sigmas: f32,
    /// Correlation `rho` between the errors of a scan's measurements of a cell and the estimate before them,
    /// for scans taken from the same place, in [0, 1]. A sensor that measures a cell again from where it stood
    /// repeats its errors (which cells a beam's noisy end points land in, where it crosses the cell, the
    /// surface's texture), so fusing them is less certain than eq. 9 says. The correlation decays with the
    /// distance `d` to the nearest of the map's last 256 views by a sensor of the same range-error model,
    /// `rho exp(-d / resolution)` (a view a cell away sees the cell through other beams), and a measurement
    /// carries the information of `(1 - rho) / (1 + rho)` independent ones
    /// ([`crate::model::correlated_variance`]). 0 (the paper): independent, eq. 9's variance shrinks with
    /// every measurement. 1: a standing sensor's cell is as certain as its best measurement.
    pub measurement_correlation: f32,
    /// Height thresholding (paper section 6.2, Fig. 12): the parts of a beam higher than this, in metres above
    /// the ground under the robot when the scan was taken ([`crate::Scan::ground_z_m`]; world z for scans
    /// that do not say), are ignored entirely, so overhangs the robot passes under never enter the map, and a
    /// robot that climbs a slope keeps mapping the ground ahead of it. `None` (the paper's base model) keeps
    /// everything; set it to the robot's height plus a margin.
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
            hit_height: HitHeight::BeamSample,
            scan_hit_elevation: ScanHitElevation::Highest,
            overhead_hits: OverheadHits::Surface,
            elevation_fusion: ElevationFusion::Kalman,
            process_noise_var_m2: 0.0,
            vertical_variance: false,
            surface_band_sigmas: DEFAULT_SURFACE_BAND_SIGMAS,
            measurement_correlation: 0.0,
            max_height_m: None,
            max_range_m: None,
            no_return_clear_range_m: None,
        }
    }
}

impl ModelOptions {
    /// The options that describe the robot and its sensors rather than the update rules (by their names in
    /// files). A preset sets every other option and leaves these as the scenario sets them.
    pub const SCENE_OPTIONS: [&'static str; 3] = ["max_height_m", "max_range_m", "no_return_clear_range_m"];
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
        check(
            o.surface_band_sigmas.is_finite() && o.surface_band_sigmas > 0.0,
            "surface_band_sigmas",
            format!(
                "must be a positive number of standard deviations, got {}",
                o.surface_band_sigmas
            ),
        )?;
        check(
            (0.0..=1.0).contains(&o.measurement_correlation),
            "measurement_correlation",
            format!(
                "must be a correlation in [0, 1], got {}",
                o.measurement_correlation
            ),
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

#[cfg(test)]
mod tests {
    use super::*;

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
