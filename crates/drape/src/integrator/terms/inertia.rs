//! Inertia in a Newmark step (docs/theory.md §1.6): with `c = 1 / (beta dt^2)` and
//! `Q_s` from the state at the start of the step,
//!
//! ```text
//! Pi_M(Y)   = c/2 (Y - Q_s/c) . M (Y - Q_s/c)
//! dPi_M/dY  = c M Y - M Q_s              = M A_{s+1}
//! d2Pi_M/dY2 = c M
//! ```
//!
//! (the acceleration at the end of the step is `A_{s+1} = c Y - Q_s`;
//! `Q_s / c` is where the step would end with no force). The value is
//! `c/2 Y . M Y - Y . M Q_s` plus a constant of the step, computed as the
//! product of the two small vectors `Y - Q_s/c` and `M Y - M Q_s/c`:
//! written the first way, two terms of order `c |Y|^2 m` cancel to the
//! size of the step's energy changes, and at short steps (`c` = 4e9 at
//! 16 µs) the round-off of that cancellation exceeds what Newton's line
//! search compares (a 30-ring drape tester stalled so on friction at the
//! pedestal's rim). Its scale in Newton's test is `c |M Y| + |M Q_s|`.

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use crate::model::Model;

/// The inertia of a dynamic step.
pub struct InertiaTerm<'a> {
    model: &'a Model,
    /// `1 / (beta dt^2)` (1/s^2).
    c: f64,
    /// `Q_s` (m/s^2).
    q: &'a [f64],
    /// `M Q_s` (N).
    mq: &'a [f64],
    /// `M Y` at the last evaluation (scratch).
    my: &'a mut [f64],
}

impl<'a> InertiaTerm<'a> {
    /// The term with `c = 1 / (beta dt^2)`, `Q_s` = `q`, `M Q_s` = `mq`
    /// and the scratch `my` (dofs long).
    pub fn new(
        model: &'a Model,
        c: f64,
        (q, mq): (&'a [f64], &'a [f64]),
        my: &'a mut [f64],
    ) -> Self {
        Self {
            model,
            c,
            q,
            mq,
            my,
        }
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
        // G, the value and the norms of both force vectors in one pass
        // (each sum in index order).
        let (mut m2, mut q2, mut value) = (0.0, 0.0, 0.0);
        for i in 0..g.len() {
            let (my, mq) = (self.my[i], self.mq[i]);
            g[i] = g[i] + c * my - mq;
            value += (y[i] - self.q[i] / c) * (my - mq / c);
            m2 += my * my;
            q2 += mq * mq;
        }
        if let Some(h) = h {
            self.model.add_mass_to_hessian(c, h);
        }
        TermValue {
            value: 0.5 * c * value,
            potential: true,
            scale: c * m2.sqrt() + q2.sqrt(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::potential::StepTerm;
    use crate::integrator::terms::{check_term, deformed, patch_model};
    use crate::material::SaintVenantKirchhoff;
    use crate::vecn::dot;

    /// At a 16 µs step (`c` = 4e9 1/s²) ten metres from the origin, the
    /// value's change between two iterates 1 nm apart matches `c delta .
    /// M (Y0 - Q/c) + c/2 delta . M delta` (from small vectors only) to
    /// 1e-4 (-1.4448e-9 J); the same change of `c/2 Y.MY - Y.MQ`, the
    /// value written the textbook way (-1.1e9 J here), comes out as
    /// +4.8e-7 J, the round-off of its cancellation: the line search
    /// compared noise, and a 30-ring drape tester stalled at its
    /// pedestal's rim.
    #[test]
    fn inertia_energy_differences_are_exact_at_short_steps() {
        let model = patch_model(1, Box::new(SaintVenantKirchhoff::new(2e6, 0.3)), vec![]);
        let n = model.dofs();
        let c = 1.0 / (1.6e-5f64 * 1.6e-5);
        let y0: Vec<f64> = deformed(&model).iter().map(|v| v + 10.0).collect();
        // Where the step would end with no force: 1 µm from Y0.
        let rest: Vec<f64> = y0
            .iter()
            .enumerate()
            .map(|(i, v)| v + 1e-6 * (1.0 + (i % 3) as f64))
            .collect();
        let q: Vec<f64> = rest.iter().map(|v| c * v).collect();
        let mut mq = vec![0.0; n];
        model.mass_times(&q, &mut mq);
        let delta: Vec<f64> = (0..n).map(|i| 1e-9 * ((i * 7 % 5) as f64 - 2.0)).collect();
        let y1: Vec<f64> = y0.iter().zip(&delta).map(|(a, d)| a + d).collect();
        let ctx = StepContext {
            time: 0.0,
            contact: None,
            project: None,
        };
        let mut my = vec![0.0; n];
        let mut value = |y: &[f64]| {
            let mut g = vec![0.0; n];
            InertiaTerm::new(&model, c, (&q, &mq), &mut my)
                .add(&ctx, y, &mut g, None)
                .value
        };
        let change = value(&y1) - value(&y0);
        let (mut md, mut mr) = (vec![0.0; n], vec![0.0; n]);
        model.mass_times(&delta, &mut md);
        let offset: Vec<f64> = y0.iter().zip(&rest).map(|(a, b)| a - b).collect();
        model.mass_times(&offset, &mut mr);
        let exact = c * dot(&delta, &mr) + 0.5 * c * dot(&delta, &md);
        assert!(
            ((change - exact) / exact).abs() < 1e-4,
            "change {change:e} against {exact:e}"
        );
        let textbook = |y: &[f64]| {
            let mut my = vec![0.0; n];
            model.mass_times(y, &mut my);
            0.5 * c * dot(y, &my) - dot(y, &mq)
        };
        let noisy = textbook(&y1) - textbook(&y0);
        assert!(
            ((noisy - exact) / exact).abs() > 1.0,
            "textbook change {noisy:e} against {exact:e}"
        );
    }

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
            let mut term = InertiaTerm::new(&model, 1e6, (&q, &mq), &mut my);
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
