//! Distances between the fabric's own triangles, for self-contact (issue
//! 33): the closest points of a point and a triangle and of two edges,
//! the squared distance and its gradient, and a spatial-hash broad phase
//! that finds the pairs that may be closer than a distance.
//!
//! Both primitives are what Incremental Potential Contact's barrier is
//! summed over (Li et al. 2020, §4): a node against a triangle it is not
//! a vertex of, and an edge against an edge it shares no node with —
//! edge–edge catches two folds that cross edge to edge, where no node
//! comes near a triangle.
//!
//! **The squared distance and its gradient.** With the closest points
//! written as weighted sums of the primitives' nodes, `p - c = sum_i w_i
//! x_i` (point–triangle: `w = (1, -u, -v, -w)` with `(u, v, w)` the
//! closest point's barycentric coordinates; edge–edge: `w = (1 - s, s,
//! t - 1, -t)`), the squared distance is `d^2 = |sum_i w_i x_i|^2` and,
//! the weights being a minimiser over the primitives' (convex) parameter
//! sets, its gradient is (the envelope theorem, Danskin's theorem where
//! the minimiser is unique)
//!
//! ```text
//! d(d^2) / dx_i = 2 w_i (p - c)
//! ```
//!
//! — continuous everywhere, and the exact derivative wherever the closest
//! points are unique (everywhere but where two edges are parallel, whose
//! distance is still right). The closest points follow Ericson (2005,
//! *Real-Time Collision Detection*, §5.1.5 and §5.1.9).
//!
//! **Broad phase** ([`candidates`]): a uniform grid hashed into a map, of
//! cells as large as the longest edge or the distance, whichever is
//! larger; each triangle and edge is entered in the cells its box (grown
//! by the distance) overlaps, and each node and edge is tested against the
//! entries of its cells whose boxes hold it. Linear in the mesh for a
//! bounded number of entries per cell (a fabric is a surface: a cell as
//! large as its elements holds a few of them, a fold a few more).
//! A box over more than `MAX_CELLS` cells — in [`swept_candidates`], a
//! node whose motion is far longer than the cells, or not finite — is
//! kept out of the grid and tested against every box of the other kind
//! instead: the grid never holds more than `MAX_CELLS` entries a box,
//! whatever the motion (issue 46: one Newton direction that moved a few
//! nodes a metre entered each in millions of cells, and the step never
//! ended while its memory grew by tens of megabytes a second).

use crate::vec3::{add, dot, scale, sub};
use std::collections::HashMap;

/// Closest points of two primitives: the squared distance and the weights
/// of the four nodes in `p - c` (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// Squared distance (m^2).
    pub d2: f64,
    /// `w`: `p - c = sum_i w_i x_i` over the four nodes, in the order the
    /// primitive was given.
    pub weights: [f64; 4],
}

impl Closest {
    /// The gradient of the squared distance with respect to the four nodes'
    /// positions `x`, `2 w_i (p - c)` (module docs).
    pub fn gradient(&self, x: [[f64; 3]; 4]) -> [[f64; 3]; 4] {
        let diff = (0..4).fold([0.0; 3], |acc, i| add(acc, scale(x[i], self.weights[i])));
        self.weights.map(|w| scale(diff, 2.0 * w))
    }
}

/// The closest points of point `p` and triangle `(a, b, c)` (Ericson
/// §5.1.5: the Voronoi regions of the vertices, the edges and the face).
/// A degenerate triangle is measured as its longest edge.
pub fn point_triangle(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Closest {
    let with = |u: f64, v: f64, w: f64| {
        let q = add(add(scale(a, u), scale(b, v)), scale(c, w));
        let d = sub(p, q);
        Closest {
            d2: dot(d, d),
            weights: [1.0, -u, -v, -w],
        }
    };
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return with(1.0, 0.0, 0.0);
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return with(0.0, 1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return with(1.0 - v, v, 0.0);
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return with(0.0, 0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return with(1.0 - w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return with(0.0, 1.0 - w, w);
    }
    let denom = va + vb + vc;
    if denom.abs() <= f64::MIN_POSITIVE || !denom.is_finite() {
        // No area: the nearest of its three edges.
        let [e1, e2, e3] = [
            edge_edge(p, p, a, b),
            edge_edge(p, p, b, c),
            edge_edge(p, p, c, a),
        ];
        let best = [(e1, [0, 1]), (e2, [1, 2]), (e3, [2, 0])]
            .into_iter()
            .min_by(|x, y| x.0.d2.total_cmp(&y.0.d2))
            .expect("three edges");
        let mut weights = [1.0, 0.0, 0.0, 0.0];
        weights[1 + best.1[0]] = best.0.weights[2];
        weights[1 + best.1[1]] = best.0.weights[3];
        return Closest {
            d2: best.0.d2,
            weights,
        };
    }
    let v = vb / denom;
    let w = vc / denom;
    with(1.0 - v - w, v, w)
}

/// The closest points of segments `(p0, p1)` and `(q0, q1)` (Ericson
/// §5.1.9; a segment of no length is a point; parallel segments take the
/// closest pair with `s` clamped from the start).
pub fn edge_edge(p0: [f64; 3], p1: [f64; 3], q0: [f64; 3], q1: [f64; 3]) -> Closest {
    let (d1, d2, r) = (sub(p1, p0), sub(q1, q0), sub(p0, q0));
    let (a, e, f) = (dot(d1, d1), dot(d2, d2), dot(d2, r));
    let tiny = 1e-30;
    let (s, t) = if a <= tiny && e <= tiny {
        (0.0, 0.0)
    } else if a <= tiny {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = dot(d1, r);
        if e <= tiny {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = dot(d1, d2);
            let denom = a * e - b * b;
            let mut s = if denom > 1e-14 * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    let cp = add(p0, scale(d1, s));
    let cq = add(q0, scale(d2, t));
    let d = sub(cp, cq);
    Closest {
        d2: dot(d, d),
        weights: [1.0 - s, s, -(1.0 - t), -t],
    }
}

/// Pairs that may be closer than a distance ([`candidates`]).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Candidates {
    /// `(node, triangle)`, the node not a vertex of the triangle, sorted.
    pub point_triangle: Vec<(usize, usize)>,
    /// `(edge, edge)`, the first the smaller, sharing no node, sorted.
    pub edge_edge: Vec<(usize, usize)>,
}

/// The unique edges of `triangles`, each `[a, b]` with `a < b`, sorted.
pub fn edges_of(triangles: &[[usize; 3]]) -> Vec<[usize; 2]> {
    let mut edges: Vec<[usize; 2]> = triangles
        .iter()
        .flat_map(|t| [0, 1, 2].map(|k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])]))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// An axis-aligned box, `(min, max)` corners.
type Aabb = ([f64; 3], [f64; 3]);

/// The box of `points` grown by `by`.
fn bounds(points: impl Iterator<Item = [f64; 3]>, by: f64) -> Aabb {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in points {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    (lo.map(|v| v - by), hi.map(|v| v + by))
}

/// Whether two boxes overlap.
fn overlap(a: &Aabb, b: &Aabb) -> bool {
    (0..3).all(|i| a.0[i] <= b.1[i] && b.0[i] <= a.1[i])
}

/// The most grid cells a box is entered in, or has its cells looked up
/// in (module docs): more than a box as large as the cells meets (at most
/// 2 x 2 x 2) and than [`candidates`] makes (its boxes are at most three
/// cells long, 4 x 4 x 4 cells).
const MAX_CELLS: f64 = 64.0;

/// How many cells of size `h` box `b` overlaps; infinite for a box that
/// is not finite.
fn cell_count(b: &Aabb, h: f64) -> f64 {
    (0..3)
        .map(|i| (b.1[i] / h).floor() - (b.0[i] / h).floor() + 1.0)
        .map(|n| {
            if n.is_finite() {
                n.max(1.0)
            } else {
                f64::INFINITY
            }
        })
        .product()
}

/// Whether box `b` is kept out of a grid of cells of size `h` and tested
/// against every box instead ([`MAX_CELLS`]).
fn too_large(b: &Aabb, h: f64) -> bool {
    cell_count(b, h) > MAX_CELLS
}

/// The grid's cells a box overlaps (cell size `h`).
fn cells(b: &Aabb, h: f64) -> impl Iterator<Item = [i64; 3]> {
    let lo = b.0.map(|v| (v / h).floor() as i64);
    let hi = b.1.map(|v| (v / h).floor() as i64);
    (lo[0]..=hi[0]).flat_map(move |i| {
        (lo[1]..=hi[1]).flat_map(move |j| (lo[2]..=hi[2]).map(move |k| [i, j, k]))
    })
}

/// The node–triangle and edge–edge pairs of a mesh at positions `x` whose
/// boxes, grown by `distance`, overlap: every pair closer than `distance`
/// is among them (a superset; [`point_triangle`] and [`edge_edge`] then
/// measure them). `edges` as [`edges_of`] gives them.
pub fn candidates(
    x: &[[f64; 3]],
    triangles: &[[usize; 3]],
    edges: &[[usize; 2]],
    distance: f64,
) -> Candidates {
    let longest = longest_edge(x, edges);
    let h = longest.max(distance).max(f64::MIN_POSITIVE);
    let point_box: Vec<_> = x.iter().map(|&p| (p, p)).collect();
    let tri_box: Vec<_> = (triangles.iter())
        .map(|t| bounds(t.iter().map(|&a| x[a]), distance))
        .collect();
    let edge_box: Vec<_> = (edges.iter())
        .map(|e| bounds(e.iter().map(|&a| x[a]), distance))
        .collect();
    pairs_of_boxes(&point_box, &tri_box, &edge_box, triangles, edges, h)
}

/// The pairs whose boxes swept over a motion — from `x` to `x + dx` —
/// and grown by `margin` overlap: every pair that comes closer than
/// `margin` at some point of the straight-line motion is among them (what
/// continuous collision detection then checks). Each primitive's box
/// holds it at both ends, so a node that moves far makes its own box
/// large, not every box.
pub fn swept_candidates(
    x: &[[f64; 3]],
    dx: &[[f64; 3]],
    triangles: &[[usize; 3]],
    edges: &[[usize; 2]],
    margin: f64,
) -> Candidates {
    let b = SweptBoxes::new(x, dx, triangles, edges, margin);
    pairs_of_boxes(&b.points, &b.triangles, &b.edges, triangles, edges, b.h)
}

/// The boxes of [`swept_candidates`] and the size of its grid's cells.
struct SweptBoxes {
    points: Vec<Aabb>,
    triangles: Vec<Aabb>,
    edges: Vec<Aabb>,
    h: f64,
}

impl SweptBoxes {
    fn new(
        x: &[[f64; 3]],
        dx: &[[f64; 3]],
        triangles: &[[usize; 3]],
        edges: &[[usize; 2]],
        margin: f64,
    ) -> Self {
        let end: Vec<[f64; 3]> = x.iter().zip(dx).map(|(&p, &d)| add(p, d)).collect();
        let both = |nodes: &[usize]| bounds(nodes.iter().flat_map(|&a| [x[a], end[a]]), margin);
        let points: Vec<_> = (0..x.len()).map(|p| both(&[p])).collect();
        let tri_box: Vec<_> = triangles.iter().map(|t| both(t)).collect();
        let edge_box: Vec<_> = edges.iter().map(|e| both(e)).collect();
        let extent = |b: &Aabb| (0..3).map(|i| b.1[i] - b.0[i]).fold(0.0, f64::max);
        // Cells as large as the typical box (the median edge box), not the
        // largest: one far-moving node must not coarsen the whole grid.
        let mut sizes: Vec<f64> = edge_box.iter().map(extent).collect();
        let h = if sizes.is_empty() {
            1.0
        } else {
            let mid = sizes.len() / 2;
            *sizes.select_nth_unstable_by(mid, f64::total_cmp).1
        };
        Self {
            points,
            triangles: tri_box,
            edges: edge_box,
            // (A median that is not finite: every box is then over more
            // than `MAX_CELLS` cells, and none is entered.)
            h: h.max(f64::MIN_POSITIVE),
        }
    }
}

/// The longest edge at `x`.
fn longest_edge(x: &[[f64; 3]], edges: &[[usize; 2]]) -> f64 {
    edges
        .iter()
        .map(|&[a, b]| {
            let d = sub(x[a], x[b]);
            dot(d, d).sqrt()
        })
        .fold(0.0f64, f64::max)
}

/// A uniform grid of cells of size `h`, hashed: for each cell, the boxes
/// that overlap it; the boxes over more than [`MAX_CELLS`] cells apart.
struct Grid {
    cells: HashMap<[i64; 3], Vec<usize>>,
    /// The boxes not entered in the cells ([`too_large`]).
    large: Vec<usize>,
}

impl Grid {
    fn new(boxes: &[Aabb], h: f64) -> Self {
        let mut map: HashMap<[i64; 3], Vec<usize>> = HashMap::with_capacity(boxes.len());
        let mut large = Vec::new();
        for (k, b) in boxes.iter().enumerate() {
            if too_large(b, h) {
                large.push(k);
                continue;
            }
            for c in cells(b, h) {
                map.entry(c).or_default().push(k);
            }
        }
        Self { cells: map, large }
    }

    /// How many entries the cells hold (the grid's memory).
    #[cfg(test)]
    fn entries(&self) -> usize {
        self.cells.values().map(Vec::len).sum()
    }

    /// The boxes entered in `cell`.
    fn get(&self, cell: [i64; 3]) -> impl Iterator<Item = usize> + '_ {
        self.cells.get(&cell).map_or(&[][..], |v| v).iter().copied()
    }
}

/// The node–triangle pairs (the node not a vertex) and edge–edge pairs
/// (sharing no node) whose boxes overlap, by a grid of cells of size `h`.
fn pairs_of_boxes(
    point_box: &[Aabb],
    tri_box: &[Aabb],
    edge_box: &[Aabb],
    triangles: &[[usize; 3]],
    edges: &[[usize; 2]],
    h: f64,
) -> Candidates {
    let tri_grid = Grid::new(tri_box, h);
    let edge_grid = Grid::new(edge_box, h);
    let mut out = Candidates::default();
    for (p, pb) in point_box.iter().enumerate() {
        let mut test = |k: usize| {
            if !triangles[k].contains(&p) && overlap(pb, &tri_box[k]) {
                out.point_triangle.push((p, k));
            }
        };
        // A large box against every triangle, a small one against those
        // of its cells and the large ones.
        if too_large(pb, h) {
            (0..tri_box.len()).for_each(&mut test);
        } else {
            cells(pb, h).for_each(|cell| tri_grid.get(cell).for_each(&mut test));
            tri_grid.large.iter().copied().for_each(&mut test);
        }
    }
    for (k, b) in edge_box.iter().enumerate() {
        let e = edges[k];
        let mut test = |m: usize| {
            let f = edges[m];
            if m > k && !e.contains(&f[0]) && !e.contains(&f[1]) && overlap(b, &edge_box[m]) {
                out.edge_edge.push((k, m));
            }
        };
        // (A small edge meets a large one of lower index when that one is
        // tested against every edge after it.)
        if too_large(b, h) {
            (k + 1..edge_box.len()).for_each(&mut test);
        } else {
            cells(b, h).for_each(|cell| edge_grid.get(cell).for_each(&mut test));
            edge_grid.large.iter().copied().for_each(&mut test);
        }
    }
    out.point_triangle.sort_unstable();
    out.point_triangle.dedup();
    out.edge_edge.sort_unstable();
    out.edge_edge.dedup();
    out
}

/// The pairs of [`candidates`] closer than `distance`, measured.
pub fn close_pairs(
    x: &[[f64; 3]],
    triangles: &[[usize; 3]],
    edges: &[[usize; 2]],
    distance: f64,
) -> Candidates {
    let c = candidates(x, triangles, edges, distance);
    let d2 = distance * distance;
    Candidates {
        point_triangle: (c.point_triangle.into_iter())
            .filter(|&(p, k)| {
                let [a, b, cc] = triangles[k].map(|v| x[v]);
                point_triangle(x[p], a, b, cc).d2 < d2
            })
            .collect(),
        edge_edge: (c.edge_edge.into_iter())
            .filter(|&(k, m)| {
                let ([a, b], [c0, c1]) = (edges[k], edges[m]);
                edge_edge(x[a], x[b], x[c0], x[c1]).d2 < d2
            })
            .collect(),
    }
}

/// Whether segment `(p, q)` passes through triangle `(a, b, c)`
/// (Möller & Trumbore 1997, the segment's parameter in [0, 1]; touching
/// counts). A segment parallel to the triangle's plane to round-off
/// (`|det| <= 1e-12 |q - p| |b - a| |c - a|`: a flat fabric's edge beside a
/// triangle of the same plane) does not pass through it: there the
/// barycentric coordinates would be round-off divided by round-off.
pub fn segment_crosses_triangle(
    p: [f64; 3],
    q: [f64; 3],
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
) -> bool {
    let dir = sub(q, p);
    let (e1, e2) = (sub(b, a), sub(c, a));
    let pv = crate::vec3::cross(dir, e2);
    let det = dot(e1, pv);
    let length = |v: [f64; 3]| dot(v, v).sqrt();
    if det.abs() <= 1e-300 || det.abs() <= 1e-12 * length(dir) * length(e1) * length(e2) {
        return false;
    }
    let inv = 1.0 / det;
    let tv = sub(p, a);
    let u = dot(tv, pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let qv = crate::vec3::cross(tv, e1);
    let v = dot(dir, qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = dot(e2, qv) * inv;
    (0.0..=1.0).contains(&t)
}

/// The number of (edge, triangle) pairs sharing no node where the edge
/// passes through the triangle at positions `x`: the fabric crossing
/// itself (0 for a fabric that never passes through itself). A grid of
/// cells as large as the longest edge, as [`candidates`].
pub fn crossings(x: &[[f64; 3]], triangles: &[[usize; 3]], edges: &[[usize; 2]]) -> usize {
    crossing_pairs(x, triangles, edges).len()
}

/// The (edge, triangle) index pairs of [`crossings`], sorted: which edge
/// passes through which triangle.
pub fn crossing_pairs(
    x: &[[f64; 3]],
    triangles: &[[usize; 3]],
    edges: &[[usize; 2]],
) -> Vec<(usize, usize)> {
    let longest = edges
        .iter()
        .map(|&[a, b]| dot(sub(x[a], x[b]), sub(x[a], x[b])).sqrt())
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let tri_box: Vec<_> = triangles
        .iter()
        .map(|t| bounds(t.iter().map(|&a| x[a]), 0.0))
        .collect();
    let grid = Grid::new(&tri_box, longest);
    let mut found = Vec::new();
    for (e, &[p, q]) in edges.iter().enumerate() {
        let b = bounds([x[p], x[q]].into_iter(), 0.0);
        for cell in cells(&b, longest) {
            for k in grid.get(cell) {
                let t = triangles[k];
                if !t.contains(&p)
                    && !t.contains(&q)
                    && overlap(&b, &tri_box[k])
                    && segment_crosses_triangle(x[p], x[q], x[t[0]], x[t[1]], x[t[2]])
                {
                    found.push((e, k));
                }
            }
        }
    }
    found.sort_unstable();
    found.dedup();
    found
}

/// Square plies of 10 cm in 8 x 8 squares (`Pattern::Right`), flat at
/// the heights `heights` (m): their nodes and triangles, ply after ply
/// (81 nodes each). The tests' two-ply meshes.
#[cfg(test)]
pub(crate) fn test_plies(heights: &[f64]) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    use crate::mesh::ElementOrder;
    use crate::mesh::generate::{Pattern, rectangle};
    let (mut x, mut triangles) = (Vec::new(), Vec::new());
    for &z in heights {
        let sheet = rectangle(
            [0.1, 0.1],
            [8, 8],
            Pattern::Right,
            [0.0; 3],
            ElementOrder::Linear,
        );
        let base = x.len();
        x.extend(sheet.nodes.iter().map(|&[u, v, _]| [u, v, z]));
        triangles.extend(
            sheet
                .elements()
                .map(|e| [base + e[0], base + e[1], base + e[2]]),
        );
    }
    (x, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift), values in [-1, 1).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
        fn point(&mut self) -> [f64; 3] {
            [self.next(), self.next(), self.next()]
        }
    }

    /// The squared distance to a triangle sampled on a barycentric grid of
    /// `n` divisions: an upper bound within the grid's spacing.
    fn sampled_triangle(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3], n: usize) -> f64 {
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let q = add(add(scale(a, 1.0 - u - v), scale(b, u)), scale(c, v));
                let d = sub(p, q);
                best = best.min(dot(d, d));
            }
        }
        best
    }

    /// Against a fine sampling of the triangle, points in every Voronoi
    /// region (1,000 random configurations): never farther than the
    /// samples, never nearer than the sampling's spacing allows; the
    /// weights reproduce `p - c` and sum to 0.
    #[test]
    fn point_triangle_matches_a_sampling() {
        let mut rng = Rng(0x2545_f491_4f6c_dd1d);
        for _ in 0..1000 {
            let (p, a, b, c) = (
                scale(rng.point(), 2.0),
                rng.point(),
                rng.point(),
                rng.point(),
            );
            let got = point_triangle(p, a, b, c);
            let sampled = sampled_triangle(p, a, b, c, 200);
            assert!(got.d2 <= sampled + 1e-12, "{} > {sampled}", got.d2);
            // The grid's spacing is at most 2/200 of the longest edge.
            let spacing = 0.02 * 3.5;
            assert!(
                sampled.sqrt() - got.d2.sqrt() <= spacing,
                "{} vs {sampled}",
                got.d2
            );
            let w = got.weights;
            assert!((w.iter().sum::<f64>()).abs() < 1e-12);
            assert!(w[1..].iter().all(|&v| v <= 1e-15));
        }
    }

    /// Against a fine sampling of both segments, parallel and touching ones
    /// included.
    #[test]
    fn edge_edge_matches_a_sampling() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut cases: Vec<[[f64; 3]; 4]> = (0..1000)
            .map(|_| [rng.point(), rng.point(), rng.point(), rng.point()])
            .collect();
        // Parallel, collinear-overlapping and crossing segments.
        cases.push([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 0.5, 0.0], [1.0, 0.5, 0.0]]);
        cases.push([[0.0; 3], [1.0, 0.0, 0.0], [0.5, 0.0, 0.0], [2.0, 0.0, 0.0]]);
        cases.push([
            [-1.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, -1.0, 0.2],
            [0.0, 1.0, 0.2],
        ]);
        for [p0, p1, q0, q1] in cases {
            let got = edge_edge(p0, p1, q0, q1);
            let n = 400;
            let mut sampled = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=n {
                    let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                    let d = sub(
                        add(p0, scale(sub(p1, p0), s)),
                        add(q0, scale(sub(q1, q0), t)),
                    );
                    sampled = sampled.min(dot(d, d));
                }
            }
            assert!(got.d2 <= sampled + 1e-12, "{} > {sampled}", got.d2);
            assert!(sampled.sqrt() - got.d2.sqrt() <= 2.0 * 3.5 / n as f64);
        }
        let crossing = edge_edge(
            [-1.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, -1.0, 0.2],
            [0.0, 1.0, 0.2],
        );
        assert!((crossing.d2 - 0.04).abs() < 1e-15);
        assert_eq!(crossing.weights, [0.5, 0.5, -0.5, -0.5]);
    }

    /// The gradient `2 w_i (p - c)` against central differences of the
    /// squared distance, point–triangle and edge–edge, in generic
    /// configurations (unique closest points), steps of 1e-7.
    #[test]
    fn the_gradient_matches_finite_differences() {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        let h = 1e-7;
        for case in 0..400 {
            let x: [[f64; 3]; 4] = [
                scale(rng.point(), 2.0),
                rng.point(),
                rng.point(),
                rng.point(),
            ];
            let f = |x: [[f64; 3]; 4]| {
                if case % 2 == 0 {
                    point_triangle(x[0], x[1], x[2], x[3])
                } else {
                    edge_edge(x[0], x[1], x[2], x[3])
                }
            };
            let g = f(x).gradient(x);
            for i in 0..4 {
                for k in 0..3 {
                    let (mut xp, mut xm) = (x, x);
                    xp[i][k] += h;
                    xm[i][k] -= h;
                    let fd = (f(xp).d2 - f(xm).d2) / (2.0 * h);
                    assert!(
                        (fd - g[i][k]).abs() < 1e-6 * (1.0 + fd.abs()),
                        "case {case}: node {i} axis {k}: {fd} vs {}",
                        g[i][k]
                    );
                }
            }
        }
    }

    /// Two wavy plies (24 x 24 squares each, 2,304 triangles) about 1 cm
    /// apart: the broad phase with the exact test finds exactly the pairs
    /// closer than 1.2 cm that testing every pair finds, and skips the
    /// pairs that share a node.
    #[test]
    fn the_broad_phase_finds_every_close_pair() {
        use crate::mesh::ElementOrder;
        use crate::mesh::generate::{Pattern, rectangle};
        let (mut x, mut triangles) = (Vec::new(), Vec::new());
        for (ply, sign) in [(0.0, 1.0), (0.01, -1.0)] {
            let sheet = rectangle(
                [0.2, 0.2],
                [24, 24],
                Pattern::Alternate,
                [0.0; 3],
                ElementOrder::Linear,
            );
            let base = x.len();
            x.extend(sheet.nodes.iter().map(|&[u, v, _]| {
                [
                    u,
                    v,
                    ply + sign * 0.004 * (30.0 * u).sin() * (20.0 * v).cos(),
                ]
            }));
            triangles.extend(
                sheet
                    .elements()
                    .map(|e| [base + e[0], base + e[1], base + e[2]]),
            );
        }
        let edges = edges_of(&triangles);
        let distance = 0.012;
        let fast = close_pairs(&x, &triangles, &edges, distance);
        let d2 = distance * distance;
        let mut slow = Candidates::default();
        for (p, &xp) in x.iter().enumerate() {
            for (k, t) in triangles.iter().enumerate() {
                if !t.contains(&p) && point_triangle(xp, x[t[0]], x[t[1]], x[t[2]]).d2 < d2 {
                    slow.point_triangle.push((p, k));
                }
            }
        }
        for (k, e) in edges.iter().enumerate() {
            for (m, f) in edges.iter().enumerate().skip(k + 1) {
                if !e.contains(&f[0])
                    && !e.contains(&f[1])
                    && edge_edge(x[e[0]], x[e[1]], x[f[0]], x[f[1]]).d2 < d2
                {
                    slow.edge_edge.push((k, m));
                }
            }
        }
        assert!(
            slow.point_triangle.len() > 100 && slow.edge_edge.len() > 100,
            "{} {}",
            slow.point_triangle.len(),
            slow.edge_edge.len()
        );
        assert_eq!(fast, slow);
    }

    /// Two plies 1 cm apart, the upper moved down through the lower (by
    /// 2 cm, and one of its nodes 30 cm sideways): every pair whose
    /// swept boxes overlap by a brute-force test is a swept candidate, and
    /// every pair that actually meets during the motion (additive CCD on
    /// every pair stops it before the end) is among them.
    #[test]
    fn swept_candidates_hold_every_pair_that_meets() {
        use crate::contact::barrier::{PairKind, additive_ccd};
        let (mut x, triangles) = test_plies(&[0.0, 0.01]);
        for p in &mut x {
            p[0] += 3.0 * p[2];
        }
        let mut dx: Vec<[f64; 3]> = (x.iter())
            .map(|p| [0.0, 0.0, if p[2] > 0.0 { -0.02 } else { 0.0 }])
            .collect();
        let far = x.len() - 5;
        dx[far] = [0.3, 0.0, -0.02];
        let edges = edges_of(&triangles);
        let swept = swept_candidates(&x, &dx, &triangles, &edges, 0.0);
        let sweep =
            |nodes: &[usize]| bounds(nodes.iter().flat_map(|&a| [x[a], add(x[a], dx[a])]), 0.0);
        let mut met = 0;
        for (p, _) in x.iter().enumerate() {
            for (k, t) in triangles.iter().enumerate() {
                if t.contains(&p) {
                    continue;
                }
                if overlap(&sweep(&[p]), &sweep(t)) {
                    assert!(
                        swept.point_triangle.binary_search(&(p, k)).is_ok(),
                        "{p} {k}"
                    );
                }
                let n = [p, t[0], t[1], t[2]];
                if additive_ccd(
                    PairKind::PointTriangle,
                    &n.map(|i| x[i]),
                    &n.map(|i| dx[i]),
                    0.0,
                    0.1,
                    1.0,
                ) < 1.0
                {
                    met += 1;
                    assert!(
                        swept.point_triangle.binary_search(&(p, k)).is_ok(),
                        "{p} {k} meets"
                    );
                }
            }
        }
        for (k, e) in edges.iter().enumerate() {
            for (m, f) in edges.iter().enumerate().skip(k + 1) {
                if e.contains(&f[0]) || e.contains(&f[1]) {
                    continue;
                }
                let n = [e[0], e[1], f[0], f[1]];
                if overlap(&sweep(e), &sweep(f))
                    || additive_ccd(
                        PairKind::EdgeEdge,
                        &n.map(|i| x[i]),
                        &n.map(|i| dx[i]),
                        0.0,
                        0.1,
                        1.0,
                    ) < 1.0
                {
                    assert!(swept.edge_edge.binary_search(&(k, m)).is_ok(), "{k} {m}");
                }
            }
        }
        assert!(met > 50, "{met}");
    }

    /// Issue 46: a Newton direction that moves a few nodes far (here one
    /// node 0.5 m along a diagonal, the cells being about 1.3 cm) entered
    /// each of their swept boxes in some 70,000 cells; one moved a metre
    /// ran the step out of memory. Now the grid holds at most
    /// [`MAX_CELLS`] entries a box whatever the motion, far or not finite,
    /// and the candidates are still exactly the pairs whose swept boxes
    /// overlap (tested pair by pair).
    #[test]
    fn a_far_motion_keeps_the_grid_small_and_the_candidates_exact() {
        let (x, triangles) = test_plies(&[0.0, 0.004]);
        let edges = edges_of(&triangles);
        let mut dx = vec![[0.0, 0.0, -0.002]; x.len()];
        for p in dx.iter_mut().take(x.len() / 2) {
            *p = [0.0; 3];
        }
        // A node of the upper ply near its first corner, one in the
        // middle of the lower.
        let (far, other) = (x.len() / 2 + 10, 40);
        let brute = |dx: &[[f64; 3]]| {
            let sweep =
                |nodes: &[usize]| bounds(nodes.iter().flat_map(|&a| [x[a], add(x[a], dx[a])]), 0.0);
            let mut c = Candidates::default();
            for p in 0..x.len() {
                for (k, t) in triangles.iter().enumerate() {
                    if !t.contains(&p) && overlap(&sweep(&[p]), &sweep(t)) {
                        c.point_triangle.push((p, k));
                    }
                }
            }
            for (k, e) in edges.iter().enumerate() {
                for (m, f) in edges.iter().enumerate().skip(k + 1) {
                    if !e.contains(&f[0]) && !e.contains(&f[1]) && overlap(&sweep(e), &sweep(f)) {
                        c.edge_edge.push((k, m));
                    }
                }
            }
            c
        };
        for (what, moves) in [
            ("0.5 m", [[0.5, 0.5, -0.5], [0.0; 3]]),
            ("two nodes 2 m", [[2.0, -2.0, 2.0], [-2.0, 2.0, -2.0]]),
            ("infinite", [[f64::INFINITY, 0.0, 0.0], [0.0; 3]]),
            ("not a number", [[f64::NAN, 0.0, 0.0], [0.0; 3]]),
        ] {
            let mut dx = dx.clone();
            dx[far] = moves[0];
            dx[other] = moves[1];
            let b = SweptBoxes::new(&x, &dx, &triangles, &edges, 0.0);
            for boxes in [&b.triangles, &b.edges] {
                let entries = Grid::new(boxes, b.h).entries();
                assert!(
                    entries as f64 <= MAX_CELLS * boxes.len() as f64,
                    "{what}: {entries} entries for {} boxes",
                    boxes.len()
                );
            }
            let swept = swept_candidates(&x, &dx, &triangles, &edges, 0.0);
            assert_eq!(swept, brute(&dx), "{what}");
            if what == "0.5 m" {
                // The far node's pairs are among them.
                assert!(swept.point_triangle.iter().filter(|c| c.0 == far).count() > 50);
            }
        }
    }

    /// Two squares of two triangles each, one crossing the other's plane
    /// through its middle: crossings found; lifted clear: none; the
    /// segment test's boundary cases.
    #[test]
    fn crossings_counts_edges_through_triangles() {
        let x = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.5, -0.5],
            [0.5, 0.5, 0.5],
            [0.6, 0.5, 0.5],
            [0.6, 0.5, -0.5],
        ];
        let tris = [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
        let edges = edges_of(&tris);
        assert!(crossings(&x, &tris, &edges) >= 2);
        let lifted: Vec<[f64; 3]> = x
            .iter()
            .enumerate()
            .map(|(i, p)| if i >= 4 { [p[0], p[1], p[2] + 1.0] } else { *p })
            .collect();
        assert_eq!(crossings(&lifted, &tris, &edges), 0);
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(segment_crosses_triangle(
            [0.2, 0.2, -1.0],
            [0.2, 0.2, 1.0],
            t[0],
            t[1],
            t[2]
        ));
        assert!(!segment_crosses_triangle(
            [0.2, 0.2, 0.1],
            [0.2, 0.2, 1.0],
            t[0],
            t[1],
            t[2]
        ));
        assert!(!segment_crosses_triangle(
            [0.8, 0.8, -1.0],
            [0.8, 0.8, 1.0],
            t[0],
            t[1],
            t[2]
        ));
        // A flat fabric: an edge in the triangle's plane, its height
        // round-off apart (as a settled ply's nodes are), never counts;
        // tilted by 1e-6 through the triangle, it does.
        let z = 0.00198038;
        let flat = [
            [0.0, 0.0, z],
            [0.01, 0.0, z * (1.0 + 1e-16)],
            [0.0, 0.01, z],
        ];
        assert!(!segment_crosses_triangle(
            [0.002, 0.002, z * (1.0 - 2e-16)],
            [0.003, -0.004, z * (1.0 + 3e-16)],
            flat[0],
            flat[1],
            flat[2]
        ));
        assert!(segment_crosses_triangle(
            [0.002, 0.002, z - 1e-6],
            [0.003, 0.003, z + 1e-6],
            flat[0],
            flat[1],
            flat[2]
        ));
    }
}
