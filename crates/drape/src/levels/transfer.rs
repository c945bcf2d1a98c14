//! Carrying a state onto a refined mesh.
//!
//! [`crate::mesh::refine`] splits the triangles and puts each new node at
//! the midpoint of the reference edge it halves. On a curved surface —
//! the reference of a curved specimen, and always the current shape of a
//! draped one — the chord's midpoint lies inside the surface, and a fold
//! carried over that way would be faceted: the fine level would start
//! with the coarse level's kinks, which its bending energy then pays for.
//! Here each new node is placed on the quadratic that the bending term's
//! edge fit describes ([`crate::bending::edge_midpoints`]: the quadratic
//! through the edge's two triangles that fits the nodes around them,
//! fitted on the coarse reference mesh): its reference position from the
//! reference positions, its current position from the current ones, its
//! velocity from the velocities — one linear rule per new node,
//! `x_new = sum_k W_k x_k`, whose weights sum to 1.
//!
//! What it keeps: a rigid motion of the coarse state is a rigid motion
//! of the fine one, and a state that is its reference (a flat or curved
//! sheet at rest, unstrained) stays its reference — the fine level starts
//! unstrained where the coarse one was (no spurious energy). A quadratic
//! surface is carried over exactly. The coarse nodes keep their values.
//!
//! **Across a fold** the quadratic fitted on the flat reference
//! overshoots: the nodes around a coarse edge that a fold crosses lie on
//! two sheets, and the weights put its new node off both, compressing
//! the fine triangles beside it (to a stretch of 0.07 from a coarse state
//! whose least was 0.996, measured). [`Transfer::onto_chords`] puts such
//! elements' new nodes back on the middle of their chords, where a fine
//! triangle away from the rim is a piece of its coarse one and strained
//! as it is; the multilevel settle does so where a fine element would be
//! compressed past Saint-Venant–Kirchhoff's stability ([`super`]'s
//! `carry`).
//!
//! **The rim.** A boundary edge has one triangle and no fit across it;
//! its new node is put on the curve through the boundary nodes around it
//! instead ([`rim_midpoints`]): the cubic through the edge's ends and the
//! boundary nodes before and after them, in the chord length, at the
//! edge's middle (the four-point rule, `(-1, 9, 9, -1) / 16` where the
//! chords are equal), so that a disc's refined rim lies on its circle
//! (to `O(h^4)`) rather than on the coarse polygon. A corner (the
//! boundary turning by more than [`CORNER_DEGREES`]) is kept: the curve
//! takes the neighbours on its smooth side only (a quadratic), or none
//! (the chord's midpoint). A straight boundary stays straight.

use crate::bending::{BendingError, edge_midpoints};
use crate::mesh::refine::{Green, RefineError, Refinement, refine_again, refine_lagrange};
use crate::mesh::{ElementOrder, Mesh};

/// Why a mesh cannot be refined.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TransferError {
    /// The split itself (the mesh's order, the flags).
    #[error("{0}")]
    Refine(#[from] RefineError),
    /// The edges' fits (an edge of more than two triangles).
    #[error("{0}")]
    Fit(#[from] BendingError),
    /// A mesh of higher order refined where marked, not everywhere.
    #[error(
        "refinement along the folds splits linear triangles; a mesh of order {0} is refined everywhere (where = \"all\")"
    )]
    Adaptive(usize),
}

/// A refinement with its new nodes on the surface, and the rule that
/// carries a field over.
#[derive(Debug, Clone)]
pub struct Transfer {
    /// The refined mesh (new nodes on the reference surface) and where its
    /// parts came from.
    pub refinement: Refinement,
    /// The coarse mesh's node count.
    coarse: usize,
    /// For each new node, the coarse nodes and their weights.
    rules: Vec<(Vec<usize>, Vec<f64>)>,
}

impl Transfer {
    /// `mesh` (linear) refined red where `marked`, closed green, the green
    /// splits `greens` of the refinement that made it undone where reached
    /// ([`refine_again`]; none for a coarse mesh), each new node placed on
    /// its edge's quadratic over the reference positions. A mesh of order
    /// 2 or 3 is refined everywhere ([`refine_lagrange`]: every flag set),
    /// each new node by its parent element's own interpolation.
    ///
    /// # Errors
    /// [`TransferError`]: a mesh of higher order, flags that do not match,
    /// a non-manifold edge.
    pub fn new(mesh: &Mesh, marked: &[bool], greens: &[Green]) -> Result<Self, TransferError> {
        if mesh.order != ElementOrder::Linear {
            if marked.len() != mesh.element_count() || marked.iter().any(|m| !m) {
                return Err(TransferError::Adaptive(mesh.order.degree()));
            }
            let (refinement, rules) = refine_lagrange(mesh)?;
            return Ok(Self {
                refinement,
                coarse: mesh.node_count(),
                rules,
            });
        }
        let mut refinement = refine_again(mesh, marked, greens)?;
        let fits = edge_midpoints(mesh)?;
        let rim = rim_midpoints(mesh);
        let rules: Vec<(Vec<usize>, Vec<f64>)> = refinement
            .midpoints
            .iter()
            .map(|&[a, b]| {
                rim.get(&[a, b])
                    .or_else(|| fits.get(&[a, b]))
                    .cloned()
                    .unwrap_or_else(|| (vec![a, b], vec![0.5, 0.5]))
            })
            .collect();
        let coarse = mesh.node_count();
        for (j, (nodes, weights)) in rules.iter().enumerate() {
            refinement.mesh.nodes[coarse + j] = std::array::from_fn(|i| {
                nodes
                    .iter()
                    .zip(weights)
                    .map(|(&k, w)| w * mesh.nodes[k][i])
                    .sum()
            });
        }
        Ok(Self {
            refinement,
            coarse,
            rules,
        })
    }

    /// `fine`, the positions `values` carried by [`Transfer::carry`], with
    /// the new nodes of the elements `compressed` names put back on the
    /// middle of the coarse chord each halves, asked again until it names
    /// no element with a new node off its chord. On the chords the fine
    /// triangles of a split are pieces of their coarse one, strained as it
    /// is — but for a green-split parent's middle triangle, which straddles
    /// the two halves, and beside the rim, whose new reference nodes lie on
    /// its curve: there the chord is shorter by its sag, about `h / 4R`
    /// of an edge `h` on a rim of radius `R`. Returns how many new nodes
    /// were moved: none for a refinement of higher order, whose new nodes
    /// halve no chord.
    pub fn onto_chords(
        &self,
        values: &[f64],
        fine: &mut [f64],
        mut compressed: impl FnMut(&[f64]) -> Vec<usize>,
    ) -> usize {
        let mesh = &self.refinement.mesh;
        let mut on_chord = vec![false; self.refinement.midpoints.len()];
        let mut moved = 0;
        loop {
            let before = moved;
            for e in compressed(fine) {
                for &node in mesh.element(e) {
                    let Some(j) = node.checked_sub(self.coarse) else {
                        continue;
                    };
                    if j >= on_chord.len() || on_chord[j] {
                        continue;
                    }
                    on_chord[j] = true;
                    moved += 1;
                    let [a, b] = self.refinement.midpoints[j];
                    for i in 0..3 {
                        fine[3 * node + i] = 0.5 * (values[3 * a + i] + values[3 * b + i]);
                    }
                }
            }
            if moved == before {
                return moved;
            }
        }
    }

    /// The field `values` of the coarse mesh (3 per node: positions or
    /// velocities) on the fine mesh: the coarse nodes' own, then each new
    /// node's from its rule.
    pub fn carry(&self, values: &[f64]) -> Vec<f64> {
        debug_assert_eq!(values.len(), 3 * self.coarse);
        let mut fine = Vec::with_capacity(values.len() + 3 * self.rules.len());
        fine.extend_from_slice(values);
        for (nodes, weights) in &self.rules {
            for i in 0..3 {
                fine.push(
                    nodes
                        .iter()
                        .zip(weights)
                        .map(|(&k, w)| w * values[3 * k + i])
                        .sum(),
                );
            }
        }
        fine
    }
}

/// The turn of the boundary (degrees) above which a boundary node is a
/// corner that the rim's curve does not round.
pub const CORNER_DEGREES: f64 = 30.0;

/// For each boundary edge `[a, b]` (`a < b`) of the linear mesh `mesh`,
/// the nodes and weights of its middle on the rim's curve (module docs):
/// the Lagrange interpolant in the chord length through the boundary
/// nodes `p, a, b, q` (those of a smooth side only at a corner), at half
/// the edge. Weights sum to 1. Edges at a node where more than two
/// boundary edges meet keep the chord.
pub fn rim_midpoints(mesh: &Mesh) -> crate::bending::MidpointRules {
    let edges = mesh.boundary_edges();
    let mut along: std::collections::HashMap<usize, Vec<usize>> = Default::default();
    for &[a, b] in &edges {
        along.entry(a).or_default().push(b);
        along.entry(b).or_default().push(a);
    }
    let x = |k: usize| mesh.nodes[k];
    let dist = |a: usize, b: usize| {
        let (p, q) = (x(a), x(b));
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    };
    // The boundary node before `a` (going away from `b`), if the boundary
    // runs on smoothly through `a`.
    let before = |a: usize, b: usize| -> Option<usize> {
        let next = along.get(&a)?;
        let [u, v] = next.as_slice() else {
            return None;
        };
        let p = if *u == b { *v } else { *u };
        let (pa, ab) = (
            std::array::from_fn::<f64, 3, _>(|i| x(a)[i] - x(p)[i]),
            std::array::from_fn::<f64, 3, _>(|i| x(b)[i] - x(a)[i]),
        );
        let cos = (pa[0] * ab[0] + pa[1] * ab[1] + pa[2] * ab[2]) / (dist(p, a) * dist(a, b));
        (cos >= CORNER_DEGREES.to_radians().cos()).then_some(p)
    };
    let mut rules = crate::bending::MidpointRules::new();
    for &[a, b] in &edges {
        let h = dist(a, b);
        let mut nodes = Vec::with_capacity(4);
        let mut at = Vec::with_capacity(4);
        if let Some(p) = before(a, b) {
            nodes.push(p);
            at.push(-dist(p, a));
        }
        nodes.extend([a, b]);
        at.extend([0.0, h]);
        if let Some(q) = before(b, a) {
            nodes.push(q);
            at.push(h + dist(b, q));
        }
        let middle = 0.5 * h;
        let weights: Vec<f64> = (0..nodes.len())
            .map(|i| {
                (0..nodes.len())
                    .filter(|&j| j != i)
                    .map(|j| (middle - at[j]) / (at[i] - at[j]))
                    .product()
            })
            .collect();
        rules.insert([a, b], (nodes, weights));
    }
    rules
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{ElementOrder, generate};

    fn flat(mesh: &Mesh) -> Vec<f64> {
        mesh.nodes.iter().flatten().copied().collect()
    }

    /// The rim: a disc's new boundary nodes lie on its circle (within
    /// 1e-4 of the chord's sag off it at 6 rings) and its refined area is
    /// nearer the circle's; a rectangle's stay on its straight sides, and
    /// its corners are not rounded (its area is kept to round-off).
    #[test]
    fn new_rim_nodes_lie_on_the_rim() {
        let disc = generate::disc(0.15, 6, [0.0; 3], ElementOrder::Linear);
        let all = vec![true; disc.element_count()];
        let t = Transfer::new(&disc, &all, &[]).unwrap();
        let rim = disc.boundary_nodes();
        let on_rim = |a: usize| rim.binary_search(&a).is_ok();
        let mut checked = 0;
        for (j, &[a, b]) in t.refinement.midpoints.iter().enumerate() {
            if !(on_rim(a) && on_rim(b)) {
                continue;
            }
            let p = t.refinement.mesh.nodes[disc.node_count() + j];
            let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
            let (pa, pb) = (disc.nodes[a], disc.nodes[b]);
            let chord = (0.25 * ((pa[0] + pb[0]).powi(2) + (pa[1] + pb[1]).powi(2))).sqrt();
            let sag = 0.15 - chord;
            assert!(
                (r - 0.15).abs() < 1e-4 * 0.15 && (r - 0.15).abs() < 0.05 * sag,
                "{r} (sag {sag})"
            );
            checked += 1;
        }
        assert_eq!(checked, 36);
        let area = |m: &Mesh| -> f64 {
            m.elements()
                .map(|t| {
                    let [a, b, c] = [t[0], t[1], t[2]].map(|v| m.nodes[v]);
                    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
                })
                .sum()
        };
        let circle = std::f64::consts::PI * 0.15 * 0.15;
        let (coarse, fine) = (area(&disc), area(&t.refinement.mesh));
        assert!(
            (circle - fine).abs() < 0.3 * (circle - coarse),
            "{coarse} → {fine} ({circle})"
        );
        let rect = generate::rectangle(
            [0.3, 0.2],
            [3, 2],
            generate::Pattern::Right,
            [0.0; 3],
            ElementOrder::Linear,
        );
        let t = Transfer::new(&rect, &vec![true; rect.element_count()], &[]).unwrap();
        assert!((area(&t.refinement.mesh) - 0.06).abs() < 1e-15);
        for p in &t.refinement.mesh.nodes {
            let inside = p[0].abs() <= 0.15 + 1e-15 && p[1].abs() <= 0.1 + 1e-15;
            assert!(inside, "{p:?} off the rectangle");
        }
    }

    /// On a curved reference the new nodes lie on the surface — a tenth of
    /// the chord's sag off it at most inside, half of it beside the rim
    /// (measured: 0.06 and 0.33) —, a flat quadratic field is carried
    /// over exactly, a rigid motion stays rigid, and the reference carried
    /// is the refined reference.
    #[test]
    fn quadratics_and_rigid_motions_are_carried_exactly() {
        let mut mesh = generate::disc(1.0, 6, [0.0; 3], ElementOrder::Linear);
        // A paraboloid cap as the reference.
        let z = |p: [f64; 3]| 0.2 * p[0] * p[0] - 0.1 * p[0] * p[1] + 0.3 * p[1] * p[1];
        for p in &mut mesh.nodes {
            p[2] = z(*p);
        }
        let marked: Vec<bool> = (0..mesh.element_count()).map(|e| e % 3 == 0).collect();
        let t = Transfer::new(&mesh, &marked, &[]).unwrap();
        let fine = &t.refinement.mesh;
        assert!(fine.node_count() > mesh.node_count());
        // The refined reference is the carried reference.
        assert_eq!(flat(fine), t.carry(&flat(&mesh)));
        // New nodes at interior edges are on the paraboloid (boundary
        // edges keep the chord's midpoint).
        let boundary = mesh.boundary_nodes();
        let on_boundary = |a: usize| boundary.binary_search(&a).is_ok();
        let mut interior = 0;
        for (j, &[a, b]) in t.refinement.midpoints.iter().enumerate() {
            let p = fine.nodes[mesh.node_count() + j];
            let mid: [f64; 3] =
                std::array::from_fn(|i| 0.5 * (mesh.nodes[a][i] + mesh.nodes[b][i]));
            if !(on_boundary(a) && on_boundary(b)) {
                let (off, sag) = ((p[2] - z(p)).abs(), (mid[2] - z(mid)).abs());
                // Fitted from one side near the rim: less well.
                let share = if on_boundary(a) || on_boundary(b) {
                    0.5
                } else {
                    interior += 1;
                    0.1
                };
                assert!(
                    off <= share * sag,
                    "node {j}: {off} off the surface, sag {sag}"
                );
            }
        }
        assert!(interior > 10);
        // A flat mesh and a quadratic field over it: exact but at the rim
        // (a boundary edge's node is its chord's midpoint).
        let plane = generate::disc(1.0, 6, [0.0; 3], ElementOrder::Linear);
        let rim = plane.boundary_nodes();
        let flat_t = Transfer::new(&plane, &marked, &[]).unwrap();
        let f = |p: [f64; 3]| {
            [
                p[0] * p[0] - 0.5 * p[0] * p[1],
                0.3 * p[1] * p[1] + p[0],
                -0.2,
            ]
        };
        let carried = flat_t.carry(&plane.nodes.iter().flat_map(|&p| f(p)).collect::<Vec<_>>());
        for (j, &[a, b]) in flat_t.refinement.midpoints.iter().enumerate() {
            if rim.binary_search(&a).is_ok() && rim.binary_search(&b).is_ok() {
                continue;
            }
            let k = plane.node_count() + j;
            let want = f(flat_t.refinement.mesh.nodes[k]);
            for i in 0..3 {
                assert!((carried[3 * k + i] - want[i]).abs() < 1e-12, "node {k}");
            }
        }
        // A rigid motion (a rotation about z and a shift).
        let (c, s) = (0.6f64, 0.8f64);
        let moved: Vec<f64> = mesh
            .nodes
            .iter()
            .flat_map(|p| {
                [
                    c * p[0] - s * p[1] + 1.0,
                    s * p[0] + c * p[1] - 2.0,
                    p[2] + 0.5,
                ]
            })
            .collect();
        let carried = t.carry(&moved);
        for (k, p) in fine.nodes.iter().enumerate() {
            let want = [
                c * p[0] - s * p[1] + 1.0,
                s * p[0] + c * p[1] - 2.0,
                p[2] + 0.5,
            ];
            for i in 0..3 {
                assert!((carried[3 * k + i] - want[i]).abs() < 1e-12, "node {k}");
            }
        }
    }

    /// A mesh of order 2 or 3 is split everywhere, each triangle into four
    /// of its order: the refined rectangle tiles the coarse one (area,
    /// boundary edges doubled), every fine node is used, and a field
    /// polynomial of the order is carried onto the new nodes exactly; a
    /// partial marking is refused.
    #[test]
    fn lagrange_meshes_are_refined_by_their_own_interpolation() {
        for order in [ElementOrder::Quadratic, ElementOrder::Cubic] {
            let mesh = generate::rectangle(
                [0.4, 0.3],
                [4, 3],
                generate::Pattern::Alternate,
                [0.0; 3],
                order,
            );
            let all = vec![true; mesh.element_count()];
            let t = Transfer::new(&mesh, &all, &[]).unwrap();
            let fine = &t.refinement.mesh;
            assert_eq!(fine.order, order);
            assert_eq!(fine.element_count(), 4 * mesh.element_count());
            let corner_area = |m: &Mesh| -> f64 {
                m.elements()
                    .map(|e| {
                        let [a, b, c] = [e[0], e[1], e[2]].map(|v| m.nodes[v]);
                        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
                    })
                    .sum()
            };
            assert!(
                (corner_area(fine) - 0.12).abs() < 1e-14,
                "{}",
                corner_area(fine)
            );
            assert_eq!(fine.boundary_edges().len(), 2 * mesh.boundary_edges().len());
            let mut used = vec![false; fine.node_count()];
            for &a in &fine.connectivity {
                used[a] = true;
            }
            assert!(used.iter().all(|&u| u), "{order:?}");
            // A polynomial of the order, in the plane's coordinates.
            let f = |x: [f64; 3]| {
                let (u, v) = (x[0], x[1]);
                let q = 1.0 + 2.0 * u - v + 3.0 * u * v - u * u + 0.5 * v * v;
                let c = if order == ElementOrder::Cubic {
                    u * u * v - 2.0 * v * v * v + u * u * u
                } else {
                    0.0
                };
                [q + c, q - c, 0.25 * q]
            };
            let coarse: Vec<f64> = mesh.nodes.iter().flat_map(|&x| f(x)).collect();
            let carried = t.carry(&coarse);
            for (a, &x) in fine.nodes.iter().enumerate() {
                let want = f(x);
                for i in 0..3 {
                    let got = carried[3 * a + i];
                    assert!(
                        (got - want[i]).abs() < 1e-12,
                        "{order:?} node {a}: {got} {}",
                        want[i]
                    );
                }
            }
            let mut some = all.clone();
            some[0] = false;
            assert!(matches!(
                Transfer::new(&mesh, &some, &[]),
                Err(TransferError::Adaptive(_))
            ));
        }
    }

    /// The smallest principal stretch of each linear triangle of `mesh`
    /// (flat in z = 0) at the positions `x`.
    fn least_stretches(mesh: &Mesh, x: &[f64]) -> Vec<f64> {
        mesh.elements()
            .map(|t| {
                let p = |k: usize| mesh.nodes[t[k]];
                let y = |k: usize| [x[3 * t[k]], x[3 * t[k] + 1], x[3 * t[k] + 2]];
                let e = [
                    [p(1)[0] - p(0)[0], p(2)[0] - p(0)[0]],
                    [p(1)[1] - p(0)[1], p(2)[1] - p(0)[1]],
                ];
                let det = e[0][0] * e[1][1] - e[0][1] * e[1][0];
                let inv = [
                    [e[1][1] / det, -e[0][1] / det],
                    [-e[1][0] / det, e[0][0] / det],
                ];
                // F = [y1 - y0, y2 - y0] E^-1 (3 x 2), then C = F^T F.
                let g: [[f64; 2]; 3] =
                    std::array::from_fn(|i| [y(1)[i] - y(0)[i], y(2)[i] - y(0)[i]]);
                let f: [[f64; 2]; 3] = std::array::from_fn(|i| {
                    std::array::from_fn(|j| g[i][0] * inv[0][j] + g[i][1] * inv[1][j])
                });
                let c = |a: usize, b: usize| (0..3).map(|i| f[i][a] * f[i][b]).sum::<f64>();
                let (tr, dt) = (c(0, 0) + c(1, 1), c(0, 0) * c(1, 1) - c(0, 1) * c(0, 1));
                (0.5 * (tr - (tr * tr - 4.0 * dt).max(0.0).sqrt()))
                    .max(0.0)
                    .sqrt()
            })
            .collect()
    }

    /// A disc rolled tightly (the fold of a draped specimen's coarse
    /// level, measured there: 0.996 carried into 0.071): the surface
    /// placement overshoots across the fold and compresses fine triangles
    /// below the coarse state's least stretch. `onto_chords` puts back on their chords the
    /// new nodes of those triangles, and only those, until every fine
    /// triangle away from the rim is as stretched as the coarse state's
    /// least (refined everywhere, each fine triangle with its new nodes on
    /// the chords is a quarter of its coarse one, strained alike).
    #[test]
    fn a_carry_that_compresses_is_put_back_on_the_chords() {
        let disc = generate::disc(0.1, 6, [0.0; 3], ElementOrder::Linear);
        let t = Transfer::new(&disc, &vec![true; disc.element_count()], &[]).unwrap();
        let fine = &t.refinement.mesh;
        // Rolled onto a cylinder of radius 2 cm, about an edge's length:
        // an isometry, which the coarse elements meet as chords of arcs.
        let r = 0.02;
        let folded: Vec<f64> = disc
            .nodes
            .iter()
            .flat_map(|p| [r * (p[0] / r).sin(), p[1], r * (1.0 - (p[0] / r).cos())])
            .collect();
        let least = |m: &Mesh, x: &[f64]| least_stretches(m, x).into_iter().fold(1.0, f64::min);
        let floor = least(&disc, &folded);
        let carried = t.carry(&folded);
        assert!(
            least(fine, &carried) < 0.6 * floor,
            "{} {floor}",
            least(fine, &carried)
        );
        let mut put = carried.clone();
        let moved = t.onto_chords(&folded, &mut put, |x| {
            least_stretches(fine, x)
                .iter()
                .enumerate()
                .filter(|&(_, &l)| l < floor)
                .map(|(e, _)| e)
                .collect()
        });
        // Away from the rim every fine triangle is now as stretched as the
        // coarse state's least; beside it, whose new reference nodes lie
        // on the circle, the chord compresses by its sag (about h / 4R).
        let rim = fine.boundary_nodes();
        let stretches = least_stretches(fine, &put);
        for (e, tri) in fine.elements().enumerate() {
            if tri.iter().all(|a| rim.binary_search(a).is_err()) {
                assert!(
                    stretches[e] >= floor - 1e-12,
                    "element {e}: {}",
                    stretches[e]
                );
            }
        }
        assert!(least(fine, &put) >= 0.95 * floor, "{}", least(fine, &put));
        let new = t.refinement.midpoints.len();
        assert!(moved > 0 && moved < new, "{moved} of {new}");
        let mut counted = 0;
        for (j, &[a, b]) in t.refinement.midpoints.iter().enumerate() {
            let k = disc.node_count() + j;
            let node = |x: &[f64]| [x[3 * k], x[3 * k + 1], x[3 * k + 2]];
            if node(&put) == node(&carried) {
                continue;
            }
            counted += 1;
            for i in 0..3 {
                let mid = 0.5 * (folded[3 * a + i] + folded[3 * b + i]);
                assert!((put[3 * k + i] - mid).abs() < 1e-15, "node {k}");
            }
        }
        assert!(counted > 0 && counted <= moved, "{counted} {moved}");
        // The coarse nodes keep their values.
        assert_eq!(put[..folded.len()], folded[..]);
        // Nothing compressed: nothing moved.
        let mut again = carried.clone();
        assert_eq!(t.onto_chords(&folded, &mut again, |_| Vec::new()), 0);
        assert_eq!(again, carried);
    }
}
