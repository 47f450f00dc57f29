//! Figures of map layers: PNG images (and SVG on request) with axes in metres, a title and a colour bar or
//! legend.
//!
//! Drawn with a small built-in rasteriser (lines, rectangles, hatching) and anti-aliased text in the embedded
//! DejaVu Sans (`ab_glyph`), so that images are byte-identical across machines and the build stays light. The
//! canvas records what it draws, so the same figure can also be written as SVG (`svg`).

pub(crate) mod canvas;
pub(crate) mod chart;
pub(crate) mod colormap;
pub(crate) mod comparison;
pub(crate) mod figure;
pub(crate) mod font;
mod layers;
pub(crate) mod svg;

use std::path::{Path, PathBuf};

use crate::error::Result;

pub use canvas::{Canvas, Rgb};
pub use colormap::Colormap;
pub use figure::{Figure, Fill, Legend, NO_DATA, Pattern, finite_range};
pub use layers::{
    TRAVERSABILITY_CLASSES, scalar_figure, scalar_figure_of, traversability_figure, traversability_figure_of,
    traversability_fill, write_layer_images,
};

/// The robot's drive on the run's images.
pub const DRIVE: Rgb = [30, 80, 230];
/// A planned path on the images.
pub const PLAN: Rgb = [200, 0, 200];

/// The files each figure is written as: always a PNG, and with `svg` an SVG beside it (same name, `.svg`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ImageFormats {
    /// Also write each figure as SVG, for papers (`--svg`).
    pub svg: bool,
}

/// Writes `canvas` to `png_path` and, when `formats` asks for it, as SVG beside it; returns the files
/// written.
///
/// # Errors
/// A failed write.
pub fn save(png_path: &Path, canvas: &Canvas, formats: ImageFormats) -> Result<Vec<PathBuf>> {
    save_with(png_path, canvas, formats, crate::output::write_bytes)
}

/// As [`save`], each file written by `write` (a sweep folder's writer, which checks its lock).
///
/// # Errors
/// A failed write.
pub fn save_with(
    png_path: &Path,
    canvas: &Canvas,
    formats: ImageFormats,
    mut write: impl FnMut(&Path, &[u8]) -> Result<()>,
) -> Result<Vec<PathBuf>> {
    write(png_path, &canvas.to_png())?;
    let mut files = vec![png_path.to_path_buf()];
    if formats.svg {
        let svg_path = png_path.with_extension("svg");
        write(&svg_path, canvas.to_svg().as_bytes())?;
        files.push(svg_path);
    }
    Ok(files)
}
