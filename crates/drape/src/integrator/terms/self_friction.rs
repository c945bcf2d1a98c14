//! Friction between the fabric's own layers
//! ([`crate::contact::self_contact`], "Friction"): for each pair closer
//! than `d̂` at the step's start, the closest points' weights, the normal
//! and the barrier's normal force lagged from there, and the pair's
//! tangential slip over the step costing `mu lambda f0(|u|)` — the
//! smoothed, lagged friction of Incremental Potential Contact (Li et al.
//! 2020, §5), the obstacles' ([`super::FrictionTerm`]) between two moving
//! surfaces. Its Hessian is positive semi-definite: nothing to project.

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use crate::contact::self_contact::{LaggedPair, SelfContact, add_friction};
use crate::solver::SparsePattern;

/// Friction between the fabric's layers over one step.
pub struct SelfFrictionTerm<'a> {
    pattern: &'a SparsePattern,
    start: &'a [f64],
    pairs: Vec<LaggedPair>,
    /// `eps_v h` (m): the slip below which friction is viscous.
    smooth: f64,
    /// Whether `add` adds the Hessian (else `add_outside` does, on the
    /// step's grown layout).
    hessian: bool,
    dissipated: f64,
}

impl<'a> SelfFrictionTerm<'a> {
    /// The friction of `contact`'s pairs in contact at `start` (the step's
    /// start positions), with its coefficient and slip speed, over a step
    /// `dt`; its Hessian added on `pattern` in `add` if `hessian`.
    pub fn new(
        contact: &SelfContact,
        pattern: &'a SparsePattern,
        (start, dt): (&'a [f64], f64),
        hessian: bool,
    ) -> Self {
        Self::lagged_at(contact, pattern, start, (start, dt), hessian)
    }

    /// As [`new`](Self::new), the pairs, normals and normal forces lagged
    /// at positions `at` instead of the start (a static round after the
    /// first: the previous round's solution, `integrator::statics`); the
    /// slip still measured from `start`.
    pub fn lagged_at(
        contact: &SelfContact,
        pattern: &'a SparsePattern,
        at: &[f64],
        (start, dt): (&'a [f64], f64),
        hessian: bool,
    ) -> Self {
        Self {
            pattern,
            start,
            pairs: contact.lag_friction(at, contact.friction()),
            smooth: contact.stick_speed() * dt,
            hessian,
            dissipated: 0.0,
        }
    }

    /// The pairs' first nodes with their `mu lambda` (N), in the broad
    /// phase's order: what a static round compares with the next round's.
    pub fn forces(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.pairs.iter().map(|p| (p.nodes[0], p.force))
    }
}

impl StepTerm for SelfFrictionTerm<'_> {
    fn name(&self) -> &'static str {
        "self-friction"
    }

    fn stencils(&self) -> Stencils<'_> {
        Stencils::Nodes
    }

    fn add(
        &mut self,
        _ctx: &StepContext,
        y: &[f64],
        g: &mut [f64],
        h: Option<&mut [f64]>,
    ) -> TermValue {
        let h = h.filter(|_| self.hessian).map(|v| (v, self.pattern, None));
        let (value, dissipated) = add_friction(&self.pairs, self.start, y, self.smooth, Some(g), h);
        self.dissipated = dissipated;
        TermValue {
            value,
            potential: true,
            scale: 0.0,
        }
    }

    fn add_outside(
        &mut self,
        _ctx: &StepContext,
        y: &[f64],
        values: &mut [f64],
        pattern: &SparsePattern,
        fixed: &[bool],
    ) {
        if !self.hessian {
            let h = Some((values, pattern, Some(fixed)));
            add_friction(&self.pairs, self.start, y, self.smooth, None, h);
        }
    }

    fn dissipation(&self) -> f64 {
        self.dissipated
    }
}

#[cfg(test)]
mod tests {
    use crate::contact::self_contact::{LaggedPair, pair_friction};
    use crate::fd::{gradient_error, jacobian_error};

    /// A pair's friction against central differences in the viscous and
    /// the sliding regime, point–triangle-like and edge–edge-like weights,
    /// and its Hessian semi-definite.
    #[test]
    fn pair_friction_matches_finite_differences() {
        let e = 1e-5;
        let pairs = [
            LaggedPair {
                nodes: [0, 1, 2, 3],
                weights: [1.0, -0.2, -0.5, -0.3],
                normal: [0.0, 0.0, 1.0],
                force: 0.7,
            },
            LaggedPair {
                nodes: [0, 1, 2, 3],
                weights: [0.6, 0.4, -0.25, -0.75],
                normal: [0.6, 0.0, 0.8],
                force: 0.3,
            },
        ];
        for pair in &pairs {
            for scale in [3e-6, 4e-5, 1e-3] {
                let base: Vec<f64> = (0..12)
                    .map(|k| scale * ((k as f64 * 1.7).sin() + 0.3))
                    .collect();
                let d = |v: &[f64]| -> [[f64; 3]; 4] {
                    std::array::from_fn(|i| [v[3 * i], v[3 * i + 1], v[3 * i + 2]])
                };
                let f = |v: &[f64]| pair_friction(pair, &d(v), e).0;
                let g = |v: &[f64]| pair_friction(pair, &d(v), e).1.to_vec();
                let h = |v: &[f64]| pair_friction(pair, &d(v), e).2.to_vec();
                let step = 1e-3 * scale;
                let eg = gradient_error(f, g, &base, step);
                let eh = jacobian_error(g, h, &base, step);
                assert!(
                    eg < 1e-6 && eh < 1e-5,
                    "slip scale {scale}: gradient {eg:e}, Hessian {eh:e}"
                );
                let hm = faer::Mat::from_fn(12, 12, |i, j| h(&base)[i * 12 + j]);
                let eig = hm.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
                let big = eig.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                assert!(eig.iter().all(|&v| v >= -1e-12 * big), "{eig:?}");
            }
        }
    }
}
