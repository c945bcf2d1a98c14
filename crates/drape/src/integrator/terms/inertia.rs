//! Inertia in a Newmark step (docs/theory.md §1.6): with `c = 1 / (beta dt^2)` and
//! `Q_s` from the state at the start of the step,
//!
//! ```text
//! Pi_M(Y)   = c/2 Y . M Y - Y . M Q_s
//! dPi_M/dY  = c M Y - M Q_s              = M A_{s+1}
//! d2Pi_M/dY2 = c M
//! ```
//!
//! (the acceleration at the end of the step is `A_{s+1} = c Y - Q_s`).
//! Its scale in Newton's test is `c |M Y| + |M Q_s|`.

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use crate::model::Model;
use crate::vecn::dot;

/// The inertia of a dynamic step.
pub struct InertiaTerm<'a> {
    model: &'a Model,
    /// `1 / (beta dt^2)` (1/s^2).
    c: f64,
    /// `M Q_s` (N).
    mq: &'a [f64],
    /// `M Y` at the last evaluation (scratch).
    my: &'a mut [f64],
}

impl<'a> InertiaTerm<'a> {
    /// The term with `c = 1 / (beta dt^2)`, `M Q_s` = `mq` and the scratch
    /// `my` (dofs long).
    pub fn new(model: &'a Model, c: f64, mq: &'a [f64], my: &'a mut [f64]) -> Self {
        Self { model, c, mq, my }
    }
}

impl StepTerm for InertiaTerm<'_> {
    fn name(&self) -> &'static str {
        "inertia"
    }

    fn stencils(&self) -> Stencils<'_> {
        Stencils::Elements
    }

    fn add(
        &mut self,
        _ctx: &StepContext,
        y: &[f64],
        g: &mut [f64],
        h: Option<&mut [f64]>,
    ) -> TermValue {
        let c = self.c;
        self.model.mass_times(y, self.my);
        // G and the norms of both force vectors in one pass (each sum of
        // squares in index order).
        let (mut m2, mut q2) = (0.0, 0.0);
        for i in 0..g.len() {
            let (my, mq) = (self.my[i], self.mq[i]);
            g[i] = g[i] + c * my - mq;
            m2 += my * my;
            q2 += mq * mq;
        }
        if let Some(h) = h {
            self.model.add_mass_to_hessian(c, h);
        }
        TermValue {
            value: 0.5 * c * dot(y, self.my) - dot(y, self.mq),
            potential: true,
            scale: c * m2.sqrt() + q2.sqrt(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::terms::{check_term, deformed, patch_model};
    use crate::material::SaintVenantKirchhoff;

    /// Value, gradient and Hessian against central differences for each
    /// order (consistent mass); the gradient is `M (c Y - Q)`.
    #[test]
    fn inertia_term_matches_finite_differences() {
        for order in 1..=3 {
            let model = patch_model(order, Box::new(SaintVenantKirchhoff::new(2e6, 0.3)), vec![]);
            let y = deformed(&model);
            let q: Vec<f64> = y.iter().map(|v| 1e6 * (v + 0.01)).collect();
            let mut mq = vec![0.0; y.len()];
            model.mass_times(&q, &mut mq);
            let mut my = vec![0.0; y.len()];
            let mut term = InertiaTerm::new(&model, 1e6, &mq, &mut my);
            let ctx = StepContext {
                time: 0.0,
                contact: None,
                project: None,
            };
            let (eh, eg) = check_term(&mut term, &ctx, model.pattern(), &y, 1e-6);
            assert!(eh < 1e-8, "order {order}: Hessian {eh:e}");
            assert!(eg < 1e-6, "order {order}: gradient {eg:e}");
        }
    }
}
