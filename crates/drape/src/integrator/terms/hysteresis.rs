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
    /// Each patch's curvatures at the step's start.
    start: Vec<[f64; 3]>,
    /// The smoothing `e` (N/m) of the step.
    smooth: f64,
    forces: Vec<f64>,
    /// Each patch's dissipation at the last evaluation (J), as bits: the
    /// patches run on several threads, and are summed in their order.
    dissipated: Vec<AtomicU64>,
}

impl<'a> HysteresisTerm<'a> {
    /// The hysteresis `law` of `bending`'s patches over the step of size
    /// `dt` from positions `start` (in statics, the load increment).
    pub fn new(
        bending: &'a Bending,
        law: Hysteresis,
        pattern: &'a SparsePattern,
        (start, dt): (&[f64], f64),
    ) -> Self {
        let mut x = [[0.0; 3]; crate::bending::kernel::MAX_NODES];
        let start = bending
            .patches()
            .iter()
            .map(|p| {
                p.positions(
                    |a| [start[3 * a], start[3 * a + 1], start[3 * a + 2]],
                    &mut x,
                );
                p.curvature(&x[..p.len()])
            })
            .collect::<Vec<_>>();
        let dissipated = start.iter().map(|_| AtomicU64::new(0)).collect();
        Self {
            bending,
            law,
            pattern,
            start,
            smooth: law.smoothing(dt),
            forces: Vec::new(),
            dissipated,
        }
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
        let (law, start, smooth) = (&self.law, &self.start, self.smooth);
        let dissipated = &self.dissipated;
        add_patches(
            (self.bending, self.pattern),
            &mut self.forces,
            (ctx, y),
            (g, h),
            &|k, kappa| {
                let (moments, work) = law.patch(patches[k].area, start[k], kappa, smooth);
                dissipated[k].store(work.to_bits(), Ordering::Relaxed);
                Some(moments)
            },
        )
    }

    fn dissipation(&self) -> f64 {
        (self.dissipated.iter())
            .map(|d| f64::from_bits(d.load(Ordering::Relaxed)))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bending::BendingRigidity;
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
                let law = Hysteresis { moment, rate: 1.0 };
                for (from, to, dt) in [(0.0, 1.0, 1.0), (1.0, 1.02, 1.0), (0.5, 3.0, 0.1)] {
                    let start = folded(&model, from);
                    let y = folded(&model, to);
                    let mut term = HysteresisTerm::new(bending, law, model.pattern(), (&start, dt));
                    // A norm of the curvature change has large third
                    // derivatives where the change is small: the errors
                    // fall as the step squared down to 1 nm (measured on
                    // T6 from the 1.0 roll to 1.02: 1.2e-4, 9.1e-6 and
                    // 6.4e-7 at 1e-7, 1e-8 and 1e-9 m), round-off below.
                    let (eh, eg) = check_term(&mut term, &ctx, model.pattern(), &y, 1e-9);
                    let what = format!("{order:?} {moment:?} from {from} to {to}, dt {dt}");
                    assert!(eh < 1e-5, "{what}: Hessian {eh:e}");
                    assert!(eg < 1e-6, "{what}: gradient {eg:e}");
                    assert!(term.dissipation() > 0.0, "{what}");
                }
            }
        }
    }
}
