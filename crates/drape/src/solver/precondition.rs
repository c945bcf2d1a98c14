//! Preconditioners of the Krylov methods and the operator that pairs one
//! with the products by `A` ([`Preconditioned`], a [`krylov::Operator`]):
//!
//! * block Jacobi, `P = D`, the 3x3 diagonal blocks, inverted once per
//!   matrix ([`BlockJacobi`]);
//! * a V-cycle of the smoothed-aggregation multigrid of [`super::amg`],
//!   with the glue that feeds it ([`Multigrid`]): the Hessian gathered
//!   into 3x3 blocks, the hierarchy kept across solves and rebuilt when it
//!   stops serving;
//! * a Cholesky factor ([`super::direct::Cholesky`]) of the matrix's
//!   symmetric part or of an earlier matrix.

use super::amg::{Amg, BlockCsr};
use super::direct::{Cholesky, Scratch};
use super::krylov;
use super::pattern::gather_block;
use super::product::Product;
use crate::block3::{Block, invert, mul_vec};
use faer::sparse::SymbolicSparseColMatRef;
use faer::{Mat, Par};

/// What preconditions the Krylov iterations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Preconditioner {
    /// The kept Cholesky factor.
    Cholesky,
    /// Inverted 3x3 diagonal blocks.
    BlockJacobi,
    /// A V-cycle of the smoothed-aggregation multigrid.
    Multigrid,
}

/// The block-Jacobi preconditioner: the inverted 3x3 diagonal blocks.
#[derive(Debug, Default)]
pub(super) struct BlockJacobi {
    blocks: Vec<Block>,
}

impl BlockJacobi {
    /// Inverts the 3x3 diagonal blocks of `values` on `pattern`; `false`
    /// if one is singular.
    pub(super) fn factorize(
        &mut self,
        pattern: SymbolicSparseColMatRef<'_, usize>,
        values: &[f64],
    ) -> bool {
        let n = pattern.nrows();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let blocks = &mut self.blocks;
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
        ok
    }

    /// `z = D^-1 r` (a trailing partial block, never met with 3 unknowns
    /// per node, acts on the entries there are).
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        for (i, m) in self.blocks.iter().enumerate() {
            let o = 3 * i;
            let len = (r.len() - o).min(3);
            let mut v = [0.0; 3];
            v[..len].copy_from_slice(&r[o..o + len]);
            let t = mul_vec(m, &v);
            z[o..o + len].copy_from_slice(&t[..len]);
        }
    }
}

/// The multigrid path: the Hessian in 3x3 blocks by rows (its structure
/// kept, values gathered per solve) and the hierarchy built from it.
///
/// Building the hierarchy (aggregation, Galerkin products) costs about as
/// much as ten V-cycles, so it is kept across Newton iterations and steps
/// — only the finest level's matrix and smoother follow each new Hessian
/// — and rebuilt when a solve needs more than half as many iterations
/// again as the first one after the last build.
pub(super) struct Multigrid {
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
    /// The matrix (scalar CSC values) the hierarchy was last built from:
    /// with the counters above, all a resumed run needs to rebuild the
    /// same hierarchy ([`KeptMultigrid`]).
    built_from: Vec<f64>,
}

/// What the multigrid path carries from one solve to the next that later
/// solutions depend on: the matrix its hierarchy was built from and the
/// counters that decide when it is rebuilt. A checkpoint stores it, so
/// that a resumed run rebuilds the same hierarchy and goes on bit for bit.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct KeptMultigrid {
    /// The scalar CSC values the hierarchy was built from; `None` before
    /// the first hierarchy (or after one could not be built).
    pub built_from: Option<Vec<f64>>,
    /// Krylov iterations of the first solve after the last build
    /// (`usize::MAX` before it).
    pub fresh_iterations: usize,
    /// Krylov iterations of the last solve (`usize::MAX`: none, or failed).
    pub last_iterations: usize,
    /// Solves still left to the fallback.
    pub skip: usize,
}

impl Multigrid {
    /// The multigrid path for the pattern of 3x3 node blocks with node
    /// graph `(node_ptr, node_rows)`, before any hierarchy.
    pub(super) fn new(node_ptr: &[usize], node_rows: &[usize]) -> Self {
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
            built_from: Vec::new(),
        }
    }

    /// The state a checkpoint keeps ([`KeptMultigrid`]).
    pub(super) fn kept(&self) -> KeptMultigrid {
        KeptMultigrid {
            built_from: self.amg.is_some().then(|| self.built_from.clone()),
            fresh_iterations: self.fresh_iterations,
            last_iterations: self.last_iterations,
            skip: self.skip,
        }
    }

    /// Restores a kept state: the hierarchy rebuilt from the matrix it was
    /// built from (the pattern's scalar values; not counted as a build),
    /// and the counters. `false` when no hierarchy can be built from it.
    pub(super) fn restore(&mut self, kept: &KeptMultigrid) -> bool {
        if let Some(values) = &kept.built_from {
            let mut finest = match (self.finest.take(), self.amg.take()) {
                (Some(f), _) => f,
                (None, Some(amg)) => amg.into_finest(),
                (None, None) => return false,
            };
            Self::gather(&self.source, values, &mut finest.vals);
            match Amg::new(finest) {
                Ok(amg) => self.amg = Some(amg),
                Err(finest) => {
                    self.finest = Some(finest);
                    return false;
                }
            }
            self.built_from.clone_from(values);
        }
        self.fresh_iterations = kept.fresh_iterations;
        self.last_iterations = kept.last_iterations;
        self.skip = kept.skip;
        true
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

    /// Copies `values` into the finest level's blocks while no hierarchy
    /// holds them (before the first build); `false` once one does.
    pub(super) fn load_finest(&mut self, values: &[f64]) -> bool {
        let Some(finest) = self.finest.as_mut() else {
            return false;
        };
        Self::gather(&self.source, values, &mut finest.vals);
        true
    }

    /// The finest matrix in 3x3 blocks: the hierarchy's, or before the
    /// first build the one [`Self::load_finest`] filled.
    fn blocks(&self) -> Option<&BlockCsr> {
        self.amg.as_ref().map(Amg::finest).or(self.finest.as_ref())
    }

    /// Hierarchies built so far.
    pub(super) fn builds(&self) -> usize {
        self.builds
    }

    /// Whether this solve is left to the fallback (counting it down)
    /// after a fresh hierarchy failed.
    pub(super) fn skips_this_solve(&mut self) -> bool {
        if self.skip > 0 {
            self.skip -= 1;
            return true;
        }
        false
    }

    /// Leaves the next solves to the fallback (a fresh hierarchy failed).
    pub(super) fn back_off(&mut self, solves: usize) {
        self.skip = solves;
    }

    /// Makes the preconditioner for `values`: the kept hierarchy with the
    /// new finest matrix while it serves, a new one otherwise (counted in
    /// `builds`). `false` if none can be built.
    pub(super) fn setup(&mut self, values: &[f64], builds: &mut usize) -> bool {
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
        self.built_from.clear();
        self.built_from.extend_from_slice(values);
        self.builds += 1;
        *builds += 1;
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

    /// Records the iterations of a solve with the current hierarchy
    /// (`usize::MAX` when it failed).
    pub(super) fn record(&mut self, iterations: usize) {
        self.last_iterations = iterations;
        if self.fresh_iterations == usize::MAX {
            self.fresh_iterations = iterations;
        }
    }
}

/// The preconditioners' state kept between solves.
#[derive(Default)]
pub(super) struct Preconditioners {
    pub(super) block_jacobi: BlockJacobi,
    /// The multigrid path (iterative mode, node-block patterns), made on
    /// first use.
    pub(super) multigrid: Option<Multigrid>,
    /// A copy of the column GMRES preconditions in place (the slice
    /// preconditioners read it while they write the column).
    column: Vec<f64>,
}

impl Preconditioners {
    /// The multigrid path, made on first use for the node graph
    /// `node_graph` (`None` without one).
    pub(super) fn multigrid(
        &mut self,
        node_graph: Option<&(Vec<usize>, Vec<usize>)>,
    ) -> Option<&mut Multigrid> {
        if self.multigrid.is_none()
            && let Some((ptr, rows)) = node_graph
        {
            self.multigrid = Some(Multigrid::new(ptr, rows));
        }
        self.multigrid.as_mut()
    }
}

/// A matrix and its preconditioner, borrowed from the linear solver's
/// parts for the length of one Krylov solve.
pub(super) struct Preconditioned<'a> {
    /// The matrix's values on `pattern`.
    pub(super) values: &'a [f64],
    pub(super) pattern: SymbolicSparseColMatRef<'a, usize>,
    pub(super) product: &'a Product,
    /// Whether the multigrid's finest blocks hold `values` (products then
    /// use them).
    pub(super) blocks_current: bool,
    pub(super) kind: Preconditioner,
    pub(super) preconditioners: &'a mut Preconditioners,
    pub(super) cholesky: &'a Cholesky,
    pub(super) scratch: &'a mut Scratch,
    pub(super) par: Par,
}

impl krylov::Operator for Preconditioned<'_> {
    fn apply(&mut self, x: &[f64], out: &mut [f64]) {
        if self.blocks_current
            && let Some(blocks) = self
                .preconditioners
                .multigrid
                .as_ref()
                .and_then(Multigrid::blocks)
        {
            blocks.matvec(x, out);
            return;
        }
        self.product.apply(self.pattern, self.values, x, out);
    }

    fn precondition(&mut self, r: &[f64], z: &mut [f64]) {
        match self.kind {
            Preconditioner::Multigrid => {
                let amg = self.preconditioners.multigrid.as_mut();
                if let Some(amg) = amg.and_then(|m| m.amg.as_mut()) {
                    amg.apply(r, z);
                } else {
                    z.copy_from_slice(r);
                }
            }
            Preconditioner::BlockJacobi => self.preconditioners.block_jacobi.apply(r, z),
            Preconditioner::Cholesky => {
                let mut x = Mat::from_fn(r.len(), 1, |i, _| r[i]);
                self.cholesky.solve_in_place(&mut x, self.par, self.scratch);
                z.copy_from_slice(x.col_as_slice_mut(0));
            }
        }
    }

    fn precondition_in_place(&mut self, x: &mut Mat<f64>) {
        if self.kind == Preconditioner::Cholesky {
            self.cholesky.solve_in_place(x, self.par, self.scratch);
            return;
        }
        let mut r = std::mem::take(&mut self.preconditioners.column);
        r.clear();
        r.extend_from_slice(x.col_as_slice_mut(0));
        self.precondition(&r, x.col_as_slice_mut(0));
        self.preconditioners.column = r;
    }
}
