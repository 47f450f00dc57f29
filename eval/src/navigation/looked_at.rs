//! The navigator's memory of what it went to look at: the uncertain cells that came within its decision distance
//! and stayed uncertain. The planner plans optimistically through cells the map cannot decide beyond that
//! distance, so that the robot drives closer and looks again; once it has, a cell it still cannot decide is
//! decided as the near rule says, for every later plan, not only while the robot stands near it. Without that,
//! two ways each closed by the cells in front of the robot open again as soon as it turns to the other, and the
//! robot swings between them until its time runs out. The memory is the navigator's transient state: a cell the
//! map decides is the map's again, and a recovery clears it all (nav2's `ClearEntireCostmap`).

use oeg::{CellIndex, CellRegion, PlannerOptions, Traversability, UncertainCells};

/// The cells looked at, row-major over the planning region.
#[derive(Debug, Clone)]
pub(super) struct LookedAt {
    cells: Vec<bool>,
}

impl LookedAt {
    /// Nothing looked at yet, over a region of `num_cells`.
    pub(super) fn new(num_cells: usize) -> Self {
        Self {
            cells: vec![false; num_cells],
        }
    }

    /// Remembers the uncertain cells within the decision distance of `from` (the planner's
    /// [`PlannerOptions::optimistic_beyond_m`], measured between cell centres as the planner measures it), and
    /// returns the decisions to plan on: every remembered cell that is still uncertain decided as a near one
    /// (`Blocked` when uncertain cells are obstacles; under [`UncertainCells::Drivable`] a near uncertain cell is
    /// drivable, as a far one is, and nothing changes).
    pub(super) fn decide(
        &mut self,
        region: &CellRegion,
        resolution_m: f64,
        decisions: &[Traversability],
        from: CellIndex,
        options: &PlannerOptions,
    ) -> Vec<Traversability> {
        let mut decided = decisions.to_vec();
        let Some(within_m) = options.optimistic_beyond_m else {
            return decided;
        };
        if options.uncertain == UncertainCells::Drivable || self.cells.len() != decisions.len() {
            return decided;
        }
        let within = within_m / resolution_m;
        let nx = region.num_x as usize;
        for (k, (d, seen)) in decided.iter_mut().zip(&mut self.cells).enumerate() {
            if *d != Traversability::Uncertain {
                continue;
            }
            let c = region.cell_at((k % nx) as u32, (k / nx) as u32);
            let (di, dj) = (f64::from(c.i - from.i), f64::from(c.j - from.j));
            *seen |= di * di + dj * dj <= within * within;
            if *seen {
                *d = Traversability::Blocked;
            }
        }
        decided
    }

    /// Forgets every cell (a recovery: the robot looks again from where it stands).
    pub(super) fn clear(&mut self) {
        self.cells.fill(false);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cell_seen_uncertain_from_near_stays_decided_until_the_map_decides_it_or_a_recovery() {
        // A 20 x 1 row of 0.1 m cells, uncertain at i = 5 and i = 15; the decision distance 0.3 m.
        let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(19, 0)).expect("region");
        let mut d = vec![Traversability::Free; 20];
        d[5] = Traversability::Uncertain;
        d[15] = Traversability::Uncertain;
        let options = PlannerOptions {
            optimistic_beyond_m: Some(0.3),
            ..PlannerOptions::default()
        };
        let mut looked = LookedAt::new(20);
        // From i = 0 neither is near: nothing changes.
        assert_eq!(looked.decide(&region, 0.1, &d, CellIndex::new(0, 0), &options), d);
        // From i = 3 the first is 0.2 m away: decided blocked.
        let near = looked.decide(&region, 0.1, &d, CellIndex::new(3, 0), &options);
        assert_eq!(
            (near[5], near[15]),
            (Traversability::Blocked, Traversability::Uncertain)
        );
        // From the far end it stays decided, and the other one is decided once near.
        let far = looked.decide(&region, 0.1, &d, CellIndex::new(17, 0), &options);
        assert_eq!(
            (far[5], far[15]),
            (Traversability::Blocked, Traversability::Blocked)
        );
        // The map decides the first: its decision stands.
        d[5] = Traversability::Traversable;
        let mapped = looked.decide(&region, 0.1, &d, CellIndex::new(17, 0), &options);
        assert_eq!(mapped[5], Traversability::Traversable);
        // A recovery forgets: from i = 0 both are far again.
        d[5] = Traversability::Uncertain;
        looked.clear();
        assert_eq!(looked.decide(&region, 0.1, &d, CellIndex::new(0, 0), &options), d);
        // Uncertain cells the planner drives on are never decided blocked.
        let drivable = PlannerOptions {
            uncertain: UncertainCells::Drivable,
            ..options
        };
        assert_eq!(
            looked.decide(&region, 0.1, &d, CellIndex::new(5, 0), &drivable),
            d
        );
    }
}
