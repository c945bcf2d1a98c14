//! The incremental potential of a step: the one place where every term of
//! the step's residual and Hessian is added up.
//!
//! An implicit step minimises (or, for terms that are not potentials,
//! solves the stationarity condition of) the incremental potential
//! (Kane, Marsden, Ortiz & West 2000, "Variational integrators and the
//! Newmark algorithm for conservative and dissipative mechanical
//! systems", Int. J. Numer. Meth. Engng 49; docs/theory.md):
//!
//! ```text
//! Pi(Y) = U(Y)                                   membrane strain energy
//!       + c/2 Y.M Y - Y.M Q_s                    inertia, c = 1/(beta dt^2)
//!       - F_dead . Y                             dead loads
//!       + sum 1/2 eta g_p(Y)^2 (g_p < 0)         penalty contact
//!       [+ bending, friction, barriers, ...]
//! G(Y) = dPi/dY (+ follower pressure, stress projection: terms with a
//!        residual and a tangent but no potential)
//! H(Y) = dG/dY
//! ```
//!
//! Each term is a [`StepTerm`]: its value, gradient and Hessian come
//! together, added into `G` and `H` on the model's sparse pattern. A new
//! term (bending, friction, self-contact) is one more implementation,
//! in its own module with its formula and its finite-difference test; the
//! terms know nothing of each other. The constraints — fixed components
//! (Dirichlet) and contact multipliers — are applied after the sum, by the
//! step system (`StepSystem` in `integrator`).
//!
//! When every term is a potential, [`IncrementalPotential::evaluate`]
//! reports `Pi`, and Newton's line search judges a step by it (Armijo on
//! the energy); otherwise by the residual.

use crate::contact::ContactState;

/// What a term sees of the step besides the positions.
#[derive(Debug, Clone, Copy)]
pub struct StepContext<'a> {
    /// Time at the end of the step (s), or the load factor in statics:
    /// where moving obstacles are.
    pub time: f64,
    /// Contact features and active set of the step, with obstacles.
    pub contact: Option<&'a ContactState>,
    /// Which stencil Hessians a term projects to their positive
    /// semi-definite part ([`crate::psd`]) before adding them: those of
    /// the stencils with a node flagged here (one flag per node; `None`:
    /// none, the exact Hessian). Newton asks for it where the exact
    /// Hessian is not positive definite (`solver::newton`, "projected
    /// Newton"); a term that is not a potential ignores it.
    pub project: Option<&'a [bool]>,
}

impl StepContext<'_> {
    /// Whether the stencil of `nodes` is to be projected.
    #[inline]
    pub fn projects(&self, nodes: &[usize]) -> bool {
        self.project
            .is_some_and(|flags| nodes.iter().any(|&a| flags[a]))
    }
}

/// Which nodes a term couples, so that the sparse pattern of the Hessian
/// (and the colouring of its parallel loop) includes them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stencils<'a> {
    /// Each node with itself only (diagonal 3x3 blocks: node-to-obstacle
    /// contact, lumped mass).
    Nodes,
    /// The mesh's elements (strain, consistent mass, pressure).
    Elements,
    /// Node lists of another family (e.g. the four nodes of a bending
    /// hinge), `nodes[ptr[k]..ptr[k + 1]]` for stencil `k`.
    Custom {
        /// Start of each stencil in `nodes`, one more than stencils.
        ptr: &'a [usize],
        /// The nodes of all stencils.
        nodes: &'a [usize],
    },
}

/// A term's contribution at one evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TermValue {
    /// The term's energy (J): its potential where it has one; otherwise
    /// the quantity it reports (the stress projection's `1/2 P : E`).
    pub value: f64,
    /// Whether `value` is a potential whose gradient the term added (then
    /// Newton may judge steps by the sum of the energies).
    pub potential: bool,
    /// Sum of the norms of the force vectors the term added (N): the scale
    /// of Newton's residual test.
    pub scale: f64,
}

/// One term of the incremental potential.
pub trait StepTerm {
    /// A short name, for reports.
    fn name(&self) -> &'static str;

    /// The node stencils whose Hessian blocks this term writes.
    fn stencils(&self) -> Stencils<'_>;

    /// Whether the term writes `g` and `h` rather than adding into them
    /// (every entry of both, so they need not be zeroed first): such a
    /// term can only be the first of a potential (the membrane, whose
    /// assembly writes every block of the pattern).
    fn overwrites(&self) -> bool {
        false
    }

    /// Once at the start of each step, from the step's first guess `y`:
    /// for quantities a term lags over the step (friction's normal force,
    /// a barrier's active pairs). Default: nothing.
    fn begin_step(&mut self, _ctx: &StepContext, _y: &[f64]) {}

    /// Adds the term's gradient to `g` and, if given, its Hessian to the
    /// values `h` on the model's pattern (a term that
    /// [`overwrites`](Self::overwrites) writes them instead); returns its
    /// value.
    fn add(
        &mut self,
        ctx: &StepContext,
        y: &[f64],
        g: &mut [f64],
        h: Option<&mut [f64]>,
    ) -> TermValue;

    /// The energy the term dissipated over the step, at its last
    /// evaluation (J): friction's work against the slip. Default 0.
    fn dissipation(&self) -> f64 {
        0.0
    }

    /// The energy the term stores at its last evaluation (J), counted with
    /// the bending energy: bending hysteresis's stick springs. Default 0.
    fn stored(&self) -> f64 {
        0.0
    }

    /// The work the moving obstacles did on the fabric through the term
    /// over the step, at its last evaluation (J): friction's force at the
    /// step's end on each node, dotted with its obstacle's displacement
    /// over the step. Default 0.
    fn obstacle_work(&self) -> f64 {
        0.0
    }

    /// Adds the Hessian couplings the term has outside the model's
    /// pattern — on `pattern`, a layout the stepper grew with them
    /// (`integrator::grown`), leaving out the rows and columns of the
    /// degrees of freedom `fixed` holds. Called only for a term built to
    /// leave them out of [`add`](Self::add) (self-contact). Default:
    /// nothing.
    fn add_outside(
        &mut self,
        _ctx: &StepContext,
        _y: &[f64],
        _values: &mut [f64],
        _pattern: &crate::solver::SparsePattern,
        _fixed: &[bool],
    ) {
    }

    /// The largest fraction `alpha` in `(0, 1]` of the increment `dy` that
    /// the term allows from `y` (a barrier's collision-free step, Li et
    /// al. 2020). Default 1: no limit.
    fn max_step(&self, _ctx: &StepContext, _y: &[f64], _dy: &[f64]) -> f64 {
        1.0
    }

    /// The symmetric low-rank part of the term's Hessian at its last
    /// evaluation with one, which [`add`](Self::add) left out of `h` (the
    /// gas's `-dp/dV g g^T`, dense): Newton's solves add it by Woodbury's
    /// identity (`solver::low_rank`). Default: none.
    fn low_rank(&self) -> Option<&crate::solver::low_rank::LowRank> {
        None
    }
}

/// The sum of the terms at one evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PotentialValue {
    /// `Pi(Y)` (J) when every term is a potential.
    pub energy: Option<f64>,
    /// Sum of the terms' scales (N).
    pub scale: f64,
}

/// The terms of a step, summed in order.
pub struct IncrementalPotential<'a> {
    terms: Vec<Box<dyn StepTerm + 'a>>,
    /// Each term's value at the last evaluation.
    values: Vec<TermValue>,
}

impl<'a> IncrementalPotential<'a> {
    /// The potential of `terms`, evaluated in this order (which fixes the
    /// floating-point sums: results are reproducible to the bit). Only the
    /// first term may [overwrite](StepTerm::overwrites) (a programming
    /// error otherwise: it would wipe out the terms before it).
    pub fn new(terms: Vec<Box<dyn StepTerm + 'a>>) -> Self {
        assert!(
            terms.iter().skip(1).all(|t| !t.overwrites()),
            "only the first term of a potential may overwrite G and H"
        );
        let values = vec![
            TermValue {
                value: 0.0,
                potential: true,
                scale: 0.0,
            };
            terms.len()
        ];
        Self { terms, values }
    }

    /// Calls every term's [`StepTerm::begin_step`].
    pub fn begin_step(&mut self, ctx: &StepContext, y: &[f64]) {
        for t in &mut self.terms {
            t.begin_step(ctx, y);
        }
    }

    /// Writes `G(y)` into `g` and, if asked, `H(y)` into `h`: the first
    /// term overwrites them if it does, otherwise they are zeroed first;
    /// every later term adds.
    pub fn evaluate(
        &mut self,
        ctx: &StepContext,
        y: &[f64],
        g: &mut [f64],
        mut h: Option<&mut [f64]>,
    ) -> PotentialValue {
        let fresh = self.terms.first().is_some_and(|t| t.overwrites());
        if !fresh {
            g.fill(0.0);
            if let Some(h) = h.as_deref_mut() {
                h.fill(0.0);
            }
        }
        let mut scale = 0.0;
        let mut energy = Some(0.0);
        for (k, term) in self.terms.iter_mut().enumerate() {
            let v = term.add(ctx, y, g, h.as_deref_mut());
            scale += v.scale;
            energy = energy.filter(|_| v.potential).map(|e| e + v.value);
            self.values[k] = v;
        }
        PotentialValue { energy, scale }
    }

    /// The value of the term named `name` at the last evaluation.
    pub fn value(&self, name: &str) -> Option<TermValue> {
        self.terms
            .iter()
            .zip(&self.values)
            .find(|(t, _)| t.name() == name)
            .map(|(_, v)| *v)
    }

    /// The energy the terms dissipated over the step at the last
    /// evaluation (J).
    pub fn dissipation(&self) -> f64 {
        self.terms.iter().map(|t| t.dissipation()).sum()
    }

    /// [`StepTerm::stored`] summed over the terms (J).
    pub fn stored(&self) -> f64 {
        self.terms.iter().map(|t| t.stored()).sum()
    }

    /// [`StepTerm::obstacle_work`] summed over the terms (J).
    pub fn obstacle_work(&self) -> f64 {
        self.terms.iter().map(|t| t.obstacle_work()).sum()
    }

    /// [`StepTerm::add_outside`] of every term.
    pub fn add_outside(
        &mut self,
        ctx: &StepContext,
        y: &[f64],
        values: &mut [f64],
        pattern: &crate::solver::SparsePattern,
        fixed: &[bool],
    ) {
        for t in &mut self.terms {
            t.add_outside(ctx, y, values, pattern, fixed);
        }
    }

    /// The smallest [`StepTerm::max_step`] of the terms.
    pub fn max_step(&self, ctx: &StepContext, y: &[f64], dy: &[f64]) -> f64 {
        self.terms
            .iter()
            .map(|t| t.max_step(ctx, y, dy))
            .fold(1.0, f64::min)
    }

    /// The terms' low-rank parts ([`StepTerm::low_rank`]) appended to
    /// `out`.
    pub fn low_rank(&self, out: &mut crate::solver::low_rank::LowRank) {
        for t in &self.terms {
            if let Some(low) = t.low_rank() {
                out.vectors.extend(low.vectors.iter().cloned());
                out.coefficients.extend_from_slice(&low.coefficients);
            }
        }
    }

    /// The names of the terms, in order.
    pub fn names(&self) -> Vec<&'static str> {
        self.terms.iter().map(|t| t.name()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::terms::{
        InertiaTerm, LoadTerm, MembraneTerm, check_term, deformed, patch_builder, patch_model,
    };
    use crate::load::{Load, LoadKind};
    use crate::material::SaintVenantKirchhoff;

    /// The whole potential as one term, for the finite-difference checker.
    struct Whole<'a>(IncrementalPotential<'a>);

    impl StepTerm for Whole<'_> {
        fn name(&self) -> &'static str {
            "whole"
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
            let v = self.0.evaluate(ctx, y, g, h);
            TermValue {
                value: v.energy.unwrap_or(f64::NAN),
                potential: v.energy.is_some(),
                scale: v.scale,
            }
        }
    }

    /// With bending, the membrane still overwrites G and H on the grown
    /// pattern (zeroing the blocks only bending's stencils touch) and the
    /// bending term adds into them: the sum's Hessian matches central
    /// differences of its gradient, for each element order.
    #[test]
    fn bending_adds_into_the_membranes_pattern() {
        use crate::bending::BendingRigidity;
        use crate::integrator::terms::BendingTerm;
        for order in 1..=3 {
            let model = patch_builder(order, Box::new(SaintVenantKirchhoff::new(2e6, 0.3)), vec![])
                .bending(BendingRigidity::Isotropic(2e-2))
                .build()
                .expect("bending");
            let bending = model.bending().expect("bending");
            let y = deformed(&model);
            let n = y.len();
            let q: Vec<f64> = y.iter().map(|v| 1e4 * (v - 0.003)).collect();
            let mut mq = vec![0.0; n];
            model.mass_times(&q, &mut mq);
            let mut my = vec![0.0; n];
            let potential = IncrementalPotential::new(vec![
                Box::new(MembraneTerm::new(&model)),
                Box::new(BendingTerm::new(bending, model.pattern())),
                Box::new(InertiaTerm::new(&model, 1e4, (&q, &mq), &mut my)),
            ]);
            let mut whole = Whole(potential);
            let ctx = StepContext {
                time: 1.0,
                contact: None,
                project: None,
            };
            let (eh, eg) = check_term(&mut whole, &ctx, model.pattern(), &y, 1e-7);
            assert!(eh < 1e-6, "order {order}: Hessian {eh:e}");
            assert!(eg < 1e-6, "order {order}: gradient {eg:e}");
        }
    }

    /// A dynamic step's potential (membrane, dead load, inertia) is a
    /// potential whose gradient and Hessian are the sum's: checked against
    /// central differences, with the membrane overwriting buffers full of
    /// NaN; with a follower pressure it is no potential, and says so.
    #[test]
    fn the_sum_of_the_terms_is_the_step_potential() {
        for pressure in [0.0, 300.0] {
            let load = Load {
                kind: LoadKind::Gravity {
                    acceleration: [0.0, 0.0, -9.8],
                },
                ramp: None,
            };
            let model = patch_model(2, Box::new(SaintVenantKirchhoff::new(2e6, 0.3)), vec![load]);
            let y = deformed(&model);
            let n = y.len();
            let mut dead = vec![0.0; n];
            model.dead_forces(1.0, None, &mut dead);
            let q: Vec<f64> = y.iter().map(|v| 1e4 * (v - 0.003)).collect();
            let mut mq = vec![0.0; n];
            model.mass_times(&q, &mut mq);
            let (mut f_ext, mut my) = (vec![0.0; n], vec![0.0; n]);
            let potential = IncrementalPotential::new(vec![
                Box::new(MembraneTerm::new(&model)),
                Box::new(LoadTerm::new(&model, &dead, pressure, &mut f_ext)),
                Box::new(InertiaTerm::new(&model, 1e4, (&q, &mq), &mut my)),
            ]);
            assert_eq!(potential.names(), ["membrane", "loads", "inertia"]);
            let mut whole = Whole(potential);
            let ctx = StepContext {
                time: 1.0,
                contact: None,
                project: None,
            };
            let mut g = vec![f64::NAN; n];
            let v = whole.add(&ctx, &y, &mut g, None);
            assert_eq!(v.potential, pressure == 0.0);
            let (eh, eg) = check_term(&mut whole, &ctx, model.pattern(), &y, 1e-7);
            assert!(eh < 1e-6, "p = {pressure}: Hessian {eh:e}");
            assert!(eg < 1e-6, "p = {pressure}: gradient {eg:e}");
        }
    }
}
