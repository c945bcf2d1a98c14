//! Mass matrix and consistent load weights (docs/theory.md §1.5).

use super::ModelError;
use crate::element::geometry::tangents;
use crate::mesh::lagrange::{MAX_NODES, ShapeFunctions};
use crate::mesh::{ElementOrder, Mesh};
use crate::quadrature::QuadratureRule;
use crate::solver::SparsePattern;
use crate::vec3::{cross, norm};

/// How the mass matrix is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MassKind {
    /// `M^ab = integral rho t phi^a phi^b dA0 I3`, exact quadrature of degree `2p`.
    Consistent,
    /// Diagonal. Order 1: row sums of the consistent matrix. Orders 2 and
    /// 3: row sums give zero or negative vertex masses (`integral phi^a dA0
    /// = 0` at the vertices of a quadratic triangle), so the diagonal of the
    /// consistent matrix is scaled to the element mass instead (Hinton,
    /// Rock & Zienkiewicz 1976, "HRZ" lumping).
    Lumped,
}

/// Element-by-element evaluation of `integral phi^a phi^b dA0` (`n x n`)
/// and `integral phi^a dA0` (`n`), by the degree-`2p` rule.
fn element_integrals(mesh: &Mesh, mut visit: impl FnMut(usize, &[f64], &[f64])) {
    let shape = ShapeFunctions::new(mesh.order);
    let n = shape.len();
    let rule = QuadratureRule::of_degree(2 * mesh.order.degree());
    let reference: Vec<_> = rule.points.iter().map(|p| shape.evaluate(*p)).collect();
    let mut x = [[0.0; 3]; MAX_NODES];
    let mut mm = vec![0.0; n * n];
    let mut m1 = vec![0.0; n];
    for (e, el) in mesh.elements().enumerate() {
        for (a, &node) in el.iter().enumerate() {
            x[a] = mesh.nodes[node];
        }
        mm.fill(0.0);
        m1.fill(0.0);
        for ((phi, dphi), w) in reference.iter().zip(&rule.weights) {
            let [g1, g2] = tangents(&x[..n], &dphi[..n]);
            let da = w * norm(cross(g1, g2));
            for a in 0..n {
                m1[a] += da * phi[a];
                for b in 0..n {
                    mm[a * n + b] += da * phi[a] * phi[b];
                }
            }
        }
        visit(e, &mm, &m1);
    }
}

/// The mass matrix on the node graph of `pattern`, for mass per unit area
/// `rho_t` (kg/m^2).
pub(super) fn assemble_mass(
    mesh: &Mesh,
    pattern: &SparsePattern,
    rho_t: f64,
    kind: MassKind,
) -> Result<Vec<f64>, ModelError> {
    let (ptr, _) = pattern.node_graph();
    let mut values = vec![0.0; ptr[mesh.node_count()]];
    let n = mesh.order.nodes_per_element();
    element_integrals(mesh, |e, mm, _| {
        let el = mesh.element(e);
        let lumped = |a: usize| -> f64 {
            if mesh.order == ElementOrder::Linear {
                (0..n).map(|b| mm[a * n + b]).sum()
            } else {
                let total: f64 = mm.iter().sum();
                let diagonal: f64 = (0..n).map(|b| mm[b * n + b]).sum();
                mm[a * n + a] * total / diagonal
            }
        };
        for a in 0..n {
            for b in 0..n {
                let m = match kind {
                    MassKind::Consistent => mm[a * n + b],
                    MassKind::Lumped if a == b => lumped(a),
                    MassKind::Lumped => continue,
                };
                if let Some(p) = pattern.node_block(el[a], el[b]) {
                    values[p] += rho_t * m;
                }
            }
        }
    });
    if kind == MassKind::Lumped {
        for a in 0..mesh.node_count() {
            if let Some(p) = pattern.node_block(a, a)
                && values[p] <= 0.0
            {
                return Err(ModelError::NonPositiveMass {
                    node: a,
                    mass: values[p],
                });
            }
        }
    }
    Ok(values)
}

/// `integral phi^a dA0` per node (m^2).
pub(super) fn area_weights(mesh: &Mesh) -> Vec<f64> {
    let mut w = vec![0.0; mesh.node_count()];
    element_integrals(mesh, |e, _, m1| {
        for (a, &node) in mesh.element(e).iter().enumerate() {
            w[node] += m1[a];
        }
    });
    w
}
