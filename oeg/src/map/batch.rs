//! Many scans at once: [`Map::integrate_batch`]. A scan of a few hundred rays is too short to split between
//! threads, but consecutive short scans can be gathered side by side, a run of them per thread, when a model's
//! samples do not read the map (the paper's rules: [`Sampling::READS_MAP`]), so that what scan `k + 1` says
//! does not depend on scan `k`'s update. Each scan's evidence is moved out of its thread's grid into a list of
//! the cells it touched ([`TouchedCells`]); the cells are then updated tile by tile in parallel, each cell from
//! the scans' evidence in their order: the same map, bit for bit, as [`Map::integrate`] on each scan in turn.

use std::borrow::Borrow;

use rayon::prelude::*;

use super::apply::ScanUpdate;
use super::integrate::{SHORT_SCAN_RAYS, gather_rays};
use super::rule_set::OptionRules;
use super::sample::{Before, Sampling};
use super::scratch::{Evidence, HitSink, PaperEvidence, ScanScratch, Scratch};
use super::update::update_cell;
use super::{IntegrationStats, Map};
use crate::error::Error;
use crate::scan::Scan;
use crate::storage::{TILES_PER_JOB, TileGrid, TileIndex};

/// Scans of a window per thread. Each thread gathers its run of scans one after another into one grid, which
/// stays in its core's cache, and moves each scan's evidence into a list ([`TouchedCells`]); no core reads a
/// grid another wrote. A laser line's list is about 80 kB, so a thread's 8 stay within its core's second-level
/// cache for the update that reads them. Measured on the default run's log on 2 threads, in a build with phase
/// timers: 4, 8 and 16 scans a thread gathered and updated within a few per cent of each other. The design
/// before the lists, one grid a scan, was slower with more scans a thread (8 took 1.4x the gathering time of
/// 1), and with one its update read grids the other core had written: it gained nothing from the second
/// thread on laser lines.
const SCANS_PER_THREAD: usize = 8;

/// The parts of the budget a window's grids and lists are given at least: each may take at most this share.
const MIN_WINDOW_SHARES: usize = 16;

/// Why [`Map::integrate_batch`] stopped: the scan that failed and its error. The scans before it are in the
/// map; it and those after it are not.
#[derive(Debug, thiserror::Error)]
#[error("scan {index} of the batch: {error}")]
pub struct BatchError {
    /// The failed scan's place in the batch, from 0.
    pub index: usize,
    /// What [`Map::integrate`] said of it.
    pub error: Error,
}

impl Map {
    /// Integrates `scans` in order: the same map, bit for bit, as [`Map::integrate`] on each in turn, and the sum
    /// of their statistics.
    ///
    /// Under a model whose samples do not read the map (one whose scratch is the paper's evidence), runs of
    /// consecutive short scans (fewer than 8,192 rays) go in windows of 8 scans a thread: each thread gathers
    /// its scans one after another and keeps what each touched in a list, then the window's cells are updated
    /// tile by tile in parallel, each from the scans' lists in their order. This is what makes a robot's log,
    /// thousands of scans of a few hundred rays each, use every core; a long scan is split between the threads
    /// on its own ([`Map::integrate`]). Windows run only while the map and its scratch hold less than half the
    /// memory limit, each thread's grid, and its lists, under a sixteenth of that half: near it, or for a scan
    /// of very long rays, scans go one at a time, so that a limit stops the same scan at the same place. Under
    /// other models the scans go one at a time on a thread of the pool, where a long scan's runs and a large
    /// update share their work without a hand-over from outside it.
    ///
    /// # Errors
    /// The first scan [`Map::integrate`] refuses, with its place in `scans`.
    pub fn integrate_batch<S: Borrow<Scan> + Sync>(
        &mut self,
        scans: &[S],
    ) -> Result<IntegrationStats, BatchError> {
        // A model whose measurements correlate takes each scan's correlation from the views before it.
        if rayon::current_num_threads() < 2 {
            return self.integrate_one_by_one(scans);
        }
        // On a worker thread, so that the threads meet without a hand-over from outside the pool: a scan's
        // parallel steps (a long scan's runs, a large update) then share out their work within the pool.
        if !matches!(self.scratch, ScanScratch::Paper(_)) || self.config.model.measurement_correlation > 0.0 {
            return rayon::scope(|_| self.integrate_one_by_one(scans));
        }
        rayon::scope(|_| self.integrate_in_windows(scans))
    }

    /// [`Map::integrate`] on each of `scans` in turn.
    fn integrate_one_by_one<S: Borrow<Scan>>(&mut self, scans: &[S]) -> Result<IntegrationStats, BatchError> {
        let mut total = IntegrationStats::default();
        for (index, scan) in scans.iter().enumerate() {
            total += self
                .integrate(scan.borrow())
                .map_err(|error| BatchError { index, error })?;
        }
        Ok(total)
    }

    /// [`Map::integrate_batch`] on a thread of the pool, for a model whose scratch is the paper's evidence.
    fn integrate_in_windows<S: Borrow<Scan> + Sync>(
        &mut self,
        scans: &[S],
    ) -> Result<IntegrationStats, BatchError> {
        let threads = rayon::current_num_threads();
        let mut total = IntegrationStats::default();
        let mut next = 0;
        while next < scans.len() {
            let window = scans[next..]
                .iter()
                .take(threads * SCANS_PER_THREAD)
                .take_while(|s| Borrow::<Scan>::borrow(*s).rays.len() < SHORT_SCAN_RAYS)
                .count();
            if window > 1
                && let Some(stats) = self.integrate_side_by_side(&scans[next..next + window])
            {
                total += stats;
                next += window;
                continue;
            }
            let stats = self
                .integrate(scans[next].borrow())
                .map_err(|error| BatchError { index: next, error })?;
            total += stats;
            next += 1;
        }
        Ok(total)
    }

    /// `scans` gathered side by side and applied in order; `None`, with the map and scratch as they were, when
    /// they cannot be (a model whose samples read the map, an invalid scan, memory near the limit): the caller
    /// then integrates them one by one, which reports any error as it always does.
    fn integrate_side_by_side<S: Borrow<Scan> + Sync>(&mut self, scans: &[S]) -> Option<IntegrationStats> {
        if scans
            .par_iter()
            .any(|s| Borrow::<Scan>::borrow(s).validate().is_err())
        {
            return None;
        }
        let Self {
            config,
            geometry,
            cells,
            ceilings,
            scratch,
            levels,
            views,
            ..
        } = self;
        let ScanScratch::Paper(scratch) = scratch else {
            return None;
        };
        let before = Before {
            geometry,
            cells,
            ceilings,
            opts: &config.model,
            memory_limit_bytes: config.memory_limit_bytes,
            own_bytes: super::OWN_BYTES + views.memory_bytes(),
            rules: OptionRules::of(&config.model),
        };
        let budget = config.memory_limit_bytes / 2;
        // The window's lists live as long as the window: the scratch kept between scans is the grids.
        let mut lists: Vec<TouchedCells<PaperEvidence>> = std::iter::repeat_with(TouchedCells::default)
            .take(scans.len())
            .collect();
        let mut stats = gather_side_by_side(&before, scans, (scratch, &mut lists), budget)?;
        // The cells' tiles, under the budget: the map's tile index grows with them, which the gathering's check
        // could not count. Near the budget the scans go one by one, as the caller does with `None` (tiles placed
        // here stay, empty, as a failed scan's do in `Map::integrate`).
        let own_bytes = before.own_bytes;
        let lists_bytes: u64 = lists.iter().map(TouchedCells::memory_bytes).sum();
        let room =
            budget.saturating_sub(scratch.memory_bytes() + lists_bytes + ceilings.memory_bytes() + own_bytes);
        if !place_tiles(cells, &lists, room) {
            scratch.recycle();
            return None;
        }
        // Side by side only under independent measurements (the caller's check): no scan correlates with another.
        let update = ScanUpdate {
            levels: *levels,
            correlation: 0.0,
            own_bytes,
        };
        stats.num_cells_updated = apply_in_order(cells, &lists, &config.model, update);
        self.num_scans += scans.len() as u64;
        self.totals += stats;
        Some(stats)
    }
}

/// One scan's evidence for the cells its rays touched, moved out of the grid it was gathered in: tile by tile
/// in the order the grid marked them, each cell's offset in its tile and its evidence. A window's scans are kept
/// so, rather than each in a grid of its own, so that each thread gathers into one grid that stays in its
/// core's cache, and no core reads a grid another core wrote.
#[derive(Debug, Clone)]
struct TouchedCells<E> {
    /// Each tile, and the end of its cells in `offsets` and `evidence`.
    tiles: Vec<(TileIndex, u32)>,
    /// Each cell's offset in its tile ([`crate::storage::offset_in_tile`]).
    offsets: Vec<u16>,
    /// Each cell's evidence, in a vector of its own: copied from the grid as it is, not through a pair.
    evidence: Vec<E>,
}

impl<E> Default for TouchedCells<E> {
    fn default() -> Self {
        Self {
            tiles: Vec::new(),
            offsets: Vec::new(),
            evidence: Vec::new(),
        }
    }
}

impl<E: Evidence> TouchedCells<E> {
    /// Bytes held, spare capacity included.
    fn memory_bytes(&self) -> u64 {
        self.bytes_with(0, 0)
    }

    /// Bytes held once room is made for `tiles` tiles and `cells` cells.
    fn bytes_with(&self, tiles: usize, cells: usize) -> u64 {
        (self.tiles.capacity().max(tiles) * size_of::<(TileIndex, u32)>()
            + self.offsets.capacity().max(cells) * size_of::<u16>()
            + self.evidence.capacity().max(cells) * size_of::<E>()) as u64
    }

    /// Moves what `grid` marked into the list, tile by tile, and leaves the grid empty, its tiles in its pool
    /// ([`TileGrid::release_reset`]); false, with the grid emptied all the same and nothing allocated, if the
    /// list would hold more than `limit_bytes`.
    fn take_from(&mut self, grid: &mut TileGrid<E>, limit_bytes: u64) -> bool {
        self.clear();
        let fill = grid.fill();
        let marked_tiles = grid.marked_tiles_mut();
        // At most the marked cells (a short scan marks each cell it wrote: exactly those), counted before the
        // list takes room for them.
        let cells: usize = marked_tiles.iter().map(|(_, _, marked)| marked.num_cells()).sum();
        let fits = self.bytes_with(marked_tiles.len(), cells) <= limit_bytes;
        if fits {
            self.tiles.reserve_exact(marked_tiles.len());
            self.offsets.reserve_exact(cells);
            self.evidence.reserve_exact(cells);
        }
        for (tile, evidence, marked) in marked_tiles {
            if fits {
                marked.for_each(|k| {
                    if !evidence[k].paper().is_untouched() {
                        self.offsets.push(k as u16);
                        self.evidence.push(evidence[k]);
                    }
                });
                self.tiles.push((tile, self.offsets.len() as u32));
            }
            marked.reset(evidence, fill);
        }
        grid.release_reset();
        fits
    }

    /// Empties the list, keeping its memory.
    fn clear(&mut self) {
        self.tiles.clear();
        self.offsets.clear();
        self.evidence.clear();
    }

    /// The cells of `tile`, if the scan touched it: their offsets and their evidence.
    fn cells_in(&self, tile: TileIndex) -> (&[u16], &[E]) {
        let mut start = 0;
        for &(t, end) in &self.tiles {
            if t == tile {
                let cells = start as usize..end as usize;
                return (&self.offsets[cells.clone()], &self.evidence[cells]);
            }
            start = end;
        }
        (&[], &[])
    }
}

/// Gathers the scans in runs of consecutive scans, one run per thread, each scan into the run's grid (the main
/// grid, then the workers') and then moved into its list ([`TouchedCells`]), all under `budget` bytes for the
/// map and the scratch together (each grid under an equal share, each run's lists under another); `None`, the
/// scratch recycled, if a ray fails or the budget is exceeded.
fn gather_side_by_side<E: Sampling<Hits = ()>, S: Borrow<Scan> + Sync>(
    before: &Before,
    scans: &[S],
    (scratch, lists): (&mut Scratch<E>, &mut [TouchedCells<E>]),
    budget: u64,
) -> Option<IntegrationStats>
where
    (): HitSink<E>,
{
    if E::READS_MAP {
        return None;
    }
    let runs = rayon::current_num_threads().clamp(1, scans.len());
    let per_run = scans.len().div_ceil(runs);
    let map_bytes = before.map_bytes();
    // Each run's grid and each run's lists under an equal share of what the budget leaves, and at most a
    // sixteenth of it: a window is for scans of ordinary rays (a few megabytes of scratch each); a scan whose
    // rays need more goes alone, under the whole limit, rather than leave a window's grids holding (and the
    // allocator keeping) large pools.
    let share = budget.checked_sub(map_bytes)? / (2 * runs).max(MIN_WINDOW_SHARES) as u64;
    let Scratch { main, workers, .. } = scratch;
    if workers.len() < runs - 1 {
        workers.resize_with(runs - 1, || TileGrid::new(E::NONE));
    }
    let grids: Vec<&mut TileGrid<E>> = std::iter::once(main)
        .chain(workers.iter_mut())
        .take(runs)
        .collect();
    let gathered = grids
        .into_par_iter()
        .zip(scans.par_chunks(per_run))
        .zip(lists.par_chunks_mut(per_run))
        .map(|((grid, scans), lists)| {
            let mut stats = IntegrationStats::default();
            let list_limit = share / scans.len() as u64;
            for (scan, list) in scans.iter().zip(lists) {
                let scan: &Scan = scan.borrow();
                stats.num_rays += scan.rays.len() as u64;
                let rays = 0..scan.rays.len();
                if gather_rays(before, scan, rays, (grid, &mut ()), share, &mut stats, &|| false).is_err() {
                    grid.recycle_marked();
                    return None;
                }
                if !list.take_from(grid, list_limit) {
                    return None;
                }
            }
            Some(stats)
        })
        .collect::<Option<Vec<_>>>();
    // The tiles the cells' grid will place, at most one per tile of each scan.
    let new_tiles: usize = lists
        .iter()
        .map(|l| l.tiles.iter().filter(|(t, _)| !before.cells.has_tile(*t)).count())
        .sum();
    let lists_bytes: u64 = lists.iter().map(TouchedCells::memory_bytes).sum();
    let needed = map_bytes
        .saturating_add(scratch.memory_bytes())
        .saturating_add(lists_bytes)
        .saturating_add((new_tiles * TileGrid::<crate::cell::Cell>::tile_bytes()) as u64);
    match gathered {
        Some(all) if needed <= budget => {
            Some(all.into_iter().fold(IntegrationStats::default(), |mut a, s| {
                a += s;
                a
            }))
        }
        _ => {
            scratch.recycle();
            None
        }
    }
}

/// Places the cells' tiles that the scans of `lists` touched, scan by scan in the order [`Map::integrate`]
/// places them, the cells' grid under `limit_bytes`; false if one does not fit.
fn place_tiles<E>(
    cells: &mut TileGrid<crate::cell::Cell>,
    lists: &[TouchedCells<E>],
    limit_bytes: u64,
) -> bool {
    lists
        .iter()
        .flat_map(|l| l.tiles.iter())
        .all(|(tile, _)| cells.tile_or_insert(*tile, limit_bytes).is_ok())
}

/// Updates every cell the scans of `lists` touched, from each scan's evidence in their order, tile by tile in
/// parallel; the cells' tiles are placed ([`place_tiles`]). Returns the cell updates.
fn apply_in_order<E: Sampling<Hits = ()>>(
    cells: &mut TileGrid<crate::cell::Cell>,
    lists: &[TouchedCells<E>],
    opts: &crate::model::ModelOptions,
    update: ScanUpdate,
) -> u64 {
    let mut tiles: Vec<TileIndex> = lists
        .iter()
        .flat_map(|l| l.tiles.iter().map(|(t, _)| *t))
        .collect();
    // Row by row over the tile index, the order the cells' grid lends them in.
    tiles.sort_unstable_by_key(|t| (t.tj, t.ti));
    tiles.dedup();
    cells
        .tiles_mut_in_order(tiles)
        .into_par_iter()
        .with_max_len(TILES_PER_JOB)
        .map(|(tile, cells)| {
            let mut updated = 0;
            for list in lists {
                let (offsets, evidence) = list.cells_in(tile);
                for (k, evidence) in offsets.iter().zip(evidence) {
                    update_cell(&mut cells[usize::from(*k)], (evidence, &()), opts, update);
                    updated += 1;
                }
            }
            updated
        })
        .sum()
}
