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
use crate::model::{GAUSSIAN_CUTOFF_SIGMAS, ModelOptions};
use crate::scan::{RayKind, Scan};
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
    let bounds = balanced_runs(scan, runs, before.opts, before.geometry.resolution_m());
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

/// The bounds of `runs` runs of consecutive rays of `scan` with about equal work: the cells their walks
/// cross, one per cell size of a ray's length over the ground up to 3 sigma past its hit, where its samples
/// end (a ray with no return: up to the range it clears). A camera's frame, whose upper rows reach far with
/// error bands that grow with the square of the range and whose lower rows reach near, is not cut at its
/// middle ray. Any cut gives the same map (the runs merge exactly); this one keeps the threads equally busy.
/// It runs on one thread before the runs start, so it costs a ray a square root and its range error, not its
/// whole span ([`super::span::RaySpan::of`]).
fn balanced_runs(scan: &Scan, runs: usize, opts: &ModelOptions, resolution_m: f64) -> Vec<usize> {
    let clear_range_m = opts.no_return_clear_range_m.unwrap_or(scan.sensor.max_range_m);
    let work: Vec<f64> = scan
        .rays
        .iter()
        .scan(0.0, |total, ray| {
            let v = ray.offset_in_world;
            let ground = v.x.hypot(v.y);
            let walked = match ray.kind {
                RayKind::Hit => {
                    let sigma = ray.range_sigma_m.unwrap_or_else(|| scan.sensor.sigma_m(ground));
                    ground + GAUSSIAN_CUTOFF_SIGMAS * sigma
                }
                RayKind::NoReturn => clear_range_m * ground / v.norm(),
            };
            // A ray the walk refuses (a zero direction) costs its check alone.
            *total += f64::from(walked).max(0.0) / resolution_m + 1.0;
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

#[cfg(test)]
mod tests {
    use nalgebra::{Point3, Vector3};

    use super::balanced_runs;
    use crate::geometry::GridGeometry;
    use crate::map::span::RaySpan;
    use crate::model::ModelOptions;
    use crate::scan::{Ray, Scan};
    use crate::sensor::SensorModel;
    use crate::traversal::GroundTraversal;

    /// The cells the walks of `scan`'s rays `rays` cross, as the gathering walks them.
    fn cells_walked(
        scan: &Scan,
        rays: std::ops::Range<usize>,
        opts: &ModelOptions,
        geometry: &GridGeometry,
    ) -> usize {
        scan.rays[rays]
            .iter()
            .filter_map(|ray| RaySpan::of(scan, ray, opts))
            .map(|s| {
                let (o, d) = (s.origin, s.dir);
                GroundTraversal::new(geometry, (o.x, o.y), (d.x, d.y), s.l_lo, s.l_hi).map_or(0, |w| w.len())
            })
            .sum()
    }

    #[test]
    fn a_camera_frame_is_cut_where_its_walks_cross_equal_cells() {
        // A stereo camera 0.5 m up, looking along x: its lower rows see the ground near, with small error bands,
        // its upper rows far, where the band grows with the square of the range, and some pixels see nothing.
        let opts = ModelOptions::default();
        let geometry = GridGeometry::new(0.05).expect("resolution");
        let mut scan = Scan::new(Point3::new(0.0, 0.0, 0.5), SensorModel::stereo());
        for row in 0..60 {
            let ahead = 0.8 + 0.1 * f64::from(row);
            for col in -20..=20 {
                let offset = Vector3::new(ahead, 0.02 * f64::from(col) * ahead, -0.5).cast::<f32>();
                scan.rays.push(if row % 7 == 6 {
                    Ray::no_return(offset)
                } else {
                    Ray::hit(offset)
                });
            }
        }
        for runs in [2, 3, 4] {
            let bounds = balanced_runs(&scan, runs, &opts, geometry.resolution_m());
            assert_eq!((bounds[0], bounds[runs]), (0, scan.rays.len()));
            let cells: Vec<usize> = bounds
                .windows(2)
                .map(|b| cells_walked(&scan, b[0]..b[1], &opts, &geometry))
                .collect();
            let (lo, hi) = (
                cells.iter().min().expect("runs"),
                cells.iter().max().expect("runs"),
            );
            assert!(
                (*hi as f64) < 1.03 * (*lo as f64),
                "{runs} runs walk {cells:?} cells (bounds {bounds:?})"
            );
        }
    }
}
