//! The ground as a grid of heights, built from the scenario's terrain settings.

use std::path::Path;

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
pub fn build(scenario: &Scenario, source: &ScenarioSource) -> Result<HeightGrid, String> {
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
            let (width, height, pixels) = read_greyscale_png(&file)?;
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

/// Reads an 8- or 16-bit greyscale PNG as values in [0, 1], row 0 first. Returns (width, height, values).
///
/// # Errors
/// As [`decode_greyscale_png`], and a file that cannot be read.
pub fn read_greyscale_png(path: &Path) -> Result<(usize, usize, Vec<f64>), String> {
    let bytes =
        std::fs::read(path).map_err(|e| format!("cannot open the terrain image {}: {e}", path.display()))?;
    decode_greyscale_png(path, &bytes)
}

/// The most pixels a terrain image may hold: the scenario's cell limit
/// ([`crate::scenario::MAX_MAP_CELLS`]), checked from the PNG header before any pixel is decoded.
pub const MAX_TERRAIN_PIXELS: u64 = crate::scenario::MAX_MAP_CELLS;

/// Decodes the bytes of an 8- or 16-bit greyscale PNG (`path` names it in messages) as values in [0, 1].
///
/// # Errors
/// A message naming the file: not a PNG, not greyscale, smaller than 2 x 2, or larger than
/// [`MAX_TERRAIN_PIXELS`] (refused before decoding).
pub fn decode_greyscale_png(path: &Path, bytes: &[u8]) -> Result<(usize, usize, Vec<f64>), String> {
    let name = path.display();
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("{name} is not a readable PNG: {e}"))?;
    let (w, h) = (reader.info().width, reader.info().height);
    if u64::from(w) * u64::from(h) > MAX_TERRAIN_PIXELS {
        return Err(format!(
            "{name}: the header declares {w} x {h} pixels, over the limit of {MAX_TERRAIN_PIXELS}"
        ));
    }
    let (color, depth) = reader.output_color_type();
    if color != png::ColorType::Grayscale {
        return Err(format!("{name}: expected a greyscale PNG, found {color:?}"));
    }
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| format!("{name}: image too large"))?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("{name}: corrupt image data: {e}"))?;
    let (w, h) = (info.width as usize, info.height as usize);
    if w < 2 || h < 2 {
        return Err(format!("{name}: expected at least 2 x 2 pixels, found {w} x {h}"));
    }
    let values = match depth {
        png::BitDepth::Eight => buf[..w * h].iter().map(|&v| f64::from(v) / 255.0).collect(),
        png::BitDepth::Sixteen => buf[..w * h * 2]
            .chunks_exact(2)
            .map(|c| f64::from(u16::from_be_bytes([c[0], c[1]])) / 65535.0)
            .collect(),
        other => return Err(format!("{name}: expected 8- or 16-bit samples, found {other:?}")),
    };
    Ok((w, h, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn crc32(bytes: &[u8]) -> u32 {
        let mut c = !0u32;
        for &b in bytes {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 == 1 {
                    0xedb8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }

    /// The bytes of a greyscale PNG that declares `w` x `h` pixels and holds a few bytes of image data.
    fn header_only_png(w: u32, h: u32) -> Vec<u8> {
        let mut bytes = b"\x89PNG\r\n\x1a\n".to_vec();
        let mut chunk = |kind: &[u8; 4], data: &[u8]| {
            bytes.extend_from_slice(&(data.len() as u32).to_be_bytes());
            let mut body = kind.to_vec();
            body.extend_from_slice(data);
            bytes.extend_from_slice(&body);
            bytes.extend_from_slice(&crc32(&body).to_be_bytes());
        };
        let mut ihdr = Vec::new();
        ihdr.extend_from_slice(&w.to_be_bytes());
        ihdr.extend_from_slice(&h.to_be_bytes());
        ihdr.extend_from_slice(&[8, 0, 0, 0, 0]); // 8-bit greyscale, deflate, no filter, no interlace
        chunk(b"IHDR", &ihdr);
        chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01]);
        chunk(b"IEND", &[]);
        bytes
    }

    #[test]
    fn a_png_declaring_too_many_pixels_is_refused_from_its_header() {
        let bytes = header_only_png(60_000, 60_000);
        assert!(bytes.len() < 200, "{} bytes", bytes.len());
        let err = decode_greyscale_png(Path::new("huge.png"), &bytes).expect_err("too large");
        assert!(err.contains("huge.png") && err.contains("60000 x 60000"), "{err}");
    }
}
