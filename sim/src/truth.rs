//! Ground truth on the map's grid, computed from the world alone (no map code): for every cell, the true
//! surface, the ground, the step and, for cells under a structure, the clearance. One physical definition,
//! the same whatever rule a map uses:
//!
//! * the **surface** at a point is the highest solid below the robot's height above the ground there: the
//!   terrain or an obstacle, whichever is higher (a structure above the robot is not seen; a board lower than
//!   the robot is);
//! * a **step** is a rise of the surface of more than `max_step_m` between two points closer than the
//!   robot's contact distance, `max_step_m / max_grade` (0.10 m for the Pioneer 3-AT:
//!   [`oeg::RobotProfile::contact_distance_m`]). A slope the robot climbs rises less than that over the contact
//!   distance, so it is never a step; a slope steeper than `max_grade` is one. The higher point of such a pair
//!   is where the robot cannot go;
//! * a **structure** over a point is a solid above a free gap higher than a step; the robot passes under it
//!   when the gap is at least its height.
//!
//! The surface is sampled at `n x n` points per cell (default 4 x 4, the centres of the cell's sub-squares),
//! on a lattice that reaches one contact distance beyond the region so that edge cells see their neighbours.
//! Per sample point:
//! 1. the ground `g`: a vertical ray against the terrain only;
//! 2. the surface: a ray down from `g + robot height`, everything but the robot; a start inside a solid counts
//!    as a surface at the start height;
//! 3. a structure overhead: a ray up from 1 mm above the ground; a hit at a gap `d` higher than a step is a
//!    structure whose underside is `d` above the ground.
//!
//! A cell's elevation is its highest surface sample, its step the largest rise of one of its samples over the
//! lowest surface within the contact distance, and it is under a structure when any sample finds one within
//! [`STRUCTURE_SEARCH_M`] (passable when the smallest gap is at least the robot's height).

use nalgebra::{Point3, Vector3};
use oeg::{CellIndex, CellRegion, GridGeometry, RobotProfile};
use rayon::prelude::*;

use crate::world::{Actors, RayStart, World};

/// How far above the ground a structure is looked for, metres.
pub const STRUCTURE_SEARCH_M: f64 = 3.0;
/// Default sample points per cell side.
pub const DEFAULT_SAMPLES_PER_SIDE: u32 = 4;

/// One cell's truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellTruth {
    /// Highest surface below the robot's height, world z, metres (NaN off the terrain).
    pub elevation_m: f32,
    /// Mean ground height, world z, metres.
    pub ground_m: f32,
    /// Largest rise of the cell's surface over the lowest surface within the contact distance, metres.
    pub step_m: f32,
    /// Whether that rise is a step the robot cannot climb (`step_m > max_step_m`).
    pub step_blocked: bool,
    /// Smallest free gap under a structure over the cell, metres; NaN when there is none.
    pub structure_gap_m: f32,
}

impl CellTruth {
    /// `Some(passable)` for a cell under a structure, `None` otherwise.
    pub fn clearance_passable(&self, profile: &RobotProfile) -> Option<bool> {
        (!self.structure_gap_m.is_nan()).then_some(self.structure_gap_m >= profile.height_m)
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
    pub profile: RobotProfile,
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
        profile: RobotProfile,
        actors: Actors,
        samples_per_side: u32,
    ) -> Self {
        let n = samples_per_side.max(1) as usize;
        let lattice = SampleLattice::new(geometry, region, n, f64::from(profile.contact_distance_m()));
        // Samples and cells are independent: computed in parallel, collected in order (the same on any thread
        // count).
        let samples: Vec<Sample> = (0..lattice.len())
            .into_par_iter()
            .map(|k| {
                let (x, y) = lattice.point(k);
                sample(world, x, y, &profile, actors)
            })
            .collect();
        let rises = lattice.rises(&samples);
        let cells = (0..region.num_cells() as usize)
            .into_par_iter()
            .map(|k| lattice.cell_truth(k, &samples, &rises, &profile))
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

    /// Whether the robot truly cannot enter the cell at raster offset `k`: a step it cannot climb, or a
    /// structure over it lower than the robot. Cells off the terrain are not blocked. This is the one
    /// definition of "truly blocked"; every metric, file and image reads it (through `oeg_eval::judge::verdict`).
    pub fn truly_blocked(&self, k: usize) -> bool {
        let t = &self.cells[k];
        t.step_blocked || t.clearance_passable(&self.profile) == Some(false)
    }

    /// The truth of `cell`, if inside the region.
    pub fn get(&self, cell: CellIndex) -> Option<&CellTruth> {
        self.region.offset(cell).map(|k| &self.cells[k])
    }
}

/// What the world holds above one point.
#[derive(Debug, Clone, Copy)]
struct Sample {
    /// Ground height, or NaN off the terrain.
    ground_m: f64,
    /// Surface height (NaN off the terrain).
    surface_m: f64,
    /// Free gap under a structure, +inf when there is none.
    gap_m: f64,
}

fn sample(world: &World, x: f64, y: f64, profile: &RobotProfile, actors: Actors) -> Sample {
    let height = f64::from(profile.height_m);
    let Some(g) = world.ground_z(x, y) else {
        return Sample {
            ground_m: f64::NAN,
            surface_m: f64::NAN,
            gap_m: f64::INFINITY,
        };
    };
    let start = Point3::new(x, y, g + height);
    let surface = world
        .cast_ray(
            &start,
            &-Vector3::z(),
            height + 0.01,
            actors,
            RayStart::InsideHits,
        )
        .map_or(g, |h| h.point_in_world.z.max(g));
    let up = Point3::new(x, y, g + 0.001);
    let gap = match world.cast_ray(
        &up,
        &Vector3::z(),
        STRUCTURE_SEARCH_M,
        actors,
        RayStart::InsideHits,
    ) {
        Some(h) if h.distance_m > 0.0 => h.distance_m + 0.001,
        _ => f64::INFINITY,
    };
    Sample {
        ground_m: g,
        surface_m: surface,
        gap_m: gap,
    }
}

/// The sample points: `n` per cell side over the region, plus a margin of one contact distance.
struct SampleLattice {
    region: CellRegion,
    n: usize,
    /// Margin, in samples, on every side.
    margin: usize,
    /// Samples per lattice row and column.
    nx: usize,
    ny: usize,
    /// World position of sample (0, 0) and the spacing, metres.
    x0_m: f64,
    y0_m: f64,
    spacing_m: f64,
    /// Offsets `(du, dv)` of the samples within the contact distance of a sample.
    disc: Vec<(isize, isize)>,
}

impl SampleLattice {
    fn new(geometry: &GridGeometry, region: CellRegion, n: usize, contact_m: f64) -> Self {
        let spacing_m = geometry.resolution_m() / n as f64;
        let reach = contact_m / spacing_m + 1e-9;
        let margin = reach.floor() as usize;
        let (cx, cy) = geometry.cell_min_corner(region.min);
        let disc = (-(margin as isize)..=margin as isize)
            .flat_map(|dv| (-(margin as isize)..=margin as isize).map(move |du| (du, dv)))
            .filter(|(du, dv)| ((du * du + dv * dv) as f64) <= reach * reach)
            .collect();
        Self {
            region,
            n,
            margin,
            nx: region.num_x as usize * n + 2 * margin,
            ny: region.num_y as usize * n + 2 * margin,
            x0_m: cx + (0.5 - margin as f64) * spacing_m,
            y0_m: cy + (0.5 - margin as f64) * spacing_m,
            spacing_m,
            disc,
        }
    }

    fn len(&self) -> usize {
        self.nx * self.ny
    }

    fn point(&self, k: usize) -> (f64, f64) {
        let (u, v) = (k % self.nx, k / self.nx);
        (
            self.x0_m + u as f64 * self.spacing_m,
            self.y0_m + v as f64 * self.spacing_m,
        )
    }

    /// For every sample, the rise of its surface over the lowest surface within the contact distance (NaN off
    /// the terrain).
    fn rises(&self, samples: &[Sample]) -> Vec<f64> {
        (0..samples.len())
            .into_par_iter()
            .map(|k| {
                let here = samples[k].surface_m;
                if here.is_nan() {
                    return f64::NAN;
                }
                let (u, v) = ((k % self.nx) as isize, (k / self.nx) as isize);
                let mut lowest = here;
                for &(du, dv) in &self.disc {
                    let (a, b) = (u + du, v + dv);
                    if a < 0 || b < 0 || a >= self.nx as isize || b >= self.ny as isize {
                        continue;
                    }
                    let s = samples[b as usize * self.nx + a as usize].surface_m;
                    if s < lowest {
                        lowest = s;
                    }
                }
                here - lowest
            })
            .collect()
    }

    /// The truth of the region's cell at raster offset `k` from its samples.
    fn cell_truth(&self, k: usize, samples: &[Sample], rises: &[f64], profile: &RobotProfile) -> CellTruth {
        let num_x = self.region.num_x as usize;
        let (cu, cv) = (k % num_x, k / num_x);
        let (mut top, mut rise, mut ground_sum, mut num_ground) =
            (f64::NEG_INFINITY, f64::NEG_INFINITY, 0.0, 0u32);
        let mut gap = f64::INFINITY;
        for sv in 0..self.n {
            for su in 0..self.n {
                let (u, v) = (self.margin + cu * self.n + su, self.margin + cv * self.n + sv);
                let i = v * self.nx + u;
                let s = samples[i];
                if s.ground_m.is_nan() {
                    continue;
                }
                ground_sum += s.ground_m;
                num_ground += 1;
                top = top.max(s.surface_m);
                rise = rise.max(rises[i]);
                gap = gap.min(s.gap_m);
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
            elevation_m: top as f32,
            ground_m: (ground_sum / f64::from(num_ground)) as f32,
            step_m: rise as f32,
            step_blocked: rise > f64::from(profile.max_step_m),
            structure_gap_m: if gap.is_finite() { gap as f32 } else { f32::NAN },
        }
    }
}
