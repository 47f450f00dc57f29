//! Map figures: a raster drawn north-up with axes in metres, a title, and a colour bar or a legend.

use oeg::{CellIndex, GridWindow};

use super::canvas::{BLACK, Canvas, Rgb, WHITE};
use super::colormap::Colormap;

/// Colour of cells with no value (never observed, no estimate).
pub const NO_DATA: Rgb = [205, 205, 205];

/// Longest side of the plot area, pixels: maps larger than this are sampled, smaller ones enlarged.
const TARGET_PLOT_PX: f64 = 900.0;
/// Largest enlargement, pixels per cell.
const MAX_PX_PER_CELL: f64 = 24.0;
const LEFT: usize = 72;
const RIGHT: usize = 240;
const TOP: usize = 40;
const BOTTOM: usize = 52;
/// Space between the plot and its legend, pixels.
const LEGEND_GAP: usize = 24;

/// A texture over a class's colour, so that classes stay apart in grey scale and for readers who do not
/// tell the colours apart. Drawn in image pixels, the same in the plot and in the legend.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pattern {
    /// The plain colour.
    Solid,
    /// Diagonal lines rising to the right, every 6 pixels.
    Hatch,
    /// Diagonal lines both ways, every 6 pixels.
    CrossHatch,
    /// A dot every 4 pixels.
    Dots,
}

/// A class's colour and texture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fill {
    /// The colour.
    pub color: Rgb,
    /// The texture drawn over it, in a darker shade of the colour.
    pub pattern: Pattern,
}

impl Fill {
    /// A colour with a texture.
    pub const fn patterned(color: Rgb, pattern: Pattern) -> Self {
        Self { color, pattern }
    }

    /// The colour of the image pixel `(x, y)`.
    pub fn at(self, x: usize, y: usize) -> Rgb {
        let ink = match self.pattern {
            Pattern::Solid => false,
            Pattern::Hatch => (x + y).is_multiple_of(6),
            Pattern::CrossHatch => (x + y).is_multiple_of(6) || (x + 6 - y % 6).is_multiple_of(6),
            Pattern::Dots => x % 4 == 1 && y % 4 == 1,
        };
        if ink {
            // 55 % of the way to black: dark enough to read on any colour, and still of its hue.
            self.color.map(|c| (f32::from(c) * 0.45).round() as u8)
        } else {
            self.color
        }
    }
}

impl From<Rgb> for Fill {
    fn from(color: Rgb) -> Self {
        Self {
            color,
            pattern: Pattern::Solid,
        }
    }
}

/// What explains the colours.
#[derive(Debug, Clone)]
pub enum Legend {
    /// A continuous colour bar from `min` to `max`, labelled (with units).
    ColorBar {
        /// The colour map.
        colormap: Colormap,
        /// Value at the bottom.
        min: f32,
        /// Value at the top.
        max: f32,
        /// Label, with units.
        label: String,
    },
    /// Discrete classes, each with its colour and texture (a line's colour for overlays).
    Classes(Vec<(String, Fill)>),
}

impl Legend {
    /// The legend's width in pixels, so that the figure can make room for its longest label.
    fn width_px(&self) -> usize {
        match self {
            Legend::ColorBar { label, min, max, .. } => (27
                + ticks(f64::from(*min), f64::from(*max))
                    .iter()
                    .map(|(_, l)| Canvas::text_width(l, 1))
                    .max()
                    .unwrap_or(0))
            .max(Canvas::text_width(label, 1).saturating_sub(4))
            .max(18 + Canvas::text_width("no data", 1)),
            Legend::Classes(classes) => classes
                .iter()
                .map(|(name, _)| 20 + Canvas::text_width(name, 1))
                .max()
                .unwrap_or(0),
        }
    }
}

/// A figure being drawn; overlays are added in world coordinates.
#[derive(Debug, Clone)]
pub struct Figure {
    canvas: Canvas,
    window: GridWindow,
    px_per_cell: f64,
    plot_w: usize,
    plot_h: usize,
}

impl Figure {
    /// Draws the raster over `window` (each cell filled by `cell_fill`: a colour, or a [`Fill`] with a
    /// texture), its axes, title and legend.
    pub fn new<F: Into<Fill>>(
        window: &GridWindow,
        title: &str,
        cell_fill: impl Fn(CellIndex) -> F,
        legend: &Legend,
    ) -> Self {
        let region = *window.region();
        let longest = f64::from(region.num_x.max(region.num_y));
        let px_per_cell = (TARGET_PLOT_PX / longest).min(MAX_PX_PER_CELL);
        let plot_w = ((f64::from(region.num_x) * px_per_cell).round() as usize).max(1);
        let plot_h = ((f64::from(region.num_y) * px_per_cell).round() as usize).max(1);
        let width = LEFT + plot_w + RIGHT.max(LEGEND_GAP + legend.width_px() + 16);
        let height = TOP + plot_h.max(200) + BOTTOM;
        let mut fig = Self {
            canvas: Canvas::new(width, height, WHITE),
            window: *window,
            px_per_cell,
            plot_w,
            plot_h,
        };
        // Each cell under the plot is coloured once and fills its block of pixels: a figure costs
        // min(cells, pixels) colour look-ups, whatever the region's extent.
        let rows = pixel_runs(plot_h, px_per_cell, region.num_y);
        let cols = pixel_runs(plot_w, px_per_cell, region.num_x);
        for &(v, py0, py1) in &rows {
            for &(u, px0, px1) in &cols {
                let fill: Fill = cell_fill(region.cell_at(u, v)).into();
                // Rows count from the bottom of the plot.
                let top = TOP + plot_h - py1;
                fig.fill_block(fill, (LEFT + px0, top), (px1 - px0, py1 - py0));
            }
        }
        fig.canvas.freeze(LEFT, TOP, plot_w, plot_h);
        fig.draw_axes();
        // The title in double size when it fits, else in single size.
        let scale = if Canvas::text_width(title, 2) + 8 <= width {
            2
        } else {
            1
        };
        let title_x = (LEFT as i64 + plot_w as i64 / 2 - Canvas::text_width(title, scale) as i64 / 2).clamp(
            4,
            (width as i64 - Canvas::text_width(title, scale) as i64 - 4).max(4),
        );
        fig.canvas.text(title_x, 8, title, scale, BLACK);
        fig.draw_legend(legend);
        fig
    }

    /// Fills a `w` x `h` block of pixels from its top-left corner, textured in image coordinates; pixels
    /// only ([`Canvas::freeze`] keeps them for SVG).
    fn fill_block(&mut self, fill: Fill, (x, y): (usize, usize), (w, h): (usize, usize)) {
        if fill.pattern == Pattern::Solid {
            self.canvas
                .fill_pixels(x as i64, y as i64, w as i64, h as i64, fill.color);
            return;
        }
        for yy in y..y + h {
            for xx in x..x + w {
                self.canvas.set(xx as i64, yy as i64, fill.at(xx, yy));
            }
        }
    }

    fn draw_axes(&mut self) {
        let th = Canvas::text_height(1) as i64;
        let (x0, y0) = (LEFT as i64, TOP as i64);
        let (w, h) = (self.plot_w as i64, self.plot_h as i64);
        self.canvas.stroke_rect(x0 - 1, y0 - 1, w + 2, h + 2, BLACK);
        let ((min_x, min_y), (span_x, span_y)) = (self.window.min_corner_m(), self.window.size_m());
        for (value, label) in ticks(min_x, min_x + span_x) {
            let px = x0 + ((value - min_x) / span_x * w as f64).round() as i64;
            self.canvas.line(px, y0 + h, px, y0 + h + 4, BLACK);
            let tw = Canvas::text_width(&label, 1) as i64;
            self.canvas.text(px - tw / 2, y0 + h + 7, &label, 1, BLACK);
        }
        for (value, label) in ticks(min_y, min_y + span_y) {
            let py = y0 + h - ((value - min_y) / span_y * h as f64).round() as i64;
            self.canvas.line(x0 - 5, py, x0 - 1, py, BLACK);
            let tw = Canvas::text_width(&label, 1) as i64;
            self.canvas.text(x0 - 8 - tw, py - th / 2, &label, 1, BLACK);
        }
        let xl = "x [m]";
        self.canvas.text(
            x0 + w / 2 - Canvas::text_width(xl, 1) as i64 / 2,
            y0 + h + 12 + th,
            xl,
            1,
            BLACK,
        );
        let yl = "y [m]";
        self.canvas
            .text_vertical(8, y0 + h / 2 + Canvas::text_width(yl, 1) as i64 / 2, yl, 1, BLACK);
    }

    fn draw_legend(&mut self, legend: &Legend) {
        let th = Canvas::text_height(1) as i64;
        let x = (LEFT + self.plot_w + LEGEND_GAP) as i64;
        let y = TOP as i64;
        match legend {
            Legend::ColorBar {
                colormap,
                min,
                max,
                label,
            } => {
                let bar_h = (self.plot_h as i64).clamp(120, 400);
                for k in 0..bar_h {
                    let t = 1.0 - k as f32 / (bar_h - 1).max(1) as f32;
                    self.canvas.fill_pixels(x, y + k, 18, 1, colormap.color(t));
                }
                self.canvas.freeze(x as usize, y as usize, 18, bar_h as usize);
                self.canvas.stroke_rect(x - 1, y - 1, 20, bar_h + 2, BLACK);
                // Ticks at round values inside the bar's range, as on the axes.
                for (value, label) in ticks(f64::from(*min), f64::from(*max)) {
                    let t = ((value - f64::from(*min)) / f64::from(max - min)) as f32;
                    let py = y + ((1.0 - t) * (bar_h - 1) as f32).round() as i64;
                    self.canvas.line(x + 19, py, x + 23, py, BLACK);
                    self.canvas.text(x + 27, py - th / 2, &label, 1, BLACK);
                }
                self.canvas.text(x - 4, y + bar_h + 10, label, 1, BLACK);
                self.canvas.fill_rect(x, y + bar_h + 26, 12, 12, NO_DATA);
                self.canvas.stroke_rect(x, y + bar_h + 26, 12, 12, BLACK);
                self.canvas
                    .text(x + 18, y + bar_h + 32 - th / 2, "no data", 1, BLACK);
            }
            Legend::Classes(classes) => {
                for (n, (name, fill)) in classes.iter().enumerate() {
                    let py = y + n as i64 * 20;
                    if fill.pattern == Pattern::Solid {
                        self.canvas.fill_rect(x, py, 14, 14, fill.color);
                    } else {
                        self.fill_block(*fill, (x as usize, py as usize), (14, 14));
                        self.canvas.freeze(x as usize, py as usize, 14, 14);
                    }
                    self.canvas.stroke_rect(x, py, 14, 14, BLACK);
                    self.canvas.text(x + 20, py + 7 - th / 2, name, 1, BLACK);
                }
            }
        }
    }

    /// The pixel of the world point `(x, y)`.
    pub fn world_to_px(&self, x_m: f64, y_m: f64) -> (i64, i64) {
        let (res, min) = (self.window.resolution_m(), self.window.region().min);
        let u = (x_m / res - f64::from(min.i)) * self.px_per_cell;
        let v = (y_m / res - f64::from(min.j)) * self.px_per_cell;
        (
            LEFT as i64 + u.round() as i64,
            TOP as i64 + self.plot_h as i64 - v.round() as i64,
        )
    }

    /// A polyline through world points, clipped to the canvas.
    pub fn polyline(&mut self, points_m: &[(f64, f64)], color: Rgb) {
        for w in points_m.windows(2) {
            let (a, b) = (self.world_to_px(w[0].0, w[0].1), self.world_to_px(w[1].0, w[1].1));
            self.canvas.line(a.0, a.1, b.0, b.1, color);
        }
    }

    /// A line of text whose lower-left corner is at a world point, clipped to the canvas.
    pub fn label(&mut self, x_m: f64, y_m: f64, text: &str, color: Rgb) {
        let (px, py) = self.world_to_px(x_m, y_m);
        self.canvas
            .text(px + 2, py - Canvas::text_height(1) as i64, text, 1, color);
    }

    /// A small filled square marker at a world point.
    pub fn marker(&mut self, x_m: f64, y_m: f64, color: Rgb) {
        let (px, py) = self.world_to_px(x_m, y_m);
        self.canvas.fill_rect(px - 3, py - 3, 7, 7, color);
        self.canvas.stroke_rect(px - 4, py - 4, 9, 9, BLACK);
    }

    /// The finished image.
    pub fn canvas(&self) -> &Canvas {
        &self.canvas
    }

    /// The finished image as PNG bytes.
    pub fn to_png(&self) -> Vec<u8> {
        self.canvas.to_png()
    }

    /// The finished image as an SVG document (the `svg` writer).
    pub fn to_svg(&self) -> String {
        super::svg::to_svg(&self.canvas)
    }
}

/// The cells sampled along one axis of a plot of `num_px` pixels, `px_per_cell` pixels a cell, over
/// `num_cells` cells: `(cell, first pixel, end pixel)` for each cell at the centre of at least one pixel, in
/// order. Pixel `p` shows the cell under its centre.
fn pixel_runs(num_px: usize, px_per_cell: f64, num_cells: u32) -> Vec<(u32, usize, usize)> {
    let mut runs: Vec<(u32, usize, usize)> = Vec::new();
    for p in 0..num_px {
        let cell = (((p as f64 + 0.5) / px_per_cell) as u32).min(num_cells.saturating_sub(1));
        match runs.last_mut() {
            Some(run) if run.0 == cell => run.2 = p + 1,
            _ => runs.push((cell, p, p + 1)),
        }
    }
    runs
}

/// "Nice" tick positions (steps of 1, 2 or 5 times a power of ten, about six of them) within `[lo, hi]`, with
/// their labels.
pub(crate) fn ticks(lo: f64, hi: f64) -> Vec<(f64, String)> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return vec![(lo, format!("{lo}"))];
    }
    let raw = span / 6.0;
    let power = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * power)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * power);
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    };
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last)
        .map(|k| {
            let v = k as f64 * step;
            // Avoid "-0".
            let v = if v == 0.0 { 0.0 } else { v };
            // The typographic minus sign, as in printed figures.
            (v, format!("{v:.decimals$}").replace('-', "\u{2212}"))
        })
        .collect()
}

/// The value range to colour: the finite values' minimum and maximum, widened when they are equal. `None`
/// when there are no finite values.
pub fn finite_range(values: &[f32]) -> Option<(f32, f32)> {
    let mut it = values.iter().copied().filter(|v| v.is_finite());
    let first = it.next()?;
    let (lo, hi) = it.fold((first, first), |(lo, hi), v| (lo.min(v), hi.max(v)));
    Some(if hi - lo < 1e-6 {
        (lo - 0.5, hi + 0.5)
    } else {
        (lo, hi)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use oeg::CellRegion;

    #[test]
    fn ticks_are_nice_and_inside() {
        let t = ticks(-1.3, 4.2);
        let values: Vec<f64> = t.iter().map(|(v, _)| *v).collect();
        assert_eq!(values, vec![-1.0, 0.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!(t[1].1, "0");
        let t = ticks(0.0, 0.5);
        assert_eq!(t[1].1, "0.1");
        assert!(ticks(2.0, 2.0).len() == 1);
    }

    #[test]
    fn textures_differ_in_grey_scale_and_solid_fills_are_plain() {
        let grey = |c: Rgb| (u32::from(c[0]) * 299 + u32::from(c[1]) * 587 + u32::from(c[2]) * 114) / 1000;
        let color = [200, 40, 40];
        let darker = |p: Pattern| {
            (0..12)
                .flat_map(|y| (0..12).map(move |x| (x, y)))
                .filter(|&(x, y)| grey(Fill::patterned(color, p).at(x, y)) < grey(color))
                .count()
        };
        assert_eq!(darker(Pattern::Solid), 0);
        let counts = [Pattern::Hatch, Pattern::CrossHatch, Pattern::Dots].map(darker);
        assert!(counts.iter().all(|&n| n > 0), "{counts:?}");
        assert!(counts[0] != counts[1] && counts[1] != counts[2] && counts[0] != counts[2]);
    }

    #[test]
    fn pixel_runs_cover_the_axis_once_in_order() {
        // Enlarged: 3 cells at 4 pixels each.
        assert_eq!(pixel_runs(12, 4.0, 3), vec![(0, 0, 4), (1, 4, 8), (2, 8, 12)]);
        // Sampled: 8 pixels over a million cells look up 8 cells, each under a pixel's centre.
        let runs = pixel_runs(8, 1.0 / 131_072.0, 1_000_000);
        assert_eq!(runs.len(), 8);
        assert_eq!(runs[0], (65_536, 0, 1));
        assert!(runs.windows(2).all(|w| w[0].2 == w[1].1 && w[0].0 < w[1].0));
        assert_eq!(runs.last().map(|r| r.2), Some(8));
    }

    #[test]
    fn finite_range_ignores_nan_and_widens_flat_data() {
        assert_eq!(finite_range(&[f32::NAN, 1.0, 3.0]), Some((1.0, 3.0)));
        assert_eq!(finite_range(&[2.0, 2.0]), Some((1.5, 2.5)));
        assert_eq!(finite_range(&[f32::NAN]), None);
    }

    fn window(region: CellRegion, resolution_m: f64) -> GridWindow {
        GridWindow::new(oeg::GridGeometry::new(resolution_m).expect("resolution"), region)
    }

    #[test]
    fn the_figure_widens_to_fit_long_legend_labels() {
        let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(9, 9)).expect("valid");
        let name = "over-cautious (mapped blocked, truly drivable), a long label";
        let legend = Legend::Classes(vec![(name.to_string(), BLACK.into())]);
        let fig = Figure::new(&window(region, 0.1), "t", |_| WHITE, &legend);
        let text_end = LEFT + fig.plot_w + LEGEND_GAP + 20 + Canvas::text_width(name, 1);
        assert!(
            fig.canvas().width() > text_end,
            "{} <= {text_end}",
            fig.canvas().width()
        );
        // The label's last character is drawn: some pixel in its cell is inked.
        let last_char_x = text_end - Canvas::text_width("l", 1);
        let drawn = (last_char_x..text_end)
            .any(|x| (0..TOP + 20).any(|y| fig.canvas().pixel(x, y).is_some_and(|p| p != WHITE)));
        assert!(drawn, "the end of the label is cut off");
    }

    #[test]
    fn north_is_up_and_east_is_right() {
        // A 2 x 2 region: paint only the max-x, max-y cell black; it must land top-right.
        let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(1, 1)).expect("valid");
        let top_right = region.max();
        let legend = Legend::Classes(vec![]);
        let fig = Figure::new(
            &window(region, 1.0),
            "t",
            |c| if c == top_right { BLACK } else { WHITE },
            &legend,
        );
        let (px, py) = fig.world_to_px(1.5, 1.5);
        assert_eq!(fig.canvas().pixel(px as usize, py as usize), Some(BLACK));
        let (px, py) = fig.world_to_px(0.5, 0.5);
        assert_eq!(fig.canvas().pixel(px as usize, py as usize), Some(WHITE));
    }
}
