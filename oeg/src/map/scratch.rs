//! The scan scratch: what one scan says about each cell it touches, gathered before any cell is updated
//! (Algorithm 1 reads the map as it was before the scan), kept in tiles beside the map and reused scan after
//! scan.

pub(crate) use super::rule_evidence::{HitEvidence, HitSample, ScanEvidence};
use crate::model::{FreeSpaceOccupancy, ModelOptions, OverheadHits, ScanHitElevation};
use crate::storage::{CapacityExceeded, TileGrid, TileIndex};

/// What one scan says about one cell under the paper's rules (eq. 10-12), gathered over all its rays before
/// the cell is updated once: all a model reads that judges no sample against the cell's surface or ceiling
/// and fuses a cell's hits by their highest or their weighted mean ([`ScanScratch::for_model`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PaperEvidence {
    /// The largest inverse-sensor-model probability of any ray's sample in the cell; 0: untouched (a sample's
    /// probability is at least `p_min` > 0).
    pub(super) p_max: f32,
    /// The scan's elevation measurement (eq. 12 with `p > l_occ`) from its hits as
    /// [`ModelOptions::scan_hit_elevation`] says (the paper: the highest); -inf: none.
    pub(super) hit_z_m: f32,
    /// Variance of that measurement.
    pub(super) hit_var_m2: f32,
    /// The lowest height at which a ray passed freely through the cell (the ray's highest point inside it),
    /// from samples more than 3 sigma before their hit (confidently free).
    pub(super) free_z_m: f32,
    /// The smallest measurement variance among the free samples.
    pub(super) free_var_m2: f32,
}

const _: () = assert!(size_of::<PaperEvidence>() == 20);

impl PaperEvidence {
    pub(crate) const NONE: Self = Self {
        p_max: 0.0,
        hit_z_m: f32::NEG_INFINITY,
        hit_var_m2: f32::INFINITY,
        free_z_m: f32::INFINITY,
        free_var_m2: f32::INFINITY,
    };

    pub(super) fn is_untouched(&self) -> bool {
        self.p_max == 0.0
    }

    // The selects below compile to single min / max instructions: no value here is NaN, so the NaN handling
    // of f32::min and f32::max is not needed in this, the hottest loop.
    #[inline(always)]
    pub(super) fn raise_p(&mut self, p: f32) {
        self.p_max = if p > self.p_max { p } else { self.p_max };
    }

    /// A sample with `p > l_occ`: an elevation measurement `z_m` (eq. 12), combined with the scan's others by
    /// `rule`.
    #[inline(always)]
    pub(super) fn add_hit(&mut self, p: f32, z_m: f32, var_m2: f32, rule: ScanHitElevation) {
        self.raise_p(p);
        (self.hit_z_m, self.hit_var_m2) = rule.combine((self.hit_z_m, self.hit_var_m2), z_m, var_m2);
    }

    /// A sample the beam passed through, its highest point in the cell at `beam_top_m`.
    #[inline(always)]
    pub(super) fn add_free(&mut self, p: f32, beam_top_m: f32, var_m2: f32) {
        self.raise_p(p);
        self.free_z_m = if beam_top_m < self.free_z_m {
            beam_top_m
        } else {
            self.free_z_m
        };
        self.free_var_m2 = if var_m2 < self.free_var_m2 {
            var_m2
        } else {
            self.free_var_m2
        };
    }

    /// Adds what later rays of the same scan said, gathered apart: afterwards `self` is what gathering both
    /// in order would have given, bit for bit, under [`ScanHitElevation::Highest`]. Every field is a maximum
    /// or a minimum, and the highest hit keeps the first of equal heights, as [`ScanHitElevation::combine`]
    /// does.
    #[inline]
    pub(super) fn merge_later(&mut self, later: &Self) {
        self.raise_p(later.p_max);
        if later.hit_z_m > self.hit_z_m {
            (self.hit_z_m, self.hit_var_m2) = (later.hit_z_m, later.hit_var_m2);
        }
        if later.free_z_m < self.free_z_m {
            self.free_z_m = later.free_z_m;
        }
        if later.free_var_m2 < self.free_var_m2 {
            self.free_var_m2 = later.free_var_m2;
        }
    }
}

/// The evidence a model gathers per cell: the paper's alone ([`PaperEvidence`], 20 bytes a cell) or every
/// rule's ([`ScanEvidence`], 32 bytes a cell and 48 more for each cell a hit reached), chosen once per map
/// ([`ScanScratch::for_model`]), so a model pays in memory and in work only for the rules it uses.
pub(crate) trait Evidence: Copy + Send + Sync + 'static {
    const NONE: Self;
    /// What the evidence keeps beside its grid: the scan's [`super::rule_evidence::HitLog`], or nothing.
    type Hits: HitStore + HitSink<Self>;
    /// What a later run of a scan gathered in parallel keeps beside its grid: its hits, in their order, to be
    /// replayed into the first run's once the grids are merged ([`Evidence::replay`]), or nothing.
    type Deferred: HitStore + HitSink<Self>;
    fn paper(&self) -> &PaperEvidence;
    /// Whether a sample of the scan left anything in the cell's evidence (an untouched cell merges as nothing).
    fn is_touched(&self) -> bool {
        !self.paper().is_untouched()
    }
    /// Called as a ray's sample is about to be added: whether the scan's rays had not crossed the cell yet
    /// (the cell's offset is then marked, so that the update and the clearing visit the cells crossed alone).
    fn first_visit(&mut self) -> bool;
    /// The scan's hits in the cell as a sample (none for evidence that does not keep them).
    fn hits(&self, _log: &Self::Hits) -> HitSample {
        HitSample::NONE
    }
    /// Whether a free sample passed through the cell's surface band.
    fn band_contradicted(&self) -> bool {
        false
    }
    /// The tiles where the scan hit something above a cell's surface band, from `log` (none for evidence that
    /// does not keep them), each at least once.
    fn overhead_tiles(_log: &Self::Hits) -> &[TileIndex] {
        &[]
    }
    /// The full evidence and the cell's hits, where they are kept (the ceiling layer reads them).
    fn full<'a>(&'a self, _log: &'a Self::Hits) -> Option<(&'a ScanEvidence, Option<&'a HitEvidence>)> {
        None
    }
    /// How evidence gathered from a later run of a scan's rays merges into an earlier run's to give exactly
    /// the evidence of one run under `opts` ([`PaperEvidence::merge_later`]), if it can: then the rays may be
    /// gathered in parallel. What the evidence keeps beside its grid is replayed, in the runs' order, after
    /// the grids merge ([`Evidence::replay`]).
    fn exact_merge(_opts: &ModelOptions) -> Option<ExactMerge<Self>> {
        None
    }
    /// Adds a later run's `deferred` hits, in their order, to `grid` (the runs' grids merged into it) and its
    /// `hits`, as gathering the runs one after the other would have, the log within `limit_bytes`.
    ///
    /// # Errors
    /// When the log would pass `limit_bytes`.
    fn replay(
        _grid: &mut TileGrid<Self>,
        _hits: &mut Self::Hits,
        _deferred: &Self::Deferred,
        _opts: &ModelOptions,
        _limit_bytes: u64,
    ) -> Result<(), CapacityExceeded> {
        Ok(())
    }
}

/// [`Evidence::exact_merge`]'s merge of a later run's grid evidence into an earlier run's.
#[derive(Clone, Copy)]
pub(crate) struct ExactMerge<E>(fn(&mut E, &E));

impl<E: Evidence> ExactMerge<E> {
    pub(crate) fn new(merge: fn(&mut E, &E)) -> Self {
        Self(merge)
    }
}

impl<E> ExactMerge<E> {
    /// Merges `later` into `earlier`.
    #[inline(always)]
    pub(crate) fn merge(self, earlier: &mut E, later: &E) {
        (self.0)(earlier, later);
    }
}

/// What evidence keeps beside its grid, cleared with it after each scan.
pub(crate) trait HitStore: Default + Clone + std::fmt::Debug + Send + Sync {
    /// Makes room for `entries` more without reallocating, if it stays within `limit_bytes`.
    fn reserve(&mut self, entries: usize, limit_bytes: u64) -> Result<(), CapacityExceeded>;
    fn clear(&mut self);
    fn memory_bytes(&self) -> u64;
}

/// Where a scan's hits go as they are sampled: into the cell's evidence and what it keeps beside the grid at
/// once ([`super::rule_evidence::HitLog`], or nothing for the paper's evidence), or, for a later run of a scan
/// gathered in parallel, into a list replayed in order once the runs' grids are merged
/// ([`super::rule_evidence::DeferredHits`]).
pub(crate) trait HitSink<E>: HitStore {
    /// A sample with `p > l_occ` at `at` (its tile and offset): an elevation measurement `z_m` of variance
    /// `var_m2` (eq. 12), combined with the scan's others by `rule`, `band_sigmas` wide
    /// ([`ScanHitElevation::HighestLevel`]).
    fn add_hit(&mut self, evidence: &mut E, at: (TileIndex, usize), hit: SampledHit, levels: HitLevels);
    /// A hit above the cell's surface band ([`crate::OverheadHits::Ceiling`]) by a beam from `side`, `score`
    /// standard deviations above the surface.
    fn add_overhead(
        &mut self,
        evidence: &mut E,
        at: (TileIndex, usize),
        hit: SampledHit,
        side: crate::model::SeenFrom,
        score: f32,
    );
}

/// One sample's hit: its probability (eq. 10) and height with its variance (eq. 12).
#[derive(Debug, Clone, Copy)]
pub(crate) struct SampledHit {
    pub(crate) p: f32,
    pub(crate) z_m: f32,
    pub(crate) var_m2: f32,
}

/// How a scan's hits in a cell combine: [`ModelOptions::scan_hit_elevation`] and
/// [`ModelOptions::surface_band_sigmas`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct HitLevels {
    pub(crate) rule: ScanHitElevation,
    pub(crate) band_sigmas: f32,
}

impl HitLevels {
    pub(crate) fn of(opts: &ModelOptions) -> Self {
        Self {
            rule: opts.scan_hit_elevation,
            band_sigmas: opts.surface_band_sigmas,
        }
    }
}

/// The paper's evidence keeps its hits in the grid alone.
impl HitSink<PaperEvidence> for () {
    #[inline(always)]
    fn add_hit(
        &mut self,
        evidence: &mut PaperEvidence,
        _at: (TileIndex, usize),
        hit: SampledHit,
        levels: HitLevels,
    ) {
        evidence.add_hit(hit.p, hit.z_m, hit.var_m2, levels.rule);
    }

    /// The paper's rules keep no structure over a cell and never ask this: a hit over its surface would count
    /// for the occupancy.
    #[inline(always)]
    fn add_overhead(
        &mut self,
        evidence: &mut PaperEvidence,
        _at: (TileIndex, usize),
        hit: SampledHit,
        _side: crate::model::SeenFrom,
        _score: f32,
    ) {
        evidence.raise_p(hit.p);
    }
}

impl HitStore for () {
    #[inline(always)]
    fn reserve(&mut self, _entries: usize, _limit_bytes: u64) -> Result<(), CapacityExceeded> {
        Ok(())
    }

    fn clear(&mut self) {}

    fn memory_bytes(&self) -> u64 {
        0
    }
}

impl Evidence for PaperEvidence {
    const NONE: Self = Self::NONE;
    type Hits = ();
    type Deferred = ();

    #[inline(always)]
    fn paper(&self) -> &PaperEvidence {
        self
    }

    /// Every sample of the paper's rules raises the probability to at least `p_min > 0`.
    #[inline(always)]
    fn first_visit(&mut self) -> bool {
        self.is_untouched()
    }

    fn exact_merge(opts: &ModelOptions) -> Option<ExactMerge<Self>> {
        (opts.scan_hit_elevation == ScanHitElevation::Highest)
            .then(|| ExactMerge::new(PaperEvidence::merge_later))
    }
}

/// The scratch of one evidence kind: the grid the scan's rays are gathered into, and one more per extra thread
/// when they are gathered in parallel, all kept between scans for reuse.
#[derive(Debug, Clone)]
pub(crate) struct Scratch<E: Evidence> {
    pub(super) main: TileGrid<E>,
    /// What `main`'s evidence keeps beside it.
    pub(super) hits: E::Hits,
    pub(super) workers: Vec<TileGrid<E>>,
}

impl<E: Evidence> Scratch<E> {
    pub(super) fn recycle(&mut self) {
        self.main.recycle_marked();
        self.hits.clear();
        self.workers.iter_mut().for_each(TileGrid::recycle_marked);
    }

    fn new() -> Self {
        Self {
            main: TileGrid::new(E::NONE),
            hits: E::Hits::default(),
            workers: Vec::new(),
        }
    }

    pub(super) fn memory_bytes(&self) -> u64 {
        self.main.memory_bytes()
            + self.hits.memory_bytes()
            + self.workers.iter().map(TileGrid::memory_bytes).sum::<u64>()
    }
}

/// A map's per-scan scratch, of the evidence kind its model needs.
#[derive(Debug, Clone)]
pub(crate) enum ScanScratch {
    Paper(Scratch<PaperEvidence>),
    Full(Scratch<ScanEvidence>),
}

impl ScanScratch {
    /// An empty scratch for `opts`: the paper's evidence unless a rule needs more. The rules that do judge a
    /// free sample against the cell's surface or ceiling ([`FreeSpaceOccupancy::SurfaceBand`],
    /// [`ModelOptions::free_space_max_depth_m`], [`OverheadHits::Ceiling`]) or read the spread of a cell's hits
    /// ([`ScanHitElevation::MeanWithSpread`], [`ScanHitElevation::HighestLevel`]).
    pub(crate) fn for_model(opts: &ModelOptions) -> Self {
        let paper = opts.free_space_occupancy != FreeSpaceOccupancy::SurfaceBand
            && opts.free_space_max_depth_m.is_none()
            && opts.overhead_hits != OverheadHits::Ceiling
            && matches!(
                opts.scan_hit_elevation,
                ScanHitElevation::Highest | ScanHitElevation::WeightedMean
            );
        if paper {
            Self::Paper(Scratch::new())
        } else {
            Self::Full(Scratch::new())
        }
    }

    /// Bytes held, workers' grids included.
    pub(crate) fn memory_bytes(&self) -> u64 {
        match self {
            Self::Paper(s) => s.memory_bytes(),
            Self::Full(s) => s.memory_bytes(),
        }
    }

    /// Clears what the last scan wrote, keeping the memory for the next.
    pub(crate) fn recycle(&mut self) {
        match self {
            Self::Paper(s) => s.recycle(),
            Self::Full(s) => s.recycle(),
        }
    }

    /// Bytes of one cell's evidence in the grid (a cell a hit reached keeps 48 more beside it under every
    /// rule's evidence: [`HitEvidence`]).
    pub(crate) fn cell_bytes(&self) -> usize {
        match self {
            Self::Paper(_) => size_of::<PaperEvidence>(),
            Self::Full(_) => size_of::<ScanEvidence>(),
        }
    }
}
