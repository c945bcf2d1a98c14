//! Vectors of any length as slices `&[f64]`: the dot product, the
//! Euclidean norm and distance, summed in index order.
//!
//! One definition serves Newton's convergence test, the Krylov methods,
//! the contact multipliers and the step's terms, so that the same
//! quantity is summed the same way wherever it is measured. The
//! fixed-size counterparts are [`crate::vec3`] and [`crate::block3`].

/// `a . b`, summed from the first entry (the shorter length of the two).
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Euclidean norm `|v| = sqrt(v . v)`.
#[inline]
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Euclidean distance `|a - b|`.
#[inline]
pub fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q) * (p - q))
        .sum::<f64>()
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact in binary floating point: small integers.
    #[test]
    fn dot_norm_and_distance_of_small_integers() {
        assert_eq!(dot(&[1.0, 2.0, 3.0], &[4.0, -5.0, 6.0]), 12.0);
        assert_eq!(norm(&[3.0, 4.0]), 5.0);
        assert_eq!(distance(&[1.0, 1.0], &[4.0, 5.0]), 5.0);
        assert_eq!(norm(&[]), 0.0);
    }
}
