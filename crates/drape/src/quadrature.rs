//! Quadrature rules on the reference triangle (area 1/2).
//!
//! | degree | points | rule |
//! |---|---|---|
//! | 0–1 | 1 | centroid |
//! | 2 | 3 | Strang & Fix (1973), points `(1/6, 1/6)`, `(2/3, 1/6)`, `(1/6, 2/3)` |
//! | 3–4 | 6 | Dunavant (1985), *High degree efficient symmetrical Gaussian quadrature rules for the triangle*, IJNME 21, degree 4 |
//! | 5+ | `n^2` | Stroud (1971), conical product: Gauss–Legendre in `u` and `v`, `xi1 = u`, `xi2 = v (1 - u)`, weight `w_u w_v (1 - u)`, with `n = ceil((d + 2) / 2)` |
//!
//! The element uses, for order `p`: degree `4(p - 1)` for the strain energy
//! of Saint-Venant–Kirchhoff (exact: `E` is of degree `2(p - 1)` on a
//! straight element), `2p` for the consistent mass (exact), `3p - 2` for the
//! follower pressure and `p` for dead surface loads (both exact on straight
//! elements). Every rule is tested on all monomials up to its degree.

/// Points (reference coordinates) and weights; the weights sum to 1/2.
#[derive(Debug, Clone, PartialEq)]
pub struct QuadratureRule {
    /// Points `(xi1, xi2)`.
    pub points: Vec<[f64; 2]>,
    /// Weights, summing to the reference area 1/2.
    pub weights: Vec<f64>,
}

impl QuadratureRule {
    /// A rule exact for polynomials of total degree `degree`.
    pub fn of_degree(degree: usize) -> Self {
        match degree {
            0 | 1 => Self {
                points: vec![[1.0 / 3.0, 1.0 / 3.0]],
                weights: vec![0.5],
            },
            2 => {
                let (a, b) = (1.0 / 6.0, 2.0 / 3.0);
                Self {
                    points: vec![[a, a], [b, a], [a, b]],
                    weights: vec![1.0 / 6.0; 3],
                }
            }
            3 | 4 => {
                let (a, wa) = (0.445_948_490_915_965, 0.223_381_589_678_011);
                let (b, wb) = (0.091_576_213_509_771, 0.109_951_743_655_322);
                let mut points = Vec::new();
                let mut weights = Vec::new();
                for (x, w) in [(a, wa), (b, wb)] {
                    let y = 1.0 - 2.0 * x;
                    for p in [[x, x], [y, x], [x, y]] {
                        points.push(p);
                        weights.push(0.5 * w);
                    }
                }
                Self { points, weights }
            }
            d => Self::conical_product((d + 2).div_ceil(2)),
        }
    }

    /// Stroud's conical product rule with `n` Gauss–Legendre points per
    /// direction: exact to degree `2n - 2`.
    pub fn conical_product(n: usize) -> Self {
        let (x, w) = gauss_legendre_unit(n);
        let mut points = Vec::with_capacity(n * n);
        let mut weights = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n {
                let u = x[i];
                points.push([u, x[j] * (1.0 - u)]);
                weights.push(w[i] * w[j] * (1.0 - u));
            }
        }
        Self { points, weights }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True for a rule without points (never built here).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// Gauss–Legendre nodes and weights on `[0, 1]`, by Newton's method on the
/// Legendre polynomial `P_n` from Chebyshev initial guesses.
pub fn gauss_legendre_unit(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let kf = k as f64;
                let p2 = ((2.0 * kf - 1.0) * z * p1 - (kf - 1.0) * p0) / kf;
                p0 = p1;
                p1 = p2;
            }
            // Here p1 = P_n(z) and p0 = P_{n-1}(z).
            dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                break;
            }
        }
        x[i] = 0.5 * (1.0 - z);
        w[i] = 1.0 / ((1.0 - z * z) * dp * dp);
    }
    (x, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn factorial(n: u32) -> f64 {
        (1..=n).map(f64::from).product()
    }

    /// `∫_T xi1^i xi2^j = i! j! / (i + j + 2)!` on the reference triangle.
    #[test]
    fn every_rule_integrates_its_monomials_exactly() {
        for degree in 0..=10usize {
            let rule = QuadratureRule::of_degree(degree);
            for i in 0..=degree as u32 {
                for j in 0..=(degree as u32 - i) {
                    let exact = factorial(i) * factorial(j) / factorial(i + j + 2);
                    let q: f64 = rule
                        .points
                        .iter()
                        .zip(&rule.weights)
                        .map(|(p, w)| w * p[0].powi(i as i32) * p[1].powi(j as i32))
                        .sum();
                    // Dunavant's tabulated points carry 15 digits.
                    assert!(
                        (q - exact).abs() < 1e-14,
                        "degree {degree}: x^{i} y^{j}: {q} vs {exact}"
                    );
                }
            }
        }
    }

    #[test]
    fn point_counts_are_the_cited_ones() {
        assert_eq!(QuadratureRule::of_degree(0).len(), 1);
        assert_eq!(QuadratureRule::of_degree(2).len(), 3);
        assert_eq!(QuadratureRule::of_degree(4).len(), 6);
        assert_eq!(QuadratureRule::of_degree(6).len(), 16);
        assert_eq!(QuadratureRule::of_degree(8).len(), 25);
    }
}
