//! Time integration: Newmark-beta in positions (dynamic) and load stepping
//! (static), each step solved by Newton–Raphson (SPEC §1.6–1.7).

pub mod newmark;
pub mod statics;

pub use newmark::Newmark;
pub use statics::StaticStepper;

use crate::model::Model;
use crate::solver::newton::{Evaluation, NewtonSystem};

/// The state carried from step to step.
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    /// Time `t` (s); in a static analysis, the load factor.
    pub time: f64,
    /// Positions `Y` (m), flattened.
    pub positions: Vec<f64>,
    /// Velocities `V` (m/s).
    pub velocities: Vec<f64>,
    /// Accelerations `A` (m/s^2).
    pub accelerations: Vec<f64>,
    /// Work done by the external loads since the start (J), by the
    /// trapezoidal rule on each step: `1/2 (F_n + F_{n+1}) . (Y_{n+1} - Y_n)`.
    pub external_work: f64,
}

/// The residual `G = F_int - F_ext + c M Y - M Q` and Hessian `H = K -
/// dF_p/dY + c M` of one step (static: `c = 0`, no `M Q`).
pub(crate) struct StepSystem<'a> {
    pub model: &'a Model,
    /// `1 / (beta dt^2)`, or 0 in statics.
    pub c: f64,
    /// `M Q_s` (dynamic) or empty (static).
    pub mq: &'a [f64],
    /// Dead external forces of this step.
    pub dead: &'a [f64],
    /// Follower pressure of this step (Pa).
    pub pressure: f64,
    /// Last evaluation's internal and external forces, and `M Y`.
    pub f_int: &'a mut [f64],
    pub f_ext: &'a mut [f64],
    pub my: &'a mut [f64],
    /// Strain energy at the last evaluation (J).
    pub strain_energy: f64,
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

impl NewtonSystem for StepSystem<'_> {
    fn evaluate(&mut self, y: &[f64], g: &mut [f64], h: Option<&mut [f64]>) -> Evaluation {
        let model = self.model;
        self.f_ext.copy_from_slice(self.dead);
        let mut h = h;
        self.strain_energy =
            model.assemble(y, self.pressure, self.f_int, self.f_ext, h.as_deref_mut());
        let mut scale = norm(self.f_int) + norm(self.f_ext);
        if self.c != 0.0 {
            model.mass_times(y, self.my);
            for i in 0..g.len() {
                g[i] = self.f_int[i] - self.f_ext[i] + self.c * self.my[i] - self.mq[i];
            }
            scale += self.c * norm(self.my) + norm(self.mq);
            if let Some(h) = h.as_deref_mut() {
                model.add_mass_to_hessian(self.c, h);
            }
        } else {
            for i in 0..g.len() {
                g[i] = self.f_int[i] - self.f_ext[i];
            }
        }
        model.apply_supports(g, h.as_deref_mut());
        let symmetric = model.symmetric_by_construction()
            || h.is_some_and(|h| model.pattern.asymmetry(h) < 1e-10);
        Evaluation { scale, symmetric }
    }
}
