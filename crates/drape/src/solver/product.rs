//! Products by the matrix on its CSC pattern: `A x` (the Krylov methods'
//! operator, the block LU's iterative refinement) and the residual
//! `|b - A x|` that checks every direct solve.
//!
//! `A x` takes one of three routes, chosen by size; each sums every row in
//! a fixed order, so results never depend on the threads:
//!
//! * from [`PARALLEL_MATVEC_ABOVE`] unknowns, with a transpose map
//!   (structurally symmetric patterns), row by row on all threads: row `c`
//!   of `A` is column `c` read through the map;
//! * else by columns in two halves, the second half into a buffer of its
//!   own added after — on [`crate::par`]'s helper thread where it runs, on
//!   the calling thread after the first where it does not (one thread, or
//!   `RAYON_NUM_THREADS=1`): the same sums either way.

use faer::sparse::SymbolicSparseColMatRef;
use std::sync::{Mutex, PoisonError};

/// Systems from this many unknowns multiply by the matrix on all threads.
const PARALLEL_MATVEC_ABOVE: usize = 50_000;

/// What `A x` keeps between products: the transpose map and the second
/// half's buffer.
#[derive(Debug, Default)]
pub(super) struct Product {
    /// Mirror of each stored entry about the diagonal (structurally
    /// symmetric patterns): `transpose[k]` is the value index of the entry
    /// mirrored from entry `k`.
    transpose: Option<Vec<usize>>,
    /// The second half's sums of a two-thread product.
    half: Mutex<Vec<f64>>,
}

impl Product {
    /// Products on a pattern with transpose map `transpose`, if known.
    pub(super) fn new(transpose: Option<Vec<usize>>) -> Self {
        Self {
            transpose,
            half: Mutex::new(Vec::new()),
        }
    }

    /// The transpose map, if known.
    pub(super) fn transpose(&self) -> Option<&[usize]> {
        self.transpose.as_deref()
    }

    /// `out = A x` for the values `values` on `pattern`.
    pub(super) fn apply(
        &self,
        pattern: SymbolicSparseColMatRef<'_, usize>,
        values: &[f64],
        x: &[f64],
        out: &mut [f64],
    ) {
        let n = pattern.nrows();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        if let Some(transpose) = self.transpose.as_deref()
            && n >= PARALLEL_MATVEC_ABOVE
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
        // Two halves whether or not a second thread runs the second: the
        // sums, hence the results, do not depend on the threads.
        // The entries are read in storage order: rows by the transpose
        // map cost a gather per entry, and the product took as long as
        // the triangular solves it checks.
        let half = n / 2;
        let mut guard = self.half.lock().unwrap_or_else(PoisonError::into_inner);
        guard.resize(n, 0.0);
        let second: &mut [f64] = &mut guard;
        let columns = |cols: std::ops::Range<usize>, out: &mut [f64]| {
            out.fill(0.0);
            add_columns(col_ptr, row_idx, values, x, cols, out);
        };
        crate::par::join(
            || columns(0..half, &mut out[..n]),
            || columns(half..n, second),
        );
        for (o, s) in out[..n].iter_mut().zip(second.iter()) {
            *o += s;
        }
    }
}

/// `out += A[:, cols] x[cols]`, column by column, skipping zero entries
/// of `x`.
fn add_columns(
    col_ptr: &[usize],
    row_idx: &[usize],
    values: &[f64],
    x: &[f64],
    cols: std::ops::Range<usize>,
    out: &mut [f64],
) {
    for c in cols {
        let xc = x[c];
        if xc != 0.0 {
            let range = col_ptr[c]..col_ptr[c + 1];
            // Zipped slices: one bounds check per column, not per entry.
            for (&r, &v) in row_idx[range.clone()].iter().zip(&values[range]) {
                out[r] += v * xc;
            }
        }
    }
}

/// `|b - A x|` for the values `values` on `pattern`, subtracting column by
/// column from `b`; `r` is the work space (left holding `b - A x`).
pub(super) fn residual_norm(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    values: &[f64],
    x: &[f64],
    b: &[f64],
    r: &mut Vec<f64>,
) -> f64 {
    r.clear();
    r.extend_from_slice(b);
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    for (c, &xc) in x.iter().enumerate().take(pattern.ncols()) {
        for k in col_ptr[c]..col_ptr[c + 1] {
            r[row_idx[k]] -= values[k] * xc;
        }
    }
    crate::vecn::norm(r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::linear::tests::tridiagonal;
    use faer::sparse::SymbolicSparseColMat;

    /// The product by columns in two halves (on two threads where the
    /// helper is available) equals the plain column-by-column sum to
    /// round-off, zero entries of `x` included, and a second product with
    /// the helper's buffer in use gives the same bits.
    #[test]
    fn products_by_columns_in_halves_equal_the_plain_sum() {
        let n = 301;
        let (cp, ri, v) = tridiagonal(n, 0.3);
        let pattern = SymbolicSparseColMat::new_checked(n, n, cp.clone(), None, ri.clone());
        let product = Product::new(None);
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
        product.apply(pattern.as_ref(), &v, &x, &mut out);
        for (o, e) in out.iter().zip(&expected) {
            assert!((o - e).abs() <= 1e-15 * e.abs().max(1.0), "{o} {e}");
        }
        // Again, the helper's buffer now in use.
        let mut again = vec![f64::NAN; n];
        product.apply(pattern.as_ref(), &v, &x, &mut again);
        assert_eq!(out, again);
        // The residual of the exact product is zero to round-off.
        let mut r = Vec::new();
        let norm = residual_norm(pattern.as_ref(), &v, &x, &expected, &mut r);
        assert!(norm <= 1e-14, "{norm:e}");
    }
}
