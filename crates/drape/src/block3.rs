//! 3x3 matrices stored row-major in `[f64; 9]`: the node blocks of the
//! Hessian, as the block LU ([`crate::solver::block_lu`]), the multigrid
//! ([`crate::solver::amg`]) and the block-Jacobi preconditioner of the
//! Krylov methods work on them.
//!
//! Beside [`crate::vec3`] rather than inside `solver/`: it is arithmetic
//! of a fixed-size value type that knows nothing of sparse patterns, and
//! kernels outside the solver (a contact or bending term's 3x3 blocks)
//! may use it without reaching into the solver. How a block sits in the
//! scalar values of the Hessian is the pattern's business
//! ([`crate::solver::pattern`]).
//!
//! Products sum over `k` in increasing order, `c_rq = sum_k a_rk b_kq`
//! (the order fixes the bits: the solvers' results do not depend on
//! where a block product is computed).

/// A 3x3 block, row-major: `m[3 r + c]`.
pub type Block = [f64; 9];

/// `a b`.
#[inline(always)]
pub fn mul(a: &Block, b: &Block) -> Block {
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
pub fn mul_acc<const SUBTRACT: bool>(c: &mut Block, a: &Block, b: &Block) {
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
pub const IDENTITY: Block = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];

/// `a^T`.
#[inline(always)]
pub fn transpose(a: &Block) -> Block {
    [a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]]
}

/// `a x` for the three entries of `x`.
#[inline(always)]
pub fn mul_vec(a: &Block, x: &[f64]) -> [f64; 3] {
    [
        a[0] * x[0] + a[1] * x[1] + a[2] * x[2],
        a[3] * x[0] + a[4] * x[1] + a[5] * x[2],
        a[6] * x[0] + a[7] * x[1] + a[8] * x[2],
    ]
}

/// Inverse of a 3x3 block, `None` when its determinant is below `1e-13`
/// of the cube of its largest entry (or not finite).
pub fn invert(m: &Block) -> Option<Block> {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A block with entries of order 1 and condition number about 10.
    const M: Block = [4.0, 1.0, -0.5, 0.3, 3.0, 1.2, -0.7, 0.4, 2.5];

    /// `M^-1 M = I` to round-off (1e-14: a few ulps of entries of order 1
    /// times the condition number), and the product with a vector agrees
    /// with the block product column by column.
    #[test]
    fn inverse_and_products_agree() {
        let inv = invert(&M).unwrap();
        for (p, e) in mul(&inv, &M).iter().zip(&IDENTITY) {
            assert!((p - e).abs() < 1e-14, "{p} vs {e}");
        }
        let t = transpose(&M);
        for c in 0..3 {
            let column = [t[3 * c], t[3 * c + 1], t[3 * c + 2]];
            let y = mul_vec(&inv, &column);
            for r in 0..3 {
                assert!((y[r] - IDENTITY[3 * r + c]).abs() < 1e-14);
            }
        }
        let mut c = mul(&M, &inv);
        mul_acc::<true>(&mut c, &M, &inv);
        assert!(c.iter().all(|v| v.abs() < 1e-15), "{c:?}");
        mul_acc::<false>(&mut c, &IDENTITY, &M);
        for (p, e) in c.iter().zip(&M) {
            assert!((p - e).abs() < 1e-15);
        }
    }

    /// A singular block (third row the sum of the first two), a block that
    /// is singular to round-off and a non-finite one have no inverse.
    #[test]
    fn singular_blocks_are_refused() {
        let singular = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 5.0, 7.0, 9.0];
        assert!(invert(&singular).is_none());
        let mut nearly = singular;
        nearly[8] += 1e-15;
        assert!(invert(&nearly).is_none());
        let mut nan = M;
        nan[4] = f64::NAN;
        assert!(invert(&nan).is_none());
    }
}
