//! Lagrange-multiplier enforcement: `g = 0` exactly for the active
//! node–body pairs, `lambda >= 0` their compressive contact forces.
//!
//! # How the constraint is imposed: exact elimination in a local basis
//!
//! For an active node `p` with gap `g`, outward normal `n` and tangents
//! `t1, t2` (`Q = [t1 t2 n]`, orthonormal), the constrained Newton step of
//! the Lagrangian `Pi(Y) - sum_p lambda_p g_p(Y)` is
//!
//! ```text
//! (H - lambda_p dn/dy at p) dY = -G,   with  n . dY_p = -g   imposed,
//! lambda_p = n . G_p                 (the node's out-of-balance force along n)
//! ```
//!
//! It is solved by rotating node `p`'s unknowns into `Q` (`H <- Q^T H Q`,
//! `G <- Q^T G`, block-wise on the sparse pattern, which does not change)
//! and eliminating the normal unknown as a prescribed increment `-g`: its
//! column times `-g` moves to the right-hand side, its row and column are
//! replaced by `k e_n` with `k` the node's mean diagonal stiffness, and its
//! residual entry becomes `k g`. The rotated system stays symmetric, so
//! Cholesky still applies; no unknowns are added and the pattern, hence the
//! symbolic factorisation, never changes with the active set. The increment
//! is rotated back before the update. On a flat face the constraint is
//! linear and `g = 0` holds to round-off after one iteration; on a curved
//! one Newton drives it to zero quadratically, with the curvature term
//! `-lambda dn/dy` in the tangent.
//!
//! # Active set
//!
//! A pair enters when its gap is negative, `g < -1e-12 L` (`L` the
//! reference length `|X|` of Newton's test), on the face its proximity reports (the face it came in by); it
//! is then held on that face's surface ([`super::Obstacle::constraint`]:
//! the plane of a box face, so the constraint stays smooth up to the
//! edges). It leaves when its multiplier is negative, `lambda < -1e-9
//! lambda_max`, or when it has slid off its face over an edge (it is then
//! outside the obstacle and free); both are checked after Newton has converged, and the step
//! is solved again until the set no longer changes (a step converges only
//! with a stable active set). A set that keeps changing for
//! [`MAX_ACTIVE_SET_ROUNDS`] rounds fails the step, which is then cut back.
//! Each step starts from the set of the step before with the nodes that
//! penetrate at the predictor admitted
//! ([`ContactModel::admit_penetrating`]), and the set is revised by the
//! same rule after each of the first Newton steps that change it, up to
//! [`REVISIONS_IN_NEWTON`] times, Newton then going on with the new set
//! from where it is (a primal–dual active-set strategy within Newton;
//! the check after convergence stays the arbiter, and the bound keeps a
//! node from switching back and forth within one solution). A set that
//! Newton's early iterates already show need not wait for convergence
//! and a whole new solution (what each saves on the pedestal with
//! multipliers: docs/performance.md).

use super::{ContactModel, ContactState, Proximity};
use crate::solver::SparsePattern;
use crate::vec3::{cross, dot, norm, scale};
use crate::vecn;

/// Most re-solutions of one step for a changing active set.
pub const MAX_ACTIVE_SET_ROUNDS: usize = 20;

/// Most revisions of the active set between the Newton steps of one
/// solution (see the module docs).
pub const REVISIONS_IN_NEWTON: usize = 2;

/// An active node during one Newton iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActiveNode {
    /// Node index.
    pub node: usize,
    /// Whether the node still lies on the face it is held on.
    pub on_face: bool,
    /// Its constraint: gap, normal and curvature of the face it is held on.
    pub proximity: Proximity,
    /// Local basis, rows `t1`, `t2`, `n`.
    pub frame: [[f64; 3]; 3],
    /// Elimination scale `k` (N/m).
    pub scale: f64,
    /// Multiplier estimate `n . G_p` (N).
    pub multiplier: f64,
}

/// An orthonormal basis `[t1, t2, n]` (rows) around the unit normal `n`:
/// `t1` the coordinate axis least aligned with `n`, made orthogonal to it,
/// and `t2 = n x t1`. For `n = e_z` (a node on the top of a box, on a
/// floor) this is the identity, which [`ContactModel::impose_lagrange`]
/// then does not apply.
pub fn frame(n: [f64; 3]) -> [[f64; 3]; 3] {
    if n == IDENTITY[2] {
        // (What the construction below gives for it, without a square root
        // and a division per active node and evaluation.)
        return IDENTITY;
    }
    let axis = if n[0].abs() <= n[1].abs() && n[0].abs() <= n[2].abs() {
        [1.0, 0.0, 0.0]
    } else if n[1].abs() <= n[2].abs() {
        [0.0, 1.0, 0.0]
    } else {
        [0.0, 0.0, 1.0]
    };
    let along = dot(axis, n);
    let t1 = [0, 1, 2].map(|i| axis[i] - along * n[i]);
    let t1 = scale(t1, 1.0 / norm(t1));
    let t2 = cross(n, t1);
    [t1, t2, n]
}

/// The frame of the normal `e_z`, which leaves a node's unknowns as they are.
const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

impl ContactModel {
    /// The active nodes of `state` at positions `y`, time `t`, with their
    /// proximities and frames (scales and multipliers still to be filled).
    /// Nodes with a fixed component are never held by contact.
    pub fn active_nodes(
        &self,
        y: &[f64],
        t: f64,
        state: &ContactState,
        fixed: &[bool],
    ) -> Vec<ActiveNode> {
        let mut out = Vec::new();
        for (p, held) in state.active.iter().enumerate() {
            let Some((k, feature)) = *held else { continue };
            if fixed[3 * p] || fixed[3 * p + 1] || fixed[3 * p + 2] {
                continue;
            }
            let (prox, on_face) = self.bodies[k as usize].constraint(
                [y[3 * p], y[3 * p + 1], y[3 * p + 2]],
                t,
                feature,
            );
            out.push(ActiveNode {
                node: p,
                on_face,
                proximity: prox,
                frame: frame(prox.normal),
                scale: 1.0,
                multiplier: 0.0,
            });
        }
        out
    }

    /// Imposes the active constraints on the residual `g` and, if given, the
    /// Hessian `h` (see the module documentation). `g` must hold the
    /// residual without contact, supports already applied. With `h`, the
    /// nodes' scales are (re)computed; without, the previous ones are used.
    ///
    /// Returns the merit norm: `|G|` of the rotated residual with the
    /// normal entries `k g`, before the right-hand-side corrections of the
    /// prescribed increments (which are not residuals).
    pub fn impose_lagrange(
        active: &mut [ActiveNode],
        g: &mut [f64],
        h: Option<(&mut [f64], &SparsePattern)>,
    ) -> f64 {
        for a in active.iter_mut() {
            let p = a.node;
            let gp = [g[3 * p], g[3 * p + 1], g[3 * p + 2]];
            a.multiplier = dot(a.proximity.normal, gp);
        }
        let Some((h, pattern)) = h else {
            for a in active.iter().filter(|a| a.frame != IDENTITY) {
                rotate_residual(a, g);
            }
            for a in active.iter() {
                g[3 * a.node + 2] = a.scale * a.proximity.gap;
            }
            return vecn::norm(g);
        };
        let (ptr, rows) = pattern.node_graph();
        // Curvature of the constraint, then the scale, on the diagonal block.
        for a in active.iter_mut() {
            let p = a.node;
            let d = pattern.node_block(p, p).expect("diagonal block");
            let dn = a.proximity.normal_derivative;
            for i in 0..3 {
                for j in 0..3 {
                    h[pattern.entry(d, p, i, j)] -= a.multiplier * dn[i][j];
                }
            }
            a.scale = (0..3).map(|i| h[pattern.entry(d, p, i, i)]).sum::<f64>() / 3.0;
            if a.scale.is_nan() || a.scale <= 0.0 {
                a.scale = 1.0;
            }
        }
        // H <- Q^T H Q: right-multiply column block p, left-multiply row block p.
        // (Blocks located once each: entry (i, j) of a block at
        // `base + j stride + i`; block (p, b) found as the mirror of block
        // (b, p)'s first entry, no search.) Nothing to do for `Q = I`.
        for a in active.iter().filter(|a| a.frame != IDENTITY) {
            let p = a.node;
            let q = a.frame;
            let (_, stride_p) = pattern.block_layout(ptr[p], p);
            for k in ptr[p]..ptr[p + 1] {
                // Block (b, p): columns j of node p; new column j = sum_m H[:, m] q[j][m].
                let (base, _) = pattern.block_layout(k, p);
                for i in 0..3 {
                    let old: [f64; 3] = [0, 1, 2].map(|m| h[base + m * stride_p + i]);
                    for j in 0..3 {
                        h[base + j * stride_p + i] = dot(old, q[j]);
                    }
                }
            }
            for k in ptr[p]..ptr[p + 1] {
                // Block (p, b) in column b.
                let b = rows[k];
                let base = pattern.transpose_of(pattern.block_layout(k, p).0);
                let (_, stride_b) = pattern.block_layout(ptr[b], b);
                for j in 0..3 {
                    let old: [f64; 3] = [0, 1, 2].map(|m| h[base + j * stride_b + m]);
                    for i in 0..3 {
                        h[base + j * stride_b + i] = dot(q[i], old);
                    }
                }
            }
            rotate_residual(a, g);
        }
        for a in active.iter() {
            g[3 * a.node + 2] = a.scale * a.proximity.gap;
        }
        let merit = vecn::norm(g);
        // Eliminate each normal unknown as the prescribed increment -gap.
        for a in active.iter() {
            let d = 3 * a.node + 2;
            let gap = a.proximity.gap;
            for k in pattern.col_ptr[d]..pattern.col_ptr[d + 1] {
                let r = pattern.row_idx[k];
                if r != d {
                    g[r] -= h[k] * gap;
                }
                h[k] = 0.0;
                h[pattern.transpose_of(k)] = 0.0;
            }
            h[pattern.diagonal_of(d)] = a.scale;
            g[d] = a.scale * gap;
        }
        merit
    }

    /// Rotates the increments of the active nodes back from their local bases.
    pub fn rotate_back(active: &[ActiveNode], dy: &mut [f64]) {
        for a in active.iter().filter(|a| a.frame != IDENTITY) {
            let p = a.node;
            let z = [dy[3 * p], dy[3 * p + 1], dy[3 * p + 2]];
            for i in 0..3 {
                dy[3 * p + i] = a.frame[0][i] * z[0] + a.frame[1][i] * z[1] + a.frame[2][i] * z[2];
            }
        }
    }

    /// After Newton has converged with `active`: stores the multipliers,
    /// releases pairs whose multiplier is negative and admits penetrating
    /// pairs. Returns whether the set changed.
    pub fn update_active_set(
        &self,
        y: &[f64],
        t: f64,
        state: &mut ContactState,
        active: &[ActiveNode],
        fixed: &[bool],
        length: f64,
    ) -> bool {
        state.multipliers.iter_mut().for_each(|m| *m = 0.0);
        let lambda_max = active
            .iter()
            .map(|a| a.multiplier.abs())
            .fold(0.0, f64::max);
        let mut changed = false;
        for a in active {
            if a.multiplier < -1e-9 * lambda_max || !a.on_face {
                state.active[a.node] = None;
                changed = true;
            } else {
                state.multipliers[a.node] = a.multiplier.max(0.0);
            }
        }
        changed |= self.admit_penetrating(y, t, state, fixed, length);
        changed
    }

    /// Admits into the active set each free node that penetrates an
    /// obstacle at `y` and is not active yet, on the face of the body it
    /// penetrates deepest. Returns whether the set changed.
    pub fn admit_penetrating(
        &self,
        y: &[f64],
        t: f64,
        state: &mut ContactState,
        fixed: &[bool],
        length: f64,
    ) -> bool {
        let mut changed = false;
        let (pairs, _) = self.near_pairs(y, t, state, -1e-12 * length, false);
        // The most penetrated body of each node.
        let mut deepest: std::collections::BTreeMap<usize, (usize, u32, f64)> = Default::default();
        for (p, k, prox) in pairs {
            if fixed[3 * p] || fixed[3 * p + 1] || fixed[3 * p + 2] {
                continue;
            }
            let e = deepest.entry(p).or_insert((k, prox.feature, prox.gap));
            if prox.gap < e.2 {
                *e = (k, prox.feature, prox.gap);
            }
        }
        let deepest = deepest.into_iter().map(|(p, (k, f, _))| (p, (k, f)));
        for (p, (k, feature)) in deepest {
            if state.active[p].is_none() {
                state.active[p] = Some((k as u32, feature));
                changed = true;
            }
        }
        changed
    }
}

fn rotate_residual(a: &ActiveNode, g: &mut [f64]) {
    let p = a.node;
    let gp = [g[3 * p], g[3 * p + 1], g[3 * p + 2]];
    for i in 0..3 {
        g[3 * p + i] = dot(a.frame[i], gp);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames are orthonormal and right-handed with `n` last; `e_z` gets
    /// the identity (whose rotation `impose_lagrange` skips).
    #[test]
    fn frames_are_orthonormal_and_the_identity_for_e_z() {
        assert_eq!(frame([0.0, 0.0, 1.0]), IDENTITY);
        let normals = [
            [0.0, 0.0, -1.0],
            [1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.6, 0.0, 0.8],
            [-0.48, 0.6, 0.64],
            [1e-9, 1.0, -1e-9],
        ];
        for n in normals {
            let n = scale(n, 1.0 / norm(n));
            let q = frame(n);
            assert_eq!(q[2], n);
            for i in 0..3 {
                for j in 0..3 {
                    let expected = if i == j { 1.0 } else { 0.0 };
                    assert!((dot(q[i], q[j]) - expected).abs() < 1e-15, "{n:?}");
                }
            }
            let c = cross(q[0], q[1]);
            assert!(
                (0..3).all(|i| (c[i] - n[i]).abs() < 1e-15),
                "{n:?}: left-handed"
            );
        }
    }
}
