//! Bending hysteresis over a step: the frictional moment of bending as a
//! dissipation potential of the step, from the curvatures at its start
//! (the formulas, the law and the citations: [`crate::bending::hysteresis`]).

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use super::bending::add_patches;
use crate::bending::Bending;
use crate::bending::hysteresis::Hysteresis;
use crate::solver::SparsePattern;
use std::sync::atomic::{AtomicU64, Ordering};

/// The bending hysteresis of a step.
pub struct HysteresisTerm<'a> {
    bending: &'a Bending,
    law: Hysteresis,
    pattern: &'a SparsePattern,
    /// Each patch's reference curvatures: at the step's start (creeping),
    /// the plastic curvatures (a stick).
    reference: Vec<[f64; 3]>,
    /// The smoothing `e` (N/m) of the step.
    smooth: f64,
    forces: Vec<f64>,
    /// Each patch's dissipation and stored energy at the last evaluation
    /// (J), as bits: the patches run on several threads, and are summed
    /// in their order.
    energies: Vec<[AtomicU64; 2]>,
}

impl<'a> HysteresisTerm<'a> {
    /// The hysteresis `law` of `bending`'s patches over the step of size
    /// `dt` from positions `start` (in statics, the load increment);
    /// with a stick, from the patches' plastic curvatures `plastic`
    /// ([`crate::integrator::State::plastic`]) instead.
    pub fn new(
        bending: &'a Bending,
        law: Hysteresis,
        pattern: &'a SparsePattern,
        (start, dt): (&[f64], f64),
        plastic: &[[f64; 3]],
    ) -> Self {
        let reference = if law.sticks() {
            assert_eq!(plastic.len(), bending.patches().len(), "plastic curvatures");
            plastic.to_vec()
        } else {
            bending.curvatures(start)
        };
        let energies = reference.iter().map(|_| Default::default()).collect();
        Self {
            bending,
            law,
            pattern,
            reference,
            smooth: law.smoothing(dt),
            forces: Vec::new(),
            energies,
        }
    }

    /// One of the two energies summed over the patches.
    fn energy(&self, which: usize) -> f64 {
        (self.energies.iter())
            .map(|d| f64::from_bits(d[which].load(Ordering::Relaxed)))
            .sum()
    }
}

impl StepTerm for HysteresisTerm<'_> {
    fn name(&self) -> &'static str {
        "bending hysteresis"
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
        let patches = self.bending.patches();
        let (law, reference, smooth) = (&self.law, &self.reference, self.smooth);
        let energies = &self.energies;
        add_patches(
            (self.bending, self.pattern),
            &mut self.forces,
            (ctx, y),
            (g, h),
            &|k, kappa| {
                let v = law.patch(patches[k].area, reference[k], kappa, smooth);
                energies[k][0].store(v.dissipated.to_bits(), Ordering::Relaxed);
                energies[k][1].store(v.stored.to_bits(), Ordering::Relaxed);
                Some(v.law)
            },
        )
    }

    fn dissipation(&self) -> f64 {
        self.energy(0)
    }

    fn stored(&self) -> f64 {
        self.energy(1)
    }
}

/// The model's bending and its hysteresis, if that is a stick.
fn stick(model: &crate::model::Model) -> Option<(&Bending, Hysteresis)> {
    let law = model.bending_hysteresis().filter(Hysteresis::sticks)?;
    Some((model.bending()?, law))
}

/// The return map of a stick hysteresis at a step's end: each patch's
/// plastic curvature in `plastic` moved by its slip at the positions `y`
/// ([`Hysteresis::slip`]). Nothing without a stick.
pub(crate) fn slip(model: &crate::model::Model, y: &[f64], plastic: &mut [[f64; 3]]) {
    if let Some((bending, law)) = stick(model) {
        let e = law.smoothing(0.0);
        for (p, kappa) in plastic.iter_mut().zip(bending.curvatures(y)) {
            law.slip(p, kappa, e);
        }
    }
}

/// The patches' plastic curvatures a run starts from at positions `y`:
/// their curvatures there (the sticks unloaded), with a stick hysteresis;
/// none otherwise.
pub(crate) fn initial_plastic(model: &crate::model::Model, y: &[f64]) -> Vec<[f64; 3]> {
    stick(model).map_or_else(Vec::new, |(bending, _)| bending.curvatures(y))
}

/// How many plastic curvatures a run of `model` keeps: one per bending
/// patch with a stick hysteresis, none otherwise.
pub(crate) fn plastic_count(model: &crate::model::Model) -> usize {
    stick(model).map_or(0, |(bending, _)| bending.patches().len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bending::BendingRigidity;
    use crate::bending::hysteresis::Hold;
    use crate::element::membrane::Section;
    use crate::integrator::terms::{check_term, folded};
    use crate::material::SaintVenantKirchhoff;
    use crate::mesh::ElementOrder;
    use crate::mesh::generate::{Pattern, rectangle};
    use crate::model::Model;

    /// The term's gradient and Hessian against finite differences, from a
    /// flat and a rolled start, for changes within the smoothing and
    /// beyond it, orders 1–3, isotropic and woven.
    #[test]
    fn hysteresis_term_matches_finite_differences() {
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
            let model = Model::builder(
                mesh,
                Box::new(SaintVenantKirchhoff::new(2e6, 0.3)),
                Section {
                    thickness: 6e-4,
                    prestress: 0.0,
                },
                320.0,
            )
            .bending(BendingRigidity::Woven {
                warp: 3e-5,
                weft: 1e-5,
                direction: [1.0, 1.0, 0.0],
            })
            .build()
            .expect("a valid model");
            let bending = model.bending().expect("bending");
            for moment in [[6e-4, 6e-4], [6e-4, 2e-4]] {
                for (from, to, dt) in [(0.0, 1.0, 1.0), (1.0, 1.02, 1.0), (0.5, 3.0, 0.1)] {
                    let start = folded(&model, from);
                    let y = folded(&model, to);
                    // Creeping from the start; a stick from the start's
                    // curvatures, with the creeping law's smoothing.
                    for hold in [
                        Hold::Creep { rate: 1.0 },
                        Hold::Stick {
                            stiffness: moment[0] / dt,
                        },
                    ] {
                        let law = Hysteresis { moment, hold };
                        let plastic = bending.curvatures(&start);
                        let mut term = HysteresisTerm::new(
                            bending,
                            law,
                            model.pattern(),
                            (&start, dt),
                            if law.sticks() { &plastic } else { &[] },
                        );
                        // A norm of the curvature change has large third
                        // derivatives where the change is small: the
                        // errors fall as the step squared down to 1 nm
                        // (measured on T6 from the 1.0 roll to 1.02:
                        // 1.2e-4, 9.1e-6 and 6.4e-7 at 1e-7, 1e-8 and
                        // 1e-9 m), round-off below.
                        let (eh, eg) = check_term(&mut term, &ctx, model.pattern(), &y, 1e-9);
                        let what =
                            format!("{order:?} {moment:?} {hold:?} from {from} to {to}, dt {dt}");
                        assert!(eh < 1e-5, "{what}: Hessian {eh:e}");
                        assert!(eg < 1e-6, "{what}: gradient {eg:e}");
                        // A stick holds the small change on its springs,
                        // slips past them on the large ones.
                        let slips = !law.sticks() || to - from > 0.1;
                        assert_eq!(term.dissipation() > 0.0, slips, "{what}");
                        assert_eq!(term.stored() > 0.0, law.sticks(), "{what}");
                    }
                }
            }
        }
    }
}
