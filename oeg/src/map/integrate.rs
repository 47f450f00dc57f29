//! Scan integration: the paper's Algorithm 1. Every ray of a scan is cast through the grid and what it says
//! about each cell is gathered (eq. 10-12, `sample.rs`); then each touched cell is updated once (`apply.rs`).
//!
//! Both steps use the threads rayon gives them ([`rayon::current_num_threads`]), and the map is the same, bit
//! for bit, on any number: a long scan's rays are gathered in runs, one per thread, into separate scratch
//! grids merged in the runs' order (`runs.rs`, where the evidence merges exactly: [`Evidence::exact_merge`],
//! the hits whose combination depends on their order replayed after), and the touched tiles are updated in
//! parallel, each cell from its own evidence alone.

use std::ops::Range;

use super::apply::{ScanUpdate, apply};
use super::rule_set::{BandCeilingRules, OptionRules, Rules};
use super::runs::gather_in_parallel;
use super::sample::{Before, Here, RaySpan, Sampling};
use super::scratch::{Evidence, HitSink, HitStore, ScanScratch, Scratch};
use super::{IntegrationStats, Map};
use crate::error::{Error, Result};
use crate::scan::Scan;
use crate::storage::{TILE_CELLS, TILE_SHIFT, TileGrid, TileIndex};
use crate::traversal::GroundTraversal;

/// Rays between two questions of [`Map::integrate_unless`]'s `stop`: a few milliseconds of work.
pub const RAYS_BETWEEN_STOP_CHECKS: usize = 16_384;

impl Map {
    /// Integrates one scan (the paper's Algorithm 1 for every ray, then one update per touched cell).
    ///
    /// # Errors
    /// [`Error::InvalidScan`] if the scan holds non-finite numbers (nothing is changed), or
    /// [`Error::MemoryLimit`] if storing the touched cells would exceed the limit (the map is left without
    /// this scan's updates).
    pub fn integrate(&mut self, scan: &Scan) -> Result<IntegrationStats> {
        // Never stopped: the check compiles away.
        self.integrate_stopping(scan, || false)
    }

    /// [`Map::integrate`], asking `stop` every [`RAYS_BETWEEN_STOP_CHECKS`] rays whether to stop: a long scan
    /// (millions of rays from Python) can be cancelled within a bounded time. The threads that gather a long
    /// scan's rays each ask, so `stop` is `Sync` and, once it says stop, should keep saying so.
    ///
    /// # Errors
    /// As [`Map::integrate`], and [`Error::Cancelled`] when `stop` said so (the map is left without this scan's
    /// updates).
    pub fn integrate_unless(
        &mut self,
        scan: &Scan,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<IntegrationStats> {
        self.integrate_stopping(scan, stop)
    }

    fn integrate_stopping(
        &mut self,
        scan: &Scan,
        stop: impl Fn() -> bool + Sync,
    ) -> Result<IntegrationStats> {
        scan.validate()?;
        let mut stats = IntegrationStats {
            num_rays: scan.rays.len() as u64,
            ..IntegrationStats::default()
        };
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
        let update = ScanUpdate {
            levels: *levels,
            correlation: views.correlation(
                &scan.origin_in_world,
                &scan.sensor.noise,
                &config.model,
                geometry.resolution_m(),
            ),
            own_bytes: super::OWN_BYTES + views.memory_bytes_after_push(&config.model),
        };
        let before = Before {
            geometry,
            cells,
            ceilings,
            opts: &config.model,
            memory_limit_bytes: config.memory_limit_bytes,
            own_bytes: update.own_bytes,
            rules: OptionRules::of(&config.model),
        };
        let done = match scratch {
            ScanScratch::Paper(s) => gather(&before, scan, s, &mut stats, &stop)
                .and_then(|()| apply(cells, ceilings, (&s.main, &s.hits), config, update, &mut stats)),
            ScanScratch::Full(s) => match BandCeilingRules::of(&config.model) {
                Some(rules) => gather(&before.with_rules(rules), scan, s, &mut stats, &stop),
                None => gather(&before, scan, s, &mut stats, &stop),
            }
            .and_then(|()| apply(cells, ceilings, (&s.main, &s.hits), config, update, &mut stats)),
        };
        scratch.recycle();
        done?;
        views.push(scan.origin_in_world, scan.sensor.noise, &config.model);
        self.num_scans += 1;
        self.totals += stats;
        Ok(stats)
    }
}

/// Rays of a short scan, at most: a few milliseconds of work. Its walks mark each cell they cross first
/// ([`TileGrid::slot_tile_and_marks_mut`]), so its update and clearing visit those cells alone rather than the
/// rows they crossed ([`TileGrid::mark_rows`], free in the walk): a short scan touches a few cells of many
/// rows, where a long scan's many rays cross each cell many times. A batch gathers short scans side by side
/// ([`Map::integrate_batch`]); a long scan is split between the threads on its own.
pub(super) const SHORT_SCAN_RAYS: usize = 8 * 1024;

/// Rays each thread gathers at least: below this, splitting a scan costs more than it saves.
const MIN_RAYS_PER_THREAD: usize = 512;

/// Casts every ray of the scan into `scratch.main`: in one run, or, for a long scan whose evidence merges
/// exactly, in one run per thread merged in order. A parallel gathering that fails (a memory limit, a corrupt
/// ray) is done again in one run, which reports the failure as it always does.
fn gather<E: Sampling, R: Rules>(
    before: &Before<R>,
    scan: &Scan,
    scratch: &mut Scratch<E>,
    stats: &mut IntegrationStats,
    stop: &(impl Fn() -> bool + Sync),
) -> Result<()> {
    let num_rays = scan.rays.len();
    let runs = rayon::current_num_threads().min(num_rays / MIN_RAYS_PER_THREAD);
    let scratch_limit = before.memory_limit_bytes.saturating_sub(before.map_bytes());
    if runs > 1
        && let Some(merge) = E::exact_merge(before.opts)
    {
        match gather_in_parallel(before, scan, scratch, runs, scratch_limit, merge, stop) {
            Ok(run_stats) => {
                *stats += run_stats;
                return Ok(());
            }
            Err(Error::Cancelled) => return Err(Error::Cancelled),
            Err(_) => {
                scratch.main.recycle_marked();
                scratch.hits.clear();
                scratch.workers.clear();
            }
        }
    }
    // The workers' grids, kept for the next long scan, count against the limit; when they are what stands in
    // the way, they are given back and the scan is gathered again, as on one thread, where there are none.
    let workers_bytes = scratch.memory_bytes() - scratch.main.memory_bytes();
    let mut run_stats = IntegrationStats::default();
    let limit = scratch_limit.saturating_sub(workers_bytes);
    match gather_rays(
        before,
        scan,
        0..num_rays,
        (&mut scratch.main, &mut scratch.hits),
        limit,
        &mut run_stats,
        stop,
    ) {
        Err(Error::MemoryLimit { .. }) if workers_bytes > 0 => {
            scratch.main.recycle_marked();
            scratch.hits.clear();
            scratch.workers.clear();
            gather_rays(
                before,
                scan,
                0..num_rays,
                (&mut scratch.main, &mut scratch.hits),
                scratch_limit,
                stats,
                stop,
            )
        }
        done => {
            *stats += run_stats;
            done
        }
    }
}

/// Casts the scan's rays `rays` into `grid` and what its evidence keeps beside it (at most `limit_bytes` of
/// both): each ray's span ([`RaySpan::of`]), checked against the grid and the limit ([`walk_of`]), then what
/// each crossed cell learns from it ([`Sampling`]).
pub(super) fn gather_rays<E: Sampling, R: Rules, L: HitSink<E>>(
    before: &Before<R>,
    scan: &Scan,
    rays: Range<usize>,
    (grid, hits): (&mut TileGrid<E>, &mut L),
    limit_bytes: u64,
    stats: &mut IntegrationStats,
    stop: &impl Fn() -> bool,
) -> Result<()> {
    let by_cell = scan.rays.len() < SHORT_SCAN_RAYS;
    for index in rays {
        if index % RAYS_BETWEEN_STOP_CHECKS == RAYS_BETWEEN_STOP_CHECKS - 1 && stop() {
            return Err(Error::Cancelled);
        }
        let Some(span) = RaySpan::of(scan, &scan.rays[index], before.opts) else {
            stats.num_rays_skipped += 1;
            continue;
        };
        let walk = walk_of(before, grid, index, &span, (limit_bytes, hits.memory_bytes()))?;
        stats.num_cell_visits += walk.len() as u64;
        if span.hit.is_some() {
            let room = limit_bytes.saturating_sub(grid.memory_bytes());
            hits.reserve(span.near_hit_cells(before.geometry.resolution_m()), room)
                .map_err(|e| before.refusal(e.requested_bytes.saturating_add(grid.memory_bytes())))?;
        }
        let walk_limit = limit_bytes.saturating_sub(hits.memory_bytes());
        let scratch = (&mut *grid, &mut *hits);
        match (span.hit.is_some(), by_cell) {
            (true, true) => sample_walk::<E, R, L, true, true>(before, &span, walk, scratch, walk_limit)?,
            (true, false) => sample_walk::<E, R, L, true, false>(before, &span, walk, scratch, walk_limit)?,
            (false, true) => sample_walk::<E, R, L, false, true>(before, &span, walk, scratch, walk_limit)?,
            (false, false) => sample_walk::<E, R, L, false, false>(before, &span, walk, scratch, walk_limit)?,
        }
    }
    Ok(())
}

/// What one ray's walk says about each cell it crosses ([`Sampling`]), added to `grid`'s evidence tile by tile:
/// a straight walk crosses a tile once, in a run of consecutive rows, so each tile is looked up once, and the
/// rows are marked once ([`TileGrid::mark_rows`]) or, `BY_CELL`, each cell the scan crosses for the first time
/// ([`TileGrid::slot_tile_and_marks_mut`], [`SHORT_SCAN_RAYS`]). `HIT`: whether the ray hit something
/// (else every cell it crosses is cleared: [`Sampling::cleared`]).
#[inline(always)]
fn sample_walk<E: Sampling, R: Rules, L: HitSink<E>, const HIT: bool, const BY_CELL: bool>(
    before: &Before<R>,
    span: &RaySpan,
    mut walk: GroundTraversal,
    (grid, hits): (&mut TileGrid<E>, &mut L),
    limit_bytes: u64,
) -> Result<()> {
    let mut z_enter_m = span.height_at(span.l_lo);
    while let Some(tile) = walk.tile() {
        let slot = grid
            .slot_or_insert(tile, limit_bytes)
            .map_err(|e| before.refusal(e.requested_bytes.saturating_add(hits.memory_bytes())))?;
        let (evidence, mut marks) = if BY_CELL {
            let (evidence, marks) = grid.slot_tile_and_marks_mut(slot);
            (evidence, Some(marks))
        } else {
            (grid.slot_tile_mut(slot), None)
        };
        let mut here = Here::tile::<E, R>(before, tile);
        let mut marked = marks.as_ref().map_or(0, |m| m.count());
        let (first_offset, mut last_offset) = (walk.offset_in_tile(), 0);
        walk.walk_tile(
            #[inline(always)]
            |offset, crossing| {
                last_offset = offset;
                here.offset = offset;
                // The beam's height where it leaves this cell is where it enters the next one.
                let z_exit_m = span.height_at(crossing.l_exit);
                (here.beam_top_m, here.beam_bottom_m) = RaySpan::top_and_bottom(z_enter_m, z_exit_m);
                z_enter_m = z_exit_m;
                let ev = &mut evidence[offset & (TILE_CELLS - 1)];
                if let Some(marks) = marks.as_deref_mut() {
                    marked = marks.mark_after(marked, offset, ev.first_visit());
                }
                if !HIT {
                    ev.cleared(before, span, crossing, &here);
                } else if crossing.l_exit < span.free_until {
                    ev.free(before, span, crossing, &here);
                } else {
                    ev.near_hit(hits, before, span, crossing, &here);
                }
            },
        );
        if let Some(marks) = marks {
            marks.set_len(marked);
        } else {
            let first_row = first_offset >> TILE_SHIFT;
            grid.mark_rows(slot, rows_between(first_row, last_offset >> TILE_SHIFT));
        }
    }
    Ok(())
}

/// The rows from `a` to `b`, either way round, as a row mask.
fn rows_between(a: usize, b: usize) -> u64 {
    let (lo, hi) = (a.min(b), a.max(b));
    (u64::MAX >> (63 - hi)) & (u64::MAX << lo)
}

/// The cells under a ray's span, refused when the span leaves the grid's index range or must take `grid` past
/// `limit_bytes` beside the scan's hit log of `log_bytes` (checked before a single tile of it is allocated).
#[inline(always)]
fn walk_of<E: Evidence, R: Rules>(
    before: &Before<R>,
    grid: &TileGrid<E>,
    index: usize,
    span: &RaySpan,
    (limit_bytes, log_bytes): (u64, u64),
) -> Result<GroundTraversal> {
    let limit_bytes = limit_bytes.saturating_sub(log_bytes);
    let geometry = before.geometry;
    let (o, dir) = (span.origin, span.dir);
    let (start, end) = (o + dir * span.l_lo, o + dir * span.l_hi);
    let walk = GroundTraversal::new(geometry, (o.x, o.y), (dir.x, dir.y), span.l_lo, span.l_hi).ok_or_else(
        || {
            Error::InvalidScan(format!(
                "ray {index} runs from ({:.3}, {:.3}) m to ({:.3}, {:.3}) m, beyond the grid's index \
                 range (2^31 cells of {} m from the origin): is the sensor's pose or this point corrupt?",
                start.x,
                start.y,
                end.x,
                end.y,
                geometry.resolution_m()
            ))
        },
    )?;
    // Fail fast: the walk touches at least one tile per tile edge it spans, so a ray that must exceed the
    // memory limit is refused before a single tile of it is allocated.
    let (ta, tb) = (TileIndex::of(walk.first_cell()), TileIndex::of(walk.last_cell()));
    let tiles_spanned = u64::from(ta.ti.abs_diff(tb.ti).max(ta.tj.abs_diff(tb.tj))) + 1;
    let tile_bytes = TileGrid::<E>::tile_bytes() as u64;
    let least_bytes = tiles_spanned.saturating_mul(tile_bytes);
    if least_bytes > limit_bytes {
        return Err(before.refusal(least_bytes.saturating_add(log_bytes)));
    }
    // The scan's rays together: when this ray may need more than the scratch has left (long rays, such as a
    // stereo hit's error band far away, add up), count the tiles it needs that the scratch lacks, before one
    // of them is allocated. Rays are straight, so their tiles come in runs.
    let in_use = grid.memory_bytes();
    let left = limit_bytes.saturating_sub(in_use);
    let pooled = grid.num_pooled() as u64;
    if least_bytes > left.saturating_add(pooled.saturating_mul(tile_bytes)) {
        let (mut new_tiles, mut last) = (0u64, None);
        for crossing in walk.clone() {
            let tile = TileIndex::of(crossing.cell);
            if last != Some(tile) {
                last = Some(tile);
                new_tiles += u64::from(!grid.has_tile(tile));
            }
        }
        let needed = new_tiles.saturating_sub(pooled).saturating_mul(tile_bytes);
        if needed > left {
            return Err(before.refusal(needed.saturating_add(in_use).saturating_add(log_bytes)));
        }
    }
    Ok(walk)
}

#[cfg(test)]
mod tests {
    use super::rows_between;

    #[test]
    fn rows_between_covers_both_ends_either_way_round() {
        assert_eq!(rows_between(0, 0), 1);
        assert_eq!(rows_between(5, 3), 0b11_1000);
        assert_eq!(rows_between(3, 5), 0b11_1000);
        assert_eq!(rows_between(0, 63), u64::MAX);
        assert_eq!(rows_between(63, 63), 1 << 63);
    }
}
