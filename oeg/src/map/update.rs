//! One cell's update from one scan's gathered evidence: eq. 5-7 for the occupancy, then eq. 12 with eq. 8-9
//! (or the free-space rule) for the elevation.

use super::apply::ScanUpdate;
use super::scratch::Evidence;
use crate::cell::Cell;
use crate::model::{
    Elevation, FreeSpaceElevation, FreeSpaceOccupancy, ModelOptions, ScanHitElevation, correlated_variance,
    free_sample_informs, fuse_elevation, kalman_fuse, log_odds, ray_bound, spread_variance, update_log_odds,
};

/// One cell's update from one scan's gathered evidence: eq. 5-7 for the occupancy, then eq. 12 with eq. 8-9 (or
/// the free-space rule) for the elevation.
pub(super) fn update_cell<E: Evidence>(
    cell: &mut Cell,
    (evidence, hits): (&E, &E::Hits),
    opts: &ModelOptions,
    update: ScanUpdate,
) {
    let (occupied_log_odds, free_log_odds) = (update.levels.occupied, update.levels.free);
    let ev = evidence.paper();
    if ev.hit_z_m == f32::NEG_INFINITY
        && !free_sample_informs(opts.free_space_occupancy, cell.elevation(), ev.free_z_m)
    {
        return;
    }
    let prior_log_odds = if cell.is_observed() { cell.log_odds } else { 0.0 };
    let was_occupied = cell.is_observed() && prior_log_odds > occupied_log_odds;
    let delta = if ev.p_max == opts.p_min {
        free_log_odds
    } else {
        log_odds(ev.p_max)
    };
    cell.log_odds = update_log_odds(prior_log_odds, delta, opts.log_odds_min, opts.log_odds_max);
    let prior = cell.elevation();
    let q = opts.process_noise_var_m2;
    let posterior = if ev.hit_z_m > f32::NEG_INFINITY {
        let s2 = match opts.scan_hit_elevation {
            ScanHitElevation::MeanWithSpread | ScanHitElevation::HighestLevel => {
                let hits = evidence.hits(hits);
                spread_variance(
                    // The hits of one scan share its errors too: their mean is no better than `rho` of one hit.
                    ev.hit_var_m2
                        .max(opts.measurement_correlation * hits.mean_variance()),
                    hits.sample_variance(),
                    hits.mean_variance(),
                )
            }
            ScanHitElevation::Highest | ScanHitElevation::WeightedMean => ev.hit_var_m2,
        };
        // A surface the scan's beams passed through, and a hit below it: the surface has gone down (a person
        // who left), so the hit starts the cell afresh.
        let moved_down = evidence.band_contradicted() && prior.is_some_and(|e| ev.hit_z_m < e.mean_m);
        let prior = if moved_down { None } else { prior };
        let fused = fuse_elevation(
            opts.elevation_fusion,
            prior,
            ev.hit_z_m,
            s2,
            q,
            opts.surface_band_sigmas,
        );
        Some(match prior {
            Some(e) if update.correlation > 0.0 => Elevation {
                var_m2: correlated_variance(fused.var_m2, e.var_m2 + q, s2, update.correlation),
                ..fused
            },
            _ => fused,
        })
    } else {
        match opts.free_space_elevation {
            FreeSpaceElevation::Zero => {
                let now_free = cell.log_odds <= occupied_log_odds;
                if !ev.free_var_m2.is_finite() {
                    // Only no-return evidence: no elevation measurement, but a cell turned free forgets its
                    // obstacle.
                    if was_occupied && now_free { None } else { prior }
                } else if !now_free
                    && matches!(
                        opts.free_space_occupancy,
                        FreeSpaceOccupancy::BelowElevation | FreeSpaceOccupancy::SurfaceBand
                    )
                {
                    // The obstacle keeps its height until the occupancy says it is gone; pulling it down to 0
                    // first would put it below the beams that are clearing it.
                    prior
                } else {
                    let prior = if was_occupied && now_free { None } else { prior };
                    Some(kalman_fuse(prior, 0.0, ev.free_var_m2, q))
                }
            }
            FreeSpaceElevation::Forget => {
                let now_free = cell.log_odds <= occupied_log_odds;
                if was_occupied && now_free { None } else { prior }
            }
            FreeSpaceElevation::Skip => prior,
            FreeSpaceElevation::RayBound => prior.map(|e: Elevation| ray_bound(e, ev.free_z_m)),
        }
    };
    cell.set_elevation(posterior);
}
