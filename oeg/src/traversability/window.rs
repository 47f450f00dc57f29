//! The windows of cells a decision reads around a cell: its 3 x 3 neighbourhood, the cells within a distance
//! (the robot's contact distance, its half width), and the levels found there (the ground a wheel comes from,
//! the top beside a cell with no height).

use crate::geometry::CellIndex;
use crate::map::Map;
use crate::model::{Elevation, Level, surface_level};
use crate::storage::{TileIndex, offset_in_tile};

impl Map {
    /// Whether a cell within `distance_m` of a point of `cell` was never observed. The window mostly lies in
    /// one tile, which is then looked up once rather than once a cell.
    pub(super) fn unobserved_within(&self, cell: CellIndex, distance_m: f32) -> bool {
        let r = self.reach_cells(distance_m).floor() as i32 + 1;
        let corner = |d: i32| CellIndex::new(cell.i.saturating_add(d), cell.j.saturating_add(d));
        let tile = TileIndex::of(corner(-r));
        if TileIndex::of(corner(r)) != tile {
            return self
                .cells_within(cell, distance_m)
                .any(|(_, c)| !self.cell(c).is_observed());
        }
        let Some(cells) = self.cells.tile(tile) else {
            return true;
        };
        self.cells_within(cell, distance_m)
            .any(|(_, c)| !cells[offset_in_tile(c)].is_observed())
    }

    /// Whether a cell within `distance_m` of a point of `cell` (itself included) holds a height estimate.
    pub(super) fn has_estimate_within(&self, cell: CellIndex, distance_m: f32) -> bool {
        self.cells_within(cell, distance_m)
            .any(|(_, c)| self.cell(c).elevation().is_some())
    }

    /// The 3 x 3 cells centred on `cell`, itself included.
    pub(super) fn neighbourhood(&self, cell: CellIndex) -> impl Iterator<Item = CellIndex> {
        (-1..=1).flat_map(move |dj| {
            (-1..=1).map(move |di| CellIndex::new(cell.i.saturating_add(di), cell.j.saturating_add(dj)))
        })
    }

    /// The highest estimate in `cell`'s 3 x 3 neighbourhood (the first of equal ones).
    pub(super) fn highest_neighbour(&self, cell: CellIndex) -> Option<Elevation> {
        self.neighbourhood(cell)
            .filter_map(|n| self.cell(n).elevation())
            .fold(None, |h: Option<Elevation>, e| match h {
                Some(h) if h.mean_m >= e.mean_m => Some(h),
                _ => Some(e),
            })
    }

    /// The ground a wheel on `cell` would come from: the lowest level among the cells that hold a point within
    /// `distance_m` of a point of `cell` (the gap between the two squares, not their centres), the cell itself
    /// included. The level is every estimate that lies within `kappa` standard deviations (of the difference)
    /// of the lowest one, and its elevation is their inverse-variance weighted mean. The lowest single estimate
    /// would be biased: among the 45 cells within 0.10 m at 5 cm, noise puts the lowest about two standard
    /// deviations below the ground, and every flat cell would seem to rise by that much. `None` if no cell in
    /// reach has an estimate.
    pub fn ground_within(&self, cell: CellIndex, distance_m: f32, kappa: f32) -> Option<Elevation> {
        let [ground] = self.grounds_within(cell, [distance_m], kappa);
        ground
    }

    /// `distance_m` in cells, the largest gap [`Map::cells_within`] keeps (a hair over, so that a distance of a
    /// whole number of cells keeps its last ring despite rounding).
    pub(super) fn reach_cells(&self, distance_m: f32) -> f64 {
        f64::from(distance_m) / self.geometry().resolution_m() + 1e-9
    }

    /// The cells that hold a point within `distance_m` of a point of `cell` (the gap between the two squares,
    /// not their centres), `cell` included, with the square of that gap in cells, row by row.
    pub(super) fn cells_within(
        &self,
        cell: CellIndex,
        distance_m: f32,
    ) -> impl Iterator<Item = (f64, CellIndex)> {
        let reach = self.reach_cells(distance_m);
        let r = reach.floor() as i32 + 1;
        (-r..=r)
            .flat_map(move |dj| (-r..=r).map(move |di| (di, dj)))
            .filter_map(move |(di, dj)| {
                let (gi, gj) = (f64::from((di.abs() - 1).max(0)), f64::from((dj.abs() - 1).max(0)));
                let gap2 = gi * gi + gj * gj;
                (gap2 <= reach * reach).then(|| {
                    (
                        gap2,
                        CellIndex::new(cell.i.saturating_add(di), cell.j.saturating_add(dj)),
                    )
                })
            })
    }

    /// The top level within `distance_m` of `cell`, whose highest estimate is `highest`: every estimate there
    /// within `kappa` standard deviations (of the difference) of it, their inverse-variance weighted mean. The
    /// mirror of the ground level ([`Map::ground_within`]), for the same reason: the highest of many noisy
    /// estimates of level ground lies about two standard deviations above it, and would make level ground
    /// beside a cell with no height look like a step. A real step's top is a level of its own, and stays.
    pub(super) fn top_level(
        &self,
        cell: CellIndex,
        highest: Elevation,
        distance_m: f32,
        kappa: f32,
    ) -> Elevation {
        let mut level = WeightedMean::default();
        for (_, c) in self.cells_within(cell, distance_m) {
            let Some(e) = self.cell(c).elevation() else {
                continue;
            };
            if surface_level(highest, e.mean_m, e.var_m2, kappa) != Level::Below {
                level.add(e);
            }
        }
        level.elevation()
    }

    /// [`Map::ground_within`] for several distances at once, in one walk over the widest window: each
    /// distance's cells are visited in the same order as alone, so each ground is the same to the bit.
    pub fn grounds_within<const N: usize>(
        &self,
        cell: CellIndex,
        distances_m: [f32; N],
        kappa: f32,
    ) -> [Option<Elevation>; N] {
        let reach = distances_m.map(|d| self.reach_cells(d));
        let widest = distances_m.iter().fold(0.0_f32, |a, b| a.max(*b));
        // Every estimate in the widest window, with the square of its gap to `cell` in cells.
        let window = move || {
            self.cells_within(cell, widest)
                .filter_map(move |(gap2, c)| Some((gap2, self.cell(c).elevation()?)))
        };
        let mut lowest: [Option<Elevation>; N] = [None; N];
        for (gap2, e) in window() {
            for (l, reach) in lowest.iter_mut().zip(&reach) {
                if gap2 <= reach * reach && l.is_none_or(|l| e.mean_m.total_cmp(&l.mean_m).is_lt()) {
                    *l = Some(e);
                }
            }
        }
        let mut sums = [WeightedMean::default(); N];
        for (gap2, e) in window() {
            for ((sum, reach), l) in sums.iter_mut().zip(&reach).zip(&lowest) {
                let Some(l) = *l else { continue };
                if gap2 > reach * reach || surface_level(l, e.mean_m, e.var_m2, kappa) == Level::Above {
                    continue;
                }
                sum.add(e);
            }
        }
        let mut out = [None; N];
        for ((o, l), sum) in out.iter_mut().zip(&lowest).zip(sums) {
            if l.is_some() {
                *o = Some(sum.elevation());
            }
        }
        out
    }
}

/// The inverse-variance weighted mean of elevation estimates: a level (the ground's, the top's) and its variance.
#[derive(Debug, Clone, Copy, Default)]
struct WeightedMean {
    sum_w: f64,
    sum_wz: f64,
}

impl WeightedMean {
    fn add(&mut self, e: Elevation) {
        let w = 1.0 / f64::from(e.var_m2.max(f32::MIN_POSITIVE));
        self.sum_w += w;
        self.sum_wz += w * f64::from(e.mean_m);
    }

    /// The mean and its variance, `1 / sum(1 / var)`.
    fn elevation(self) -> Elevation {
        Elevation {
            mean_m: (self.sum_wz / self.sum_w) as f32,
            var_m2: (1.0 / self.sum_w) as f32,
        }
    }
}
