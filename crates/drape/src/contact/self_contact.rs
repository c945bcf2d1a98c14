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
//! **Parallel edges.** An edge–edge pair's barrier is multiplied by IPC's
//! mollifier of the edges' cross product
//! ([`super::barrier::edge_mollifier`], its scale from the rest lengths),
//! which takes it smoothly to zero as the edges turn parallel, where the
//! edge–edge distance is only continuous; the point–triangle pairs of
//! their ends hold such edges apart.
//!
//! **Hessian.** Each pair's 12 x 12 Hessian is projected to its positive
//! semi-definite part ([`crate::psd`]; exact where it already is) and
//! scattered into a pattern: the stepper's layout grown with the pairs
//! that may touch (`integrator::grown`, [`SelfContact::stencils_near`],
//! [`PairHessians::Collect`], [`scatter_hessians`]), or the model's own. A pair whose nodes
//! are not coupled in the pattern has its off-diagonal block `K_ab` moved
//! to the diagonal as `|K_ab|_F I` on both nodes, which keeps the sum
//! positive semi-definite (`[[s I, -K], [-Kᵀ, s I]] ⪰ 0` for `s >= |K|_2`)
//! but makes Newton's Hessian an approximation there: convergence is then
//! linear rather than quadratic.
//!
//! **Friction** between the fabric's own layers, with `[contact]
//! friction` and `stick_speed` as for the obstacles: the smoothed, lagged potential of
//! Incremental Potential Contact (Li et al. 2020, §5) as the obstacles'
//! (`integrator::terms::friction`). For each pair closer than `d̂` at the
//! step's start `x`, the closest points' weights `w`, the normal `n` (from
//! the second closest point to the first) and the barrier's normal force
//! `lambda = kappa |b'(s)| 2 d` are lagged from there, and the pair's
//! relative slip over the step costs
//!
//! ```text
//! u = (I - n nᵀ) sum_i w_i (y_i - x_i),     D = mu lambda f0(|u|)
//! ```
//!
//! (`f0` the mollifier of the obstacles' friction, with the slip speed
//! `stick_speed`). Its gradient on node `i` is `w_i mu lambda f1 u / |u|`
//! and its Hessian block `(i, j)` is `w_i w_j` times the obstacles'
//! positive semi-definite 3 x 3, so the whole 12 x 12 is semi-definite.
//!
//! **The step never crosses.** [`SelfContact::max_step`] is the largest
//! fraction of a Newton increment that additive CCD allows over the pairs
//! that may meet (those whose boxes swept over the increment overlap,
//! [`super::proximity::swept_candidates`]): Newton's line search starts below it, and a trial point
//! whose barrier is infinite is rejected, so every accepted iterate keeps
//! every pair apart.

use super::barrier::{Hessian, PairKind, additive_ccd, barrier_of, box_separation};
use super::proximity::Closest;
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
    /// Coulomb's coefficient between the layers.
    friction: f64,
    /// The slip speed below which that friction is viscous (m/s).
    stick_speed: f64,
    /// Each edge's squared rest length (m²): the mollifier's scale.
    rest_length2: Vec<f64>,
}

/// The broad phase's pairs at positions `at`: every pair closer than
/// `margin` there (module docs, "Broad phase").
#[derive(Debug, Default)]
struct Kept {
    at: Vec<[f64; 3]>,
    margin: f64,
    pairs: Candidates,
}

/// What a scenario asks of self-contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfContactSpec {
    /// `d̂` (m).
    pub distance: f64,
    /// The penalty `eta` (N/m) that `kappa = eta / d̂^2` derives from.
    pub stiffness: f64,
    /// Coulomb's coefficient between the layers.
    pub friction: f64,
    /// The slip speed below which that friction is viscous (m/s).
    pub stick_speed: f64,
}

/// Why self-contact cannot start from the initial mesh.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TooClose {
    /// A pair closer than `d̂`.
    #[error(
        "= {} m is larger than the distance between parts of the mesh that share no node at the start ({what}: {} m); give a smaller self_distance or a mesh whose pieces and folds are farther apart",
        crate::human::human(*distance),
        crate::human::human(*found)
    )]
    Distance {
        /// `d̂` (m).
        distance: f64,
        /// The closest such pair, in words.
        what: String,
        /// Its distance (m).
        found: f64,
    },
    /// The mesh already passes through itself: self-contact keeps a
    /// fabric from crossing itself, it cannot undo a crossing (issue 46).
    #[error(
        "= {} m, but the mesh already passes through itself: the edge between nodes {} and {} crosses the triangle of nodes {}, {} and {} ({count} such crossing{}; nodes 0-based, as read, of the linear mesh or a higher order's sub-triangles); self-contact keeps a fabric from crossing itself and cannot undo a crossing: give a mesh whose pieces do not intersect",
        crate::human::human(*distance),
        edge[0],
        edge[1],
        triangle[0],
        triangle[1],
        triangle[2],
        if *count == 1 { "" } else { "s" }
    )]
    Crossing {
        /// `d̂` (m).
        distance: f64,
        /// The first crossing edge's nodes.
        edge: [usize; 2],
        /// The triangle it passes through.
        triangle: [usize; 3],
        /// How many (edge, triangle) pairs cross.
        count: usize,
    },
}

impl SelfContact {
    /// Self-contact of the `triangles` (a linear mesh's elements, a higher
    /// order's sub-triangles) at the initial positions `x`, with distance
    /// `d̂ = distance` and penalty `eta` (N/m); frictionless
    /// ([`SelfContact::with_friction`]).
    pub fn new(
        triangles: Vec<[usize; 3]>,
        x: &[f64],
        distance: f64,
        eta: f64,
    ) -> Result<Self, TooClose> {
        let edges = edges_of(&triangles);
        let rest_length2 = (edges.iter())
            .map(|&[a, b]| {
                let d: [f64; 3] = std::array::from_fn(|i| x[3 * a + i] - x[3 * b + i]);
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
            })
            .collect();
        let s = Self {
            rest_length2,
            triangles,
            edges,
            distance,
            kappa: eta / (distance * distance),
            kept: Mutex::new(Kept::default()),
            friction: 0.0,
            stick_speed: super::DEFAULT_STICK_SPEED,
        };
        let pts = points(x);
        let crossing = super::proximity::crossing_pairs(&pts, &s.triangles, &s.edges);
        if let Some(&(e, k)) = crossing.first() {
            return Err(TooClose::Crossing {
                distance,
                edge: s.edges[e],
                triangle: s.triangles[k],
                count: crossing.len(),
            });
        }
        if let Some((d, what)) = s.closest_pair(&pts) {
            return Err(TooClose::Distance {
                distance,
                what,
                found: d,
            });
        }
        Ok(s)
    }

    /// With friction `mu` between the layers and the slip speed
    /// `stick_speed` (m/s) below which it is viscous (module docs,
    /// "Friction").
    pub fn with_friction(mut self, mu: f64, stick_speed: f64) -> Self {
        self.friction = mu;
        self.stick_speed = stick_speed;
        self
    }

    /// Coulomb's coefficient between the layers (0: frictionless).
    pub fn friction(&self) -> f64 {
        self.friction
    }

    /// The slip speed below which friction is viscous (m/s).
    pub fn stick_speed(&self) -> f64 {
        self.stick_speed
    }

    /// `d̂` (m).
    pub fn distance(&self) -> f64 {
        self.distance
    }

    /// The edge–edge mollifier's `eps` of pair `(e, k)` of edges:
    /// `1e-3 |a_0|^2 |b_0|^2` from their rest lengths
    /// ([`super::barrier::edge_mollifier`]); `None` for point–triangle pairs.
    fn mollifier_eps(&self, kind: PairKind, a: usize, b: usize) -> Option<f64> {
        (kind == PairKind::EdgeEdge).then(|| 1e-3 * self.rest_length2[a] * self.rest_length2[b])
    }

    /// The triangles measured.
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// The closest pair closer than `d̂` at `x`, with its distance.
    fn closest_pair(&self, x: &[[f64; 3]]) -> Option<(f64, String)> {
        let mut best: Option<(f64, String)> = None;
        self.for_close_pairs(x, |kind, _, c, a, b| {
            let d = c.d2.sqrt();
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
        mut f: impl FnMut(PairKind, [[f64; 3]; 4], &Closest, usize, usize),
    ) {
        let d2 = self.distance * self.distance;
        let mut near = |kind: PairKind, pos: [[f64; 3]; 4], a: usize, b: usize| {
            if box_separation(kind, &pos) < self.distance {
                let c = kind.closest(&pos);
                if c.d2 < d2 {
                    f(kind, pos, &c, a, b);
                }
            }
        };
        self.with_candidates(x, 0.0, |pairs| {
            for &(p, t) in &pairs.point_triangle {
                let [a, b, c] = self.triangles[t];
                near(PairKind::PointTriangle, [x[p], x[a], x[b], x[c]], p, t);
            }
            for &(e, k) in &pairs.edge_edge {
                let ([a, b], [c, d]) = (self.edges[e], self.edges[k]);
                near(PairKind::EdgeEdge, [x[a], x[b], x[c], x[d]], e, k);
            }
        });
    }

    /// Forgets the kept broad phase: called at the start of every step
    /// (each attempt), so that what a step computes depends on the step's
    /// start alone and a resumed run takes the same steps as an
    /// uninterrupted one.
    pub fn forget_broad_phase(&self) {
        *self.kept.lock().unwrap_or_else(|e| e.into_inner()) = Kept::default();
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
        self.for_close_pairs(&points(y), |_, _, _, _, _| n += 1);
        n
    }

    /// Adds the barrier's gradient to `g` and, as `hessians` says, its
    /// projected Hessian (module docs); returns its value (infinite where
    /// a pair touches).
    pub fn add(&self, y: &[f64], g: &mut [f64], hessians: PairHessians<'_>) -> f64 {
        let x = points(y);
        let s_hat = self.distance * self.distance;
        let which = match hessians {
            PairHessians::None => Hessian::None,
            _ => Hessian::Projected,
        };
        let mut hessians = hessians;
        if let PairHessians::Collect(list) = &mut hessians {
            list.clear();
        }
        let mut value = 0.0;
        self.for_close_pairs(&x, |kind, pos, c, a, b| {
            let eps = self.mollifier_eps(kind, a, b);
            let Some((e, grad, hess)) = barrier_of(kind, &pos, c, s_hat, self.kappa, which, eps)
            else {
                return;
            };
            value += e;
            if !e.is_finite() {
                return;
            }
            let nodes = self.nodes(kind, a, b);
            for (i, &n) in nodes.iter().enumerate() {
                for c in 0..3 {
                    g[3 * n + c] += grad[3 * i + c];
                }
            }
            match (&mut hessians, hess) {
                (PairHessians::Scatter(values, pattern), Some(k)) => {
                    scatter(&k, &nodes, values, pattern, None)
                }
                (PairHessians::Collect(list), Some(k)) => list.push((nodes, k)),
                _ => {}
            }
        });
        value
    }

    /// The pairs closer than `d̂` at the step's start positions `start`,
    /// lagged for friction with coefficient `mu` (module docs,
    /// "Friction"): their nodes, closest-point weights and normal, and
    /// `mu lambda` with `lambda` the barrier's normal force there.
    pub fn lag_friction(&self, start: &[f64], mu: f64) -> Vec<LaggedPair> {
        let x = points(start);
        let s_hat = self.distance * self.distance;
        let mut out = Vec::new();
        self.for_close_pairs(&x, |kind, pos, c, a, b| {
            let r = (0..4).fold([0.0; 3], |acc, i| {
                crate::vec3::add(acc, crate::vec3::scale(pos[i], c.weights[i]))
            });
            let d = norm(r);
            let (_, b1, _) = super::barrier::barrier(c.d2, s_hat);
            // A mollified edge pair presses by its mollified force.
            let m = self
                .mollifier_eps(kind, a, b)
                .map_or(1.0, |eps| super::barrier::edge_mollifier(&pos, eps).0);
            if d > 0.0 && b1.is_finite() && m > 0.0 {
                out.push(LaggedPair {
                    nodes: self.nodes(kind, a, b),
                    weights: c.weights,
                    normal: crate::vec3::scale(r, 1.0 / d),
                    force: mu * m * self.kappa * (-b1) * 2.0 * d,
                });
            }
        });
        out
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
    /// pair apart (module docs); 0 for an increment that is not finite
    /// (no step along it is admissible: the step is cut back).
    pub fn max_step(&self, y: &[f64], dy: &[f64]) -> f64 {
        if !dy.iter().all(|v| v.is_finite()) {
            return 0.0;
        }
        let (x, p) = (points(y), points(dy));
        let reach = p.iter().map(|v| norm(*v)).fold(0.0f64, f64::max);
        if reach == 0.0 {
            return 1.0;
        }
        // The largest fraction CCD allows over `pairs`.
        let ccd = |pairs: &Candidates| {
            let mut t = 1.0f64;
            let kinds =
                (pairs.point_triangle.iter()).map(|&(q, k)| (PairKind::PointTriangle, q, k));
            let kinds = kinds.chain(
                pairs
                    .edge_edge
                    .iter()
                    .map(|&(e, k)| (PairKind::EdgeEdge, e, k)),
            );
            for (kind, a, b) in kinds {
                let n = self.nodes(kind, a, b);
                let (xn, pn) = (n.map(|i| x[i]), n.map(|i| p[i]));
                t = t.min(additive_ccd(kind, &xn, &pn, 0.0, CCD_SCALE, t));
            }
            t
        };
        // A short increment: the kept broad phase covers its sweep; a long
        // one: the boxes swept over it (a margin as long would take in far
        // too many pairs).
        if reach <= 2.0 * self.distance {
            self.with_candidates(&x, reach, ccd)
        } else {
            ccd(&swept_candidates(&x, &p, &self.triangles, &self.edges, 0.0))
        }
    }
}

/// A pair in contact at the start of a step, lagged for friction
/// ([`SelfContact::lag_friction`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaggedPair {
    /// Its four nodes.
    pub nodes: [usize; 4],
    /// `w`: the relative position of its closest points is `sum_i w_i x_i`.
    pub weights: [f64; 4],
    /// The unit normal from the second closest point to the first.
    pub normal: [f64; 3],
    /// `mu lambda` (N).
    pub force: f64,
}

/// The friction of one lagged pair (module docs, "Friction") for the nodes'
/// displacements `delta` over the step: the energy `mu lambda f0(|u|)`,
/// its gradient (12) and its Hessian (12 x 12, positive semi-definite),
/// and the work done against the slip `mu lambda f1 |u|`, with `e` the
/// smoothing slip.
pub fn pair_friction(
    pair: &LaggedPair,
    delta: &[[f64; 3]; 4],
    e: f64,
) -> (f64, [f64; 12], [f64; 144], f64) {
    let n = pair.normal;
    let w = pair.weights;
    let rel = (0..4).fold([0.0; 3], |acc, i| {
        crate::vec3::add(acc, crate::vec3::scale(delta[i], w[i]))
    });
    let dn = crate::vec3::dot(rel, n);
    let u: [f64; 3] = std::array::from_fn(|i| rel[i] - dn * n[i]);
    let s = norm(u);
    let (f0, f1, df1) = super::mollifier(s, e);
    let f = pair.force;
    let mut g = [0.0; 12];
    if s > 0.0 {
        for i in 0..4 {
            for a in 0..3 {
                g[3 * i + a] = f * f1 * w[i] * u[a] / s;
            }
        }
    }
    let (ca, cb) = if s > 0.0 {
        (f1 / s, (df1 - f1 / s) / (s * s))
    } else {
        (2.0 / e, 0.0)
    };
    let mut k = [0.0; 9];
    for a in 0..3 {
        for b in 0..3 {
            let t = f64::from(u8::from(a == b)) - n[a] * n[b];
            k[3 * a + b] = f * (ca * t + cb * u[a] * u[b]);
        }
    }
    let mut h = [0.0; 144];
    for i in 0..4 {
        for j in 0..4 {
            for a in 0..3 {
                for b in 0..3 {
                    h[(3 * i + a) * 12 + 3 * j + b] = w[i] * w[j] * k[3 * a + b];
                }
            }
        }
    }
    (f * f0, g, h, f * f1 * s)
}

/// What [`SelfContact::add`] does with the pairs' projected Hessians.
pub enum PairHessians<'a> {
    /// Nothing: value and gradient only.
    None,
    /// Adds them to values on a pattern (couplings it lacks to the
    /// diagonal).
    Scatter(&'a mut [f64], &'a SparsePattern),
    /// Keeps each with its four nodes (cleared first), for
    /// [`scatter_hessians`] onto another pattern later.
    Collect(&'a mut Vec<([usize; 4], [f64; 144])>),
}

/// Adds the pair Hessians `hessians` (as [`PairHessians::Collect`] keeps
/// them) to `values` on `pattern`, leaving out the held degrees of
/// freedom `fixed`: self-contact's couplings on the stepper's grown layout
/// (`integrator::grown`).
pub fn scatter_hessians(
    hessians: &[([usize; 4], [f64; 144])],
    values: &mut [f64],
    pattern: &SparsePattern,
    fixed: &[bool],
) {
    for (nodes, k) in hessians {
        scatter(k, nodes, values, pattern, Some(fixed));
    }
}

/// Where a Hessian goes: values on a pattern and, if given, the held
/// degrees of freedom to leave out.
pub type HessianTarget<'a> = (&'a mut [f64], &'a SparsePattern, Option<&'a [bool]>);

/// Adds the friction of `pairs` at `y` from the step's start `start` to
/// `g` and, with `h`, its Hessian on a pattern (couplings it lacks to the
/// diagonal; the held degrees of freedom left out when `fixed` is given);
/// returns the energy and the dissipation.
pub fn add_friction(
    pairs: &[LaggedPair],
    start: &[f64],
    y: &[f64],
    e: f64,
    g: Option<&mut [f64]>,
    h: Option<HessianTarget<'_>>,
) -> (f64, f64) {
    let (mut energy, mut dissipated) = (0.0, 0.0);
    let mut g = g;
    let mut h = h;
    for pair in pairs {
        let delta: [[f64; 3]; 4] = pair
            .nodes
            .map(|a| std::array::from_fn(|i| y[3 * a + i] - start[3 * a + i]));
        let (v, grad, hess, work) = pair_friction(pair, &delta, e);
        energy += v;
        dissipated += work;
        if let Some(g) = g.as_deref_mut() {
            for (i, &a) in pair.nodes.iter().enumerate() {
                for c in 0..3 {
                    g[3 * a + c] += grad[3 * i + c];
                }
            }
        }
        if let Some((values, pattern, fixed)) = h.as_mut() {
            scatter(&hess, &pair.nodes, values, pattern, *fixed);
        }
    }
    (energy, dissipated)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::proximity::test_plies;

    /// Issue 46: two plies 4 mm apart, `d̂` = 1 mm. A Newton increment
    /// that throws one node of the upper ply a metre down through the
    /// lower is cut to a fraction that stops it above the lower ply (the
    /// broad phase no longer enters its swept box in half a million
    /// cells); an increment that is not finite admits no step.
    #[test]
    fn a_far_or_infinite_increment_is_cut_short() {
        let (x, triangles) = test_plies(&[0.0, 0.004]);
        let y: Vec<f64> = x.concat();
        let sc = SelfContact::new(triangles, &y, 1e-3, 5e4).unwrap();
        // A node inside the upper ply (row 4, column 4 of 9 x 9).
        let node = 81 + 40;
        let mut dy = vec![0.0; y.len()];
        dy[3 * node..3 * node + 3].copy_from_slice(&[0.6, 0.6, -0.6]);
        let t = sc.max_step(&y, &dy);
        // Its 4 mm fall to the lower ply is 1/150 of the increment.
        assert!(t > 0.0 && t < 0.004 / 0.6, "{t}");
        for bad in [f64::INFINITY, f64::NAN] {
            dy[3 * node] = bad;
            assert_eq!(sc.max_step(&y, &dy), 0.0);
        }
    }
}
