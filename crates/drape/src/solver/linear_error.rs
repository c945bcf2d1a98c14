//! Why a linear solve could not be done ([`LinearSolveError`]): of which
//! matrix, and what failed — the pivot LU did not find, the path whose
//! solution was not finite or left too large a residual, or the analysis
//! or factorisation that ran out of memory or indices.

use super::Factorization;
use super::block_lu::BlockLuError;
use super::faer_failure::FaerFailure;
use faer::sparse::FaerError;

/// A linear solve that could not be done: of which matrix, and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{matrix} {failure}")]
pub struct LinearSolveError {
    /// The matrix solved for.
    pub matrix: Matrix,
    /// What failed.
    pub failure: SolveFailure,
}

/// The matrix of a linear solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Matrix {
    /// Newton's Hessian `H` of `H dY = -G`
    /// ([`LinearSolver::solve`](super::LinearSolver::solve)).
    Hessian,
    /// The mass matrix of the initial acceleration `M A_0 = F`
    /// ([`LinearSolver::solve_mass`](super::LinearSolver::solve_mass)).
    Mass,
}

impl std::fmt::Display for Matrix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Matrix::Hessian => "the Hessian",
            Matrix::Mass => "the mass matrix",
        })
    }
}

/// What failed in a linear solve.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SolveFailure {
    /// Sparse LU found no pivot: the matrix is singular.
    #[error("is singular (sparse LU found no pivot at elimination step {step} of {dimension})")]
    NoPivot {
        /// The (0-based) elimination step without a pivot.
        step: usize,
        /// Unknowns of the system.
        dimension: usize,
    },
    /// Nothing before LU solved the system, and it is too large for LU.
    #[error(
        "is singular (no iterative or Cholesky solve converged, and sparse LU is not tried above {limit} unknowns; this system has {dimension})"
    )]
    BeyondLu {
        /// Unknowns of the system.
        dimension: usize,
        /// The most unknowns LU is tried on.
        limit: usize,
    },
    /// The solution has a NaN or an infinity.
    #[error("is singular (the {method} solution is not finite)")]
    NotFinite {
        /// The path that produced it.
        method: Factorization,
    },
    /// A factorisation's solution leaves too large a residual: the
    /// matrix is singular to round-off.
    #[error("is singular (the {method} solve leaves a relative residual of {relative:.1e})")]
    Residual {
        /// The factorisation.
        method: Factorization,
        /// `|b - A x| / |b|`.
        relative: f64,
    },
    /// faer could not analyse or factorise the pattern, whatever its values.
    #[error("could not be solved: the {stage} failed ({cause})")]
    Faer {
        /// Which analysis or factorisation.
        stage: FactorStage,
        /// Why.
        cause: FaerFailure,
    },
    /// The node-block LU could not analyse the pattern.
    #[error("could not be solved: the block LU's analysis failed ({0})")]
    BlockLu(BlockLuError),
}

/// An analysis or factorisation of faer's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FactorStage {
    /// The symbolic Cholesky analysis (AMD ordering).
    CholeskyAnalysis,
    /// The symbolic LU analysis (COLAMD ordering).
    LuAnalysis,
    /// The numeric LU factorisation.
    LuFactorization,
}

impl std::fmt::Display for FactorStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FactorStage::CholeskyAnalysis => "sparse Cholesky analysis",
            FactorStage::LuAnalysis => "sparse LU analysis",
            FactorStage::LuFactorization => "sparse LU factorisation",
        })
    }
}

impl SolveFailure {
    /// faer's `cause` in `stage`.
    pub(super) fn faer(stage: FactorStage, cause: FaerError) -> Self {
        SolveFailure::Faer {
            stage,
            cause: cause.into(),
        }
    }

    /// The failure, of `matrix`.
    pub(super) fn of(self, matrix: Matrix) -> LinearSolveError {
        LinearSolveError {
            matrix,
            failure: self,
        }
    }
}
