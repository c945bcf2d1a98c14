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

use super::patch::Patch;
use crate::vec3::{cross, dot, norm, scale, sub};

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

/// The curvatures `kappa` (Voigt: `kappa_11, kappa_22, 2 kappa_12`) of the
/// patch at positions `x` (its nodes' positions, in the patch's order).
pub fn curvature(patch: &Patch, x: &[[f64; 3]]) -> [f64; 3] {
    let n = normal(x).0;
    let mut kappa = [0.0; 3];
    for (j, kj) in kappa.iter_mut().enumerate() {
        let v = second_derivative(patch, x, j);
        *kj = dot(n, v);
    }
    kappa
}

/// The unit normal of the patch's triangle and `|m|`, twice its area.
#[inline]
fn normal(x: &[[f64; 3]]) -> ([f64; 3], f64) {
    let m = cross(sub(x[1], x[0]), sub(x[2], x[0]));
    let r = norm(m);
    (scale(m, 1.0 / r), r)
}

/// `v_j = sum_k C_jk x_k`.
#[inline]
fn second_derivative(patch: &Patch, x: &[[f64; 3]], j: usize) -> [f64; 3] {
    let mut v = [0.0; 3];
    for (k, xk) in x.iter().enumerate() {
        let c = patch.coefficients[j][k];
        for i in 0..3 {
            v[i] += c * xk[i];
        }
    }
    v
}

/// The bending energy of `patch` at `x`; with `hessian`, also its gradient
/// and Hessian into `out` (the gradient always).
pub fn evaluate(patch: &Patch, x: &[[f64; 3]], hessian: bool, out: &mut Local) -> f64 {
    let len = patch.len();
    debug_assert_eq!(x.len(), len);
    let (n, r) = normal(x);
    let v = [0, 1, 2].map(|j| second_derivative(patch, x, j));
    let kappa = v.map(|vj| dot(n, vj));
    let e = [0, 1, 2].map(|j| kappa[j] - patch.rest[j]);
    let ad = &patch.stiffness;
    let m = [0, 1, 2].map(|i| ad[i][0] * e[0] + ad[i][1] * e[1] + ad[i][2] * e[2]);
    let energy = 0.5 * (e[0] * m[0] + e[1] * m[1] + e[2] * m[2]);
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
