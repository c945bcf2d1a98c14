//! Reference geometry of every element at its quadrature points, computed
//! once: material gradients of the shape functions and integration weights.
//!
//! At a point with initial tangents `G_k = sum_a X^a d phi^a / d xi_k`, the
//! local orthonormal frame is `e1 = G_1 / |G_1|`, `e3 = G_1 x G_2 / |G_1 x
//! G_2|`, `e2 = e3 x e1`; `J0[b][k] = e_b . G_k`; `dA0 = det(J0) dxi =
//! |G_1 x G_2| dxi`; `grad phi^a = J0^{-T} d phi^a / d xi` (docs/theory.md §1.2).
//!
//! A material with axes (an orthotropic fabric, [`crate::material::Material::axis`])
//! takes instead `e1` along its axis `a` projected on the tangent plane,
//! `e1 = (a - (a . e3) e3) / |...|`: the strains are then in the material's
//! axes, whatever the node numbering. The projection must be at least
//! [`AXIS_MIN_PROJECTION`] of `|a|` long.

use crate::mesh::Mesh;
use crate::mesh::lagrange::ShapeFunctions;
use crate::quadrature::QuadratureRule;
use crate::vec3::{cross, dot, norm, scale, sub};

/// The shortest projection of a material axis on an element's plane, as a
/// fraction of the axis' length (the axis at most 89.4 degrees from the
/// plane): below it the axis gives no reliable in-plane direction.
pub const AXIS_MIN_PROJECTION: f64 = 1e-2;

/// The unit projection of `axis` on the plane of unit normal `normal`, or
/// `None` when it is shorter than [`AXIS_MIN_PROJECTION`] `|axis|` (or not
/// finite).
pub fn in_plane_axis(axis: [f64; 3], normal: [f64; 3]) -> Option<[f64; 3]> {
    let t = sub(axis, scale(normal, dot(axis, normal)));
    let len = norm(t);
    (len >= AXIS_MIN_PROJECTION * norm(axis) && len > 0.0).then(|| scale(t, 1.0 / len))
}

/// The 2x2 initial mapping gradient `J0` and the reference area element
/// `det J0` at one point with initial tangents `g1`, `g2`.
#[allow(non_snake_case)]
pub fn initial_mapping(g1: [f64; 3], g2: [f64; 3]) -> ([[f64; 2]; 2], f64) {
    let n = cross(g1, g2);
    let e1 = scale(g1, 1.0 / norm(g1));
    initial_mapping_in(g1, g2, e1, scale(n, 1.0 / norm(n)))
}

/// [`initial_mapping`] in the frame with first axis `e1` (a unit vector
/// in the plane of unit normal `e3`).
#[allow(non_snake_case)]
fn initial_mapping_in(
    g1: [f64; 3],
    g2: [f64; 3],
    e1: [f64; 3],
    e3: [f64; 3],
) -> ([[f64; 2]; 2], f64) {
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

/// `J0^{-1}` at a point: [`to_material`] maps a reference derivative
/// through it.
type InverseMapping = [[f64; 2]; 2];

/// The material gradient `J0^{-T} d phi / d xi` of a reference derivative
/// `d`.
fn to_material(inv: &InverseMapping, d: [f64; 2]) -> [f64; 2] {
    [
        inv[0][0] * d[0] + inv[1][0] * d[1],
        inv[0][1] * d[0] + inv[1][1] * d[1],
    ]
}

/// At a point of `element` with initial tangents `[g1, g2]`: `J0^{-1}`
/// (in the frame along `axis` when there is one) and `det J0`.
#[allow(non_snake_case)]
fn point_mapping(
    [g1, g2]: [[f64; 3]; 2],
    axis: Option<[f64; 3]>,
    element: usize,
) -> Result<(InverseMapping, f64), AxisError> {
    let (J0, det) = match axis {
        None => initial_mapping(g1, g2),
        Some(axis) => {
            let n = cross(g1, g2);
            let e3 = scale(n, 1.0 / norm(n));
            let e1 = in_plane_axis(axis, e3).ok_or(AxisError { element, axis })?;
            initial_mapping_in(g1, g2, e1, e3)
        }
    };
    let inv = [
        [J0[1][1] / det, -J0[0][1] / det],
        [-J0[1][0] / det, J0[0][0] / det],
    ];
    Ok((inv, det))
}

/// `[mesh] membrane`: where a curved element (T6, T10) measures its
/// membrane strain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MembraneIntegration {
    /// `sub-triangles` for a fabric with bending, `curved` for a pure
    /// membrane ([`MembraneIntegration::resolve`]).
    #[default]
    Auto,
    /// The element's own interpolation, integrated exactly (degree
    /// `4 (p - 1)`): the quadratic or cubic membrane of release 1.
    Curved,
    /// On the element's flat sub-triangles, each a linear triangle
    /// ([`ElementGeometry::on_sub_triangles`]): the membrane the bending
    /// sees, free of membrane locking.
    SubTriangles,
}

impl MembraneIntegration {
    /// `auto` made definite for a model with (`bending`) or without
    /// bending. With bending the curved elements lock: on one node lattice
    /// Peirce's cantilever in T6 reads a chord angle 2.5 deg short of the
    /// elastica's at `E t` = 1e5 N/m and 6.6 deg at 1e6, where T3 is
    /// within 0.15 deg (docs/validation.md, "Higher orders with
    /// bending"); on its sub-triangles it bends as T3 does.
    pub fn resolve(self, bending: bool) -> Self {
        match self {
            MembraneIntegration::Auto if bending => MembraneIntegration::SubTriangles,
            MembraneIntegration::Auto => MembraneIntegration::Curved,
            m => m,
        }
    }
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

/// A material axis lies (nearly) along an element's normal
/// ([`AXIS_MIN_PROJECTION`]).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error(
    "the material axis {axis:?} is normal to element {element} (its projection on the element's plane is shorter than {AXIS_MIN_PROJECTION} of its length), so it gives no direction in the element"
)]
pub struct AxisError {
    /// The element.
    pub element: usize,
    /// The axis.
    pub axis: [f64; 3],
}

impl ElementGeometry {
    /// Computes the geometry of every element of a validated mesh, in the
    /// frames `e1 = G_1 / |G_1|`.
    pub fn new(mesh: &Mesh, rule: &QuadratureRule) -> Self {
        match Self::with_axis(mesh, rule, None) {
            Ok(g) => g,
            Err(_) => unreachable!("no axis, no axis error"),
        }
    }

    /// As [`Self::new`], with the local frames along the material axis
    /// `axis` (projected on each quadrature point's tangent plane) when
    /// there is one; an axis normal to an element is an error naming it.
    pub fn with_axis(
        mesh: &Mesh,
        rule: &QuadratureRule,
        axis: Option<[f64; 3]>,
    ) -> Result<Self, AxisError> {
        let shape = ShapeFunctions::new(mesh.order);
        let n = shape.len();
        let nq = rule.len();
        let reference: Vec<_> = rule.points.iter().map(|p| shape.evaluate(*p)).collect();
        let ne = mesh.element_count();
        let mut grad = Vec::with_capacity(ne * nq * n);
        let mut weight = Vec::with_capacity(ne * nq);
        let mut x = [[0.0; 3]; crate::mesh::lagrange::MAX_NODES];
        for (element, el) in mesh.elements().enumerate() {
            for (a, &node) in el.iter().enumerate() {
                x[a] = mesh.nodes[node];
            }
            for (q, (_, dphi)) in reference.iter().enumerate() {
                let (inv, det) = point_mapping(tangents(&x[..n], &dphi[..n]), axis, element)?;
                grad.extend(dphi[..n].iter().map(|d| to_material(&inv, *d)));
                weight.push(rule.weights[q] * det);
            }
        }
        Ok(Self {
            nodes_per_element: n,
            points_per_element: nq,
            grad,
            weight,
        })
    }

    /// The geometry of a curved mesh's membrane measured on its flat
    /// sub-triangles (`triangles`, `p^2` per element in element order, as
    /// [`crate::bending::triangulate`] cuts them): one point per
    /// sub-triangle, where the deformation gradient is that of the linear
    /// triangle on its three nodes (the other nodes' gradients zero) and
    /// the weight its initial area. The membrane energy of a T6 or T10 is
    /// then that of the T3 mesh of its sub-triangles: a bending mode of the
    /// node lattice that leaves every sub-triangle unstretched costs no
    /// membrane energy, where the curved element's quadratic or cubic
    /// interpolation stretches (membrane locking; docs/theory.md §1.10).
    pub fn on_sub_triangles(
        mesh: &Mesh,
        triangles: &[[usize; 3]],
        axis: Option<[f64; 3]>,
    ) -> Result<Self, AxisError> {
        let n = mesh.order.nodes_per_element();
        let p = mesh.order.degree();
        let nq = p * p;
        let ne = mesh.element_count();
        assert_eq!(triangles.len(), ne * nq, "p^2 sub-triangles per element");
        let mut grad = vec![[0.0; 2]; ne * nq * n];
        let mut weight = Vec::with_capacity(ne * nq);
        const DPHI: [[f64; 2]; 3] = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
        for (element, el) in mesh.elements().enumerate() {
            for q in 0..nq {
                let tri = triangles[element * nq + q];
                let x = tri.map(|a| mesh.nodes[a]);
                let (inv, det) = point_mapping(tangents(&x, &DPHI), axis, element)?;
                for (v, &node) in tri.iter().enumerate() {
                    let a = el
                        .iter()
                        .position(|&b| b == node)
                        .expect("a sub-triangle's nodes are its element's");
                    grad[(element * nq + q) * n + a] = to_material(&inv, DPHI[v]);
                }
                weight.push(0.5 * det);
            }
        }
        Ok(Self {
            nodes_per_element: n,
            points_per_element: nq,
            grad,
            weight,
        })
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
