//! Figures of map layers: PNG images with axes in metres, a title and a colour bar or legend.
//!
//! Drawn with a small built-in rasteriser (lines, rectangles, hatching) and anti-aliased text in the embedded
//! DejaVu Sans (`ab_glyph`), so that images are byte-identical across machines and the build stays light.

pub mod canvas;
pub mod chart;
pub mod colormap;
pub mod comparison;
pub mod figure;
pub mod font;
mod layers;

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
