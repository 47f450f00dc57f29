//! Scan integration: the paper's Algorithm 1. Every ray of a scan is cast through the grid and what it says
//! about each cell is gathered (eq. 10-12); then each touched cell is updated once (eq. 5-9, or the rule the
//! options choose).

use nalgebra::Vector3;

use super::scratch::{ScanEvidence, ScratchCursor};
use super::{IntegrationStats, Map};
use crate::cell::{Ceiling, Cell, SeenFrom};
use crate::error::{Error, Result};
use crate::model::{
    Elevation, FreeSpaceElevation, FreeSpaceOccupancy, GAUSSIAN_CUTOFF_SIGMAS, HitHeight, Level,
    ModelOptions, OverheadHits, ScanHitElevation, band_contradicts, ceiling_contradicts,
    ceiling_passed_under, clamp_probability, correlated_variance, elevation_observation, fuse_elevation,
    inverse_sensor_model, kalman_fuse, log_odds, ray_bound, spread_variance, surface_level, update_ceiling,
    update_log_odds, vertical_variance,
};
use crate::scan::{Ray, RayKind, Scan};
use crate::sensor::MIN_RANGE_SIGMA_M;
use crate::storage::{TileGrid, TileIndex};
use crate::traversal::{CellCrossing, GroundTraversal};

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
    /// (millions of rays from Python) can be cancelled within a bounded time.
    ///
    /// # Errors
    /// As [`Map::integrate`], and [`Error::Cancelled`] when `stop` said so (the map is left without this scan's
    /// updates).
    pub fn integrate_unless(&mut self, scan: &Scan, stop: &dyn Fn() -> bool) -> Result<IntegrationStats> {
        self.integrate_stopping(scan, stop)
    }

    fn integrate_stopping(&mut self, scan: &Scan, stop: impl Fn() -> bool) -> Result<IntegrationStats> {
        scan.validate()?;
        let mut stats = IntegrationStats {
            num_rays: scan.rays.len() as u64,
            ..IntegrationStats::default()
        };
        let gathered = self
            .gather(scan, &mut stats, &stop)
            .and_then(|()| self.apply(&mut stats));
        self.scratch.recycle_all();
        gathered?;
        self.num_scans += 1;
        self.totals += stats;
        Ok(stats)
    }

    /// Casts every ray of the scan into the scratch grid: each ray's span ([`RaySpan::of`]), checked against
    /// the grid and the memory limit ([`Map::walk_of`]), then what each crossed cell learns from it, a free
    /// sample ([`free_sample`]) or a sample near the hit ([`hit_sample`]).
    fn gather(&mut self, scan: &Scan, stats: &mut IntegrationStats, stop: &impl Fn() -> bool) -> Result<()> {
        let opts = self.config.model;
        // When no rule judges a free sample against the cell's surface or ceiling (the paper's model), a free
        // sample is the paper's alone: the probability, and the beam's height in the cell where the ray hit
        // something. `free_sample` does the same in that case, with look-ups and checks this loop skips.
        let plain_free = opts.free_space_occupancy != FreeSpaceOccupancy::SurfaceBand
            && opts.free_space_max_depth_m.is_none()
            && opts.overhead_hits != OverheadHits::Ceiling;
        let scratch_limit = self
            .config
            .memory_limit_bytes
            .saturating_sub(self.cells.memory_bytes());
        for (index, ray) in scan.rays.iter().enumerate() {
            if index % RAYS_BETWEEN_STOP_CHECKS == RAYS_BETWEEN_STOP_CHECKS - 1 && stop() {
                return Err(Error::Cancelled);
            }
            let Some(span) = RaySpan::of(scan, ray, &opts) else {
                stats.num_rays_skipped += 1;
                continue;
            };
            let walk = self.walk_of(index, &span, scratch_limit)?;
            stats.num_cell_visits += walk.len() as u64;
            let mut cursor = ScratchCursor::new(&mut self.scratch, scratch_limit);
            for crossing in walk {
                let evidence = cursor.at(crossing.cell)?;
                if crossing.l_exit < span.free_until {
                    if !plain_free {
                        free_sample(&self.cells, &self.ceilings, &opts, &span, &crossing, evidence);
                    } else if span.hit.is_none() {
                        evidence.raise_p(opts.p_min);
                    } else {
                        evidence.add_free(opts.p_min, span.top_and_bottom(&crossing).0, span.s2);
                    }
                } else {
                    hit_sample(&self.cells, &opts, &span, &crossing, evidence);
                }
            }
        }
        Ok(())
    }

    /// The cells under a ray's span, refused when the span leaves the grid's index range or must exceed the
    /// memory limit (checked before a single tile of it is allocated).
    fn walk_of(&self, index: usize, span: &RaySpan, scratch_limit: u64) -> Result<GroundTraversal> {
        let (o, dir) = (span.origin, span.dir);
        let (start, end) = (o + dir * span.l_lo, o + dir * span.l_hi);
        let walk = GroundTraversal::new(&self.geometry, (o.x, o.y), (dir.x, dir.y), span.l_lo, span.l_hi)
            .ok_or_else(|| {
                Error::InvalidScan(format!(
                    "ray {index} runs from ({:.3}, {:.3}) m to ({:.3}, {:.3}) m, beyond the grid's index \
                     range (2^31 cells of {} m from the origin): is the sensor's pose or this point corrupt?",
                    start.x,
                    start.y,
                    end.x,
                    end.y,
                    self.geometry.resolution_m()
                ))
            })?;
        // Fail fast: the walk touches at least one tile per tile edge it spans, so a ray that must exceed
        // the memory limit is refused before a single tile of it is allocated.
        let tiles_spanned = match (
            self.geometry.cell_of(start.x, start.y),
            self.geometry.cell_of(end.x, end.y),
        ) {
            (Some(a), Some(b)) => {
                let (ta, tb) = (TileIndex::of(a), TileIndex::of(b));
                u64::from(ta.ti.abs_diff(tb.ti).max(ta.tj.abs_diff(tb.tj))) + 1
            }
            _ => 1,
        };
        let tile_bytes = TileGrid::<ScanEvidence>::tile_bytes() as u64;
        let least_bytes = tiles_spanned.saturating_mul(tile_bytes);
        if least_bytes > scratch_limit {
            return Err(Error::MemoryLimit {
                requested_bytes: least_bytes.saturating_add(self.cells.memory_bytes()),
                limit_bytes: self.config.memory_limit_bytes,
            });
        }
        // The scan's rays together: when this ray may need more than the scratch has left (long rays, such as a
        // stereo hit's error band far away, add up), count the tiles it needs that the scratch lacks, before
        // one of them is allocated. Rays are straight, so their tiles come in runs.
        let in_use = self.scratch.memory_bytes();
        let left = scratch_limit.saturating_sub(in_use);
        let pooled = self.scratch.num_pooled() as u64;
        if least_bytes > left.saturating_add(pooled.saturating_mul(tile_bytes)) {
            let (mut new_tiles, mut last) = (0u64, None);
            for crossing in walk.clone() {
                let tile = TileIndex::of(crossing.cell);
                if last != Some(tile) {
                    last = Some(tile);
                    new_tiles += u64::from(!self.scratch.has_tile(tile));
                }
            }
            let needed = new_tiles.saturating_sub(pooled).saturating_mul(tile_bytes);
            if needed > left {
                return Err(Error::MemoryLimit {
                    requested_bytes: needed
                        .saturating_add(in_use)
                        .saturating_add(self.cells.memory_bytes()),
                    limit_bytes: self.config.memory_limit_bytes,
                });
            }
        }
        Ok(walk)
    }

    /// Updates every cell the scan touched, once.
    fn apply(&mut self, stats: &mut IntegrationStats) -> Result<()> {
        let opts = self.config.model;
        let ceiling_rule = opts.overhead_hits == OverheadHits::Ceiling;
        let scratch_bytes = self.scratch.memory_bytes();
        let limit = self.config.memory_limit_bytes.saturating_sub(scratch_bytes);
        for (tile, evidence) in self.scratch.tiles() {
            let memory_error = |e: crate::storage::CapacityExceeded| Error::MemoryLimit {
                requested_bytes: e.requested_bytes.saturating_add(scratch_bytes),
                limit_bytes: self.config.memory_limit_bytes,
            };
            let cells = self
                .cells
                .tile_or_insert(tile, limit.saturating_sub(self.ceilings.memory_bytes()))
                .map_err(memory_error)?;
            for (cell, ev) in cells.iter_mut().zip(evidence.iter()) {
                if ev.is_untouched() {
                    continue;
                }
                stats.num_cells_updated += 1;
                update_cell(cell, ev, &opts, self.occupied_log_odds, self.free_log_odds);
            }
            if !ceiling_rule {
                continue;
            }
            // The ceiling layer: allocated where a ceiling is hit, updated where one exists. One pass tells both.
            let (hit, touched) = evidence.iter().fold((false, false), |(h, t), ev| {
                (h || ev.ceiling_p > 0.0, t || ev.touches_ceiling())
            });
            let ceilings = if hit {
                let room = limit.saturating_sub(self.cells.memory_bytes());
                Some(self.ceilings.tile_or_insert(tile, room).map_err(memory_error)?)
            } else if touched {
                self.ceilings.tile_mut(tile)
            } else {
                None
            };
            if let Some(ceilings) = ceilings {
                for (ceiling, ev) in ceilings.iter_mut().zip(evidence.iter()) {
                    if ev.touches_ceiling() {
                        *ceiling = update_ceiling(
                            *ceiling,
                            ev.ceiling_hit(opts.measurement_correlation, opts.surface_band_sigmas),
                            ev.ceiling_contradicted,
                            ev.ceiling_clear_m,
                            &opts,
                            self.occupied_log_odds,
                        );
                    }
                }
            }
        }
        Ok(())
    }
}

/// The part of one ray the map learns from, in the ray's parameter (metres along it from the sensor).
struct RaySpan {
    /// The sensor.
    origin: Vector3<f64>,
    /// The unit direction.
    dir: Vector3<f64>,
    /// The hit's range and its standard deviation, or `None` for a ray that only clears.
    hit: Option<(f64, f64)>,
    /// Where the span starts, after height thresholding.
    l_lo: f64,
    /// Where it ends: 3 sigma past the hit, the clearing range, or the height threshold.
    l_hi: f64,
    /// The variance a sample's height gets (the range variance, or its vertical projection).
    s2: f32,
    /// Samples that end before this are plain free samples (`p = p_min`, no exponential); only the few cells
    /// within 3 sigma of the hit evaluate eq. 10.
    free_until: f64,
}

impl RaySpan {
    /// The span of `ray`, or `None` for a ray that teaches nothing (zero length, or wholly above the height
    /// threshold).
    fn of(scan: &Scan, ray: &Ray, opts: &ModelOptions) -> Option<Self> {
        let o = scan.origin_in_world.coords;
        let clear_range_m = f64::from(opts.no_return_clear_range_m.unwrap_or(scan.sensor.max_range_m));
        let max_range_m = opts.max_range_m.map_or(f64::INFINITY, f64::from);
        let v: Vector3<f64> = ray.offset_in_world.cast();
        let length = v.norm();
        if length == 0.0 {
            return None;
        }
        let dir = v / length;
        // The hit range, or None for a ray that only clears; and the end of the traversal.
        let (hit, l_end) = match ray.kind {
            RayKind::Hit if length <= max_range_m => {
                let sigma = ray
                    .range_sigma_m
                    .unwrap_or_else(|| scan.sensor.sigma_m(length as f32));
                let sigma = f64::from(sigma.max(MIN_RANGE_SIGMA_M));
                (
                    Some((length, sigma)),
                    length + f64::from(GAUSSIAN_CUTOFF_SIGMAS) * sigma,
                )
            }
            RayKind::Hit => (None, max_range_m),
            RayKind::NoReturn => (None, clear_range_m.min(max_range_m)),
        };
        let sigma_for_free = hit.map_or_else(
            || {
                f64::from(
                    ray.range_sigma_m
                        .unwrap_or_else(|| scan.sensor.sigma_m(l_end as f32)),
                )
            },
            |(_, s)| s,
        );
        // Height thresholding: keep the part of the ray at or below max_height.
        let (mut l_lo, mut l_hi): (f64, f64) = (0.0, l_end);
        if let Some(h) = opts.max_height_m {
            let h = f64::from(h);
            if dir.z > 0.0 {
                l_hi = l_hi.min((h - o.z) / dir.z);
            } else if dir.z < 0.0 {
                l_lo = l_lo.max((h - o.z) / dir.z);
            } else if o.z > h {
                l_hi = -1.0;
            }
        }
        if l_hi < l_lo {
            return None;
        }
        let s2 = if opts.vertical_variance {
            vertical_variance(sigma_for_free, dir.z, hit.map_or(l_end, |(l, _)| l))
        } else {
            (sigma_for_free * sigma_for_free) as f32
        };
        let free_until = hit.map_or(f64::INFINITY, |(l_p, s)| {
            l_p - f64::from(GAUSSIAN_CUTOFF_SIGMAS) * s
        });
        Some(Self {
            origin: o,
            dir,
            hit,
            l_lo,
            l_hi,
            s2,
            free_until,
        })
    }

    /// The beam's highest and lowest heights inside a crossed cell.
    fn top_and_bottom(&self, crossing: &CellCrossing) -> (f32, f32) {
        let (l_top, l_bottom) = if self.dir.z > 0.0 {
            (crossing.l_exit, crossing.l_enter)
        } else {
            (crossing.l_enter, crossing.l_exit)
        };
        (
            (self.origin.z + self.dir.z * l_top) as f32,
            (self.origin.z + self.dir.z * l_bottom) as f32,
        )
    }
}

/// What a cell the beam passes through before its hit (or a ray that returned nothing) says, under the
/// free-space rules of the options: against the cell's surface (surface band, depth limit) and its ceiling.
fn free_sample(
    cells: &TileGrid<Cell>,
    ceilings: &TileGrid<Ceiling>,
    opts: &ModelOptions,
    span: &RaySpan,
    crossing: &CellCrossing,
    evidence: &mut ScanEvidence,
) {
    let band_rule = opts.free_space_occupancy == FreeSpaceOccupancy::SurfaceBand;
    let needs_surface = band_rule || opts.free_space_max_depth_m.is_some();
    // The cell's surface, looked up once for the rules that judge a free sample against it.
    let surface = if needs_surface {
        cells.get(crossing.cell).and_then(Cell::elevation)
    } else {
        None
    };
    let (beam_top, beam_bottom) = span.top_and_bottom(crossing);
    if span.hit.is_none() {
        // A ray that returned nothing clears, but bounds no height: it may have left through the ground or
        // past anything (a dropout), so its heights prove nothing. Under the surface-band rule it therefore
        // says nothing about a cell with a surface.
        if !(band_rule && surface.is_some()) {
            evidence.raise_p(opts.p_min);
        }
        return;
    }
    if opts.overhead_hits == OverheadHits::Ceiling
        && let Some(c) = ceilings.get(crossing.cell).filter(|c| c.is_some())
    {
        if ceiling_contradicts(c, beam_bottom, beam_top, opts.surface_band_sigmas) {
            evidence.ceiling_contradicted = true;
        } else if ceiling_passed_under(c, beam_top, opts.surface_band_sigmas) {
            evidence.ceiling_clear_m = evidence.ceiling_clear_m.max(beam_top);
        }
    }
    if let (Some(depth), Some(e)) = (opts.free_space_max_depth_m, surface)
        && e.mean_m - beam_top > depth
    {
        // Far below the cell's surface: perhaps under an overhang, so it says nothing.
        return;
    }
    if band_rule && let Some(e) = surface {
        if !band_contradicts(e, beam_bottom, beam_top, opts.surface_band_sigmas) {
            // Over or under the surface: it says nothing about it.
            return;
        }
        evidence.band_contradicted = true;
    }
    evidence.add_free(opts.p_min, beam_top, span.s2);
}

/// What a cell within 3 sigma of the hit says: eq. 10's probability, and eq. 12's height where the cell
/// measures one (every such cell, or only the end point's under [`HitHeight::Endpoint`]), as a hit on the
/// surface or, above its band under [`OverheadHits::Ceiling`], on a structure over it.
fn hit_sample(
    cells: &TileGrid<Cell>,
    opts: &ModelOptions,
    span: &RaySpan,
    crossing: &CellCrossing,
    evidence: &mut ScanEvidence,
) {
    let Some((l_p, sigma)) = span.hit else {
        unreachable!("free_until is infinite without a hit")
    };
    let (o, dir, s2) = (span.origin, span.dir, span.s2);
    let l = l_p.clamp(crossing.l_enter, crossing.l_exit);
    let p = inverse_sensor_model(
        l as f32,
        l_p as f32,
        sigma as f32,
        opts.significance_k_m,
        opts.p_min,
    );
    let p = clamp_probability(p, opts.p_min, opts.p_max);
    // Under `HitHeight::Endpoint` only the cell holding the end point (where the clamp leaves `l_p` as it is)
    // measures a height.
    let measures_height = opts.hit_height == HitHeight::BeamSample || l == l_p;
    let z = elevation_observation(p, (o.z + dir.z * l) as f32, opts.elevation_threshold)
        .filter(|_| measures_height);
    // How far above the band of the cell's surface the hit lies, in standard deviations: above it, a structure
    // over the surface (if it stands out of the scan's hits: `ceiling_hit`).
    let overhead_score = z
        .filter(|_| opts.overhead_hits == OverheadHits::Ceiling)
        .and_then(|z| {
            let e = cells.get(crossing.cell).and_then(Cell::elevation)?;
            let grown = Elevation {
                var_m2: e.var_m2 + opts.process_noise_var_m2,
                ..e
            };
            (surface_level(grown, z, s2, opts.surface_band_sigmas) == Level::Above)
                .then(|| (z - grown.mean_m) / (grown.var_m2 + s2).sqrt())
        });
    match z {
        Some(z) if let Some(score) = overhead_score => {
            evidence.add_overhead(p, z, s2, SeenFrom::of_beam(dir.z), score);
        }
        Some(z) => evidence.add_hit(p, z, s2, opts.scan_hit_elevation, opts.surface_band_sigmas),
        // Within 3 sigma of the measured range the surface may lie anywhere: the sample counts for the
        // occupancy, but its height bounds nothing (a noisy long reading would otherwise "prove" free space
        // under the ground).
        None => evidence.raise_p(p),
    }
}

/// One cell's update from one scan's gathered evidence: eq. 5-7 for the occupancy, then eq. 12 with eq. 8-9 (or
/// the free-space rule) for the elevation.
fn update_cell(
    cell: &mut Cell,
    ev: &ScanEvidence,
    opts: &ModelOptions,
    occupied_log_odds: f32,
    free_log_odds: f32,
) {
    if ev.hit_z_m == f32::NEG_INFINITY
        && !crate::model::free_sample_informs(opts.free_space_occupancy, cell.elevation(), ev.free_z_m)
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
            ScanHitElevation::MeanWithSpread | ScanHitElevation::HighestLevel => spread_variance(
                // The hits of one scan share its errors too: their mean is no better than `rho` of one hit.
                ev.hit_var_m2
                    .max(opts.measurement_correlation * ev.hits.mean_variance()),
                ev.hits.sample_variance(),
                ev.hits.mean_variance(),
            ),
            ScanHitElevation::Highest | ScanHitElevation::WeightedMean => ev.hit_var_m2,
        };
        // A surface the scan's beams passed through, and a hit below it: the surface has gone down (a person
        // who left), so the hit starts the cell afresh.
        let moved_down = ev.band_contradicted && prior.is_some_and(|e| ev.hit_z_m < e.mean_m);
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
            Some(e) if opts.measurement_correlation > 0.0 => Elevation {
                var_m2: correlated_variance(fused.var_m2, e.var_m2 + q, s2, opts.measurement_correlation),
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
