//! Coulomb friction against the obstacles: the smoothed, lagged friction
//! potential of Incremental Potential Contact (Li et al. 2020,
//! "Incremental Potential Contact", ACM TOG 39(4), §5; docs/theory.md
//! §1.8), for penalty contact and for multipliers.
//!
//! For each node `p` in contact with a body at the start of the step, the
//! normal force and the tangent plane are lagged from there: with a
//! penalty, the nodes inside a body (`g < 0` at the start positions `x`),
//! pressed by `eta |g|`; with multipliers, the nodes of the active set,
//! pressed by their multiplier — the normal force the constraint exerted
//! at the end of the step before (a node that enters the set feels
//! friction from its second step in contact, as a penalty node that
//! enters does):
//!
//! ```text
//! lambda_p = eta |g_p(x)|  or  lambda_p         normal force (N)
//! T_p      = I - n n^T                          tangent projector, n the normal at x
//! u_p      = T_p (y_p - x_p - v h)              tangential slip over the step (m),
//!                                               v the body's velocity
//! D(Y)     = sum_p mu lambda_p f0(|u_p|)        (J)
//! f0(s)    = -s^3 / (3 e^2) + s^2 / e + e / 3   s < e = eps_v h
//!          = s                                  s >= e
//! ```
//!
//! `f1 = f0'` rises from 0 at no slip to 1 at the slip `eps_v h`: below
//! the slip speed `eps_v` friction is a stiff viscous resistance (the
//! fabric creeps at most at `eps_v`), above it Coulomb's force `mu lambda`
//! against the slip. `f0` is C^1 and convex on `s >= 0`, so each node's
//! 3x3 Hessian
//!
//! ```text
//! dD/dy_p   = mu lambda f1(s) u / s
//! d2D/dy_p2 = mu lambda [ f1(s)/s T + (f1'(s) - f1(s)/s) u u^T / s^2 ]
//!           = mu lambda [ (2/e - s/e^2) T - (s/e^2) û û^T ]     s < e
//!           = mu lambda / s [ T - û û^T ]                       s >= e
//! ```
//!
//! (`û = u / s`) is positive semi-definite: nothing to project. The lag
//! (one per step: the normal force and the tangent plane of the step's
//! start) makes `D` a potential of the step, so the line search and the
//! projected Newton apply. The work friction does against the slip over
//! the step, `mu lambda f1(s) s` a node, is the energy it dissipates.
//!
//! A static load increment (`integrator::statics`) is the step from the
//! increment's start, its load factor standing for the time (so `h` is
//! the increment and the smoothing slip `eps_v h`), and lags the normal
//! force in rounds — the lagged iterations of Li et al. 2020, §5: a
//! first round in which the nodes touching an obstacle at the start
//! stick ([`FrictionTerm::stick`]), then rounds whose normal force and
//! tangent plane are the previous round's solution's
//! ([`FrictionTerm::lagged_at`]), the slip still measured from the
//! increment's start. Sticking, a node is held by a spring along the
//! tangent plane:
//!
//! ```text
//! S(Y)      = sum_p 1/2 k_p |u_p|^2,  dS/dy_p = k_p u_p,  d2S/dy_p2 = k_p T_p
//! k_p       = eta                   penalty: the contact's own stiffness
//!           = 2 mu lambda_p / e     multipliers: Coulomb's at no slip
//! ```
//!
//! which dissipates nothing: it only finds the normal forces the load
//! increment brings, which a normal force lagged from the start lacks
//! (from an unloaded start it has none).

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use crate::contact::{ContactMethod, ContactModel, ContactState, mollifier};
use crate::solver::SparsePattern;
use crate::vec3::dot;

/// A node in contact at the start of the step, with what is lagged.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Lagged {
    node: usize,
    /// `mu lambda` (N); sticking, the spring's stiffness `k` (N/m).
    force: f64,
    /// The unit normal at the start.
    normal: [f64; 3],
    /// Where the node would be with no slip: its start position carried
    /// by the body's motion over the step (m).
    anchor: [f64; 3],
    /// The body's displacement over the step, `v h` (m).
    carried: [f64; 3],
}

/// What the pairs' `force` stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Law {
    /// Coulomb's smoothed friction, `force` = `mu lambda`.
    Coulomb,
    /// Sticking (a static increment's first round), `force` = `k`.
    Stick,
}

/// The friction potential of a step.
pub struct FrictionTerm<'a> {
    pattern: &'a SparsePattern,
    pairs: Vec<Lagged>,
    law: Law,
    /// `eps_v h` (m): the slip below which friction is viscous.
    smooth: f64,
    /// Dissipation at the last evaluation (J).
    dissipated: f64,
    /// The moving bodies' work through friction at the last evaluation (J).
    worked: f64,
}

impl<'a> FrictionTerm<'a> {
    /// The friction of `contact` over the step of size `dt` from positions
    /// `start` at time `t0`, whose contact state is `state`: the pairs in
    /// contact at the start, lagged (the module docs: penalty pairs by
    /// their depth, multipliers' by the multiplier `state` holds).
    pub fn new(
        contact: &ContactModel,
        pattern: &'a SparsePattern,
        (start, t0, dt): (&[f64], f64, f64),
        state: &ContactState,
    ) -> Self {
        Self::lagged_at(contact, pattern, (start, t0), (start, dt), state)
    }

    /// The friction of `contact` over the step of size `dt` from positions
    /// `start`, its normal forces and tangent planes lagged at positions
    /// `at`, time `t`, whose contact state is `state` (a static round's:
    /// the previous round's solution, module docs); the slip measured
    /// from `start`.
    pub fn lagged_at(
        contact: &ContactModel,
        pattern: &'a SparsePattern,
        (at, t): (&[f64], f64),
        (start, dt): (&[f64], f64),
        state: &ContactState,
    ) -> Self {
        let lagged = |p: usize, k: usize, lambda: f64, normal: [f64; 3]| {
            let v = contact.bodies[k].velocity;
            Lagged {
                node: p,
                force: contact.friction_of(k) * lambda,
                normal,
                anchor: std::array::from_fn(|i| start[3 * p + i] + v[i] * dt),
                carried: v.map(|v| v * dt),
            }
        };
        let pairs = match contact.method {
            ContactMethod::Penalty { stiffness } => {
                let (near, _) = contact.near_pairs(at, t, state, 0.0, false);
                near.into_iter()
                    .filter(|&(_, k, _)| contact.friction_of(k) > 0.0)
                    .map(|(p, k, prox)| lagged(p, k, stiffness * (-prox.gap), prox.normal))
                    .collect()
            }
            ContactMethod::Lagrange => (state.active.iter().enumerate())
                .filter_map(|(p, held)| {
                    let (k, face) = (*held)?;
                    let (k, lambda) = (k as usize, state.multipliers[p]);
                    (contact.friction_of(k) > 0.0 && lambda > 0.0).then(|| {
                        let x = [at[3 * p], at[3 * p + 1], at[3 * p + 2]];
                        let (prox, _) = contact.bodies[k].constraint(x, t, face);
                        lagged(p, k, lambda, prox.normal)
                    })
                })
                .collect(),
        };
        Self {
            pattern,
            pairs,
            law: Law::Coulomb,
            smooth: contact.stick_speed * dt,
            dissipated: 0.0,
            worked: 0.0,
        }
    }

    /// A static increment's first round (module docs): over the increment
    /// `dt` from positions `start` at load factor `t0`, whose contact state
    /// is `state`, every node touching an obstacle with friction — a
    /// penalty node closer than the smoothing slip `eps_v dt`, a node of
    /// the multipliers' active set pressed by its multiplier — sticks, held
    /// along the tangent plane by a spring (`eta`, or `2 mu lambda / e`);
    /// with multipliers, a node touching an obstacle (closer than `eps_v
    /// dt`) with no multiplier yet sticks by a spring of `membrane` (N/m,
    /// the membrane's stiffness [`crate::model::Model::membrane_stiffness`]).
    pub fn stick(
        contact: &ContactModel,
        pattern: &'a SparsePattern,
        (start, t0, dt): (&[f64], f64, f64),
        state: &ContactState,
        membrane: f64,
    ) -> Self {
        let smooth = contact.stick_speed * dt;
        let mut term = match contact.method {
            ContactMethod::Penalty { stiffness } => {
                let (near, _) = contact.near_pairs(start, t0, state, smooth, false);
                let pairs = near
                    .into_iter()
                    .filter(|&(_, k, _)| contact.friction_of(k) > 0.0)
                    .map(|(p, k, prox)| {
                        let v = contact.bodies[k].velocity;
                        Lagged {
                            node: p,
                            force: stiffness,
                            normal: prox.normal,
                            anchor: std::array::from_fn(|i| start[3 * p + i] + v[i] * dt),
                            carried: v.map(|v| v * dt),
                        }
                    })
                    .collect();
                Self {
                    pattern,
                    pairs,
                    law: Law::Coulomb,
                    smooth,
                    dissipated: 0.0,
                    worked: 0.0,
                }
            }
            ContactMethod::Lagrange => {
                let mut term = Self::new(contact, pattern, (start, t0, dt), state);
                for pair in &mut term.pairs {
                    pair.force *= 2.0 / smooth;
                }
                // A node touching an obstacle with no multiplier yet — every
                // node of a first increment, which starts unloaded (issue
                // 46) — is held by a spring as stiff as the membrane.
                let mut held = vec![false; start.len() / 3];
                for pair in &term.pairs {
                    held[pair.node] = true;
                }
                let (near, _) = contact.near_pairs(start, t0, state, smooth, false);
                for (p, k, prox) in near {
                    if contact.friction_of(k) > 0.0 && !std::mem::replace(&mut held[p], true) {
                        let v = contact.bodies[k].velocity;
                        term.pairs.push(Lagged {
                            node: p,
                            force: membrane,
                            normal: prox.normal,
                            anchor: std::array::from_fn(|i| start[3 * p + i] + v[i] * dt),
                            carried: v.map(|v| v * dt),
                        });
                    }
                }
                term.pairs.sort_by_key(|pair| pair.node);
                term
            }
        };
        term.law = Law::Stick;
        term
    }

    /// The nodes of the pairs with their `mu lambda` (N; sticking, their
    /// springs' stiffness), in node order: what a static round compares
    /// with the next round's lag.
    pub fn forces(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.pairs.iter().map(|p| (p.node, p.force))
    }

    /// Sticking, the tangential force the springs carry at `y` (N, summed
    /// over the nodes): what the contact must hold by friction; 0 for
    /// Coulomb's law.
    pub fn stick_force(&self, y: &[f64]) -> f64 {
        if self.law != Law::Stick {
            return 0.0;
        }
        self.pairs
            .iter()
            .map(|pair| {
                let u = self.slip(pair, y);
                pair.force * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt()
            })
            .sum()
    }

    /// The pair's tangential slip `u = T (y_p - anchor)` at `y` (m).
    fn slip(&self, pair: &Lagged, y: &[f64]) -> [f64; 3] {
        let (p, n) = (pair.node, pair.normal);
        let d: [f64; 3] = std::array::from_fn(|i| y[3 * p + i] - pair.anchor[i]);
        let dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
        std::array::from_fn(|i| d[i] - dn * n[i])
    }

    /// The energy friction dissipates over the step, at the last
    /// evaluation (J).
    pub fn dissipated(&self) -> f64 {
        self.dissipated
    }
}

impl StepTerm for FrictionTerm<'_> {
    fn name(&self) -> &'static str {
        "friction"
    }

    fn stencils(&self) -> Stencils<'_> {
        Stencils::Nodes
    }

    fn add(
        &mut self,
        _ctx: &StepContext,
        y: &[f64],
        g: &mut [f64],
        mut h: Option<&mut [f64]>,
    ) -> TermValue {
        if self.law == Law::Stick {
            return self.add_stick(y, g, h);
        }
        let e = self.smooth;
        let (mut energy, mut dissipated, mut scale, mut worked) = (0.0, 0.0, 0.0, 0.0);
        for pair in &self.pairs {
            let p = pair.node;
            let n = pair.normal;
            let u = self.slip(pair, y);
            let s = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
            let (f0, f1, df1) = mollifier(s, e);
            let mu_lambda = pair.force;
            energy += mu_lambda * f0;
            dissipated += mu_lambda * f1 * s;
            scale += mu_lambda * f1;
            if s > 0.0 {
                for i in 0..3 {
                    g[3 * p + i] += mu_lambda * f1 * u[i] / s;
                }
                // The force on the node is -mu lambda f1 u / s.
                worked -= mu_lambda * f1 / s * dot(u, pair.carried);
            }
            if let Some(h) = h.as_deref_mut() {
                // f1 / s, and (f1' - f1 / s) / s^2 multiplying u u^T; at
                // s = 0 (no slip yet) the limits 2 / e and 0.
                let (a, b) = if s > 0.0 {
                    (f1 / s, (df1 - f1 / s) / (s * s))
                } else {
                    (2.0 / e, 0.0)
                };
                self.add_block(h, (p, n, u), (mu_lambda, a, b));
            }
        }
        self.dissipated = dissipated;
        self.worked = worked;
        TermValue {
            value: energy,
            potential: true,
            scale,
        }
    }

    fn dissipation(&self) -> f64 {
        self.dissipated
    }

    fn obstacle_work(&self) -> f64 {
        self.worked
    }
}

impl FrictionTerm<'_> {
    /// Adds `c (a T + b u u^T)` to node `p`'s diagonal block of `h`, `T =
    /// I - n n^T` the tangent projector of the normal `n`, `u` the slip.
    fn add_block(
        &self,
        h: &mut [f64],
        (p, n, u): (usize, [f64; 3], [f64; 3]),
        (c, a, b): (f64, f64, f64),
    ) {
        let block = self
            .pattern
            .node_block(p, p)
            .expect("diagonal blocks are in the pattern");
        for i in 0..3 {
            for j in 0..3 {
                let t = f64::from(u8::from(i == j)) - n[i] * n[j];
                h[self.pattern.entry(block, p, i, j)] += c * (a * t + b * u[i] * u[j]);
            }
        }
    }

    /// [`StepTerm::add`] sticking: `1/2 k |u|^2` a pair (module docs),
    /// which dissipates nothing.
    fn add_stick(&mut self, y: &[f64], g: &mut [f64], mut h: Option<&mut [f64]>) -> TermValue {
        let (mut energy, mut scale, mut worked) = (0.0, 0.0, 0.0);
        for pair in &self.pairs {
            let (p, n, k) = (pair.node, pair.normal, pair.force);
            let u = self.slip(pair, y);
            let s2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
            energy += 0.5 * k * s2;
            worked -= k * dot(u, pair.carried);
            scale += k * s2.sqrt();
            for i in 0..3 {
                g[3 * p + i] += k * u[i];
            }
            if let Some(h) = h.as_deref_mut() {
                self.add_block(h, (p, n, u), (k, 1.0, 0.0));
            }
        }
        self.dissipated = 0.0;
        self.worked = worked;
        TermValue {
            value: energy,
            potential: true,
            scale,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::terms::{check_projection, check_term, contact_patch};

    /// A 10 cm patch of 4 x 4 squares pressed 1 mm (vertically) into a
    /// plane tilted about y, moving along x at 1 cm/s, with friction 0.4
    /// and a slip speed of 1e-3 m/s, over a step of 10 ms from its start
    /// (the smoothing slip is 1e-5 m), contact by `method` (`[contact]`'s
    /// keys but friction's).
    fn pressed_patch_by(method: &str) -> (crate::setup::Setup, Vec<f64>) {
        let contact = format!(
            "[[obstacle]]\nshape = \"plane\"\npoint = [0.0, 0.0, -0.1]\nnormal = [-0.3, 0.0, 1.0]\n\
             velocity = [0.01, 0.0, 0.0]\n[contact]\n{method}\nfriction = 0.4\nstick_speed = 1.0e-3"
        );
        let setup = contact_patch(&contact, 1e-2);
        // Every node 1 mm below the tilted plane.
        let start = setup
            .model
            .initial_positions()
            .chunks(3)
            .flat_map(|x| [x[0], x[1], -0.1 + 0.3 * x[0] - 1e-3])
            .collect();
        (setup, start)
    }

    /// [`pressed_patch_by`] with a penalty of 5e4 N/m.
    fn pressed_patch() -> (crate::setup::Setup, Vec<f64>) {
        pressed_patch_by("method = \"penalty\"\npenalty = 5.0e4")
    }

    /// The friction term of [`pressed_patch`] over a 10 ms step from
    /// `start`, and the contact state it was lagged from.
    fn lagged<'a>(
        setup: &'a crate::setup::Setup,
        start: &[f64],
    ) -> (FrictionTerm<'a>, crate::contact::ContactState) {
        let model = &setup.model;
        let contact = model.contact().expect("an obstacle");
        let state = contact.initial_state(start);
        let term = FrictionTerm::new(contact, model.pattern(), (start, 0.0, 1e-2), &state);
        (term, state)
    }

    /// Value, gradient and Hessian against central differences, with the
    /// nodes slipped from their anchors by a spread of amounts: some
    /// below the smoothing slip (viscous), some above (Coulomb), one not
    /// at all; and the Hessian semi-definite, so that its projection is
    /// itself. Steps of 1e-9 m against slips from 3e-6 to 1e-3 m.
    #[test]
    fn friction_term_matches_finite_differences() {
        let (setup, start) = pressed_patch();
        let model = &setup.model;
        let (mut term, state) = lagged(&setup, &start);
        assert_eq!(term.pairs.len(), 25, "every node in contact");
        // The anchors moved with the plane by 1e-4 m along x.
        let y: Vec<f64> = start
            .chunks(3)
            .enumerate()
            .flat_map(|(a, x)| {
                let slip = if a == 12 {
                    0.0
                } else {
                    3e-6 * (a as f64).powf(1.5)
                };
                [
                    x[0] + 1e-4 + slip,
                    x[1] - 0.5 * slip,
                    x[2] + 0.3 * (1e-4 + slip),
                ]
            })
            .collect();
        let ctx = StepContext {
            time: 1e-2,
            contact: Some(&state),
            project: None,
        };
        let (eh, eg) = check_term(&mut term, &ctx, model.pattern(), &y, 1e-9);
        assert!(eh < 1e-6, "Hessian {eh:e}");
        assert!(eg < 1e-6, "gradient {eg:e}");
        let (exact, projected, smallest) = check_projection(&mut term, &ctx, model.pattern(), &y);
        assert!(smallest > -1e-12, "smallest eigenvalue {smallest:e}");
        assert_eq!(exact, projected);
        let mut g = vec![0.0; y.len()];
        term.add(&ctx, &y, &mut g, None);
        assert!(term.dissipated() > 0.0);
    }

    /// A static increment's terms (module docs) against central
    /// differences: the stick round's springs (every node of the patch
    /// within the smoothing slip of the plane at the start), and Coulomb's
    /// friction lagged at other positions than the start the slip is
    /// measured from; both Hessians semi-definite. Slips as in
    /// [`friction_term_matches_finite_differences`].
    #[test]
    fn static_rounds_match_finite_differences() {
        let (setup, start) = pressed_patch();
        let model = &setup.model;
        let contact = model.contact().expect("an obstacle");
        let state = contact.initial_state(&start);
        let y: Vec<f64> = start
            .iter()
            .enumerate()
            .map(|(i, x)| x + 2e-5 * ((i as f64) * 0.7).sin())
            .collect();
        let at: Vec<f64> = start.iter().map(|x| x - 2e-4).collect();
        let terms = [
            FrictionTerm::stick(contact, model.pattern(), (&start, 0.0, 1e-2), &state, 1.0e3),
            FrictionTerm::lagged_at(
                contact,
                model.pattern(),
                (&at, 1e-2),
                (&start, 1e-2),
                &state,
            ),
        ];
        for (k, mut term) in terms.into_iter().enumerate() {
            assert_eq!(term.pairs.len(), 25, "term {k}: every node");
            let ctx = StepContext {
                time: 1e-2,
                contact: Some(&state),
                project: None,
            };
            let (eh, eg) = check_term(&mut term, &ctx, model.pattern(), &y, 1e-9);
            assert!(
                eh < 1e-6 && eg < 1e-6,
                "term {k}: Hessian {eh:e}, gradient {eg:e}"
            );
            let (exact, projected, smallest) =
                check_projection(&mut term, &ctx, model.pattern(), &y);
            assert!(
                smallest > -1e-12,
                "term {k}: smallest eigenvalue {smallest:e}"
            );
            assert_eq!(exact, projected);
        }
    }

    /// With multipliers the lagged normal force is the multiplier of the
    /// step before, on the nodes of the active set only (a node of the
    /// set whose multiplier is 0 feels none), and the tangent plane the
    /// face the node is held on: each pair's `mu lambda`, its normal the
    /// plane's.
    #[test]
    fn with_multipliers_the_normal_force_is_the_multiplier() {
        let (setup, start) = pressed_patch_by("method = \"lagrange\"");
        let model = &setup.model;
        let contact = model.contact().expect("an obstacle");
        let mut state = contact.initial_state(&start);
        for (p, lambda) in [(3, 0.25), (7, 0.0), (12, 1.5)] {
            let x = [start[3 * p], start[3 * p + 1], start[3 * p + 2]];
            let face = contact.bodies[0].proximity(x, 0.0, None).feature;
            state.active[p] = Some((0, face));
            state.multipliers[p] = lambda;
        }
        let term = FrictionTerm::new(contact, model.pattern(), (&start, 0.0, 1e-2), &state);
        let len = (1.0f64 + 0.09).sqrt();
        let normal = [-0.3 / len, 0.0, 1.0 / len];
        let pairs: Vec<(usize, f64)> = term.pairs.iter().map(|l| (l.node, l.force)).collect();
        assert_eq!(pairs, [(3, 0.4 * 0.25), (12, 0.4 * 1.5)]);
        for pair in &term.pairs {
            let off = (0..3)
                .map(|i| (pair.normal[i] - normal[i]).abs())
                .fold(0.0, f64::max);
            assert!(off < 1e-15, "normal {:?}", pair.normal);
        }
    }

    /// Sliding well above the smoothing slip, each node's friction force
    /// is Coulomb's, `mu lambda`, against the slip: the gradient's
    /// magnitude is 0.4 x 5e4 x 1e-3 N = 20 N, whatever the slip.
    #[test]
    fn sliding_friction_is_coulombs_force() {
        let (setup, start) = pressed_patch();
        let (mut term, state) = lagged(&setup, &start);
        let len = (1.0f64 + 0.09).sqrt();
        let (nx, nz) = (-0.3 / len, 1.0 / len);
        let lambda = 5.0e4 * 1e-3 * nz;
        for slip in [1e-4, 1e-2] {
            // Along the plane's slope, beyond the plane's own motion.
            let y: Vec<f64> = start
                .chunks(3)
                .flat_map(|x| [x[0] + 1e-4 + slip * nz, x[1], x[2] - slip * nx])
                .collect();
            let mut g = vec![0.0; y.len()];
            let ctx = StepContext {
                time: 1e-2,
                contact: Some(&state),
                project: None,
            };
            term.add(&ctx, &y, &mut g, None);
            for f in g.chunks(3) {
                let norm = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
                assert!(
                    (norm - 0.4 * lambda).abs() < 1e-9 * lambda,
                    "{norm} at slip {slip}"
                );
            }
        }
    }
}
