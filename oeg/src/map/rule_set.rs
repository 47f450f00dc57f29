//! The rules a scan's samples follow, as the samplers read them (`map/sample.rs`): resolved from the options
//! once a scan ([`OptionRules`]), or fixed at compile time for the rule set of the recommended preset
//! ([`BandCeilingRules`], [`crate::MapPreset::Robust`]). The map's hot loop is the free sample, once per cell a
//! beam crosses; with the rules fixed, it carries no option's check and its state stays in registers. Both give
//! the same samples under the same options: the fixed set is chosen only where the options hold exactly it.

use crate::model::{FreeSpaceOccupancy, ModelOptions, OverheadHits};

/// Which of the free and hit samples' rules are on.
pub(super) trait Rules: Copy + Sync {
    /// Free samples are judged against the cell's surface band ([`FreeSpaceOccupancy::SurfaceBand`]).
    fn surface_band(self) -> bool;
    /// A free sample deeper than this under the cell's surface says nothing
    /// ([`ModelOptions::free_space_max_depth_m`]).
    fn max_depth_m(self) -> Option<f32>;
    /// Hits over a surface's band measure a structure over it ([`OverheadHits::Ceiling`]).
    fn ceiling(self) -> bool;
    /// A hit's variance is the beam's vertical noise where it meets the surface
    /// ([`ModelOptions::vertical_variance`]).
    fn vertical_variance(self) -> bool;
}

/// The rules as the options give them, read once a scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct OptionRules {
    surface_band: bool,
    max_depth_m: Option<f32>,
    ceiling: bool,
    vertical_variance: bool,
}

impl OptionRules {
    pub(super) fn of(opts: &ModelOptions) -> Self {
        Self {
            surface_band: opts.free_space_occupancy == FreeSpaceOccupancy::SurfaceBand,
            max_depth_m: opts.free_space_max_depth_m,
            ceiling: opts.overhead_hits == OverheadHits::Ceiling,
            vertical_variance: opts.vertical_variance,
        }
    }
}

impl Rules for OptionRules {
    #[inline(always)]
    fn surface_band(self) -> bool {
        self.surface_band
    }
    #[inline(always)]
    fn max_depth_m(self) -> Option<f32> {
        self.max_depth_m
    }
    #[inline(always)]
    fn ceiling(self) -> bool {
        self.ceiling
    }
    #[inline(always)]
    fn vertical_variance(self) -> bool {
        self.vertical_variance
    }
}

/// The surface band, the ceiling layer and the vertical variance on, no depth bound: the recommended preset's
/// rules, fixed at compile time.
#[derive(Debug, Clone, Copy)]
pub(super) struct BandCeilingRules;

impl BandCeilingRules {
    const RULES: OptionRules = OptionRules {
        surface_band: true,
        max_depth_m: None,
        ceiling: true,
        vertical_variance: true,
    };

    /// The fixed set, where `opts` choose exactly its rules.
    pub(super) fn of(opts: &ModelOptions) -> Option<Self> {
        (OptionRules::of(opts) == Self::RULES).then_some(Self)
    }
}

impl Rules for BandCeilingRules {
    #[inline(always)]
    fn surface_band(self) -> bool {
        Self::RULES.surface_band
    }
    #[inline(always)]
    fn max_depth_m(self) -> Option<f32> {
        Self::RULES.max_depth_m
    }
    #[inline(always)]
    fn ceiling(self) -> bool {
        Self::RULES.ceiling
    }
    #[inline(always)]
    fn vertical_variance(self) -> bool {
        Self::RULES.vertical_variance
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{MapPreset, RobotProfile};

    #[test]
    fn the_fixed_set_is_chosen_for_the_recommended_preset_and_only_where_the_options_hold_it() {
        let robust = MapPreset::Robust.model(&RobotProfile::default());
        assert!(BandCeilingRules::of(&robust).is_some());
        assert_eq!(OptionRules::of(&robust), BandCeilingRules::RULES);
        for preset in [MapPreset::Paper, MapPreset::Static] {
            assert!(BandCeilingRules::of(&preset.model(&RobotProfile::default())).is_none());
        }
        // One rule changed, and the options are read again.
        let without_ceiling = ModelOptions {
            overhead_hits: OverheadHits::Surface,
            ..robust
        };
        assert!(BandCeilingRules::of(&without_ceiling).is_none());
        let with_depth = ModelOptions {
            free_space_max_depth_m: Some(0.3),
            ..robust
        };
        assert!(BandCeilingRules::of(&with_depth).is_none());
        let without_vertical = ModelOptions {
            vertical_variance: false,
            ..robust
        };
        assert!(BandCeilingRules::of(&without_vertical).is_none());
    }
}
