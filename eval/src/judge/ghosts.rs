//! Ghosts: how well a map forgets what moved and keeps what stands, with the measures of KTH's DynamicMap
//! benchmark (Zhang et al. 2023) adapted from points to cells.
//!
//! - **SA** (static accuracy): of the truly blocked cells the sensors could have told about (the observability
//!   truth) and no actor passed through, the fraction the map keeps blocked or uncertain: what a ghost
//!   remover must not remove.
//! - **DA** (dynamic accuracy): of the cells an actor's footprint covered at some time of the run, that are
//!   truly drivable and that no actor covers at its end, the fraction the map calls drivable at the end: the
//!   ghosts removed. A cell the map leaves uncertain only because the sensors measured it too coarsely to tell
//!   a step ([`oeg::Doubt::Imprecise`]: a stereo camera's ground a few metres away) says nothing about a
//!   ghost, and is left out.
//! - **AA** (associated accuracy): `sqrt(SA x DA)`.
//!
//! Both are over the scored cells (observed, on the terrain, not left unknown): a cell the map never observed
//! is neither kept nor removed. DynamicMap reports them in percent; on KITTI sequence 00 it gives OctoMap an AA
//! of 82.37 and DUFOMap 98.56.

use oeg::{CellIndex, Doubt, GridWindow, Traversability};
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

/// Per cell of `window`: whether an actor's footprint covered its centre at some time of `[0, end_s]`, and
/// whether one covers it at `end_s`. Each actor's path is followed in steps of at most half a cell.
pub(crate) fn actor_cells(actors: &[Actor], end_s: f64, window: &GridWindow) -> (Vec<bool>, Vec<bool>) {
    let n = window.num_cells() as usize;
    let (mut swept, mut at_end) = (vec![false; n], vec![false; n]);
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
                mark_disk(&mut swept, window, (x, y), radius);
            }
            if t >= t1 {
                break;
            }
            t = (t + step_s).min(t1);
        }
        if let Some((x, y)) = actor.position_at(end_s) {
            mark_disk(&mut at_end, window, (x, y), radius);
        }
    }
    (swept, at_end)
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

/// Marks the cells of `window` whose centre lies within `radius_m` of `(x, y)`.
fn mark_disk(cells: &mut [bool], window: &GridWindow, (x, y): (f64, f64), radius_m: f64) {
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
                cells[k] = true;
            }
        }
    }
}

/// SA and DA's counts for the map judged in `verdicts` (with its observability marks), the actors of `s`
/// over its whole duration; `doubts` says why the map left each cell undecided (empty: it does not say).
pub(crate) fn count(s: &Scenario, verdicts: &Verdicts, doubts: &[Option<Doubt>]) -> GhostCounts {
    let (swept, at_end) = actor_cells(&s.actors, s.duration_s, &verdicts.window);
    let mut c = GhostCounts::default();
    for k in 0..verdicts.verdict.len() {
        if verdicts.verdict[k] == Verdict::NotScored {
            continue;
        }
        let imprecise = doubts.get(k).copied().flatten() == Some(Doubt::Imprecise);
        let truth = verdicts.truth[k];
        let mapped = verdicts.mapped[k];
        if truth.is_blocked() && !swept[k] && !verdicts.unobservable[k] {
            c.num_static_cells += 1;
            c.static_kept_cells += u64::from(matches!(
                mapped,
                Traversability::Blocked | Traversability::Uncertain
            ));
        } else if !truth.is_blocked() && swept[k] && !at_end[k] && !imprecise {
            c.num_dynamic_cells += 1;
            c.dynamic_cleared_cells += u64::from(mapped.is_drivable());
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
        let (swept, at_end) = actor_cells(&[walker], 10.0, &GridWindow::new(g, region));
        assert!(at_end.iter().all(|c| !c));
        let at = |x: f64, y: f64| swept[region.offset(g.cell_of(x, y).expect("cell")).expect("inside")];
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
