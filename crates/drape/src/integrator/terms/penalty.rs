//! Penalty contact with the rigid obstacles (docs/theory.md §1.8,
//! [`crate::contact::penalty`]): for every node–obstacle pair with a
//! negative gap `g_p`,
//!
//! ```text
//! Pi_c = sum 1/2 eta g_p^2,   dPi_c/dy_p = eta g_p n,   d2Pi_c/dy_p^2 = eta (n n^T + g_p dn/dy)
//! ```
//!
//! with `n = dg/dy`. Each pair couples one node with itself. The term adds
//! nothing to Newton's force scale (as before the seam: the contact force
//! balances forces already counted).

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use crate::contact::{ContactModel, PenaltyHessian};
use crate::solver::SparsePattern;

/// Penalty contact of stiffness `eta` (N/m).
pub struct PenaltyTerm<'a> {
    contact: &'a ContactModel,
    pattern: &'a SparsePattern,
    stiffness: f64,
}

impl<'a> PenaltyTerm<'a> {
    /// The term of `contact`'s obstacles with stiffness `stiffness` (N/m),
    /// adding its Hessian on `pattern`.
    pub fn new(contact: &'a ContactModel, pattern: &'a SparsePattern, stiffness: f64) -> Self {
        Self {
            contact,
            pattern,
            stiffness,
        }
    }
}

impl StepTerm for PenaltyTerm<'_> {
    fn name(&self) -> &'static str {
        "penalty contact"
    }

    fn stencils(&self) -> Stencils<'_> {
        Stencils::Nodes
    }

    fn add(
        &mut self,
        ctx: &StepContext,
        y: &[f64],
        g: &mut [f64],
        h: Option<&mut [f64]>,
    ) -> TermValue {
        let value = match ctx.contact {
            Some(state) => self.contact.add_penalty(
                self.stiffness,
                y,
                ctx.time,
                state,
                g,
                h.map(|values| PenaltyHessian {
                    values,
                    pattern: self.pattern,
                    project: ctx.project,
                }),
            ),
            None => 0.0,
        };
        TermValue {
            value,
            potential: true,
            scale: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::terms::{check_term, contact_patch};

    /// The sphere a patch is pressed into.
    const SPHERE: &str = "shape = \"sphere\"\ncenter = [0.0, 0.0, -0.2]\nradius = 0.19";

    /// A 10 cm patch of 4 x 4 squares with `obstacle` (its keys), penalty
    /// contact, and its nodes lifted into a paraboloid 1.5 cm below the
    /// plane at its centre.
    fn pressed_patch(obstacle: &str) -> (crate::setup::Setup, Vec<f64>) {
        let contact =
            format!("[[obstacle]]\n{obstacle}\n[contact]\nmethod = \"penalty\"\npenalty = 5.0e4");
        let setup = contact_patch(&contact, 1e-3);
        let y = setup
            .model
            .initial_positions()
            .chunks(3)
            .flat_map(|x| [x[0], x[1], -0.015 + 2.0 * (x[0] * x[0] + x[1] * x[1])])
            .collect();
        (setup, y)
    }

    /// A 10 cm patch pressed into a sphere (5 mm at its centre, clear of
    /// it at its corners): the penalty's value, gradient and Hessian (with
    /// the curvature term `g dn/dy`) against central differences.
    #[test]
    fn penalty_term_matches_finite_differences() {
        let (setup, y) = pressed_patch(SPHERE);
        let model = &setup.model;
        let contact = model.contact().expect("an obstacle");
        let state = contact.initial_state(&y);
        let ctx = StepContext {
            time: 0.0,
            contact: Some(&state),
            project: None,
        };
        let mut term = PenaltyTerm::new(contact, model.pattern(), 5.0e4);
        let mut g = vec![0.0; y.len()];
        assert!(term.add(&ctx, &y, &mut g, None).value > 0.0);
        let (eh, eg) = check_term(&mut term, &ctx, model.pattern(), &y, 1e-7);
        assert!(eh < 1e-6, "Hessian {eh:e}");
        assert!(eg < 1e-6, "gradient {eg:e}");
    }

    /// The projected Hessian of a patch pressed into a sphere is positive
    /// semi-definite (each node's `eta (n n^T + g dn/dy)` has negative
    /// eigenvalues on the tangent plane where `g < 0` on a convex surface)
    /// and the exact one to the bit against a plane (`dn/dy = 0`).
    #[test]
    fn projected_penalty_hessian_is_semi_definite() {
        use crate::integrator::terms::{check_projection, relative_smallest_eigenvalue};
        let plane = "shape = \"plane\"\npoint = [0.0, 0.0, -0.01]\nnormal = [0.0, 0.0, 1.0]";
        for (obstacle, indefinite) in [(SPHERE, true), (plane, false)] {
            let (setup, y) = pressed_patch(obstacle);
            let model = &setup.model;
            let contact = model.contact().expect("an obstacle");
            let n = y.len();
            let state = contact.initial_state(&y);
            let ctx = StepContext {
                time: 0.0,
                contact: Some(&state),
                project: None,
            };
            let mut term = PenaltyTerm::new(contact, model.pattern(), 5.0e4);
            let (exact, projected, smallest) =
                check_projection(&mut term, &ctx, model.pattern(), &y);
            assert!(smallest > -1e-12, "{obstacle}: projected {smallest:e}");
            if indefinite {
                assert!(relative_smallest_eigenvalue(&exact, n) < -1e-6);
                assert_ne!(exact, projected);
            } else {
                assert_eq!(exact, projected);
            }
        }
    }
}
