//! The volume a surface of the fabric's triangles encloses, with its exact
//! gradient and Hessian (docs/theory.md §1.16).
//!
//! By the divergence theorem the volume inside a closed surface `S` is
//!
//! ```text
//! V = 1/3 integral_S (x - o) . n dA = sum_e V_e,
//! V_e = 1/3 integral (x - o) . (g_1 x g_2) dxi
//! ```
//!
//! for any point `o` (the apex), with `x = sum_a phi^a Y^a` and `g_k = sum_a
//! dphi^a/dxi_k Y^a` the element's own interpolation, so that `V_e` is the
//! volume of the cone from `o` over the (curved) element. The integrand
//! is a polynomial of degree `3p - 2` in `xi` (`x` of degree `p`, the
//! tangents of degree `p - 1`), so the follower pressure's rule of that
//! degree integrates it exactly for every order. Differentiating `V_e`:
//!
//! ```text
//! dV_e/dY^a   = 1/3 integral [ phi^a n + dphi^a_1 (g_2 x x) + dphi^a_2 (x x g_1) ] dxi
//! d2V_e/dY^a dY^b = 1/3 integral [ v_ab ]x dxi,
//! v_ab = (dphi^a_1 phi^b - phi^a dphi^b_1) g_2 + (phi^a dphi^b_2 - dphi^a_2 phi^b) g_1
//!      + (dphi^a_2 dphi^b_1 - dphi^a_1 dphi^b_2) (x - o)
//! ```
//!
//! with `n = g_1 x g_2`, `dphi^a_k = dphi^a/dxi_k` and `[v]x` the
//! cross-product matrix; `v_ab = -v_ba`, so the element's Hessian is
//! symmetric (unlike the follower pressure's tangent, whose element
//! blocks only sum to a symmetric matrix on a closed surface). On a closed
//! surface `sum_e dV_e/dY^a` is the follower pressure's force per unit
//! pressure (`load::pressure`).
//!
//! A surface that is not closed is closed by the cone from the apex over
//! its open edges: the formula then measures the volume between the
//! fabric and that cone, which is the cavity's when the open edges lie on
//! rigid walls or symmetry planes through the apex (a clamped rim on a
//! flat base, the cut planes of a symmetric model). [`Cavity::new`]
//! accepts an open edge only then: each node on it held (all three
//! components), or held in a component `i` with `X_i = o_i` (on the
//! symmetry plane `x_i = o_i` through the apex, where it stays). A rigid
//! `chamber` volume may be added (the test rig under a bulge test's disc).

use crate::mesh::lagrange::{MAX_NODES, ShapeFunctions};
use crate::mesh::{ElementOrder, Mesh};
use crate::quadrature::QuadratureRule;
use crate::vec3::{cross, dot, sub};
use std::collections::HashMap;

/// Why a set of triangles encloses no cavity.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CavityError {
    /// No triangles were selected.
    #[error("has no triangles")]
    Empty,
    /// An edge of the surface belongs to one of its triangles only, and
    /// no apex closes it (or its node is neither held nor on a symmetry
    /// plane through the apex).
    #[error(
        "is not closed: the edge between nodes {a} and {b} (0-based) belongs to one of its triangles only{why}"
    )]
    Open {
        /// The open edge's corner nodes.
        a: usize,
        /// See `a`.
        b: usize,
        /// What would close it, in words.
        why: String,
    },
    /// Two triangles run through their shared edge in the same direction:
    /// their normals disagree, and the volume has no sign.
    #[error(
        "is not consistently oriented: elements {first} and {second} run through their edge between nodes {a} and {b} in the same direction"
    )]
    Misoriented {
        /// The edge's nodes.
        a: usize,
        /// See `a`.
        b: usize,
        /// The two elements (0-based).
        first: usize,
        /// See `first`.
        second: usize,
    },
    /// The surface encloses no volume at the start (a flat bag's coincident
    /// plies): the gas's pressure would be infinite.
    #[error(
        "encloses no volume at the start ({volume:e} m^3); give it a shape that encloses some, or a chamber"
    )]
    NoVolume {
        /// The volume (m^3).
        volume: f64,
    },
}

/// One quadrature point: weight, shape function values and derivatives.
type Point = (f64, [f64; MAX_NODES], [[f64; 2]; MAX_NODES]);

/// The surface of a cavity: its triangles, its apex and the orientation
/// that makes its volume positive.
#[derive(Debug, Clone)]
pub struct Cavity {
    /// The surface's elements (indices into the mesh's).
    elements: Vec<usize>,
    /// Their node lists, `nodes` per element.
    connectivity: Vec<usize>,
    apex: [f64; 3],
    /// `+1` or `-1`: the triangles' normals point out of the cavity or in.
    sign: f64,
    /// A rigid volume added (m^3).
    chamber: f64,
    /// Nodes per element.
    nodes: usize,
    points: Vec<Point>,
}

impl Cavity {
    /// The cavity of `elements` (indices into `mesh`'s elements): closed,
    /// or closed by the cone from `apex` over edges held as the module
    /// docs say (`fixed`: the held components, `3 a + i`), plus a rigid
    /// `chamber` (m^3, >= 0). Without an apex it is the centroid of the
    /// surface's nodes (any point gives the same volume of a closed
    /// surface; a near one keeps the round-off small). Its orientation is
    /// taken from its initial volume, which must not be zero unless a
    /// chamber gives the cavity one: a surface that encloses none (a disc
    /// on its own closing plane) is taken with its normals pointing out
    /// of the cavity.
    pub fn new(
        mesh: &Mesh,
        elements: Vec<usize>,
        apex: Option<[f64; 3]>,
        chamber: f64,
        fixed: &[bool],
    ) -> Result<Self, CavityError> {
        if elements.is_empty() {
            return Err(CavityError::Empty);
        }
        check_closed(mesh, &elements, apex, fixed)?;
        let connectivity: Vec<usize> = elements
            .iter()
            .flat_map(|&e| mesh.element(e).iter().copied())
            .collect();
        let apex = apex.unwrap_or_else(|| centroid(mesh, &connectivity));
        let mut cavity = Self {
            elements,
            connectivity,
            apex,
            sign: 1.0,
            chamber,
            nodes: mesh.order.nodes_per_element(),
            points: points(mesh.order),
        };
        let v = cavity.surface_volume(&mesh.nodes.concat());
        if v.abs() <= 1e-9 * mesh.diagonal().powi(3) && chamber <= 0.0 {
            return Err(CavityError::NoVolume { volume: v });
        }
        if v < 0.0 {
            cavity.sign = -1.0;
        }
        Ok(cavity)
    }

    /// The elements of the surface (indices into the mesh's).
    pub fn elements(&self) -> &[usize] {
        &self.elements
    }

    /// The apex `o` (m).
    pub fn apex(&self) -> [f64; 3] {
        self.apex
    }

    /// The rigid chamber's volume (m^3).
    pub fn chamber(&self) -> f64 {
        self.chamber
    }

    /// `+1` when the triangles' normals point out of the cavity, `-1`
    /// when they point in.
    pub fn sign(&self) -> f64 {
        self.sign
    }

    /// The area of the surface at positions `y` (m^2).
    pub fn area(&self, y: &[f64]) -> f64 {
        let mut local = [[0.0; 3]; MAX_NODES];
        let mut area = 0.0;
        for el in self.connectivity.chunks_exact(self.nodes) {
            gather(el, y, self.apex, &mut local);
            for (w, phi, dphi) in &self.points {
                let (_, g1, g2) = interpolate(&local[..self.nodes], phi, dphi);
                area += w * crate::vec3::norm(cross(g1, g2));
            }
        }
        area
    }

    /// `sum_e V_e` at `y`, unsigned, without the chamber (m^3).
    fn surface_volume(&self, y: &[f64]) -> f64 {
        let mut local = [[0.0; 3]; MAX_NODES];
        let mut v = 0.0;
        for el in self.connectivity.chunks_exact(self.nodes) {
            gather(el, y, self.apex, &mut local);
            v += element_volume(&local[..self.nodes], &self.points);
        }
        v
    }

    /// The enclosed volume at positions `y` (m^3), the chamber included.
    pub fn volume(&self, y: &[f64]) -> f64 {
        self.chamber + self.sign * self.surface_volume(y)
    }

    /// The volume at `y` (returned, m^3) and its gradient `dV/dY`, written
    /// into `g` (every entry: zero off the surface).
    pub fn volume_gradient(&self, y: &[f64], g: &mut [f64]) -> f64 {
        g.fill(0.0);
        let n = self.nodes;
        let mut local = [[0.0; 3]; MAX_NODES];
        let mut ge = [0.0; 3 * MAX_NODES];
        let mut v = 0.0;
        for el in self.connectivity.chunks_exact(n) {
            gather(el, y, self.apex, &mut local);
            ge[..3 * n].fill(0.0);
            v += element_gradient(&local[..n], &self.points, &mut ge[..3 * n]);
            for (a, &node) in el.iter().enumerate() {
                for i in 0..3 {
                    g[3 * node + i] += self.sign * ge[3 * a + i];
                }
            }
        }
        self.chamber + self.sign * v
    }

    /// For each element of the surface, its Hessian `scale d2V_e/dY2`
    /// (`3n x 3n`, row-major, `n` nodes per element) handed to `add`
    /// with the element's index in the mesh and its node list; projected
    /// to its positive semi-definite part ([`crate::psd`]) first where
    /// `project` says so for its nodes.
    pub fn hessians(
        &self,
        y: &[f64],
        scale: f64,
        project: impl Fn(&[usize]) -> bool,
        mut add: impl FnMut(usize, &[usize], &[f64]),
    ) {
        let n = self.nodes;
        let m = 3 * n;
        let mut local = [[0.0; 3]; MAX_NODES];
        let mut k = vec![0.0; m * m];
        for (&e, el) in self.elements.iter().zip(self.connectivity.chunks_exact(n)) {
            gather(el, y, self.apex, &mut local);
            k.fill(0.0);
            element_hessian(&local[..n], &self.points, self.sign * scale, &mut k);
            if project(el) {
                crate::psd::project(&mut k, m, m);
            }
            add(e, el, &k);
        }
    }
}

/// The quadrature of degree `3p - 2` (exact: module docs) with the shape
/// functions at its points.
fn points(order: ElementOrder) -> Vec<Point> {
    let shape = ShapeFunctions::new(order);
    let rule = QuadratureRule::of_degree(3 * order.degree() - 2);
    rule.points
        .iter()
        .zip(&rule.weights)
        .map(|(xi, w)| {
            let (phi, dphi) = shape.evaluate(*xi);
            (*w, phi, dphi)
        })
        .collect()
}

/// The centroid of the nodes of `connectivity` (repeated nodes counted
/// each time: any point inside will do).
fn centroid(mesh: &Mesh, connectivity: &[usize]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for &a in connectivity {
        for i in 0..3 {
            c[i] += mesh.nodes[a][i];
        }
    }
    c.map(|v| v / connectivity.len() as f64)
}

/// The element's nodes' positions relative to the apex, into `local`.
fn gather(el: &[usize], y: &[f64], apex: [f64; 3], local: &mut [[f64; 3]; MAX_NODES]) {
    for (a, &node) in el.iter().enumerate() {
        local[a] = sub([y[3 * node], y[3 * node + 1], y[3 * node + 2]], apex);
    }
}

/// `x - o`, `g_1`, `g_2` at one point.
#[inline]
fn interpolate(
    x: &[[f64; 3]],
    phi: &[f64; MAX_NODES],
    dphi: &[[f64; 2]; MAX_NODES],
) -> ([f64; 3], [f64; 3], [f64; 3]) {
    let (mut p, mut g1, mut g2) = ([0.0; 3], [0.0; 3], [0.0; 3]);
    for (a, xa) in x.iter().enumerate() {
        for i in 0..3 {
            p[i] += phi[a] * xa[i];
            g1[i] += dphi[a][0] * xa[i];
            g2[i] += dphi[a][1] * xa[i];
        }
    }
    (p, g1, g2)
}

/// `V_e` of one element, positions relative to the apex (m^3).
fn element_volume(x: &[[f64; 3]], points: &[Point]) -> f64 {
    points
        .iter()
        .map(|(w, phi, dphi)| {
            let (p, g1, g2) = interpolate(x, phi, dphi);
            w * dot(p, cross(g1, g2))
        })
        .sum::<f64>()
        / 3.0
}

/// Adds `dV_e/dY` (`3n`) into `g`; returns `V_e`.
fn element_gradient(x: &[[f64; 3]], points: &[Point], g: &mut [f64]) -> f64 {
    let mut v = 0.0;
    for (w, phi, dphi) in points {
        let (p, g1, g2) = interpolate(x, phi, dphi);
        let normal = cross(g1, g2);
        let (t1, t2) = (cross(g2, p), cross(p, g1));
        v += w * dot(p, normal);
        let s = w / 3.0;
        for a in 0..x.len() {
            for i in 0..3 {
                g[3 * a + i] += s * (phi[a] * normal[i] + dphi[a][0] * t1[i] + dphi[a][1] * t2[i]);
            }
        }
    }
    v / 3.0
}

/// Adds `scale d2V_e/dY2` (`3n x 3n`, row-major) into `k`.
fn element_hessian(x: &[[f64; 3]], points: &[Point], scale: f64, k: &mut [f64]) {
    let n = x.len();
    let m = 3 * n;
    for (w, phi, dphi) in points {
        let (p, g1, g2) = interpolate(x, phi, dphi);
        let s = scale * w / 3.0;
        for a in 0..n {
            for b in 0..n {
                let alpha = dphi[a][0] * phi[b] - phi[a] * dphi[b][0];
                let beta = phi[a] * dphi[b][1] - dphi[a][1] * phi[b];
                let gamma = dphi[a][1] * dphi[b][0] - dphi[a][0] * dphi[b][1];
                let v: [f64; 3] =
                    std::array::from_fn(|i| s * (alpha * g2[i] + beta * g1[i] + gamma * p[i]));
                // [v]x = [[0, -v2, v1], [v2, 0, -v0], [-v1, v0, 0]].
                let r0 = (3 * a) * m + 3 * b;
                let (r1, r2) = (r0 + m, r0 + 2 * m);
                k[r0 + 1] -= v[2];
                k[r0 + 2] += v[1];
                k[r1] += v[2];
                k[r1 + 2] -= v[0];
                k[r2] -= v[1];
                k[r2 + 1] += v[0];
            }
        }
    }
}

/// [`CavityError::Open`] or [`CavityError::Misoriented`] unless every
/// corner edge of `elements` is shared by two of them running through it
/// in opposite directions, or is open and closed by the apex (module
/// docs: its nodes, the edge's inner ones too, held or on a symmetry plane
/// through the apex).
fn check_closed(
    mesh: &Mesh,
    elements: &[usize],
    apex: Option<[f64; 3]>,
    fixed: &[bool],
) -> Result<(), CavityError> {
    let p = mesh.order.degree();
    // Sorted edge -> (element, whether it runs from the smaller node), uses.
    let mut edges: HashMap<(usize, usize), (usize, bool, usize)> = HashMap::new();
    for &e in elements {
        let el = mesh.element(e);
        for k in 0..3 {
            let (a, b) = (el[k], el[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            let forward = a < b;
            match edges.get_mut(&key) {
                None => {
                    edges.insert(key, (e, forward, 1));
                }
                Some((first, dir, uses)) => {
                    if *dir == forward {
                        return Err(CavityError::Misoriented {
                            a: key.0,
                            b: key.1,
                            first: *first,
                            second: e,
                        });
                    }
                    *uses += 1;
                }
            }
        }
    }
    let tolerance = 1e-9 * mesh.diagonal();
    let held = |node: usize, o: [f64; 3]| {
        let all = (0..3).all(|i| fixed.get(3 * node + i).copied().unwrap_or(false));
        all || (0..3).any(|i| {
            fixed.get(3 * node + i).copied().unwrap_or(false)
                && (mesh.nodes[node][i] - o[i]).abs() <= tolerance
        })
    };
    let mut open: Vec<(usize, usize)> = edges
        .iter()
        .filter(|(_, (_, _, uses))| *uses == 1)
        .map(|(k, _)| *k)
        .collect();
    open.sort_unstable();
    for &e in elements {
        let el = mesh.element(e);
        for k in 0..3 {
            let (a, b) = (el[k], el[(k + 1) % 3]);
            if open.binary_search(&(a.min(b), a.max(b))).is_err() {
                continue;
            }
            let Some(o) = apex else {
                return Err(CavityError::Open {
                    a: a.min(b),
                    b: a.max(b),
                    why: ": give the cavity an origin to close it by a wall or symmetry plane"
                        .into(),
                });
            };
            let inner = (0..p.saturating_sub(1)).map(|j| el[3 + k * (p - 1) + j]);
            if let Some(node) = [a, b].into_iter().chain(inner).find(|&c| !held(c, o)) {
                return Err(CavityError::Open {
                    a: a.min(b),
                    b: a.max(b),
                    why: format!(
                        ", and its node {node} is neither held in all three components nor held on a symmetry plane through the origin [{}, {}, {}] (a component i held, with the node's x_i equal to the origin's)",
                        o[0], o[1], o[2]
                    ),
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fd::{gradient_error, jacobian_error};
    use crate::mesh::generate::sphere;

    fn order(p: usize) -> ElementOrder {
        ElementOrder::from_degree(p).expect("order")
    }

    /// The sphere's nodes moved off it by a smooth deterministic field.
    fn perturbed(mesh: &Mesh) -> Vec<f64> {
        mesh.nodes
            .iter()
            .flat_map(|x| {
                let s = (3.0 * x[0] + 1.7 * x[1] - 2.3 * x[2]).sin();
                [
                    x[0] * (1.0 + 0.1 * s),
                    x[1] - 0.05 * s,
                    x[2] + 0.07 * s * x[0],
                ]
            })
            .collect()
    }

    fn whole(mesh: &Mesh) -> Vec<usize> {
        (0..mesh.element_count()).collect()
    }

    /// A sphere's volume converges to `4/3 pi R^3` — faster for curved
    /// elements —, is positive with the generator's outward normals and
    /// does not depend on the apex.
    #[test]
    fn sphere_volume_converges_and_does_not_depend_on_the_apex() {
        let exact = 4.0 / 3.0 * std::f64::consts::PI;
        let mut errors = Vec::new();
        for p in 1..=2 {
            let mesh = sphere(1.0, 2, [0.3, -0.2, 0.1], order(p));
            let y = mesh.nodes.concat();
            let c = Cavity::new(&mesh, whole(&mesh), None, 0.0, &[]).expect("closed");
            assert_eq!(c.sign(), 1.0);
            let other =
                Cavity::new(&mesh, whole(&mesh), Some([5.0, 1.0, -2.0]), 0.0, &[]).expect("closed");
            let (v, w) = (c.volume(&y), other.volume(&y));
            // Apex-independence holds to the round-off of the sum.
            assert!((v - w).abs() < 1e-13 * v, "order {p}: {v} vs {w}");
            errors.push((v / exact - 1.0).abs());
        }
        // 320 flat triangles miss 3.4 % of the volume, their curved T6
        // 0.014 %.
        assert!(
            errors[0] < 0.04 && errors[1] < 0.01 * errors[0],
            "{errors:?}"
        );
    }

    /// `dV/dY` against central differences of `V`, and the assembled
    /// Hessian `d2V/dY2` (dense) against central differences of `dV/dY`,
    /// every order, on a sphere deformed out of symmetry; the Hessian is
    /// symmetric. Tolerances: central differences with `h = 1e-6`
    /// (truncation `h^2`, round-off `eps / h` relative: about 1e-9).
    #[test]
    fn volume_gradient_and_hessian_match_finite_differences() {
        for p in 1..=3 {
            let mesh = sphere(1.0, 1, [0.0; 3], order(p));
            let c = Cavity::new(&mesh, whole(&mesh), None, 0.0, &[]).expect("closed");
            let y = perturbed(&mesh);
            let n = y.len();
            let gradient = |x: &[f64]| {
                let mut g = vec![0.0; n];
                c.volume_gradient(x, &mut g);
                g
            };
            let eg = gradient_error(|x| c.volume(x), gradient, &y, 1e-6);
            assert!(eg < 1e-8, "order {p}: gradient {eg:e}");
            let hessian = |x: &[f64]| {
                let mut h = vec![0.0; n * n];
                c.hessians(
                    x,
                    1.0,
                    |_| false,
                    |_, el, k| {
                        let m = 3 * el.len();
                        for (a, &na) in el.iter().enumerate() {
                            for (b, &nb) in el.iter().enumerate() {
                                for i in 0..3 {
                                    for j in 0..3 {
                                        h[(3 * na + i) * n + 3 * nb + j] +=
                                            k[(3 * a + i) * m + 3 * b + j];
                                    }
                                }
                            }
                        }
                    },
                );
                h
            };
            let eh = jacobian_error(gradient, hessian, &y, 1e-6);
            assert!(eh < 1e-8, "order {p}: Hessian {eh:e}");
            let h = hessian(&y);
            let asymmetry = (0..n)
                .flat_map(|i| (0..n).map(move |j| (i, j)))
                .map(|(i, j)| (h[i * n + j] - h[j * n + i]).abs())
                .fold(0.0, f64::max);
            assert!(asymmetry < 1e-13, "order {p}: asymmetry {asymmetry:e}");
        }
    }

    /// On a closed surface the volume's gradient is the follower
    /// pressure's force per pascal (`load::pressure`), every order.
    #[test]
    fn volume_gradient_is_the_pressure_force_on_a_closed_surface() {
        use crate::load::pressure::{PressureQuadrature, add_pressure_force};
        for p in 1..=3 {
            let mesh = sphere(0.5, 1, [0.1; 3], order(p));
            let c = Cavity::new(&mesh, whole(&mesh), None, 0.0, &[]).expect("closed");
            let y = perturbed(&mesh);
            let mut g = vec![0.0; y.len()];
            c.volume_gradient(&y, &mut g);
            let q = PressureQuadrature::new(mesh.order);
            let mut f = vec![0.0; y.len()];
            let m = 3 * mesh.order.nodes_per_element();
            for el in mesh.elements() {
                let local: Vec<[f64; 3]> = el
                    .iter()
                    .map(|&a| [y[3 * a], y[3 * a + 1], y[3 * a + 2]])
                    .collect();
                let mut fe = vec![0.0; m];
                add_pressure_force(1.0, &local, &q, &mut fe, None, 1.0);
                for (a, &node) in el.iter().enumerate() {
                    for i in 0..3 {
                        f[3 * node + i] += fe[3 * a + i];
                    }
                }
            }
            let worst = g
                .iter()
                .zip(&f)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            let scale = f.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            assert!(worst < 1e-13 * scale, "order {p}: {worst:e}");
        }
    }

    /// A sphere with one triangle taken out is open: refused, naming an
    /// edge of the hole; an apex alone does not close it unless the hole's
    /// nodes are held. A triangle turned over is refused as misoriented.
    #[test]
    fn open_or_misoriented_surfaces_are_refused() {
        let mesh = sphere(1.0, 1, [0.0; 3], ElementOrder::Linear);
        let hole = mesh.element(0).to_vec();
        let some: Vec<usize> = (1..mesh.element_count()).collect();
        let e = Cavity::new(&mesh, some.clone(), None, 0.0, &[]).unwrap_err();
        match &e {
            CavityError::Open { a, b, .. } => {
                assert!(hole.contains(a) && hole.contains(b), "{e}");
            }
            other => panic!("{other}"),
        }
        assert!(e.to_string().contains("origin"), "{e}");
        let e = Cavity::new(&mesh, some.clone(), Some([0.0; 3]), 0.0, &[]).unwrap_err();
        assert!(e.to_string().contains("neither held"), "{e}");
        // The hole's nodes held: closed by the cone from the centre, the
        // volume is the sphere's less the cone over the missing triangle.
        let mut fixed = vec![false; 3 * mesh.node_count()];
        for &a in &hole {
            fixed[3 * a..3 * a + 3].fill(true);
        }
        let full = Cavity::new(&mesh, whole(&mesh), None, 0.0, &[]).expect("closed");
        let open = Cavity::new(&mesh, some, Some([0.0; 3]), 0.0, &fixed).expect("held");
        let y = mesh.nodes.concat();
        let x: Vec<[f64; 3]> = hole.iter().map(|&a| mesh.nodes[a]).collect();
        let cone = dot(x[0], cross(x[1], x[2])) / 6.0;
        assert!((open.volume(&y) + cone - full.volume(&y)).abs() < 1e-14);
        let mut turned = mesh.clone();
        turned.connectivity.swap(1, 2);
        let e = Cavity::new(&turned, whole(&turned), None, 0.0, &[]).unwrap_err();
        assert!(matches!(e, CavityError::Misoriented { .. }), "{e}");
    }

    /// A surface whose normals point into the cavity gets the sign that
    /// makes its volume positive.
    #[test]
    fn inward_normals_give_a_positive_volume() {
        let outward = sphere(1.0, 1, [0.0; 3], ElementOrder::Linear);
        let v = Cavity::new(&outward, whole(&outward), None, 0.0, &[])
            .expect("closed")
            .volume(&outward.nodes.concat());
        let mut mesh = outward;
        for el in mesh.connectivity.chunks_exact_mut(3) {
            el.swap(1, 2);
        }
        let c = Cavity::new(&mesh, whole(&mesh), None, 0.0, &[]).expect("closed");
        assert_eq!(c.sign(), -1.0);
        assert!((c.volume(&mesh.nodes.concat()) - v).abs() < 1e-15 * v);
    }
}
