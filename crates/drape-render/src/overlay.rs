//! Outlines drawn over a single-frame figure: circles given in scene
//! coordinates (a drape tester's pedestal and specimen, the picture a
//! laboratory takes of the shadow), stroked anti-aliased on top of the
//! fabric, whatever hides them.

use crate::geom::{V3, add, basis, normalize, scale};
use crate::image::RgbImage;

/// A circle in the scene, drawn over single frames and animations.
#[derive(Debug, Clone, PartialEq)]
pub struct Circle {
    /// Centre (m).
    pub center: [f64; 3],
    /// Normal of its plane, any length but not zero.
    pub normal: [f64; 3],
    /// Radius (m), > 0.
    pub radius: f64,
    /// Colour of the line.
    pub color: [u8; 3],
    /// Dashed instead of solid.
    pub dashed: bool,
}

/// Points round a circle: enough for a smooth outline at any figure size.
const SEGMENTS: usize = 720;

impl Circle {
    /// Whether it can be drawn: a finite centre, a positive finite radius
    /// and a normal that is a direction.
    pub(crate) fn is_valid(&self) -> bool {
        let n = self.normal;
        let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        self.center.iter().all(|c| c.is_finite())
            && self.radius.is_finite()
            && self.radius > 0.0
            && length.is_finite()
            && length > 0.0
    }

    /// [`SEGMENTS`] points round the circle (the first not repeated).
    pub(crate) fn points(&self) -> Vec<V3> {
        let (e1, e2) = basis(normalize(self.normal));
        (0..SEGMENTS)
            .map(|j| {
                let t = std::f64::consts::TAU * j as f64 / SEGMENTS as f64;
                add(
                    self.center,
                    add(
                        scale(e1, self.radius * t.cos()),
                        scale(e2, self.radius * t.sin()),
                    ),
                )
            })
            .collect()
    }
}

/// Strokes the closed polyline through the pixel positions `pts` on `img`,
/// `width` pixels wide, solid or in dashes of `3 width` with gaps of
/// `2 width`. Each pixel is blended once, with its largest coverage
/// `clamp(width / 2 + 1/2 − d, 0, 1)`, `d` its centre's distance to the
/// line.
pub(crate) fn stroke(
    img: &mut RgbImage,
    pts: &[(f64, f64)],
    color: [u8; 3],
    width: f64,
    dashed: bool,
) {
    let (w, h) = (img.width as usize, img.height as usize);
    if pts.len() < 2 || w == 0 || h == 0 {
        return;
    }
    let mut coverage = vec![0f32; w * h];
    let half = 0.5 * width;
    let (on, period) = (3.0 * width, 5.0 * width);
    let mut along = 0.0;
    for i in 0..pts.len() {
        let (p, q) = (pts[i], pts[(i + 1) % pts.len()]);
        let (dx, dy) = (q.0 - p.0, q.1 - p.1);
        let length = dx.hypot(dy);
        if !length.is_finite() {
            continue;
        }
        let reach = half + 1.0;
        let x0 = (p.0.min(q.0) - reach).floor().max(0.0) as usize;
        let x1 = ((p.0.max(q.0) + reach).ceil().max(0.0) as usize).min(w);
        let y0 = (p.1.min(q.1) - reach).floor().max(0.0) as usize;
        let y1 = ((p.1.max(q.1) + reach).ceil().max(0.0) as usize).min(h);
        for y in y0..y1 {
            for x in x0..x1 {
                let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
                let s = if length > 0.0 {
                    (((cx - p.0) * dx + (cy - p.1) * dy) / (length * length)).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                if dashed && (along + s * length) % period > on {
                    continue;
                }
                let d = (cx - p.0 - s * dx).hypot(cy - p.1 - s * dy);
                let c = (half + 0.5 - d).clamp(0.0, 1.0) as f32;
                let slot = &mut coverage[y * w + x];
                *slot = slot.max(c);
            }
        }
        along += length;
    }
    for (i, &c) in coverage.iter().enumerate() {
        if c > 0.0 {
            img.blend((i % w) as i64, (i / w) as i64, color, c);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_lie_on_the_circle_in_its_plane() {
        let c = Circle {
            center: [0.1, 0.2, -0.05],
            normal: [0.0, 0.0, 2.0],
            radius: 0.09,
            color: [0, 0, 0],
            dashed: false,
        };
        assert!(c.is_valid());
        for p in c.points() {
            let r = (p[0] - 0.1).hypot(p[1] - 0.2);
            assert!((r - 0.09).abs() < 1e-15 && p[2] == -0.05);
        }
        assert!(
            !Circle {
                radius: 0.0,
                ..c.clone()
            }
            .is_valid()
        );
        assert!(
            !Circle {
                normal: [0.0; 3],
                ..c
            }
            .is_valid()
        );
    }

    #[test]
    fn a_stroke_covers_its_line_and_nothing_far_from_it() {
        let mut img = RgbImage::new(40, 40);
        let square = [(10.0, 10.0), (30.0, 10.0), (30.0, 30.0), (10.0, 30.0)];
        stroke(&mut img, &square, [0, 0, 0], 2.0, false);
        // On the line: black; at the centre and 3 px off: white.
        assert_eq!(img.get(20, 9), Some([0, 0, 0]));
        assert_eq!(img.get(20, 10), Some([0, 0, 0]));
        assert_eq!(img.get(20, 20), Some([255, 255, 255]));
        assert_eq!(img.get(20, 13), Some([255, 255, 255]));
        // Dashed: some of the line is left white.
        let mut dashed = RgbImage::new(40, 40);
        stroke(&mut dashed, &square, [0, 0, 0], 2.0, true);
        let row: Vec<[u8; 3]> = (10..30).filter_map(|x| dashed.get(x, 10)).collect();
        assert!(row.contains(&[0, 0, 0]) && row.contains(&[255, 255, 255]));
    }
}
