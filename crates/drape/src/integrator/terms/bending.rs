//! The bending energy ([`crate::bending`], docs/theory.md §1.10):
//!
//! ```text
//! W_bend(Y) = sum_T 1/2 A_T (kappa_T(Y) - kappa_T0) . D (kappa_T(Y) - kappa_T0)
//! ```
//!
//! over the mesh's (sub-)triangles, each coupling its nodes with the nodes
//! opposite its edges (the patch stencils, part of the model's pattern).

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use crate::bending::Bending;
use crate::solver::SparsePattern;

/// The bending energy of a model with bending stiffness.
pub struct BendingTerm<'a> {
    bending: &'a Bending,
    pattern: &'a SparsePattern,
    /// Scratch for the term's own forces (their norm is its scale).
    forces: Vec<f64>,
}

impl<'a> BendingTerm<'a> {
    /// The term of `bending`, adding its Hessian on `pattern` (the
    /// model's [`Model::pattern`](crate::model::Model::pattern), which holds
    /// the bending stencils).
    pub fn new(bending: &'a Bending, pattern: &'a SparsePattern) -> Self {
        Self {
            bending,
            pattern,
            forces: Vec::new(),
        }
    }
}

impl StepTerm for BendingTerm<'_> {
    fn name(&self) -> &'static str {
        "bending"
    }

    fn stencils(&self) -> Stencils<'_> {
        let (ptr, nodes) = self.bending.stencil_lists();
        Stencils::Custom { ptr, nodes }
    }

    fn add(
        &mut self,
        ctx: &StepContext,
        y: &[f64],
        g: &mut [f64],
        h: Option<&mut [f64]>,
    ) -> TermValue {
        let patches = (self.bending, self.pattern);
        add_patches(patches, &mut self.forces, (ctx, y), (g, h), &|_, _| None)
    }
}

/// Adds an energy of `bending`'s patches' curvatures, `law` as
/// [`Bending::add_law`] takes it (`None`: the elastic one), to `g` and
/// `h` (on `pattern`), through `forces` (scratch): the bending term's and
/// the hysteresis term's assembly, and their value.
pub(super) fn add_patches<L>(
    (bending, pattern): (&Bending, &SparsePattern),
    forces: &mut Vec<f64>,
    (ctx, y): (&StepContext, &[f64]),
    (g, h): (&mut [f64], Option<&mut [f64]>),
    law: &L,
) -> TermValue
where
    L: Fn(usize, [f64; 3]) -> Option<crate::bending::kernel::LawValue> + Sync,
{
    forces.clear();
    forces.resize(y.len(), 0.0);
    let value = bending.add_law(pattern, y, forces, h, ctx.project, law);
    let mut scale = 0.0;
    for (gi, fi) in g.iter_mut().zip(forces.iter()) {
        *gi += fi;
        scale += fi * fi;
    }
    TermValue {
        value,
        potential: true,
        scale: scale.sqrt(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bending::BendingRigidity;
    use crate::integrator::terms::{bending_builder as builder, check_term, folded};
    use crate::mesh::generate::{Pattern, rectangle};
    use crate::mesh::{ElementOrder, Mesh};
    use crate::model::Model;

    fn model(mesh: Mesh, rigidity: BendingRigidity) -> Model {
        builder(mesh, rigidity).build().expect("a valid model")
    }

    /// Energy, gradient and Hessian against central differences, flat,
    /// near-flat, folded and strongly folded, for each element order and
    /// each kind of rigidity.
    #[test]
    fn bending_term_matches_finite_differences() {
        let ctx = StepContext {
            time: 0.0,
            contact: None,
            project: None,
        };
        let rigidities = [
            BendingRigidity::Isotropic(2e-5),
            BendingRigidity::Woven {
                warp: 3e-5,
                weft: 1e-5,
                direction: [1.0, 1.0, 0.0],
            },
            BendingRigidity::Plate {
                rigidity: 4e-5,
                poisson_ratio: 0.3,
            },
        ];
        for order in [
            ElementOrder::Linear,
            ElementOrder::Quadratic,
            ElementOrder::Cubic,
        ] {
            for rigidity in rigidities {
                let mesh = rectangle([0.1, 0.1], [4, 3], Pattern::Alternate, [0.0; 3], order);
                let m = model(mesh, rigidity);
                let bending = m.bending().expect("bending");
                for fold in [0.0, 1e-3, 1.0, 3.0] {
                    let y = folded(&m, fold);
                    let mut term = BendingTerm::new(bending, m.pattern());
                    let (eh, eg) = check_term(&mut term, &ctx, m.pattern(), &y, 1e-7);
                    assert!(
                        eh < 1e-6,
                        "{order:?} {rigidity:?} fold {fold}: Hessian {eh:e}"
                    );
                    assert!(
                        eg < 1e-6,
                        "{order:?} {rigidity:?} fold {fold}: gradient {eg:e}"
                    );
                }
            }
        }
    }

    /// With the sheet's edge x = -5 cm clamped (`[[fix]] clamp = true`),
    /// the patches along it take the mirror image of their free vertex
    /// for the missing neighbour (a ghost that moves with that vertex):
    /// energy, gradient and Hessian — the ghost's folded onto the vertex —
    /// against central differences, flat and folded, each order; the
    /// flat sheet has no energy (the ghost keeps the reference curvature).
    #[test]
    fn clamped_edge_patches_match_finite_differences() {
        let ctx = StepContext {
            time: 0.0,
            contact: None,
            project: None,
        };
        for order in [
            ElementOrder::Linear,
            ElementOrder::Quadratic,
            ElementOrder::Cubic,
        ] {
            let mesh = rectangle([0.1, 0.1], [4, 3], Pattern::Alternate, [0.0; 3], order);
            let clamped = mesh
                .nodes
                .iter()
                .map(|x| x[0] < -0.0499)
                .collect::<Vec<_>>();
            let m = builder(mesh, BendingRigidity::Isotropic(2e-5))
                .clamped(clamped)
                .build()
                .expect("a valid model");
            let bending = m.bending().expect("bending");
            let ghosts = bending
                .patches()
                .iter()
                .filter(|p| p.clamped_edges > 0)
                .count();
            assert!(
                ghosts >= 3,
                "{order:?}: {ghosts} patches with a clamped edge"
            );
            let mut term = BendingTerm::new(bending, m.pattern());
            for fold in [0.0, 1.0, 3.0] {
                let y = folded(&m, fold);
                let (eh, eg) = check_term(&mut term, &ctx, m.pattern(), &y, 1e-7);
                assert!(eh < 1e-6, "{order:?} fold {fold}: Hessian {eh:e}");
                assert!(eg < 1e-6, "{order:?} fold {fold}: gradient {eg:e}");
            }
            let flat = m.initial_positions().to_vec();
            assert!(
                bending.energy(&flat).abs() < 1e-20,
                "{order:?}: flat sheet bent"
            );
        }
    }

    /// The projected Hessian (every patch projected) is positive
    /// semi-definite on the folded sheet, whose exact bending Hessian
    /// is not (the curvature's second derivatives weighted by the
    /// moments), and is the exact one to the bit on the flat sheet,
    /// where the moments vanish and each patch Hessian is the
    /// semi-definite `J^T D J`. Each element order.
    #[test]
    fn projected_bending_hessian_is_semi_definite() {
        use crate::integrator::terms::{check_projection, relative_smallest_eigenvalue};
        let ctx = StepContext {
            time: 0.0,
            contact: None,
            project: None,
        };
        for order in [
            ElementOrder::Linear,
            ElementOrder::Quadratic,
            ElementOrder::Cubic,
        ] {
            let mesh = rectangle([0.1, 0.1], [4, 3], Pattern::Alternate, [0.0; 3], order);
            let m = model(mesh, BendingRigidity::Isotropic(2e-5));
            let bending = m.bending().expect("bending");
            let n = m.initial_positions().len();
            let mut term = BendingTerm::new(bending, m.pattern());
            let y = folded(&m, 1.0);
            let (exact, projected, smallest) = check_projection(&mut term, &ctx, m.pattern(), &y);
            assert!(
                relative_smallest_eigenvalue(&exact, n) < -1e-6,
                "{order:?}: the folded sheet's bending Hessian is indefinite"
            );
            assert!(smallest > -1e-12, "{order:?}: projected {smallest:e}");
            assert_ne!(exact, projected);
            let flat = folded(&m, 0.0);
            let (exact, projected, smallest) =
                check_projection(&mut term, &ctx, m.pattern(), &flat);
            assert_eq!(exact, projected, "{order:?}: flat, nothing to project");
            assert!(smallest > -1e-12, "{order:?}: flat {smallest:e}");
        }
    }
}
