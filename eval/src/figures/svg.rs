//! Figures as SVG, for papers: the same drawing as the PNG, with lines, rectangles and text as vectors.
//!
//! - Text is written as the embedded font's glyph outlines (each glyph once, in `<defs>`, placed with
//!   `<use>`), as matplotlib's default `svg.fonttype = 'path'` does: the figure looks the same in every
//!   viewer and converter, and needs no font installed. Each line of text carries its words in `aria-label`.
//! - The parts drawn pixel by pixel (a map's cells, textures, colour bars) are PNG images inside the file,
//!   drawn without smoothing, so that cells stay sharp at any zoom.
//! - Glyphs, lines and rectangles sit where the PNG's pixels are: a shape covering pixel `(x, y)` covers the
//!   square `[x, x + 1] x [y, y + 1]` of the SVG's user space.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use super::canvas::{Canvas, Rgb, Shape};
use super::font;

fn hex(c: Rgb) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// The canvas as an SVG document. Deterministic: the same drawing gives the same bytes.
pub(crate) fn to_svg(canvas: &Canvas) -> String {
    let (w, h) = (canvas.width(), canvas.height());
    let mut out = String::new();
    // Writing into a String cannot fail; the results are ignored.
    let _ = writeln!(out, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" version="1.1" width="{w}" height="{h}" viewBox="0 0 {w} {h}">"#
    );
    let glyphs: BTreeSet<u16> = canvas
        .shapes()
        .iter()
        .filter_map(|s| match s {
            Shape::Text { text, scale, .. } => Some(font::placed_glyphs(text, *scale).0),
            _ => None,
        })
        .flatten()
        .map(|g| g.id)
        .collect();
    // Each glyph with an outline once; a space has none and is only an advance.
    let mut defined = BTreeSet::new();
    let _ = writeln!(out, "<defs>");
    for id in glyphs {
        if let Some(d) = font::outline_path(id) {
            let _ = writeln!(out, r#"<path id="g{id}" d="{d}"/>"#);
            defined.insert(id);
        }
    }
    let _ = writeln!(out, "</defs>");
    for shape in canvas.shapes() {
        write_shape(&mut out, shape, (w as i64, h as i64), &defined);
    }
    let _ = writeln!(out, "</svg>");
    out
}

fn write_shape(out: &mut String, shape: &Shape, (w, h): (i64, i64), glyphs: &BTreeSet<u16>) {
    match shape {
        Shape::Rect {
            x,
            y,
            w: rw,
            h: rh,
            color,
        } => {
            // Clipped to the canvas: a marker far outside the plot adds nothing to the file.
            let (x0, y0) = ((*x).max(0), (*y).max(0));
            let (x1, y1) = ((x + rw).min(w), (y + rh).min(h));
            if x1 > x0 && y1 > y0 {
                let _ = writeln!(
                    out,
                    r#"<rect x="{x0}" y="{y0}" width="{}" height="{}" fill="{}" shape-rendering="crispEdges"/>"#,
                    x1 - x0,
                    y1 - y0,
                    hex(*color)
                );
            }
        }
        Shape::Line {
            from,
            to,
            color,
            dashes,
        } => write_line(out, *from, *to, *color, *dashes),
        Shape::Text {
            x,
            y,
            text,
            scale,
            color,
            vertical,
        } => {
            let turn = if *vertical { " rotate(-90)" } else { "" };
            let _ = writeln!(
                out,
                r#"<g fill="{}" transform="translate({x} {y}){turn}" aria-label="{}">"#,
                hex(*color),
                // The HTML pages' escaping serves XML attributes too (`&`, `<`, `>`, both quotes).
                crate::output::html::escape(text)
            );
            let (placed, k) = font::placed_glyphs(text, *scale);
            for g in placed {
                if glyphs.contains(&g.id) {
                    let _ = writeln!(
                        out,
                        r##"<use xlink:href="#g{}" transform="translate({} {}) scale({k:.7} {:.7})"/>"##,
                        g.id, g.x, g.y, -k
                    );
                }
            }
            let _ = writeln!(out, "</g>");
        }
        Shape::Image { x, y, image } => {
            let _ = writeln!(
                out,
                r#"<image x="{x}" y="{y}" width="{}" height="{}" preserveAspectRatio="none" image-rendering="pixelated" style="image-rendering:pixelated" xlink:href="data:image/png;base64,{}"/>"#,
                image.width(),
                image.height(),
                crate::output::base64(&image.to_png())
            );
        }
    }
}

/// A one-pixel line through the pixel centres `from` and `to`, reaching half a pixel past both as the
/// pixels do; a dashed line keeps the PNG's pattern (4 pixels on, 4 off, counted along its longer side).
fn write_line(out: &mut String, from: (i64, i64), to: (i64, i64), color: Rgb, dashes: Option<i64>) {
    let (dx, dy) = ((to.0 - from.0) as f64, (to.1 - from.1) as f64);
    let steps = dx.abs().max(dy.abs());
    if steps == 0.0 {
        let _ = writeln!(
            out,
            r#"<rect x="{}" y="{}" width="1" height="1" fill="{}" shape-rendering="crispEdges"/>"#,
            from.0,
            from.1,
            hex(color)
        );
        return;
    }
    // A step along the longer side, in user units along the line.
    let (ux, uy) = (dx / steps, dy / steps);
    let (x0, y0) = (from.0 as f64 + 0.5 - ux / 2.0, from.1 as f64 + 0.5 - uy / 2.0);
    let (x1, y1) = (to.0 as f64 + 0.5 + ux / 2.0, to.1 as f64 + 0.5 + uy / 2.0);
    let dash = match dashes {
        Some(skipped) => {
            let step = ux.hypot(uy);
            format!(
                r#" stroke-dasharray="{:.3} {:.3}" stroke-dashoffset="{:.3}""#,
                4.0 * step,
                4.0 * step,
                skipped as f64 * step
            )
        }
        None => String::new(),
    };
    let _ = writeln!(
        out,
        r#"<line x1="{x0:.3}" y1="{y0:.3}" x2="{x1:.3}" y2="{y1:.3}" stroke="{}" stroke-width="1"{dash}/>"#,
        hex(color)
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figures::canvas::{BLACK, WHITE};

    #[test]
    fn shapes_become_vectors_and_frozen_pixels_an_image() {
        let mut c = Canvas::new(40, 30, WHITE);
        for x in 0..10 {
            c.set(x + 5, 5, BLACK);
        }
        c.fill_rect(5, 6, 3, 3, BLACK);
        c.freeze(5, 5, 10, 10);
        c.line(0, 20, 39, 20, BLACK);
        c.dashed_line(0, 25, 39, 25, [255, 0, 0]);
        c.text(2, 2, "x [m]", 1, BLACK);
        c.text_vertical(2, 28, "y", 1, BLACK);
        c.fill_rect(-1000, -1000, 5, 5, BLACK);
        let svg = to_svg(&c);
        assert!(svg.starts_with("<?xml"));
        assert_eq!(svg.matches("<image ").count(), 1, "{svg}");
        // The rectangle inside the frozen block is in the image, not drawn twice.
        assert_eq!(svg.matches("<rect ").count(), 1, "only the background: {svg}");
        assert_eq!(svg.matches("<line ").count(), 2);
        assert!(svg.contains("stroke-dasharray"));
        assert!(svg.contains(r#"aria-label="x [m]""#));
        assert!(svg.contains("rotate(-90)"));
        // "x [m]" uses 4 glyphs with outlines ("x", "[", "m", "]"); "y" one more, each defined once.
        assert_eq!(svg.matches("<path id=").count(), 5, "{svg}");
        assert_eq!(svg.matches("<use ").count(), 5);
        assert_eq!(svg, to_svg(&c.clone()), "deterministic");
    }

    #[test]
    fn a_horizontal_line_covers_its_pixels() {
        let mut c = Canvas::new(10, 10, WHITE);
        c.line(2, 3, 6, 3, BLACK);
        let svg = to_svg(&c);
        // From the left edge of pixel 2 to the right edge of pixel 6, through the row's centre.
        assert!(
            svg.contains(r#"<line x1="2.000" y1="3.500" x2="7.000" y2="3.500""#),
            "{svg}"
        );
    }

    #[test]
    fn glyph_outlines_sit_where_the_pixels_are() {
        // The outline of "H" placed by the SVG's transform covers the inked pixels of the PNG.
        let (placed, k) = font::placed_glyphs("H", 1);
        let (gx, gy) = (placed[0].x, placed[0].y);
        let d = font::outline_path(placed[0].id).expect("H has an outline");
        let numbers: Vec<f32> = d
            .split(|ch: char| ch.is_ascii_alphabetic() || ch == ' ')
            .filter_map(|n| n.parse().ok())
            .collect();
        let xs = numbers.iter().step_by(2).map(|x| gx + x * k);
        let ys = numbers.iter().skip(1).step_by(2).map(|y| gy - y * k);
        let (min_x, max_x) = xs.fold((f32::MAX, f32::MIN), |(a, b), v| (a.min(v), b.max(v)));
        let (min_y, max_y) = ys.fold((f32::MAX, f32::MIN), |(a, b), v| (a.min(v), b.max(v)));
        let mut inked = (i64::MAX, i64::MAX, i64::MIN, i64::MIN);
        font::rasterize("H", 1, |x, y, c| {
            if c > 0.5 {
                inked = (inked.0.min(x), inked.1.min(y), inked.2.max(x), inked.3.max(y));
            }
        });
        assert!((min_x - inked.0 as f32).abs() <= 1.0, "{min_x} vs {inked:?}");
        assert!(
            (max_x - (inked.2 + 1) as f32).abs() <= 1.0,
            "{max_x} vs {inked:?}"
        );
        assert!((min_y - inked.1 as f32).abs() <= 1.0, "{min_y} vs {inked:?}");
        assert!(
            (max_y - (inked.3 + 1) as f32).abs() <= 1.0,
            "{max_y} vs {inked:?}"
        );
    }
}
