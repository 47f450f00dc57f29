//! Many scans at once: [`Map::integrate_batch`]. A scan of a few hundred rays is too short to split between
//! threads, but consecutive short scans can be gathered side by side, one per thread, when a model's samples do
//! not read the map (the paper's rules: [`Sampling::READS_MAP`]), so that what scan `k + 1` says does not
//! depend on scan `k`'s update. The cells are then updated tile by tile in parallel, each cell from the scans'
//! evidence in their order: the same map, bit for bit, as [`Map::integrate`] on each scan in turn.

use std::borrow::Borrow;

use rayon::prelude::*;

use super::apply::{ScanUpdate, update_marked};
use super::integrate::{SHORT_SCAN_RAYS, gather_rays};
use super::sample::{Before, Sampling};
use super::scratch::{ScanScratch, Scratch};
use super::{IntegrationStats, Map};
use crate::error::Error;
use crate::scan::Scan;
use crate::storage::{TileGrid, marked_by_tile};

/// Scans of a window per thread. One: each scan of a window is gathered into a scratch grid of its own, and
/// every grid more is a working set more that the cores' caches must hold between two uses of it. Measured on
/// the default run's log on 2 threads, in a build with phase timers: 8 scans a thread took 1.4x the gathering
/// time and 1.3x the update time of 1; the threads' meetings, twice a window, cost less than that.
const SCANS_PER_THREAD: usize = 1;

/// The parts of the budget a window's grids are given at least: each grid may take at most this share.
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
    /// consecutive short scans (fewer than 8,192 rays) go in windows of one scan a thread: a window's scans
    /// are gathered side by side, then its cells are updated tile by tile in parallel, where the evidence read
    /// is reset. This is what makes a robot's log, thousands of scans of a few hundred rays each, use every
    /// core; a long scan is split between the threads on its own ([`Map::integrate`]). Windows run only while
    /// the map and its scratch hold less than half the memory limit, each scan's scratch under a sixteenth of
    /// that half: near it, or for a scan of very long rays, scans go one at a time, so that a limit stops the
    /// same scan at the same place.
    ///
    /// # Errors
    /// The first scan [`Map::integrate`] refuses, with its place in `scans`.
    pub fn integrate_batch<S: Borrow<Scan> + Sync>(
        &mut self,
        scans: &[S],
    ) -> Result<IntegrationStats, BatchError> {
        // A model whose measurements correlate takes each scan's correlation from the views before it.
        if rayon::current_num_threads() < 2
            || !matches!(self.scratch, ScanScratch::Paper(_))
            || self.config.model.measurement_correlation > 0.0
        {
            let mut total = IntegrationStats::default();
            for (index, scan) in scans.iter().enumerate() {
                total += self
                    .integrate(scan.borrow())
                    .map_err(|error| BatchError { index, error })?;
            }
            return Ok(total);
        }
        // On a worker thread, so that the threads meet without a hand-over from outside the pool.
        rayon::scope(|_| self.integrate_in_windows(scans))
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
        };
        let budget = config.memory_limit_bytes / 2;
        let mut stats = gather_side_by_side(&before, scans, scratch, budget)?;
        // The cells' tiles, under the budget: the map's tile index grows with them, which the gathering's check
        // could not count. Near the budget the scans go one by one, as the caller does with `None` (tiles placed
        // here stay, empty, as a failed scan's do in `Map::integrate`).
        let own_bytes = before.own_bytes;
        let room = budget.saturating_sub(scratch.memory_bytes() + ceilings.memory_bytes() + own_bytes);
        if !place_tiles(cells, scratch, scans.len(), room) {
            scratch.recycle();
            return None;
        }
        // The evidence is reset as it is read: the scratch is empty again.
        // Side by side only under independent measurements (the caller's check): no scan correlates with another.
        let update = ScanUpdate {
            levels: *levels,
            correlation: 0.0,
            own_bytes,
        };
        stats.num_cells_updated = apply_in_order(cells, scratch, scans.len(), &config.model, update);
        self.num_scans += scans.len() as u64;
        self.totals += stats;
        Some(stats)
    }
}

/// Gathers scan `k` into the scratch's grid `k` (the main grid, then the workers'), all in parallel, under
/// `budget` bytes for the map and every grid together (each grid under an equal share); `None`, the scratch
/// recycled, if a ray fails or the budget is exceeded.
fn gather_side_by_side<E: Sampling<Hits = ()>, S: Borrow<Scan> + Sync>(
    before: &Before,
    scans: &[S],
    scratch: &mut Scratch<E>,
    budget: u64,
) -> Option<IntegrationStats> {
    if E::READS_MAP {
        return None;
    }
    let map_bytes = before.map_bytes();
    // Each grid under an equal share of what the budget leaves, and at most a sixteenth of it: a window is for
    // scans of ordinary rays (a few megabytes of scratch each); a scan whose rays need more goes alone, under
    // the whole limit, rather than leave a window's grids holding (and the allocator keeping) large pools.
    let share = budget.checked_sub(map_bytes)? / scans.len().max(MIN_WINDOW_SHARES) as u64;
    if scratch.workers.len() < scans.len() - 1 {
        scratch
            .workers
            .resize_with(scans.len() - 1, || TileGrid::new(E::NONE));
    }
    let grids: Vec<&mut TileGrid<E>> = std::iter::once(&mut scratch.main)
        .chain(scratch.workers.iter_mut())
        .take(scans.len())
        .collect();
    let gathered = grids
        .into_par_iter()
        .zip(scans.par_iter())
        .map(|(grid, scan)| {
            let scan: &Scan = scan.borrow();
            let mut stats = IntegrationStats {
                num_rays: scan.rays.len() as u64,
                ..IntegrationStats::default()
            };
            gather_rays(
                before,
                scan,
                0..scan.rays.len(),
                (grid, &mut ()),
                share,
                &mut stats,
                &|| false,
            )
            .map(|()| stats)
        })
        .collect::<crate::error::Result<Vec<_>>>();
    // The tiles the cells' grid will place, at most one per marked tile of each scan.
    let new_tiles: usize = std::iter::once(&scratch.main)
        .chain(scratch.workers.iter())
        .map(|g| {
            g.marked_tiles()
                .filter(|(t, _, _)| !before.cells.has_tile(*t))
                .count()
        })
        .sum();
    let needed = map_bytes
        .saturating_add(scratch.memory_bytes())
        .saturating_add((new_tiles * TileGrid::<crate::cell::Cell>::tile_bytes()) as u64);
    match gathered {
        Ok(all) if needed <= budget => Some(all.into_iter().fold(IntegrationStats::default(), |mut a, s| {
            a += s;
            a
        })),
        _ => {
            scratch.recycle();
            None
        }
    }
}

/// Places the cells' tiles that the first `num_scans` grids of the scratch touched, scan by scan in the order
/// [`Map::integrate`] places them, the cells' grid under `limit_bytes`; false if one does not fit.
fn place_tiles<E: Sampling<Hits = ()>>(
    cells: &mut TileGrid<crate::cell::Cell>,
    scratch: &Scratch<E>,
    num_scans: usize,
    limit_bytes: u64,
) -> bool {
    std::iter::once(&scratch.main)
        .chain(scratch.workers.iter())
        .take(num_scans)
        .flat_map(|grid| grid.marked_tiles())
        .all(|(tile, _, _)| cells.tile_or_insert(tile, limit_bytes).is_ok())
}

/// Updates every cell the first `num_scans` grids of the scratch touched, from each grid's evidence in their
/// order, tile by tile in parallel, and resets that evidence where it was read, on the same thread (while it is
/// in that core's cache), before the grids take their tiles back; the cells' tiles are placed ([`place_tiles`]).
/// Returns the cell updates.
fn apply_in_order<E: Sampling<Hits = ()>>(
    cells: &mut TileGrid<crate::cell::Cell>,
    scratch: &mut Scratch<E>,
    num_scans: usize,
    opts: &crate::model::ModelOptions,
    update: ScanUpdate,
) -> u64 {
    let Scratch { main, workers, .. } = scratch;
    let mut grids: Vec<&mut TileGrid<E>> = std::iter::once(main)
        .chain(workers.iter_mut())
        .take(num_scans)
        .collect();
    let fill = grids.first().map_or(E::NONE, |g| g.fill());
    let work = marked_by_tile(cells, grids.iter_mut().map(|g| &mut **g));
    let updated = work
        .into_par_iter()
        .map(|(mut cells, evidence)| {
            let mut updated = 0;
            for (evidence, marks) in evidence {
                if let Some(cells) = cells.as_deref_mut() {
                    updated += update_marked(cells, (evidence, &()), marks, opts, update);
                }
                marks.reset(evidence, fill);
            }
            updated
        })
        .sum();
    grids.iter_mut().for_each(|g| g.release_reset());
    updated
}
