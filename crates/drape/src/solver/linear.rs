//! Sparse direct solution of `H dY = -G` with faer, reusing the symbolic
//! analysis for as long as the sparsity pattern holds.
//!
//! * Symmetric Hessians (Saint-Venant–Kirchhoff with dead loads, mass and
//!   supports; a follower pressure on a membrane whose edge is fixed, once
//!   the element contributions have cancelled) are factorised by sparse
//!   Cholesky `H = L L^T` with an AMD fill-reducing ordering. Only the lower
//!   triangle is read.
//! * A Hessian that is not symmetric (follower pressure on a free edge, the
//!   wrinkling tangent) or not positive definite (a membrane in compression
//!   in statics) is factorised by sparse LU with partial pivoting and a
//!   COLAMD column ordering.
//!
//! Each symbolic analysis is made once, on first use, and kept; numeric
//! factors are written into storage that is reused from call to call.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::linalg::lu::{NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, Mat, Par, Side};

/// Which factorisation solved a system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Factorization {
    /// Sparse Cholesky `L L^T`.
    Cholesky,
    /// Sparse LU with partial pivoting.
    Lu,
    /// GMRES preconditioned by the Cholesky factor of the symmetric part
    /// `(A + A^T) / 2`.
    PreconditionedGmres,
}

/// A linear solve that could not be done.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LinearSolveError {
    /// The matrix is singular (LU found no pivot, or the solution is not finite).
    #[error("the Hessian is singular ({detail})")]
    Singular {
        /// What the factorisation reported.
        detail: String,
    },
    /// faer failed for another reason (memory, structure).
    #[error("the sparse factorisation failed: {0}")]
    Factorization(String),
}

/// Sparse direct solver bound to one sparsity pattern.
pub struct LinearSolver {
    symbolic: SymbolicSparseColMat<usize>,
    llt: Option<(SymbolicCholesky<usize>, Vec<f64>)>,
    lu: Option<(SymbolicLu<usize>, NumericLu<usize, f64>)>,
    memory: MemBuffer,
    memory_req: StackReq,
    rhs: Mat<f64>,
    par: Par,
    /// Mirror of each stored entry (structurally symmetric patterns), for
    /// the preconditioned Krylov path.
    transpose: Option<Vec<usize>>,
    /// Work space of the Krylov path.
    krylov: Krylov,
    /// Krylov iterations of the last solve (0 for direct solves).
    pub last_krylov_iterations: usize,
}

struct Krylov {
    symmetric_part: Vec<f64>,
    basis: Vec<Vec<f64>>,
    work: Mat<f64>,
    z: Vec<f64>,
}

impl Default for Krylov {
    fn default() -> Self {
        Self {
            symmetric_part: Vec::new(),
            basis: Vec::new(),
            work: Mat::zeros(0, 0),
            z: Vec::new(),
        }
    }
}

impl std::fmt::Debug for LinearSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LinearSolver")
            .field("dimension", &self.symbolic.nrows())
            .field("nnz", &self.symbolic.compute_nnz())
            .field("cholesky", &self.llt.is_some())
            .field("lu", &self.lu.is_some())
            .finish()
    }
}

impl LinearSolver {
    /// A solver for square matrices with CSC pattern `(col_ptr, row_idx)`
    /// (rows sorted in each column).
    pub fn new(col_ptr: &[usize], row_idx: &[usize]) -> Result<Self, LinearSolveError> {
        let n = col_ptr.len() - 1;
        let symbolic =
            SymbolicSparseColMat::new_checked(n, n, col_ptr.to_vec(), None, row_idx.to_vec());
        Ok(Self {
            symbolic,
            llt: None,
            lu: None,
            memory: MemBuffer::new(StackReq::EMPTY),
            memory_req: StackReq::EMPTY,
            rhs: Mat::zeros(n, 1),
            // A second thread does not speed up faer's sparse factorisation
            // at these sizes (FACTS.md); the threads serve assembly.
            par: Par::Seq,
            transpose: None,
            krylov: Krylov::default(),
            last_krylov_iterations: 0,
        })
    }

    /// Enables the preconditioned Krylov path for non-symmetric matrices
    /// on a structurally symmetric pattern: `transpose[k]` is the value
    /// index of the entry mirrored about the diagonal of entry `k`.
    pub fn with_transpose(mut self, transpose: Vec<usize>) -> Self {
        self.transpose = Some(transpose);
        self
    }

    /// Entries of the Cholesky factor `L`, once it has been analysed.
    pub fn cholesky_nnz(&self) -> Option<usize> {
        self.llt.as_ref().map(|(s, _)| s.len_val())
    }

    /// Dimension of the system.
    pub fn dimension(&self) -> usize {
        self.symbolic.nrows()
    }

    fn ensure_memory(&mut self, req: StackReq) {
        let combined = self.memory_req.or(req);
        if combined != self.memory_req {
            self.memory_req = combined;
            self.memory = MemBuffer::new(combined);
        }
    }

    /// Solves `A x = b` in place (`rhs`: `b` in, `x` out) for the values
    /// `values` on the pattern. With `symmetric`, Cholesky is tried first and
    /// LU is the fallback when `A` is not positive definite.
    pub fn solve(
        &mut self,
        values: &[f64],
        symmetric: bool,
        rhs: &mut [f64],
    ) -> Result<Factorization, LinearSolveError> {
        let n = self.dimension();
        self.last_krylov_iterations = 0;
        for (i, v) in rhs.iter().enumerate() {
            self.rhs[(i, 0)] = *v;
        }
        let mut used = None;
        if symmetric {
            if self.factor_cholesky(values)? {
                self.cholesky_solve_rhs();
                used = Some(Factorization::Cholesky);
            }
        } else if self.transpose.is_some() && self.gmres(values, rhs)? {
            used = Some(Factorization::PreconditionedGmres);
        }
        let used = match used {
            Some(u) => u,
            None => {
                for (i, v) in rhs.iter().enumerate() {
                    self.rhs[(i, 0)] = *v;
                }
                self.solve_lu(values)?;
                Factorization::Lu
            }
        };
        // A (numerically) singular matrix can factorise without error and
        // return garbage: check the solution's residual, `O(nnz)`.
        let b_norm = rhs.iter().map(|v| v * v).sum::<f64>().sqrt();
        let residual = self.residual_norm(values, rhs);
        for (i, x) in rhs.iter_mut().enumerate().take(n) {
            *x = self.rhs[(i, 0)];
        }
        if rhs.iter().any(|x| !x.is_finite()) {
            return Err(LinearSolveError::Singular {
                detail: "the solution is not finite".into(),
            });
        }
        if residual.is_nan() || residual > 1e-6 * b_norm {
            return Err(LinearSolveError::Singular {
                detail: format!(
                    "the {} solve leaves a relative residual of {:.1e}",
                    match used {
                        Factorization::Cholesky => "Cholesky",
                        Factorization::Lu => "LU",
                        Factorization::PreconditionedGmres => "preconditioned GMRES",
                    },
                    residual / b_norm
                ),
            });
        }
        Ok(used)
    }

    /// `|A x - b|` with `x` in `self.rhs` and `b` in `rhs`.
    fn residual_norm(&self, values: &[f64], b: &[f64]) -> f64 {
        let mut r = b.to_vec();
        let col_ptr = self.symbolic.col_ptr();
        let row_idx = self.symbolic.row_idx();
        for c in 0..self.dimension() {
            let x = self.rhs[(c, 0)];
            for k in col_ptr[c]..col_ptr[c + 1] {
                r[row_idx[k]] -= values[k] * x;
            }
        }
        r.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// Factorises `values` (lower triangle read) by Cholesky into the kept
    /// storage; `Ok(false)` when the matrix is not positive definite.
    fn factor_cholesky(&mut self, values: &[f64]) -> Result<bool, LinearSolveError> {
        if self.llt.is_none() {
            let symb = factorize_symbolic_cholesky(
                self.symbolic.as_ref(),
                Side::Lower,
                SymmetricOrdering::Amd,
                Default::default(),
            )
            .map_err(|e| LinearSolveError::Factorization(format!("{e:?}")))?;
            let l = vec![0.0; symb.len_val()];
            self.llt = Some((symb, l));
        }
        let par = self.par;
        let req = {
            let (symb, _) = self.llt.as_ref().expect("set above");
            symb.factorize_numeric_llt_scratch::<f64>(par, Default::default())
                .or(symb.solve_in_place_scratch::<f64>(1, par))
        };
        self.ensure_memory(req);
        let (symb, l) = self.llt.as_mut().expect("set above");
        let a = SparseColMatRef::new(self.symbolic.as_ref(), values);
        let stack = MemStack::new(&mut self.memory);
        Ok(symb
            .factorize_numeric_llt::<f64>(
                l,
                a,
                Side::Lower,
                LltRegularization::default(),
                par,
                stack,
                Default::default(),
            )
            .is_ok())
    }

    /// `self.rhs <- L^-T L^-1 self.rhs` with the current Cholesky factor.
    fn cholesky_solve_rhs(&mut self) {
        let mut rhs = std::mem::replace(&mut self.rhs, Mat::zeros(0, 0));
        self.cholesky_solve(&mut rhs);
        self.rhs = rhs;
    }

    fn cholesky_solve(&mut self, x: &mut Mat<f64>) {
        let par = self.par;
        let (symb, l) = self.llt.as_ref().expect("factorised before");
        let stack = MemStack::new(&mut self.memory);
        LltRef::<usize, f64>::new(symb, l).solve_in_place_with_conj(
            Conj::No,
            x.as_mut(),
            par,
            stack,
        );
    }

    /// `out = A x` on the pattern.
    fn matvec(&self, values: &[f64], x: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        let (col_ptr, row_idx) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        for c in 0..self.dimension() {
            let xc = x[c];
            if xc != 0.0 {
                for k in col_ptr[c]..col_ptr[c + 1] {
                    out[row_idx[k]] += values[k] * xc;
                }
            }
        }
    }

    /// Restarted GMRES, right-preconditioned by the Cholesky factor `P` of
    /// the symmetric part `(A + A^T) / 2`: solves `A P^-1 u = b`, `x = P^-1
    /// u`, to `|b - A x| <= 1e-12 |b|`, so that the result equals a direct
    /// solve's to well within Newton's tolerance. When the skew part of `A`
    /// is small against the symmetric part (the wrinkling tangent next to
    /// the mass term), few iterations are needed. Returns `Ok(false)` (the
    /// caller then uses LU) when the symmetric part is not positive
    /// definite or GMRES has not converged in 100 iterations. The solution
    /// is left in `self.rhs`.
    fn gmres(&mut self, values: &[f64], b: &[f64]) -> Result<bool, LinearSolveError> {
        const RESTART: usize = 25;
        const MAX_ITERATIONS: usize = 100;
        let n = self.dimension();
        let transpose = self.transpose.take().expect("checked by the caller");
        let mut sym = std::mem::take(&mut self.krylov.symmetric_part);
        sym.resize(values.len(), 0.0);
        for (k, s) in sym.iter_mut().enumerate() {
            *s = 0.5 * (values[k] + values[transpose[k]]);
        }
        self.transpose = Some(transpose);
        let ok = self.factor_cholesky(&sym)?;
        self.krylov.symmetric_part = sym;
        if !ok {
            return Ok(false);
        }
        let b_norm = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        let mut x = vec![0.0; n];
        if b_norm == 0.0 {
            self.rhs.as_mut().fill(0.0);
            return Ok(true);
        }
        let mut basis = std::mem::take(&mut self.krylov.basis);
        basis.resize_with(RESTART + 1, || vec![0.0; n]);
        let mut work = std::mem::replace(&mut self.krylov.work, Mat::zeros(0, 0));
        if work.nrows() != n {
            work = Mat::zeros(n, 1);
        }
        let mut r = vec![0.0; n];
        let mut ax = vec![0.0; n];
        let mut iterations = 0;
        let mut converged = false;
        while iterations < MAX_ITERATIONS && !converged {
            // r = b - A x
            self.matvec(values, &x, &mut ax);
            for i in 0..n {
                r[i] = b[i] - ax[i];
            }
            let beta = r.iter().map(|v| v * v).sum::<f64>().sqrt();
            if beta <= 1e-12 * b_norm {
                converged = true;
                break;
            }
            for i in 0..n {
                basis[0][i] = r[i] / beta;
            }
            let mut h = vec![[0.0f64; RESTART + 1]; RESTART];
            let (mut cs, mut sn) = ([0.0f64; RESTART], [0.0f64; RESTART]);
            let mut g = [0.0f64; RESTART + 1];
            g[0] = beta;
            let mut k_used = 0;
            for k in 0..RESTART {
                // w = A P^-1 v_k
                for i in 0..n {
                    work[(i, 0)] = basis[k][i];
                }
                self.cholesky_solve(&mut work);
                let mut z = std::mem::take(&mut self.krylov.z);
                z.clear();
                z.extend((0..n).map(|i| work[(i, 0)]));
                let (head, tail) = basis.split_at_mut(k + 1);
                let w = &mut tail[0];
                self.matvec(values, &z, w);
                self.krylov.z = z;
                for (j, vj) in head.iter().enumerate() {
                    let hj = vj.iter().zip(w.iter()).map(|(a, c)| a * c).sum::<f64>();
                    h[k][j] = hj;
                    for i in 0..n {
                        w[i] -= hj * vj[i];
                    }
                }
                let norm_w = w.iter().map(|v| v * v).sum::<f64>().sqrt();
                h[k][k + 1] = norm_w;
                if norm_w > 0.0 {
                    for v in w.iter_mut() {
                        *v /= norm_w;
                    }
                }
                for j in 0..k {
                    let t = cs[j] * h[k][j] + sn[j] * h[k][j + 1];
                    h[k][j + 1] = -sn[j] * h[k][j] + cs[j] * h[k][j + 1];
                    h[k][j] = t;
                }
                let d = (h[k][k] * h[k][k] + h[k][k + 1] * h[k][k + 1]).sqrt();
                (cs[k], sn[k]) = if d > 0.0 {
                    (h[k][k] / d, h[k][k + 1] / d)
                } else {
                    (1.0, 0.0)
                };
                h[k][k] = d;
                h[k][k + 1] = 0.0;
                g[k + 1] = -sn[k] * g[k];
                g[k] *= cs[k];
                iterations += 1;
                k_used = k + 1;
                if g[k + 1].abs() <= 1e-12 * b_norm || iterations >= MAX_ITERATIONS {
                    break;
                }
            }
            // Solve the triangular system, x += P^-1 V y.
            let mut y = [0.0f64; RESTART];
            for j in (0..k_used).rev() {
                let mut s = g[j];
                for l in j + 1..k_used {
                    s -= h[l][j] * y[l];
                }
                y[j] = s / h[j][j];
            }
            for i in 0..n {
                work[(i, 0)] = (0..k_used).map(|j| basis[j][i] * y[j]).sum();
            }
            self.cholesky_solve(&mut work);
            for i in 0..n {
                x[i] += work[(i, 0)];
            }
        }
        if !converged {
            self.matvec(values, &x, &mut ax);
            let res = b
                .iter()
                .zip(&ax)
                .map(|(p, q)| (p - q) * (p - q))
                .sum::<f64>()
                .sqrt();
            converged = res <= 1e-10 * b_norm;
        }
        self.krylov.basis = basis;
        self.krylov.work = work;
        self.last_krylov_iterations = iterations;
        for i in 0..n {
            self.rhs[(i, 0)] = x[i];
        }
        Ok(converged && x.iter().all(|v| v.is_finite()))
    }

    fn solve_lu(&mut self, values: &[f64]) -> Result<(), LinearSolveError> {
        if self.lu.is_none() {
            let symb = factorize_symbolic_lu(self.symbolic.as_ref(), Default::default())
                .map_err(|e| LinearSolveError::Factorization(format!("{e:?}")))?;
            self.lu = Some((symb, NumericLu::new()));
        }
        let par = self.par;
        let req = {
            let (symb, _) = self.lu.as_ref().expect("set above");
            symb.factorize_numeric_lu_scratch::<f64>(par, Default::default())
                .or(symb.solve_in_place_scratch::<f64>(1, par))
        };
        self.ensure_memory(req);
        let (symb, numeric) = self.lu.as_mut().expect("set above");
        let a = SparseColMatRef::new(self.symbolic.as_ref(), values);
        let stack = MemStack::new(&mut self.memory);
        let lu = symb
            .factorize_numeric_lu::<f64>(numeric, a, par, stack, Default::default())
            .map_err(|e| LinearSolveError::Singular {
                detail: format!("{e:?}"),
            })?;
        lu.solve_in_place_with_conj(Conj::No, self.rhs.as_mut(), par, stack);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1D Laplacian plus identity: SPD, tridiagonal.
    fn tridiagonal(n: usize, asym: f64) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let (mut cp, mut ri, mut v) = (vec![0], vec![], vec![]);
        for c in 0..n {
            if c > 0 {
                ri.push(c - 1);
                v.push(-1.0 - asym);
            }
            ri.push(c);
            v.push(3.0);
            if c + 1 < n {
                ri.push(c + 1);
                v.push(-1.0 + asym);
            }
            cp.push(ri.len());
        }
        (cp, ri, v)
    }

    fn residual(cp: &[usize], ri: &[usize], v: &[f64], x: &[f64], b: &[f64]) -> f64 {
        let mut r = b.to_vec();
        for c in 0..cp.len() - 1 {
            for k in cp[c]..cp[c + 1] {
                r[ri[k]] -= v[k] * x[c];
            }
        }
        r.iter().map(|x| x.abs()).fold(0.0, f64::max)
    }

    #[test]
    fn cholesky_and_lu_solve_and_are_reused() {
        let n = 50;
        for (asym, symmetric, expected) in [
            (0.0, true, Factorization::Cholesky),
            (0.3, false, Factorization::Lu),
        ] {
            let (cp, ri, v) = tridiagonal(n, asym);
            let mut solver = LinearSolver::new(&cp, &ri).unwrap();
            for round in 0..3 {
                let b: Vec<f64> = (0..n).map(|i| (i + round) as f64).collect();
                let mut x = b.clone();
                assert_eq!(solver.solve(&v, symmetric, &mut x).unwrap(), expected);
                assert!(residual(&cp, &ri, &v, &x, &b) < 1e-12);
            }
        }
    }

    #[test]
    fn indefinite_symmetric_falls_back_to_lu() {
        let (cp, ri, mut v) = tridiagonal(10, 0.0);
        v.iter_mut().for_each(|x| *x = -*x);
        let mut solver = LinearSolver::new(&cp, &ri).unwrap();
        let b = vec![1.0; 10];
        let mut x = b.clone();
        assert_eq!(solver.solve(&v, true, &mut x).unwrap(), Factorization::Lu);
        assert!(residual(&cp, &ri, &v, &x, &b) < 1e-12);
    }
}
