//! External loads of a step (docs/theory.md §1.5): the dead loads (surface,
//! gravity, nodal forces, at their ramped values at the end of the step)
//! and the follower pressure,
//!
//! ```text
//! F_ext(Y) = F_dead + F_p(Y),   F_p^a = p integral phi^a (g_1 x g_2) dxi
//! G       -= F_ext,             H -= dF_p/dY
//! Pi_ext   = -F_dead . Y        (dead loads only)
//! ```
//!
//! A follower pressure is no potential in general (it is one, `-p V`, only
//! on a closed or edge-held membrane), so with a pressure the term
//! reports none. The external forces of the last evaluation stay in the
//! caller's buffer: the run's work integral needs them.

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use crate::model::Model;
use crate::vecn::{dot, norm};

/// Dead loads and follower pressure.
pub struct LoadTerm<'a> {
    model: &'a Model,
    /// Dead forces of the step (N).
    dead: &'a [f64],
    /// Follower pressure of the step (Pa).
    pressure: f64,
    /// External forces at the last evaluation (N).
    f_ext: &'a mut [f64],
}

impl<'a> LoadTerm<'a> {
    /// The loads `dead` and `pressure`; `f_ext` receives the external
    /// forces of each evaluation.
    pub fn new(model: &'a Model, dead: &'a [f64], pressure: f64, f_ext: &'a mut [f64]) -> Self {
        Self {
            model,
            dead,
            pressure,
            f_ext,
        }
    }
}

impl StepTerm for LoadTerm<'_> {
    fn name(&self) -> &'static str {
        "loads"
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
        self.f_ext.copy_from_slice(self.dead);
        self.model.add_pressure(y, self.pressure, self.f_ext, h);
        for (gi, fi) in g.iter_mut().zip(self.f_ext.iter()) {
            *gi -= fi;
        }
        TermValue {
            value: -dot(self.dead, y),
            potential: self.pressure == 0.0,
            scale: norm(self.f_ext),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::terms::{check_term, deformed, patch_model};
    use crate::load::{Load, LoadKind};
    use crate::material::SaintVenantKirchhoff;

    /// A dead surface load (a potential, no Hessian) and a follower
    /// pressure (its tangent) against central differences, every order.
    #[test]
    fn load_term_matches_finite_differences() {
        for order in 1..=3 {
            for pressure in [0.0, 250.0] {
                let load = Load {
                    kind: LoadKind::Surface {
                        force: [0.3, -0.2, -1.9],
                    },
                    ramp: None,
                };
                let model = patch_model(
                    order,
                    Box::new(SaintVenantKirchhoff::new(2e6, 0.3)),
                    vec![load],
                );
                let y = deformed(&model);
                let mut dead = vec![0.0; y.len()];
                model.dead_forces(1.0, None, &mut dead);
                let mut f_ext = vec![0.0; y.len()];
                let mut term = LoadTerm::new(&model, &dead, pressure, &mut f_ext);
                let ctx = StepContext {
                    time: 1.0,
                    contact: None,
                    project: None,
                };
                let (eh, eg) = check_term(&mut term, &ctx, model.pattern(), &y, 1e-7);
                // Without pressure the Hessian is zero: errors relative to
                // the checker's floor.
                assert!(eh < 1e-6, "order {order}, p {pressure}: Hessian {eh:e}");
                assert!(eg < 1e-6, "order {order}, p {pressure}: gradient {eg:e}");
            }
        }
    }
}
