//! Direct factorisations: faer's sparse Cholesky `A = L L^T` (AMD
//! ordering, supernodal, lower triangle read) and sparse LU with partial
//! pivoting (COLAMD column ordering), with the scratch space they share;
//! the symmetric part `(A + A^T) / 2` that Cholesky factorises to
//! precondition a non-symmetric matrix; and the solve by the node-block
//! LU ([`super::block_lu`]) with one step of iterative refinement.
//!
//! Two levels, as faer has them: the symbolic analysis (`analyse`) is
//! made once, on first use, and kept for as long as the pattern holds;
//! each numeric factorisation is written into the storage of the last.

use super::block_lu::BlockLu;
use super::linear_error::{FactorStage, SolveFailure};
use crate::vecn::{distance, norm};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::LuError;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::linalg::lu::{NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, Par, Side};

/// Scratch space of faer's numeric factorisations and solves, grown to
/// the largest request seen and reused.
pub(super) struct Scratch {
    memory: MemBuffer,
    req: StackReq,
}

impl Default for Scratch {
    fn default() -> Self {
        Self {
            memory: MemBuffer::new(StackReq::EMPTY),
            req: StackReq::EMPTY,
        }
    }
}

impl Scratch {
    /// Grows the space to hold `req` as well as what it holds already.
    fn reserve(&mut self, req: StackReq) {
        let combined = self.req.or(req);
        if combined != self.req {
            self.req = combined;
            self.memory = MemBuffer::new(combined);
        }
    }

    fn stack(&mut self) -> &mut MemStack {
        MemStack::new(&mut self.memory)
    }
}

/// Sparse Cholesky factorisation: the symbolic analysis and the values of
/// `L`, once analysed.
#[derive(Default)]
pub(super) struct Cholesky {
    factor: Option<(SymbolicCholesky<usize>, Vec<f64>)>,
}

impl Cholesky {
    /// Entries of `L`, once analysed.
    pub(super) fn nnz(&self) -> Option<usize> {
        self.factor.as_ref().map(|(s, _)| s.len_val())
    }

    /// Analyses `pattern` (AMD ordering) unless done already.
    pub(super) fn analyse(
        &mut self,
        pattern: SymbolicSparseColMatRef<'_, usize>,
    ) -> Result<(), SolveFailure> {
        if self.factor.is_none() {
            let params = CholeskySymbolicParams {
                // faer picks its simplicial kernel below a flop threshold;
                // with 3x3 node blocks the supernodal one is faster at every
                // size measured (docs/performance.md, "The pedestal after
                // the first optimisations").
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            };
            let symb =
                factorize_symbolic_cholesky(pattern, Side::Lower, SymmetricOrdering::Amd, params)
                    .map_err(|e| SolveFailure::faer(FactorStage::CholeskyAnalysis, e))?;
            let l = vec![0.0; symb.len_val()];
            self.factor = Some((symb, l));
        }
        Ok(())
    }

    /// Factorises `values` on the analysed `pattern` (lower triangle
    /// read) into the kept storage; `false` when the matrix is not
    /// positive definite (the storage then holds no usable factor).
    pub(super) fn factorize(
        &mut self,
        pattern: SymbolicSparseColMatRef<'_, usize>,
        values: &[f64],
        par: Par,
        scratch: &mut Scratch,
    ) -> bool {
        let (symb, l) = self.factor.as_mut().expect("analysed before");
        scratch.reserve(
            symb.factorize_numeric_llt_scratch::<f64>(par, Default::default())
                .or(symb.solve_in_place_scratch::<f64>(1, par)),
        );
        let a = SparseColMatRef::new(pattern, values);
        symb.factorize_numeric_llt::<f64>(
            l,
            a,
            Side::Lower,
            LltRegularization::default(),
            par,
            scratch.stack(),
            Default::default(),
        )
        .is_ok()
    }

    /// `x <- L^-T L^-1 x` with the current factor.
    pub(super) fn solve_in_place(&self, x: &mut Mat<f64>, par: Par, scratch: &mut Scratch) {
        let (symb, l) = self.factor.as_ref().expect("factorised before");
        LltRef::<usize, f64>::new(symb, l).solve_in_place_with_conj(
            Conj::No,
            x.as_mut(),
            par,
            scratch.stack(),
        );
    }
}

/// Sparse LU with partial pivoting: the symbolic analysis and the
/// numeric factors, once analysed.
#[derive(Default)]
pub(super) struct Lu {
    factor: Option<(SymbolicLu<usize>, NumericLu<usize, f64>)>,
}

impl Lu {
    /// Whether the pattern has been analysed.
    pub(super) fn is_analysed(&self) -> bool {
        self.factor.is_some()
    }

    /// Analyses `pattern` (COLAMD ordering) unless done already.
    pub(super) fn analyse(
        &mut self,
        pattern: SymbolicSparseColMatRef<'_, usize>,
    ) -> Result<(), SolveFailure> {
        if self.factor.is_none() {
            let symb = factorize_symbolic_lu(pattern, Default::default())
                .map_err(|e| SolveFailure::faer(FactorStage::LuAnalysis, e))?;
            self.factor = Some((symb, NumericLu::new()));
        }
        Ok(())
    }

    /// Factorises `values` on the analysed `pattern` and solves for `rhs`
    /// in place (`b` in, `x` out).
    pub(super) fn factorize_and_solve(
        &mut self,
        pattern: SymbolicSparseColMatRef<'_, usize>,
        values: &[f64],
        rhs: &mut Mat<f64>,
        par: Par,
        scratch: &mut Scratch,
    ) -> Result<(), SolveFailure> {
        let (symb, numeric) = self.factor.as_mut().expect("analysed before");
        scratch.reserve(
            symb.factorize_numeric_lu_scratch::<f64>(par, Default::default())
                .or(symb.solve_in_place_scratch::<f64>(1, par)),
        );
        let a = SparseColMatRef::new(pattern, values);
        let stack = scratch.stack();
        let lu = symb
            .factorize_numeric_lu::<f64>(numeric, a, par, stack, Default::default())
            .map_err(|e| match e {
                LuError::SymbolicSingular { index } => SolveFailure::NoPivot {
                    step: index,
                    dimension: pattern.ncols(),
                },
                LuError::Generic(e) => SolveFailure::faer(FactorStage::LuFactorization, e),
            })?;
        lu.solve_in_place_with_conj(Conj::No, rhs.as_mut(), par, stack);
        Ok(())
    }
}

/// The values of the symmetric part `(A + A^T) / 2` of `values` into
/// `out`, `transpose[k]` being the mirror of entry `k`.
pub(super) fn symmetric_part(values: &[f64], transpose: &[usize], out: &mut Vec<f64>) {
    out.resize(values.len(), 0.0);
    for (k, s) in out.iter_mut().enumerate() {
        *s = 0.5 * (values[k] + values[transpose[k]]);
    }
}

/// Solves `A x = b` with the node-block LU `lu` of `A` (already
/// factorised) and refines `x` once by the residual, `product` computing
/// `A x`. Leaves `x` in `x`; `ax` and `d` are work space. `false` when the
/// residual is not finite, or above `1e-10 |b|` after the refinement (the
/// caller then pivots).
pub(super) fn solve_refined(
    lu: &mut BlockLu,
    b: &[f64],
    mut product: impl FnMut(&[f64], &mut [f64]),
    x: &mut Vec<f64>,
    ax: &mut Vec<f64>,
    d: &mut Vec<f64>,
) -> bool {
    x.clear();
    x.extend_from_slice(b);
    lu.solve_in_place(x);
    ax.resize(b.len(), 0.0);
    product(x, ax);
    let b_norm = norm(b);
    d.clear();
    d.extend(b.iter().zip(ax.iter()).map(|(p, q)| p - q));
    let r_norm = norm(d);
    let mut ok = r_norm.is_finite();
    if ok && r_norm > 1e-12 * b_norm {
        // One step of iterative refinement: cheap (a solve with the
        // factor) and it removes what the unpivoted elimination lost.
        lu.solve_in_place(d);
        for (xi, di) in x.iter_mut().zip(d.iter()) {
            *xi += di;
        }
        product(x, ax);
        ok = distance(b, ax) <= 1e-10 * b_norm;
    }
    ok
}
