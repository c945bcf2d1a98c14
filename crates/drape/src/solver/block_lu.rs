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

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;

/// A 3x3 block, row-major: `m[3 r + c]`.
pub type Block = [f64; 9];

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

/// `a b`.
#[inline(always)]
pub(crate) fn mul(a: &Block, b: &Block) -> Block {
    let mut c = [0.0; 9];
    for r in 0..3 {
        for k in 0..3 {
            let s = a[3 * r + k];
            for q in 0..3 {
                c[3 * r + q] += s * b[3 * k + q];
            }
        }
    }
    c
}

/// `c -= a b` (`SUBTRACT`) or `c += a b`.
#[inline(always)]
pub(crate) fn mul_acc<const SUBTRACT: bool>(c: &mut Block, a: &Block, b: &Block) {
    for r in 0..3 {
        for k in 0..3 {
            let s = if SUBTRACT {
                -a[3 * r + k]
            } else {
                a[3 * r + k]
            };
            for q in 0..3 {
                c[3 * r + q] += s * b[3 * k + q];
            }
        }
    }
}

/// The 3x3 identity.
pub(crate) const IDENTITY: Block = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];

/// `a^T`.
#[inline(always)]
pub(crate) fn transpose(a: &Block) -> Block {
    [a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]]
}

/// `a x` for the three entries of `x`.
#[inline(always)]
pub(crate) fn mul_vec(a: &Block, x: &[f64]) -> [f64; 3] {
    [
        a[0] * x[0] + a[1] * x[1] + a[2] * x[2],
        a[3] * x[0] + a[4] * x[1] + a[5] * x[2],
        a[6] * x[0] + a[7] * x[1] + a[8] * x[2],
    ]
}

/// Inverse of a 3x3 block, `None` when its determinant is below `1e-13`
/// of the cube of its largest entry (or not finite).
pub(crate) fn invert(m: &Block) -> Option<Block> {
    let c00 = m[4] * m[8] - m[5] * m[7];
    let c01 = m[5] * m[6] - m[3] * m[8];
    let c02 = m[3] * m[7] - m[4] * m[6];
    let det = m[0] * c00 + m[1] * c01 + m[2] * c02;
    let scale = m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if !det.is_finite() || det.abs() <= 1e-13 * scale * scale * scale {
        return None;
    }
    let d = 1.0 / det;
    Some([
        c00 * d,
        (m[2] * m[7] - m[1] * m[8]) * d,
        (m[1] * m[5] - m[2] * m[4]) * d,
        c01 * d,
        (m[0] * m[8] - m[2] * m[6]) * d,
        (m[2] * m[3] - m[0] * m[5]) * d,
        c02 * d,
        (m[1] * m[6] - m[0] * m[7]) * d,
        (m[0] * m[4] - m[1] * m[3]) * d,
    ])
}

/// The 3x3 block of scalar CSC `values` whose entry `(0, 0)` is at `base`,
/// with its columns `stride` apart (the layout of
/// [`super::SparsePattern`]: rows of a block are consecutive).
#[inline(always)]
pub(crate) fn gather_block(values: &[f64], base: usize, stride: usize) -> Block {
    let (b, t) = (base, stride);
    [
        values[b],
        values[b + t],
        values[b + 2 * t],
        values[b + 1],
        values[b + 1 + t],
        values[b + 1 + 2 * t],
        values[b + 2],
        values[b + 2 + t],
        values[b + 2 + 2 * t],
    ]
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

/// Symbolic analysis and numeric storage of the block LU of one pattern.
#[derive(Debug, Clone)]
pub struct BlockLu {
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
    /// `L~_ij` by position in `l_rows`.
    l: Vec<Block>,
    /// `U_ji` (row `j`, column `i = l_rows[q]`) by position `q`.
    u: Vec<Block>,
    /// `D_j^-1`.
    d_inv: Vec<Block>,
    /// Dense accumulators of one column and one row.
    x_col: Vec<Block>,
    x_row: Vec<Block>,
    /// Linked lists of the columns `k` whose next row is `j`.
    head: Vec<u32>,
    next: Vec<u32>,
    cursor: Vec<usize>,
    /// Solve work (permuted right-hand side).
    work: Vec<[f64; 3]>,
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
    pub fn new(node_ptr: &[usize], node_rows: &[usize]) -> Result<Self, BlockLuError> {
        let n = node_ptr.len() - 1;
        let (perm, perm_inv) = Self::amd_order(node_ptr, node_rows)?;

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

        // Pattern of L: column j gathers its own rows below the diagonal
        // and those of its children in the elimination tree.
        let mut l_ptr = vec![0usize; n + 1];
        let mut l_rows: Vec<u32> = Vec::new();
        let mut mark = vec![NONE; n];
        let mut child_head = vec![NONE; n];
        let mut child_next = vec![NONE; n];
        let mut list: Vec<u32> = Vec::new();
        for j in 0..n {
            list.clear();
            mark[j] = j as u32;
            for s in &col_src[col_src_ptr[j]..col_src_ptr[j + 1]] {
                let i = s.row as usize;
                if mark[i] != j as u32 {
                    mark[i] = j as u32;
                    list.push(s.row);
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

        // Multiply–adds: per (k, j) pair, the block updates below j.
        let mut flops = (0.0, 0.0);
        for k in 0..n {
            let c = (l_ptr[k + 1] - l_ptr[k]) as f64;
            // Column k updates sum_{m=1..c} m blocks (x_col) and as many
            // minus one (x_row), 27 multiply–adds each.
            flops.0 += 27.0 * c * (c + 1.0) / 2.0;
            flops.1 += 27.0 * c * c;
        }

        let nnz = l_rows.len();
        Ok(Self {
            perm,
            l_ptr,
            l_rows,
            col_src_ptr,
            col_src,
            row_src_ptr,
            row_src,
            l: vec![[0.0; 9]; nnz],
            u: vec![[0.0; 9]; nnz],
            d_inv: vec![[0.0; 9]; n],
            x_col: vec![[0.0; 9]; n],
            x_row: vec![[0.0; 9]; n],
            head: vec![NONE; n],
            next: vec![NONE; n],
            cursor: vec![0; n],
            work: vec![[0.0; 3]; n],
            flops,
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
        self.perm.len()
    }

    /// Blocks stored in `L` (strictly lower; `U` has as many).
    pub fn factor_blocks(&self) -> usize {
        self.l_rows.len()
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
        let n = self.nodes();
        (2 * self.l_rows.len() + 3 * n) * std::mem::size_of::<Block>()
            + self.l_rows.len() * 4
            + (self.col_src.len() + self.row_src.len()) * std::mem::size_of::<Source>()
    }

    #[inline(always)]
    fn gather(values: &[f64], s: &Source) -> Block {
        gather_block(values, s.base, s.stride)
    }

    /// Factorises the matrix with scalar CSC values `values` (the layout
    /// of [`BlockLu::new`]). With `symmetric` (the values must be), only
    /// the blocks on and below the permuted diagonal are read and the
    /// factorisation is `L D L^T`.
    pub fn factorize(&mut self, values: &[f64], symmetric: bool) -> Result<(), BlockLuError> {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            if has!("avx2") && has!("fma") && has!("avx512f") && has!("avx512vl") {
                // SAFETY: the CPU has the features the function is compiled for.
                return unsafe { self.factorize_avx512(values, symmetric) };
            }
            if has!("avx2") && has!("fma") {
                // SAFETY: as above.
                return unsafe { self.factorize_avx2(values, symmetric) };
            }
        }
        self.factorize_generic(values, symmetric)
    }

    /// [`BlockLu::factorize`] compiled for AVX-512 (F and VL): the 3x3
    /// block products are register-bound, and AVX-512's 32 vector
    /// registers (against AVX2's 16) spill less — median 0.44 ms instead
    /// of 0.53 ms for the pedestal's non-symmetric Hessian over 15
    /// interleaved runs of the breakdown example (the best runs alike,
    /// 0.36–0.37 ms). Results are bit for bit the other builds'.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
    unsafe fn factorize_avx512(
        &mut self,
        values: &[f64],
        symmetric: bool,
    ) -> Result<(), BlockLuError> {
        self.factorize_generic(values, symmetric)
    }

    /// [`BlockLu::factorize`] compiled for AVX2 (the portable build
    /// targets baseline x86-64, whose 128-bit vectors leave the 3x3 block
    /// products about 20 % slower: 0.39 ms instead of 0.48 ms for the
    /// pedestal's Hessian). Rust does not fuse multiplies and adds on its
    /// own, so the results are the portable build's to the bit.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn factorize_avx2(
        &mut self,
        values: &[f64],
        symmetric: bool,
    ) -> Result<(), BlockLuError> {
        self.factorize_generic(values, symmetric)
    }

    #[inline(always)]
    fn factorize_generic(&mut self, values: &[f64], symmetric: bool) -> Result<(), BlockLuError> {
        let n = self.nodes();
        self.head.fill(NONE);
        for j in 0..n {
            // Scatter column j (rows >= j) and row j (columns > j) of A.
            for s in &self.col_src[self.col_src_ptr[j]..self.col_src_ptr[j + 1]] {
                self.x_col[s.row as usize] = Self::gather(values, s);
            }
            if !symmetric {
                for s in &self.row_src[self.row_src_ptr[j]..self.row_src_ptr[j + 1]] {
                    // Block (J, I) as stored: gather gives A_JI directly.
                    self.x_row[s.row as usize] = Self::gather(values, s);
                }
            }
            let diagonal_scale = self.x_col[j].iter().fold(0.0f64, |a, v| a.max(v.abs()));
            // Updates from every column k < j with L_jk != 0.
            let mut k = self.head[j];
            while k != NONE {
                let ku = k as usize;
                let next_k = self.next[ku];
                let pos = self.cursor[ku];
                let end = self.l_ptr[ku + 1];
                let u_kj = self.u[pos];
                for q in pos..end {
                    let i = self.l_rows[q] as usize;
                    mul_acc::<true>(&mut self.x_col[i], &self.l[q], &u_kj);
                }
                if !symmetric {
                    let l_jk = self.l[pos];
                    for q in pos + 1..end {
                        let i = self.l_rows[q] as usize;
                        mul_acc::<true>(&mut self.x_row[i], &l_jk, &self.u[q]);
                    }
                }
                // Column k's next row.
                self.cursor[ku] = pos + 1;
                if pos + 1 < end {
                    let r = self.l_rows[pos + 1] as usize;
                    self.next[ku] = self.head[r];
                    self.head[r] = k;
                }
                k = next_k;
            }
            let d = self.x_col[j];
            let d_scale = d.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let d_inv = match invert(&d) {
                Some(inv) if d_scale > 1e-10 * diagonal_scale => inv,
                _ => {
                    // Leave the accumulators clean for the next call.
                    self.x_col[j] = [0.0; 9];
                    for q in self.l_ptr[j]..self.l_ptr[j + 1] {
                        let i = self.l_rows[q] as usize;
                        self.x_col[i] = [0.0; 9];
                        self.x_row[i] = [0.0; 9];
                    }
                    return Err(BlockLuError::Pivot { node: self.perm[j] });
                }
            };
            self.d_inv[j] = d_inv;
            self.x_col[j] = [0.0; 9];
            for q in self.l_ptr[j]..self.l_ptr[j + 1] {
                let i = self.l_rows[q] as usize;
                let l_ij = std::mem::replace(&mut self.x_col[i], [0.0; 9]);
                self.u[q] = if symmetric {
                    mul(&d_inv, &transpose(&l_ij))
                } else {
                    mul(&d_inv, &std::mem::replace(&mut self.x_row[i], [0.0; 9]))
                };
                self.l[q] = l_ij;
            }
            // Column j joins the list of its first row.
            self.cursor[j] = self.l_ptr[j];
            if self.l_ptr[j] < self.l_ptr[j + 1] {
                let r = self.l_rows[self.l_ptr[j]] as usize;
                self.next[j] = self.head[r];
                self.head[r] = j as u32;
            }
        }
        Ok(())
    }

    /// Solves `A x = b` in place (`x`: `b` in, `x` out; `3 nodes` long)
    /// with the last factorisation.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        let n = self.nodes();
        let w = &mut self.work;
        for (j, wj) in w.iter_mut().enumerate() {
            let o = 3 * self.perm[j];
            *wj = [x[o], x[o + 1], x[o + 2]];
        }
        // L~ y = b, by columns.
        for j in 0..n {
            let y = mul_vec(&self.d_inv[j], &w[j]);
            w[j] = y;
            for q in self.l_ptr[j]..self.l_ptr[j + 1] {
                let i = self.l_rows[q] as usize;
                let t = mul_vec(&self.l[q], &y);
                for c in 0..3 {
                    w[i][c] -= t[c];
                }
            }
        }
        // U x = y, by rows (U_ji stored at column j's positions).
        for j in (0..n).rev() {
            let mut s = w[j];
            for q in self.l_ptr[j]..self.l_ptr[j + 1] {
                let i = self.l_rows[q] as usize;
                let t = mul_vec(&self.u[q], &w[i]);
                for c in 0..3 {
                    s[c] -= t[c];
                }
            }
            w[j] = s;
        }
        for (j, wj) in w.iter().enumerate() {
            let o = 3 * self.perm[j];
            x[o..o + 3].copy_from_slice(wj);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
        let mut bad = v.clone();
        // Node 4's block column and row zero: singular.
        for c in 0..p.dimension() {
            for k in p.col_ptr[c]..p.col_ptr[c + 1] {
                if c / 3 == 4 || p.row_idx[k] / 3 == 4 {
                    bad[k] = 0.0;
                }
            }
        }
        assert_eq!(
            lu.factorize(&bad, false),
            Err(BlockLuError::Pivot { node: 4 })
        );
        lu.factorize(&v, false).unwrap();
        let b = vec![1.0; p.dimension()];
        let mut x = b.clone();
        lu.solve_in_place(&mut x);
        assert!(residual(&p, &v, &x, &b) < 1e-12);
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
