//! An RGB pixel buffer with the few drawing operations the figures need, and PNG encoding.
//!
//! Each drawing operation also records itself as a [`Shape`], so that the same drawing can be written as SVG
//! ([`super::svg`]): lines, rectangles and text stay vectors, and the parts drawn pixel by pixel (a map's
//! cells, textures, colour bars) are kept as [`Shape::Image`]s by [`Canvas::freeze`].

use super::font;

/// An RGB colour.
pub type Rgb = [u8; 3];

/// Black.
pub(crate) const BLACK: Rgb = [0, 0, 0];
/// White.
pub(crate) const WHITE: Rgb = [255, 255, 255];

/// One recorded drawing operation, in pixel coordinates (row 0 at the top); see [`Canvas::shapes`].
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// A filled rectangle covering the pixels `[x, x + w) x [y, y + h)`.
    Rect {
        /// Left pixel.
        x: i64,
        /// Top pixel.
        y: i64,
        /// Width, pixels.
        w: i64,
        /// Height, pixels.
        h: i64,
        /// Fill.
        color: Rgb,
    },
    /// A one-pixel line through the centres of the pixels `(x0, y0)` and `(x1, y1)`, both drawn.
    Line {
        /// First pixel.
        from: (i64, i64),
        /// Last pixel.
        to: (i64, i64),
        /// Colour.
        color: Rgb,
        /// For a dashed line (4 pixels drawn, 4 left out), the pixels of its pattern cut off before `from`
        /// (the part of the line off the canvas).
        dashes: Option<i64>,
    },
    /// A line of text; `(x, y)` is the top-left corner of its line box, or for vertical text (reading
    /// upwards) the bottom-left corner of the turned line.
    Text {
        /// Where the line starts.
        x: i64,
        /// Where the line starts.
        y: i64,
        /// The text.
        text: String,
        /// 1 for labels, 2 for titles.
        scale: usize,
        /// Colour.
        color: Rgb,
        /// Turned 90 degrees counter-clockwise.
        vertical: bool,
    },
    /// A block of pixels, as they were when [`Canvas::freeze`] was called.
    Image {
        /// Left pixel.
        x: usize,
        /// Top pixel.
        y: usize,
        /// The pixels.
        image: Canvas,
    },
}

impl Shape {
    /// The shape moved `dx` pixels to the right.
    fn shifted(&self, dx: i64) -> Shape {
        let mut s = self.clone();
        match &mut s {
            Shape::Rect { x, .. } | Shape::Text { x, .. } => *x += dx,
            Shape::Line { from, to, .. } => {
                from.0 += dx;
                to.0 += dx;
            }
            Shape::Image { x, .. } => *x = (*x as i64 + dx).max(0) as usize,
        }
        s
    }

    /// Whether the shape lies wholly inside the pixels `[x, x + w) x [y, y + h)`.
    fn inside(&self, x: i64, y: i64, w: i64, h: i64) -> bool {
        let within = |px: i64, py: i64| px >= x && py >= y && px < x + w && py < y + h;
        match self {
            Shape::Rect {
                x: rx,
                y: ry,
                w: rw,
                h: rh,
                ..
            } => *rw > 0 && *rh > 0 && within(*rx, *ry) && within(rx + rw - 1, ry + rh - 1),
            Shape::Line { from, to, .. } => within(from.0, from.1) && within(to.0, to.1),
            Shape::Text { .. } => false,
            Shape::Image { x: ix, y: iy, image } => {
                within(*ix as i64, *iy as i64)
                    && within((*ix + image.width) as i64 - 1, (*iy + image.height) as i64 - 1)
            }
        }
    }
}

/// A width x height RGB image, row 0 at the top, with the shapes drawn on it.
#[derive(Debug, Clone, PartialEq)]
pub struct Canvas {
    width: usize,
    height: usize,
    pixels: Vec<u8>,
    shapes: Vec<Shape>,
}

impl Canvas {
    /// A canvas filled with `background`.
    pub fn new(width: usize, height: usize, background: Rgb) -> Self {
        let mut pixels = Vec::with_capacity(width * height * 3);
        for _ in 0..width * height {
            pixels.extend_from_slice(&background);
        }
        let shapes = vec![Shape::Rect {
            x: 0,
            y: 0,
            w: width as i64,
            h: height as i64,
            color: background,
        }];
        Self {
            width,
            height,
            pixels,
            shapes,
        }
    }

    /// What was drawn, in order: the background, then every line, rectangle and text, with the parts drawn
    /// pixel by pixel as images where [`Canvas::freeze`] kept them.
    pub fn shapes(&self) -> &[Shape] {
        &self.shapes
    }

    /// Keeps the pixels `[x, x + w) x [y, y + h)` (clipped to the canvas) as they are now as one image
    /// shape, for the parts drawn pixel by pixel ([`Canvas::set`], [`Canvas::fill_pixels`]). Shapes drawn
    /// before wholly inside the block are dropped: the image holds them.
    pub fn freeze(&mut self, x: usize, y: usize, w: usize, h: usize) {
        let (x1, y1) = ((x + w).min(self.width), (y + h).min(self.height));
        if x >= x1 || y >= y1 {
            return;
        }
        let mut image = Canvas::new(x1 - x, y1 - y, WHITE);
        image.shapes.clear();
        for row in y..y1 {
            let (src, dst) = ((row * self.width + x) * 3, (row - y) * image.width * 3);
            image.pixels[dst..dst + image.width * 3]
                .copy_from_slice(&self.pixels[src..src + image.width * 3]);
        }
        let (bx, by, bw, bh) = (x as i64, y as i64, image.width as i64, image.height as i64);
        self.shapes.retain(|s| !s.inside(bx, by, bw, bh));
        self.shapes.push(Shape::Image { x, y, image });
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The colour at `(x, y)`, or `None` outside.
    pub fn pixel(&self, x: usize, y: usize) -> Option<Rgb> {
        (x < self.width && y < self.height).then(|| {
            let k = (y * self.width + x) * 3;
            [self.pixels[k], self.pixels[k + 1], self.pixels[k + 2]]
        })
    }

    /// Sets one pixel; outside the canvas it does nothing. Not recorded as a shape: see [`Canvas::freeze`].
    pub fn set(&mut self, x: i64, y: i64, color: Rgb) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let k = (y as usize * self.width + x as usize) * 3;
            self.pixels[k..k + 3].copy_from_slice(&color);
        }
    }

    /// Fills the rectangle `[x, x + w) x [y, y + h)`, clipped to the canvas.
    pub fn fill_rect(&mut self, x: i64, y: i64, w: i64, h: i64, color: Rgb) {
        self.shapes.push(Shape::Rect { x, y, w, h, color });
        self.fill_pixels(x, y, w, h, color);
    }

    /// Fills the rectangle `[x, x + w) x [y, y + h)` pixel by pixel, clipped to the canvas, without recording
    /// a shape (see [`Canvas::freeze`]).
    pub fn fill_pixels(&mut self, x: i64, y: i64, w: i64, h: i64, color: Rgb) {
        for yy in y.max(0)..(y + h).min(self.height as i64) {
            for xx in x.max(0)..(x + w).min(self.width as i64) {
                self.set(xx, yy, color);
            }
        }
    }

    /// A one-pixel rectangle outline.
    pub fn stroke_rect(&mut self, x: i64, y: i64, w: i64, h: i64, color: Rgb) {
        self.line(x, y, x + w - 1, y, color);
        self.line(x, y + h - 1, x + w - 1, y + h - 1, color);
        self.line(x, y, x, y + h - 1, color);
        self.line(x + w - 1, y, x + w - 1, y + h - 1, color);
    }

    /// A one-pixel line (Bresenham), clipped to the canvas.
    pub fn line(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, color: Rgb) {
        self.record_line(x0, y0, x1, y1, color, false);
        self.stroke(x0, y0, x1, y1, color, |_| true);
    }

    /// Records a line's shape, the part of it on the canvas only (a line from a kilometre-sized obstacle
    /// would otherwise reach far outside the SVG's view).
    fn record_line(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, color: Rgb, dashed: bool) {
        if let Some((a0, a1, b0, b1, skipped)) = self.clip(x0, y0, x1, y1) {
            self.shapes.push(Shape::Line {
                from: (a0, a1),
                to: (b0, b1),
                color,
                dashes: dashed.then_some(skipped),
            });
        }
    }

    /// The part of the segment within one pixel of the canvas (Liang-Barsky), and the Bresenham steps cut
    /// from its start; `None` when none of it is. A segment inside the canvas is returned unchanged.
    fn clip(&self, x0: i64, y0: i64, x1: i64, y1: i64) -> Option<(i64, i64, i64, i64, i64)> {
        let (fx, fy) = (x0 as f64, y0 as f64);
        let (dx, dy) = ((x1 as f64) - fx, (y1 as f64) - fy);
        let (w, h) = (self.width as f64, self.height as f64);
        let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
        for (p, q) in [(-dx, fx + 1.0), (dx, w - fx), (-dy, fy + 1.0), (dy, h - fy)] {
            if p == 0.0 {
                if q < 0.0 {
                    return None;
                }
                continue;
            }
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
            if t0 > t1 {
                return None;
            }
        }
        let at = |t: f64| ((fx + t * dx).round() as i64, (fy + t * dy).round() as i64);
        let (a, b) = (
            if t0 > 0.0 { at(t0) } else { (x0, y0) },
            if t1 < 1.0 { at(t1) } else { (x1, y1) },
        );
        let steps = (x1 - x0).abs().max((y1 - y0).abs()) as f64;
        Some((a.0, a.1, b.0, b.1, (t0 * steps).round() as i64))
    }

    /// A dashed one-pixel line: 4 pixels drawn, 4 left out.
    pub fn dashed_line(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, color: Rgb) {
        self.record_line(x0, y0, x1, y1, color, true);
        self.stroke(x0, y0, x1, y1, color, |k| (k / 4) % 2 == 0);
    }

    /// Bresenham from `(x0, y0)` to `(x1, y1)`, drawing the `k`-th pixel when `draw(k)`. The segment is first
    /// clipped to the canvas, so a line from a kilometre-sized obstacle costs its visible pixels only.
    fn stroke(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, color: Rgb, draw: impl Fn(i64) -> bool) {
        let Some((x0, y0, x1, y1, skipped)) = self.clip(x0, y0, x1, y1) else {
            return;
        };
        let draw = |k| draw(k + skipped);
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
        let (mut x, mut y, mut err) = (x0, y0, dx + dy);
        // Bound the loop: a line never needs more steps than its longer side.
        for k in 0..=(dx.max(-dy) + 1) {
            if draw(k) {
                self.set(x, y, color);
            }
            if x == x1 && y == y1 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
        }
    }

    /// Blends `color` over the pixel at `(x, y)` with opacity `alpha` in [0, 1]; outside the canvas it does
    /// nothing. Rounded the same way everywhere, so the same drawing gives the same bytes.
    pub fn blend(&mut self, x: i64, y: i64, color: Rgb, alpha: f32) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let k = (y as usize * self.width + x as usize) * 3;
            for (c, dst) in self.pixels[k..k + 3].iter_mut().enumerate() {
                let mixed = f32::from(*dst) + (f32::from(color[c]) - f32::from(*dst)) * alpha;
                *dst = mixed.round().clamp(0.0, 255.0) as u8;
            }
        }
    }

    /// Anti-aliased text (the embedded DejaVu Sans, `font`) with the top-left corner of its line at
    /// `(x, y)`; `scale` 1 for labels, 2 for titles.
    pub fn text(&mut self, x: i64, y: i64, text: &str, scale: usize, color: Rgb) {
        self.shapes.push(Shape::Text {
            x,
            y,
            text: text.to_string(),
            scale,
            color,
            vertical: false,
        });
        font::rasterize(text, scale, |gx, gy, c| self.blend(x + gx, y + gy, color, c));
    }

    /// Width in pixels of `text` at `scale`.
    pub fn text_width(text: &str, scale: usize) -> usize {
        font::width(text, scale)
    }

    /// Height in pixels of a line of text at `scale`.
    pub fn text_height(scale: usize) -> usize {
        font::line_height(scale)
    }

    /// Text rotated 90 degrees counter-clockwise (reading upwards), for vertical axis labels: `(x, y)` is the
    /// bottom-left corner of the rotated line (where the text starts).
    pub fn text_vertical(&mut self, x: i64, y: i64, text: &str, scale: usize, color: Rgb) {
        self.shapes.push(Shape::Text {
            x,
            y,
            text: text.to_string(),
            scale,
            color,
            vertical: true,
        });
        // A pixel (gx, gy) of the upright line lands gx up from the start and gy right of the left edge.
        font::rasterize(text, scale, |gx, gy, c| self.blend(x + gy, y - gx, color, c));
    }

    /// `images` side by side, left to right, `gap` white pixels apart, top-aligned on a white background.
    pub fn side_by_side(images: &[&Canvas], gap: usize) -> Canvas {
        let width = images.iter().map(|c| c.width).sum::<usize>() + gap * images.len().saturating_sub(1);
        let height = images.iter().map(|c| c.height).max().unwrap_or(0);
        let mut out = Canvas::new(width, height, WHITE);
        let mut x0 = 0;
        for c in images {
            for y in 0..c.height {
                let (src, dst) = (y * c.width * 3, (y * width + x0) * 3);
                out.pixels[dst..dst + c.width * 3].copy_from_slice(&c.pixels[src..src + c.width * 3]);
            }
            out.shapes.extend(c.shapes.iter().map(|s| s.shifted(x0 as i64)));
            x0 += c.width + gap;
        }
        out
    }

    /// The drawing as an SVG document (the `svg` writer).
    pub fn to_svg(&self) -> String {
        super::svg::to_svg(self)
    }

    /// The image as PNG bytes (8-bit RGB). Deterministic: the same pixels give the same bytes.
    pub fn to_png(&self) -> Vec<u8> {
        let mut out = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut out, self.width as u32, self.height as u32);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            // Writing into a Vec cannot fail for a well-formed header and a buffer of the right size.
            let written = encoder
                .write_header()
                .and_then(|mut w| w.write_image_data(&self.pixels));
            debug_assert!(written.is_ok(), "{written:?}");
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drawing_stays_on_the_canvas() {
        let mut c = Canvas::new(10, 5, WHITE);
        c.fill_rect(-3, -3, 100, 100, BLACK);
        assert_eq!(c.pixel(9, 4), Some(BLACK));
        c.line(-50, 2, 50, 2, WHITE);
        assert_eq!(c.pixel(0, 2), Some(WHITE));
        assert_eq!(c.pixel(10, 0), None);
    }

    #[test]
    fn a_line_a_billion_pixels_long_draws_its_visible_part_at_once() {
        let mut c = Canvas::new(100, 50, WHITE);
        let started = std::time::Instant::now();
        c.line(-1_000_000_000_000, 25, 1_000_000_000_000, 25, BLACK);
        c.dashed_line(50, -1_000_000_000_000, 50, 1_000_000_000_000, BLACK);
        c.line(
            -5_000_000_000,
            -5_000_000_000,
            -4_000_000_000,
            -4_000_000_000,
            BLACK,
        );
        assert!(started.elapsed().as_secs_f64() < 1.0, "{:?}", started.elapsed());
        assert!((0..100).all(|x| c.pixel(x, 25) == Some(BLACK)));
        let dashes = (0..50).filter(|&y| c.pixel(50, y) == Some(BLACK)).count();
        assert!((20..=30).contains(&dashes), "{dashes} dashed pixels");
        // A segment inside the canvas draws exactly as before clipping.
        let (mut a, mut b) = (Canvas::new(30, 30, WHITE), Canvas::new(30, 30, WHITE));
        a.line(2, 3, 27, 19, BLACK);
        b.line(2, 3, 27, 19, BLACK);
        b.line(-40, -40, -30, -30, BLACK);
        assert!(a == b);
    }

    #[test]
    fn text_draws_inside_its_line_box_and_vertical_text_turns_it() {
        let (w, h) = (Canvas::text_width("x [m]", 1), Canvas::text_height(1));
        let mut c = Canvas::new(w + 20, h + 20, WHITE);
        c.text(10, 10, "x [m]", 1, BLACK);
        let inked: Vec<(usize, usize)> = (0..c.height())
            .flat_map(|y| (0..c.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| c.pixel(x, y) != Some(WHITE))
            .collect();
        assert!(inked.len() > 20);
        assert!(
            inked
                .iter()
                .all(|&(x, y)| (10..10 + w + 1).contains(&x) && (10..10 + h).contains(&y))
        );
        // Stems are nearly black, edges in between.
        assert!(
            inked
                .iter()
                .any(|&(x, y)| c.pixel(x, y).is_some_and(|p| p[0] < 40))
        );
        assert!(
            inked
                .iter()
                .any(|&(x, y)| c.pixel(x, y).is_some_and(|p| (80..200).contains(&p[0])))
        );
        // Turned: as tall as the line was wide, reading upwards from (x, y).
        let mut v = Canvas::new(h + 20, w + 20, WHITE);
        v.text_vertical(10, (w + 10) as i64, "x [m]", 1, BLACK);
        let inked = (0..v.height())
            .flat_map(|y| (0..v.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| v.pixel(x, y) != Some(WHITE));
        assert!(
            inked
                .clone()
                .all(|(x, y)| (10..10 + h).contains(&x) && (10..=w + 10).contains(&y))
        );
        assert!(inked.count() > 20);
    }

    #[test]
    fn images_go_side_by_side() {
        let (a, b) = (Canvas::new(2, 3, BLACK), Canvas::new(4, 1, BLACK));
        let c = Canvas::side_by_side(&[&a, &b], 1);
        assert_eq!((c.width(), c.height()), (7, 3));
        assert_eq!(c.pixel(1, 2), Some(BLACK));
        assert_eq!(c.pixel(2, 0), Some(WHITE), "the gap");
        assert_eq!(c.pixel(3, 0), Some(BLACK));
        assert_eq!(c.pixel(3, 1), Some(WHITE), "below the shorter image");
    }

    #[test]
    fn png_bytes_are_a_png() {
        let png = Canvas::new(3, 2, BLACK).to_png();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        let decoder = png::Decoder::new(std::io::Cursor::new(png));
        let reader = decoder.read_info().expect("valid png");
        assert_eq!((reader.info().width, reader.info().height), (3, 2));
    }
}
