//! Text: DejaVu Sans (regular and bold, subset to Latin-1, Greek and a few
//! symbols) rasterised with `ab_glyph`, anti-aliased by glyph coverage.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};

use crate::image::RgbImage;

/// DejaVu Sans, subset (see `assets/fonts/README.md`).
pub(crate) static REGULAR_BYTES: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");
/// DejaVu Sans Bold, subset.
pub(crate) static BOLD_BYTES: &[u8] = include_bytes!("../assets/fonts/DejaVuSans-Bold.ttf");

/// Regular or bold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Weight {
    Regular,
    Bold,
}

fn font(w: Weight) -> FontRef<'static> {
    let bytes = match w {
        Weight::Regular => REGULAR_BYTES,
        Weight::Bold => BOLD_BYTES,
    };
    FontRef::try_from_slice(bytes).expect("the embedded font parses (checked by a test)")
}

/// Horizontal anchor of a text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Align {
    Left,
    Center,
}

/// Width of `text` at `px` pixels, in pixels.
pub(crate) fn width(text: &str, px: f32, w: Weight) -> f32 {
    let f = font(w);
    let sf = f.as_scaled(PxScale::from(px));
    let mut x = 0.0;
    let mut prev = None;
    for c in text.chars() {
        let g = sf.glyph_id(c);
        if let Some(p) = prev {
            x += sf.kern(p, g);
        }
        x += sf.h_advance(g);
        prev = Some(g);
    }
    x
}

/// Ascent (above the baseline) at `px`, pixels.
pub(crate) fn ascent(px: f32) -> f32 {
    font(Weight::Regular).as_scaled(PxScale::from(px)).ascent()
}

/// Size, weight and colour of a text.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pen {
    /// Size: pixels per em.
    pub px: f32,
    pub weight: Weight,
    pub color: [u8; 3],
}

/// Draws `text` with its baseline at `y` and its anchor at `x`.
pub(crate) fn draw(img: &mut RgbImage, text: &str, (x, y): (f32, f32), pen: &Pen, align: Align) {
    let Pen {
        px,
        weight: w,
        color,
    } = *pen;
    let f = font(w);
    let sf = f.as_scaled(PxScale::from(px));
    let tw = width(text, px, w);
    let mut pen = match align {
        Align::Left => x,
        Align::Center => x - 0.5 * tw,
    };
    let mut prev = None;
    for c in text.chars() {
        let id = sf.glyph_id(c);
        if let Some(p) = prev {
            pen += sf.kern(p, id);
        }
        let glyph = id.with_scale_and_position(PxScale::from(px), point(pen, y));
        if let Some(outline) = f.outline_glyph(glyph) {
            let b = outline.px_bounds();
            outline.draw(|gx, gy, cov| {
                img.blend(
                    b.min.x as i64 + gx as i64,
                    b.min.y as i64 + gy as i64,
                    color,
                    cov,
                );
            });
        }
        pen += sf.h_advance(id);
        prev = Some(id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fonts_parse_and_cover_the_symbols_used() {
        for w in [Weight::Regular, Weight::Bold] {
            let f = font(w);
            for c in "t = 0.1450 s −×²³σ·–—…µ°()[]".chars() {
                assert_ne!(f.glyph_id(c).0, 0, "{c:?} missing");
            }
        }
        assert!(width("abc", 20.0, Weight::Regular) > 20.0);
    }

    #[test]
    fn draws_dark_pixels() {
        let mut img = RgbImage::new(60, 30);
        let pen = Pen {
            px: 20.0,
            weight: Weight::Bold,
            color: [0, 0, 0],
        };
        draw(&mut img, "Hi", (5.0, 22.0), &pen, Align::Left);
        assert!(img.data.iter().any(|&v| v < 50));
    }
}
