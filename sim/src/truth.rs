//! Ground truth on the map's grid, computed from the world alone (no map code): for every cell, the true
//! elevation, the ground, the step decision, and for cells under a structure the clearance decision.
//!
//! Per cell, `n x n` sample points (default 4 x 4) at the centres of the cell's sub-squares:
//! 1. the ground `g`: a vertical ray against the terrain only;
//! 2. the top surface: a ray down from `g + robot height`, everything but the robot; a start inside a solid
//!    counts as a surface at the start height. Structures above the robot's height are therefore not seen,
//!    and a board lower than the robot is;
//! 3. a structure overhead: a ray up from 1 mm above the ground; a hit at a gap `d` higher than a step is a
//!    structure whose underside is `d` above the ground (a start inside a solid, or a gap a wheel could not
//!    even enter, is a step obstacle, not a structure).
//!
//! The cell's elevation is the highest top surface, its step the largest `top - g`: blocked when it exceeds the
//! robot's `max_step_m` (the step measured against the ground beside it, so a slope alone never blocks). A
//! cell is under a structure when any sample finds one within [`STRUCTURE_SEARCH_M`]; it is passable under it
//! when the smallest gap is at least the robot's height.

use nalgebra::{Point3, Vector3};
use oeg::{CellIndex, CellRegion, GridGeometry};
use rayon::prelude::*;

use crate::world::{Actors, RayStart, World};

/// How far above the ground a structure is looked for, metres.
pub const STRUCTURE_SEARCH_M: f64 = 3.0;
/// Default sample points per cell side.
pub const DEFAULT_SAMPLES_PER_SIDE: u32 = 4;

/// The robot as the truth sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthProfile {
    /// Largest step the robot climbs, metres.
    pub max_step_m: f64,
    /// Robot height, metres.
    pub height_m: f64,
}

/// What a cell's step is measured against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StepReference {
    /// The ground under the cell: a ramp on flat ground is a step as high as the ramp (pairs with the map's
    /// absolute rule).
    #[default]
    Ground,
    /// The lowest surface among the cell and its 8 neighbours: a ramp or a slope is drivable, a curb's edge is
    /// not (pairs with the map's terrain rule).
    Neighbours,
}

/// One cell's truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellTruth {
    /// Highest surface below the robot's height, world z, metres (NaN off the terrain).
    pub elevation_m: f32,
    /// Mean ground height, world z, metres.
    pub ground_m: f32,
    /// Largest height of a surface above the ground beside it, metres.
    pub step_m: f32,
    /// Whether the robot cannot drive over the cell.
    pub step_blocked: bool,
    /// Smallest free gap under a structure over the cell, metres; NaN when there is none.
    pub structure_gap_m: f32,
}

impl CellTruth {
    /// `Some(passable)` for a cell under a structure, `None` otherwise.
    pub fn clearance_passable(&self, profile: &TruthProfile) -> Option<bool> {
        (!self.structure_gap_m.is_nan()).then(|| f64::from(self.structure_gap_m) >= profile.height_m)
    }
}

/// The truth over a region of the map's grid, row-major from its min-x, min-y cell (as `oeg` rasters).
#[derive(Debug, Clone, PartialEq)]
pub struct TruthRaster {
    /// The cells.
    pub region: CellRegion,
    /// Cell size, metres.
    pub resolution_m: f64,
    /// The robot used for the decisions.
    pub profile: TruthProfile,
    /// Simulated time of the truth.
    pub time_s: f64,
    /// Whether moving actors were part of it.
    pub actors: Actors,
    /// One entry per cell.
    pub cells: Vec<CellTruth>,
}

impl TruthRaster {
    /// Computes the truth over `region` at the world's current time.
    pub fn compute(
        world: &World,
        geometry: &GridGeometry,
        region: CellRegion,
        profile: TruthProfile,
        actors: Actors,
        samples_per_side: u32,
    ) -> Self {
        let n = samples_per_side.max(1);
        // Cells are independent: computed in parallel, collected in raster order (the same on any thread count).
        let cells = (0..region.num_cells() as usize)
            .into_par_iter()
            .map(|k| {
                let (u, v) = (
                    (k % region.num_x as usize) as u32,
                    (k / region.num_x as usize) as u32,
                );
                cell_truth(world, geometry, region.cell_at(u, v), &profile, actors, n)
            })
            .collect();
        Self {
            region,
            resolution_m: geometry.resolution_m(),
            profile,
            time_s: world.time_s(),
            actors,
            cells,
        }
    }

    /// Whether the cell at raster offset `k` is a step the robot cannot drive over, measured against
    /// `reference`. Cells off the terrain are not blocked.
    pub fn step_blocked(&self, k: usize, reference: StepReference) -> bool {
        let t = &self.cells[k];
        match reference {
            StepReference::Ground => t.step_blocked,
            StepReference::Neighbours => {
                if t.elevation_m.is_nan() {
                    return false;
                }
                let (nx, ny) = (self.region.num_x as i64, self.region.num_y as i64);
                let (u, v) = ((k as i64) % nx, (k as i64) / nx);
                let mut lowest = t.elevation_m;
                for dv in -1..=1 {
                    for du in -1..=1 {
                        let (a, b) = (u + du, v + dv);
                        if a >= 0 && b >= 0 && a < nx && b < ny {
                            let n = self.cells[(b * nx + a) as usize].elevation_m;
                            if n < lowest {
                                lowest = n;
                            }
                        }
                    }
                }
                f64::from(t.elevation_m - lowest) > self.profile.max_step_m
            }
        }
    }

    /// The truth of `cell`, if inside the region.
    pub fn get(&self, cell: CellIndex) -> Option<&CellTruth> {
        self.region.offset(cell).map(|k| &self.cells[k])
    }
}

fn cell_truth(
    world: &World,
    geometry: &GridGeometry,
    cell: CellIndex,
    profile: &TruthProfile,
    actors: Actors,
    n: u32,
) -> CellTruth {
    let (x0, y0) = geometry.cell_min_corner(cell);
    let r = geometry.resolution_m();
    let (mut top_max, mut step_max, mut ground_sum, mut num_ground) =
        (f64::NEG_INFINITY, f64::NEG_INFINITY, 0.0, 0u32);
    let mut gap_min = f64::INFINITY;
    for sj in 0..n {
        for si in 0..n {
            let x = x0 + (f64::from(si) + 0.5) / f64::from(n) * r;
            let y = y0 + (f64::from(sj) + 0.5) / f64::from(n) * r;
            let Some(g) = world.ground_z(x, y) else { continue };
            ground_sum += g;
            num_ground += 1;
            let start = Point3::new(x, y, g + profile.height_m);
            let top = world
                .cast_ray(
                    &start,
                    &-Vector3::z(),
                    profile.height_m + 0.01,
                    actors,
                    RayStart::InsideHits,
                )
                .map_or(g, |h| h.point_in_world.z.max(g));
            top_max = top_max.max(top);
            step_max = step_max.max(top - g);
            let up = Point3::new(x, y, g + 0.001);
            if let Some(h) = world.cast_ray(
                &up,
                &Vector3::z(),
                STRUCTURE_SEARCH_M,
                actors,
                RayStart::InsideHits,
            ) && h.distance_m > 0.0
            {
                gap_min = gap_min.min(h.distance_m + 0.001);
            }
        }
    }
    if num_ground == 0 {
        return CellTruth {
            elevation_m: f32::NAN,
            ground_m: f32::NAN,
            step_m: f32::NAN,
            step_blocked: false,
            structure_gap_m: f32::NAN,
        };
    }
    CellTruth {
        elevation_m: top_max as f32,
        ground_m: (ground_sum / f64::from(num_ground)) as f32,
        step_m: step_max as f32,
        step_blocked: step_max > profile.max_step_m,
        structure_gap_m: if gap_min.is_finite() {
            gap_min as f32
        } else {
            f32::NAN
        },
    }
}
