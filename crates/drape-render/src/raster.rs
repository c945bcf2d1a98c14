//! Cameras (orthographic top and side, perspective oblique), projection and a
//! z-buffered triangle rasteriser that draws into a supersampled buffer which
//! is then box-filtered down (anti-aliased edges).
//!
//! No crate does this well for our case — plotters' 3-D charts sort
//! triangles (painter's algorithm) and have no z-buffer — so it is written
//! here: edge functions over each triangle's pixel bounding box, depth and
//! attributes interpolated perspective-correctly, two-sided Lambert shading
//! with a light at the camera.

use crate::colormap::ColorMap;
use crate::geom::{Aabb, V3, cross, dot, normalize, scale, sub};
use crate::image::RgbImage;

/// The direction the figure is seen from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum View {
    /// Orthographic, from above (+z), x to the right, y up.
    Top,
    /// Orthographic, from the front (−y), x to the right, z up.
    Side,
    /// Perspective, from an elevated oblique angle (azimuth −55° from +x,
    /// elevation 35°).
    #[default]
    Perspective,
}

impl View {
    /// Every view, in the order of the help text.
    pub const ALL: [View; 3] = [View::Top, View::Side, View::Perspective];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            View::Top => "top",
            View::Side => "side",
            View::Perspective => "perspective",
        }
    }
}

impl std::str::FromStr for View {
    type Err = crate::RenderError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        View::ALL
            .into_iter()
            .find(|v| v.name() == s)
            .ok_or_else(|| {
                crate::RenderError::InvalidOption(format!(
                    "unknown view {s:?}; the views are top, side, perspective"
                ))
            })
    }
}

// The command line's `--view`, by [`View::name`].
#[cfg(feature = "clap")]
crate::value_enum_by_name!(View);

impl std::fmt::Display for View {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A camera: orientation, eye (perspective) and the mapping of projected
/// coordinates to pixels of the supersampled buffer.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Camera {
    right: V3,
    up: V3,
    fwd: V3,
    origin: V3,
    perspective: bool,
    /// Pixel = (ox + s u, oy − s v).
    s: f64,
    ox: f64,
    oy: f64,
    /// Direction towards the light (unit).
    pub light: V3,
}

impl Camera {
    /// A camera looking at `region` from `view`; call [`Camera::fit`] before
    /// projecting to pixels.
    pub fn new(view: View, region: &Aabb) -> Self {
        let center = region.center();
        let radius = (region.diagonal() * 0.5).max(1e-12);
        let (fwd, right, up, perspective) = match view {
            View::Top => ([0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], false),
            View::Side => ([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], false),
            View::Perspective => {
                let (az, el) = (-55f64.to_radians(), 35f64.to_radians());
                let to_eye = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
                let fwd = scale(to_eye, -1.0);
                let right = normalize(cross(fwd, [0.0, 0.0, 1.0]));
                let up = cross(right, fwd);
                (fwd, right, up, true)
            }
        };
        let origin = if perspective {
            sub(center, scale(fwd, 3.2 * radius))
        } else {
            center
        };
        let light = if perspective {
            // From the camera, a little above and to the left.
            normalize(sub(sub(scale(up, 0.45), scale(right, 0.25)), fwd))
        } else {
            scale(fwd, -1.0)
        };
        Self {
            right,
            up,
            fwd,
            origin,
            perspective,
            s: 1.0,
            ox: 0.0,
            oy: 0.0,
            light,
        }
    }

    /// Projected coordinates `(u, v)` and view depth `f` (distance along the
    /// view direction) of `p`.
    pub fn project_uv(&self, p: V3) -> (f64, f64, f64) {
        let r = sub(p, self.origin);
        let (x, y, f) = (dot(r, self.right), dot(r, self.up), dot(r, self.fwd));
        if self.perspective {
            let f = f.max(1e-12);
            (x / f, y / f, f)
        } else {
            (x, y, f)
        }
    }

    /// Sets the pixel mapping so that the projected points `pts` fill the
    /// rectangle `(x0, y0, w, h)` (pixels of the buffer), centred, keeping
    /// the aspect ratio, with a small margin.
    pub fn fit(&mut self, pts: impl Iterator<Item = V3>, rect: (f64, f64, f64, f64)) {
        let (mut umin, mut umax, mut vmin, mut vmax) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for p in pts {
            let (u, v, _) = self.project_uv(p);
            if u.is_finite() && v.is_finite() {
                umin = umin.min(u);
                umax = umax.max(u);
                vmin = vmin.min(v);
                vmax = vmax.max(v);
            }
        }
        if umin > umax {
            (umin, umax, vmin, vmax) = (-1.0, 1.0, -1.0, 1.0);
        }
        let (x0, y0, w, h) = rect;
        let du = (umax - umin).max(1e-12);
        let dv = (vmax - vmin).max(1e-12);
        // A flat figure seen edge-on (a flat fabric from the side) gets the
        // scale of its width alone.
        let s = if dv < 1e-9 * du {
            w / du
        } else if du < 1e-9 * dv {
            h / dv
        } else {
            (w / du).min(h / dv)
        };
        self.s = 0.94 * s;
        self.ox = x0 + 0.5 * w - self.s * 0.5 * (umin + umax);
        self.oy = y0 + 0.5 * h + self.s * 0.5 * (vmin + vmax);
    }

    /// Screen vertex of `p` (pixels of the buffer).
    pub fn vertex(&self, p: V3, depth_bias: f64) -> ScreenVertex {
        let (u, v, f) = self.project_uv(p);
        let f = f + depth_bias;
        let (key, q) = if self.perspective {
            (1.0 / f, 1.0 / f)
        } else {
            (-f, 1.0)
        };
        ScreenVertex {
            x: self.ox + self.s * u,
            y: self.oy - self.s * v,
            key,
            q,
        }
    }
}

/// A projected vertex: pixel position, a depth key that is affine in screen
/// space (larger is nearer) and the perspective weight `q`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScreenVertex {
    pub x: f64,
    pub y: f64,
    pub key: f64,
    pub q: f64,
}

/// What a triangle is painted with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Paint {
    /// The fabric: the scalar is mapped through the colour map.
    Field,
    /// A grey obstacle.
    Obstacle,
}

/// A triangle ready to rasterise.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RasterTri {
    pub v: [ScreenVertex; 3],
    /// Scalar per vertex (equal for cell fields).
    pub s: [f64; 3],
    /// Normal per vertex (unit, any orientation: lighting is two-sided).
    pub n: [V3; 3],
    pub paint: Paint,
    /// Bit i set: the edge opposite vertex i is an element edge to outline.
    pub edges: u8,
}

/// The supersampled frame buffer.
pub(crate) struct Buffer {
    pub w: usize,
    pub h: usize,
    /// 0x00RRGGBB per pixel.
    color: Vec<u32>,
    depth: Vec<f32>,
}

const WHITE: u32 = 0x00ff_ffff;

fn pack(c: [f32; 3]) -> u32 {
    let b = c.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u32);
    (b[0] << 16) | (b[1] << 8) | b[2]
}

/// Shading and outline settings.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Style {
    pub shading: bool,
    /// Half the width of element outlines, in buffer pixels (0: none).
    pub edge_half_width: f64,
    pub light: V3,
}

const OBSTACLE_GREY: [f32; 3] = [0.70, 0.70, 0.70];
const EDGE_COLOUR: [f32; 3] = [0.08, 0.08, 0.08];
const EDGE_ALPHA: f32 = 0.45;

impl Buffer {
    pub fn new(w: usize, h: usize) -> Self {
        Self {
            w,
            h,
            color: vec![WHITE; w * h],
            depth: vec![f32::NEG_INFINITY; w * h],
        }
    }

    /// Resizes to `w` x `h` and clears to white, keeping the allocation.
    pub fn reset(&mut self, w: usize, h: usize) {
        self.w = w;
        self.h = h;
        self.color.clear();
        self.color.resize(w * h, WHITE);
        self.depth.clear();
        self.depth.resize(w * h, f32::NEG_INFINITY);
    }

    /// Rasterises `t` with depth test.
    pub fn draw(&mut self, t: &RasterTri, cmap: &ColorMap, style: &Style) {
        let [a, b, c] = t.v;
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area.abs() <= 1e-12 || !area.is_finite() {
            return;
        }
        let inv = 1.0 / area;
        let xmin = a.x.min(b.x).min(c.x).floor().max(0.0);
        let xmax = a.x.max(b.x).max(c.x).ceil().min(self.w as f64 - 1.0);
        let ymin = a.y.min(b.y).min(c.y).floor().max(0.0);
        let ymax = a.y.max(b.y).max(c.y).ceil().min(self.h as f64 - 1.0);
        if xmin > xmax || ymin > ymax {
            return;
        }
        // Altitudes (pixels) for the distance of a pixel to each edge.
        let len =
            |p: ScreenVertex, q: ScreenVertex| ((q.x - p.x).powi(2) + (q.y - p.y).powi(2)).sqrt();
        let alt = [
            area.abs() / len(b, c).max(1e-12),
            area.abs() / len(c, a).max(1e-12),
            area.abs() / len(a, b).max(1e-12),
        ];
        let hw = style.edge_half_width;
        for py in ymin as usize..=ymax as usize {
            let y = py as f64 + 0.5;
            for px in xmin as usize..=xmax as usize {
                let x = px as f64 + 0.5;
                let w0 = ((b.x - x) * (c.y - y) - (b.y - y) * (c.x - x)) * inv;
                let w1 = ((c.x - x) * (a.y - y) - (c.y - y) * (a.x - x)) * inv;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let key = (w0 * a.key + w1 * b.key + w2 * c.key) as f32;
                let idx = py * self.w + px;
                if key <= self.depth[idx] {
                    continue;
                }
                self.depth[idx] = key;
                // Perspective-correct weights.
                let (p0, p1, p2) = (w0 * a.q, w1 * b.q, w2 * c.q);
                let qs = p0 + p1 + p2;
                let (p0, p1, p2) = (p0 / qs, p1 / qs, p2 / qs);
                let base = match t.paint {
                    Paint::Field => cmap.color(p0 * t.s[0] + p1 * t.s[1] + p2 * t.s[2]),
                    Paint::Obstacle => OBSTACLE_GREY,
                };
                let shade = if style.shading {
                    let n = normalize([
                        p0 * t.n[0][0] + p1 * t.n[1][0] + p2 * t.n[2][0],
                        p0 * t.n[0][1] + p1 * t.n[1][1] + p2 * t.n[2][1],
                        p0 * t.n[0][2] + p1 * t.n[1][2] + p2 * t.n[2][2],
                    ]);
                    let d = dot(n, style.light).abs().min(1.0);
                    (0.40 + 0.60 * d) as f32
                } else {
                    1.0
                };
                let mut col = base.map(|ch| ch * shade);
                if hw > 0.0 && t.edges != 0 {
                    let ws = [w0, w1, w2];
                    let near = (0..3).any(|i| t.edges & (1 << i) != 0 && ws[i] * alt[i] < hw);
                    if near {
                        // Dark lines throughout (as ParaView draws them):
                        // switching to light lines on dark colours makes
                        // lines change colour halfway along.
                        for k in 0..3 {
                            col[k] = col[k] * (1.0 - EDGE_ALPHA) + EDGE_COLOUR[k] * EDGE_ALPHA;
                        }
                    }
                }
                self.color[idx] = pack(col);
            }
        }
    }

    /// Box-filters the buffer down by `factor` into `dst` at `(x0, y0)`.
    pub fn downsample_into(&self, factor: usize, dst: &mut RgbImage, x0: usize, y0: usize) {
        let (w, h) = (self.w / factor, self.h / factor);
        let n = (factor * factor) as u32;
        for y in 0..h {
            for x in 0..w {
                let mut acc = [0u32; 3];
                for sy in 0..factor {
                    let row = (y * factor + sy) * self.w + x * factor;
                    for &c in &self.color[row..row + factor] {
                        acc[0] += c >> 16;
                        acc[1] += (c >> 8) & 0xff;
                        acc[2] += c & 0xff;
                    }
                }
                dst.put(x0 + x, y0 + y, acc.map(|v| ((v + n / 2) / n) as u8));
            }
        }
    }
}
