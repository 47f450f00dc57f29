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

/// The `[map.model]` keys a settings file gives, each `None` where the file is silent: what it changes of a
/// preset's options ([`ModelChoice::resolve`]). The names, types and meanings are [`ModelOptions`]'s, field
/// for field (its documentation has the defaults).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
#[allow(
    missing_docs,
    reason = "each field is `ModelOptions`' field of the same name, documented there"
)]
pub struct ModelKeys {
    pub log_odds_min: Option<f32>,
    pub log_odds_max: Option<f32>,
    pub occupied_threshold: Option<f32>,
    pub significance_k_m: Option<f32>,
    pub p_min: Option<f32>,
    pub p_max: Option<f32>,
    pub elevation_threshold: Option<f32>,
    pub free_space_elevation: Option<FreeSpaceElevation>,
    pub free_space_occupancy: Option<FreeSpaceOccupancy>,
    pub free_space_max_depth_m: Option<f32>,
    pub hit_height: Option<HitHeight>,
    pub scan_hit_elevation: Option<ScanHitElevation>,
    pub overhead_hits: Option<OverheadHits>,
    pub elevation_fusion: Option<ElevationFusion>,
    pub process_noise_var_m2: Option<f32>,
    pub vertical_variance: Option<bool>,
    pub surface_band_sigmas: Option<f32>,
    pub measurement_correlation: Option<f32>,
    pub max_height_m: Option<f32>,
    pub max_range_m: Option<f32>,
    pub no_return_clear_range_m: Option<f32>,
}

impl ModelKeys {
    /// `base` with every given key in its place.
    pub fn over(&self, base: ModelOptions) -> ModelOptions {
        let Self {
            log_odds_min,
            log_odds_max,
            occupied_threshold,
            significance_k_m,
            p_min,
            p_max,
            elevation_threshold,
            free_space_elevation,
            free_space_occupancy,
            free_space_max_depth_m,
            hit_height,
            scan_hit_elevation,
            overhead_hits,
            elevation_fusion,
            process_noise_var_m2,
            vertical_variance,
            surface_band_sigmas,
            measurement_correlation,
            max_height_m,
            max_range_m,
            no_return_clear_range_m,
        } = *self;
        ModelOptions {
            log_odds_min: log_odds_min.unwrap_or(base.log_odds_min),
            log_odds_max: log_odds_max.unwrap_or(base.log_odds_max),
            occupied_threshold: occupied_threshold.unwrap_or(base.occupied_threshold),
            significance_k_m: significance_k_m.unwrap_or(base.significance_k_m),
            p_min: p_min.unwrap_or(base.p_min),
            p_max: p_max.unwrap_or(base.p_max),
            elevation_threshold: elevation_threshold.unwrap_or(base.elevation_threshold),
            free_space_elevation: free_space_elevation.unwrap_or(base.free_space_elevation),
            free_space_occupancy: free_space_occupancy.unwrap_or(base.free_space_occupancy),
            free_space_max_depth_m: free_space_max_depth_m.or(base.free_space_max_depth_m),
            hit_height: hit_height.unwrap_or(base.hit_height),
            scan_hit_elevation: scan_hit_elevation.unwrap_or(base.scan_hit_elevation),
            overhead_hits: overhead_hits.unwrap_or(base.overhead_hits),
            elevation_fusion: elevation_fusion.unwrap_or(base.elevation_fusion),
            process_noise_var_m2: process_noise_var_m2.unwrap_or(base.process_noise_var_m2),
            vertical_variance: vertical_variance.unwrap_or(base.vertical_variance),
            surface_band_sigmas: surface_band_sigmas.unwrap_or(base.surface_band_sigmas),
            measurement_correlation: measurement_correlation.unwrap_or(base.measurement_correlation),
            max_height_m: max_height_m.or(base.max_height_m),
            max_range_m: max_range_m.or(base.max_range_m),
            no_return_clear_range_m: no_return_clear_range_m.or(base.no_return_clear_range_m),
        }
    }
}

/// A model as a settings file chooses it: a named preset, and the options and step rule it gives over the
/// preset's (`[map] preset`, `[map.model]`, `[map] traversability` of a scenario, of `oeg map` and of `oeg
/// plan`; `oeg run --compare` and a sweep's `preset` axis change the preset).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ModelChoice {
    /// The preset the options start from.
    pub preset: MapPreset,
    /// The options given over the preset's.
    pub keys: ModelKeys,
    /// The step rule, unless the preset's.
    pub traversability: Option<TraversabilityRule>,
}

/// A map's model, resolved: its update rules' options and its step rule.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MapModel {
    /// The update rules' options.
    pub options: ModelOptions,
    /// The step rule.
    pub rule: TraversabilityRule,
}

impl ModelChoice {
    /// The one rule that turns a choice into a model: the preset's options for `robot` (`robust` cuts beams
    /// above its height), the given keys over them, and the given step rule or the preset's. The caller
    /// checks the result ([`ModelOptions::validate`], [`TraversabilityRule::validate`]) where it can name the
    /// file and key at fault.
    pub fn resolve(&self, robot: &RobotProfile) -> MapModel {
        MapModel {
            options: self.keys.over(self.preset.model(robot)),
            rule: self
                .traversability
                .unwrap_or_else(|| self.preset.traversability()),
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

    /// Every option of [`ModelOptions`] is a key of [`ModelKeys`], under the same name: a model written out
    /// and read back as keys over any preset is itself.
    #[test]
    fn keys_cover_every_option_by_name() {
        let robot = RobotProfile::default();
        for written in MapPreset::ALL {
            let mut options = written.model(&robot);
            // Every optional field given, so that each is written out.
            options.free_space_max_depth_m = Some(0.25);
            options.max_height_m = Some(1.5);
            options.max_range_m = Some(20.0);
            options.no_return_clear_range_m = Some(10.0);
            options.hit_height = HitHeight::Endpoint;
            options.overhead_hits = OverheadHits::Ceiling;
            let text = serde_json::to_string(&options).expect("serialize");
            let keys: ModelKeys = serde_json::from_str(&text).expect("every option is a key");
            for base in MapPreset::ALL {
                assert_eq!(
                    keys.over(base.model(&robot)),
                    options,
                    "{written:?} over {base:?}"
                );
            }
        }
    }

    #[test]
    fn a_choice_is_the_preset_with_its_given_keys_and_rule_over_it() {
        let robot = RobotProfile {
            height_m: 0.8,
            ..RobotProfile::default()
        };
        let silent = ModelChoice {
            preset: MapPreset::Robust,
            ..ModelChoice::default()
        };
        let model = silent.resolve(&robot);
        assert_eq!(model.options, MapPreset::Robust.model(&robot));
        assert_eq!(model.options.max_height_m, Some(0.8 + ROBUST_HEIGHT_MARGIN_M));
        assert_eq!(model.rule, MapPreset::Robust.traversability());
        let given = ModelChoice {
            keys: ModelKeys {
                p_max: Some(0.9),
                max_height_m: Some(2.0),
                ..ModelKeys::default()
            },
            traversability: Some(TraversabilityRule::Absolute),
            ..silent
        };
        let model = given.resolve(&robot);
        assert_eq!(model.options.p_max, 0.9);
        assert_eq!(model.options.max_height_m, Some(2.0));
        assert_eq!(model.options.hit_height, HitHeight::Endpoint);
        assert_eq!(model.rule, TraversabilityRule::Absolute);
        assert_eq!(
            ModelChoice::default().resolve(&robot).options,
            ModelOptions::default()
        );
    }
}
