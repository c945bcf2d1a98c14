//! The colour bar beside a figure: the field's caption over its scale,
//! five labelled ticks from the bottom of the range to the top — or, for
//! the wrinkling state, a legend of the three states' colours.

use crate::colormap::{ColorMap, WRINKLE_COLOURS};
use crate::field::{Field, WRINKLE_STATES, format_value};
use crate::image::RgbImage;
use crate::render::Metrics;
use crate::text::{self, Align, Weight};

/// Text colour of the bar's caption and labels.
const DARK: [u8; 3] = [30, 30, 30];
/// Colour of the bar's frame, its ticks and the legend's swatch borders.
const GREY: [u8; 3] = [90, 90, 90];

/// The colour bar of `field` over `range`, coloured by `cmap`.
pub(crate) struct Colorbar<'a> {
    pub(crate) field: Field,
    /// The scale's bottom and top.
    pub(crate) range: (f64, f64),
    pub(crate) cmap: &'a ColorMap,
}

impl Colorbar<'_> {
    /// The labels from the bottom of the scale to the top (the states, for
    /// the wrinkling state): five, or the two ends of an empty range.
    pub(crate) fn labels(&self) -> Vec<String> {
        if self.field.is_categorical() {
            return WRINKLE_STATES.iter().map(|s| (*s).to_owned()).collect();
        }
        let (a, b) = self.range;
        if a == b {
            return vec![format_value(a), format_value(b)];
        }
        (0..=4)
            .map(|k| match k {
                0 => format_value(a),
                4 => format_value(b),
                _ => format_value(a + (b - a) * k as f64 / 4.0),
            })
            .collect()
    }

    /// Width of the band the bar takes at the figure's right.
    pub(crate) fn band_width(&self, m: &Metrics) -> f32 {
        let lw = self
            .labels()
            .iter()
            .map(|l| text::width(l, m.label_px, Weight::Regular))
            .fold(0.0, f32::max);
        let bar = (m.label_px * 1.2).round();
        let caption = text::width(&self.field.label(), m.label_px, Weight::Bold);
        m.pad + caption.max(bar + m.label_px * 0.8 + lw) + m.pad
    }

    /// Draws the bar (or the legend) in the band starting at `x0`,
    /// vertically centred on `[y0, y1]`.
    pub(crate) fn draw(&self, img: &mut RgbImage, m: &Metrics, x0: f32, y0: f32, y1: f32) {
        let bx = (x0 + m.pad).round();
        if self.field.is_categorical() {
            self.draw_legend(img, m, bx, 0.5 * (y0 + y1));
        } else {
            self.draw_scale(img, m, bx, y0, y1);
        }
    }

    /// The wrinkling states' legend at `bx`, centred on `middle`: the
    /// caption, then a framed swatch and the name of each state.
    fn draw_legend(&self, img: &mut RgbImage, m: &Metrics, bx: f32, middle: f32) {
        let row = m.label_px * 1.8;
        let total = m.label_px * 1.6 + row * WRINKLE_STATES.len() as f32;
        let mut y = middle - 0.5 * total;
        label(
            img,
            m,
            &self.field.label(),
            (bx, y + m.label_px),
            Weight::Bold,
        );
        y += m.label_px * 1.6;
        for (k, name) in WRINKLE_STATES.iter().enumerate() {
            let sw = m.label_px * 1.1;
            let top = y + 0.2 * row;
            img.fill_rect(
                bx as i64 - 1,
                top as i64 - 1,
                sw as i64 + 2,
                sw as i64 + 2,
                GREY,
            );
            img.fill_rect(
                bx as i64,
                top as i64,
                sw as i64,
                sw as i64,
                WRINKLE_COLOURS[k],
            );
            let at = (
                bx + sw + m.label_px * 0.6,
                top + sw * 0.5 + text::ascent(m.label_px) * 0.38,
            );
            label(img, m, name, at, Weight::Regular);
            y += row;
        }
    }

    /// The continuous scale at `bx` in `[y0, y1]`: the caption, the
    /// colour gradient in a frame, and the labelled ticks.
    fn draw_scale(&self, img: &mut RgbImage, m: &Metrics, bx: f32, y0: f32, y1: f32) {
        let bw = (m.label_px * 1.2).round();
        let h = ((y1 - y0) * 0.62).max(40.0);
        let top = (0.5 * (y0 + y1) - 0.5 * h + m.label_px).round();
        let bottom = (top + h).round();
        let caption = self.field.label();
        label(img, m, &caption, (bx, top - m.label_px * 0.9), Weight::Bold);
        for y in top as i64..bottom as i64 {
            let t = (bottom as f64 - 0.5 - y as f64) / (bottom - top - 1.0).max(1.0) as f64;
            img.fill_rect(bx as i64, y, bw as i64, 1, self.cmap.color_at_fraction(t));
        }
        frame(img, (bx, top), (bw, bottom - top));
        let labels = self.labels();
        let n = labels.len();
        for (k, value) in labels.iter().enumerate() {
            let frac = if n > 1 {
                k as f32 / (n - 1) as f32
            } else {
                0.5
            };
            let y = bottom - 0.5 - frac * (bottom - top - 1.0);
            let tick = (m.label_px * 0.3).round() as i64;
            img.fill_rect((bx + bw) as i64, y.round() as i64, tick, 1, GREY);
            let at = (
                bx + bw + m.label_px * 0.6,
                y + text::ascent(m.label_px) * 0.36,
            );
            label(img, m, value, at, Weight::Regular);
        }
    }
}

/// A one-pixel frame just outside the rectangle at `(x, y)` of size
/// `(w, h)`.
fn frame(img: &mut RgbImage, (x, y): (f32, f32), (w, h): (f32, f32)) {
    img.fill_rect(x as i64 - 1, y as i64 - 1, w as i64 + 2, 1, GREY);
    img.fill_rect(x as i64 - 1, (y + h) as i64, w as i64 + 2, 1, GREY);
    img.fill_rect(x as i64 - 1, y as i64 - 1, 1, h as i64 + 2, GREY);
    img.fill_rect((x + w) as i64, y as i64 - 1, 1, h as i64 + 2, GREY);
}

/// `text` at `at` in the bar's label size and colour.
fn label(img: &mut RgbImage, m: &Metrics, text: &str, at: (f32, f32), weight: Weight) {
    let pen = text::Pen {
        px: m.label_px,
        weight,
        color: DARK,
    };
    text::draw(img, text, at, &pen, Align::Left);
}
