//! Self-contact (issue 33, SPEC §6.3 `[contact] self`): the fabric's
//! triangles against each other, within a piece and between pieces, by
//! the barrier of [`super::barrier`] summed over every point–triangle and
//! edge–edge pair closer than `d̂` (Li et al. 2020):
//!
//! ```text
//! B(y) = kappa sum_{pairs closer than d̂} b(d^2(y)),      kappa = eta / d̂^2
//! ```
//!
//! with `eta` the obstacle penalty (N/m; [`DEFAULT_STIFFNESS`] with
//! Lagrange contact or no obstacles): near `d̂` the barrier is cubic in the
//! gap's shortfall, so a layer of fabric resting on another settles within
//! a fraction of a micrometre of `d̂` below it, and it never reaches 0.
//! Pairs sharing a node are not pairs; the initial mesh must have no
//! other pair closer than `d̂` ([`SelfContact::new`] says which).
//!
//! **Hessian.** Each pair's 12 x 12 Hessian is projected to its positive
//! semi-definite part ([`crate::psd`]; exact where it already is) and
//! scattered into a pattern: the stepper's layout grown with the pairs
//! that may touch (`integrator::grown`, [`SelfContact::stencils_near`],
//! [`SelfContact::add_hessian`]), or the model's own. A pair whose nodes
//! are not coupled in the pattern has its off-diagonal block `K_ab` moved
//! to the diagonal as `|K_ab|_F I` on both nodes, which keeps the sum
//! positive semi-definite (`[[s I, -K], [-Kᵀ, s I]] ⪰ 0` for `s >= |K|_2`)
//! but makes Newton's Hessian an approximation there: convergence is then
//! linear rather than quadratic.
//!
//! **The step never crosses.** [`SelfContact::max_step`] is the largest
//! fraction of a Newton increment that additive CCD allows over the pairs
//! that may meet (those whose boxes swept over the increment overlap,
//! [`super::proximity::swept_candidates`]): Newton's line search starts below it, and a trial point
//! whose barrier is infinite is rejected, so every accepted iterate keeps
//! every pair apart.

use super::barrier::{Hessian, PairKind, additive_ccd, box_separation, pair_barrier};
use super::proximity::{Candidates, close_pairs, edges_of, swept_candidates};
use crate::solver::SparsePattern;
use crate::vec3::norm;
use std::sync::Mutex;

/// The obstacle penalty self-contact's stiffness derives from when none is
/// given (N/m; the README's drape tester's).
pub const DEFAULT_STIFFNESS: f64 = 5.0e4;

/// ACCD's `σ`: a step may close at most 90 % of a pair's gap.
const CCD_SCALE: f64 = 0.1;

/// Self-contact's model: the triangles and edges it measures, `d̂` and
/// `kappa`.
#[derive(Debug)]
pub struct SelfContact {
    triangles: Vec<[usize; 3]>,
    edges: Vec<[usize; 2]>,
    distance: f64,
    kappa: f64,
    /// The broad phase kept across evaluations.
    kept: Mutex<Kept>,
}

/// The broad phase's pairs at positions `at`: every pair closer than
/// `margin` there (module docs, "Broad phase").
#[derive(Debug, Default)]
struct Kept {
    at: Vec<[f64; 3]>,
    margin: f64,
    pairs: Candidates,
}

/// The initial mesh already has a pair closer than `d̂`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "= {} m is larger than the distance between parts of the mesh that share no node at the start ({what}: {} m); give a smaller self_distance or a mesh whose pieces and folds are farther apart",
    crate::human::human(*distance),
    crate::human::human(*found)
)]
pub struct TooClose {
    /// `d̂` (m).
    pub distance: f64,
    /// The closest such pair, in words.
    pub what: String,
    /// Its distance (m).
    pub found: f64,
}

impl SelfContact {
    /// Self-contact of the `triangles` (a linear mesh's elements, a higher
    /// order's sub-triangles) at the initial positions `x`, with distance
    /// `d̂ = distance` and penalty `eta` (N/m).
    pub fn new(
        triangles: Vec<[usize; 3]>,
        x: &[f64],
        distance: f64,
        eta: f64,
    ) -> Result<Self, TooClose> {
        let edges = edges_of(&triangles);
        let s = Self {
            triangles,
            edges,
            distance,
            kappa: eta / (distance * distance),
            kept: Mutex::new(Kept::default()),
        };
        let pts = points(x);
        if let Some((d, what)) = s.closest_pair(&pts) {
            return Err(TooClose {
                distance,
                what,
                found: d,
            });
        }
        Ok(s)
    }

    /// `d̂` (m).
    pub fn distance(&self) -> f64 {
        self.distance
    }

    /// The triangles measured.
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// The closest pair closer than `d̂` at `x`, with its distance.
    fn closest_pair(&self, x: &[[f64; 3]]) -> Option<(f64, String)> {
        let mut best: Option<(f64, String)> = None;
        self.for_close_pairs(x, |kind, nodes, a, b| {
            let d = kind.closest(&nodes).d2.sqrt();
            if best.as_ref().is_none_or(|(bd, _)| d < *bd) {
                let what = match kind {
                    PairKind::PointTriangle => format!("node {a} and triangle {b}"),
                    PairKind::EdgeEdge => {
                        format!("edges {:?} and {:?}", self.edges[a], self.edges[b])
                    }
                };
                best = Some((d, what));
            }
        });
        best
    }

    /// Calls `f(kind, positions, a, b)` for every pair closer than `d̂`
    /// (point–triangle: node `a`, triangle `b`; edge–edge: edges `a`, `b`).
    fn for_close_pairs(
        &self,
        x: &[[f64; 3]],
        mut f: impl FnMut(PairKind, [[f64; 3]; 4], usize, usize),
    ) {
        let d2 = self.distance * self.distance;
        self.with_candidates(x, 0.0, |pairs| {
            for &(p, t) in &pairs.point_triangle {
                let [a, b, c] = self.triangles[t];
                let pos = [x[p], x[a], x[b], x[c]];
                if box_separation(PairKind::PointTriangle, &pos) < self.distance
                    && PairKind::PointTriangle.closest(&pos).d2 < d2
                {
                    f(PairKind::PointTriangle, pos, p, t);
                }
            }
            for &(e, k) in &pairs.edge_edge {
                let ([a, b], [c, d]) = (self.edges[e], self.edges[k]);
                let pos = [x[a], x[b], x[c], x[d]];
                if box_separation(PairKind::EdgeEdge, &pos) < self.distance
                    && PairKind::EdgeEdge.closest(&pos).d2 < d2
                {
                    f(PairKind::EdgeEdge, pos, e, k);
                }
            }
        });
    }

    /// Calls `f` with a superset of the pairs that come closer than `d̂`
    /// at `x` or anywhere within `reach` of it (the pairs closer than a
    /// margin, measured when it was made): the kept broad phase when
    /// no node has moved far enough since it was made to bring a pair in
    /// from outside it, else a new one made at `x` with room (its margin
    /// `2 d̂ + 2 reach` more than needed, so that the next evaluations,
    /// moved by less than `d̂`, reuse it).
    fn with_candidates<R>(
        &self,
        x: &[[f64; 3]],
        reach: f64,
        f: impl FnOnce(&Candidates) -> R,
    ) -> R {
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        let moved = if kept.at.len() == x.len() {
            (x.iter().zip(&kept.at))
                .map(|(a, b)| norm(crate::vec3::sub(*a, *b)))
                .fold(0.0f64, f64::max)
        } else {
            f64::INFINITY
        };
        if self.distance + 2.0 * (moved + reach) > kept.margin {
            let margin = 3.0 * self.distance + 2.0 * reach;
            kept.pairs = close_pairs(x, &self.triangles, &self.edges, margin);
            kept.at = x.to_vec();
            kept.margin = margin;
        }
        f(&kept.pairs)
    }

    /// The four nodes of pair `(a, b)` of `kind`.
    fn nodes(&self, kind: PairKind, a: usize, b: usize) -> [usize; 4] {
        match kind {
            PairKind::PointTriangle => {
                let [i, j, k] = self.triangles[b];
                [a, i, j, k]
            }
            PairKind::EdgeEdge => {
                let ([i, j], [k, l]) = (self.edges[a], self.edges[b]);
                [i, j, k, l]
            }
        }
    }

    /// The number of pairs closer than `d̂` at `y` (a report).
    pub fn active_pairs(&self, y: &[f64]) -> usize {
        let mut n = 0;
        self.for_close_pairs(&points(y), |_, _, _, _| n += 1);
        n
    }

    /// Adds the barrier's gradient to `g` and, with `h`, its projected
    /// Hessian to the values on `pattern` (module docs); returns its value
    /// (infinite where a pair touches).
    pub fn add(&self, y: &[f64], g: &mut [f64], h: Option<(&mut [f64], &SparsePattern)>) -> f64 {
        let x = points(y);
        let mut value = 0.0;
        let mut h = h;
        let s_hat = self.distance * self.distance;
        let mut pairs = Vec::new();
        self.for_close_pairs(&x, |kind, pos, a, b| pairs.push((kind, pos, a, b)));
        for (kind, pos, a, b) in pairs {
            let nodes = self.nodes(kind, a, b);
            let which = if h.is_some() {
                Hessian::Projected
            } else {
                Hessian::None
            };
            let Some((e, grad, hess)) = pair_barrier(kind, &pos, s_hat, self.kappa, which) else {
                continue;
            };
            value += e;
            if !e.is_finite() {
                continue;
            }
            for (i, &n) in nodes.iter().enumerate() {
                for c in 0..3 {
                    g[3 * n + c] += grad[3 * i + c];
                }
            }
            if let (Some((values, pattern)), Some(k)) = (h.as_mut(), hess) {
                scatter(&k, &nodes, values, pattern, None);
            }
        }
        value
    }

    /// Adds the barrier's projected Hessian to the values on `pattern`
    /// (module docs), leaving out the rows and columns of the degrees of
    /// freedom `fixed` holds: what the step adds after the supports, on
    /// the Hessian's layout grown with the pairs
    /// (`integrator::grown`).
    pub fn add_hessian(
        &self,
        y: &[f64],
        values: &mut [f64],
        pattern: &SparsePattern,
        fixed: &[bool],
    ) {
        let x = points(y);
        let s_hat = self.distance * self.distance;
        let mut pairs = Vec::new();
        self.for_close_pairs(&x, |kind, pos, a, b| pairs.push((kind, pos, a, b)));
        for (kind, pos, a, b) in pairs {
            let nodes = self.nodes(kind, a, b);
            if let Some((e, _, Some(k))) =
                pair_barrier(kind, &pos, s_hat, self.kappa, Hessian::Projected)
                && e.is_finite()
            {
                scatter(&k, &nodes, values, pattern, Some(fixed));
            }
        }
    }

    /// The four-node stencils of every pair closer than `distance` at `y`:
    /// the couplings a Hessian layout makes room for.
    pub fn stencils_near(&self, y: &[f64], distance: f64) -> Vec<[usize; 4]> {
        let c = close_pairs(&points(y), &self.triangles, &self.edges, distance);
        let pt = (c.point_triangle.iter()).map(|&(p, t)| self.nodes(PairKind::PointTriangle, p, t));
        let ee = (c.edge_edge.iter()).map(|&(e, k)| self.nodes(PairKind::EdgeEdge, e, k));
        pt.chain(ee).collect()
    }

    /// The largest fraction in `(0, 1]` of `dy` from `y` that keeps every
    /// pair apart (module docs).
    pub fn max_step(&self, y: &[f64], dy: &[f64]) -> f64 {
        let (x, p) = (points(y), points(dy));
        let reach = p.iter().map(|v| norm(*v)).fold(0.0f64, f64::max);
        if reach == 0.0 {
            return 1.0;
        }
        // A short increment: the kept broad phase covers its sweep; a long
        // one: the boxes swept over it (a margin as long would take in far
        // too many pairs).
        let c = if reach <= 2.0 * self.distance {
            self.with_candidates(&x, reach, Candidates::clone)
        } else {
            swept_candidates(&x, &p, &self.triangles, &self.edges, 0.0)
        };
        let mut t = 1.0f64;
        for &(q, k) in &c.point_triangle {
            let n = self.nodes(PairKind::PointTriangle, q, k);
            t = t.min(additive_ccd(
                PairKind::PointTriangle,
                &n.map(|i| x[i]),
                &n.map(|i| p[i]),
                0.0,
                CCD_SCALE,
                t,
            ));
        }
        for &(e, k) in &c.edge_edge {
            let n = self.nodes(PairKind::EdgeEdge, e, k);
            t = t.min(additive_ccd(
                PairKind::EdgeEdge,
                &n.map(|i| x[i]),
                &n.map(|i| p[i]),
                0.0,
                CCD_SCALE,
                t,
            ));
        }
        t
    }
}

/// `y` as points.
fn points(y: &[f64]) -> Vec<[f64; 3]> {
    y.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// Adds the 12 x 12 `k` of `nodes` into `values` on `pattern`; a block
/// the pattern lacks goes to the two diagonal blocks as `|K_ab|_F I`
/// (module docs). With `fixed`, the rows and columns of held degrees of
/// freedom are left out.
fn scatter(
    k: &[f64; 144],
    nodes: &[usize; 4],
    values: &mut [f64],
    pattern: &SparsePattern,
    fixed: Option<&[bool]>,
) {
    let free = |d: usize| fixed.is_none_or(|f| !f[d]);
    for (i, &a) in nodes.iter().enumerate() {
        for (j, &b) in nodes.iter().enumerate() {
            let block = |r: usize, c: usize| k[(3 * i + r) * 12 + 3 * j + c];
            match pattern.node_block(a, b) {
                Some(pos) => {
                    for r in 0..3 {
                        for c in 0..3 {
                            if free(3 * a + r) && free(3 * b + c) {
                                values[pattern.entry(pos, b, r, c)] += block(r, c);
                            }
                        }
                    }
                }
                None => {
                    let f = (0..9)
                        .map(|m| block(m / 3, m % 3).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    for node in [a, b] {
                        for r in 0..3 {
                            if free(3 * node + r) {
                                values[pattern.diagonal_of(3 * node + r)] += 0.5 * f;
                            }
                        }
                    }
                }
            }
        }
    }
}
