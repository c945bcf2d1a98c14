//! A triangle's bending patch: its constant curvature as a linear function
//! of the positions of the nodes around it, fitted once on the reference
//! mesh.
//!
//! The mean of the position field's second derivatives over a triangle `T`
//! (area `A`, reference frame `(e_1, e_2)`: the projected warp for a woven
//! fabric) is, by the divergence theorem, a sum over its three edges `e`
//! (length `l_e`, outward unit normal `nu` in `T`'s plane, tangent `t`):
//!
//! ```text
//! v_ab = 1/A int_T x_,ab dA = 1/A sum_e l_e x_,a(M_e) nu_b
//!      = 1/A sum_e l_e (t_a x_,t + nu_a x_,nu)(M_e) nu_b
//! ```
//!
//! (the midpoint rule, exact for the linear gradient of a quadratic
//! field), with the derivatives at each edge's midpoint `M_e` taken from
//! the edge's own fit ([`super::edge`]), **one per edge, shared by its two
//! triangles**: `x_,t` the chord's, `x_,nu = s x_,m` with `s = sign(nu .
//! m)`. The curvature is the normal component, Voigt `(kappa_11, kappa_22,
//! 2 kappa_12)`:
//!
//! ```text
//! kappa_j = n . v_j,   v = (v_11, v_22, v_12 + v_21) = sum_k C_k x_k + v_0
//! ```
//!
//! `C` (3 x nodes, 1/m^2) is stored; `v_0` is the constant part of a
//! clamped edge. Because the edge derivatives are exact for quadratic
//! fields, so is the curvature, on every mesh (consistency). Because each
//! is shared, the triangles' `A v` summed over any region of the mesh
//! leave only the region's boundary edges (a discrete divergence theorem):
//! a local oscillation of the nodes cannot shift the region's mean
//! curvature, which is what made the patch through a triangle's six nodes
//! (Oñate & Zárate 2000; Flores & Oñate 2005) soft by +74 % on criss-cross
//! meshes (docs/validation.md). The structure is Morley's (1971) element —
//! constant curvature from the normal slopes at the edge midpoints — with
//! the mid-edge slopes computed from the nodes (rotation-free), as in the
//! Basic Shell Triangle; the quadratic edge fit in place of the two
//! triangles' averaged gradients makes it exact on irregular meshes.
//!
//! **Boundaries.** A free or simply supported edge rotates freely: its
//! cross slope `s_e = n . x_,nu` is a free unknown, minimised out of the
//! energy once, which condenses the constitutive matrix to
//!
//! ```text
//! D' = D - D F (F^T D F)^-1 F^T D,   F = [l_e / A Voigt(nu nu^T)]
//! ```
//!
//! (the moment normal to the edge vanishes). A **clamped edge** (`[[fix]]
//! clamp = true`: both its nodes held) keeps the reference surface's slope
//! across it: `x_,nu = nu`, a constant of `v_0`. A triangle with every
//! node clamped carries no patch, nor does one whose three edges are free.

use super::edge::{EdgeFit, EdgeKind};
use crate::element::geometry::in_plane_axis;
use crate::vec3::{add, cross, dot, norm, scale, sub};

/// Largest number of nodes of a patch: its triangle's three, the three
/// across its edges, two beyond each neighbour and two further nodes per
/// edge where a fit needs them ([`super::edge`]).
pub const MAX_NODES: usize = 18;

/// One triangle's bending patch: its nodes, its curvature coefficients,
/// its condensed stiffness and its reference curvature.
#[derive(Debug, Clone)]
pub struct Patch {
    /// Global nodes: the triangle's three vertices, then the others its
    /// edges' fits use.
    nodes: [usize; MAX_NODES],
    len: u8,
    /// `C_jk`: Voigt component `j` of `v` per unit position of local node
    /// `k` (1/m^2).
    pub coefficients: [[f64; MAX_NODES]; 3],
    /// `v_0`: the constant part of `v` (1/m), from clamped edges.
    pub offset: [[f64; 3]; 3],
    /// `A D'` (N m^3): the reference area times the condensed bending
    /// stiffness (Voigt, for `kappa_11, kappa_22, 2 kappa_12`).
    pub stiffness: [[f64; 3]; 3],
    /// Curvature of the reference configuration, `kappa_0` (1/m).
    pub rest: [f64; 3],
    /// The triangle's reference area `A` (m^2).
    pub area: f64,
    /// How many of its edges are clamped.
    pub clamped_edges: u8,
    /// The frame `(e_1, e_2)` of its curvatures, in the reference
    /// configuration.
    pub frame: [[f64; 3]; 2],
    /// The mesh element the triangle belongs to (set by
    /// [`super::Bending::new`]).
    pub element: usize,
}

/// Why a patch cannot be fitted.
#[derive(Debug, Clone, PartialEq)]
pub enum PatchError {
    /// The triangle has no area.
    Degenerate,
    /// The frame direction is (nearly) normal to the triangle.
    Frame,
}

impl Patch {
    /// Number of nodes (3 to [`MAX_NODES`]).
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    /// Whether the patch has no nodes (never: a patch has at least its
    /// triangle's three).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The patch's global nodes.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes[..self.len()]
    }

    /// The positions of the patch's nodes into `out` (its first
    /// [`Self::len`] entries), node `a` at `at(a)`.
    #[inline]
    pub fn positions(&self, at: impl Fn(usize) -> [f64; 3], out: &mut [[f64; 3]]) {
        for (k, &a) in self.nodes().iter().enumerate() {
            out[k] = at(a);
        }
    }

    /// The patch of triangle `vertices` at reference positions `x`, from
    /// the fits of its edges (`edges[m]`: the edge opposite vertex `m`),
    /// with constitutive matrix `d` (Voigt, N m) given in the frame whose
    /// first axis is `axis` projected on the triangle's plane (`None`:
    /// along its first edge, for an isotropic `d`). `None` where it cannot
    /// bend: all three edges free.
    pub fn fit(
        vertices: [usize; 3],
        edges: [&EdgeFit; 3],
        x: &[[f64; 3]],
        d: &[[f64; 3]; 3],
        axis: Option<[f64; 3]>,
    ) -> Result<Option<Self>, PatchError> {
        let [x0, x1, x2] = vertices.map(|v| x[v]);
        let m = cross(sub(x1, x0), sub(x2, x0));
        let twice_area = norm(m);
        let scale_len = norm(sub(x1, x0)).max(norm(sub(x2, x0)));
        if twice_area.is_nan() || twice_area <= 1e-12 * scale_len * scale_len {
            return Err(PatchError::Degenerate);
        }
        if edges.iter().all(|e| e.kind == EdgeKind::Free) {
            return Ok(None);
        }
        let normal = scale(m, 1.0 / twice_area);
        let e1 = match axis {
            Some(a) => in_plane_axis(a, normal).ok_or(PatchError::Frame)?,
            None => {
                let a = sub(x1, x0);
                let t = sub(a, scale(normal, dot(a, normal)));
                scale(t, 1.0 / norm(t))
            }
        };
        let e2 = cross(normal, e1);
        let area = 0.5 * twice_area;
        let xs = [x0, x1, x2];

        let mut nodes = [usize::MAX; MAX_NODES];
        nodes[..3].copy_from_slice(&vertices);
        let mut len = 3;
        let mut coefficients = [[0.0; MAX_NODES]; 3];
        let mut offset = [[0.0; 3]; 3];
        let mut free: Vec<[f64; 3]> = Vec::new();
        let mut clamped_edges = 0;
        for (vm, edge) in edges.iter().enumerate() {
            let (pa, pb) = (xs[(vm + 1) % 3], xs[(vm + 2) % 3]);
            // The outward normal in T's plane: away from vertex m.
            let mut nu = cross(edge.tangent, normal);
            nu = scale(nu, 1.0 / norm(nu));
            if dot(nu, sub(scale(add(pa, pb), 0.5), xs[vm])) < 0.0 {
                nu = scale(nu, -1.0);
            }
            let (t, n2) = (
                [dot(edge.tangent, e1), dot(edge.tangent, e2)],
                [dot(nu, e1), dot(nu, e2)],
            );
            let w = edge.length / area;
            let along = [t[0] * n2[0], t[1] * n2[1], t[0] * n2[1] + t[1] * n2[0]].map(|v| w * v);
            let normal_part = [n2[0] * n2[0], n2[1] * n2[1], 2.0 * n2[0] * n2[1]].map(|v| w * v);
            let sign = if dot(nu, edge.cross) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            for (i, &node) in edge.nodes.iter().enumerate() {
                let k = match nodes[..len].iter().position(|&a| a == node) {
                    Some(k) => k,
                    None => {
                        // MAX_NODES bounds every union of three edge fits.
                        nodes[len] = node;
                        len += 1;
                        len - 1
                    }
                };
                let across = edge.across.get(i).copied().unwrap_or(0.0);
                for j in 0..3 {
                    coefficients[j][k] += along[j] * edge.along[i] + normal_part[j] * sign * across;
                }
            }
            match edge.kind {
                EdgeKind::Fitted => {}
                EdgeKind::Free => free.push(normal_part),
                EdgeKind::Clamped => {
                    clamped_edges += 1;
                    for j in 0..3 {
                        offset[j] = add(offset[j], scale(nu, normal_part[j]));
                    }
                }
            }
        }
        let reduced = condense(d, &free);
        let stiffness = reduced.map(|row| row.map(|v| area * v));
        let mut patch = Self {
            nodes,
            len: len as u8,
            coefficients,
            offset,
            stiffness,
            rest: [0.0; 3],
            area,
            clamped_edges,
            frame: [e1, e2],
            element: 0,
        };
        let mut at = [[0.0; 3]; MAX_NODES];
        patch.positions(|a| x[a], &mut at);
        patch.rest = patch.curvature(&at[..len]);
        Ok(Some(patch))
    }

    /// The curvatures `kappa` (Voigt: `kappa_11, kappa_22, 2 kappa_12`) of the
    /// patch at positions `x` (its nodes' positions, in the patch's order):
    /// `kappa_j = n . v_j` ([`super::kernel`] has the symbols).
    pub fn curvature(&self, x: &[[f64; 3]]) -> [f64; 3] {
        let n = normal(x).0;
        let mut kappa = [0.0; 3];
        for (j, kj) in kappa.iter_mut().enumerate() {
            let v = self.second_derivative(x, j);
            *kj = dot(n, v);
        }
        kappa
    }

    /// `v_j = sum_k C_jk x_k + v_0j`.
    #[inline]
    pub(super) fn second_derivative(&self, x: &[[f64; 3]], j: usize) -> [f64; 3] {
        let mut v = self.offset[j];
        for (k, xk) in x.iter().enumerate() {
            let c = self.coefficients[j][k];
            for i in 0..3 {
                v[i] += c * xk[i];
            }
        }
        v
    }
}

/// The unit normal of the patch's triangle (its first three positions in
/// `x`) and `|m|`, twice its area.
#[inline]
pub(super) fn normal(x: &[[f64; 3]]) -> ([f64; 3], f64) {
    let m = cross(sub(x[1], x[0]), sub(x[2], x[0]));
    let r = norm(m);
    (scale(m, 1.0 / r), r)
}

/// `D - D F (F^T D F)^-1 F^T D`: `d` with the curvature directions `free`
/// condensed out (energy minimised over them); zero when they span all.
fn condense(d: &[[f64; 3]; 3], free: &[[f64; 3]]) -> [[f64; 3]; 3] {
    let mut out = *d;
    // One direction at a time: condensing successively is the same as at
    // once (a sequence of rank-one updates of the Schur complement).
    for f in free {
        let df: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| out[i][j] * f[j]).sum());
        let fdf: f64 = (0..3).map(|i| f[i] * df[i]).sum();
        let scale_d: f64 = (0..3).map(|i| out[i][i].abs()).sum::<f64>() * dot(*f, *f);
        if fdf <= 1e-12 * scale_d {
            continue;
        }
        for i in 0..3 {
            for j in 0..3 {
                out[i][j] -= df[i] * df[j] / fdf;
            }
        }
    }
    out
}
