//! Newmark-beta in positions (SPEC §1.6):
//!
//! ```text
//! Q_s     = Y_s/(beta dt^2) + V_s/(beta dt) + (1/(2 beta) - 1) A_s
//! A_{s+1} = Y_{s+1}/(beta dt^2) - Q_s
//! V_{s+1} = V_s + (1 - gamma) dt A_s + gamma dt A_{s+1}
//! G(Y)    = F_int(Y) + M (Y/(beta dt^2) - Q_s) - F_ext(Y)
//! ```
//!
//! The first guess is the predictor `Y_s + dt V_s + dt^2/2 A_s`, which
//! satisfies the step exactly when the acceleration does not change (free
//! fall under a uniform load, for any `beta`, `gamma`).

use super::{State, StepTerms, solve_step};
use crate::model::Model;
use crate::solver::newton::{NewtonError, NewtonReport, NewtonSettings, NewtonWorkspace};

/// Newmark parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Newmark {
    /// `beta` (> 0).
    pub beta: f64,
    /// `gamma` (>= 1/2 for stability).
    pub gamma: f64,
}

/// Buffers of a dynamic run.
#[derive(Debug)]
pub struct DynamicWorkspace {
    q: Vec<f64>,
    mq: Vec<f64>,
    dead: Vec<f64>,
    /// Internal forces at the last converged state.
    pub f_int: Vec<f64>,
    /// External forces at the last converged state.
    pub f_ext: Vec<f64>,
    my: Vec<f64>,
    /// Newton buffers and the linear solver.
    pub newton: NewtonWorkspace,
}

impl DynamicWorkspace {
    /// Buffers for `model`, with direct linear solves.
    pub fn new(model: &Model) -> Result<Self, crate::solver::LinearSolveError> {
        Self::with_mode(model, crate::solver::LinearMode::Direct)
    }

    /// Buffers for `model`, solving linear systems as `mode` says.
    pub fn with_mode(
        model: &Model,
        mode: crate::solver::LinearMode,
    ) -> Result<Self, crate::solver::LinearSolveError> {
        let n = model.dofs();
        let (node_ptr, node_rows) = model.pattern.node_graph();
        let linear =
            crate::solver::LinearSolver::new(&model.pattern.col_ptr, &model.pattern.row_idx)?
                .with_transpose(model.pattern.transpose_map().to_vec())
                .with_node_blocks(node_ptr, node_rows)
                .with_mode(mode);
        Ok(Self {
            q: vec![0.0; n],
            mq: vec![0.0; n],
            dead: vec![0.0; n],
            f_int: vec![0.0; n],
            f_ext: vec![0.0; n],
            my: vec![0.0; n],
            newton: NewtonWorkspace::new(n, model.pattern.nnz(), linear),
        })
    }
}

/// Outcome of a converged step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepOutcome {
    /// Newton's report.
    pub newton: NewtonReport,
    /// Strain energy at the end of the step (J).
    pub strain_energy: f64,
}

impl Newmark {
    /// The initial state at rest in the initial configuration, with `A_0 =
    /// M^{-1} (F_ext(0) - F_int(X))` (zero at fixed components).
    pub fn initial_state(
        &self,
        model: &Model,
        ws: &mut DynamicWorkspace,
    ) -> Result<State, crate::solver::LinearSolveError> {
        let x = model.initial_positions();
        let n = x.len();
        model.dead_forces(0.0, None, &mut ws.dead);
        ws.f_ext.copy_from_slice(&ws.dead);
        model.assemble(
            &x,
            model.pressure_at(0.0, None),
            &mut ws.f_int,
            &mut ws.f_ext,
            None,
        );
        let mut rhs: Vec<f64> = (0..n).map(|i| ws.f_ext[i] - ws.f_int[i]).collect();
        let (m, linear) = ws.newton.matrix_and_solver();
        m.fill(0.0);
        model.add_mass_to_hessian(1.0, m);
        model.apply_supports(&mut rhs, Some(&mut *m));
        linear.solve_mass(m, &mut rhs)?;
        let mut state = State::at_rest(model, x);
        state.accelerations = rhs;
        Ok(state)
    }

    /// Advances `state` by `dt`. On error `state` is unchanged.
    pub fn step(
        &self,
        model: &Model,
        state: &mut State,
        dt: f64,
        settings: &NewtonSettings,
        length: f64,
        ws: &mut DynamicWorkspace,
    ) -> Result<StepOutcome, NewtonError> {
        let (beta, gamma) = (self.beta, self.gamma);
        let c = 1.0 / (beta * dt * dt);
        let t1 = state.time + dt;
        for i in 0..state.positions.len() {
            ws.q[i] = c * state.positions[i]
                + state.velocities[i] / (beta * dt)
                + (0.5 / beta - 1.0) * state.accelerations[i];
        }
        model.mass_times(&ws.q, &mut ws.mq);
        model.dead_forces(t1, None, &mut ws.dead);
        let old_ext = ws.f_ext.clone();
        let mut y: Vec<f64> = (0..state.positions.len())
            .map(|i| {
                state.positions[i]
                    + dt * state.velocities[i]
                    + 0.5 * dt * dt * state.accelerations[i]
            })
            .collect();
        let terms = StepTerms {
            c,
            mq: &ws.mq,
            dead: &ws.dead,
            pressure: model.pressure_at(t1, None),
            time: t1,
        };
        let result = solve_step(
            model,
            terms,
            &mut state.contact,
            &mut y,
            length,
            settings,
            &mut ws.newton,
            &mut ws.f_int,
            &mut ws.f_ext,
            &mut ws.my,
        );
        let (report, strain_energy) = match result {
            Ok(r) => r,
            Err(e) => {
                ws.f_ext.copy_from_slice(&old_ext);
                return Err(e);
            }
        };
        let mut work = 0.0;
        for i in 0..y.len() {
            let a1 = c * y[i] - ws.q[i];
            state.velocities[i] += (1.0 - gamma) * dt * state.accelerations[i] + gamma * dt * a1;
            state.accelerations[i] = a1;
            work += 0.5 * (old_ext[i] + ws.f_ext[i]) * (y[i] - state.positions[i]);
        }
        state.positions = y;
        state.time = t1;
        state.external_work += work;
        Ok(StepOutcome {
            newton: report,
            strain_energy,
        })
    }
}
