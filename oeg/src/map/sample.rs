//! What one ray says about each cell it crosses (eq. 10-12): the samples it adds to the scan's evidence along
//! its span (`map/span.rs`), the paper's ([`PaperEvidence`]) or every rule's ([`ScanEvidence`]).

pub(super) use super::span::RaySpan;

use super::rule_set::{OptionRules, Rules};
use super::scratch::{Evidence, HitLevels, HitSink, PaperEvidence, SampledHit, ScanEvidence};
use crate::cell::Cell;
use crate::error::Error;
use crate::geometry::GridGeometry;
use crate::model::{Ceiling, SeenFrom};
use crate::model::{
    Elevation, Level, ModelOptions, band_contradicts, beam_footprint_m, ceiling_contradicts,
    ceiling_passed_under, surface_level,
};
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

    /// The crossed cell's tile and offset in it.
    #[inline(always)]
    fn at(&self) -> (TileIndex, usize) {
        (self.tile, self.offset & (TILE_CELLS - 1))
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
    /// A cell within 3 sigma of the hit, its hits kept in `log` (at once, or deferred: [`HitSink`]).
    fn near_hit<R: Rules, L: HitSink<Self>>(
        &mut self,
        log: &mut L,
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
    fn near_hit<R: Rules, L: HitSink<Self>>(
        &mut self,
        log: &mut L,
        before: &Before<R>,
        span: &RaySpan,
        crossing: &CellCrossing,
        here: &Here,
    ) {
        match span.hit_probability_and_height(before.opts, crossing) {
            (p, Some(z)) => {
                let hit = SampledHit {
                    p,
                    z_m: z,
                    var_m2: span.s2,
                };
                log.add_hit(self, here.at(), hit, HitLevels::of(before.opts));
            }
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
        crossing: &CellCrossing,
        here: &Here,
    ) {
        free_sample(before, span, crossing, here, self);
    }

    #[inline(always)]
    fn free<R: Rules>(&mut self, before: &Before<R>, span: &RaySpan, crossing: &CellCrossing, here: &Here) {
        free_sample(before, span, crossing, here, self);
    }

    #[inline(always)]
    fn near_hit<R: Rules, L: HitSink<Self>>(
        &mut self,
        log: &mut L,
        before: &Before<R>,
        span: &RaySpan,
        crossing: &CellCrossing,
        here: &Here,
    ) {
        hit_sample(before, span, crossing, here, self, log);
    }
}

/// What a cell the beam passes through before its hit (or a ray that returned nothing) says, under the
/// free-space rules of the options: against the cell's surface (surface band, depth limit) and its ceiling.
#[inline(always)]
fn free_sample<R: Rules>(
    before: &Before<R>,
    span: &RaySpan,
    crossing: &CellCrossing,
    here: &Here,
    evidence: &mut ScanEvidence,
) {
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
        free_under_ceiling(c, opts, span, crossing.l_exit, here, evidence);
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

/// What a free sample says of the structure `ceiling` over its cell ([`crate::OverheadHits::Ceiling`]): whether the
/// beam contradicts it, its footprint ([`beam_footprint_m`]) taken where it leaves the cell, `l_exit` along it,
/// or passed under it.
#[inline(always)]
fn free_under_ceiling(
    ceiling: &Ceiling,
    opts: &ModelOptions,
    span: &RaySpan,
    l_exit: f64,
    here: &Here,
    evidence: &mut ScanEvidence,
) {
    let (beam_top, beam_bottom) = (here.beam_top_m, here.beam_bottom_m);
    let horizontal_m = l_exit * (1.0 - span.dir.z * span.dir.z).max(0.0).sqrt();
    let footprint_m = beam_footprint_m(horizontal_m) as f32;
    if ceiling_contradicts(
        ceiling,
        beam_bottom,
        beam_top,
        opts.surface_band_sigmas,
        footprint_m,
    ) {
        evidence.ceiling_contradicted = true;
    } else if ceiling_passed_under(ceiling, beam_top, opts.surface_band_sigmas) {
        evidence.ceiling_clear_m = evidence.ceiling_clear_m.max(beam_top);
    }
}

/// What a cell within 3 sigma of the hit says: eq. 10's probability, and eq. 12's height where the cell
/// measures one (every such cell, or only the end point's under [`crate::HitHeight::Endpoint`]), as a hit on the
/// surface or, above its band under [`crate::OverheadHits::Ceiling`], on a structure over it.
#[inline(always)]
fn hit_sample<R: Rules, L: HitSink<ScanEvidence>>(
    before: &Before<R>,
    span: &RaySpan,
    crossing: &CellCrossing,
    here: &Here,
    evidence: &mut ScanEvidence,
    log: &mut L,
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
            let hit = SampledHit {
                p,
                z_m: z,
                var_m2: s2,
            };
            log.add_overhead(evidence, here.at(), hit, SeenFrom::of_beam(dir.z), score);
        }
        Some(z) => {
            // Under the vertical-variance rule a hit is weighted by the noise its beam has where it meets the
            // surface, not by the error its range reported: short readings report less and would pull it up.
            let s2 = surface
                .filter(|_| rules.vertical_variance())
                .map_or(s2, |(_, meeting)| meeting);
            log.add_hit(
                evidence,
                here.at(),
                SampledHit {
                    p,
                    z_m: z,
                    var_m2: s2,
                },
                HitLevels::of(opts),
            )
        }
        None => evidence.paper.raise_p(p),
    }
}
