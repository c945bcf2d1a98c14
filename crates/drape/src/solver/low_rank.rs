//! Solves with a sparse matrix plus a symmetric low-rank part, `(A + U C
//! U^T) x = b`, without forming the dense sum (the gas in a cavity couples
//! every node of its surface with every other through `-dp/dV g g^T`,
//! `g = dV/dY`: docs/theory.md §1.16).
//!
//! By the Sherman–Morrison–Woodbury identity (Golub & Van Loan, *Matrix
//! Computations*, 4th ed., §2.1.4),
//!
//! ```text
//! (A + U C U^T)^-1 b = x - W S^-1 U^T x,   x = A^-1 b,  W = A^-1 U,  S = C^-1 + U^T W
//! ```
//!
//! so a solve costs one factorisation of the sparse `A` (by whichever path
//! [`LinearSolver`] takes: the node-block LU, Cholesky, multigrid Krylov)
//! and `k + 1` solves with it for `k` columns of `U`, plus a `k x k`
//! system. [`Woodbury::prepare`] computes `W` and `S` once per
//! factorisation, right after the solve that made it; chord steps, which
//! reuse the factorisation, reuse them ([`Woodbury::correct`]).

use super::linear::LinearSolver;
use super::linear_error::LinearSolveError;
use crate::vecn::dot;

/// A symmetric low-rank part of a Hessian, `sum_k c_k u_k u_k^T`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LowRank {
    /// The vectors `u_k`, each of the system's dimension.
    pub vectors: Vec<Vec<f64>>,
    /// The coefficients `c_k` (non-zero).
    pub coefficients: Vec<f64>,
}

impl LowRank {
    /// Whether it has no columns.
    pub fn is_empty(&self) -> bool {
        self.vectors.is_empty()
    }

    /// Drops the columns, keeping their storage.
    pub fn clear(&mut self) {
        self.vectors.clear();
        self.coefficients.clear();
    }

    /// `y += sum_k c_k u_k (u_k . x)`: the product with the part.
    pub fn add_product(&self, x: &[f64], y: &mut [f64]) {
        for (u, c) in self.vectors.iter().zip(&self.coefficients) {
            let s = c * dot(u, x);
            for (yi, ui) in y.iter_mut().zip(u) {
                *yi += s * ui;
            }
        }
    }
}

/// Woodbury's correction for one factorisation: `U`, `W = A^-1 U` and
/// `S^-1`.
#[derive(Debug, Default)]
pub struct Woodbury {
    u: Vec<Vec<f64>>,
    w: Vec<Vec<f64>>,
    /// `S^-1`, `k x k` row-major.
    s_inv: Vec<f64>,
}

impl Woodbury {
    /// After a solve `x = A^-1 b` that left `linear` factorised (or its
    /// hierarchy built) for the matrix `values`: prepares the correction
    /// for `low` (or forgets it, without one) and applies it to `x`, which
    /// becomes `(A + U C U^T)^-1 b`. The extra right-hand sides go through
    /// [`LinearSolver::solve_again`] when the path keeps a factor, else
    /// through [`LinearSolver::solve`] with the same values.
    pub fn prepare(
        &mut self,
        low: Option<&LowRank>,
        linear: &mut LinearSolver,
        values: &[f64],
        symmetric: bool,
        x: &mut [f64],
    ) -> Result<(), LinearSolveError> {
        self.u.clear();
        self.w.clear();
        self.s_inv.clear();
        let Some(low) = low.filter(|l| !l.is_empty()) else {
            return Ok(());
        };
        let k = low.vectors.len();
        for u in &low.vectors {
            let mut w = u.clone();
            if !linear.solve_again(values, &mut w) {
                w.copy_from_slice(u);
                linear.solve(values, symmetric, &mut w)?;
            }
            self.w.push(w);
            self.u.push(u.clone());
        }
        let mut s = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..k {
                s[i * k + j] = dot(&self.u[i], &self.w[j]);
            }
            s[i * k + i] += 1.0 / low.coefficients[i];
        }
        self.s_inv = invert(&s, k);
        self.correct(x);
        Ok(())
    }

    /// `x <- x - W S^-1 U^T x` with the prepared correction (none: `x`
    /// unchanged).
    pub fn correct(&self, x: &mut [f64]) {
        let k = self.u.len();
        if k == 0 {
            return;
        }
        let ux: Vec<f64> = self.u.iter().map(|u| dot(u, x)).collect();
        for (i, w) in self.w.iter().enumerate() {
            let z: f64 = (0..k).map(|j| self.s_inv[i * k + j] * ux[j]).sum();
            for (xi, wi) in x.iter_mut().zip(w) {
                *xi -= z * wi;
            }
        }
    }
}

/// The inverse of the `k x k` matrix `s` (row-major) by Gauss–Jordan
/// elimination with partial pivoting (`k` is the number of cavities: a
/// handful). A singular `S` gives non-finite entries, which the caller's
/// residual check then meets.
fn invert(s: &[f64], k: usize) -> Vec<f64> {
    let mut a = s.to_vec();
    let mut inv: Vec<f64> = (0..k * k)
        .map(|ij| if ij / k == ij % k { 1.0 } else { 0.0 })
        .collect();
    for c in 0..k {
        let pivot = (c..k)
            .max_by(|&i, &j| a[i * k + c].abs().total_cmp(&a[j * k + c].abs()))
            .unwrap_or(c);
        for j in 0..k {
            a.swap(c * k + j, pivot * k + j);
            inv.swap(c * k + j, pivot * k + j);
        }
        let d = a[c * k + c];
        for j in 0..k {
            a[c * k + j] /= d;
            inv[c * k + j] /= d;
        }
        for i in 0..k {
            if i != c {
                let f = a[i * k + c];
                for j in 0..k {
                    a[i * k + j] -= f * a[c * k + j];
                    inv[i * k + j] -= f * inv[c * k + j];
                }
            }
        }
    }
    inv
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::SparsePattern;

    /// On a tridiagonal-by-blocks SPD matrix plus two rank-one parts, the
    /// corrected solution solves the full system: its residual, with the
    /// full product, is at round-off; and a chord-step correction of
    /// another right-hand side does the same.
    #[test]
    fn woodbury_solves_the_full_system() {
        let nodes = 6;
        let elements: Vec<[usize; 3]> = (0..nodes - 2).map(|a| [a, a + 1, a + 2]).collect();
        let pattern = SparsePattern::new(nodes, elements.iter().map(|e| &e[..]));
        let n = 3 * nodes;
        let mut values = vec![0.0; pattern.nnz()];
        for r in 0..n {
            for c in 0..n {
                if let Some(p) = pattern.find(r, c) {
                    values[p] = if r == c {
                        4.0 + r as f64 * 0.1
                    } else {
                        -0.3 / (1.0 + (r + c) as f64)
                    };
                }
            }
        }
        let mut linear = LinearSolver::new(&pattern.col_ptr, &pattern.row_idx).expect("solver");
        let low = LowRank {
            vectors: (0..2)
                .map(|k| (0..n).map(|i| ((i + k) as f64 * 0.7).sin()).collect())
                .collect(),
            coefficients: vec![3.0, 0.5],
        };
        let product = |x: &[f64]| {
            let mut y = vec![0.0; n];
            for c in 0..n {
                for r in 0..n {
                    if let Some(p) = pattern.find(r, c) {
                        y[r] += values[p] * x[c];
                    }
                }
            }
            low.add_product(x, &mut y);
            y
        };
        let b: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64).cos()).collect();
        let mut x = b.clone();
        linear.solve(&values, true, &mut x).expect("solve");
        let mut woodbury = Woodbury::default();
        woodbury
            .prepare(Some(&low), &mut linear, &values, true, &mut x)
            .expect("prepare");
        let r: f64 = product(&x)
            .iter()
            .zip(&b)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(r < 1e-12, "residual {r:e}");
        let b2: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let mut x2 = b2.clone();
        assert!(linear.solve_again(&values, &mut x2));
        woodbury.correct(&mut x2);
        let r2: f64 = product(&x2)
            .iter()
            .zip(&b2)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(r2 < 1e-12, "chord residual {r2:e}");
    }
}
