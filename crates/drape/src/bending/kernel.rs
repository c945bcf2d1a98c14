//! The bending energy of one patch, with its exact gradient and Hessian.
//!
//! A patch is a triangle `T` (local nodes 0–2) and the nodes opposite its
//! edges across the neighbouring triangles (local nodes 3.., at most 3).
//! With the constant coefficients `C` of the patch's quadratic surface
//! ([`super::patch`]) and the normal `n` of `T`'s plane,
//!
//! ```text
//! v_j   = sum_k C_jk x_k                    (x_,11  x_,22  2 x_,12)
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

/// Largest number of nodes of a patch.
pub const MAX_NODES: usize = 6;
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
/// and Hessian into `out` (the gradient always).
//
// Longer than a function should be, and kept whole: it is one formula,
// the energy, its gradient and its Hessian (Gauss–Newton and curvature
// parts) written from the same intermediates (`n`, `r`, `v`, `J_k`, `M`)
// in the order the finite-difference tests and the bit-identical runs
// were checked in; cut into pieces, each would take most of them as
// arguments.
pub fn evaluate(patch: &Patch, x: &[[f64; 3]], hessian: bool, out: &mut Local) -> f64 {
    let len = patch.len();
    debug_assert_eq!(x.len(), len);
    let (n, r) = normal(x);
    let v = [0, 1, 2].map(|j| patch.second_derivative(x, j));
    let kappa = v.map(|vj| dot(n, vj));
    let (m, energy) = moments(patch, kappa);
    let ad = &patch.stiffness;
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
        for l in 0..len {
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

/// Folds a patch's ghost's gradient and Hessian rows and columns in `local`
/// (as the kernel wrote them, the ghost a node of its own) onto the
/// vertex it mirrors — `g_v += R g_g`, `H <- J^T H J` with `dx_g / dx_v
/// = R` — and zeroes them: the derivatives with respect to the patch's
/// real nodes. Nothing without a ghost.
pub fn fold(patch: &Patch, local: &mut Local, hessian: bool) {
    let Some(g) = &patch.ghost else {
        return;
    };
    let (s, v, r) = (3 * g.slot, 3 * g.vertex, &g.reflect);
    let gs: [f64; 3] = std::array::from_fn(|i| local.gradient[s + i]);
    for i in 0..3 {
        local.gradient[v + i] += dot(r[i], gs);
        local.gradient[s + i] = 0.0;
    }
    if !hessian {
        return;
    }
    let n = 3 * patch.len();
    let h = &mut local.hessian;
    // Rows: H[v, :] += R H[s, :] (R symmetric), then zero row s.
    for c in 0..n {
        let hs: [f64; 3] = std::array::from_fn(|i| h[s + i][c]);
        for i in 0..3 {
            h[v + i][c] += dot(r[i], hs);
            h[s + i][c] = 0.0;
        }
    }
    // Columns: H[:, v] += H[:, s] R, then zero column s.
    for row in h.iter_mut().take(n) {
        let hs: [f64; 3] = std::array::from_fn(|j| row[s + j]);
        for j in 0..3 {
            row[v + j] += dot(r[j], hs);
            row[s + j] = 0.0;
        }
    }
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
    //! [`evaluate`] and [`Patch::curvature`] on single patches: a skewed, irregular
    //! triangle (local nodes 0–2) and the three nodes opposite its edges
    //! (3: across edge 1–2, 4: across 2–0, 5: across 0–1), fitted flat or
    //! on a curved surface, at 1 cm. The finite-difference checks of the
    //! derivatives are in `integrator/terms/bending.rs`; these check the
    //! invariances and the exactness the formulation promises.

    use super::*;
    use crate::bending::BendingRigidity;
    use crate::vec3::{add, cross, norm};

    /// The patch's size (m).
    const H: f64 = 0.01;

    /// The six points in the plane of the triangle, whose first edge is
    /// along x and which turns counter-clockwise (normal +z).
    fn plane_points() -> [[f64; 2]; 6] {
        [
            [0.0, 0.0],
            [1.0, 0.0],
            [0.35, 0.9],
            [1.1, 0.85],
            [-0.55, 0.5],
            [0.6, -0.7],
        ]
        .map(|p| p.map(|c| c * H))
    }

    /// The quadratic `a x^2 + b xy + c y^2 + d x + e y` with `d`, `e` such
    /// that it vanishes at the triangle's vertices (the first at the
    /// origin): its Hessian is `[2a b; b 2c]` and the triangle stays in
    /// z = 0.
    fn vanishing(a: f64, b: f64, c: f64) -> impl Fn([f64; 2]) -> f64 {
        let p = plane_points();
        let quad = move |q: [f64; 2]| a * q[0] * q[0] + b * q[0] * q[1] + c * q[1] * q[1];
        // [x1 y1; x2 y2] [d; e] = -[quad(X1); quad(X2)].
        let (x1, x2) = (p[1], p[2]);
        let det = x1[0] * x2[1] - x1[1] * x2[0];
        let (r1, r2) = (-quad(x1), -quad(x2));
        let d = (r1 * x2[1] - r2 * x1[1]) / det;
        let e = (x1[0] * r2 - x2[0] * r1) / det;
        move |q| quad(q) + d * q[0] + e * q[1]
    }

    /// The points on `z = f(x, y)`.
    fn on_surface(f: impl Fn([f64; 2]) -> f64) -> Vec<[f64; 3]> {
        plane_points().iter().map(|&p| [p[0], p[1], f(p)]).collect()
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
    /// about 40 1/m, i.e. radii of 2.5 cm on the 1 cm patch), placed.
    fn reference(curved: bool) -> Vec<[f64; 3]> {
        if curved {
            place(&on_surface(vanishing(20.0, 7.0, -12.0)))
        } else {
            place(&on_surface(|_| 0.0))
        }
    }

    /// `x_p` turned by `angle` about the line through `x_a` and `x_b`.
    fn fold(x: &mut [[f64; 3]], a: usize, b: usize, p: usize, angle: f64) {
        let q = rotation(sub(x[b], x[a]), angle);
        x[p] = add(x[a], apply(&q, sub(x[p], x[a])));
    }

    /// The deformed configurations: flat (stretched and sheared in its
    /// plane), near-flat (out of plane by 1e-3 of the patch),
    /// folded (about 35–70 degrees across each edge) and strongly folded
    /// (150–172 degrees: nearly onto itself).
    #[derive(Debug, Clone, Copy)]
    enum Shape {
        Flat,
        NearFlat,
        Folded,
        StronglyFolded,
    }

    fn deformed(shape: Shape) -> Vec<[f64; 3]> {
        let flat: Vec<[f64; 3]> = plane_points()
            .iter()
            .map(|p| [1.08 * p[0] + 0.15 * p[1], -0.04 * p[0] + 0.95 * p[1], 0.0])
            .collect();
        let mut x = flat;
        match shape {
            Shape::Flat => {}
            Shape::NearFlat => {
                let dz = [0.3, -0.7, 0.5, 1.0, -0.4, 0.8];
                for (p, d) in x.iter_mut().zip(dz) {
                    p[2] += 1e-3 * H * d;
                }
            }
            Shape::Folded | Shape::StronglyFolded => {
                let angles = if matches!(shape, Shape::Folded) {
                    [0.6, -0.9, 1.2]
                } else {
                    [2.9, -2.6, 3.0]
                };
                fold(&mut x, 1, 2, 3, angles[0]);
                fold(&mut x, 2, 0, 4, angles[1]);
                fold(&mut x, 0, 1, 5, angles[2]);
            }
        }
        place(&x)
    }

    /// A constitutive matrix (N m) and the frame axis it is fitted with.
    type Rigidity = ([[f64; 3]; 3], Option<[f64; 3]>);

    /// The three kinds of rigidity (N m) and the frame axis each is fitted
    /// with: isotropic, woven (with a warp out of the plane, projected)
    /// and a plate (with Poisson coupling).
    fn rigidities() -> [Rigidity; 3] {
        let woven = BendingRigidity::Woven {
            warp: 2e-5,
            weft: 5e-6,
            direction: [1.0, 0.4, 0.2],
        };
        [
            (BendingRigidity::Isotropic(1e-5).matrix(), None),
            (woven.matrix(), Some([1.0, 0.4, 0.2])),
            (
                BendingRigidity::Plate {
                    rigidity: 3e-5,
                    poisson_ratio: 0.3,
                }
                .matrix(),
                None,
            ),
        ]
    }

    /// The patch of nodes 0–5 of `x` (opposite nodes `opposite`).
    fn fit(x: &[[f64; 3]], opposite: [Option<usize>; 3], rigidity: &Rigidity) -> Patch {
        Patch::fit([0, 1, 2], opposite, x, &rigidity.0, rigidity.1, None).expect("a valid patch")
    }

    const ALL: [Option<usize>; 3] = [Some(3), Some(4), Some(5)];

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
            assert!((got - want).abs() < 1e-14, "{l:?}");
        }
    }

    /// Rotating and translating all six nodes of a folded patch leaves the
    /// energy unchanged and rotates the gradient with it; the gradient is
    /// a self-equilibrated set of nodal forces: no net force, no net
    /// moment.
    #[test]
    fn rigid_motion_leaves_energy_and_rotates_gradient() {
        let q = rotation([-0.4, 0.9, 0.25], 2.3);
        let t = [0.7, -1.1, 0.45];
        for rigidity in &rigidities() {
            for curved in [false, true] {
                let patch = fit(&reference(curved), ALL, rigidity);
                for shape in [Shape::NearFlat, Shape::Folded, Shape::StronglyFolded] {
                    let x = deformed(shape);
                    let y = moved(&x, &q, t);
                    let mut a = Local::new();
                    let mut b = Local::new();
                    let ea = evaluate(&patch, &x, false, &mut a);
                    let eb = evaluate(&patch, &y, false, &mut b);
                    let what = format!("{shape:?}, curved {curved}, D {:?}", rigidity.0);
                    // Near-flat, the curvatures (about 0.1 1/m) are what is
                    // left of sums `C x` of positions about 1 m from the
                    // origin with `C` about 1/H^2: round-off of about
                    // eps |x| / (1e-3 H) = 3e-11 relative, so the folded
                    // shapes are held to 1e-12 and this one to 1e-9.
                    let tol = if matches!(shape, Shape::NearFlat) {
                        1e-9
                    } else {
                        1e-12
                    };
                    assert!(ea > 0.0, "{what}");
                    assert!(
                        (eb - ea).abs() <= tol * ea,
                        "{what}: energy {ea:e} -> {eb:e}"
                    );
                    let gmax = (0..6)
                        .map(|k| norm(node(&a.gradient, k)))
                        .fold(0.0, f64::max);
                    let gsum: f64 = (0..6).map(|k| norm(node(&a.gradient, k))).sum();
                    for k in 0..6 {
                        let rotated = apply(&q, node(&a.gradient, k));
                        let diff = norm(sub(node(&b.gradient, k), rotated));
                        assert!(diff <= tol * gmax, "{what}: node {k}: {diff:e} of {gmax:e}");
                    }
                    for (x, g) in [(&x, &a.gradient), (&y, &b.gradient)] {
                        let mut force = [0.0; 3];
                        let mut moment = [0.0; 3];
                        let mut moment_scale = 0.0;
                        for k in 0..6 {
                            let gk = node(g, k);
                            force = add(force, gk);
                            moment = add(moment, cross(x[k], gk));
                            moment_scale += norm(x[k]) * norm(gk);
                        }
                        assert!(
                            norm(force) <= 1e-13 * gsum,
                            "{what}: net force {force:?} of {gsum:e}"
                        );
                        assert!(
                            norm(moment) <= 1e-13 * moment_scale,
                            "{what}: net moment {moment:?} of {moment_scale:e}"
                        );
                    }
                }
            }
        }
    }

    /// The Hessian is symmetric to round-off, flat (away from a curved
    /// reference), near-flat, folded and strongly folded, for each kind of
    /// rigidity and with boundary edges.
    #[test]
    fn hessian_is_symmetric() {
        let boundaries = [ALL, [Some(3), None, Some(5)], [None, None, Some(5)]];
        for rigidity in &rigidities() {
            for curved in [false, true] {
                for opposite in boundaries {
                    let patch = fit(&reference(curved), opposite, rigidity);
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
                            "{shape:?}, curved {curved}, {opposite:?}, D {:?}: |H - H^T| {asym:e} of {max:e}",
                            rigidity.0
                        );
                    }
                }
            }
        }
    }

    /// At its reference (flat or curved) a patch has no energy and no
    /// force, and its Hessian `K^T (A D') K` is positive semi-definite, of
    /// the rank of the condensed stiffness (3 with three neighbours),
    /// with the six rigid motions in its null space.
    #[test]
    fn hessian_at_reference_is_semidefinite_with_rigid_null_space() {
        let cases = [
            (ALL, 3),
            ([Some(3), Some(4), None], 2),
            ([None, Some(4), None], 1),
        ];
        for rigidity in &rigidities() {
            for curved in [false, true] {
                for (opposite, rank) in cases {
                    let xg = reference(curved);
                    let patch = fit(&xg, opposite, rigidity);
                    let x = local(&patch, &xg);
                    let n = patch.len();
                    let dofs = 3 * n;
                    let mut out = Local::new();
                    let energy = evaluate(&patch, &x, true, &mut out);
                    let h: Vec<Vec<f64>> =
                        (0..dofs).map(|a| out.hessian[a][..dofs].to_vec()).collect();
                    let what = format!("curved {curved}, {opposite:?}, D {:?}", rigidity.0);
                    let l = eigenvalues(&h);
                    let lmax = l[dofs - 1];
                    assert!(lmax > 0.0, "{what}");
                    assert!(l[0] >= -1e-12 * lmax, "{what}: {l:?}");
                    let positive = l.iter().filter(|&&v| v > 1e-9 * lmax).count();
                    assert_eq!(positive, rank, "{what}: {l:?}");
                    // The reference curvature is the curvature at the
                    // reference: nothing to relax.
                    assert!(energy.abs() <= 1e-30, "{what}: {energy:e}");
                    let g = out.gradient[..dofs]
                        .iter()
                        .map(|v| v.abs())
                        .fold(0.0, f64::max);
                    assert!(g <= 1e-12 * lmax * H, "{what}: gradient {g:e}");
                    // The three translations and three infinitesimal
                    // rotations (about the origin, away from the patch).
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
                        assert!(
                            hv <= 1e-12 * lmax * vn,
                            "{what}: mode {m}: |H v| {hv:e}, {:e}",
                            lmax * vn
                        );
                    }
                }
            }
        }
    }

    /// Voigt `(f_,11, f_,22, 2 f_,12)` of a Hessian `[[f11, f12], [f12, f22]]`.
    fn voigt(h: [[f64; 2]; 2]) -> [f64; 3] {
        [h[0][0], h[1][1], 2.0 * h[0][1]]
    }

    /// Voigt `(k_11, k_22, 2 k_12)` of the plane tensor `h` (in x, y) in
    /// the frame whose first axis is along `a` (in the plane) and second
    /// is z x `a`.
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

    fn assert_close(got: [f64; 3], want: [f64; 3], tol: f64, what: &str) {
        let scale = want.iter().map(|v| v.abs()).fold(0.0, f64::max);
        for j in 0..3 {
            assert!(
                (got[j] - want[j]).abs() <= tol * scale,
                "{what}: kappa {got:?}, expected {want:?}"
            );
        }
    }

    /// The curvature is exact for quadratic surfaces on the skewed patch.
    /// With the reference flat in z = 0 and the triangle's first edge
    /// along x, the patch's frame is (x, y):
    ///
    /// * nodes on `z = f(x, y)`, `f` quadratic and zero at the triangle's
    ///   vertices (so the deformed triangle's normal is exactly z):
    ///   `kappa = (f_,xx, f_,yy, 2 f_,xy) = (2a, 2c, 2b)` for
    ///   `f = a x^2 + b xy + c y^2 + linear`, small and large;
    /// * nodes at `x(X, Y)`, any quadratic map of the plane into space:
    ///   `kappa_ab = n . x_,ab` with `n` the deformed triangle's unit
    ///   normal, computed here from its vertices;
    /// * the same surfaces as references: the rest curvature is theirs;
    /// * with a frame axis at angle theta in the plane, the curvature is the
    ///   same tensor in the rotated frame.
    #[test]
    fn curvature_is_exact_for_quadratic_surfaces() {
        let d = BendingRigidity::Isotropic(1e-5).matrix();
        let flat = on_surface(|_| 0.0);
        let patch = Patch::fit([0, 1, 2], ALL, &flat, &d, None, None).unwrap();
        assert_eq!(patch.rest, [0.0; 3]);
        for (a, b, c) in [(3.0, -1.7, 5.2), (80.0, -40.0, 120.0), (-25.0, 60.0, 10.0)] {
            let f = vanishing(a, b, c);
            let x = on_surface(&f);
            for k in 0..3 {
                assert!(x[k][2].abs() <= 1e-15 * H, "vertex {k}: {:?}", x[k]);
            }
            let want = voigt([[2.0 * a, b], [b, 2.0 * c]]);
            let what = format!("z = {a} x^2 + {b} xy + {c} y^2 + ...");
            assert_close(patch.curvature(&x), want, 1e-9, &what);
            // As a reference: its rest curvature.
            let curved = Patch::fit([0, 1, 2], ALL, &x, &d, None, None).unwrap();
            assert_close(curved.rest, want, 1e-9, &format!("reference {what}"));
            // The energy is 1/2 e . (A D') e, e = kappa - kappa_0.
            let mut out = Local::new();
            let energy = evaluate(&patch, &x, false, &mut out);
            let e = patch.curvature(&x);
            let s = &patch.stiffness;
            let want_energy: f64 = 0.5
                * (0..3)
                    .map(|i| e[i] * (0..3).map(|j| s[i][j] * e[j]).sum::<f64>())
                    .sum::<f64>();
            assert!(
                (energy - want_energy).abs() <= 1e-12 * want_energy,
                "{what}"
            );
            // In a frame turned by theta (the warp given with a component
            // out of the plane, which is projected away).
            let theta: f64 = 0.6;
            let (sn, cs) = theta.sin_cos();
            let turned = Patch::fit([0, 1, 2], ALL, &flat, &d, Some([cs, sn, 0.3]), None).unwrap();
            let rotated = voigt_along([[2.0 * a, b], [b, 2.0 * c]], [cs, sn]);
            assert_close(
                turned.curvature(&x),
                rotated,
                1e-9,
                &format!("turned, {what}"),
            );
        }

        // A general quadratic map of the plane into space (stretched,
        // sheared, tilted, every component curved).
        let lin = [[1.1, 0.2], [-0.3, 0.9], [0.4, -0.5]];
        let hess = [
            [[12.0, -5.0], [-5.0, 30.0]],
            [[-8.0, 14.0], [14.0, 3.0]],
            [[45.0, 20.0], [20.0, -35.0]],
        ];
        let origin = [0.2, -0.1, 0.05];
        let map = |p: [f64; 2]| -> [f64; 3] {
            std::array::from_fn(|i| {
                origin[i]
                    + lin[i][0] * p[0]
                    + lin[i][1] * p[1]
                    + 0.5
                        * (hess[i][0][0] * p[0] * p[0]
                            + 2.0 * hess[i][0][1] * p[0] * p[1]
                            + hess[i][1][1] * p[1] * p[1])
            })
        };
        let x: Vec<[f64; 3]> = plane_points().iter().map(|&p| map(p)).collect();
        let n = {
            let m = cross(sub(x[1], x[0]), sub(x[2], x[0]));
            scale(m, 1.0 / norm(m))
        };
        let second: [[f64; 3]; 3] = [0, 1, 2].map(|j| std::array::from_fn(|i| voigt(hess[i])[j]));
        let want = second.map(|v| dot(n, v));
        assert_close(patch.curvature(&x), want, 1e-9, "quadratic map");
    }

    /// A quadratic `f = a x^2 + b xy + c y^2 + d x + e y` zero at the
    /// triangle's vertices, as `(a, b, c)` -> its value at `p`.
    fn vanishing_at(abc: [f64; 3], p: [f64; 2]) -> f64 {
        vanishing(abc[0], abc[1], abc[2])(p)
    }

    /// With boundary edges (opposite nodes missing), the quadratics through
    /// the nodes that remain are not unique: the free curvatures are those
    /// of the quadratics vanishing at all the remaining nodes (computed
    /// here independently of the fit). The condensed stiffness `A D'`
    /// gives them no energy (it is singular along them), keeps its rank
    /// on the rest and stays positive semi-definite; a patch bent along a
    /// free curvature has no energy.
    #[test]
    fn boundary_edges_are_free_and_stiffness_stays_semidefinite() {
        let flat = on_surface(|_| 0.0);
        let p = plane_points();
        for rigidity in &rigidities() {
            for missing in [
                vec![0],
                vec![1],
                vec![2],
                vec![0, 2],
                vec![1, 2],
                vec![0, 1, 2],
            ] {
                let opposite: [Option<usize>; 3] =
                    std::array::from_fn(|m| (!missing.contains(&m)).then_some(3 + m));
                let patch = fit(&flat, opposite, rigidity);
                let s = patch.stiffness;
                let what = format!("missing {missing:?}, D {:?}", rigidity.0);
                // The rows `(a, b, c) -> f(P_p)` of the remaining opposite
                // nodes; the free quadratics are their null space.
                let rows: Vec<[f64; 3]> = opposite
                    .iter()
                    .flatten()
                    .map(|&q| {
                        std::array::from_fn(|i| {
                            let mut e = [0.0; 3];
                            e[i] = 1.0;
                            vanishing_at(e, p[q])
                        })
                    })
                    .collect();
                let free: Vec<[f64; 3]> = match rows.len() {
                    2 => vec![cross(rows[0], rows[1])],
                    1 => (0..3)
                        .map(|i| {
                            let mut e = [0.0; 3];
                            e[i] = 1.0;
                            cross(rows[0], e)
                        })
                        .collect(),
                    _ => vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                };
                let smax = s.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
                let dmax = rigidity
                    .0
                    .iter()
                    .flatten()
                    .map(|v| v.abs())
                    .fold(0.0, f64::max);
                let area = 0.5 * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
                for (i, j) in [(0, 1), (0, 2), (1, 2)] {
                    assert!((s[i][j] - s[j][i]).abs() <= 1e-14 * smax, "{what}: {s:?}");
                }
                // The patch's frame: x, y, or along the projected warp.
                let axis = rigidity.1.map_or([1.0, 0.0], |a| [a[0], a[1]]);
                for abc in &free {
                    let k = voigt_along([[2.0 * abc[0], abc[1]], [abc[1], 2.0 * abc[2]]], axis);
                    let sk: [f64; 3] = std::array::from_fn(|i| dot(s[i], k));
                    assert!(
                        norm(sk) <= 1e-12 * area * dmax * norm(k),
                        "{what}: A D' kappa_free = {sk:?} for kappa_free {k:?}"
                    );
                    // Bent along it: no energy, against the energy of a
                    // curvature of the same size that is not free.
                    if norm(k) > 0.0 {
                        let bent = on_surface(|q| vanishing_at(*abc, q));
                        let mut out = Local::new();
                        let energy = evaluate(&patch, &local(&patch, &bent), false, &mut out);
                        let reference = 0.5 * area * dmax * dot(k, k);
                        assert!(
                            energy.abs() <= 1e-12 * reference,
                            "{what}: energy {energy:e} of {reference:e}"
                        );
                    }
                }
                let l = eigenvalues(&s.iter().map(|r| r.to_vec()).collect::<Vec<_>>());
                let rank = 3 - missing.len();
                assert!(l[0] >= -1e-12 * area * dmax, "{what}: {l:?}");
                let positive = l.iter().filter(|&&v| v > 1e-9 * area * dmax).count();
                assert_eq!(positive, rank, "{what}: eigenvalues {l:?}");
            }
        }
    }
}
