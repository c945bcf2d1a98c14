//! Bending hysteresis over a step: the frictional moment of bending as a
//! potential of the step, from the curvatures at its start (creeping) or
//! from the patches' plastic curvatures (a stick), and the stick's state
//! between steps: its return map, its start and its carry onto a finer
//! level (the formulas, the law and the citations:
//! [`crate::bending::hysteresis`]).

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use super::bending::add_patches;
use crate::bending::Bending;
use crate::bending::hysteresis::Hysteresis;
use crate::solver::SparsePattern;
use std::borrow::Cow;
use std::sync::atomic::{AtomicU64, Ordering};

/// The bending hysteresis of a step.
pub struct HysteresisTerm<'a> {
    bending: &'a Bending,
    law: Hysteresis,
    pattern: &'a SparsePattern,
    /// Each patch's reference curvatures: at the step's start (creeping),
    /// the state's plastic curvatures (a stick, borrowed).
    reference: Cow<'a, [[f64; 3]]>,
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
        plastic: &'a [[f64; 3]],
    ) -> Self {
        let reference = if law.sticks() {
            assert_eq!(plastic.len(), bending.patches().len(), "plastic curvatures");
            Cow::Borrowed(plastic)
        } else {
            Cow::Owned(bending.curvatures(start))
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

/// Loads a finer level's springs as the coarse level's were: `plastic`,
/// the fine patches' plastic curvatures with the springs unloaded (their
/// curvatures `kappa` at the level's start, [`initial_plastic`]), moved
/// to `kappa - delta`.
/// Each coarse patch's spring curvature `kappa - kappa_p` (at the coarse
/// state `coarse`) is a tensor of the reference plane, averaged over its
/// element's patches by area; each fine patch takes its coarse element's
/// tensor (`parent[e]`: the coarse element of fine element `e`) in its
/// own frame as `delta`. The fine patches of a coarse element lie in its
/// plane, so the tensor carries over unchanged (a spring's moment,
/// whatever the frames). Nothing without a stick.
pub(crate) fn carry_springs(
    (coarse_model, coarse): (&crate::model::Model, &crate::integrator::State),
    fine_model: &crate::model::Model,
    parent: &[usize],
    plastic: &mut [[f64; 3]],
) {
    let (Some((coarse_bending, _)), Some((fine_bending, _))) =
        (stick(coarse_model), stick(fine_model))
    else {
        return;
    };
    let mut tensors = vec![([[0.0; 3]; 3], 0.0); coarse_model.mesh().element_count()];
    let kappa = coarse_bending.curvatures(&coarse.positions);
    for ((p, k), kp) in coarse_bending
        .patches()
        .iter()
        .zip(kappa)
        .zip(&coarse.plastic)
    {
        // `2 kappa_12` in Voigt's third entry.
        let d = [k[0] - kp[0], k[1] - kp[1], 0.5 * (k[2] - kp[2])];
        let [e1, e2] = p.frame;
        let (t, area) = &mut tensors[p.element];
        for i in 0..3 {
            for j in 0..3 {
                t[i][j] += p.area
                    * (d[0] * (e1[i] * e1[j])
                        + d[1] * (e2[i] * e2[j])
                        + d[2] * (e1[i] * e2[j] + e2[i] * e1[j]));
            }
        }
        *area += p.area;
    }
    for (p, kp) in fine_bending.patches().iter().zip(plastic) {
        let (t, area) = &tensors[parent[p.element]];
        if *area == 0.0 {
            continue;
        }
        let [e1, e2] = p.frame;
        let along = |a: [f64; 3], b: [f64; 3]| {
            (0..3)
                .map(|i| (0..3).map(|j| a[i] * t[i][j] * b[j]).sum::<f64>())
                .sum::<f64>()
                / area
        };
        let delta = [along(e1, e1), along(e2, e2), 2.0 * along(e1, e2)];
        for j in 0..3 {
            kp[j] -= delta[j];
        }
    }
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
    use crate::integrator::terms::{bending_builder, check_term, folded};
    use crate::mesh::ElementOrder;
    use crate::mesh::generate::{Pattern, rectangle};

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
            let model = bending_builder(
                mesh,
                BendingRigidity::Woven {
                    warp: 3e-5,
                    weft: 1e-5,
                    direction: [1.0, 1.0, 0.0],
                },
            )
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

    /// A finer level's springs start loaded as the coarse level's were:
    /// a flat sheet whose springs hold a uniform curvature tensor, refined
    /// everywhere, gives each fine patch the same tensor — for a woven
    /// fabric (every frame along the warp) the same components, for an
    /// isotropic one (each frame along its triangle's first edge) the
    /// same invariants.
    #[test]
    fn a_finer_level_keeps_the_springs_loads() {
        let tensor = [[3.0, -1.5, 0.0], [-1.5, -2.0, 0.0], [0.0, 0.0, 0.0]];
        let voigt = |[e1, e2]: [[f64; 3]; 2]| {
            let along = |a: [f64; 3], b: [f64; 3]| {
                (0..3)
                    .map(|i| (0..3).map(|j| a[i] * tensor[i][j] * b[j]).sum::<f64>())
                    .sum::<f64>()
            };
            [along(e1, e1), along(e2, e2), 2.0 * along(e1, e2)]
        };
        for rigidity in [
            BendingRigidity::Isotropic(2e-5),
            BendingRigidity::Woven {
                warp: 3e-5,
                weft: 1e-5,
                direction: [1.0, 1.0, 0.0],
            },
        ] {
            let build = |mesh| {
                bending_builder(mesh, rigidity)
                    .bending_hysteresis(Some(Hysteresis {
                        moment: [3e-4, 2e-4],
                        hold: Hold::Stick { stiffness: 1e-4 },
                    }))
                    .build()
                    .expect("a valid model")
            };
            let mesh = rectangle(
                [0.1, 0.1],
                [4, 3],
                Pattern::Alternate,
                [0.0; 3],
                ElementOrder::Linear,
            );
            let refinement = crate::mesh::refine::refine(&mesh, &vec![true; mesh.element_count()])
                .expect("refined");
            let coarse = build(mesh);
            let fine = build(refinement.mesh.clone());
            let mut state = crate::integrator::State::at_rest(&coarse, coarse.initial_positions());
            let patches = coarse.bending().unwrap().patches();
            for (p, kp) in patches.iter().zip(&mut state.plastic) {
                let d = voigt(p.frame);
                *kp = [0, 1, 2].map(|j| kp[j] - d[j]);
            }
            let y = fine.initial_positions();
            let mut plastic = initial_plastic(&fine, &y);
            carry_springs((&coarse, &state), &fine, &refinement.parent, &mut plastic);
            let kappa = fine.bending().unwrap().curvatures(&y);
            let fine_patches = fine.bending().unwrap().patches();
            assert!(fine_patches.len() > 3 * patches.len());
            for ((p, k), kp) in fine_patches.iter().zip(kappa).zip(plastic) {
                let d = [0, 1, 2].map(|j| k[j] - kp[j]);
                let expected = voigt(p.frame);
                let what = format!("{rigidity:?}: {d:?} against {expected:?}");
                if matches!(rigidity, BendingRigidity::Woven { .. }) {
                    assert!((0..3).all(|j| (d[j] - expected[j]).abs() < 1e-9), "{what}");
                }
                // The tensor again from the fine patch's components and
                // frame (the sheet's plane holds both axes).
                let [e1, e2] = p.frame;
                for i in 0..3 {
                    for j in 0..3 {
                        let t = d[0] * e1[i] * e1[j]
                            + d[1] * e2[i] * e2[j]
                            + 0.5 * d[2] * (e1[i] * e2[j] + e2[i] * e1[j]);
                        assert!((t - tensor[i][j]).abs() < 1e-9, "{what}: T_{i}{j} {t}");
                    }
                }
            }
        }
    }
}
