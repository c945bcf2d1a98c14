//! Frictionless contact of the fabric's nodes with rigid obstacles
//! (docs/theory.md §1.8): node-to-surface, every node a projectile, every obstacle a
//! target.
//!
//! * [`obstacle`]: the geometry — gap, normal, normal derivative of plane,
//!   box, sphere, capped cylinder and closed triangle mesh, and the rule
//!   that decides which face pushes a node out near edges and corners.
//! * [`penalty`]: the potential `C = 1/2 eta g^2` while `g < 0`.
//! * [`lagrange`]: exact `g = 0` on an active set, by elimination.
//!
//! # Per-node state across steps
//!
//! For every node and obstacle the *feature* (face) reported at the end of
//! the last converged step is kept and handed back as the hint during the
//! whole of the next step: a node that came down onto the top face of a box
//! is pushed back through the top face even when it lies exactly above an
//! edge, with penalty and multipliers alike (see [`obstacle`]). Features are
//! refreshed for every node within a margin of a quarter of the obstacle's
//! bounding-box diagonal around its bounding box; nodes further away cannot
//! reach it in one step (a node would need to travel that far).
//!
//! A node in contact with several obstacles at once is in contact with the
//! one it penetrates most (Lagrange), or with all of them (penalty).

pub mod barrier;
pub mod features;
pub mod lagrange;
pub mod obstacle;
pub mod penalty;
pub mod proximity;
pub mod self_contact;

pub use obstacle::{Obstacle, ObstacleError, Proximity};
pub use penalty::PenaltyHessian;

use crate::vec3::{add, dot, norm, scale, sub};
use rayon::prelude::*;

/// Meshes with fewer nodes search for contact on the calling thread (a
/// thread hand-off costs more than a search of a few thousand nodes).
const PARALLEL_NODES_ABOVE: usize = 4096;

/// Node–body pairs with a force: `(node, body, force on the node)`.
type PairForces = Vec<(usize, usize, [f64; 3])>;

/// An obstacle and its prescribed rigid motion.
#[derive(Debug)]
pub struct RigidBody {
    /// The shape, at `t = 0`.
    pub shape: Box<dyn Obstacle>,
    /// Rigid translation velocity (m/s): at time `t` the body has moved by `v t`.
    pub velocity: [f64; 3],
}

impl RigidBody {
    /// Proximity of point `y` at time `t`.
    pub fn proximity(&self, y: [f64; 3], t: f64, hint: Option<u32>) -> Proximity {
        let offset = scale(self.velocity, t);
        self.shape
            .proximity(sub(y, offset), hint)
            .translated(offset)
    }

    /// The constraint of a node held on `feature` at time `t`, and whether
    /// it still lies on that face (see [`Obstacle::constraint`]).
    pub fn constraint(&self, y: [f64; 3], t: f64, feature: u32) -> (Proximity, bool) {
        let offset = scale(self.velocity, t);
        let (p, on) = self.shape.constraint(sub(y, offset), feature);
        (p.translated(offset), on)
    }

    /// Whether `y` is far enough from the body at time `t` to be skipped
    /// (outside its bounding box grown by `margin`).
    fn far(&self, y: [f64; 3], t: f64, margin: f64) -> bool {
        let (lo, hi) = self.shape.bounding_box();
        let offset = scale(self.velocity, t);
        (0..3).any(|i| y[i] < lo[i] + offset[i] - margin || y[i] > hi[i] + offset[i] + margin)
    }

    /// The feature-refresh margin (m): a quarter of the bounding box's diagonal
    /// (1 m for unbounded shapes such as planes).
    fn margin(&self) -> f64 {
        let diag = self.diagonal();
        if diag.is_finite() { 0.25 * diag } else { 1.0 }
    }

    /// A distance outside the bounding box beyond which a point surely has
    /// a positive gap: a millionth of the box diagonal, well above the
    /// touching band (`TOUCH_TOLERANCE`, a billionth) within which a hinted
    /// face may still report a negative gap. 0 for unbounded boxes (whose
    /// infinite sides nothing lies beyond).
    fn apart_margin(&self) -> f64 {
        let diag = self.diagonal();
        if diag.is_finite() { 1e-6 * diag } else { 0.0 }
    }

    fn diagonal(&self) -> f64 {
        let (lo, hi) = self.shape.bounding_box();
        norm(sub(hi, lo))
    }
}

/// How contact is enforced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactMethod {
    /// Penalty with stiffness `eta` (N/m per node).
    Penalty {
        /// `eta` (N/m).
        stiffness: f64,
    },
    /// Lagrange multipliers, `g = 0` exactly on the active set.
    Lagrange,
}

/// The obstacles and the enforcement method.
#[derive(Debug)]
pub struct ContactModel {
    /// Rigid obstacles.
    pub bodies: Vec<RigidBody>,
    /// Enforcement.
    pub method: ContactMethod,
    /// Coulomb's friction coefficient `mu` against every obstacle (0:
    /// frictionless). Penalty contact only ([`crate::integrator::terms::FrictionTerm`]).
    pub friction: f64,
    /// Obstacle `k`'s own coefficient in place of `friction`, where
    /// `body_friction[k]` is `Some` (empty: none).
    pub body_friction: Vec<Option<f64>>,
    /// The slip speed `eps_v` (m/s) below which friction is a stiff
    /// viscous resistance rather than Coulomb's constant force (the
    /// smoothing of Li et al. 2020): the creep speed of a fabric that
    /// sticks.
    pub stick_speed: f64,
    /// Whether the obstacles' sharp features (corners, edges, rims) are
    /// kept out of the fabric's triangles too, with the penalty
    /// ([`features`]; `[contact] features`). Nothing with multipliers.
    pub features: bool,
}

/// The default `[contact] stick_speed` (m/s): creep of at most 1 mm in
/// a second where friction holds (Li et al. 2020 use 1e-3 of the scene's
/// size a second).
pub const DEFAULT_STICK_SPEED: f64 = 1e-3;

/// Friction's mollifier `f0(s)`, `f1(s) = f0'(s)` and `f1'(s)`
/// (`integrator::terms::friction`'s module docs), for a slip
/// `s >= 0` and the smoothing slip `e > 0`.
pub(crate) fn mollifier(s: f64, e: f64) -> (f64, f64, f64) {
    if s >= e {
        (s, 1.0, 0.0)
    } else {
        let r = s / e;
        (
            e * (-r * r * r / 3.0 + r * r + 1.0 / 3.0),
            -r * r + 2.0 * r,
            (2.0 - 2.0 * r) / e,
        )
    }
}

/// Contact state carried from step to step.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactState {
    /// `hints[p * bodies + k]`: feature of node `p` on body `k` at the end of
    /// the last converged step (`u32::MAX`: unknown).
    pub hints: Vec<u32>,
    /// Lagrange: the body and the feature (face) node `p` is held on, if any.
    pub active: Vec<Option<(u32, u32)>>,
    /// Lagrange: multiplier `lambda_p >= 0` (N), the compressive contact
    /// force of node `p` (0 when inactive).
    pub multipliers: Vec<f64>,
}

/// What contact does at a converged state.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactReport {
    /// Node–obstacle pairs in contact.
    pub active: usize,
    /// Resultant contact force on the fabric `sum_p f_p` (N).
    pub resultant: [f64; 3],
    /// Smallest gap over all nodes and obstacles (m); `+inf` without obstacles.
    pub min_gap: f64,
    /// Stored penalty energy `sum 1/2 eta g^2` (J); 0 with multipliers.
    pub energy: f64,
    /// Contact force on each node (N), pushing it out of the obstacles.
    pub nodal_forces: Vec<[f64; 3]>,
}

impl ContactModel {
    /// The friction coefficient against obstacle `k`: its own, or
    /// `friction`.
    pub fn friction_of(&self, k: usize) -> f64 {
        self.body_friction
            .get(k)
            .copied()
            .flatten()
            .unwrap_or(self.friction)
    }

    /// Whether friction acts against any obstacle.
    pub fn has_friction(&self) -> bool {
        (0..self.bodies.len()).any(|k| self.friction_of(k) > 0.0)
    }

    /// The initial state of `nodes` nodes: features computed at the initial
    /// positions, nothing active.
    pub fn initial_state(&self, y: &[f64]) -> ContactState {
        let nodes = y.len() / 3;
        let mut state = ContactState {
            hints: vec![u32::MAX; nodes * self.bodies.len()],
            active: vec![None; nodes],
            multipliers: vec![0.0; nodes],
        };
        self.refresh_features(y, 0.0, &mut state);
        state
    }

    /// The hint of node `p` on body `k`.
    #[inline]
    pub fn hint(&self, state: &ContactState, p: usize, k: usize) -> Option<u32> {
        let h = state.hints[p * self.bodies.len() + k];
        (h != u32::MAX).then_some(h)
    }

    /// Records the features of the nodes near each body at positions `y`,
    /// time `t` (after a converged step).
    pub fn refresh_features(&self, y: &[f64], t: f64, state: &mut ContactState) {
        let nb = self.bodies.len();
        if nb == 0 {
            return;
        }
        let margins: Vec<f64> = self.bodies.iter().map(RigidBody::margin).collect();
        let refresh = |(p, hints): (usize, &mut [u32])| {
            let yp = [y[3 * p], y[3 * p + 1], y[3 * p + 2]];
            for (k, body) in self.bodies.iter().enumerate() {
                if body.far(yp, t, margins[k]) {
                    continue;
                }
                let h = (hints[k] != u32::MAX).then_some(hints[k]);
                hints[k] = body.proximity(yp, t, h).feature;
            }
        };
        if y.len() / 3 >= PARALLEL_NODES_ABOVE {
            state.hints.par_chunks_mut(nb).enumerate().for_each(refresh);
        } else {
            state.hints.chunks_mut(nb).enumerate().for_each(refresh);
        }
    }

    /// Every node–body pair with a gap at or below `threshold` at `y`, time `t`,
    /// using the state's hints: `(node, body, proximity)`; and the smallest
    /// gap of all.
    /// With `exact_min_gap`, every node is queried so that the smallest gap
    /// is exact; otherwise nodes outside the bodies' grown bounding boxes
    /// are skipped and count with the margin (a lower bound of their gap).
    pub fn near_pairs(
        &self,
        y: &[f64],
        t: f64,
        state: &ContactState,
        threshold: f64,
        exact_min_gap: bool,
    ) -> (Vec<(usize, usize, Proximity)>, f64) {
        let nodes = y.len() / 3;
        // Only pairs with a negative gap wanted (the enforcement's
        // searches): a node just outside a bounding box can be skipped,
        // which spares most nodes of a fabric draped over an obstacle the
        // closest-point query.
        let margin_of = if threshold <= 0.0 {
            RigidBody::apart_margin
        } else {
            RigidBody::margin
        };
        let margins: Vec<f64> = self.bodies.iter().map(margin_of).collect();
        let visit = |(mut acc, mut min): (Vec<(usize, usize, Proximity)>, f64), p: usize| {
            let yp = [y[3 * p], y[3 * p + 1], y[3 * p + 2]];
            for (k, body) in self.bodies.iter().enumerate() {
                if !exact_min_gap && body.far(yp, t, margins[k]) {
                    // Outside the box by the margin: the gap is at least
                    // the margin.
                    min = min.min(margins[k]);
                    continue;
                }
                let prox = body.proximity(yp, t, self.hint(state, p, k));
                min = min.min(prox.gap);
                // A node exactly on the surface touches it (issue 46): the
                // penalty gives it its normal stiffness, so that a sheet
                // laid on a plane is not singular in statics.
                if prox.gap <= threshold {
                    acc.push((p, k, prox));
                }
            }
            (acc, min)
        };
        let (pairs, min_gap) = if nodes >= PARALLEL_NODES_ABOVE {
            (0..nodes)
                .into_par_iter()
                .fold(|| (Vec::new(), f64::INFINITY), visit)
                .reduce(
                    || (Vec::new(), f64::INFINITY),
                    |(mut a, ma), (b, mb)| {
                        a.extend(b);
                        (a, ma.min(mb))
                    },
                )
        } else {
            // Two halves, the second on the helper thread (`crate::par`);
            // the pairs stay in node order.
            let mid = nodes / 2;
            let ((mut pairs, a), (rest, b)) = crate::par::join(
                || (0..mid).fold((Vec::new(), f64::INFINITY), visit),
                || (mid..nodes).fold((Vec::new(), f64::INFINITY), visit),
            );
            pairs.extend(rest);
            (pairs, a.min(b))
        };
        // A fixed order, whatever the threads did: sums over pairs are
        // then reproducible to the bit.
        let mut pairs = pairs;
        pairs.sort_unstable_by_key(|(p, k, _)| (*p, *k));
        (pairs, min_gap)
    }

    /// The contact force on the fabric of each node–body pair in contact
    /// at `y`, time `t` (N: `-eta g n` with a penalty, `lambda n` with
    /// multipliers, `state` holding the converged active set and
    /// multipliers), in node order; the penalty's stored energy (J); and
    /// the smallest gap ([`near_pairs`](Self::near_pairs), exact with
    /// `exact_min_gap`).
    fn normal_forces(
        &self,
        y: &[f64],
        t: f64,
        state: &ContactState,
        exact_min_gap: bool,
    ) -> (PairForces, f64, f64) {
        let (pairs, min_gap) = self.near_pairs(y, t, state, 0.0, exact_min_gap);
        let mut energy = 0.0;
        let forces = match self.method {
            ContactMethod::Penalty { stiffness } => pairs
                .into_iter()
                .map(|(p, k, prox)| {
                    energy += 0.5 * stiffness * prox.gap * prox.gap;
                    (p, k, scale(prox.normal, -stiffness * prox.gap))
                })
                .collect(),
            ContactMethod::Lagrange => (state.active.iter().enumerate())
                .filter_map(|(p, held)| {
                    let (k, feature) = (*held)?;
                    let x = [y[3 * p], y[3 * p + 1], y[3 * p + 2]];
                    let (prox, _) = self.bodies[k as usize].constraint(x, t, feature);
                    Some((p, k as usize, scale(prox.normal, state.multipliers[p])))
                })
                .collect(),
        };
        (forces, energy, min_gap)
    }

    /// The work the moving obstacles' normal forces do on the fabric over
    /// a step of `dt` that ended at `y`, time `t` (J): each pair's force at
    /// the step's end dotted with its body's displacement `v dt` over the
    /// step (`d/dt` of the contact potential at fixed positions is
    /// `v . f`). 0 when no obstacle moves, without a search.
    pub fn normal_work(&self, y: &[f64], t: f64, state: &ContactState, dt: f64) -> f64 {
        if self.bodies.iter().all(|b| b.velocity == [0.0; 3]) {
            return 0.0;
        }
        let (forces, _, _) = self.normal_forces(y, t, state, false);
        forces
            .iter()
            .map(|(_, k, f)| dot(*f, scale(self.bodies[*k].velocity, dt)))
            .sum()
    }

    /// The contact report at a converged state. For multipliers, `state`
    /// holds the converged active set and multipliers.
    pub fn report(&self, y: &[f64], t: f64, state: &ContactState) -> ContactReport {
        let nodes = y.len() / 3;
        let mut nodal_forces = vec![[0.0; 3]; nodes];
        let (forces, energy, min_gap) = self.normal_forces(y, t, state, true);
        let active = forces.len();
        for (p, _, f) in forces {
            nodal_forces[p] = add(nodal_forces[p], f);
        }
        let resultant = nodal_forces.iter().fold([0.0; 3], |a, f| add(a, *f));
        ContactReport {
            active,
            resultant,
            min_gap: if self.bodies.is_empty() {
                f64::INFINITY
            } else {
                min_gap
            },
            energy,
            nodal_forces,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::obstacle::{BoxObstacle, Rounded, SphereObstacle};

    /// The enforcement's search (negative gaps only, nodes outside a
    /// bounding box skipped) finds exactly the pairs that querying every
    /// node finds, also for nodes within the touching band of a face with a
    /// hint, above edges and corners, and for a moving obstacle.
    #[test]
    fn skipping_nodes_outside_the_bounding_box_loses_no_contact() {
        let (lo, hi) = ([-0.05, -0.05, -0.25], [0.05, 0.05, -0.05]);
        let sharp = BoxObstacle::new(lo, hi).expect("a box");
        let inner = BoxObstacle::new(lo.map(|v| v + 1e-4), hi.map(|v| v - 1e-4)).expect("a box");
        let model = ContactModel {
            bodies: vec![
                RigidBody {
                    shape: Box::new(sharp),
                    velocity: [0.0; 3],
                },
                RigidBody {
                    shape: Box::new(Rounded::new(inner, 1e-4)),
                    velocity: [0.0, 0.0, -0.2],
                },
                RigidBody {
                    shape: Box::new(SphereObstacle::new([0.2, 0.0, -0.1], 0.05).expect("a sphere")),
                    velocity: [0.1, 0.0, 0.0],
                },
            ],
            method: ContactMethod::Penalty { stiffness: 1e4 },
            friction: 0.0,
            body_friction: Vec::new(),
            stick_speed: DEFAULT_STICK_SPEED,
            features: false,
        };
        // Points on a lattice through the boxes' faces, edges and corners,
        // each also nudged by +-1e-12 m (inside the touching band) and
        // +-1e-3 m.
        let marks = [-0.06, -0.05, -0.02, 0.0, 0.05, 0.06, 0.15, 0.2, 0.25];
        let heights = [-0.3, -0.25, -0.1, -0.05, -0.04, 0.0];
        let nudges = [0.0, 1e-12, -1e-12, 1e-3, -1e-3];
        let mut y = Vec::new();
        for &x in &marks {
            for &yy in &marks {
                for &z in &heights {
                    for &d in &nudges {
                        y.extend_from_slice(&[x + d, yy - d, z + d]);
                    }
                }
            }
        }
        let t = 0.01;
        // Hints from a state a little above (nodes coming down through the
        // top face), as the run loop keeps them.
        let above: Vec<f64> = y
            .chunks(3)
            .flat_map(|p| [p[0], p[1], p[2] + 0.02])
            .collect();
        let state = model.initial_state(&above);
        let (all, _) = model.near_pairs(&y, t, &state, 0.0, true);
        let (skipped, _) = model.near_pairs(&y, t, &state, 0.0, false);
        let key = |v: &[(usize, usize, Proximity)]| -> Vec<(usize, usize, u64)> {
            v.iter()
                .map(|(p, k, prox)| (*p, *k, prox.gap.to_bits()))
                .collect()
        };
        assert_eq!(key(&all), key(&skipped));
        assert!(
            all.len() > 100,
            "the lattice meets the obstacles: {}",
            all.len()
        );
    }

    /// `admit_penetrating` admits each free, inactive node that is inside
    /// an obstacle, on the body it is deepest in, and nothing else; a
    /// second call finds nothing more to admit.
    #[test]
    fn admitting_penetrating_nodes_takes_the_deepest_body_of_free_inactive_nodes() {
        let model = ContactModel {
            bodies: vec![
                RigidBody {
                    shape: Box::new(
                        BoxObstacle::new([-0.05, -0.05, -0.25], [0.05, 0.05, -0.05])
                            .expect("a box"),
                    ),
                    velocity: [0.0; 3],
                },
                RigidBody {
                    shape: Box::new(SphereObstacle::new([0.0, 0.0, -0.1], 0.06).expect("a sphere")),
                    velocity: [0.0; 3],
                },
            ],
            method: ContactMethod::Lagrange,
            friction: 0.0,
            body_friction: Vec::new(),
            stick_speed: DEFAULT_STICK_SPEED,
            features: false,
        };
        let y = [
            0.0, 0.0, 0.01, // 0: above both: free
            0.03, 0.0, -0.051, // 1: 1 mm into the box, 2.6 mm into the sphere
            0.0, 0.0, -0.049, // 2: 9 mm into the sphere, above the box
            0.02, 0.02, -0.06, // 3: inside both, but fixed
            -0.02, 0.0, -0.052, // 4: inside both, already active
        ];
        let mut fixed = vec![false; y.len()];
        fixed[9..12].fill(true);
        let mut state = model.initial_state(&y);
        state.active[4] = Some((0, 7));
        let before = state.active.clone();
        assert!(model.admit_penetrating(&y, 0.0, &mut state, &fixed, 1.0));
        let (pairs, _) = model.near_pairs(&y, 0.0, &state, 0.0, true);
        let deepest = |p: usize| {
            pairs
                .iter()
                .filter(|(q, _, prox)| *q == p && prox.gap < 0.0)
                .min_by(|a, b| a.2.gap.total_cmp(&b.2.gap))
                .map(|(_, k, prox)| (*k as u32, prox.feature))
        };
        assert_eq!(state.active[0], None);
        assert_eq!(state.active[1], deepest(1));
        assert_eq!(
            state.active[1].map(|a| a.0),
            Some(1),
            "deeper in the sphere"
        );
        assert_eq!(state.active[2], deepest(2));
        assert_eq!(state.active[2].map(|a| a.0), Some(1));
        assert_eq!(state.active[3], None, "fixed");
        assert_eq!(state.active[4], before[4], "already active");
        assert!(!model.admit_penetrating(&y, 0.0, &mut state, &fixed, 1.0));
    }
}
