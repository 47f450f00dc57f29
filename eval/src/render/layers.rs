//! Figures of the map's layers.

use oeg::{Layer, Raster, Traversability};

use super::canvas::Rgb;
use super::colormap::Colormap;
use super::figure::{Figure, Legend, NO_DATA, finite_range};

/// A continuous layer: NaN cells in [`NO_DATA`] grey, the rest coloured over `range` (default: the data's).
pub fn scalar_figure(
    layer: &Layer,
    title: &str,
    label: &str,
    colormap: Colormap,
    range: Option<(f32, f32)>,
) -> Figure {
    let (min, max) = range
        .or_else(|| finite_range(&layer.values))
        .unwrap_or((0.0, 1.0));
    let legend = Legend::ColorBar {
        colormap,
        min,
        max,
        label: label.to_string(),
    };
    Figure::new(
        layer.region,
        layer.resolution_m,
        title,
        |c| match layer.get(c) {
            Some(v) if v.is_finite() => colormap.color((v - min) / (max - min)),
            _ => NO_DATA,
        },
        &legend,
    )
}

/// The colour of each traversability class.
pub fn traversability_color(t: Traversability) -> Rgb {
    match t {
        Traversability::Unknown => NO_DATA,
        Traversability::Free => [255, 255, 255],
        Traversability::Traversable => [120, 190, 90],
        Traversability::Blocked => [200, 40, 40],
        Traversability::Uncertain => [240, 200, 40],
    }
}

/// The traversability classes in legend order.
pub const TRAVERSABILITY_CLASSES: [(Traversability, &str); 5] = [
    (Traversability::Unknown, "unknown"),
    (Traversability::Free, "free"),
    (Traversability::Traversable, "traversable (step ok)"),
    (Traversability::Blocked, "blocked"),
    (Traversability::Uncertain, "uncertain"),
];

/// The traversability layer with a class legend.
pub fn traversability_figure(layer: &Raster<Traversability>, title: &str) -> Figure {
    let legend = Legend::Classes(
        TRAVERSABILITY_CLASSES
            .iter()
            .map(|(t, name)| (name.to_string(), traversability_color(*t)))
            .collect(),
    );
    Figure::new(
        layer.region,
        layer.resolution_m,
        title,
        |c| traversability_color(layer.get(c).unwrap_or(Traversability::Unknown)),
        &legend,
    )
}
