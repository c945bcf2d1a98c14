//! Newmark-beta in positions (docs/theory.md §1.6):
//!
//! ```text
//! Q_s     = Y_s/(beta dt^2) + V_s/(beta dt) + (1/(2 beta) - 1) A_s
//! A_{s+1} = Y_{s+1}/(beta dt^2) - Q_s
//! V_{s+1} = V_s + (1 - gamma) dt A_s + gamma dt A_{s+1}
//! G(Y)    = F_int(Y) + M (Y/(beta dt^2) - Q_s) - F_ext(Y)
//! ```
//!
//! The first guess is Newmark's update with the next acceleration
//! estimated as `rho A_s`:
//!
//! ```text
//! Y_pred = Y_s + dt V_s + dt^2 ((1/2 - beta) + beta rho) A_s
//! ```
//!
//! With `rho = 1` this is the constant-acceleration predictor
//! `Y_s + dt V_s + dt^2/2 A_s`, exact when the acceleration does not change
//! (free fall under a uniform load, for any `beta`, `gamma`). Where the
//! motion is not smooth (nodes entering contact, folds, wrinkles) the
//! acceleration does not persist: with `beta = 1, gamma = 1.5` a stiff
//! mode's acceleration changes sign from one step to the next, and
//! extrapolating it puts those nodes on the wrong side of where they end,
//! which costs Newton iterations. So `rho`, the acceleration persistence
//! ([`State::persistence`]), is measured on each converged step: per node
//! `a` with `A_s^a != 0`, the least-squares factor `rho_a = A_{s+1}^a .
//! A_s^a / |A_s^a|^2` of `A_{s+1}^a ~ rho_a A_s^a`, clamped to `[0, 1]`;
//! the next step takes their lower decile (the function `persistence`).
//! Newton's work is set by the nodes predicted worst, not by the smoothly
//! moving majority that a single fit over all nodes follows (that fit
//! saves less than the decile: docs/performance.md, which has the
//! figures). Free fall and smooth motion keep `rho = 1`. The converged
//! steps are the same as with `rho = 1` to the Newton tolerance.

use super::{FrictionLag, State, StepTerms, end_gas_steps, gas_steps, solve_step};
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

/// A static increment that friction could not hold: its stick round found
/// equilibrium, a round with Coulomb's limit did not (`integrator::statics`;
/// kept in the steppers' shared workspace, [`DynamicWorkspace`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionShortfall {
    /// The tangential force the sticking nodes carried (N, summed over
    /// them).
    pub needed: f64,
    /// Coulomb's limit `mu lambda` at the stick round's solution (N,
    /// summed over the nodes in contact).
    pub limit: f64,
}

/// Buffers of a dynamic run.
#[derive(Debug)]
pub struct DynamicWorkspace {
    q: Vec<f64>,
    mq: Vec<f64>,
    pub(crate) dead: Vec<f64>,
    /// Internal forces at the last converged state.
    pub f_int: Vec<f64>,
    /// External forces at the last converged state.
    pub f_ext: Vec<f64>,
    pub(crate) my: Vec<f64>,
    /// The nodes' acceleration persistences (scratch of `persistence`).
    ratios: Vec<f64>,
    /// The external forces at the start of the step (the work integral's
    /// left end, restored when a step fails).
    pub(crate) old_ext: Vec<f64>,
    /// The step's iterate (first guess, then solution), swapped with the
    /// state's positions when the step converges.
    pub(crate) y: Vec<f64>,
    /// Newton buffers and the linear solver.
    pub newton: NewtonWorkspace,
    /// The Hessian's layout grown with self-contact's pairs, once a step
    /// has needed it (`integrator::grown`).
    pub(crate) grown: Option<super::grown::Grown>,
    /// A static round's lag: the previous round's solution (empty until
    /// a static increment with friction needs it).
    pub(crate) lag: Vec<f64>,
    /// Why the last static increment failed, when friction could not
    /// hold its load (`integrator::statics`).
    pub(crate) friction_shortfall: Option<FrictionShortfall>,
}

impl DynamicWorkspace {
    /// How many times the Hessian's layout was grown with self-contact's
    /// pairs (`integrator::grown`; 0 without self-contact).
    pub fn layout_builds(&self) -> usize {
        self.grown.as_ref().map_or(0, |g| g.builds)
    }

    /// The stencils self-contact's grown Hessian layout was built from
    /// (none without one): what a checkpoint keeps.
    pub fn layout_stencils(&self) -> Vec<[usize; 4]> {
        super::grown::stencils(&self.grown)
    }

    /// Builds self-contact's Hessian layout from a checkpoint's `stencils`
    /// (nothing for none, or without self-contact).
    ///
    /// # Errors
    /// The linear solver cannot be made for the layout's pattern.
    pub fn restore_layout(
        &mut self,
        model: &Model,
        stencils: &[[usize; 4]],
    ) -> Result<(), crate::solver::LinearSolveError> {
        super::grown::restore(model, &mut self.grown, &mut self.newton, stencils)
    }

    /// When the last static increment failed because friction could not
    /// hold its load: the forces compared (`integrator::statics`).
    pub fn friction_shortfall(&self) -> Option<FrictionShortfall> {
        self.friction_shortfall
    }

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
        let (node_ptr, node_rows) = model.pattern().node_graph();
        let mut linear =
            crate::solver::LinearSolver::new(&model.pattern().col_ptr, &model.pattern().row_idx)?
                .with_transpose(model.pattern().transpose_map().to_vec())
                .with_node_blocks(node_ptr, node_rows)
                .with_mode(mode);
        let compact = matches!(
            mode,
            crate::solver::LinearMode::Compact | crate::solver::LinearMode::Auto
        );
        if compact && model.bending().is_some() {
            let mesh = model.mesh();
            linear = linear.with_compact(crate::solver::SparsePattern::new(
                mesh.node_count(),
                mesh.elements(),
            ));
        }
        Ok(Self {
            q: vec![0.0; n],
            mq: vec![0.0; n],
            dead: vec![0.0; n],
            f_int: vec![0.0; n],
            f_ext: vec![0.0; n],
            my: vec![0.0; n],
            ratios: Vec::with_capacity(n / 3),
            old_ext: vec![0.0; n],
            y: vec![0.0; n],
            newton: NewtonWorkspace::new(n, model.pattern().nnz(), linear),
            grown: None,
            lag: Vec::new(),
            friction_shortfall: None,
        })
    }
}

/// Outcome of a converged step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepOutcome {
    /// Newton's report.
    pub newton: NewtonReport,
    /// The energies at the end of the step: strain by part, friction's
    /// dissipation over the step.
    pub energies: super::StepEnergies,
}

impl Newmark {
    /// The initial state at rest in the initial configuration, with `A_0 =
    /// M^{-1} (F_ext(0) - F_int(X))` (zero at fixed components; `F_ext`
    /// with the cavities' gas).
    pub fn initial_state(
        &self,
        model: &Model,
        ws: &mut DynamicWorkspace,
    ) -> Result<State, crate::solver::LinearSolveError> {
        let x = model.initial_positions();
        let n = x.len();
        model.dead_forces(0.0, None, &mut ws.dead);
        ws.f_ext.copy_from_slice(&ws.dead);
        model.assemble(&x, &mut ws.f_int, None);
        model.add_pressure(&x, model.pressure_at(0.0, None), &mut ws.f_ext, None);
        let mut rhs: Vec<f64> = (0..n).map(|i| ws.f_ext[i] - ws.f_int[i]).collect();
        // The gas's net pressure on its cavity, `(p_0 - p_amb) dV/dY` (not
        // in `f_ext`: its work is counted by the gas's law, `super::end_gas_steps`).
        if !model.cavities().is_empty() {
            let mut dv = vec![0.0; n];
            for cavity in model.cavities() {
                let gas = cavity.initial_state(&x);
                cavity.surface.volume_gradient(&x, &mut dv);
                let net = gas.pressure - cavity.gas.ambient;
                for (r, d) in rhs.iter_mut().zip(&dv) {
                    *r += net * d;
                }
            }
        }
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
        ws.old_ext.copy_from_slice(&ws.f_ext);
        let theta = 0.5 - beta + beta * state.persistence;
        for (i, y) in ws.y.iter_mut().enumerate() {
            *y = state.positions[i]
                + dt * state.velocities[i]
                + theta * dt * dt * state.accelerations[i];
        }
        let gas = gas_steps(model, state, t1);
        let terms = StepTerms {
            c,
            q: &ws.q,
            mq: &ws.mq,
            dead: &ws.dead,
            pressure: model.pressure_at(t1, None),
            time: t1,
            start: Some((&state.positions, dt)),
            friction: FrictionLag::Start,
            gas: &gas,
            plastic: &state.plastic,
        };
        let settings = &NewtonSettings {
            dt: Some(dt),
            ..*settings
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
        let (y, old_ext) = (&ws.y, &ws.old_ext);
        let mut work = 0.0;
        for i in 0..y.len() {
            // A_{s+1} = Y/(beta dt^2) - Q_s, into `q`.
            let a1 = c * y[i] - ws.q[i];
            ws.q[i] = a1;
            state.velocities[i] += (1.0 - gamma) * dt * state.accelerations[i] + gamma * dt * a1;
            work += 0.5 * (old_ext[i] + ws.f_ext[i]) * (y[i] - state.positions[i]);
        }
        work += end_gas_steps(model, &gas, &ws.y, state) + energies.obstacles;
        super::terms::slip(model, &ws.y, &mut state.plastic);
        state.persistence = persistence(&state.accelerations, &ws.q, &mut ws.ratios);
        state.accelerations.copy_from_slice(&ws.q);
        std::mem::swap(&mut state.positions, &mut ws.y);
        state.time = t1;
        state.external_work += work;
        state.friction_dissipation += energies.friction;
        Ok(StepOutcome {
            newton: report,
            energies,
        })
    }
}

/// The acceleration persistence `rho` of a step from `A_s` (`old`) to
/// `A_{s+1}` (`new`), both flattened by node: the lower decile of the
/// nodes' `rho_a = A_{s+1}^a . A_s^a / |A_s^a|^2`, each clamped to `[0, 1]`,
/// over the nodes with `A_s^a != 0`; 1 when there are none (see the
/// module docs). `ratios` is scratch.
fn persistence(old: &[f64], new: &[f64], ratios: &mut Vec<f64>) -> f64 {
    ratios.clear();
    for (a0, a1) in old.chunks_exact(3).zip(new.chunks_exact(3)) {
        let squared = a0[0] * a0[0] + a0[1] * a0[1] + a0[2] * a0[2];
        if squared > 0.0 {
            let dot = a1[0] * a0[0] + a1[1] * a0[1] + a1[2] * a0[2];
            ratios.push((dot / squared).clamp(0.0, 1.0));
        }
    }
    if ratios.is_empty() {
        return 1.0;
    }
    let k = ratios.len() / 10;
    *ratios.select_nth_unstable_by(k, f64::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::persistence;

    /// Twenty nodes in a shuffled order (node `k` is number `ORDER[k]`).
    const ORDER: [usize; 20] = [
        7, 3, 19, 0, 12, 5, 16, 1, 9, 14, 2, 18, 11, 6, 4, 17, 8, 13, 10, 15,
    ];

    /// `A_s` of the twenty nodes and of two nodes at rest, flattened, and
    /// `A_{s+1} = r(a) A_s` for node number `a` (the resting nodes' next
    /// accelerations given apart).
    fn accelerations(r: impl Fn(f64) -> f64) -> (Vec<f64>, Vec<f64>) {
        let (mut old, mut new) = (Vec::new(), Vec::new());
        for a in ORDER {
            let a = a as f64;
            let v = [1.0 + a, -2.0, 0.5 * a];
            old.extend_from_slice(&v);
            new.extend(v.iter().map(|x| r(a) * x));
        }
        old.extend_from_slice(&[0.0; 6]);
        new.extend_from_slice(&[3.0, 1.0, 2.0, 0.0, 0.0, 0.0]);
        (old, new)
    }

    #[test]
    fn persistence_is_the_lower_decile_of_the_nodes_ratios() {
        let mut scratch = Vec::new();
        // r = a / 10 - 0.5: -0.5 ... 1.4, clamped to 0 ... 1; the two
        // nodes at rest do not count. Sorted clamped ratios: six zeros (a
        // = 0..5), then 0.1, 0.2, ... The decile is the third smallest
        // (20 / 10 = 2): 0.
        let (old, new) = accelerations(|a| a / 10.0 - 0.5);
        assert_eq!(persistence(&old, &new, &mut scratch), 0.0);
        // Shifted up by 0.4: ratios a / 10 - 0.1, clamped: 0, 0, 0.1, ...
        let (old, new) = accelerations(|a| a / 10.0 - 0.1);
        let rho = persistence(&old, &new, &mut scratch);
        assert!((rho - 0.1).abs() < 1e-12, "{rho}");
        // A steady acceleration persists fully; no acceleration at all: 1.
        assert_eq!(persistence(&old, &old, &mut scratch), 1.0);
        assert_eq!(persistence(&[0.0; 6], &[1.0; 6], &mut scratch), 1.0);
    }
}
