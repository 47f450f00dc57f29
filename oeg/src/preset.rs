//! Named models, the one list every reader of a `preset` uses (a scenario's `[map] preset`, `oeg run
//! --compare`, a sweep's `preset` axis): `paper`, the model exactly as published; `static`, the paper with the
//! free-space and fusion rules for scenes where nothing moves; and `robust`, the recommended model built from
//! the rules of the model. `oeg/README.md` lists `robust`'s rules, each linked to its documentation.

use serde::{Deserialize, Serialize};

use crate::model::{
    ElevationFusion, FreeSpaceElevation, FreeSpaceOccupancy, HitHeight, ModelOptions, OverheadHits,
    ScanHitElevation,
};
use crate::traversability::{DEFAULT_REACH_M, DEFAULT_UNCERTAIN_KAPPA, RobotProfile, TraversabilityRule};

/// How far above the robot's height `robust` still maps a structure, metres: its height thresholding
/// (the paper's section 6.2) cuts beams at `height_m + 0.05`. A structure's underside up to 5 cm above the
/// robot is kept and judged (blocked, or uncertain within `kappa` sigma of the robot's height); higher ones
/// never enter the map, so the robot is let under them.
pub const ROBUST_HEIGHT_MARGIN_M: f32 = 0.05;

/// How far below a cell's surface a passing beam still says something about it under `static`, metres
/// ([`ModelOptions::free_space_max_depth_m`]): 1 cm, so a beam under a board or a table leaves its top alone.
pub const STATIC_MAX_DEPTH_M: f32 = 0.01;

/// A named model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MapPreset {
    /// The paper as published (every option at its documented default, the absolute step rule): the model for
    /// reproducing the paper.
    #[default]
    Paper,
    /// The paper's model for scenes where nothing moves: a beam passing above a cell's surface, or more than
    /// [`STATIC_MAX_DEPTH_M`] below it, says nothing about the cell
    /// ([`FreeSpaceOccupancy::BelowElevation`]), and a much higher hit replaces the estimate
    /// ([`ElevationFusion::HighestSurface`], elevation_mapping's rule). Its step rule is the paper's.
    Static,
    /// The recommended model: the paper's equations with the surface-band free-space rule, heights at the
    /// hits' end points, the highest level of a scan's hits with its spread, structures over a surface kept
    /// in a ceiling layer, the top surface across scans, the
    /// vertical variance of a hit, correlated measurements, height thresholding at the robot's height and the
    /// contact step rule with an uncertain band.
    Robust,
}

impl MapPreset {
    /// Every preset, in a fixed order.
    pub const ALL: [MapPreset; 3] = [Self::Paper, Self::Robust, Self::Static];

    /// The preset's name in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::Static => "static",
            Self::Robust => "robust",
        }
    }

    /// The model options for a robot described by `profile` (`robust` cuts beams above its height).
    pub fn model(self, profile: &RobotProfile) -> ModelOptions {
        match self {
            Self::Paper => ModelOptions::default(),
            Self::Static => ModelOptions {
                free_space_occupancy: FreeSpaceOccupancy::BelowElevation,
                free_space_max_depth_m: Some(STATIC_MAX_DEPTH_M),
                elevation_fusion: ElevationFusion::HighestSurface {
                    mahalanobis_threshold: 3.0,
                    lower_threshold: Some(1.0),
                    multi_height_noise_m2: 1e-4,
                },
                ..ModelOptions::default()
            },
            Self::Robust => ModelOptions {
                free_space_occupancy: FreeSpaceOccupancy::SurfaceBand,
                free_space_elevation: FreeSpaceElevation::Forget,
                hit_height: HitHeight::Endpoint,
                scan_hit_elevation: ScanHitElevation::HighestLevel,
                overhead_hits: OverheadHits::Ceiling,
                elevation_fusion: ElevationFusion::TopSurface,
                measurement_correlation: 1.0,
                vertical_variance: true,
                max_height_m: Some(profile.height_m + ROBUST_HEIGHT_MARGIN_M),
                ..ModelOptions::default()
            },
        }
    }

    /// The preset's step rule.
    pub fn traversability(self) -> TraversabilityRule {
        match self {
            Self::Paper | Self::Static => TraversabilityRule::Absolute,
            Self::Robust => TraversabilityRule::Contact {
                kappa: DEFAULT_UNCERTAIN_KAPPA,
                reach_m: DEFAULT_REACH_M,
            },
        }
    }
}

impl std::str::FromStr for MapPreset {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("unknown map preset `{s}`; presets: paper, static, robust"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paper_preset_is_the_default_model_and_robust_validates() {
        let p = RobotProfile::default();
        assert_eq!(MapPreset::Paper.model(&p), ModelOptions::default());
        assert_eq!(MapPreset::Paper.traversability(), TraversabilityRule::Absolute);
        let robust = MapPreset::Robust.model(&p);
        robust.validate().expect("valid");
        assert_eq!(robust.max_height_m, Some(0.46 + ROBUST_HEIGHT_MARGIN_M));
        assert_eq!("robust".parse::<MapPreset>(), Ok(MapPreset::Robust));
        assert_eq!("static".parse::<MapPreset>(), Ok(MapPreset::Static));
        MapPreset::Static.model(&p).validate().expect("valid");
        assert_eq!(MapPreset::Static.traversability(), TraversabilityRule::Absolute);
        for preset in MapPreset::ALL {
            assert_eq!(preset.name().parse::<MapPreset>(), Ok(preset));
        }
        assert!("fast".parse::<MapPreset>().is_err());
    }
}
