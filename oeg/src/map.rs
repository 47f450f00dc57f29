//! The Occupancy-Elevation Grid: its configuration, cells and counters, and everything a map does, found from
//! here:
//!
//! * `integrate` (`map/integrate.rs`): [`Map::integrate`], the paper's Algorithm 1, in parallel where threads
//!   are given: each ray's samples (`map/sample.rs`) gathered into the scan scratch (`map/scratch.rs`), then
//!   each touched cell updated once (`map/apply.rs`, one cell's update in `map/update.rs`); [`Map::integrate_batch`] (`map/batch.rs`): many short
//!   scans side by side, a run of them per thread;
//! * `stance` (`map/stance.rs`): the ground a standing robot's wheels touch, as a measurement
//!   ([`Map::integrate_stance`]), and what a driving robot's body fills, as proof ([`Map::integrate_footprint`]);
//! * `layers` (`map/layers.rs`): dense rasters of one quantity ([`Map::layer`]);
//! * the decisions ([`Map::traversability`], [`Map::traversability_layer`], [`Map::traversability_counts`]):
//!   `traversability/decide.rs`, beside the pure rules they apply;
//! * saving and loading: [`crate::save_map`], [`crate::load_map`] (`io/mapfile.rs`).

mod apply;
mod batch;
mod deferred_hits;
mod integrate;
pub use batch::BatchError;
pub use integrate::RAYS_BETWEEN_STOP_CHECKS;
mod layers;
mod rule_evidence;
mod rule_set;
mod runs;
mod sample;
mod scratch;
mod span;
mod stance;
mod update;
mod views;

pub use layers::{Layer, LayerKind, Raster};
pub use stance::{BodySpan, DEFAULT_STANCE_SIGMA_M, Stance};

use serde::{Deserialize, Serialize};

use self::apply::LogOddsLevels;
use self::scratch::ScanScratch;
use self::views::RecentViews;
use crate::cell::Cell;
use crate::error::{Error, Result};
use crate::geometry::{CellIndex, CellRegion, GridGeometry};
use crate::model::Ceiling;
use crate::model::{ModelOptions, log_odds};
use crate::storage::{TILE_CELLS, TileGrid, TileIndex};

/// Default memory limit of a map, bytes (4 GiB): far above any sensible map, low enough that a corrupt point
/// a million kilometres away gives an error instead of exhausting the machine.
pub const DEFAULT_MEMORY_LIMIT_BYTES: u64 = 4 << 30;

/// Bytes of the map's own structure, beside its tiles and its recent views: part of [`Map::memory_bytes`], so
/// every limit check leaves room for it.
const OWN_BYTES: u64 = size_of::<Map>() as u64;

/// Everything needed to create a map.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapConfig {
    /// Cell size, metres.
    pub resolution_m: f64,
    /// The update rules' parameters.
    #[serde(default)]
    pub model: ModelOptions,
    /// The most memory the map may hold, bytes ([`Map::memory_bytes`]).
    #[serde(default = "default_memory_limit")]
    pub memory_limit_bytes: u64,
}

fn default_memory_limit() -> u64 {
    DEFAULT_MEMORY_LIMIT_BYTES
}

impl MapConfig {
    /// A configuration with the default model at `resolution_m`.
    pub fn new(resolution_m: f64) -> Self {
        Self {
            resolution_m,
            model: ModelOptions::default(),
            memory_limit_bytes: DEFAULT_MEMORY_LIMIT_BYTES,
        }
    }
}

/// What one call to [`Map::integrate`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct IntegrationStats {
    /// Rays in the scan.
    pub num_rays: u64,
    /// Rays skipped entirely: zero length, or wholly above the height threshold.
    pub num_rays_skipped: u64,
    /// Cell visits by rays (a cell crossed by three rays counts three times).
    pub num_cell_visits: u64,
    /// Distinct cells updated (each once per scan).
    pub num_cells_updated: u64,
}

impl std::ops::AddAssign for IntegrationStats {
    fn add_assign(&mut self, o: Self) {
        self.num_rays += o.num_rays;
        self.num_rays_skipped += o.num_rays_skipped;
        self.num_cell_visits += o.num_cell_visits;
        self.num_cells_updated += o.num_cells_updated;
    }
}

/// An Occupancy-Elevation Grid.
///
/// Each observed cell holds its occupancy log-odds, elevation mean and elevation variance (see [`Cell`]); the
/// storage is sparse (64 x 64 tiles allocated on first write). Feed it with [`Map::integrate`]; read it cell by cell
/// ([`Map::cell`]) or a whole layer at a time ([`Map::layer`], [`Map::traversability_layer`]).
///
/// # Several rays in one scan
///
/// Within one scan, a cell crossed by several rays is updated once (OctoMap's rule, so that a dense scan does
/// not count one surface as many independent observations): its occupancy takes the most occupied of the
/// rays' samples (occupied wins), its elevation the highest elevation measurement among them ("the elevation
/// is computed considering the higher point of the obstacle"), or, if no ray hit it, the free-space rule with
/// the lowest beam height and smallest variance.
#[derive(Debug, Clone)]
pub struct Map {
    pub(crate) config: MapConfig,
    pub(crate) geometry: GridGeometry,
    pub(crate) cells: TileGrid<Cell>,
    /// The ceiling layer ([`crate::OverheadHits::Ceiling`]): tiles only where a ceiling was seen.
    pub(crate) ceilings: TileGrid<Ceiling>,
    pub(crate) scratch: ScanScratch,
    /// The occupancy threshold and a plain free sample in log-odds, resolved once from the model.
    pub(crate) levels: LogOddsLevels,
    pub(crate) totals: IntegrationStats,
    pub(crate) num_scans: u64,
    /// Where the last scans were taken from ([`ModelOptions::measurement_correlation`]); not saved in a map
    /// file, so a map read back takes its next scan as a new view.
    pub(crate) views: RecentViews,
}

impl Map {
    /// An empty map.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a bad resolution or model option.
    pub fn new(config: MapConfig) -> Result<Self> {
        let geometry = GridGeometry::new(config.resolution_m)?;
        config.model.validate()?;
        Ok(Self {
            geometry,
            cells: TileGrid::new(Cell::UNOBSERVED),
            ceilings: TileGrid::new(Ceiling::NONE),
            scratch: ScanScratch::for_model(&config.model),
            levels: LogOddsLevels {
                occupied: log_odds(config.model.occupied_threshold),
                free: log_odds(config.model.p_min),
            },
            totals: IntegrationStats::default(),
            num_scans: 0,
            views: RecentViews::default(),
            config,
        })
    }

    /// The configuration the map was made with.
    pub fn config(&self) -> &MapConfig {
        &self.config
    }

    /// The grid geometry.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// Number of scans integrated.
    pub fn num_scans(&self) -> u64 {
        self.num_scans
    }

    /// Totals over every scan integrated.
    pub fn totals(&self) -> IntegrationStats {
        self.totals
    }

    /// The cell's state; [`Cell::UNOBSERVED`] for a cell never observed.
    pub fn cell(&self, cell: CellIndex) -> Cell {
        self.cells.get(cell).copied().unwrap_or(Cell::UNOBSERVED)
    }

    /// The lowest structure seen over the cell's surface ([`crate::OverheadHits::Ceiling`]), if any.
    pub fn ceiling(&self, cell: CellIndex) -> Option<Ceiling> {
        self.ceilings.get(cell).copied().filter(Ceiling::is_some)
    }

    /// The cell holding the world point `(x, y)`, if any.
    pub fn cell_at(&self, x_m: f64, y_m: f64) -> Option<Cell> {
        self.geometry.cell_of(x_m, y_m).map(|c| self.cell(c))
    }

    /// Whether the cell is occupied (`P > occupied_threshold`); `None` if never observed.
    pub fn is_occupied(&self, cell: CellIndex) -> Option<bool> {
        let c = self.cell(cell);
        c.is_observed().then_some(c.log_odds > self.levels.occupied)
    }

    /// The occupancy threshold as log-odds: a cell is occupied when its `L` is above it.
    pub fn occupied_log_odds(&self) -> f32 {
        self.levels.occupied
    }

    /// Bytes the map holds: the cells' tiles, the ceiling layer's, their indices and the map itself. The
    /// per-scan scratch is apart ([`Map::scratch_bytes`]); the figure is the same on any number of threads.
    pub fn memory_bytes(&self) -> u64 {
        self.cells.memory_bytes() + self.ceilings.memory_bytes() + self.own_bytes()
    }

    /// Bytes of the map's own structure and its recent views: the part of [`Map::memory_bytes`] beside the
    /// tiles.
    fn own_bytes(&self) -> u64 {
        OWN_BYTES + self.views.memory_bytes()
    }

    /// Bytes of the per-scan scratch that [`Map::integrate`] keeps for reuse: for every tile the largest scan
    /// touched, 20 bytes a cell under the paper's rules or 32 under rules that judge samples against the
    /// surface or the ceiling (with 48 more for each cell the largest scan's hits reached, kept in a list beside
    /// the grid), once per thread that gathered a long scan's rays. The memory limit counts it with
    /// [`Map::memory_bytes`].
    pub fn scratch_bytes(&self) -> u64 {
        self.scratch.memory_bytes()
    }

    /// Bytes of one cell's evidence in the per-scan scratch's grid: 20 under the paper's rules, 32 under the
    /// rules that judge samples against the cell's surface or ceiling or read the spread of its hits (a cell a
    /// hit reached keeps 48 more beside the grid).
    pub fn scratch_cell_bytes(&self) -> usize {
        self.scratch.cell_bytes()
    }

    /// Gives back the per-scan scratch ([`Map::scratch_bytes`]). The map reads the same; the next integration
    /// allocates the scratch again.
    pub fn release_scratch(&mut self) {
        self.scratch = ScanScratch::for_model(&self.config.model);
    }

    /// Bytes of the cells alone: 12 per cell of every allocated tile (observed or not).
    pub fn cell_bytes(&self) -> u64 {
        (self.cells.num_tiles() * TileGrid::<Cell>::tile_bytes()) as u64
    }

    /// Every observed cell with its state, tile by tile in a fixed order.
    pub fn observed_cells(&self) -> impl Iterator<Item = (CellIndex, Cell)> + '_ {
        self.cells.tiles().flat_map(|(tile, cells)| {
            cells
                .iter()
                .enumerate()
                .filter(|(_, c)| c.is_observed())
                .map(move |(k, c)| (tile.cell(k), *c))
        })
    }

    /// Number of observed cells.
    pub fn num_observed_cells(&self) -> u64 {
        self.cells
            .tiles()
            .map(|(_, cells)| cells.iter().filter(|c| c.is_observed()).count() as u64)
            .sum()
    }

    /// Number of cells with a structure over their surface ([`Map::ceiling`]).
    pub fn num_ceilings(&self) -> u64 {
        self.ceilings
            .tiles()
            .map(|(_, t)| t.iter().filter(|c| c.is_some()).count() as u64)
            .sum()
    }

    /// The smallest region holding every observed cell, or `None` for an empty map.
    pub fn observed_region(&self) -> Option<CellRegion> {
        let mut it = self.observed_cells().map(|(c, _)| c);
        let first = it.next()?;
        let (lo, hi) = it.fold((first, first), |(lo, hi), c| {
            (
                CellIndex::new(lo.i.min(c.i), lo.j.min(c.j)),
                CellIndex::new(hi.i.max(c.i), hi.j.max(c.j)),
            )
        });
        CellRegion::from_corners(lo, hi)
    }

    pub(crate) fn tiles(&self) -> impl Iterator<Item = (TileIndex, &[Cell; TILE_CELLS])> + '_ {
        self.cells.tiles()
    }

    pub(crate) fn insert_tile(&mut self, tile: TileIndex, cells: Box<[Cell; TILE_CELLS]>) -> Result<()> {
        let limit = self.config.memory_limit_bytes;
        let others = self.ceilings.memory_bytes() + self.own_bytes();
        self.cells
            .insert_tile(tile, cells, limit.saturating_sub(others))
            .map_err(|e| Error::MemoryLimit {
                requested_bytes: e.requested_bytes,
                limit_bytes: limit,
            })
    }

    /// Tiles of the ceiling layer that hold a ceiling, in a fixed order.
    pub(crate) fn ceiling_tiles(&self) -> impl Iterator<Item = (TileIndex, &[Ceiling; TILE_CELLS])> + '_ {
        self.ceilings
            .tiles()
            .filter(|(_, t)| t.iter().any(Ceiling::is_some))
    }

    pub(crate) fn insert_ceiling_tile(
        &mut self,
        tile: TileIndex,
        ceilings: Box<[Ceiling; TILE_CELLS]>,
    ) -> Result<()> {
        let limit = self.config.memory_limit_bytes;
        let others = self.cells.memory_bytes() + self.own_bytes();
        self.ceilings
            .insert_tile(tile, ceilings, limit.saturating_sub(others))
            .map_err(|e| Error::MemoryLimit {
                requested_bytes: e.requested_bytes.saturating_add(others),
                limit_bytes: limit,
            })
    }

    pub(crate) fn restore_counters(&mut self, num_scans: u64, totals: IntegrationStats) {
        self.num_scans = num_scans;
        self.totals = totals;
    }
}
