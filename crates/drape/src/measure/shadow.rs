//! The shadow of the fabric on the horizontal plane: the union of its
//! elements' projections, folds that overlap counted once.
//!
//! # Method
//!
//! Each element is cut into `m²` flat sub-triangles through the points
//! `x(ξ)` of the lattice `ξ = (i/m, j/m)`, `i + j <= m`, of its reference
//! triangle (`m = p k`: order `p`, `k` subdivisions of each node interval;
//! for `k = 1` the lattice points are the element's nodes, as in the
//! renderer). Each sub-triangle is projected, turned counter-clockwise
//! (a fold turns it over; two opposite windings would cancel under the
//! non-zero rule) and the union of all of them is taken in one sweep by
//! `i_overlay` (a Vatti-type sweep on a 64-bit integer grid of
//! `2^-59` of the shadow's extent; non-zero fill rule). Its area is the
//! sum of the shoelace areas of the outer contours less those of the holes.
//!
//! # Error bound
//!
//! A flat T3 projects exactly: the only error is rounding (a few units of
//! the last place of the coordinates). A curved element `x(ξ)` of order
//! `p > 1` is replaced by its piecewise-linear interpolant `x_h` on the
//! sub-triangles, whose legs in the reference triangle are `h = 1/m`. For
//! each horizontal component `f` the linear interpolation error on a
//! simplex is at most `R_T² |f|_{2,∞} / 2`, `R_T` the radius of the
//! smallest ball holding it (Waldron 1998, "The error in linear
//! interpolation at the vertices of a simplex", SIAM J. Numer. Anal. 35),
//! here `R_T² = h² / 2`, so every point of the element moves by at most
//!
//! ```text
//! δ_e = S_e / (4 m²),   S_e = max_ξ sqrt(‖H_1(ξ)‖² + ‖H_2(ξ)‖²)
//! ```
//!
//! with `H_c = Σ_a (e_c · x_a) ∂²φ_a/∂ξ²` the reference Hessian of the
//! projected component `c` and `‖·‖` its spectral norm. `H_c` is constant
//! on a T6 and affine on a T10, so `S_e` is its largest value at the three
//! vertices. The exact shadow and the computed one are then within
//! `δ = max_e δ_e` of each other (each point of one lies within `δ` of the
//! other), so their areas differ by at most the area of the band of width
//! `δ` on either side of the outline:
//!
//! ```text
//! |A − A_h| <= 2 δ L + N π δ²
//! ```
//!
//! (`L` the outline's length, `N` its vertices; exact where the shadow has
//! no feature narrower than `2δ`). `δ` also carries the rounding of the
//! coordinates, `8 ε_mach` times the extent `D`, and the bound that of the
//! shoelace sum, `4 ε_mach D²` per outline vertex. For curved elements `k` is raised from 1
//! until the bound is at most [`TOLERANCE`] of the area, or the
//! sub-triangles reach [`MAX_TRIANGLES`]; the bound is reported either way.

use super::{Horizontal, MeasureError, Surface};
use crate::mesh::ElementOrder;
use crate::mesh::lagrange::{ShapeFunctions, reference_nodes};
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::overlay::FloatOverlay;

/// Relative bound `|A − A_h| / A` that refinement of curved elements aims
/// for: 1e-3, at most 0.15 percentage points of drape coefficient on the
/// 30 cm / 18 cm tester (`A / (π R² − π r_p²) <= 1.6`). The bound is
/// pessimistic (on single curved elements 7 to 25 times the error).
pub const TOLERANCE: f64 = 1e-3;

/// Most sub-triangles refinement may make (64 bytes each, and the union's
/// own segments): a 10,000-element T6 mesh may be cut up to 10 times per
/// node interval, a 100,000-element one 3 times.
pub const MAX_TRIANGLES: usize = 4_000_000;

/// The shadow of a surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Shadow {
    /// Area `A_h` (m²) of the union of the projected sub-triangles.
    pub area: f64,
    /// Bound on `|A_h − A|` (m²), `A` the area of the union of the exact
    /// elements' projections (see the module's documentation).
    pub error_bound: f64,
    /// The outline in plane coordinates ([`Horizontal::project`]): each
    /// shape's outer contour counter-clockwise, then its holes clockwise.
    pub outline: Vec<Vec<[f64; 2]>>,
    /// `m`: sub-triangles per element edge.
    pub subdivisions: usize,
}

/// The shadow of `surface` on `plane`.
///
/// # Errors
/// A surface that fails [`Surface::check`].
pub fn shadow(surface: &Surface, plane: &Horizontal) -> Result<Shadow, MeasureError> {
    surface.check()?;
    let n = surface.order.nodes_per_element();
    let projected: Vec<[f64; 2]> = surface
        .positions
        .iter()
        .map(|&y| plane.project(y))
        .collect();
    let elements = surface.connectivity.len() / n;
    let p = surface.order.degree();
    let size = extent(&projected);
    let rounding = 8.0 * f64::EPSILON * size;
    // The shoelace sum's rounding: a few units of the last place of each
    // of its terms, at most the extent squared.
    let summation = 4.0 * f64::EPSILON * size * size;
    let mut k = 1;
    let curvature = if p > 1 {
        max_curvature(surface.order, surface.connectivity, &projected)
    } else {
        0.0
    };
    loop {
        let m = p * k;
        let delta = curvature / (4.0 * (m * m) as f64) + rounding;
        let triangles = sub_triangles(surface.order, m, surface.connectivity, &projected);
        let (area, outline) = union_area(&triangles);
        let (length, vertices) = perimeter(&outline);
        let bound = 2.0 * delta * length
            + vertices as f64 * (std::f64::consts::PI * delta * delta + summation);
        let wanted = TOLERANCE * area;
        let most = ((MAX_TRIANGLES / elements.max(1)) as f64).sqrt() as usize / p;
        if bound <= wanted || curvature == 0.0 || k >= most {
            return Ok(Shadow {
                area,
                error_bound: bound,
                outline,
                subdivisions: m,
            });
        }
        // The bound falls as 1/k² (the outline's length barely changes).
        let factor = (bound / wanted).sqrt().ceil() as usize;
        k = (k * factor.max(2)).min(most);
    }
}

/// The largest extent of the points, for the rounding term.
fn extent(points: &[[f64; 2]]) -> f64 {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for q in points {
        for c in 0..2 {
            lo[c] = lo[c].min(q[c]);
            hi[c] = hi[c].max(q[c]);
        }
    }
    (hi[0] - lo[0]).max(hi[1] - lo[1]).max(0.0)
}

/// `max_e S_e`: the largest `sqrt(‖H_1‖² + ‖H_2‖²)` over the elements'
/// vertices, `H_c` the reference Hessian of projected component `c`.
///
/// The shape functions' second derivatives are central differences of
/// their first derivatives, exact for the polynomials of degree <= 2 that
/// those are (orders 1–3).
fn max_curvature(order: ElementOrder, connectivity: &[usize], projected: &[[f64; 2]]) -> f64 {
    let basis = ShapeFunctions::new(order);
    let n = order.nodes_per_element();
    let h = 0.5;
    // d2phi[v][a] = [φ_a,11, φ_a,12, φ_a,22] at vertex v.
    let vertices = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    let mut d2phi = vec![[[0.0; 3]; 10]; 3];
    for (v, xi) in vertices.iter().enumerate() {
        let (_, plus1) = basis.evaluate([xi[0] + h, xi[1]]);
        let (_, minus1) = basis.evaluate([xi[0] - h, xi[1]]);
        let (_, plus2) = basis.evaluate([xi[0], xi[1] + h]);
        let (_, minus2) = basis.evaluate([xi[0], xi[1] - h]);
        for a in 0..n {
            let d11 = (plus1[a][0] - minus1[a][0]) / (2.0 * h);
            let d22 = (plus2[a][1] - minus2[a][1]) / (2.0 * h);
            let d12 = 0.5
                * ((plus1[a][1] - minus1[a][1]) / (2.0 * h)
                    + (plus2[a][0] - minus2[a][0]) / (2.0 * h));
            d2phi[v][a] = [d11, d12, d22];
        }
    }
    let mut largest: f64 = 0.0;
    for el in connectivity.chunks_exact(n) {
        for d in &d2phi {
            let mut squared = 0.0;
            for c in 0..2 {
                let mut hc = [0.0; 3];
                for (a, &node) in el.iter().enumerate() {
                    for i in 0..3 {
                        hc[i] += d[a][i] * projected[node][c];
                    }
                }
                squared += spectral_norm(hc).powi(2);
            }
            largest = largest.max(squared.sqrt());
        }
    }
    largest
}

/// Largest `|λ|` of the symmetric matrix `[[a, b], [b, c]]` given as
/// `[a, b, c]`: `|a + c| / 2 + sqrt(((a − c) / 2)² + b²)`.
fn spectral_norm([a, b, c]: [f64; 3]) -> f64 {
    0.5 * (a + c).abs() + (0.25 * (a - c) * (a - c) + b * b).sqrt()
}

/// The projected sub-triangles of every element on the lattice of `m`
/// intervals per edge, each counter-clockwise; those of zero area left
/// out.
fn sub_triangles(
    order: ElementOrder,
    m: usize,
    connectivity: &[usize],
    projected: &[[f64; 2]],
) -> Vec<[[f64; 2]; 3]> {
    let n = order.nodes_per_element();
    let index = |i: usize, j: usize| j * (m + 1) - j * (j.saturating_sub(1)) / 2 + i;
    let lattice: Vec<[f64; 2]> = (0..=m)
        .flat_map(|j| (0..=m - j).map(move |i| [i as f64 / m as f64, j as f64 / m as f64]))
        .collect();
    // Weights of the nodes at the lattice points; on the nodes' own
    // lattice (m = p) the nodes themselves, exactly.
    let weights: Vec<[f64; 10]> = if m == order.degree() {
        let nodes = reference_nodes(order);
        lattice
            .iter()
            .map(|xi| {
                let mut w = [0.0; 10];
                if let Some(a) = nodes
                    .iter()
                    .position(|q| (q[0] - xi[0]).abs() < 1e-12 && (q[1] - xi[1]).abs() < 1e-12)
                {
                    w[a] = 1.0;
                }
                w
            })
            .collect()
    } else {
        let basis = ShapeFunctions::new(order);
        lattice.iter().map(|&xi| basis.evaluate(xi).0).collect()
    };
    let mut local = vec![[0.0; 2]; lattice.len()];
    let mut out = Vec::with_capacity(connectivity.len() / n * m * m);
    for el in connectivity.chunks_exact(n) {
        for (q, w) in local.iter_mut().zip(&weights) {
            *q = [0.0; 2];
            for (a, &node) in el.iter().enumerate() {
                q[0] += w[a] * projected[node][0];
                q[1] += w[a] * projected[node][1];
            }
        }
        for j in 0..m {
            for i in 0..m - j {
                push_ccw(
                    &mut out,
                    [
                        local[index(i, j)],
                        local[index(i + 1, j)],
                        local[index(i, j + 1)],
                    ],
                );
                if i + j + 1 < m {
                    push_ccw(
                        &mut out,
                        [
                            local[index(i + 1, j)],
                            local[index(i + 1, j + 1)],
                            local[index(i, j + 1)],
                        ],
                    );
                }
            }
        }
    }
    out
}

/// Adds `t` turned counter-clockwise, unless it has no area.
fn push_ccw(out: &mut Vec<[[f64; 2]; 3]>, [a, b, c]: [[f64; 2]; 3]) {
    let twice = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if twice > 0.0 {
        out.push([a, b, c]);
    } else if twice < 0.0 {
        out.push([a, c, b]);
    }
}

/// Area and contours of the union of counter-clockwise triangles.
fn union_area(triangles: &[[[f64; 2]; 3]]) -> (f64, Vec<Vec<[f64; 2]>>) {
    if triangles.is_empty() {
        return (0.0, Vec::new());
    }
    let contours: Vec<&[[f64; 2]]> = triangles.iter().map(|t| &t[..]).collect();
    let shapes = FloatOverlay::<[f64; 2], i64>::from_subj(&contours)
        .overlay(OverlayRule::Subject, FillRule::NonZero);
    let mut area = 0.0;
    let mut outline = Vec::new();
    for shape in shapes {
        for (i, contour) in shape.into_iter().enumerate() {
            let a = shoelace(&contour).abs();
            // The first contour of a shape is its outer boundary, the
            // others its holes.
            area += if i == 0 { a } else { -a };
            outline.push(contour);
        }
    }
    (area, outline)
}

/// Signed area of a closed polygon (positive counter-clockwise).
fn shoelace(contour: &[[f64; 2]]) -> f64 {
    let n = contour.len();
    (0..n)
        .map(|i| {
            let (p, q) = (contour[i], contour[(i + 1) % n]);
            p[0] * q[1] - p[1] * q[0]
        })
        .sum::<f64>()
        / 2.0
}

/// Total length and number of vertices of the contours.
fn perimeter(outline: &[Vec<[f64; 2]>]) -> (f64, usize) {
    let mut length = 0.0;
    let mut vertices = 0;
    for c in outline {
        vertices += c.len();
        for i in 0..c.len() {
            let (p, q) = (c[i], c[(i + 1) % c.len()]);
            length += (q[0] - p[0]).hypot(q[1] - p[1]);
        }
    }
    (length, vertices)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn z_up() -> Horizontal {
        Horizontal::new([0.0; 3], [0.0, 0.0, 1.0]).unwrap()
    }

    /// Two triangles of opposite winding over the same square's halves,
    /// and a third over both: the union is the unit square.
    #[test]
    fn union_counts_overlap_once_whatever_the_winding() {
        let t = [
            [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
            [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0]], // clockwise
            [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        ];
        let mut ccw = Vec::new();
        for x in t {
            push_ccw(&mut ccw, x);
        }
        let (area, outline) = union_area(&ccw);
        assert!((area - 1.0).abs() < 1e-14, "{area}");
        let (length, _) = perimeter(&outline);
        assert!((length - 4.0).abs() < 1e-14);
    }

    #[test]
    fn lattice_covers_the_element_once() {
        for order in [
            ElementOrder::Linear,
            ElementOrder::Quadratic,
            ElementOrder::Cubic,
        ] {
            let nodes = reference_nodes(order);
            let projected: Vec<[f64; 2]> = nodes.clone();
            let connectivity: Vec<usize> = (0..nodes.len()).collect();
            for m in [order.degree(), 2 * order.degree(), 5] {
                let t = sub_triangles(order, m, &connectivity, &projected);
                assert_eq!(t.len(), m * m);
                let sum: f64 = t.iter().map(|t| shoelace(t)).sum();
                assert!((sum - 0.5).abs() < 1e-14, "{order:?} m = {m}: {sum}");
            }
        }
    }

    #[test]
    fn spectral_norm_of_symmetric_2x2() {
        assert!((spectral_norm([2.0, 0.0, -3.0]) - 3.0).abs() < 1e-15);
        assert!((spectral_norm([1.0, 1.0, 1.0]) - 2.0).abs() < 1e-15);
        assert_eq!(spectral_norm([0.0; 3]), 0.0);
    }

    /// A flat T3 square: exact, no refinement, a bound of rounding only.
    #[test]
    fn flat_linear_mesh_is_exact() {
        let positions = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let s = shadow(
            &Surface {
                positions: &positions,
                connectivity: &[0, 1, 2, 0, 2, 3],
                order: ElementOrder::Linear,
            },
            &z_up(),
        )
        .unwrap();
        assert!((s.area - 2.0).abs() < 1e-14);
        assert_eq!(s.subdivisions, 1);
        assert!(
            s.error_bound > 0.0 && s.error_bound < 1e-13,
            "{}",
            s.error_bound
        );
    }
}
