//! Line charts: one or more series of `(x, y)` points with an interval band, axes with units, a title and a
//! legend. The sweep report draws each metric against each numeric axis with them.

use super::canvas::{BLACK, Canvas, Rgb, WHITE};
use super::figure::ticks;

const LEFT: usize = 84;
const TOP: usize = 44;
const PLOT_W: usize = 640;
const PLOT_H: usize = 400;
const BOTTOM: usize = 56;
const LEGEND_GAP: usize = 24;

/// Distinct series colours (Okabe-Ito, readable by colour-blind readers).
pub(crate) const SERIES_COLORS: [Rgb; 7] = [
    [0, 114, 178],
    [213, 94, 0],
    [0, 158, 115],
    [204, 121, 167],
    [230, 159, 0],
    [86, 180, 233],
    [120, 120, 120],
];

/// One point: `x`, `y`, and the band `[low, high]` (NaN: no band there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Point {
    /// Position along x.
    pub x: f64,
    /// Value.
    pub y: f64,
    /// Lower end of the interval.
    pub low: f64,
    /// Upper end.
    pub high: f64,
}

/// A line with its band.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Series {
    /// Legend label.
    pub label: String,
    /// Points, sorted by x.
    pub points: Vec<Point>,
}

/// A chart to draw.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Chart {
    /// Title.
    pub title: String,
    /// x-axis label, with units.
    pub x_label: String,
    /// y-axis label, with units.
    pub y_label: String,
    /// The lines.
    pub series: Vec<Series>,
    /// A note under the legend (what the band is).
    pub note: String,
}

fn lighten(c: Rgb) -> Rgb {
    c.map(|v| (u16::from(v) + 3 * 255).div_ceil(4) as u8)
}

/// The data's extent on the plot, and the pixel of a value.
struct Frame {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Frame {
    /// The column of `x`.
    fn px(&self, x: f64) -> i64 {
        LEFT as i64 + ((x - self.x0) / (self.x1 - self.x0) * PLOT_W as f64).round() as i64
    }

    /// The row of `y` (up is smaller).
    fn py(&self, y: f64) -> i64 {
        TOP as i64 + PLOT_H as i64 - ((y - self.y0) / (self.y1 - self.y0) * PLOT_H as f64).round() as i64
    }
}

impl Chart {
    /// Draws the chart: the intervals' bands, the axes, the bands' edges, the lines and markers, the legend
    /// and the title.
    pub(crate) fn draw(&self) -> Canvas {
        let frame = self.frame();
        let legend_w = self
            .series
            .iter()
            .map(|s| 28 + Canvas::text_width(&s.label, 1))
            .chain([Canvas::text_width(&self.note, 1)])
            .max()
            .unwrap_or(0);
        let width = LEFT + PLOT_W + LEGEND_GAP + legend_w + 16;
        let height = TOP + PLOT_H + BOTTOM;
        let mut c = Canvas::new(width, height, WHITE);
        // Bands first, then lines and markers over them.
        self.draw_bands(&mut c, &frame);
        self.draw_axes(&mut c, (frame.x0, frame.x1), (frame.y0, frame.y1));
        self.draw_band_edges(&mut c, &frame);
        self.draw_lines(&mut c, &frame);
        self.draw_legend(&mut c);
        let scale = if Canvas::text_width(&self.title, 2) + 8 <= width {
            2
        } else {
            1
        };
        c.text(8, 8, &self.title, scale, BLACK);
        c
    }

    /// The data's extent: every finite x, and every finite mean and interval bound with 5 % padding.
    fn frame(&self) -> Frame {
        let finite = |v: f64| v.is_finite().then_some(v);
        let xs: Vec<f64> = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().filter_map(|p| finite(p.x)))
            .collect();
        let ys: Vec<f64> = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().flat_map(|p| [p.y, p.low, p.high]))
            .filter(|v| v.is_finite())
            .collect();
        let range = |v: &[f64]| {
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if !lo.is_finite() {
                (0.0, 1.0)
            } else if hi - lo < 1e-12 {
                (lo - 0.5f64.max(lo.abs() * 0.1), hi + 0.5f64.max(hi.abs() * 0.1))
            } else {
                (lo, hi)
            }
        };
        let (x0, x1) = range(&xs);
        let (y0, y1) = range(&ys);
        let pad = 0.05 * (y1 - y0);
        Frame {
            x0,
            x1,
            y0: y0 - pad,
            y1: y1 + pad,
        }
    }

    /// Each series' interval as a light band between consecutive points.
    fn draw_bands(&self, c: &mut Canvas, f: &Frame) {
        for (k, s) in self.series.iter().enumerate() {
            let color = lighten(SERIES_COLORS[k % SERIES_COLORS.len()]);
            for w in s.points.windows(2) {
                let (a, b) = (w[0], w[1]);
                if ![a.x, b.x, a.low, a.high, b.low, b.high]
                    .iter()
                    .all(|v| v.is_finite())
                {
                    continue;
                }
                let (pa, pb) = (f.px(a.x), f.px(b.x));
                for x in pa.min(pb)..=pa.max(pb) {
                    let t = if pb == pa {
                        0.0
                    } else {
                        (x - pa) as f64 / (pb - pa) as f64
                    };
                    let lo = a.low + t * (b.low - a.low);
                    let hi = a.high + t * (b.high - a.high);
                    let (top, bottom) = (f.py(hi), f.py(lo));
                    c.fill_rect(x, top, 1, bottom - top + 1, color);
                }
            }
        }
    }

    /// The bands' edges, dashed, so that a band behind another stays visible.
    fn draw_band_edges(&self, c: &mut Canvas, f: &Frame) {
        for (k, s) in self.series.iter().enumerate() {
            let color = SERIES_COLORS[k % SERIES_COLORS.len()];
            for w in s.points.windows(2) {
                let (a, b) = (w[0], w[1]);
                for (ya, yb) in [(a.low, b.low), (a.high, b.high)] {
                    if [a.x, b.x, ya, yb].iter().all(|v| v.is_finite()) {
                        c.dashed_line(f.px(a.x), f.py(ya), f.px(b.x), f.py(yb), color);
                    }
                }
            }
        }
    }

    /// The means as lines with square markers; a lone point gets its interval as a bar.
    fn draw_lines(&self, c: &mut Canvas, f: &Frame) {
        for (k, s) in self.series.iter().enumerate() {
            let color = SERIES_COLORS[k % SERIES_COLORS.len()];
            let pts: Vec<(i64, i64)> = s
                .points
                .iter()
                .filter(|p| p.x.is_finite() && p.y.is_finite())
                .map(|p| (f.px(p.x), f.py(p.y)))
                .collect();
            for w in pts.windows(2) {
                for d in 0..2 {
                    c.line(w[0].0, w[0].1 + d, w[1].0, w[1].1 + d, color);
                }
            }
            for p in &s.points {
                if p.x.is_finite() && p.y.is_finite() {
                    c.fill_rect(f.px(p.x) - 3, f.py(p.y) - 3, 7, 7, color);
                }
                if p.x.is_finite() && p.low.is_finite() && p.high.is_finite() && s.points.len() == 1 {
                    c.line(f.px(p.x), f.py(p.low), f.px(p.x), f.py(p.high), color);
                }
            }
        }
    }

    /// One swatch and label per series, and the note under them.
    fn draw_legend(&self, c: &mut Canvas) {
        let th = Canvas::text_height(1) as i64;
        let lx = (LEFT + PLOT_W + LEGEND_GAP) as i64;
        for (k, s) in self.series.iter().enumerate() {
            let y = TOP as i64 + 20 * k as i64;
            let color = SERIES_COLORS[k % SERIES_COLORS.len()];
            c.fill_rect(lx, y + 2, 20, 10, lighten(color));
            c.fill_rect(lx, y + 6, 20, 3, color);
            c.text(lx + 28, y + 7 - th / 2, &s.label, 1, BLACK);
        }
        c.text(
            lx,
            TOP as i64 + 20 * self.series.len() as i64 + 8,
            &self.note,
            1,
            BLACK,
        );
    }

    fn draw_axes(&self, c: &mut Canvas, (x0, x1): (f64, f64), (y0, y1): (f64, f64)) {
        let th = Canvas::text_height(1) as i64;
        let (l, t) = (LEFT as i64, TOP as i64);
        let (w, h) = (PLOT_W as i64, PLOT_H as i64);
        c.stroke_rect(l - 1, t - 1, w + 2, h + 2, BLACK);
        for (v, label) in ticks(x0, x1) {
            let x = l + ((v - x0) / (x1 - x0) * w as f64).round() as i64;
            c.line(x, t + h, x, t + h + 4, BLACK);
            let tw = Canvas::text_width(&label, 1) as i64;
            c.text(x - tw / 2, t + h + 7, &label, 1, BLACK);
        }
        for (v, label) in ticks(y0, y1) {
            let y = t + h - ((v - y0) / (y1 - y0) * h as f64).round() as i64;
            c.line(l - 5, y, l - 1, y, BLACK);
            let tw = Canvas::text_width(&label, 1) as i64;
            c.text(l - 8 - tw, y - th / 2, &label, 1, BLACK);
        }
        let xw = Canvas::text_width(&self.x_label, 1) as i64;
        c.text(l + w / 2 - xw / 2, t + h + 12 + th, &self.x_label, 1, BLACK);
        let yw = Canvas::text_width(&self.y_label, 1) as i64;
        c.text_vertical(8, t + h / 2 + yw / 2, &self.y_label, 1, BLACK);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_lines_and_legend_are_drawn() {
        let chart = Chart {
            title: "t".into(),
            x_label: "x [m]".into(),
            y_label: "y [cells]".into(),
            series: vec![Series {
                label: "paper".into(),
                points: vec![
                    Point {
                        x: 0.0,
                        y: 1.0,
                        low: 0.0,
                        high: 2.0,
                    },
                    Point {
                        x: 1.0,
                        y: 3.0,
                        low: 2.0,
                        high: 4.0,
                    },
                ],
            }],
            note: "band: 95 % interval".into(),
        };
        let c = chart.draw();
        let count = |color: Rgb| {
            (0..c.height())
                .flat_map(|y| (0..c.width()).map(move |x| (x, y)))
                .filter(|&(x, y)| c.pixel(x, y) == Some(color))
                .count()
        };
        assert!(count(SERIES_COLORS[0]) > PLOT_W, "the line");
        assert!(count(lighten(SERIES_COLORS[0])) > 10 * PLOT_W, "the band");
    }
}
