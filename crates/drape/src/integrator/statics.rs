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
//!
//! Friction (against the obstacles and between the layers) acts as in a
//! dynamic step, the increment standing for the step: the load factor is
//! the time (obstacles move by `v lambda`, the smoothing slip is `eps_v
//! dlambda`) and the slip is measured from the increment's start. Its
//! normal force is lagged in rounds (`terms::friction`'s module docs, the
//! lagged iterations of Li et al. 2020, §5): a first round in which the
//! nodes touching an obstacle stick, then rounds lagged at the previous
//! round's solution until the normal forces `mu lambda` change by at
//! most [`SETTLED`] of their sum between two rounds (at most
//! [`FRICTION_ROUNDS`] of them; the last is kept). Lagged from the
//! increment's start alone, as a dynamic step lags, a load that grows
//! with the factor would meet the normal force of the increment before:
//! none at all in the first. A load friction cannot hold has no static
//! equilibrium: the round fails, and with it the increment, which the
//! run reports as friction's ([`FrictionShortfall`]).
//!
//! **Relaxation in pseudo-time.** Where the loading path buckles (a
//! skirt folding under its weight), the equilibrium the increment
//! starts from turns unstable, and the one it must reach lies across a
//! bifurcation, further than Newton's line search carries it: the
//! increment fails however small it is cut (a 60-ring drape tester's
//! failed at a third of its weight with increments cut to 1/1280).
//! An increment that fails once it is halved ([`StaticStepper::relax`])
//! is therefore solved again by pseudo-transient continuation (Kelley &
//! Keyes 1998, "Convergence analysis of pseudo-transient continuation",
//! SIAM J. Numer. Anal. 35): a sequence of pseudo-steps, each minimising
//!
//! ```text
//! Pi(Y) + 1 / (2 tau_k^2) (Y - Y_k) . M (Y - Y_k)
//! ```
//!
//! from `Y_k`, the last pseudo-step's solution — a backward-Euler step of
//! size `tau_k` from rest, the fabric's own mass `M` the metric. Each is a
//! proximal step: it lowers `Pi` and stays near `Y_k`, so it goes down
//! the unstable direction instead of stalling on it, and the sequence
//! ends at a minimum of `Pi` (a stable equilibrium) as a damped fall to
//! rest would, without its oscillations. `tau` starts at `sqrt(h / a)`,
//! the time a node takes to fall one mean edge `h` under the load's
//! acceleration `a`, grows by the static residual's decrease (switched
//! evolution relaxation: `tau_{k+1} = tau_k |R_{k-1}| / |R_k|`, between
//! 1/2 and 4 times), and is quartered where a pseudo-step fails. The
//! static residual of a pseudo-step's solution is its inertia force
//! `R_k = M (Y_{k+1} - Y_k) / tau_k^2` off the supports; the increment
//! ends where it is within Newton's residual tolerance of the external
//! forces. As `tau` grows the pseudo-steps become Newton's, and converge
//! as fast. A pseudo-step need only carry the fabric nearer to rest, so it
//! is solved inexactly (`RELAX_TOLERANCE`); the one whose solution ends
//! the increment is solved again from there to Newton's tolerances. For
//! the same reason a pseudo-step cut at its iterations while creeping to
//! its end (its last increment within `RELAX_KEEP`) is kept where its
//! energy fell and no element is compressed past Saint-Venant–Kirchhoff's
//! stability (as no converged step may be), as an inexact proximal step
//! (a sufficient decrease of `Pi`: Rockafellar 1976, "Monotone operators
//! and the proximal point algorithm", SIAM J. Control Optim. 14): its
//! last iterate is the next anchor, and `tau` is cut as after a failure. A pseudo-step cut further
//! from its end (across a fold) is repeated shorter: kept as well, such
//! steps led the relaxed settle of `tests/relaxation.rs` to rest states
//! of a potential 1–2.5 % higher than the fine loading path's
//! (docs/performance.md, "Pseudo-steps kept, and the direct solve's
//! accuracy").
//! With friction, each of the increment's rounds is relaxed alike:
//! within a round the friction term is an energy (the stick round's
//! springs, or the friction lagged at the previous round's solution), so
//! the pseudo-steps minimise the round's potential as they minimise a
//! frictionless one, and the rounds then lag the normal force as before.

use super::terms::{FrictionTerm, SelfFrictionTerm};
use super::{
    FrictionLag, State, StepEnergies, StepTerms, end_gas_steps, gas_steps, merge_reports,
    solve_step,
};
use crate::integrator::newmark::{DynamicWorkspace, FrictionShortfall, StepOutcome};
use crate::model::Model;
use crate::solver::newton::{NewtonError, NewtonReport, NewtonSettings};
use crate::vecn::norm;

/// The change of the lagged normal forces `mu lambda` between two rounds,
/// summed over the nodes, relative to their sum, below which a static
/// increment's friction has settled: 1 %, the friction force's error
/// then. Tighter would chase Newton's tolerance: a node's penalty force
/// moves by `eta |dY|`.
pub const SETTLED: f64 = 1e-2;

/// The most rounds of a static increment's friction after its stick
/// round; the last is kept.
pub const FRICTION_ROUNDS: usize = 8;

/// Load stepping: each step raises the load factor by the increment it
/// is given (the schedule's `1 / steps`) and solves for equilibrium.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StaticStepper {
    /// The time the load factor counts from: `lambda = state.time - from`
    /// (0, but on a finer level of a multilevel settle:
    /// [`crate::setup::Analysis::Static`]).
    pub from: f64,
    /// Whether an increment Newton cannot solve is relaxed in
    /// pseudo-time (module docs): the run asks it of an increment already
    /// halved, whose halving did not help, and of a finer level's settle
    /// at once (its load is whole from the start: halving it would unload
    /// the carried shape).
    pub relax: bool,
}

impl StaticStepper {
    /// Advances the load factor `state.time - from` by `dlambda` and
    /// solves for equilibrium. Velocities and accelerations stay zero. On
    /// error `state` is unchanged.
    pub fn step(
        &self,
        model: &Model,
        state: &mut State,
        dlambda: f64,
        settings: &NewtonSettings,
        length: f64,
        ws: &mut DynamicWorkspace,
    ) -> Result<StepOutcome, NewtonError> {
        let from = self.from;
        let lambda = (state.time - from + dlambda).min(1.0 + 1e-12);
        model.dead_forces(lambda, Some(lambda), &mut ws.dead);
        ws.old_ext.copy_from_slice(&ws.f_ext);
        ws.y.copy_from_slice(&state.positions);
        ws.friction_shortfall = None;
        let rounds = has_friction(model);
        // A fixed gas (no inflator or vents in statics: the scenario's
        // check) over the increment.
        let gas = gas_steps(model, state, from + lambda);
        let start_contact = if rounds { state.contact.clone() } else { None };
        // The contact state of the round lagged from, the forces lagged,
        // the stick round's tangential force.
        let (mut lagging, mut lag_contact) = (false, None);
        let mut lagged: Option<Vec<(usize, f64)>> = None;
        let mut needed = 0.0;
        let mut total = None;
        let mut round = 0;
        let energies = loop {
            if let Some(p) = &ws.newton.progress {
                p.friction_round(round);
            }
            let friction = if lagging {
                FrictionLag::At(&ws.lag, lag_contact.as_ref())
            } else if rounds {
                FrictionLag::Stick
            } else {
                FrictionLag::Start
            };
            let terms = StepTerms {
                c: 0.0,
                q: &[],
                mq: &[],
                dead: &ws.dead,
                pressure: model.pressure_at(lambda, Some(lambda)),
                time: lambda,
                start: Some((&state.positions, dlambda)),
                friction,
                gas: &gas,
                plastic: &state.plastic,
            };
            let solved = solve_increment(
                self.relax,
                model,
                terms,
                // A round after the first relaxes from the round before's
                // solution, the increment's first from its start.
                (
                    if lagging { &ws.lag } else { &state.positions },
                    &mut state.contact,
                ),
                &mut ws.y,
                length,
                settings,
                &mut ws.newton,
                &mut ws.f_ext,
                &ws.old_ext,
                &mut ws.my,
                &mut ws.grown,
            );
            let (report, energies) = match solved {
                Ok(solved) => solved,
                Err(e) => {
                    if round > 0 {
                        let limit = lagged.iter().flatten().map(|(_, f)| f).sum();
                        ws.friction_shortfall = Some(FrictionShortfall { needed, limit });
                        state.contact = start_contact;
                    }
                    return Err(e);
                }
            };
            total = Some(merge_reports(total, report));
            if !rounds {
                break energies;
            }
            if round == 0 {
                needed = stick_force(model, state, (&ws.y, lambda, dlambda));
            }
            let now = lagged_forces(model, state, (&ws.y, lambda, dlambda));
            let settled = round > 0 && lagged.as_ref().is_some_and(|f| same_forces(f, &now));
            if settled || round == FRICTION_ROUNDS {
                break energies;
            }
            lagged = Some(now);
            ws.lag.clear();
            ws.lag.extend_from_slice(&ws.y);
            lag_contact.clone_from(&state.contact);
            lagging = true;
            round += 1;
        };
        let mut work = 0.0;
        for i in 0..ws.y.len() {
            work += 0.5 * (ws.old_ext[i] + ws.f_ext[i]) * (ws.y[i] - state.positions[i]);
        }
        work += end_gas_steps(model, &gas, &ws.y, state) + energies.obstacles;
        super::terms::slip(model, &ws.y, &mut state.plastic);
        std::mem::swap(&mut state.positions, &mut ws.y);
        state.time = from + lambda;
        state.external_work += work;
        state.friction_dissipation += energies.friction;
        Ok(StepOutcome {
            newton: total.unwrap_or_else(super::empty_report),
            energies,
        })
    }
}

/// Most pseudo-steps of one relaxed increment.
const RELAX_STEPS: usize = 400;
/// The factor on `tau` after a pseudo-step that failed.
const RELAX_SHRINK: f64 = 0.25;
/// The bounds on `tau`'s factor after a pseudo-step that converged.
const RELAX_GROWTH: (f64, f64) = (0.5, 4.0);
/// Newton iterations within which a pseudo-step counts as easy: the next
/// is at least twice as long.
const RELAX_EASY: usize = 4;
/// The most Newton iterations of one pseudo-step (fewer where
/// `[solver] max_iterations` says): a longer one is cut. A pseudo-step
/// across a fold converges slowly (projected Newton clipping the
/// unstable direction); cut at 30, half of a relaxed level's iterations
/// went into pseudo-steps that were then repeated shorter. With 100 (and
/// pseudo-steps solved to 1e-8, before `RELAX_TOLERANCE`), a Matsudaira
/// A level relaxed in 1,130 iterations against 2,694 and a B level in
/// 1,705 against 3,521 (docs/performance.md, "What a relaxed pseudo-step
/// may cost").
const RELAX_ITERATIONS: usize = 100;
/// The increment tolerance (`|dY| / L`) of a pseudo-step that does not
/// end its increment, where `[solver] tolerance` is tighter. A pseudo-step
/// only has to carry the fabric nearer to rest: solved to 1e-8, a
/// pseudo-step of a friction round stalled for tens of iterations just
/// above that tolerance (residual met, increments of 1e-7 creeping along
/// a fold). The pseudo-step whose solution meets the end test is solved
/// again from there to `[solver] tolerance`, so an increment's result is
/// as converged as before (docs/performance.md, "Inexact pseudo-steps").
const RELAX_TOLERANCE: f64 = 1e-6;
/// The last Newton increment (`|dY| / L`) within which a pseudo-step cut
/// at [`RELAX_ITERATIONS`] is kept when its energy fell: a hundred times
/// [`RELAX_TOLERANCE`], a pseudo-step creeping to its end (measured on
/// the library's M2: cut at 1e-5, against 1e-4 to 2e-3 for the
/// pseudo-steps across a fold, which are repeated shorter).
const RELAX_KEEP: f64 = 1e-4;
/// The shortest `tau`, relative to the first, before relaxing gives up.
const RELAX_SHORTEST: f64 = 1e-6;

/// Solves the static increment `base` (its inertia unset) from `y` by
/// Newton, and where that fails and `relax` is set, by pseudo-transient
/// continuation from `start` (the increment's start, or a friction
/// round's: the round before's solution; module docs); the
/// arguments otherwise [`solve_step`]'s. Returns the Newton iterations of
/// the pseudo-steps (or of the plain solve) and the last one's energies.
#[allow(clippy::too_many_arguments)]
fn solve_increment(
    relax: bool,
    model: &Model,
    base: StepTerms,
    (start, contact): (&[f64], &mut Option<crate::contact::ContactState>),
    y: &mut [f64],
    length: f64,
    settings: &NewtonSettings,
    newton: &mut crate::solver::newton::NewtonWorkspace,
    f_ext: &mut [f64],
    old_ext: &[f64],
    my: &mut [f64],
    grown: &mut Option<super::grown::Grown>,
) -> Result<(NewtonReport, StepEnergies), NewtonError> {
    // The plain increment first (no inertia: `tau` infinite); the
    // pseudo-steps' buffers are made when they start.
    let (mut anchor, mut q, mut mq) = (Vec::new(), Vec::new(), Vec::new());
    let (mut tau, mut first) = (f64::INFINITY, f64::INFINITY);
    let mut total: Option<NewtonReport> = None;
    let (mut previous, mut scale) = (None::<f64>, 0.0f64);
    let mut last = (f64::INFINITY, f64::INFINITY);
    // Set while the pseudo-step just solved loosely, whose solution met
    // the end test, is solved again from that solution to full tolerance.
    let mut polishing = false;
    for _ in 0..RELAX_STEPS {
        let c = if tau.is_finite() {
            1.0 / (tau * tau)
        } else {
            0.0
        };
        if let (Some(p), true) = (&newton.progress, c > 0.0) {
            p.pseudo_step();
        }
        let terms = if c > 0.0 {
            for (qi, a) in q.iter_mut().zip(&anchor) {
                *qi = c * a;
            }
            model.mass_times(&q, &mut mq);
            if !polishing {
                y.copy_from_slice(&anchor);
            }
            StepTerms {
                c,
                q: &q,
                mq: &mq,
                ..base
            }
        } else {
            base
        };
        // A pseudo-step is meant to be easy: one Newton cannot solve in
        // a few iterations is made shorter rather than pursued; and it is
        // solved loosely unless it is being polished.
        let loose = settings.tolerance.max(RELAX_TOLERANCE);
        let pseudo = NewtonSettings {
            max_iterations: settings.max_iterations.min(RELAX_ITERATIONS),
            tolerance: if polishing { settings.tolerance } else { loose },
            ..*settings
        };
        let polish_next = !polishing && loose > settings.tolerance;
        let settings = if c > 0.0 { &pseudo } else { settings };
        let solved = solve_step(
            model, terms, contact, y, length, settings, newton, f_ext, old_ext, my, grown,
        );
        match solved {
            Err(e @ NewtonError::Interrupted { .. }) => return Err(e),
            Err(e) if tau.is_infinite() && !relax => return Err(e),
            Err(_) if tau.is_infinite() => {
                anchor = start.to_vec();
                (q, mq) = (vec![0.0; start.len()], vec![0.0; start.len()]);
                first = pseudo_time(model, base.dead);
                tau = first;
            }
            Ok(solved) if tau.is_infinite() => return Ok(solved),
            Err(e) => {
                // A pseudo-step cut at its iterations when it was all but
                // solved, downhill, is kept (module docs): its last
                // iterate is the next anchor, its iterations count. Not
                // one that compresses an element past Saint-Venant–
                // Kirchhoff's stability, which no converged step may
                // either (measured: kept at a stretch of 1e-4 with a
                // residual of 2.8e3 N, its next pseudo-steps all failed).
                if !polishing
                    && let NewtonError::NotConverged {
                        iterations,
                        increment,
                        ..
                    } = e
                    && increment <= RELAX_KEEP
                    && newton.descent.is_some_and(|(first, last)| last < first)
                    && super::unstable(model, y).is_none()
                {
                    let kept = NewtonReport {
                        iterations,
                        ..super::empty_report()
                    };
                    total = Some(merge_reports(total, kept));
                    anchor.copy_from_slice(y);
                    if let (Some(cm), Some(state)) = (model.contact(), contact.as_mut()) {
                        cm.refresh_features(y, base.time, state);
                    }
                }
                // A polish that fails (it starts at a loose solution
                // near rest, so it should not) counts as the pseudo-step's
                // failure: `y` is reset to the solution before.
                polishing = false;
                tau *= RELAX_SHRINK;
                if tau < RELAX_SHORTEST * first {
                    return Err(e);
                }
            }
            Ok((report, energies)) => {
                let iterations = report.iterations;
                total = Some(merge_reports(total, report));
                // The static residual: the pseudo-step's inertia force
                // off the supports.
                for ((d, yi), a) in q.iter_mut().zip(y.iter()).zip(&anchor) {
                    *d = yi - a;
                }
                model.mass_times(&q, &mut mq);
                let residual = c * mq
                    .iter()
                    .zip(model.fixed())
                    .filter(|(_, held)| !**held)
                    .map(|(f, _)| f * f)
                    .sum::<f64>()
                    .sqrt();
                if previous.is_none() {
                    // The loads' size; without loads (an increment
                    // driven by its supports or obstacles alone), the
                    // first pseudo-step's residual.
                    scale = norm(f_ext);
                    if scale == 0.0 {
                        scale = residual;
                    }
                }
                last = (residual, norm(&q) / length);
                if residual <= settings.residual_tolerance * scale {
                    if polish_next {
                        // Solve this pseudo-step again, from here, to
                        // full tolerance; its anchor and `tau` are kept.
                        polishing = true;
                        continue;
                    }
                    let report = total.unwrap_or_else(super::empty_report);
                    return Ok((report, energies));
                }
                polishing = false;
                anchor.copy_from_slice(y);
                // A pseudo-step Newton solved at once may be longer,
                // whatever the residual did (a fold creeping across
                // lowers it slowly).
                let easy = if iterations <= RELAX_EASY { 2.0 } else { 0.0 };
                let growth = previous.map_or(RELAX_GROWTH.1, |p| p / residual).max(easy);
                tau *= growth.clamp(RELAX_GROWTH.0, RELAX_GROWTH.1);
                previous = Some(residual);
            }
        }
    }
    Err(NewtonError::NotConverged {
        iterations: total.map_or(0, |t| t.iterations),
        residual: last.0,
        increment: last.1,
    })
}

/// The first pseudo-step's `tau` (s): `sqrt(h / a)`, the time a node
/// takes to fall the mesh's mean edge `h` from rest under the load's
/// acceleration `a` (the dead loads' nodal magnitudes over the mass); 10 ms
/// without dead loads.
fn pseudo_time(model: &Model, dead: &[f64]) -> f64 {
    let mesh = model.mesh();
    let (mut edges, mut count) = (0.0, 0usize);
    for t in mesh.elements() {
        for m in 0..3 {
            let (a, b) = (mesh.nodes[t[m]], mesh.nodes[t[(m + 1) % 3]]);
            edges += crate::vec3::norm(crate::vec3::sub(b, a));
            count += 1;
        }
    }
    let ones = vec![1.0; dead.len()];
    let mut m1 = vec![0.0; dead.len()];
    model.mass_times(&ones, &mut m1);
    let mass: f64 = m1.iter().step_by(3).sum();
    let load: f64 = dead
        .chunks_exact(3)
        .map(|f| (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt())
        .sum();
    let h = edges / count.max(1) as f64;
    if load > 0.0 && mass > 0.0 && h > 0.0 {
        (h * mass / load).sqrt()
    } else {
        1e-2
    }
}

/// Whether friction acts: against an obstacle or between the layers.
fn has_friction(model: &Model) -> bool {
    model.contact().is_some_and(|c| c.has_friction())
        || model.self_contact().is_some_and(|s| s.friction() > 0.0)
}

/// The normal forces `mu lambda` (N) friction would lag at `y`, the end of
/// the increment `dlambda` to the load factor `lambda` from `state`'s
/// positions, whose contact state `state` holds: the obstacles' by node,
/// then the layers' pairs by their first node.
fn lagged_forces(
    model: &Model,
    state: &State,
    (y, lambda, dlambda): (&[f64], f64, f64),
) -> Vec<(usize, f64)> {
    let start = (&state.positions[..], dlambda);
    let mut forces = Vec::new();
    if let (Some(contact), Some(cs)) = (model.contact(), state.contact.as_ref())
        && contact.has_friction()
    {
        let term = FrictionTerm::lagged_at(contact, model.pattern(), (y, lambda), start, cs);
        forces.extend(term.forces());
    }
    if let Some(sc) = model.self_contact().filter(|s| s.friction() > 0.0) {
        let term = SelfFrictionTerm::lagged_at(sc, model.pattern(), y, start, true);
        forces.extend(term.forces());
    }
    forces
}

/// The tangential force the stick round's springs carry at its solution
/// `y` (N; 0 without friction against the obstacles).
fn stick_force(model: &Model, state: &State, (y, lambda, dlambda): (&[f64], f64, f64)) -> f64 {
    let (Some(contact), Some(cs)) = (model.contact(), state.contact.as_ref()) else {
        return 0.0;
    };
    if !contact.has_friction() {
        return 0.0;
    }
    let t0 = lambda - dlambda;
    FrictionTerm::stick(
        contact,
        model.pattern(),
        (&state.positions, t0, dlambda),
        cs,
        model.membrane_stiffness(),
    )
    .stick_force(y)
}

/// Whether two rounds' lagged forces agree: the sum over the nodes of the
/// change of each node's force (summed over its pairs; a node in one
/// round's pairs only counts 0 in the other's) within [`SETTLED`] of the
/// forces' sum. Summed, not node by node: a node at an obstacle's edge
/// may graze it in one round and not in the next, for ever (measured on
/// examples/drape-tester-static.toml: the pedestal's rim nodes alternate
/// between two rounds' sets with 0.4–0.9 % of the whole force).
fn same_forces(a: &[(usize, f64)], b: &[(usize, f64)]) -> bool {
    let mut by_node = std::collections::BTreeMap::new();
    for &(p, f) in a {
        *by_node.entry(p).or_insert(0.0) += f;
    }
    for &(p, f) in b {
        *by_node.entry(p).or_insert(0.0) -= f;
    }
    let change: f64 = by_node.values().map(|d: &f64| d.abs()).sum();
    let whole: f64 = a.iter().chain(b).map(|(_, f)| 0.5 * f.abs()).sum();
    change <= SETTLED * whole
}
