//! The one place where cells are judged: for every cell of a run's region, what the truth says (its class),
//! what the map says (its [`Traversability`]) and the verdict on the map. Every metric, CSV file, image and the
//! planner check read this raster; "truly blocked" is defined once, by [`TruthRaster::truly_blocked`].

use oeg::{CellIndex, GridWindow, Map, Traversability, TraversabilityRule};
use serde::Serialize;
use sim::truth::TruthRaster;

use crate::error::Result;

/// What the truth says about a cell. A cell both under a too-low structure and a step is [`Self::TooLow`]: the
/// classes partition the cells, so counts add up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum TruthClass {
    /// No terrain under the cell.
    OffTerrain,
    /// The robot drives there.
    Drivable,
    /// The robot drives there, under a structure higher than itself.
    PassableUnder,
    /// A step the robot cannot climb (a rise of more than its step within its contact distance).
    Step,
    /// Under a structure lower than the robot.
    TooLow,
}

impl TruthClass {
    /// Every class, in the order of their codes (`as u8`).
    pub const ALL: [TruthClass; 5] = [
        Self::OffTerrain,
        Self::Drivable,
        Self::PassableUnder,
        Self::Step,
        Self::TooLow,
    ];

    /// The snake_case name used in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::OffTerrain => "off_terrain",
            Self::Drivable => "drivable",
            Self::PassableUnder => "passable_under",
            Self::Step => "step",
            Self::TooLow => "too_low",
        }
    }

    /// Whether the robot truly cannot enter the cell.
    pub fn is_blocked(self) -> bool {
        matches!(self, Self::Step | Self::TooLow)
    }

    /// Whether a ray could have told about the truth's cell at raster offset `k` of this class, by the run's
    /// observability truth `o` over the truth's region: a step when a ray ended on it, a structure lower than
    /// the robot when a ray ended in its band, on the structure. A cell the robot may enter is never blind.
    pub fn could_be_told(self, o: &sim::observability::Observability, k: usize) -> bool {
        match self {
            Self::Step => o.step[k],
            Self::TooLow => o.band_hit[k],
            _ => true,
        }
    }

    /// Whether a structure stands over the cell (passable or not): the clearance decision's cells.
    pub fn is_under_structure(self) -> bool {
        matches!(self, Self::PassableUnder | Self::TooLow)
    }

    /// The class of the truth's cell at raster offset `k`.
    pub fn of(truth: &TruthRaster, k: usize) -> Self {
        let t = &truth.cells[k];
        if t.elevation_m.is_nan() {
            return Self::OffTerrain;
        }
        match t.clearance_passable(&truth.profile) {
            Some(false) => Self::TooLow,
            _ if truth.truly_blocked(k) => Self::Step,
            Some(true) => Self::PassableUnder,
            None => Self::Drivable,
        }
    }
}

/// The verdict on the map's decision for one cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Not scored: never observed by the map, or off the terrain.
    NotScored,
    /// Truly drivable, mapped drivable.
    RightDrivable,
    /// Truly blocked, mapped blocked.
    RightBlocked,
    /// Truly blocked, mapped drivable: where the robot would drive into something.
    Unsafe,
    /// Truly drivable, mapped blocked.
    OverCautious,
    /// The map cannot tell (its step or clearance lies within `kappa` sigma of the threshold).
    Uncertain,
}

impl Verdict {
    /// Every verdict, in a fixed order.
    pub const ALL: [Verdict; 6] = [
        Self::NotScored,
        Self::RightDrivable,
        Self::RightBlocked,
        Self::Unsafe,
        Self::OverCautious,
        Self::Uncertain,
    ];

    /// The verdict on a map class `mapped` for a cell of truth class `truth`.
    pub fn of(truth: TruthClass, mapped: Traversability) -> Self {
        if truth == TruthClass::OffTerrain || mapped == Traversability::Unknown {
            return Self::NotScored;
        }
        if mapped == Traversability::Uncertain {
            return Self::Uncertain;
        }
        match (truth.is_blocked(), mapped == Traversability::Blocked) {
            (false, false) => Self::RightDrivable,
            (true, true) => Self::RightBlocked,
            (true, false) => Self::Unsafe,
            (false, true) => Self::OverCautious,
        }
    }

    /// The snake_case name used in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::NotScored => "not_scored",
            Self::RightDrivable => "right_drivable",
            Self::RightBlocked => "right_blocked",
            Self::Unsafe => "unsafe",
            Self::OverCautious => "over_cautious",
            Self::Uncertain => "uncertain",
        }
    }
}

/// The verdict raster of one map against one truth: row-major over the truth's region.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdicts {
    /// The cells: the truth's window.
    pub window: GridWindow,
    /// The truth's class of every cell.
    pub truth: Vec<TruthClass>,
    /// The map's class of every cell.
    pub mapped: Vec<Traversability>,
    /// The verdict on every cell.
    pub verdict: Vec<Verdict>,
    /// Per cell: truly blocked, and no ray could have told (`sim::observability`): no ray ended on a step
    /// cell, or inside the band of a cell under a structure lower than the robot. All false when the run has no observability truth (a
    /// replayed log).
    pub unobservable: Vec<bool>,
    /// Per cell, from the run's observability truth: whether any ray truly ended on the cell or crossed the
    /// band over it between a step and the robot's height, the rays that can tell a map what is there. `None`
    /// without an observability truth (a replayed log).
    pub reached: Option<Vec<bool>>,
}

/// How many cells got each verdict, with the unsafe and over-cautious ones split by what decides them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct VerdictCounts {
    /// Cells scored (observed, on the terrain): the sum of the verdicts below.
    pub num_scored_cells: u64,
    /// Truly drivable, mapped drivable.
    pub right_drivable_cells: u64,
    /// Truly blocked, mapped blocked.
    pub right_blocked_cells: u64,
    /// Truly a step, mapped drivable.
    pub unsafe_step_cells: u64,
    /// Under a structure lower than the robot, mapped drivable.
    pub unsafe_clearance_cells: u64,
    /// Truly drivable (no structure over it), mapped blocked.
    pub overcautious_step_cells: u64,
    /// Under a structure the robot passes under, mapped blocked.
    pub overcautious_clearance_cells: u64,
    /// Mapped uncertain.
    pub uncertain_cells: u64,
    /// Mapped uncertain and truly blocked: the uncertain cells that kept the robot out of trouble.
    pub uncertain_truly_blocked_cells: u64,
    /// Scored cells under a structure.
    pub num_clearance_cells: u64,
    /// Of the unsafe step cells, those no ray ended on: blind, not the map's fault.
    pub blind_step_cells: u64,
    /// Of the unsafe clearance cells, those whose band no ray crossed: blind.
    pub blind_clearance_cells: u64,
}

impl VerdictCounts {
    /// Unsafe cells, step and clearance.
    pub fn unsafe_cells(&self) -> u64 {
        self.unsafe_step_cells + self.unsafe_clearance_cells
    }

    /// Blind cells: unsafe cells no ray could have told, step and clearance.
    pub fn blind_cells(&self) -> u64 {
        self.blind_step_cells + self.blind_clearance_cells
    }

    /// Over-cautious cells, step and clearance.
    pub fn overcautious_cells(&self) -> u64 {
        self.overcautious_step_cells + self.overcautious_clearance_cells
    }
}

impl Verdicts {
    /// Judges `map` under `rule` against `truth` (whose profile is the robot's) over the truth's region.
    ///
    /// # Errors
    /// A raster too large for the map's memory limit.
    pub fn new(map: &Map, truth: &TruthRaster, rule: TraversabilityRule) -> Result<Self> {
        let mapped = map
            .traversability_layer(*truth.window.region(), &truth.profile, rule)?
            .values;
        Ok(Self::from_classes(truth, mapped))
    }

    /// The verdicts on the map classes `mapped` (row-major over the truth's region).
    pub fn from_classes(truth: &TruthRaster, mapped: Vec<Traversability>) -> Self {
        let truth_classes: Vec<TruthClass> =
            (0..truth.cells.len()).map(|k| TruthClass::of(truth, k)).collect();
        let verdict = truth_classes
            .iter()
            .zip(&mapped)
            .map(|(t, m)| Verdict::of(*t, *m))
            .collect();
        Self {
            window: truth.window,
            unobservable: vec![false; truth_classes.len()],
            reached: None,
            truth: truth_classes,
            mapped,
            verdict,
        }
    }

    /// Marks the truly blocked cells no ray could have told about, from the run's observability truth over
    /// the same region (a step: no ray ended on the cell; a structure lower than the robot: no ray ended in
    /// its band, on the structure). Without one (`None`, or another region) nothing is marked.
    pub fn with_observability(mut self, observability: Option<&sim::observability::Observability>) -> Self {
        let Some(o) = observability.filter(|o| o.window == self.window) else {
            return self;
        };
        for (k, t) in self.truth.iter().enumerate() {
            self.unobservable[k] = !t.could_be_told(o, k);
        }
        self.reached = Some(o.step.iter().zip(&o.clearance).map(|(s, c)| *s || *c).collect());
        self
    }

    /// Whether the cell at raster offset `k` is one no ray reached ([`Verdicts::reached`]); false without an
    /// observability truth.
    pub fn unreached(&self, k: usize) -> bool {
        self.reached.as_ref().is_some_and(|r| !r[k])
    }

    /// The raster offset of `cell`, if inside the region.
    pub fn offset(&self, cell: CellIndex) -> Option<usize> {
        self.window.region().offset(cell)
    }

    /// The counts of every verdict.
    pub fn counts(&self) -> VerdictCounts {
        let mut c = VerdictCounts::default();
        for ((t, v), blind) in self.truth.iter().zip(&self.verdict).zip(&self.unobservable) {
            if *v == Verdict::Unsafe && *blind {
                match t {
                    TruthClass::TooLow => c.blind_clearance_cells += 1,
                    _ => c.blind_step_cells += 1,
                }
            }
            if *v == Verdict::NotScored {
                continue;
            }
            c.num_scored_cells += 1;
            c.num_clearance_cells += u64::from(t.is_under_structure());
            let structure = t.is_under_structure();
            match v {
                Verdict::NotScored => {}
                Verdict::RightDrivable => c.right_drivable_cells += 1,
                Verdict::RightBlocked => c.right_blocked_cells += 1,
                Verdict::Unsafe if *t == TruthClass::TooLow => c.unsafe_clearance_cells += 1,
                Verdict::Unsafe => c.unsafe_step_cells += 1,
                Verdict::OverCautious if structure => c.overcautious_clearance_cells += 1,
                Verdict::OverCautious => c.overcautious_step_cells += 1,
                Verdict::Uncertain => {
                    c.uncertain_cells += 1;
                    c.uncertain_truly_blocked_cells += u64::from(t.is_blocked());
                }
            }
        }
        c
    }

    /// The truth's decisions as map classes, for planning on the truth: blocked where the robot truly cannot
    /// enter, free elsewhere, unknown off the terrain.
    pub fn truth_decisions(&self) -> Vec<Traversability> {
        self.truth
            .iter()
            .map(|t| match t {
                TruthClass::OffTerrain => Traversability::Unknown,
                t if t.is_blocked() => Traversability::Blocked,
                _ => Traversability::Free,
            })
            .collect()
    }

    /// The truth's decisions as the sensors could have told them: `truly` ([`Verdicts::truth_decisions`]) with
    /// every truly drivable cell that no ray reached unknown, as it is to any map of these readings (a truly
    /// blocked cell stays blocked). `None` without an observability truth.
    pub fn observable_truth_decisions(&self, truly: &[Traversability]) -> Option<Vec<Traversability>> {
        self.reached.as_ref()?;
        let mut decisions = truly.to_vec();
        for (k, d) in decisions.iter_mut().enumerate() {
            if *d == Traversability::Free && self.unreached(k) {
                *d = Traversability::Unknown;
            }
        }
        Some(decisions)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{truth_cell, truth_raster};
    use oeg::CellRegion;
    use proptest::prelude::*;

    const MAPPED: [Traversability; 5] = [
        Traversability::Unknown,
        Traversability::Free,
        Traversability::Traversable,
        Traversability::Blocked,
        Traversability::Uncertain,
    ];

    #[test]
    fn each_pair_of_classes_gets_its_verdict() {
        use Traversability as T;
        assert_eq!(Verdict::of(TruthClass::Step, T::Free), Verdict::Unsafe);
        assert_eq!(Verdict::of(TruthClass::TooLow, T::Traversable), Verdict::Unsafe);
        assert_eq!(
            Verdict::of(TruthClass::Drivable, T::Blocked),
            Verdict::OverCautious
        );
        assert_eq!(
            Verdict::of(TruthClass::PassableUnder, T::Free),
            Verdict::RightDrivable
        );
        assert_eq!(Verdict::of(TruthClass::Step, T::Uncertain), Verdict::Uncertain);
        assert_eq!(Verdict::of(TruthClass::Step, T::Unknown), Verdict::NotScored);
        assert_eq!(
            Verdict::of(TruthClass::OffTerrain, T::Blocked),
            Verdict::NotScored
        );
    }

    #[test]
    fn a_drivable_cell_no_ray_reached_is_unknown_to_the_observable_truth() {
        // 1 m cells, 5 x 3: a wall across x = 2 m but for its gap at y = 1 m, which no ray reached.
        let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(4, 2)).expect("region");
        let wall = |c: CellIndex| c.i == 2 && c.j != 1;
        let truth = truth_raster(
            region,
            region
                .cells()
                .map(|c| truth_cell(if wall(c) { 0.2 } else { 0.0 }, wall(c), f32::NAN))
                .collect(),
        );
        let gap = region.offset(CellIndex::new(2, 1)).expect("inside");
        let mut v = Verdicts::from_classes(&truth, vec![Traversability::Unknown; truth.cells.len()]);
        let truly = v.truth_decisions();
        assert_eq!(
            v.observable_truth_decisions(&truly),
            None,
            "no observability truth"
        );
        assert!(!v.unreached(gap));
        let mut reached = vec![true; truth.cells.len()];
        reached[gap] = false;
        // A blocked cell no ray reached stays blocked.
        let blocked = region.offset(CellIndex::new(2, 0)).expect("inside");
        reached[blocked] = false;
        v.reached = Some(reached);
        let told = v.observable_truth_decisions(&truly).expect("observability");
        for k in 0..truly.len() {
            let want = if k == gap {
                Traversability::Unknown
            } else {
                truly[k]
            };
            assert_eq!(told[k], want, "cell {k}");
        }
        assert_eq!(told[blocked], Traversability::Blocked);
        // The planner that avoids unknown cells finds the truth's path through the gap, and none through what
        // the rays reached.
        let options = oeg::PlannerOptions {
            inflation_radius_m: 0.0,
            ..oeg::PlannerOptions::default()
        };
        let (s, g) = (CellIndex::new(0, 1), CellIndex::new(4, 1));
        assert!(
            oeg::plan(&v.window, &truly, s, g, &options)
                .expect("valid")
                .is_some()
        );
        assert!(
            oeg::plan(&v.window, &told, s, g, &options)
                .expect("valid")
                .is_none()
        );
    }

    proptest! {
        /// Every cell gets exactly one verdict, and the counts are the raster's.
        #[test]
        fn every_cell_gets_one_verdict_and_the_counts_are_the_rasters(
            cells in prop::collection::vec((0usize..5, 0.0f32..0.1, prop::option::of(0.2f32..0.8), any::<bool>()), 1..200)
        ) {
            let n = cells.len() as i32;
            let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(n - 1, 0)).expect("region");
            let truth = truth_raster(
                region,
                cells
                    .iter()
                    .map(|(_, z, gap, off)| {
                        let mut c = truth_cell(*z, *z > 0.035, gap.unwrap_or(f32::NAN));
                        if *off { c.elevation_m = f32::NAN; }
                        c
                    })
                    .collect(),
            );
            let mapped: Vec<Traversability> = cells.iter().map(|(m, ..)| MAPPED[*m]).collect();
            let v = Verdicts::from_classes(&truth, mapped.clone());
            prop_assert_eq!(v.verdict.len(), cells.len());
            let c = v.counts();
            let tally = |want: Verdict| v.verdict.iter().filter(|x| **x == want).count() as u64;
            prop_assert_eq!(c.right_drivable_cells, tally(Verdict::RightDrivable));
            prop_assert_eq!(c.right_blocked_cells, tally(Verdict::RightBlocked));
            prop_assert_eq!(c.unsafe_cells(), tally(Verdict::Unsafe));
            prop_assert_eq!(c.overcautious_cells(), tally(Verdict::OverCautious));
            prop_assert_eq!(c.uncertain_cells, tally(Verdict::Uncertain));
            prop_assert_eq!(
                c.num_scored_cells,
                c.right_drivable_cells + c.right_blocked_cells + c.unsafe_cells() + c.overcautious_cells()
                    + c.uncertain_cells
            );
            prop_assert_eq!(c.num_scored_cells + tally(Verdict::NotScored), cells.len() as u64);
            for (k, m) in mapped.iter().enumerate() {
                // The one definition: the raster's truth agrees with the truth raster's.
                let off = truth.cells[k].elevation_m.is_nan();
                prop_assert_eq!(v.truth[k].is_blocked(), !off && truth.truly_blocked(k));
                prop_assert_eq!(v.verdict[k], Verdict::of(v.truth[k], *m));
            }
        }
    }
}
