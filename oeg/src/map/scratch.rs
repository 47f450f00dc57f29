//! The scan scratch: what one scan says about each cell it touches, gathered before any cell is updated
//! (Algorithm 1 reads the map as it was before the scan), kept in tiles beside the map and reused scan after
//! scan.

use crate::model::SeenFrom;
use crate::model::{
    CeilingHit, Elevation, FreeSpaceOccupancy, Level, ModelOptions, OverheadHits, ScanHitElevation,
    overhead_significant, spread_variance, surface_level,
};
use crate::storage::TileGrid;

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

/// What one scan says about one cell under every rule of [`ModelOptions`]: the paper's evidence, and what the
/// rules beyond it judge (the surface band, the ceiling layer, the spread of the hits).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScanEvidence {
    pub(super) paper: PaperEvidence,
    /// The scan's hits in the cell as an unweighted sample: their number, mean and sum of squared deviations
    /// (Welford), and the sum of their variances ([`crate::model::spread_variance`]).
    pub(super) hits: HitSample,
    /// Whether a free sample passed through the cell's surface band
    /// ([`FreeSpaceOccupancy::SurfaceBand`]).
    pub(super) band_contradicted: bool,
    /// Whether a free sample passed through the band of the cell's ceiling.
    pub(super) ceiling_contradicted: bool,
    /// The highest point of a free sample that passed under the band of the cell's ceiling (-inf: none).
    pub(super) ceiling_clear_m: f32,
    /// From which side the beams of the scan's overhead hits came.
    pub(super) ceiling_seen_from: SeenFrom,
    /// The scan's hits above the cell's surface band ([`OverheadHits::Ceiling`]) as a sample, and their largest
    /// probability (0: none).
    pub(super) overhead: HitSample,
    pub(super) ceiling_p: f32,
    /// The largest distance of an overhead hit above the cell's surface, in standard deviations of the
    /// difference ([`overhead_significant`]).
    pub(super) overhead_score: f32,
    /// The number of the scan's samples in the cell that measured a height, overhead hits included.
    pub(super) num_heights: f32,
    /// Whether a ray of the scan crossed the cell ([`Evidence::first_visit`]): a sample may leave every other
    /// field as it was (a beam over a surface says nothing about it).
    visited: bool,
}

const _: () = assert!(size_of::<ScanEvidence>() == 72);

impl ScanEvidence {
    pub(crate) const NONE: Self = Self {
        paper: PaperEvidence::NONE,
        hits: HitSample::NONE,
        band_contradicted: false,
        ceiling_contradicted: false,
        ceiling_clear_m: f32::NEG_INFINITY,
        ceiling_seen_from: SeenFrom::Both,
        overhead: HitSample::NONE,
        ceiling_p: 0.0,
        overhead_score: 0.0,
        num_heights: 0.0,
        visited: false,
    };

    /// Whether the scan said something about the cell's ceiling.
    pub(super) fn touches_ceiling(&self) -> bool {
        self.ceiling_contradicted || self.ceiling_p > 0.0 || self.ceiling_clear_m > f32::NEG_INFINITY
    }

    /// The scan's measurement of the cell's ceiling, if it hit one: the mean of its overhead hits, with the
    /// variance of [`ScanHitElevation::MeanWithSpread`] (the hits' spread over their noise is the structure's
    /// extent in the cell), the hits no better than `rho` of one ([`ModelOptions::measurement_correlation`]).
    /// None when the overhead hits are the tail of the surface's noise among the scan's samples of the cell
    /// ([`overhead_significant`], with the band `band_sigmas` wide).
    pub(super) fn ceiling_hit(&self, rho: f32, band_sigmas: f32) -> Option<CeilingHit> {
        let hits = &self.overhead;
        let structure =
            self.ceiling_p > 0.0 && overhead_significant(self.overhead_score, self.num_heights, band_sigmas);
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

    /// A hit above the cell's surface band ([`OverheadHits::Ceiling`]), by a beam from `side`, `score` standard
    /// deviations above the surface.
    #[inline(always)]
    pub(super) fn add_overhead(&mut self, p: f32, z_m: f32, var_m2: f32, side: SeenFrom, score: f32) {
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

    /// A sample with `p > l_occ`: an elevation measurement `z_m` (eq. 12). Under
    /// [`ScanHitElevation::HighestLevel`] a hit above the band of the hits so far starts them afresh and one
    /// below it is left out (`band_sigmas` wide).
    #[inline(always)]
    pub(super) fn add_hit(
        &mut self,
        p: f32,
        z_m: f32,
        var_m2: f32,
        rule: ScanHitElevation,
        band_sigmas: f32,
    ) {
        self.paper.raise_p(p);
        self.num_heights += 1.0;
        if rule == ScanHitElevation::HighestLevel && self.hits.n > 0.0 {
            let level = Elevation {
                mean_m: self.hits.mean_m,
                var_m2: self.hits.mean_variance(),
            };
            match surface_level(level, z_m, var_m2, band_sigmas) {
                Level::Below => return,
                Level::Above => {
                    self.paper.hit_z_m = f32::NEG_INFINITY;
                    self.paper.hit_var_m2 = f32::INFINITY;
                    self.hits = HitSample::NONE;
                }
                Level::Same => {}
            }
        }
        let paper = &mut self.paper;
        (paper.hit_z_m, paper.hit_var_m2) = rule.combine((paper.hit_z_m, paper.hit_var_m2), z_m, var_m2);
        self.hits.add(z_m, var_m2);
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
    const NONE: Self = Self {
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

/// The evidence a model gathers per cell: the paper's alone ([`PaperEvidence`], 20 bytes a cell) or every
/// rule's ([`ScanEvidence`], 72 bytes), chosen once per map ([`ScanScratch::for_model`]), so a model pays in
/// memory and in work only for the rules it uses.
pub(crate) trait Evidence: Copy + Send + Sync + 'static {
    const NONE: Self;
    fn paper(&self) -> &PaperEvidence;
    /// Called as a ray's sample is about to be added: whether the scan's rays had not crossed the cell yet
    /// (the cell's offset is then marked, so that the update and the clearing visit the cells crossed alone).
    fn first_visit(&mut self) -> bool;
    /// The scan's hits in the cell as a sample (none for evidence that does not keep them).
    fn hits(&self) -> HitSample {
        HitSample::NONE
    }
    /// Whether a free sample passed through the cell's surface band.
    fn band_contradicted(&self) -> bool {
        false
    }
    /// The full evidence, where it is kept (the ceiling layer reads it).
    fn full(&self) -> Option<&ScanEvidence> {
        None
    }
    /// How evidence gathered from a later run of a scan's rays merges into an earlier run's to give exactly
    /// the evidence of one run under `opts` ([`PaperEvidence::merge_later`]), if it can: then the rays may be
    /// gathered in parallel.
    fn exact_merge(_opts: &ModelOptions) -> Option<fn(&mut Self, &Self)> {
        None
    }
}

impl Evidence for PaperEvidence {
    const NONE: Self = Self::NONE;

    #[inline(always)]
    fn paper(&self) -> &PaperEvidence {
        self
    }

    /// Every sample of the paper's rules raises the probability to at least `p_min > 0`.
    #[inline(always)]
    fn first_visit(&mut self) -> bool {
        self.is_untouched()
    }

    fn exact_merge(opts: &ModelOptions) -> Option<fn(&mut Self, &Self)> {
        (opts.scan_hit_elevation == ScanHitElevation::Highest).then_some(PaperEvidence::merge_later)
    }
}

impl Evidence for ScanEvidence {
    const NONE: Self = Self::NONE;

    #[inline(always)]
    fn paper(&self) -> &PaperEvidence {
        &self.paper
    }

    #[inline(always)]
    fn first_visit(&mut self) -> bool {
        !std::mem::replace(&mut self.visited, true)
    }

    fn hits(&self) -> HitSample {
        self.hits
    }

    fn band_contradicted(&self) -> bool {
        self.band_contradicted
    }

    fn full(&self) -> Option<&ScanEvidence> {
        Some(self)
    }
}

/// The scratch of one evidence kind: the grid the scan's rays are gathered into, and one more per extra thread
/// when they are gathered in parallel, all kept between scans for reuse.
#[derive(Debug, Clone)]
pub(crate) struct Scratch<E: Evidence> {
    pub(super) main: TileGrid<E>,
    pub(super) workers: Vec<TileGrid<E>>,
}

impl<E: Evidence> Scratch<E> {
    pub(super) fn recycle(&mut self) {
        self.main.recycle_marked();
        self.workers.iter_mut().for_each(TileGrid::recycle_marked);
    }

    fn new() -> Self {
        Self {
            main: TileGrid::new(E::NONE),
            workers: Vec::new(),
        }
    }

    pub(super) fn memory_bytes(&self) -> u64 {
        self.main.memory_bytes() + self.workers.iter().map(TileGrid::memory_bytes).sum::<u64>()
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

    /// Bytes of one cell's evidence.
    pub(crate) fn cell_bytes(&self) -> usize {
        match self {
            Self::Paper(_) => size_of::<PaperEvidence>(),
            Self::Full(_) => size_of::<ScanEvidence>(),
        }
    }
}
