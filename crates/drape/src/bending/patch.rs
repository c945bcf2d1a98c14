//! The quadratic surface of a triangle's patch, fitted once on the
//! reference mesh.
//!
//! For a triangle `T` with vertices `X_0..X_2` and the vertices `X_p` of
//! its neighbours opposite its edges, in a Cartesian frame `(e_1, e_2)` of
//! `T`'s reference plane (the projected warp direction for a woven
//! fabric), the patch's surface is
//!
//! ```text
//! q(P) = sum_v lambda_v(P) x_v + sum_m c_m b_m(P),   b_m = 4 lambda_j lambda_k
//! ```
//!
//! with `lambda` `T`'s barycentric coordinates and `b_m` the bubble of the
//! edge opposite vertex `m` (between vertices `j` and `k`). Each opposite
//! vertex `p` gives one equation, `q(P_p) = x_p`; their solution `c = G r`
//! (`r_p = x_p - sum_v lambda_v(P_p) x_v`) makes `q` reproduce every
//! quadratic, so the curvature below is exact for every quadratic surface
//! on every mesh — the consistency that a hinge's dihedral angle lacks on
//! irregular meshes. The second derivatives of `q`,
//!
//! ```text
//! (q_,11  q_,22  2 q_,12) = sum_m c_m hhat_m,   hhat_m = Voigt(Hess b_m)
//!                         = sum_k C_k x_k
//! ```
//!
//! are constant on the patch; `C` (3 x nodes) is stored.
//!
//! A boundary edge has no opposite vertex: its equation is missing and `c`
//! is free along the null space `z` of the remaining equations. Minimising
//! the energy over that freedom (a free rotation of the edge: the natural
//! condition of a free or simply supported edge, as a free mid-edge
//! rotation in Morley's element) condenses the constitutive matrix to
//!
//! ```text
//! D' = D - D F (F^T D F)^-1 F^T D,   F = [hhat(z) for z in null]
//! ```
//!
//! A **clamped edge** (`[[fix]] clamp = true`: both its nodes held, its
//! triangle's third vertex free) holds the slope across it: the node
//! opposite it is a ghost, the mirror image of the triangle's own third
//! vertex `X_m` across the edge, in the reference plane of the triangle,
//!
//! ```text
//! x_g = a + R (x_m - a),   R = I - 2 m m^T
//! ```
//!
//! (`a` a node of the edge, held; `m` the unit vector of the reference
//! plane normal to the edge): the clamped-edge treatment of the Basic
//! Shell Triangle (Oñate & Zárate 2000, §4), for which the surface through
//! the patch has, across the edge, the slope of its reference plane — a
//! beam clamped at a node and bent to `w` at the next one `h` away gets
//! the curvature `2 w / h^2` of a clamp at that node, where the held
//! triangle beyond gave `w / h^2`, a clamp half an element further. The
//! ghost moves with `x_m`, so its derivatives are folded onto `x_m` by
//! `R` ([`super::kernel::fold`]).
//!
//! The patch is the rotation-free triangle of Oñate & Zárate (2000,
//! "Rotation-free triangular plate and shell elements", Int. J. Numer.
//! Meth. Engng 47) with the quadratic interpolation over the patch of
//! Flores & Oñate (2005, "Improvements in the membrane behaviour of the
//! three node rotation-free BST shell triangle using an assumed strain
//! approach", CMAME 194): curvatures constant on each triangle, the
//! unknowns the nodal positions only.

use crate::element::geometry::in_plane_axis;
use crate::vec3::{cross, dot, norm, scale, sub};

/// One triangle's bending patch: its nodes, its curvature coefficients,
/// its condensed stiffness and its reference curvature.
#[derive(Debug, Clone)]
pub struct Patch {
    /// Global nodes: the triangle's three vertices, then the opposite
    /// vertices that exist (up to 3).
    pub nodes: [usize; 6],
    len: u8,
    /// `C_jk`: Voigt component `j` of `(q_,11, q_,22, 2 q_,12)` per unit
    /// position of local node `k` (1/m^2).
    pub coefficients: [[f64; 6]; 3],
    /// `A D'` (N m^3): the reference area times the condensed bending
    /// stiffness (Voigt, for `kappa_11, kappa_22, 2 kappa_12`).
    pub stiffness: [[f64; 3]; 3],
    /// Curvature of the reference configuration, `kappa_0` (1/m).
    pub rest: [f64; 3],
    /// The ghost across a clamped edge, if any (its slot in `nodes` holds
    /// the global node it mirrors).
    pub ghost: Option<Ghost>,
}

/// The mirror image of a triangle's vertex across its clamped edge (the
/// module docs): a patch node whose position follows the vertex's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ghost {
    /// Its local index among the patch's nodes (3 to 5).
    pub slot: usize,
    /// The local index of the vertex it mirrors (0 to 2).
    pub vertex: usize,
    /// A node of the clamped edge, at its (held) reference position (m).
    pub anchor: [f64; 3],
    /// The reflection `R = I - 2 m m^T` (symmetric).
    pub reflect: [[f64; 3]; 3],
}

impl Ghost {
    /// The ghost's position when the vertex it mirrors is at `x`.
    #[inline]
    pub fn position(&self, x: [f64; 3]) -> [f64; 3] {
        let d = sub(x, self.anchor);
        std::array::from_fn(|i| self.anchor[i] + dot(self.reflect[i], d))
    }
}

/// Why a patch cannot be fitted.
#[derive(Debug, Clone, PartialEq)]
pub enum PatchError {
    /// The triangle has no area.
    Degenerate,
    /// The frame direction is (nearly) normal to the triangle.
    Frame,
    /// The six nodes lie (nearly) on a conic of the plane: the quadratic
    /// surface through them is not unique.
    Conic,
}

impl Patch {
    /// Number of nodes (3 to 6).
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    /// Whether the patch has no nodes (never: a patch has at least its
    /// triangle's three).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The patch's global nodes (a ghost's slot holds the node it
    /// mirrors).
    pub fn nodes(&self) -> &[usize] {
        &self.nodes[..self.len()]
    }

    /// The positions of the patch's nodes into `out` (its first
    /// [`Self::len`] entries), node `a` at `at(a)`, the ghost's mirrored.
    #[inline]
    pub fn positions(&self, at: impl Fn(usize) -> [f64; 3], out: &mut [[f64; 3]]) {
        for (k, &a) in self.nodes().iter().enumerate() {
            out[k] = at(a);
        }
        if let Some(g) = &self.ghost {
            out[g.slot] = g.position(out[g.vertex]);
        }
    }

    /// Fits the patch of triangle `vertices` with opposite vertices
    /// `opposite[m]` (across the edge opposite vertex `m`, `None` on a
    /// boundary), at reference positions `x`, with constitutive matrix
    /// `d` (Voigt, N m) given in the frame whose first axis is `axis`
    /// projected on the triangle's plane (`None`: along the first edge,
    /// for an isotropic `d`). With `clamped = Some(m)` the edge opposite
    /// vertex `m` is clamped: its opposite node is the ghost of vertex `m`
    /// (the module docs), in place of `opposite[m]`.
    pub fn fit(
        vertices: [usize; 3],
        opposite: [Option<usize>; 3],
        x: &[[f64; 3]],
        d: &[[f64; 3]; 3],
        axis: Option<[f64; 3]>,
        clamped: Option<usize>,
    ) -> Result<Self, PatchError> {
        let [x0, x1, x2] = vertices.map(|v| x[v]);
        let m = cross(sub(x1, x0), sub(x2, x0));
        let twice_area = norm(m);
        let scale_len = norm(sub(x1, x0)).max(norm(sub(x2, x0)));
        if twice_area.is_nan() || twice_area <= 1e-12 * scale_len * scale_len {
            return Err(PatchError::Degenerate);
        }
        let normal = scale(m, 1.0 / twice_area);
        let e1 = match axis {
            Some(a) => in_plane_axis(a, normal).ok_or(PatchError::Frame)?,
            None => {
                // An edge of the triangle: in its plane.
                let a = sub(x1, x0);
                let t = sub(a, scale(normal, dot(a, normal)));
                scale(t, 1.0 / norm(t))
            }
        };
        let e2 = cross(normal, e1);
        let c = scale(crate::vec3::add(crate::vec3::add(x0, x1), x2), 1.0 / 3.0);
        let local = |p: [f64; 3]| {
            let d = sub(p, c);
            [dot(d, e1), dot(d, e2)]
        };
        let pv = [x0, x1, x2].map(local);
        let area2 = (pv[1][0] - pv[0][0]) * (pv[2][1] - pv[0][1])
            - (pv[1][1] - pv[0][1]) * (pv[2][0] - pv[0][0]);
        // grad lambda_i = perp(P_k - P_j) / (2A), (i, j, k) cyclic.
        let grad: [[f64; 2]; 3] = std::array::from_fn(|i| {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let u = [pv[k][0] - pv[j][0], pv[k][1] - pv[j][1]];
            [-u[1] / area2, u[0] / area2]
        });
        let lambda = |p: [f64; 2]| -> [f64; 3] {
            std::array::from_fn(|i| {
                let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                let a = [pv[j][0] - p[0], pv[j][1] - p[1]];
                let b = [pv[k][0] - p[0], pv[k][1] - p[1]];
                (a[0] * b[1] - a[1] * b[0]) / area2
            })
        };
        // hhat_m = Voigt(Hess b_m), b_m = 4 lambda_j lambda_k.
        let hhat: [[f64; 3]; 3] = std::array::from_fn(|m| {
            let (j, k) = ((m + 1) % 3, (m + 2) % 3);
            let (gj, gk) = (grad[j], grad[k]);
            [
                8.0 * gj[0] * gk[0],
                8.0 * gj[1] * gk[1],
                2.0 * 4.0 * (gj[0] * gk[1] + gj[1] * gk[0]),
            ]
        });
        let bubble = |l: [f64; 3]| -> [f64; 3] {
            std::array::from_fn(|m| 4.0 * l[(m + 1) % 3] * l[(m + 2) % 3])
        };

        // The equations of the opposite vertices that exist (and the
        // ghost's, across a clamped edge).
        let mut nodes = [usize::MAX; 6];
        nodes[..3].copy_from_slice(&vertices);
        let mut len = 3;
        let mut rows: Vec<[f64; 3]> = Vec::new();
        let mut lambdas: Vec<[f64; 3]> = Vec::new();
        let mut ghost = None;
        for (m, p) in opposite.iter().enumerate() {
            let (position, node) = if clamped == Some(m) {
                let g = Ghost::across([x0, x1, x2], m, normal, len);
                ghost = Some(g);
                (g.position([x0, x1, x2][m]), vertices[m])
            } else if let Some(p) = *p {
                (x[p], p)
            } else {
                continue;
            };
            let l = lambda(local(position));
            rows.push(bubble(l));
            lambdas.push(l);
            nodes[len] = node;
            len += 1;
        }
        let (g, null) = solve_rows(&rows)?;
        // C_jk: node p (row r): sum_m hhat_m[j] G[m][r]; vertex v:
        // -sum_r C_j,3+r lambda_v(P_r).
        let mut coefficients = [[0.0; 6]; 3];
        for j in 0..3 {
            for r in 0..rows.len() {
                let cp: f64 = (0..3).map(|m| hhat[m][j] * g[m][r]).sum();
                coefficients[j][3 + r] = cp;
                for v in 0..3 {
                    coefficients[j][v] -= cp * lambdas[r][v];
                }
            }
        }
        let area = 0.5 * twice_area;
        let free: Vec<[f64; 3]> = null
            .iter()
            .map(|z| std::array::from_fn(|j| (0..3).map(|m| z[m] * hhat[m][j]).sum()))
            .collect();
        let reduced = condense(d, &free);
        let stiffness = reduced.map(|row| row.map(|v| area * v));
        let mut patch = Self {
            nodes,
            len: len as u8,
            coefficients,
            stiffness,
            rest: [0.0; 3],
            ghost,
        };
        let mut xs = [[0.0; 3]; 6];
        patch.positions(|a| x[a], &mut xs);
        patch.rest = patch.curvature(&xs[..len]);
        Ok(patch)
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

    /// `v_j = sum_k C_jk x_k`.
    #[inline]
    pub(super) fn second_derivative(&self, x: &[[f64; 3]], j: usize) -> [f64; 3] {
        let mut v = [0.0; 3];
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

impl Ghost {
    /// The ghost of vertex `m` of the triangle with reference vertices `x`
    /// and unit normal `normal`, across the edge opposite it, in patch
    /// slot `slot`.
    fn across(x: [[f64; 3]; 3], m: usize, normal: [f64; 3], slot: usize) -> Self {
        let (a, b) = (x[(m + 1) % 3], x[(m + 2) % 3]);
        // The in-plane unit vector normal to the edge.
        let e = sub(b, a);
        let u = cross(normal, e);
        let u = scale(u, 1.0 / norm(u));
        Self {
            slot,
            vertex: m,
            anchor: a,
            reflect: std::array::from_fn(|i| {
                std::array::from_fn(|j| f64::from(u8::from(i == j)) - 2.0 * u[i] * u[j])
            }),
        }
    }
}

/// For the equations `rows . c = r` (1 to 3 rows of 3), the minimum-norm
/// solution operator `G` (3 x rows: `c = G r`) and a basis of the null
/// space of `rows`.
#[allow(clippy::type_complexity)]
fn solve_rows(rows: &[[f64; 3]]) -> Result<([[f64; 3]; 3], Vec<[f64; 3]>), PatchError> {
    let mut g = [[0.0; 3]; 3];
    match rows.len() {
        0 => Ok((g, vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])),
        1 => {
            let b = rows[0];
            let bb = dot(b, b);
            if bb.is_nan() || bb <= 0.0 {
                return Err(PatchError::Conic);
            }
            for m in 0..3 {
                g[m][0] = b[m] / bb;
            }
            // Two unit vectors orthogonal to b.
            let u = scale(b, 1.0 / bb.sqrt());
            let t = if u[0].abs() < 0.9 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            let z1 = {
                let z = sub(t, scale(u, dot(t, u)));
                scale(z, 1.0 / norm(z))
            };
            let z2 = cross(u, z1);
            Ok((g, vec![z1, z2]))
        }
        2 => {
            // G = B^T (B B^T)^-1.
            let (a, b) = (rows[0], rows[1]);
            let (aa, ab, bb) = (dot(a, a), dot(a, b), dot(b, b));
            let det = aa * bb - ab * ab;
            if det.is_nan() || det <= 1e-6 * aa * bb {
                return Err(PatchError::Conic);
            }
            let inv = [[bb / det, -ab / det], [-ab / det, aa / det]];
            for m in 0..3 {
                g[m][0] = a[m] * inv[0][0] + b[m] * inv[1][0];
                g[m][1] = a[m] * inv[0][1] + b[m] * inv[1][1];
            }
            let z = cross(a, b);
            Ok((g, vec![scale(z, 1.0 / norm(z))]))
        }
        _ => {
            let b = [rows[0], rows[1], rows[2]];
            let det = dot(b[0], cross(b[1], b[2]));
            if det.is_nan() || det.abs() <= 1e-3 * norm(b[0]) * norm(b[1]) * norm(b[2]) {
                return Err(PatchError::Conic);
            }
            // Columns of B^-1: (b1 x b2, b2 x b0, b0 x b1) / det as rows'
            // duals: B^-1[m][r] = cof[r][m] / det.
            let cof = [cross(b[1], b[2]), cross(b[2], b[0]), cross(b[0], b[1])];
            for m in 0..3 {
                for r in 0..3 {
                    g[m][r] = cof[r][m] / det;
                }
            }
            Ok((g, Vec::new()))
        }
    }
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
