//! Self-contact's barrier and its collision-free step (issue 33): the
//! Incremental Potential Contact barrier on the squared distance of a
//! point–triangle or edge–edge pair, its exact gradient and Hessian, and
//! additive continuous collision detection.
//!
//! **The barrier** (Li et al. 2020, "Incremental Potential Contact", eq. 6,
//! written in the squared distance as their code does): with `s = d^2`
//! and `ŝ = d̂^2` (`d̂` the self-contact distance),
//!
//! ```text
//! b(s) = -(s - ŝ)^2 ln(s / ŝ)                       for 0 < s < ŝ, else 0
//! b'(s) = -2 (s - ŝ) ln(s / ŝ) - (s - ŝ)^2 / s
//! b''(s) = -2 ln(s / ŝ) - 4 (s - ŝ) / s + (s - ŝ)^2 / s^2
//! ```
//!
//! twice continuously differentiable at `s = ŝ` (all three vanish there)
//! and infinite as `s -> 0`: a pair can come close but never touch. A
//! pair's energy is `kappa b(s(x))`, its gradient `kappa b' ∇s` and its
//! Hessian `kappa (b'' ∇s ∇sᵀ + b' ∇²s)`.
//!
//! **The squared distance's Hessian.** `s(x) = min_θ |r(x, θ)|^2` with
//! `r = sum_i w_i(θ) x_i` and weights affine in the free parameters `θ`
//! of the closest points' region (point–triangle: two on the face, one on
//! an edge, none at a vertex; edge–edge: `s` and `t` where they lie
//! strictly inside their edges). With `f(x, θ) = |r|^2`, the value
//! function's Hessian at a minimiser interior to the region is
//!
//! ```text
//! ∇²s = f_xx - f_xθ f_θθ^-1 f_θx,
//! f_xx = 2 w wᵀ ⊗ I_3,   f_θθ = 2 Dᵀ D,   (f_xθ)_{i k} = 2 (a_{k i} r + w_i D_k)
//! ```
//!
//! where `a_k = ∂w/∂θ_k` and `D_k = sum_i a_{k i} x_i` (the derivative of
//! the implicit minimiser, as in sensitivity analysis of a parametric
//! minimum). It is the exact Hessian wherever the region does not change,
//! which is everywhere but on the regions' borders (a set of measure
//! zero, where `s` is C¹). Two parallel edges (`Dᵀ D` singular) keep the
//! one parameter that still moves the closest point: there the distance
//! is not twice differentiable, as in every edge–edge barrier without a
//! mollifier (IPC adds one; drape does not yet).
//!
//! **Additive CCD** (Li, Kaufman & Jiang 2021, "Codimensional Incremental
//! Potential Contact", Algorithm 1): the pair's displacements are shifted
//! by their mean, `l_p` bounds how fast their distance can shrink
//! (point–triangle `max |p_0| + max_{1..3} |p_i|`, edge–edge
//! `max(|p_0|, |p_1|) + max(|p_2|, |p_3|)`), and the pair advances by
//! steps `(1 - σ) d / l_p` (then `0.9 d / l_p`), each provably shorter
//! than the time to touch, until the distance falls below `σ` times its
//! start or the step is taken whole. The fraction returned never lets the
//! pair touch: a conservative time of impact, without root finding.

use super::proximity::{Closest, edge_edge, point_triangle};
use crate::vec3::{add, dot, norm, scale, sub};

/// Which primitives a pair is, in the order of its four nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairKind {
    /// A node (first) against a triangle (the other three).
    PointTriangle,
    /// Edge `(x0, x1)` against edge `(x2, x3)`.
    EdgeEdge,
}

impl PairKind {
    /// The closest points of the pair at `x`.
    pub fn closest(self, x: &[[f64; 3]; 4]) -> Closest {
        match self {
            PairKind::PointTriangle => point_triangle(x[0], x[1], x[2], x[3]),
            PairKind::EdgeEdge => edge_edge(x[0], x[1], x[2], x[3]),
        }
    }

    /// `∂w/∂θ_k` of the free parameters of the closest points' region
    /// (module docs): at most two.
    fn directions(self, w: &[f64; 4]) -> Vec<[f64; 4]> {
        match self {
            PairKind::PointTriangle => {
                let free: Vec<usize> = (1..4).filter(|&i| w[i] != 0.0).collect();
                (free.iter().skip(1))
                    .map(|&k| {
                        let mut a = [0.0; 4];
                        a[free[0]] = 1.0;
                        a[k] = -1.0;
                        a
                    })
                    .collect()
            }
            PairKind::EdgeEdge => {
                let mut out = Vec::new();
                if w[1] > 0.0 && w[0] > 0.0 {
                    out.push([-1.0, 1.0, 0.0, 0.0]);
                }
                if w[3] < 0.0 && w[2] < 0.0 {
                    out.push([0.0, 0.0, 1.0, -1.0]);
                }
                out
            }
        }
    }
}

/// The squared distance `s`, its gradient (12, node-major) and Hessian
/// (12 x 12, row-major) at `x` (module docs).
pub fn squared_distance(kind: PairKind, x: &[[f64; 3]; 4]) -> (f64, [f64; 12], [f64; 144]) {
    let (s, g, h, _) = distance_parts(kind, x, &kind.closest(x));
    (s, g, h)
}

/// [`squared_distance`] and a set of 12-vectors spanning the range of its
/// Hessian and gradient (`w ⊗ e_a` for the three axes and the columns of
/// `f_xθ`, module docs): at most five, so that a pair's Hessian can be
/// projected in that subspace.
fn distance_parts(
    kind: PairKind,
    x: &[[f64; 3]; 4],
    c: &Closest,
) -> (f64, [f64; 12], [f64; 144], Vec<[f64; 12]>) {
    distance_parts_along(x, c, kind.directions(&c.weights))
}

/// The squared distance `s` of point `x[0]` to the plane of the triangle
/// `(x[1], x[2], x[3])`, its gradient (12, node-major) and Hessian (12 x
/// 12, row-major): the point–triangle distance's face region (module
/// docs) with the projection's barycentric coordinates left free of the
/// triangle's bounds. `None` for a triangle of no area.
pub fn point_plane_squared_distance(x: &[[f64; 3]; 4]) -> Option<(f64, [f64; 12], [f64; 144])> {
    let (u, v, p) = (sub(x[2], x[1]), sub(x[3], x[1]), sub(x[0], x[1]));
    let (uu, uv, vv, pu, pv) = (dot(u, u), dot(u, v), dot(v, v), dot(p, u), dot(p, v));
    let det = uu * vv - uv * uv;
    // Also refuses a NaN determinant.
    if det.is_nan() || det <= 1e-14 * uu * vv {
        return None;
    }
    let (b, c) = ((vv * pu - uv * pv) / det, (uu * pv - uv * pu) / det);
    let weights = [1.0, -(1.0 - b - c), -b, -c];
    let r = (0..4).fold([0.0; 3], |acc, i| add(acc, scale(x[i], weights[i])));
    let closest = Closest {
        d2: dot(r, r),
        weights,
    };
    let along = vec![[0.0, 1.0, -1.0, 0.0], [0.0, 1.0, 0.0, -1.0]];
    let (s, g, h, _) = distance_parts_along(x, &closest, along);
    Some((s, g, h))
}

/// [`distance_parts`] with the free parameters' directions `dirs` given.
fn distance_parts_along(
    x: &[[f64; 3]; 4],
    c: &Closest,
    mut dirs: Vec<[f64; 4]>,
) -> (f64, [f64; 12], [f64; 144], Vec<[f64; 12]>) {
    let w = c.weights;
    let r = (0..4).fold([0.0; 3], |acc, i| add(acc, scale(x[i], w[i])));
    let mut g = [0.0; 12];
    for i in 0..4 {
        for a in 0..3 {
            g[3 * i + a] = 2.0 * w[i] * r[a];
        }
    }
    let mut h = [0.0; 144];
    for i in 0..4 {
        for j in 0..4 {
            for a in 0..3 {
                h[(3 * i + a) * 12 + 3 * j + a] = 2.0 * w[i] * w[j];
            }
        }
    }
    let along = |a: &[f64; 4]| (0..4).fold([0.0; 3], |acc, i| add(acc, scale(x[i], a[i])));
    let mut d: Vec<[f64; 3]> = dirs.iter().map(along).collect();
    if d.len() == 2 {
        let (aa, bb, ab) = (dot(d[0], d[0]), dot(d[1], d[1]), dot(d[0], d[1]));
        if aa * bb - ab * ab <= 1e-12 * aa * bb {
            // Parallel: one parameter is enough to move the closest point.
            dirs.truncate(1);
            d.truncate(1);
        }
    }
    d.retain(|v| dot(*v, *v) > 0.0);
    let m = d.len().min(dirs.len());
    let mut span: Vec<[f64; 12]> = (0..3)
        .map(|a| std::array::from_fn(|k| if k % 3 == a { w[k / 3] } else { 0.0 }))
        .collect();
    if m == 0 {
        return (c.d2, g, h, span);
    }
    // f_θθ = 2 Dᵀ D and its inverse.
    let f: Vec<Vec<f64>> = (0..m)
        .map(|k| (0..m).map(|l| 2.0 * dot(d[k], d[l])).collect())
        .collect();
    let inv: Vec<Vec<f64>> = if m == 1 {
        vec![vec![1.0 / f[0][0]]]
    } else {
        let det = f[0][0] * f[1][1] - f[0][1] * f[1][0];
        vec![
            vec![f[1][1] / det, -f[0][1] / det],
            vec![-f[1][0] / det, f[0][0] / det],
        ]
    };
    // f_xθ, column k.
    let b: Vec<[f64; 12]> = (0..m)
        .map(|k| {
            let mut col = [0.0; 12];
            for i in 0..4 {
                for a in 0..3 {
                    col[3 * i + a] = 2.0 * (dirs[k][i] * r[a] + w[i] * d[k][a]);
                }
            }
            col
        })
        .collect();
    for p in 0..12 {
        for q in 0..12 {
            let mut s = 0.0;
            for k in 0..m {
                for l in 0..m {
                    s += b[k][p] * inv[k][l] * b[l][q];
                }
            }
            h[p * 12 + q] -= s;
        }
    }
    span.extend(b);
    (c.d2, g, h, span)
}

/// Replaces the symmetric 12 x 12 `h`, whose range lies in the span of
/// `span`, by its positive semi-definite part, computed in that subspace:
/// with `Q` an orthonormal basis of the span (at most five columns),
/// `H = Q (Qᵀ H Q) Qᵀ` and `H+ = Q (Qᵀ H Q)+ Qᵀ` — a 5 x 5 eigenproblem
/// instead of a 12 x 12 one.
fn project_in_span(h: &mut [f64; 144], span: &[[f64; 12]]) {
    let mut q: Vec<[f64; 12]> = Vec::with_capacity(span.len());
    let scale = span
        .iter()
        .map(|v| dot12(v, v))
        .fold(0.0f64, f64::max)
        .sqrt();
    for v in span {
        let mut u = *v;
        for _ in 0..2 {
            for e in &q {
                let c = dot12(&u, e);
                for k in 0..12 {
                    u[k] -= c * e[k];
                }
            }
        }
        let n = dot12(&u, &u).sqrt();
        if n > 1e-10 * scale {
            q.push(u.map(|v| v / n));
        }
    }
    let k = q.len();
    let mut hq = [[0.0; 12]; 5];
    for (j, e) in q.iter().enumerate() {
        for p in 0..12 {
            hq[j][p] = (0..12).map(|r| h[p * 12 + r] * e[r]).sum();
        }
    }
    let mut m = [0.0; 25];
    for i in 0..k {
        for j in 0..k {
            m[i * k + j] = dot12(&q[i], &hq[j]);
        }
    }
    for i in 0..k {
        for j in 0..i {
            let a = 0.5 * (m[i * k + j] + m[j * k + i]);
            m[i * k + j] = a;
            m[j * k + i] = a;
        }
    }
    if !crate::psd::project(&mut m, k, k) {
        return;
    }
    for p in 0..12 {
        for r in 0..12 {
            let mut v = 0.0;
            for i in 0..k {
                for j in 0..k {
                    v += q[i][p] * m[i * k + j] * q[j][r];
                }
            }
            h[p * 12 + r] = v;
        }
    }
}

fn dot12(a: &[f64; 12], b: &[f64; 12]) -> f64 {
    (0..12).map(|k| a[k] * b[k]).sum()
}

/// `b(s)`, `b'(s)`, `b''(s)` of the barrier with `ŝ = s_hat` (module
/// docs): 0 from `ŝ` on, infinite at and below 0.
pub fn barrier(s: f64, s_hat: f64) -> (f64, f64, f64) {
    if s >= s_hat {
        return (0.0, 0.0, 0.0);
    }
    if s <= 0.0 {
        return (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY);
    }
    let (e, l) = (s - s_hat, (s / s_hat).ln());
    (
        -e * e * l,
        -2.0 * e * l - e * e / s,
        -2.0 * l - 4.0 * e / s + e * e / (s * s),
    )
}

/// One pair's barrier energy `kappa b(s)` with its gradient and Hessian
/// (12, 12 x 12): `None` when the pair is farther than `d̂` (no term).
pub fn pair_barrier(
    kind: PairKind,
    x: &[[f64; 3]; 4],
    s_hat: f64,
    kappa: f64,
    hessian: Hessian,
) -> Option<(f64, [f64; 12], Option<[f64; 144]>)> {
    pair_barrier_mollified(kind, x, s_hat, kappa, hessian, None)
}

/// [`pair_barrier`] with, for an edge–edge pair, the barrier multiplied by
/// [`edge_mollifier`] of `eps` where it is below 1 (the product's
/// gradient and Hessian; its projection on the whole 12 x 12 then).
pub fn pair_barrier_mollified(
    kind: PairKind,
    x: &[[f64; 3]; 4],
    s_hat: f64,
    kappa: f64,
    hessian: Hessian,
    eps: Option<f64>,
) -> Option<(f64, [f64; 12], Option<[f64; 144]>)> {
    barrier_of(kind, x, &kind.closest(x), s_hat, kappa, hessian, eps)
}

/// [`pair_barrier_mollified`] with the pair's closest points `c` already
/// found (the narrow phase finds them to tell whether the pair is near).
pub fn barrier_of(
    kind: PairKind,
    x: &[[f64; 3]; 4],
    c: &Closest,
    s_hat: f64,
    kappa: f64,
    hessian: Hessian,
    eps: Option<f64>,
) -> Option<(f64, [f64; 12], Option<[f64; 144]>)> {
    let s = c.d2;
    if s >= s_hat {
        return None;
    }
    if let (PairKind::EdgeEdge, Some(eps)) = (kind, eps) {
        let (m, gm, hm) = edge_mollifier(x, eps);
        if m < 1.0 {
            let which = if hessian == Hessian::None {
                Hessian::None
            } else {
                Hessian::Exact
            };
            let (e, g, h) = barrier_of(kind, x, c, s_hat, kappa, which, None)?;
            let grad: [f64; 12] = std::array::from_fn(|k| e * gm[k] + m * g[k]);
            let hess = h.map(|h| {
                let mut out: [f64; 144] = std::array::from_fn(|k| {
                    let (p, q) = (k / 12, k % 12);
                    e * hm[k] + gm[p] * g[q] + g[p] * gm[q] + m * h[k]
                });
                if hessian == Hessian::Projected {
                    crate::psd::project(&mut out, 12, 12);
                }
                out
            });
            return Some((m * e, grad, hess));
        }
    }
    let mut span = Vec::new();
    let (ds, dh) = if hessian != Hessian::None {
        let (_, g, h, basis) = distance_parts(kind, x, c);
        span = basis;
        (g, Some(h))
    } else {
        let gr = c.gradient(*x);
        (std::array::from_fn(|k| gr[k / 3][k % 3]), None)
    };
    let (b, b1, b2) = barrier(s, s_hat);
    let grad = ds.map(|v| kappa * b1 * v);
    let hess = dh.map(|h2| {
        let mut out = [0.0; 144];
        for p in 0..12 {
            for q in 0..12 {
                out[p * 12 + q] = kappa * (b2 * ds[p] * ds[q] + b1 * h2[p * 12 + q]);
            }
        }
        if hessian == Hessian::Projected {
            project_in_span(&mut out, &span);
        }
        out
    });
    Some((kappa * b, grad, hess))
}

/// IPC's edge–edge mollifier (Li et al. 2020, §4.3): with `a = x1 - x0`,
/// `b = x3 - x2` and `c = |a × b|^2`,
///
/// ```text
/// m(c) = -c^2 / eps^2 + 2 c / eps   for c < eps,   else 1
/// ```
///
/// (`eps = 1e-3 |a_0|^2 |b_0|^2` from the rest lengths): the edge–edge
/// barrier is multiplied by `m`, which vanishes with the cross product, so
/// that two edges turning parallel — where their closest points jump and
/// the distance is only C⁰ — feel a barrier that goes smoothly to zero
/// (the point–triangle pairs of their ends hold them apart there).
/// Returns `m`, its gradient and its Hessian in the four nodes.
pub fn edge_mollifier(x: &[[f64; 3]; 4], eps: f64) -> (f64, [f64; 12], [f64; 144]) {
    let a = sub(x[1], x[0]);
    let b = sub(x[3], x[2]);
    let (aa, bb, ab) = (dot(a, a), dot(b, b), dot(a, b));
    let c = aa * bb - ab * ab;
    if c >= eps {
        return (1.0, [0.0; 12], [0.0; 144]);
    }
    let m = -c * c / (eps * eps) + 2.0 * c / eps;
    let m1 = -2.0 * c / (eps * eps) + 2.0 / eps;
    let m2 = -2.0 / (eps * eps);
    // ∇c in (a, b), then in the nodes (a = x1 - x0, b = x3 - x2).
    let ga: [f64; 3] = std::array::from_fn(|i| 2.0 * bb * a[i] - 2.0 * ab * b[i]);
    let gb: [f64; 3] = std::array::from_fn(|i| 2.0 * aa * b[i] - 2.0 * ab * a[i]);
    let sign = [-1.0, 1.0, -1.0, 1.0];
    let gc: [f64; 12] = std::array::from_fn(|k| {
        let (node, i) = (k / 3, k % 3);
        sign[node] * if node < 2 { ga[i] } else { gb[i] }
    });
    // ∇²c in (a, b): Haa = 2|b|² I - 2 b bᵀ, Hbb = 2|a|² I - 2 a aᵀ,
    // Hab = 4 a bᵀ - 2 b aᵀ - 2 (a.b) I.
    let delta = |i: usize, j: usize| f64::from(u8::from(i == j));
    let hc = |p: usize, q: usize| -> f64 {
        let (np, i, nq, j) = (p / 3, p % 3, q / 3, q % 3);
        let v = match (np < 2, nq < 2) {
            (true, true) => 2.0 * bb * delta(i, j) - 2.0 * b[i] * b[j],
            (false, false) => 2.0 * aa * delta(i, j) - 2.0 * a[i] * a[j],
            (true, false) => 4.0 * a[i] * b[j] - 2.0 * b[i] * a[j] - 2.0 * ab * delta(i, j),
            (false, true) => 4.0 * a[j] * b[i] - 2.0 * b[j] * a[i] - 2.0 * ab * delta(i, j),
        };
        sign[np] * sign[nq] * v
    };
    let g = gc.map(|v| m1 * v);
    let h: [f64; 144] = std::array::from_fn(|k| {
        let (p, q) = (k / 12, k % 12);
        m2 * gc[p] * gc[q] + m1 * hc(p, q)
    });
    (m, g, h)
}

/// Which Hessian [`pair_barrier`] gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Hessian {
    /// None: value and gradient only.
    None,
    /// The exact one.
    Exact,
    /// Its positive semi-definite part.
    Projected,
}

/// The distance between the boxes of the pair's two primitives (0 where
/// they overlap): a lower bound on the pair's distance.
pub fn box_separation(kind: PairKind, x: &[[f64; 3]; 4]) -> f64 {
    let split = match kind {
        PairKind::PointTriangle => 1,
        PairKind::EdgeEdge => 2,
    };
    let (a, b) = x.split_at(split);
    let mut d2 = 0.0;
    for i in 0..3 {
        let (alo, ahi) = a
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p[i]), h.max(p[i]))
            });
        let (blo, bhi) = b
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p[i]), h.max(p[i]))
            });
        let gap = (blo - ahi).max(alo - bhi).max(0.0);
        d2 += gap * gap;
    }
    d2.sqrt()
}

/// The distance function ACCD measures, `(d^2 - ξ^2) / (d + ξ) = d - ξ`.
fn gap(kind: PairKind, x: &[[f64; 3]; 4], xi: f64) -> f64 {
    kind.closest(x).d2.sqrt() - xi
}

/// The largest fraction `t` in `[0, t_max]` of the displacements `p` that
/// the pair at `x` can take without coming closer than `ξ` (additive CCD,
/// module docs, with `σ = sigma`: it stops once the gap `d - ξ` has fallen
/// to `σ` times its start). `t_max` when nothing comes near; at most
/// `max_iterations` advances (then the fraction reached, still safe).
pub fn additive_ccd(
    kind: PairKind,
    x: &[[f64; 3]; 4],
    p: &[[f64; 3]; 4],
    xi: f64,
    sigma: f64,
    t_max: f64,
) -> f64 {
    let max_iterations = 10_000;
    let mean = scale(p.iter().fold([0.0; 3], |a, v| add(a, *v)), 0.25);
    let p: [[f64; 3]; 4] = p.map(|v| sub(v, mean));
    let len = p.map(norm);
    let lp = match kind {
        PairKind::PointTriangle => len[0] + len[1].max(len[2]).max(len[3]),
        PairKind::EdgeEdge => len[0].max(len[1]) + len[2].max(len[3]),
    };
    if lp <= 0.0 {
        return t_max;
    }
    // The primitives' boxes bound their distance from below: a pair whose
    // boxes are farther apart than `ξ + lp t_max` cannot close its gap
    // within the step (the common case, without a distance computed).
    if box_separation(kind, x) > xi + lp * t_max {
        return t_max;
    }
    let mut y = *x;
    let start = gap(kind, &y, xi);
    if start <= 0.0 {
        return 0.0;
    }
    let target = sigma * start;
    let mut t = 0.0;
    let mut step = (1.0 - sigma) * start / lp;
    for _ in 0..max_iterations {
        for i in 0..4 {
            y[i] = add(y[i], scale(p[i], step));
        }
        let g = gap(kind, &y, xi);
        if t > 0.0 && g < target {
            return t;
        }
        t += step;
        if t > t_max {
            return t_max;
        }
        step = 0.9 * g / lp;
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fd::{gradient_error, jacobian_error};

    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
    }

    fn nodes(v: &[f64]) -> [[f64; 3]; 4] {
        std::array::from_fn(|i| [v[3 * i], v[3 * i + 1], v[3 * i + 2]])
    }

    /// Random pairs of both kinds in every region: the squared distance's
    /// gradient and Hessian against central differences (h = 1e-7 on unit
    /// coordinates). Pairs within 1e-4 of a region border are skipped
    /// (there `s` is only C¹).
    #[test]
    fn squared_distance_derivatives_match_finite_differences() {
        let mut rng = Rng(0x5eed_1234_abcd);
        let mut regions = std::collections::BTreeMap::new();
        for kind in [PairKind::PointTriangle, PairKind::EdgeEdge] {
            let mut checked = 0;
            while checked < 300 {
                let x: Vec<f64> = (0..12).map(|_| rng.next()).collect();
                let w = kind.closest(&nodes(&x)).weights;
                // Away from region borders: every weight 0 or clearly not.
                let near = w.iter().any(|v| v.abs() > 0.0 && v.abs() < 1e-4)
                    || w.iter()
                        .any(|v| (v.abs() - 1.0).abs() < 1e-4 && v.abs() != 1.0);
                if near {
                    continue;
                }
                // The region must not change within the differences' reach.
                let region = kind.directions(&w).len();
                *regions
                    .entry((kind == PairKind::EdgeEdge, region))
                    .or_insert(0) += 1;
                let s = |v: &[f64]| squared_distance(kind, &nodes(v)).0;
                let g = |v: &[f64]| squared_distance(kind, &nodes(v)).1.to_vec();
                let h = |v: &[f64]| squared_distance(kind, &nodes(v)).2.to_vec();
                let eg = gradient_error(s, g, &x, 1e-7);
                let eh = jacobian_error(g, h, &x, 1e-7);
                assert!(eg < 1e-6, "{kind:?} {x:?}: gradient {eg:e}");
                assert!(eh < 1e-5, "{kind:?} region {region} {x:?}: Hessian {eh:e}");
                checked += 1;
            }
        }
        // Every region was met: face, edge and vertex; inside-inside, one
        // clamped, both clamped.
        for key in [
            (false, 0),
            (false, 1),
            (false, 2),
            (true, 0),
            (true, 1),
            (true, 2),
        ] {
            assert!(
                regions.get(&key).copied().unwrap_or(0) > 3,
                "{key:?}: {regions:?}"
            );
        }
    }

    /// The barrier's derivatives against central differences in `s`, its
    /// C² join at `ŝ`, positivity and divergence at contact.
    #[test]
    fn barrier_is_c2_positive_and_divergent() {
        let s_hat = 1e-6;
        for s in [1e-10, 1e-8, 3e-7, 9e-7] {
            let h = 1e-6 * s;
            let (b, b1, b2) = barrier(s, s_hat);
            let (bp, b1p, _) = barrier(s + h, s_hat);
            let (bm, b1m, _) = barrier(s - h, s_hat);
            assert!(b > 0.0 && b1 < 0.0 && b2 > 0.0, "{s}");
            assert!(((bp - bm) / (2.0 * h) - b1).abs() < 1e-6 * b1.abs(), "{s}");
            assert!(
                ((b1p - b1m) / (2.0 * h) - b2).abs() < 1e-5 * b2.abs(),
                "{s}"
            );
        }
        let near = barrier(s_hat * (1.0 - 1e-9), s_hat);
        assert!(near.0.abs() < 1e-25 && near.1.abs() < 1e-18 && near.2.abs() < 1e-7);
        assert!(barrier(1e-30, s_hat).0 > 3.0 * barrier(1e-12, s_hat).0);
        assert_eq!(barrier(0.0, s_hat).0, f64::INFINITY);
    }

    /// A pair's barrier gradient and Hessian (through the chain rule)
    /// against central differences, point–triangle and edge–edge, on
    /// pairs 0.2–0.8 d̂ apart.
    #[test]
    fn pair_barrier_derivatives_match_finite_differences() {
        let d_hat: f64 = 1e-3;
        let cases: [(PairKind, [[f64; 3]; 4]); 3] = [
            (
                PairKind::PointTriangle,
                [
                    [0.2e-2, 0.3e-2, 0.5e-3],
                    [0.0; 3],
                    [1e-2, 0.0, 0.0],
                    [0.0, 1e-2, 0.0],
                ],
            ),
            (
                PairKind::PointTriangle,
                [
                    [0.55e-2, 0.55e-2, 0.3e-3],
                    [0.0; 3],
                    [1e-2, 0.0, 1e-4],
                    [0.0, 1e-2, 0.0],
                ],
            ),
            (
                PairKind::EdgeEdge,
                [
                    [0.0, 0.0, 0.0],
                    [1e-2, 1e-3, 0.0],
                    [5e-3, -5e-3, 4e-4],
                    [4e-3, 5e-3, 6e-4],
                ],
            ),
        ];
        for (kind, x) in cases {
            let flat: Vec<f64> = x.concat();
            let s = kind.closest(&x).d2;
            assert!(
                s < d_hat * d_hat && s > 0.01 * d_hat * d_hat,
                "{kind:?}: {}",
                s.sqrt()
            );
            let e = |v: &[f64]| {
                pair_barrier(kind, &nodes(v), d_hat * d_hat, 1e6, Hessian::None)
                    .unwrap()
                    .0
            };
            let g = |v: &[f64]| {
                pair_barrier(kind, &nodes(v), d_hat * d_hat, 1e6, Hessian::None)
                    .unwrap()
                    .1
                    .to_vec()
            };
            let h = |v: &[f64]| {
                pair_barrier(kind, &nodes(v), d_hat * d_hat, 1e6, Hessian::Exact)
                    .unwrap()
                    .2
                    .unwrap()
                    .to_vec()
            };
            let eg = gradient_error(e, g, &flat, 1e-9);
            let eh = jacobian_error(g, h, &flat, 1e-9);
            assert!(
                eg < 1e-5 && eh < 1e-5,
                "{kind:?}: gradient {eg:e}, Hessian {eh:e}"
            );
        }
    }

    /// The projection in the Hessian's five-dimensional span equals the
    /// projection of the whole 12 x 12 matrix (faer's eigendecomposition
    /// through `psd`), on random pairs of both kinds closer than `d̂`, and
    /// leaves a positive semi-definite Hessian untouched.
    #[test]
    fn projection_in_the_span_equals_the_full_projection() {
        let mut rng = Rng(0xfeed_5eed_0042);
        let d_hat = 0.5f64;
        let mut changed = 0;
        for kind in [PairKind::PointTriangle, PairKind::EdgeEdge] {
            let mut done = 0;
            while done < 200 {
                let v: Vec<f64> = (0..12).map(|_| rng.next()).collect();
                let x = nodes(&v);
                let Some((_, _, Some(exact))) =
                    pair_barrier(kind, &x, d_hat * d_hat, 1.0, Hessian::Exact)
                else {
                    continue;
                };
                let (_, _, Some(fast)) =
                    pair_barrier(kind, &x, d_hat * d_hat, 1.0, Hessian::Projected).unwrap()
                else {
                    unreachable!()
                };
                let mut full = exact;
                if crate::psd::project(&mut full, 12, 12) {
                    changed += 1;
                }
                let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let err = (0..144)
                    .map(|k| (fast[k] - full[k]).abs())
                    .fold(0.0f64, f64::max);
                assert!(err <= 1e-9 * scale, "{kind:?}: {err:e} of {scale:e}");
                done += 1;
            }
        }
        assert!(changed > 50, "{changed}");
    }

    /// Two nearly parallel edges closer than `d̂`: the mollifier's and the
    /// mollified barrier's gradient and Hessian against central
    /// differences; the mollifier is 1 for crossing edges and goes to 0 as
    /// the edges turn parallel.
    #[test]
    fn mollified_edge_barrier_matches_finite_differences() {
        let x = [
            [0.0, 0.0, 0.0],
            [1e-2, 0.0, 0.0],
            [2e-3, 1e-5, 5e-4],
            [1.2e-2, 4e-5, 4e-4],
        ];
        let eps = 1e-3 * 1e-4 * 1e-4;
        let flat: Vec<f64> = x.concat();
        let (m, _, _) = edge_mollifier(&x, eps);
        assert!(m > 0.0 && m < 1.0, "{m}");
        let mf = |v: &[f64]| edge_mollifier(&nodes(v), eps).0;
        let mg = |v: &[f64]| edge_mollifier(&nodes(v), eps).1.to_vec();
        let mh = |v: &[f64]| edge_mollifier(&nodes(v), eps).2.to_vec();
        assert!(gradient_error(mf, mg, &flat, 1e-9) < 1e-5);
        assert!(jacobian_error(mg, mh, &flat, 1e-9) < 1e-5);
        let s_hat = 1e-6;
        let pair = |v: &[f64], hessian| {
            pair_barrier_mollified(
                PairKind::EdgeEdge,
                &nodes(v),
                s_hat,
                1e6,
                hessian,
                Some(eps),
            )
            .unwrap()
        };
        let e = |v: &[f64]| pair(v, Hessian::None).0;
        let g = |v: &[f64]| pair(v, Hessian::None).1.to_vec();
        let h = |v: &[f64]| pair(v, Hessian::Exact).2.unwrap().to_vec();
        let (eg, eh) = (
            gradient_error(e, g, &flat, 1e-10),
            jacobian_error(g, h, &flat, 1e-10),
        );
        assert!(eg < 1e-5 && eh < 1e-4, "gradient {eg:e}, Hessian {eh:e}");
        let crossing = [
            [0.0, 0.0, 0.0],
            [1e-2, 0.0, 0.0],
            [5e-3, -5e-3, 5e-4],
            [5e-3, 5e-3, 5e-4],
        ];
        assert_eq!(edge_mollifier(&crossing, eps).0, 1.0);
        let parallel = [
            [0.0, 0.0, 0.0],
            [1e-2, 0.0, 0.0],
            [2e-3, 0.0, 5e-4],
            [1.2e-2, 0.0, 5e-4],
        ];
        assert_eq!(edge_mollifier(&parallel, eps).0, 0.0);
    }

    /// A node falling onto a triangle stops short of it: the fraction ACCD
    /// allows leaves a gap, and the exact time of impact (the node would
    /// reach the plane at t = 0.5) bounds it. Moving apart, or parallel
    /// without approaching, the whole step is allowed. Two crossing edges
    /// likewise.
    #[test]
    fn additive_ccd_never_lets_a_pair_touch() {
        let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let x = [[0.2, 0.2, 0.1], tri[0], tri[1], tri[2]];
        let down = [[0.0, 0.0, -0.2], [0.0; 3], [0.0; 3], [0.0; 3]];
        let t = additive_ccd(PairKind::PointTriangle, &x, &down, 0.0, 0.1, 1.0);
        assert!(t > 0.3 && t < 0.5, "{t}");
        let up = [[0.0, 0.0, 0.2], [0.0; 3], [0.0; 3], [0.0; 3]];
        assert_eq!(
            additive_ccd(PairKind::PointTriangle, &x, &up, 0.0, 0.1, 1.0),
            1.0
        );
        let slide = [[0.1, 0.1, 0.0], [0.0; 3], [0.0; 3], [0.0; 3]];
        assert_eq!(
            additive_ccd(PairKind::PointTriangle, &x, &slide, 0.0, 0.1, 1.0),
            1.0
        );
        // Edge (0,0,1)-(1,0,1) falling through edge (0.5,-1,0)-(0.5,1,0).
        let e = [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [0.5, -1.0, 0.0],
            [0.5, 1.0, 0.0],
        ];
        let fall = [[0.0, 0.0, -2.0], [0.0, 0.0, -2.0], [0.0; 3], [0.0; 3]];
        let t = additive_ccd(PairKind::EdgeEdge, &e, &fall, 0.0, 0.1, 1.0);
        assert!(t > 0.4 && t < 0.5, "{t}");
        let mut y = e;
        for i in 0..4 {
            y[i] = add(y[i], scale(fall[i], t));
        }
        assert!(PairKind::EdgeEdge.closest(&y).d2.sqrt() > 0.05);
    }
}
