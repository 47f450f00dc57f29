//! Whole-layer access: dense rasters of one quantity over a region, for analysis and images.
//!
//! An analysis is then one line over two slices (`error = estimate - truth`). Rasters are row-major from the
//! region's min-x, min-y cell (see [`crate::geometry`]).

use serde::{Deserialize, Serialize};

use super::Map;
use crate::cell::Cell;
use crate::error::{Error, Result};
use crate::geometry::{CellIndex, CellRegion, GridWindow};
use crate::model::probability_from_log_odds;

/// A per-cell quantity of the map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LayerKind {
    /// Occupancy probability (eq. 3), NaN where never observed.
    OccupancyProbability,
    /// Occupancy log-odds, NaN where never observed.
    LogOdds,
    /// Elevation mean, metres, NaN where there is no estimate.
    ElevationM,
    /// Elevation variance, m^2, NaN where there is no estimate.
    VarianceM2,
    /// Elevation standard deviation, metres, NaN where there is no estimate.
    StdDevM,
}

impl LayerKind {
    /// Every kind, in a fixed order.
    pub const ALL: [LayerKind; 5] = [
        Self::OccupancyProbability,
        Self::LogOdds,
        Self::ElevationM,
        Self::VarianceM2,
        Self::StdDevM,
    ];

    /// The snake_case name used in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::OccupancyProbability => "occupancy_probability",
            Self::LogOdds => "log_odds",
            Self::ElevationM => "elevation_m",
            Self::VarianceM2 => "variance_m2",
            Self::StdDevM => "std_dev_m",
        }
    }

    /// The value of this quantity for one cell.
    pub fn value(self, cell: &Cell) -> f32 {
        if !cell.is_observed() {
            return f32::NAN;
        }
        let elevation = cell.elevation();
        match self {
            Self::OccupancyProbability => probability_from_log_odds(cell.log_odds),
            Self::LogOdds => cell.log_odds,
            Self::ElevationM => elevation.map_or(f32::NAN, |e| e.mean_m),
            Self::VarianceM2 => elevation.map_or(f32::NAN, |e| e.var_m2),
            Self::StdDevM => elevation.map_or(f32::NAN, |e| e.var_m2.sqrt()),
        }
    }
}

/// A dense raster over a window onto the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Raster<T> {
    /// The cells covered, on the map's grid.
    pub window: GridWindow,
    /// One value per cell, row-major from the window's min corner.
    pub values: Vec<T>,
}

impl<T: Copy> Raster<T> {
    /// The value at `cell`, or `None` outside the window.
    pub fn get(&self, cell: CellIndex) -> Option<T> {
        self.window.region().offset(cell).map(|k| self.values[k])
    }

    /// The cells covered.
    pub fn region(&self) -> &CellRegion {
        self.window.region()
    }
}

/// A raster of one [`LayerKind`], NaN where the quantity is undefined.
pub type Layer = Raster<f32>;

impl Map {
    /// Checks a raster of `region` against the memory limit, counted with the map itself (one budget), and
    /// returns its number of cells.
    pub(crate) fn check_raster_size(&self, region: &CellRegion, bytes_per_cell: u64) -> Result<usize> {
        let bytes = region
            .num_cells()
            .saturating_mul(bytes_per_cell)
            .saturating_add(self.memory_bytes());
        if bytes > self.config().memory_limit_bytes {
            return Err(Error::MemoryLimit {
                requested_bytes: bytes,
                limit_bytes: self.config().memory_limit_bytes,
            });
        }
        usize::try_from(region.num_cells())
            .map_err(|_| Error::setting("region", "too many cells for this machine"))
    }

    /// A dense raster of `kind` over `region`.
    ///
    /// # Errors
    /// [`Error::MemoryLimit`] if the raster would exceed the map's memory limit.
    pub fn layer(&self, kind: LayerKind, region: CellRegion) -> Result<Layer> {
        let n = self.check_raster_size(&region, 4)?;
        let mut values = Vec::with_capacity(n);
        values.extend(region.cells().map(|c| kind.value(&self.cell(c))));
        Ok(Raster {
            window: GridWindow::new(*self.geometry(), region),
            values,
        })
    }
}
