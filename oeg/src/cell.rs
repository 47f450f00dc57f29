//! One map cell: exactly three f32. The optional structure over it, the ceiling layer's cell, is the model's
//! ([`crate::Ceiling`]).

use crate::model::{Elevation, probability_from_log_odds};

/// The state of one cell, 12 bytes as the paper's Table I assumes.
///
/// * never observed: `log_odds` is NaN (the other fields are then meaningless);
/// * observed, no elevation estimate yet (possible with [`crate::FreeSpaceElevation::Skip`] or
///   [`crate::FreeSpaceElevation::RayBound`]): `var_m2` is +infinity;
/// * otherwise the elevation is `N(mean_m, var_m2)`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Cell {
    /// Occupancy log-odds `L` (eq. 5).
    pub log_odds: f32,
    /// Elevation mean `mu`, world z, metres (eq. 8).
    pub mean_m: f32,
    /// Elevation variance `sigma^2`, m^2 (eq. 9).
    pub var_m2: f32,
}

const _: () = assert!(size_of::<Cell>() == 12);

impl Cell {
    /// A cell nobody has observed.
    pub const UNOBSERVED: Cell = Cell {
        log_odds: f32::NAN,
        mean_m: 0.0,
        var_m2: f32::INFINITY,
    };

    /// Whether any scan has touched the cell.
    #[inline]
    pub fn is_observed(&self) -> bool {
        !self.log_odds.is_nan()
    }

    /// The occupancy probability (eq. 3), or `None` if never observed.
    pub fn occupancy_probability(&self) -> Option<f32> {
        self.is_observed()
            .then(|| probability_from_log_odds(self.log_odds))
    }

    /// The elevation estimate, or `None` if there is none yet.
    #[inline]
    pub fn elevation(&self) -> Option<Elevation> {
        (self.is_observed() && self.var_m2.is_finite()).then_some(Elevation {
            mean_m: self.mean_m,
            var_m2: self.var_m2,
        })
    }

    pub(crate) fn set_elevation(&mut self, e: Option<Elevation>) {
        match e {
            Some(e) => {
                self.mean_m = e.mean_m;
                self.var_m2 = e.var_m2;
            }
            None => {
                self.mean_m = 0.0;
                self.var_m2 = f32::INFINITY;
            }
        }
    }
}
