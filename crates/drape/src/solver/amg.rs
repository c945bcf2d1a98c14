//! Smoothed-aggregation algebraic multigrid in 3x3 node blocks, the
//! preconditioner of the `iterative` linear-solver path.
//!
//! On fine meshes the membrane stiffness outweighs the mass term of the
//! dynamic Hessian by `(c dt / h)^2` (`c` the membrane wave speed, `h` the
//! element size: about 800 for 0.29 mm elements at `dt = 1e-4` s), so
//! one-level preconditioners need more Krylov iterations the finer the
//! mesh (block-Jacobi CG: ~270 per solve at 200x200 divisions, doubling
//! with each refinement). Multigrid treats every scale of the error on a
//! grid of its own size, so the iterations stay about constant and a
//! solve costs `O(n)`.
//!
//! Construction (Vaněk, Mandel & Brezina 1996), on the node graph:
//!
//! * **aggregates**: a node whose neighbours are all free starts an
//!   aggregate with them; the nodes left join a neighbouring aggregate;
//! * **tentative prolongator** `P0`: node `a` of aggregate `J` maps to
//!   `P0_aJ = I3` (the three rigid translations, the membrane's lowest
//!   modes, are represented exactly on the coarse grid);
//! * **smoothed prolongator** `P = (I - omega D^-1 A) P0`, `omega = 4 / (3
//!   rho(D^-1 A))`, `D` the 3x3 diagonal blocks;
//! * **coarse operator** `A_c = P^T A P` (Galerkin), recursively, until at
//!   most [`COARSEST_NODES`] nodes remain, factorised by the node-block LU.
//!
//! A V-cycle smooths with damped block Jacobi (`x += omega D^-1 (b - A
//! x)`, two sweeps before and after the coarse correction, the same
//! `omega`): for a symmetric positive definite `A` the cycle is symmetric
//! positive definite and preconditions conjugate gradients; for the
//! non-symmetric wrinkling tangent it preconditions GMRES.

use super::block_lu::BlockLu;
use crate::block3::{Block, IDENTITY, invert, mul, mul_acc, mul_vec, transpose};
use rayon::prelude::*;

/// The coarsest level has at most this many nodes (factorised directly).
pub const COARSEST_NODES: usize = 400;
/// Smoothing sweeps before and after each coarse correction.
const SWEEPS: usize = 1;
/// Levels with more rows than this run their loops on all threads.
const PARALLEL_ROWS: usize = 20_000;

/// Nodes per partial sum of a reduction over the nodes: a fixed run, so
/// that the sum's order, and its value, do not depend on the threads.
const SUM_NODES: usize = 4_096;

/// Inverse of a 3x3 block, or the identity if it is singular (a smoother
/// that skips a node rather than failing).
fn invert_or_identity(m: &Block) -> Block {
    invert(m).unwrap_or(IDENTITY)
}

/// A sparse matrix of 3x3 blocks by rows, columns sorted in each row.
#[derive(Debug, Clone, Default)]
pub struct BlockCsr {
    /// Row `r` holds blocks `ptr[r]..ptr[r + 1]`.
    pub ptr: Vec<usize>,
    /// Block column of each block.
    pub cols: Vec<u32>,
    /// The blocks, row-major (`m[3 r + c]`).
    pub vals: Vec<Block>,
    /// Number of block columns.
    pub ncols: usize,
}

impl BlockCsr {
    /// Block rows.
    pub fn rows(&self) -> usize {
        self.ptr.len() - 1
    }

    /// `y = A x` (scalar vectors, 3 per block).
    pub fn matvec(&self, x: &[f64], y: &mut [f64]) {
        let row = |(r, out): (usize, &mut [f64])| {
            let mut s = [0.0; 3];
            for k in self.ptr[r]..self.ptr[r + 1] {
                let c = self.cols[k] as usize;
                let t = mul_vec(&self.vals[k], &x[3 * c..3 * c + 3]);
                s[0] += t[0];
                s[1] += t[1];
                s[2] += t[2];
            }
            out.copy_from_slice(&s);
        };
        if self.rows() > PARALLEL_ROWS {
            y.par_chunks_mut(3).enumerate().for_each(row);
        } else {
            y.chunks_mut(3).enumerate().for_each(row);
        }
    }

    /// `A^T` (block-wise: each block transposed too). Large matrices are
    /// transposed by ranges of output rows (columns of `A`) in parallel:
    /// each range scans the column indices of `A` whole (cheap: 4 bytes a
    /// block) and moves only its own blocks into its own slice of the
    /// result, rows in order.
    pub fn transpose(&self) -> BlockCsr {
        let mut ptr = vec![0usize; self.ncols + 1];
        for &c in &self.cols {
            ptr[c as usize + 1] += 1;
        }
        for i in 0..self.ncols {
            ptr[i + 1] += ptr[i];
        }
        let mut cols = vec![0u32; self.cols.len()];
        let mut vals = vec![[0.0; 9]; self.cols.len()];
        let per = self.ncols.div_ceil(ranges_for(self.rows())).max(1);
        let parts = split_rows(&ptr, per, &mut cols, &mut vals);
        run_ranges(parts, |(start, end, c, v)| {
            let base = ptr[start];
            let mut next: Vec<usize> = ptr[start..end].iter().map(|p| p - base).collect();
            for r in 0..self.rows() {
                for k in self.ptr[r]..self.ptr[r + 1] {
                    let col = self.cols[k] as usize;
                    if (start..end).contains(&col) {
                        let dst = &mut next[col - start];
                        c[*dst] = r as u32;
                        v[*dst] = transpose(&self.vals[k]);
                        *dst += 1;
                    }
                }
            }
        });
        BlockCsr {
            ptr,
            cols,
            vals,
            ncols: self.rows(),
        }
    }

    /// The product `self * other` (Gustavson's row-by-row algorithm, in
    /// the two passes of `build_by_rows`: the columns of each row, then
    /// its blocks, written in place).
    pub fn multiply(&self, other: &BlockCsr) -> BlockCsr {
        let n = other.ncols;
        // Scratch of one row range: a marker and a dense accumulator over
        // the columns of the product, and the list of a row's columns.
        // Rows differ, so the row index marks a column as seen.
        let scratch = || (vec![u32::MAX; n], vec![[0.0; 9]; n], Vec::<u32>::new());
        build_by_rows(
            self.rows(),
            n,
            scratch,
            |r, (marker, _, list)| {
                list.clear();
                for k in self.ptr[r]..self.ptr[r + 1] {
                    let mid = self.cols[k] as usize;
                    for &c in &other.cols[other.ptr[mid]..other.ptr[mid + 1]] {
                        if marker[c as usize] != r as u32 {
                            marker[c as usize] = r as u32;
                            list.push(c);
                        }
                    }
                }
                list.len()
            },
            |r, (marker, dense, list), cols, vals| {
                list.clear();
                for k in self.ptr[r]..self.ptr[r + 1] {
                    let mid = self.cols[k] as usize;
                    let a = &self.vals[k];
                    for q in other.ptr[mid]..other.ptr[mid + 1] {
                        let c = other.cols[q] as usize;
                        if marker[c] != r as u32 {
                            marker[c] = r as u32;
                            dense[c] = [0.0; 9];
                            list.push(c as u32);
                        }
                        mul_acc::<false>(&mut dense[c], a, &other.vals[q]);
                    }
                }
                list.sort_unstable();
                cols.copy_from_slice(list);
                for (v, &c) in vals.iter_mut().zip(list.iter()) {
                    *v = dense[c as usize];
                }
            },
        )
    }

    /// Inverted diagonal blocks (identity where singular or missing).
    fn diagonal_inverse(&self) -> Vec<Block> {
        let mut d_inv = vec![IDENTITY; self.rows()];
        self.diagonal_inverse_into(&mut d_inv);
        d_inv
    }

    /// [`Self::diagonal_inverse`] into existing storage (one per row).
    fn diagonal_inverse_into(&self, d_inv: &mut [Block]) {
        let inverse = |(r, d): (usize, &mut Block)| {
            *d = (self.ptr[r]..self.ptr[r + 1])
                .find(|&k| self.cols[k] as usize == r)
                .map_or(IDENTITY, |k| invert_or_identity(&self.vals[k]));
        };
        if self.rows() > PARALLEL_ROWS {
            d_inv.par_iter_mut().enumerate().for_each(inverse);
        } else {
            d_inv.iter_mut().enumerate().for_each(inverse);
        }
    }
}

/// Aggregates of the graph of `a` (ignoring values): `agg[node]`, and
/// their number.
fn aggregate(a: &BlockCsr) -> (Vec<u32>, usize) {
    const FREE: u32 = u32::MAX;
    let n = a.rows();
    let mut agg = vec![FREE; n];
    let mut count = 0u32;
    // Phase 1: a node with all neighbours free roots an aggregate.
    for r in 0..n {
        let neighbours = &a.cols[a.ptr[r]..a.ptr[r + 1]];
        if agg[r] == FREE && neighbours.iter().all(|&c| agg[c as usize] == FREE) {
            agg[r] = count;
            for &c in neighbours {
                agg[c as usize] = count;
            }
            count += 1;
        }
    }
    // Phase 2: the rest join an aggregate of a neighbour (one of phase 1's).
    let first = agg.clone();
    for r in 0..n {
        if agg[r] == FREE {
            let joined = a.cols[a.ptr[r]..a.ptr[r + 1]]
                .iter()
                .map(|&c| first[c as usize])
                .find(|&g| g != FREE);
            agg[r] = joined.unwrap_or_else(|| {
                count += 1;
                count - 1
            });
        }
    }
    (agg, count as usize)
}

/// The rows `start..end` of a block matrix with row pointers `ptr`, in
/// ranges of `per` rows, each with its own (disjoint) slices of the
/// column indices and blocks: the work items of a parallel fill.
type RowRange<'a> = (usize, usize, &'a mut [u32], &'a mut [Block]);

fn split_rows<'a>(
    ptr: &[usize],
    per: usize,
    cols: &'a mut [u32],
    vals: &'a mut [Block],
) -> Vec<RowRange<'a>> {
    let rows = ptr.len() - 1;
    let mut parts = Vec::with_capacity(rows.div_ceil(per.max(1)));
    let (mut c_rest, mut v_rest) = (cols, vals);
    for start in (0..rows).step_by(per.max(1)) {
        let end = (start + per).min(rows);
        let len = ptr[end] - ptr[start];
        let (c, cr) = std::mem::take(&mut c_rest).split_at_mut(len);
        let (v, vr) = std::mem::take(&mut v_rest).split_at_mut(len);
        (c_rest, v_rest) = (cr, vr);
        parts.push((start, end, c, v));
    }
    parts
}

/// How many row ranges a loop over `rows` rows is cut into: a few per
/// thread on large matrices (for balance), one on small ones.
fn ranges_for(rows: usize) -> usize {
    if rows > PARALLEL_ROWS {
        4 * rayon::current_num_threads()
    } else {
        1
    }
}

/// Runs `work` on every range, on all threads when there are several.
fn run_ranges<T: Send>(parts: Vec<T>, work: impl Fn(T) + Sync + Send) {
    if parts.len() > 1 {
        parts.into_par_iter().for_each(work);
    } else {
        parts.into_iter().for_each(work);
    }
}

/// Builds a block matrix of `rows` rows and `ncols` columns row by row,
/// in two passes over a few contiguous row ranges (in parallel on large
/// matrices): `count(r, scratch)` gives the length of row `r`, then
/// `fill(r, scratch, cols, vals)` writes it into its final place. The
/// arrays are allocated once at their final size and written once: no
/// growing vectors, no concatenation of per-range parts (on the largest
/// meshes the products hold hundreds of megabytes). `scratch` makes each
/// range's work space, afresh for each pass.
fn build_by_rows<S>(
    rows: usize,
    ncols: usize,
    scratch: impl Fn() -> S + Sync,
    count: impl Fn(usize, &mut S) -> usize + Sync,
    fill: impl Fn(usize, &mut S, &mut [u32], &mut [Block]) + Sync,
) -> BlockCsr {
    let per = rows.div_ceil(ranges_for(rows)).max(1);
    let mut ptr = vec![0usize; rows + 1];
    let lens: Vec<(usize, &mut [usize])> = ptr[1..].chunks_mut(per).enumerate().collect();
    run_ranges(lens, |(i, out)| {
        let mut s = scratch();
        for (j, len) in out.iter_mut().enumerate() {
            *len = count(i * per + j, &mut s);
        }
    });
    for r in 0..rows {
        ptr[r + 1] += ptr[r];
    }
    let total = ptr[rows];
    let mut cols = vec![0u32; total];
    let mut vals = vec![[0.0; 9]; total];
    let parts = split_rows(&ptr, per, &mut cols, &mut vals);
    run_ranges(parts, |(start, end, c, v)| {
        let mut s = scratch();
        let base = ptr[start];
        for r in start..end {
            let (a, b) = (ptr[r] - base, ptr[r + 1] - base);
            fill(r, &mut s, &mut c[a..b], &mut v[a..b]);
        }
    });
    BlockCsr {
        ptr,
        cols,
        vals,
        ncols,
    }
}

/// The smoothed prolongator `P = (I - omega D^-1 A) P0` of the aggregation
/// `agg` (`count` aggregates), in one pass over `A`: row `r` of `A P0`
/// sums the blocks `A_rk` of each aggregate `J = agg[k]`, so
/// `P_rJ = [agg[r] = J] I - omega D_r^-1 sum_{agg[k] = J} A_rk`.
fn smoothed_prolongator(
    a: &BlockCsr,
    d_inv: &[Block],
    agg: &[u32],
    count: usize,
    omega: f64,
) -> BlockCsr {
    // The aggregates of a row, in order, with their summed blocks (a row
    // of A meets a handful of aggregates).
    let scratch = || Vec::<(u32, Block)>::new();
    let sums = |r: usize, list: &mut Vec<(u32, Block)>| {
        list.clear();
        for k in a.ptr[r]..a.ptr[r + 1] {
            let g = agg[a.cols[k] as usize];
            match list.iter_mut().find(|e| e.0 == g) {
                Some(e) => {
                    for (s, v) in e.1.iter_mut().zip(&a.vals[k]) {
                        *s += v;
                    }
                }
                None => list.push((g, a.vals[k])),
            }
        }
        list.sort_unstable_by_key(|e| e.0);
        list.len()
    };
    build_by_rows(a.rows(), count, scratch, sums, |r, list, cols, vals| {
        sums(r, list);
        for ((c, v), (g, sum)) in cols.iter_mut().zip(vals.iter_mut()).zip(list.iter()) {
            let mut block = mul(&d_inv[r], sum);
            for x in &mut block {
                *x *= -omega;
            }
            if *g == agg[r] {
                for d in 0..3 {
                    block[4 * d] += 1.0;
                }
            }
            *c = *g;
            *v = block;
        }
    })
}

/// What one node's smoother update reads and writes: `(x, b)`, `(A x, D^-1)`.
type SmootherItem<'a> = ((&'a mut [f64], &'a [f64]), (&'a [f64], &'a Block));

/// One level of the hierarchy.
#[derive(Debug, Clone)]
struct Level {
    a: BlockCsr,
    d_inv: Vec<Block>,
    /// Prolongator to this level from the next coarser one, and its transpose.
    p: BlockCsr,
    pt: BlockCsr,
    /// Jacobi damping `4 / (3 rho(D^-1 A))`.
    omega: f64,
    /// Work vectors: solution, right-hand side, residual.
    x: Vec<f64>,
    b: Vec<f64>,
    r: Vec<f64>,
}

/// A multigrid hierarchy built from one matrix.
#[derive(Debug)]
pub struct Amg {
    levels: Vec<Level>,
    coarse: BlockLu,
    coarse_a: BlockCsr,
    coarse_values: Vec<f64>,
    coarse_x: Vec<f64>,
}

/// Largest eigenvalue modulus of `D^-1 A` by power iterations (a few
/// suffice: only the damping factor depends on it).
fn spectral_radius(a: &BlockCsr, d_inv: &[Block]) -> f64 {
    let n = 3 * a.rows();
    let mut v: Vec<f64> = (0..n)
        .map(|i| 1.0 + ((i * 7919) % 13) as f64 / 13.0)
        .collect();
    let mut w = vec![0.0; n];
    let parallel = a.rows() > PARALLEL_ROWS;
    // w <- D^-1 w, returning |w|^2: summed over fixed runs of
    // `SUM_NODES` nodes, then the runs' sums in order, so that the result
    // does not depend on the threads (rayon's own `sum` splits by them).
    let scale = |w: &mut [f64]| -> f64 {
        let run = |(ws, ds): (&mut [f64], &[Block])| -> f64 {
            ws.chunks_mut(3)
                .zip(ds)
                .map(|(wn, d)| {
                    let t = mul_vec(d, wn);
                    wn.copy_from_slice(&t);
                    t[0] * t[0] + t[1] * t[1] + t[2] * t[2]
                })
                .sum()
        };
        let runs: Vec<f64> = if parallel {
            w.par_chunks_mut(3 * SUM_NODES)
                .zip(d_inv.par_chunks(SUM_NODES))
                .map(run)
                .collect()
        } else {
            w.chunks_mut(3 * SUM_NODES)
                .zip(d_inv.chunks(SUM_NODES))
                .map(run)
                .collect()
        };
        runs.iter().sum()
    };
    let mut vnorm = crate::vecn::norm(&v);
    let mut rho = 1.0;
    for _ in 0..12 {
        a.matvec(&v, &mut w);
        let norm = scale(&mut w).sqrt();
        if norm == 0.0 || vnorm == 0.0 {
            break;
        }
        rho = norm / vnorm;
        let normalise = |(vi, wi): (&mut f64, &f64)| *vi = wi / norm;
        if parallel {
            v.par_iter_mut().zip(w.par_iter()).for_each(normalise);
        } else {
            v.iter_mut().zip(&w).for_each(normalise);
        }
        vnorm = 1.0;
    }
    rho.max(1e-300)
}

/// A coarse matrix (structurally symmetric) in the scalar CSC layout of
/// [`super::SparsePattern`], for the node-block LU.
fn to_pattern_layout(a: &BlockCsr) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let ptr = a.ptr.clone();
    let rows: Vec<usize> = a.cols.iter().map(|&c| c as usize).collect();
    let mut values = vec![0.0; 9 * a.cols.len()];
    for b in 0..a.rows() {
        let deg = ptr[b + 1] - ptr[b];
        for p in ptr[b]..ptr[b + 1] {
            let row = rows[p];
            // Block (row, b) sits in row `row` at column b.
            let k = (ptr[row]..ptr[row + 1])
                .find(|&k| a.cols[k] as usize == b)
                .expect("Galerkin products of a structurally symmetric matrix are");
            let m = &a.vals[k];
            for j in 0..3 {
                for i in 0..3 {
                    values[9 * ptr[b] + 3 * j * deg + 3 * (p - ptr[b]) + i] = m[3 * i + j];
                }
            }
        }
    }
    (ptr, rows, values)
}

impl Amg {
    /// Builds the hierarchy of `a` (block rows of a structurally symmetric
    /// matrix whose diagonal blocks are stored). When the coarsest level
    /// cannot be factorised, `a` is handed back.
    pub fn new(a: BlockCsr) -> Result<Self, BlockCsr> {
        let mut levels = Vec::new();
        let mut current = a;
        while current.rows() > COARSEST_NODES {
            let d_inv = current.diagonal_inverse();
            let omega = 4.0 / (3.0 * spectral_radius(&current, &d_inv));
            let (agg, count) = aggregate(&current);
            if count as f64 > 0.8 * current.rows() as f64 {
                break; // aggregation no longer coarsens
            }
            let p = smoothed_prolongator(&current, &d_inv, &agg, count, omega);
            let pt = p.transpose();
            let coarse = pt.multiply(&current.multiply(&p));
            let n = 3 * current.rows();
            levels.push(Level {
                a: current,
                d_inv,
                p,
                pt,
                omega,
                x: vec![0.0; n],
                b: vec![0.0; n],
                r: vec![0.0; n],
            });
            current = coarse;
        }
        let (ptr, rows, values) = to_pattern_layout(&current);
        let coarse = BlockLu::new(&ptr, &rows).ok().and_then(|mut lu| {
            lu.factorize(&values, false).ok()?;
            Some(lu)
        });
        let Some(coarse) = coarse else {
            return Err(if levels.is_empty() {
                current
            } else {
                levels.swap_remove(0).a
            });
        };
        let n = 3 * current.rows();
        Ok(Self {
            levels,
            coarse,
            coarse_a: current,
            coarse_values: values,
            coarse_x: vec![0.0; n],
        })
    }

    /// The finest level's matrix.
    pub fn finest(&self) -> &BlockCsr {
        self.levels.first().map_or(&self.coarse_a, |l| &l.a)
    }

    /// Takes the hierarchy apart, returning the finest level's matrix (to
    /// refill for the next build without allocating it again).
    pub fn into_finest(mut self) -> BlockCsr {
        if self.levels.is_empty() {
            self.coarse_a
        } else {
            self.levels.swap_remove(0).a
        }
    }

    /// Replaces the finest level's values by `fill` and refreshes what
    /// depends on them there (its smoother; the factor, if it is the only
    /// level), keeping the coarse levels: a preconditioner for a matrix
    /// that has changed little since the hierarchy was built. `false` if
    /// the single-level factorisation fails.
    pub fn refresh_finest(&mut self, fill: impl FnOnce(&mut [Block])) -> bool {
        match self.levels.first_mut() {
            Some(level) => {
                fill(&mut level.a.vals);
                // (In place: this runs every Newton iteration.)
                level.a.diagonal_inverse_into(&mut level.d_inv);
                true
            }
            None => {
                fill(&mut self.coarse_a.vals);
                let (_, _, values) = to_pattern_layout(&self.coarse_a);
                self.coarse_values = values;
                self.coarse.factorize(&self.coarse_values, false).is_ok()
            }
        }
    }

    /// Number of levels, the directly solved one included.
    pub fn depth(&self) -> usize {
        self.levels.len() + 1
    }

    /// Block rows of every level, finest first.
    pub fn level_sizes(&self) -> Vec<usize> {
        let mut s: Vec<usize> = self.levels.iter().map(|l| l.a.rows()).collect();
        s.push(self.coarse_a.rows());
        s
    }

    /// `x = B^-1 b` by one V-cycle (`x` overwritten).
    pub fn apply(&mut self, b: &[f64], x: &mut [f64]) {
        if self.levels.is_empty() {
            x.copy_from_slice(b);
            self.coarse.solve_in_place(x);
            return;
        }
        self.levels[0].b.copy_from_slice(b);
        self.cycle(0);
        x.copy_from_slice(&self.levels[0].x);
    }

    /// `sweeps` damped block-Jacobi sweeps on `level.x`; with `from_zero`
    /// the first starts from `x = 0` and skips its product with `A`.
    fn smooth(level: &mut Level, sweeps: usize, from_zero: bool) {
        for sweep in 0..sweeps {
            if from_zero && sweep == 0 {
                level.r.fill(0.0);
            } else {
                level.a.matvec(&level.x, &mut level.r);
            }
            let omega = level.omega;
            let (x, b, r, d_inv) = (&mut level.x, &level.b, &level.r, &level.d_inv);
            let update = |((xs, bs), (rs, d)): SmootherItem| {
                let res = [bs[0] - rs[0], bs[1] - rs[1], bs[2] - rs[2]];
                let t = mul_vec(d, &res);
                for i in 0..3 {
                    xs[i] += omega * t[i];
                }
            };
            if d_inv.len() > PARALLEL_ROWS {
                x.par_chunks_mut(3)
                    .zip(b.par_chunks(3))
                    .zip(r.par_chunks(3).zip(d_inv.par_iter()))
                    .for_each(update);
            } else {
                x.chunks_mut(3)
                    .zip(b.chunks(3))
                    .zip(r.chunks(3).zip(d_inv.iter()))
                    .for_each(update);
            }
        }
    }

    /// One V-cycle from level `l` down: `levels[l].x <- B^-1 levels[l].b`.
    fn cycle(&mut self, l: usize) {
        {
            let level = &mut self.levels[l];
            level.x.fill(0.0);
            Self::smooth(level, SWEEPS, true);
            level.a.matvec(&level.x, &mut level.r);
            for (r, b) in level.r.iter_mut().zip(&level.b) {
                *r = b - *r;
            }
        }
        // Coarse correction: x += P A_c^-1 P^T r (recursively).
        if l + 1 < self.levels.len() {
            let (fine, coarse) = self.levels.split_at_mut(l + 1);
            fine[l].pt.matvec(&fine[l].r, &mut coarse[0].b);
            self.cycle(l + 1);
            let (fine, coarse) = self.levels.split_at_mut(l + 1);
            let level = &mut fine[l];
            level.p.matvec(&coarse[0].x, &mut level.r);
        } else {
            let level = &mut self.levels[l];
            level.pt.matvec(&level.r, &mut self.coarse_x);
            self.coarse.solve_in_place(&mut self.coarse_x);
            level.p.matvec(&self.coarse_x, &mut level.r);
        }
        let level = &mut self.levels[l];
        for (x, c) in level.x.iter_mut().zip(&level.r) {
            *x += c;
        }
        Self::smooth(level, SWEEPS, false);
    }

    /// Bytes held by the hierarchy (matrices and prolongators).
    pub fn bytes(&self) -> usize {
        let block = std::mem::size_of::<Block>() + 4;
        self.levels
            .iter()
            .map(|l| (l.a.vals.len() + l.p.vals.len() + l.pt.vals.len()) * block)
            .sum::<usize>()
            + self.coarse.bytes()
            + self.coarse_values.len() * 8
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::pattern::SparsePattern;
    use crate::vecn::dot;

    /// A mass-plus-stiffness-like SPD matrix on an `n x n` triangle grid:
    /// a graph Laplacian in each component (the stiffness, weight 1) plus
    /// `mass` on the diagonal.
    fn grid(n: usize, mass: f64) -> BlockCsr {
        let nodes = (n + 1) * (n + 1);
        let p = SparsePattern::triangle_grid(n, n);
        let (ptr, rows) = p.node_graph();
        let mut vals = Vec::new();
        for r in 0..nodes {
            let deg = (ptr[r + 1] - ptr[r] - 1) as f64;
            for &c in &rows[ptr[r]..ptr[r + 1]] {
                let s = if c == r { deg + mass } else { -1.0 };
                vals.push([s, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, s]);
            }
        }
        BlockCsr {
            ptr: ptr.to_vec(),
            cols: rows.iter().map(|&c| c as u32).collect(),
            vals,
            ncols: nodes,
        }
    }

    /// Preconditioned CG iterations to reduce the residual 1e-8-fold.
    fn pcg_iterations(a: &BlockCsr, amg: &mut Amg) -> usize {
        let n = 3 * a.rows();
        let b: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        let mut x = vec![0.0; n];
        let mut r = b.clone();
        let mut z = vec![0.0; n];
        amg.apply(&r, &mut z);
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        let b_norm = dot(&b, &b).sqrt();
        let mut ap = vec![0.0; n];
        for it in 1..200 {
            a.matvec(&p, &mut ap);
            let alpha = rz / dot(&p, &ap);
            for i in 0..n {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
            }
            if dot(&r, &r).sqrt() < 1e-8 * b_norm {
                return it;
            }
            amg.apply(&r, &mut z);
            let rz_new = dot(&r, &z);
            for i in 0..n {
                p[i] = z[i] + rz_new / rz * p[i];
            }
            rz = rz_new;
        }
        200
    }

    /// Multigrid's point: the PCG iteration count stays flat as the mesh
    /// is refined (here within 2x from 40x40 to 160x160, 16 times the
    /// nodes, on a Laplacian with a small mass term whose condition number
    /// grows 16-fold), where block Jacobi's would grow 4-fold.
    #[test]
    fn iterations_do_not_grow_with_the_mesh() {
        let mut counts = Vec::new();
        for n in [40, 80, 160] {
            let a = grid(n, 1e-3);
            let mut amg = Amg::new(a.clone()).ok().unwrap();
            assert!(amg.depth() >= 2, "{:?}", amg.level_sizes());
            counts.push(pcg_iterations(&a, &mut amg));
            eprintln!(
                "{n}: levels {:?}, iterations {:?}",
                amg.level_sizes(),
                counts.last()
            );
        }
        assert!(
            counts[2] <= 2 * counts[0].max(5),
            "PCG iterations {counts:?}"
        );
        assert!(counts[2] < 60, "PCG iterations {counts:?}");
    }

    /// A matrix small enough for the coarsest level alone is solved
    /// exactly by one application.
    #[test]
    fn a_small_matrix_is_solved_directly() {
        let a = grid(6, 0.5);
        let mut amg = Amg::new(a.clone()).ok().unwrap();
        assert_eq!(amg.depth(), 1);
        let n = 3 * a.rows();
        let b: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let mut x = vec![0.0; n];
        amg.apply(&b, &mut x);
        let mut ax = vec![0.0; n];
        a.matvec(&x, &mut ax);
        let err = ax
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-10, "{err:e}");
    }

    /// The grid matrix with a non-symmetric pseudo-random part in every block.
    fn skewed(n: usize) -> BlockCsr {
        let mut a = grid(n, 1.0);
        for (k, v) in a.vals.iter_mut().enumerate() {
            for (i, x) in v.iter_mut().enumerate() {
                *x += ((k * 31 + i * 7) % 17) as f64 / 17.0 - 0.5;
            }
        }
        a
    }

    /// Transpose, product and smoothed prolongator on a non-symmetric
    /// matrix, on the one-range path (7x7 grid) and on the parallel,
    /// range-split one (151 x 151 = 22,801 block rows): `y . A x = A^T y .
    /// x`, `(A A^T) x = A (A^T x)`, and the one-pass prolongator equals
    /// `P0 - omega D^-1 (A P0)` formed by the general product, block for
    /// block. Tolerances: round-off of sums of a few hundred terms.
    #[test]
    fn transpose_products_and_prolongator_on_both_paths() {
        for n in [6, 150] {
            let a = skewed(n);
            let rows = a.rows();
            let m = 3 * rows;
            let x: Vec<f64> = (0..m).map(|i| (i as f64 * 0.7).sin()).collect();
            let y: Vec<f64> = (0..m).map(|i| (i as f64 * 0.3).cos()).collect();
            let at = a.transpose();
            assert_eq!(at.vals.len(), a.vals.len());
            let (mut ax, mut aty) = (vec![0.0; m], vec![0.0; m]);
            a.matvec(&x, &mut ax);
            at.matvec(&y, &mut aty);
            let (l, r) = (dot(&y, &ax), dot(&aty, &x));
            assert!((l - r).abs() < 1e-10 * l.abs().max(1.0), "{n}: {l} vs {r}");
            // (A A^T) x against A (A^T x).
            let aat = a.multiply(&at);
            let (mut p1, mut atx, mut p2) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
            aat.matvec(&x, &mut p1);
            at.matvec(&x, &mut atx);
            a.matvec(&atx, &mut p2);
            for (p, q) in p1.iter().zip(&p2) {
                assert!((p - q).abs() < 1e-9 * q.abs().max(1.0), "{n}: {p} vs {q}");
            }
            // The prolongator, both ways.
            let d_inv = a.diagonal_inverse();
            let (agg, count) = aggregate(&a);
            let omega = 0.6;
            let p = smoothed_prolongator(&a, &d_inv, &agg, count, omega);
            let p0 = BlockCsr {
                ptr: (0..=rows).collect(),
                cols: agg.clone(),
                vals: vec![IDENTITY; rows],
                ncols: count,
            };
            let mut reference = a.multiply(&p0);
            for r in 0..rows {
                for k in reference.ptr[r]..reference.ptr[r + 1] {
                    let mut block = mul(&d_inv[r], &reference.vals[k]);
                    for v in &mut block {
                        *v *= -omega;
                    }
                    if reference.cols[k] == agg[r] {
                        for d in 0..3 {
                            block[4 * d] += 1.0;
                        }
                    }
                    reference.vals[k] = block;
                }
            }
            assert_eq!(p.ptr, reference.ptr);
            assert_eq!(p.cols, reference.cols);
            for (u, v) in p.vals.iter().zip(&reference.vals) {
                for (s, t) in u.iter().zip(v) {
                    assert!((s - t).abs() < 1e-12 * t.abs().max(1.0));
                }
            }
        }
    }

    /// Transpose and product agree with their definitions on a small case.
    #[test]
    fn transpose_and_product() {
        let a = grid(3, 1.0);
        let at = a.transpose();
        let n = 3 * a.rows();
        let x: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let (mut y1, mut y2) = (vec![0.0; n], vec![0.0; n]);
        // A is symmetric: A^T x = A x.
        a.matvec(&x, &mut y1);
        at.matvec(&x, &mut y2);
        assert!(y1.iter().zip(&y2).all(|(p, q)| (p - q).abs() < 1e-12));
        // (A A) x = A (A x).
        let aa = a.multiply(&a);
        aa.matvec(&x, &mut y2);
        let mut y3 = vec![0.0; n];
        a.matvec(&y1, &mut y3);
        assert!(y2.iter().zip(&y3).all(|(p, q)| (p - q).abs() < 1e-9));
    }
}
