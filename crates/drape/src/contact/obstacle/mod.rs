//! Geometry of the rigid obstacles: signed distance (the gap), closest
//! point, outward normal and the normal's derivative, for node-to-surface
//! contact (docs/theory.md §1.8).
//!
//! Every obstacle answers one question for a point `y` (a node of the
//! fabric): [`Obstacle::proximity`]. The answer, a [`Proximity`], holds
//!
//! * the gap `g = (y - y') . n`, where `y'` is the closest point of the
//!   obstacle's surface and `n` its outward unit normal there: a signed
//!   distance, negative when `y` is inside the obstacle (penetration);
//! * `n = dg/dy`, the gradient of the gap;
//! * `dn/dy = d^2 g / dy^2`, the (symmetric) Hessian of the gap, which the
//!   penalty Hessian `eta (n n^T + g dn/dy)` needs;
//! * the *feature* (face, part or triangle) that decided the answer, which
//!   the caller hands back as `hint` at the next step.
//!
//! The enforcement (penalty or Lagrange) is written on top of this trait and
//! is not part of this module.
//!
//! # Which face pushes a node out: the edge and corner rule
//!
//! Nodes of a fabric can lie exactly above an edge of a box (a 20 x 20 grid
//! over the pedestal has nodes at `x = 0.05` over a box whose side is the
//! plane `x = 0.05`). When such a node sinks below the top face by `delta`,
//! the nearest face by distance is the *side* face (distance 0): a plain
//! closest-point rule returns `g = 0` with the side's normal, the contact
//! gives no force, and the node falls through the top. The rule here is
//! deliberate:
//!
//! **A node is pushed out through the face it came in by; a node above an
//! edge or a corner meets the top face.**
//!
//! For the convex capped shapes ([`BoxObstacle`], [`CylinderObstacle`]) each
//! face `f` has a plane signed distance `d_f(y) = n_f . (y - p_f)` (the
//! cylinder's lateral surface uses the radial distance `rho - R`), and
//! `D = max_f d_f` is positive outside, negative inside.
//!
//! 1. The *feature* of a point is the face whose plane distance is largest,
//!    `argmax_f d_f`. For a point outside, exactly above an edge, this is the
//!    top face (`d_top > 0`, `d_side = 0`); for a point inside, the nearest
//!    face. Ties go to the face listed first, and the top face (`+z` for a
//!    box, the top cap for a cylinder) is listed first: see
//!    [`BoxObstacle::FACE_NORMALS`] and [`CylinderObstacle::TOP`].
//! 2. **Outside** (`D > tau`, `tau` the touching tolerance below): the gap is
//!    the true Euclidean distance to the surface and `n = (y - y') / |y -
//!    y'|`, whatever the hint. Near an edge or a corner the distance field is
//!    curved: `dn/dy = (I - n n^T - e e^T) / g` about an edge of direction
//!    `e`, `(I - n n^T) / g` about a corner. The reported feature is still
//!    the argmax face, so that a node approaching from above an edge reports
//!    the top face.
//! 3. **Inside or touching** (`D <= tau`) **with a hint** `Some(f)` (the
//!    feature the node had at the end of the previous step): face `f`
//!    decides, `g = d_f`, `n = n_f`, `y' = y - g n`, `dn/dy = 0` for a plane
//!    face (the cylinder's lateral surface keeps its curvature term). A node
//!    that entered through the top stays in contact with the top, however
//!    near the side it is.
//! 4. **Inside or touching without a hint**: the argmax face (the nearest
//!    one), with the same formulas.
//!
//! The *touching tolerance* `tau = TOUCH_TOLERANCE x (diagonal of the
//! obstacle's bounding box)` (0.25 nm for the 0.1 x 0.1 x 0.2 m pedestal)
//! treats points that round-off put a hair outside a face as touching it: a
//! node one rounding error (`1e-17` m) outside the side plane that came in
//! through the top still meets the top. Within that band the gap differs
//! from the Euclidean distance by at most `tau`.
//!
//! The caller must therefore keep, for every node and obstacle, the
//! `feature` of the last converged step **whether or not the pair was in
//! contact** (a node above an edge reports the top face while still in the
//! air), hand it back as `hint` during the whole of the next step (fixed
//! during the Newton iterations, so that the gap is one smooth function for
//! the step), and pass `None` only when nothing is known (the first step).
//! An invalid hint (a feature the obstacle does not have) is ignored.
//!
//! The smooth shapes need no rule: [`PlaneObstacle`] and [`SphereObstacle`]
//! ignore the hint. [`TriMeshObstacle`] applies the same idea to its
//! triangles (see its documentation): outside, the true distance, and among
//! triangles at the same distance the one with the largest plane distance;
//! inside, the plane of the hinted triangle as long as the point's
//! projection onto it falls on the triangle's flat patch (a whole face of a
//! box mesh).
//!
//! # Continuity
//!
//! Without a hint the gap is the signed distance (up to `tau` in the
//! touching band): continuous. With a hint `f` it is continuous inside and
//! outside, but it jumps where `y` leaves the obstacle through another face
//! than `f` (a node held by the top and pushed sideways past the side's
//! plane): from `d_f < 0` to the distance outside, about `0`, and the node
//! is free. `dn/dy` jumps across the boundaries between the face, edge and
//! corner regions outside and across the medial surfaces inside; the
//! finite-difference tests keep their points away from all of these.
//!
//! # Moving obstacles
//!
//! An obstacle that has moved rigidly by the translation `u(t)` is queried at
//! `y - u` and its answer shifted back with [`Proximity::translated`]; the
//! gap, normal and `dn/dy` are unchanged by the shift.

mod bvh;
pub mod cuboid;
pub mod cylinder;
pub mod plane;
pub mod rounded;
pub mod sphere;
pub mod stl;
pub mod trimesh;

pub use cuboid::BoxObstacle;
pub use cylinder::CylinderObstacle;
pub use plane::PlaneObstacle;
pub use rounded::Rounded;
pub use sphere::SphereObstacle;
pub use trimesh::{TriMeshObstacle, read_mesh_obstacle, read_mesh_obstacle_with_bytes};

use crate::mesh::gmsh::MeshReadError;
use crate::vec3::{add, norm, scale};

/// Relative size of the touching band: points at most `TOUCH_TOLERANCE x`
/// (the diagonal of the obstacle's bounding box) outside the surface are
/// treated as touching it (see the [module documentation](self)). A number
/// well above the round-off of coordinates (`1e-16` relative) and far below
/// any physical length.
pub const TOUCH_TOLERANCE: f64 = 1e-9;

/// Result of a closest-point query for one point `y`.
///
/// `gap = (y - closest) . normal`; `normal = d gap / dy`;
/// `normal_derivative = d normal / dy = d^2 gap / dy^2` (symmetric).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Proximity {
    /// Signed distance `g` (m) from the surface: positive outside, zero on
    /// the surface, negative inside (penetration).
    pub gap: f64,
    /// Closest point `y'` of the surface (m), or, for a point inside that
    /// follows a hinted face, the projection of `y` onto that face's plane.
    pub closest: [f64; 3],
    /// Outward unit normal `n` at the closest point, such that `g = (y -
    /// y') . n` and `n = dg/dy`.
    pub normal: [f64; 3],
    /// `dn/dy` (1/m), row `i` holding `d n_i / d y_j`: zero on a plane face,
    /// `(I - n n^T) / r` on a sphere of radius `r`, `(I - n n^T - e e^T) /
    /// g` near an edge of direction `e`, `(I - n n^T) / g` near a corner.
    pub normal_derivative: [[f64; 3]; 3],
    /// The face, part or triangle that determined the result; hand it back
    /// as `hint` at the next step. Its meaning depends on the obstacle (see
    /// each type's documentation).
    pub feature: u32,
}

impl Proximity {
    /// The same answer for the obstacle moved rigidly by the translation
    /// `offset` (m): the closest point moves by `offset`; gap, normal and
    /// its derivative are unchanged. Query the unmoved obstacle at `y -
    /// offset` first.
    pub fn translated(self, offset: [f64; 3]) -> Self {
        Self {
            closest: add(self.closest, offset),
            ..self
        }
    }

    /// Whether the point is inside the obstacle (`gap < 0`).
    pub fn is_penetrating(&self) -> bool {
        self.gap < 0.0
    }
}

/// A rigid obstacle: anything that can tell a point its gap, normal and
/// normal derivative.
pub trait Obstacle: Send + Sync + std::fmt::Debug {
    /// Closest-point query for the point `y` (m).
    ///
    /// `hint`: the feature this point was in contact with (or reported) at
    /// the end of the previous step, or `None`. It decides which face pushes
    /// a point out when the point is inside (see the [module
    /// documentation](self)); an invalid hint is ignored. A non-finite `y`
    /// gives a NaN gap, closest point and normal (feature `0`), without
    /// panicking.
    fn proximity(&self, y: [f64; 3], hint: Option<u32>) -> Proximity;

    /// Axis-aligned bounding box `(min, max)` (m) of the obstacle, for
    /// broad-phase culling: a point outside it has a positive gap. A plane's
    /// box is infinite in the directions the half-space is unbounded.
    fn bounding_box(&self) -> ([f64; 3], [f64; 3]);

    /// Short human description for messages, e.g. `box
    /// [-0.05,-0.05,-0.25]..[0.05,0.05,-0.05]`.
    fn describe(&self) -> String;

    /// The constraint of a node held on `feature` (Lagrange multipliers):
    /// the signed distance to that face's surface (its plane, for a flat
    /// face) with its normal and curvature, whether the node is inside or
    /// outside, and whether the node's projection lies on the face (with the
    /// touching tolerance). A node that has slid off its face is released by
    /// the enforcement once Newton has converged.
    ///
    /// Holding a node on its face's smooth surface, rather than on the
    /// obstacle's distance field, keeps the constraint smooth while the
    /// node slides up to an edge (around an edge the distance field's
    /// normal turns through 90 degrees over no distance, and Newton cannot
    /// converge on it). Default: the hinted proximity, for shapes without
    /// edges.
    fn constraint(&self, y: [f64; 3], feature: u32) -> (Proximity, bool) {
        (self.proximity(y, Some(feature)), true)
    }

    /// The obstacle's sharp convex features — corners, edges, rim circles —
    /// as points no farther apart than `spacing` (m) along each edge or
    /// rim, each with its outward direction: what
    /// [`crate::contact::features`] keeps out of the fabric's triangles,
    /// where node-to-surface contact cannot see them (between nodes).
    /// Default none: a smooth surface (plane, sphere) has no feature a
    /// fabric's nodes would not meet first.
    fn sharp_points(&self, _spacing: f64) -> Vec<SharpPoint> {
        Vec::new()
    }
}

/// A point of an obstacle's sharp feature ([`Obstacle::sharp_points`]), in
/// the obstacle's frame at `t = 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SharpPoint {
    /// Where it is (m).
    pub position: [f64; 3],
    /// The feature's outward direction (unit): the normalised sum of the
    /// outward normals of the faces that meet there, the axis of the
    /// feature's cone of normals. The obstacle lies on its negative side.
    pub outward: [f64; 3],
}

/// `n` points strictly inside the segment `a`–`b`, spaced equally and at
/// most `spacing` apart (its ends are corners, sampled on their own), each
/// with the outward direction `outward`.
fn sample_segment(
    a: [f64; 3],
    b: [f64; 3],
    outward: [f64; 3],
    spacing: f64,
    out: &mut Vec<SharpPoint>,
) {
    let pieces = pieces(norm(crate::vec3::sub(b, a)), spacing);
    for i in 1..pieces {
        let s = i as f64 / pieces as f64;
        out.push(SharpPoint {
            position: std::array::from_fn(|k| a[k] + s * (b[k] - a[k])),
            outward,
        });
    }
}

/// How many equal pieces a curve of `length` (m) is cut into so that none
/// is longer than `spacing` (at least 1; a non-positive or non-finite
/// spacing gives 1).
fn pieces(length: f64, spacing: f64) -> usize {
    let n = (length / spacing).ceil();
    if n.is_finite() && n >= 1.0 {
        n.min(u32::MAX as f64) as usize
    } else {
        1
    }
}

/// `v / |v|` of a non-zero vector.
fn normalised(v: [f64; 3]) -> [f64; 3] {
    scale(v, 1.0 / norm(v))
}

/// Invalid obstacle data: a scenario's numbers or a mesh file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ObstacleError {
    /// A value is NaN or infinite.
    #[error("{shape}: {key} has a non-finite value ({value})")]
    NonFinite {
        /// Kind of obstacle, e.g. `box`.
        shape: &'static str,
        /// Scenario key, e.g. `min`.
        key: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A direction (a plane's normal, a cylinder's axis) is the zero vector.
    #[error("{shape}: {key} must not be the zero vector")]
    ZeroVector {
        /// Kind of obstacle.
        shape: &'static str,
        /// Scenario key, e.g. `normal`.
        key: &'static str,
    },
    /// A length that must be positive is not.
    #[error("{shape}: {key} must be positive, found {value}")]
    NonPositive {
        /// Kind of obstacle.
        shape: &'static str,
        /// Scenario key, e.g. `radius`.
        key: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A box whose `min` is not below its `max` in some component.
    #[error(
        "box: min must be less than max in every component, but min {axis} = {min} >= max {axis} = {max}"
    )]
    EmptyBox {
        /// `x`, `y` or `z`.
        axis: char,
        /// `min` in that component.
        min: f64,
        /// `max` in that component.
        max: f64,
    },
    /// The mesh file could not be read (the message names the file and,
    /// where known, the line or byte).
    #[error(transparent)]
    MeshFile(#[from] MeshReadError),
    /// The mesh file's extension is neither `.obj` nor `.stl`.
    #[error("{file}: unsupported obstacle mesh format; use a .obj or .stl file")]
    UnsupportedFormat {
        /// File name.
        file: String,
    },
    /// The mesh has no triangles.
    #[error("{mesh}: the mesh has no triangles")]
    EmptyMesh {
        /// Mesh name (the file).
        mesh: String,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "{mesh}: triangle {triangle} refers to vertex {vertex}, but there are {vertices} vertices"
    )]
    VertexOutOfRange {
        /// Mesh name.
        mesh: String,
        /// 1-based triangle number.
        triangle: usize,
        /// 1-based vertex number.
        vertex: usize,
        /// Number of vertices.
        vertices: usize,
    },
    /// A vertex has a NaN or infinite coordinate.
    #[error("{mesh}: vertex {vertex} has a non-finite coordinate")]
    NonFiniteVertex {
        /// Mesh name.
        mesh: String,
        /// 1-based vertex number.
        vertex: usize,
    },
    /// A triangle of (nearly) zero area, whose normal is undefined.
    #[error("{mesh}: triangle {triangle} is degenerate (zero area): corners {a:?}, {b:?}, {c:?}")]
    DegenerateTriangle {
        /// Mesh name.
        mesh: String,
        /// 1-based triangle number.
        triangle: usize,
        /// First corner (m).
        a: [f64; 3],
        /// Second corner (m).
        b: [f64; 3],
        /// Third corner (m).
        c: [f64; 3],
    },
    /// An edge belongs to one triangle only: the surface has a hole.
    #[error(
        "{mesh}: the mesh is not closed: the edge {a:?}-{b:?} of triangle {triangle} belongs to no other triangle"
    )]
    OpenMesh {
        /// Mesh name.
        mesh: String,
        /// 1-based triangle number.
        triangle: usize,
        /// One end of the edge (m).
        a: [f64; 3],
        /// The other end (m).
        b: [f64; 3],
    },
    /// An edge is shared by more than two triangles.
    #[error(
        "{mesh}: the mesh is not a manifold: the edge {a:?}-{b:?} of triangle {triangle} belongs to {count} triangles"
    )]
    NonManifoldEdge {
        /// Mesh name.
        mesh: String,
        /// 1-based triangle number.
        triangle: usize,
        /// One end of the edge (m).
        a: [f64; 3],
        /// The other end (m).
        b: [f64; 3],
        /// Number of triangles sharing the edge.
        count: usize,
    },
    /// Two neighbouring triangles run through their shared edge in the
    /// same direction: their normals disagree.
    #[error(
        "{mesh}: triangles {first} and {second} are inconsistently oriented (they run through their shared edge {a:?}-{b:?} in the same direction)"
    )]
    InconsistentOrientation {
        /// Mesh name.
        mesh: String,
        /// 1-based number of the first triangle.
        first: usize,
        /// 1-based number of the second triangle.
        second: usize,
        /// One end of the edge (m).
        a: [f64; 3],
        /// The other end (m).
        b: [f64; 3],
    },
    /// The closed mesh encloses no volume.
    #[error("{mesh}: the mesh encloses no volume")]
    ZeroVolume {
        /// Mesh name.
        mesh: String,
    },
    /// More triangles than a `u32` feature number can name.
    #[error(
        "{mesh}: too many triangles ({count}); at most {} are supported",
        u32::MAX
    )]
    TooManyTriangles {
        /// Mesh name.
        mesh: String,
        /// Number of triangles.
        count: usize,
    },
}

/// Checks that every component of `v` is finite.
fn check_finite(shape: &'static str, key: &'static str, v: &[f64]) -> Result<(), ObstacleError> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(&value) => Err(ObstacleError::NonFinite { shape, key, value }),
        None => Ok(()),
    }
}

/// Checks that a length is finite and positive.
fn check_positive(shape: &'static str, key: &'static str, value: f64) -> Result<(), ObstacleError> {
    check_finite(shape, key, &[value])?;
    if value > 0.0 {
        Ok(())
    } else {
        Err(ObstacleError::NonPositive { shape, key, value })
    }
}

/// `v / |v|`, or an error for the zero vector.
fn unit(shape: &'static str, key: &'static str, v: [f64; 3]) -> Result<[f64; 3], ObstacleError> {
    check_finite(shape, key, &v)?;
    let length = norm(v);
    if length > 0.0 && length.is_finite() {
        Ok(scale(v, 1.0 / length))
    } else if length > 0.0 {
        // |v| overflows: scale down first.
        let big = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let w = scale(v, 1.0 / big);
        Ok(scale(w, 1.0 / norm(w)))
    } else {
        Err(ObstacleError::ZeroVector { shape, key })
    }
}

/// `[x,y,z]` with the shortest round-trip representation of each number.
fn show_point(p: [f64; 3]) -> String {
    format!("[{},{},{}]", p[0], p[1], p[2])
}

/// The 3x3 zero matrix.
const ZERO3: [[f64; 3]; 3] = [[0.0; 3]; 3];

/// `s (I - sum_k w_k v_k v_k^T)`: the curvature matrices of distance fields,
/// e.g. `(I - n n^T) / r` for a sphere, `(I - n n^T - e e^T) / g` for an edge.
fn identity_minus(terms: &[([f64; 3], f64)], s: f64) -> [[f64; 3]; 3] {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, mij) in row.iter_mut().enumerate() {
            let delta = if i == j { 1.0 } else { 0.0 };
            let sum: f64 = terms.iter().map(|(v, w)| w * v[i] * v[j]).sum();
            *mij = s * (delta - sum);
        }
    }
    m
}

/// Proximity to one face's plane: `g = d`, `y' = y - d n`, `dn/dy = 0`.
fn plane_proximity(y: [f64; 3], d: f64, n: [f64; 3], feature: u32) -> Proximity {
    Proximity {
        gap: d,
        closest: crate::vec3::sub(y, scale(n, d)),
        normal: n,
        normal_derivative: ZERO3,
        feature,
    }
}

/// The answer for a non-finite point: NaN everywhere, feature `0`.
fn undefined() -> Proximity {
    Proximity {
        gap: f64::NAN,
        closest: [f64::NAN; 3],
        normal: [f64::NAN; 3],
        normal_derivative: [[f64::NAN; 3]; 3],
        feature: 0,
    }
}

/// Whether every coordinate of `y` is finite.
fn is_finite(y: [f64; 3]) -> bool {
    y.iter().all(|v| v.is_finite())
}

/// Diagonal `|max - min|` of a bounding box.
fn diagonal(lo: [f64; 3], hi: [f64; 3]) -> f64 {
    norm(crate::vec3::sub(hi, lo))
}

#[cfg(test)]
pub(crate) mod testing {
    //! Shared checks for the obstacles' tests.

    use super::Obstacle;
    use crate::fd::jacobian_error;
    use crate::vec3::{dot, norm, sub};

    /// Asserts, at `y` with `hint`, that central differences (step `h =
    /// 1e-7 size`, `size` the obstacle's length scale) of the gap give the
    /// normal and those of the normal give `normal_derivative` (through
    /// [`crate::fd::jacobian_error`]), that the reported gap is `(y -
    /// closest) . n`, that `n` is a unit vector and that `dn/dy` is
    /// symmetric.
    ///
    /// Tolerance `1e-6`, relative to the derivative's largest entry: the
    /// truncation error is `O(h^2 kappa^2)` (`kappa` the curvature of the
    /// field, at most `1/|g|`, and the tests keep `|g| >= 1e-3 size`), the
    /// round-off `O(1e-16 |g| / h)`; both stay below `1e-7`. Where the exact
    /// `dn/dy` is zero the error is measured against `1/size`. Every point
    /// of the stencil must report the same feature: a stencil across a
    /// feature switch would straddle a kink of the field (or at least a
    /// change of the face that decides).
    pub fn check_derivatives(o: &dyn Obstacle, y: [f64; 3], hint: Option<u32>, size: f64) {
        let h = 1e-7 * size;
        let p = o.proximity(y, hint);
        let label = format!("{} at {y:?} hint {hint:?}: {p:?}", o.describe());
        assert!((norm(p.normal) - 1.0).abs() < 1e-12, "unit normal: {label}");
        let g = dot(sub(y, p.closest), p.normal);
        assert!(
            (g - p.gap).abs() <= 1e-12 * (1.0 + p.gap.abs()),
            "g = (y - y').n: {label}"
        );
        let m = p.normal_derivative;
        let scale = m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        let transposed: Vec<f64> = (0..9).map(|k| m[k % 3][k / 3]).collect();
        let asymmetry = m
            .concat()
            .iter()
            .zip(&transposed)
            .fold(0.0f64, |a, (u, v)| a.max((u - v).abs()));
        assert!(asymmetry <= 1e-12 * scale, "symmetry: {label}");
        for k in 0..3 {
            for s in [-1.0, 1.0] {
                let mut z = y;
                z[k] += s * h;
                let q = o.proximity(z, hint);
                assert_eq!(
                    q.feature, p.feature,
                    "feature switch in the stencil: {label}"
                );
            }
        }
        let at = |x: &[f64]| o.proximity([x[0], x[1], x[2]], hint);
        let gap_error = jacobian_error(|x| vec![at(x).gap], |x| at(x).normal.to_vec(), &y, h);
        assert!(gap_error < 1e-6, "dg/dy vs n: error {gap_error:e}: {label}");
        // `y / size` added to the normal and `I / size` to its derivative
        // give the error an absolute floor, `1/size`, where `dn/dy = 0`: the
        // normal `(y - y') / |y - y'|` of a face region is constant only up
        // to an ulp, which a purely relative measure would magnify.
        let normal_error = jacobian_error(
            |x| {
                let n = at(x).normal;
                (0..3).map(|i| n[i] + x[i] / size).collect()
            },
            |x| {
                let mut d = at(x).normal_derivative;
                for (i, row) in d.iter_mut().enumerate() {
                    row[i] += 1.0 / size;
                }
                d.concat()
            },
            &y,
            h,
        );
        assert!(
            normal_error < 1e-6,
            "dn/dy: error {normal_error:e}: {label}"
        );
    }
}

impl ObstacleError {
    /// The scenario key the error is about, when it is one value
    /// (`None` for mesh-file errors, which are about `path`).
    pub fn key(&self) -> Option<&'static str> {
        match self {
            Self::NonFinite { key, .. }
            | Self::ZeroVector { key, .. }
            | Self::NonPositive { key, .. } => Some(key),
            Self::EmptyBox { .. } => Some("max"),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A moved obstacle queried at `y - u` and shifted back answers as the
    /// obstacle built at its new place.
    #[test]
    fn translated_answer_matches_the_moved_obstacle() {
        let u = [0.01, -0.02, 0.3];
        let here = SphereObstacle::new([0.0, 0.0, 0.0], 0.1).unwrap();
        let there = SphereObstacle::new(u, 0.1).unwrap();
        let y = [0.05, 0.04, 0.38];
        let moved = here.proximity(crate::vec3::sub(y, u), None).translated(u);
        let direct = there.proximity(y, None);
        assert!((moved.gap - direct.gap).abs() < 1e-15);
        assert!(norm(crate::vec3::sub(moved.closest, direct.closest)) < 1e-15);
        assert!(norm(crate::vec3::sub(moved.normal, direct.normal)) < 1e-15);
        assert!(!moved.is_penetrating());
    }

    /// Every sharp point lies on its obstacle's surface (gap 0 within
    /// round-off), its outward direction is a unit vector along which the
    /// gap grows, the points of an edge or rim are at most the spacing
    /// apart, a box has its 8 corners and a cylinder's rims their circles;
    /// a rounded box's points are its sharp core's moved out by the radius.
    #[test]
    fn sharp_points_lie_on_the_edges_at_most_the_spacing_apart() {
        let spacing = 0.013;
        let b = BoxObstacle::new([-0.05, -0.04, -0.25], [0.05, 0.06, -0.05]).unwrap();
        let c = CylinderObstacle::new([0.0, 0.0, 0.01], [0.0, 0.6, 0.8], 0.09, 0.2).unwrap();
        let r = Rounded::new(
            BoxObstacle::new([-0.049, -0.039, -0.249], [0.049, 0.059, -0.051]).unwrap(),
            1e-3,
        );
        let shapes: [(&dyn Obstacle, usize); 3] = [(&b, 8), (&c, 0), (&r, 8)];
        for (shape, corners) in shapes {
            let points = shape.sharp_points(spacing);
            assert!(points.len() > 20, "{}", shape.describe());
            for p in &points {
                assert!((norm(p.outward) - 1.0).abs() < 1e-12);
                let gap = shape.proximity(p.position, None).gap;
                assert!(gap.abs() < 1e-12, "{}: gap {gap:e}", shape.describe());
                let out = add(p.position, scale(p.outward, 1e-3));
                assert!(shape.proximity(out, None).gap > 0.5e-3);
            }
            // Each point's nearest other point is within the spacing.
            for p in &points {
                let nearest = (points.iter())
                    .filter(|q| *q != p)
                    .map(|q| norm(crate::vec3::sub(q.position, p.position)))
                    .fold(f64::INFINITY, f64::min);
                assert!(nearest <= spacing, "{}: {nearest}", shape.describe());
            }
            let diagonal_outward = points
                .iter()
                .filter(|p| {
                    p.outward
                        .iter()
                        .all(|v| (v.abs() - 3f64.sqrt().recip()).abs() < 1e-12)
                })
                .count();
            assert_eq!(diagonal_outward, corners, "{}", shape.describe());
        }
        // A rim of radius 0.09 in arcs of at most 1.3 cm: 44 points each.
        assert_eq!(c.sharp_points(spacing).len(), 2 * 44);
        // The plane and the sphere have none.
        assert!(
            PlaneObstacle::new([0.0; 3], [0.0, 0.0, 1.0])
                .unwrap()
                .sharp_points(spacing)
                .is_empty()
        );
        assert!(
            SphereObstacle::new([0.0; 3], 1.0)
                .unwrap()
                .sharp_points(spacing)
                .is_empty()
        );
    }

    #[test]
    fn obstacles_are_trait_objects() {
        let all: Vec<Box<dyn Obstacle>> = vec![
            Box::new(PlaneObstacle::new([0.0; 3], [0.0, 0.0, 1.0]).unwrap()),
            Box::new(BoxObstacle::new([-1.0; 3], [1.0; 3]).unwrap()),
            Box::new(SphereObstacle::new([0.0; 3], 1.0).unwrap()),
            Box::new(CylinderObstacle::new([0.0; 3], [0.0, 0.0, 1.0], 1.0, 1.0).unwrap()),
        ];
        for o in &all {
            let p = o.proximity([0.0, 0.0, 2.0], None);
            assert!(p.gap > 0.0, "{}", o.describe());
            let (lo, hi) = o.bounding_box();
            assert!((0..3).all(|k| lo[k] <= hi[k]));
        }
    }
}
