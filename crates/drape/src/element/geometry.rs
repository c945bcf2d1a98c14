//! Reference geometry of every element at its quadrature points, computed
//! once: material gradients of the shape functions and integration weights.
//!
//! At a point with initial tangents `G_k = sum_a X^a d phi^a / d xi_k`, the
//! local orthonormal frame is `e1 = G_1 / |G_1|`, `e3 = G_1 x G_2 / |G_1 x
//! G_2|`, `e2 = e3 x e1`; `J0[b][k] = e_b . G_k`; `dA0 = det(J0) dxi =
//! |G_1 x G_2| dxi`; `grad phi^a = J0^{-T} d phi^a / d xi` (docs/theory.md §1.2).

use super::lagrange::ShapeFunctions;
use super::quadrature::QuadratureRule;
use crate::mesh::Mesh;
use crate::vec3::{cross, dot, norm, scale};

/// The 2x2 initial mapping gradient `J0` and the reference area element
/// `det J0` at one point with initial tangents `g1`, `g2`.
#[allow(non_snake_case)]
pub fn initial_mapping(g1: [f64; 3], g2: [f64; 3]) -> ([[f64; 2]; 2], f64) {
    let n = cross(g1, g2);
    let e1 = scale(g1, 1.0 / norm(g1));
    let e3 = scale(n, 1.0 / norm(n));
    let e2 = cross(e3, e1);
    let J0 = [[dot(e1, g1), dot(e1, g2)], [dot(e2, g1), dot(e2, g2)]];
    let det = J0[0][0] * J0[1][1] - J0[0][1] * J0[1][0];
    (J0, det)
}

/// Initial tangents `G_k` of element nodes `x` for reference derivatives `dphi`.
pub fn tangents(x: &[[f64; 3]], dphi: &[[f64; 2]]) -> [[f64; 3]; 2] {
    let mut g = [[0.0; 3]; 2];
    for (xa, da) in x.iter().zip(dphi) {
        for k in 0..2 {
            for i in 0..3 {
                g[k][i] += xa[i] * da[k];
            }
        }
    }
    g
}

/// Precomputed reference geometry of all elements for one quadrature rule.
#[derive(Debug, Clone)]
pub struct ElementGeometry {
    nodes_per_element: usize,
    points_per_element: usize,
    /// `grad[(e * nq + q) * n + a]`: material gradient of `phi^a` (1/m).
    grad: Vec<[f64; 2]>,
    /// `weight[e * nq + q] = w_q det J0` (m^2).
    weight: Vec<f64>,
}

impl ElementGeometry {
    /// Computes the geometry of every element of a validated mesh.
    #[allow(non_snake_case)]
    pub fn new(mesh: &Mesh, rule: &QuadratureRule) -> Self {
        let shape = ShapeFunctions::new(mesh.order);
        let n = shape.len();
        let nq = rule.len();
        let reference: Vec<_> = rule.points.iter().map(|p| shape.evaluate(*p)).collect();
        let ne = mesh.element_count();
        let mut grad = Vec::with_capacity(ne * nq * n);
        let mut weight = Vec::with_capacity(ne * nq);
        let mut x = [[0.0; 3]; super::lagrange::MAX_NODES];
        for el in mesh.elements() {
            for (a, &node) in el.iter().enumerate() {
                x[a] = mesh.nodes[node];
            }
            for (q, (_, dphi)) in reference.iter().enumerate() {
                let [g1, g2] = tangents(&x[..n], &dphi[..n]);
                let (J0, det) = initial_mapping(g1, g2);
                // J0^{-T} applied to the reference derivative.
                let inv = [
                    [J0[1][1] / det, -J0[0][1] / det],
                    [-J0[1][0] / det, J0[0][0] / det],
                ];
                for d in &dphi[..n] {
                    grad.push([
                        inv[0][0] * d[0] + inv[1][0] * d[1],
                        inv[0][1] * d[0] + inv[1][1] * d[1],
                    ]);
                }
                weight.push(rule.weights[q] * det);
            }
        }
        Self {
            nodes_per_element: n,
            points_per_element: nq,
            grad,
            weight,
        }
    }

    /// Quadrature points per element.
    pub fn points_per_element(&self) -> usize {
        self.points_per_element
    }

    /// Nodes per element.
    pub fn nodes_per_element(&self) -> usize {
        self.nodes_per_element
    }

    /// Material gradients (`points * nodes`, point-major) and weights of element `e`.
    pub fn element(&self, e: usize) -> (&[[f64; 2]], &[f64]) {
        let (n, nq) = (self.nodes_per_element, self.points_per_element);
        (
            &self.grad[e * nq * n..(e + 1) * nq * n],
            &self.weight[e * nq..(e + 1) * nq],
        )
    }

    /// Initial area of element `e` (m^2), the sum of its weights.
    pub fn area(&self, e: usize) -> f64 {
        self.element(e).1.iter().sum()
    }
}
