//! The numeric factorisation of the block LU: the left-looking
//! recurrence of the module docs over a range of columns, the updates a
//! half sends to the separator, and the block product `x -= a b` they are
//! made of — by AVX-512 intrinsics, compiled for AVX2 and FMA, or
//! portable, all three by the same fused multiply–adds in the same order.

use super::{BlockLu, BlockLuError, Columns, Contribution, NONE, Padded, Symbolic, Work, ZERO};
use crate::block3::{invert, mul};
use std::ops::Range;

impl Symbolic {
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
pub(super) enum Job<'s, 'c> {
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
    pub(super) fn run(
        &self,
        values: &[f64],
        symmetric: bool,
        job: Job,
    ) -> Result<(), BlockLuError> {
        #[cfg(test)]
        if super::tests::PORTABLE.with(|p| p.get()) {
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
