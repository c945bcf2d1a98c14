//! The compact preconditioner of the projected Newton's systems: the
//! factor of the Hessian's *compact part* — its couplings between nodes
//! that share a triangle — with every farther coupling moved onto the
//! diagonal, preconditioning conjugate gradients on the whole Hessian.
//!
//! Bending's stencils (docs/theory.md §1.10) couple nodes up to four
//! edges apart, and a factor of the whole pattern fills accordingly
//! (issue 42: 2.7 times the flops of the membrane's pattern on the
//! settle benchmark). The compact part has the membrane's pattern. A
//! dropped coupling `B` between nodes `a` and `b` (a 3x3 block and its
//! transpose) is replaced by `|B|_F I` added to both diagonal blocks:
//!
//! ```text
//! [ |B| I    -B   ]
//! [ -B^T   |B| I  ]   is positive semi-definite (|B|_F >= |B|_2),
//! ```
//!
//! so the preconditioner `M = A_compact + D >= A` — positive definite
//! whenever `A` is, and the eigenvalues of `M^-1 A` lie in `(0, 1]`:
//! conjugate gradients converge, and a factorisation of `M` that fails
//! says that `A` is not positive definite either.
//!
//! `M` is factorised by the node-block `L D L^T` ([`super::block_lu`])
//! up to [`BLOCK_LU_MAX`] unknowns, by faer's supernodal Cholesky above.

use super::block_lu::BlockLu;
use super::direct::{Cholesky, Scratch};
use super::linear_error::SolveFailure;
use super::pattern::{SparsePattern, block_layout as layout};
use faer::sparse::SymbolicSparseColMat;
use faer::{Mat, Par};

/// Largest system (unknowns) whose compact part the node-block `L D L^T`
/// factorises; faer's Cholesky above (the same bound as the whole
/// Hessian's, `linear::BLOCK_LU_MAX_SYMMETRIC`).
const BLOCK_LU_MAX: usize = 5_000;

/// How the compact part is factorised.
enum Factor {
    /// Not yet analysed.
    None,
    BlockLu(Box<BlockLu>),
    Cholesky(Box<CholeskyFactor>),
}

/// faer's Cholesky of the compact part, with its pattern and work space.
struct CholeskyFactor {
    pattern: SymbolicSparseColMat<usize>,
    cholesky: Cholesky,
    scratch: Scratch,
    column: Mat<f64>,
}

/// The compact part's pattern, where its values come from in the whole
/// Hessian, its factor.
pub(super) struct Compact {
    compact: SparsePattern,
    /// Per 3x3 block of the compact pattern: its layout `(base, stride)`
    /// in the whole Hessian's values, then in the compact values.
    near: Vec<[usize; 4]>,
    /// Per coupling outside the compact pattern, below the diagonal: its
    /// layout in the whole Hessian's values, and the compact diagonal
    /// blocks' layouts of its row node and its column node.
    far: Vec<[usize; 6]>,
    values: Vec<f64>,
    factor: Factor,
}

impl Compact {
    /// The compact part `compact` of the whole Hessian's node graph
    /// `(ptr, rows)`, which must hold it.
    pub(super) fn new(compact: SparsePattern, ptr: &[usize], rows: &[usize]) -> Self {
        let (cptr, _) = compact.node_graph();
        let cptr = cptr.to_vec();
        let mut near = Vec::new();
        let mut far = Vec::new();
        for b in 0..ptr.len() - 1 {
            for (p, &a) in rows.iter().enumerate().take(ptr[b + 1]).skip(ptr[b]) {
                let (fb, fs) = layout(ptr, p, b);
                if let Some(q) = compact.node_block(a, b) {
                    let (cb, cs) = layout(&cptr, q, b);
                    near.push([fb, fs, cb, cs]);
                } else if a > b {
                    let qa = compact.node_block(a, a).expect("a diagonal block");
                    let qb = compact.node_block(b, b).expect("a diagonal block");
                    let (da, sa) = layout(&cptr, qa, a);
                    let (db, sb) = layout(&cptr, qb, b);
                    far.push([fb, fs, da, sa, db, sb]);
                }
            }
        }
        let values = vec![0.0; compact.nnz()];
        Self {
            compact,
            near,
            far,
            values,
            factor: Factor::None,
        }
    }

    /// The compact part's pattern.
    pub(super) fn pattern(&self) -> &SparsePattern {
        &self.compact
    }

    /// Whether the node-block `L D L^T` factorises `M` (else Cholesky).
    pub(super) fn uses_block_lu(&self) -> bool {
        self.compact.dimension() <= BLOCK_LU_MAX
    }

    /// Couplings outside the compact part (each counted once).
    pub(super) fn far_blocks(&self) -> usize {
        self.far.len()
    }

    /// `M = A_compact + D` from the whole Hessian's values `full`
    /// (module docs).
    fn gather(&mut self, full: &[f64]) {
        let v = &mut self.values;
        for &[fb, fs, cb, cs] in &self.near {
            for j in 0..3 {
                for i in 0..3 {
                    v[cb + j * cs + i] = full[fb + j * fs + i];
                }
            }
        }
        for &[fb, fs, da, sa, db, sb] in &self.far {
            let mut s = 0.0;
            for j in 0..3 {
                for i in 0..3 {
                    let x = full[fb + j * fs + i];
                    s += x * x;
                }
            }
            let s = s.sqrt();
            for i in 0..3 {
                v[da + i * sa + i] += s;
                v[db + i * sb + i] += s;
            }
        }
    }

    /// Factorises `M` of the whole Hessian `full`; `Ok(false)` when it is
    /// not positive definite (nor then is `A`).
    pub(super) fn factorize(&mut self, full: &[f64]) -> Result<bool, SolveFailure> {
        self.gather(full);
        if matches!(self.factor, Factor::None) {
            let n = self.compact.dimension();
            self.factor = if n <= BLOCK_LU_MAX {
                let (ptr, rows) = self.compact.node_graph();
                Factor::BlockLu(Box::new(
                    BlockLu::new(ptr, rows).map_err(SolveFailure::BlockLu)?,
                ))
            } else {
                let pattern = SymbolicSparseColMat::new_checked(
                    n,
                    n,
                    self.compact.col_ptr.clone(),
                    None,
                    self.compact.row_idx.clone(),
                );
                let mut cholesky = Cholesky::default();
                cholesky.analyse(pattern.as_ref())?;
                Factor::Cholesky(Box::new(CholeskyFactor {
                    pattern,
                    cholesky,
                    scratch: Scratch::default(),
                    column: Mat::zeros(n, 1),
                }))
            };
        }
        let factored = match &mut self.factor {
            Factor::None => false,
            Factor::BlockLu(lu) => lu.factorize(&self.values, true).is_ok() && lu.pivots_positive(),
            Factor::Cholesky(c) => {
                c.cholesky
                    .factorize(c.pattern.as_ref(), &self.values, Par::Seq, &mut c.scratch)
            }
        };
        Ok(factored)
    }

    /// `z = M^-1 r` with the last factor.
    pub(super) fn apply(&mut self, r: &[f64], z: &mut [f64]) {
        match &mut self.factor {
            Factor::None => z.copy_from_slice(r),
            Factor::BlockLu(lu) => {
                z.copy_from_slice(r);
                lu.solve_in_place(z);
            }
            Factor::Cholesky(c) => {
                c.column.col_as_slice_mut(0).copy_from_slice(r);
                c.cholesky
                    .solve_in_place(&mut c.column, Par::Seq, &mut c.scratch);
                z.copy_from_slice(c.column.col_as_slice(0));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric positive definite matrix on the pattern of a grid's
    /// triangles widened by couplings two nodes apart, with its compact
    /// part the grid's own pattern: `M - A` is positive semi-definite.
    #[test]
    fn the_compact_preconditioner_bounds_the_matrix_from_above() {
        let (full, compact) = SparsePattern::wide_grid(4, 3);
        let nodes = full.dimension() / 3;
        let n = 3 * nodes;
        // A = B^T B + I on the full pattern: a random B with the pattern's
        // block structure would fill beyond it, so take A itself random
        // and symmetric, with a dominant diagonal.
        let mut values = vec![0.0; full.nnz()];
        let mut seed = 12345u64;
        let mut rand = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        for c in 0..n {
            for k in full.col_ptr[c]..full.col_ptr[c + 1] {
                let r = full.row_idx[k];
                if r > c {
                    let v = rand();
                    values[k] = v;
                    values[full.transpose_of(k)] = v;
                }
            }
        }
        for d in 0..n {
            values[full.diagonal_of(d)] = 30.0;
        }
        let (ptr, rows) = full.node_graph();
        let mut pc = Compact::new(compact.clone(), ptr, rows);
        assert!(pc.far_blocks() > 0);
        assert!(pc.factorize(&values).unwrap());
        // M - A, dense, must have no negative eigenvalue.
        let mut diff = faer::Mat::<f64>::zeros(n, n);
        for c in 0..n {
            for k in full.col_ptr[c]..full.col_ptr[c + 1] {
                diff[(full.row_idx[k], c)] -= values[k];
            }
            for k in compact.col_ptr[c]..compact.col_ptr[c + 1] {
                diff[(compact.row_idx[k], c)] += pc.values[k];
            }
        }
        let eig = diff.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
        let smallest = eig.iter().cloned().fold(f64::INFINITY, f64::min);
        assert!(smallest > -1e-12, "M - A has eigenvalue {smallest}");
        // And M^-1 solves M: apply to M x.
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut mx = vec![0.0; n];
        for c in 0..n {
            for k in compact.col_ptr[c]..compact.col_ptr[c + 1] {
                mx[compact.row_idx[k]] += pc.values[k] * x[c];
            }
        }
        let mut z = vec![0.0; n];
        pc.apply(&mx, &mut z);
        let err = crate::vecn::distance(&z, &x) / crate::vecn::norm(&x);
        assert!(err < 1e-12, "M^-1 M x differs from x by {err}");
    }
}
