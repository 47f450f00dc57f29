//! Ghosts: how well a map forgets what moved and keeps what stands, with the measures of KTH's DynamicMap
//! benchmark (Zhang et al. 2023) adapted from points to cells.
//!
//! - **SA** (static accuracy): of the truly blocked cells the sensors could have told about (the observability
//!   truth) and no actor passed through, the fraction the map keeps blocked or uncertain: what a ghost
//!   remover must not remove.
//! - **DA** (dynamic accuracy): of the cells an actor's footprint covered at some time of the run, that are
//!   truly drivable and that no actor covers at its end, the fraction the map calls drivable at the end: the
//!   ghosts removed. Two kinds of cell say nothing about a ghost and are left out: one the map leaves
//!   uncertain only because the sensors measured it too coarsely to tell a step ([`oeg::Doubt::Imprecise`]:
//!   a stereo camera's ground a few metres away), and one where a ray met an actor at a height the sensors
//!   never observed again after the last actor left ([`sim::observability::Observability::seen_again`]): no
//!   map of these readings could have cleared what the actor left there, as SA leaves out the blocked cells
//!   no ray could tell about.
//! - **AA** (associated accuracy): `sqrt(SA x DA)`.
//!
//! Both are over the scored cells (observed, on the terrain, not left unknown): a cell the map never observed
//! is neither kept nor removed. DynamicMap reports them in percent; on KITTI sequence 00 it gives OctoMap an AA
//! of 82.37 and DUFOMap 98.56.

use oeg::{CellIndex, Doubt, GridWindow, Traversability};
use sim::observability::Observability;
use sim::scenario::{Actor, Scenario};

use crate::judge::verdict::{Verdict, Verdicts};

/// The counts behind SA, DA and AA.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct GhostCounts {
    /// Truly blocked, observable, scored cells no actor passed through.
    pub num_static_cells: u64,
    /// Of those, the ones the map keeps blocked or uncertain.
    pub static_kept_cells: u64,
    /// Cells an actor covered and left, truly drivable, scored.
    pub num_dynamic_cells: u64,
    /// Of those, the ones the map calls drivable at the end.
    pub dynamic_cleared_cells: u64,
}

impl GhostCounts {
    /// SA, a fraction; `None` without static cells.
    pub fn static_accuracy(&self) -> Option<f64> {
        fraction(self.static_kept_cells, self.num_static_cells)
    }

    /// DA, a fraction; `None` without dynamic cells (no actor, or none the map observed).
    pub fn dynamic_accuracy(&self) -> Option<f64> {
        fraction(self.dynamic_cleared_cells, self.num_dynamic_cells)
    }

    /// AA = `sqrt(SA x DA)`, a fraction; `None` when either is.
    pub fn associated_accuracy(&self) -> Option<f64> {
        Some((self.static_accuracy()? * self.dynamic_accuracy()?).sqrt())
    }
}

fn fraction(part: u64, whole: u64) -> Option<f64> {
    (whole > 0).then(|| part as f64 / whole as f64)
}

/// Per cell of `window`: the last time in `[0, end_s]` an actor's footprint covered its centre (-inf: never),
/// and whether one covers it at `end_s`. Each actor's path is followed in steps of at most half a cell.
pub(crate) fn actor_cells(actors: &[Actor], end_s: f64, window: &GridWindow) -> (Vec<f64>, Vec<bool>) {
    let n = window.num_cells() as usize;
    let (mut covered_until_s, mut at_end) = (vec![f64::NEG_INFINITY; n], vec![false; n]);
    let res = window.resolution_m();
    for actor in actors {
        let Some([t0, t1]) = actor.time_span_s() else {
            continue;
        };
        let (t0, t1) = (t0.max(0.0), t1.min(end_s));
        if t1 < t0 {
            continue;
        }
        let radius = actor.radius_m();
        // Steps of at most half a cell along the path: the fastest leg sets the time step.
        let mut t = t0;
        let step_s = max_speed_step(actor, res / 2.0);
        loop {
            if let Some((x, y)) = actor.position_at(t) {
                for_disk(window, (x, y), radius, |k| {
                    covered_until_s[k] = covered_until_s[k].max(t)
                });
            }
            if t >= t1 {
                break;
            }
            t = (t + step_s).min(t1);
        }
        if let Some((x, y)) = actor.position_at(end_s) {
            for_disk(window, (x, y), radius, |k| at_end[k] = true);
        }
    }
    (covered_until_s, at_end)
}

/// The time step that moves `actor` at most `step_m` on its fastest leg (the whole span when it never
/// moves), at least 1 ms.
fn max_speed_step(actor: &Actor, step_m: f64) -> f64 {
    let Actor::Person { waypoints, .. } = actor;
    let mut step = waypoints
        .last()
        .zip(waypoints.first())
        .map_or(1.0, |(l, f)| l[0] - f[0]);
    for w in waypoints.windows(2) {
        let (dt, d) = (w[1][0] - w[0][0], (w[1][1] - w[0][1]).hypot(w[1][2] - w[0][2]));
        if d > 0.0 {
            step = step.min(dt * step_m / d);
        }
    }
    step.max(1e-3)
}

/// Calls `f` with the raster offset of every cell of `window` whose centre lies within `radius_m` of `(x, y)`.
fn for_disk(window: &GridWindow, (x, y): (f64, f64), radius_m: f64, mut f: impl FnMut(usize)) {
    let (geometry, region) = (window.geometry(), window.region());
    let (Some(lo), Some(hi)) = (
        geometry.cell_of(x - radius_m, y - radius_m),
        geometry.cell_of(x + radius_m, y + radius_m),
    ) else {
        return;
    };
    for j in lo.j..=hi.j {
        for i in lo.i..=hi.i {
            let c = CellIndex::new(i, j);
            let (cx, cy) = geometry.cell_center(c);
            if (cx - x).hypot(cy - y) <= radius_m
                && let Some(k) = region.offset(c)
            {
                f(k);
            }
        }
    }
}

/// SA and DA's counts for the map judged in `verdicts` (with its observability marks), the actors of `s`
/// over its whole duration; `doubts` says why the map left each cell undecided (empty: it does not say);
/// `observability`, the run's observability truth over the same region, says which cells the sensors observed
/// again after the actors left (none, another region, or not tracked: every cell counts as observed again).
pub(crate) fn count(
    s: &Scenario,
    verdicts: &Verdicts,
    doubts: &[Option<Doubt>],
    observability: Option<&Observability>,
) -> GhostCounts {
    // With no actor no cell was swept: SA alone is counted, without a raster of times as large as the region.
    let actors = (!s.actors.is_empty()).then(|| actor_cells(&s.actors, s.duration_s, &verdicts.window));
    let seen_again = observability
        .filter(|o| o.window == verdicts.window)
        .and_then(Observability::seen_again);
    let swept = actors
        .as_ref()
        .map(|(until, at_end)| (until.as_slice(), at_end.as_slice()));
    tally(verdicts, doubts, swept, seen_again.as_deref())
}

/// [`count`] over the actors' cells: `swept`, the last time an actor covered each cell and whether one covers
/// it at the end, from [`actor_cells`] (`None`: no actor, no cell was swept); `seen_again` from the
/// observability truth.
fn tally(
    verdicts: &Verdicts,
    doubts: &[Option<Doubt>],
    swept: Option<(&[f64], &[bool])>,
    seen_again: Option<&[bool]>,
) -> GhostCounts {
    let mut c = GhostCounts::default();
    for k in 0..verdicts.verdict.len() {
        if verdicts.verdict[k] == Verdict::NotScored {
            continue;
        }
        let (swept, left) = swept.map_or((false, false), |(until, at_end)| {
            (until[k] > f64::NEG_INFINITY, !at_end[k])
        });
        let truth = verdicts.truth[k];
        let mapped = verdicts.mapped[k];
        if truth.is_blocked() && !swept && !verdicts.unobservable[k] {
            c.num_static_cells += 1;
            c.static_kept_cells += u64::from(matches!(
                mapped,
                Traversability::Blocked | Traversability::Uncertain
            ));
        } else if !truth.is_blocked() && swept && left {
            let imprecise = doubts.get(k).copied().flatten() == Some(Doubt::Imprecise);
            if !imprecise && seen_again.is_none_or(|seen| seen[k]) {
                c.num_dynamic_cells += 1;
                c.dynamic_cleared_cells += u64::from(mapped.is_drivable());
            }
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use oeg::{CellRegion, GridGeometry};

    fn person(waypoints: Vec<[f64; 3]>) -> Actor {
        Actor::Person {
            name: None,
            waypoints,
            radius_m: 0.25,
            height_m: 1.7,
        }
    }

    #[test]
    fn a_walk_sweeps_a_band_as_wide_as_the_person_and_one_who_stays_covers_cells_at_the_end() {
        let g = GridGeometry::new(0.05).expect("grid");
        let region =
            CellRegion::from_corners(CellIndex::new(0, -20), CellIndex::new(99, 19)).expect("region");
        // Walks 4 m along y = 0 in 2 s (2 m/s), then leaves the scene.
        let walker = person(vec![[0.0, 0.5, 0.0], [2.0, 4.5, 0.0]]);
        let (covered_until_s, at_end) = actor_cells(&[walker], 10.0, &GridWindow::new(g, region));
        assert!(at_end.iter().all(|c| !c));
        let until =
            |x: f64, y: f64| covered_until_s[region.offset(g.cell_of(x, y).expect("cell")).expect("inside")];
        let at = |x: f64, y: f64| until(x, y) > f64::NEG_INFINITY;
        // The cell centred at x = 2.025 m is covered while the walker is within 0.25 m of it: until it reaches
        // x = 2.275 m, at 0.8875 s, or up to a step of half a cell (0.0125 s at 2 m/s) before.
        let last = until(2.025, 0.0);
        assert!((0.8875 - 0.0125 - 1e-9..=0.8875 + 1e-9).contains(&last), "{last}");
        // Every cell along the way, no gap between the steps; the band is 0.5 m wide.
        for k in 0..80 {
            assert!(
                at(0.525 + 0.05 * f64::from(k), 0.0),
                "x = {}",
                0.525 + 0.05 * f64::from(k)
            );
        }
        assert!(at(2.0, 0.225) && !at(2.0, 0.275));
        assert!(!at(4.9, 0.0));
        // One who stands still to the end covers their cells at the end.
        let stander = person(vec![[0.0, 2.0, 0.0], [20.0, 2.0, 0.0]]);
        let (_, at_end) = actor_cells(&[stander], 10.0, &GridWindow::new(g, region));
        assert_eq!(at_end.iter().filter(|c| **c).count(), swept_disk_cells(&g));
    }

    /// Cells whose centre lies within 0.25 m of a point on a cell corner.
    fn swept_disk_cells(g: &GridGeometry) -> usize {
        let r = 0.25 / g.resolution_m();
        (-10..10)
            .flat_map(|j| (-10..10).map(move |i| (i, j)))
            .filter(|(i, j)| (f64::from(*i) + 0.5).hypot(f64::from(*j) + 0.5) <= r)
            .count()
    }

    #[test]
    fn da_leaves_out_a_cell_whose_ghost_the_sensors_never_observed_again() {
        use crate::judge::verdict::{TruthClass, Verdict, Verdicts};
        let g = GridGeometry::new(0.05).expect("grid");
        let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(3, 0)).expect("region");
        // Four truly drivable cells. The first three were covered by an actor: the map cleared the first; the
        // second is a ghost at a height no ray crossed again; the third a ghost the sensors did observe
        // again. The fourth was never covered.
        let mapped = vec![
            Traversability::Traversable,
            Traversability::Blocked,
            Traversability::Blocked,
            Traversability::Traversable,
        ];
        let verdicts = Verdicts {
            window: GridWindow::new(g, region),
            truth: vec![TruthClass::Drivable; 4],
            verdict: vec![
                Verdict::RightDrivable,
                Verdict::OverCautious,
                Verdict::OverCautious,
                Verdict::RightDrivable,
            ],
            mapped,
            unobservable: vec![false; 4],
            reached: None,
        };
        let covered_until_s = [1.0, 1.0, 1.0, f64::NEG_INFINITY];
        let at_end = [false; 4];
        let swept = Some((&covered_until_s[..], &at_end[..]));
        let seen = tally(&verdicts, &[], swept, Some(&[true, false, true, true]));
        assert_eq!((seen.num_dynamic_cells, seen.dynamic_cleared_cells), (2, 1));
        // Without the observability truth, every covered cell counts, the ghost nobody could clear included.
        let all = tally(&verdicts, &[], swept, None);
        assert_eq!((all.num_dynamic_cells, all.dynamic_cleared_cells), (3, 1));
    }

    #[test]
    fn without_actors_no_cell_is_dynamic_and_every_observable_blocked_cell_counts_for_sa() {
        use crate::judge::verdict::{TruthClass, Verdict, Verdicts};
        let g = GridGeometry::new(0.05).expect("grid");
        let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(3, 0)).expect("region");
        // Three truly blocked cells, the map kept two (one as uncertain); the third no ray could tell about.
        // A drivable cell beside them.
        let verdicts = Verdicts {
            window: GridWindow::new(g, region),
            truth: vec![
                TruthClass::Step,
                TruthClass::Step,
                TruthClass::Step,
                TruthClass::Drivable,
            ],
            verdict: vec![
                Verdict::RightBlocked,
                Verdict::Uncertain,
                Verdict::Unsafe,
                Verdict::RightDrivable,
            ],
            mapped: vec![
                Traversability::Blocked,
                Traversability::Uncertain,
                Traversability::Traversable,
                Traversability::Traversable,
            ],
            unobservable: vec![false, false, true, false],
            reached: None,
        };
        // No actor: no raster of times (what `count` passes for a scene without actors).
        let c = tally(&verdicts, &[], None, None);
        assert_eq!((c.num_static_cells, c.static_kept_cells), (2, 2));
        assert_eq!((c.num_dynamic_cells, c.dynamic_cleared_cells), (0, 0));
        assert_eq!(c.associated_accuracy(), None);
    }

    #[test]
    fn aa_is_the_geometric_mean_and_undefined_without_dynamic_cells() {
        let c = GhostCounts {
            num_static_cells: 100,
            static_kept_cells: 90,
            num_dynamic_cells: 10,
            dynamic_cleared_cells: 10,
        };
        assert_eq!(c.static_accuracy(), Some(0.9));
        assert_eq!(c.dynamic_accuracy(), Some(1.0));
        assert!((c.associated_accuracy().expect("aa") - 0.9_f64.sqrt()).abs() < 1e-12);
        let none = GhostCounts {
            num_dynamic_cells: 0,
            dynamic_cleared_cells: 0,
            ..c
        };
        assert_eq!(none.dynamic_accuracy(), None);
        assert_eq!(none.associated_accuracy(), None);
    }
}
