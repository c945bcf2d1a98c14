//! The gas in the model's cavities (docs/theory.md §1.16; `load::gas`,
//! `load::cavity`): for each cavity, with the step's law `p(V)`,
//!
//! ```text
//! Pi_gas = E(V) + p_amb V                      (E' = -p)
//! G     += -(p - p_amb) g,                     g = dV/dY
//! H      = -(p - p_amb) d2V/dY2  +  (-dp/dV) g g^T
//! ```
//!
//! The first part of `H` is sparse (element by element, like a follower
//! pressure's tangent, but each element's block symmetric) and goes into
//! the Hessian on the model's pattern; the second couples every node of
//! the cavity with every other and is reported apart as a rank-one part
//! ([`StepTerm::low_rank`]), which Newton's solves add by Woodbury's
//! identity (`solver::low_rank`). `-dp/dV > 0`, so the rank-one part is
//! positive semi-definite and a projected Newton projects only the sparse
//! part (per element). The term is a potential: Newton's line search sees
//! the gas's energy.

use super::super::potential::{Stencils, StepContext, StepTerm, TermValue};
use crate::load::gas::GasStep;
use crate::model::Model;
use crate::solver::low_rank::LowRank;
use crate::vecn::norm;

/// The gas of every cavity over one step.
pub struct GasTerm<'a> {
    model: &'a Model,
    /// Each cavity's law over the step.
    steps: &'a [GasStep],
    /// Each cavity's `dV/dY` at the last evaluation.
    gradients: Vec<Vec<f64>>,
    /// The rank-one parts of the last evaluation with a Hessian.
    low: LowRank,
    /// Each cavity's volume at the last evaluation (m^3).
    volumes: Vec<f64>,
}

impl<'a> GasTerm<'a> {
    /// The gas of `model`'s cavities, following `steps` (one per cavity).
    pub fn new(model: &'a Model, steps: &'a [GasStep]) -> Self {
        let n = model.dofs();
        Self {
            model,
            steps,
            gradients: vec![vec![0.0; n]; steps.len()],
            low: LowRank::default(),
            volumes: vec![0.0; steps.len()],
        }
    }

    /// Each cavity's volume at the last evaluation (m^3).
    pub fn volumes(&self) -> &[f64] {
        &self.volumes
    }
}

impl StepTerm for GasTerm<'_> {
    fn name(&self) -> &'static str {
        "gas"
    }

    fn stencils(&self) -> Stencils<'_> {
        Stencils::Elements
    }

    fn add(
        &mut self,
        ctx: &StepContext,
        y: &[f64],
        g: &mut [f64],
        mut h: Option<&mut [f64]>,
    ) -> TermValue {
        let mut value = 0.0;
        let mut scale = 0.0;
        if h.is_some() {
            self.low.clear();
        }
        for (k, (cavity, step)) in self.model.cavities().iter().zip(self.steps).enumerate() {
            let dv = &mut self.gradients[k];
            let v = cavity.surface.volume_gradient(y, dv);
            self.volumes[k] = v;
            if v <= 0.0 {
                // No gas state there: an infinite energy, which the line
                // search never accepts.
                value = f64::INFINITY;
                continue;
            }
            value += step.potential(v);
            let net = step.law.pressure(v) - step.ambient;
            for (gi, di) in g.iter_mut().zip(dv.iter()) {
                *gi -= net * di;
            }
            scale += net.abs() * norm(dv);
            if let Some(h) = h.as_deref_mut() {
                let model = self.model;
                cavity.surface.hessians(
                    y,
                    -net,
                    |nodes| ctx.projects(nodes),
                    |e, _, ke| model.add_element_matrix(e, ke, h),
                );
                self.low.vectors.push(dv.clone());
                self.low.coefficients.push(step.law.stiffness(v));
            }
        }
        TermValue {
            value,
            potential: true,
            scale,
        }
    }

    fn low_rank(&self) -> Option<&LowRank> {
        (!self.low.is_empty()).then_some(&self.low)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::terms::dense_hessian;
    use crate::load::cavity::Cavity;
    use crate::load::gas::{Gas, GasCavity, GasLaw, InitialGas};
    use crate::material::SaintVenantKirchhoff;
    use crate::mesh::ElementOrder;
    use crate::mesh::generate::sphere;

    /// A closed sphere of `order` with gas following `law`, at 1.3 times
    /// ambient pressure.
    fn balloon(order: ElementOrder, law: GasLaw) -> Model {
        let mesh = sphere(0.2, 1, [0.0; 3], order);
        let elements = (0..mesh.element_count()).collect();
        let surface = Cavity::new(&mesh, elements, None, 0.0, &[]).expect("closed");
        let gas = Gas {
            law,
            gamma: 1.4,
            gas_constant: 287.0,
            ambient: 101_325.0,
            inflator: None,
            vents: Vec::new(),
        };
        let initial = InitialGas {
            pressure: 1.3 * 101_325.0,
            mass: None,
            temperature: 293.15,
        };
        let section = crate::element::membrane::Section {
            thickness: 5e-4,
            prestress: 0.0,
        };
        Model::builder(
            mesh,
            Box::new(SaintVenantKirchhoff::new(1e6, 0.3)),
            section,
            1000.0,
        )
        .cavities(vec![GasCavity {
            surface,
            gas,
            initial,
        }])
        .build()
        .expect("model")
    }

    /// The term's energy, gradient and its full Hessian — the sparse part
    /// on the pattern plus the rank-one part — against central
    /// differences, both laws and every order, on a deformed balloon; the
    /// rank-one part alone is `-dp/dV g g^T` with `g` the term's own
    /// gradient per unit net pressure. Tolerances as in `check_term`.
    #[test]
    fn gas_term_full_hessian_matches_finite_differences() {
        for p in 1..=3 {
            for law in [GasLaw::Isothermal, GasLaw::Adiabatic] {
                let order = ElementOrder::from_degree(p).expect("order");
                let model = balloon(order, law);
                let y0 = model.initial_positions();
                let cavity = &model.cavities()[0];
                let state = cavity.initial_state(&y0);
                let steps = [cavity.gas.begin_step(&state, 0.0, 1e-3)];
                let y: Vec<f64> = y0
                    .chunks(3)
                    .flat_map(|x| {
                        let s = (7.0 * x[0] - 5.0 * x[2]).sin();
                        [x[0] * (1.0 + 0.1 * s), x[1] + 0.01 * s, x[2] * 1.05]
                    })
                    .collect();
                let n = y.len();
                let ctx = StepContext {
                    time: 1e-3,
                    contact: None,
                    project: None,
                };
                let mut term = GasTerm::new(&model, &steps);
                let mut full = dense_hessian(&mut term, &ctx, model.pattern(), &y);
                let low = term.low_rank().expect("a rank-one part").clone();
                assert_eq!(low.vectors.len(), 1);
                for col in 0..n {
                    let mut e = vec![0.0; n];
                    e[col] = 1.0;
                    let mut column = vec![0.0; n];
                    low.add_product(&e, &mut column);
                    for row in 0..n {
                        full[row * n + col] += column[row];
                    }
                }
                let term = std::cell::RefCell::new(term);
                let gradient = |x: &[f64]| {
                    let mut g = vec![0.0; n];
                    term.borrow_mut().add(&ctx, x, &mut g, None);
                    g
                };
                let energy = |x: &[f64]| {
                    let mut g = vec![0.0; n];
                    term.borrow_mut().add(&ctx, x, &mut g, None).value
                };
                let eg = crate::fd::gradient_error(energy, gradient, &y, 1e-7);
                let eh = crate::fd::jacobian_error(gradient, |_| full.clone(), &y, 1e-7);
                assert!(eg < 1e-6, "order {p} {law:?}: gradient {eg:e}");
                assert!(eh < 1e-6, "order {p} {law:?}: Hessian {eh:e}");
                // The rank-one vector is dV/dY: the gradient over -(p - p_amb).
                let g = gradient(&y);
                let v = term.borrow().volumes()[0];
                let net = steps[0].law.pressure(v) - steps[0].ambient;
                let worst = g
                    .iter()
                    .zip(&low.vectors[0])
                    .map(|(gi, ui)| (gi + net * ui).abs())
                    .fold(0.0, f64::max);
                assert!(worst <= 1e-12 * norm(&g), "order {p}: {worst:e}");
                assert!(low.coefficients[0] > 0.0);
            }
        }
    }
}
