//! Triangles of a planar polygon (an OBJ face of more than three corners)
//! by ear clipping, or why it has none.
//!
//! A fan about the first corner is right only for a polygon that is
//! star-shaped about that corner: a concave face fanned gives overlapping,
//! flipped triangles and a wrong area (and mass). Ear clipping cuts off,
//! one after the other, a corner whose triangle is convex and holds no
//! other corner; every simple polygon has such an "ear" (Meisters' two-ears
//! theorem, 1975). Tried from the second corner on, the ears of a convex
//! polygon are the fan's triangles, so convex faces give what they gave
//! before.
//!
//! The polygon is projected on its plane, the one through its centroid
//! normal to Newell's normal `n = sum_i x_i x x_{i+1}` (which also gives
//! the winding: the polygon turns counter-clockwise about `n`). Refused:
//! a polygon whose corners lie off that plane by more than
//! [`PLANARITY`] of its diameter, one with no area, one whose edges cross
//! or touch (self-intersecting: it has no inside to triangulate), and one
//! of more than [`MAX_CORNERS`] corners.

use crate::vec3::{cross, dot, norm, scale, sub};

/// The largest distance of a corner from the polygon's plane, as a
/// fraction of its diameter: a face bent more than this is not one flat
/// piece of fabric, and which diagonal splits it would change the shape.
pub const PLANARITY: f64 = 1.0e-3;

/// The most corners a polygon may have (the checks are quadratic in them).
pub const MAX_CORNERS: usize = 1000;

/// Why a polygon cannot be triangulated. Corners are 0-based positions in
/// the polygon.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PolygonError {
    /// Too many corners.
    #[error("it has {0} corners, more than {MAX_CORNERS}")]
    TooManyCorners(usize),
    /// No area: its corners are (nearly) on one line.
    #[error("it has no area (its corners lie on one line)")]
    NoArea,
    /// A corner off the plane.
    #[error(
        "it is not planar: corner {corner} lies {distance:.3e} m off its plane, more than {PLANARITY} of its size {size:.3e} m; split it into triangles in the file"
    )]
    NotPlanar {
        /// The corner.
        corner: usize,
        /// Its distance from the plane (m).
        distance: f64,
        /// The polygon's diameter (m).
        size: f64,
    },
    /// Two edges cross or touch.
    #[error("it intersects itself: its edges from corner {0} and from corner {1} cross or touch")]
    SelfIntersecting(usize, usize),
}

/// The triangles of the polygon `x` (its corners in order), as triples of
/// positions in `x`, in the polygon's orientation.
///
/// # Errors
/// See [`PolygonError`].
pub fn triangulate(x: &[[f64; 3]]) -> Result<Vec<[usize; 3]>, PolygonError> {
    let n = x.len();
    if n > MAX_CORNERS {
        return Err(PolygonError::TooManyCorners(n));
    }
    if n < 3 {
        return Err(PolygonError::NoArea);
    }
    let mut normal = [0.0; 3];
    let mut centroid = [0.0; 3];
    for i in 0..n {
        let c = cross(x[i], x[(i + 1) % n]);
        for k in 0..3 {
            normal[k] += c[k];
            centroid[k] += x[i][k] / n as f64;
        }
    }
    let size = (0..n)
        .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
        .map(|(i, j)| norm(sub(x[i], x[j])))
        .fold(0.0, f64::max);
    // Twice the area is |n|; against the diameter squared for "no area".
    let length = norm(normal);
    if length.is_nan() || length <= 1e-10 * size * size {
        return Err(PolygonError::NoArea);
    }
    let e3 = scale(normal, 1.0 / length);
    for (corner, p) in x.iter().enumerate() {
        let distance = dot(sub(*p, centroid), e3).abs();
        if distance > PLANARITY * size {
            return Err(PolygonError::NotPlanar {
                corner,
                distance,
                size,
            });
        }
    }
    // In-plane axes with e1 x e2 = e3: the polygon runs counter-clockwise.
    let helper = if e3[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = {
        let c = cross(helper, e3);
        scale(c, 1.0 / norm(c))
    };
    let e2 = cross(e3, e1);
    let p: Vec<[f64; 2]> = x
        .iter()
        .map(|q| {
            let d = sub(*q, centroid);
            [dot(d, e1), dot(d, e2)]
        })
        .collect();
    for i in 0..n {
        for j in i + 1..n {
            // Neighbouring edges share a corner and meet there only.
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            if segments_meet(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]) {
                return Err(PolygonError::SelfIntersecting(i, j));
            }
        }
    }
    Ok(clip_ears(&p))
}

/// Twice the signed area of the triangle `a b c` (> 0: counter-clockwise).
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Whether the segments `a b` and `c d` cross or touch.
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: [f64; 2], q: [f64; 2], r: [f64; 2], o: f64| {
        o == 0.0
            && r[0] >= p[0].min(q[0])
            && r[0] <= p[0].max(q[0])
            && r[1] >= p[1].min(q[1])
            && r[1] <= p[1].max(q[1])
    };
    on(c, d, a, d1) || on(c, d, b, d2) || on(a, b, c, d3) || on(a, b, d, d4)
}

/// Ear clipping of the simple counter-clockwise polygon `p`.
fn clip_ears(p: &[[f64; 2]]) -> Vec<[usize; 3]> {
    let mut left: Vec<usize> = (0..p.len()).collect();
    let mut out = Vec::with_capacity(p.len() - 2);
    while left.len() > 3 {
        let m = left.len();
        // From the second corner on: a convex polygon's ears are its fan.
        let ear = (1..=m).map(|k| k % m).find(|&k| {
            let (a, b, c) = (left[(k + m - 1) % m], left[k], left[(k + 1) % m]);
            orient(p[a], p[b], p[c]) > 0.0
                && !left.iter().any(|&q| {
                    q != a
                        && q != b
                        && q != c
                        && orient(p[a], p[b], p[q]) >= 0.0
                        && orient(p[b], p[c], p[q]) >= 0.0
                        && orient(p[c], p[a], p[q]) >= 0.0
                })
        });
        // A simple polygon always has an ear; round-off may hide it, and
        // the most convex corner is then the best cut.
        let k = ear.unwrap_or_else(|| {
            (0..m)
                .max_by(|&i, &j| {
                    let turn = |k: usize| {
                        orient(p[left[(k + m - 1) % m]], p[left[k]], p[left[(k + 1) % m]])
                    };
                    turn(i).total_cmp(&turn(j))
                })
                .unwrap_or(0)
        });
        out.push([left[(k + m - 1) % m], left[k], left[(k + 1) % m]]);
        left.remove(k);
    }
    out.push([left[0], left[1], left[2]]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(x: &[[f64; 3]], t: &[[usize; 3]]) -> f64 {
        t.iter()
            .map(|&[a, b, c]| 0.5 * cross(sub(x[b], x[a]), sub(x[c], x[a]))[2].abs())
            .sum()
    }

    /// A convex polygon gives the fan about its first corner, as before.
    #[test]
    fn a_convex_polygon_gives_the_fan() {
        let hexagon: Vec<[f64; 3]> = (0..6)
            .map(|k| {
                let a = std::f64::consts::PI / 3.0 * k as f64;
                [a.cos(), a.sin(), 0.0]
            })
            .collect();
        let t = triangulate(&hexagon).unwrap();
        assert_eq!(t, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]);
    }

    /// An L (concave at its corner 4) and an arrow: every triangle turns
    /// as the polygon does and their areas add up to the polygon's
    /// (shoelace formula), where the fan overlapped.
    #[test]
    fn concave_polygons_are_cut_into_ears() {
        // The L: 2 x 2 minus the 1 x 1 top-right square, area 3.
        let l = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, 2.0, 0.0],
            [0.0, 2.0, 0.0],
        ];
        // An arrow, concave at corner 1, area 1.5: a fan about corner 0
        // would hold a flipped triangle.
        let arrow = [
            [0.0, 0.0, 0.0],
            [1.0, 0.5, 0.0],
            [2.0, 0.0, 0.0],
            [1.0, 2.0, 0.0],
        ];
        for (x, expected) in [(&l[..], 3.0), (&arrow[..], 1.5)] {
            let t = triangulate(x).unwrap();
            assert_eq!(t.len(), x.len() - 2);
            for &[a, b, c] in &t {
                assert!(cross(sub(x[b], x[a]), sub(x[c], x[a]))[2] > 0.0, "{t:?}");
            }
            // Exact in binary: the corners are small integers and halves.
            assert_eq!(area(x, &t), expected, "{t:?}");
        }
        // The fan about corner 0 of the arrow overlaps: its area is 2.5.
        let fan = [[0, 1, 2], [0, 2, 3]];
        assert_ne!(area(&arrow, &fan), 1.5);
    }

    #[test]
    fn bent_self_intersecting_and_flat_polygons_are_refused() {
        let bent = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.1],
            [0.0, 1.0, 0.0],
        ];
        assert!(matches!(
            triangulate(&bent),
            Err(PolygonError::NotPlanar { .. })
        ));
        // Edges 0 and 2 cross (lobes of unequal area: the polygon has one).
        let bow_tie = [
            [0.0, 0.0, 0.0],
            [2.0, 2.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        assert_eq!(
            triangulate(&bow_tie),
            Err(PolygonError::SelfIntersecting(0, 2))
        );
        let line = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
        ];
        assert_eq!(triangulate(&line), Err(PolygonError::NoArea));
    }
}
