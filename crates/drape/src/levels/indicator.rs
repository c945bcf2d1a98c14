//! Where to refine: the curvature of the current shape, element by
//! element, and the elements that hold most of it.
//!
//! **The indicator** is the discrete shell's bending energy density
//! without its rigidity (Grinspun, Hirani, Desbrun & Schröder 2003,
//! "Discrete shells", SCA): an interior edge `e` between triangles `T_1`
//! and `T_2` carries
//!
//! ```text
//! E_e = theta_e^2 |e|^2 / (A_1 + A_2)
//! ```
//!
//! with `theta_e` the angle between the triangles' current normals and
//! `|e|`, `A_1`, `A_2` the reference edge length and areas; it tends to
//! `(3/2) ∫ kappa_n^2 dA` over the edge's diamond, `kappa_n` the normal
//! curvature across the edge, and does not depend on a bending model — a
//! membrane without bending folds too. Each triangle holds half of each of
//! its edges' `E_e`: `eta_T = sum_{e in T} E_e / 2`. A flat region holds
//! nothing, a fold most; the measure is relative, so only the ratios
//! between triangles matter.
//!
//! **The chord indicator** (`[refine] indicator = "chord"`) is `eta_T`
//! times the triangle's reference area `A_T`. Where the surface's normal
//! curvature is `kappa`, `theta_e ~ kappa h` and the flat triangle lies
//! a sag `delta ~ kappa h^2 / 8` from the surface, so `eta_T A_T ~
//! kappa^2 h^4 ~ delta^2`: the chordal error of the piecewise flat
//! surface. A split triangle's children hold a sixteenth of it each,
//! their sum a quarter, where `eta_T` keeps its sum (the energy of the
//! region): so with `"bending"` each level refines the folds again,
//! however fine they already are, and with `"chord"` the levels
//! equidistribute the sag — each refines where the mesh resolves the
//! curvature worst.
//!
//! **Marking** is Dörfler's bulk criterion (Dörfler 1996, "A convergent
//! adaptive algorithm for Poisson's equation", SIAM J. Numer. Anal. 33):
//! the fewest triangles, largest indicator first, whose indicators sum to
//! `fraction` of the total. Ties are broken by element index, so the
//! marking depends on the state alone.

use crate::mesh::Mesh;
use crate::vec3::{cross, dot, norm, sub};
use std::collections::HashMap;

/// `eta_T` of every triangle of the linear mesh `mesh` at positions `y`
/// (flat, 3 per node): the module docs.
pub fn curvature_indicator(mesh: &Mesh, y: &[f64]) -> Vec<f64> {
    let at = |a: usize| [y[3 * a], y[3 * a + 1], y[3 * a + 2]];
    let triangles: Vec<[usize; 3]> = mesh.elements().map(|t| [t[0], t[1], t[2]]).collect();
    let area = |t: &[usize; 3]| reference_area(mesh, *t);
    let normal = |t: &[usize; 3]| {
        let [a, b, c] = t.map(at);
        let n = cross(sub(b, a), sub(c, a));
        let r = norm(n);
        if r > 0.0 { n.map(|v| v / r) } else { [0.0; 3] }
    };
    let mut beside: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for (e, t) in triangles.iter().enumerate() {
        for m in 0..3 {
            let (a, b) = (t[m], t[(m + 1) % 3]);
            beside.entry((a.min(b), a.max(b))).or_default().push(e);
        }
    }
    let mut eta = vec![0.0; triangles.len()];
    // Each interior edge once, from its first triangle, in the order of
    // the elements' edges: the sums do not depend on the map's order.
    for (p, t) in triangles.iter().enumerate() {
        for m in 0..3 {
            let (a, b) = (t[m], t[(m + 1) % 3]);
            let &[first, q] = beside[&(a.min(b), a.max(b))].as_slice() else {
                continue; // a boundary (or non-manifold) edge bends nothing
            };
            if first != p {
                continue;
            }
            let (np, nq) = (normal(&triangles[p]), normal(&triangles[q]));
            let theta = norm(cross(np, nq)).atan2(dot(np, nq));
            let d = sub(mesh.nodes[b], mesh.nodes[a]);
            let areas = area(&triangles[p]) + area(&triangles[q]);
            if areas > 0.0 {
                let e = theta * theta * dot(d, d) / areas;
                eta[p] += 0.5 * e;
                eta[q] += 0.5 * e;
            }
        }
    }
    eta
}

/// `eta` (one per triangle of the linear mesh `mesh`) times each
/// triangle's reference area: the chord indicator of the module docs.
pub fn times_area(mesh: &Mesh, eta: &mut [f64]) {
    for (e, t) in mesh.elements().enumerate() {
        eta[e] *= reference_area(mesh, [t[0], t[1], t[2]]);
    }
}

/// The reference area of the triangle with corners `t` of `mesh`.
fn reference_area(mesh: &Mesh, t: [usize; 3]) -> f64 {
    let [a, b, c] = t.map(|v| mesh.nodes[v]);
    0.5 * norm(cross(sub(b, a), sub(c, a)))
}

/// Sets `flags[e]` for every triangle `e` of the linear mesh `mesh` with
/// an edge on its free boundary (`[refine] also = ["rim"]`).
pub fn mark_rim(mesh: &Mesh, flags: &mut [bool]) {
    let rim: std::collections::HashSet<[usize; 2]> = mesh.boundary_edges().into_iter().collect();
    for (e, t) in mesh.elements().enumerate() {
        for m in 0..3 {
            let (a, b) = (t[m], t[(m + 1) % 3]);
            if rim.contains(&[a.min(b), a.max(b)]) {
                flags[e] = true;
            }
        }
    }
}

/// Sets `flags[e]` for every triangle `e` of the linear mesh `mesh` whose
/// corners are some `touching` and some not: the contact line
/// (`[refine] also = ["contact"]`).
pub fn mark_across(mesh: &Mesh, touching: &[bool], flags: &mut [bool]) {
    for (e, t) in mesh.elements().enumerate() {
        let n = t[..3].iter().filter(|&&a| touching[a]).count();
        if n > 0 && n < 3 {
            flags[e] = true;
        }
    }
}

/// Dörfler's marking: the fewest elements, largest `eta` first (ties by
/// index), whose `eta` sum to at least `fraction` of the total; every
/// element where the total is zero (nothing to tell them apart) or
/// `fraction` is 1.
pub fn dorfler(eta: &[f64], fraction: f64) -> Vec<bool> {
    let total: f64 = eta.iter().sum();
    if total <= 0.0 || total.is_nan() || fraction >= 1.0 {
        return vec![true; eta.len()];
    }
    let mut order: Vec<usize> = (0..eta.len()).collect();
    order.sort_by(|&i, &j| eta[j].total_cmp(&eta[i]).then(i.cmp(&j)));
    let mut marked = vec![false; eta.len()];
    let mut sum = 0.0;
    for i in order {
        if sum >= fraction * total {
            break;
        }
        marked[i] = true;
        sum += eta[i];
    }
    marked
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    fn flat(mesh: &Mesh) -> Vec<f64> {
        mesh.nodes.iter().flatten().copied().collect()
    }

    /// The unit square in 4 x 4 squares of two triangles, from (0, 0).
    fn square() -> Mesh {
        generate::rectangle(
            [1.0, 1.0],
            [4, 4],
            generate::Pattern::Right,
            [0.5, 0.5, 0.0],
            crate::mesh::ElementOrder::Linear,
        )
    }

    /// A flat sheet holds nothing; a sheet folded along a line holds it
    /// all on the triangles that have an edge on the fold, as much on each
    /// side, and the closed form.
    #[test]
    fn a_fold_holds_the_indicator() {
        let mesh = square();
        let y = flat(&mesh);
        assert!(curvature_indicator(&mesh, &y).iter().all(|&e| e == 0.0));
        // Fold about the line x = 0.5 by 90 degrees: z = |x - 0.5|.
        let y: Vec<f64> = mesh
            .nodes
            .iter()
            .flat_map(|p| [p[0].min(0.5), p[1], (p[0] - 0.5).max(0.0)])
            .collect();
        let eta = curvature_indicator(&mesh, &y);
        let centroid_x = |e: usize| {
            let t = &mesh.connectivity[3 * e..3 * e + 3];
            t.iter().map(|&a| mesh.nodes[a][0]).sum::<f64>() / 3.0
        };
        for (e, &v) in eta.iter().enumerate() {
            let t = &mesh.connectivity[3 * e..3 * e + 3];
            let on_fold = t.iter().filter(|&&a| mesh.nodes[a][0] == 0.5).count() == 2;
            assert_eq!(v > 0.0, on_fold, "element {e}: {v}");
        }
        let left: f64 = (0..eta.len())
            .filter(|&e| centroid_x(e) < 0.5)
            .map(|e| eta[e])
            .sum();
        let right: f64 = (0..eta.len())
            .filter(|&e| centroid_x(e) > 0.5)
            .map(|e| eta[e])
            .sum();
        assert!((left - right).abs() < 1e-12 * left, "{left} {right}");
        // Each of the 4 fold edges: a right angle, length 0.25, two
        // triangles of 1/32 m² beside it.
        let want = 4.0 * (std::f64::consts::FRAC_PI_2).powi(2) * 0.0625 / (2.0 / 32.0);
        assert!(
            (left + right - want).abs() < 1e-12 * want,
            "{} {want}",
            left + right
        );
    }

    /// On a cylinder of radius R the chord indicator of a triangle
    /// falls sixteenfold when its edges halve (`theta^2` fourfold, the
    /// area fourfold), and the region's sum fourfold, where the bending
    /// indicator's sum stays.
    #[test]
    fn the_chord_indicator_falls_where_the_mesh_is_finer() {
        let on_cylinder = |divisions: usize| {
            let mesh = generate::rectangle(
                [0.2, 0.2],
                [divisions, divisions],
                generate::Pattern::Right,
                [0.0, 0.0, 0.0],
                crate::mesh::ElementOrder::Linear,
            );
            let radius = 0.5;
            let y: Vec<f64> = mesh
                .nodes
                .iter()
                .flat_map(|p| {
                    let phi = p[0] / radius;
                    [radius * phi.sin(), p[1], radius * (1.0 - phi.cos())]
                })
                .collect();
            let bending = curvature_indicator(&mesh, &y);
            let mut chord = bending.clone();
            times_area(&mesh, &mut chord);
            let sum = |v: &[f64]| v.iter().sum::<f64>();
            (sum(&bending), sum(&chord))
        };
        let (coarse, fine) = (on_cylinder(8), on_cylinder(16));
        // The boundary's edges bend nothing: the interior's share grows a
        // little with the divisions (7/8 to 15/16 of the x-edges).
        assert!((fine.0 / coarse.0 - 1.0).abs() < 0.1, "{coarse:?} {fine:?}");
        assert!(
            (fine.1 / coarse.1 - 0.25).abs() < 0.025,
            "{coarse:?} {fine:?}"
        );
    }

    /// The rim's triangles are those with a boundary edge; the contact
    /// line's those with corners on both sides of it.
    #[test]
    fn rim_and_contact_line_are_marked() {
        let mesh = square();
        let mut flags = vec![false; mesh.element_count()];
        mark_rim(&mesh, &mut flags);
        let on_rim = |e: usize| {
            let t = &mesh.connectivity[3 * e..3 * e + 3];
            let side = |c: usize, v: f64| t.iter().filter(|&&a| mesh.nodes[a][c] == v).count() == 2;
            side(0, 0.0) || side(0, 1.0) || side(1, 0.0) || side(1, 1.0)
        };
        for (e, &f) in flags.iter().enumerate() {
            assert_eq!(f, on_rim(e), "element {e}");
        }
        // 4 x 4 squares of two triangles: 16 boundary edges, of 14
        // triangles (two corner triangles hold two each).
        assert_eq!(flags.iter().filter(|&&f| f).count(), 14);
        // The nodes at x = 0 and 0.25 touch, those from x = 0.5 on do
        // not: the second column of squares' triangles are across.
        let touching: Vec<bool> = mesh.nodes.iter().map(|p| p[0] < 0.3).collect();
        let mut flags = vec![false; mesh.element_count()];
        mark_across(&mesh, &touching, &mut flags);
        for (e, &f) in flags.iter().enumerate() {
            let t = &mesh.connectivity[3 * e..3 * e + 3];
            let xs: Vec<f64> = t.iter().map(|&a| mesh.nodes[a][0]).collect();
            let across = xs.contains(&0.25) && xs.contains(&0.5);
            assert_eq!(f, across, "element {e}: {xs:?}");
        }
        assert_eq!(flags.iter().filter(|&&f| f).count(), 8);
    }

    /// Dörfler marks the largest first until the share is reached, ties by
    /// index; all where nothing tells the elements apart.
    #[test]
    fn dorfler_marks_the_fewest_that_hold_the_share() {
        let eta = [1.0, 5.0, 0.0, 3.0, 1.0];
        assert_eq!(dorfler(&eta, 0.5), [false, true, false, false, false]);
        assert_eq!(dorfler(&eta, 0.6), [false, true, false, true, false]);
        assert_eq!(dorfler(&eta, 0.85), [true, true, false, true, false]);
        assert_eq!(dorfler(&eta, 1.0), [true; 5]);
        assert_eq!(dorfler(&[0.0; 3], 0.5), [true; 3]);
    }
}
