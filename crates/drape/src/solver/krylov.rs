//! Krylov methods on any [`Operator`] (products by `A` and applications
//! of a preconditioner `P^-1`): restarted GMRES, right-preconditioned, for
//! non-symmetric matrices, and preconditioned conjugate gradients for
//! symmetric positive definite ones (Saad, *Iterative Methods for Sparse
//! Linear Systems*, 2nd ed., 2003: algorithms 6.11 and 9.1).
//!
//! Neither allocates once its [`Work`] space has grown to the system's
//! size; both leave the solution in [`Work::x`] and report whether they
//! converged and after how many iterations.

use crate::vecn::{distance, dot, norm};
use faer::Mat;

/// Restart length of GMRES (Krylov vectors kept).
const RESTART: usize = 25;

/// A matrix `A` and a preconditioner `P` as the Krylov methods use them.
pub(super) trait Operator {
    /// `out = A x`.
    fn apply(&mut self, x: &[f64], out: &mut [f64]);
    /// `z = P^-1 r`.
    fn precondition(&mut self, r: &[f64], z: &mut [f64]);
    /// `x <- P^-1 x` on GMRES's work column.
    fn precondition_in_place(&mut self, x: &mut Mat<f64>);
}

/// Work space of the Krylov methods, kept between solves.
pub(super) struct Work {
    /// The solution of the last solve.
    pub(super) x: Vec<f64>,
    pub(super) r: Vec<f64>,
    pub(super) ax: Vec<f64>,
    pub(super) z: Vec<f64>,
    /// CG's search direction.
    p: Vec<f64>,
    /// GMRES's Krylov basis, `RESTART + 1` vectors.
    basis: Vec<Vec<f64>>,
    /// GMRES's column for the preconditioner.
    column: Mat<f64>,
}

impl Default for Work {
    fn default() -> Self {
        Self {
            x: Vec::new(),
            r: Vec::new(),
            ax: Vec::new(),
            z: Vec::new(),
            p: Vec::new(),
            basis: Vec::new(),
            column: Mat::zeros(0, 0),
        }
    }
}

/// How a Krylov solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Outcome {
    /// Whether the residual reached the tolerance (the solution may still
    /// not be finite).
    pub(super) converged: bool,
    /// Iterations made (products by `A P^-1` or `A`).
    pub(super) iterations: usize,
}

/// Restarted GMRES (restart 25), right-preconditioned: solves `A P^-1 u =
/// b`, `x = P^-1 u`, from `x = 0` to `|b - A x| <= tolerance |b|` in at
/// most `max_iterations` — or, when the iterations run out, to
/// `max(tolerance, 1e-10) |b|` measured on the last iterate. Arnoldi with
/// modified Gram–Schmidt, Givens rotations on the Hessenberg matrix.
pub(super) fn gmres(
    op: &mut impl Operator,
    b: &[f64],
    tolerance: f64,
    max_iterations: usize,
    work: &mut Work,
) -> Outcome {
    let n = b.len();
    let b_norm = norm(b);
    let Work {
        x,
        r,
        ax,
        z,
        basis,
        column,
        ..
    } = work;
    x.clear();
    x.resize(n, 0.0);
    if b_norm == 0.0 {
        return Outcome {
            converged: true,
            iterations: 0,
        };
    }
    basis.resize_with(RESTART + 1, || vec![0.0; n]);
    if column.nrows() != n {
        *column = Mat::zeros(n, 1);
    }
    r.resize(n, 0.0);
    ax.resize(n, 0.0);
    let mut iterations = 0;
    let mut converged = false;
    while iterations < max_iterations && !converged {
        // r = b - A x
        op.apply(x, ax);
        for i in 0..n {
            r[i] = b[i] - ax[i];
        }
        let beta = norm(r);
        if beta <= tolerance * b_norm {
            converged = true;
            break;
        }
        for i in 0..n {
            basis[0][i] = r[i] / beta;
        }
        let mut ls = LeastSquares::new(beta);
        let mut k_used = 0;
        for k in 0..RESTART {
            // w = A P^-1 v_k
            for i in 0..n {
                column[(i, 0)] = basis[k][i];
            }
            op.precondition_in_place(column);
            z.clear();
            z.extend((0..n).map(|i| column[(i, 0)]));
            let (head, tail) = basis.split_at_mut(k + 1);
            let w = &mut tail[0];
            op.apply(z, w);
            // Modified Gram–Schmidt against v_0..v_k.
            let h = &mut ls.h[k];
            for (j, vj) in head.iter().enumerate() {
                let hj = dot(vj, w);
                h[j] = hj;
                for i in 0..n {
                    w[i] -= hj * vj[i];
                }
            }
            let norm_w = norm(w);
            h[k + 1] = norm_w;
            if norm_w > 0.0 {
                for v in w.iter_mut() {
                    *v /= norm_w;
                }
            }
            let residual = ls.rotate_column(k);
            iterations += 1;
            k_used = k + 1;
            if residual <= tolerance * b_norm || iterations >= max_iterations {
                break;
            }
        }
        // x += P^-1 V y.
        let y = ls.solve(k_used);
        for i in 0..n {
            column[(i, 0)] = (0..k_used).map(|j| basis[j][i] * y[j]).sum();
        }
        op.precondition_in_place(column);
        for i in 0..n {
            x[i] += column[(i, 0)];
        }
    }
    if !converged {
        op.apply(x, ax);
        converged = distance(b, ax) <= tolerance.max(1e-10) * b_norm;
    }
    Outcome {
        converged,
        iterations,
    }
}

/// The small least-squares problem of a GMRES cycle, `min |beta e_1 - H
/// y|` over the Hessenberg matrix `H` of the Arnoldi steps so far, kept
/// upper triangular by Givens rotations applied as its columns arrive.
struct LeastSquares {
    /// Column `k` of `H` (then of `R`) is `h[k][..=k + 1]`.
    h: [[f64; RESTART + 1]; RESTART],
    /// The rotations: cosines and sines.
    cs: [f64; RESTART],
    sn: [f64; RESTART],
    /// The rotated right-hand side; `|g[k + 1]|` is the residual norm
    /// after `k + 1` steps.
    g: [f64; RESTART + 1],
}

impl LeastSquares {
    fn new(beta: f64) -> Self {
        let mut g = [0.0f64; RESTART + 1];
        g[0] = beta;
        Self {
            h: [[0.0f64; RESTART + 1]; RESTART],
            cs: [0.0f64; RESTART],
            sn: [0.0f64; RESTART],
            g,
        }
    }

    /// Applies the earlier rotations to the new column `k`, then the one
    /// that zeroes its subdiagonal entry, to it and to `g`; returns the
    /// residual norm `|g[k + 1]|`.
    fn rotate_column(&mut self, k: usize) -> f64 {
        let Self { h, cs, sn, g } = self;
        let h = &mut h[k];
        for j in 0..k {
            let t = cs[j] * h[j] + sn[j] * h[j + 1];
            h[j + 1] = -sn[j] * h[j] + cs[j] * h[j + 1];
            h[j] = t;
        }
        let d = (h[k] * h[k] + h[k + 1] * h[k + 1]).sqrt();
        (cs[k], sn[k]) = if d > 0.0 {
            (h[k] / d, h[k + 1] / d)
        } else {
            (1.0, 0.0)
        };
        h[k] = d;
        h[k + 1] = 0.0;
        g[k + 1] = -sn[k] * g[k];
        g[k] *= cs[k];
        g[k + 1].abs()
    }

    /// `y = R^-1 g` over the first `k` columns, by back substitution.
    fn solve(&self, k: usize) -> [f64; RESTART] {
        let (h, g) = (&self.h, &self.g);
        let mut y = [0.0f64; RESTART];
        for j in (0..k).rev() {
            let mut s = g[j];
            for l in j + 1..k {
                s -= h[l][j] * y[l];
            }
            y[j] = s / h[j][j];
        }
        y
    }
}

/// Preconditioned conjugate gradients for symmetric positive definite
/// `A` (and `P`), from `x = 0` to `|b - A x| <= tolerance |b|` (the
/// recursively updated residual) in at most `max_iterations`. Not
/// converged when `A` shows a non-positive curvature `p . A p`.
pub(super) fn pcg(
    op: &mut impl Operator,
    b: &[f64],
    tolerance: f64,
    max_iterations: usize,
    work: &mut Work,
) -> Outcome {
    let n = b.len();
    let b_norm = norm(b);
    let Work {
        x, r, ax: ap, z, p, ..
    } = work;
    x.clear();
    x.resize(n, 0.0);
    r.clear();
    r.extend_from_slice(b);
    ap.resize(n, 0.0);
    z.resize(n, 0.0);
    let mut converged = b_norm == 0.0;
    let mut iterations = 0;
    if !converged {
        op.precondition(r, z);
        p.clear();
        p.extend_from_slice(z);
        let mut rz = dot(r, z);
        while iterations < max_iterations {
            op.apply(p, ap);
            let pap = dot(p, ap);
            if pap.is_nan() || pap <= 0.0 {
                break;
            }
            let alpha = rz / pap;
            for i in 0..n {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
            }
            iterations += 1;
            if norm(r) <= tolerance * b_norm {
                converged = true;
                break;
            }
            op.precondition(r, z);
            let rz_new = dot(r, z);
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                p[i] = z[i] + beta * p[i];
            }
        }
    }
    Outcome {
        converged,
        iterations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dense `n x n` matrix (row-major) with the identity or Jacobi
    /// (inverted diagonal) as the preconditioner.
    struct Dense {
        a: Vec<f64>,
        n: usize,
        jacobi: bool,
    }

    impl Operator for Dense {
        fn apply(&mut self, x: &[f64], out: &mut [f64]) {
            for (i, o) in out.iter_mut().enumerate() {
                *o = dot(&self.a[i * self.n..(i + 1) * self.n], x);
            }
        }
        fn precondition(&mut self, r: &[f64], z: &mut [f64]) {
            for (i, (zi, ri)) in z.iter_mut().zip(r).enumerate() {
                *zi = if self.jacobi {
                    ri / self.a[i * self.n + i]
                } else {
                    *ri
                };
            }
        }
        fn precondition_in_place(&mut self, x: &mut Mat<f64>) {
            let r: Vec<f64> = x.col_as_slice(0).to_vec();
            self.precondition(&r, x.col_as_slice_mut(0));
        }
    }

    /// `n = 40`: a diagonal that grows from 2 to 41 (condition number
    /// about 20, badly scaled without the preconditioner), neighbours
    /// coupled by `-0.5 ± skew`.
    fn matrix(n: usize, skew: f64, jacobi: bool) -> Dense {
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            a[i * n + i] = 2.0 + i as f64;
            if i + 1 < n {
                a[i * n + i + 1] = -0.5 + skew;
                a[(i + 1) * n + i] = -0.5 - skew;
            }
        }
        Dense { a, n, jacobi }
    }

    fn residual(op: &mut Dense, x: &[f64], b: &[f64]) -> f64 {
        let mut ax = vec![0.0; b.len()];
        op.apply(x, &mut ax);
        distance(b, &ax) / norm(b)
    }

    /// GMRES solves a non-symmetric system and CG a symmetric one to the
    /// tolerance asked (1e-12, checked on the true residual with a margin
    /// of 10 for the recursively updated one), with and without the
    /// preconditioner, GMRES past a restart (more than 25 iterations
    /// without it); a zero right-hand side gives zero at once.
    #[test]
    fn gmres_and_cg_solve_to_the_tolerance() {
        let n = 40;
        let b: Vec<f64> = (0..n).map(|i| (0.7 * i as f64).sin()).collect();
        let mut work = Work::default();
        for jacobi in [false, true] {
            let mut op = matrix(n, 0.3, jacobi);
            let out = gmres(&mut op, &b, 1e-12, 200, &mut work);
            assert!(out.converged && out.iterations > 0, "{out:?}");
            assert!(residual(&mut op, &work.x, &b) < 1e-11);
            let mut op = matrix(n, 0.0, jacobi);
            let out = pcg(&mut op, &b, 1e-12, 200, &mut work);
            assert!(out.converged && out.iterations > 0, "{out:?}");
            assert!(residual(&mut op, &work.x, &b) < 1e-11);
        }
        let zero = vec![0.0; n];
        let mut op = matrix(n, 0.3, false);
        let out = gmres(&mut op, &zero, 1e-12, 200, &mut work);
        assert_eq!((out.converged, out.iterations), (true, 0));
        assert!(work.x.iter().all(|&v| v == 0.0));
    }

    /// Too few iterations: neither method claims convergence; CG stops at
    /// the first non-positive curvature of an indefinite matrix.
    #[test]
    fn unconverged_and_indefinite_are_reported() {
        let n = 40;
        let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let mut work = Work::default();
        let mut op = matrix(n, 0.3, false);
        assert!(!gmres(&mut op, &b, 1e-12, 3, &mut work).converged);
        let mut op = matrix(n, 0.0, false);
        assert!(!pcg(&mut op, &b, 1e-12, 3, &mut work).converged);
        let mut op = matrix(n, 0.0, false);
        for v in op.a.iter_mut() {
            *v = -*v;
        }
        let out = pcg(&mut op, &b, 1e-12, 200, &mut work);
        assert_eq!((out.converged, out.iterations), (false, 0));
    }
}
