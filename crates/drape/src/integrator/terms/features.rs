//! The obstacles' sharp features against the fabric's triangles
//! (`[contact] features`, [`crate::contact::features`]): for every feature
//! point `p` through a triangle `(a, b, c)`, with `s` the squared distance
//! of `p` to the triangle's plane,
//!
//! ```text
//! Pi_f = sum 1/2 eta s,   dPi_f/dx = 1/2 eta ∇s,   d2Pi_f/dx^2 = 1/2 eta ∇²s
//! ```
//!
//! over the triangle's nodes `x = (a, b, c)` (the point is the obstacle's,
//! not an unknown). Each pair couples one triangle's three nodes. As the
//! nodes' penalty, the term adds nothing to Newton's force scale.

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use crate::contact::PenaltyHessian;
use crate::contact::features::{FeaturePair, ObstacleFeatures};
use crate::solver::SparsePattern;

/// The features' penalty of stiffness `eta` (N/m).
pub struct FeatureTerm<'a> {
    features: &'a ObstacleFeatures,
    pattern: &'a SparsePattern,
    stiffness: f64,
    /// The step's pairs, found at its first guess ([`StepTerm::begin_step`]).
    pairs: Vec<FeaturePair>,
    /// The step's size (s; 0 in a term without one): the moving
    /// obstacles' work over the step.
    dt: f64,
    /// That work at the last evaluation (J).
    worked: f64,
}

impl<'a> FeatureTerm<'a> {
    /// The term of `features` with the obstacles' penalty `stiffness`
    /// (N/m), adding its Hessian on `pattern`.
    pub fn new(features: &'a ObstacleFeatures, pattern: &'a SparsePattern, stiffness: f64) -> Self {
        Self {
            features,
            pattern,
            stiffness,
            pairs: Vec::new(),
            dt: 0.0,
            worked: 0.0,
        }
    }

    /// The term over a step of `dt`: [`StepTerm::obstacle_work`] then
    /// counts the moving obstacles' work through it.
    pub fn over(mut self, dt: f64) -> Self {
        self.dt = dt;
        self
    }
}

impl StepTerm for FeatureTerm<'_> {
    fn name(&self) -> &'static str {
        "obstacle features"
    }

    fn stencils(&self) -> Stencils<'_> {
        Stencils::Elements
    }

    /// The pairs of the step, fixed over its Newton iterations so that
    /// the energy is one smooth function for the step.
    fn begin_step(&mut self, ctx: &StepContext, y: &[f64]) {
        self.pairs = self.features.pairs(y, ctx.time);
    }

    fn add(
        &mut self,
        ctx: &StepContext,
        y: &[f64],
        g: &mut [f64],
        h: Option<&mut [f64]>,
    ) -> TermValue {
        let (value, power) = self.features.add_penalty(
            self.stiffness,
            &self.pairs,
            y,
            ctx.time,
            g,
            h.map(|values| PenaltyHessian {
                values,
                pattern: self.pattern,
                project: ctx.project,
            }),
        );
        self.worked = power * self.dt;
        TermValue {
            value,
            potential: true,
            scale: 0.0,
        }
    }

    fn obstacle_work(&self) -> f64 {
        self.worked
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::terms::{check_projection, check_term, contact_patch};

    /// A fixed obstacle's step context at `t = 0`, unprojected.
    const AT_START: StepContext<'static> = StepContext {
        time: 0.0,
        contact: None,
        project: None,
    };

    /// A 10 cm patch of 4 x 4 squares over a box whose top edges and
    /// corners stand `lift` above the patch's plane, off the mesh's lines,
    /// and the patch's nodes lifted into a gentle wave (so that the
    /// triangles' normals, and their derivatives, differ).
    fn patch_over_box(lift: f64) -> (crate::setup::Setup, Vec<f64>) {
        patch_over_moving_box(lift, [0.0; 3])
    }

    /// [`patch_over_box`] with the box moving at `velocity` (m/s).
    fn patch_over_moving_box(lift: f64, velocity: [f64; 3]) -> (crate::setup::Setup, Vec<f64>) {
        // Built clear of the box (a fabric may not start inside an
        // obstacle), then lowered onto it.
        let contact = format!(
            "[[obstacle]]\nshape = \"box\"\nmin = [-0.031, -0.037, -0.2]\nmax = [0.027, 0.033, -0.002]\n\
             velocity = {velocity:?}\n[contact]\nmethod = \"penalty\"\npenalty = 5.0e4\nfeatures = true"
        );
        let contact = contact.as_str();
        let setup = contact_patch(contact, 1e-3);
        let y = setup
            .model
            .initial_positions()
            .chunks(3)
            .flat_map(|x| {
                let wave = 1e-3 * (40.0 * x[0]).sin() * (30.0 * x[1]).cos();
                [x[0], x[1], wave - 0.002 - lift]
            })
            .collect();
        (setup, y)
    }

    /// Edges and corners 3 mm through a wavy patch: the features' value,
    /// gradient and Hessian (with the normal's derivatives) against
    /// central differences, and the projected Hessian semi-definite.
    #[test]
    fn feature_term_matches_finite_differences() {
        let (setup, y) = patch_over_box(3e-3);
        let model = &setup.model;
        let features = model.obstacle_features().expect("a box has features");
        let ctx = AT_START;
        let mut term = FeatureTerm::new(features, model.pattern(), 5.0e4);
        term.begin_step(&ctx, &y);
        let through = (term.pairs.iter())
            .filter(|p| features.depth(p, &y, 0.0) > 0.0)
            .count();
        assert!(through >= 8, "points through the patch: {through}");
        let (eh, eg) = check_term(&mut term, &ctx, model.pattern(), &y, 1e-8);
        assert!(eh < 1e-6, "Hessian {eh:e}");
        assert!(eg < 1e-6, "gradient {eg:e}");
        let (_, _, smallest) = check_projection(&mut term, &ctx, model.pattern(), &y);
        assert!(smallest > -1e-12, "projected {smallest:e}");
    }

    /// The work of a moving box through its features over a step of `dt`
    /// (issue 46) is the energy's change as the box moves at fixed
    /// positions, `dt dC/dt`, against central differences in time.
    #[test]
    fn a_moving_boxs_work_through_its_features_is_the_energys_time_derivative() {
        let velocity = [0.3, -0.2, 0.1];
        let (setup, y) = patch_over_moving_box(3e-3, velocity);
        let model = &setup.model;
        let features = model.obstacle_features().expect("a box has features");
        let (t, dt, delta) = (0.0, 1e-3, 1e-6);
        let ctx = StepContext {
            time: t,
            ..AT_START
        };
        let mut term = FeatureTerm::new(features, model.pattern(), 5.0e4).over(dt);
        term.begin_step(&ctx, &y);
        let mut g = vec![0.0; y.len()];
        term.add(&ctx, &y, &mut g, None);
        let work = term.obstacle_work();
        let energy = |t: f64| {
            features
                .add_penalty(5.0e4, &term.pairs, &y, t, &mut g.clone(), None)
                .0
        };
        let expected = dt * (energy(t + delta) - energy(t - delta)) / (2.0 * delta);
        assert!(work.abs() > 1e-9, "work {work:e}");
        assert!(
            (work - expected).abs() < 1e-6 * expected.abs(),
            "{work:e} against {expected:e}"
        );
        // A fixed box, or a term without a step, does no work.
        let still = FeatureTerm::new(features, model.pattern(), 5.0e4);
        assert_eq!(still.obstacle_work(), 0.0);
    }

    /// The same box 3 mm below the patch: its points have triangles near
    /// them but none passes through, and the term adds nothing (not even
    /// a zero), its energy 0.
    #[test]
    fn features_below_the_fabric_add_nothing() {
        let (setup, y) = patch_over_box(-3e-3);
        let model = &setup.model;
        let features = model.obstacle_features().expect("a box has features");
        assert_eq!(features.deepest(&y, 0.0), 0.0);
        let ctx = AT_START;
        let mut term = FeatureTerm::new(features, model.pattern(), 5.0e4);
        term.begin_step(&ctx, &y);
        assert!(!term.pairs.is_empty(), "points near the patch, below it");
        let mut g = vec![f64::NAN; y.len()];
        let mut h = vec![f64::NAN; model.pattern().nnz()];
        let v = term.add(&ctx, &y, &mut g, Some(&mut h));
        assert_eq!(v.value, 0.0);
        assert!(g.iter().chain(&h).all(|v| v.is_nan()), "nothing written");
    }
}
