//! The structure over a cell's surface (the ceiling layer's cell) and the side its beams came from: the state
//! the ceiling rule ([`crate::model::update_ceiling`]) updates.

use super::Elevation;

/// The lowest structure seen over a cell's surface: a board, a table top or a person above the ground the
/// cell holds ([`crate::OverheadHits::Ceiling`]). Kept in a layer of its own, allocated only where a
/// ceiling was seen, so the paper's 12-byte cell is unchanged.
///
/// * none: `log_odds` is NaN ([`Ceiling::NONE`]);
/// * otherwise the structure's height is `N(z_m, var_m2)` and `log_odds` the evidence that it is there (eq. 5-7,
///   as a cell's occupancy), always above the occupancy threshold: a ceiling that falls to it is removed.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Ceiling {
    /// Height of the structure's lowest hits, world z, metres.
    pub z_m: f32,
    /// Variance of that height, m^2.
    pub var_m2: f32,
    /// Evidence that the structure is there, log-odds.
    pub log_odds: f32,
    /// From which side the beams that measured it came ([`crate::model::ceiling_contradicts`]).
    pub seen_from: SeenFrom,
    /// The highest point, world z in metres, at which a beam passed freely through the cell under the
    /// structure's band since the structure was first seen (`-inf`: none). The structure's lowest part lies
    /// between it and `z_m`: a beam that rises onto a board's face measures where it met the face, not the
    /// underside, which may hang lower ([`crate::traversability::ceiling_decision`]).
    pub clear_m: f32,
}

/// From which side the beams that measured a structure came.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum SeenFrom {
    /// Every beam came down onto it: a top. The structure lies under its height; beams skimming over it are
    /// free.
    Above = 0,
    /// Every beam came up onto it: an underside. The structure lies over its height; beams skimming under it
    /// are free.
    Below = 1,
    /// Beams from both sides (a person's front, hit by beams level with it): the structure lies on both sides.
    Both = 2,
}

impl SeenFrom {
    /// The side of a beam with vertical direction component `dir_z`.
    pub fn of_beam(dir_z: f64) -> Self {
        if dir_z < 0.0 { Self::Above } else { Self::Below }
    }

    /// The side of two sets of beams together.
    pub fn and(self, other: Self) -> Self {
        if self == other { self } else { Self::Both }
    }

    /// From its byte in a map file.
    pub fn from_byte(b: u8) -> Option<Self> {
        [Self::Above, Self::Below, Self::Both]
            .into_iter()
            .find(|s| *s as u8 == b)
    }
}

impl Ceiling {
    /// No structure over the cell.
    pub const NONE: Ceiling = Ceiling {
        z_m: 0.0,
        var_m2: f32::INFINITY,
        log_odds: f32::NAN,
        seen_from: SeenFrom::Both,
        clear_m: f32::NEG_INFINITY,
    };

    /// Whether there is a structure over the cell.
    #[inline]
    pub fn is_some(&self) -> bool {
        !self.log_odds.is_nan()
    }

    /// The structure's height as an estimate, or `None`.
    #[inline]
    pub fn height(&self) -> Option<Elevation> {
        self.is_some().then_some(Elevation {
            mean_m: self.z_m,
            var_m2: self.var_m2,
        })
    }
}
