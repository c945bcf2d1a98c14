//! Static analysis: the loads are scaled by a factor `lambda` that rises
//! linearly from 0 to 1 over the steps (ramps of individual loads are
//! ignored), and each step solves `F_int(Y) = lambda F_ext(Y)` by Newton.
//!
//! When it applies: the static Hessian `K` of a membrane is singular
//! wherever the membrane carries no tension (an unstressed flat membrane
//! has no stiffness across its plane). Static analysis therefore needs a
//! configuration that is tensioned from the first step on: a `prestress`,
//! or supports that stretch it. A slack membrane (a fabric hanging or
//! draping, a flat membrane under the first increment of pressure) needs a
//! dynamic analysis, which the mass term regularises; run it to rest with
//! `beta = 1, gamma = 1.5` for a static solution.

use super::{State, StepTerms, solve_step};
use crate::integrator::newmark::{DynamicWorkspace, StepOutcome};
use crate::model::Model;
use crate::solver::newton::{NewtonError, NewtonSettings};

/// Load stepping: each step raises the load factor by the increment it
/// is given (the schedule's `1 / steps`) and solves for equilibrium.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StaticStepper;

impl StaticStepper {
    /// Advances the load factor `state.time` by `dlambda` and solves for
    /// equilibrium. Velocities and accelerations stay zero. On error `state`
    /// is unchanged.
    pub fn step(
        &self,
        model: &Model,
        state: &mut State,
        dlambda: f64,
        settings: &NewtonSettings,
        length: f64,
        ws: &mut DynamicWorkspace,
    ) -> Result<StepOutcome, NewtonError> {
        let lambda = (state.time + dlambda).min(1.0 + 1e-12);
        model.dead_forces(lambda, Some(lambda), &mut ws.dead);
        ws.old_ext.copy_from_slice(&ws.f_ext);
        ws.y.copy_from_slice(&state.positions);
        let terms = StepTerms {
            c: 0.0,
            q: &[],
            mq: &[],
            dead: &ws.dead,
            pressure: model.pressure_at(lambda, Some(lambda)),
            time: lambda,
            start: None,
        };
        let (report, energies) = solve_step(
            model,
            terms,
            &mut state.contact,
            &mut ws.y,
            length,
            settings,
            &mut ws.newton,
            &mut ws.f_ext,
            &ws.old_ext,
            &mut ws.my,
            &mut ws.grown,
        )?;
        let mut work = 0.0;
        for i in 0..ws.y.len() {
            work += 0.5 * (ws.old_ext[i] + ws.f_ext[i]) * (ws.y[i] - state.positions[i]);
        }
        std::mem::swap(&mut state.positions, &mut ws.y);
        state.time = lambda;
        state.external_work += work;
        Ok(StepOutcome {
            newton: report,
            energies,
        })
    }
}
