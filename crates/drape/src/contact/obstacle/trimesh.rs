//! The closed triangle mesh obstacle, read from OBJ or STL.
//!
//! # Geometry
//!
//! The closest point `y'` of the surface to `y` is found with a bounding
//! volume hierarchy over the triangles (an AABB tree, see `bvh.rs`) and the
//! closest point on each candidate triangle by Ericson's region test
//! (*Real-Time Collision Detection*, 2005, §5.1.5), which also tells which
//! *region* of the triangle `y'` lies in: its interior, one of its edges or
//! one of its corners.
//!
//! Inside or outside comes from the angle-weighted pseudo-normal of that
//! region (Bærentzen & Aanæs, *Signed distance computation using the angle
//! weighted pseudonormal*, IEEE TVCG 11(3), 2005): the face normal `n_t`
//! for the interior, `n_t + n_u` (the two triangles sharing the edge) for
//! an edge, `sum_t alpha_t n_t` (`alpha_t` the triangle's angle at the
//! vertex) for a vertex. `y` is outside when `(y - y') . N >= 0`. The test
//! is exact for a closed, consistently oriented manifold mesh, which the
//! constructor enforces.
//!
//! With `s = +1` outside, `-1` inside, and `delta = |y - y'|`:
//!
//! * **face region**: `g = n_t . (y - a_t)` (the plane distance, `a_t` a
//!   corner), `n = n_t`, `dn/dy = 0`. A point straight above (or below) the
//!   triangle's boundary (`y - y'` along `n_t` to `1e-9` relative) counts as
//!   in the face region: there the edge and face formulas give the same gap
//!   and normal, and above an edge between two coplanar triangles only the
//!   face's `dn/dy = 0` is right;
//! * **edge region** (edge direction `e`): `g = s delta`, `n = (y - y') /
//!   g`, `dn/dy = (I - n n^T - e e^T) / g`;
//! * **vertex region**: `g = s delta`, `n = (y - y') / g`, `dn/dy = (I - n
//!   n^T) / g`;
//! * on the surface (`delta <= 1e-12 x` the bounding box's diagonal, outside
//!   a face region): `n` is the normalised pseudo-normal, `dn/dy = 0`.
//!
//! # Features and the hint
//!
//! The feature is the triangle's number (0-based, in file order; an OBJ
//! polygon counts as the triangles of its fan). The rule of the [module
//! documentation](super) carries over:
//!
//! * Several triangles can share the closest point (an edge, a corner).
//!   The candidates are the triangles within the touching tolerance `tau` of
//!   the smallest distance; among them, those whose plane distance `n_t .
//!   (y - a_t)` is within `tau` of the largest; among those, the nearest,
//!   then the lowest number. A point above the top edge of a box mesh thus
//!   reports a triangle of the top face (plane distance `> 0` against the
//!   side's `0`), and between coplanar triangles (equal plane distances) the
//!   one under the point.
//! * Inside or touching (`g <= tau`) with a hint `Some(t)`: `y` is projected
//!   onto the plane of triangle `t`; if the projection falls on the *flat
//!   patch* of `t` (the triangles edge-connected to `t` whose normals are
//!   within `1e-5` rad of their neighbour's: a whole face of a box mesh),
//!   within `tau`, the triangle `t'` of the patch under the projection
//!   decides: `g = n_t' . (y - a_t')`, `n = n_t'`, `dn/dy = 0`, feature
//!   `t'`. Otherwise, or when `y` lies outside `t`'s plane, the hint is
//!   ignored. A node that came in through the top of a box mesh is pushed
//!   back out through the top, and it keeps that face while it slides over
//!   the face's other triangles; on a curved mesh, where every patch is one
//!   triangle, a node follows its triangle until its projection leaves it.
//!
//! # Mesh requirements
//!
//! [`TriMeshObstacle::new`] joins vertices with bit-identical coordinates
//! (STL stores every triangle's corners separately; `-0.0` equals `0.0`),
//! then rejects: no triangles, a vertex number out of range, a non-finite
//! coordinate, a degenerate triangle (`|(b - a) x (c - a)| <= 1e-10
//! l_max^2`, `l_max` its longest edge), an edge of one triangle only (an
//! open mesh), an edge of more than two triangles (not a manifold), two
//! neighbours that run through their shared edge in the same direction
//! (inconsistent orientation), and a mesh that encloses no volume (`|V| <=
//! 1e-12 d^3`, `d` the bounding box's diagonal). A mesh whose enclosed
//! volume `V = sum_t a_t . (b_t x c_t) / 6` is negative (all triangles
//! clockwise seen from outside) is turned inside out, silently: see
//! [`TriMeshObstacle::was_inverted`]. Several closed shells are allowed;
//! after that global turn, a shell oriented inward is a cavity (meant to lie
//! inside another shell).

use std::collections::HashMap;
use std::path::Path;

use super::bvh::Bvh;
use super::{
    Obstacle, ObstacleError, Proximity, SharpPoint, TOUCH_TOLERANCE, ZERO3, diagonal,
    identity_minus, normalised, plane_proximity, sample_segment, show_point,
};
use crate::vec3::{add, cross, dot, norm, scale, sub};

/// Largest angle (rad) between the normals of two neighbouring triangles of
/// one flat patch.
const FLAT_PATCH_ANGLE: f64 = 1e-5;

/// Where on a triangle its closest point lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Region {
    /// The interior.
    Face,
    /// Edge `k`, from corner `k` to corner `(k + 1) % 3`.
    Edge(usize),
    /// Corner `k`.
    Vertex(usize),
}

/// Closest point of the triangle `(a, b, c)` to `p` and the region it lies
/// in (Ericson 2005, §5.1.5: Voronoi regions tested by dot products).
fn closest_on_triangle(p: [f64; 3], [a, b, c]: [[f64; 3]; 3]) -> ([f64; 3], Region) {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Region::Vertex(0));
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Region::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (add(a, scale(ab, v)), Region::Edge(0));
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Region::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (add(a, scale(ac, w)), Region::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (add(b, scale(sub(c, b), w)), Region::Edge(1));
    }
    let denominator = 1.0 / (va + vb + vc);
    let v = vb * denominator;
    let w = vc * denominator;
    (add(a, add(scale(ab, v), scale(ac, w))), Region::Face)
}

/// The closest triangle found by a query.
#[derive(Debug, Clone, Copy)]
struct Hit {
    triangle: usize,
    closest: [f64; 3],
    region: Region,
    distance: f64,
}

/// A closed triangle mesh (scenario `shape = "mesh"`, key `path`).
#[derive(Debug, Clone)]
pub struct TriMeshObstacle {
    name: String,
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[usize; 3]>,
    /// Outward unit normal `n_t` of each triangle.
    face_normals: Vec<[f64; 3]>,
    /// Pseudo-normal `n_t + n_u` of edge `k` of triangle `t`.
    edge_normals: Vec<[[f64; 3]; 3]>,
    /// Angle-weighted pseudo-normal of each vertex.
    vertex_normals: Vec<[f64; 3]>,
    /// Flat patch of each triangle.
    patches: Vec<u32>,
    bvh: Bvh,
    lo: [f64; 3],
    hi: [f64; 3],
    /// Touching tolerance `tau` (m).
    tolerance: f64,
    /// Below this distance (m) a point is on the surface.
    on_surface: f64,
    inverted: bool,
}

/// Neighbour `u` across edge `k` of every triangle `t`: `neighbours[t][k]`.
/// Checks that the mesh is closed, manifold and consistently oriented.
fn neighbours(
    name: &str,
    vertices: &[[f64; 3]],
    triangles: &[[usize; 3]],
) -> Result<Vec<[usize; 3]>, ObstacleError> {
    let mut edges: HashMap<(usize, usize), Vec<(usize, bool)>> = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            edges
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push((t, a < b));
        }
    }
    let mut result = vec![[0; 3]; triangles.len()];
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let users = &edges[&(a.min(b), a.max(b))];
            let (pa, pb) = (vertices[a], vertices[b]);
            match users.as_slice() {
                [_] => {
                    return Err(ObstacleError::OpenMesh {
                        mesh: name.to_owned(),
                        triangle: t + 1,
                        a: pa,
                        b: pb,
                    });
                }
                [(t1, f1), (t2, f2)] => {
                    if f1 == f2 {
                        return Err(ObstacleError::InconsistentOrientation {
                            mesh: name.to_owned(),
                            first: t1.min(t2) + 1,
                            second: t1.max(t2) + 1,
                            a: pa,
                            b: pb,
                        });
                    }
                    result[t][k] = if *t1 == t { *t2 } else { *t1 };
                }
                _ => {
                    return Err(ObstacleError::NonManifoldEdge {
                        mesh: name.to_owned(),
                        triangle: t + 1,
                        a: pa,
                        b: pb,
                        count: users.len(),
                    });
                }
            }
        }
    }
    Ok(result)
}

/// Joins the vertices with bit-identical coordinates (`-0.0` as `0.0`):
/// the vertices used by `triangles`, in order of first use, and the
/// triangles renumbered onto them.
fn weld(vertices: &[[f64; 3]], mut triangles: Vec<[usize; 3]>) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let mut index: HashMap<[u64; 3], usize> = HashMap::new();
    let mut welded: Vec<[f64; 3]> = Vec::new();
    for tri in &mut triangles {
        for v in tri.iter_mut() {
            let x = vertices[*v].map(|c| c + 0.0);
            *v = *index.entry(x.map(f64::to_bits)).or_insert_with(|| {
                welded.push(x);
                welded.len() - 1
            });
        }
    }
    (welded, triangles)
}

/// Axis-aligned bounding box `(min, max)` of points.
fn bounds(points: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for x in points {
        for k in 0..3 {
            lo[k] = lo[k].min(x[k]);
            hi[k] = hi[k].max(x[k]);
        }
    }
    (lo, hi)
}

/// Angle-weighted pseudo-normal of every vertex, `sum_t alpha_t n_t` over
/// the triangles `t` at the vertex, `alpha_t` their angle there (not
/// normalised: only its direction is used).
fn vertex_pseudo_normals(
    vertices: &[[f64; 3]],
    triangles: &[[usize; 3]],
    face_normals: &[[f64; 3]],
) -> Vec<[f64; 3]> {
    let mut normals = vec![[0.0; 3]; vertices.len()];
    for (tri, &n) in triangles.iter().zip(face_normals) {
        for k in 0..3 {
            let p = vertices[tri[k]];
            let e1 = sub(vertices[tri[(k + 1) % 3]], p);
            let e2 = sub(vertices[tri[(k + 2) % 3]], p);
            let angle = norm(cross(e1, e2)).atan2(dot(e1, e2));
            let v = &mut normals[tri[k]];
            *v = add(*v, scale(n, angle));
        }
    }
    normals
}

/// Flat patch of every triangle: the number of the lowest triangle of its
/// class under "neighbours whose normals differ by at most
/// `FLAT_PATCH_ANGLE`".
fn flat_patches(face_normals: &[[f64; 3]], adjacent: &[[usize; 3]]) -> Vec<u32> {
    let mut parent: Vec<usize> = (0..face_normals.len()).collect();
    let flat = FLAT_PATCH_ANGLE.cos();
    for (t, across) in adjacent.iter().enumerate() {
        for &u in across {
            if dot(face_normals[t], face_normals[u]) >= flat {
                let (rt, ru) = (find(&mut parent, t), find(&mut parent, u));
                parent[rt.max(ru)] = rt.min(ru);
            }
        }
    }
    (0..face_normals.len())
        .map(|t| find(&mut parent, t) as u32)
        .collect()
}

/// Root of `i` in a union-find forest, with path halving.
fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

impl TriMeshObstacle {
    /// The obstacle bounded by the closed triangle mesh `triangles` (corner
    /// numbers into `vertices`, 0-based, counter-clockwise seen from
    /// outside, or all clockwise) over `vertices` (m). `name` (the file)
    /// appears in messages and errors; error messages number triangles and
    /// vertices from 1.
    ///
    /// Errors: see the [module documentation](self), "Mesh requirements".
    pub fn new(
        name: impl Into<String>,
        vertices: Vec<[f64; 3]>,
        triangles: Vec<[usize; 3]>,
    ) -> Result<Self, ObstacleError> {
        let name = name.into();
        if triangles.is_empty() {
            return Err(ObstacleError::EmptyMesh { mesh: name });
        }
        if u32::try_from(triangles.len()).is_err() {
            return Err(ObstacleError::TooManyTriangles {
                mesh: name,
                count: triangles.len(),
            });
        }
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| v >= vertices.len()) {
                return Err(ObstacleError::VertexOutOfRange {
                    mesh: name,
                    triangle: t + 1,
                    vertex: v.saturating_add(1),
                    vertices: vertices.len(),
                });
            }
        }
        if let Some(v) = vertices.iter().position(|x| !super::is_finite(*x)) {
            return Err(ObstacleError::NonFiniteVertex {
                mesh: name,
                vertex: v + 1,
            });
        }

        let (vertices, mut triangles) = weld(&vertices, triangles);
        for (t, tri) in triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|v| vertices[v]);
            let longest = [sub(b, a), sub(c, b), sub(a, c)]
                .iter()
                .fold(0.0f64, |m, e| m.max(dot(*e, *e)));
            if norm(cross(sub(b, a), sub(c, a))) <= 1e-10 * longest {
                return Err(ObstacleError::DegenerateTriangle {
                    mesh: name,
                    triangle: t + 1,
                    a,
                    b,
                    c,
                });
            }
        }

        let mut adjacent = neighbours(&name, &vertices, &triangles)?;
        let (lo, hi) = bounds(&vertices);
        let size = diagonal(lo, hi);
        // Corners relative to the box centre, so that the volume's terms do
        // not cancel catastrophically far from the origin.
        let centre = scale(add(lo, hi), 0.5);
        let volume: f64 = triangles
            .iter()
            .map(|tri| {
                let [a, b, c] = tri.map(|v| sub(vertices[v], centre));
                dot(a, cross(b, c)) / 6.0
            })
            .sum();
        if volume.abs() <= 1e-12 * size.powi(3) {
            return Err(ObstacleError::ZeroVolume { mesh: name });
        }
        let inverted = volume < 0.0;
        if inverted {
            for tri in &mut triangles {
                tri.swap(1, 2);
            }
            adjacent = neighbours(&name, &vertices, &triangles)?;
        }

        let face_normals: Vec<[f64; 3]> = triangles
            .iter()
            .map(|tri| {
                let [a, b, c] = tri.map(|v| vertices[v]);
                let n = cross(sub(b, a), sub(c, a));
                scale(n, 1.0 / norm(n))
            })
            .collect();
        let edge_normals = adjacent
            .iter()
            .enumerate()
            .map(|(t, across)| across.map(|u| add(face_normals[t], face_normals[u])))
            .collect();
        let vertex_normals = vertex_pseudo_normals(&vertices, &triangles, &face_normals);
        let patches = flat_patches(&face_normals, &adjacent);
        let boxes: Vec<_> = triangles
            .iter()
            .map(|tri| bounds(&tri.map(|v| vertices[v])))
            .collect();
        Ok(Self {
            name,
            bvh: Bvh::new(&boxes),
            vertices,
            triangles,
            face_normals,
            edge_normals,
            vertex_normals,
            patches,
            lo,
            hi,
            tolerance: TOUCH_TOLERANCE * size,
            on_surface: 1e-12 * size,
            inverted,
        })
    }

    /// The name given to [`new`](Self::new) (the file).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The vertices (m) after joining equal ones.
    pub fn vertices(&self) -> &[[f64; 3]] {
        &self.vertices
    }

    /// The triangles (corner numbers into [`vertices`](Self::vertices)),
    /// counter-clockwise seen from outside, in the order given; triangle `t`
    /// is feature `t`.
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// Outward unit normal of triangle `t`, if it exists.
    pub fn triangle_normal(&self, t: usize) -> Option<[f64; 3]> {
        self.face_normals.get(t).copied()
    }

    /// Whether the mesh was given inside out (negative enclosed volume) and
    /// every triangle was reversed.
    pub fn was_inverted(&self) -> bool {
        self.inverted
    }

    /// Corners of triangle `t`.
    fn corners(&self, t: usize) -> [[f64; 3]; 3] {
        self.triangles[t].map(|v| self.vertices[v])
    }

    /// Plane distance `n_t . (y - a_t)` of triangle `t`.
    fn plane_distance(&self, t: usize, y: [f64; 3]) -> f64 {
        dot(
            sub(y, self.vertices[self.triangles[t][0]]),
            self.face_normals[t],
        )
    }

    /// The closest triangle to `y`, in three passes over the tree: the
    /// smallest distance `m`; the largest plane distance `P` among the
    /// candidates (the triangles within `tau` of `m`); among the candidates
    /// whose plane distance is within `tau` of `P`, the smallest distance,
    /// then the lowest number. The second pass picks the top face at a box's
    /// edge; the third, between coplanar triangles (whose plane distances
    /// differ by round-off only), the one under `y`. `None` only when the
    /// query fails (a non-finite `y`).
    fn nearest(&self, y: [f64; 3]) -> Option<Hit> {
        let tau = self.tolerance;
        let distance = |t: usize| {
            let (closest, region) = closest_on_triangle(y, self.corners(t));
            (norm(sub(y, closest)), closest, region)
        };
        let mut min = f64::INFINITY;
        self.bvh.visit_nearest(y, f64::INFINITY, 0.0, |t| {
            min = min.min(distance(t as usize).0);
            min
        });
        if !min.is_finite() {
            return None;
        }
        let mut top_plane = f64::NEG_INFINITY;
        self.bvh.visit_nearest(y, min, tau, |t| {
            let t = t as usize;
            if distance(t).0 <= min + tau {
                top_plane = top_plane.max(self.plane_distance(t, y));
            }
            min
        });
        let mut best: Option<Hit> = None;
        self.bvh.visit_nearest(y, min, tau, |t| {
            let t = t as usize;
            let (d, closest, region) = distance(t);
            if d <= min + tau
                && self.plane_distance(t, y) >= top_plane - tau
                && best.is_none_or(|b| d < b.distance || (d == b.distance && t < b.triangle))
            {
                best = Some(Hit {
                    triangle: t,
                    closest,
                    region,
                    distance: d,
                });
            }
            min
        });
        best
    }

    /// The signed answer for a closest triangle.
    fn signed(&self, y: [f64; 3], hit: &Hit) -> Proximity {
        let t = hit.triangle;
        let feature = t as u32;
        let n_t = self.face_normals[t];
        let diff = sub(y, hit.closest);
        // Straight above (or below) the triangle's boundary, `y - y'` is
        // along `n_t`: the face region's answer, which is also the only
        // right one above an edge between two coplanar triangles.
        let lateral = norm(sub(diff, scale(n_t, dot(diff, n_t))));
        if hit.region == Region::Face || lateral <= 1e-9 * hit.distance {
            return plane_proximity(y, self.plane_distance(t, y), n_t, feature);
        }
        let (pseudo, edge) = match hit.region {
            Region::Edge(k) => {
                let [a, b] = [k, (k + 1) % 3].map(|i| self.vertices[self.triangles[t][i]]);
                let e = sub(b, a);
                (self.edge_normals[t][k], Some(scale(e, 1.0 / norm(e))))
            }
            Region::Vertex(k) => (self.vertex_normals[self.triangles[t][k]], None),
            Region::Face => (n_t, None),
        };
        if hit.distance > self.on_surface {
            let sign = if dot(diff, pseudo) < 0.0 { -1.0 } else { 1.0 };
            let gap = sign * hit.distance;
            let n = scale(diff, 1.0 / gap);
            let normal_derivative = match edge {
                Some(e) => identity_minus(&[(n, 1.0), (e, 1.0)], 1.0 / gap),
                None => identity_minus(&[(n, 1.0)], 1.0 / gap),
            };
            Proximity {
                gap,
                closest: hit.closest,
                normal: n,
                normal_derivative,
                feature,
            }
        } else {
            let length = norm(pseudo);
            let n = if length > 0.0 {
                scale(pseudo, 1.0 / length)
            } else {
                self.face_normals[t]
            };
            Proximity {
                gap: dot(diff, n),
                closest: hit.closest,
                normal: n,
                normal_derivative: ZERO3,
                feature,
            }
        }
    }

    /// The answer of the hinted triangle `t`'s flat patch, if `y` lies on
    /// the inner side of `t`'s plane (within `tau`) and its projection onto
    /// that plane falls on the patch (within `tau`).
    fn follow(&self, y: [f64; 3], t: usize) -> Option<Proximity> {
        let n = self.face_normals[t];
        let d = self.plane_distance(t, y);
        if d > self.tolerance {
            return None;
        }
        let projection = sub(y, scale(n, d));
        let gap_to = |u: usize| {
            let (c, _) = closest_on_triangle(projection, self.corners(u));
            norm(sub(projection, c))
        };
        let on = if gap_to(t) <= self.tolerance {
            t
        } else {
            let patch = self.patches[t];
            let mut found: Option<usize> = None;
            self.bvh
                .visit_nearest(projection, self.tolerance, 0.0, |u| {
                    let u = u as usize;
                    if self.patches[u] == patch
                        && found.is_none_or(|f| u < f)
                        && gap_to(u) <= self.tolerance
                    {
                        found = Some(u);
                    }
                    self.tolerance
                });
            found?
        };
        Some(plane_proximity(
            y,
            self.plane_distance(on, y),
            self.face_normals[on],
            on as u32,
        ))
    }
}

impl Obstacle for TriMeshObstacle {
    /// See the [module documentation](self): signed distance by
    /// pseudo-normals, the hinted flat patch for a point inside.
    fn proximity(&self, y: [f64; 3], hint: Option<u32>) -> Proximity {
        if !super::is_finite(y) {
            return super::undefined();
        }
        let Some(hit) = self.nearest(y) else {
            return super::undefined();
        };
        let answer = self.signed(y, &hit);
        if let Some(t) = hint.map(|t| t as usize)
            && t < self.triangles.len()
            && answer.gap <= self.tolerance
            && let Some(followed) = self.follow(y, t)
        {
            return followed;
        }
        answer
    }

    fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        (self.lo, self.hi)
    }

    fn describe(&self) -> String {
        format!(
            "mesh {} ({} triangles, {}..{})",
            self.name,
            self.triangles.len(),
            show_point(self.lo),
            show_point(self.hi)
        )
    }

    /// The convex edges whose two faces turn by more than
    /// [`SHARP_TURN_DEGREES`] (points inside them, outward the mean of the
    /// two faces' normals) and the vertices at their ends (outward the
    /// normalised sum of the distinct normals of the faces around them: a
    /// box mesh's corners and edges are then a box's). An edge between
    /// faces `t` and `u` running `a -> b` in `t` is convex where `(n_t x
    /// n_u) . (b - a) > 0`. Flatter edges — a finely tessellated curve —
    /// are left to node-to-surface contact.
    fn sharp_points(&self, spacing: f64) -> Vec<SharpPoint> {
        let sharp_cos = SHARP_TURN_DEGREES.to_radians().cos();
        let mut out = Vec::new();
        let mut corner = vec![false; self.vertices.len()];
        for (t, tri) in self.triangles.iter().enumerate() {
            let n_t = self.face_normals[t];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                // Each edge once: its other face runs it b -> a.
                if a > b {
                    continue;
                }
                let n_u = sub(self.edge_normals[t][k], n_t);
                let along = sub(self.vertices[b], self.vertices[a]);
                if dot(cross(n_t, n_u), along) > 0.0 && dot(n_t, n_u) < sharp_cos {
                    let outward = normalised(add(n_t, n_u));
                    sample_segment(
                        self.vertices[a],
                        self.vertices[b],
                        outward,
                        spacing,
                        &mut out,
                    );
                    corner[a] = true;
                    corner[b] = true;
                }
            }
        }
        // The distinct face normals round each corner.
        let mut normals: Vec<Vec<[f64; 3]>> = vec![Vec::new(); self.vertices.len()];
        for (t, tri) in self.triangles.iter().enumerate() {
            for &v in tri.iter().filter(|&&v| corner[v]) {
                let n = self.face_normals[t];
                if !normals[v].iter().any(|m| dot(*m, n) > 1.0 - 1e-12) {
                    normals[v].push(n);
                }
            }
        }
        for (v, around) in normals.iter().enumerate() {
            let sum = around.iter().fold([0.0; 3], |s, n| add(s, *n));
            if corner[v] && norm(sum) > 1e-9 {
                out.push(SharpPoint {
                    position: self.vertices[v],
                    outward: normalised(sum),
                });
            }
        }
        out
    }
}

/// How far (degrees) a mesh obstacle's two faces must turn across a convex
/// edge for the edge to be sharp ([`Obstacle::sharp_points`]): a fabric's
/// chord across an edge turning by `theta` sags inside it by about `h
/// theta / 4` (`h` the element size), 0.04 `h` at 10 degrees.
pub const SHARP_TURN_DEGREES: f64 = 10.0;

/// Reads a closed triangle mesh obstacle from a Wavefront OBJ (`.obj`,
/// through [`crate::mesh::obj::read_obj`]) or STL (`.stl`, ASCII or binary,
/// through [`super::stl::read_stl`]) file; the extension decides, in any
/// case. Coordinates are in metres, like the scenario's.
///
/// Errors: an unreadable or malformed file ([`ObstacleError::MeshFile`],
/// naming the file and the line or byte), another extension, and every
/// error of [`TriMeshObstacle::new`] (named after the file).
pub fn read_mesh_obstacle(path: &Path) -> Result<TriMeshObstacle, ObstacleError> {
    read_mesh_obstacle_with_bytes(path).map(|(obstacle, _)| obstacle)
}

/// [`read_mesh_obstacle`], with the file's bytes as read (a run records
/// their hash, for a resume to tell a changed file).
pub fn read_mesh_obstacle_with_bytes(
    path: &Path,
) -> Result<(TriMeshObstacle, Vec<u8>), ObstacleError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let parse = match extension.as_deref() {
        // The fabric's node cap (`MAX_MESH_NODES`) is not an obstacle's:
        // an STL has none either.
        Some("obj") => {
            |bytes: &[u8], file: &str| crate::mesh::obj::parse_obj_at_most(bytes, file, usize::MAX)
        }
        Some("stl") => super::stl::parse_stl,
        _ => {
            let file = path.display().to_string();
            return Err(ObstacleError::UnsupportedFormat { file });
        }
    };
    let (bytes, file) = crate::mesh::MeshReadError::read(path)?;
    let mesh = parse(&bytes, &file)?;
    let triangles = mesh
        .elements()
        .filter_map(|e| <[usize; 3]>::try_from(e.get(..3)?).ok())
        .collect();
    Ok((TriMeshObstacle::new(file, mesh.nodes, triangles)?, bytes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::obstacle::testing::check_derivatives;
    use crate::contact::obstacle::{BoxObstacle, SphereObstacle};

    type Soup = (Vec<[f64; 3]>, Vec<[usize; 3]>);

    fn rng(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// An icosahedron subdivided `levels` times, projected onto the sphere
    /// (the mesh generator's sphere, as a soup).
    fn icosphere(levels: usize, centre: [f64; 3], radius: f64) -> Soup {
        let mesh = crate::mesh::generate::sphere(
            radius,
            levels,
            centre,
            crate::mesh::ElementOrder::Linear,
        );
        let t = mesh.elements().map(|e| [e[0], e[1], e[2]]).collect();
        (mesh.nodes, t)
    }

    /// The prism over a polygon (counter-clockwise seen from +z, star-shaped
    /// about its first corner) between `z0 < z1`.
    fn prism(polygon: &[[f64; 2]], z0: f64, z1: f64) -> Soup {
        let n = polygon.len();
        let mut v: Vec<[f64; 3]> = polygon.iter().map(|p| [p[0], p[1], z0]).collect();
        v.extend(polygon.iter().map(|p| [p[0], p[1], z1]));
        let mut t = Vec::new();
        for i in 0..n {
            let j = (i + 1) % n;
            t.push([i, j, n + j]);
            t.push([i, n + j, n + i]);
        }
        for k in 1..n - 1 {
            t.push([n, n + k, n + k + 1]);
            t.push([0, k + 1, k]);
        }
        (v, t)
    }

    /// The box `[lo, hi]` as 12 triangles, the top face first.
    fn box_mesh(lo: [f64; 3], hi: [f64; 3]) -> Soup {
        let (v, t) = prism(
            &[
                [lo[0], lo[1]],
                [hi[0], lo[1]],
                [hi[0], hi[1]],
                [lo[0], hi[1]],
            ],
            lo[2],
            hi[2],
        );
        // Put the two top triangles (cap triangles with corners >= 4) first.
        let (mut top, rest): (Vec<_>, Vec<_>) =
            t.into_iter().partition(|tri| tri.iter().all(|&i| i >= 4));
        top.extend(rest);
        (v, top)
    }

    /// A regular `sides`-gon prism: a faceted cylinder, top face at z = 0.
    fn faceted_cylinder(sides: usize, radius: f64, height: f64) -> Soup {
        let polygon: Vec<[f64; 2]> = (0..sides)
            .map(|i| {
                let a = 2.0 * std::f64::consts::PI * i as f64 / sides as f64;
                [radius * a.cos(), radius * a.sin()]
            })
            .collect();
        prism(&polygon, -height, 0.0)
    }

    /// Generalised winding number of the mesh about `p` (Van Oosterom &
    /// Strackee's solid angle of each triangle over 4 pi): 1 inside, 0
    /// outside a closed, outward-oriented mesh.
    fn winding_number(m: &TriMeshObstacle, p: [f64; 3]) -> f64 {
        let mut total = 0.0;
        for tri in m.triangles() {
            let [a, b, c] = tri.map(|i| sub(m.vertices()[i], p));
            let (la, lb, lc) = (norm(a), norm(b), norm(c));
            let numerator = dot(a, cross(b, c));
            let denominator = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
            total += 2.0 * numerator.atan2(denominator);
        }
        total / (4.0 * std::f64::consts::PI)
    }

    fn obstacle((v, t): Soup) -> TriMeshObstacle {
        TriMeshObstacle::new("test mesh", v, t).unwrap()
    }

    const PEDESTAL_LO: [f64; 3] = [-0.05, -0.05, -0.25];
    const PEDESTAL_HI: [f64; 3] = [0.05, 0.05, -0.05];
    const TOP_Z: f64 = -0.05;

    #[test]
    fn closest_point_on_a_triangle_regions() {
        let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let cases = [
            ([0.2, 0.2, 1.0], [0.2, 0.2, 0.0], Region::Face),
            ([-1.0, -1.0, 0.5], [0.0, 0.0, 0.0], Region::Vertex(0)),
            ([2.0, -0.5, 0.0], [1.0, 0.0, 0.0], Region::Vertex(1)),
            ([-0.1, 3.0, 0.0], [0.0, 1.0, 0.0], Region::Vertex(2)),
            ([0.5, -1.0, 0.3], [0.5, 0.0, 0.0], Region::Edge(0)),
            ([1.0, 1.0, 0.0], [0.5, 0.5, 0.0], Region::Edge(1)),
            ([-2.0, 0.25, -0.4], [0.0, 0.25, 0.0], Region::Edge(2)),
        ];
        for (p, c, r) in cases {
            let (closest, region) = closest_on_triangle(p, tri);
            assert!(norm(sub(closest, c)) < 1e-15, "{p:?}");
            assert_eq!(region, r, "{p:?}");
        }
    }

    #[test]
    fn icosphere_is_outward_and_close_to_the_sphere() {
        let (r, centre) = (0.1, [0.02, -0.01, 0.03]);
        let mesh = obstacle(icosphere(3, centre, r));
        assert!(!mesh.was_inverted());
        let sphere = SphereObstacle::new(centre, r).unwrap();
        // The largest gap between the sphere and the inscribed mesh: the
        // sagitta at a face centre, R (1 - cos phi) with phi the angle from a
        // face's centre to its corners (edges span about 8 degrees after 3
        // levels, phi about 0.08 rad): 3.2e-3 R; the bound has a margin for
        // the larger triangles.
        let bound = 6e-3 * r;
        let mut rand = rng(11);
        for _ in 0..3000 {
            let d = [rand() - 0.5, rand() - 0.5, rand() - 0.5];
            let d = scale(d, 1.0 / norm(d));
            let y = add(centre, scale(d, r * (0.3 + 1.4 * rand())));
            let p = mesh.proximity(y, None);
            let s = sphere.proximity(y, None);
            assert!(
                (p.gap - s.gap).abs() <= bound,
                "{y:?}: {} vs {}",
                p.gap,
                s.gap
            );
            if p.gap > 0.05 * r {
                assert!(dot(p.normal, s.normal) > 0.99);
            }
            // |g| is the smallest distance to any triangle (brute force), up
            // to the tolerance within which ties are broken.
            let exact = (0..mesh.triangles().len())
                .map(|t| norm(sub(y, closest_on_triangle(y, mesh.corners(t)).0)))
                .fold(f64::INFINITY, f64::min);
            assert!((p.gap.abs() - exact).abs() <= mesh.tolerance);
        }
    }

    #[test]
    fn sign_by_pseudo_normals_on_a_convex_mesh() {
        let mesh = obstacle(icosphere(2, [0.0; 3], 1.0));
        // Convex: inside exactly when every plane distance is negative.
        let convex_gap = |y: [f64; 3]| {
            (0..mesh.triangles().len())
                .map(|t| mesh.plane_distance(t, y))
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let mut rand = rng(5);
        let mut points = Vec::new();
        for _ in 0..2000 {
            let d = [rand() - 0.5, rand() - 0.5, rand() - 0.5];
            points.push(scale(d, (0.9 + 0.2 * rand()) / norm(d)));
        }
        // Just off every vertex and edge midpoint, inside and outside.
        for &v in mesh.vertices() {
            for s in [1.0 - 1e-6, 1.0 + 1e-6, 0.99, 1.01] {
                points.push(scale(v, s));
            }
        }
        for tri in mesh.triangles() {
            let m = scale(add(mesh.vertices()[tri[0]], mesh.vertices()[tri[1]]), 0.5);
            for s in [1.0 - 1e-6, 1.0 + 1e-6, 0.995, 1.005] {
                points.push(scale(m, s));
            }
        }
        for y in points {
            let g = mesh.proximity(y, None).gap;
            let reference = convex_gap(y);
            assert_eq!(g < 0.0, reference < 0.0, "{y:?}: {g} vs {reference}");
        }
    }

    #[test]
    fn sign_by_pseudo_normals_on_a_non_convex_mesh() {
        // An L-shaped prism, its polygon starting at the reflex corner.
        let l = [
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
        ];
        let mesh = obstacle(prism(&l, 0.0, 1.0));
        assert!(!mesh.was_inverted());
        let mut rand = rng(17);
        let mut points = Vec::new();
        for _ in 0..3000 {
            points.push([2.4 * rand() - 0.2, 2.4 * rand() - 0.2, 1.4 * rand() - 0.2]);
        }
        // Near the reflex edge (x = y = 1), and near every vertex.
        for _ in 0..500 {
            let o = [rand() - 0.5, rand() - 0.5, rand() - 0.5];
            points.push(add([1.0, 1.0, rand()], scale(o, 1e-3)));
        }
        for &v in mesh.vertices() {
            for _ in 0..100 {
                let o = [rand() - 0.5, rand() - 0.5, rand() - 0.5];
                points.push(add(v, scale(o, 1e-3)));
            }
        }
        for y in points {
            let g = mesh.proximity(y, None).gap;
            if g.abs() < 1e-9 {
                continue;
            }
            let w = winding_number(&mesh, y);
            assert!((w - 1.0).abs() < 1e-6 || w.abs() < 1e-6, "{y:?}: w = {w}");
            assert_eq!(g < 0.0, w > 0.5, "{y:?}: g = {g}, w = {w}");
        }
    }

    /// A box mesh's sharp points are the box's (corners and edge points,
    /// with their outward directions), whatever the order; a finely
    /// tessellated sphere has none.
    #[test]
    fn box_mesh_has_the_boxs_sharp_points() {
        let spacing = 0.013;
        let mesh = obstacle(box_mesh(PEDESTAL_LO, PEDESTAL_HI)).sharp_points(spacing);
        let sharp = BoxObstacle::new(PEDESTAL_LO, PEDESTAL_HI)
            .unwrap()
            .sharp_points(spacing);
        assert_eq!(mesh.len(), sharp.len());
        let close = |a: [f64; 3], b: [f64; 3]| norm(sub(a, b)) < 1e-12;
        for p in &mesh {
            assert!(
                sharp
                    .iter()
                    .any(|q| close(p.position, q.position) && close(p.outward, q.outward)),
                "{p:?}"
            );
        }
        // Level 3: 1,280 faces, turning by about 5 degrees.
        let round = obstacle(icosphere(3, [0.0; 3], 0.1));
        assert!(round.sharp_points(spacing).is_empty());
    }

    #[test]
    fn box_mesh_matches_the_box() {
        let mesh = obstacle(box_mesh(PEDESTAL_LO, PEDESTAL_HI));
        let cuboid = BoxObstacle::new(PEDESTAL_LO, PEDESTAL_HI).unwrap();
        let mut rand = rng(23);
        for _ in 0..5000 {
            let y = [0.2 * rand() - 0.1, 0.2 * rand() - 0.1, 0.3 * rand() - 0.3];
            let p = mesh.proximity(y, None);
            let q = cuboid.proximity(y, None);
            assert!((p.gap - q.gap).abs() < 1e-15, "{y:?}: {p:?} vs {q:?}");
            assert!(
                norm(sub(p.normal, q.normal)) < 1e-12,
                "{y:?}: {p:?} vs {q:?}"
            );
            assert!(norm(sub(p.closest, q.closest)) < 1e-15);
            // The same face decides (the box's argmax face).
            let face = mesh.triangle_normal(p.feature as usize).unwrap();
            assert_eq!(face, BoxObstacle::FACE_NORMALS[q.feature as usize], "{y:?}");
        }
    }

    #[test]
    fn edge_and_corner_trap_on_a_box_mesh() {
        let mesh = obstacle(box_mesh(PEDESTAL_LO, PEDESTAL_HI));
        // Triangles 0 and 1 are the top face.
        for x in [[0.05, 0.0], [0.05, 0.05], [-0.05, 0.02]] {
            let above = mesh.proximity([x[0], x[1], TOP_Z + 1e-3], None);
            assert_eq!(
                mesh.triangle_normal(above.feature as usize),
                Some([0.0, 0.0, 1.0])
            );
            assert!((above.gap - 1e-3).abs() < 1e-15);
            assert_eq!(above.normal, [0.0, 0.0, 1.0]);
            let y = [x[0], x[1], TOP_Z - 1e-4];
            let lost = mesh.proximity(y, None);
            assert!(lost.gap.abs() < 1e-15, "{lost:?}");
            assert_ne!(lost.normal, [0.0, 0.0, 1.0]);
            // Held by the top, with either top triangle as the hint.
            for hint in [above.feature, 0, 1] {
                let held = mesh.proximity(y, Some(hint));
                assert!((held.gap + 1e-4).abs() < 1e-15, "{held:?}");
                assert_eq!(held.normal, [0.0, 0.0, 1.0]);
                assert!(held.feature < 2);
            }
        }
        // Sliding over the top face, across its diagonal, near the edge.
        for s in [-0.04, -0.01, 0.0, 0.01, 0.04] {
            let held = mesh.proximity([0.05, s, TOP_Z - 1e-4], Some(0));
            assert!((held.gap + 1e-4).abs() < 1e-15);
        }
        // Beyond the touching band, outside the side: free.
        let off = mesh.proximity([0.05 + 1e-6, 0.0, TOP_Z - 1e-4], Some(0));
        assert!((off.gap - 1e-6).abs() < 1e-15);
        // An invalid hint is ignored.
        let p = mesh.proximity([0.0, 0.0, TOP_Z - 1e-3], Some(1000));
        assert!((p.gap + 1e-3).abs() < 1e-15);
    }

    #[test]
    fn rim_trap_on_a_faceted_cylinder() {
        let mesh = obstacle(faceted_cylinder(32, 0.1, 0.05));
        let above = mesh.proximity([0.1, 0.0, 1e-3], None);
        assert_eq!(
            mesh.triangle_normal(above.feature as usize),
            Some([0.0, 0.0, 1.0])
        );
        let y = [0.1, 0.0, -1e-4];
        assert!(mesh.proximity(y, None).gap.abs() < 1e-15);
        let held = mesh.proximity(y, Some(above.feature));
        assert!((held.gap + 1e-4).abs() < 1e-15);
        assert_eq!(held.normal, [0.0, 0.0, 1.0]);
    }

    /// Points for finite differences around triangle `t` of a convex mesh:
    /// outside its face, edge and vertex regions (off the symmetric
    /// directions, where the reported triangle would switch), and inside
    /// its face region.
    fn points_around(mesh: &TriMeshObstacle, t: usize, offset: f64) -> Vec<[f64; 3]> {
        let n = mesh.face_normals[t];
        // The first edge with a fold (not between coplanar triangles), and
        // the normal of the triangle across it.
        let (k, nu) = (0..3)
            .find_map(|k| {
                let u = mesh.triangles()[t];
                let (p, q) = (u[k], u[(k + 1) % 3]);
                (0..mesh.triangles().len())
                    .find(|&s| {
                        s != t
                            && mesh.triangles()[s].contains(&p)
                            && mesh.triangles()[s].contains(&q)
                    })
                    .map(|s| mesh.face_normals[s])
                    .filter(|m| dot(*m, n) < 0.9999)
                    .map(|m| (k, m))
            })
            .unwrap();
        let u = mesh.triangles()[t];
        let u = [u[k], u[(k + 1) % 3], u[(k + 2) % 3]];
        let [a, b, c] = u.map(|i| mesh.vertices()[i]);
        let centroid = scale(add(a, add(b, c)), 1.0 / 3.0);
        let mid = scale(add(a, b), 0.5);
        let edge_dir = add(scale(n, 0.6), scale(nu, 0.4));
        let vertex_dir = add(
            scale(
                mesh.vertex_normals[u[2]],
                1.0 / norm(mesh.vertex_normals[u[2]]),
            ),
            scale(n, 0.2),
        );
        vec![
            add(centroid, scale(n, offset)),
            add(
                add(centroid, scale(sub(a, centroid), 0.3)),
                scale(n, 2.0 * offset),
            ),
            add(mid, scale(edge_dir, offset / norm(edge_dir))),
            add(c, scale(vertex_dir, offset / norm(vertex_dir))),
            sub(centroid, scale(n, 0.5 * offset)),
        ]
    }

    #[test]
    fn derivatives_on_an_icosphere() {
        let r = 0.1;
        let mesh = obstacle(icosphere(2, [0.01, 0.02, -0.03], r));
        for t in [0, 37, 150, 301] {
            for y in points_around(&mesh, t, 0.01 * r) {
                check_derivatives(&mesh, y, None, r);
            }
            // Inside, following the hinted triangle.
            let [a, b, c] = mesh.corners(t);
            let inner = add(scale(add(a, add(b, c)), 0.3), scale(a, 0.1));
            let y = sub(inner, scale(mesh.face_normals[t], 0.02 * r));
            check_derivatives(&mesh, y, Some(t as u32), r);
        }
    }

    #[test]
    fn derivatives_on_a_faceted_cylinder() {
        let r = 0.1;
        let mesh = obstacle(faceted_cylinder(24, r, 0.05));
        // Lateral facets (curved field across the vertical edges), the top
        // rim edges and corners.
        for t in [0, 9, 20] {
            for y in points_around(&mesh, t, 0.02 * r) {
                check_derivatives(&mesh, y, None, r);
            }
        }
        for y in [
            [0.11, 0.004, 0.01],
            [0.001, -0.105, 0.003],
            [0.03, 0.02, 0.02],
            [0.03, 0.02, -0.01],
        ] {
            check_derivatives(&mesh, y, None, r);
        }
    }

    #[test]
    fn an_inverted_mesh_is_turned_outside_out() {
        let (v, t) = box_mesh(PEDESTAL_LO, PEDESTAL_HI);
        let reversed: Vec<_> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
        let mesh = TriMeshObstacle::new("inverted", v, reversed).unwrap();
        assert!(mesh.was_inverted());
        let p = mesh.proximity([0.0, 0.0, 0.0], None);
        assert!((p.gap - 0.05).abs() < 1e-15);
        assert_eq!(p.normal, [0.0, 0.0, 1.0]);
    }

    #[test]
    fn describe_and_bounding_box() {
        let mesh = obstacle(box_mesh(PEDESTAL_LO, PEDESTAL_HI));
        assert_eq!(mesh.bounding_box(), (PEDESTAL_LO, PEDESTAL_HI));
        assert_eq!(
            mesh.describe(),
            "mesh test mesh (12 triangles, [-0.05,-0.05,-0.25]..[0.05,0.05,-0.05])"
        );
        let p = mesh.proximity([f64::NAN, 0.0, 0.0], Some(0));
        assert!(p.gap.is_nan());
    }

    #[test]
    fn constructor_errors() {
        let (v, t) = box_mesh([0.0; 3], [1.0; 3]);
        let e = TriMeshObstacle::new("m.obj", v.clone(), vec![]).unwrap_err();
        assert_eq!(e.to_string(), "m.obj: the mesh has no triangles");

        let mut open = t.clone();
        open.pop();
        let e = TriMeshObstacle::new("m.obj", v.clone(), open).unwrap_err();
        assert!(matches!(e, ObstacleError::OpenMesh { .. }), "{e}");
        assert!(
            e.to_string().starts_with("m.obj: the mesh is not closed"),
            "{e}"
        );

        let mut flipped = t.clone();
        flipped[3].swap(0, 1);
        let e = TriMeshObstacle::new("m.obj", v.clone(), flipped).unwrap_err();
        assert!(
            matches!(e, ObstacleError::InconsistentOrientation { .. }),
            "{e}"
        );

        let mut bad = t.clone();
        bad[5][2] = 8;
        let e = TriMeshObstacle::new("m.obj", v.clone(), bad).unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.obj: triangle 6 refers to vertex 9, but there are 8 vertices"
        );

        let mut nan = v.clone();
        nan[2][1] = f64::NAN;
        let e = TriMeshObstacle::new("m.obj", nan, t.clone()).unwrap_err();
        assert_eq!(e.to_string(), "m.obj: vertex 3 has a non-finite coordinate");

        // A sliver: a corner on the opposite edge.
        let mut sliver = v.clone();
        sliver.push([0.5, 0.0, 0.0]);
        let mut tris = t.clone();
        tris.push([0, 1, 8]);
        let e = TriMeshObstacle::new("m.obj", sliver, tris).unwrap_err();
        assert!(
            matches!(e, ObstacleError::DegenerateTriangle { triangle: 13, .. }),
            "{e}"
        );
        // Two corners joined by welding.
        let mut twin = v.clone();
        twin.push(v[0]);
        let mut tris = t.clone();
        tris.push([0, 1, 8]);
        let e = TriMeshObstacle::new("m.obj", twin, tris).unwrap_err();
        assert!(
            matches!(e, ObstacleError::DegenerateTriangle { triangle: 13, .. }),
            "{e}"
        );

        // Two tetrahedra sharing an edge: four triangles on it.
        let v2 = vec![
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.5],
            [0.0, 1.0, 0.5],
            [-1.0, 0.0, 0.5],
            [0.0, -1.0, 0.5],
        ];
        let tet = |p: usize, q: usize| vec![[0, 1, p], [1, 0, q], [0, p, q], [1, q, p]];
        let mut tris = tet(2, 3);
        tris.extend(tet(4, 5));
        let e = TriMeshObstacle::new("m.obj", v2, tris).unwrap_err();
        assert!(
            matches!(e, ObstacleError::NonManifoldEdge { count: 4, .. }),
            "{e}"
        );

        // A triangle and its reverse: closed, but no volume.
        let flat = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let e = TriMeshObstacle::new("m.obj", flat, vec![[0, 1, 2], [0, 2, 1]]).unwrap_err();
        assert_eq!(e.to_string(), "m.obj: the mesh encloses no volume");
    }

    /// A box written as OBJ (quads), ASCII STL and binary STL reads back as
    /// the same obstacle.
    #[test]
    fn reads_obj_and_stl_files() {
        let dir = std::env::temp_dir().join(format!("drape-trimesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (lo, hi) = ([-0.5, -0.25, -1.0], [0.5, 0.25, 0.0]);
        let (v, t) = box_mesh(lo, hi);
        let mut obj = String::from("# box\n");
        for p in &v {
            obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
        }
        // The four sides as quads, the caps as triangles.
        obj += "f 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\nf 5 6 7\nf 5 7 8\nf 1 3 2\nf 1 4 3\n";
        let mut ascii = String::from("solid box\n");
        for tri in &t {
            ascii += "facet normal 0 0 0\nouter loop\n";
            for &i in tri {
                ascii += &format!("vertex {} {} {}\n", v[i][0], v[i][1], v[i][2]);
            }
            ascii += "endloop\nendfacet\n";
        }
        ascii += "endsolid box\n";
        let records: Vec<[[f32; 3]; 3]> = t
            .iter()
            .map(|tri| tri.map(|i| v[i].map(|c| c as f32)))
            .collect();
        let binary = crate::contact::obstacle::stl::tests::binary(b"solid box", &records);
        let files = [
            ("box.obj", obj.into_bytes()),
            ("box.stl", ascii.into_bytes()),
            ("BOX.STL", binary),
        ];
        let reference = BoxObstacle::new(lo, hi).unwrap();
        for (name, bytes) in files {
            let path = dir.join(name);
            std::fs::write(&path, bytes).unwrap();
            let mesh = read_mesh_obstacle(&path).unwrap();
            assert_eq!(mesh.vertices().len(), 8, "{name}");
            assert!(!mesh.was_inverted());
            assert!(mesh.describe().contains(name));
            for y in [
                [0.1, 0.1, 0.3],
                [0.0, 0.0, -0.1],
                [0.7, 0.4, -0.5],
                [0.45, -0.2, -0.9],
            ] {
                let g = mesh.proximity(y, None).gap;
                assert!(
                    (g - reference.proximity(y, None).gap).abs() < 1e-12,
                    "{name} {y:?}"
                );
            }
        }
        // Errors name the file.
        let open = dir.join("open.stl");
        std::fs::write(&open, "solid o\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n").unwrap();
        let e = read_mesh_obstacle(&open).unwrap_err();
        assert!(matches!(e, ObstacleError::OpenMesh { .. }), "{e}");
        assert!(
            e.to_string().starts_with(&open.display().to_string()),
            "{e}"
        );
        let bad = dir.join("bad.obj");
        std::fs::write(&bad, "v 0 0 0\nv 1 0 x\n").unwrap();
        let e = read_mesh_obstacle(&bad).unwrap_err();
        assert!(matches!(e, ObstacleError::MeshFile(_)), "{e}");
        assert!(e.to_string().contains("bad.obj, line 2"), "{e}");
        let e = read_mesh_obstacle(&dir.join("missing.obj")).unwrap_err();
        assert!(matches!(e, ObstacleError::MeshFile(_)), "{e}");
        assert!(e.to_string().contains("missing.obj"), "{e}");
        let e = read_mesh_obstacle(&dir.join("shape.ply")).unwrap_err();
        assert!(
            e.to_string()
                .ends_with("shape.ply: unsupported obstacle mesh format; use a .obj or .stl file"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
