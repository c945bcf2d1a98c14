//! Small 3-vector helpers, triangulation of the obstacles and clipping of
//! triangles to a box.

use crate::scenario::{Obstacle, Shape};

pub(crate) type V3 = [f64; 3];

pub(crate) fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub(crate) fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
pub(crate) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
pub(crate) fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
pub(crate) fn normalize(a: V3) -> V3 {
    let n = norm(a);
    if n > 0.0 { scale(a, 1.0 / n) } else { a }
}
pub(crate) fn lerp(a: V3, b: V3, t: f64) -> V3 {
    add(a, scale(sub(b, a), t))
}

/// An axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Aabb {
    pub min: V3,
    pub max: V3,
}

impl Aabb {
    pub fn empty() -> Self {
        Self {
            min: [f64::INFINITY; 3],
            max: [f64::NEG_INFINITY; 3],
        }
    }
    pub fn add(&mut self, p: V3) {
        if p.iter().all(|x| x.is_finite()) {
            for (k, &v) in p.iter().enumerate() {
                self.min[k] = self.min[k].min(v);
                self.max[k] = self.max[k].max(v);
            }
        }
    }
    pub fn is_empty(&self) -> bool {
        self.min[0] > self.max[0]
    }
    pub fn center(&self) -> V3 {
        scale(add(self.min, self.max), 0.5)
    }
    pub fn extent(&self) -> V3 {
        sub(self.max, self.min)
    }
    pub fn diagonal(&self) -> f64 {
        norm(self.extent())
    }
    /// Grown by `m` on every side.
    pub fn grown(&self, m: f64) -> Aabb {
        Aabb {
            min: sub(self.min, [m; 3]),
            max: add(self.max, [m; 3]),
        }
    }
}

/// A flat triangle with its outward normal (for shading).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Tri {
    pub p: [V3; 3],
    pub n: V3,
}

fn quad(out: &mut Vec<Tri>, a: V3, b: V3, c: V3, d: V3) {
    let n = normalize(cross(sub(b, a), sub(d, a)));
    out.push(Tri { p: [a, b, c], n });
    out.push(Tri { p: [a, c, d], n });
}

/// Orthonormal vectors perpendicular to `axis` (unit).
pub(crate) fn basis(axis: V3) -> (V3, V3) {
    let helper = if axis[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let u = normalize(cross(axis, helper));
    let v = cross(axis, u);
    (u, v)
}

/// Triangles of `obstacle` at time `t`, clipped to `region`. A plane is
/// drawn as its part inside `region`.
pub(crate) fn obstacle_triangles(obstacle: &Obstacle, t: f64, region: &Aabb) -> Vec<Tri> {
    let shift = scale(obstacle.velocity, t);
    let mut tris = Vec::new();
    match obstacle.shape {
        Shape::Plane { point, normal } => {
            let n = normalize(normal);
            let p = add(point, shift);
            // The plane point nearest the region's centre, and a square
            // larger than the region around it.
            let c = region.center();
            let c = sub(c, scale(n, dot(sub(c, p), n)));
            let (u, v) = basis(n);
            let h = region.diagonal().max(1e-9) * 2.0;
            let corner = |a: f64, b: f64| add(c, add(scale(u, a * h), scale(v, b * h)));
            quad(
                &mut tris,
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(1.0, 1.0),
                corner(-1.0, 1.0),
            );
            // Subdivide so that the clipped polygon's triangles stay small
            // (not needed for correctness, kept simple).
        }
        Shape::Box { min, max } => {
            let a = add(min, shift);
            let b = add(max, shift);
            let v = |i: usize, j: usize, k: usize| {
                [
                    if i == 0 { a[0] } else { b[0] },
                    if j == 0 { a[1] } else { b[1] },
                    if k == 0 { a[2] } else { b[2] },
                ]
            };
            quad(&mut tris, v(0, 0, 1), v(1, 0, 1), v(1, 1, 1), v(0, 1, 1)); // top
            quad(&mut tris, v(0, 0, 0), v(0, 1, 0), v(1, 1, 0), v(1, 0, 0)); // bottom
            quad(&mut tris, v(0, 0, 0), v(1, 0, 0), v(1, 0, 1), v(0, 0, 1)); // -y
            quad(&mut tris, v(1, 1, 0), v(0, 1, 0), v(0, 1, 1), v(1, 1, 1)); // +y
            quad(&mut tris, v(0, 1, 0), v(0, 0, 0), v(0, 0, 1), v(0, 1, 1)); // -x
            quad(&mut tris, v(1, 0, 0), v(1, 1, 0), v(1, 1, 1), v(1, 0, 1)); // +x
        }
        Shape::Sphere { center, radius } => {
            let c = add(center, shift);
            let (nu, nv) = (64usize, 32usize);
            let pt = |i: usize, j: usize| {
                let phi = std::f64::consts::TAU * i as f64 / nu as f64;
                let th = std::f64::consts::PI * j as f64 / nv as f64;
                [th.sin() * phi.cos(), th.sin() * phi.sin(), th.cos()]
            };
            for i in 0..nu {
                for j in 0..nv {
                    let ps = [pt(i, j), pt(i + 1, j), pt(i + 1, j + 1), pt(i, j + 1)];
                    let w = ps.map(|d| add(c, scale(d, radius)));
                    // Smooth-ish: flat normal at the quad's centre direction.
                    let n = normalize(add(add(ps[0], ps[1]), add(ps[2], ps[3])));
                    if j != 0 {
                        tris.push(Tri {
                            p: [w[0], w[2], w[1]],
                            n,
                        });
                    }
                    if j != nv - 1 {
                        tris.push(Tri {
                            p: [w[0], w[3], w[2]],
                            n,
                        });
                    }
                }
            }
        }
        Shape::Cylinder {
            center,
            axis,
            radius,
            height,
        } => {
            let a = normalize(axis);
            let top = add(center, shift);
            let bottom = sub(top, scale(a, height));
            let (u, v) = basis(a);
            let seg = 96usize;
            let dir = |i: usize| {
                let phi = std::f64::consts::TAU * i as f64 / seg as f64;
                add(scale(u, phi.cos()), scale(v, phi.sin()))
            };
            for i in 0..seg {
                let (d0, d1) = (dir(i), dir(i + 1));
                let t0 = add(top, scale(d0, radius));
                let t1 = add(top, scale(d1, radius));
                let b0 = add(bottom, scale(d0, radius));
                let b1 = add(bottom, scale(d1, radius));
                let n = normalize(add(d0, d1));
                tris.push(Tri { p: [b0, b1, t1], n });
                tris.push(Tri { p: [b0, t1, t0], n });
                tris.push(Tri {
                    p: [top, t0, t1],
                    n: a,
                });
                tris.push(Tri {
                    p: [bottom, b1, b0],
                    n: scale(a, -1.0),
                });
            }
        }
    }
    let mut out = Vec::with_capacity(tris.len());
    for t in tris {
        clip_triangle(&t, region, &mut out);
    }
    out
}

/// Clips `t` to `b` (Sutherland–Hodgman against the six faces) and appends
/// the fan triangulation of what is left.
pub(crate) fn clip_triangle(t: &Tri, b: &Aabb, out: &mut Vec<Tri>) {
    let inside_all =
        t.p.iter()
            .all(|p| (0..3).all(|k| p[k] >= b.min[k] && p[k] <= b.max[k]));
    if inside_all {
        out.push(*t);
        return;
    }
    let mut poly: Vec<V3> = t.p.to_vec();
    for k in 0..3 {
        for (bound, keep_above) in [(b.min[k], true), (b.max[k], false)] {
            if poly.is_empty() {
                return;
            }
            let inside = |p: &V3| {
                if keep_above {
                    p[k] >= bound
                } else {
                    p[k] <= bound
                }
            };
            let mut next = Vec::with_capacity(poly.len() + 2);
            for i in 0..poly.len() {
                let a = poly[i];
                let c = poly[(i + 1) % poly.len()];
                let (ia, ic) = (inside(&a), inside(&c));
                if ia {
                    next.push(a);
                }
                if ia != ic {
                    let s = (bound - a[k]) / (c[k] - a[k]);
                    let mut p = lerp(a, c, s);
                    p[k] = bound;
                    next.push(p);
                }
            }
            poly = next;
        }
    }
    if poly.len() < 3 {
        return;
    }
    for i in 1..poly.len() - 1 {
        out.push(Tri {
            p: [poly[0], poly[i], poly[i + 1]],
            n: t.n,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_keeps_area_inside() {
        let t = Tri {
            p: [[-1.0, -1.0, 0.0], [3.0, -1.0, 0.0], [-1.0, 3.0, 0.0]],
            n: [0.0, 0.0, 1.0],
        };
        let b = Aabb {
            min: [0.0, 0.0, -1.0],
            max: [1.0, 1.0, 1.0],
        };
        let mut out = Vec::new();
        clip_triangle(&t, &b, &mut out);
        let area: f64 = out
            .iter()
            .map(|t| 0.5 * norm(cross(sub(t.p[1], t.p[0]), sub(t.p[2], t.p[0]))))
            .sum();
        assert!((area - 1.0).abs() < 1e-12, "{area}");
    }

    #[test]
    fn box_is_clipped_to_region() {
        let o = Obstacle {
            shape: Shape::Box {
                min: [-0.05, -0.05, -0.25],
                max: [0.05, 0.05, -0.05],
            },
            velocity: [0.0; 3],
        };
        let region = Aabb {
            min: [-1.0, -1.0, -0.1],
            max: [1.0, 1.0, 1.0],
        };
        let tris = obstacle_triangles(&o, 0.0, &region);
        assert!(
            tris.iter()
                .all(|t| t.p.iter().all(|p| p[2] >= -0.1 - 1e-12))
        );
        assert!(!tris.is_empty());
    }
}
