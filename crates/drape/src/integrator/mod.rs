//! Time integration: Newmark-beta in positions (dynamic) and load stepping
//! (static), each step solved by Newton–Raphson (SPEC §1.6–1.7), with the
//! contact active-set loop for Lagrange multipliers (SPEC §1.8).

pub mod newmark;
pub mod statics;

pub use newmark::Newmark;
pub use statics::StaticStepper;

use crate::contact::lagrange::{ActiveNode, MAX_ACTIVE_SET_ROUNDS, REVISIONS_IN_NEWTON};
use crate::contact::{ContactMethod, ContactModel, ContactState};
use crate::model::Model;
use crate::solver::newton::{
    self, Evaluation, NewtonError, NewtonReport, NewtonSettings, NewtonSystem, NewtonWorkspace,
};

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
    /// How much of the acceleration the next step's predictor carries
    /// over, `rho` in `[0, 1]` ([`newmark`]'s module docs): 1 at rest and
    /// after a step whose accelerations persisted.
    pub persistence: f64,
    /// Work done by the external loads since the start (J), by the
    /// trapezoidal rule on each step: `1/2 (F_n + F_{n+1}) . (Y_{n+1} - Y_n)`.
    pub external_work: f64,
    /// Contact features, active set and multipliers (with obstacles).
    pub contact: Option<ContactState>,
}

impl State {
    /// At rest in the configuration `positions`, at time 0.
    pub fn at_rest(model: &Model, positions: Vec<f64>) -> Self {
        let n = positions.len();
        let contact = model.contact.as_ref().map(|c| c.initial_state(&positions));
        Self {
            time: 0.0,
            positions,
            velocities: vec![0.0; n],
            accelerations: vec![0.0; n],
            persistence: 1.0,
            external_work: 0.0,
            contact,
        }
    }
}

/// The residual `G = F_int - F_ext + c M Y - M Q + F_contact` and Hessian
/// `H = K - dF_p/dY + c M + H_contact` of one step (static: `c = 0`, no
/// `M Q`), supports and (Lagrange) contact constraints imposed.
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
    /// Time at the end of the step (obstacle positions).
    pub time: f64,
    /// Contact state of the step (hints, active set); the active set
    /// changes during Newton only through [`NewtonSystem::revise`].
    pub contact: Option<&'a mut ContactState>,
    /// The reference length `|X|` of Newton's test (m), which scales the
    /// active set's penetration tolerance (`-1e-12 |X|`).
    pub length: f64,
    /// Revisions of the active set left in this Newton solve.
    pub revisions: usize,
    /// Last evaluation's internal and external forces, and `M Y`.
    pub f_int: &'a mut [f64],
    pub f_ext: &'a mut [f64],
    pub my: &'a mut [f64],
    /// Strain energy at the last evaluation (J).
    pub strain_energy: f64,
    /// Lagrange: the active nodes at the last evaluation.
    pub active: Vec<ActiveNode>,
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
        let mut scale;
        if self.c != 0.0 {
            model.mass_times(y, self.my);
            // G and the norms of its four terms in one pass (each sum of
            // squares in index order, as `norm` takes it).
            let mut squares = [0.0; 4];
            for i in 0..g.len() {
                let (fi, fe, my, mq) = (self.f_int[i], self.f_ext[i], self.my[i], self.mq[i]);
                g[i] = fi - fe + self.c * my - mq;
                squares[0] += fi * fi;
                squares[1] += fe * fe;
                squares[2] += my * my;
                squares[3] += mq * mq;
            }
            let [a, b, m, q] = squares.map(f64::sqrt);
            scale = a + b;
            scale += self.c * m + q;
            if let Some(h) = h.as_deref_mut() {
                model.add_mass_to_hessian(self.c, h);
            }
        } else {
            scale = norm(self.f_int) + norm(self.f_ext);
            for i in 0..g.len() {
                g[i] = self.f_int[i] - self.f_ext[i];
            }
        }
        if let (Some(contact), Some(state)) = (&model.contact, self.contact.as_deref())
            && let ContactMethod::Penalty { stiffness } = contact.method
        {
            contact.add_penalty(
                stiffness,
                y,
                self.time,
                state,
                g,
                h.as_deref_mut().map(|h| (h, &model.pattern)),
            );
        }
        model.apply_supports(g, h.as_deref_mut());
        let mut merit = None;
        if let (Some(contact), Some(state)) = (&model.contact, self.contact.as_deref())
            && contact.method == ContactMethod::Lagrange
        {
            let mut active = contact.active_nodes(y, self.time, state, &model.fixed);
            // Keep the elimination scales of the last Hessian evaluation.
            for (new, old) in active.iter_mut().zip(&self.active) {
                new.scale = old.scale;
            }
            merit = Some(ContactModel::impose_lagrange(
                &mut active,
                g,
                h.as_deref_mut().map(|h| (h, &model.pattern)),
            ));
            self.active = active;
        }
        let symmetric = model.symmetric_by_construction()
            || h.is_some_and(|h| model.pattern.is_symmetric(h, 1e-10));
        Evaluation {
            scale,
            symmetric,
            merit,
        }
    }

    fn transform_increment(&self, dy: &mut [f64]) {
        ContactModel::rotate_back(&self.active, dy);
    }

    /// Multipliers: the active set revised after a Newton step, as after
    /// convergence ([`ContactModel::update_active_set`]), at most
    /// [`REVISIONS_IN_NEWTON`] times per Newton solve.
    fn revise(&mut self, y: &[f64]) -> bool {
        if self.revisions == 0 {
            return false;
        }
        let model = self.model;
        let (Some(cm), Some(state)) = (&model.contact, self.contact.as_deref_mut()) else {
            return false;
        };
        if cm.method != ContactMethod::Lagrange {
            return false;
        }
        let changed =
            cm.update_active_set(y, self.time, state, &self.active, &model.fixed, self.length);
        if changed {
            self.revisions -= 1;
        }
        changed
    }
}

/// The terms of a step's residual other than the elements'.
pub(crate) struct StepTerms<'a> {
    pub c: f64,
    pub mq: &'a [f64],
    pub dead: &'a [f64],
    pub pressure: f64,
    pub time: f64,
}

/// Solves one step from the first guess `y`: Newton, and for Lagrange
/// contact the active-set loop around it. On success `contact` holds the
/// converged active set, multipliers and refreshed features; on error it is
/// unchanged. Returns Newton's report (iterations summed over re-solutions)
/// and the strain energy.
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_step(
    model: &Model,
    terms: StepTerms,
    contact: &mut Option<ContactState>,
    y: &mut [f64],
    length: f64,
    settings: &NewtonSettings,
    ws: &mut NewtonWorkspace,
    f_int: &mut [f64],
    f_ext: &mut [f64],
    my: &mut [f64],
) -> Result<(NewtonReport, f64), NewtonError> {
    let saved = contact.clone();
    let mut total: Option<NewtonReport> = None;
    let mut rounds = 0;
    // Multipliers: the first guess's penetrating nodes join the active set
    // at once. The loop below settles the set as before (it releases
    // nodes whose multiplier pulls), but a node that the predictor already
    // puts inside an obstacle no longer costs a re-solution of the step to
    // be admitted: the pedestal with multipliers needs 1,067 Newton
    // iterations instead of 1,165, 89 re-solutions instead of 129.
    if let (Some(cm), Some(state)) = (&model.contact, contact.as_mut())
        && cm.method == ContactMethod::Lagrange
    {
        cm.admit_penetrating(y, terms.time, state, &model.fixed, length);
    }
    loop {
        let mut system = StepSystem {
            model,
            c: terms.c,
            mq: terms.mq,
            dead: terms.dead,
            pressure: terms.pressure,
            time: terms.time,
            contact: contact.as_mut(),
            length,
            revisions: REVISIONS_IN_NEWTON,
            f_int: &mut *f_int,
            f_ext: &mut *f_ext,
            my: &mut *my,
            strain_energy: 0.0,
            active: Vec::new(),
        };
        let result = newton::solve(&mut system, y, length, settings, ws);
        let strain = system.strain_energy;
        let active = std::mem::take(&mut system.active);
        let report = match result {
            Ok(r) => r,
            Err(e) => {
                *contact = saved;
                return Err(e);
            }
        };
        total = Some(match total {
            None => report,
            Some(mut t) => {
                t.iterations += report.iterations;
                t.chord_steps += report.chord_steps;
                t.residuals.extend(report.residuals);
                t.increments.extend(report.increments);
                t.factorization = report.factorization.or(t.factorization);
                t
            }
        });
        let (Some(cm), Some(state)) = (&model.contact, contact.as_mut()) else {
            return Ok((total.unwrap_or_else(empty_report), strain));
        };
        let changed = cm.method == ContactMethod::Lagrange
            && cm.update_active_set(y, terms.time, state, &active, &model.fixed, length);
        if !changed {
            cm.refresh_features(y, terms.time, state);
            return Ok((total.unwrap_or_else(empty_report), strain));
        }
        rounds += 1;
        if rounds > MAX_ACTIVE_SET_ROUNDS {
            *contact = saved;
            return Err(NewtonError::ActiveSetCycle { rounds });
        }
    }
}

fn empty_report() -> NewtonReport {
    NewtonReport {
        iterations: 0,
        chord_steps: 0,
        residuals: Vec::new(),
        increments: Vec::new(),
        factorization: None,
    }
}
