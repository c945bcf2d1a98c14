//! Lagrange shape functions `phi^a(xi1, xi2)` of order 1–3 on the reference
//! triangle `{xi1 >= 0, xi2 >= 0, xi1 + xi2 <= 1}`.
//!
//! The basis is built from the monomials `xi1^i xi2^j` (`i + j <= p`) by
//! inverting their Vandermonde matrix at the element's nodes, so the same
//! code serves every order and the Kronecker property `phi^a(xi_b) =
//! delta_ab` holds by construction (tested). Node order: see [`crate::mesh`].

use super::ElementOrder;

/// Most nodes an element can have (order 3).
pub const MAX_NODES: usize = 10;

/// Values and reference derivatives of the shape functions at one point:
/// `phi[a]` and `dphi[a] = [d phi^a / d xi1, d phi^a / d xi2]`.
pub type ShapeValues = ([f64; MAX_NODES], [[f64; 2]; MAX_NODES]);

/// The Lagrange basis of one order.
#[derive(Debug, Clone)]
pub struct ShapeFunctions {
    order: ElementOrder,
    /// Monomial exponents `(i, j)`.
    exponents: Vec<(i32, i32)>,
    /// `coefficients[a][m]`: coefficient of monomial `m` in `phi^a`.
    coefficients: Vec<Vec<f64>>,
    nodes: Vec<[f64; 2]>,
    check_points: Vec<[f64; 2]>,
}

/// Reference coordinates of the nodes of an element of the given order, in
/// the mesh's node order.
pub fn reference_nodes(order: ElementOrder) -> Vec<[f64; 2]> {
    let t = 1.0 / 3.0;
    match order {
        ElementOrder::Linear => vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        ElementOrder::Quadratic => vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [0.0, 1.0],
            [0.5, 0.0],
            [0.5, 0.5],
            [0.0, 0.5],
        ],
        ElementOrder::Cubic => vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [0.0, 1.0],
            [t, 0.0],
            [2.0 * t, 0.0],
            [2.0 * t, t],
            [t, 2.0 * t],
            [0.0, 2.0 * t],
            [0.0, t],
            [t, t],
        ],
    }
}

impl ShapeFunctions {
    /// Builds the basis of the given order.
    pub fn new(order: ElementOrder) -> Self {
        let p = order.degree() as i32;
        let mut exponents = Vec::new();
        for total in 0..=p {
            for j in 0..=total {
                exponents.push((total - j, j));
            }
        }
        let nodes = reference_nodes(order);
        let n = nodes.len();
        // Vandermonde V[b][m] = monomial m at node b; phi^a = sum_m C[a][m] mono_m
        // with sum_m C[a][m] V[b][m] = delta_ab, i.e. C = (V^T)^{-1}.
        let mut v = vec![vec![0.0; n]; n];
        for (b, xi) in nodes.iter().enumerate() {
            for (m, &(i, j)) in exponents.iter().enumerate() {
                v[b][m] = xi[0].powi(i) * xi[1].powi(j);
            }
        }
        // Solve V C^T = I  <=>  rows: sum_m V[b][m] C[a][m] = delta_ab.
        let ct = invert(&v);
        let mut coefficients = vec![vec![0.0; n]; n];
        for a in 0..n {
            for m in 0..n {
                coefficients[a][m] = ct[m][a];
            }
        }
        let check_points = crate::quadrature::QuadratureRule::of_degree(4).points;
        Self {
            order,
            exponents,
            coefficients,
            nodes,
            check_points,
        }
    }

    /// The element order.
    pub fn order(&self) -> ElementOrder {
        self.order
    }

    /// Number of shape functions (nodes).
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Never true; present for symmetry with `len`.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Reference coordinates of the nodes.
    pub fn nodes(&self) -> &[[f64; 2]] {
        &self.nodes
    }

    /// Interior points used to check a curved element's Jacobian.
    pub fn check_points(&self) -> &[[f64; 2]] {
        &self.check_points
    }

    /// `phi^a(xi)` and `d phi^a / d xi_k (xi)`; entries past
    /// [`Self::len`] are zero.
    pub fn evaluate(&self, xi: [f64; 2]) -> ShapeValues {
        let mut phi = [0.0; MAX_NODES];
        let mut dphi = [[0.0; 2]; MAX_NODES];
        for (m, &(i, j)) in self.exponents.iter().enumerate() {
            let value = xi[0].powi(i) * xi[1].powi(j);
            let d1 = if i > 0 {
                f64::from(i) * xi[0].powi(i - 1) * xi[1].powi(j)
            } else {
                0.0
            };
            let d2 = if j > 0 {
                f64::from(j) * xi[0].powi(i) * xi[1].powi(j - 1)
            } else {
                0.0
            };
            for a in 0..self.nodes.len() {
                let c = self.coefficients[a][m];
                phi[a] += c * value;
                dphi[a][0] += c * d1;
                dphi[a][1] += c * d2;
            }
        }
        (phi, dphi)
    }
}

/// Inverse of a small dense matrix by Gauss–Jordan elimination with partial
/// pivoting. Only called on the (well-conditioned) Vandermonde matrices of
/// the reference nodes.
fn invert(a: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = a.len();
    let mut m: Vec<Vec<f64>> = a
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let mut r = row.clone();
            r.extend((0..n).map(|j| if i == j { 1.0 } else { 0.0 }));
            r
        })
        .collect();
    for col in 0..n {
        let pivot = (col..n)
            .max_by(|&x, &y| m[x][col].abs().total_cmp(&m[y][col].abs()))
            .unwrap_or(col);
        m.swap(col, pivot);
        let d = m[col][col];
        for v in m[col].iter_mut() {
            *v /= d;
        }
        for r in 0..n {
            if r != col {
                let f = m[r][col];
                if f != 0.0 {
                    for c in 0..2 * n {
                        m[r][c] -= f * m[col][c];
                    }
                }
            }
        }
    }
    m.into_iter().map(|r| r[n..].to_vec()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const ORDERS: [ElementOrder; 3] = [
        ElementOrder::Linear,
        ElementOrder::Quadratic,
        ElementOrder::Cubic,
    ];

    #[test]
    fn kronecker_property_and_partition_of_unity() {
        for order in ORDERS {
            let s = ShapeFunctions::new(order);
            for (b, xi) in s.nodes().iter().enumerate() {
                let (phi, _) = s.evaluate(*xi);
                for a in 0..s.len() {
                    let expected = if a == b { 1.0 } else { 0.0 };
                    assert!((phi[a] - expected).abs() < 1e-12, "{order:?} a={a} b={b}");
                }
            }
            let (phi, dphi) = s.evaluate([0.21, 0.37]);
            let sum: f64 = phi.iter().sum();
            let dsum: [f64; 2] = [
                dphi.iter().map(|d| d[0]).sum(),
                dphi.iter().map(|d| d[1]).sum(),
            ];
            assert!((sum - 1.0).abs() < 1e-13);
            assert!(dsum[0].abs() < 1e-12 && dsum[1].abs() < 1e-12);
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for order in ORDERS {
            let s = ShapeFunctions::new(order);
            let xi = [0.23, 0.41];
            let h = 1e-6;
            let (_, d) = s.evaluate(xi);
            let (pp, _) = s.evaluate([xi[0] + h, xi[1]]);
            let (pm, _) = s.evaluate([xi[0] - h, xi[1]]);
            let (qp, _) = s.evaluate([xi[0], xi[1] + h]);
            let (qm, _) = s.evaluate([xi[0], xi[1] - h]);
            for a in 0..s.len() {
                // Central differences of a cubic: error O(h^2) ~ 1e-12.
                assert!((d[a][0] - (pp[a] - pm[a]) / (2.0 * h)).abs() < 1e-8);
                assert!((d[a][1] - (qp[a] - qm[a]) / (2.0 * h)).abs() < 1e-8);
            }
        }
    }
}
