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
//! 8–10 times its Cholesky (FACTS.md); this factorisation reuses one
//! symbolic analysis for symmetric and non-symmetric values alike, works
//! on 3x3 blocks (27 multiply–adds per block update, no index arithmetic
//! per scalar), and at the sizes where one factorisation per Newton
//! iteration is affordable it is faster than faer's Cholesky, whose fixed
//! costs dominate small matrices (docs/performance.md).

use super::pattern::gather_block;
use crate::block3::{Block, invert, mul, mul_vec};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;
use std::ops::Range;

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
    /// The fill-reducing ordering failed.
    #[error("the minimum degree ordering failed: {0}")]
    Ordering(String),
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
/// block ([`updates`]), against nine multiplies of three-wide vectors
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

/// Below this many nodes the ordering is not split in two.
const SPLIT_MIN_NODES: usize = 100;

/// Level sets tried as separators (the best balanced ones).
const CUT_CANDIDATES: usize = 5;

impl Symbolic {
    /// The analysis of the node graph for the ordering `perm`
    /// (`perm_inv` its inverse) split as `split`.
    fn new(
        node_ptr: &[usize],
        node_rows: &[usize],
        perm: Vec<usize>,
        perm_inv: &[usize],
        split: (usize, usize),
    ) -> Result<Self, BlockLuError> {
        let n = perm.len();
        // Permuted columns: the rows of each, and the value sources.
        let mut col_src_ptr = vec![0; n + 1];
        let mut row_src_ptr = vec![0; n + 1];
        let mut col_src = Vec::with_capacity(node_rows.len() / 2 + n);
        let mut row_src = Vec::with_capacity(node_rows.len() / 2);
        let mut lower: Vec<(u32, Source)> = Vec::new();
        let mut upper: Vec<(u32, Source)> = Vec::new();
        for jn in 0..n {
            let b = perm[jn];
            let deg = node_ptr[b + 1] - node_ptr[b];
            lower.clear();
            upper.clear();
            for p in node_ptr[b]..node_ptr[b + 1] {
                let a = node_rows[p];
                let i_new = perm_inv[a] as u32;
                // Block (a, b) of A is block (I, J) of P A P^T.
                let src = Source {
                    row: i_new,
                    base: 9 * node_ptr[b] + 3 * (p - node_ptr[b]),
                    stride: 3 * deg,
                };
                if i_new as usize >= jn {
                    lower.push((i_new, src));
                }
                if (i_new as usize) > jn {
                    // Block (J, I) = (b, a) of A: position of b in column a.
                    let q = node_rows[node_ptr[a]..node_ptr[a + 1]]
                        .binary_search(&b)
                        .map_err(|_| {
                            BlockLuError::Ordering("the node graph is not symmetric".into())
                        })?;
                    let deg_a = node_ptr[a + 1] - node_ptr[a];
                    upper.push((
                        i_new,
                        Source {
                            row: i_new,
                            base: 9 * node_ptr[a] + 3 * q,
                            stride: 3 * deg_a,
                        },
                    ));
                }
            }
            lower.sort_unstable_by_key(|e| e.0);
            upper.sort_unstable_by_key(|e| e.0);
            col_src.extend(lower.iter().map(|e| e.1));
            row_src.extend(upper.iter().map(|e| e.1));
            col_src_ptr[jn + 1] = col_src.len();
            row_src_ptr[jn + 1] = row_src.len();
        }
        let (l_ptr, l_rows) = l_pattern(n, |j, rows| {
            rows.extend(
                col_src[col_src_ptr[j]..col_src_ptr[j + 1]]
                    .iter()
                    .map(|s| s.row)
                    .filter(|&i| i as usize != j),
            )
        });
        Ok(Self {
            perm,
            l_ptr,
            l_rows,
            col_src_ptr,
            col_src,
            row_src_ptr,
            row_src,
            split,
        })
    }

    fn nodes(&self) -> usize {
        self.perm.len()
    }

    /// Multiply–adds of the columns `range` (symmetric, non-symmetric):
    /// column `k` updates `sum_{m=1..c} m` blocks of `x_col` and as many
    /// minus one of `x_row`, 27 multiply–adds each.
    fn flops(&self, range: Range<usize>) -> (f64, f64) {
        range.fold((0.0, 0.0), |(s, g), k| {
            let c = (self.l_ptr[k + 1] - self.l_ptr[k]) as f64;
            (s + 27.0 * c * (c + 1.0) / 2.0, g + 27.0 * c * c)
        })
    }

    /// Applies to the accumulators the updates of column `j` (and row `j`)
    /// from the columns `k` in `work.head[j]` — all of `cols`' range —
    /// and moves each `k` on to the list of its next row.
    #[inline(always)]
    fn update<const WIDE: bool>(
        &self,
        cols: &mut Columns,
        work: &mut Work,
        j: usize,
        symmetric: bool,
    ) {
        let (c0, q0) = (cols.c0, cols.q0);
        let mut k = work.head[j];
        while k != NONE {
            let ku = k as usize;
            let next_k = cols.next[ku - c0];
            let pos = cols.cursor[ku - c0];
            let end = self.l_ptr[ku + 1];
            let rows = &self.l_rows[pos..end];
            // x_col[i] -= L~_ik U_kj, and x_row[i]^T -= U_ki^T L~_jk^T.
            let u_kj = cols.u[pos - q0];
            updates::<WIDE>(&mut work.x_col, rows, &cols.l[pos - q0..end - q0], &u_kj);
            if !symmetric {
                let l_jk = cols.l[pos - q0];
                let u_k = &cols.u[pos + 1 - q0..end - q0];
                updates::<WIDE>(&mut work.x_row, &rows[1..], u_k, &l_jk);
            }
            // Column k's next row.
            cols.cursor[ku - c0] = pos + 1;
            if pos + 1 < end {
                let r = self.l_rows[pos + 1] as usize;
                cols.next[ku - c0] = work.head[r];
                work.head[r] = k;
            }
            k = next_k;
        }
    }

    /// Factorises the columns `range` (those of `cols`) by the left-looking
    /// recurrence of the module docs, with the updates from the columns in
    /// `work`'s lists and, for the separator, the parts' `contributions`.
    #[inline(always)]
    fn factor_range<const WIDE: bool>(
        &self,
        values: &[f64],
        symmetric: bool,
        cols: &mut Columns,
        work: &mut Work,
        range: Range<usize>,
        contributions: &[Contribution],
    ) -> Result<(), BlockLuError> {
        let (c0, q0) = (cols.c0, cols.q0);
        let (s0, qs0) = (self.split.1, self.l_ptr[self.split.1]);
        for j in range {
            // Scatter column j (rows >= j) and row j (columns > j) of A.
            for s in &self.col_src[self.col_src_ptr[j]..self.col_src_ptr[j + 1]] {
                work.x_col[s.row as usize] = Padded::new(&BlockLu::gather(values, s), false);
            }
            if !symmetric {
                for s in &self.row_src[self.row_src_ptr[j]..self.row_src_ptr[j + 1]] {
                    // Block (J, I) as stored: gather gives A_JI directly.
                    work.x_row[s.row as usize] = Padded::new(&BlockLu::gather(values, s), true);
                }
            }
            let diagonal_scale = work.x_col[j].max_abs();
            for c in contributions {
                add(&mut work.x_col[j], &c.diag[j - s0]);
                for q in self.l_ptr[j]..self.l_ptr[j + 1] {
                    let i = self.l_rows[q] as usize;
                    add(&mut work.x_col[i], &c.col[q - qs0]);
                    if !symmetric {
                        add(&mut work.x_row[i], &c.row[q - qs0]);
                    }
                }
            }
            self.update::<WIDE>(cols, work, j, symmetric);
            let d = work.x_col[j].block(false);
            let d_scale = d.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let d_inv = match invert(&d) {
                Some(inv) if d_scale > 1e-10 * diagonal_scale => inv,
                _ => {
                    // Leave the accumulators clean for the next call.
                    work.x_col[j] = ZERO;
                    for q in self.l_ptr[j]..self.l_ptr[j + 1] {
                        let i = self.l_rows[q] as usize;
                        work.x_col[i] = ZERO;
                        work.x_row[i] = ZERO;
                    }
                    return Err(BlockLuError::Pivot { node: self.perm[j] });
                }
            };
            cols.d_inv[j - c0] = d_inv;
            work.x_col[j] = ZERO;
            for q in self.l_ptr[j]..self.l_ptr[j + 1] {
                let i = self.l_rows[q] as usize;
                let l_ij = std::mem::replace(&mut work.x_col[i], ZERO);
                // U_ji = D_j^-1 (L~_ij^T if symmetric, else A_ji - ...).
                let rhs = if symmetric {
                    l_ij.block(true)
                } else {
                    std::mem::replace(&mut work.x_row[i], ZERO).block(true)
                };
                cols.u[q - q0] = Padded::new(&mul(&d_inv, &rhs), true);
                cols.l[q - q0] = l_ij;
            }
            // Column j joins the list of its first row.
            cols.cursor[j - c0] = self.l_ptr[j];
            if self.l_ptr[j] < self.l_ptr[j + 1] {
                let r = self.l_rows[self.l_ptr[j]] as usize;
                cols.next[j - c0] = work.head[r];
                work.head[r] = j as u32;
            }
        }
        Ok(())
    }

    /// After a part's columns are factorised: their updates of the
    /// separator's columns, gathered into `out` (the accumulators are left
    /// clean and the lists empty).
    #[inline(always)]
    fn contribute<const WIDE: bool>(
        &self,
        symmetric: bool,
        cols: &mut Columns,
        work: &mut Work,
        out: &mut Contribution,
    ) {
        let (s0, qs0) = (self.split.1, self.l_ptr[self.split.1]);
        for j in s0..self.nodes() {
            self.update::<WIDE>(cols, work, j, symmetric);
            work.head[j] = NONE;
            out.diag[j - s0] = std::mem::replace(&mut work.x_col[j], ZERO);
            for q in self.l_ptr[j]..self.l_ptr[j + 1] {
                let i = self.l_rows[q] as usize;
                out.col[q - qs0] = std::mem::replace(&mut work.x_col[i], ZERO);
                if !symmetric {
                    out.row[q - qs0] = std::mem::replace(&mut work.x_row[i], ZERO);
                }
            }
        }
    }
}

/// A unit of a factorisation: the columns of one part, then their
/// updates of the separator; or the separator's columns, with the parts'
/// contributions (none when the ordering is not split).
enum Job<'s, 'c> {
    Part(
        &'s mut Columns<'c>,
        &'s mut Work,
        Range<usize>,
        &'s mut Contribution,
    ),
    Last(
        &'s mut Columns<'c>,
        &'s mut Work,
        Range<usize>,
        &'s [Contribution],
    ),
}

impl Symbolic {
    /// Runs `job`; `WIDE`: with the AVX-512 block product (only where
    /// the CPU has AVX-512 F and VL).
    #[inline(always)]
    fn run_generic<const WIDE: bool>(
        &self,
        values: &[f64],
        symmetric: bool,
        job: Job,
    ) -> Result<(), BlockLuError> {
        match job {
            Job::Part(cols, work, range, out) => {
                self.factor_range::<WIDE>(values, symmetric, cols, work, range, &[])?;
                self.contribute::<WIDE>(symmetric, cols, work, out);
                Ok(())
            }
            Job::Last(cols, work, range, contributions) => {
                self.factor_range::<WIDE>(values, symmetric, cols, work, range, contributions)
            }
        }
    }

    /// [`Symbolic::run_generic`] compiled for AVX-512 (F and VL).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
    unsafe fn run_avx512(
        &self,
        values: &[f64],
        symmetric: bool,
        job: Job,
    ) -> Result<(), BlockLuError> {
        self.run_generic::<true>(values, symmetric, job)
    }

    /// [`Symbolic::run_generic`] compiled for AVX2 with FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn run_avx2(
        &self,
        values: &[f64],
        symmetric: bool,
        job: Job,
    ) -> Result<(), BlockLuError> {
        self.run_generic::<false>(values, symmetric, job)
    }

    /// Runs `job` compiled for the widest vectors the CPU has. Every
    /// build computes each entry by the same fused multiply–adds in the
    /// same order (the portable one through the C library's `fma`, on
    /// CPUs without AVX2 and FMA), so the results do not depend on the
    /// build.
    fn run(&self, values: &[f64], symmetric: bool, job: Job) -> Result<(), BlockLuError> {
        #[cfg(test)]
        if tests::PORTABLE.with(|p| p.get()) {
            return self.run_generic::<false>(values, symmetric, job);
        }
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            if has!("avx2") && has!("fma") && has!("avx512f") && has!("avx512vl") {
                // SAFETY: the CPU has the features the function is compiled for.
                return unsafe { self.run_avx512(values, symmetric, job) };
            }
            if has!("avx2") && has!("fma") {
                // SAFETY: as above.
                return unsafe { self.run_avx2(values, symmetric, job) };
            }
        }
        self.run_generic::<false>(values, symmetric, job)
    }
}

/// `x[rows[q]] -= a[q] b` for every `q`, in [`Padded`] blocks: `x` and
/// `a` by columns, `b` transposed (entry `(k, c)` of the factor `B` at
/// `4 k + c`). Each entry is `c - a_0 b_0 - a_1 b_1 - a_2 b_2`, by fused
/// multiply–adds in that order. `WIDE`: by AVX-512 intrinsics (the CPU
/// must have AVX-512 F and VL); else by `f64::mul_add`, which is one
/// instruction in code compiled with the `fma` feature ([`Symbolic::run`]'s
/// AVX2 build). (Slices as arguments tell the compiler that `x` aliases
/// neither `a` nor `rows`.)
#[inline(always)]
fn updates<const WIDE: bool>(x: &mut [Padded], rows: &[u32], a: &[Padded], b: &Padded) {
    #[cfg(target_arch = "x86_64")]
    if WIDE {
        // SAFETY: `WIDE` is only set in `Symbolic::run_avx512`, called
        // where the CPU has the features.
        unsafe { updates_avx512(x, rows, a, b) };
        return;
    }
    for (&i, a) in rows.iter().zip(a) {
        let c = &mut x[i as usize].0;
        for q in 0..3 {
            for k in 0..3 {
                let bkq = b.0[4 * k + q];
                for r in 0..3 {
                    c[4 * q + r] = (-a.0[4 * k + r]).mul_add(bkq, c[4 * q + r]);
                }
            }
        }
    }
}

/// [`updates`] by AVX-512: columns 0 and 1 of a target block in one
/// 512-bit vector, column 2 in a 256-bit one; per `k`, column `k` of `a`
/// broadcast to both halves and multiplied by `b_k0` (low half), `b_k1`
/// (high half) and `b_k2`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
#[inline]
unsafe fn updates_avx512(x: &mut [Padded], rows: &[u32], a: &[Padded], b: &Padded) {
    use std::arch::x86_64::*;
    let mut b01 = [_mm512_setzero_pd(); 3];
    let mut b2 = [_mm256_setzero_pd(); 3];
    for k in 0..3 {
        let lo = _mm256_set1_pd(b.0[4 * k]);
        let hi = _mm256_set1_pd(b.0[4 * k + 1]);
        b01[k] = _mm512_insertf64x4::<1>(_mm512_castpd256_pd512(lo), hi);
        b2[k] = _mm256_set1_pd(b.0[4 * k + 2]);
    }
    for (&i, a) in rows.iter().zip(a) {
        let c = &mut x[i as usize].0;
        // SAFETY: `c` and `a.0` hold 12 doubles: loads and stores of 8
        // from 0 and of 4 from 8 (and 4 from 4 k) stay inside.
        unsafe {
            let cp = c.as_mut_ptr();
            let ap = a.0.as_ptr();
            let mut c01 = _mm512_loadu_pd(cp);
            let mut c2 = _mm256_loadu_pd(cp.add(8));
            for k in 0..3 {
                let ak = _mm256_loadu_pd(ap.add(4 * k));
                c01 = _mm512_fnmadd_pd(_mm512_broadcast_f64x4(ak), b01[k], c01);
                c2 = _mm256_fnmadd_pd(ak, b2[k], c2);
            }
            _mm512_storeu_pd(cp, c01);
            _mm256_storeu_pd(cp.add(8), c2);
        }
    }
}

/// `c += a`.
#[inline(always)]
fn add(c: &mut Padded, a: &Padded) {
    let (c, a) = (&mut c.0, &a.0);
    for (x, y) in c.iter_mut().zip(a) {
        *x += y;
    }
}

/// The strictly lower pattern of the Cholesky factor of a matrix with a
/// symmetric pattern, by the elimination tree: column `j` gathers the rows
/// `rows_of(j, ..)` pushes (its own entries below the diagonal) and those
/// of its children. Returns `(l_ptr, l_rows)`.
fn l_pattern(n: usize, mut rows_of: impl FnMut(usize, &mut Vec<u32>)) -> (Vec<usize>, Vec<u32>) {
    let mut l_ptr = vec![0usize; n + 1];
    let mut l_rows: Vec<u32> = Vec::new();
    let mut mark = vec![NONE; n];
    let mut child_head = vec![NONE; n];
    let mut child_next = vec![NONE; n];
    let mut own: Vec<u32> = Vec::new();
    let mut list: Vec<u32> = Vec::new();
    for j in 0..n {
        list.clear();
        own.clear();
        rows_of(j, &mut own);
        mark[j] = j as u32;
        for &i in &own {
            if mark[i as usize] != j as u32 {
                mark[i as usize] = j as u32;
                list.push(i);
            }
        }
        let mut c = child_head[j];
        while c != NONE {
            for &i in &l_rows[l_ptr[c as usize]..l_ptr[c as usize + 1]] {
                if mark[i as usize] != j as u32 {
                    mark[i as usize] = j as u32;
                    list.push(i);
                }
            }
            c = child_next[c as usize];
        }
        list.sort_unstable();
        l_rows.extend_from_slice(&list);
        l_ptr[j + 1] = l_rows.len();
        if let Some(&parent) = list.first() {
            child_next[j] = child_head[parent as usize];
            child_head[parent as usize] = j as u32;
        }
    }
    (l_ptr, l_rows)
}

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
    /// of AMD's work and adds at most 20 % to the total (the 20x20
    /// pedestal: 2.36 M multiply–adds with AMD, 2.52 M split, of which
    /// 1.32 M on the longer path). Whether it is split depends on the
    /// graph alone, never on the machine, so results do not either.
    pub fn new(node_ptr: &[usize], node_rows: &[usize]) -> Result<Self, BlockLuError> {
        let n = node_ptr.len() - 1;
        let (perm, perm_inv) = Self::amd_order(node_ptr, node_rows)?;
        let mut sym = Symbolic::new(node_ptr, node_rows, perm, &perm_inv, (0, 0))?;
        let serial = sym.flops(0..n).1;
        let mut best = 0.7 * serial;
        for (perm, split) in bisect(node_ptr, node_rows, &sym.perm) {
            let mut inv = vec![0; n];
            for (new, &old) in perm.iter().enumerate() {
                inv[old] = new;
            }
            let cut = Symbolic::new(node_ptr, node_rows, perm, &inv, split)?;
            let (a, b) = split;
            let path = cut.flops(0..a).1.max(cut.flops(a..b).1) + cut.flops(b..n).1;
            if path <= best && cut.flops(0..n).1 <= 1.2 * serial {
                best = path;
                sym = cut;
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

    /// AMD on the node graph: `(perm, perm_inv)`.
    fn amd_order(
        node_ptr: &[usize],
        node_rows: &[usize],
    ) -> Result<(Vec<usize>, Vec<usize>), BlockLuError> {
        let n = node_ptr.len() - 1;
        let mut perm = vec![0usize; n];
        let mut perm_inv = vec![0usize; n];
        if n == 0 {
            return Ok((perm, perm_inv));
        }
        let graph = SymbolicSparseColMatRef::new_checked(n, n, node_ptr, None, node_rows);
        let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(n, node_rows.len()))
            .map_err(|e| BlockLuError::Ordering(format!("{e:?}")))?;
        amd::order(
            &mut perm,
            &mut perm_inv,
            graph,
            amd::Control::default(),
            MemStack::new(&mut mem),
        )
        .map_err(|e| BlockLuError::Ordering(format!("{e:?}")))?;
        Ok((perm, perm_inv))
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
    /// all three give the same bits (the private `updates`). The pedestal's
    /// non-symmetric Hessian: 0.15 ms on two threads, 0.27 ms on one
    /// (docs/performance.md).
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

impl Symbolic {
    /// Where the separator's rows start for a substitution over a range
    /// starting at `start`: for a half, the split's separator (its rows
    /// are passed apart); for the separator itself or an unsplit
    /// ordering, never (`usize::MAX`: every row is its own).
    fn separator_start(&self, start: usize) -> usize {
        if self.split.1 > start {
            self.split.1
        } else {
            usize::MAX
        }
    }

    /// Forward substitution over the columns `cols`, whose entries are
    /// `own` (from `cols.start`): `y_j = D_j^-1 w_j`, then `w_i -= L~_ij
    /// y_j` below, into `separator` (from row `split.1`) for the
    /// separator's rows.
    fn forward(
        &self,
        d_inv: &[Block],
        l: &[Padded],
        cols: Range<usize>,
        own: &mut [[f64; 3]],
        separator: &mut [[f64; 3]],
    ) {
        let (c0, s0) = (cols.start, self.separator_start(cols.start));
        for j in cols {
            let y = mul_vec(&d_inv[j], &own[j - c0]);
            own[j - c0] = y;
            for q in self.l_ptr[j]..self.l_ptr[j + 1] {
                let i = self.l_rows[q] as usize;
                // L~_ij y, L~_ij by columns.
                let a = &l[q].0;
                let t: [f64; 3] =
                    std::array::from_fn(|r| a[r] * y[0] + a[4 + r] * y[1] + a[8 + r] * y[2]);
                let wi = if i >= s0 {
                    &mut separator[i - s0]
                } else {
                    &mut own[i - c0]
                };
                for c in 0..3 {
                    wi[c] -= t[c];
                }
            }
        }
    }

    /// Backward substitution over the rows `rows` (descending), whose
    /// entries are `own` (from `rows.start`), reading the separator's
    /// solved entries from `separator` (from row `split.1`).
    fn backward(
        &self,
        u: &[Padded],
        rows: Range<usize>,
        own: &mut [[f64; 3]],
        separator: &[[f64; 3]],
    ) {
        let (c0, s0) = (rows.start, self.separator_start(rows.start));
        for j in rows.rev() {
            let mut s = own[j - c0];
            for q in self.l_ptr[j]..self.l_ptr[j + 1] {
                let i = self.l_rows[q] as usize;
                let wi = if i >= s0 {
                    &separator[i - s0]
                } else {
                    &own[i - c0]
                };
                // U_ji w_i, U_ji stored transposed (by rows).
                let b = &u[q].0;
                let t: [f64; 3] = std::array::from_fn(|r| {
                    b[4 * r] * wi[0] + b[4 * r + 1] * wi[1] + b[4 * r + 2] * wi[2]
                });
                for c in 0..3 {
                    s[c] -= t[c];
                }
            }
            own[j - c0] = s;
        }
    }
}

/// Cuts a connected node graph in two by a level set of a breadth-first
/// search from a peripheral node (found as in George & Liu 1979: restart
/// from a node of least degree in the last level while the number of
/// levels grows). Candidates are the [`CUT_CANDIDATES`] best-balanced
/// levels that leave at least a quarter of the nodes on each side (the
/// two sides then share no edge); for each, the ordering — `order`'s
/// nodes of the first side, those of the second, those of the level, each
/// in `order`'s sequence — and the split `(a, b)`. None for small or
/// disconnected graphs.
fn bisect(
    node_ptr: &[usize],
    node_rows: &[usize],
    order: &[usize],
) -> Vec<(Vec<usize>, (usize, usize))> {
    let n = node_ptr.len() - 1;
    if n < SPLIT_MIN_NODES {
        return Vec::new();
    }
    let degree = |v: usize| node_ptr[v + 1] - node_ptr[v];
    let mut level = vec![usize::MAX; n];
    let mut queue = Vec::with_capacity(n);
    let mut bfs = |root: usize, level: &mut Vec<usize>| -> usize {
        level.fill(usize::MAX);
        queue.clear();
        queue.push(root);
        level[root] = 0;
        let mut head = 0;
        while head < queue.len() {
            let v = queue[head];
            head += 1;
            for &w in &node_rows[node_ptr[v]..node_ptr[v + 1]] {
                if level[w] == usize::MAX {
                    level[w] = level[v] + 1;
                    queue.push(w);
                }
            }
        }
        queue.len()
    };
    let Some(mut root) = (0..n).min_by_key(|&v| degree(v)) else {
        return Vec::new();
    };
    let mut depth = 0;
    // Whether `level` holds the levels from `root`.
    let mut current = false;
    for _ in 0..8 {
        if bfs(root, &mut level) < n {
            return Vec::new();
        }
        current = true;
        let last = level.iter().copied().max().unwrap_or(0);
        if last <= depth {
            break;
        }
        depth = last;
        let next = (0..n)
            .filter(|&v| level[v] == last)
            .min_by_key(|&v| degree(v))
            .unwrap_or(root);
        current = next == root;
        root = next;
    }
    if !current {
        bfs(root, &mut level);
    }
    let depth = level.iter().copied().max().unwrap_or(0);
    let mut sizes = vec![0usize; depth + 1];
    for &l in &level {
        sizes[l] += 1;
    }
    // The levels that leave at least a quarter of the nodes on each side,
    // best balanced first.
    let mut below = 0;
    let mut cuts = Vec::new();
    for (l, &size) in sizes.iter().enumerate() {
        let above = n - below - size;
        if l > 0 && l < depth && below.min(above) >= n / 4 {
            cuts.push((below.abs_diff(above), l));
        }
        below += size;
    }
    cuts.sort_unstable();
    cuts.truncate(CUT_CANDIDATES);
    cuts.into_iter()
        .map(|(_, cut)| {
            let side = |v: usize| (level[v] > cut) as usize + 2 * (level[v] == cut) as usize;
            let mut perm = Vec::with_capacity(n);
            for s in 0..3 {
                perm.extend(order.iter().copied().filter(|&v| side(v) == s));
            }
            let a = order.iter().filter(|&&v| side(v) == 0).count();
            let b = a + order.iter().filter(|&&v| side(v) == 1).count();
            (perm, (a, b))
        })
        .collect()
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
