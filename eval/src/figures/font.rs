//! The figures' typeface: DejaVu Sans, embedded in the program (a subset of its Latin, Greek and symbol
//! glyphs, `eval/assets/fonts/`), drawn anti-aliased with `ab_glyph`. No system font is ever read, so the same
//! text gives the same pixels on every machine.

use std::sync::OnceLock;

use ab_glyph::{Font as _, FontRef, GlyphId, PxScale, ScaleFont as _, point};

/// The embedded font file: DejaVu Sans 2.37, subset (`eval/assets/fonts/README.md`). Its licence is
/// `eval/assets/fonts/LICENSE-DejaVu.txt`.
pub(crate) const FONT_FILE: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-subset.ttf");

fn font() -> &'static FontRef<'static> {
    static FONT: OnceLock<FontRef<'static>> = OnceLock::new();
    FONT.get_or_init(|| {
        // The file is part of the program and is checked by a test; it cannot fail to parse.
        FontRef::try_from_slice(FONT_FILE).expect("the embedded font parses")
    })
}

/// The text size of a `scale`, as `ab_glyph` measures it (the line's height, ascent to descent, in pixels;
/// an em is 0.86 of it): 1 for labels and ticks (an em of 13 pixels), 2 for titles.
pub(crate) fn size_px(scale: usize) -> f32 {
    match scale {
        0 | 1 => 15.0,
        2 => 22.0,
        s => 11.0 * s as f32,
    }
}

/// The height of a line of text at `scale`, pixels: the font's ascent to its descent.
pub(crate) fn line_height(scale: usize) -> usize {
    let f = font().as_scaled(PxScale::from(size_px(scale)));
    (f.ascent() - f.descent()).ceil() as usize
}

/// Each glyph of `text` at `scale` with where it starts (pixels from the line's start, advances and kerning),
/// and where the line ends.
fn layout(text: &str, scale: usize) -> (Vec<(GlyphId, f32)>, f32) {
    let f = font().as_scaled(PxScale::from(size_px(scale)));
    let mut caret = 0.0_f32;
    let mut previous = None;
    let mut glyphs = Vec::with_capacity(text.len());
    for ch in text.chars() {
        let id = f.glyph_id(ch);
        if let Some(p) = previous {
            caret += f.kern(p, id);
        }
        glyphs.push((id, caret));
        caret += f.h_advance(id);
        previous = Some(id);
    }
    (glyphs, caret)
}

/// The width of `text` at `scale`, pixels (advances and kerning).
pub(crate) fn width(text: &str, scale: usize) -> usize {
    layout(text, scale).1.ceil() as usize
}

/// A glyph where a line of text draws it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PlacedGlyph {
    /// The glyph's id in the embedded font.
    pub id: u16,
    /// Its outline's origin (on the baseline), pixels right of the line's left edge.
    pub x: f32,
    /// Its outline's origin, pixels below the line's top.
    pub y: f32,
}

/// Where each glyph of `text` at `scale` is drawn, with the pixels per font unit. [`rasterize`] places
/// glyphs the same way.
pub(crate) fn placed_glyphs(text: &str, scale: usize) -> (Vec<PlacedGlyph>, f32) {
    let f = font().as_scaled(PxScale::from(size_px(scale)));
    let baseline = f.ascent().round();
    let glyphs = layout(text, scale)
        .0
        .into_iter()
        .map(|(id, caret)| PlacedGlyph {
            id: id.0,
            x: caret.round(),
            y: baseline,
        })
        .collect();
    (glyphs, f.h_scale_factor())
}

/// The outline of glyph `id` as SVG path data, in font units with y pointing up; `None` for a glyph with
/// no outline (a space).
pub(crate) fn outline_path(id: u16) -> Option<String> {
    use ab_glyph::OutlineCurve::{Cubic, Line, Quad};
    use std::fmt::Write as _;
    let outline = font().outline(GlyphId(id))?;
    let mut d = String::new();
    let mut at: Option<ab_glyph::Point> = None;
    for curve in &outline.curves {
        let start = match curve {
            Line(a, _) | Quad(a, _, _) | Cubic(a, _, _, _) => *a,
        };
        if at != Some(start) {
            if at.is_some() {
                d.push('Z');
            }
            let _ = write!(d, "M{} {}", start.x, start.y);
        }
        // Writing into a String cannot fail.
        let _ = match curve {
            Line(_, b) => write!(d, "L{} {}", b.x, b.y),
            Quad(_, c, b) => write!(d, "Q{} {} {} {}", c.x, c.y, b.x, b.y),
            Cubic(_, c1, c2, b) => write!(d, "C{} {} {} {} {} {}", c1.x, c1.y, c2.x, c2.y, b.x, b.y),
        };
        at = Some(match curve {
            Line(_, b) | Quad(_, _, b) | Cubic(_, _, _, b) => *b,
        });
    }
    if at.is_some() {
        d.push('Z');
    }
    Some(d)
}

/// Calls `coverage(x, y, c)` for each pixel of `text` at `scale` with its coverage `c` in (0, 1], the line's
/// top-left corner at (0, 0). Characters the font lacks are drawn as its missing-glyph box.
pub(crate) fn rasterize(text: &str, scale: usize, mut coverage: impl FnMut(i64, i64, f32)) {
    let f = font().as_scaled(PxScale::from(size_px(scale)));
    for (id, caret) in layout(text, scale).0 {
        // Each glyph starts on a whole pixel, so the same letter looks the same wherever it falls.
        let glyph = id.with_scale_and_position(f.scale(), point(caret.round(), f.ascent().round()));
        if let Some(outline) = font().outline_glyph(glyph) {
            let b = outline.px_bounds();
            let (x0, y0) = (b.min.x as i64, b.min.y as i64);
            outline.draw(|gx, gy, c| {
                if c > 0.0 {
                    coverage(x0 + i64::from(gx), y0 + i64::from(gy), c.min(1.0));
                }
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_font_has_the_glyphs_the_figures_use() {
        for ch in "0123456789 abcxyz ABC [m] m^2 - + . , ( ) % ° ² σ µ ± ≤ ≥ – —".chars() {
            assert!(font().glyph_id(ch).0 != 0 || ch == ' ', "no glyph for {ch:?}");
        }
        assert!(width("mm", 1) > width("m", 1));
        assert!(line_height(2) > line_height(1));
    }

    #[test]
    fn text_is_anti_aliased() {
        let mut partial = 0;
        let mut full = 0;
        rasterize("Elevation [m]", 1, |_, _, c| {
            if c < 0.9 {
                partial += 1;
            } else {
                full += 1;
            }
        });
        assert!(partial > 20 && full > 20, "{partial} partial, {full} full pixels");
    }
}
