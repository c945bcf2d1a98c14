//! The positive semi-definite part of a small symmetric matrix: how a term
//! of the step's incremental potential projects its stencil Hessians
//! (an element's, a bending patch's, a contact pair's) before they are
//! summed, so that the sum — with the mass term, positive definite — is
//! a matrix Cholesky factorises and whose Newton direction descends
//! (Teran, Sifakis, Irving & Fedkiw 2005, "Robust quasistatic finite
//! elements and flesh simulation"; Li et al. 2020, "Incremental
//! Potential Contact", §4; docs/theory.md §1.7).
//!
//! For a symmetric `K = U diag(lambda) U^T` the projection is
//!
//! ```text
//! K+ = U diag(max(lambda_i, 0)) U^T
//! ```
//!
//! the positive semi-definite matrix nearest to `K` in the Frobenius norm
//! (Higham 1988). Most stencil Hessians are already semi-definite where a
//! run needs them projected; they are recognised by a Cholesky
//! factorisation of `K + delta I` with `delta = 1e-10 max |K_ii|` (it
//! succeeds exactly when `K`'s smallest eigenvalue is above `-delta`,
//! up to round-off) and left untouched, so the projection of a
//! semi-definite Hessian is that Hessian to the bit. Only the others pay
//! for a symmetric eigendecomposition (faer's, into reused storage: the
//! projector allocates nothing after it is made).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::{
    LltRegularization, cholesky_in_place, cholesky_in_place_scratch,
};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::{ColMut, MatMut, MatRef, Par};

/// Largest matrix a [`Projector`] takes: a T10 element (10 nodes). A
/// bending patch (up to 18 nodes) is not projected here: it takes its
/// Gauss–Newton part (`bending::kernel::evaluate_with`).
pub const MAX_DIM: usize = 30;

/// Relative shift of the semi-definiteness test: eigenvalues above
/// `-DELTA max |K_ii|` count as non-negative (round-off of a Hessian
/// with rigid-body null modes is ~1e-15 of its diagonal).
const DELTA: f64 = 1e-10;

/// Projects small symmetric matrices to their positive semi-definite
/// part; holds the scratch of the test and of the eigendecomposition.
pub struct Projector {
    a: Vec<f64>,
    u: Vec<f64>,
    s: Vec<f64>,
    mem: MemBuffer,
}

impl std::fmt::Debug for Projector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Projector").finish_non_exhaustive()
    }
}

impl Default for Projector {
    fn default() -> Self {
        Self::new()
    }
}

/// [`Projector::project`] with this thread's projector, made on the
/// thread's first projection and kept: the callers (an element loop, a
/// bending patch loop, the contact pairs, on whichever threads run them)
/// allocate nothing per stencil or per assembly.
pub fn project(k: &mut [f64], m: usize, stride: usize) -> bool {
    thread_local! {
        static PROJECTOR: std::cell::RefCell<Projector> = std::cell::RefCell::new(Projector::new());
    }
    PROJECTOR.with(|p| p.borrow_mut().project(k, m, stride))
}

impl Projector {
    /// A projector for matrices up to [`MAX_DIM`] x [`MAX_DIM`].
    pub fn new() -> Self {
        let par = Par::Seq;
        let req = StackReq::any_of(&[
            cholesky_in_place_scratch::<f64>(MAX_DIM, par, Default::default()),
            evd::self_adjoint_evd_scratch::<f64>(
                MAX_DIM,
                ComputeEigenvectors::Yes,
                par,
                Default::default(),
            ),
        ]);
        Self {
            a: vec![0.0; MAX_DIM * MAX_DIM],
            u: vec![0.0; MAX_DIM * MAX_DIM],
            s: vec![0.0; MAX_DIM],
            mem: MemBuffer::new(req),
        }
    }

    /// Replaces the symmetric `m x m` matrix `k` (entry `(i, j)` at
    /// `k[i * stride + j]`; only this block is read and written) by its
    /// positive semi-definite part `K+` (module docs). Returns whether it
    /// changed it: `false` when `K` was semi-definite (within the test's
    /// shift), and then `k` is untouched.
    ///
    /// # Panics
    /// If `m > MAX_DIM` or `k` is shorter than the block (programming
    /// errors: the callers' stencils are bounded).
    pub fn project(&mut self, k: &mut [f64], m: usize, stride: usize) -> bool {
        assert!(m <= MAX_DIM, "a stencil Hessian of {m} > {MAX_DIM} rows");
        if m == 0 {
            return false;
        }
        let scale = (0..m).fold(0.0f64, |s, i| s.max(k[i * stride + i].abs()));
        if scale == 0.0 && (0..m * m).all(|ij| k[(ij / m) * stride + ij % m] == 0.0) {
            return false;
        }
        if self.semi_definite(k, m, stride, scale) {
            return false;
        }
        for j in 0..m {
            for i in 0..m {
                self.a[j * m + i] = k[i * stride + j];
            }
        }
        let a = MatRef::from_column_major_slice(&self.a[..m * m], m, m);
        let u = MatMut::from_column_major_slice_mut(&mut self.u[..m * m], m, m);
        let s = ColMut::from_slice_mut(&mut self.s[..m]).as_diagonal_mut();
        let stack = MemStack::new(&mut self.mem);
        if evd::self_adjoint_evd(a, s, Some(u), Par::Seq, stack, Default::default()).is_err() {
            // The eigensolver did not converge (a matrix with NaN): a
            // clean zero is the only semi-definite answer at hand.
            for i in 0..m {
                k[i * stride..i * stride + m].fill(0.0);
            }
            return true;
        }
        // K+_ij = sum over positive lambda_l of lambda_l u_il u_jl,
        // computed for i <= j and mirrored: exactly symmetric.
        for i in 0..m {
            for j in i..m {
                let mut v = 0.0;
                for l in 0..m {
                    let lambda = self.s[l];
                    if lambda > 0.0 {
                        v += lambda * self.u[l * m + i] * self.u[l * m + j];
                    }
                }
                k[i * stride + j] = v;
                k[j * stride + i] = v;
            }
        }
        true
    }

    /// Whether `K + DELTA scale I` has a Cholesky factor.
    fn semi_definite(&mut self, k: &[f64], m: usize, stride: usize, scale: f64) -> bool {
        for j in 0..m {
            for i in 0..m {
                self.a[j * m + i] = k[i * stride + j];
            }
            self.a[j * m + j] += DELTA * scale;
        }
        let a = MatMut::from_column_major_slice_mut(&mut self.a[..m * m], m, m);
        let stack = MemStack::new(&mut self.mem);
        // No regularisation: a pivot that is not positive fails the test.
        let regularization = LltRegularization {
            dynamic_regularization_delta: 0.0,
            dynamic_regularization_epsilon: 0.0,
        };
        cholesky_in_place(a, regularization, Par::Seq, stack, Default::default()).is_ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric matrix `Q diag(lambda) Q^T` with a rotation `Q` made of
    /// Givens rotations, row-major.
    fn with_eigenvalues(lambda: &[f64]) -> Vec<f64> {
        let m = lambda.len();
        let mut q = vec![0.0; m * m];
        for i in 0..m {
            q[i * m + i] = 1.0;
        }
        for p in 0..m {
            for r in p + 1..m {
                let t = 0.3 + 0.1 * (p + 2 * r) as f64;
                let (c, s) = (t.cos(), t.sin());
                for i in 0..m {
                    let (a, b) = (q[i * m + p], q[i * m + r]);
                    q[i * m + p] = c * a - s * b;
                    q[i * m + r] = s * a + c * b;
                }
            }
        }
        let mut k = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                k[i * m + j] = (0..m)
                    .map(|l| q[i * m + l] * lambda[l] * q[j * m + l])
                    .sum();
            }
        }
        k
    }

    fn eigenvalues(k: &[f64], m: usize) -> Vec<f64> {
        let a = faer::Mat::from_fn(m, m, |i, j| k[i * m + j]);
        let mut s: Vec<f64> = a
            .self_adjoint_eigenvalues(faer::Side::Lower)
            .expect("eigenvalues");
        s.sort_by(f64::total_cmp);
        s
    }

    /// The projection keeps the eigenvectors and clamps the negative
    /// eigenvalues to zero (Higham's nearest semi-definite matrix):
    /// checked by the eigenvalues of the result, to round-off.
    #[test]
    fn negative_eigenvalues_are_clamped_to_zero() {
        let lambda = [3.0, -2.0, 1.0, -0.5, 0.0, 7.0, 2.0, -1e-3, 4.0];
        let mut k = with_eigenvalues(&lambda);
        let mut p = Projector::new();
        assert!(p.project(&mut k, 9, 9));
        let mut want: Vec<f64> = lambda.iter().map(|l| l.max(0.0)).collect();
        want.sort_by(f64::total_cmp);
        for (g, w) in eigenvalues(&k, 9).iter().zip(&want) {
            assert!((g - w).abs() < 1e-12 * 7.0, "{g} against {w}");
        }
        for i in 0..9 {
            for j in 0..9 {
                assert_eq!(k[i * 9 + j], k[j * 9 + i], "symmetric to the bit");
            }
        }
    }

    /// A semi-definite matrix, singular (rigid-body null modes) or not,
    /// is left as it is, to the bit.
    #[test]
    fn a_semi_definite_matrix_is_untouched() {
        for lambda in [
            vec![1.0, 2.0, 3.0, 0.5, 4.0, 6.0],
            vec![1.0, 0.0, 3.0, 0.0, 0.0, 6.0],
        ] {
            let k0 = with_eigenvalues(&lambda);
            let mut k = k0.clone();
            assert!(!Projector::new().project(&mut k, 6, 6));
            assert_eq!(k, k0);
        }
    }

    /// A block inside a larger array (the bending patch's fixed-size
    /// Hessian) is projected in place; the rest of the array is untouched.
    #[test]
    fn a_strided_block_is_projected_in_place() {
        let k0 = with_eigenvalues(&[1.0, -1.0, 2.0]);
        let mut big = vec![9.0; 5 * 5];
        for i in 0..3 {
            for j in 0..3 {
                big[i * 5 + j] = k0[i * 3 + j];
            }
        }
        assert!(Projector::new().project(&mut big, 3, 5));
        let mut small = k0.clone();
        Projector::new().project(&mut small, 3, 3);
        for i in 0..5 {
            for j in 0..5 {
                let want = if i < 3 && j < 3 {
                    small[i * 3 + j]
                } else {
                    9.0
                };
                assert_eq!(big[i * 5 + j], want);
            }
        }
    }
}
