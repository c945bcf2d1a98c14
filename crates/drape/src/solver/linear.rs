//! The choice of how to solve `H dY = -G`: [`LinearSolver`] is bound to
//! one sparsity pattern and solves each system on it by the cheapest path
//! that works, then checks the solution.
//!
//! The cascade, in the order [`LinearSolver::solve`] tries it (the first
//! path that succeeds ends it; [`LinearMode`] says which are open):
//!
//! 0. **CG with the compact factor** (`compact`; `auto` up to 300,000
//!    unknowns, with bending): a symmetric system with couplings beyond
//!    the triangles' (bending's stencils) by conjugate gradients
//!    preconditioned with the factor of its compact part
//!    (`super::compact`), while that converges in 20 iterations; a
//!    weak or indefinite try leaves the next systems to the paths below,
//!    8 of them, then twice as many each time in a row, up to 512.
//! 1. **Block LU** (`direct`; `auto` up to 300,000 unknowns). Small
//!    systems — up to 5,000 unknowns when symmetric, 15,000 when not — are
//!    factorised by the node-block LU of [`super::block_lu`], symmetric
//!    (`L D L^T`) or not: one factorisation and one solve for the
//!    non-symmetric wrinkling tangent, no Krylov iterations. A bad pivot
//!    block, or a residual one step of refinement cannot bring below
//!    `1e-10 |b|`, hands the system on.
//! 2. **A reused factor** (`reuse`; `auto` above 300,000 unknowns): GMRES
//!    preconditioned by the Cholesky factor of an earlier Hessian, while
//!    it converges in 8 iterations.
//! 3. **Multigrid** (`iterative`; `auto` above 300,000 unknowns): CG, or
//!    GMRES when not symmetric, preconditioned by a V-cycle of
//!    [`super::amg`]; the hierarchy is kept across solves.
//! 4. In `iterative`, **block Jacobi**: CG (GMRES when not symmetric or
//!    when CG fails) preconditioned by the inverted 3x3 diagonal blocks.
//!    Otherwise **Cholesky**: a symmetric Hessian (Saint-Venant–Kirchhoff
//!    with dead loads, mass and supports; a follower pressure on a
//!    membrane whose edge is fixed, once the element contributions have
//!    cancelled) is factorised by sparse Cholesky `H = L L^T` with an AMD
//!    ordering, a non-symmetric one (a follower pressure on a free edge,
//!    the wrinkling tangent) solved by GMRES preconditioned by the
//!    Cholesky factor of its symmetric part. The factor is kept for the
//!    reuse path and for Newton's chord steps.
//! 5. **Block LU**, unless it was tried first, for what Cholesky refused
//!    (a Hessian that is not positive definite: a fabric folding, a
//!    membrane in compression in statics) or did not bring GMRES through;
//!    then **LU** with partial
//!    pivoting and a COLAMD ordering, for what nothing above solved — both
//!    up to 300,000 unknowns, above which their fill would take tens of
//!    gigabytes and the solve fails instead.
//!
//! A direct solution whose residual exceeds `1e-6 |b|`, and any solution
//! that is not finite, is an error; the Krylov methods check their own
//! residual, to their tolerance.
//!
//! The work is done by the module's other files, one verb each:
//! `direct` (Cholesky, LU, the block LU's refined solve), `krylov` (GMRES,
//! CG), `precondition` (block Jacobi, the multigrid glue) and `product`
//! (`A x`, residuals). Each symbolic analysis is made once, on first use,
//! and kept; numeric factors are written into storage reused from call to
//! call.

use super::block_lu::BlockLu;
use super::compact::Compact;
use super::direct::{self, Cholesky, Lu, Scratch};
use super::krylov;
pub use super::linear_error::{LinearSolveError, Matrix, SolveFailure};
use super::pattern::SparsePattern;
pub use super::precondition::KeptMultigrid;
use super::precondition::{Preconditioned, Preconditioner, Preconditioners};
use super::product::{self, Product};
use crate::vecn::norm;
use faer::sparse::SymbolicSparseColMat;
use faer::{Mat, Par};

/// Steps of iterative refinement after a Cholesky solve whose residual
/// is above `1e-6 |b|`, before the solve counts as failed.
const REFINEMENTS: usize = 3;

/// Which factorisation solved a system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Factorization {
    /// Sparse LU in 3x3 node blocks without pivoting between nodes
    /// ([`super::block_lu`]), symmetric (`L D L^T`) or not.
    BlockLu,
    /// Sparse Cholesky `L L^T`.
    Cholesky,
    /// Sparse LU with partial pivoting.
    Lu,
    /// GMRES preconditioned by the Cholesky factor of the symmetric part
    /// `(A + A^T) / 2`.
    PreconditionedGmres,
    /// GMRES preconditioned by the Cholesky factor of an earlier matrix.
    ReusedFactorGmres,
    /// GMRES preconditioned by the inverted 3x3 diagonal blocks.
    BlockJacobiGmres,
    /// Conjugate gradients preconditioned by the inverted 3x3 diagonal
    /// blocks (symmetric matrices).
    BlockJacobiCg,
    /// Conjugate gradients preconditioned by a multigrid V-cycle.
    MultigridCg,
    /// GMRES preconditioned by a multigrid V-cycle (non-symmetric).
    MultigridGmres,
    /// Conjugate gradients preconditioned by the factor of the Hessian's
    /// compact part (`super::compact`).
    CompactCg,
}

impl std::fmt::Display for Factorization {
    /// What solved the system, in words (error messages).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Factorization::BlockLu => "block LU",
            Factorization::Cholesky => "Cholesky",
            Factorization::Lu => "LU",
            Factorization::PreconditionedGmres => "preconditioned GMRES",
            Factorization::ReusedFactorGmres => "GMRES with a reused factor",
            Factorization::BlockJacobiGmres => "block-Jacobi GMRES",
            Factorization::BlockJacobiCg => "block-Jacobi CG",
            Factorization::MultigridCg => "multigrid CG",
            Factorization::MultigridGmres => "multigrid GMRES",
            Factorization::CompactCg => "CG with the compact part's factor",
        })
    }
}

impl Factorization {
    /// Whether the solution comes from a factorisation, whose residual
    /// the solve checks (Krylov methods check their own).
    fn is_direct(self) -> bool {
        matches!(
            self,
            Factorization::Cholesky | Factorization::Lu | Factorization::BlockLu
        )
    }
}

/// What the linear solver has done (for reports and benchmarks).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct LinearStats {
    /// Systems solved.
    pub solves: usize,
    /// Numeric Cholesky factorisations.
    pub cholesky_factorizations: usize,
    /// Numeric LU factorisations.
    pub lu_factorizations: usize,
    /// Krylov (GMRES) iterations.
    pub krylov_iterations: usize,
    /// Numeric block LU factorisations (3x3 node blocks).
    pub block_lu_factorizations: usize,
    /// Solves with the factor of an earlier matrix (Newton's chord steps).
    pub chord_solves: usize,
    /// Multigrid hierarchies built (the `iterative` path).
    pub multigrid_builds: usize,
}

/// Above this many unknowns `auto` solves by multigrid-preconditioned
/// Krylov iterations (a reused factorisation as the fallback), and no solve
/// falls back to the node-block LU or sparse LU (whose fill would take
/// tens of gigabytes).
const AUTO_ITERATIVE_ABOVE: usize = 300_000;
/// Largest symmetric system (unknowns) that `direct` and `auto` factorise
/// by the node-block LU: above it faer's supernodal Cholesky, whose dense
/// kernels pay off on large fronts, is faster (docs/performance.md, "The
/// node-block LU against faer").
const BLOCK_LU_MAX_SYMMETRIC: usize = 5_000;
/// Largest non-symmetric system for the node-block LU: above it a
/// Cholesky factorisation of the symmetric part and a few preconditioned
/// GMRES iterations cost less than the general block LU (twice the
/// symmetric one's work; docs/performance.md, "The node-block LU against
/// faer").
const BLOCK_LU_MAX_GENERAL: usize = 15_000;
/// Krylov iterations a reused factor gets before the matrix is refactorised.
const REUSE_ITERATIONS: usize = 8;
/// Most GMRES iterations preconditioned by the factor of the symmetric
/// part before the node-block LU, then LU, take over.
const SYMMETRIC_PART_ITERATIONS: usize = 100;
/// Most multigrid-preconditioned Krylov iterations before the one-level
/// preconditioner is tried.
const MULTIGRID_ITERATIONS: usize = 100;
/// Solves that skip multigrid after a freshly built hierarchy failed.
const MULTIGRID_BACKOFF: usize = 8;
/// Most block-Jacobi GMRES iterations before LU takes over.
const ITERATIVE_ITERATIONS: usize = 400;
/// Most CG iterations preconditioned by the compact part's factor
/// before the whole Hessian is factorised.
const COMPACT_ITERATIONS: usize = 30;
/// CG iterations above which the compact part's factor counts as weak:
/// the next [`COMPACT_BACKOFF`] systems factorise the whole Hessian. The
/// compact part of a fourth-order operator is a second-order one, a good
/// preconditioner where the mass term dominates (dynamic steps) and a poor
/// one in statics on fine meshes (docs/performance.md, "The compact
/// preconditioner").
const COMPACT_WEAK: usize = 20;
/// Systems that factorise the whole Hessian after the compact factor was
/// weak once; each weak try in a row doubles them, up to
/// [`COMPACT_BACKOFF_MAX`].
const COMPACT_BACKOFF: usize = 8;
/// The most systems the compact path is skipped for in a row.
const COMPACT_BACKOFF_MAX: usize = 512;

/// How linear systems are solved (`[solver] linear`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LinearMode {
    /// A fresh factorisation for every solve: the node-block LU for small
    /// systems; else Cholesky when symmetric positive definite, GMRES
    /// preconditioned by the Cholesky factor of the symmetric part when not
    /// symmetric; the node-block LU, then LU, otherwise.
    Direct,
    /// `direct` up to 300,000 unknowns — with the compact path of
    /// [`LinearMode::Compact`] first where the solver has a compact part
    /// (bending) —; above (where a sparse factorisation costs tens of
    /// seconds and gigabytes) `iterative`, with `reuse` as the fallback
    /// when multigrid does not converge.
    #[default]
    Auto,
    /// GMRES preconditioned by the Cholesky factor of an earlier Hessian,
    /// refactorised only when it stops converging in 8 iterations (the
    /// Hessian changes little from one Newton iteration and step to the
    /// next). On small meshes it saves factorisations but not time
    /// (docs/performance.md, "Linear-solver modes on the pedestal"); meant
    /// for larger meshes.
    Reuse,
    /// Conjugate gradients (GMRES when not symmetric) preconditioned by a
    /// smoothed-aggregation multigrid V-cycle ([`super::amg`]): no
    /// factorisation but the coarsest level's; cost per solve about linear
    /// in the mesh size. Block-Jacobi CG/GMRES is the fallback.
    Iterative,
    /// The projected Newton's systems (symmetric positive definite) by
    /// conjugate gradients preconditioned with the factor of the
    /// Hessian's compact part: the couplings of nodes that share a
    /// triangle, bending's farther couplings moved onto the diagonal
    /// (`super::compact`). Its factor has the membrane's fill, not the
    /// bending stencils'. Other systems as `direct`; without bending,
    /// `direct`.
    Compact,
}

/// What a [`LinearSolver`] carries from one time step to the next that
/// later solutions depend on: in `iterative` (and `auto` above 300,000
/// unknowns) the multigrid hierarchy, in `reuse` the kept Cholesky factor;
/// nothing in `direct`, whose every factorisation is fresh. Each is kept as
/// the matrix it was made from, so that a checkpoint holds it and a
/// resumed run makes the same preconditioner again
/// ([`LinearSolver::kept`], [`LinearSolver::restore`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct KeptLinear {
    /// The multigrid path's state, once it has been used.
    pub multigrid: Option<KeptMultigrid>,
    /// `reuse`: the matrix (scalar CSC values) whose Cholesky factor — of
    /// its symmetric part when `symmetric` is false — preconditions GMRES.
    pub factor: Option<KeptFactor>,
}

/// The matrix of the factor `reuse` keeps ([`KeptLinear::factor`]).
#[derive(Debug, Clone, PartialEq)]
pub struct KeptFactor {
    /// Scalar CSC values, the pattern's length.
    pub values: Vec<f64>,
    /// Whether the matrix was symmetric (factorised itself) or not (its
    /// symmetric part factorised).
    pub symmetric: bool,
}

/// Linear solver bound to one sparsity pattern: the policy of the module
/// documentation, and the state of every path kept between solves.
pub struct LinearSolver {
    /// The CSC pattern of the matrices solved.
    pattern: SymbolicSparseColMat<usize>,
    /// Products by the matrix (and the transpose map).
    product: Product,
    cholesky: Cholesky,
    lu: Lu,
    /// faer's scratch space, shared by Cholesky and LU.
    scratch: Scratch,
    par: Par,
    /// The node graph, when the pattern is made of 3x3 node blocks, and
    /// its block LU (analysed on first use).
    node_graph: Option<(Vec<usize>, Vec<usize>)>,
    block_lu: Option<BlockLu>,
    /// The values of the symmetric part `(A + A^T) / 2`.
    symmetric_part: Vec<f64>,
    /// Block Jacobi and the multigrid path.
    preconditioners: Preconditioners,
    /// Work space of the Krylov methods (and of the block LU's refinement).
    krylov: krylov::Work,
    /// `b` in and `x` out of the factorisations' solves; every path
    /// leaves its solution here.
    rhs: Mat<f64>,
    /// Krylov iterations of the last solve (0 for direct solves).
    pub last_krylov_iterations: usize,
    /// Counts since the solver was made.
    pub stats: LinearStats,
    /// Relative residual the Krylov solves stop at (default 1e-12); Newton
    /// loosens it while far from the solution (inexact Newton). A direct
    /// solution is accepted up to the larger of this and 1e-6.
    pub krylov_tolerance: f64,
    /// How systems are solved.
    mode: LinearMode,
    /// Whether the Cholesky storage holds a usable factor (reusable).
    factor_kept: bool,
    /// Whether the multigrid's finest matrix holds the values being solved
    /// for (products then use its 3x3 blocks).
    blocks_current: bool,
    /// How the last system was solved, if it succeeded.
    last_used: Option<Factorization>,
    /// `reuse`: the matrix of the kept factor ([`KeptLinear::factor`]).
    factor_from: Option<KeptFactor>,
    /// `compact`: the compact part's preconditioner, when the Hessian
    /// has couplings beyond it.
    compact: Option<Box<Compact>>,
    /// Systems left that skip the compact path after it was weak, and how
    /// many the next weak try skips.
    compact_skips: usize,
    compact_backoff: usize,
}

impl std::fmt::Debug for LinearSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LinearSolver")
            .field("dimension", &self.pattern.nrows())
            .field("nnz", &self.pattern.compute_nnz())
            .field("cholesky", &self.cholesky.nnz().is_some())
            .field("lu", &self.lu.is_analysed())
            .finish()
    }
}

impl LinearSolver {
    /// The value index of each diagonal entry (`None` where the pattern
    /// has none).
    pub fn diagonal_positions(&self) -> Vec<Option<usize>> {
        let col_ptr = self.pattern.col_ptr();
        let rows = self.pattern.row_idx();
        (0..self.pattern.ncols())
            .map(|c| {
                let range = col_ptr[c]..col_ptr[c + 1];
                rows[range.clone()]
                    .binary_search(&c)
                    .ok()
                    .map(|k| range.start + k)
            })
            .collect()
    }

    /// A solver for square matrices with CSC pattern `(col_ptr, row_idx)`
    /// (rows sorted in each column).
    pub fn new(col_ptr: &[usize], row_idx: &[usize]) -> Result<Self, LinearSolveError> {
        let n = col_ptr.len() - 1;
        let pattern =
            SymbolicSparseColMat::new_checked(n, n, col_ptr.to_vec(), None, row_idx.to_vec());
        Ok(Self {
            pattern,
            product: Product::new(None),
            cholesky: Cholesky::default(),
            lu: Lu::default(),
            scratch: Scratch::default(),
            // A second thread did not speed up faer's sparse factorisation
            // at these sizes when measured; the threads serve assembly.
            par: Par::Seq,
            node_graph: None,
            block_lu: None,
            symmetric_part: Vec::new(),
            preconditioners: Preconditioners::default(),
            krylov: krylov::Work::default(),
            rhs: Mat::zeros(n, 1),
            last_krylov_iterations: 0,
            stats: LinearStats::default(),
            krylov_tolerance: 1e-12,
            mode: LinearMode::Direct,
            factor_kept: false,
            blocks_current: false,
            last_used: None,
            factor_from: None,
            compact: None,
            compact_skips: 0,
            compact_backoff: COMPACT_BACKOFF,
        })
    }

    /// How systems are solved.
    pub fn mode(&self) -> LinearMode {
        self.mode
    }

    /// Chooses how systems are solved (default [`LinearMode::Direct`]).
    pub fn with_mode(mut self, mode: LinearMode) -> Self {
        self.mode = mode;
        self
    }

    /// Enables the preconditioned Krylov path for non-symmetric matrices
    /// on a structurally symmetric pattern: `transpose[k]` is the value
    /// index of the entry mirrored about the diagonal of entry `k`.
    pub fn with_transpose(mut self, transpose: Vec<usize>) -> Self {
        self.product = Product::new(Some(transpose));
        self
    }

    /// Enables the node-block LU ([`super::block_lu`]) for a pattern of 3x3
    /// node blocks in [`super::SparsePattern`]'s layout with node graph
    /// `(node_ptr, node_rows)`.
    pub fn with_node_blocks(mut self, node_ptr: &[usize], node_rows: &[usize]) -> Self {
        self.node_graph = Some((node_ptr.to_vec(), node_rows.to_vec()));
        self
    }

    /// Preconditions the projected Newton's systems by the factor of the
    /// compact part `compact` (a node-block pattern within this one's,
    /// [`LinearMode::Compact`]); after [`LinearSolver::with_node_blocks`].
    /// Nothing when `compact` holds every coupling.
    pub fn with_compact(mut self, compact: SparsePattern) -> Self {
        if let Some((ptr, rows)) = &self.node_graph {
            let c = Compact::new(compact, ptr, rows);
            self.compact = (c.far_blocks() > 0).then(|| Box::new(c));
        }
        self
    }

    /// The compact part's pattern, when its preconditioner is in use.
    pub fn compact_pattern(&self) -> Option<&SparsePattern> {
        self.compact.as_ref().map(|c| c.pattern())
    }

    /// Entries of the Cholesky factor `L`, once it has been analysed.
    pub fn cholesky_nnz(&self) -> Option<usize> {
        self.cholesky.nnz()
    }

    /// Dimension of the system.
    pub fn dimension(&self) -> usize {
        self.pattern.nrows()
    }

    /// Solves `A x = b` in place (`rhs`: `b` in, `x` out) for the values
    /// `values` on the pattern, by the cascade of the module's
    /// documentation. `symmetric` says that `A` is: Cholesky and CG are
    /// then open, and the node-block LU, then LU, are the fallback when
    /// `A` is not positive definite.
    pub fn solve(
        &mut self,
        values: &[f64],
        symmetric: bool,
        rhs: &mut [f64],
    ) -> Result<Factorization, LinearSolveError> {
        self.solve_matrix(values, symmetric, rhs)
            .map_err(|failure| failure.of(Matrix::Hessian))
    }

    /// Solves `A x = b` in place for a symmetric `A` that should be
    /// positive definite (the projected Newton's Hessian), by the first
    /// path that applies: multigrid-preconditioned CG where
    /// [`LinearSolver::solve`] would take it, else the node-block
    /// `L D L^T` for small systems (up to 5,000 unknowns), else sparse
    /// Cholesky. `Ok(None)` — `rhs` then unchanged — when `A` is not
    /// positive definite: a pivot block or pivot that is not (Sylvester's
    /// law of inertia), or CG meeting a direction of non-positive
    /// curvature (or not converging); no other path is tried, so that
    /// the caller can project the Hessian and try again.
    pub fn solve_spd(
        &mut self,
        values: &[f64],
        rhs: &mut [f64],
    ) -> Result<Option<Factorization>, LinearSolveError> {
        self.last_krylov_iterations = 0;
        self.last_used = None;
        let n = self.dimension();
        let compact = match self.solve_compact(values, rhs) {
            Ok(c) => c,
            Err(f) => return Err(f.of(Matrix::Hessian)),
        };
        let used = if let Some(c) = compact {
            c
        } else if self.uses_multigrid() {
            self.solve_multigrid(values, true, rhs)
        } else if self.mode != LinearMode::Reuse
            && n <= BLOCK_LU_MAX_SYMMETRIC
            && self.node_graph.is_some()
        {
            let solved = self
                .solve_block_lu_checked(values, true, rhs, true)
                .map_err(|f| f.of(Matrix::Hessian))?;
            solved.then_some(Factorization::BlockLu)
        } else {
            self.factor_kept = self
                .factor_cholesky(values)
                .map_err(|f| f.of(Matrix::Hessian))?;
            if self.factor_kept {
                self.record_factor(values, true);
                self.load_rhs(rhs);
                self.cholesky
                    .solve_in_place(&mut self.rhs, self.par, &mut self.scratch);
                Some(Factorization::Cholesky)
            } else {
                None
            }
        };
        let Some(used) = used else {
            return Ok(None);
        };
        self.stats.solves += 1;
        self.deliver(values, rhs, used)
            .map_err(|f| f.of(Matrix::Hessian))?;
        self.last_used = Some(used);
        Ok(Some(used))
    }

    /// [`LinearSolver::solve`], for any matrix: why it failed.
    fn solve_matrix(
        &mut self,
        values: &[f64],
        symmetric: bool,
        rhs: &mut [f64],
    ) -> Result<Factorization, SolveFailure> {
        self.last_krylov_iterations = 0;
        self.last_used = None;
        self.stats.solves += 1;
        self.load_rhs(rhs);
        let used = match self.solve_before_lu(values, symmetric, rhs)? {
            Some(used) => used,
            None => self.solve_lu(values, rhs)?,
        };
        self.deliver(values, rhs, used)?;
        self.last_used = Some(used);
        Ok(used)
    }

    /// The mode solves take: `auto` made definite by the system's size.
    pub fn effective_mode(&self) -> LinearMode {
        match self.mode {
            LinearMode::Auto if self.dimension() > AUTO_ITERATIVE_ABOVE => LinearMode::Reuse,
            LinearMode::Auto | LinearMode::Compact => LinearMode::Direct,
            m => m,
        }
    }

    /// The cascade up to LU, cheapest path first: the path that solved
    /// the system, its solution in `self.rhs`, or `None`.
    fn solve_before_lu(
        &mut self,
        values: &[f64],
        symmetric: bool,
        rhs: &[f64],
    ) -> Result<Option<Factorization>, SolveFailure> {
        // `compact` tries a symmetric system as positive definite first;
        // one that is not goes down the cascade.
        // (An indefinite one — the exact Hessian of a fabric in
        // compression — backs the path off as a weak preconditioner does.)
        if symmetric {
            match self.solve_compact(values, rhs)? {
                Some(Some(used)) => return Ok(Some(used)),
                Some(None) => self.back_off_compact(),
                None => {}
            }
        }
        let n = self.dimension();
        let mode = self.effective_mode();
        // (A block LU of an earlier Hessian as GMRES preconditioner does
        // not pay on the pedestal: the wrinkling tangent changes too much
        // from one iteration to the next; docs/performance.md.)
        let block_lu_max = if symmetric {
            BLOCK_LU_MAX_SYMMETRIC
        } else {
            BLOCK_LU_MAX_GENERAL
        };
        let block_lu_first = mode == LinearMode::Direct && n <= block_lu_max;
        if block_lu_first && self.solve_block_lu(values, symmetric, rhs)? {
            return Ok(Some(Factorization::BlockLu));
        }
        // Reuse the kept factor (of an earlier Hessian) as a preconditioner
        // while it pays: a few Krylov iterations instead of a factorisation.
        if mode == LinearMode::Reuse
            && self.factor_kept
            && self.gmres(values, rhs, Preconditioner::Cholesky, REUSE_ITERATIONS)
        {
            return Ok(Some(Factorization::ReusedFactorGmres));
        }
        // Large systems in `auto` try multigrid first, and keep a reused
        // factorisation as the fallback.
        if self.uses_multigrid()
            && let Some(used) = self.solve_multigrid(values, symmetric, rhs)
        {
            return Ok(Some(used));
        }
        let used = if mode == LinearMode::Iterative {
            self.solve_block_jacobi(values, symmetric, rhs)
        } else {
            self.solve_cholesky(values, symmetric, rhs)?
        };
        if used.is_some() {
            return Ok(used);
        }
        // The Cholesky storage may hold an unfinished attempt: do not
        // reuse it.
        self.factor_kept = false;
        // An indefinite Hessian (a fabric folding, or compressed beyond
        // buckling) that Cholesky refused, or a non-symmetric one its
        // symmetric part's factor did not bring GMRES through: the
        // node-block LU, whose 3x3 pivots need no definiteness, unless it
        // was tried first, before the pivoting LU, which costs several
        // times more (docs/performance.md, "Indefinite Hessians of a
        // mid-size settle"). A block LU it cannot analyse leaves the
        // system to LU, as before it existed.
        if !block_lu_first
            && mode != LinearMode::Iterative
            && n <= AUTO_ITERATIVE_ABOVE
            && self.solve_block_lu(values, symmetric, rhs).unwrap_or(false)
        {
            return Ok(Some(Factorization::BlockLu));
        }
        Ok(None)
    }

    /// Factorises by the node-block LU and solves for `b`, leaving the
    /// solution in `self.rhs`, refined once by the residual. `Ok(false)`
    /// when the block LU does not apply, meets a bad pivot, or leaves a
    /// residual above `1e-10 |b|` (the caller then pivots).
    fn solve_block_lu(
        &mut self,
        values: &[f64],
        symmetric: bool,
        b: &[f64],
    ) -> Result<bool, SolveFailure> {
        self.solve_block_lu_checked(values, symmetric, b, false)
    }

    /// [`LinearSolver::solve_block_lu`]; with `positive` (a matrix that
    /// should be positive definite), also `Ok(false)` when a pivot block
    /// is not positive definite.
    fn solve_block_lu_checked(
        &mut self,
        values: &[f64],
        symmetric: bool,
        b: &[f64],
        positive: bool,
    ) -> Result<bool, SolveFailure> {
        if self.block_lu.is_none() {
            let Some((ptr, rows)) = &self.node_graph else {
                return Ok(false);
            };
            self.block_lu = Some(BlockLu::new(ptr, rows).map_err(SolveFailure::BlockLu)?);
        }
        let lu = self.block_lu.as_mut().expect("set above");
        self.stats.block_lu_factorizations += 1;
        if lu.factorize(values, symmetric).is_err() || (positive && !lu.pivots_positive()) {
            return Ok(false);
        }
        let (pattern, product, work) = (self.pattern.as_ref(), &self.product, &mut self.krylov);
        let ok = direct::solve_refined(
            lu,
            b,
            |x, out| product.apply(pattern, values, x, out),
            &mut work.x,
            &mut work.ax,
            &mut work.r,
        );
        for (i, v) in work.x.iter().enumerate() {
            self.rhs[(i, 0)] = *v;
        }
        Ok(ok)
    }

    /// The compact path ([`LinearMode::Compact`]) for a matrix that
    /// should be positive definite: `None` where it does not apply (no
    /// compact preconditioner, another mode) or CG did not converge in
    /// [`COMPACT_ITERATIONS`] (the caller then factorises the whole
    /// Hessian); `Some(None)` when the matrix is not positive definite
    /// (the compact factor failed, or CG met a non-positive curvature);
    /// else the solution in `self.rhs`.
    fn solve_compact(
        &mut self,
        values: &[f64],
        b: &[f64],
    ) -> Result<Option<Option<Factorization>>, SolveFailure> {
        let open = match self.mode {
            LinearMode::Compact => true,
            LinearMode::Auto => !self.uses_multigrid(),
            _ => false,
        };
        if !open {
            return Ok(None);
        }
        let Some(compact) = self.compact.as_deref_mut() else {
            return Ok(None);
        };
        if self.compact_skips > 0 {
            self.compact_skips -= 1;
            return Ok(None);
        }
        if compact.uses_block_lu() {
            self.stats.block_lu_factorizations += 1;
        } else {
            self.stats.cholesky_factorizations += 1;
        }
        if !compact.factorize(values)? {
            return Ok(Some(None));
        }
        let tolerance = self.krylov_tolerance;
        let mut op = CompactOperator {
            values,
            pattern: self.pattern.as_ref(),
            product: &self.product,
            compact,
        };
        let outcome = krylov::pcg(&mut op, b, tolerance, COMPACT_ITERATIONS, &mut self.krylov);
        let out_of_iterations = outcome.iterations >= COMPACT_ITERATIONS;
        if outcome.iterations > COMPACT_WEAK {
            self.back_off_compact();
        } else {
            self.compact_backoff = COMPACT_BACKOFF;
        }
        if self.finish_krylov(outcome) {
            return Ok(Some(Some(Factorization::CompactCg)));
        }
        Ok(if out_of_iterations { None } else { Some(None) })
    }

    /// Skips the compact path for the next systems after a weak try,
    /// twice as many as the last time in a row.
    fn back_off_compact(&mut self) {
        self.compact_skips = self.compact_backoff;
        self.compact_backoff = (2 * self.compact_backoff).min(COMPACT_BACKOFF_MAX);
    }

    /// Multigrid-preconditioned CG (GMRES when not symmetric). A kept
    /// hierarchy that fails is rebuilt once for this matrix; a fresh one
    /// that fails leaves the next [`MULTIGRID_BACKOFF`] solves to the
    /// fallback.
    fn solve_multigrid(
        &mut self,
        values: &[f64],
        symmetric: bool,
        rhs: &[f64],
    ) -> Option<Factorization> {
        let tolerance = self.krylov_tolerance;
        for _ in 0..2 {
            let mg = self.preconditioners.multigrid(self.node_graph.as_ref())?;
            if mg.skips_this_solve() {
                return None;
            }
            let builds = mg.builds();
            if !mg.setup(values, &mut self.stats.multigrid_builds) {
                return None;
            }
            let fresh = mg.builds() > builds;
            self.blocks_current = true;
            let ok = if symmetric {
                let kind = Preconditioner::Multigrid;
                self.pcg(values, rhs, kind, tolerance, MULTIGRID_ITERATIONS)
            } else {
                self.gmres(values, rhs, Preconditioner::Multigrid, MULTIGRID_ITERATIONS)
            };
            // Later products must read `values`, not the blocks.
            self.blocks_current = false;
            let iterations = self.last_krylov_iterations;
            let mg = self.preconditioners.multigrid.as_mut().expect("made above");
            mg.record(if ok { iterations } else { usize::MAX });
            if ok {
                return Some(if symmetric {
                    Factorization::MultigridCg
                } else {
                    Factorization::MultigridGmres
                });
            }
            if fresh {
                mg.back_off(MULTIGRID_BACKOFF);
                return None;
            }
        }
        None
    }

    /// Block-Jacobi CG, then (not symmetric, or CG failed) block-Jacobi
    /// GMRES; `None` when a diagonal block is singular or neither
    /// converges.
    fn solve_block_jacobi(
        &mut self,
        values: &[f64],
        symmetric: bool,
        rhs: &[f64],
    ) -> Option<Factorization> {
        let tolerance = self.krylov_tolerance;
        let kind = Preconditioner::BlockJacobi;
        if !self
            .preconditioners
            .block_jacobi
            .factorize(self.pattern.as_ref(), values)
        {
            return None;
        }
        if symmetric && self.pcg(values, rhs, kind, tolerance, ITERATIVE_ITERATIONS) {
            return Some(Factorization::BlockJacobiCg);
        }
        if self.gmres(values, rhs, kind, ITERATIVE_ITERATIONS) {
            return Some(Factorization::BlockJacobiGmres);
        }
        None
    }

    /// Cholesky of `A` when symmetric, solved directly; of its symmetric
    /// part when not, preconditioning GMRES. The factor is kept when it
    /// exists; `None` when `A` (or its symmetric part) is not positive
    /// definite or GMRES does not converge.
    fn solve_cholesky(
        &mut self,
        values: &[f64],
        symmetric: bool,
        rhs: &[f64],
    ) -> Result<Option<Factorization>, SolveFailure> {
        self.factor_kept = self.factor_symmetric_part(values, symmetric)?;
        if !self.factor_kept {
            return Ok(None);
        }
        self.record_factor(values, symmetric);
        if symmetric {
            self.load_rhs(rhs);
            self.cholesky
                .solve_in_place(&mut self.rhs, self.par, &mut self.scratch);
            return Ok(Some(Factorization::Cholesky));
        }
        let kind = Preconditioner::Cholesky;
        let solved = self.gmres(values, rhs, kind, SYMMETRIC_PART_ITERATIONS);
        Ok(solved.then_some(Factorization::PreconditionedGmres))
    }

    /// Sparse LU, the last resort: refused above [`AUTO_ITERATIVE_ABOVE`]
    /// unknowns.
    fn solve_lu(&mut self, values: &[f64], rhs: &[f64]) -> Result<Factorization, SolveFailure> {
        if self.dimension() > AUTO_ITERATIVE_ABOVE {
            return Err(SolveFailure::BeyondLu {
                dimension: self.dimension(),
                limit: AUTO_ITERATIVE_ABOVE,
            });
        }
        self.load_rhs(rhs);
        let pattern = self.pattern.as_ref();
        self.lu.analyse(pattern)?;
        self.stats.lu_factorizations += 1;
        self.lu
            .factorize_and_solve(pattern, values, &mut self.rhs, self.par, &mut self.scratch)?;
        Ok(Factorization::Lu)
    }

    /// Copies the solution in `self.rhs` into `rhs` (which holds `b`),
    /// after checking it: finite, and for a factorisation a residual of at
    /// most `1e-6 |b|`, or `krylov_tolerance |b|` where that is looser — a
    /// (numerically) singular matrix can factorise without error and
    /// return garbage. The check costs `O(nnz)`.
    fn deliver(
        &mut self,
        values: &[f64],
        rhs: &mut [f64],
        used: Factorization,
    ) -> Result<(), SolveFailure> {
        let b_norm = norm(rhs);
        // (The block LU has checked its residual already.)
        let mut residual = if used == Factorization::BlockLu {
            0.0
        } else {
            let x = self.rhs.col_as_slice(0);
            product::residual_norm(self.pattern.as_ref(), values, x, rhs, &mut self.krylov.r)
        };
        // An ill-conditioned matrix (a stiff membrane with a soft bending
        // and no mass term: `E t / B` of 1e9 /m^2 in statics) loses digits
        // in the Cholesky solve: a few steps of iterative refinement with
        // the factor recover them (each a solve with the factor and a
        // product), where they are needed only.
        // (The correction's buffer is made only then: most solves need
        // none, and this runs at every Newton iteration.)
        if used == Factorization::Cholesky && residual.is_finite() && residual > 1e-6 * b_norm {
            let mut correction = Mat::zeros(self.dimension(), 1);
            for _ in 0..REFINEMENTS {
                if residual <= 1e-6 * b_norm {
                    break;
                }
                for (i, r) in self.krylov.r.iter().enumerate() {
                    correction[(i, 0)] = *r;
                }
                self.cholesky
                    .solve_in_place(&mut correction, self.par, &mut self.scratch);
                for i in 0..self.dimension() {
                    self.rhs[(i, 0)] += correction[(i, 0)];
                }
                let x = self.rhs.col_as_slice(0);
                residual = product::residual_norm(
                    self.pattern.as_ref(),
                    values,
                    x,
                    rhs,
                    &mut self.krylov.r,
                );
            }
        }
        for (i, x) in rhs.iter_mut().enumerate().take(self.dimension()) {
            *x = self.rhs[(i, 0)];
        }
        if rhs.iter().any(|x| !x.is_finite()) {
            return Err(SolveFailure::NotFinite { method: used });
        }
        // A direct solution is held to 1e-6, or to Newton's forcing term
        // where that is looser (as a Krylov solution is: inexact Newton,
        // Eisenstat & Walker 1996). An ill-conditioned Hessian whose
        // refinement stalls just above 1e-6 (a relaxed pseudo-step of a
        // fine level, whose `K + M / tau^2` lost its digits) would
        // otherwise fail Newton at its first iteration, where a direction
        // accurate to 1e-4 serves as well (docs/performance.md,
        // "Pseudo-steps kept, and the direct solve's accuracy").
        let bound = 1e-6f64.max(self.krylov_tolerance);
        if residual.is_nan() || (used.is_direct() && residual > bound * b_norm) {
            return Err(SolveFailure::Residual {
                method: used,
                relative: residual / b_norm,
            });
        }
        Ok(())
    }

    /// `reuse` keeps the Cholesky factor just made of `values` (of its
    /// symmetric part unless `symmetric`) across steps: records its matrix
    /// for a checkpoint ([`KeptLinear::factor`]).
    fn record_factor(&mut self, values: &[f64], symmetric: bool) {
        if self.mode != LinearMode::Reuse {
            return;
        }
        let kept = self.factor_from.get_or_insert_with(|| KeptFactor {
            values: Vec::new(),
            symmetric,
        });
        kept.values.clear();
        kept.values.extend_from_slice(values);
        kept.symmetric = symmetric;
    }

    /// What this solver carries across time steps ([`KeptLinear`]), for a
    /// checkpoint.
    pub fn kept(&self) -> KeptLinear {
        KeptLinear {
            multigrid: self.preconditioners.multigrid.as_ref().map(|m| m.kept()),
            factor: self.factor_kept.then(|| self.factor_from.clone()).flatten(),
        }
    }

    /// Makes again what [`Self::kept`] described (a resumed run): the
    /// multigrid hierarchy from the matrix it was built from, the `reuse`
    /// factor from its matrix, the counters as they were; the counts in
    /// [`Self::stats`] do not change. `false` when a kept matrix does not
    /// have the pattern's length or cannot be factorised or coarsened
    /// again.
    pub fn restore(&mut self, kept: &KeptLinear) -> bool {
        let nnz = self.pattern.compute_nnz();
        let fits = |v: &[f64]| v.len() == nnz;
        if kept
            .multigrid
            .as_ref()
            .and_then(|m| m.built_from.as_deref())
            .is_some_and(|v| !fits(v))
            || kept.factor.as_ref().is_some_and(|f| !fits(&f.values))
        {
            return false;
        }
        let stats = self.stats;
        let restored = (|| {
            if let Some(m) = &kept.multigrid {
                let node_graph = self.node_graph.as_ref();
                let Some(mg) = self.preconditioners.multigrid(node_graph) else {
                    return Ok(false);
                };
                if !mg.restore(m) {
                    return Ok(false);
                }
            }
            if let Some(f) = &kept.factor {
                self.factor_kept = self.factor_symmetric_part(&f.values, f.symmetric)?;
                if !self.factor_kept {
                    return Ok(false);
                }
                self.factor_from = Some(f.clone());
            }
            Ok::<bool, SolveFailure>(true)
        })();
        self.stats = stats;
        restored.unwrap_or(false)
    }

    /// Solves `A_old x = b` in place with the factorisation of the last
    /// successful [`LinearSolver::solve`] (a chord step of Newton's
    /// method: the matrix of an earlier iterate, no new factorisation).
    /// `values` are the last solve's matrix: the compact path solves with
    /// it by CG preconditioned with the factor it made. `false`, with
    /// `rhs` unchanged, when the last solve left no factor that can be
    /// reused this way (the other Krylov paths and LU).
    pub fn solve_again(&mut self, values: &[f64], rhs: &mut [f64]) -> bool {
        match self.last_used {
            Some(Factorization::CompactCg) => {
                let Some(compact) = self.compact.as_deref_mut() else {
                    return false;
                };
                let mut op = CompactOperator {
                    values,
                    pattern: self.pattern.as_ref(),
                    product: &self.product,
                    compact,
                };
                let outcome = krylov::pcg(
                    &mut op,
                    rhs,
                    self.krylov_tolerance,
                    COMPACT_ITERATIONS,
                    &mut self.krylov,
                );
                if !self.finish_krylov(outcome) {
                    return false;
                }
                rhs.copy_from_slice(&self.krylov.x);
            }
            Some(Factorization::BlockLu) => {
                let Some(lu) = self.block_lu.as_mut() else {
                    return false;
                };
                lu.solve_in_place(rhs);
            }
            Some(Factorization::Cholesky) => {
                self.load_rhs(rhs);
                self.cholesky
                    .solve_in_place(&mut self.rhs, self.par, &mut self.scratch);
                for (i, x) in rhs.iter_mut().enumerate() {
                    *x = self.rhs[(i, 0)];
                }
            }
            _ => return false,
        }
        self.stats.solves += 1;
        self.stats.chord_solves += 1;
        true
    }

    /// Solves `M x = b` in place for a mass-like matrix `M` (symmetric
    /// positive definite with a condition number bounded independently of
    /// the mesh size: about 4 for the consistent mass of linear triangles
    /// after block-Jacobi scaling) by block-Jacobi conjugate gradients to a
    /// relative residual of 1e-14: a few tens of iterations at any size,
    /// where a factorisation of a million-element mass matrix would take
    /// tens of seconds and gigabytes. Falls back to [`LinearSolver::solve`]
    /// if CG does not converge in 1,000 iterations.
    ///
    /// On the multigrid path the matrix is first copied into the finest
    /// level's 3x3 blocks, and CG's products use them: they are the
    /// products of the later solves, and the first step's multigrid build
    /// then refills an array that set-up has already written (the first
    /// write of fresh memory is slow on some machines: docs/performance.md,
    /// "Fresh memory").
    pub fn solve_mass(&mut self, values: &[f64], rhs: &mut [f64]) -> Result<(), LinearSolveError> {
        self.blocks_current = self.uses_multigrid() && self.load_finest_blocks(values);
        let solved = self
            .preconditioners
            .block_jacobi
            .factorize(self.pattern.as_ref(), values)
            && self.pcg(values, rhs, Preconditioner::BlockJacobi, 1e-14, 1000);
        self.blocks_current = false;
        if solved {
            self.stats.solves += 1;
            for (i, x) in rhs.iter_mut().enumerate() {
                *x = self.rhs[(i, 0)];
            }
            return Ok(());
        }
        self.solve_matrix(values, true, rhs)
            .map(|_| ())
            .map_err(|failure| failure.of(Matrix::Mass))
    }

    /// Whether systems of this size and mode go to the multigrid path.
    fn uses_multigrid(&self) -> bool {
        self.mode == LinearMode::Iterative
            || (self.mode == LinearMode::Auto && self.dimension() > AUTO_ITERATIVE_ABOVE)
    }

    /// Copies `values` into the finest multigrid level's blocks while no
    /// hierarchy holds them (before the first build); `false` when the
    /// pattern has no node blocks or a hierarchy exists.
    fn load_finest_blocks(&mut self, values: &[f64]) -> bool {
        self.preconditioners
            .multigrid(self.node_graph.as_ref())
            .is_some_and(|mg| mg.load_finest(values))
    }

    /// `self.rhs <- b`.
    fn load_rhs(&mut self, b: &[f64]) {
        for (i, v) in b.iter().enumerate() {
            self.rhs[(i, 0)] = *v;
        }
    }

    /// Factorises `values` (lower triangle read) by Cholesky into the kept
    /// storage; `Ok(false)` when the matrix is not positive definite.
    fn factor_cholesky(&mut self, values: &[f64]) -> Result<bool, SolveFailure> {
        let pattern = self.pattern.as_ref();
        self.cholesky.analyse(pattern)?;
        self.stats.cholesky_factorizations += 1;
        Ok(self
            .cholesky
            .factorize(pattern, values, self.par, &mut self.scratch))
    }

    /// Factorises the symmetric part `(A + A^T) / 2` of `values` (`A`
    /// itself when `symmetric`) by Cholesky, to precondition with;
    /// `Ok(false)` without a transpose map.
    fn factor_symmetric_part(
        &mut self,
        values: &[f64],
        symmetric: bool,
    ) -> Result<bool, SolveFailure> {
        if symmetric {
            return self.factor_cholesky(values);
        }
        let Some(transpose) = self.product.transpose() else {
            return Ok(false);
        };
        direct::symmetric_part(values, transpose, &mut self.symmetric_part);
        let sym = std::mem::take(&mut self.symmetric_part);
        let ok = self.factor_cholesky(&sym);
        self.symmetric_part = sym;
        ok
    }

    /// GMRES on `values` preconditioned by `kind`, to the Krylov
    /// tolerance in at most `max_iterations`, so that a converged result
    /// equals a direct solve's to well within Newton's tolerance. The
    /// solution is left in `self.rhs`; `false` when it has not converged.
    fn gmres(
        &mut self,
        values: &[f64],
        b: &[f64],
        kind: Preconditioner,
        max_iterations: usize,
    ) -> bool {
        let tolerance = self.krylov_tolerance;
        let (mut op, work) = self.krylov_parts(values, kind);
        let outcome = krylov::gmres(&mut op, b, tolerance, max_iterations, work);
        self.finish_krylov(outcome)
    }

    /// Conjugate gradients on `values` (symmetric positive definite)
    /// preconditioned by `kind`, to `|b - A x| <= tolerance |b|` in at
    /// most `max_iterations`. The solution is left in `self.rhs`; `false`
    /// when it has not converged (or `A` showed a non-positive curvature).
    fn pcg(
        &mut self,
        values: &[f64],
        b: &[f64],
        kind: Preconditioner,
        tolerance: f64,
        max_iterations: usize,
    ) -> bool {
        let (mut op, work) = self.krylov_parts(values, kind);
        let outcome = krylov::pcg(&mut op, b, tolerance, max_iterations, work);
        self.finish_krylov(outcome)
    }

    /// The operator of a Krylov solve on `values` preconditioned by
    /// `kind`, and the work space, borrowed from the solver's parts.
    fn krylov_parts<'s>(
        &'s mut self,
        values: &'s [f64],
        kind: Preconditioner,
    ) -> (Preconditioned<'s>, &'s mut krylov::Work) {
        let op = Preconditioned {
            values,
            pattern: self.pattern.as_ref(),
            product: &self.product,
            blocks_current: self.blocks_current,
            kind,
            preconditioners: &mut self.preconditioners,
            cholesky: &self.cholesky,
            scratch: &mut self.scratch,
            par: self.par,
        };
        (op, &mut self.krylov)
    }

    /// Records a Krylov solve's iterations, leaves its solution in
    /// `self.rhs` and tells whether it converged to a finite solution.
    fn finish_krylov(&mut self, outcome: krylov::Outcome) -> bool {
        self.last_krylov_iterations = outcome.iterations;
        self.stats.krylov_iterations += outcome.iterations;
        let x = &self.krylov.x;
        for (i, v) in x.iter().enumerate() {
            self.rhs[(i, 0)] = *v;
        }
        let finite = x.iter().all(|v| v.is_finite());
        outcome.converged && finite
    }
}

/// The whole Hessian and the compact part's factor, for CG.
struct CompactOperator<'a> {
    values: &'a [f64],
    pattern: faer::sparse::SymbolicSparseColMatRef<'a, usize>,
    product: &'a Product,
    compact: &'a mut Compact,
}

impl krylov::Operator for CompactOperator<'_> {
    fn apply(&mut self, x: &[f64], out: &mut [f64]) {
        self.product.apply(self.pattern, self.values, x, out);
    }

    fn precondition(&mut self, r: &[f64], z: &mut [f64]) {
        self.compact.apply(r, z);
    }

    fn precondition_in_place(&mut self, x: &mut Mat<f64>) {
        let r = x.col_as_slice(0).to_vec();
        self.compact.apply(&r, x.col_as_slice_mut(0));
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// 1D Laplacian plus identity: SPD, tridiagonal; with `asym`, `-1 -
    /// asym` above the diagonal and `-1 + asym` below.
    pub(in crate::solver) fn tridiagonal(
        n: usize,
        asym: f64,
    ) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
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

    /// A singular matrix (row and column 2 of the tridiagonal zeroed) is
    /// an error naming the matrix: the Hessian from `solve`, the mass
    /// matrix from `solve_mass` (whose conjugate gradients fail first).
    #[test]
    fn a_singular_matrix_is_named_in_the_error() {
        let n = 6;
        let (cp, ri, mut v) = tridiagonal(n, 0.0);
        for c in 0..n {
            for k in cp[c]..cp[c + 1] {
                if c == 2 || ri[k] == 2 {
                    v[k] = 0.0;
                }
            }
        }
        let b = vec![1.0; n];
        let e = LinearSolver::new(&cp, &ri)
            .unwrap()
            .solve(&v, true, &mut b.clone())
            .unwrap_err();
        assert_eq!(e.matrix, Matrix::Hessian);
        assert!(
            e.to_string().starts_with("the Hessian is singular ("),
            "{e}"
        );
        let e = LinearSolver::new(&cp, &ri)
            .unwrap()
            .solve_mass(&v, &mut b.clone())
            .unwrap_err();
        assert_eq!(e.matrix, Matrix::Mass);
        assert!(
            e.to_string().starts_with("the mass matrix is singular ("),
            "{e}"
        );
    }

    /// A chain of springs alternating between `stiff` and 1, with `shift`
    /// on the diagonal: SPD, and as ill-conditioned as a stiff membrane
    /// with a soft bending under a small mass term.
    fn stiff_chain(n: usize, stiff: f64, shift: f64) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let k = |i: usize| if i.is_multiple_of(2) { stiff } else { 1.0 };
        let (mut cp, mut ri, mut v) = (vec![0], vec![], vec![]);
        for c in 0..n {
            let left = if c > 0 { k(c - 1) } else { 0.0 };
            let right = if c + 1 < n { k(c) } else { 0.0 };
            if c > 0 {
                ri.push(c - 1);
                v.push(-left);
            }
            ri.push(c);
            v.push(left + right + shift);
            if c + 1 < n {
                ri.push(c + 1);
                v.push(-right);
            }
            cp.push(ri.len());
        }
        (cp, ri, v)
    }

    /// A direct solution is held to 1e-6, or to Newton's forcing term
    /// where that is looser (`deliver`). On the stiff chain (springs of
    /// 1e10 and 1, shift 1e-2: a stiff membrane with a soft bending under
    /// a small mass term) the Cholesky solve and its refinement leave a
    /// relative residual of about 3e-6 (measured with faer 0.24): a
    /// failure at the default tolerance, and a solution at Newton's
    /// loosest forcing term, 1e-4, as a Krylov solve would be.
    #[test]
    fn a_direct_solve_is_held_to_newtons_forcing_term() {
        let n = 200;
        let (cp, ri, v) = stiff_chain(n, 1e10, 1e-2);
        let b: Vec<f64> = (0..n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
        let b_norm = b.iter().map(|x| x * x).sum::<f64>().sqrt();
        let relative = |x: &[f64]| {
            let mut r = b.clone();
            for c in 0..n {
                for k in cp[c]..cp[c + 1] {
                    r[ri[k]] -= v[k] * x[c];
                }
            }
            r.iter().map(|x| x * x).sum::<f64>().sqrt() / b_norm
        };
        let mut solver = LinearSolver::new(&cp, &ri).unwrap();
        let e = solver.solve_spd(&v, &mut b.clone()).unwrap_err();
        let SolveFailure::Residual {
            method,
            relative: r,
        } = e.failure
        else {
            panic!("{e}");
        };
        assert_eq!(method, Factorization::Cholesky);
        assert!(r > 1e-6 && r < 1e-4, "{r:e}");
        solver.krylov_tolerance = 1e-4;
        let mut x = b.clone();
        let used = solver.solve_spd(&v, &mut x).unwrap();
        assert_eq!(used, Some(Factorization::Cholesky));
        let r = relative(&x);
        assert!(r > 1e-6 && r <= 1e-4, "{r:e}");
    }

    /// The transpose map of a tridiagonal pattern.
    fn transpose(cp: &[usize], ri: &[usize]) -> Vec<usize> {
        let n = cp.len() - 1;
        let find = |r: usize, c: usize| (cp[c]..cp[c + 1]).find(|&k| ri[k] == r).unwrap();
        (0..n)
            .flat_map(|c| (cp[c]..cp[c + 1]).map(move |k| (c, k)))
            .map(|(c, k)| find(c, ri[k]))
            .collect()
    }

    /// Every mode solves a non-symmetric system to the same answer (1e-10):
    /// direct (Cholesky-preconditioned GMRES on the symmetric part),
    /// iterative (block-Jacobi GMRES) and reuse (an earlier factor as the
    /// preconditioner, on a changed matrix).
    #[test]
    fn every_mode_solves_a_nonsymmetric_system() {
        let n = 60;
        let (cp, ri, v) = tridiagonal(n, 0.3);
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let mut reference = b.clone();
        LinearSolver::new(&cp, &ri)
            .unwrap()
            .solve(&v, false, &mut reference)
            .unwrap();
        for (mode, expected) in [
            (LinearMode::Direct, Factorization::PreconditionedGmres),
            (LinearMode::Iterative, Factorization::BlockJacobiGmres),
        ] {
            let mut s = LinearSolver::new(&cp, &ri)
                .unwrap()
                .with_transpose(transpose(&cp, &ri))
                .with_mode(mode);
            let mut x = b.clone();
            assert_eq!(s.solve(&v, false, &mut x).unwrap(), expected, "{mode:?}");
            let err = x
                .iter()
                .zip(&reference)
                .map(|(a, c)| (a - c).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-10, "{mode:?}: {err:e}");
        }
        // A mildly non-symmetric matrix for the reuse path (8 iterations).
        let (cp, ri, v) = tridiagonal(n, 0.02);
        let mut s = LinearSolver::new(&cp, &ri)
            .unwrap()
            .with_transpose(transpose(&cp, &ri))
            .with_mode(LinearMode::Reuse);
        let mut x = b.clone();
        s.solve(&v, false, &mut x).unwrap();
        // A slightly changed matrix: the kept factor preconditions it.
        let v2: Vec<f64> = v.iter().map(|a| 1.01 * a).collect();
        let mut x = b.clone();
        assert_eq!(
            s.solve(&v2, false, &mut x).unwrap(),
            Factorization::ReusedFactorGmres
        );
        assert!(residual(&cp, &ri, &v2, &x, &b) < 1e-10);
        assert_eq!(s.stats.cholesky_factorizations, 1);
    }

    /// `reuse`'s kept factor survives a checkpoint: a solver restored from
    /// [`LinearSolver::kept`] solves the next system as the one that kept
    /// it does, bit for bit (a fresh solver factorises that system itself
    /// and answers in other last bits); its counts do not change, and a
    /// kept matrix of another length is refused.
    #[test]
    fn a_restored_reuse_factor_solves_as_the_kept_one() {
        let n = 40;
        let (cp, ri, v) = tridiagonal(n, 0.02);
        let make = || {
            LinearSolver::new(&cp, &ri)
                .unwrap()
                .with_transpose(transpose(&cp, &ri))
                .with_mode(LinearMode::Reuse)
        };
        let b: Vec<f64> = (0..n).map(|i| (0.7 * i as f64).sin()).collect();
        let mut kept = make();
        kept.solve(&v, false, &mut b.clone()).unwrap();
        let state = kept.kept();
        assert_eq!(state.factor.as_ref().map(|f| f.symmetric), Some(false));
        let mut restored = make();
        assert!(restored.restore(&state));
        assert_eq!(restored.stats, LinearStats::default());
        let v2: Vec<f64> = v.iter().map(|a| 1.01 * a).collect();
        let solve = |s: &mut LinearSolver| {
            let mut x = b.clone();
            let used = s.solve(&v2, false, &mut x).unwrap();
            (used, x)
        };
        let (used, x) = solve(&mut kept);
        assert_eq!(used, Factorization::ReusedFactorGmres);
        assert_eq!(solve(&mut restored), (used, x.clone()));
        let (fresh_used, fresh) = solve(&mut make());
        assert_ne!(fresh_used, used);
        assert_ne!(fresh, x);
        let mut short = state.clone();
        short.factor.as_mut().unwrap().values.pop();
        assert!(!make().restore(&short));
    }

    /// Block-Jacobi CG: the mass solve and the `iterative` mode on a
    /// symmetric positive definite system give the direct solution (1e-10;
    /// the CG tolerance of the mass solve is 1e-14, the iterative mode's
    /// the default 1e-12).
    #[test]
    fn block_jacobi_cg_solves_spd_systems() {
        let n = 60;
        let (cp, ri, v) = tridiagonal(n, 0.0);
        let b: Vec<f64> = (0..n).map(|i| (0.3 * i as f64).cos()).collect();
        let mut reference = b.clone();
        LinearSolver::new(&cp, &ri)
            .unwrap()
            .solve(&v, true, &mut reference)
            .unwrap();
        let mut mass = LinearSolver::new(&cp, &ri).unwrap();
        let mut x = b.clone();
        mass.solve_mass(&v, &mut x).unwrap();
        assert!(mass.stats.krylov_iterations > 0);
        assert_eq!(mass.stats.cholesky_factorizations, 0);
        let mut it = LinearSolver::new(&cp, &ri)
            .unwrap()
            .with_transpose(transpose(&cp, &ri))
            .with_mode(LinearMode::Iterative);
        let mut y = b.clone();
        assert_eq!(
            it.solve(&v, true, &mut y).unwrap(),
            Factorization::BlockJacobiCg
        );
        for sol in [&x, &y] {
            let err = sol
                .iter()
                .zip(&reference)
                .map(|(a, c)| (a - c).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-10, "{err:e}");
        }
    }

    /// A symmetric indefinite system above the block LU's size (a 45 x 45
    /// node grid, 6,348 unknowns; one component's Laplacian negated):
    /// Cholesky refuses it, the node-block LU solves it once — no pivoting
    /// LU — to a residual of 1e-10, in `direct` and `auto` alike, and its
    /// factor serves a chord step.
    #[test]
    fn an_indefinite_system_goes_to_the_block_lu_before_lu() {
        let (p, v) = indefinite_grid(45, 0.0);
        let dim = p.dimension();
        assert!(dim > BLOCK_LU_MAX_SYMMETRIC);
        let b: Vec<f64> = (0..dim).map(|i| ((i * 7) % 5) as f64 - 2.0).collect();
        for mode in [LinearMode::Direct, LinearMode::Auto] {
            let mut solver = node_block_solver(&p, mode);
            solved_by_block_lu(&mut solver, &p, &v, true, &b, 1);
            // Newton's chord steps reuse the block LU's factor.
            let b2: Vec<f64> = (0..dim).map(|i| ((i * 3) % 7) as f64 - 3.0).collect();
            let mut x2 = b2.clone();
            assert!(solver.solve_again(&v, &mut x2), "{mode:?}");
            let r2 = residual(&p.col_ptr, &p.row_idx, &v, &x2, &b2);
            assert!(r2 < 1e-8, "{mode:?}: chord residual {r2:e}");
        }
    }

    /// The multigrid path (iterative mode on a node-block pattern with
    /// several levels: 961 nodes) solves a symmetric positive definite
    /// system by CG and a non-symmetric one by GMRES, to the direct
    /// solution within 1e-8 relative (Krylov tolerance 1e-10); the
    /// hierarchy built for the first matrix serves a slightly changed one;
    /// a mass solve before them (block-Jacobi CG on the finest blocks)
    /// matches the direct solution.
    #[test]
    fn multigrid_path_solves_symmetric_and_nonsymmetric_systems() {
        use crate::solver::SparsePattern;
        let n = 30;
        let nodes = (n + 1) * (n + 1);
        let p = SparsePattern::triangle_grid(n, n);
        let (ptr, rows) = p.node_graph();
        // Graph Laplacian per component plus mass, with a skew coupling.
        let matrix = |skew: f64| -> Vec<f64> {
            let mut v = vec![0.0; p.nnz()];
            for b in 0..nodes {
                let deg = (ptr[b + 1] - ptr[b] - 1) as f64;
                for q in ptr[b]..ptr[b + 1] {
                    let a = rows[q];
                    for i in 0..3 {
                        let off = if a == b { deg + 0.05 } else { -1.0 };
                        v[p.entry(q, b, i, i)] = off;
                        if a != b && i < 2 {
                            let sign = if a < b { 1.0 } else { -1.0 };
                            v[p.entry(q, b, i, i + 1)] = skew * sign;
                        }
                    }
                }
            }
            v
        };
        let dim = p.dimension();
        let b: Vec<f64> = (0..dim).map(|i| ((i * 7) % 5) as f64 - 2.0).collect();
        for (skew, symmetric, expected) in [
            (0.0, true, Factorization::MultigridCg),
            (0.2, false, Factorization::MultigridGmres),
        ] {
            let mut solver = LinearSolver::new(&p.col_ptr, &p.row_idx)
                .unwrap()
                .with_transpose(p.transpose_map().to_vec())
                .with_node_blocks(ptr, rows)
                .with_mode(LinearMode::Iterative);
            solver.krylov_tolerance = 1e-10;
            // The initial acceleration's solve comes first: its products
            // use the finest level's blocks, which the first build must
            // then refill with the Hessian (a stale copy would show in
            // the solutions below).
            let mass: Vec<f64> = matrix(0.0).iter().map(|x| 0.5 * x).collect();
            let (mut xm, mut reference_m) = (b.clone(), b.clone());
            solver.solve_mass(&mass, &mut xm).unwrap();
            LinearSolver::new(&p.col_ptr, &p.row_idx)
                .unwrap()
                .solve(&mass, true, &mut reference_m)
                .unwrap();
            for (a, c) in xm.iter().zip(&reference_m) {
                assert!((a - c).abs() < 1e-9 * c.abs().max(1.0), "mass: {a} vs {c}");
            }
            let mass_iterations = solver.stats.krylov_iterations;
            for round in 0..2 {
                let v: Vec<f64> = matrix(skew)
                    .iter()
                    .map(|x| x * (1.0 + 0.01 * round as f64))
                    .collect();
                let mut reference = b.clone();
                LinearSolver::new(&p.col_ptr, &p.row_idx)
                    .unwrap()
                    .solve(&v, symmetric, &mut reference)
                    .unwrap();
                let mut x = b.clone();
                assert_eq!(solver.solve(&v, symmetric, &mut x).unwrap(), expected);
                let err = x
                    .iter()
                    .zip(&reference)
                    .map(|(a, c)| (a - c).abs())
                    .fold(0.0, f64::max);
                let size = reference.iter().fold(0.0f64, |a, c| a.max(c.abs()));
                assert!(err < 1e-8 * size, "skew {skew}, round {round}: {err:e}");
            }
            assert_eq!(solver.stats.multigrid_builds, 1);
            assert!(
                solver.stats.krylov_iterations - mass_iterations < 2 * 60,
                "{:?}",
                solver.stats
            );
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

    /// A system on the node graph of `n x n` squares (two triangles each),
    /// 3x3 diagonal blocks: a shifted graph Laplacian on components x and
    /// y, its negative on z (indefinite), plus a skew coupling `skew`
    /// between neighbours (non-symmetric unless 0; the symmetric part is
    /// the indefinite one).
    fn indefinite_grid(n: usize, skew: f64) -> (crate::solver::SparsePattern, Vec<f64>) {
        let p = crate::solver::SparsePattern::triangle_grid(n, n);
        let (ptr, rows) = p.node_graph();
        let mut v = vec![0.0; p.nnz()];
        for b in 0..(n + 1) * (n + 1) {
            let deg = (ptr[b + 1] - ptr[b] - 1) as f64;
            for q in ptr[b]..ptr[b + 1] {
                let r = rows[q];
                for i in 0..3 {
                    let x = if r == b { deg + 0.05 } else { -1.0 };
                    let x = if i == 2 { -x } else { x };
                    let s = match r.cmp(&b) {
                        std::cmp::Ordering::Less => skew,
                        std::cmp::Ordering::Greater => -skew,
                        std::cmp::Ordering::Equal => 0.0,
                    };
                    v[p.entry(q, b, i, i)] = x + s;
                }
            }
        }
        (p, v)
    }

    /// A graph Laplacian plus `shift` on an `n x n` grid of squares cut
    /// into triangles, widened by couplings two nodes apart along the rows
    /// (bending's farther couplings): the whole pattern, the compact one
    /// (the triangles' alone) and the values, on the z component negated
    /// when `indefinite`.
    fn wide_grid(
        n: usize,
        shift: f64,
        indefinite: bool,
    ) -> (
        crate::solver::SparsePattern,
        crate::solver::SparsePattern,
        Vec<f64>,
    ) {
        let (p, compact) = crate::solver::SparsePattern::wide_grid(n, n);
        let nodes = p.dimension() / 3;
        let (ptr, rows) = p.node_graph();
        let mut v = vec![0.0; p.nnz()];
        for b in 0..nodes {
            let deg = (ptr[b + 1] - ptr[b] - 1) as f64;
            for q in ptr[b]..ptr[b + 1] {
                for i in 0..3 {
                    let x = if rows[q] == b { deg + shift } else { -1.0 };
                    let x = if indefinite && i == 2 { -x } else { x };
                    v[p.entry(q, b, i, i)] = x;
                }
            }
        }
        (p, compact, v)
    }

    /// `compact` solves a positive definite system with couplings beyond
    /// its compact part by CG preconditioned with the compact factor (the
    /// node-block `L D L^T` below 5,000 unknowns, Cholesky above), to the
    /// Krylov tolerance, and serves a chord step with the same factor; an
    /// indefinite one it refuses (`None`, for the projected Newton to
    /// project). Without a compact part it solves as `direct`.
    #[test]
    fn compact_solves_by_cg_with_the_compact_factor() {
        for (n, factor) in [(12, "block LU"), (45, "Cholesky")] {
            let (p, compact, v) = wide_grid(n, 1.0, false);
            let dim = p.dimension();
            let b: Vec<f64> = (0..dim).map(|i| ((i * 7) % 5) as f64 - 2.0).collect();
            let mut solver =
                node_block_solver(&p, LinearMode::Compact).with_compact(compact.clone());
            solver.krylov_tolerance = 1e-10;
            let mut x = b.clone();
            assert_eq!(
                solver.solve_spd(&v, &mut x).unwrap(),
                Some(Factorization::CompactCg),
                "{factor}"
            );
            let r = residual(&p.col_ptr, &p.row_idx, &v, &x, &b) / crate::vecn::norm(&b);
            assert!(r < 1e-9, "{factor}: relative residual {r:e}");
            assert!(solver.last_krylov_iterations > 1, "{factor}");
            let (choleskys, block_lus) = (
                solver.stats.cholesky_factorizations,
                solver.stats.block_lu_factorizations,
            );
            assert_eq!(
                (choleskys, block_lus),
                if dim <= BLOCK_LU_MAX_SYMMETRIC {
                    (0, 1)
                } else {
                    (1, 0)
                },
                "{factor}"
            );
            let b2: Vec<f64> = (0..dim).map(|i| ((i * 3) % 7) as f64 - 3.0).collect();
            let mut x2 = b2.clone();
            assert!(solver.solve_again(&v, &mut x2), "{factor}");
            let r2 = residual(&p.col_ptr, &p.row_idx, &v, &x2, &b2) / crate::vecn::norm(&b2);
            assert!(r2 < 1e-9, "{factor}: chord relative residual {r2:e}");
            assert_eq!(solver.stats.chord_solves, 1);

            let (_, _, w) = wide_grid(n, 1.0, true);
            let mut y = b.clone();
            assert_eq!(solver.solve_spd(&w, &mut y).unwrap(), None, "{factor}");
            assert_eq!(y, b, "{factor}: a refused solve leaves b");
        }
        // The compact part holding every coupling: no preconditioner, the
        // node-block L D L^T of `direct`.
        let p = crate::solver::SparsePattern::triangle_grid(6, 6);
        let mut solver = node_block_solver(&p, LinearMode::Compact).with_compact(p.clone());
        assert!(solver.compact_pattern().is_none());
        let (ptr, rows) = p.node_graph();
        let mut v = vec![0.0; p.nnz()];
        for b in 0..ptr.len() - 1 {
            let deg = (ptr[b + 1] - ptr[b] - 1) as f64;
            for q in ptr[b]..ptr[b + 1] {
                for i in 0..3 {
                    v[p.entry(q, b, i, i)] = if rows[q] == b { deg + 0.05 } else { -1.0 };
                }
            }
        }
        let mut x = vec![1.0; p.dimension()];
        assert_eq!(
            solver.solve_spd(&v, &mut x).unwrap(),
            Some(Factorization::BlockLu)
        );
    }

    /// A non-symmetric system with node blocks goes to the node-block LU
    /// (its `L D U` path): first in `direct`; in `reuse`, after Cholesky
    /// of the symmetric part refused it (indefinite) — no pivoting LU
    /// either way — to a residual of 1e-10.
    #[test]
    fn a_nonsymmetric_system_goes_to_the_block_lu() {
        let n = 8;
        let (p, v) = indefinite_grid(n, 0.3);
        let b: Vec<f64> = (0..p.dimension())
            .map(|i| ((i * 7) % 5) as f64 - 2.0)
            .collect();
        for (mode, choleskys) in [(LinearMode::Direct, 0), (LinearMode::Reuse, 1)] {
            solved_by_block_lu(
                &mut node_block_solver(&p, mode),
                &p,
                &v,
                false,
                &b,
                choleskys,
            );
        }
    }

    /// A solver of `p`'s systems in `mode`, with its transpose map and
    /// node blocks.
    fn node_block_solver(p: &crate::solver::SparsePattern, mode: LinearMode) -> LinearSolver {
        let (ptr, rows) = p.node_graph();
        LinearSolver::new(&p.col_ptr, &p.row_idx)
            .unwrap()
            .with_transpose(p.transpose_map().to_vec())
            .with_node_blocks(ptr, rows)
            .with_mode(mode)
    }

    /// Solves `v x = b` with `solver`, which must take the node-block LU
    /// once, after `choleskys` Cholesky factorisations and without the
    /// pivoting LU, to a residual of 1e-10.
    fn solved_by_block_lu(
        solver: &mut LinearSolver,
        p: &crate::solver::SparsePattern,
        v: &[f64],
        symmetric: bool,
        b: &[f64],
        choleskys: usize,
    ) {
        let mode = solver.mode;
        let mut x = b.to_vec();
        assert_eq!(
            solver.solve(v, symmetric, &mut x).unwrap(),
            Factorization::BlockLu,
            "{mode:?}"
        );
        assert_eq!(solver.stats.cholesky_factorizations, choleskys, "{mode:?}");
        assert_eq!(solver.stats.block_lu_factorizations, 1, "{mode:?}");
        assert_eq!(solver.stats.lu_factorizations, 0, "{mode:?}");
        let r = residual(&p.col_ptr, &p.row_idx, v, &x, b);
        assert!(r < 1e-10, "{mode:?}: residual {r:e}");
    }

    /// A non-symmetric system the node-block LU cannot factorise (a zero
    /// pivot block: nodes 0 and 3 swap their unknowns, `[[0, I], [I, 0]]`,
    /// which needs pivoting between nodes) is solved by the pivoting LU:
    /// `x` is `b` with the two nodes' components exchanged.
    #[test]
    fn a_zero_pivot_block_falls_back_to_lu() {
        let p = crate::solver::SparsePattern::triangle_grid(1, 1);
        let (ptr, rows) = p.node_graph();
        let mut v = vec![0.0; p.nnz()];
        for b in 0..4 {
            for q in ptr[b]..ptr[b + 1] {
                let r = rows[q];
                let one = matches!((r, b), (0, 3) | (3, 0)) || (r == b && (b == 1 || b == 2));
                if one {
                    for i in 0..3 {
                        v[p.entry(q, b, i, i)] = 1.0;
                    }
                }
                // A non-symmetric coupling the LU must carry: node 1
                // feels node 0's x.
                if (r, b) == (1, 0) {
                    v[p.entry(q, b, 0, 0)] = 0.5;
                }
            }
        }
        let mut solver = LinearSolver::new(&p.col_ptr, &p.row_idx)
            .unwrap()
            .with_transpose(p.transpose_map().to_vec())
            .with_node_blocks(ptr, rows);
        let b: Vec<f64> = (0..12).map(|i| i as f64 + 1.0).collect();
        let mut x = b.clone();
        assert_eq!(solver.solve(&v, false, &mut x).unwrap(), Factorization::Lu);
        assert_eq!(solver.stats.block_lu_factorizations, 1);
        assert_eq!(solver.stats.lu_factorizations, 1);
        assert!(residual(&p.col_ptr, &p.row_idx, &v, &x, &b) < 1e-12);
        // Nodes 0 and 3 exchanged: x_0 = b_3, x_3 = b_0.
        assert_eq!(&x[0..3], &b[9..12]);
        assert_eq!(&x[9..12], &b[0..3]);
    }

    /// A pattern with an empty column (unknown 2 coupled to nothing, not
    /// even to itself) leaves the sparse LU without a pivot at the step
    /// that eliminates it: the error says so, with the step and the
    /// system's size. (Zero values on a full pattern give a solution that
    /// is not finite instead: [`a_singular_matrix_is_named_in_the_error`].)
    #[test]
    fn an_empty_column_is_a_missing_pivot() {
        let (cp, ri, v) = (vec![0, 2, 4, 4], vec![0, 1, 0, 1], vec![2.0, 1.0, 1.0, 2.0]);
        let e = LinearSolver::new(&cp, &ri)
            .unwrap()
            .solve(&v, false, &mut [1.0; 3])
            .unwrap_err();
        assert_eq!(e.matrix, Matrix::Hessian);
        assert!(
            matches!(e.failure, SolveFailure::NoPivot { dimension: 3, .. }),
            "{e:?}"
        );
        assert!(
            e.to_string().starts_with(
                "the Hessian is singular (sparse LU found no pivot at elimination step"
            ) && e.to_string().ends_with("of 3)"),
            "{e}"
        );
    }
}
