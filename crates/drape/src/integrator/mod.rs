//! Time integration: Newmark-beta in positions (dynamic) and load stepping
//! (static), each step solved by Newton–Raphson (docs/theory.md §1.6–1.7), with the
//! contact active-set loop for Lagrange multipliers (docs/theory.md §1.8).

mod grown;
pub mod newmark;
pub mod potential;
pub mod statics;
pub mod terms;

pub use newmark::Newmark;
pub use statics::StaticStepper;
pub(crate) use terms::{carry_springs, plastic_count};

use crate::contact::lagrange::{ActiveNode, MAX_ACTIVE_SET_ROUNDS, REVISIONS_IN_NEWTON};
use crate::contact::{ContactMethod, ContactModel, ContactState};
use crate::load::gas::{GasState, GasStep};
use crate::material::CRITICAL_STRETCH;
use crate::model::Model;
use crate::solver::low_rank::LowRank;
use crate::solver::newton::{
    self, Evaluation, NewtonError, NewtonReport, NewtonSettings, NewtonSystem, NewtonWorkspace,
};
use potential::{IncrementalPotential, StepContext, StepTerm};
use terms::{
    BendingTerm, FeatureTerm, FrictionTerm, GasTerm, HysteresisTerm, InertiaTerm, LoadTerm,
    MembraneTerm, PenaltyTerm, SelfContactTerm, SelfFrictionTerm,
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
    /// Energy friction has dissipated since the start (J): the work of the
    /// friction forces against the sliding, summed step by step; never
    /// decreasing.
    pub friction_dissipation: f64,
    /// Contact features, active set and multipliers (with obstacles).
    pub contact: Option<ContactState>,
    /// The gas of each of the model's cavities (none without).
    pub gas: Vec<GasState>,
    /// Each bending patch's plastic curvature (1/m, Voigt, in its frame)
    /// with a stick hysteresis ([`crate::bending::hysteresis`], "The
    /// stick"); empty otherwise.
    pub plastic: Vec<[f64; 3]>,
}

impl State {
    /// At rest in the configuration `positions`, at time 0.
    pub fn at_rest(model: &Model, positions: Vec<f64>) -> Self {
        let n = positions.len();
        let contact = model.contact().map(|c| c.initial_state(&positions));
        let gas = model
            .cavities()
            .iter()
            .map(|c| c.initial_state(&positions))
            .collect();
        let plastic = terms::initial_plastic(model, &positions);
        Self {
            time: 0.0,
            positions,
            velocities: vec![0.0; n],
            accelerations: vec![0.0; n],
            persistence: 1.0,
            external_work: 0.0,
            friction_dissipation: 0.0,
            contact,
            gas,
            plastic,
        }
    }
}

/// The residual and Hessian of one step: the sum of the terms of its
/// incremental potential ([`potential`]), then the supports and (Lagrange)
/// contact constraints imposed.
pub(crate) struct StepSystem<'a> {
    pub model: &'a Model,
    /// The terms of the step.
    pub potential: IncrementalPotential<'a>,
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
    /// The membrane's strain energy at the last evaluation (J).
    pub strain_energy: f64,
    /// The bending energy at the last evaluation (J; 0 without bending).
    pub bending_energy: f64,
    /// Self-contact's barrier energy at the last evaluation (J; 0
    /// without).
    pub self_contact_energy: f64,
    /// The obstacle features' penalty energy at the last evaluation (J;
    /// 0 without).
    pub features_energy: f64,
    /// Lagrange: the active nodes at the last evaluation.
    pub active: Vec<ActiveNode>,
    /// The nodes whose stencils' Hessians are projected to their
    /// positive semi-definite part ([`NewtonSystem::project`]), when
    /// `projecting`.
    pub project: Vec<bool>,
    /// Whether Hessians are projected.
    pub projecting: bool,
    /// Whether the step's terms are all potentials (a hyperelastic
    /// membrane, no follower pressure) and no multipliers constrain it:
    /// only then are Hessians ever projected (the stress projection's
    /// tangent and the pressure's are not a potential's Hessian, and
    /// projecting the bending beside them would only spoil the tangent).
    pub can_project: bool,
    /// The Hessian's layout grown with self-contact's pairs, when the step
    /// uses one ([`grown`]): Newton's Hessian is on its pattern.
    pub grown: Option<&'a mut grown::Grown>,
    /// The terms' low-rank parts at the last evaluation with a Hessian
    /// (the gas's), zero on the held components.
    pub low_rank: LowRank,
}

impl NewtonSystem for StepSystem<'_> {
    fn evaluate(&mut self, y: &[f64], g: &mut [f64], h: Option<&mut [f64]>) -> Evaluation {
        let model = self.model;
        let mut h = h;
        let ctx = StepContext {
            time: self.time,
            contact: self.contact.as_deref(),
            project: (self.projecting && self.can_project).then_some(&self.project[..]),
        };
        // With a grown layout (self-contact, `grown`) and a Hessian asked
        // for, the terms assemble on the model's pattern into the layout's
        // buffer, the supports are applied there, the values are copied
        // into the grown layout and the pairs' couplings added on it; the
        // multipliers' elimination then works on the grown layout.
        let value = match (self.grown.as_deref_mut(), h.as_deref_mut()) {
            (Some(grown), Some(h)) => {
                let value = self
                    .potential
                    .evaluate(&ctx, y, g, Some(&mut grown.model_values));
                model.apply_supports(g, Some(&mut grown.model_values));
                h.fill(0.0);
                for (k, &v) in grown.model_values.iter().enumerate() {
                    h[grown.map[k]] = v;
                }
                self.potential
                    .add_outside(&ctx, y, h, &grown.pattern, model.fixed());
                value
            }
            (_, mut h) => {
                let value = self.potential.evaluate(&ctx, y, g, h.as_deref_mut());
                model.apply_supports(g, h);
                value
            }
        };
        if h.is_some() {
            self.low_rank.clear();
            self.potential.low_rank(&mut self.low_rank);
            for u in &mut self.low_rank.vectors {
                for (ui, &held) in u.iter_mut().zip(model.fixed()) {
                    if held {
                        *ui = 0.0;
                    }
                }
            }
        }
        self.strain_energy = self.potential.value("membrane").map_or(0.0, |v| v.value);
        // (With a stick hysteresis, its springs' energy too.)
        self.bending_energy =
            self.potential.value("bending").map_or(0.0, |v| v.value) + self.potential.stored();
        self.self_contact_energy = self
            .potential
            .value("self-contact")
            .map_or(0.0, |v| v.value);
        self.features_energy = self
            .potential
            .value("obstacle features")
            .map_or(0.0, |v| v.value);
        let grown = self.grown.as_deref().filter(|_| h.is_some());
        let pattern = grown.map_or(model.pattern(), |g| &g.pattern);
        let mut merit = None;
        if let (Some(contact), Some(state)) = (model.contact(), self.contact.as_deref())
            && contact.method == ContactMethod::Lagrange
        {
            let mut active = contact.active_nodes(y, self.time, state, model.fixed());
            // Keep the elimination scales of the last Hessian evaluation.
            for (new, old) in active.iter_mut().zip(&self.active) {
                new.scale = old.scale;
            }
            merit = Some(ContactModel::impose_lagrange(
                &mut active,
                g,
                h.as_deref_mut().map(|h| (h, pattern)),
            ));
            self.active = active;
        }
        let symmetric =
            model.symmetric_by_construction() || h.is_some_and(|h| pattern.is_symmetric(h, 1e-10));
        Evaluation {
            scale: value.scale,
            symmetric,
            // With multipliers the constrained problem is not the
            // potential's unconstrained minimum: judged by its residual.
            energy: value.energy.filter(|_| merit.is_none()),
            merit,
        }
    }

    fn low_rank(&self) -> Option<&LowRank> {
        (!self.low_rank.is_empty()).then_some(&self.low_rank)
    }

    fn transform_increment(&self, dy: &mut [f64]) {
        ContactModel::rotate_back(&self.active, dy);
    }

    /// The smallest fraction of `dy` any term of the step admits
    /// ([`StepTerm::max_step`]): the line search starts there.
    fn max_step(&self, y: &[f64], dy: &[f64]) -> f64 {
        let ctx = StepContext {
            time: self.time,
            contact: self.contact.as_deref(),
            project: None,
        };
        self.potential.max_step(&ctx, y, dy)
    }

    fn project(&mut self, nodes: Option<&[bool]>) {
        self.projecting = nodes.is_some();
        if let Some(nodes) = nodes {
            self.project.clear();
            self.project.extend_from_slice(nodes);
        }
    }

    /// Multipliers: the active set revised after a Newton step, as after
    /// convergence ([`ContactModel::update_active_set`]), at most
    /// [`REVISIONS_IN_NEWTON`] times per Newton solve.
    fn revise(&mut self, y: &[f64]) -> bool {
        if self.revisions == 0 {
            return false;
        }
        let model = self.model;
        let (Some(cm), Some(state)) = (model.contact(), self.contact.as_deref_mut()) else {
            return false;
        };
        if cm.method != ContactMethod::Lagrange {
            return false;
        }
        let changed = cm.update_active_set(
            y,
            self.time,
            state,
            &self.active,
            model.fixed(),
            self.length,
        );
        if changed {
            self.revisions -= 1;
        }
        changed
    }
}

/// Each cavity's gas over the step from `state` to `t1`: the flows
/// over the step and the law it follows (`load::gas`).
pub(crate) fn gas_steps(model: &Model, state: &State, t1: f64) -> Vec<GasStep> {
    model
        .cavities()
        .iter()
        .zip(&state.gas)
        .map(|(c, s)| c.gas.begin_step(s, state.time, t1))
        .collect()
}

/// Ends the gas's steps at the solution `y`: each cavity's new state into
/// `state.gas`; returns the gas's work on the fabric over the step, net of
/// ambient (J).
pub(crate) fn end_gas_steps(model: &Model, steps: &[GasStep], y: &[f64], state: &mut State) -> f64 {
    let mut work = 0.0;
    for ((c, step), s) in model.cavities().iter().zip(steps).zip(&mut state.gas) {
        let v = c.surface.volume(y);
        work += step.work(v);
        *s = c.gas.end_step(step, v);
    }
    work
}

/// The energies of a step's solution (J): the fabric's strain energy by
/// part — the membrane's and the bending's (0 without bending) — and
/// what friction dissipated over the step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepEnergies {
    /// The membrane's strain energy (J).
    pub membrane: f64,
    /// The bending energy (J).
    pub bending: f64,
    /// The energy friction dissipated over the step (J; 0 without).
    pub friction: f64,
    /// Self-contact's barrier energy (J; 0 without): part of
    /// `history.csv`'s `contact_energy`.
    pub self_contact: f64,
    /// The work the moving obstacles did on the fabric over the step (J;
    /// 0 when none moves): their normal and friction forces at the step's
    /// end dotted with their displacements. Part of `external_work`.
    pub obstacles: f64,
    /// The obstacle features' penalty energy (J; 0 without): part of
    /// `history.csv`'s `contact_energy`.
    pub features: f64,
}

impl StepEnergies {
    /// The strain energy, both parts (J): `history.csv`'s `strain_energy`.
    pub fn strain(&self) -> f64 {
        self.membrane + self.bending
    }
}

/// What a step adds to the membrane: its time, inertia and loads.
#[derive(Clone, Copy)]
pub(crate) struct StepTerms<'a> {
    /// `1 / (beta dt^2)`, or 0 in statics (no inertia).
    pub c: f64,
    /// `Q_s` (dynamic) or empty (static).
    pub q: &'a [f64],
    /// `M Q_s` (dynamic) or empty (static).
    pub mq: &'a [f64],
    /// Dead external forces of this step.
    pub dead: &'a [f64],
    /// Follower pressure of this step (Pa).
    pub pressure: f64,
    /// Time at the end of the step (obstacle positions).
    pub time: f64,
    /// The positions at the step's start and its size (s), for the terms
    /// that lag over the step (friction); in statics the load increment's
    /// start and size. `None`: no friction, no bending hysteresis.
    pub start: Option<(&'a [f64], f64)>,
    /// Where friction lags its normal force from.
    pub friction: FrictionLag<'a>,
    /// The gas of each cavity over the step (none without cavities).
    pub gas: &'a [GasStep],
    /// The bending patches' plastic curvatures ([`State::plastic`]).
    pub plastic: &'a [[f64; 3]],
}

/// Where a step's friction takes its normal forces and tangent planes
/// from (`terms::friction`'s module docs); the slip is always measured
/// from the step's start.
#[derive(Clone, Copy)]
pub(crate) enum FrictionLag<'a> {
    /// The step's start (a dynamic step).
    Start,
    /// A static increment's first round: the nodes touching an obstacle
    /// at the start stick ([`FrictionTerm::stick`]); friction between the
    /// layers lags from the start.
    Stick,
    /// A static increment's later rounds: these positions, at the end of
    /// the increment, with this contact state (the previous round's
    /// solution; none without obstacles).
    At(&'a [f64], Option<&'a ContactState>),
}

/// The terms of a step's incremental potential, in their order: membrane,
/// bending (with a bending stiffness), loads, inertia (dynamic), penalty contact (with obstacles and
/// penalties), friction (a friction coefficient, either contact method:
/// lagged from `state`, the step's start's contact state, or as
/// `terms.friction` says in a static round).
/// `f_ext` receives the external forces, `my` is scratch.
fn step_potential<'a>(
    model: &'a Model,
    terms: &StepTerms<'a>,
    state: Option<&ContactState>,
    f_ext: &'a mut [f64],
    my: &'a mut [f64],
    grown: bool,
) -> IncrementalPotential<'a> {
    let mut list: Vec<Box<dyn StepTerm + 'a>> = vec![Box::new(MembraneTerm::new(model))];
    if let Some(bending) = model.bending() {
        list.push(Box::new(BendingTerm::new(bending, model.pattern())));
        // Its hysteresis over the step, from the step's start or the
        // plastic curvatures.
        if let (Some(law), Some(start)) = (model.bending_hysteresis(), terms.start) {
            list.push(Box::new(HysteresisTerm::new(
                bending,
                law,
                model.pattern(),
                start,
                terms.plastic,
            )));
        }
    }
    list.push(Box::new(LoadTerm::new(
        model,
        terms.dead,
        terms.pressure,
        f_ext,
    )));
    if !terms.gas.is_empty() {
        list.push(Box::new(GasTerm::new(model, terms.gas)));
    }
    if terms.c != 0.0 {
        list.push(Box::new(InertiaTerm::new(
            model,
            terms.c,
            (terms.q, terms.mq),
            my,
        )));
    }
    if let Some(contact) = model.contact() {
        if let ContactMethod::Penalty { stiffness } = contact.method {
            list.push(Box::new(PenaltyTerm::new(
                contact,
                model.pattern(),
                stiffness,
            )));
            if let Some(features) = model.obstacle_features() {
                let dt = terms.start.map_or(0.0, |(_, dt)| dt);
                list.push(Box::new(
                    FeatureTerm::new(features, model.pattern(), stiffness).over(dt),
                ));
            }
        }
        // Friction lags the normal force and the tangent plane of the
        // step's start (the contact state is the step's start's too), or
        // in a static round where `terms.friction` says.
        if contact.has_friction()
            && let (Some((start, dt)), Some(state)) = (terms.start, state)
        {
            let (pattern, t0) = (model.pattern(), terms.time - dt);
            list.push(Box::new(match terms.friction {
                FrictionLag::Start => FrictionTerm::new(contact, pattern, (start, t0, dt), state),
                FrictionLag::Stick => {
                    let membrane = model.membrane_stiffness();
                    FrictionTerm::stick(contact, pattern, (start, t0, dt), state, membrane)
                }
                FrictionLag::At(at, lag) => {
                    let lag = lag.unwrap_or(state);
                    FrictionTerm::lagged_at(contact, pattern, (at, terms.time), (start, dt), lag)
                }
            }));
        }
    }
    if let Some(self_contact) = model.self_contact()
        && let Some((start, dt)) = terms.start
        && self_contact.friction() > 0.0
    {
        // Friction between the layers: `[contact] friction`, lagged from
        // the step's start, or a static round's lag as against obstacles.
        let at = match terms.friction {
            FrictionLag::At(at, _) => at,
            FrictionLag::Start | FrictionLag::Stick => start,
        };
        list.push(Box::new(SelfFrictionTerm::lagged_at(
            self_contact,
            model.pattern(),
            at,
            (start, dt),
            !grown,
        )));
    }
    if let Some(self_contact) = model.self_contact() {
        // On a grown layout the step adds the pairs' Hessians itself.
        list.push(Box::new(SelfContactTerm::new(
            self_contact,
            model.pattern(),
            !grown,
        )));
    }
    IncrementalPotential::new(list)
}

/// Solves one step from the first guess `y`: Newton, and for Lagrange
/// contact the active-set loop around it. On success `contact` holds the
/// converged active set, multipliers and refreshed features; on error it is
/// unchanged. Returns Newton's report (iterations summed over re-solutions)
/// and the step's energies; `f_ext` holds the external forces at the
/// solution, or `old_ext` (the step's start's) again after an error, so
/// that a step cut back starts from them.
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_step(
    model: &Model,
    terms: StepTerms,
    contact: &mut Option<ContactState>,
    y: &mut [f64],
    length: f64,
    settings: &NewtonSettings,
    ws: &mut NewtonWorkspace,
    f_ext: &mut [f64],
    old_ext: &[f64],
    my: &mut [f64],
    grown: &mut Option<grown::Grown>,
) -> Result<(NewtonReport, StepEnergies), NewtonError> {
    let saved = contact.clone();
    if let Some(sc) = model.self_contact() {
        sc.forget_broad_phase();
    }
    feasible_guess(model, y, terms.start.map(|s| s.0));
    if grown::applies(model, ws.linear.effective_mode()) {
        grown::grow(model, grown, ws, y)?;
    }
    let mut total: Option<NewtonReport> = None;
    let mut rounds = 0;
    // Multipliers: the first guess's penetrating nodes join the active set
    // at once. The loop below settles the set as before (it releases
    // nodes whose multiplier pulls), but a node that the predictor already
    // puts inside an obstacle no longer costs a re-solution of the step to
    // be admitted (docs/performance.md).
    if let (Some(cm), Some(state)) = (model.contact(), contact.as_mut())
        && cm.method == ContactMethod::Lagrange
    {
        cm.admit_penetrating(y, terms.time, state, model.fixed(), length);
    }
    // The loop returns on success and breaks with the error, after which
    // the contact state and the external forces are the step's start's.
    let can_project = model.material().is_hyperelastic()
        && terms.pressure == 0.0
        && model
            .contact()
            .is_none_or(|c| c.method != ContactMethod::Lagrange);
    let error = loop {
        // Every round starts the terms anew (a term that lags does so
        // from the step's start, each round alike).
        let mut potential = step_potential(
            model,
            &terms,
            saved.as_ref(),
            &mut *f_ext,
            &mut *my,
            grown.is_some(),
        );
        let ctx = StepContext {
            time: terms.time,
            contact: contact.as_ref(),
            project: None,
        };
        potential.begin_step(&ctx, y);
        let mut system = StepSystem {
            model,
            potential,
            time: terms.time,
            contact: contact.as_mut(),
            length,
            revisions: REVISIONS_IN_NEWTON,
            strain_energy: 0.0,
            bending_energy: 0.0,
            self_contact_energy: 0.0,
            features_energy: 0.0,
            active: Vec::new(),
            project: Vec::new(),
            projecting: false,
            can_project,
            grown: grown.as_mut(),
            low_rank: LowRank::default(),
        };
        let result = newton::solve(&mut system, y, length, settings, ws);
        let mut strain = StepEnergies {
            membrane: system.strain_energy,
            bending: system.bending_energy,
            self_contact: system.self_contact_energy,
            features: system.features_energy,
            friction: system.potential.dissipation(),
            obstacles: system.potential.obstacle_work(),
        };
        let active = std::mem::take(&mut system.active);
        drop(system);
        let report = match result {
            Ok(r) => r,
            Err(e) => break e,
        };
        total = Some(merge_reports(total, report));
        let (Some(cm), Some(state)) = (model.contact(), contact.as_mut()) else {
            if let Some(e) = unstable(model, y) {
                break e;
            }
            return Ok((total.unwrap_or_else(empty_report), strain));
        };
        let changed = cm.method == ContactMethod::Lagrange
            && cm.update_active_set(y, terms.time, state, &active, model.fixed(), length);
        if !changed {
            if let Some(e) = unstable(model, y) {
                break e;
            }
            if let Some((_, dt)) = terms.start {
                strain.obstacles += cm.normal_work(y, terms.time, state, dt);
            }
            cm.refresh_features(y, terms.time, state);
            return Ok((total.unwrap_or_else(empty_report), strain));
        }
        rounds += 1;
        if rounds > MAX_ACTIVE_SET_ROUNDS {
            break NewtonError::ActiveSetCycle { rounds };
        }
    };
    *contact = saved;
    f_ext.copy_from_slice(old_ext);
    Err(error)
}

/// With self-contact, Newton must start where the fabric does not cross
/// itself: the step's first guess (the predictor) is pulled back along
/// the straight line from the step's start to the largest fraction that
/// continuous collision detection allows (the start itself is such a
/// state: the last converged step's, or the initial mesh).
fn feasible_guess(model: &Model, y: &mut [f64], start: Option<&[f64]>) {
    let (Some(sc), Some(start)) = (model.self_contact(), start) else {
        return;
    };
    let dy: Vec<f64> = y.iter().zip(start).map(|(a, b)| a - b).collect();
    let alpha = sc.max_step(start, &dy);
    if alpha < 1.0 {
        for ((yi, si), di) in y.iter_mut().zip(start).zip(&dy) {
            *yi = si + alpha * di;
        }
    }
}

/// A converged step that compresses an element of a membrane without
/// tension field below [`CRITICAL_STRETCH`] (Saint-Venant–Kirchhoff's
/// compressive instability) is no solution to keep: an error, so that
/// the step is cut back. Newton minimising a step's energy can reach the
/// collapsed branch, of lower energy, where a shorter step (a larger
/// mass term) stays on the one the motion follows.
fn unstable(model: &Model, y: &[f64]) -> Option<NewtonError> {
    if model.material().wrinkle_state([0.0; 3]).is_some() {
        return None;
    }
    let (stretch, element) = model.min_stretch(y);
    (stretch < CRITICAL_STRETCH).then_some(NewtonError::MaterialInstability { element, stretch })
}

/// Newton's reports of two solves of one step, as one: `report` after
/// `total` (none: `report` alone).
fn merge_reports(total: Option<NewtonReport>, report: NewtonReport) -> NewtonReport {
    match total {
        None => report,
        Some(mut t) => {
            t.iterations += report.iterations;
            t.chord_steps += report.chord_steps;
            t.residuals.extend(report.residuals);
            t.increments.extend(report.increments);
            t.factorization = report.factorization.or(t.factorization);
            t.shifts += report.shifts;
            t.projections += report.projections;
            t
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
        shifts: 0,
        projections: 0,
    }
}
