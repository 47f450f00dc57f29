//! Figures of the map's layers.

use std::path::{Path, PathBuf};

use oeg::{
    CellIndex, CellRegion, GridWindow, Layer, LayerKind, Map, Raster, RobotProfile, Traversability,
    TraversabilityRule,
};

use super::colormap::Colormap;
use super::comparison::verdict_fill;
use super::figure::{Figure, Fill, Legend, NO_DATA, finite_range};
use super::{ImageFormats, save};
use crate::error::Result;
use crate::judge::verdict::Verdict;

/// A continuous layer: NaN cells in [`NO_DATA`] grey, the rest coloured over `range` (default: the data's).
pub fn scalar_figure(
    layer: &Layer,
    title: &str,
    label: &str,
    colormap: Colormap,
    range: Option<(f32, f32)>,
) -> Figure {
    let range = range.or_else(|| finite_range(&layer.values));
    scalar_figure_of(&layer.window, title, label, colormap, range, |c| {
        layer.get(c).unwrap_or(f32::NAN)
    })
}

/// A continuous quantity over `window`, read cell by cell (only the cells the figure shows are read):
/// non-finite values in [`NO_DATA`] grey, the rest coloured over `range` (default: 0 to 1).
pub fn scalar_figure_of(
    window: &GridWindow,
    title: &str,
    label: &str,
    colormap: Colormap,
    range: Option<(f32, f32)>,
    value: impl Fn(CellIndex) -> f32,
) -> Figure {
    let (min, max) = range.unwrap_or((0.0, 1.0));
    let legend = Legend::ColorBar {
        colormap,
        min,
        max,
        label: label.to_string(),
    };
    Figure::new(
        window,
        title,
        |c| match value(c) {
            v if v.is_finite() => colormap.color((v - min) / (max - min)),
            _ => NO_DATA,
        },
        &legend,
    )
}

/// The fill of each traversability class. Blocked is the grey and uncertain the dotted blue of the same
/// decisions on `decisions.png` (`verdict_fill`), so that a class looks the same in every figure; red is
/// kept for unsafe cells, which only a comparison with the truth can tell.
pub fn traversability_fill(t: Traversability) -> Fill {
    match t {
        Traversability::Unknown => NO_DATA.into(),
        Traversability::Free => [255, 255, 255].into(),
        Traversability::Traversable => [120, 190, 90].into(),
        Traversability::Blocked => verdict_fill(Verdict::RightBlocked),
        Traversability::Uncertain => verdict_fill(Verdict::Uncertain),
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
    traversability_figure_of(&layer.window, title, |c| {
        layer.get(c).unwrap_or(Traversability::Unknown)
    })
}

/// The decisions over `window`, read cell by cell (only the cells the figure shows are read), with a class
/// legend.
pub fn traversability_figure_of(
    window: &GridWindow,
    title: &str,
    class: impl Fn(CellIndex) -> Traversability,
) -> Figure {
    let legend = Legend::Classes(
        TRAVERSABILITY_CLASSES
            .iter()
            .map(|(t, name)| (name.to_string(), traversability_fill(*t)))
            .collect(),
    );
    Figure::new(window, title, |c| traversability_fill(class(c)), &legend)
}

/// The finite range of one layer over the observed cells in `region`: the cost follows what the map holds,
/// not the region's extent.
fn observed_range(
    map: &Map,
    kind: LayerKind,
    region: CellRegion,
    scale: fn(f32) -> f32,
) -> Option<(f32, f32)> {
    let values: Vec<f32> = map
        .observed_cells()
        .filter(|(c, _)| region.contains(*c))
        .map(|(_, cell)| scale(kind.value(&cell)))
        .collect();
    finite_range(&values)
}

/// Writes `occupancy.png`, `elevation.png`, `variance.png` and `traversability.png` over `region` (default: the
/// observed region). An empty map with no region given gets no images. The images read only the cells they
/// show, so their cost follows the image's size and the map's observed cells, never the region's extent.
///
/// # Errors
/// A failed write.
pub fn write_layer_images(
    map: &Map,
    out_dir: &Path,
    profile: &RobotProfile,
    rule: TraversabilityRule,
    region: Option<CellRegion>,
    formats: ImageFormats,
) -> Result<Vec<PathBuf>> {
    let Some(region) = region.or_else(|| map.observed_region()) else {
        return Ok(Vec::new());
    };
    let window = GridWindow::new(*map.geometry(), region);
    let res = window.resolution_m();
    let mut files = Vec::new();
    let same: fn(f32) -> f32 = |v| v;
    // The variance spans orders of magnitude (a laser's millimetres beside far stereo's metres): on a linear
    // scale every laser cell is black, so it is drawn as log10.
    let log10: fn(f32) -> f32 = f32::log10;
    let layers = [
        (
            "occupancy.png",
            LayerKind::OccupancyProbability,
            "Occupancy probability",
            "P(occupied)",
            Colormap::GreysReversed,
            Some((0.0, 1.0)),
            same,
        ),
        (
            "elevation.png",
            LayerKind::ElevationM,
            "Elevation mean",
            "elevation [m]",
            Colormap::Viridis,
            None,
            same,
        ),
        (
            "variance.png",
            LayerKind::VarianceM2,
            "Elevation variance, log scale",
            "log10(variance / m\u{b2}): -4 is (1 cm)\u{b2}",
            Colormap::Inferno,
            None,
            log10,
        ),
    ];
    for (name, kind, title, label, colormap, range, scale) in layers {
        let range = range.or_else(|| observed_range(map, kind, region, scale));
        let title = format!("{title} ({res} m cells)");
        let figure = scalar_figure_of(&window, &title, label, colormap, range, |c| {
            scale(kind.value(&map.cell(c)))
        });
        files.extend(save(&out_dir.join(name), figure.canvas(), formats)?);
    }
    let title = format!("Traversability (max step {} m)", profile.max_step_m);
    let figure = traversability_figure_of(&window, &title, |c| map.traversability(c, profile, rule));
    files.extend(save(
        &out_dir.join("traversability.png"),
        figure.canvas(),
        formats,
    )?);
    Ok(files)
}
