//! The terms of a step's incremental potential ([`super::potential`]),
//! one concept per file: the membrane's strain energy, inertia, the
//! external loads, penalty contact, friction. Each states its energy, gradient and
//! Hessian, and its test checks them against central finite differences
//! through the one checker, `check_term` (a test helper).

mod bending;
mod features;
mod friction;
mod gas;
mod hysteresis;
mod inertia;
mod loads;
mod membrane;
mod penalty;
mod self_contact;
mod self_friction;

pub use bending::BendingTerm;
pub use features::FeatureTerm;
pub use friction::FrictionTerm;
pub use gas::GasTerm;
pub use hysteresis::HysteresisTerm;
pub(crate) use hysteresis::{carry_springs, initial_plastic, plastic_count, slip};
pub use inertia::InertiaTerm;
pub use loads::LoadTerm;
pub use membrane::MembraneTerm;
pub use penalty::PenaltyTerm;
pub use self_contact::SelfContactTerm;
pub use self_friction::SelfFrictionTerm;

#[cfg(test)]
pub(crate) use check::{
    bending_builder, check_projection, check_term, contact_patch, deformed, dense_hessian, folded,
    patch_builder, patch_model, relative_smallest_eigenvalue,
};

#[cfg(test)]
mod check {
    use super::super::potential::{StepContext, StepTerm};
    use crate::element::membrane::Section;
    use crate::fd::{gradient_error, jacobian_error};
    use crate::load::Load;
    use crate::material::Material;
    use crate::mesh::ElementOrder;
    use crate::mesh::generate::{Pattern, rectangle};
    use crate::model::{Model, ModelBuilder};
    use crate::solver::SparsePattern;

    /// A fabric on `mesh` that bends with `rigidity` (E 2 MPa, nu 0.3, 0.6
    /// mm, 320 kg/m^3), to add to.
    pub(crate) fn bending_builder(
        mesh: crate::mesh::Mesh,
        rigidity: crate::bending::BendingRigidity,
    ) -> ModelBuilder {
        Model::builder(
            mesh,
            Box::new(crate::material::SaintVenantKirchhoff::new(2e6, 0.3)),
            Section {
                thickness: 6e-4,
                prestress: 0.0,
            },
            320.0,
        )
        .bending(rigidity)
    }

    /// A 10 cm square (4 x 3 squares, alternating diagonals) of `order`,
    /// folded: `fold` scales a deformation that stretches, shears and
    /// rolls the sheet up (0: flat; 1: about a right angle of folding;
    /// 3: folded nearly onto itself).
    pub(crate) fn folded(model: &Model, fold: f64) -> Vec<f64> {
        // Rolled onto a cylinder of curvature k about the y axis (k = 15
        // 1/m per unit `fold`: a right angle over the 10 cm at fold 1),
        // then stretched, sheared and rippled.
        let k = 15.0 * fold;
        let roll = |s: f64| {
            if k == 0.0 {
                (s, 0.0)
            } else {
                ((k * s).sin() / k, (1.0 - (k * s).cos()) / k)
            }
        };
        model
            .initial_positions()
            .chunks(3)
            .flat_map(|x| {
                let (u, w) = roll(x[0] + 0.05);
                [
                    1.01 * u + 0.01 * x[1],
                    x[1] + 0.02 * x[0] * x[1],
                    w + 0.01 * fold.min(1.0) * (30.0 * x[1]).sin(),
                ]
            })
            .collect()
    }

    /// A 10 cm square of 3 x 2 squares (12 triangles) of `order` (1–3),
    /// 0.6 mm thick, 320 kg/m^3, with `loads`.
    pub(crate) fn patch_model(
        order: usize,
        material: Box<dyn Material>,
        loads: Vec<Load>,
    ) -> Model {
        patch_builder(order, material, loads)
            .build()
            .expect("a valid mesh")
    }

    /// A 10 cm square of 4 x 4 squares (T3, the reference membrane) with
    /// the scenario tables `contact` (its obstacles and `[contact]`) and
    /// one step of `dt`, built: the contact terms' test set-up.
    pub(crate) fn contact_patch(contact: &str, dt: f64) -> crate::setup::Setup {
        let text = format!(
            "[mesh]\nshape = \"rectangle\"\nsize = [0.1, 0.1]\ndivisions = [4, 4]\n\
             [material]\nyoungs_modulus = 2.0e6\npoisson_ratio = 0.3\ndensity = 320.0\nthickness = 0.6e-3\n\
             {contact}\n[time]\nsegments = [{{ steps = 1, dt = {dt:e} }}]\n"
        );
        let path = std::path::Path::new("patch.toml");
        crate::scenario::Scenario::parse(&text, path)
            .and_then(|s| s.build(path, &text))
            .expect("a valid scenario")
    }

    /// The parts of [`patch_model`], to add to.
    pub(crate) fn patch_builder(
        order: usize,
        material: Box<dyn Material>,
        loads: Vec<Load>,
    ) -> ModelBuilder {
        let order = match order {
            1 => ElementOrder::Linear,
            2 => ElementOrder::Quadratic,
            _ => ElementOrder::Cubic,
        };
        let mesh = rectangle([0.1, 0.1], [3, 2], Pattern::Alternate, [0.0; 3], order);
        let section = Section {
            thickness: 6e-4,
            prestress: 0.0,
        };
        Model::builder(mesh, material, section, 320.0).loads(loads)
    }

    /// The patch stretched along x, compressed along y (so wrinkling
    /// models see taut, wrinkled and slack points), sheared and lifted
    /// into a wave.
    pub(crate) fn deformed(model: &Model) -> Vec<f64> {
        model
            .initial_positions()
            .chunks(3)
            .flat_map(|x| {
                [
                    1.03 * x[0] + 0.01 * x[1],
                    (0.97 + 0.5 * x[0]) * x[1],
                    0.02 * (20.0 * x[0]).sin() * (1.0 + 10.0 * x[1]),
                ]
            })
            .collect()
    }

    /// The dense Hessian of `term` at `y` (columns of the sparse pattern
    /// expanded), row-major.
    pub(crate) fn dense_hessian(
        term: &mut dyn StepTerm,
        ctx: &StepContext,
        pattern: &SparsePattern,
        y: &[f64],
    ) -> Vec<f64> {
        let n = y.len();
        let mut g = vec![0.0; n];
        let mut h = vec![f64::NAN; pattern.nnz()];
        if !term.overwrites() {
            h.fill(0.0);
        }
        term.add(ctx, y, &mut g, Some(&mut h));
        let mut dense = vec![0.0; n * n];
        for col in 0..n {
            for k in pattern.col_ptr[col]..pattern.col_ptr[col + 1] {
                dense[pattern.row_idx[k] * n + col] = h[k];
            }
        }
        dense
    }

    /// The projection check of a step term at `y`: its Hessian with every
    /// stencil projected ([`StepContext::project`] all set) must be
    /// positive semi-definite (smallest eigenvalue at least `-1e-12` of
    /// the largest magnitude: round-off of the sums), and its gradient
    /// must be the exact one (a projection touches the Hessian only).
    /// Returns the exact and the projected dense Hessians and the
    /// projected one's smallest eigenvalue relative to its largest
    /// magnitude.
    pub(crate) fn check_projection(
        term: &mut dyn StepTerm,
        ctx: &StepContext,
        pattern: &SparsePattern,
        y: &[f64],
    ) -> (Vec<f64>, Vec<f64>, f64) {
        let n = y.len();
        let exact = dense_hessian(term, ctx, pattern, y);
        let flags = vec![true; n / 3];
        let all = StepContext {
            project: Some(&flags),
            ..*ctx
        };
        let projected = dense_hessian(term, &all, pattern, y);
        let (g, _) = gradient(term, ctx, y);
        let (gp, _) = gradient(term, &all, y);
        assert_eq!(g, gp, "a projection changes the Hessian only");
        let smallest = relative_smallest_eigenvalue(&projected, n);
        (exact, projected, smallest)
    }

    /// The smallest eigenvalue of a dense symmetric `n x n` matrix
    /// relative to its largest magnitude.
    pub(crate) fn relative_smallest_eigenvalue(h: &[f64], n: usize) -> f64 {
        let a = faer::Mat::from_fn(n, n, |i, j| h[i * n + j]);
        let eig = a
            .self_adjoint_eigenvalues(faer::Side::Lower)
            .expect("eigenvalues");
        let largest = eig.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let smallest = eig.iter().copied().fold(f64::INFINITY, f64::min);
        smallest / largest.max(f64::MIN_POSITIVE)
    }

    /// The gradient (residual contribution) of `term` at `y`.
    fn gradient(term: &mut dyn StepTerm, ctx: &StepContext, y: &[f64]) -> (Vec<f64>, f64) {
        let mut g = vec![0.0; y.len()];
        let v = term.add(ctx, y, &mut g, None);
        (g, v.value)
    }

    /// The generic finite-difference check of a step term at `y`: its
    /// Hessian against central differences of its gradient, and, for a
    /// potential, its gradient against central differences of its value.
    /// Returns the two relative errors (the second 0 for a term that is
    /// not a potential). `h`: the difference step (m).
    pub(crate) fn check_term(
        term: &mut dyn StepTerm,
        ctx: &StepContext,
        pattern: &SparsePattern,
        y: &[f64],
        h: f64,
    ) -> (f64, f64) {
        let term = std::cell::RefCell::new(term);
        let hess = dense_hessian(&mut **term.borrow_mut(), ctx, pattern, y);
        let hessian_err = jacobian_error(
            |x| gradient(&mut **term.borrow_mut(), ctx, x).0,
            |_| hess.clone(),
            y,
            h,
        );
        let (_, v0) = {
            let mut g = vec![0.0; y.len()];
            let v = term.borrow_mut().add(ctx, y, &mut g, None);
            (g, v)
        };
        let gradient_err = if v0.potential {
            let (g0, _) = gradient(&mut **term.borrow_mut(), ctx, y);
            gradient_error(
                |x| gradient(&mut **term.borrow_mut(), ctx, x).1,
                |_| g0.clone(),
                y,
                h,
            )
        } else {
            0.0
        };
        (hessian_err, gradient_err)
    }
}
