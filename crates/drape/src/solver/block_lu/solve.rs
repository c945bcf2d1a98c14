//! The solve with the block LU's factors: forward substitution with `L~`
//! by columns, backward substitution with `U` by rows, each half of a
//! split ordering on its own thread.

use super::{Padded, Symbolic};
use crate::block3::{Block, mul_vec};
use std::ops::Range;

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
    pub(super) fn forward(
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
    pub(super) fn backward(
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
