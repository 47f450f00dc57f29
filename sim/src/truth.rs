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
use oeg::{CellIndex, CellRegion, GridGeometry, GridWindow, RobotProfile};
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
    /// The cells, on the map's grid.
    pub window: GridWindow,
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
    /// Computes the truth over `window` at the world's current time.
    ///
    /// The work goes in bands of cell rows, so memory stays within [`TruthCost::peak_bytes`] whatever the
    /// region; `keep_going` is asked before every band and the computation stops with [`TruthCancelled`] when it
    /// answers `false`.
    ///
    /// # Errors
    /// [`TruthCancelled`] when `keep_going` said stop.
    pub fn compute(
        world: &World,
        window: &GridWindow,
        profile: RobotProfile,
        actors: Actors,
        samples_per_side: u32,
        keep_going: &dyn Fn() -> bool,
    ) -> Result<Self, TruthCancelled> {
        let (geometry, region) = (window.geometry(), *window.region());
        let n = samples_per_side.max(1) as usize;
        let lattice = SampleLattice::new(geometry, region, n, f64::from(profile.contact_distance_m()));
        let mut cells = Vec::with_capacity(region.num_cells() as usize);
        let mut band = Band::default();
        let num_rows = region.num_y as usize;
        let rows_per_band = lattice.cell_rows_per_band();
        let mut first_row = 0;
        while first_row < num_rows {
            if !keep_going() {
                return Err(TruthCancelled);
            }
            let end_row = (first_row + rows_per_band).min(num_rows);
            band.advance(&lattice, first_row, end_row, |x, y| {
                sample(world, x, y, &profile, actors)
            });
            let rises = lattice.rises(&band);
            let num_x = region.num_x as usize;
            cells.par_extend(
                (0..(end_row - first_row) * num_x)
                    .into_par_iter()
                    .map(|k| lattice.cell_truth(k % num_x, k / num_x, &band, &rises, &profile)),
            );
            first_row = end_row;
        }
        Ok(Self {
            window: *window,
            profile,
            time_s: world.time_s(),
            actors,
            cells,
        })
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
        self.window.region().offset(cell).map(|k| &self.cells[k])
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

/// The truth was stopped before it was complete: the caller's `keep_going` said stop.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the truth was cancelled")]
pub struct TruthCancelled;

/// Samples held at once while the truth is computed (a band of sample rows), at most: about 24 MiB of samples,
/// plus the band's rises. A band holds at least one row of cells and its margin.
const BAND_SAMPLES: usize = 1 << 20;

/// What computing a truth costs, known before it starts (from the region's size, the resolution, the samples per
/// cell and the robot's contact distance), so that a scenario can be refused before the work begins.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TruthCost {
    /// Sample points, each three ray casts.
    pub samples: u64,
    /// Steps of the running minimum that finds each sample's lowest neighbour: about three per sample and row of
    /// the contact disc.
    pub filter_steps: u64,
    /// Memory the computation holds at its peak, bytes: one band of samples and rises, and the result.
    pub peak_bytes: u64,
}

impl TruthCost {
    /// The cost of a truth over `num_x` x `num_y` cells of `resolution_m`, with `samples_per_side` samples per
    /// cell side and a contact distance of `contact_m`.
    pub fn estimate(
        num_x: u64,
        num_y: u64,
        resolution_m: f64,
        samples_per_side: u32,
        contact_m: f64,
    ) -> Self {
        let n = u64::from(samples_per_side.max(1));
        let margin = margin_of(resolution_m / n as f64, contact_m) as u64;
        let nx = num_x.saturating_mul(n).saturating_add(2 * margin);
        let ny = num_y.saturating_mul(n).saturating_add(2 * margin);
        let samples = nx.saturating_mul(ny);
        let scored = num_x.saturating_mul(num_y).saturating_mul(n * n);
        let filter_steps = scored.saturating_mul(3).saturating_mul(2 * margin + 1);
        let band_rows =
            (cell_rows_per_band(nx as usize, n as usize, margin as usize) as u64).min(num_y.max(1));
        let band = nx.saturating_mul(band_rows * n + 2 * margin);
        let per_cell = size_of::<CellTruth>() as u64;
        let peak_bytes = band
            .saturating_mul(size_of::<Sample>() as u64 + 2 * 8)
            .saturating_add(num_x.saturating_mul(num_y).saturating_mul(per_cell));
        Self {
            samples,
            filter_steps,
            peak_bytes,
        }
    }
}

/// Samples within the contact distance, on one side, at `spacing_m` between samples.
fn margin_of(spacing_m: f64, contact_m: f64) -> usize {
    (contact_m / spacing_m + 1e-9).floor() as usize
}

/// Cell rows computed at once, so that a band of `nx` samples per row holds about [`BAND_SAMPLES`], and at
/// least one cell row.
fn cell_rows_per_band(nx: usize, n: usize, margin: usize) -> usize {
    ((BAND_SAMPLES / nx.max(1)).saturating_sub(2 * margin) / n.max(1)).max(1)
}

/// The sample points: `n` per cell side over the region, plus a margin of one contact distance.
struct SampleLattice {
    n: usize,
    /// Margin, in samples, on every side.
    margin: usize,
    /// Samples per lattice row.
    nx: usize,
    /// World position of sample (0, 0) and the spacing, metres.
    x0_m: f64,
    y0_m: f64,
    spacing_m: f64,
    /// For each row offset `|dv|` of the contact disc, the largest column offset `|du|` inside it: the disc as
    /// rows of samples, each row one window of the running minimum.
    half_widths: Vec<usize>,
}

/// A band of consecutive sample rows of the lattice, `first_row..` on.
#[derive(Default)]
struct Band {
    first_row: usize,
    samples: Vec<Sample>,
}

impl Band {
    /// Moves the band to the sample rows that cell rows `first..end` need (their samples and one margin above
    /// and below), keeping the rows it already holds and sampling the rest with `sample(x, y)`.
    fn advance(
        &mut self,
        lattice: &SampleLattice,
        first: usize,
        end: usize,
        sample: impl Fn(f64, f64) -> Sample + Sync,
    ) {
        let nx = lattice.nx;
        let (from, to) = (first * lattice.n, end * lattice.n + 2 * lattice.margin);
        let held_end = self.first_row + self.samples.len() / nx;
        let keep_from = from.clamp(self.first_row, held_end);
        self.samples.drain(..(keep_from - self.first_row) * nx);
        self.first_row = from;
        let start = from.max(held_end);
        self.samples
            .par_extend((start * nx..to * nx).into_par_iter().map(|k| {
                let (x, y) = lattice.point(k);
                sample(x, y)
            }));
    }
}

impl SampleLattice {
    fn new(geometry: &GridGeometry, region: CellRegion, n: usize, contact_m: f64) -> Self {
        let spacing_m = geometry.resolution_m() / n as f64;
        let reach = contact_m / spacing_m + 1e-9;
        let margin = margin_of(spacing_m, contact_m);
        let (cx, cy) = geometry.cell_min_corner(region.min);
        // The same disc as `du^2 + dv^2 <= reach^2`, row by row.
        let half_widths = (0..=margin)
            .map(|dv| {
                (0..=margin)
                    .take_while(|du| ((du * du + dv * dv) as f64) <= reach * reach)
                    .last()
                    .unwrap_or(0)
            })
            .collect();
        Self {
            n,
            margin,
            nx: region.num_x as usize * n + 2 * margin,
            x0_m: cx + (0.5 - margin as f64) * spacing_m,
            y0_m: cy + (0.5 - margin as f64) * spacing_m,
            spacing_m,
            half_widths,
        }
    }

    fn cell_rows_per_band(&self) -> usize {
        cell_rows_per_band(self.nx, self.n, self.margin)
    }

    fn point(&self, k: usize) -> (f64, f64) {
        let (u, v) = (k % self.nx, k / self.nx);
        (
            self.x0_m + u as f64 * self.spacing_m,
            self.y0_m + v as f64 * self.spacing_m,
        )
    }

    /// For every sample of the band's cell rows (band rows `margin..len - margin`), the rise of its surface over
    /// the lowest surface within the contact distance (NaN off the terrain). The lowest surface is a running
    /// minimum along each row of the contact disc (van Herk / Gil-Werman: three steps a sample whatever the
    /// window), so a sample costs one pass per disc row, not one look per disc sample.
    fn rises(&self, band: &Band) -> Vec<f64> {
        let nx = self.nx;
        let m = self.margin;
        let rows = band.samples.len() / nx;
        // Off the terrain is no surface: never the lowest.
        let lows: Vec<f64> = band
            .samples
            .iter()
            .map(|s| {
                if s.surface_m.is_nan() {
                    f64::INFINITY
                } else {
                    s.surface_m
                }
            })
            .collect();
        let mut rises = vec![0.0; (rows - 2 * m) * nx];
        rises.par_chunks_mut(nx).enumerate().for_each_init(
            || RunningMin::new(nx + 2 * m),
            |window, (r, out)| {
                let centre = r + m;
                out.fill(f64::INFINITY);
                for dv in 0..=2 * m {
                    let w = self.half_widths[dv.abs_diff(m)];
                    let row = centre + dv - m;
                    window.fold_into(&lows[row * nx..(row + 1) * nx], w, out);
                }
                for (u, rise) in out.iter_mut().enumerate() {
                    let here = band.samples[centre * nx + u].surface_m;
                    *rise = if here.is_nan() { f64::NAN } else { here - *rise };
                }
            },
        );
        rises
    }

    /// The truth of the cell in column `cu` and band cell row `cv` from its samples.
    fn cell_truth(
        &self,
        cu: usize,
        cv: usize,
        band: &Band,
        rises: &[f64],
        profile: &RobotProfile,
    ) -> CellTruth {
        let (mut top, mut rise, mut ground_sum, mut num_ground) =
            (f64::NEG_INFINITY, f64::NEG_INFINITY, 0.0, 0u32);
        let mut gap = f64::INFINITY;
        for sv in 0..self.n {
            for su in 0..self.n {
                let (u, v) = (self.margin + cu * self.n + su, cv * self.n + sv);
                let s = band.samples[(v + self.margin) * self.nx + u];
                if s.ground_m.is_nan() {
                    continue;
                }
                ground_sum += s.ground_m;
                num_ground += 1;
                top = top.max(s.surface_m);
                rise = rise.max(rises[v * self.nx + u]);
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

/// The scratch of a running minimum over windows of `2 w + 1` values (van Herk / Gil-Werman): the minima from
/// each block's start and to each block's end, over the row padded with `w` infinities on each side.
struct RunningMin {
    from_start: Vec<f64>,
    to_end: Vec<f64>,
}

impl RunningMin {
    fn new(capacity: usize) -> Self {
        Self {
            from_start: Vec::with_capacity(capacity),
            to_end: Vec::with_capacity(capacity),
        }
    }

    /// `out[u] = min(out[u], least of row[u - w ..= u + w])`, the window cut at the row's ends.
    fn fold_into(&mut self, row: &[f64], w: usize, out: &mut [f64]) {
        if w == 0 {
            for (o, &x) in out.iter_mut().zip(row) {
                *o = o.min(x);
            }
            return;
        }
        let k = 2 * w + 1;
        let len = row.len() + 2 * w;
        let padded = |i: usize| {
            if i < w || i >= w + row.len() {
                f64::INFINITY
            } else {
                row[i - w]
            }
        };
        self.from_start.clear();
        self.from_start.extend((0..len).map(&padded));
        for i in 1..len {
            if i % k != 0 {
                self.from_start[i] = self.from_start[i].min(self.from_start[i - 1]);
            }
        }
        self.to_end.clear();
        self.to_end.extend((0..len).map(padded));
        for i in (0..len - 1).rev() {
            if (i + 1) % k != 0 {
                self.to_end[i] = self.to_end[i].min(self.to_end[i + 1]);
            }
        }
        for (u, o) in out.iter_mut().enumerate() {
            *o = o.min(self.to_end[u]).min(self.from_start[u + 2 * w]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The least of `row[u - w ..= u + w]` by looking at every value.
    fn brute(row: &[f64], w: usize) -> Vec<f64> {
        (0..row.len())
            .map(|u| {
                row[u.saturating_sub(w)..=(u + w).min(row.len() - 1)]
                    .iter()
                    .fold(f64::INFINITY, |a, &b| a.min(b))
            })
            .collect()
    }

    #[test]
    fn running_min_equals_the_least_value_of_every_window() {
        // A fixed pseudo-random row with repeats, infinities and both signs.
        let mut state = 12345u64;
        let row: Vec<f64> = (0..97)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                match state >> 60 {
                    0 => f64::INFINITY,
                    v => (v as f64 - 8.0) * 0.01 + (state >> 40 & 0xff) as f64 * 1e-4,
                }
            })
            .collect();
        let mut window = RunningMin::new(0);
        for w in [0, 1, 2, 3, 7, 30, 96, 200] {
            let mut out = vec![f64::INFINITY; row.len()];
            window.fold_into(&row, w, &mut out);
            assert_eq!(out, brute(&row, w), "half-width {w}");
        }
    }

    #[test]
    fn the_disc_rows_are_the_disc() {
        let geometry = GridGeometry::new(0.01).expect("resolution");
        let region = geometry
            .region_covering((0.0, 0.0), (0.05, 0.05))
            .expect("region");
        let lattice = SampleLattice::new(&geometry, region, 4, 0.1);
        let reach = 0.1 / 0.0025 + 1e-9;
        assert_eq!(lattice.margin, 40);
        for (dv, &w) in lattice.half_widths.iter().enumerate() {
            for du in 0..=lattice.margin {
                let inside = ((du * du + dv * dv) as f64) <= reach * reach;
                assert_eq!(inside, du <= w, "du {du}, dv {dv}");
            }
        }
    }
}
