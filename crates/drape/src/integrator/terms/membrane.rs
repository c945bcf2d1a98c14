//! The membrane's strain energy (docs/theory.md §1.2–1.4):
//!
//! ```text
//! U(Y)   = sum_e integral t W(E) dA0,   E = 1/2 (F^T F - I)
//! dU/dY^a = integral t F S grad phi^a dA0
//! ```
//!
//! with the Hessian blocks of [`crate::element::membrane`]. With the
//! stress-projection wrinkling model `S` is the projected stress, which is
//! not the derivative of an energy: the term is then no potential (its
//! reported value is `1/2 P : E`) and its tangent is not symmetric.

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use crate::model::Model;
use crate::vecn::norm;

/// The strain energy of the membrane: written first into `G` and `H` (it
/// fills every block of the pattern, so they need not be zeroed).
pub struct MembraneTerm<'a> {
    model: &'a Model,
}

impl<'a> MembraneTerm<'a> {
    /// The term of `model`'s membrane.
    pub fn new(model: &'a Model) -> Self {
        Self { model }
    }
}

impl StepTerm for MembraneTerm<'_> {
    fn name(&self) -> &'static str {
        "membrane"
    }

    fn stencils(&self) -> Stencils<'_> {
        Stencils::Elements
    }

    fn overwrites(&self) -> bool {
        true
    }

    fn add(
        &mut self,
        ctx: &StepContext,
        y: &[f64],
        g: &mut [f64],
        h: Option<&mut [f64]>,
    ) -> TermValue {
        let model = self.model;
        let hyperelastic = model.material().is_hyperelastic();
        // The assembly overwrites the forces and the Hessian: the first
        // term, it writes straight into G and H. (The stress projection's
        // tangent is no potential's Hessian: never projected.)
        let project = ctx.project.filter(|_| hyperelastic);
        let value = model.assemble_projected(y, g, h, project);
        TermValue {
            value,
            potential: hyperelastic,
            scale: norm(g),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::terms::{check_term, deformed, patch_model};
    use crate::material::wrinkling::{Wrinkling, WrinklingModel};
    use crate::material::{Material, SaintVenantKirchhoff};

    /// Gradient and Hessian against central differences, on a stretched,
    /// sheared and lifted patch of each order, for a hyperelastic material
    /// and for both wrinkling models (whose patch mixes taut, wrinkled and
    /// slack points). Steps of 1e-7 m on 0.1 m: truncation ~1e-12,
    /// round-off ~1e-9 relative.
    #[test]
    fn membrane_term_matches_finite_differences() {
        type Make = fn() -> Box<dyn Material>;
        let materials: [(Make, bool); 3] = [
            (|| Box::new(SaintVenantKirchhoff::new(2.0e6, 0.3)), true),
            (
                || {
                    Box::new(Wrinkling::new(
                        2.0e6,
                        0.3,
                        0.0,
                        WrinklingModel::RelaxedEnergy,
                    ))
                },
                true,
            ),
            (
                || {
                    Box::new(Wrinkling::new(
                        2.0e6,
                        0.3,
                        0.0,
                        WrinklingModel::StressProjection,
                    ))
                },
                false,
            ),
        ];
        for order in 1..=3 {
            for (material, potential) in materials {
                let model = patch_model(order, material(), Vec::new());
                let y = deformed(&model);
                let ctx = StepContext {
                    time: 0.0,
                    contact: None,
                    project: None,
                };
                let mut term = MembraneTerm::new(&model);
                let (eh, eg) = check_term(&mut term, &ctx, model.pattern(), &y, 1e-7);
                assert!(eh < 1e-6, "order {order}: Hessian {eh:e}");
                assert!(eg < 1e-6, "order {order}: gradient {eg:e}");
                let mut g = vec![0.0; y.len()];
                assert_eq!(term.add(&ctx, &y, &mut g, None).potential, potential);
            }
        }
    }

    /// The projected Hessian (every element projected) is positive
    /// semi-definite where the exact one is not — the patch compressed
    /// along y, so that Saint-Venant–Kirchhoff's geometric stiffness is
    /// negative there — and is the exact Hessian to the bit where every
    /// element's Hessian is semi-definite (a biaxial stretch: `S`
    /// positive definite, both parts of each element Hessian
    /// semi-definite). Each element order.
    #[test]
    fn projected_membrane_hessian_is_semi_definite() {
        use crate::integrator::terms::{check_projection, relative_smallest_eigenvalue};
        let ctx = StepContext {
            time: 0.0,
            contact: None,
            project: None,
        };
        for order in 1..=3 {
            let model = patch_model(
                order,
                Box::new(SaintVenantKirchhoff::new(2.0e6, 0.3)),
                vec![],
            );
            let n = model.initial_positions().len();
            let mut term = MembraneTerm::new(&model);
            let y = deformed(&model);
            let (exact, projected, smallest) =
                check_projection(&mut term, &ctx, model.pattern(), &y);
            assert!(
                relative_smallest_eigenvalue(&exact, n) < -1e-6,
                "order {order}: the compressed patch's exact Hessian is indefinite"
            );
            assert!(smallest > -1e-12, "order {order}: projected {smallest:e}");
            assert_ne!(exact, projected);
            let stretched: Vec<f64> = model.initial_positions().iter().map(|x| 1.05 * x).collect();
            let (exact, projected, smallest) =
                check_projection(&mut term, &ctx, model.pattern(), &stretched);
            assert_eq!(
                exact, projected,
                "order {order}: stretched, nothing to project"
            );
            assert!(smallest > -1e-12, "order {order}: stretched {smallest:e}");
        }
    }
}
