//! The position field's derivatives at an edge's midpoint, fitted once on
//! the reference mesh and shared by the edge's two triangles.
//!
//! An interior edge `(a, b)` between triangles `(a, b, c)` and `(b, a, d)`
//! has a chart: its midpoint `M`, the unit tangent `t = (X_b - X_a) / l`,
//! the mean unit normal `N` of its two triangles and the cross-edge
//! direction `m = N x t`. Every node `k` near the edge has chart
//! coordinates `P_k = ((X_k - M) . t, (X_k - M) . m)`. The quadratic
//!
//! ```text
//! q(P) = c_0 + c_1 P_t + c_2 P_m + c_3 P_t^2 / 2 + c_4 P_m^2 / 2 + c_5 P_t P_m
//! ```
//!
//! **interpolates** the four nodes of the two triangles (`a, b, c, d`) and
//! fits the nodes opposite their four other edges (up to four) **by least
//! squares** — an equality-constrained least-squares problem, solved once
//! through its KKT system. Its derivatives at `M` are linear in the nodes'
//! positions:
//!
//! ```text
//! x_,t(M) = sum_k T_k x_k,    x_,m(M) = sum_k S_k x_k
//! ```
//!
//! (3-vectors: the same coefficients fit each component). Both are exact
//! for every quadratic field, and `x_,t(M) = (x_b - x_a) / l` exactly,
//! because `q` interpolates `a` and `b` and is a parabola along the edge.
//! Where the opposite nodes do not fix the quadratic (fewer than two of
//! them, as near corners and in strips one element wide), the nearest
//! further neighbours of the four nodes are added, two at the most.
//!
//! A **boundary edge** has no second triangle: its tangential derivative
//! is the chord's, and the derivative across it is left free (a free or
//! simply supported edge rotates freely: [`super::patch`] condenses it
//! out of the stiffness); an edge whose two nodes a `[[fix]] clamp = true`
//! holds is **clamped**: the derivative across it is the reference
//! surface's, a constant. An interior edge whose quadratic is not fixed
//! even then is treated as free.
//!
//! Why one derivative per edge, shared: see [`super::patch`] — it makes the
//! triangles' curvatures sum, over any patch of the mesh, to a boundary
//! term (a discrete divergence theorem), which no oscillation of the nodes
//! can change; a curvature fitted triangle by triangle has no such sum, and
//! on criss-cross meshes an `O(h^2)` oscillation of half the nodes lowers
//! the energy of every smooth shape (docs/theory.md §1.10).

use crate::vec3::{cross, dot, norm, scale, sub};

/// Largest number of nodes one edge's fit uses: the four of its two
/// triangles, four opposite nodes, two further neighbours.
pub const MAX_EDGE_NODES: usize = 10;

/// How an edge's cross derivative is known.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EdgeKind {
    /// Fitted from the nodes around the edge.
    Fitted,
    /// Free: a boundary edge (or one whose fit is not unique): the
    /// patches condense it out.
    Free,
    /// Clamped: the reference surface's slope, held.
    Clamped,
}

/// One edge's chart and the coefficients of its derivatives.
#[derive(Debug, Clone)]
pub struct EdgeFit {
    /// How the cross derivative is known.
    pub kind: EdgeKind,
    /// The nodes the derivatives combine (`a`, `b` first).
    pub nodes: Vec<usize>,
    /// `T_k`: `x_,t(M) = sum_k T_k x_k` (1/m).
    pub along: Vec<f64>,
    /// `S_k`: `x_,m(M) = sum_k S_k x_k` (1/m); empty unless fitted.
    pub across: Vec<f64>,
    /// `W_k`: the quadratic's value at the midpoint, `q(M) = sum_k W_k
    /// x_k` (the chord's midpoint, `1/2, 1/2`, unless fitted): where a
    /// refinement places the node that halves the edge, on the surface
    /// the fit describes. The weights sum to 1 (a rigid motion moves it
    /// rigidly) and are exact for every quadratic field.
    pub middle: Vec<f64>,
    /// The unit tangent `t`, from the edge's lower-numbered node.
    pub tangent: [f64; 3],
    /// The unit cross-edge direction `m = N x t` of the chart.
    pub cross: [f64; 3],
    /// The edge's length `l` (m).
    pub length: f64,
}

/// The nodes around an interior edge: its two triangles' four nodes and
/// the candidates for the least-squares part.
pub struct EdgeNodes<'a> {
    /// `a`, `b`: the edge's nodes (the lower-numbered first).
    pub ends: [usize; 2],
    /// `c`, `d`: the nodes opposite it in its two triangles (`None`: a
    /// boundary edge).
    pub opposite: [Option<usize>; 2],
    /// The nodes opposite the two triangles' other edges.
    pub outer: &'a [usize],
    /// Further candidates, nearest first, where `outer` does not fix the
    /// quadratic.
    pub further: &'a [usize],
    /// The unit normals of the edge's triangles (one for a boundary edge).
    pub normals: [Option<[f64; 3]>; 2],
}

impl EdgeFit {
    /// The derivatives at the midpoint of the edge `nodes`, at reference
    /// positions `x`; `clamped`: both ends held by a clamp.
    pub fn new(e: &EdgeNodes<'_>, x: &[[f64; 3]], clamped: bool) -> Self {
        let [a, b] = e.ends;
        let (xa, xb) = (x[a], x[b]);
        let chord = sub(xb, xa);
        let length = norm(chord);
        let tangent = scale(chord, 1.0 / length);
        let normal = match e.normals {
            [Some(n0), Some(n1)] => {
                let s = crate::vec3::add(n0, n1);
                let r = norm(s);
                if r > 1e-8 { scale(s, 1.0 / r) } else { n0 }
            }
            [Some(n), None] | [None, Some(n)] => n,
            [None, None] => [0.0, 0.0, 1.0],
        };
        let cross_dir = {
            let m = cross(normal, tangent);
            scale(m, 1.0 / norm(m))
        };
        let chord_only = |kind| Self {
            kind,
            nodes: vec![a, b],
            along: vec![-1.0 / length, 1.0 / length],
            across: Vec::new(),
            middle: vec![0.5, 0.5],
            tangent,
            cross: cross_dir,
            length,
        };
        if clamped {
            return chord_only(EdgeKind::Clamped);
        }
        let [Some(c), Some(d)] = e.opposite else {
            return chord_only(EdgeKind::Free);
        };
        let mid = scale(crate::vec3::add(xa, xb), 0.5);
        // Chart coordinates, in units of the edge's length.
        let chart = |k: usize| {
            let r = sub(x[k], mid);
            [dot(r, tangent) / length, dot(r, cross_dir) / length]
        };
        let inner = [a, b, c, d];
        let mut outer: Vec<usize> = Vec::with_capacity(6);
        for &k in e.outer {
            if !inner.contains(&k) && !outer.contains(&k) {
                outer.push(k);
            }
        }
        let further: Vec<usize> = e
            .further
            .iter()
            .copied()
            .filter(|k| !inner.contains(k) && !outer.contains(k))
            .collect();
        let mut further = further.iter();
        let mut added = 0;
        loop {
            if let Some((middle, along, across)) =
                constrained_fit(&inner.map(chart), &outer, &chart)
            {
                let mut nodes = inner.to_vec();
                nodes.extend_from_slice(&outer);
                return Self {
                    kind: EdgeKind::Fitted,
                    nodes,
                    along: along.iter().map(|v| v / length).collect(),
                    across: across.iter().map(|v| v / length).collect(),
                    middle,
                    tangent,
                    cross: cross_dir,
                    length,
                };
            }
            match further.next() {
                Some(&k) if added < 2 => {
                    outer.push(k);
                    added += 1;
                }
                _ => return chord_only(EdgeKind::Free),
            }
        }
    }
}

/// The quadratic monomials at chart point `p`: `1, P_t, P_m, P_t^2 / 2,
/// P_m^2 / 2, P_t P_m`.
fn monomials(p: [f64; 2]) -> [f64; 6] {
    [
        1.0,
        p[0],
        p[1],
        0.5 * p[0] * p[0],
        0.5 * p[1] * p[1],
        p[0] * p[1],
    ]
}

/// The value and the derivatives at the origin (`c_0`, `c_1`, `c_2`) of
/// the quadratic through the four `inner` points that fits the `outer`
/// nodes (charted by `chart`) by least squares, as coefficients of the
/// node values, inner first; `None` where it is not unique.
#[allow(clippy::type_complexity)]
fn constrained_fit(
    inner: &[[f64; 2]; 4],
    outer: &[usize],
    chart: &impl Fn(usize) -> [f64; 2],
) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    // KKT: [V_o^T V_o  V_i^T; V_i  0] [c; lambda] = [V_o^T w_o; w_i].
    const N: usize = 10;
    let ko = outer.len();
    let k = 4 + ko;
    let mut kkt = [[0.0; N]; N];
    let vo: Vec<[f64; 6]> = outer.iter().map(|&o| monomials(chart(o))).collect();
    for r in 0..6 {
        for s in 0..6 {
            kkt[r][s] = vo.iter().map(|v| v[r] * v[s]).sum();
        }
    }
    for (i, p) in inner.iter().enumerate() {
        let v = monomials(*p);
        for s in 0..6 {
            kkt[6 + i][s] = v[s];
            kkt[s][6 + i] = v[s];
        }
    }
    // Right-hand sides, one per node value (inner, then outer).
    let mut rhs = vec![[0.0; N]; k];
    for (i, row) in rhs.iter_mut().take(4).enumerate() {
        row[6 + i] = 1.0;
    }
    for (o, v) in vo.iter().enumerate() {
        rhs[4 + o][..6].copy_from_slice(v);
    }
    solve_dense(kkt, &mut rhs)?;
    Some((
        rhs.iter().map(|r| r[0]).collect(),
        rhs.iter().map(|r| r[1]).collect(),
        rhs.iter().map(|r| r[2]).collect(),
    ))
}

/// Solves `A x = b` in place for each `b` in `rhs` by Gaussian elimination
/// with partial pivoting; `None` when a pivot falls below `1e-10` of the
/// matrix's largest entry (not unique).
fn solve_dense<const N: usize>(mut a: [[f64; N]; N], rhs: &mut [[f64; N]]) -> Option<()> {
    let big = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    if big.is_nan() || big <= 0.0 {
        return None;
    }
    let mut perm: [usize; N] = std::array::from_fn(|i| i);
    for col in 0..N {
        let p = (col..N).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[p][col].abs() <= 1e-10 * big || a[p][col].is_nan() {
            return None;
        }
        a.swap(col, p);
        perm.swap(col, p);
        for r in col + 1..N {
            let f = a[r][col] / a[col][col];
            if f != 0.0 {
                for c in col..N {
                    a[r][c] -= f * a[col][c];
                }
            }
            a[r][col] = f;
        }
    }
    for b in rhs.iter_mut() {
        let mut y: [f64; N] = std::array::from_fn(|i| b[perm[i]]);
        for r in 0..N {
            for c in 0..r {
                y[r] -= a[r][c] * y[c];
            }
        }
        for r in (0..N).rev() {
            for c in r + 1..N {
                y[r] -= a[r][c] * y[c];
            }
            y[r] /= a[r][r];
        }
        *b = y;
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a grid of unit squares, the fit's derivatives at an interior
    /// edge's midpoint are exact for every quadratic field, whatever the
    /// diagonals, and the tangential one is the chord's.
    #[test]
    fn derivatives_are_exact_for_quadratics() {
        // Nodes of a 4 x 4 patch of points (i, j), jittered.
        let mut x = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                let jitter = 0.1 * ((3 * i + 7 * j) as f64).sin();
                x.push([i as f64 + jitter, j as f64 - 0.5 * jitter, 0.0]);
            }
        }
        let id = |i: usize, j: usize| j * 4 + i;
        // Edge (1,1)-(2,1) between triangles with (1,2) and (2,0).
        let e = EdgeNodes {
            ends: [id(1, 1), id(2, 1)],
            opposite: [Some(id(1, 2)), Some(id(2, 0))],
            outer: &[id(2, 2), id(0, 1), id(1, 0), id(3, 1)],
            further: &[],
            normals: [Some([0.0, 0.0, 1.0]), Some([0.0, 0.0, 1.0])],
        };
        let fit = EdgeFit::new(&e, &x, false);
        assert_eq!(fit.kind, EdgeKind::Fitted);
        let mid = scale(crate::vec3::add(x[id(1, 1)], x[id(2, 1)]), 0.5);
        // A quadratic height field z = f(x, y).
        let f = |p: [f64; 3]| {
            0.3 + 0.2 * p[0] - 0.7 * p[1] + 0.5 * p[0] * p[0] - 0.4 * p[0] * p[1]
                + 0.9 * p[1] * p[1]
        };
        let grad = |p: [f64; 3]| [0.2 + p[0] - 0.4 * p[1], -0.7 - 0.4 * p[0] + 1.8 * p[1]];
        let g = grad(mid);
        let want_t = g[0] * fit.tangent[0] + g[1] * fit.tangent[1];
        let want_m = g[0] * fit.cross[0] + g[1] * fit.cross[1];
        let got_t: f64 = fit
            .nodes
            .iter()
            .zip(&fit.along)
            .map(|(&k, c)| c * f(x[k]))
            .sum();
        let got_m: f64 = fit
            .nodes
            .iter()
            .zip(&fit.across)
            .map(|(&k, c)| c * f(x[k]))
            .sum();
        assert!((got_t - want_t).abs() < 1e-12, "{got_t} {want_t}");
        assert!((got_m - want_m).abs() < 1e-12, "{got_m} {want_m}");
        let chord = (f(x[id(2, 1)]) - f(x[id(1, 1)])) / fit.length;
        assert!((got_t - chord).abs() < 1e-12);
    }
}
