//! The bending energy of one patch, with its exact gradient and Hessian.
//!
//! A patch is a triangle `T` (local nodes 0–2) and the nodes around it
//! that its edges' fits use (local nodes 3..). With the constant
//! coefficients `C` and offset `v_0` of the patch's mean second
//! derivatives ([`super::patch`]) and the normal `n` of `T`'s plane,
//!
//! ```text
//! v_j   = sum_k C_jk x_k + v_0j             (x_,11  x_,22  2 x_,12)
//! kappa_j = n . v_j,   n = m / |m|,  m = (x_1 - x_0) x (x_2 - x_0)
//! e     = kappa - kappa_0
//! W     = 1/2 e . (A D') e
//! ```
//!
//! and, with `M = A D' e`, `mu_k = sum_j M_j C_jk`, `w = sum_j M_j v_j`,
//! `P = I - n n^T`, `r = |m|`, `E_k = x_{k+2} - x_{k+1}` (so that
//! `dm/dx_k = [E_k]x`) and `J_k = dn/dx_k = P [E_k]x / r`:
//!
//! ```text
//! dkappa_j/dx_k = C_jk n + J_k^T v_j          (J_k = 0 for k >= 3)
//! dW/dx_k       = mu_k n + J_k^T w
//! d2W/dx_k dx_l = sum_ij (A D')_ij dkappa_i/dx_k (dkappa_j/dx_l)^T
//!               + mu_k J_l + mu_l J_k^T + S_kl
//! S_kl = d2(n . w)/dx_k dx_l
//!      = [E_k]x^T H_m [E_l]x + s_kl [u]x,    u = P w / r,
//! H_m  = -(P w n^T + n (P w)^T + (n . w) P) / r^2
//! ```
//!
//! with `s_kl = +1` for `l = k + 2`, `-1` for `l = k + 1` (mod 3), 0 for
//! `l = k`. The Hessian is symmetric block by block.

use super::patch::{Patch, normal};
use crate::vec3::{dot, scale, sub};

/// What a law of the curvatures gives a patch ([`evaluate_law`]): its
/// energy `psi` (J), the moments `M = dpsi/dkappa` and `dM/dkappa`.
pub type LawValue = (f64, [f64; 3], [[f64; 3]; 3]);

/// Largest number of nodes of a patch.
pub const MAX_NODES: usize = super::patch::MAX_NODES;
/// Largest number of degrees of freedom of a patch.
pub const MAX_DOFS: usize = 3 * MAX_NODES;

/// The energy, gradient and Hessian of one patch (only the first `3 len`
/// rows and columns are meaningful).
pub struct Local {
    /// Bending energy (J).
    pub energy: f64,
    /// `dW/dx`, node-major.
    pub gradient: [f64; MAX_DOFS],
    /// `d2W/dx2`, row-major, `MAX_DOFS` columns.
    pub hessian: [[f64; MAX_DOFS]; MAX_DOFS],
}

/// `[a]x`, the matrix of `b -> a x b`.
#[inline]
fn skew(a: [f64; 3]) -> [[f64; 3]; 3] {
    [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]]
}

#[inline]
fn matmul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    c
}

#[inline]
fn transpose(a: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut t = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            t[i][j] = a[j][i];
        }
    }
    t
}

/// `J^T u` for a 3x3 `J`.
#[inline]
fn mul_t(a: &[[f64; 3]; 3], u: [f64; 3]) -> [f64; 3] {
    [
        a[0][0] * u[0] + a[1][0] * u[1] + a[2][0] * u[2],
        a[0][1] * u[0] + a[1][1] * u[1] + a[2][1] * u[2],
        a[0][2] * u[0] + a[1][2] * u[1] + a[2][2] * u[2],
    ]
}

/// The moments `M = A D' (kappa - kappa_0)` of curvatures `kappa` and the
/// energy `1/2 (kappa - kappa_0) . M`.
#[inline]
fn moments(patch: &Patch, kappa: [f64; 3]) -> ([f64; 3], f64) {
    let e = [0, 1, 2].map(|j| kappa[j] - patch.rest[j]);
    let ad = &patch.stiffness;
    let m = [0, 1, 2].map(|i| ad[i][0] * e[0] + ad[i][1] * e[1] + ad[i][2] * e[2]);
    (m, 0.5 * (e[0] * m[0] + e[1] * m[1] + e[2] * m[2]))
}

/// The bending energy of `patch` at `x` alone (J).
pub fn energy(patch: &Patch, x: &[[f64; 3]]) -> f64 {
    moments(patch, patch.curvature(x)).1
}

/// The bending energy of `patch` at `x`; with `hessian`, also its gradient
/// and Hessian into `out` (the gradient always). With `gauss_newton`, the
/// Hessian is its Gauss–Newton part `K^T (A D') K` alone, positive
/// semi-definite by construction: what the projected Newton asks for
/// (`project` of `Bending::add_law`), without the
/// eigendecomposition of a matrix of up to 54 x 54 that the nearest
/// semi-definite matrix would take.
//
// Longer than a function should be, and kept whole: it is one formula,
// the energy, its gradient and its Hessian (Gauss–Newton and curvature
// parts) written from the same intermediates (`n`, `r`, `v`, `J_k`, `M`)
// in the order the finite-difference tests and the bit-identical runs
// were checked in; cut into pieces, each would take most of them as
// arguments.
pub fn evaluate(patch: &Patch, x: &[[f64; 3]], hessian: bool, out: &mut Local) -> f64 {
    evaluate_with(patch, x, hessian, false, out)
}

/// [`evaluate`], the Hessian's Gauss–Newton part alone with `gauss_newton`.
pub fn evaluate_with(
    patch: &Patch,
    x: &[[f64; 3]],
    hessian: bool,
    gauss_newton: bool,
    out: &mut Local,
) -> f64 {
    evaluate_law(patch, x, hessian, gauss_newton, out, |kappa| {
        elastic(patch, kappa)
    })
}

/// The elastic law of `patch` at curvatures `kappa`, as
/// [`evaluate_law`] takes it: `1/2 e . A D' e`, `A D' e` and `A D'`.
#[inline]
pub(super) fn elastic(patch: &Patch, kappa: [f64; 3]) -> LawValue {
    let (m, energy) = moments(patch, kappa);
    (energy, m, patch.stiffness)
}

/// [`evaluate_with`] for an energy `psi(kappa)` of the patch's curvatures
/// other than the elastic one: `law(kappa)` gives `psi`, the moments `M
/// = dpsi/dkappa` and `dM/dkappa` (for the elastic energy `A D' (kappa -
/// kappa_0)` and `A D'`; the module docs' formulas hold with these). The
/// Gauss–Newton part is positive semi-definite where `dM/dkappa` is.
pub fn evaluate_law(
    patch: &Patch,
    x: &[[f64; 3]],
    hessian: bool,
    gauss_newton: bool,
    out: &mut Local,
    law: impl Fn([f64; 3]) -> LawValue,
) -> f64 {
    let len = patch.len();
    debug_assert_eq!(x.len(), len);
    let (n, r) = normal(x);
    let v = [0, 1, 2].map(|j| patch.second_derivative(x, j));
    let kappa = v.map(|vj| dot(n, vj));
    let (energy, m, stiffness) = law(kappa);
    let ad = &stiffness;
    out.energy = energy;

    let p = {
        let mut p = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                p[i][j] = f64::from(u8::from(i == j)) - n[i] * n[j];
            }
        }
        p
    };
    let edges = [sub(x[2], x[1]), sub(x[0], x[2]), sub(x[1], x[0])];
    // J_k = P [E_k]x / r.
    let jac: [[[f64; 3]; 3]; 3] = edges.map(|ek| {
        let mut j = matmul(&p, &skew(ek));
        for row in &mut j {
            for val in row.iter_mut() {
                *val /= r;
            }
        }
        j
    });
    let w = [0, 1, 2].map(|i| m[0] * v[0][i] + m[1] * v[1][i] + m[2] * v[2][i]);
    // dkappa_j/dx_k, stacked: grad_kappa[j][3k + i].
    let mut grad_kappa = [[0.0; MAX_DOFS]; 3];
    for j in 0..3 {
        for k in 0..len {
            let c = patch.coefficients[j][k];
            let mut d = scale(n, c);
            if k < 3 {
                let t = mul_t(&jac[k], v[j]);
                d = [d[0] + t[0], d[1] + t[1], d[2] + t[2]];
            }
            grad_kappa[j][3 * k..3 * k + 3].copy_from_slice(&d);
        }
    }
    let dofs = 3 * len;
    for a in 0..dofs {
        out.gradient[a] =
            m[0] * grad_kappa[0][a] + m[1] * grad_kappa[1][a] + m[2] * grad_kappa[2][a];
    }
    if !hessian {
        return energy;
    }

    // Gauss-Newton part: K^T (A D') K.
    let mut dk = [[0.0; MAX_DOFS]; 3];
    for i in 0..3 {
        for a in 0..dofs {
            dk[i][a] = ad[i][0] * grad_kappa[0][a]
                + ad[i][1] * grad_kappa[1][a]
                + ad[i][2] * grad_kappa[2][a];
        }
    }
    for a in 0..dofs {
        for b in 0..dofs {
            out.hessian[a][b] = grad_kappa[0][a] * dk[0][b]
                + grad_kappa[1][a] * dk[1][b]
                + grad_kappa[2][a] * dk[2][b];
        }
    }

    if gauss_newton {
        return energy;
    }
    // Curvature part: mu_k J_l + mu_l J_k^T + S_kl.
    let mu: [f64; MAX_NODES] = std::array::from_fn(|k| {
        if k < len {
            (0..3).map(|j| m[j] * patch.coefficients[j][k]).sum()
        } else {
            0.0
        }
    });
    let pw = mul_t(&p, w); // P symmetric
    let nw = dot(n, w);
    let mut hm = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            hm[i][j] = -(pw[i] * n[j] + n[i] * pw[j] + nw * p[i][j]) / (r * r);
        }
    }
    let u = scale(pw, 1.0 / r);
    let skews = edges.map(skew);
    let skew_u = skew(u);
    for k in 0..len {
        // Only the triangle's vertices (k or l < 3) move the normal: the
        // blocks between two other nodes have no curvature part.
        for l in 0..if k < 3 { len } else { 3 } {
            let mut block = [[0.0; 3]; 3];
            if l < 3 {
                for i in 0..3 {
                    for j in 0..3 {
                        block[i][j] += mu[k] * jac[l][i][j];
                    }
                }
            }
            if k < 3 {
                for i in 0..3 {
                    for j in 0..3 {
                        block[i][j] += mu[l] * jac[k][j][i];
                    }
                }
            }
            if k < 3 && l < 3 {
                let s = matmul(&transpose(&skews[k]), &matmul(&hm, &skews[l]));
                let sign = if l == (k + 2) % 3 {
                    1.0
                } else if l == (k + 1) % 3 {
                    -1.0
                } else {
                    0.0
                };
                for i in 0..3 {
                    for j in 0..3 {
                        block[i][j] += s[i][j] + sign * skew_u[i][j];
                    }
                }
            }
            for i in 0..3 {
                for j in 0..3 {
                    out.hessian[3 * k + i][3 * l + j] += block[i][j];
                }
            }
        }
    }
    energy
}

impl Local {
    /// Zeroed buffers.
    pub fn new() -> Self {
        Self {
            energy: 0.0,
            gradient: [0.0; MAX_DOFS],
            hessian: [[0.0; MAX_DOFS]; MAX_DOFS],
        }
    }
}

impl Default for Local {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    //! [`evaluate`] and [`Patch::curvature`] on the patches of a small
    //! irregular mesh at 1 cm — 5 x 5 jittered squares whose diagonals
    //! alternate square by square (criss-cross: nodes of four and eight
    //! triangles) — fitted flat or on a curved surface: an interior patch
    //! (twelve nodes), one with a free edge and one with two. The
    //! finite-difference checks of the derivatives are in
    //! `integrator/terms/bending.rs`; these check the invariances and the
    //! exactness the formulation promises.

    use super::*;
    use crate::bending::{Bending, BendingRigidity};
    use crate::mesh::{ElementOrder, Mesh};
    use crate::vec3::{add, cross, norm};

    /// The patch's size (m).
    const H: f64 = 0.01;
    /// Squares along a side.
    const N: usize = 5;

    /// The nodes in the plane, jittered inside, and the triangles.
    fn plane() -> (Vec<[f64; 2]>, Vec<usize>) {
        let h = H / 2.0;
        let mut p = Vec::new();
        for j in 0..=N {
            for i in 0..=N {
                let inside = i > 0 && j > 0 && i < N && j < N;
                let s = if inside { 0.2 } else { 0.0 };
                let (a, b) = ((3 * i + 7 * j) as f64, (5 * i + 2 * j) as f64);
                p.push([h * (i as f64 + s * a.sin()), h * (j as f64 + s * b.cos())]);
            }
        }
        let id = |i: usize, j: usize| j * (N + 1) + i;
        let mut t = Vec::new();
        for j in 0..N {
            for i in 0..N {
                let (p00, p10, p11, p01) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                if (i + j).is_multiple_of(2) {
                    t.extend_from_slice(&[p00, p10, p11, p00, p11, p01]);
                } else {
                    t.extend_from_slice(&[p00, p10, p01, p10, p11, p01]);
                }
            }
        }
        (p, t)
    }

    /// The points on `z = f(x, y)`.
    fn on_surface(f: impl Fn([f64; 2]) -> f64) -> Vec<[f64; 3]> {
        plane().0.iter().map(|&p| [p[0], p[1], f(p)]).collect()
    }

    /// The rotation by `angle` about `axis` (Rodrigues).
    fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
        let u = scale(axis, 1.0 / norm(axis));
        let (s, c) = angle.sin_cos();
        let k = skew(u);
        let kk = matmul(&k, &k);
        std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                f64::from(u8::from(i == j)) + s * k[i][j] + (1.0 - c) * kk[i][j]
            })
        })
    }

    fn apply(q: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| dot(q[i], v))
    }

    /// A rigid motion: rotation `q` then translation `t`.
    fn moved(x: &[[f64; 3]], q: &[[f64; 3]; 3], t: [f64; 3]) -> Vec<[f64; 3]> {
        x.iter().map(|&p| add(apply(q, p), t)).collect()
    }

    /// A generic placement in space (tilted, away from the origin).
    fn place(x: &[[f64; 3]]) -> Vec<[f64; 3]> {
        moved(x, &rotation([0.3, -0.5, 0.8], 0.7), [0.12, -0.05, 0.3])
    }

    /// The reference: flat, or on a curved surface (a saddle of curvatures
    /// of 20–40 1/m on the 2.5 cm mesh), placed.
    fn reference(curved: bool) -> Vec<[f64; 3]> {
        if curved {
            place(&on_surface(|p| {
                20.0 * p[0] * p[0] + 7.0 * p[0] * p[1] - 12.0 * p[1] * p[1]
            }))
        } else {
            place(&on_surface(|_| 0.0))
        }
    }

    /// The deformed configurations: flat (stretched and sheared in its
    /// plane), near-flat (out of plane by 1e-3 of the squares), folded
    /// (about 35–70 degrees across three lines) and strongly folded
    /// (150–172 degrees: nearly onto itself).
    #[derive(Debug, Clone, Copy)]
    enum Shape {
        Flat,
        NearFlat,
        Folded,
        StronglyFolded,
    }

    fn deformed(shape: Shape) -> Vec<[f64; 3]> {
        let mut x: Vec<[f64; 3]> = plane()
            .0
            .iter()
            .map(|p| [1.08 * p[0] + 0.15 * p[1], -0.04 * p[0] + 0.95 * p[1], 0.0])
            .collect();
        match shape {
            Shape::Flat => {}
            Shape::NearFlat => {
                for (k, p) in x.iter_mut().enumerate() {
                    p[2] += 1e-3 * H * (1.7 * k as f64).sin();
                }
            }
            Shape::Folded | Shape::StronglyFolded => {
                let angles = if matches!(shape, Shape::Folded) {
                    [0.6, -0.9, 1.2]
                } else {
                    [2.9, -2.6, 3.0]
                };
                // Fold lines: (point, direction) in the plane; the nodes
                // on the positive side turn about each.
                let lines = [
                    ([0.6 * H, 0.0], [0.3, 1.0]),
                    ([0.0, 0.55 * H], [1.0, 0.2]),
                    ([1.9 * H, 1.9 * H], [1.0, -1.0]),
                ];
                for ((origin, dir), angle) in lines.into_iter().zip(angles) {
                    let a = [origin[0], origin[1], 0.0];
                    let d = [dir[0], dir[1], 0.0];
                    let normal = [-dir[1], dir[0]];
                    let q = rotation(d, angle);
                    let flat: Vec<[f64; 2]> = plane().0;
                    for (p, f) in x.iter_mut().zip(&flat) {
                        let side = (f[0] - origin[0]) * normal[0] + (f[1] - origin[1]) * normal[1];
                        if side > 0.0 {
                            *p = add(a, apply(&q, sub(*p, a)));
                        }
                    }
                }
            }
        }
        place(&x)
    }

    /// The three kinds of rigidity: isotropic, woven (with a warp out of
    /// the plane, projected) and a plate (with Poisson coupling).
    fn rigidities() -> [BendingRigidity; 3] {
        [
            BendingRigidity::Isotropic(1e-5),
            BendingRigidity::Woven {
                warp: 2e-5,
                weft: 5e-6,
                direction: [1.0, 0.4, 0.2],
            },
            BendingRigidity::Plate {
                rigidity: 3e-5,
                poisson_ratio: 0.3,
            },
        ]
    }

    /// The patches of the mesh at reference positions `x`.
    fn patches(x: &[[f64; 3]], rigidity: BendingRigidity) -> Vec<Patch> {
        let mesh = Mesh {
            nodes: x.to_vec(),
            order: ElementOrder::Linear,
            connectivity: plane().1,
        };
        Bending::new(&mesh, rigidity, &[])
            .expect("valid patches")
            .patches()
            .to_vec()
    }

    /// How many free edges a patch's triangle has (edges on the mesh's
    /// boundary: both nodes there, and the triangle a boundary square's).
    fn free_edges(patch: &Patch) -> usize {
        let (p, _) = plane();
        let on = |a: usize, b: usize| {
            let (pa, pb) = (p[a], p[b]);
            let edge = H / 2.0 * N as f64;
            let side = |v: f64| v.abs() < 1e-12 || (v - edge).abs() < 1e-12;
            (side(pa[0]) && side(pb[0]) && (pa[0] - pb[0]).abs() < 1e-12)
                || (side(pa[1]) && side(pb[1]) && (pa[1] - pb[1]).abs() < 1e-12)
        };
        let t = &patch.nodes()[..3];
        (0..3).filter(|&m| on(t[m], t[(m + 1) % 3])).count()
    }

    /// An interior patch, one with a free edge and one with two.
    fn chosen(all: &[Patch]) -> [Patch; 3] {
        let pick = |free: usize| {
            all.iter()
                .filter(|p| free_edges(p) == free)
                .max_by_key(|p| p.len())
                .expect("such a patch")
                .clone()
        };
        [pick(0), pick(1), pick(2)]
    }

    /// The patch's nodes' positions in `x` (indexed by global node).
    fn local(patch: &Patch, x: &[[f64; 3]]) -> Vec<[f64; 3]> {
        patch.nodes().iter().map(|&a| x[a]).collect()
    }

    fn node(g: &[f64], k: usize) -> [f64; 3] {
        [g[3 * k], g[3 * k + 1], g[3 * k + 2]]
    }

    /// Eigenvalues of the symmetric part of `a` (cyclic Jacobi).
    fn eigenvalues(a: &[Vec<f64>]) -> Vec<f64> {
        let n = a.len();
        let mut a: Vec<Vec<f64>> = (0..n)
            .map(|i| (0..n).map(|j| 0.5 * (a[i][j] + a[j][i])).collect())
            .collect();
        let total: f64 = a.iter().flatten().map(|v| v * v).sum();
        for _ in 0..100 {
            let off: f64 = (0..n)
                .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
                .map(|(i, j)| a[i][j] * a[i][j])
                .sum();
            if off <= 1e-32 * total {
                break;
            }
            for p in 0..n {
                for q in p + 1..n {
                    if a[p][q] == 0.0 {
                        continue;
                    }
                    let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                    let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                    let c = 1.0 / (t * t + 1.0).sqrt();
                    let s = t * c;
                    for row in a.iter_mut() {
                        let (kp, kq) = (row[p], row[q]);
                        row[p] = c * kp - s * kq;
                        row[q] = s * kp + c * kq;
                    }
                    for k in 0..n {
                        let (pk, qk) = (a[p][k], a[q][k]);
                        a[p][k] = c * pk - s * qk;
                        a[q][k] = s * pk + c * qk;
                    }
                }
            }
        }
        let mut l: Vec<f64> = (0..n).map(|i| a[i][i]).collect();
        l.sort_by(f64::total_cmp);
        l
    }

    #[test]
    fn jacobi_eigenvalues_of_a_known_matrix() {
        // [2 1 0; 1 2 1; 0 1 2]: 2 - sqrt 2, 2, 2 + sqrt 2.
        let a = vec![
            vec![2.0, 1.0, 0.0],
            vec![1.0, 2.0, 1.0],
            vec![0.0, 1.0, 2.0],
        ];
        let l = eigenvalues(&a);
        let s = 2f64.sqrt();
        for (got, want) in l.iter().zip([2.0 - s, 2.0, 2.0 + s]) {
            assert!((got - want).abs() < 1e-12, "{l:?}");
        }
    }

    /// Rotating and translating every node of a folded patch leaves the
    /// energy unchanged and rotates the gradient with it; the gradient is
    /// a self-equilibrated set of nodal forces: no net force, no net
    /// moment.
    #[test]
    fn rigid_motion_leaves_energy_and_rotates_gradient() {
        let q = rotation([-0.4, 0.9, 0.25], 2.3);
        let t = [0.7, -1.1, 0.45];
        for rigidity in rigidities() {
            for curved in [false, true] {
                for (which, patch) in chosen(&patches(&reference(curved), rigidity))
                    .into_iter()
                    .enumerate()
                {
                    let n = patch.len();
                    for shape in [Shape::NearFlat, Shape::Folded, Shape::StronglyFolded] {
                        let x = local(&patch, &deformed(shape));
                        let y = moved(&x, &q, t);
                        let mut a = Local::new();
                        let mut b = Local::new();
                        let ea = evaluate(&patch, &x, false, &mut a);
                        let eb = evaluate(&patch, &y, false, &mut b);
                        let what = format!("{shape:?}, curved {curved}, {rigidity:?}, {n} nodes");
                        // Near-flat, the curvatures are what is left of sums
                        // `C x` of positions about 1 m from the origin with
                        // `C` about 1/H^2: round-off of about eps |x| /
                        // (1e-3 H), so that shape is held to 1e-9 and the
                        // folded ones to 1e-12.
                        let tol = if matches!(shape, Shape::NearFlat) {
                            1e-9
                        } else {
                            1e-11
                        };
                        // The fold lines cross the interior patch; a corner
                        // patch they miss stays flat, with nothing to turn.
                        assert!(which > 0 || ea > 1e-12, "{what}: {ea:e} J");
                        if ea < 1e-24 {
                            continue;
                        }
                        assert!(
                            (eb - ea).abs() <= tol * ea,
                            "{what}: energy {ea:e} -> {eb:e}"
                        );
                        let gmax = (0..n)
                            .map(|k| norm(node(&a.gradient, k)))
                            .fold(0.0, f64::max);
                        let gsum: f64 = (0..n).map(|k| norm(node(&a.gradient, k))).sum();
                        for k in 0..n {
                            let rotated = apply(&q, node(&a.gradient, k));
                            let diff = norm(sub(node(&b.gradient, k), rotated));
                            assert!(diff <= tol * gmax, "{what}: node {k}: {diff:e} of {gmax:e}");
                        }
                        for (x, g) in [(&x, &a.gradient), (&y, &b.gradient)] {
                            let mut force = [0.0; 3];
                            let mut moment = [0.0; 3];
                            let mut moment_scale = 0.0;
                            for k in 0..n {
                                let gk = node(g, k);
                                force = add(force, gk);
                                moment = add(moment, cross(x[k], gk));
                                moment_scale += norm(x[k]) * norm(gk);
                            }
                            assert!(norm(force) <= 1e-12 * gsum, "{what}: net force {force:?}");
                            assert!(
                                norm(moment) <= 1e-12 * moment_scale,
                                "{what}: net moment {moment:?} of {moment_scale:e}"
                            );
                        }
                    }
                }
            }
        }
    }

    /// The Hessian is symmetric to round-off, flat (away from a curved
    /// reference), near-flat, folded and strongly folded, for each kind of
    /// rigidity and with free edges.
    #[test]
    fn hessian_is_symmetric() {
        for rigidity in rigidities() {
            for curved in [false, true] {
                for patch in chosen(&patches(&reference(curved), rigidity)) {
                    let dofs = 3 * patch.len();
                    for shape in [
                        Shape::Flat,
                        Shape::NearFlat,
                        Shape::Folded,
                        Shape::StronglyFolded,
                    ] {
                        let x = local(&patch, &deformed(shape));
                        let mut out = Local::new();
                        evaluate(&patch, &x, true, &mut out);
                        let h = &out.hessian;
                        let max = (0..dofs)
                            .flat_map(|a| (0..dofs).map(move |b| h[a][b].abs()))
                            .fold(0.0, f64::max);
                        assert!(max > 0.0);
                        let asym = (0..dofs)
                            .flat_map(|a| (0..dofs).map(move |b| (h[a][b] - h[b][a]).abs()))
                            .fold(0.0, f64::max);
                        assert!(
                            asym <= 1e-12 * max,
                            "{shape:?}, curved {curved}, {rigidity:?}: |H - H^T| {asym:e} of {max:e}"
                        );
                    }
                }
            }
        }
    }

    /// At its reference (flat or curved) a patch has no energy and no
    /// force, and its Hessian `K^T (A D') K` is positive semi-definite, of
    /// the rank of the condensed stiffness (3 inside, one less per free
    /// edge), with the six rigid motions in its null space.
    #[test]
    fn hessian_at_reference_is_semidefinite_with_rigid_null_space() {
        for rigidity in rigidities() {
            for curved in [false, true] {
                let xg = reference(curved);
                for patch in chosen(&patches(&xg, rigidity)) {
                    let rank = 3 - free_edges(&patch);
                    let x = local(&patch, &xg);
                    let n = patch.len();
                    let dofs = 3 * n;
                    let mut out = Local::new();
                    let energy = evaluate(&patch, &x, true, &mut out);
                    let h: Vec<Vec<f64>> =
                        (0..dofs).map(|a| out.hessian[a][..dofs].to_vec()).collect();
                    let what = format!("curved {curved}, {rigidity:?}, rank {rank}");
                    let l = eigenvalues(&h);
                    let lmax = l[dofs - 1];
                    assert!(lmax > 0.0, "{what}");
                    assert!(l[0] >= -1e-12 * lmax, "{what}: {l:?}");
                    let positive = l.iter().filter(|&&v| v > 1e-9 * lmax).count();
                    assert_eq!(positive, rank, "{what}: {l:?}");
                    assert!(energy.abs() <= 1e-30, "{what}: {energy:e}");
                    let g = out.gradient[..dofs]
                        .iter()
                        .map(|v| v.abs())
                        .fold(0.0, f64::max);
                    assert!(g <= 1e-12 * lmax * H, "{what}: gradient {g:e}");
                    let mut modes: Vec<Vec<f64>> = Vec::new();
                    for i in 0..3 {
                        let mut e = [0.0; 3];
                        e[i] = 1.0;
                        modes.push((0..n).flat_map(|_| e).collect());
                        modes.push((0..n).flat_map(|k| cross(e, x[k])).collect());
                    }
                    for (m, v) in modes.iter().enumerate() {
                        let vn = v.iter().map(|c| c * c).sum::<f64>().sqrt();
                        let hv = (0..dofs)
                            .map(|a| (0..dofs).map(|b| h[a][b] * v[b]).sum::<f64>().powi(2))
                            .sum::<f64>()
                            .sqrt();
                        assert!(hv <= 1e-12 * lmax * vn, "{what}: mode {m}: |H v| {hv:e}");
                    }
                }
            }
        }
    }

    /// Voigt `(f_,11, f_,22, 2 f_,12)` of a Hessian `[[f11, f12], [f12, f22]]`
    /// in the frame whose first axis is along `a` (in the plane).
    fn voigt_along(h: [[f64; 2]; 2], a: [f64; 2]) -> [f64; 3] {
        let l = (a[0] * a[0] + a[1] * a[1]).sqrt();
        let (t, n) = ([a[0] / l, a[1] / l], [-a[1] / l, a[0] / l]);
        let form = |u: [f64; 2], v: [f64; 2]| {
            (0..2)
                .map(|i| (0..2).map(|j| u[i] * h[i][j] * v[j]).sum::<f64>())
                .sum::<f64>()
        };
        [form(t, t), form(n, n), 2.0 * form(t, n)]
    }

    /// The patch frame's first axis (in the plane z = 0): the triangle's
    /// first edge, or the projected warp.
    fn frame_axis(patch: &Patch, rigidity: BendingRigidity, p: &[[f64; 2]]) -> [f64; 2] {
        match rigidity {
            BendingRigidity::Woven { direction, .. } => [direction[0], direction[1]],
            _ => {
                let (a, b) = (p[patch.nodes()[0]], p[patch.nodes()[1]]);
                [b[0] - a[0], b[1] - a[1]]
            }
        }
    }

    /// The curvature is exact for quadratic surfaces on every patch whose
    /// edges are all fitted, and the energy is `1/2 e . (A D') e`; with a
    /// free edge, exact but for curvatures along the free directions,
    /// which `A D'` does not see:
    ///
    /// * nodes on `z = f(x, y)`, `f` quadratic, in the flat reference's
    ///   plane: `kappa = n . (f_,xx, f_,yy, 2 f_,xy) e_z`, `n` the deformed
    ///   triangle's normal;
    /// * the same surfaces as references: at rest there;
    /// * with the warp's frame, the same tensor in the rotated frame.
    #[test]
    fn curvature_is_exact_for_quadratic_surfaces() {
        let (p, _) = plane();
        let flat = on_surface(|_| 0.0);
        for rigidity in rigidities() {
            let all = patches(&flat, rigidity);
            for (a, b, c) in [(3.0, -1.7, 5.2), (80.0, -40.0, 120.0), (-25.0, 60.0, 10.0)] {
                let f = |q: [f64; 2]| a * q[0] * q[0] + b * q[0] * q[1] + c * q[1] * q[1];
                let x = on_surface(f);
                let curved = patches(&x, rigidity);
                let hess = [[2.0 * a, b], [b, 2.0 * c]];
                for (patch, reference) in all.iter().zip(&curved) {
                    let xl = local(patch, &x);
                    let n = normal(&xl).0;
                    let want = voigt_along(hess, frame_axis(patch, rigidity, &p)).map(|v| v * n[2]);
                    let got = patch.curvature(&xl);
                    let what = format!("{rigidity:?}, z = {a} x^2 + {b} xy + {c} y^2");
                    let s = &patch.stiffness;
                    let scale = want.iter().map(|v| v.abs()).fold(0.0, f64::max);
                    let smax = s.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
                    // Seen through A D': exact on every patch.
                    let diff: [f64; 3] = std::array::from_fn(|i| got[i] - want[i]);
                    let seen: [f64; 3] = std::array::from_fn(|i| dot(s[i], diff));
                    assert!(
                        norm(seen) <= 1e-9 * smax * scale,
                        "{what}: {got:?} {want:?}"
                    );
                    if free_edges(patch) == 0 {
                        assert!(norm(diff) <= 1e-9 * scale, "{what}: {got:?} {want:?}");
                    }
                    // As a reference: at rest there.
                    let rest = reference.curvature(&local(reference, &x));
                    assert_eq!(rest, reference.rest, "reference {what}");
                    let mut out = Local::new();
                    let energy = evaluate(patch, &xl, false, &mut out);
                    let want_energy: f64 =
                        0.5 * (0..3).map(|i| got[i] * dot(s[i], got)).sum::<f64>();
                    assert!((energy - want_energy).abs() <= 1e-12 * want_energy.abs().max(1e-300));
                }
            }
        }
    }

    /// A free edge's cross slope is condensed out: `A D'` is singular along
    /// `Voigt(nu nu^T)` of each free edge (`nu` its outward normal, computed
    /// here from the triangle), keeps rank 3 minus the free edges and
    /// stays positive semi-definite and symmetric.
    #[test]
    fn free_edges_are_condensed_and_stiffness_stays_semidefinite() {
        let (p, _) = plane();
        let flat = on_surface(|_| 0.0);
        let edge = H / 2.0 * N as f64;
        for rigidity in rigidities() {
            for patch in chosen(&patches(&flat, rigidity)) {
                let s = patch.stiffness;
                let smax = s.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
                let what = format!("{rigidity:?}, {} free edges", free_edges(&patch));
                for (i, j) in [(0, 1), (0, 2), (1, 2)] {
                    assert!((s[i][j] - s[j][i]).abs() <= 1e-14 * smax, "{what}: {s:?}");
                }
                let axis = frame_axis(&patch, rigidity, &p);
                let t = &patch.nodes()[..3];
                for m in 0..3 {
                    let (a, b) = (p[t[m]], p[t[(m + 1) % 3]]);
                    let side = |v: f64| v.abs() < 1e-12 || (v - edge).abs() < 1e-12;
                    let free = (side(a[0]) && (a[0] - b[0]).abs() < 1e-12)
                        || (side(a[1]) && (a[1] - b[1]).abs() < 1e-12);
                    if !free {
                        continue;
                    }
                    let d = [b[0] - a[0], b[1] - a[1]];
                    let nu = [d[1], -d[0]];
                    let k = voigt_along(
                        [
                            [nu[0] * nu[0], nu[0] * nu[1]],
                            [nu[0] * nu[1], nu[1] * nu[1]],
                        ],
                        axis,
                    );
                    let sk: [f64; 3] = std::array::from_fn(|i| dot(s[i], k));
                    assert!(
                        norm(sk) <= 1e-12 * smax * norm(k),
                        "{what}: A D' f = {sk:?}"
                    );
                }
                let l = eigenvalues(&s.iter().map(|r| r.to_vec()).collect::<Vec<_>>());
                assert!(l[0] >= -1e-12 * smax, "{what}: {l:?}");
                let positive = l.iter().filter(|&&v| v > 1e-9 * smax).count();
                assert_eq!(
                    positive,
                    3 - free_edges(&patch),
                    "{what}: eigenvalues {l:?}"
                );
            }
        }
    }
}
