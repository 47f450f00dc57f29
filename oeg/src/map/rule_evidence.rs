//! Every rule's evidence ([`ModelOptions`](crate::model::ModelOptions)): the part of a cell's evidence every sample touches, kept in the
//! scratch's grid, and the part only hits touch, kept in a list beside it.

pub(crate) use super::deferred_hits::DeferredHits;
use super::scratch::{Evidence, ExactMerge, HitLevels, HitSink, HitStore, PaperEvidence, SampledHit};
use crate::model::ModelOptions;
use crate::model::SeenFrom;
use crate::model::{
    CeilingHit, Elevation, Level, ScanHitElevation, overhead_significant, spread_variance, surface_level,
};
use crate::storage::{CapacityExceeded, TileGrid, TileIndex};

/// What one scan says about one cell under every rule of [`ModelOptions`](crate::model::ModelOptions), the part every sample reads or
/// writes: the paper's evidence, what a free sample judges against the cell's surface and ceiling, and where
/// the cell's hits are kept ([`HitEvidence`]). A free sample, most of a ray's, touches these 32 bytes alone,
/// half a cache line; the 48 bytes of the hits, which a few cells near each ray's end touch, live in a list
/// beside the grid ([`HitLog`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScanEvidence {
    pub(super) paper: PaperEvidence,
    /// The highest point of a free sample that passed under the band of the cell's ceiling (-inf: none).
    pub(super) ceiling_clear_m: f32,
    /// One more than the place of the cell's [`HitEvidence`] in the scan's [`HitLog`]; 0: no hit yet.
    hit_entry: u32,
    /// Whether a free sample passed through the cell's surface band
    /// ([`FreeSpaceOccupancy::SurfaceBand`](crate::model::FreeSpaceOccupancy::SurfaceBand)).
    pub(super) band_contradicted: bool,
    /// Whether a free sample passed through the band of the cell's ceiling.
    pub(super) ceiling_contradicted: bool,
    /// Whether a ray of the scan crossed the cell ([`Evidence::first_visit`]): a sample may leave every other
    /// field as it was (a beam over a surface says nothing about it).
    visited: bool,
}

const _: () = assert!(size_of::<ScanEvidence>() == 32);

/// What one scan's hits say about one cell under every rule of [`ModelOptions`](crate::model::ModelOptions): the spread of the hits, and
/// those above the cell's surface band (the ceiling layer's measurement).
#[derive(Debug, Clone, Copy)]
pub(crate) struct HitEvidence {
    /// The scan's hits in the cell as an unweighted sample: their number, mean and sum of squared deviations
    /// (Welford), and the sum of their variances ([`crate::model::spread_variance`]).
    pub(super) hits: HitSample,
    /// The scan's hits above the cell's surface band ([`OverheadHits::Ceiling`](crate::model::OverheadHits::Ceiling)) as a sample, and their largest
    /// probability (0: none).
    pub(super) overhead: HitSample,
    pub(super) ceiling_p: f32,
    /// The largest distance of an overhead hit above the cell's surface, in standard deviations of the
    /// difference ([`overhead_significant`]).
    pub(super) overhead_score: f32,
    /// The number of the scan's samples in the cell that measured a height, overhead hits included.
    pub(super) num_heights: f32,
    /// From which side the beams of the scan's overhead hits came.
    pub(super) ceiling_seen_from: SeenFrom,
}

const _: () = assert!(size_of::<HitEvidence>() == 48);

/// The [`HitEvidence`] of the cells a scan's hits reached, in the order they were first hit, and the tiles of
/// those with a hit above their surface band (the ceiling layer needs a tile there), cleared after each scan
/// with the grid it belongs to.
#[derive(Debug, Clone, Default)]
pub(crate) struct HitLog {
    entries: Vec<HitEvidence>,
    /// The tile of each cell at its scan's first overhead hit: at most one per entry.
    overhead_tiles: Vec<TileIndex>,
}

impl HitLog {
    /// The tiles with a hit above a cell's surface band, each as often as it has such cells.
    pub(super) fn overhead_tiles(&self) -> &[TileIndex] {
        &self.overhead_tiles
    }
}

impl HitEvidence {
    const NONE: Self = Self {
        hits: HitSample::NONE,
        overhead: HitSample::NONE,
        ceiling_p: 0.0,
        overhead_score: 0.0,
        num_heights: 0.0,
        ceiling_seen_from: SeenFrom::Both,
    };

    /// The scan's measurement of the cell's ceiling, if it hit one: the mean of its overhead hits, with the
    /// variance of [`ScanHitElevation::MeanWithSpread`] (the hits' spread over their noise is the structure's
    /// extent in the cell), the hits no better than `rho` of one ([`ModelOptions::measurement_correlation`](crate::model::ModelOptions::measurement_correlation)).
    /// None when the overhead hits are the tail of the surface's noise ([`overhead_significant`], with the band
    /// `band_sigmas` wide) among the hits the surface stands on: the scan's samples of the cell, times the
    /// hits like these that the surface's variance `surface_var_m2` is worth (`s^2 / var`, at least 1). A
    /// surface measured by many views has given noise as many chances to put one hit past the band.
    pub(super) fn ceiling_hit(
        &self,
        rho: f32,
        band_sigmas: f32,
        surface_var_m2: Option<f32>,
    ) -> Option<CeilingHit> {
        let hits = &self.overhead;
        let views = surface_var_m2
            .filter(|v| *v > 0.0)
            .map_or(1.0, |v| (hits.mean_variance() / v).max(1.0));
        let structure = self.ceiling_p > 0.0
            && overhead_significant(self.overhead_score, self.num_heights * views, band_sigmas);
        structure.then(|| CeilingHit {
            z_m: hits.mean_m,
            var_m2: spread_variance(
                (hits.mean_variance() / hits.n).max(rho * hits.mean_variance()),
                hits.sample_variance(),
                hits.mean_variance(),
            ),
            p: self.ceiling_p,
            seen_from: self.ceiling_seen_from,
        })
    }

    /// A hit above the cell's surface band ([`OverheadHits::Ceiling`](crate::model::OverheadHits::Ceiling)), by a beam from `side`, `score` standard
    /// deviations above the surface.
    #[inline(always)]
    fn add_overhead(&mut self, p: f32, z_m: f32, var_m2: f32, side: SeenFrom, score: f32) {
        self.num_heights += 1.0;
        self.overhead_score = self.overhead_score.max(score);
        self.ceiling_seen_from = if self.ceiling_p > 0.0 {
            self.ceiling_seen_from.and(side)
        } else {
            side
        };
        self.ceiling_p = self.ceiling_p.max(p);
        self.overhead.add(z_m, var_m2);
    }
}

impl ScanEvidence {
    pub(crate) const NONE: Self = Self {
        paper: PaperEvidence::NONE,
        ceiling_clear_m: f32::NEG_INFINITY,
        hit_entry: 0,
        band_contradicted: false,
        ceiling_contradicted: false,
        visited: false,
    };

    /// Adds what a later run of the same scan's rays said, gathered apart with its hits deferred
    /// ([`DeferredHits`]): every field of the grid's part is a maximum, a minimum or a flag, so afterwards
    /// `self` is what gathering both runs would have given, but for the later run's hits, replayed next.
    pub(super) fn merge_later(&mut self, later: &Self) {
        self.paper.merge_later(&later.paper);
        if later.ceiling_clear_m > self.ceiling_clear_m {
            self.ceiling_clear_m = later.ceiling_clear_m;
        }
        self.band_contradicted |= later.band_contradicted;
        self.ceiling_contradicted |= later.ceiling_contradicted;
        self.visited |= later.visited;
    }

    /// The cell's hit evidence in `log`, if the scan hit it.
    #[inline(always)]
    pub(super) fn hit_evidence<'a>(&self, log: &'a HitLog) -> Option<&'a HitEvidence> {
        (self.hit_entry > 0).then(|| &log.entries[self.hit_entry as usize - 1])
    }

    /// The cell's hit evidence in `log`, added on the scan's first hit in the cell. `log` has room for it
    /// ([`HitStore::reserve`], before each ray), so this never reallocates.
    #[inline(always)]
    fn hit_evidence_mut<'a>(&mut self, log: &'a mut HitLog) -> &'a mut HitEvidence {
        if self.hit_entry == 0 {
            let entries = &mut log.entries;
            debug_assert!(
                entries.len() < entries.capacity(),
                "the hit log was not reserved for this ray"
            );
            entries.push(HitEvidence::NONE);
            self.hit_entry = entries.len() as u32;
        }
        &mut log.entries[self.hit_entry as usize - 1]
    }

    /// Whether the scan said something about the cell's ceiling.
    pub(super) fn touches_ceiling(&self, hits: Option<&HitEvidence>) -> bool {
        self.ceiling_contradicted
            || hits.is_some_and(|h| h.ceiling_p > 0.0)
            || self.ceiling_clear_m > f32::NEG_INFINITY
    }

    /// A hit above the cell's surface band ([`OverheadHits::Ceiling`](crate::model::OverheadHits::Ceiling)),
    /// in `tile`, by a beam from `side`, `score` standard deviations above the surface.
    #[inline(always)]
    pub(super) fn add_overhead(
        &mut self,
        (log, tile): (&mut HitLog, TileIndex),
        p: f32,
        z_m: f32,
        var_m2: f32,
        side: SeenFrom,
        score: f32,
    ) {
        if self.hit_evidence_mut(log).ceiling_p == 0.0 {
            // Room was reserved with the entry's ([`HitStore::reserve`]).
            log.overhead_tiles.push(tile);
        }
        self.hit_evidence_mut(log)
            .add_overhead(p, z_m, var_m2, side, score);
    }

    /// A sample with `p > l_occ`: an elevation measurement `z_m` (eq. 12). Under
    /// [`ScanHitElevation::HighestLevel`] a hit above the band of the hits so far starts them afresh and one
    /// below it is left out (`band_sigmas` wide).
    #[inline(always)]
    pub(super) fn add_hit(
        &mut self,
        log: &mut HitLog,
        p: f32,
        z_m: f32,
        var_m2: f32,
        rule: ScanHitElevation,
        band_sigmas: f32,
    ) {
        self.paper.raise_p(p);
        let hit = self.hit_evidence_mut(log);
        hit.num_heights += 1.0;
        if rule == ScanHitElevation::HighestLevel && hit.hits.n > 0.0 {
            let level = Elevation {
                mean_m: hit.hits.mean_m,
                var_m2: hit.hits.mean_variance(),
            };
            match surface_level(level, z_m, var_m2, band_sigmas) {
                Level::Below => return,
                Level::Above => {
                    self.paper.hit_z_m = f32::NEG_INFINITY;
                    self.paper.hit_var_m2 = f32::INFINITY;
                    hit.hits = HitSample::NONE;
                }
                Level::Same => {}
            }
        }
        let paper = &mut self.paper;
        (paper.hit_z_m, paper.hit_var_m2) = rule.combine((paper.hit_z_m, paper.hit_var_m2), z_m, var_m2);
        hit.hits.add(z_m, var_m2);
    }
}

/// A scan's hits in one cell as a sample: enough to tell their spread from their noise.
#[derive(Debug, Clone, Copy)]
pub(crate) struct HitSample {
    pub(super) n: f32,
    pub(super) mean_m: f32,
    pub(super) m2: f32,
    pub(super) sum_var_m2: f32,
}

impl HitSample {
    pub(super) const NONE: Self = Self {
        n: 0.0,
        mean_m: 0.0,
        m2: 0.0,
        sum_var_m2: 0.0,
    };

    #[inline(always)]
    pub(super) fn add(&mut self, z_m: f32, var_m2: f32) {
        self.n += 1.0;
        let d = z_m - self.mean_m;
        self.mean_m += d / self.n;
        self.m2 += d * (z_m - self.mean_m);
        self.sum_var_m2 += var_m2;
    }

    /// The sample variance of the hits' heights (0 for fewer than two).
    pub(super) fn sample_variance(&self) -> f32 {
        if self.n < 2.0 {
            0.0
        } else {
            self.m2 / (self.n - 1.0)
        }
    }

    /// The mean of the hits' own variances.
    pub(super) fn mean_variance(&self) -> f32 {
        if self.n < 1.0 {
            0.0
        } else {
            self.sum_var_m2 / self.n
        }
    }
}

impl HitLog {
    /// Bytes an entry reserves: its evidence, and room for its tile in `overhead_tiles`.
    const ENTRY_BYTES: u64 = (size_of::<HitEvidence>() + size_of::<TileIndex>()) as u64;
}

impl HitStore for HitLog {
    /// Grows as a `Vec` does (at least doubling), or to exactly what is needed when doubling would pass the
    /// limit.
    #[inline]
    fn reserve(&mut self, entries: usize, limit_bytes: u64) -> Result<(), CapacityExceeded> {
        let (len, capacity) = (self.entries.len(), self.entries.capacity());
        let needed = len.saturating_add(entries);
        if needed <= capacity && needed <= self.overhead_tiles.capacity() {
            return Ok(());
        }
        let bytes = |n: usize| (n as u64).saturating_mul(Self::ENTRY_BYTES);
        let doubled = needed.max(capacity.saturating_mul(2));
        let target = if bytes(doubled) <= limit_bytes {
            doubled
        } else if bytes(needed) <= limit_bytes {
            needed
        } else {
            return Err(CapacityExceeded {
                requested_bytes: bytes(needed),
            });
        };
        self.entries.reserve_exact(target - len);
        let tiles = &mut self.overhead_tiles;
        tiles.reserve_exact(target - tiles.len());
        Ok(())
    }

    fn clear(&mut self) {
        self.entries.clear();
        self.overhead_tiles.clear();
    }

    fn memory_bytes(&self) -> u64 {
        (self.entries.capacity() * size_of::<HitEvidence>()
            + self.overhead_tiles.capacity() * size_of::<TileIndex>()) as u64
    }
}

impl HitSink<ScanEvidence> for HitLog {
    #[inline(always)]
    fn add_hit(
        &mut self,
        evidence: &mut ScanEvidence,
        _at: (TileIndex, usize),
        hit: SampledHit,
        levels: HitLevels,
    ) {
        evidence.add_hit(self, hit.p, hit.z_m, hit.var_m2, levels.rule, levels.band_sigmas);
    }

    #[inline(always)]
    fn add_overhead(
        &mut self,
        evidence: &mut ScanEvidence,
        (tile, _): (TileIndex, usize),
        hit: SampledHit,
        side: SeenFrom,
        score: f32,
    ) {
        evidence.add_overhead((self, tile), hit.p, hit.z_m, hit.var_m2, side, score);
    }
}

impl Evidence for ScanEvidence {
    const NONE: Self = Self::NONE;
    type Hits = HitLog;
    type Deferred = DeferredHits;

    /// A free sample may leave the probability as it was and still say something of the cell's ceiling.
    fn is_touched(&self) -> bool {
        !self.paper.is_untouched()
            || self.ceiling_contradicted
            || self.band_contradicted
            || self.ceiling_clear_m > f32::NEG_INFINITY
    }

    /// The grid's part merges exactly under every option: the hits, whose combination depends on their
    /// order, are deferred and replayed.
    fn exact_merge(_opts: &ModelOptions) -> Option<ExactMerge<Self>> {
        Some(ExactMerge::new(ScanEvidence::merge_later))
    }

    fn replay(
        grid: &mut TileGrid<Self>,
        log: &mut HitLog,
        deferred: &DeferredHits,
        opts: &ModelOptions,
        limit_bytes: u64,
    ) -> Result<(), CapacityExceeded> {
        deferred.replay(grid, log, opts, limit_bytes)
    }

    #[inline(always)]
    fn paper(&self) -> &PaperEvidence {
        &self.paper
    }

    #[inline(always)]
    fn first_visit(&mut self) -> bool {
        !std::mem::replace(&mut self.visited, true)
    }

    fn hits(&self, log: &HitLog) -> HitSample {
        self.hit_evidence(log).map_or(HitSample::NONE, |h| h.hits)
    }

    fn band_contradicted(&self) -> bool {
        self.band_contradicted
    }

    fn full<'a>(&'a self, log: &'a HitLog) -> Option<(&'a ScanEvidence, Option<&'a HitEvidence>)> {
        Some((self, self.hit_evidence(log)))
    }

    fn overhead_tiles(log: &HitLog) -> &[TileIndex] {
        log.overhead_tiles()
    }
}
