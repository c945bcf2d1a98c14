//! Self-contact's barrier ([`crate::contact::self_contact`]): the IPC
//! barrier `kappa b(d^2)` over the fabric's point–triangle and edge–edge
//! pairs closer than `d̂` (Li et al. 2020), with its gradient, its
//! per-pair projected Hessian and the collision-free step fraction of
//! additive CCD, which Newton's line search starts below. The pairs are
//! found again at every evaluation (they come and go within a step); the
//! term lags nothing.

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use crate::contact::self_contact::{PairHessians, SelfContact, scatter_hessians};
use crate::solver::SparsePattern;

/// The self-contact barrier.
pub struct SelfContactTerm<'a> {
    contact: &'a SelfContact,
    pattern: &'a SparsePattern,
    hessian: bool,
    /// The pairs' projected Hessians of the last evaluation that asked for
    /// one, kept for [`StepTerm::add_outside`] when `hessian` is off.
    pairs: Vec<([usize; 4], [f64; 144])>,
}

impl<'a> SelfContactTerm<'a> {
    /// The barrier of `contact`, its Hessian added on `pattern` if
    /// `hessian` (else the step adds it on its grown layout,
    /// `integrator::grown`, through [`StepTerm::add_outside`]).
    pub fn new(contact: &'a SelfContact, pattern: &'a SparsePattern, hessian: bool) -> Self {
        Self {
            contact,
            pattern,
            hessian,
            pairs: Vec::new(),
        }
    }
}

impl StepTerm for SelfContactTerm<'_> {
    fn name(&self) -> &'static str {
        "self-contact"
    }

    /// Pairs come and go; the Hessian's couplings the pattern lacks go to
    /// the diagonal ([`crate::contact::self_contact`], "Hessian").
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
        let hessians = match h {
            None => PairHessians::None,
            Some(v) if self.hessian => PairHessians::Scatter(v, self.pattern),
            // Computed with the gradient, added on the grown layout after.
            Some(_) => PairHessians::Collect(&mut self.pairs),
        };
        let value = self.contact.add(y, g, hessians);
        TermValue {
            value,
            potential: true,
            scale: 0.0,
        }
    }

    fn add_outside(
        &mut self,
        _ctx: &StepContext,
        _y: &[f64],
        values: &mut [f64],
        pattern: &SparsePattern,
        fixed: &[bool],
    ) {
        if !self.hessian {
            scatter_hessians(&self.pairs, values, pattern, fixed);
        }
    }

    fn max_step(&self, _ctx: &StepContext, y: &[f64], dy: &[f64]) -> f64 {
        self.contact.max_step(y, dy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ElementOrder;
    use crate::mesh::generate::{Pattern, rectangle};
    use crate::solver::SparsePattern;

    /// Two 2 cm plies of 2 x 2 squares, the upper `gap` above the lower
    /// and shifted by a third of a square, as one mesh.
    fn plies(gap: f64) -> (Vec<[usize; 3]>, Vec<f64>, SparsePattern) {
        let one = rectangle(
            [0.02, 0.02],
            [2, 2],
            Pattern::Right,
            [0.0; 3],
            ElementOrder::Linear,
        );
        let n = one.node_count();
        let mut x: Vec<f64> = one.nodes.concat();
        x.extend(
            one.nodes
                .iter()
                .flat_map(|p| [p[0] + 0.0033, p[1] + 0.0031, p[2] + gap]),
        );
        let mut tris: Vec<[usize; 3]> = one.elements().map(|e| [e[0], e[1], e[2]]).collect();
        let upper: Vec<[usize; 3]> = tris.iter().map(|t| t.map(|a| a + n)).collect();
        tris.extend(upper);
        let pattern = SparsePattern::new(2 * n, tris.iter().map(|t| t.as_slice()));
        (tris, x, pattern)
    }

    /// The barrier's value and gradient against central differences on two
    /// plies 0.3–0.7 d̂ apart (bent so that pairs of every kind are
    /// active), its assembled Hessian positive semi-definite, and its step
    /// limit stopping the upper ply short of the lower.
    #[test]
    fn barrier_term_gradient_semi_definite_hessian_and_step() {
        use crate::fd::gradient_error;
        use crate::integrator::terms::check_projection;
        let d_hat = 1e-3;
        let (tris, x0, pattern) = plies(2.0 * d_hat);
        let contact = SelfContact::new(tris, &x0, d_hat, 5e4).expect("apart");
        // Bring the upper ply down to 0.3–0.7 d̂, wavy.
        let n = x0.len() / 3;
        let y: Vec<f64> = x0
            .chunks(3)
            .enumerate()
            .flat_map(|(i, p)| {
                let z = if i >= n / 2 {
                    0.5e-3 + 0.2e-3 * (300.0 * p[0]).sin()
                } else {
                    p[2]
                };
                [p[0], p[1], z]
            })
            .collect();
        assert!(contact.active_pairs(&y) > 4);
        let mut term = SelfContactTerm::new(&contact, &pattern, true);
        let ctx = StepContext {
            time: 0.0,
            contact: None,
            project: None,
        };
        let energy = |v: &[f64]| {
            let mut g = vec![0.0; v.len()];
            SelfContactTerm::new(&contact, &pattern, true)
                .add(&ctx, v, &mut g, None)
                .value
        };
        let grad = |v: &[f64]| {
            let mut g = vec![0.0; v.len()];
            SelfContactTerm::new(&contact, &pattern, true).add(&ctx, v, &mut g, None);
            g
        };
        assert!(energy(&y) > 0.0);
        let eg = gradient_error(energy, grad, &y, 1e-9);
        assert!(eg < 1e-5, "gradient {eg:e}");
        let (_, _, smallest) = check_projection(&mut term, &ctx, &pattern, &y);
        assert!(smallest > -1e-10, "{smallest:e}");
        // The upper ply pushed 2 mm down: CCD stops it above the lower.
        let dy: Vec<f64> = (0..y.len())
            .map(|k| {
                if k / 3 >= n / 2 && k % 3 == 2 {
                    -2e-3
                } else {
                    0.0
                }
            })
            .collect();
        let alpha = term.max_step(&ctx, &y, &dy);
        assert!(alpha > 0.0 && alpha < 0.15, "{alpha}");
        let moved: Vec<f64> = y.iter().zip(&dy).map(|(a, b)| a + alpha * b).collect();
        assert!(energy(&moved).is_finite());
        // Too close at the start: refused, naming a pair.
        let (tris, x0, _) = plies(0.5 * d_hat);
        let err = SelfContact::new(tris, &x0, d_hat, 5e4).unwrap_err();
        assert!(err.to_string().starts_with("= 0.001 m is larger"), "{err}");
    }
}
