//! The obstacles' sharp features kept out of the fabric's triangles
//! (issue 46, `[contact] features = true`; docs/theory.md §1.8): the
//! second pass of a two-pass node-to-surface contact, the obstacle's
//! corners, edges and rims as slave points against the fabric's
//! triangles as master surface (Wriggers, *Computational Contact
//! Mechanics*, 2nd ed. 2006, §5.2 and §8.1, the two-pass node-to-segment
//! algorithm; Hallquist, *LS-DYNA Theory Manual*, 2006, §23.8, the
//! symmetric penalty method).
//!
//! Node-to-surface contact ([`super::penalty`]) keeps the fabric's nodes
//! out of the obstacles, but a box's corner or a cylinder's rim can pass
//! through a triangle between its nodes. Here each obstacle's sharp
//! features are sampled as points ([`Obstacle::sharp_points`]: a box's
//! corners and edges, a capped cylinder's two rims, a rounded shape's
//! fillets' outer points, a triangle mesh's convex edges turning by more
//! than 10° and their ends) no farther apart than half the fabric's
//! shortest edge, so that no triangle lies across a feature between two
//! points, and each point `p` is penalised against its triangle `(a, b,
//! c)`:
//!
//! ```text
//! n = (b - a) x (c - a) / |(b - a) x (c - a)|,    d = n . (p - a)
//! sigma = sign(n . m),   g = -sigma d,            C = 1/2 eta g^2   (g < 0)
//! ```
//!
//! with `m` the feature's outward direction (the mean of the normals of
//! the faces meeting there: the obstacle lies on its negative side), `eta`
//! the obstacles' penalty (`[contact] penalty`, N/m) and `g` the signed
//! distance of the point from the triangle's plane, negative once the
//! point lies on the side of the fabric away from the obstacle. Since `g^2
//! = s`, the squared distance of `p` to the plane, the pair's gradient and
//! Hessian with respect to the triangle's nodes are `1/2 eta ∇s` and `1/2
//! eta ∇²s`, exact with the normal's derivatives
//! ([`super::barrier::point_plane_squared_distance`], the face region of
//! self-contact's point–triangle distance). The energy is C¹ where `g`
//! changes sign (`C` and its gradient vanish there). The point moves with
//! its obstacle (`RigidBody::velocity`) and is not an unknown; a pair
//! couples the three nodes of one triangle, which its element already
//! couples, so the Hessian's pattern does not grow (nor self-contact's
//! grown layout, which starts from it). With
//! [`crate::integrator::potential::StepContext::project`] flags on one of
//! its nodes a pair's 9 x 9 Hessian is replaced by its positive
//! semi-definite part ([`crate::psd`]): `∇²s` is indefinite (turning the
//! triangle about the point shortens the distance).
//!
//! **Which pairs.** At the start of each step (the step's first guess,
//! [`ObstacleFeatures::pairs`]) each point is paired with the nearest
//! triangle it projects into (the face region of
//! [`super::proximity::point_triangle`]) within the reach (half the
//! fabric's longest edge), if that triangle faces the feature (`|n . m| >=
//! `[`MIN_ALIGNMENT`]); `sigma` is taken there. The pairs and their sides
//! are then fixed for the step's Newton iterations, so that the step's
//! energy is one smooth function (as the obstacles' face hints are, and
//! friction's lagged normal forces); the next step finds them again, so
//! nothing is carried across steps (nothing for the checkpoint). The
//! reasons for each choice (docs/validation.md, "Obstacle features"):
//!
//! * *Lagged pairs, not found at every evaluation*: a point whose nearest
//!   triangle changes within Newton's iterations changes the energy
//!   discontinuously; found at every evaluation, Newton cycled and a 20 cm
//!   sheet of 5 cm elements on a box failed at its first contact.
//! * *Only triangles the point projects into*: the plane of a triangle the
//!   point merely lies beside, extended, may pass anywhere near the point
//!   (a steep hanging triangle beside an edge) and give a large false
//!   depth. A point above a convex fold lies in no triangle's face
//!   region, but it lay below the fold at the step before, inside both
//!   triangles, and keeps its pair's extended plane over the step.
//! * *The nearest such triangle, not every one*: paired with every
//!   triangle it projects into, the pedestal example ended with a total
//!   energy of +0.091 J instead of −0.0028 J (the second triangles'
//!   extended planes pushed where the fabric had folded away).
//! * *The side from the feature's outward direction, not from the step's
//!   start*: it takes a feature that starts a hair through the fabric —
//!   the gripped drape tester's rims, 2 µm into it — as the small
//!   penetration it is, where a side kept from the start would hold it
//!   through (an IPC barrier on the unsigned distance, infinite at
//!   contact, could not start there at all).
//!
//! What it leaves out: friction of the features (the nodes' friction
//! acts), multipliers (`method = "lagrange"` keeps node-to-surface only),
//! and a point that crosses a triangle other than
//! its pair within a step is caught only at the next step (by at most
//! what the fabric moves in a step). On coarse meshes (elements several
//! times the obstacle's fillet and a good fraction of its size) a
//! triangle that spans an edge pivots on it as a rigid lever; with a
//! tension-field membrane the elements beside it collapse and the
//! fabric may be thrown (docs/validation.md): hence the default `false`.
//!
//! [`Obstacle::sharp_points`]: super::obstacle::Obstacle::sharp_points

use super::barrier::point_plane_squared_distance;
use super::obstacle::SharpPoint;
use super::proximity::point_triangle;
use super::{ContactModel, PenaltyHessian};
use crate::vec3::{add, cross, dot, norm, scale, sub};
use std::collections::HashMap;

/// The smallest `|n . m|` of a pair: a triangle turned by more than 78°
/// from the feature's outward direction is not one the feature could have
/// entered through from outside (nor one whose side it could tell).
pub const MIN_ALIGNMENT: f64 = 0.2;

/// At most this many points over all obstacles: the spacing is doubled
/// until they fit (a fabric of millimetre elements on a metre-long box).
pub const MAX_POINTS: usize = 200_000;

/// Cells a triangle's box may cover in a body's grid before the body's
/// points are scanned instead (a triangle a Newton trial flung far).
const MAX_CELLS: i64 = 4096;

/// The obstacles' sampled features and the fabric's triangles they are
/// kept out of.
#[derive(Debug)]
pub struct ObstacleFeatures {
    triangles: Vec<[usize; 3]>,
    bodies: Vec<BodyFeatures>,
    spacing: f64,
    reach: f64,
}

/// One obstacle's points, in its frame at `t = 0`, and a grid of them.
#[derive(Debug)]
struct BodyFeatures {
    velocity: [f64; 3],
    points: Vec<SharpPoint>,
    lo: [f64; 3],
    hi: [f64; 3],
    cell: f64,
    grid: HashMap<[i64; 3], Vec<u32>>,
}

/// A feature point and the triangle it is kept on the obstacle's side
/// of over a step (module docs, "Which pairs").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeaturePair {
    /// The obstacle (index among the contact model's bodies that have
    /// features, in order).
    pub body: usize,
    /// The point's index among its obstacle's.
    pub point: usize,
    /// The triangle's index.
    pub triangle: usize,
    /// `sigma = sign(n . m)` when the pair was found: the side of the
    /// triangle's plane the obstacle lies on.
    pub side: f64,
}

impl ObstacleFeatures {
    /// The sharp features of `contact`'s obstacles against `triangles` (a
    /// linear mesh's elements, a higher order's sub-triangles) at the rest
    /// positions `x`: sampled at half the shortest edge (or coarser, to
    /// at most [`MAX_POINTS`]), reaching half the longest. `None` when no
    /// obstacle has a sharp feature (planes, spheres) or the mesh has no
    /// edge of positive length.
    pub fn new(contact: &ContactModel, triangles: Vec<[usize; 3]>, x: &[f64]) -> Option<Self> {
        let node = |a: usize| [x[3 * a], x[3 * a + 1], x[3 * a + 2]];
        let (mut shortest, mut longest) = (f64::INFINITY, 0.0f64);
        for t in &triangles {
            for k in 0..3 {
                let l = norm(sub(node(t[k]), node(t[(k + 1) % 3])));
                if l > 0.0 {
                    shortest = shortest.min(l);
                    longest = longest.max(l);
                }
            }
        }
        if !(shortest.is_finite() && longest > 0.0) {
            return None;
        }
        let sample = |spacing: f64| -> Vec<Vec<SharpPoint>> {
            (contact.bodies.iter())
                .map(|b| b.shape.sharp_points(spacing))
                .collect()
        };
        let count = |points: &[Vec<SharpPoint>]| points.iter().map(Vec::len).sum::<usize>();
        // The features' length, about, from a coarse sampling: a sliver of
        // an edge must not ask for billions of points before they are
        // counted.
        let length = count(&sample(longest)) as f64 * longest;
        let mut spacing = (0.5 * shortest).max(2.0 * length / MAX_POINTS as f64);
        let mut points = sample(spacing);
        while count(&points) > MAX_POINTS {
            spacing *= 2.0;
            points = sample(spacing);
        }
        let reach = 0.5 * longest;
        let bodies: Vec<BodyFeatures> = (contact.bodies.iter())
            .zip(points)
            .filter(|(_, p)| !p.is_empty())
            .map(|(b, p)| BodyFeatures::new(b.velocity, p, reach))
            .collect();
        (!bodies.is_empty()).then_some(Self {
            triangles,
            bodies,
            spacing,
            reach,
        })
    }

    /// The largest distance between neighbouring points of a feature (m).
    pub fn spacing(&self) -> f64 {
        self.spacing
    }

    /// How far a point may lie through a triangle and still be its pair
    /// (m): half the fabric's longest edge at rest.
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// The number of sampled points over all obstacles.
    pub fn point_count(&self) -> usize {
        self.bodies.iter().map(|b| b.points.len()).sum()
    }

    /// The fabric's triangles the features are kept out of.
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// The step's pairs from its first guess `y` at time `t`: each point
    /// with the nearest triangle it projects into within the reach, if
    /// that triangle faces the feature (module docs, "Which pairs"); in
    /// the order of the bodies and their points.
    pub fn pairs(&self, y: &[f64], t: f64) -> Vec<FeaturePair> {
        let node = |a: usize| [y[3 * a], y[3 * a + 1], y[3 * a + 2]];
        let reach2 = self.reach * self.reach;
        let mut out = Vec::new();
        for (j, body) in self.bodies.iter().enumerate() {
            let offset = scale(body.velocity, t);
            // Each point's nearest triangle: (squared distance, triangle).
            let mut nearest = vec![(f64::INFINITY, usize::MAX); body.points.len()];
            for (k, tri) in self.triangles.iter().enumerate() {
                let x = tri.map(node);
                // The triangle's box in the body's frame, grown by the reach.
                let lo = std::array::from_fn(|i| {
                    x[0][i].min(x[1][i]).min(x[2][i]) - offset[i] - self.reach
                });
                let hi = std::array::from_fn(|i| {
                    x[0][i].max(x[1][i]).max(x[2][i]) - offset[i] + self.reach
                });
                body.near(lo, hi, |q| {
                    let p = add(body.points[q].position, offset);
                    let closest = point_triangle(p, x[0], x[1], x[2]);
                    // Only a triangle the point projects into: the plane of
                    // one it lies beside may pass anywhere near the point.
                    let inside = closest.weights[1..].iter().all(|&w| w < 0.0);
                    if inside && closest.d2 <= reach2 && closest.d2 < nearest[q].0 {
                        nearest[q] = (closest.d2, k);
                    }
                });
            }
            for (q, &(_, k)) in nearest.iter().enumerate() {
                if k == usize::MAX {
                    continue;
                }
                let x = self.triangles[k].map(node);
                let normal = cross(sub(x[1], x[0]), sub(x[2], x[0]));
                let alignment = dot(normal, body.points[q].outward);
                if alignment.abs() >= MIN_ALIGNMENT * norm(normal) && alignment != 0.0 {
                    out.push(FeaturePair {
                        body: j,
                        point: q,
                        triangle: k,
                        side: alignment.signum(),
                    });
                }
            }
        }
        out
    }

    /// Pair `pair`'s point at time `t` and its triangle's nodes at `y`:
    /// the four nodes of a point–triangle pair.
    fn nodes(&self, pair: &FeaturePair, y: &[f64], t: f64) -> [[f64; 3]; 4] {
        let body = &self.bodies[pair.body];
        let p = add(body.points[pair.point].position, scale(body.velocity, t));
        let node = |a: usize| [y[3 * a], y[3 * a + 1], y[3 * a + 2]];
        let [a, b, c] = self.triangles[pair.triangle].map(node);
        [p, a, b, c]
    }

    /// How far pair `pair`'s point lies through its triangle's plane at
    /// `y`, time `t` (m): `-g = sigma n . (p - a)`, positive through it.
    pub fn depth(&self, pair: &FeaturePair, y: &[f64], t: f64) -> f64 {
        let [p, a, b, c] = self.nodes(pair, y, t);
        let normal = cross(sub(b, a), sub(c, a));
        pair.side * dot(normal, sub(p, a)) / norm(normal)
    }

    /// Adds `C = sum 1/2 eta g^2` over the pairs `pairs` with `g < 0` at
    /// `y`, time `t`, to `g` and (if given) its Hessian to `h` (module
    /// docs); returns `C` (J) and `dC/dt` at fixed `y` (W): the power the
    /// moving obstacles put in through their points, `sum dC/dp . v`
    /// (docs/theory.md (1.8d)).
    pub fn add_penalty(
        &self,
        stiffness: f64,
        pairs: &[FeaturePair],
        y: &[f64],
        t: f64,
        g: &mut [f64],
        mut h: Option<PenaltyHessian>,
    ) -> (f64, f64) {
        let (mut energy, mut power) = (0.0, 0.0);
        for pair in pairs {
            // Not through the plane (or not finite): no energy.
            let depth = self.depth(pair, y, t);
            if depth.is_nan() || depth <= 0.0 {
                continue;
            }
            let Some((s, ds, d2s)) = point_plane_squared_distance(&self.nodes(pair, y, t)) else {
                continue;
            };
            let tri = self.triangles[pair.triangle];
            energy += 0.5 * stiffness * s;
            power += 0.5 * stiffness * dot(self.bodies[pair.body].velocity, [ds[0], ds[1], ds[2]]);
            for (a, &node) in tri.iter().enumerate() {
                for i in 0..3 {
                    g[3 * node + i] += 0.5 * stiffness * ds[3 + 3 * a + i];
                }
            }
            let Some(PenaltyHessian {
                values,
                pattern,
                project,
            }) = h.as_mut()
            else {
                continue;
            };
            let mut k: [f64; 81] =
                std::array::from_fn(|rc| 0.5 * stiffness * d2s[(3 + rc / 9) * 12 + 3 + rc % 9]);
            if project.is_some_and(|flags| tri.iter().any(|&a| flags[a])) {
                crate::psd::project(&mut k, 9, 9);
            }
            for (a, &na) in tri.iter().enumerate() {
                for (b, &nb) in tri.iter().enumerate() {
                    let block = pattern
                        .node_block(na, nb)
                        .expect("a triangle's nodes are coupled in the pattern");
                    for i in 0..3 {
                        for j in 0..3 {
                            values[pattern.entry(block, nb, i, j)] +=
                                k[(3 * a + i) * 9 + 3 * b + j];
                        }
                    }
                }
            }
        }
        (energy, power)
    }

    /// The deepest any feature point lies through the nearest triangle it
    /// projects into at `y`, time `t` (m; 0 when none does): what `[contact] features`
    /// keeps to the penalty's own scale.
    pub fn deepest(&self, y: &[f64], t: f64) -> f64 {
        (self.pairs(y, t).iter())
            .map(|pair| self.depth(pair, y, t))
            .fold(0.0f64, f64::max)
    }
}

impl BodyFeatures {
    fn new(velocity: [f64; 3], points: Vec<SharpPoint>, reach: f64) -> Self {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &points {
            for i in 0..3 {
                lo[i] = lo[i].min(p.position[i]);
                hi[i] = hi[i].max(p.position[i]);
            }
        }
        let cell = reach;
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (k, p) in points.iter().enumerate() {
            grid.entry(cell_of(p.position, cell))
                .or_default()
                .push(k as u32);
        }
        Self {
            velocity,
            points,
            lo,
            hi,
            cell,
            grid,
        }
    }

    /// Calls `visit` with the index of every point inside the box `[lo,
    /// hi]` (the body's frame), in a fixed order.
    fn near(&self, lo: [f64; 3], hi: [f64; 3], mut visit: impl FnMut(usize)) {
        if (0..3).any(|i| !(hi[i] >= self.lo[i] && lo[i] <= self.hi[i])) {
            return;
        }
        let inside =
            |p: &SharpPoint| (0..3).all(|i| p.position[i] >= lo[i] && p.position[i] <= hi[i]);
        let (a, b) = (cell_of(lo, self.cell), cell_of(hi, self.cell));
        let cells = (0..3).fold(1i64, |n, i| n.saturating_mul(b[i] - a[i] + 1));
        if cells > MAX_CELLS {
            (0..self.points.len())
                .filter(|&k| inside(&self.points[k]))
                .for_each(visit);
            return;
        }
        for cx in a[0]..=b[0] {
            for cy in a[1]..=b[1] {
                for cz in a[2]..=b[2] {
                    for &k in self.grid.get(&[cx, cy, cz]).into_iter().flatten() {
                        if inside(&self.points[k as usize]) {
                            visit(k as usize);
                        }
                    }
                }
            }
        }
    }
}

/// The grid cell of `x` (cells of side `cell`), clamped so that far
/// coordinates stay representable.
fn cell_of(x: [f64; 3], cell: f64) -> [i64; 3] {
    x.map(|v| (v / cell).floor().clamp(-1e15, 1e15) as i64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::obstacle::BoxObstacle;
    use crate::contact::{DEFAULT_STICK_SPEED, RigidBody};

    /// A fabric with a sliver edge of 1 nm on a 1 m box: the spacing is
    /// coarsened to at most `MAX_POINTS` points (not half a nanometre),
    /// and the points still lie within the spacing of each other.
    #[test]
    fn a_sliver_edge_does_not_ask_for_billions_of_points() {
        let contact = ContactModel {
            bodies: vec![RigidBody {
                shape: Box::new(BoxObstacle::new([-0.5; 3], [0.5; 3]).expect("a box")),
                velocity: [0.0; 3],
            }],
            method: crate::contact::ContactMethod::Penalty { stiffness: 5e4 },
            friction: 0.0,
            body_friction: Vec::new(),
            stick_speed: DEFAULT_STICK_SPEED,
            features: true,
        };
        let x = [0.0, 0.0, 1.0, 0.01, 0.0, 1.0, 0.01, 1e-9, 1.0];
        let features = ObstacleFeatures::new(&contact, vec![[0, 1, 2]], &x).expect("features");
        assert!(features.point_count() <= MAX_POINTS);
        assert!(features.spacing() > 1e-5, "spacing {}", features.spacing());
    }
}
