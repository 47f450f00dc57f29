//! A scan's update: every cell its rays touched, updated once from the evidence they gathered (eq. 5-9, or the
//! rule the options choose: `update.rs`), tile by tile in parallel, then the ceiling layer.

use rayon::prelude::*;

use super::IntegrationStats;
use super::scratch::{Evidence, HitStore};
use super::update::update_cell;
use crate::cell::Cell;
use crate::error::{Error, Result};
use crate::model::{Ceiling, OverheadHits, update_ceiling};
use crate::storage::{Marked, TILE_CELLS, TILES_PER_JOB, TileGrid};

/// The log-odds levels a cell update compares with.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LogOddsLevels {
    /// `L` above which a cell is occupied.
    pub(crate) occupied: f32,
    /// The log-odds of a plain free sample.
    pub(crate) free: f32,
}

/// What a scan's update reads beside the model: the log-odds levels, how the scan's measurements correlate with
/// the map's estimates ([`super::views::RecentViews::correlation`]), and the map's own bytes for the memory
/// checks.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScanUpdate {
    pub(crate) levels: LogOddsLevels,
    /// The correlation `rho` of this scan's measurements with the estimates before it, in [0, 1].
    pub(crate) correlation: f32,
    /// Bytes of the map's own structure and recent views (the part of [`super::Map::memory_bytes`] beside the
    /// tiles).
    pub(crate) own_bytes: u64,
}

/// Cells a scan touched from which its tiles are updated in parallel. Below it the thread that gathered the
/// scan updates its cells from its own cache: on the default run's log under `robust`, whose laser lines of
/// 361 rays are integrated one by one and touch a few thousand cells each, 4,096 made two threads slower than
/// one (`oeg map`'s `integrate_wall_time_s`: 1.79 s against 1.58 s at 16,384, one thread 1.93 s).
const MIN_CELLS_IN_PARALLEL: usize = 16_384;
/// Updates every cell the scan touched, once: first the tiles the update needs are placed, in a fixed order
/// (so a memory limit leaves the map without any of this scan's updates), then the cells are updated, tile by
/// tile in parallel, then the ceiling layer.
pub(super) fn apply<E: Evidence>(
    cells: &mut TileGrid<Cell>,
    ceilings: &mut TileGrid<Ceiling>,
    (scratch, hits): (&TileGrid<E>, &E::Hits),
    config: &super::MapConfig,
    update: ScanUpdate,
    stats: &mut IntegrationStats,
) -> Result<()> {
    let opts = &config.model;
    let ceiling_rule = opts.overhead_hits == OverheadHits::Ceiling;
    let scratch_bytes = scratch.memory_bytes() + hits.memory_bytes();
    // The map's own structure counts too ([`super::Map::memory_bytes`]).
    let limit = config
        .memory_limit_bytes
        .saturating_sub(scratch_bytes + update.own_bytes);
    // A refusal reports what the map and its scratch would have held: the refusing layer's request, the other
    // layer's bytes, the scratch and the map's own structure.
    let memory_error = |other_layer_bytes: u64| {
        move |e: crate::storage::CapacityExceeded| Error::MemoryLimit {
            requested_bytes: e
                .requested_bytes
                .saturating_add(other_layer_bytes)
                .saturating_add(scratch_bytes + update.own_bytes),
            limit_bytes: config.memory_limit_bytes,
        }
    };
    // The ceiling layer: allocated where a ceiling is hit, updated where one exists.
    let mut overhead_tiles = E::overhead_tiles(hits).to_vec();
    overhead_tiles.sort_unstable();
    overhead_tiles.dedup();
    for (tile, _, _) in scratch.marked_tiles() {
        let ceilings_bytes = ceilings.memory_bytes();
        cells
            .tile_or_insert(tile, limit.saturating_sub(ceilings_bytes))
            .map_err(memory_error(ceilings_bytes))?;
        if ceiling_rule && overhead_tiles.binary_search(&tile).is_ok() {
            let cells_bytes = cells.memory_bytes();
            ceilings
                .tile_or_insert(tile, limit.saturating_sub(cells_bytes))
                .map_err(memory_error(cells_bytes))?;
        }
    }
    // The marked tiles come row by row over the tile index, the order the cells' grid lends them in.
    let work: Vec<_> = cells
        .tiles_mut_in_order(scratch.marked_tiles().map(|(tile, _, _)| tile))
        .into_iter()
        .filter_map(|(tile, cells)| {
            let (evidence, marks) = scratch.marked_tile(tile)?;
            Some((cells, evidence, marks))
        })
        .collect();
    let update_tile = |(cells, evidence, marks): (&mut [Cell; TILE_CELLS], &[E; TILE_CELLS], Marked<'_>)| {
        update_marked(cells, (evidence, hits), marks, opts, update)
    };
    // Cells to update: below [`MIN_CELLS_IN_PARALLEL`], handing tiles to threads costs more than it saves.
    let touched: usize = work.iter().map(|(_, _, marks)| marks.num_cells()).sum();
    stats.num_cells_updated += if touched >= MIN_CELLS_IN_PARALLEL && rayon::current_num_threads() > 1 {
        work.into_par_iter()
            .with_max_len(TILES_PER_JOB)
            .map(update_tile)
            .sum::<u64>()
    } else {
        work.into_iter().map(update_tile).sum::<u64>()
    };
    if ceiling_rule {
        update_ceilings((ceilings, cells), (scratch, hits), opts, update);
    }
    Ok(())
}

/// The ceiling layer's update ([`OverheadHits::Ceiling`]), where the scan said something about a ceiling, over
/// the cells' surfaces as the scan left them.
fn update_ceilings<E: Evidence>(
    (ceilings, cells): (&mut TileGrid<Ceiling>, &TileGrid<Cell>),
    (scratch, hits): (&TileGrid<E>, &E::Hits),
    opts: &crate::model::ModelOptions,
    update: ScanUpdate,
) {
    for (tile, evidence, marks) in scratch.marked_tiles() {
        let Some(ceilings) = ceilings.tile_mut(tile) else {
            continue;
        };
        let surfaces = cells.tile(tile);
        marks.for_each(|k| {
            let Some((ev, cell_hits)) = evidence[k].full(hits).filter(|(ev, h)| ev.touches_ceiling(*h))
            else {
                return;
            };
            let ceiling = &mut ceilings[k];
            *ceiling = update_ceiling(
                *ceiling,
                cell_hits.and_then(|h| {
                    let surface_var_m2 = surfaces.and_then(|s| s[k].elevation()).map(|e| e.var_m2);
                    h.ceiling_hit(
                        opts.measurement_correlation,
                        opts.surface_band_sigmas,
                        surface_var_m2,
                    )
                }),
                ev.ceiling_contradicted,
                ev.ceiling_clear_m,
                opts,
                update.correlation,
                update.levels.occupied,
            );
        });
    }
}

/// Updates a tile's cells that a scan touched, from their evidence (each once, in any order: every cell's update
/// reads its own evidence alone). Returns the cells updated.
pub(super) fn update_marked<E: Evidence>(
    cells: &mut [Cell; TILE_CELLS],
    (evidence, hits): (&[E; TILE_CELLS], &E::Hits),
    marks: Marked<'_>,
    opts: &crate::model::ModelOptions,
    update: ScanUpdate,
) -> u64 {
    let mut updated = 0u64;
    marks.for_each(|k| {
        let ev = &evidence[k];
        if !ev.paper().is_untouched() {
            updated += 1;
            update_cell(&mut cells[k], (ev, hits), opts, update);
        }
    });
    updated
}
