//! A long scan's rays gathered in parallel: in runs of consecutive rays, one per thread, each into a scratch
//! grid of its own, merged into the first run's in the runs' order where the evidence merges exactly
//! ([`Evidence::exact_merge`]), with the hits whose combination depends on their order replayed after
//! ([`Evidence::replay`]). The map is the same, bit for bit, as when one thread gathers the rays in order.

use rayon::prelude::*;

use super::IntegrationStats;
use super::integrate::gather_rays;
use super::rule_set::Rules;
use super::sample::{Before, Sampling};
use super::scratch::{Evidence, ExactMerge, HitStore, Scratch};
use crate::error::{Error, Result};
use crate::scan::Scan;
use crate::storage::{CapacityExceeded, TILES_PER_JOB, TileGrid, marked_by_tile};

/// [`super::integrate`]'s gathering of a long scan in `runs` runs of consecutive rays, the first into
/// `scratch.main` and its hit log, the others into the workers' grids with their hits deferred
/// ([`Evidence::Deferred`]), each under an equal share of the memory left; then the workers' evidence merged
/// into the first's in the runs' order, and their hits replayed in that order ([`Evidence::replay`]).
pub(super) fn gather_in_parallel<E: Sampling, R: Rules>(
    before: &Before<R>,
    scan: &Scan,
    scratch: &mut Scratch<E>,
    runs: usize,
    scratch_limit: u64,
    merge: ExactMerge<E>,
    stop: &(impl Fn() -> bool + Sync),
) -> Result<IntegrationStats> {
    // Workers' grids are kept, with their pooled tiles, for the next scan that needs them (here or in
    // `Map::integrate_batch`).
    if scratch.workers.len() < runs - 1 {
        scratch.workers.resize_with(runs - 1, || TileGrid::new(E::NONE));
    }
    let bounds = balanced_runs(scan, runs, before.geometry.resolution_m());
    let share = scratch_limit / runs as u64;
    let grids = std::iter::once((&mut scratch.main, Some(&mut scratch.hits)))
        .chain(scratch.workers.iter_mut().map(|w| (w, None)))
        .take(runs)
        .collect::<Vec<_>>();
    let gathered = grids
        .into_par_iter()
        .enumerate()
        .map(|(k, (grid, first_hits))| {
            let rays = bounds[k]..bounds[k + 1];
            let mut stats = IntegrationStats::default();
            match first_hits {
                Some(hits) => gather_rays(before, scan, rays, (grid, hits), share, &mut stats, stop)
                    .map(|()| (stats, E::Deferred::default())),
                None => {
                    let mut deferred = E::Deferred::default();
                    gather_rays(before, scan, rays, (grid, &mut deferred), share, &mut stats, stop)
                        .map(|()| (stats, deferred))
                }
            }
        })
        .collect::<Result<Vec<_>>>()?;
    let refusal = |e: CapacityExceeded| Error::MemoryLimit {
        requested_bytes: e.requested_bytes,
        limit_bytes: before.memory_limit_bytes,
    };
    merge_runs(
        &mut scratch.main,
        &mut scratch.workers[..runs - 1],
        scratch_limit,
        merge,
    )
    .map_err(refusal)?;
    // The log grows under what the grids and the lists still to replay leave of the limit.
    let grids_bytes = scratch.memory_bytes() - scratch.hits.memory_bytes();
    let mut deferred_bytes: u64 = gathered.iter().map(|(_, d)| d.memory_bytes()).sum();
    let mut stats = IntegrationStats::default();
    for (run_stats, deferred) in gathered {
        let limit = scratch_limit.saturating_sub(grids_bytes + deferred_bytes);
        E::replay(
            &mut scratch.main,
            &mut scratch.hits,
            &deferred,
            before.opts,
            limit,
        )
        .map_err(refusal)?;
        deferred_bytes -= deferred.memory_bytes();
        stats += run_stats;
    }
    Ok(stats)
}

/// Merges the workers' evidence into `main`'s, in the workers' order, where each cell's evidence merges exactly
/// (`merge`): first the tiles `main` lacks are placed, in order, under `limit_bytes`, and the rows the workers
/// wrote are marked in `main` (the update visits them, and skips the cells no ray touched); then tile by tile
/// in parallel, each worker's cells are merged and reset where they are read, and the workers take their tiles
/// back.
fn merge_runs<E: Evidence>(
    main: &mut TileGrid<E>,
    workers: &mut [TileGrid<E>],
    limit_bytes: u64,
    merge: ExactMerge<E>,
) -> std::result::Result<(), CapacityExceeded> {
    for worker in workers.iter() {
        for (tile, _, marked) in worker.marked_tiles() {
            let slot = main.slot_or_insert(tile, limit_bytes)?;
            main.mark_rows(slot, marked.rows_covered());
        }
    }
    let fill = main.fill();
    // Every worker tile has its tile in `main`, placed above; a worker's evidence is reset in any case.
    let work = marked_by_tile(main, workers.iter_mut());
    work.into_par_iter()
        .with_max_len(TILES_PER_JOB)
        .for_each(|(mut merged, runs)| {
            for (evidence, marked) in runs {
                if let Some(merged) = merged.as_deref_mut() {
                    marked.for_each(|k| {
                        // An untouched cell's evidence merges as nothing.
                        if evidence[k].is_touched() {
                            merge.merge(&mut merged[k], &evidence[k]);
                        }
                    });
                }
                marked.reset(evidence, fill);
            }
        });
    workers.iter_mut().for_each(TileGrid::release_reset);
    Ok(())
}

/// The bounds of `runs` runs of consecutive rays of `scan` with about equal work: a ray's walk crosses about
/// one cell per cell size of its length over the ground, so a camera's frame, whose upper rows reach far and
/// lower rows near, is not cut at its middle ray. Any cut gives the same map (the runs merge exactly); this
/// one keeps the threads equally busy.
fn balanced_runs(scan: &Scan, runs: usize, resolution_m: f64) -> Vec<usize> {
    let work: Vec<f64> = scan
        .rays
        .iter()
        .scan(0.0, |total, ray| {
            let v = ray.offset_in_world;
            *total += f64::from(v.x.hypot(v.y)) / resolution_m + 1.0;
            Some(*total)
        })
        .collect();
    let total = work.last().copied().unwrap_or(0.0);
    let mut bounds: Vec<usize> = (0..runs)
        .map(|k| work.partition_point(|&w| w < total * k as f64 / runs as f64))
        .collect();
    bounds[0] = 0;
    bounds.push(scan.rays.len());
    bounds
}
