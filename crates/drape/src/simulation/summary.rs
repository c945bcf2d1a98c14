//! `summary.json`: what it holds ([`Summary`]), the figures of the state
//! it reports ([`Figures`], the history's last row), how it is made and
//! written, and the record of a run or a resume that failed before its
//! loop ([`record_failure`], [`record_refused_resume`]).

use super::{RunError, io_err, warnings};
use crate::integrator::State;
use crate::output::atomic::write_atomic;
use crate::setup::Setup;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// `"completed"`, `"failed"` or `"interrupted"`.
    pub status: String,
    /// Human-readable outcome; it says "at rest" when the rest criterion
    /// ended the run.
    pub message: String,
    /// Whether the rest criterion ended the run; absent without a rest
    /// criterion (`[time] rest`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at_rest: Option<bool>,
    /// Scenario title.
    pub title: String,
    /// Converged steps.
    pub steps: usize,
    /// Final simulated time (s), or load factor in statics.
    pub time: f64,
    /// Time of the first step that ended with an active contact, or null.
    pub first_contact_time: Option<f64>,
    /// Total Newton iterations of the converged steps (each step's
    /// iterations in `history.csv` summed).
    pub newton_iterations: usize,
    /// Newton iterations besides, of the solves whose result the run
    /// threw away: a step's attempts that failed before it was cut back,
    /// relaxed or refused, a pseudo-step repeated shorter. With
    /// `newton_iterations`, all the iterations the run did (a run resumed
    /// from a checkpoint older than this count: those since).
    pub newton_iterations_discarded: usize,
    /// Steps that had to be cut back.
    pub cutbacks: usize,
    /// Wall-clock time of the run (s).
    pub wall_seconds: f64,
    /// Of which: set-up before the first step (s) — linear-solver
    /// structures, the initial acceleration, the initial outputs (of this
    /// session, for a resumed run). `wall_seconds - setup_seconds` is the
    /// time of the steps.
    pub setup_seconds: f64,
    /// Of which: the run loop's output work after the set-up (s) — writing
    /// the history rows, handing the field frames to the thread that
    /// writes them, and waiting for that thread (when it falls behind,
    /// before a checkpoint and at the end).
    /// `wall_seconds - setup_seconds - output_seconds` is the time of the
    /// mechanics and the solvers.
    pub output_seconds: f64,
    /// The time the thread writing the field frames spent on them (s):
    /// element results, encoding, writing and syncing the VTU files and the
    /// collection, the initial frame's included. It runs alongside the
    /// steps and is not part of `wall_seconds`' breakdown; only the part
    /// the loop waits for shows in `output_seconds`.
    pub output_thread_seconds: f64,
    /// Of which: the first step of this session (s), without its outputs;
    /// it also builds what the linear solver keeps across steps (symbolic
    /// factorisations, the multigrid hierarchy).
    pub first_step_seconds: f64,
    /// Threads the run's parallel loops had (rayon's pool:
    /// `RAYON_NUM_THREADS`, else the CPUs). The results do not depend on
    /// it (every sum runs in an order the work fixes); it is recorded so
    /// that a run's times can be read, and a sweep's rows say what each
    /// case had.
    pub threads: usize,
    /// Nodes of the mesh.
    pub nodes: usize,
    /// Elements of the mesh.
    pub elements: usize,
    /// Degrees of freedom (3 per node).
    pub dofs: usize,
    /// Fixed components.
    pub fixed_dofs: usize,
    /// Final kinetic energy (J).
    pub kinetic_energy: f64,
    /// Final strain energy (J).
    pub strain_energy: f64,
    /// Work of the external loads (J).
    pub external_work: f64,
    /// Final position of each monitor.
    pub monitors: BTreeMap<String, [f64; 3]>,
    /// What the linear solver did over the whole run (a resumed session
    /// adds to the checkpoint's counts).
    pub linear: crate::solver::LinearStats,
    /// What the scenario may not do as it says ([`warnings`]); absent when
    /// there is nothing to warn about.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// The multilevel settle (`[refine]`): one entry per level finished,
    /// the coarse one first; absent without `[refine]`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub levels: Vec<LevelRecord>,
    /// Each `[[cavity]]`'s gas at the last state (the history's last
    /// `cavity<i>_...` values); absent without cavities.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub cavities: Vec<CavityRecord>,
}

/// A cavity's gas as `summary.json`'s `cavities` lists it.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct CavityRecord {
    /// Volume (m^3).
    pub volume: f64,
    /// Absolute pressure (Pa).
    pub pressure: f64,
    /// Gas mass (kg).
    pub mass: f64,
    /// Temperature (K).
    pub temperature: f64,
    /// Mass delivered by the inflator since the start (kg).
    pub inflow: f64,
    /// Mass let out by the vents since the start (kg).
    pub outflow: f64,
}

/// One level of a multilevel settle, as `summary.json`'s `levels` lists
/// it (SPEC §6.7: `elements`, `drape_coefficient`, `folds`).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct LevelRecord {
    /// Triangles of the level's mesh.
    pub elements: usize,
    /// Nodes of the level's mesh.
    pub nodes: usize,
    /// The drape coefficient of the level's last state, where the run
    /// has a pedestal (and the measurement succeeded).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drape_coefficient: Option<f64>,
    /// The folds counted on it, likewise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub folds: Option<usize>,
    /// Steps of the level (converged history rows).
    pub steps: usize,
    /// Newton iterations of the level.
    pub newton_iterations: usize,
    /// Wall time of the level (s), its refinement and measurement included.
    pub wall_seconds: f64,
    /// The level's last time (s): a finer level's static load factor
    /// counts from it.
    pub time: f64,
    /// Why the drape coefficient is absent, where it is.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// The figures of a state that a history row and the summary report.
#[derive(Debug, Clone, Default)]
pub(super) struct Figures {
    /// Time (s), or load factor in statics.
    pub(super) time: f64,
    /// Kinetic energy (J).
    pub(super) kinetic: f64,
    /// Strain energy (J).
    pub(super) strain: f64,
    /// Work of the external loads (J).
    pub(super) external_work: f64,
    /// Each monitor's position, in the scenario's order.
    pub(super) monitors: Vec<[f64; 3]>,
    /// Each cavity's gas.
    pub(super) cavities: Vec<CavityRecord>,
}

impl Figures {
    /// Sets the figures of `state`, whose kinetic and strain energies are
    /// `kinetic` and `strain`.
    pub(super) fn set(&mut self, setup: &Setup, state: &State, kinetic: f64, strain: f64) {
        self.time = state.time;
        self.kinetic = kinetic;
        self.strain = strain;
        self.external_work = state.external_work;
        self.monitors.clear();
        self.monitors.extend(setup.monitors.iter().map(|m| {
            let p = &state.positions[3 * m.node..3 * m.node + 3];
            [p[0], p[1], p[2]]
        }));
        self.cavities.clear();
        self.cavities.extend(state.gas.iter().map(|g| CavityRecord {
            volume: g.volume,
            pressure: g.pressure,
            mass: g.mass,
            temperature: g.temperature,
            inflow: g.inflow,
            outflow: g.outflow,
        }));
    }

    /// The figures of `state` (see [`Figures::set`]).
    pub(super) fn of(setup: &Setup, state: &State, kinetic: f64, strain: f64) -> Self {
        let mut figures = Self::default();
        figures.set(setup, state, kinetic, strain);
        figures
    }
}

/// Sets the status of the summary in `out` to `"failed"` with `message`,
/// its counts kept — a completed coarser level's summary included (a
/// finer level that could not be made: [`super::record_level_failure`]).
pub(super) fn mark_failed(out: &Path, message: &str) -> std::io::Result<()> {
    let path = out.join("summary.json");
    let mut value = std::fs::read(&path)
        .ok()
        .and_then(|bytes| serde_json::from_slice::<serde_json::Value>(&bytes).ok())
        .filter(serde_json::Value::is_object)
        .unwrap_or_else(|| serde_json::json!({}));
    value["status"] = "failed".into();
    value["message"] = message.into();
    let text = serde_json::to_string_pretty(&value).unwrap_or_default();
    write_atomic(&path, text.as_bytes())
}

/// Records in `out/summary.json` that a run or a resume failed before its
/// loop could (status `"failed"`, `message`): when `keep_previous` and the
/// directory holds a summary, that summary keeps its counts (those of the
/// session its history and checkpoint come from) and only its status and
/// message change — but a `"completed"` one is left alone: the outputs
/// beside it are still that run's; otherwise the summary of `setup`'s
/// initial state (0 steps), or, without a setup, a summary of the status
/// and the message alone.
///
/// # Errors
/// The summary could not be written.
pub(super) fn record_failure(
    out: &Path,
    setup: Option<&Setup>,
    keep_previous: bool,
    message: &str,
) -> std::io::Result<()> {
    let path = out.join("summary.json");
    let previous = keep_previous
        .then(|| std::fs::read(&path).ok())
        .flatten()
        .and_then(|bytes| serde_json::from_slice::<serde_json::Value>(&bytes).ok())
        .filter(serde_json::Value::is_object);
    let json = match (previous, setup) {
        (Some(value), _) if value["status"] == "completed" => return Ok(()),
        (Some(mut value), _) => {
            value["status"] = "failed".into();
            value["message"] = message.into();
            value
        }
        (None, Some(setup)) => {
            let s = initial_summary(setup, message.to_owned(), Instant::now());
            serde_json::to_value(&s).unwrap_or_default()
        }
        (None, None) => serde_json::json!({ "status": "failed", "message": message }),
    };
    let text = serde_json::to_string_pretty(&json).unwrap_or_default();
    write_atomic(&path, text.as_bytes())
}

/// Records in `out/summary.json` that a resume was refused — after it took
/// the directory's lock, before its loop — for `why` (a changed or
/// missing input file, a checkpoint it cannot use, a scenario that no
/// longer reads): status `"failed"`, message `"cannot resume: {why}"`, the
/// counts of the session the history and checkpoint come from kept (see
/// [`record_failure`]; a `"completed"` run's summary is left alone).
/// Returns the message. Both front ends record their refusals with it,
/// through [`Session::refuse`](super::Session::refuse), so that they say
/// the same.
///
/// # Errors
/// The summary could not be written.
pub(super) fn record_refused_resume(
    out: &Path,
    why: &dyn std::fmt::Display,
) -> std::io::Result<String> {
    let message = format!("cannot resume: {why}");
    record_failure(out, None, true, &message).map(|()| message)
}

/// The summary of a run after `steps` steps whose last state has
/// `figures`; failed when there is a `failure` message.
pub(super) fn summary(
    setup: &Setup,
    figures: &Figures,
    failure: Option<String>,
    steps: usize,
    iterations: usize,
    cutbacks: usize,
    start: Instant,
) -> Summary {
    let model = &setup.model;
    Summary {
        status: if failure.is_some() {
            "failed"
        } else {
            "completed"
        }
        .into(),
        message: failure.unwrap_or_else(|| {
            let noun = if steps == 1 { "step" } else { "steps" };
            format!("completed {steps} {noun} to t = {:.6} s", figures.time)
        }),
        at_rest: setup.rest.map(|_| false),
        title: setup.title.clone(),
        steps,
        time: figures.time,
        first_contact_time: None,
        newton_iterations: iterations,
        newton_iterations_discarded: 0,
        cutbacks,
        wall_seconds: start.elapsed().as_secs_f64(),
        setup_seconds: 0.0,
        output_seconds: 0.0,
        output_thread_seconds: 0.0,
        first_step_seconds: 0.0,
        threads: rayon::current_num_threads(),
        nodes: model.mesh().node_count(),
        elements: model.mesh().element_count(),
        dofs: model.dofs(),
        fixed_dofs: model.fixed_count(),
        kinetic_energy: figures.kinetic,
        strain_energy: figures.strain,
        external_work: figures.external_work,
        monitors: (setup.monitors.iter())
            .zip(&figures.monitors)
            .map(|(m, p)| (m.name.clone(), *p))
            .collect(),
        linear: Default::default(),
        warnings: warnings(setup),
        levels: Vec::new(),
        cavities: figures.cavities.clone(),
    }
}

/// The figures of the initial state, at rest and unstrained: the
/// summary of a run that could not start.
fn initial_figures(setup: &Setup) -> Figures {
    let state = State::at_rest(&setup.model, setup.model.initial_positions());
    Figures::of(setup, &state, 0.0, 0.0)
}

/// Writes `summary` to `out/summary.json` (atomically).
pub(super) fn write_summary(out: &Path, summary: &Summary) -> Result<(), RunError> {
    let path = out.join("summary.json");
    let json = serde_json::to_string_pretty(summary).unwrap_or_default();
    write_atomic(&path, json.as_bytes()).map_err(io_err(&path))
}

/// The failed summary of a run that could not start: the initial state's
/// figures, 0 steps, and `message`.
pub(super) fn initial_summary(setup: &Setup, message: String, start: Instant) -> Summary {
    summary(
        setup,
        &initial_figures(setup),
        Some(message),
        0,
        0,
        0,
        start,
    )
}
