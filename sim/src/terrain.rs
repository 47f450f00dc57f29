//! The ground as a grid of heights, built from the scenario's terrain settings.

use crate::scenario::heightmap::HeightmapError;
use rand::RngExt;

use crate::scenario::{Scenario, ScenarioSource, Terrain};
use crate::seed;

/// Extra ground around the map region, metres, so that sensors looking past the region's edge still see the
/// ground.
pub const TERRAIN_MARGIN_M: f64 = 20.0;

/// Heights on a regular grid: point `(i, j)` is at `origin + (i, j) * cell_m`, height `heights[j * num_x + i]`.
/// Between points the ground is the two triangles of each square (as Rapier's heightfield).
#[derive(Debug, Clone, PartialEq)]
pub struct HeightGrid {
    /// World position of point (0, 0), metres.
    pub origin_xy_m: [f64; 2],
    /// Spacing, metres.
    pub cell_m: f64,
    /// Points along x.
    pub num_x: usize,
    /// Points along y.
    pub num_y: usize,
    /// Heights, row-major from the min-x, min-y point, metres.
    pub heights_m: Vec<f64>,
}

impl HeightGrid {
    fn sample(origin: [f64; 2], max: [f64; 2], cell_m: f64, f: impl Fn(f64, f64) -> f64) -> Self {
        let num_x = (((max[0] - origin[0]) / cell_m).ceil() as usize + 1).max(2);
        let num_y = (((max[1] - origin[1]) / cell_m).ceil() as usize + 1).max(2);
        let mut heights_m = Vec::with_capacity(num_x * num_y);
        for j in 0..num_y {
            for i in 0..num_x {
                heights_m.push(f(origin[0] + i as f64 * cell_m, origin[1] + j as f64 * cell_m));
            }
        }
        Self {
            origin_xy_m: origin,
            cell_m,
            num_x,
            num_y,
            heights_m,
        }
    }
}

/// Builds the terrain of a validated scenario.
///
/// # Errors
/// A message if the terrain image cannot be read.
pub fn build(scenario: &Scenario, source: &ScenarioSource) -> Result<HeightGrid, HeightmapError> {
    let m = TERRAIN_MARGIN_M;
    let lo = [scenario.map.min_xy_m[0] - m, scenario.map.min_xy_m[1] - m];
    let hi = [scenario.map.max_xy_m[0] + m, scenario.map.max_xy_m[1] + m];
    match &scenario.terrain {
        Terrain::Flat { height_m } => {
            let h = *height_m;
            Ok(HeightGrid::sample(
                lo,
                hi,
                (hi[0] - lo[0]).max(hi[1] - lo[1]),
                |_, _| h,
            ))
        }
        Terrain::Slope {
            height_m,
            slope_x,
            slope_y,
        } => {
            // A plane is exact on any triangulation: one square.
            let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
            Ok(HeightGrid::sample(lo, hi, span, |x, y| {
                height_m + slope_x * x + slope_y * y
            }))
        }
        Terrain::Noise {
            amplitude_m,
            wavelength_m,
            cell_m,
        } => {
            let mut rng = seed::stream(scenario.seed, "terrain");
            // Six plane waves with random directions, wavelengths (0.5 to 1.5 times the nominal) and phases;
            // their sum is scaled so its peak never exceeds the amplitude.
            let waves: Vec<(f64, f64, f64)> = (0..6)
                .map(|_| {
                    let dir = rng.random_range(0.0..std::f64::consts::TAU);
                    let k = std::f64::consts::TAU / (wavelength_m * rng.random_range(0.5..1.5));
                    (
                        k * dir.cos(),
                        k * dir.sin(),
                        rng.random_range(0.0..std::f64::consts::TAU),
                    )
                })
                .collect();
            let a = amplitude_m / waves.len() as f64;
            Ok(HeightGrid::sample(
                scenario.map.min_xy_m.map(|v| v - 2.0),
                scenario.map.max_xy_m.map(|v| v + 2.0),
                *cell_m,
                |x, y| {
                    waves
                        .iter()
                        .map(|(kx, ky, phase)| a * (kx * x + ky * y + phase).sin())
                        .sum()
                },
            ))
        }
        Terrain::Image {
            path,
            height_scale_m,
            cell_m,
            origin_xy_m,
        } => {
            let file = source.resolve(path);
            let (width, height, pixels) = crate::scenario::heightmap::read_greyscale_png(&file)?;
            let origin = origin_xy_m.unwrap_or(scenario.map.min_xy_m);
            let mut heights_m = Vec::with_capacity(pixels.len());
            // Image row 0 is the max-y edge: grid row j is image row (height - 1 - j).
            for j in 0..height {
                let row = height - 1 - j;
                heights_m.extend(
                    pixels[row * width..(row + 1) * width]
                        .iter()
                        .map(|v| v * height_scale_m),
                );
            }
            Ok(HeightGrid {
                origin_xy_m: origin,
                cell_m: *cell_m,
                num_x: width,
                num_y: height,
                heights_m,
            })
        }
    }
}
