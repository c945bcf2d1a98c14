//! Sparse LU factorisation in 3x3 node blocks, without pivoting between
//! nodes, for the Hessians of membranes.
//!
//! The Hessian of a positional membrane model has one 3x3 block per pair
//! of nodes that share an element, and a structurally symmetric pattern
//! whatever its values: the wrinkling tangent and the follower pressure
//! make it non-symmetric, never its pattern. This module factorises such a
//! matrix, permuted by an approximate minimum degree ordering of the node
//! graph (`P A P^T`), as
//!
//! ```text
//! P A P^T = L~ U,   L~ = L D   (L unit lower, D block diagonal),   U unit upper,
//! ```
//!
//! with 3x3 blocks throughout, by a left-looking column algorithm:
//!
//! ```text
//! L~_ij = A_ij - sum_{k<j} L~_ik U_kj                  (i >= j; L~_jj = D_j)
//! U_ji  = D_j^-1 (A_ji - sum_{k<j} L~_jk U_ki)          (i > j)
//! ```
//!
//! The pattern of `L` is that of `U^T` (the pattern of `A` is symmetric),
//! computed once by the elimination tree. For a symmetric matrix the second
//! line is `U_ji = D_j^-1 L~_ij^T` and costs nothing extra: the
//! factorisation is then a block `L D L^T`, half the work.
//!
//! Only the 3x3 diagonal blocks `D_j` are inverted (with a check of their
//! conditioning): no pivoting between nodes. That is stable for the
//! matrices it is meant for — symmetric positive definite ones, and
//! non-symmetric ones whose symmetric part is positive definite
//! (`M / (beta dt^2)` plus a tangent stiffness, as in dynamics), for which
//! Gaussian elimination without pivoting has a bounded growth factor. A
//! pivot block that is singular or that has lost all but `1e-10` of the
//! diagonal it started from reports [`BlockLuError::Pivot`], and the
//! caller answers with a pivoting factorisation; the caller also checks
//! every solution's residual.
//!
//! Why not faer's sparse LU: its partial pivoting and column ordering cost
//! about 8 times its Cholesky (docs/performance.md, "Where the time
//! goes"); this factorisation reuses one
//! symbolic analysis for symmetric and non-symmetric values alike, works
//! on 3x3 blocks (27 multiply–adds per block update, no index arithmetic
//! per scalar), and at the sizes where one factorisation per Newton
//! iteration is affordable it is faster than faer's Cholesky, whose fixed
//! costs dominate small matrices (docs/performance.md).
//!
//! The files follow the two levels of the factorisation and its use:
//! `symbolic` (the orderings, the value sources, the pattern of `L`; once
//! per pattern), `factor` (the numeric factorisation and its block
//! kernels; once per matrix), `solve` (the substitutions; once per
//! right-hand side). This file holds the types they share and the public
//! [`BlockLu`].

mod factor;
mod solve;
mod symbolic;

use super::pattern::gather_block;
use crate::block3::Block;
use factor::Job;
use symbolic::{amd_order, bisect};

/// Why a numeric factorisation stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BlockLuError {
    /// A pivot block is singular or has cancelled to nothing.
    #[error("the pivot block of node {node} is singular or cancelled (no pivoting between nodes)")]
    Pivot {
        /// The (original) node index of the pivot.
        node: usize,
    },
    /// The node graph is not symmetric: node `row` is in column
    /// `column`, but `column` is not in column `row`.
    #[error(
        "the node graph is not symmetric: node {row} couples to node {column}, but not node {column} to node {row}"
    )]
    NotSymmetric {
        /// A node of the column.
        row: usize,
        /// The column.
        column: usize,
    },
    /// The fill-reducing ordering failed.
    #[error("the minimum degree ordering failed: {0}")]
    Ordering(super::faer_failure::FaerFailure),
}

/// Where block `(I, J)` of the permuted matrix sits in the scalar CSC
/// values: `values[base + 3 j + ... ]`, see [`BlockLu::gather`].
#[derive(Debug, Clone, Copy)]
struct Source {
    /// Permuted block row.
    row: u32,
    /// Value index of the block's entry (0, 0).
    base: usize,
    /// Value-index distance between the block's columns.
    stride: usize,
}

/// The symbolic analysis of one pattern: the ordering, the pattern of `L`
/// and where the blocks of `A` lie in the scalar values.
#[derive(Debug, Clone)]
struct Symbolic {
    /// `perm[new] = old` node.
    perm: Vec<usize>,
    /// Strictly lower pattern of `L` by block column (permuted indices,
    /// sorted); also the pattern of `U^T`.
    l_ptr: Vec<usize>,
    l_rows: Vec<u32>,
    /// Per permuted column `J`: the blocks `A_IJ` with `I >= J`.
    col_src_ptr: Vec<usize>,
    col_src: Vec<Source>,
    /// Per permuted column `J`: the blocks `A_JI` with `I > J`.
    row_src_ptr: Vec<usize>,
    row_src: Vec<Source>,
    /// `(a, b)`: columns `0..a` and `a..b` are two parts that share no
    /// entry of `L` (neither is coupled to the other but through the
    /// separator `b..n`); `(0, 0)` when the ordering is not split.
    split: (usize, usize),
}

/// A 3x3 block padded to four rows, stored by columns: entry `(r, c)` at
/// `4 c + r`, the fourth row zero. A column is then one 256-bit vector
/// and two columns one 512-bit vector: the block products of the
/// factorisation run as three broadcasts and six fused multiply–adds per
/// block (`factor::updates`), against nine multiplies of three-wide vectors
/// and their shuffles for a 3x3 row-major block. The factor's `U` blocks
/// and the row accumulators hold the transpose (entry `(r, c)` at
/// `4 r + c`), so that the row updates are the same product.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
struct Padded([f64; 12]);

const ZERO: Padded = Padded([0.0; 12]);

impl Padded {
    /// From a row-major block, by columns (`transposed`: its transpose).
    #[inline(always)]
    fn new(m: &Block, transposed: bool) -> Self {
        let mut p = ZERO;
        for r in 0..3 {
            for c in 0..3 {
                let (i, j) = if transposed { (c, r) } else { (r, c) };
                p.0[4 * j + i] = m[3 * r + c];
            }
        }
        p
    }

    /// The row-major block (`transposed`: of the transpose).
    #[inline(always)]
    fn block(&self, transposed: bool) -> Block {
        let mut m = [0.0; 9];
        for r in 0..3 {
            for c in 0..3 {
                let (i, j) = if transposed { (c, r) } else { (r, c) };
                m[3 * r + c] = self.0[4 * j + i];
            }
        }
        m
    }

    fn max_abs(&self) -> f64 {
        self.0.iter().fold(0.0f64, |a, v| a.max(v.abs()))
    }
}

/// The accumulators of one thread: a column and a row of the active
/// submatrix, and the linked lists of the columns `k` whose next row is
/// `j` (`head[j]`).
#[derive(Debug, Clone)]
struct Work {
    x_col: Vec<Padded>,
    x_row: Vec<Padded>,
    head: Vec<u32>,
}

impl Work {
    fn new(n: usize) -> Self {
        Self {
            x_col: vec![ZERO; n],
            x_row: vec![ZERO; n],
            head: vec![NONE; n],
        }
    }
}

/// The bounds a split ordering must meet, tried in turn: the longer path
/// (a half, then the separator) at most this share of AMD's work, and the
/// total at most this share of it.
const SPLIT_BOUNDS: [(f64, f64); 2] = [(0.7, 1.2), (0.85, 1.5)];

/// What the columns of one part subtract from the separator's columns,
/// `sum_k L~_ik U_kj` over the part's `k` (negated), by the positions of
/// `L`'s separator columns.
#[derive(Debug, Clone)]
struct Contribution {
    diag: Vec<Padded>,
    col: Vec<Padded>,
    row: Vec<Padded>,
}

/// The numeric arrays of a range of columns (`c0..`, whose entries of `L`
/// start at position `q0`), borrowed apart from the other ranges'.
struct Columns<'a> {
    c0: usize,
    q0: usize,
    l: &'a mut [Padded],
    u: &'a mut [Padded],
    d_inv: &'a mut [Block],
    next: &'a mut [u32],
    cursor: &'a mut [usize],
}

/// Symbolic analysis and numeric storage of the block LU of one pattern.
#[derive(Debug, Clone)]
pub struct BlockLu {
    sym: Symbolic,
    /// `L~_ij` by position in `l_rows`.
    l: Vec<Padded>,
    /// `U_ji` (row `j`, column `i = l_rows[q]`) by position `q`, stored
    /// transposed (see [`Padded`]).
    u: Vec<Padded>,
    /// `D_j^-1`.
    d_inv: Vec<Block>,
    /// Per column `k`: the next entry of `L` to use, and the next column
    /// in the list of that entry's row.
    next: Vec<u32>,
    cursor: Vec<usize>,
    /// Accumulators of the first part and the separator, and of the
    /// second part.
    work: Work,
    work_b: Work,
    /// The two parts' updates of the separator.
    contribution: [Contribution; 2],
    /// Solve work (permuted right-hand side).
    rhs: Vec<[f64; 3]>,
    /// The second half's updates of the separator's rows in a solve.
    rhs_separator: Vec<[f64; 3]>,
    /// Multiply–adds of one symmetric / non-symmetric factorisation.
    flops: (f64, f64),
}

const NONE: u32 = u32::MAX;

impl BlockLu {
    /// Analyses the node graph `(node_ptr, node_rows)` (CSC, symmetric,
    /// diagonal included, rows sorted) of a matrix whose scalar CSC values
    /// follow [`super::pattern::SparsePattern`]'s layout: the value index
    /// of entry `(3a + i, 3b + j)`, with `p` the position of `a` in column
    /// `b`, is `9 ptr[b] + 3 j deg(b) + 3 (p - ptr[b]) + i`.
    ///
    /// The ordering is approximate minimum degree (AMD) on the node graph.
    /// From 100 nodes on (`SPLIT_MIN_NODES`), the graph is also cut in two by
    /// a level set of a breadth-first search from a peripheral node, and
    /// AMD's order is kept within each half and the separator, which goes
    /// last (nested dissection at the top level only). The two halves
    /// then factorise independently, on two threads
    /// ([`crate::par::join`]). The split is kept when it leaves the
    /// longer of the two paths (a half, then the separator) at most 70 %
    /// of AMD's work and adds at most 20 % to the total (the pedestal's
    /// counts: docs/performance.md, "The round before"); where no cut
    /// does, at most 85 % and 50 % (`SPLIT_BOUNDS`: bending's wide
    /// stencils, whose level-set separators are wide). Whether it is
    /// split depends on the graph alone, never on the machine, so results
    /// do not either.
    pub fn new(node_ptr: &[usize], node_rows: &[usize]) -> Result<Self, BlockLuError> {
        let n = node_ptr.len() - 1;
        let (perm, perm_inv) = amd_order(node_ptr, node_rows)?;
        let mut sym = Symbolic::new(node_ptr, node_rows, perm, &perm_inv, (0, 0))?;
        let serial = sym.flops(0..n).1;
        let mut cuts = Vec::new();
        for (perm, split) in bisect(node_ptr, node_rows, &sym.perm) {
            let mut inv = vec![0; n];
            for (new, &old) in perm.iter().enumerate() {
                inv[old] = new;
            }
            let cut = Symbolic::new(node_ptr, node_rows, perm, &inv, split)?;
            let (a, b) = split;
            let path = cut.flops(0..a).1.max(cut.flops(a..b).1) + cut.flops(b..n).1;
            let total = cut.flops(0..n).1;
            cuts.push((cut, path, total));
        }
        // The strict bounds first; where no cut meets them (a wide
        // separator, as bending's twelve-node stencils make: issue 42), the
        // looser ones, which still shorten the longer path by 15 %.
        for (path_share, work_share) in SPLIT_BOUNDS {
            let mut best = path_share * serial;
            let mut chosen = None;
            for (k, (_, path, total)) in cuts.iter().enumerate() {
                if *path <= best && *total <= work_share * serial {
                    best = *path;
                    chosen = Some(k);
                }
            }
            if let Some(k) = chosen {
                sym = cuts.swap_remove(k).0;
                break;
            }
        }
        let nnz = sym.l_rows.len();
        let separator = n - sym.split.1;
        let separator_nnz = nnz - sym.l_ptr[sym.split.1];
        let split = sym.split != (0, 0);
        // (Unused, and empty, when the ordering is not split.)
        let (separator, separator_nnz) = if split {
            (separator, separator_nnz)
        } else {
            (0, 0)
        };
        let contribution = || Contribution {
            diag: vec![ZERO; separator],
            col: vec![ZERO; separator_nnz],
            row: vec![ZERO; separator_nnz],
        };
        Ok(Self {
            flops: sym.flops(0..n),
            l: vec![ZERO; nnz],
            u: vec![ZERO; nnz],
            d_inv: vec![[0.0; 9]; n],
            next: vec![NONE; n],
            cursor: vec![0; n],
            work: Work::new(n),
            work_b: Work::new(if split { n } else { 0 }),
            contribution: [contribution(), contribution()],
            rhs: vec![[0.0; 3]; n],
            rhs_separator: vec![[0.0; 3]; separator],
            sym,
        })
    }

    /// Number of nodes (block rows).
    pub fn nodes(&self) -> usize {
        self.sym.nodes()
    }

    /// Blocks stored in `L` (strictly lower; `U` has as many).
    pub fn factor_blocks(&self) -> usize {
        self.sym.l_rows.len()
    }

    /// Whether the ordering is split in two halves that factorise on two
    /// threads (see [`BlockLu::new`]).
    pub fn is_split(&self) -> bool {
        self.sym.split != (0, 0)
    }

    /// Multiply–adds of one numeric factorisation (symmetric values: half).
    pub fn flops(&self, symmetric: bool) -> f64 {
        if symmetric {
            self.flops.0
        } else {
            self.flops.1
        }
    }

    /// Bytes held by the factor and its work arrays.
    pub fn bytes(&self) -> usize {
        let (block, padded) = (std::mem::size_of::<Block>(), std::mem::size_of::<Padded>());
        let c = &self.contribution;
        2 * self.sym.l_rows.len() * padded
            + self.nodes() * block
            + 2 * (self.work.x_col.len() + self.work_b.x_col.len()) * padded
            + 2 * (c[0].diag.len() + 2 * c[0].col.len()) * padded
            + self.sym.l_rows.len() * 4
            + (self.sym.col_src.len() + self.sym.row_src.len()) * std::mem::size_of::<Source>()
    }

    #[inline(always)]
    fn gather(values: &[f64], s: &Source) -> Block {
        gather_block(values, s.base, s.stride)
    }

    /// Factorises the matrix with scalar CSC values `values` (the layout
    /// of [`BlockLu::new`]). With `symmetric` (the values must be), only
    /// the blocks on and below the permuted diagonal are read and the
    /// factorisation is `L D L^T`.
    ///
    /// A split ordering factorises its two halves on two threads, each
    /// also summing its updates of the separator's columns, then the
    /// separator; the sums are the same whichever thread runs a half.
    /// The block updates run as AVX-512 intrinsics where the CPU has
    /// AVX-512 F and VL, else compiled for AVX2 and FMA, else portable;
    /// all three give the same bits (the private `updates`). Timings:
    /// docs/performance.md, "The node-block LU against faer".
    pub fn factorize(&mut self, values: &[f64], symmetric: bool) -> Result<(), BlockLuError> {
        let sym = &self.sym;
        let n = sym.nodes();
        let (a, b) = sym.split;
        let (l_ptr_a, l_ptr_b) = (sym.l_ptr[a], sym.l_ptr[b]);
        let (l_ab, l_s) = self.l.split_at_mut(l_ptr_b);
        let (l_a, l_b) = l_ab.split_at_mut(l_ptr_a);
        let (u_ab, u_s) = self.u.split_at_mut(l_ptr_b);
        let (u_a, u_b) = u_ab.split_at_mut(l_ptr_a);
        let (d_ab, d_s) = self.d_inv.split_at_mut(b);
        let (d_a, d_b) = d_ab.split_at_mut(a);
        let (n_ab, n_s) = self.next.split_at_mut(b);
        let (n_a, n_b) = n_ab.split_at_mut(a);
        let (c_ab, c_s) = self.cursor.split_at_mut(b);
        let (c_a, c_b) = c_ab.split_at_mut(a);
        let work = &mut self.work;
        work.head.fill(NONE);
        if b > 0 {
            let work_b = &mut self.work_b;
            work_b.head.fill(NONE);
            let [con_a, con_b] = &mut self.contribution;
            let mut cols_a = Columns {
                c0: 0,
                q0: 0,
                l: l_a,
                u: u_a,
                d_inv: d_a,
                next: n_a,
                cursor: c_a,
            };
            let mut cols_b = Columns {
                c0: a,
                q0: l_ptr_a,
                l: l_b,
                u: u_b,
                d_inv: d_b,
                next: n_b,
                cursor: c_b,
            };
            let (ra, rb) = crate::par::join(
                || sym.run(values, symmetric, Job::Part(&mut cols_a, work, 0..a, con_a)),
                || {
                    sym.run(
                        values,
                        symmetric,
                        Job::Part(&mut cols_b, work_b, a..b, con_b),
                    )
                },
            );
            ra?;
            rb?;
        }
        let mut cols_s = Columns {
            c0: b,
            q0: l_ptr_b,
            l: l_s,
            u: u_s,
            d_inv: d_s,
            next: n_s,
            cursor: c_s,
        };
        let contributions: &[Contribution] = if b > 0 { &self.contribution } else { &[] };
        sym.run(
            values,
            symmetric,
            Job::Last(&mut cols_s, work, b..n, contributions),
        )
    }

    /// Whether every pivot block of the last symmetric factorisation
    /// `A = L D L^T` is positive definite — then, by Sylvester's law of
    /// inertia, so is `A` (the test of the projected Newton, which needs
    /// a positive definite Hessian). Checked on `D^-1` (positive definite
    /// exactly when `D` is) by its leading principal minors.
    pub fn pivots_positive(&self) -> bool {
        self.d_inv.iter().all(|d| {
            let m2 = d[0] * d[4] - d[1] * d[3];
            let m3 = d[0] * (d[4] * d[8] - d[5] * d[7]) - d[1] * (d[3] * d[8] - d[5] * d[6])
                + d[2] * (d[3] * d[7] - d[4] * d[6]);
            d[0] > 0.0 && m2 > 0.0 && m3 > 0.0
        })
    }

    /// Solves `A x = b` in place (`x`: `b` in, `x` out; `3 nodes` long)
    /// with the last factorisation.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        let sym = &self.sym;
        let n = sym.nodes();
        let (a, b) = sym.split;
        let w = &mut self.rhs;
        for (j, wj) in w.iter_mut().enumerate() {
            let o = 3 * sym.perm[j];
            *wj = [x[o], x[o + 1], x[o + 2]];
        }
        let (d_inv, l, u) = (&self.d_inv[..], &self.l[..], &self.u[..]);
        // L~ y = b, by columns: the halves on two threads (the second one
        // gathers its updates of the separator's rows apart, added after),
        // then the separator.
        let (w_ab, w_s) = w.split_at_mut(b);
        let (w_a, w_b) = w_ab.split_at_mut(a);
        if b > 0 {
            let acc = &mut self.rhs_separator;
            acc.fill([0.0; 3]);
            crate::par::join(
                || sym.forward(d_inv, l, 0..a, w_a, w_s),
                || sym.forward(d_inv, l, a..b, w_b, acc),
            );
            for (wi, ai) in w_s.iter_mut().zip(acc.iter()) {
                for c in 0..3 {
                    wi[c] += ai[c];
                }
            }
        }
        sym.forward(d_inv, l, b..n, w_s, &mut []);
        // U x = y, by rows: the separator, then the halves on two threads.
        sym.backward(u, b..n, w_s, &[]);
        if b > 0 {
            let w_s = &*w_s;
            crate::par::join(
                || sym.backward(u, 0..a, w_a, w_s),
                || sym.backward(u, a..b, w_b, w_s),
            );
        }
        for (j, wj) in w.iter().enumerate() {
            let o = 3 * sym.perm[j];
            x[o..o + 3].copy_from_slice(wj);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    thread_local! {
        /// Runs the factorisations of this thread by the portable code.
        pub(super) static PORTABLE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }

    /// The AVX-512 and AVX2 builds of the factorisation (where the CPU
    /// has them) and the portable one give the same factor to the bit.
    #[test]
    fn every_build_gives_the_same_factor() {
        for (skew, symmetric) in [(0.0, true), (0.6, false)] {
            let (p, v) = grid_matrix(20, 20, 8.0, skew);
            let (ptr, rows) = p.node_graph();
            let mut lu = BlockLu::new(ptr, rows).unwrap();
            // (One thread: the helper does not see this thread's flag.)
            let factor = |lu: &mut BlockLu, portable: bool| {
                PORTABLE.with(|f| f.set(portable));
                crate::par::join(|| lu.factorize(&v, symmetric).unwrap(), || ());
                PORTABLE.with(|f| f.set(false));
                (lu.l.clone(), lu.u.clone(), lu.d_inv.clone())
            };
            let fast = factor(&mut lu, false);
            let portable = factor(&mut lu, true);
            assert!(fast == portable, "skew {skew}");
        }
    }
    use crate::solver::pattern::SparsePattern;

    /// A node grid of `nx x ny` squares cut into triangles, its pattern and
    /// a matrix on it: `shift` on the diagonal, pseudo-random blocks
    /// elsewhere, skew part scaled by `skew`.
    fn grid_matrix(nx: usize, ny: usize, shift: f64, skew: f64) -> (SparsePattern, Vec<f64>) {
        let pattern = SparsePattern::triangle_grid(nx, ny);
        let n = pattern.dimension();
        let mut values = vec![0.0; pattern.nnz()];
        let hash = |r: usize, c: usize| {
            let h = (r.wrapping_mul(2654435761) ^ c.wrapping_mul(40503)) % 1000;
            h as f64 / 1000.0 - 0.5
        };
        for c in 0..n {
            for k in pattern.col_ptr[c]..pattern.col_ptr[c + 1] {
                let r = pattern.row_idx[k];
                let (lo, hi) = (r.min(c), r.max(c));
                let sym = hash(lo, hi);
                let anti = if r < c { 1.0 } else { -1.0 } * hash(hi, lo);
                values[k] = if r == c { shift } else { sym + skew * anti };
            }
        }
        (pattern, values)
    }

    fn multiply(p: &SparsePattern, v: &[f64], x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        for c in 0..p.dimension() {
            for k in p.col_ptr[c]..p.col_ptr[c + 1] {
                y[p.row_idx[k]] += v[k] * x[c];
            }
        }
        y
    }

    /// `max |A x - b|`.
    fn residual(p: &SparsePattern, v: &[f64], x: &[f64], b: &[f64]) -> f64 {
        let ax = multiply(p, v, x);
        ax.iter().zip(b).fold(0.0, |m, (a, c)| m.max((a - c).abs()))
    }

    fn max_abs(v: &[f64]) -> f64 {
        v.iter().fold(0.0, |a, x| a.max(x.abs()))
    }

    /// Symmetric and non-symmetric systems are solved to round-off:
    /// `|A x - b| / |b|` at 1e-12 (the matrices have condition numbers
    /// near 10), twice with the same symbolic analysis.
    #[test]
    fn solves_symmetric_and_nonsymmetric_systems() {
        for (skew, symmetric) in [(0.0, true), (0.0, false), (0.7, false)] {
            let (p, v) = grid_matrix(7, 5, 8.0, skew);
            let (ptr, rows) = p.node_graph();
            let mut lu = BlockLu::new(ptr, rows).unwrap();
            for round in 0..2 {
                let v: Vec<f64> = v.iter().map(|a| a * (1.0 + 0.1 * round as f64)).collect();
                lu.factorize(&v, symmetric).unwrap();
                let b: Vec<f64> = (0..p.dimension())
                    .map(|i| (i as f64 * 0.37).sin())
                    .collect();
                let mut x = b.clone();
                lu.solve_in_place(&mut x);
                let r = residual(&p, &v, &x, &b);
                assert!(r < 1e-12 * max_abs(&b), "skew {skew}: {r:e}");
            }
        }
    }

    /// For a symmetric matrix the `L D L^T` shortcut and the general path
    /// give the same solution (to round-off).
    #[test]
    fn symmetric_shortcut_agrees_with_the_general_path() {
        let (p, v) = grid_matrix(6, 4, 8.0, 0.0);
        let (ptr, rows) = p.node_graph();
        let mut lu = BlockLu::new(ptr, rows).unwrap();
        let b: Vec<f64> = (0..p.dimension()).map(|i| i as f64).collect();
        let mut x = [b.clone(), b.clone()];
        for (symmetric, x) in [true, false].into_iter().zip(x.iter_mut()) {
            lu.factorize(&v, symmetric).unwrap();
            lu.solve_in_place(x);
        }
        let d: Vec<f64> = x[0].iter().zip(&x[1]).map(|(a, c)| a - c).collect();
        assert!(max_abs(&d) < 1e-12 * max_abs(&x[0]));
        assert!(lu.flops(true) < lu.flops(false));
    }

    /// A singular pivot block is reported (and the next factorisation of a
    /// good matrix still works: the accumulators were left clean).
    #[test]
    fn singular_pivot_is_reported() {
        let (p, v) = grid_matrix(3, 3, 8.0, 0.2);
        let (ptr, rows) = p.node_graph();
        let mut lu = BlockLu::new(ptr, rows).unwrap();
        pivot_of_node_is_reported_then_recovered(&mut lu, &p, &v, 4);
    }

    /// With `node`'s block column and row zero (singular), factorising
    /// reports that node's pivot; the next factorisation of `v` solves to
    /// round-off (the accumulators were left clean).
    fn pivot_of_node_is_reported_then_recovered(
        lu: &mut BlockLu,
        p: &SparsePattern,
        v: &[f64],
        node: usize,
    ) {
        let mut bad = v.to_vec();
        for c in 0..p.dimension() {
            for k in p.col_ptr[c]..p.col_ptr[c + 1] {
                if c / 3 == node || p.row_idx[k] / 3 == node {
                    bad[k] = 0.0;
                }
            }
        }
        assert_eq!(lu.factorize(&bad, false), Err(BlockLuError::Pivot { node }));
        lu.factorize(v, false).unwrap();
        let b = vec![1.0; p.dimension()];
        let mut x = b.clone();
        lu.solve_in_place(&mut x);
        assert!(residual(p, v, &x, &b) < 1e-12);
    }

    /// From 100 nodes on a grid's ordering is split in two halves joined
    /// only through the separator, and the split factorisation solves
    /// symmetric and non-symmetric systems to round-off, with results
    /// bit for bit the same whether the halves run on two threads or one.
    #[test]
    fn split_factorisation_solves_and_does_not_depend_on_the_threads() {
        for (nx, ny) in [(20, 20), (30, 14)] {
            for (skew, symmetric) in [(0.0, true), (0.7, false)] {
                let (p, v) = grid_matrix(nx, ny, 8.0, skew);
                let (ptr, rows) = p.node_graph();
                let mut lu = BlockLu::new(ptr, rows).unwrap();
                assert!(lu.is_split(), "{nx}x{ny}");
                // No edge between the halves: each half's columns of L
                // reach only their own half and the separator.
                let (a, b) = lu.sym.split;
                for j in 0..b {
                    for &i in &lu.sym.l_rows[lu.sym.l_ptr[j]..lu.sym.l_ptr[j + 1]] {
                        let i = i as usize;
                        assert!(if j < a { i < a || i >= b } else { i >= a }, "{j} -> {i}");
                    }
                }
                let rhs: Vec<f64> = (0..p.dimension())
                    .map(|i| (i as f64 * 0.37).sin())
                    .collect();
                let mut x = rhs.clone();
                lu.factorize(&v, symmetric).unwrap();
                lu.solve_in_place(&mut x);
                let r = residual(&p, &v, &x, &rhs);
                assert!(r < 1e-12 * max_abs(&rhs), "{nx}x{ny} skew {skew}: {r:e}");
                // Inside a join the nested one runs both halves here.
                let mut y = rhs.clone();
                crate::par::join(
                    || {
                        lu.factorize(&v, symmetric).unwrap();
                        lu.solve_in_place(&mut y);
                    },
                    || (),
                );
                assert_eq!(x, y);
            }
        }
    }

    /// A singular pivot in either half or in the separator is reported by
    /// its node, and the next factorisation of a good matrix is right.
    #[test]
    fn split_factorisation_reports_a_singular_pivot_in_any_part() {
        let (p, v) = grid_matrix(20, 20, 8.0, 0.3);
        let (ptr, rows) = p.node_graph();
        let mut lu = BlockLu::new(ptr, rows).unwrap();
        let (a, b) = lu.sym.split;
        let n = lu.nodes();
        for column in [a / 2, (a + b) / 2, (b + n) / 2] {
            let node = lu.sym.perm[column];
            pivot_of_node_is_reported_then_recovered(&mut lu, &p, &v, node);
        }
    }

    /// A graph in two pieces is not split (no level set separates it),
    /// nor is a small one.
    #[test]
    fn disconnected_and_small_graphs_are_not_split() {
        let (p, _) = grid_matrix(20, 20, 8.0, 0.0);
        let (ptr, rows) = p.node_graph();
        let n = ptr.len() - 1;
        // Two copies of the grid side by side.
        let mut ptr2 = ptr.to_vec();
        let mut rows2 = rows.to_vec();
        for c in 0..n {
            let range = ptr[c]..ptr[c + 1];
            rows2.extend(rows[range].iter().map(|r| r + n));
            ptr2.push(rows2.len());
        }
        assert!(!BlockLu::new(&ptr2, &rows2).unwrap().is_split());
        let (p, _) = grid_matrix(6, 6, 8.0, 0.0);
        let (ptr, rows) = p.node_graph();
        assert!(!BlockLu::new(ptr, rows).unwrap().is_split());
    }

    /// The ordering reduces fill: on a 30x30 grid the factor holds fewer
    /// blocks than a banded (natural order) one would, `nodes x (nx + 2)`.
    #[test]
    fn ordering_reduces_fill() {
        let (p, _) = grid_matrix(30, 30, 8.0, 0.0);
        let (ptr, rows) = p.node_graph();
        let lu = BlockLu::new(ptr, rows).unwrap();
        let banded = 31 * 31 * 32;
        assert!(
            lu.factor_blocks() < banded / 2,
            "{} blocks",
            lu.factor_blocks()
        );
    }
}
