//! What one ray says about each cell it crosses (eq. 10-12): its span, and the samples it adds to the scan's
//! evidence, the paper's ([`PaperEvidence`]) or every rule's ([`ScanEvidence`]).

use nalgebra::Vector3;

use super::rule_set::{OptionRules, Rules};
use super::scratch::{Evidence, HitLog, PaperEvidence, ScanEvidence};
use crate::cell::Cell;
use crate::error::Error;
use crate::geometry::GridGeometry;
use crate::model::{Ceiling, SeenFrom};
use crate::model::{
    Elevation, GAUSSIAN_CUTOFF_SIGMAS, HitHeight, Level, ModelOptions, band_contradicts, ceiling_contradicts,
    ceiling_passed_under, clamp_probability, elevation_observation, inverse_sensor_model, surface_level,
    vertical_variance,
};
use crate::scan::{Ray, RayKind, Scan};
use crate::sensor::{MIN_RANGE_SIGMA_M, RangeNoiseModel};
use crate::storage::{TILE_CELLS, TileGrid, TileIndex};
use crate::traversal::CellCrossing;

/// What the samples of a scan read: the map as it was before the scan (Algorithm 1), its settings, and the
/// rules they follow, read from the settings or fixed ([`Rules`]).
#[derive(Clone, Copy)]
pub(super) struct Before<'a, R: Rules = OptionRules> {
    pub(super) geometry: &'a GridGeometry,
    pub(super) cells: &'a TileGrid<Cell>,
    pub(super) ceilings: &'a TileGrid<Ceiling>,
    pub(super) opts: &'a ModelOptions,
    pub(super) memory_limit_bytes: u64,
    /// Bytes of the map's own structure and recent views (the part of [`crate::Map::memory_bytes`] beside the
    /// tiles).
    pub(super) own_bytes: u64,
    pub(super) rules: R,
}

impl<'a> Before<'a> {
    /// The same, with the rules fixed as `rules` (which the options must hold: [`super::rule_set`]).
    pub(super) fn with_rules<R: Rules>(&self, rules: R) -> Before<'a, R> {
        Before {
            geometry: self.geometry,
            cells: self.cells,
            ceilings: self.ceilings,
            opts: self.opts,
            memory_limit_bytes: self.memory_limit_bytes,
            own_bytes: self.own_bytes,
            rules,
        }
    }
}

impl<R: Rules> Before<'_, R> {
    /// Bytes the map holds ([`crate::Map::memory_bytes`]): what the scratch's share of the limit leaves out.
    pub(super) fn map_bytes(&self) -> u64 {
        self.cells.memory_bytes() + self.ceilings.memory_bytes() + self.own_bytes
    }

    /// The error of a scan refused for its memory: the map would have held its bytes and `scratch_bytes`,
    /// against the map's limit.
    pub(super) fn refusal(&self, scratch_bytes: u64) -> Error {
        Error::MemoryLimit {
            requested_bytes: scratch_bytes.saturating_add(self.map_bytes()),
            limit_bytes: self.memory_limit_bytes,
        }
    }
}

/// The map's tiles (cells and ceilings) under the tile a walk is in, looked up once per tile for the rules
/// that read the map ([`Sampling::READS_MAP`]), and a crossed cell's place in them.
#[derive(Clone, Copy)]
pub(super) struct Here<'a> {
    cells: Option<&'a [Cell; TILE_CELLS]>,
    ceilings: Option<&'a [Ceiling; TILE_CELLS]>,
    /// The tile the walk is in.
    pub(super) tile: TileIndex,
    /// The crossed cell's [`crate::storage::offset_in_tile`].
    pub(super) offset: usize,
    /// The beam's highest and lowest heights inside the crossed cell ([`RaySpan::top_and_bottom`]).
    pub(super) beam_top_m: f32,
    pub(super) beam_bottom_m: f32,
}

impl<'a> Here<'a> {
    /// The map's tiles at `tile`, where the rules read the map.
    #[inline]
    pub(super) fn tile<E: Sampling, R: Rules>(before: &Before<'a, R>, tile: TileIndex) -> Self {
        if E::READS_MAP {
            Self {
                cells: before.cells.tile(tile),
                ceilings: before.ceilings.tile(tile),
                tile,
                offset: 0,
                beam_top_m: 0.0,
                beam_bottom_m: 0.0,
            }
        } else {
            Self {
                cells: None,
                ceilings: None,
                tile,
                offset: 0,
                beam_top_m: 0.0,
                beam_bottom_m: 0.0,
            }
        }
    }

    /// The crossed cell's state before the scan (none where its tile was never written).
    #[inline(always)]
    fn cell(&self) -> Option<&Cell> {
        self.cells.map(|t| &t[self.offset & (TILE_CELLS - 1)])
    }

    #[inline(always)]
    fn ceiling(&self) -> Option<&Ceiling> {
        self.ceilings.map(|t| &t[self.offset & (TILE_CELLS - 1)])
    }
}

/// How a crossed cell's evidence learns from a ray: a free sample before the hit, or a sample near it.
pub(super) trait Sampling: Evidence {
    /// Whether the samples read the map's cells or ceilings ([`Here`]).
    const READS_MAP: bool;
    /// A cell crossed by a ray that returned nothing.
    fn cleared<R: Rules>(&mut self, before: &Before<R>, span: &RaySpan, crossing: &CellCrossing, here: &Here);
    /// A cell the beam passes through before its hit.
    fn free<R: Rules>(&mut self, before: &Before<R>, span: &RaySpan, crossing: &CellCrossing, here: &Here);
    /// A cell within 3 sigma of the hit, its hits kept in `log`.
    fn near_hit<R: Rules>(
        &mut self,
        log: &mut Self::Hits,
        before: &Before<R>,
        span: &RaySpan,
        crossing: &CellCrossing,
        here: &Here,
    );
}

/// The paper's samples: the probability, the beam's height in a cell it passed through on its way to a hit,
/// and the hits' heights. No look-up of the map and no rule's check: [`free_sample`] and [`hit_sample`] add
/// the same under the options that choose this evidence.
impl Sampling for PaperEvidence {
    const READS_MAP: bool = false;

    #[inline(always)]
    fn cleared<R: Rules>(
        &mut self,
        before: &Before<R>,
        _span: &RaySpan,
        _crossing: &CellCrossing,
        _here: &Here,
    ) {
        self.raise_p(before.opts.p_min);
    }

    #[inline(always)]
    fn free<R: Rules>(&mut self, before: &Before<R>, span: &RaySpan, _crossing: &CellCrossing, here: &Here) {
        self.add_free(before.opts.p_min, here.beam_top_m, span.s2);
    }

    #[inline(always)]
    fn near_hit<R: Rules>(
        &mut self,
        _log: &mut (),
        before: &Before<R>,
        span: &RaySpan,
        crossing: &CellCrossing,
        _here: &Here,
    ) {
        match span.hit_probability_and_height(before.opts, crossing) {
            (p, Some(z)) => self.add_hit(p, z, span.s2, before.opts.scan_hit_elevation),
            (p, None) => self.raise_p(p),
        }
    }
}

impl Sampling for ScanEvidence {
    const READS_MAP: bool = true;

    #[inline(always)]
    fn cleared<R: Rules>(
        &mut self,
        before: &Before<R>,
        span: &RaySpan,
        _crossing: &CellCrossing,
        here: &Here,
    ) {
        free_sample(before, span, here, self);
    }

    #[inline(always)]
    fn free<R: Rules>(&mut self, before: &Before<R>, span: &RaySpan, _crossing: &CellCrossing, here: &Here) {
        free_sample(before, span, here, self);
    }

    #[inline(always)]
    fn near_hit<R: Rules>(
        &mut self,
        log: &mut HitLog,
        before: &Before<R>,
        span: &RaySpan,
        crossing: &CellCrossing,
        here: &Here,
    ) {
        hit_sample(before, span, crossing, here, self, log);
    }
}

/// The part of one ray the map learns from, in the ray's parameter (metres along it from the sensor).
pub(super) struct RaySpan {
    /// The sensor.
    pub(super) origin: Vector3<f64>,
    /// The unit direction.
    pub(super) dir: Vector3<f64>,
    /// The hit's range and its standard deviation, or `None` for a ray that only clears.
    pub(super) hit: Option<(f64, f64)>,
    /// Where the span starts, after height thresholding.
    pub(super) l_lo: f64,
    /// Where it ends: 3 sigma past the hit, the clearing range, or the height threshold.
    pub(super) l_hi: f64,
    /// The variance a sample's height gets (the range variance, or its vertical projection).
    pub(super) s2: f32,
    /// Samples that end before this are plain free samples (`p = p_min`, no exponential); only the few cells
    /// within 3 sigma of the hit evaluate eq. 10.
    pub(super) free_until: f64,
    /// The sensor's range error model and range.
    pub(super) noise: RangeNoiseModel,
    pub(super) max_range_m: f64,
}

impl RaySpan {
    /// The span of `ray`, or `None` for a ray that teaches nothing (zero length, or wholly above the height
    /// threshold).
    #[inline(always)]
    pub(super) fn of(scan: &Scan, ray: &Ray, opts: &ModelOptions) -> Option<Self> {
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
            noise: scan.sensor.noise,
            max_range_m: f64::from(scan.sensor.max_range_m),
        })
    }

    /// The variance of the hit's height had its beam met a surface at `surface_m`, where a descending beam
    /// crosses that height: the sensor's range error there, in proportion to the hit's own
    /// ([`RangeNoiseModel::sigma_m`]). A sensor reports the error of the range it measured, so a reading
    /// that fell short of the surface reports less error than the beam has there, and one that went long
    /// more: weighted by what they report, the short ones would pull the surface up, and one far short would
    /// look like a structure over it. The hit's own variance for a level or rising beam, or a surface not
    /// below the sensor. `vertical`: the variance projected on the vertical
    /// ([`ModelOptions::vertical_variance`]).
    pub(super) fn s2_meeting(&self, surface_m: f32, vertical: bool) -> f32 {
        let Some((l_p, sigma)) = self.hit else {
            return self.s2;
        };
        let r0 = (f64::from(surface_m) - self.origin.z) / self.dir.z;
        if self.dir.z >= 0.0 || r0.is_nan() || r0 <= 0.0 {
            return self.s2;
        }
        let r0 = r0.min(self.max_range_m);
        let (at_hit, at_surface) = (self.noise.sigma_m(l_p as f32), self.noise.sigma_m(r0 as f32));
        if at_hit.is_nan() || at_hit <= 0.0 || !at_surface.is_finite() {
            return self.s2;
        }
        let sigma0 = (sigma * f64::from(at_surface / at_hit)).max(f64::from(MIN_RANGE_SIGMA_M));
        if vertical {
            vertical_variance(sigma0, self.dir.z, r0)
        } else {
            (sigma0 * sigma0) as f32
        }
    }

    /// The most cells the samples within 3 sigma of the hit can cross, at `resolution_m`: a straight segment
    /// crosses one cell more than the cell boundaries it passes, at most `|dx| / resolution_m + 1` of each
    /// axis (and one more for rounding).
    #[inline]
    pub(super) fn near_hit_cells(&self, resolution_m: f64) -> usize {
        let length = (self.l_hi - self.free_until.max(self.l_lo)).max(0.0);
        let across = (self.dir.x.abs() + self.dir.y.abs()) * length / resolution_m;
        // A finite ray's span is bounded by the grid's index range ([`super::integrate`]'s walk check).
        across as usize + 4
    }

    /// The beam's height at `l` along it.
    #[inline(always)]
    pub(super) fn height_at(&self, l: f64) -> f64 {
        self.origin.z + self.dir.z * l
    }

    /// The beam's highest and lowest heights inside a crossed cell, from its heights where it enters
    /// (`z_enter_m`, [`RaySpan::height_at`] the crossing's `l_enter`) and leaves (`z_exit_m`): the beam is
    /// straight, so they are its heights at the crossing's two ends, the higher first (the enter height when
    /// the two are equal).
    #[inline(always)]
    pub(super) fn top_and_bottom(z_enter_m: f64, z_exit_m: f64) -> (f32, f32) {
        if z_exit_m > z_enter_m {
            (z_exit_m as f32, z_enter_m as f32)
        } else {
            (z_enter_m as f32, z_exit_m as f32)
        }
    }

    /// A sample within 3 sigma of the hit: eq. 10's probability (clamped), and eq. 12's height where the cell
    /// measures one (every such cell, or only the end point's under [`HitHeight::Endpoint`]). Within 3 sigma
    /// of the measured range the surface may lie anywhere: a sample without a height counts for the occupancy,
    /// but its height bounds nothing (a noisy long reading would otherwise "prove" free space under the
    /// ground).
    #[inline(always)]
    fn hit_probability_and_height(&self, opts: &ModelOptions, crossing: &CellCrossing) -> (f32, Option<f32>) {
        let Some((l_p, sigma)) = self.hit else {
            unreachable!("free_until is infinite without a hit")
        };
        let l = l_p.clamp(crossing.l_enter, crossing.l_exit);
        let p = inverse_sensor_model(
            l as f32,
            l_p as f32,
            sigma as f32,
            opts.significance_k_m,
            opts.p_min,
        );
        let p = clamp_probability(p, opts.p_min, opts.p_max);
        // Under `HitHeight::Endpoint` only the cell holding the end point (where the clamp leaves `l_p` as it
        // is) measures a height.
        let measures_height = opts.hit_height == HitHeight::BeamSample || l == l_p;
        let z = elevation_observation(
            p,
            (self.origin.z + self.dir.z * l) as f32,
            opts.elevation_threshold,
        )
        .filter(|_| measures_height);
        (p, z)
    }
}

/// What a cell the beam passes through before its hit (or a ray that returned nothing) says, under the
/// free-space rules of the options: against the cell's surface (surface band, depth limit) and its ceiling.
#[inline(always)]
fn free_sample<R: Rules>(before: &Before<R>, span: &RaySpan, here: &Here, evidence: &mut ScanEvidence) {
    let (opts, rules) = (before.opts, before.rules);
    let band_rule = rules.surface_band();
    let needs_surface = band_rule || rules.max_depth_m().is_some();
    // The cell's surface, looked up once for the rules that judge a free sample against it.
    let surface = if needs_surface {
        here.cell().and_then(Cell::elevation)
    } else {
        None
    };
    let (beam_top, beam_bottom) = (here.beam_top_m, here.beam_bottom_m);
    if span.hit.is_none() {
        // A ray that returned nothing clears, but bounds no height: it may have left through the ground or
        // past anything (a dropout), so its heights prove nothing. Under the surface-band rule it therefore
        // says nothing about a cell with a surface.
        if !(band_rule && surface.is_some()) {
            evidence.paper.raise_p(opts.p_min);
        }
        return;
    }
    if rules.ceiling()
        && let Some(c) = here.ceiling().filter(|c| c.is_some())
    {
        if ceiling_contradicts(c, beam_bottom, beam_top, opts.surface_band_sigmas) {
            evidence.ceiling_contradicted = true;
        } else if ceiling_passed_under(c, beam_top, opts.surface_band_sigmas) {
            evidence.ceiling_clear_m = evidence.ceiling_clear_m.max(beam_top);
        }
    }
    if let (Some(depth), Some(e)) = (rules.max_depth_m(), surface)
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
    evidence.paper.add_free(opts.p_min, beam_top, span.s2);
}

/// What a cell within 3 sigma of the hit says: eq. 10's probability, and eq. 12's height where the cell
/// measures one (every such cell, or only the end point's under [`HitHeight::Endpoint`]), as a hit on the
/// surface or, above its band under [`OverheadHits::Ceiling`], on a structure over it.
#[inline(always)]
fn hit_sample<R: Rules>(
    before: &Before<R>,
    span: &RaySpan,
    crossing: &CellCrossing,
    here: &Here,
    evidence: &mut ScanEvidence,
    log: &mut HitLog,
) {
    let (opts, rules) = (before.opts, before.rules);
    let (p, z) = span.hit_probability_and_height(opts, crossing);
    let (dir, s2) = (span.dir, span.s2);
    // How far above the band of the cell's surface the hit lies, in standard deviations: above it, a structure
    // over the surface (if it stands out of the scan's hits: `ceiling_hit`).
    let ceiling_rule = rules.ceiling();
    // The cell's surface, and the noise the beam has where it meets it, for the rules that ask.
    let surface = z
        .filter(|_| ceiling_rule || rules.vertical_variance())
        .and_then(|_| here.cell().and_then(Cell::elevation))
        .map(|e| (e, span.s2_meeting(e.mean_m, rules.vertical_variance())));
    let overhead_score = z.filter(|_| ceiling_rule).and_then(|z| {
        let (e, s2) = surface?;
        let grown = Elevation {
            var_m2: e.var_m2 + opts.process_noise_var_m2,
            ..e
        };
        // Whether the hit is the surface's noise is asked of the noise the beam has where it meets it.
        (surface_level(grown, z, s2, opts.surface_band_sigmas) == Level::Above)
            .then(|| (z - grown.mean_m) / (grown.var_m2 + s2).sqrt())
    });
    match z {
        Some(z) if let Some(score) = overhead_score => {
            evidence.add_overhead((log, here.tile), p, z, s2, SeenFrom::of_beam(dir.z), score);
        }
        Some(z) => {
            // Under the vertical-variance rule a hit is weighted by the noise its beam has where it meets the
            // surface, not by the error its range reported: short readings report less and would pull it up.
            let s2 = surface
                .filter(|_| rules.vertical_variance())
                .map_or(s2, |(_, meeting)| meeting);
            evidence.add_hit(log, p, z, s2, opts.scan_hit_elevation, opts.surface_band_sigmas)
        }
        None => evidence.paper.raise_p(p),
    }
}
