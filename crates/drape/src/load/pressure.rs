//! Follower pressure on one element and its tangent.
//!
//! With the current tangents `g_k = sum_b Y^b d phi^b / d xi_k`, the
//! pressure force on node `a` is
//!
//! ```text
//! f^a = p integral phi^a (g_1 x g_2) dxi
//! ```
//!
//! (`g_1 x g_2 dxi` is the current normal times the current area element),
//! and its derivative, with `[v]x` the cross-product matrix (`[v]x u = v x u`):
//!
//! ```text
//! d f^a / d Y^b = p integral phi^a ( d phi^b/d xi_2 [g_1]x - d phi^b/d xi_1 [g_2]x ) dxi
//! ```
//!
//! The load is not conservative in general, so this tangent is not
//! symmetric element by element; on a membrane whose edge is held, the
//! assembled tangent is the (symmetric) Hessian of `-p V` with `V` the
//! enclosed volume.

use crate::mesh::ElementOrder;
use crate::mesh::lagrange::{MAX_NODES, ShapeFunctions};
use crate::quadrature::QuadratureRule;
use crate::vec3::cross;

/// Shape function values and reference derivatives at the points of the
/// pressure rule (degree `3p - 2`), shared by all elements.
#[derive(Debug, Clone)]
pub struct PressureQuadrature {
    nodes: usize,
    points: Vec<(f64, [f64; MAX_NODES], [[f64; 2]; MAX_NODES])>,
}

impl PressureQuadrature {
    /// The rule for elements of `order`.
    pub fn new(order: ElementOrder) -> Self {
        let shape = ShapeFunctions::new(order);
        let rule = QuadratureRule::of_degree(3 * order.degree() - 2);
        let points = rule
            .points
            .iter()
            .zip(&rule.weights)
            .map(|(xi, w)| {
                let (phi, dphi) = shape.evaluate(*xi);
                (*w, phi, dphi)
            })
            .collect();
        Self {
            nodes: shape.len(),
            points,
        }
    }
}

/// Adds the pressure force of one element to `f` (`3n`) and, if given, its
/// derivative `d f / d Y` to `k` (`3n x 3n`, row-major) multiplied by
/// `k_sign` (the Hessian of the residual takes `-d f_ext / d Y`).
pub fn add_pressure_force(
    pressure: f64,
    y: &[[f64; 3]],
    quadrature: &PressureQuadrature,
    f: &mut [f64],
    k: Option<&mut [f64]>,
    k_sign: f64,
) {
    let n = quadrature.nodes;
    let m = 3 * n;
    let mut k = k;
    for (w, phi, dphi) in &quadrature.points {
        let mut g = [[0.0; 3]; 2];
        for a in 0..n {
            for i in 0..3 {
                g[0][i] += y[a][i] * dphi[a][0];
                g[1][i] += y[a][i] * dphi[a][1];
            }
        }
        let normal = cross(g[0], g[1]);
        let pw = pressure * w;
        for a in 0..n {
            for i in 0..3 {
                f[3 * a + i] += pw * phi[a] * normal[i];
            }
        }
        let Some(k) = k.as_deref_mut() else { continue };
        for a in 0..n {
            let s = k_sign * pw * phi[a];
            for b in 0..n {
                // v = d phi^b/d xi_2 g_1 - d phi^b/d xi_1 g_2;  block = s [v]x.
                let v = [
                    dphi[b][1] * g[0][0] - dphi[b][0] * g[1][0],
                    dphi[b][1] * g[0][1] - dphi[b][0] * g[1][1],
                    dphi[b][1] * g[0][2] - dphi[b][0] * g[1][2],
                ];
                let r0 = (3 * a) * m + 3 * b;
                let (r1, r2) = (r0 + m, r0 + 2 * m);
                k[r0 + 1] -= s * v[2];
                k[r0 + 2] += s * v[1];
                k[r1] += s * v[2];
                k[r1 + 2] -= s * v[0];
                k[r2] -= s * v[1];
                k[r2 + 1] += s * v[0];
            }
        }
    }
}
