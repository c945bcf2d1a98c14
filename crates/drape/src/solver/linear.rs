//! Sparse direct solution of `H dY = -G` with faer, reusing the symbolic
//! analysis for as long as the sparsity pattern holds.
//!
//! * Small systems (up to 5,000 unknowns when symmetric, 15,000 when not)
//!   are factorised by the node-block LU of [`super::block_lu`], symmetric
//!   (`L D L^T`) or not — one factorisation and one solve for the
//!   non-symmetric wrinkling tangent, no Krylov iterations. A bad pivot
//!   block or a residual it cannot refine below `1e-10 |b|` hands the
//!   system to the paths below.
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

use super::amg::{Amg, BlockCsr};
use super::block_lu::BlockLu;
use super::pattern::gather_block;
use crate::block3::{Block, invert, mul_vec};
use crate::vecn::{distance, dot, norm};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::linalg::lu::{NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, Mat, Par, Side};

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
/// falls back to sparse LU (whose fill would take tens of gigabytes).
const AUTO_ITERATIVE_ABOVE: usize = 300_000;
/// Largest symmetric system (unknowns) that `direct` and `auto` factorise
/// by the node-block LU: above it faer's supernodal Cholesky, whose dense
/// kernels pay off on large fronts, is faster (measured: equal at 7,800
/// unknowns, twice as fast at 30,600; docs/performance.md).
const BLOCK_LU_MAX_SYMMETRIC: usize = 5_000;
/// Largest non-symmetric system for the node-block LU: above it a
/// Cholesky factorisation of the symmetric part and ~10 preconditioned
/// GMRES iterations cost less than the general block LU (twice the
/// symmetric one's work).
const BLOCK_LU_MAX_GENERAL: usize = 15_000;
/// Krylov iterations a reused factor gets before the matrix is refactorised.
const REUSE_ITERATIONS: usize = 8;
/// Most multigrid-preconditioned Krylov iterations before the one-level
/// preconditioner is tried.
const MULTIGRID_ITERATIONS: usize = 100;
/// Solves that skip multigrid after a freshly built hierarchy failed.
const MULTIGRID_BACKOFF: usize = 8;
/// Systems from this many unknowns multiply by the matrix on all threads.
const PARALLEL_MATVEC_ABOVE: usize = 50_000;
/// Most block-Jacobi GMRES iterations before LU takes over.
const ITERATIVE_ITERATIONS: usize = 400;

/// What preconditions the Krylov iterations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Preconditioner {
    /// The kept Cholesky factor.
    Cholesky,
    /// Inverted 3x3 diagonal blocks.
    BlockJacobi,
    /// A V-cycle of the smoothed-aggregation multigrid.
    Multigrid,
}

/// How linear systems are solved (`[solver] linear`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LinearMode {
    /// A fresh factorisation for every solve: the node-block LU for small
    /// systems; else Cholesky when symmetric positive definite, GMRES
    /// preconditioned by the Cholesky factor of the symmetric part when not
    /// symmetric; LU otherwise.
    Direct,
    /// `direct` up to 300,000 unknowns; above (where a sparse
    /// factorisation costs tens of seconds and gigabytes) `iterative`, with
    /// `reuse` as the fallback when multigrid does not converge.
    #[default]
    Auto,
    /// GMRES preconditioned by the Cholesky factor of an earlier Hessian,
    /// refactorised only when it stops converging in 8 iterations (the
    /// Hessian changes little from one Newton iteration and step to the
    /// next). On the 20x20 pedestal it cuts the factorisations by 3 without
    /// saving time (docs/performance.md); meant for larger meshes.
    Reuse,
    /// Conjugate gradients (GMRES when not symmetric) preconditioned by a
    /// smoothed-aggregation multigrid V-cycle ([`super::amg`]): no
    /// factorisation but the coarsest level's; cost per solve about linear
    /// in the mesh size. Block-Jacobi CG/GMRES is the fallback.
    Iterative,
}

/// `z = D^-1 r` for the inverted 3x3 diagonal blocks `blocks` (a trailing
/// partial block, never met with 3 unknowns per node, acts on the entries
/// there are).
fn block_jacobi_apply(blocks: &[Block], r: &[f64], z: &mut [f64]) {
    for (i, m) in blocks.iter().enumerate() {
        let o = 3 * i;
        let len = (r.len() - o).min(3);
        let mut v = [0.0; 3];
        v[..len].copy_from_slice(&r[o..o + len]);
        let t = mul_vec(m, &v);
        z[o..o + len].copy_from_slice(&t[..len]);
    }
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

/// The multigrid path: the Hessian in 3x3 blocks by rows (its structure
/// kept, values gathered per solve) and the hierarchy built from it.
///
/// Building the hierarchy (aggregation, Galerkin products) costs about as
/// much as ten V-cycles, so it is kept across Newton iterations and steps
/// — only the finest level's matrix and smoother follow each new Hessian
/// — and rebuilt when a solve needs more than half as many iterations
/// again as the first one after the last build.
struct Multigrid {
    /// Per block of the finest matrix: value index of its entry (0, 0)
    /// and the index distance between its columns in the scalar values.
    source: Vec<(usize, usize)>,
    /// The finest matrix while no hierarchy holds it.
    finest: Option<BlockCsr>,
    amg: Option<Amg>,
    /// Krylov iterations of the first solve after the last build, and of
    /// the last solve.
    fresh_iterations: usize,
    last_iterations: usize,
    /// Hierarchies built.
    builds: usize,
    /// Solves to leave to the fallback after a fresh hierarchy failed
    /// (rebuilding for every solve of a problem multigrid cannot handle
    /// would cost more than the fallback itself).
    skip: usize,
}

impl Multigrid {
    fn new(node_ptr: &[usize], node_rows: &[usize]) -> Self {
        let n = node_ptr.len() - 1;
        let mut source = Vec::with_capacity(node_rows.len());
        for a in 0..n {
            for &b in &node_rows[node_ptr[a]..node_ptr[a + 1]] {
                // Block (a, b): row a of column b.
                let p = node_ptr[b]
                    + node_rows[node_ptr[b]..node_ptr[b + 1]]
                        .binary_search(&a)
                        .unwrap_or(0);
                let deg = node_ptr[b + 1] - node_ptr[b];
                source.push((9 * node_ptr[b] + 3 * (p - node_ptr[b]), 3 * deg));
            }
        }
        Self {
            source,
            finest: Some(BlockCsr {
                ptr: node_ptr.to_vec(),
                cols: node_rows.iter().map(|&c| c as u32).collect(),
                vals: vec![[0.0; 9]; node_rows.len()],
                ncols: n,
            }),
            amg: None,
            fresh_iterations: 0,
            last_iterations: usize::MAX,
            builds: 0,
            skip: 0,
        }
    }

    /// Copies the blocks of the scalar CSC `values` into `blocks`.
    fn gather(source: &[(usize, usize)], values: &[f64], blocks: &mut [[f64; 9]]) {
        use rayon::prelude::*;
        let gather = |(v, &(b, t)): (&mut [f64; 9], &(usize, usize))| {
            *v = gather_block(values, b, t);
        };
        if source.len() > 100_000 {
            blocks.par_iter_mut().zip(source).for_each(gather);
        } else {
            blocks.iter_mut().zip(source).for_each(gather);
        }
    }

    /// Makes the preconditioner for `values`: the kept hierarchy with the
    /// new finest matrix while it serves, a new one otherwise. `false` if
    /// none can be built.
    fn setup(&mut self, values: &[f64], stats: &mut LinearStats) -> bool {
        let rebuild = self.amg.is_none()
            || self.last_iterations > self.fresh_iterations + self.fresh_iterations / 2 + 2;
        if !rebuild {
            let source = &self.source;
            let amg = self.amg.as_mut().expect("checked above");
            if amg.refresh_finest(|blocks| Self::gather(source, values, blocks)) {
                return true;
            }
        }
        let mut finest = match (self.finest.take(), self.amg.take()) {
            (Some(f), _) => f,
            (None, Some(amg)) => amg.into_finest(),
            (None, None) => return false,
        };
        Self::gather(&self.source, values, &mut finest.vals);
        self.builds += 1;
        stats.multigrid_builds += 1;
        self.fresh_iterations = usize::MAX;
        match Amg::new(finest) {
            Ok(amg) => {
                self.amg = Some(amg);
                true
            }
            Err(finest) => {
                self.finest = Some(finest);
                false
            }
        }
    }

    /// Records the iterations of a solve with the current hierarchy.
    fn record(&mut self, iterations: usize) {
        self.last_iterations = iterations;
        if self.fresh_iterations == usize::MAX {
            self.fresh_iterations = iterations;
        }
    }
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
    /// Counts since the solver was made.
    pub stats: LinearStats,
    /// Relative residual the Krylov solves stop at (default 1e-12); Newton
    /// loosens it while far from the solution (inexact Newton).
    pub krylov_tolerance: f64,
    /// How systems are solved.
    mode: LinearMode,
    /// Whether the Cholesky storage holds a usable factor (reusable).
    factor_kept: bool,
    /// The node graph, when the pattern is made of 3x3 node blocks, and
    /// its block LU (analysed on first use).
    node_graph: Option<(Vec<usize>, Vec<usize>)>,
    block_lu: Option<BlockLu>,
    /// The multigrid path (iterative mode, node-block patterns).
    multigrid: Option<Multigrid>,
    /// Whether the multigrid's finest matrix holds the values being solved
    /// for (products then use its 3x3 blocks).
    blocks_current: bool,
    /// How the last system was solved, if it succeeded.
    last_used: Option<Factorization>,
    /// The second half's sums of a two-thread product ([`Self::matvec`]).
    matvec_half: std::sync::Mutex<Vec<f64>>,
}

struct Krylov {
    slice_in: Vec<f64>,
    symmetric_part: Vec<f64>,
    blocks: Vec<Block>,
    basis: Vec<Vec<f64>>,
    work: Mat<f64>,
    z: Vec<f64>,
    x: Vec<f64>,
    r: Vec<f64>,
    ax: Vec<f64>,
}

impl Default for Krylov {
    fn default() -> Self {
        Self {
            slice_in: Vec::new(),
            symmetric_part: Vec::new(),
            blocks: Vec::new(),
            basis: Vec::new(),
            work: Mat::zeros(0, 0),
            z: Vec::new(),
            x: Vec::new(),
            r: Vec::new(),
            ax: Vec::new(),
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
            mode: LinearMode::Direct,
            factor_kept: false,
            node_graph: None,
            block_lu: None,
            multigrid: None,
            blocks_current: false,
            last_used: None,
            matvec_half: std::sync::Mutex::new(Vec::new()),
            stats: LinearStats::default(),
            krylov_tolerance: 1e-12,
        })
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
        self.transpose = Some(transpose);
        self
    }

    /// Enables the node-block LU ([`super::block_lu`]) for a pattern of 3x3
    /// node blocks in [`super::SparsePattern`]'s layout with node graph
    /// `(node_ptr, node_rows)`.
    pub fn with_node_blocks(mut self, node_ptr: &[usize], node_rows: &[usize]) -> Self {
        self.node_graph = Some((node_ptr.to_vec(), node_rows.to_vec()));
        self
    }

    /// Factorises by the node-block LU and solves for `b`, leaving the
    /// solution in `self.rhs`, refined once by the residual. `Ok(false)`
    /// when the block LU does not apply, meets a bad pivot, or leaves a
    /// residual above `1e-10 |b|` (the caller then pivots).
    fn block_lu_solve(
        &mut self,
        values: &[f64],
        symmetric: bool,
        b: &[f64],
    ) -> Result<bool, LinearSolveError> {
        if self.block_lu.is_none() {
            let Some((ptr, rows)) = &self.node_graph else {
                return Ok(false);
            };
            self.block_lu = Some(
                BlockLu::new(ptr, rows)
                    .map_err(|e| LinearSolveError::Factorization(e.to_string()))?,
            );
        }
        let mut lu = self.block_lu.take().expect("set above");
        self.stats.block_lu_factorizations += 1;
        if lu.factorize(values, symmetric).is_err() {
            self.block_lu = Some(lu);
            return Ok(false);
        }
        let mut x = std::mem::take(&mut self.krylov.x);
        x.clear();
        x.extend_from_slice(b);
        lu.solve_in_place(&mut x);
        let mut ax = std::mem::take(&mut self.krylov.ax);
        ax.resize(b.len(), 0.0);
        self.matvec(values, &x, &mut ax);
        let b_norm = norm(b);
        let mut d = std::mem::take(&mut self.krylov.r);
        d.clear();
        d.extend(b.iter().zip(&ax).map(|(p, q)| p - q));
        let r_norm = norm(&d);
        let mut ok = r_norm.is_finite();
        if ok && r_norm > 1e-12 * b_norm {
            // One step of iterative refinement: cheap (a solve with the
            // factor) and it removes what the unpivoted elimination lost.
            lu.solve_in_place(&mut d);
            for (xi, di) in x.iter_mut().zip(&d) {
                *xi += di;
            }
            self.matvec(values, &x, &mut ax);
            ok = distance(b, &ax) <= 1e-10 * b_norm;
        }
        for (i, v) in x.iter().enumerate() {
            self.rhs[(i, 0)] = *v;
        }
        self.krylov.x = x;
        self.krylov.ax = ax;
        self.krylov.r = d;
        self.block_lu = Some(lu);
        Ok(ok)
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
        self.last_used = None;
        self.stats.solves += 1;
        for (i, v) in rhs.iter().enumerate() {
            self.rhs[(i, 0)] = *v;
        }
        let mode = match self.mode {
            LinearMode::Auto if n > AUTO_ITERATIVE_ABOVE => LinearMode::Reuse,
            LinearMode::Auto => LinearMode::Direct,
            m => m,
        };
        // Large systems in `auto` try multigrid first, and keep a reused
        // factorisation as the fallback.
        let multigrid = self.uses_multigrid();
        let mut used = None;
        // (A block LU of an earlier Hessian as GMRES preconditioner does
        // not pay on the pedestal: the wrinkling tangent changes too much
        // from one iteration to the next; docs/performance.md.)
        let block_lu_max = if symmetric {
            BLOCK_LU_MAX_SYMMETRIC
        } else {
            BLOCK_LU_MAX_GENERAL
        };
        if mode == LinearMode::Direct
            && n <= block_lu_max
            && self.block_lu_solve(values, symmetric, rhs)?
        {
            used = Some(Factorization::BlockLu);
        }
        // Reuse the kept factor (of an earlier Hessian) as a preconditioner
        // while it pays: a few Krylov iterations instead of a factorisation.
        if mode == LinearMode::Reuse
            && self.factor_kept
            && self.gmres(values, rhs, Preconditioner::Cholesky, REUSE_ITERATIONS)?
        {
            used = Some(Factorization::ReusedFactorGmres);
        }
        if used.is_none() && multigrid {
            let tolerance = self.krylov_tolerance;
            if self.multigrid.is_none()
                && let Some((ptr, rows)) = &self.node_graph
            {
                self.multigrid = Some(Multigrid::new(ptr, rows));
            }
            // A kept hierarchy that fails is rebuilt once for this matrix.
            for _ in 0..2 {
                let Some(mg) = self.multigrid.as_mut() else {
                    break;
                };
                if mg.skip > 0 {
                    mg.skip -= 1;
                    break;
                }
                let builds = mg.builds;
                if !mg.setup(values, &mut self.stats) {
                    break;
                }
                let fresh = mg.builds > builds;
                self.blocks_current = true;
                let ok = if symmetric {
                    Ok(self.pcg(
                        values,
                        rhs,
                        Preconditioner::Multigrid,
                        tolerance,
                        MULTIGRID_ITERATIONS,
                    ))
                } else {
                    self.gmres(values, rhs, Preconditioner::Multigrid, MULTIGRID_ITERATIONS)
                };
                // (Reset before any early return: later products must read
                // `values`, not the blocks.)
                self.blocks_current = false;
                let ok = ok?;
                let iterations = self.last_krylov_iterations;
                let mg = self.multigrid.as_mut().expect("checked above");
                mg.record(if ok { iterations } else { usize::MAX });
                if ok {
                    used = Some(if symmetric {
                        Factorization::MultigridCg
                    } else {
                        Factorization::MultigridGmres
                    });
                    break;
                }
                if fresh {
                    mg.skip = MULTIGRID_BACKOFF;
                    break;
                }
            }
        }
        if used.is_none() && mode == LinearMode::Iterative {
            let tolerance = self.krylov_tolerance;
            if self.factor_block_jacobi(values) {
                if symmetric
                    && self.pcg(
                        values,
                        rhs,
                        Preconditioner::BlockJacobi,
                        tolerance,
                        ITERATIVE_ITERATIONS,
                    )
                {
                    used = Some(Factorization::BlockJacobiCg);
                } else if self.gmres(
                    values,
                    rhs,
                    Preconditioner::BlockJacobi,
                    ITERATIVE_ITERATIONS,
                )? {
                    used = Some(Factorization::BlockJacobiGmres);
                }
            }
        } else if used.is_none() {
            self.factor_kept = self.factor_symmetric_part(values, symmetric)?;
            if self.factor_kept {
                if symmetric {
                    for (i, v) in rhs.iter().enumerate() {
                        self.rhs[(i, 0)] = *v;
                    }
                    self.cholesky_solve_rhs();
                    used = Some(Factorization::Cholesky);
                } else if self.gmres(values, rhs, Preconditioner::Cholesky, 100)? {
                    used = Some(Factorization::PreconditionedGmres);
                }
            }
        }
        if used.is_none() {
            // LU overwrote nothing we keep, but the Cholesky storage may hold
            // an indefinite attempt: do not reuse it.
            self.factor_kept = false;
        }
        if used.is_none() && n > AUTO_ITERATIVE_ABOVE {
            return Err(LinearSolveError::Singular {
                detail: format!(
                    "no iterative or Cholesky solve converged, and sparse LU is not tried above {AUTO_ITERATIVE_ABOVE} unknowns"
                ),
            });
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
        let b_norm = norm(rhs);
        // (The block LU has checked its residual already.)
        let residual = if used == Factorization::BlockLu {
            0.0
        } else {
            self.residual_norm(values, rhs)
        };
        for (i, x) in rhs.iter_mut().enumerate().take(n) {
            *x = self.rhs[(i, 0)];
        }
        if rhs.iter().any(|x| !x.is_finite()) {
            return Err(LinearSolveError::Singular {
                detail: "the solution is not finite".into(),
            });
        }
        // (Krylov solves have checked their own residual, to their tolerance.)
        let direct = matches!(
            used,
            Factorization::Cholesky | Factorization::Lu | Factorization::BlockLu
        );
        if residual.is_nan() || (direct && residual > 1e-6 * b_norm) {
            return Err(LinearSolveError::Singular {
                detail: format!(
                    "the {} solve leaves a relative residual of {:.1e}",
                    match used {
                        Factorization::BlockLu => "block LU",
                        Factorization::Cholesky => "Cholesky",
                        Factorization::Lu => "LU",
                        Factorization::PreconditionedGmres => "preconditioned GMRES",
                        Factorization::ReusedFactorGmres => "GMRES with a reused factor",
                        Factorization::BlockJacobiGmres => "block-Jacobi GMRES",
                        Factorization::BlockJacobiCg => "block-Jacobi CG",
                        Factorization::MultigridCg => "multigrid CG",
                        Factorization::MultigridGmres => "multigrid GMRES",
                    },
                    residual / b_norm
                ),
            });
        }
        self.last_used = Some(used);
        Ok(used)
    }

    /// Solves `A_old x = b` in place with the factorisation of the last
    /// successful [`LinearSolver::solve`] (a chord step of Newton's
    /// method: the matrix of an earlier iterate, no new factorisation).
    /// `false`, with `rhs` unchanged, when the last solve left no factor
    /// that can be reused this way (Krylov and LU paths).
    pub fn solve_again(&mut self, rhs: &mut [f64]) -> bool {
        match self.last_used {
            Some(Factorization::BlockLu) => {
                let Some(lu) = self.block_lu.as_mut() else {
                    return false;
                };
                lu.solve_in_place(rhs);
            }
            Some(Factorization::Cholesky) => {
                for (i, v) in rhs.iter().enumerate() {
                    self.rhs[(i, 0)] = *v;
                }
                self.cholesky_solve_rhs();
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

    /// `|A x - b|` with `x` in `self.rhs` and `b` in `rhs`.
    fn residual_norm(&mut self, values: &[f64], b: &[f64]) -> f64 {
        let mut r = std::mem::take(&mut self.krylov.r);
        r.clear();
        r.extend_from_slice(b);
        let col_ptr = self.symbolic.col_ptr();
        let row_idx = self.symbolic.row_idx();
        for c in 0..self.dimension() {
            let x = self.rhs[(c, 0)];
            for k in col_ptr[c]..col_ptr[c + 1] {
                r[row_idx[k]] -= values[k] * x;
            }
        }
        let residual = norm(&r);
        self.krylov.r = r;
        residual
    }

    /// Factorises `values` (lower triangle read) by Cholesky into the kept
    /// storage; `Ok(false)` when the matrix is not positive definite.
    fn factor_cholesky(&mut self, values: &[f64]) -> Result<bool, LinearSolveError> {
        if self.llt.is_none() {
            let params = CholeskySymbolicParams {
                // faer picks its simplicial kernel below a flop threshold;
                // with 3x3 node blocks the supernodal one is faster at every
                // size measured here (the 20x20 pedestal: -39 % CPU).
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            };
            let symb = factorize_symbolic_cholesky(
                self.symbolic.as_ref(),
                Side::Lower,
                SymmetricOrdering::Amd,
                params,
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
        self.stats.cholesky_factorizations += 1;
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

    /// `out = A x` on the pattern. Large systems with a known transpose map
    /// (structurally symmetric patterns) compute it row by row in parallel:
    /// row `c` of `A` is column `c` read through the transpose map. Smaller
    /// ones, by columns in two halves on two threads ([`crate::par`]), or
    /// by columns on one.
    fn matvec(&self, values: &[f64], x: &[f64], out: &mut [f64]) {
        if self.blocks_current
            && let Some(mg) = self.multigrid.as_ref()
        {
            // The hierarchy's finest level, or before the first build the
            // blocks `load_finest_blocks` filled.
            if let Some(amg) = mg.amg.as_ref() {
                amg.finest().matvec(x, out);
                return;
            }
            if let Some(finest) = mg.finest.as_ref() {
                finest.matvec(x, out);
                return;
            }
        }
        let (col_ptr, row_idx) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        if let Some(transpose) = self.transpose.as_deref()
            && self.dimension() >= PARALLEL_MATVEC_ABOVE
        {
            use rayon::prelude::*;
            out.par_chunks_mut(4096)
                .enumerate()
                .for_each(|(chunk, out)| {
                    for (o, c) in out.iter_mut().zip(chunk * 4096..) {
                        let mut s = 0.0;
                        for k in col_ptr[c]..col_ptr[c + 1] {
                            s += values[transpose[k]] * x[row_idx[k]];
                        }
                        *o = s;
                    }
                });
            return;
        }
        if crate::par::helper_available() {
            // Two halves of the columns, the second on the helper thread
            // into a buffer of its own, added after: the entries are read
            // in storage order (rows by the transpose map cost a gather
            // per entry, and the product took as long as the triangular
            // solves it checks).
            let n = self.dimension();
            let half = n / 2;
            let mut guard = self
                .matvec_half
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            guard.resize(n, 0.0);
            let second: &mut [f64] = &mut guard;
            let columns = |cols: std::ops::Range<usize>, out: &mut [f64]| {
                out.fill(0.0);
                for c in cols {
                    let xc = x[c];
                    if xc != 0.0 {
                        let range = col_ptr[c]..col_ptr[c + 1];
                        for (&r, &v) in row_idx[range.clone()].iter().zip(&values[range]) {
                            out[r] += v * xc;
                        }
                    }
                }
            };
            crate::par::join(
                || columns(0..half, &mut out[..n]),
                || columns(half..n, second),
            );
            for (o, s) in out[..n].iter_mut().zip(second.iter()) {
                *o += s;
            }
            return;
        }
        out.fill(0.0);
        for (c, &xc) in x.iter().enumerate().take(self.dimension()) {
            if xc != 0.0 {
                let range = col_ptr[c]..col_ptr[c + 1];
                // Zipped slices: one bounds check per column, not per entry.
                for (&r, &v) in row_idx[range.clone()].iter().zip(&values[range]) {
                    out[r] += v * xc;
                }
            }
        }
    }

    /// Factorises the symmetric part `(A + A^T) / 2` of `values` (`A`
    /// itself when `symmetric`) by Cholesky, to precondition with.
    fn factor_symmetric_part(
        &mut self,
        values: &[f64],
        symmetric: bool,
    ) -> Result<bool, LinearSolveError> {
        if symmetric {
            return self.factor_cholesky(values);
        }
        let Some(transpose) = self.transpose.take() else {
            return Ok(false);
        };
        let mut sym = std::mem::take(&mut self.krylov.symmetric_part);
        sym.resize(values.len(), 0.0);
        for (k, s) in sym.iter_mut().enumerate() {
            *s = 0.5 * (values[k] + values[transpose[k]]);
        }
        self.transpose = Some(transpose);
        let ok = self.factor_cholesky(&sym);
        self.krylov.symmetric_part = sym;
        ok
    }

    /// Inverts the 3x3 diagonal blocks of `values` (block-Jacobi
    /// preconditioner); `false` if one is singular.
    fn factor_block_jacobi(&mut self, values: &[f64]) -> bool {
        let n = self.dimension();
        let (col_ptr, row_idx) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        let mut blocks = std::mem::take(&mut self.krylov.blocks);
        blocks.clear();
        blocks.resize(n.div_ceil(3), [0.0; 9]);
        for c in 0..n {
            for k in col_ptr[c]..col_ptr[c + 1] {
                let r = row_idx[k];
                if r / 3 == c / 3 {
                    blocks[c / 3][3 * (r % 3) + c % 3] = values[k];
                }
            }
        }
        let mut ok = true;
        for (i, m) in blocks.iter_mut().enumerate() {
            // Trailing partial block (never for 3 unknowns per node): identity.
            let size = (n - 3 * i).min(3);
            for d in size..3 {
                m[4 * d] = 1.0;
            }
            match invert(m) {
                Some(inv) => *m = inv,
                None => ok = false,
            }
        }
        self.krylov.blocks = blocks;
        ok
    }

    /// `z = P^-1 r` with the block-Jacobi blocks or a multigrid V-cycle
    /// (the preconditioners of conjugate gradients; the Cholesky factor,
    /// which works on faer matrices, goes through [`Self::precondition`]).
    fn precondition_slice(&mut self, kind: Preconditioner, r: &[f64], z: &mut [f64]) {
        match kind {
            Preconditioner::Multigrid => {
                if let Some(amg) = self.multigrid.as_mut().and_then(|m| m.amg.as_mut()) {
                    amg.apply(r, z);
                } else {
                    z.copy_from_slice(r);
                }
            }
            Preconditioner::BlockJacobi => block_jacobi_apply(&self.krylov.blocks, r, z),
            Preconditioner::Cholesky => {
                let mut x = Mat::from_fn(r.len(), 1, |i, _| r[i]);
                self.cholesky_solve(&mut x);
                z.copy_from_slice(x.col_as_slice_mut(0));
            }
        }
    }

    /// `x <- P^-1 x` (GMRES's preconditioner application).
    fn precondition(&mut self, kind: Preconditioner, x: &mut Mat<f64>) {
        if kind == Preconditioner::Cholesky {
            self.cholesky_solve(x);
            return;
        }
        let mut r = std::mem::take(&mut self.krylov.slice_in);
        r.clear();
        r.extend_from_slice(x.col_as_slice_mut(0));
        self.precondition_slice(kind, &r, x.col_as_slice_mut(0));
        self.krylov.slice_in = r;
    }

    /// Restarted GMRES (restart 25), right-preconditioned: solves `A P^-1 u
    /// = b`, `x = P^-1 u`, to `|b - A x| <= 1e-12 |b|` in at most
    /// `max_iterations`, so that a converged result equals a direct solve's
    /// to well within Newton's tolerance. `P` is the current Cholesky
    /// factor (of this matrix's symmetric part, or of an earlier Hessian's,
    /// reused) or the block-Jacobi blocks. `Ok(false)` when it has not
    /// converged. The solution is left in `self.rhs`.
    fn gmres(
        &mut self,
        values: &[f64],
        b: &[f64],
        preconditioner: Preconditioner,
        max_iterations: usize,
    ) -> Result<bool, LinearSolveError> {
        const RESTART: usize = 25;
        let n = self.dimension();
        let b_norm = norm(b);
        let mut x = std::mem::take(&mut self.krylov.x);
        x.clear();
        x.resize(n, 0.0);
        if b_norm == 0.0 {
            self.krylov.x = x;
            self.rhs.as_mut().fill(0.0);
            return Ok(true);
        }
        let mut basis = std::mem::take(&mut self.krylov.basis);
        basis.resize_with(RESTART + 1, || vec![0.0; n]);
        let mut work = std::mem::replace(&mut self.krylov.work, Mat::zeros(0, 0));
        if work.nrows() != n {
            work = Mat::zeros(n, 1);
        }
        let mut r = std::mem::take(&mut self.krylov.r);
        r.resize(n, 0.0);
        let mut ax = std::mem::take(&mut self.krylov.ax);
        ax.resize(n, 0.0);
        let mut iterations = 0;
        let mut converged = false;
        while iterations < max_iterations && !converged {
            // r = b - A x
            self.matvec(values, &x, &mut ax);
            for i in 0..n {
                r[i] = b[i] - ax[i];
            }
            let beta = norm(&r);
            if beta <= self.krylov_tolerance * b_norm {
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
                self.precondition(preconditioner, &mut work);
                let mut z = std::mem::take(&mut self.krylov.z);
                z.clear();
                z.extend((0..n).map(|i| work[(i, 0)]));
                let (head, tail) = basis.split_at_mut(k + 1);
                let w = &mut tail[0];
                self.matvec(values, &z, w);
                self.krylov.z = z;
                for (j, vj) in head.iter().enumerate() {
                    let hj = dot(vj, w);
                    h[k][j] = hj;
                    for i in 0..n {
                        w[i] -= hj * vj[i];
                    }
                }
                let norm_w = norm(w);
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
                if g[k + 1].abs() <= self.krylov_tolerance * b_norm || iterations >= max_iterations
                {
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
            self.precondition(preconditioner, &mut work);
            for i in 0..n {
                x[i] += work[(i, 0)];
            }
        }
        if !converged {
            self.matvec(values, &x, &mut ax);
            converged = distance(b, &ax) <= self.krylov_tolerance.max(1e-10) * b_norm;
        }
        self.krylov.basis = basis;
        self.krylov.work = work;
        self.krylov.r = r;
        self.krylov.ax = ax;
        let finite = self.finish_krylov(iterations, x);
        Ok(converged && finite)
    }

    /// Conjugate gradients preconditioned by the inverted 3x3 diagonal
    /// blocks (already in `self.krylov.blocks`), for symmetric positive
    /// definite `A`: to `|b - A x| <= tolerance |b|` in at most
    /// `max_iterations`. The solution is left in `self.rhs`; `false` when
    /// it has not converged (or `A` showed a non-positive curvature).
    fn pcg(
        &mut self,
        values: &[f64],
        b: &[f64],
        preconditioner: Preconditioner,
        tolerance: f64,
        max_iterations: usize,
    ) -> bool {
        let n = self.dimension();
        let b_norm = norm(b);
        let mut x = std::mem::take(&mut self.krylov.x);
        x.clear();
        x.resize(n, 0.0);
        let mut r = std::mem::take(&mut self.krylov.r);
        r.clear();
        r.extend_from_slice(b);
        let mut p = std::mem::take(&mut self.krylov.z);
        let mut ap = std::mem::take(&mut self.krylov.ax);
        ap.resize(n, 0.0);
        let mut z = std::mem::take(&mut self.krylov.symmetric_part);
        z.resize(n, 0.0);
        let mut converged = b_norm == 0.0;
        let mut iterations = 0;
        if !converged {
            self.precondition_slice(preconditioner, &r, &mut z);
            p.clear();
            p.extend_from_slice(&z);
            let mut rz = dot(&r, &z);
            while iterations < max_iterations {
                self.matvec(values, &p, &mut ap);
                let pap = dot(&p, &ap);
                if pap.is_nan() || pap <= 0.0 {
                    break;
                }
                let alpha = rz / pap;
                for i in 0..n {
                    x[i] += alpha * p[i];
                    r[i] -= alpha * ap[i];
                }
                iterations += 1;
                if norm(&r) <= tolerance * b_norm {
                    converged = true;
                    break;
                }
                self.precondition_slice(preconditioner, &r, &mut z);
                let rz_new = dot(&r, &z);
                let beta = rz_new / rz;
                rz = rz_new;
                for i in 0..n {
                    p[i] = z[i] + beta * p[i];
                }
            }
        }
        let finite = self.finish_krylov(iterations, x);
        self.krylov.r = r;
        self.krylov.z = p;
        self.krylov.ax = ap;
        self.krylov.symmetric_part = z;
        converged && finite
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
    /// write of fresh memory is slow here: about 0.3 s for the 250 MB of a
    /// million elements).
    pub fn solve_mass(&mut self, values: &[f64], rhs: &mut [f64]) -> Result<(), LinearSolveError> {
        self.blocks_current = self.uses_multigrid() && self.load_finest_blocks(values);
        let solved = self.factor_block_jacobi(values)
            && self.pcg(values, rhs, Preconditioner::BlockJacobi, 1e-14, 1000);
        self.blocks_current = false;
        if solved {
            self.stats.solves += 1;
            for (i, x) in rhs.iter_mut().enumerate() {
                *x = self.rhs[(i, 0)];
            }
            return Ok(());
        }
        self.solve(values, true, rhs).map(|_| ())
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
        if self.multigrid.is_none()
            && let Some((ptr, rows)) = &self.node_graph
        {
            self.multigrid = Some(Multigrid::new(ptr, rows));
        }
        let Some(mg) = self.multigrid.as_mut() else {
            return false;
        };
        let Some(finest) = mg.finest.as_mut() else {
            return false;
        };
        Multigrid::gather(&mg.source, values, &mut finest.vals);
        true
    }

    /// Records a Krylov solve's iterations, leaves its solution `x` in
    /// `self.rhs` (keeping the buffer) and tells whether it is finite.
    fn finish_krylov(&mut self, iterations: usize, x: Vec<f64>) -> bool {
        self.last_krylov_iterations = iterations;
        self.stats.krylov_iterations += iterations;
        for (i, v) in x.iter().enumerate() {
            self.rhs[(i, 0)] = *v;
        }
        let finite = x.iter().all(|v| v.is_finite());
        self.krylov.x = x;
        finite
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
        self.stats.lu_factorizations += 1;
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

    /// The product by columns in two halves (on two threads where the
    /// helper is available) equals the plain column-by-column sum to
    /// round-off, zero entries of `x` included, and a second product with
    /// the helper's buffer in use gives the same bits.
    #[test]
    fn products_by_columns_in_halves_equal_the_plain_sum() {
        let n = 301;
        let (cp, ri, v) = tridiagonal(n, 0.3);
        let solver = LinearSolver::new(&cp, &ri).unwrap();
        let x: Vec<f64> = (0..n)
            .map(|i| {
                if i % 7 == 0 {
                    0.0
                } else {
                    (i as f64 * 0.61).sin()
                }
            })
            .collect();
        let mut expected = vec![0.0; n];
        for c in 0..n {
            for k in cp[c]..cp[c + 1] {
                expected[ri[k]] += v[k] * x[c];
            }
        }
        let mut out = vec![f64::NAN; n];
        solver.matvec(&v, &x, &mut out);
        for (o, e) in out.iter().zip(&expected) {
            assert!((o - e).abs() <= 1e-15 * e.abs().max(1.0), "{o} {e}");
        }
        // Again, the helper's buffer now in use.
        let mut again = vec![f64::NAN; n];
        solver.matvec(&v, &x, &mut again);
        assert_eq!(out, again);
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
}
