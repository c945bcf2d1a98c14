//! Newton–Raphson on `G(Y) = 0` (docs/theory.md §1.7).
//!
//! Each iteration solves `H dY = -G` and sets `Y <- Y + dY`. The iteration
//! has converged when both
//!
//! * `|dY| / L <= tolerance`, with `L` the Euclidean norm of the initial
//!   positions measured from their centroid (docs/theory.md §1.7), made
//!   independent of where the origin lies and never zero for a mesh of
//!   more than one node (the safeguard for `|X|` near zero); and
//! * `|G| <= residual_tolerance * scale`, with `scale` the sum of the norms
//!   of the force terms that make up `G` (internal, external, inertial),
//!   so the test is relative to the forces at play.
//!
//! An increment at the round-off of the positions (`|dY| / L <= 4
//! eps`) also ends the iteration: nothing is left to gain.
//! A first guess whose residual is already at round-off (`|G| <= 1e-13
//! scale`, e.g. free fall from the Newmark predictor) is accepted with no
//! iteration. Each Newton increment is applied in full when it reduces
//! `|G|`, as it always does near a solution (so quadratic convergence is
//! kept). A system with an energy ([`Evaluation::energy`]: every term of
//! the step's incremental potential a potential) accepts it when it lowers
//! the energy by Armijo's condition `E(Y + a dY) <= E(Y) + 1e-4 a G.dY`,
//! or reduces `|G|` without raising the energy beyond its round-off (a
//! residual can fall while the energy rises: far from a minimum, `|G|` is
//! no merit function). Otherwise the increment is halved, at most four
//! times without an energy and ten with one (a backtracking line search:
//! contact makes `G` only piecewise smooth, and a full step can overshoot
//! a node's entry into or exit from contact; Nocedal & Wright 2006,
//! §3.1). The search starts at the system's [`NewtonSystem::max_step`]
//! when that is below 1 (a barrier's collision-free step), and a trial
//! whose energy is not finite is never taken: when every trial has one,
//! the solve fails ([`NewtonError::NoAdmissibleStep`]).
//!
//! When a full step's increment is above the tolerance (so the iteration
//! cannot end there) and no chord step will follow, the trial point's
//! residual is evaluated together with its Hessian, which the next
//! iteration then uses: one element loop per Newton iteration instead of
//! two. A trial the line search shortens is evaluated for its residual only.
//!
//! After a full Newton step that shrank the increment at least fourfold
//! (from the second Newton step of a time step on) or the residual at
//! least a hundredfold, up to
//! [`NewtonSettings::chord_steps`] chord steps reuse its factorisation
//! (the function `chord_steps`); the convergence test is the same for
//! either kind of increment.
//!
//! A system may revise itself after a Newton step
//! ([`NewtonSystem::revise`]: the active set of contact by multipliers);
//! its residual and Hessian are then evaluated again, and the iteration
//! goes on with no step of the old system counting towards convergence.
//!
//! NaN or infinite residuals, a residual that grows by `1e8` over the
//! first one, and running out of linear solves (Newton iterations and
//! chord steps together) are errors that the time integrator answers by
//! cutting the step.

use super::linear::{Factorization, LinearSolveError, LinearSolver};
use super::low_rank::{LowRank, Woodbury};
use crate::vecn::{dot, norm};

/// Convergence settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonSettings {
    /// Bound on `|dY| / |X|` (dimensionless).
    pub tolerance: f64,
    /// Bound on `|G| / scale` (dimensionless).
    pub residual_tolerance: f64,
    /// Most linear solves (Newton iterations and chord steps) per step.
    pub max_iterations: usize,
    /// Most chord steps after each Newton step (0: plain Newton).
    pub chord_steps: usize,
    /// How a system with an energy meets a Hessian that is not positive
    /// definite ([`Projection`]).
    pub projection: Projection,
    /// The increment test as a speed (`[solver] speed_tolerance`, m/s):
    /// in a dynamic step (`dt` set) the increment is measured as the
    /// largest nodal correction per unit time, `max_a |dY_a| / dt`, and
    /// must be at most this, instead of `|dY| / L <= tolerance`.
    pub speed_tolerance: Option<f64>,
    /// The step's size (s), set per step by the dynamic integrator;
    /// `None` in statics.
    pub dt: Option<f64>,
}

impl NewtonSettings {
    /// `(v, dt)` when the increment test is a speed.
    fn speed(&self) -> Option<(f64, f64)> {
        self.speed_tolerance.zip(self.dt)
    }
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-8,
            residual_tolerance: 1e-6,
            max_iterations: 30,
            chord_steps: 2,
            projection: Projection::default(),
            speed_tolerance: None,
            dt: None,
        }
    }
}

/// `[solver] projection`: what Newton does, on a system with an energy
/// (every term of the step a potential, no multipliers) and a symmetric
/// Hessian, when that Hessian is not positive definite — a fabric
/// folding, a membrane compressed past its buckling load, a node pressed
/// into a convex obstacle (module docs, "Projected Newton").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    /// `progressive` for a fabric with bending, `never` for a pure
    /// membrane ([`Projection::resolve`]).
    #[default]
    Auto,
    /// Progressively projected Newton (Fernández-Fernández, Löschner &
    /// Bender 2026): the exact Hessian first; where it is not positive
    /// definite, the stencil Hessians around the nodes of largest residual
    /// are projected to their positive semi-definite part, more of them
    /// until it is.
    Progressive,
    /// Every stencil Hessian projected at every iteration ("projected
    /// Newton", Teran et al. 2005): always a descent direction, but
    /// slower convergence near a solution whose exact Hessian is definite.
    Always,
    /// No projection: the exact Hessian, and a diagonal shift where its
    /// direction goes uphill (release 2's Newton).
    Never,
}

impl Projection {
    /// `auto` made definite for a model with (`bending`) or without
    /// bending. With bending, folds make the Hessian indefinite at the
    /// steps a settle takes, and projecting settles with a tenth of the
    /// cut-backs (docs/performance.md). Without, a Saint-Venant–Kirchhoff
    /// membrane's out-of-plane geometric stiffness is negative wherever it
    /// is compressed, from the first step on; the projected Newton then
    /// minimises each step's energy over directions the exact Newton never
    /// takes, and on a swinging strip (tests/settling.rs) it found
    /// steps that compress elements into the material's unstable branch
    /// where the exact Newton keeps them taut.
    pub fn resolve(self, bending: bool) -> Self {
        match self {
            Projection::Auto if bending => Projection::Progressive,
            Projection::Auto => Projection::Never,
            p => p,
        }
    }
}

/// How a converged Newton iteration went.
#[derive(Debug, Clone, PartialEq)]
pub struct NewtonReport {
    /// Newton iterations (each with a new Hessian).
    pub iterations: usize,
    /// Chord steps accepted besides (solves with the factorisation of an
    /// earlier iterate's Hessian).
    pub chord_steps: usize,
    /// `|G|` at each evaluation, the last one at the converged point.
    pub residuals: Vec<f64>,
    /// `|dY| / |X|` of each iteration.
    pub increments: Vec<f64>,
    /// Factorisation used by the last solve, if any.
    pub factorization: Option<Factorization>,
    /// Times the Hessian's diagonal was shifted for a descent direction
    /// (an energy whose Hessian is indefinite).
    pub shifts: usize,
    /// Hessians evaluated again with more stencils projected, after a
    /// factorisation found the Hessian not positive definite.
    pub projections: usize,
}

/// Why Newton stopped without converging.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum NewtonError {
    /// Asked to stop (a signal) before the solve ended: not a failure of
    /// the step, never cut back.
    #[error("interrupted at iteration {iteration}")]
    Interrupted {
        /// Iteration.
        iteration: usize,
    },
    /// Out of iterations.
    #[error(
        "no convergence in {iterations} iterations (residual {residual:.3e}, relative increment {increment:.3e})"
    )]
    NotConverged {
        /// Iterations done.
        iterations: usize,
        /// Last `|G|` (N).
        residual: f64,
        /// Last `|dY| / |X|`.
        increment: f64,
    },
    /// The residual grew out of bounds.
    #[error("diverged at iteration {iteration}: residual {residual:.3e} N")]
    Diverged {
        /// Iteration.
        iteration: usize,
        /// `|G|` (N).
        residual: f64,
    },
    /// NaN or infinity in the residual.
    #[error("non-finite residual at iteration {iteration}")]
    NonFinite {
        /// Iteration.
        iteration: usize,
    },
    /// The linear system could not be solved.
    #[error(transparent)]
    Linear(#[from] LinearSolveError),
    /// The step's solution compresses an element of a membrane without
    /// tension field below the stretch `1/sqrt(3)` where
    /// Saint-Venant–Kirchhoff loses stability: not a solution to keep
    /// (a shorter step may find the one that stays clear of it).
    #[error(
        "element {element} compressed to a stretch of {stretch:.4}, below 1/sqrt(3) where Saint-Venant-Kirchhoff loses stability in compression"
    )]
    MaterialInstability {
        /// The element.
        element: usize,
        /// Its smallest principal stretch.
        stretch: f64,
    },
    /// The contact active set did not settle.
    #[error("the contact active set kept changing for {rounds} re-solutions of the step")]
    ActiveSetCycle {
        /// Re-solutions tried.
        rounds: usize,
    },
    /// The line search found no admissible point along the Newton
    /// direction: the system admits no step of it (`max_step` not
    /// positive), or every trial down to the shortest had an energy that
    /// is not finite (a barrier crossed).
    #[error("no admissible step at iteration {iteration}: {why} along the Newton direction")]
    NoAdmissibleStep {
        /// Iteration.
        iteration: usize,
        /// Why: the system's limit, or the energy.
        why: &'static str,
    },
}

/// What an evaluation of the system reports besides `G` and `H`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluation {
    /// Sum of the norms of the force terms of `G` (N).
    pub scale: f64,
    /// Whether `H` is symmetric (Cholesky applies).
    pub symmetric: bool,
    /// The residual norm to judge convergence and progress by, when it is
    /// not `|G|` (constrained systems whose `G` carries right-hand-side
    /// corrections).
    pub merit: Option<f64>,
    /// The energy whose gradient `G` is, when the system has one (every
    /// term of the incremental potential a potential, no multipliers):
    /// the line search then accepts a step that lowers it enough (Armijo).
    pub energy: Option<f64>,
}

/// A nonlinear system `G(Y) = 0` with Hessian `H = dG/dY` on a fixed pattern.
pub trait NewtonSystem {
    /// Writes `G(y)` into `g` and, if asked, `H(y)` into `h`.
    fn evaluate(&mut self, y: &[f64], g: &mut [f64], h: Option<&mut [f64]>) -> Evaluation;

    /// Maps the solution of `H dY = -G` to the increment of `Y` (for systems
    /// solved in rotated local bases). Default: the identity.
    fn transform_increment(&self, _dy: &mut [f64]) {}

    /// From now on, until called again, the Hessian's evaluations project
    /// the stencil Hessians of every term that is a potential to their
    /// positive semi-definite part where a stencil has a node flagged in
    /// `nodes` (one flag per node, `3 n` unknowns); `None`: the exact
    /// Hessian. Default: ignored (a system that cannot project).
    fn project(&mut self, _nodes: Option<&[bool]>) {}

    /// After a Newton step to `y` (whose residual was just evaluated): lets
    /// the system revise its constraints; returns whether it changed (then
    /// `G` and `H` are evaluated again at `y`). Default: never.
    fn revise(&mut self, _y: &[f64]) -> bool {
        false
    }

    /// The largest fraction of the increment `dy` from `y` the system
    /// admits (a barrier's: the step that no collision cuts, Li et al.
    /// 2020); the line search starts there, and a chord step that it would
    /// cut is not taken. Default 1: no limit.
    fn max_step(&self, _y: &[f64], _dy: &[f64]) -> f64 {
        1.0
    }

    /// The symmetric low-rank part of the Hessian last evaluated, which
    /// `H` leaves out (`H + U C U^T` is the tangent): every solve adds it
    /// by Woodbury's identity ([`super::low_rank`]). Default: none.
    fn low_rank(&self) -> Option<&LowRank> {
        None
    }
}

/// Buffers reused across Newton iterations and steps.
#[derive(Debug)]
pub struct NewtonWorkspace {
    g: Vec<f64>,
    h: Vec<f64>,
    dy: Vec<f64>,
    y_old: Vec<f64>,
    /// The sparse direct solver (symbolic analysis kept).
    pub linear: LinearSolver,
    /// Where the Hessian's diagonal entries are (found on first use) and
    /// their values before a shift.
    diagonal: Vec<Option<usize>>,
    unshifted: Vec<f64>,
    /// The projected Newton's state in the current solve.
    ppn: Progressive,
    /// The system's low-rank part for the last factorisation.
    woodbury: Woodbury,
    /// Set from outside (a signal, through the run's stop flag) to end a
    /// solve at its next iteration or line-search trial with
    /// [`NewtonError::Interrupted`] (issue 46: a step that never ends
    /// must not hold a Ctrl-C back).
    pub interrupt: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
    /// Where a front end reads the step in progress: each solve and
    /// iteration counted, the last residual (`crate::progress`).
    pub progress: Option<std::sync::Arc<crate::progress::StepProgress>>,
    /// The last solve's energy at its first guess and at its last
    /// iterate, when its system has a finite energy throughout and was
    /// not revised in between: whether a solve that did not converge
    /// still went downhill (a relaxed pseudo-step keeps such an iterate,
    /// `integrator::statics`).
    pub descent: Option<(f64, f64)>,
    /// The Newton iterations (each with a new Hessian, as
    /// [`NewtonReport::iterations`] counts them) of every solve in this
    /// workspace since it was made, converged or not: what a step's
    /// attempts cost, the solves it threw away included.
    pub iterations: usize,
}

/// The progressively projected Newton's state over one solve: the
/// residual threshold above which a node's stencils are projected
/// (`None`: nothing projected yet in this solve), and the node flags.
#[derive(Debug, Default)]
struct Progressive {
    threshold: Option<f64>,
    flags: Vec<bool>,
}

/// What [`backtrack`] says when the workspace's interrupt stopped it.
const INTERRUPTED: &str = "interrupted";

/// [`NewtonError::Interrupted`] once the workspace's interrupt is set.
fn interrupted(ws: &NewtonWorkspace, iteration: usize) -> Result<(), NewtonError> {
    match &ws.interrupt {
        Some(flag) if flag.load(std::sync::atomic::Ordering::Relaxed) => {
            Err(NewtonError::Interrupted { iteration })
        }
        _ => Ok(()),
    }
}

impl NewtonWorkspace {
    /// The Hessian buffer (values on the linear solver's pattern) and the
    /// linear solver, for a one-off system on the same pattern between
    /// Newton solves — the initial acceleration's mass matrix: no second
    /// array of that size (250 MB for a million elements), and the buffer
    /// is first written in set-up rather than in the first step. Newton
    /// overwrites the values at its next evaluation.
    pub fn matrix_and_solver(&mut self) -> (&mut [f64], &mut LinearSolver) {
        (&mut self.h, &mut self.linear)
    }

    /// Binds the workspace to another pattern: `linear` solves on it and
    /// the Hessian buffer gets its `nnz` entries (the stepper's layout
    /// grown with self-contact's pairs, `integrator::grown`).
    pub fn rebind(&mut self, linear: LinearSolver, nnz: usize) {
        self.linear = linear;
        self.h = vec![0.0; nnz];
        self.diagonal.clear();
        self.unshifted.clear();
    }

    /// Buffers for `n` unknowns and `nnz` Hessian entries on `linear`'s pattern.
    pub fn new(n: usize, nnz: usize, linear: LinearSolver) -> Self {
        Self {
            g: vec![0.0; n],
            h: vec![0.0; nnz],
            dy: vec![0.0; n],
            y_old: vec![0.0; n],
            linear,
            diagonal: Vec::new(),
            unshifted: Vec::new(),
            ppn: Progressive::default(),
            woodbury: Woodbury::default(),
            interrupt: None,
            progress: None,
            descent: None,
            iterations: 0,
        }
    }
}

/// The largest number of shifts tried on a Hessian whose Newton direction
/// goes uphill, and the first shift (relative to each diagonal entry).
const MAX_SHIFTS: usize = 4;
const FIRST_SHIFT: f64 = 0.03;

/// With an energy whose Newton direction `dY = -H^-1 G` is no descent
/// direction (`G . dY >= 0`: `H` is indefinite, as where a membrane is
/// compressed beyond its buckling load at a long time step), solves again
/// with the diagonal shifted, `(H + tau |diag H|) dY = -G`, `tau = 0.03`,
/// `0.3`, `3`, `30` (never 1, which would zero a negative diagonal entry;
/// Levenberg and Marquardt's scaling; Nocedal & Wright 2006,
/// §3.4, "modified Newton"), until the direction descends; the Hessian is
/// left shifted for the step's line search and chord steps. Returns the
/// slope `G . dY` of the direction kept; `report` counts the shifts and
/// records the last factorisation.
fn descend(
    system: &impl NewtonSystem,
    ws: &mut NewtonWorkspace,
    report: &mut NewtonReport,
    symmetric: bool,
    mut slope: f64,
) -> Result<f64, NewtonError> {
    if slope < 0.0 {
        return Ok(slope);
    }
    if ws.diagonal.is_empty() {
        ws.diagonal = ws.linear.diagonal_positions();
    }
    ws.unshifted.clear();
    ws.unshifted
        .extend(ws.diagonal.iter().map(|p| p.map_or(0.0, |p| ws.h[p])));
    let mut tau = FIRST_SHIFT;
    for _ in 0..MAX_SHIFTS {
        if slope < 0.0 {
            break;
        }
        for (p, d) in ws.diagonal.iter().zip(&ws.unshifted) {
            if let Some(p) = *p {
                ws.h[p] = d + tau * d.abs();
            }
        }
        solve_for_increment(system, ws, report, symmetric)?;
        slope = dot(&ws.g, &ws.dy);
        report.shifts += 1;
        tau *= 10.0;
    }
    Ok(slope)
}

/// The factor on the projected Newton's residual threshold after a
/// Hessian that is not positive definite: the threshold starts at half
/// the largest nodal residual and halves from there, so each retry
/// projects the stencils of more nodes (Fernández-Fernández et al. 2026).
const TIGHTEN: f64 = 0.5;
/// The factor on the threshold after a positive definite Hessian: fewer
/// stencils are projected as the iteration converges, where the exact
/// Hessian's quadratic convergence is wanted.
const RELEASE: f64 = 2.0;
/// Retries with a tighter threshold before every stencil is projected:
/// each costs a Hessian assembly and a failed factorisation.
const PARTIAL_RETRIES: usize = 2;

/// Whether the projected Newton serves this evaluation: a system with
/// an energy and a symmetric Hessian, projection not switched off.
fn projects(settings: &NewtonSettings, eval: &Evaluation) -> bool {
    matches!(
        settings.projection,
        Projection::Progressive | Projection::Always
    ) && eval.energy.is_some()
        && eval.symmetric
}

/// At the start of a solve: nothing projected (`progressive`, `never`),
/// or every stencil (`always`); `n` unknowns.
fn start_projection(
    system: &mut impl NewtonSystem,
    settings: &NewtonSettings,
    ws: &mut NewtonWorkspace,
    n: usize,
) {
    ws.ppn.threshold = None;
    ws.ppn.flags.clear();
    ws.ppn
        .flags
        .resize(n / 3, settings.projection == Projection::Always);
    if settings.projection == Projection::Always {
        system.project(Some(&ws.ppn.flags));
    } else {
        system.project(None);
    }
}

/// The largest nodal residual `max_a |G_a|_inf` (N).
fn largest_nodal(g: &[f64]) -> f64 {
    g.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// Before the Hessian at an iterate whose residual is in `ws.g` is
/// evaluated (progressive projection with a threshold): flags the nodes
/// whose residual `|G_a|_inf` reaches it; none flagged, the exact Hessian.
fn flag_for_projection(
    system: &mut impl NewtonSystem,
    settings: &NewtonSettings,
    ws: &mut NewtonWorkspace,
) {
    if settings.projection != Projection::Progressive {
        return;
    }
    let Some(threshold) = ws.ppn.threshold else {
        return;
    };
    if flag_nodes(&ws.g, threshold, &mut ws.ppn.flags) == 0 {
        system.project(None);
    } else {
        system.project(Some(&ws.ppn.flags));
    }
}

/// Sets `flags[a]` where node `a`'s residual `|G_a|_inf >= threshold`;
/// returns how many.
fn flag_nodes(g: &[f64], threshold: f64, flags: &mut [bool]) -> usize {
    let mut count = 0;
    for (flag, ga) in flags.iter_mut().zip(g.chunks_exact(3)) {
        *flag = ga.iter().any(|v| v.abs() >= threshold);
        count += usize::from(*flag);
    }
    count
}

/// The projected Newton's direction (module docs): `ws.dy = -H^-1 G`
/// with a positive definite `H` — the exact Hessian when it is one,
/// otherwise evaluated again at `y` with the stencils of more and more
/// nodes projected to their positive semi-definite part, the nodes of
/// largest residual first, until the factorisation succeeds and the
/// direction descends. A Hessian singular even with every stencil
/// projected (a static problem without supports enough) goes to
/// release 2's path: the general solve, then a diagonal shift
/// ([`descend`]). Returns the slope `G . dY < 0`.
#[allow(clippy::too_many_arguments)]
fn projected_direction(
    system: &mut impl NewtonSystem,
    y: &[f64],
    ws: &mut NewtonWorkspace,
    report: &mut NewtonReport,
    eval: &mut Evaluation,
    settings: &NewtonSettings,
    relative: f64,
) -> Result<f64, NewtonError> {
    ws.linear.krylov_tolerance = relative.clamp(1e-12, 1e-4);
    let mut all = settings.projection == Projection::Always;
    let mut retries = 0;
    loop {
        for (d, g) in ws.dy.iter_mut().zip(&ws.g) {
            *d = -g;
        }
        if let Some(used) = ws.linear.solve_spd(&ws.h, &mut ws.dy)? {
            ws.woodbury
                .prepare(system.low_rank(), &mut ws.linear, &ws.h, true, &mut ws.dy)?;
            system.transform_increment(&mut ws.dy);
            let slope = dot(&ws.g, &ws.dy);
            if slope < 0.0 {
                report.factorization = Some(used);
                ws.ppn.threshold = ws.ppn.threshold.map(|t| t * RELEASE);
                return Ok(slope);
            }
        }
        if all {
            direction(system, ws, report, eval.symmetric, relative)?;
            return descend(system, ws, report, eval.symmetric, dot(&ws.g, &ws.dy));
        }
        let largest = largest_nodal(&ws.g);
        let threshold = match ws.ppn.threshold {
            None => TIGHTEN * largest,
            Some(t) => TIGHTEN * t.min(largest),
        };
        ws.ppn.threshold = Some(threshold);
        all = retries >= PARTIAL_RETRIES
            || flag_nodes(&ws.g, threshold, &mut ws.ppn.flags) == ws.ppn.flags.len();
        if all {
            ws.ppn.flags.fill(true);
        }
        retries += 1;
        system.project(Some(&ws.ppn.flags));
        *eval = system.evaluate(y, &mut ws.g, Some(&mut ws.h[..]));
        report.projections += 1;
    }
}

/// An increment `|dY| / L` at the round-off of the positions: Newton
/// cannot move them any more, so the iterate is the solution (a problem
/// with no load, whose residual is the round-off of forces that are all
/// zero, has no force scale to judge it by).
const STALLED: f64 = 4.0 * f64::EPSILON;

/// The size of the increment `dy` as the convergence test measures it:
/// `|dY| / L` (`length` = L), or with a speed tolerance the largest nodal
/// correction per unit time, `max_a |dY_a| / dt` (m/s).
fn increment_of(settings: &NewtonSettings, dy: &[f64], length: f64) -> f64 {
    match settings.speed() {
        None => norm(dy) / length,
        Some((_, dt)) => {
            dy.chunks_exact(3)
                .map(|d| d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
                .fold(0.0f64, f64::max)
                .sqrt()
                / dt
        }
    }
}

/// The bound on [`increment_of`]: `tolerance`, or the speed tolerance.
fn increment_tolerance(settings: &NewtonSettings) -> f64 {
    settings.speed().map_or(settings.tolerance, |(v, _)| v)
}

/// The convergence test of the module docs: the last increment applied
/// (`INFINITY` before the first) and the residual both small, or the
/// residual at round-off.
fn converged(settings: &NewtonSettings, increment: f64, residual: f64, scale: f64) -> bool {
    (increment <= increment_tolerance(settings) && residual <= settings.residual_tolerance * scale)
        || residual <= 1e-13 * scale
        || residual == 0.0
        || match settings.speed() {
            None => increment <= STALLED,
            // The largest correction at the round-off of positions of
            // order 1 m.
            Some((_, dt)) => increment * dt <= STALLED,
        }
}

/// Whether the iteration ends before iteration `it`: `Ok(true)` when it
/// has converged ([`converged`]), an error when its residual is not finite
/// or above `diverged_above` (after the first iteration), or when it is
/// out of iterations.
fn ended(
    settings: &NewtonSettings,
    it: usize,
    residual: f64,
    increment: f64,
    scale: f64,
    diverged_above: f64,
) -> Result<bool, NewtonError> {
    if !residual.is_finite() {
        return Err(NewtonError::NonFinite { iteration: it });
    }
    if converged(settings, increment, residual, scale) {
        return Ok(true);
    }
    if residual > diverged_above && it > 0 {
        return Err(NewtonError::Diverged {
            iteration: it,
            residual,
        });
    }
    if it >= settings.max_iterations {
        return Err(NewtonError::NotConverged {
            iterations: it,
            residual,
            increment,
        });
    }
    Ok(false)
}

/// The line search along `ws.dy` from `ws.y_old` (the module docs): the
/// full step or the system's [`NewtonSystem::max_step`] if smaller,
/// halved while it neither lowers the residual below `residual` nor, with
/// an energy (`energy0` and the direction's `slope`), meets Armijo's
/// condition — down to 1/16 of the first (1/1024 with an energy), which
/// is taken whatever it gives unless its energy is not finite: a trial of
/// infinite energy (a barrier crossed) is never taken, and the search
/// fails instead. `y` and `eval` are left at the step taken, its Hessian
/// assembled if `hessian_at_trial` and the first step was taken. Returns
/// the step's fraction `alpha`, its residual and whether its Hessian was
/// assembled; `Err(why)` when no step is admissible.
fn backtrack(
    system: &mut impl NewtonSystem,
    y: &mut [f64],
    ws: &mut NewtonWorkspace,
    eval: &mut Evaluation,
    (energy0, slope): (Option<f64>, f64),
    residual: f64,
    mut hessian_at_trial: bool,
) -> Result<(f64, f64, bool), &'static str> {
    let first = system.max_step(&ws.y_old, &ws.dy);
    if first.is_nan() || first <= 0.0 {
        return Err("the system admits no step");
    }
    let mut alpha = first.min(1.0);
    // A first step the system cut short is no full step: its Hessian is
    // not assembled with the trial (nor is it one a chord step reuses).
    hessian_at_trial &= alpha == 1.0;
    let shortest = alpha
        * if energy0.is_some() {
            1.0 / 1024.0
        } else {
            1.0 / 16.0
        };
    loop {
        if interrupted(ws, 0).is_err() {
            return Err(INTERRUPTED);
        }
        for ((yi, y0), d) in y.iter_mut().zip(&ws.y_old).zip(&ws.dy) {
            *yi = y0 + alpha * d;
        }
        *eval = if hessian_at_trial {
            system.evaluate(y, &mut ws.g, Some(&mut ws.h[..]))
        } else {
            system.evaluate(y, &mut ws.g, None)
        };
        let trial = eval.merit.unwrap_or_else(|| norm(&ws.g));
        // With an energy, a smaller residual counts only where the
        // energy did not rise beyond its round-off (near the solution,
        // where Armijo's decrease drowns in it); Armijo's condition
        // counts on its own.
        let (armijo, not_higher) = match (energy0, eval.energy) {
            (Some(e0), Some(e1)) => (
                slope < 0.0 && e1 <= e0 + 1e-4 * alpha * slope,
                e1 <= e0 + 1e-12 * e0.abs(),
            ),
            _ => (false, true),
        };
        let smaller = trial <= (1.0 - 1e-4 * alpha) * residual && not_higher;
        let infinite = eval.energy.is_some_and(|e| !e.is_finite());
        if !infinite && ((trial.is_finite() && (smaller || armijo)) || alpha <= shortest) {
            return Ok((alpha, trial, hessian_at_trial));
        }
        if infinite && alpha <= shortest {
            return Err("every trial down to the shortest had an energy that is not finite");
        }
        alpha *= 0.5;
        // (A shortened step is accepted with a residual only.)
        hessian_at_trial = false;
    }
}

/// The Newton direction `ws.dy = -H^-1 G` with the Hessian and residual
/// in `ws`, transformed by the system; `relative` is `|G| / |G_0|`.
fn direction(
    system: &mut impl NewtonSystem,
    ws: &mut NewtonWorkspace,
    report: &mut NewtonReport,
    symmetric: bool,
    relative: f64,
) -> Result<(), NewtonError> {
    // Inexact Newton (Eisenstat & Walker 1996): Krylov solves need only
    // reduce their residual as far as Newton's has fallen since the
    // step's first iterate, so the tolerance is |G| / |G_0| (keeping
    // quadratic convergence), between 1e-4 and 1e-12.
    ws.linear.krylov_tolerance = relative.clamp(1e-12, 1e-4);
    solve_for_increment(system, ws, report, symmetric)
}

/// `ws.dy = -H^-1 G` with the Hessian (as it stands, shifted or not) and
/// the residual in `ws`, transformed by the system; the factorisation
/// used goes into `report`.
fn solve_for_increment(
    system: &impl NewtonSystem,
    ws: &mut NewtonWorkspace,
    report: &mut NewtonReport,
    symmetric: bool,
) -> Result<(), NewtonError> {
    for (d, g) in ws.dy.iter_mut().zip(&ws.g) {
        *d = -g;
    }
    report.factorization = Some(ws.linear.solve(&ws.h, symmetric, &mut ws.dy)?);
    ws.woodbury.prepare(
        system.low_rank(),
        &mut ws.linear,
        &ws.h,
        symmetric,
        &mut ws.dy,
    )?;
    system.transform_increment(&mut ws.dy);
    Ok(())
}

/// Whether a Newton step of fraction `alpha` contracts fast enough for
/// chord steps to follow: a full step at most a quarter of the one before
/// (`increments`: before, now), or one that cut the residual a
/// hundredfold (`residuals`: before, now) — the local regime where the
/// Hessian changes little. Far from it a chord step can carry the iterate
/// to another root (seen on an undamped swinging cloth whose elements
/// approach SVK's compressive instability). The residual test catches the
/// step after a linear phase: where wrinkling states or contacts switched
/// between the first iterates, the second increment is only a few times
/// smaller than the first, yet the residual falls by orders of magnitude
/// and the next increment is at the tolerance. A step's first Newton step
/// has no step before it, so only the residual test applies to it (an
/// infinite "step before" once let chord steps follow every first
/// iteration, to be rejected at once: docs/performance.md).
fn contracts(alpha: f64, increments: (f64, f64), residuals: (f64, f64)) -> bool {
    let ((previous, increment), (previous_residual, residual)) = (increments, residuals);
    alpha == 1.0
        && ((previous.is_finite() && increment <= 0.25 * previous)
            || residual <= 0.01 * previous_residual)
}

/// Runs Newton from the first guess in `y` (overwritten by the solution).
/// `length`: the reference length `|X|` of the convergence test (m).
pub fn solve(
    system: &mut impl NewtonSystem,
    y: &mut [f64],
    length: f64,
    settings: &NewtonSettings,
    ws: &mut NewtonWorkspace,
) -> Result<NewtonReport, NewtonError> {
    let mut report = NewtonReport {
        iterations: 0,
        chord_steps: 0,
        residuals: Vec::new(),
        increments: Vec::new(),
        factorization: None,
        shifts: 0,
        projections: 0,
    };
    start_projection(system, settings, ws, y.len());
    if let Some(p) = &ws.progress {
        p.solve_started();
    }
    let mut eval = system.evaluate(y, &mut ws.g, Some(&mut ws.h[..]));
    let mut have_hessian = true;
    let mut residual = eval.merit.unwrap_or_else(|| norm(&ws.g));
    report.residuals.push(residual);
    let r0 = residual;
    // The residual beyond which the iteration has diverged.
    let diverged_above = 1e8 * r0.max(eval.scale);
    let mut increment = f64::INFINITY;
    ws.descent = eval.energy.filter(|e| e.is_finite()).map(|e| (e, e));
    loop {
        // The energy at the iterate (a revised system's is not comparable).
        ws.descent = match (ws.descent, eval.energy) {
            (Some((first, _)), Some(e)) if e.is_finite() => Some((first, e)),
            _ => None,
        };
        let it = report.iterations + report.chord_steps;
        interrupted(ws, it)?;
        if let Some(p) = &ws.progress {
            p.iterate(residual);
        }
        if ended(
            settings,
            it,
            residual,
            increment,
            eval.scale,
            diverged_above,
        )? {
            return Ok(report);
        }
        if !have_hessian {
            flag_for_projection(system, settings, ws);
            eval = system.evaluate(y, &mut ws.g, Some(&mut ws.h[..]));
        }
        let relative = residual / r0.max(f64::MIN_POSITIVE);
        let projecting = projects(settings, &eval);
        let mut slope = 0.0;
        if projecting {
            slope = projected_direction(system, y, ws, &mut report, &mut eval, settings, relative)?;
        } else {
            direction(system, ws, &mut report, eval.symmetric, relative)?;
        }
        // Backtracking on |G|: full steps as long as they reduce the
        // residual (always, near a solution); halved up to four times where
        // the residual is only piecewise smooth (contact entering and
        // leaving) and a full step overshoots.
        ws.y_old.copy_from_slice(y);
        let previous = increment;
        let previous_residual = residual;
        let full_increment = increment_of(settings, &ws.dy, length);
        // Chord steps are likely to follow when the increment shrank: they
        // follow a step that shrank it fourfold, or cut the residual a
        // hundredfold, which a shrinking increment usually does.
        let chord_ahead =
            settings.chord_steps > 0 && previous.is_finite() && full_increment <= previous;
        // A full step whose increment is above the tolerance cannot end
        // the iteration: the next iteration needs the Hessian at the trial
        // point, so it is assembled with the trial's residual (one element
        // loop instead of two). Not when chord steps are likely to be tried
        // first: they reuse the factorisation just made, and a Hessian
        // assembled for nothing costs more than a second evaluation of the
        // residual when they are not (measured against expecting chord
        // steps only after a fourfold shrink: docs/performance.md, "The
        // round before").
        // (Nor while the projected Newton flags nodes by their residual:
        // the trial's Hessian needs the trial's residual first.)
        let flags_by_residual =
            settings.projection == Projection::Progressive && ws.ppn.threshold.is_some();
        let hessian_at_trial =
            full_increment > increment_tolerance(settings) && !chord_ahead && !flags_by_residual;
        // With an energy, Armijo's condition on it (the incremental
        // potential's decrease along the Newton direction, whose slope is
        // G . dY) accepts a step as well as a smaller residual does, and
        // the backtracking may go further (the energy is a merit function
        // that the residual of a non-convex potential is not).
        let energy0 = eval.energy;
        if !projecting && energy0.is_some() {
            slope = descend(system, ws, &mut report, eval.symmetric, dot(&ws.g, &ws.dy))?;
        }
        let alpha;
        (alpha, residual, have_hessian) = backtrack(
            system,
            y,
            ws,
            &mut eval,
            (energy0, slope),
            residual,
            hessian_at_trial,
        )
        .map_err(|why| match why {
            INTERRUPTED => NewtonError::Interrupted {
                iteration: report.iterations + 1,
            },
            why => NewtonError::NoAdmissibleStep {
                iteration: report.iterations + 1,
                why,
            },
        })?;
        report.residuals.push(residual);
        increment = alpha * increment_of(settings, &ws.dy, length);
        report.increments.push(increment);
        report.iterations += 1;
        ws.iterations += 1;
        if let Some(p) = &ws.progress {
            p.iterated();
        }
        if system.revise(y) {
            // Another system from here on: its residual and Hessian at `y`,
            // and no step of the old one counts towards convergence.
            eval = system.evaluate(y, &mut ws.g, Some(&mut ws.h[..]));
            have_hessian = true;
            ws.descent = None;
            residual = eval.merit.unwrap_or_else(|| norm(&ws.g));
            report.residuals.push(residual);
            increment = f64::INFINITY;
            continue;
        }
        if contracts(alpha, (previous, increment), (previous_residual, residual))
            && chord_steps(
                system,
                y,
                length,
                settings,
                ws,
                &mut report,
                &mut eval,
                &mut residual,
                &mut increment,
            )
        {
            // The iterate moved: a Hessian assembled at the Newton
            // iterate (with its residual, above) is out of date.
            have_hessian = false;
        }
    }
}

/// Chord steps after a full Newton step: `dY = -H_old^-1 G(Y)` with the
/// factorisation just made, while each step contracts (its increment at
/// most a quarter of the previous one and the residual smaller), at most
/// `settings.chord_steps` of them and only while not yet converged.
///
/// Near a solution a chord step costs a triangular solve and a force
/// evaluation instead of a Hessian assembly and a factorisation, and gains
/// nearly as much as a Newton step: the Hessian has hardly changed (a
/// Newton step followed by chord steps is Shamanskii's method, of
/// convergence order `2 + chords` per factorisation, Kelley 1995 §5.4).
/// Far from it, where the tangent changes (contact entering, wrinkling
/// states switching), the contraction test rejects the step and Newton
/// assembles a new Hessian. A rejected step is undone. The convergence
/// test is unchanged: the last increment applied, chord or Newton, must be
/// below the tolerance. Returns whether a chord step was accepted.
#[allow(clippy::too_many_arguments)]
fn chord_steps(
    system: &mut impl NewtonSystem,
    y: &mut [f64],
    length: f64,
    settings: &NewtonSettings,
    ws: &mut NewtonWorkspace,
    report: &mut NewtonReport,
    eval: &mut Evaluation,
    residual: &mut f64,
    increment: &mut f64,
) -> bool {
    let mut moved = false;
    for _ in 0..settings.chord_steps {
        if converged(settings, *increment, *residual, eval.scale)
            || report.iterations + report.chord_steps >= settings.max_iterations
        {
            return moved;
        }
        for (d, g) in ws.dy.iter_mut().zip(&ws.g) {
            *d = -g;
        }
        if !ws.linear.solve_again(&ws.h, &mut ws.dy) {
            return moved;
        }
        ws.woodbury.correct(&mut ws.dy);
        system.transform_increment(&mut ws.dy);
        let step = increment_of(settings, &ws.dy, length);
        // A chord step the system would cut short is left to a Newton
        // step, whose line search starts below the limit.
        if step.is_nan() || step > 0.25 * *increment || system.max_step(y, &ws.dy) < 1.0 {
            return moved;
        }
        ws.y_old.copy_from_slice(y);
        for (yi, d) in y.iter_mut().zip(&ws.dy) {
            *yi += d;
        }
        let trial_eval = system.evaluate(y, &mut ws.g, None);
        let trial = trial_eval.merit.unwrap_or_else(|| norm(&ws.g));
        let infinite = trial_eval.energy.is_some_and(|e| !e.is_finite());
        if infinite || !(trial.is_finite() && trial < *residual) {
            // Undo: back to the Newton iterate, its residual re-evaluated
            // (the system keeps per-evaluation state).
            y.copy_from_slice(&ws.y_old);
            *eval = system.evaluate(y, &mut ws.g, None);
            return moved;
        }
        *eval = trial_eval;
        *residual = trial;
        *increment = step;
        report.residuals.push(trial);
        report.increments.push(step);
        report.chord_steps += 1;
        moved = true;
    }
    moved
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `G(y) = A y + y^3 / 10 - b` (cubes by component) on three unknowns,
    /// with `A` symmetric positive definite; a revision swaps `b` for
    /// `b_revised`.
    struct Cubic {
        b: [f64; 3],
        b_revised: [f64; 3],
        revisions: usize,
        offered: usize,
    }

    const A: [[f64; 3]; 3] = [[4.0, 1.0, 0.0], [1.0, 3.0, 0.5], [0.0, 0.5, 2.0]];

    impl Cubic {
        fn residual(y: &[f64], b: &[f64; 3]) -> Vec<f64> {
            (0..3)
                .map(|i| (0..3).map(|j| A[i][j] * y[j]).sum::<f64>() + 0.1 * y[i].powi(3) - b[i])
                .collect()
        }
    }

    impl NewtonSystem for Cubic {
        fn evaluate(&mut self, y: &[f64], g: &mut [f64], h: Option<&mut [f64]>) -> Evaluation {
            g.copy_from_slice(&Self::residual(y, &self.b));
            if let Some(h) = h {
                // Dense, column by column.
                for j in 0..3 {
                    for i in 0..3 {
                        h[3 * j + i] = A[i][j] + if i == j { 0.3 * y[i] * y[i] } else { 0.0 };
                    }
                }
            }
            Evaluation {
                scale: self.b.iter().map(|v| v.abs()).sum::<f64>() + 1.0,
                symmetric: true,
                merit: None,
                energy: None,
            }
        }

        fn revise(&mut self, _y: &[f64]) -> bool {
            self.offered += 1;
            if self.revisions == 0 {
                return false;
            }
            self.revisions -= 1;
            self.b = self.b_revised;
            true
        }
    }

    fn workspace() -> NewtonWorkspace {
        let col_ptr = [0, 3, 6, 9];
        let row_idx = [0, 1, 2, 0, 1, 2, 0, 1, 2];
        NewtonWorkspace::new(3, 9, LinearSolver::new(&col_ptr, &row_idx).unwrap())
    }

    /// A revision after the first Newton step: Newton goes on with the new
    /// system, to its root.
    #[test]
    fn a_revised_system_is_solved_from_where_newton_is() {
        let settings = NewtonSettings::default();
        for revisions in [0, 1] {
            let mut system = Cubic {
                b: [1.0, 2.0, 3.0],
                b_revised: [-2.0, 0.5, 1.0],
                revisions,
                offered: 0,
            };
            let mut y = [0.0; 3];
            let report = solve(&mut system, &mut y, 1.0, &settings, &mut workspace()).unwrap();
            let b = if revisions == 0 {
                [1.0, 2.0, 3.0]
            } else {
                [-2.0, 0.5, 1.0]
            };
            let g = Cubic::residual(&y, &b);
            assert!(g.iter().all(|v| v.abs() < 1e-10), "{revisions}: {g:?}");
            // Every Newton step (not the chord steps) was offered for
            // revision.
            assert_eq!(system.offered, report.iterations);
            // The revision's own evaluation is among the residuals.
            assert_eq!(
                report.residuals.len(),
                1 + report.iterations + report.chord_steps + revisions
            );
        }
    }

    /// `E(y) = sum_i sqrt(1 + y_i^2)`: convex, but far from its minimum
    /// a full Newton step (`dy = -y (1 + y^2)`) lands ever further away.
    struct Hyperbola {
        with_energy: bool,
        energies: Vec<f64>,
    }

    impl NewtonSystem for Hyperbola {
        fn evaluate(&mut self, y: &[f64], g: &mut [f64], h: Option<&mut [f64]>) -> Evaluation {
            for i in 0..3 {
                g[i] = y[i] / (1.0 + y[i] * y[i]).sqrt();
            }
            if let Some(h) = h {
                h.fill(0.0);
                for i in 0..3 {
                    h[4 * i] = (1.0 + y[i] * y[i]).powf(-1.5);
                }
            }
            let energy: f64 = y.iter().map(|v| (1.0 + v * v).sqrt()).sum();
            self.energies.push(energy);
            Evaluation {
                scale: 1.0,
                symmetric: true,
                merit: None,
                energy: self.with_energy.then_some(energy),
            }
        }
    }

    /// Armijo on the energy finds the minimum from where the residual's
    /// line search (at most four halvings, then the step is taken) is
    /// thrown ever further out: the energy of the accepted iterates only
    /// falls, and the last steps contract quadratically.
    #[test]
    fn the_energy_line_search_converges_where_full_steps_diverge() {
        let settings = NewtonSettings {
            chord_steps: 0,
            ..NewtonSettings::default()
        };
        let start = [20.0, -15.0, 8.0];
        let mut plain = Hyperbola {
            with_energy: false,
            energies: Vec::new(),
        };
        let mut y = start;
        assert!(solve(&mut plain, &mut y, 1.0, &settings, &mut workspace()).is_err());
        let mut system = Hyperbola {
            with_energy: true,
            energies: Vec::new(),
        };
        let mut y = start;
        let report = solve(&mut system, &mut y, 1.0, &settings, &mut workspace()).unwrap();
        assert!(y.iter().all(|v| v.abs() < 1e-10), "{y:?}");
        // Quadratic at the end: each residual about the square of the one
        // before (|G| ~ |y| near 0, where the step is y^3).
        let r = &report.residuals;
        let n = r.len();
        assert!(r[n - 1] <= 10.0 * r[n - 2].powi(2) + 1e-300, "{r:?}");
    }

    /// `ws.descent` after a solve cut at its iterations: the energy at the
    /// first guess and at the last iterate, the second below the first
    /// (the energy's line search only goes downhill); none for a system
    /// without an energy.
    #[test]
    fn a_solve_cut_short_says_whether_it_went_downhill() {
        let settings = NewtonSettings {
            chord_steps: 0,
            max_iterations: 3,
            ..NewtonSettings::default()
        };
        let start: [f64; 3] = [20.0, -15.0, 8.0];
        let first: f64 = start.iter().map(|v| (1.0 + v * v).sqrt()).sum();
        for with_energy in [true, false] {
            let mut system = Hyperbola {
                with_energy,
                energies: Vec::new(),
            };
            let (mut y, mut ws) = (start, workspace());
            let e = solve(&mut system, &mut y, 1.0, &settings, &mut ws).unwrap_err();
            assert!(
                matches!(e, NewtonError::NotConverged { iterations: 3, .. }),
                "{e}"
            );
            if with_energy {
                let (e0, e1) = ws.descent.expect("an energy throughout");
                let last: f64 = y.iter().map(|v| (1.0 + v * v).sqrt()).sum();
                assert_eq!((e0, e1), (first, last));
                assert!(e1 < e0, "{e0} {e1}");
            } else {
                assert_eq!(ws.descent, None);
            }
        }
    }

    /// `E(y) = sum_i (y_i^2 - 1)^2 / 4`, a double well in each component:
    /// between the wells (`|y_i| < 1 / sqrt 3`) its Hessian `3 y_i^2 - 1`
    /// is negative, and the Newton direction points uphill, to the
    /// maximum at 0.
    struct DoubleWell {
        energies: Vec<f64>,
    }

    impl NewtonSystem for DoubleWell {
        fn evaluate(&mut self, y: &[f64], g: &mut [f64], h: Option<&mut [f64]>) -> Evaluation {
            for i in 0..3 {
                g[i] = y[i] * (y[i] * y[i] - 1.0);
            }
            if let Some(h) = h {
                h.fill(0.0);
                for i in 0..3 {
                    h[4 * i] = 3.0 * y[i] * y[i] - 1.0;
                }
            }
            let energy: f64 = y.iter().map(|v| 0.25 * (v * v - 1.0).powi(2)).sum();
            self.energies.push(energy);
            Evaluation {
                scale: 1.0,
                symmetric: true,
                merit: None,
                energy: Some(energy),
            }
        }
    }

    /// From between the wells, where the Hessian is negative definite,
    /// the shifted Hessian gives a descent direction: Newton ends in a
    /// minimum (every |y_i| = 1), not at the maximum it would run to, the
    /// energy of its iterates only falls, and it still ends quadratically.
    #[test]
    fn an_indefinite_hessian_is_shifted_into_a_descent_direction() {
        let settings = NewtonSettings {
            chord_steps: 0,
            projection: Projection::Never,
            ..NewtonSettings::default()
        };
        let mut system = DoubleWell {
            energies: Vec::new(),
        };
        let mut y = [0.3, -0.2, 0.4];
        let report = solve(&mut system, &mut y, 1.0, &settings, &mut workspace()).unwrap();
        assert!(report.shifts > 0);
        assert!(y.iter().all(|v| (v.abs() - 1.0).abs() < 1e-10), "{y:?}");
        // Energies of the accepted iterates (the trial points of the line
        // search are among the evaluations; the accepted ones fall).
        let e = &system.energies;
        assert!(e.last().unwrap() < &1e-15 && e[0] > 0.5, "{e:?}");
        let r = &report.residuals;
        let n = r.len();
        assert!(r[n - 1] <= 10.0 * r[n - 2].powi(2) + 1e-300, "{r:?}");
    }

    /// `E(y) = sum_i (y_i^2 - 1)^2 / 4 + 0.05 (y_0 - y_1)^2 + c/2 |y - y_p|^2`
    /// on one node: a double well in each component, coupled, plus an
    /// inertia-like convex term (`c = 0.5`, never projected, as the mass).
    /// Near `y = 0` the well's Hessian `3 y_i^2 - 1` is negative: the sum
    /// is indefinite, and its stationary point near 0 a maximum. The well
    /// is the node's one stencil, projected when the node is flagged.
    struct Wells {
        with_energy: bool,
        project: bool,
        predictor: [f64; 3],
    }

    const INERTIA: f64 = 0.5;

    impl Wells {
        fn well_hessian(y: &[f64]) -> [f64; 9] {
            let mut k = [0.0; 9];
            for i in 0..3 {
                k[4 * i] = 3.0 * y[i] * y[i] - 1.0;
            }
            k[0] += 0.1;
            k[4] += 0.1;
            k[1] -= 0.1;
            k[3] -= 0.1;
            k
        }
    }

    impl NewtonSystem for Wells {
        fn evaluate(&mut self, y: &[f64], g: &mut [f64], h: Option<&mut [f64]>) -> Evaluation {
            let mut energy = 0.05 * (y[0] - y[1]).powi(2);
            for i in 0..3 {
                let d = y[i] - self.predictor[i];
                energy += 0.25 * (y[i] * y[i] - 1.0).powi(2) + 0.5 * INERTIA * d * d;
                g[i] = (y[i] * y[i] - 1.0) * y[i] + INERTIA * d;
            }
            g[0] += 0.1 * (y[0] - y[1]);
            g[1] -= 0.1 * (y[0] - y[1]);
            if let Some(h) = h {
                let mut k = Self::well_hessian(y);
                if self.project {
                    crate::psd::Projector::new().project(&mut k, 3, 3);
                }
                for i in 0..3 {
                    k[4 * i] += INERTIA;
                }
                h.copy_from_slice(&k);
            }
            Evaluation {
                scale: 1.0,
                symmetric: true,
                merit: None,
                energy: self.with_energy.then_some(energy),
            }
        }

        fn project(&mut self, nodes: Option<&[bool]>) {
            self.project = nodes.is_some_and(|n| n[0]);
        }
    }

    /// Whether the exact Hessian at `y` is positive definite (a strict
    /// minimum where the gradient vanishes).
    fn at_a_minimum(y: &[f64]) -> bool {
        let mut k = Wells::well_hessian(y);
        for i in 0..3 {
            k[4 * i] += INERTIA;
        }
        let a = faer::Mat::from_fn(3, 3, |i, j| k[3 * i + j]);
        let eig: Vec<f64> = a.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
        eig.iter().all(|&l| l > 0.0)
    }

    /// From next to the maximum of a non-convex potential, the projected
    /// Newton (progressive and always) ends at a minimum — zero gradient
    /// and a positive definite exact Hessian — with an energy below the
    /// start's, and the progressive one ends quadratically (the exact
    /// Hessian, definite there, is used again). Plain Newton on the same
    /// residual, with no energy to judge it by, converges to the maximum:
    /// the test tells the two apart.
    #[test]
    fn projected_newton_reaches_a_minimum_not_a_maximum() {
        let start = [0.05, -0.02, 0.1];
        let energy_at = |y: &[f64]| {
            let mut s = Wells {
                with_energy: true,
                project: false,
                predictor: start,
            };
            let mut g = [0.0; 3];
            s.evaluate(y, &mut g, None).energy.unwrap()
        };
        for projection in [Projection::Progressive, Projection::Always] {
            let settings = NewtonSettings {
                chord_steps: 0,
                projection,
                ..NewtonSettings::default()
            };
            let mut system = Wells {
                with_energy: true,
                project: false,
                predictor: start,
            };
            let mut y = start;
            let report = solve(&mut system, &mut y, 1.0, &settings, &mut workspace()).unwrap();
            let mut g = [0.0; 3];
            system.evaluate(&y, &mut g, None);
            assert!(g.iter().all(|v| v.abs() < 1e-9), "{projection:?}: {g:?}");
            assert!(at_a_minimum(&y), "{projection:?}: {y:?} is no minimum");
            assert!(energy_at(&y) < energy_at(&start));
            assert!(report.projections > 0 || projection == Projection::Always);
            assert_eq!(report.shifts, 0, "{projection:?}: no diagonal shift");
            if projection == Projection::Progressive {
                let r = &report.residuals;
                let n = r.len();
                assert!(r[n - 1] <= 10.0 * r[n - 2].powi(2) + 1e-300, "{r:?}");
            }
        }
        let mut plain = Wells {
            with_energy: false,
            project: false,
            predictor: start,
        };
        let mut y = start;
        let settings = NewtonSettings {
            chord_steps: 0,
            ..NewtonSettings::default()
        };
        solve(&mut plain, &mut y, 1.0, &settings, &mut workspace()).unwrap();
        assert!(!at_a_minimum(&y), "plain Newton found the maximum: {y:?}");
    }

    /// `E(y) = sum_i (y_i - 2)^2 / 2 - kappa ln(1 - y_i)` for every `y_i < 1`,
    /// infinite beyond (a barrier at 1); `G` beyond it is the quadratic's
    /// alone, a smaller residual than inside (so that only the energy can
    /// tell the trial is not admissible). With `limit`, `max_step` keeps
    /// the step to `limit` of the way to the barrier. Records every point
    /// evaluated.
    struct Barrier {
        kappa: f64,
        limit: Option<f64>,
        seen: Vec<[f64; 3]>,
    }

    impl NewtonSystem for Barrier {
        fn evaluate(&mut self, y: &[f64], g: &mut [f64], h: Option<&mut [f64]>) -> Evaluation {
            self.seen.push([y[0], y[1], y[2]]);
            let inside = y.iter().all(|&v| v < 1.0);
            let mut energy = 0.0;
            for i in 0..3 {
                let gap = 1.0 - y[i];
                g[i] = y[i] - 2.0 + if inside { self.kappa / gap } else { 0.0 };
                energy += 0.5 * (y[i] - 2.0).powi(2) - self.kappa * gap.ln();
            }
            if let Some(h) = h {
                h.fill(0.0);
                for i in 0..3 {
                    h[4 * i] = 1.0 + self.kappa / (1.0 - y[i]).powi(2);
                }
            }
            Evaluation {
                scale: 1.0,
                symmetric: true,
                merit: None,
                energy: Some(if inside { energy } else { f64::INFINITY }),
            }
        }

        fn max_step(&self, y: &[f64], dy: &[f64]) -> f64 {
            let Some(limit) = self.limit else {
                return 1.0;
            };
            (0..3)
                .filter(|&i| dy[i] > 0.0)
                .map(|i| limit * (1.0 - y[i]) / dy[i])
                .fold(1.0, f64::min)
        }
    }

    /// The minimum inside the barrier, `y = (3 - sqrt(1 + 4 kappa)) / 2`.
    fn barrier_minimum(kappa: f64) -> f64 {
        0.5 * (3.0 - (1.0 + 4.0 * kappa).sqrt())
    }

    /// Issue 33's seam: the first Newton step from 0 jumps past the
    /// barrier (to 1.73), where the energy is infinite though the residual
    /// is smaller. Without a limit the line search rejects that trial and
    /// halves into the admissible region; with the system's `max_step`
    /// (half the way to the barrier) no point beyond it is ever evaluated.
    /// Both end at the minimum inside, quadratically.
    #[test]
    fn the_line_search_rejects_infinite_energy_and_starts_below_max_step() {
        let settings = NewtonSettings {
            chord_steps: 0,
            projection: Projection::Never,
            ..NewtonSettings::default()
        };
        let exact = barrier_minimum(0.1);
        for limit in [None, Some(0.5)] {
            let mut system = Barrier {
                kappa: 0.1,
                limit,
                seen: Vec::new(),
            };
            let mut y = [0.0; 3];
            let report = solve(&mut system, &mut y, 1.0, &settings, &mut workspace()).unwrap();
            assert!(
                y.iter().all(|v| (v - exact).abs() < 1e-12),
                "{limit:?}: {y:?}"
            );
            let beyond = system.seen.iter().filter(|p| p[0] >= 1.0).count();
            if limit.is_some() {
                assert_eq!(beyond, 0, "{:?}", system.seen);
            } else {
                assert!(beyond > 0, "the full step was tried: {:?}", system.seen);
            }
            // Quadratic to round-off (1e-14: the residual's floor here).
            let r = &report.residuals;
            let n = r.len();
            assert!(r[n - 1] <= 10.0 * r[n - 2].powi(2) + 1e-14, "{r:?}");
            assert!(r[n - 2] <= 10.0 * r[n - 3].powi(2) + 1e-14, "{r:?}");
        }
    }

    /// A start a hair below the barrier with a stiff pull outwards: every
    /// trial down to 1/1024 of the Newton step lies beyond it. The step
    /// is an error (the time step is then cut back), not the shortest
    /// trial taken — which put the state inside the obstacle before.
    #[test]
    fn no_admissible_step_is_an_error() {
        let settings = NewtonSettings {
            projection: Projection::Never,
            ..NewtonSettings::default()
        };
        let mut system = Barrier {
            kappa: 1e-12,
            limit: None,
            seen: Vec::new(),
        };
        let mut y = [1.0 - 1e-7; 3];
        let e = solve(&mut system, &mut y, 1.0, &settings, &mut workspace()).unwrap_err();
        assert!(
            matches!(e, NewtonError::NoAdmissibleStep { iteration: 1, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("not finite"), "{e}");
        // A system that admits no step at all says so.
        let mut stuck = Barrier {
            kappa: 0.1,
            limit: Some(0.0),
            seen: Vec::new(),
        };
        let e = solve(&mut stuck, &mut [0.0; 3], 1.0, &settings, &mut workspace()).unwrap_err();
        assert!(e.to_string().contains("admits no step"), "{e}");
    }
}
