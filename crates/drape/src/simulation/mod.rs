//! The run loop: steps through the schedule with cut-back, writes the
//! history, the field frames and the summary (the README's command line and outputs).
//!
//! A step whose Newton iteration fails (no convergence, divergence, NaN,
//! singular Hessian) is retried as two steps of half the size, recursively
//! up to `max_cutbacks` halvings; the next scheduled step takes the
//! original size again. When even the smallest step fails, the run stops:
//! the last converged state is written as a field frame, the history holds
//! every converged step, and `summary.json` says `"failed"` and why.
//!
//! With `[time] adaptive = true` the steps are sized by a controller
//! instead (`schedule.rs`, [`schedule::StepController`]): they grow after
//! easy steps and shrink after hard ones, end every segment at its end
//! time, and a failing step is halved and retried, the controller going on
//! from the smaller size. With `[time] rest` the run ends, completed, once
//! every node has been slower than the rest speed for
//! [`schedule::REST_STEPS`] consecutive steps ([`schedule::RestWatch`]).
//!
//! The history rows are written and flushed by the loop itself, one per
//! step. The field frames are handed to a writer thread (`frames.rs`)
//! that writes them in order while the loop goes on; the loop waits for it
//! before a checkpoint (which records the frames as written) and before
//! the summary, so that whatever a run ends with, everything it computed
//! is on disk when `summary.json` says so.

use crate::contact::ContactReport;
use std::sync::atomic::{AtomicBool, Ordering};

mod checkpoint;
mod frames;
pub mod schedule;
mod session;
mod start;
mod summary;
mod warnings;
use crate::integrator::newmark::{DynamicWorkspace, FrictionShortfall, StepOutcome};
use crate::integrator::{State, StaticStepper, StepEnergies};
use crate::model::Model;
use crate::output::atomic::write_atomic;
use crate::output::history::HistoryWriter;
use crate::setup::{Analysis, Setup};
use crate::solver::{LinearMode, NewtonError};
pub use checkpoint::{Checkpoint, CheckpointError, Counters, Levels};
use frames::Snapshot;
use schedule::{RestWatch, StepController, fastest_node};
pub use session::{Explained, Front, Session};
use start::Start;
pub use start::{ResumeError, SetupError, check_resume_inputs};
use std::path::{Path, PathBuf};
use std::time::Instant;
use summary::record_failure;
use summary::{Figures, initial_summary, summary, write_summary};
pub use summary::{LevelRecord, Summary};
pub use warnings::{MAX_MOTION_PER_STEP, warnings};

/// What the observer hears after each converged step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepInfo {
    /// Converged steps so far.
    pub step: usize,
    /// Time (s) or load factor (static).
    pub time: f64,
    /// End time of the schedule (s), or 1 in statics.
    pub end_time: f64,
    /// Scheduled steps completed, counting this one (cut-back sub-steps
    /// belong to their scheduled step); 0 with adaptive steps, whose
    /// progress is `time / end_time`.
    pub scheduled_done: usize,
    /// Scheduled steps in all; 0 with adaptive steps.
    pub scheduled_total: usize,
    /// Size of this step.
    pub dt: f64,
    /// Newton iterations of this step.
    pub iterations: usize,
    /// Halvings needed for this step (0 if none).
    pub cutbacks: usize,
    /// Kinetic energy (J).
    pub kinetic_energy: f64,
    /// Strain energy (J).
    pub strain_energy: f64,
    /// Work of the external loads since the start (J).
    pub external_work: f64,
}

/// A run that stopped early; everything up to the last converged step is on disk.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// Output files could not be written.
    #[error("cannot write {path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        error: std::io::Error,
    },
    /// A step failed even at the smallest step size.
    #[error(
        "{} after {cutbacks} cut-backs: {cause}{hint}. The last converged state is in {out}", which_step(*.step, *.time, *.dt, *.statics)
    )]
    Step {
        /// Converged steps before the failure.
        step: usize,
        /// Time of the last converged state (s), or its load factor.
        time: f64,
        /// Smallest step size tried (s), or load increment.
        dt: f64,
        /// Whether the step was a static analysis's load increment.
        statics: bool,
        /// Halvings tried.
        cutbacks: usize,
        /// Newton's error.
        cause: NewtonError,
        /// Advice, if any (starts with "; ").
        hint: String,
        /// Output directory.
        out: PathBuf,
    },
    /// Saint-Venant–Kirchhoff driven past its stability limit by a step
    /// that its cut-backs could not keep clear of it.
    #[error(
        "at t = {time:.6e} s element {element} is compressed to a stretch of {stretch:.4}, below 1/sqrt(3) = 0.5774 where Saint-Venant-Kirchhoff loses stability in compression; results past this point would be meaningless. {advice}. The last state is in {out}"
    )]
    MaterialInstability {
        /// Time (s).
        time: f64,
        /// Element index.
        element: usize,
        /// Smallest principal stretch.
        stretch: f64,
        /// What to change, from what the run has (without a full stop).
        advice: String,
        /// Output directory.
        out: PathBuf,
    },
    /// The run could not start (nothing was stepped).
    #[error("{0}")]
    Setup(SetupError),
    /// Stopped on request (Ctrl-C, SIGTERM) after a step; a checkpoint was written.
    #[error("{message}")]
    Interrupted {
        /// What was done and how to resume.
        message: String,
    },
    /// The checkpoint, history or collection to resume from is unusable.
    #[error("cannot resume: {}", Explained { error, front: *front })]
    Resume {
        /// Why.
        error: ResumeError,
        /// Whose user reads it ([`RunControl::front`]).
        front: Front,
    },
    /// A finer level of the multilevel settle could not be made (the mesh
    /// refined, or the scenario built on it); the coarser levels' outputs
    /// stay.
    #[error("cannot make refinement level {level}: {reason}. The last level's state is in {out}")]
    Refine {
        /// The level (1: the first refinement).
        level: usize,
        /// Why.
        reason: String,
        /// Output directory.
        out: PathBuf,
    },
    /// The run failed, and `summary.json` could not say so either.
    #[error("{cause}; summary.json could not be written either: {error}")]
    Unrecorded {
        /// Why the run failed.
        cause: Box<RunError>,
        /// Why the summary could not be written.
        error: std::io::Error,
    },
}

/// The step that failed, in the words of its analysis: a dynamic step
/// by its time and size, a static increment by its load factors.
fn which_step(step: usize, time: f64, dt: f64, statics: bool) -> String {
    if statics {
        format!(
            "load increment {} from load factor {time:.6} failed at an increment of {dt:.3e} (to load factor {:.6})",
            step + 1,
            time + dt
        )
    } else {
        format!(
            "step {} from t = {time:.6e} s failed at dt = {dt:.3e} s",
            step + 1
        )
    }
}

impl RunError {
    /// `self`, an output error met after the run had already failed with
    /// `first`, with `first` said in its message.
    fn after(self, first: &RunError) -> RunError {
        match self {
            RunError::Io { path, error } => RunError::Io {
                path,
                error: std::io::Error::new(
                    error.kind(),
                    format!("{error} (the run had stopped before: {first})"),
                ),
            },
            e => e,
        }
    }

    /// The failure itself, past an [`RunError::Unrecorded`] wrapper.
    pub fn cause(&self) -> &RunError {
        match self {
            RunError::Unrecorded { cause, .. } => cause.cause(),
            e => e,
        }
    }
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |error| RunError::Io {
        path: path.to_path_buf(),
        error,
    }
}

/// One converged step, as recorded in the history.
struct StepRecord {
    step: usize,
    dt: f64,
    iterations: usize,
    /// The strain energy by part (and the step's friction, unused here:
    /// the state sums it).
    energies: StepEnergies,
    cutbacks: usize,
    min_stretch: f64,
    contact: Option<ContactReport>,
    /// Fractions of taut, wrinkled and slack elements.
    states: [f64; 3],
}

/// The history's rows, written by the run loop.
struct History<'a> {
    setup: &'a Setup,
    writer: HistoryWriter,
    scratch: Vec<f64>,
    /// The figures of the history's last row on disk — this session's
    /// last, or the checkpoint's of a resumed session that has written
    /// none: what the summary reports, so that it describes the history
    /// even when the next row could not be written.
    last: Figures,
}

/// The history's column names, in order.
pub fn history_columns(setup: &Setup) -> Vec<String> {
    let mut columns: Vec<String> = [
        "step",
        "time",
        "dt",
        "iterations",
        "kinetic_energy",
        "strain_energy",
        "active_contacts",
        "contact_force",
        "min_gap",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for m in &setup.monitors {
        for c in ["x", "y", "z"] {
            columns.push(format!("{}_{c}", m.name));
        }
    }
    columns.extend(
        [
            "external_work",
            "contact_energy",
            "total_energy",
            "min_stretch",
            "cutbacks",
            "taut_fraction",
            "wrinkled_fraction",
            "slack_fraction",
            "membrane_energy",
            "bending_energy",
            "friction_dissipation",
            "elements",
        ]
        .map(String::from),
    );
    for i in 0..setup.model.cavities().len() {
        for c in CAVITY_COLUMNS {
            columns.push(format!("cavity{i}_{c}"));
        }
    }
    columns
}

/// Each cavity's columns (`cavity<i>_...`, SPEC §6.7; `inflow` and
/// `outflow`: the gas mass the inflator has delivered and the vents have
/// let out since the start, kg).
pub const CAVITY_COLUMNS: [&str; 6] = [
    "volume",
    "pressure",
    "mass",
    "temperature",
    "inflow",
    "outflow",
];

impl History<'_> {
    /// Appends and flushes the row of `state` after `r`; returns the
    /// kinetic energy.
    fn row(&mut self, state: &State, r: &StepRecord) -> Result<f64, RunError> {
        let model = &self.setup.model;
        let kinetic = model.kinetic_energy(&state.velocities, &mut self.scratch);
        let (active, force, min_gap, contact_energy) = match &r.contact {
            Some(c) => (
                c.active as f64,
                crate::vec3::norm(c.resultant),
                c.min_gap,
                c.energy,
            ),
            None => (0.0, 0.0, f64::NAN, 0.0),
        };
        let strain = r.energies.strain();
        let contact_energy = contact_energy + r.energies.self_contact + r.energies.features;
        let mut row = vec![
            r.step as f64,
            state.time,
            r.dt,
            r.iterations as f64,
            kinetic,
            strain,
            active,
            force,
            min_gap,
        ];
        for m in &self.setup.monitors {
            row.extend_from_slice(&state.positions[3 * m.node..3 * m.node + 3]);
        }
        row.extend_from_slice(&[
            state.external_work,
            contact_energy,
            kinetic + strain + contact_energy - state.external_work,
            r.min_stretch,
            r.cutbacks as f64,
            r.states[0],
            r.states[1],
            r.states[2],
            r.energies.membrane,
            r.energies.bending,
            state.friction_dissipation,
            model.mesh().element_count() as f64,
        ]);
        for g in &state.gas {
            row.extend_from_slice(&[
                g.volume,
                g.pressure,
                g.mass,
                g.temperature,
                g.inflow,
                g.outflow,
            ]);
        }
        let path = self.writer.path().to_path_buf();
        self.writer.write_row(&row).map_err(io_err(&path))?;
        self.last.set(self.setup, state, kinetic, strain);
        Ok(kinetic)
    }
}

/// How a run is controlled from outside.
#[derive(Debug, Default, Clone, Copy)]
pub struct RunControl<'a> {
    /// Set (e.g. by a signal handler) to stop after the current step: a
    /// checkpoint and the summary (`"interrupted"`) are written.
    pub stop: Option<&'a AtomicBool>,
    /// Continue from the checkpoint in the output directory.
    pub resume: bool,
    /// The front end whose user reads the messages.
    pub front: Front,
    /// Where the run counts the step in progress for the front end to
    /// read ([`crate::progress`]); none: nothing counted.
    pub progress: Option<&'a std::sync::Arc<crate::progress::StepProgress>>,
}

/// The checkpoint file in an output directory.
pub fn checkpoint_path(out: &Path) -> PathBuf {
    out.join("checkpoint.bin")
}

/// Runs a scenario into `out`, calling `observer` after each converged
/// step. Writes `summary.json` in every case; returns it on success.
pub fn run(
    setup: &Setup,
    out: &Path,
    observer: &mut dyn FnMut(&StepInfo),
) -> Result<Summary, RunError> {
    run_with(setup, out, observer, RunControl::default())
}

/// [`run`] with external control: interruption and resumption.
///
/// A resumed run continues from `out/checkpoint.bin` ([`Checkpoint::read`]:
/// the same scenario text and input files, every value sound and within
/// the schedule; the frames it lists on disk): the history is cut
/// back to the checkpoint's rows, the ParaView collection to its frames,
/// and the run goes on exactly as the uninterrupted run would have — the
/// same history and final state to the last bit (assembly and solvers are
/// deterministic: parallel sums use fixed chunks, summed in order).
pub fn run_with(
    setup: &Setup,
    out: &Path,
    observer: &mut dyn FnMut(&StepInfo),
    control: RunControl,
) -> Result<Summary, RunError> {
    run_level(
        setup,
        out,
        observer,
        control,
        None,
        (&Levels::default(), false),
    )
    .map(|f| f.summary)
}

/// A finer level's start in a multilevel settle (`crate::levels`): the
/// state carried onto the level's mesh, and what the run has done so far.
#[derive(Debug, Clone)]
pub struct LevelStart {
    /// The state on the level's mesh, at rest, its time the coarser
    /// level's end (the static level's `from`).
    pub state: State,
    /// The run's counters so far; the level's schedule starts afresh.
    pub counters: Counters,
    /// The frames written so far, `(time, step)`.
    pub written: Vec<(f64, usize)>,
}

/// How a session ended well: its summary, and where a next level starts
/// from.
#[derive(Debug)]
pub struct Finished {
    /// The summary written.
    pub summary: Summary,
    /// The last state.
    pub state: State,
    /// The counters at the end.
    pub counters: Counters,
    /// The frames written, `(time, step)`.
    pub written: Vec<(f64, usize)>,
}

/// One session of a run: [`run_with`]'s, or — `level` given — a finer
/// level of a multilevel settle, which goes on writing the history and
/// the collection where the coarser level left them. `levels` is the
/// multilevel record so far, which the checkpoints keep and the summary
/// lists. With `multilevel`, a session that ends as scheduled (or at
/// rest) writes no summary: the caller decides whether the run goes on
/// to a finer level, and writes the run's summary once it ends
/// ([`rewrite_summary`]), so that `summary.json` never says
/// `"completed"` of a run still refining (a run killed on a finer level
/// would otherwise look finished). A session that fails or is
/// interrupted writes its summary as ever; a finer level starts with a
/// checkpoint (with `checkpoint_every` 0 too), so that a kill loses at
/// most that level's work.
pub fn run_level(
    setup: &Setup,
    out: &Path,
    observer: &mut dyn FnMut(&StepInfo),
    control: RunControl,
    level: Option<LevelStart>,
    (levels, multilevel): (&Levels, bool),
) -> Result<Finished, RunError> {
    let mut recorded = false;
    let leveled = level.is_some();
    match run_session(
        setup,
        out,
        observer,
        control,
        (level, levels, multilevel),
        &mut recorded,
    ) {
        // The loop's own ends (a failed step, an I/O error while stepping,
        // an interruption) and a set-up that failed wrote their summary.
        Ok(finished) => Ok(finished),
        Err(e @ (RunError::Resume { .. } | RunError::Io { .. })) if !recorded => {
            // A refused resume keeps the counts of the session before it
            // (its history and checkpoint are left as they were), as does
            // a finer level that could not start; a fresh run that could
            // not start records its initial state.
            let previous = (control.resume || leveled).then_some(());
            let message = e.to_string();
            match record_failure(out, Some(setup), previous.is_some(), &message) {
                Ok(()) => Err(e),
                Err(error) => Err(RunError::Unrecorded {
                    cause: Box::new(e),
                    error,
                }),
            }
        }
        Err(e) => Err(e),
    }
}

/// [`run_with`] but for the summary of a failure before the loop;
/// `recorded` is set once the loop has ended (and written its summary).
fn run_session(
    setup: &Setup,
    out: &Path,
    observer: &mut dyn FnMut(&StepInfo),
    control: RunControl,
    (level, levels, multilevel): (Option<LevelStart>, &Levels, bool),
    recorded: &mut bool,
) -> Result<Finished, RunError> {
    let start = Instant::now();
    let model = &setup.model;
    std::fs::create_dir_all(out.join("fields")).map_err(io_err(out))?;
    let mut ws = DynamicWorkspace::with_mode(model, setup.linear)
        .map_err(|e| setup_failure(setup, out, start, SetupError::LinearSolver(e)))?;
    let x = model.initial_positions();
    let length = reference_length(&x);
    let (schedule, end_time) = (setup.analysis.schedule(), setup.analysis.end_time());
    let leveled = level.is_some();
    let Start {
        state,
        counters,
        controller,
        history,
        pvd,
        written,
        initial_frame,
        pending,
    } = if let Some(level) = level {
        start::level(setup, out, &mut ws, level)?
    } else if control.resume {
        start::resume(setup, out, &mut ws, control.front)?
    } else {
        start::fresh(setup, out, &mut ws, &x, start)?
    };
    let rest = setup
        .rest
        .map(|criterion| RestWatch::new(criterion, counters.still_steps));
    // A stop asked for inside a step reaches Newton through its interrupt,
    // which a watcher sets from the run's stop flag (issue 46: a step that
    // never ends held a Ctrl-C back for ever).
    // A stop asked for before the loop starts reaches the first step.
    let asked = control.stop.is_some_and(|s| s.load(Ordering::SeqCst));
    let interrupt = std::sync::Arc::new(AtomicBool::new(asked));
    let watching = AtomicBool::new(control.stop.is_some());
    if control.stop.is_some() {
        ws.newton.interrupt = Some(interrupt.clone());
    }
    ws.newton.progress = control.progress.cloned();
    // The frames' thread borrows the model and the output directory; the
    // scope ends only when it has written every frame handed to it.
    std::thread::scope(|scope| {
        let _unwatch = Unwatch(&watching);
        if let Some(stop) = control.stop {
            let (watching, interrupt) = (&watching, &interrupt);
            scope.spawn(move || {
                while watching.load(Ordering::SeqCst) {
                    if stop.load(Ordering::SeqCst) {
                        interrupt.store(true, Ordering::SeqCst);
                        return;
                    }
                    std::thread::sleep(WATCH_INTERVAL);
                }
            });
        }
        let mut frame_writer = match frames::spawn(scope, model, out, pvd) {
            Ok(w) => w,
            Err(e) => return Err(setup_failure(setup, out, start, SetupError::FrameThread(e))),
        };
        if let Some(snapshot) = initial_frame {
            frame_writer.submit(snapshot)?;
        }
        let mut run = Stepper {
            setup,
            out,
            start,
            setup_seconds: start.elapsed().as_secs_f64(),
            length,
            end_time,
            scheduled_total: if controller.is_some() {
                0
            } else {
                schedule.iter().map(|(n, _)| n).sum()
            },
            stop: control.stop,
            ws: &mut ws,
            last_contact: contact_report(model, &state),
            state,
            counters,
            history,
            frame_writer,
            written,
            output_seconds: 0.0,
            first_step_seconds: None,
            rest,
            observer,
            levels,
            pending,
            multilevel,
        };
        // A finer level's first resume point, whatever `checkpoint_every`
        // says: its carried shape on its mesh (a kill during its settle,
        // which may take an hour, resumes here rather than from scratch).
        if leveled {
            run.checkpoint()?;
        }
        // An output that cannot be written ends the run as a failed step
        // does: the summary says why.
        let end = match controller {
            Some(controller) => run.adaptive(controller),
            None => run.fixed(&schedule),
        }
        .unwrap_or_else(End::Failed);
        *recorded = true;
        run.finish(end)
    })
}

/// How often the watcher looks at the run's stop flag.
const WATCH_INTERVAL: std::time::Duration = std::time::Duration::from_millis(20);

/// Ends the stop flag's watcher when the session's scope ends, however
/// it ends.
struct Unwatch<'a>(&'a AtomicBool);

impl Drop for Unwatch<'_> {
    fn drop(&mut self) {
        self.0.store(false, Ordering::SeqCst);
    }
}

/// How the loop over the schedule ended.
enum End {
    /// The schedule's end.
    Done,
    /// The rest criterion was met.
    AtRest,
    /// Stopped on request; a checkpoint was written.
    Interrupted,
    /// A step failed, or the material became unstable.
    Failed(RunError),
}

/// The run loop's state: what it steps, what it writes, what it counts.
struct Stepper<'a, 'scope> {
    setup: &'a Setup,
    out: &'a Path,
    start: Instant,
    /// Wall time of the set-up (s).
    setup_seconds: f64,
    /// `|X|` of Newton's test (m).
    length: f64,
    /// End time of the schedule (s), or 1 in statics.
    end_time: f64,
    /// Scheduled steps in all (0 with adaptive steps).
    scheduled_total: usize,
    stop: Option<&'a AtomicBool>,
    ws: &'a mut DynamicWorkspace,
    state: State,
    counters: Counters,
    history: History<'a>,
    frame_writer: frames::FrameWriter<'scope>,
    /// The frames handed to the writer thread, `(time, step)`.
    written: Vec<(f64, usize)>,
    last_contact: Option<ContactReport>,
    /// The loop's own output work (s).
    output_seconds: f64,
    first_step_seconds: Option<f64>,
    rest: Option<RestWatch>,
    observer: &'a mut dyn FnMut(&StepInfo),
    /// The multilevel record so far (empty without `[refine]`).
    levels: &'a Levels,
    /// A level of a multilevel settle: the caller writes the summary of a
    /// session that ends as scheduled ([`run_level`]).
    multilevel: bool,
    /// The sub-steps left of the scheduled step under way, where a stop
    /// inside it ends the run (and a resume goes on with them); else
    /// empty.
    pending: Vec<(f64, usize)>,
}

impl Stepper<'_, '_> {
    /// The segments' fixed steps: each scheduled step is tried whole, and a
    /// failing one is split in two halves, recursively up to
    /// `max_cutbacks` halvings; the next scheduled step takes the
    /// scheduled size again.
    fn fixed(&mut self, schedule: &[(usize, f64)]) -> Result<End, RunError> {
        let mut k = 0usize; // scheduled-step index
        for (count, dt) in schedule {
            for _ in 0..*count {
                k += 1;
                if k <= self.counters.scheduled_done {
                    continue;
                }
                // Each scheduled step may be split into 2^k sub-steps; a
                // resumed one goes on with the halves it had left.
                let resumed = std::mem::take(&mut self.pending);
                let mut progressed = !resumed.is_empty();
                let mut pending: Vec<(f64, usize)> =
                    if progressed { resumed } else { vec![(*dt, 0)] };
                while let Some((h, depth)) = pending.pop() {
                    match self.attempt(h, depth) {
                        Ok(outcome) => {
                            progressed = true;
                            if let Some(end) = self.record(&outcome, h, depth, k)? {
                                return Ok(end);
                            }
                        }
                        Err(NewtonError::Interrupted { .. }) => {
                            // Past the scheduled step's first sub-steps,
                            // the checkpoint keeps the halves left (the
                            // interrupted one included).
                            if progressed {
                                pending.push((h, depth));
                                self.pending = pending;
                            }
                            self.checkpoint()?;
                            self.pending.clear();
                            return Ok(End::Interrupted);
                        }
                        Err(_) if depth < self.setup.max_cutbacks => {
                            pending.push((0.5 * h, depth + 1));
                            pending.push((0.5 * h, depth + 1));
                        }
                        Err(e) => return Ok(End::Failed(self.step_failure(h, depth, e))),
                    }
                }
                self.counters.scheduled_done = k;
                if let Some(end) = self.between_steps(k)? {
                    return Ok(end);
                }
            }
        }
        Ok(End::Done)
    }

    /// Adaptive steps, sized by `controller` (see [`StepController`]). A
    /// checkpoint is written every `checkpoint_every` converged steps, and
    /// records the controller's segment and step size.
    fn adaptive(&mut self, mut controller: StepController) -> Result<End, RunError> {
        while let Some(h) = controller.next_step(self.state.time) {
            match self.attempt(h, 0) {
                Ok(outcome) => {
                    let halvings = controller.converged(outcome.newton.iterations);
                    self.counters.segment = controller.segment();
                    self.counters.step_size = controller.step_size();
                    if let Some(end) = self.record(&outcome, h, halvings, 0)? {
                        return Ok(end);
                    }
                    if let Some(end) = self.between_steps(self.counters.step)? {
                        return Ok(end);
                    }
                }
                Err(NewtonError::Interrupted { .. }) => {
                    self.checkpoint()?;
                    return Ok(End::Interrupted);
                }
                Err(_) if controller.failed() => {}
                Err(e) => {
                    let halvings = controller.halvings();
                    return Ok(End::Failed(self.step_failure(h, halvings, e)));
                }
            }
        }
        Ok(End::Done)
    }

    /// One step of size `h`, the `depth`-th halving of its scheduled one.
    fn attempt(&mut self, h: f64, depth: usize) -> Result<StepOutcome, NewtonError> {
        // A stop asked for between two steps (the observer's) ends the run
        // before the next, whatever the watcher has seen yet.
        if self.stop.is_some_and(|s| s.load(Ordering::SeqCst)) {
            return Err(NewtonError::Interrupted { iteration: 0 });
        }
        // A finer level's settle is relaxed without a halving first: its
        // increment starts at the full load, from the coarser level's
        // shape, and half the load would unload that shape rather than
        // ease the step.
        let depth = if self.levels.marks.is_empty() {
            depth
        } else {
            depth.max(RELAX_DEPTH)
        };
        let before = self.ws.newton.iterations;
        let advanced = advance(
            self.setup,
            &mut self.state,
            (h, depth),
            self.length,
            self.ws,
        );
        // What the attempt did besides what its outcome reports: its
        // failed solves, or all of it when it failed.
        let done = self.ws.newton.iterations - before;
        let kept = advanced.as_ref().map_or(0, |o| o.newton.iterations);
        debug_assert!(kept <= done, "{kept} iterations reported, {done} done");
        self.counters.discarded_iterations += done.saturating_sub(kept);
        advanced
    }

    /// Books a converged step of size `h` that needed `cutbacks` halvings:
    /// counters, history row, observer, field frame; then the rest
    /// criterion, which may end the run. (A step that crushed an element
    /// past Saint-Venant–Kirchhoff's stability limit never gets here: the
    /// step solver refuses it, and it is cut back — `step_failure`.)
    fn record(
        &mut self,
        outcome: &StepOutcome,
        h: f64,
        cutbacks: usize,
        scheduled_done: usize,
    ) -> Result<Option<End>, RunError> {
        let model = &self.setup.model;
        let state = &self.state;
        let step = self.counters.step + 1;
        let ((stretch, _), fractions) = model.stretch_and_states(&state.positions);
        self.last_contact = contact_report(model, state);
        if self.first_step_seconds.is_none() {
            self.first_step_seconds = Some(self.start.elapsed().as_secs_f64() - self.setup_seconds);
        }
        let output_start = Instant::now();
        let kinetic = self.history.row(
            state,
            &StepRecord {
                step,
                dt: h,
                iterations: outcome.newton.iterations,
                energies: outcome.energies,
                cutbacks,
                min_stretch: stretch,
                contact: self.last_contact.clone(),
                states: fractions,
            },
        )?;
        self.output_seconds += output_start.elapsed().as_secs_f64();
        // The step counts once its row is on disk: a row that cannot be
        // written ends the run with a summary of the rows there are.
        let counters = &mut self.counters;
        counters.step = step;
        counters.iterations += outcome.newton.iterations;
        if cutbacks > 0 {
            counters.cutback_steps += 1;
        }
        counters.last_strain = outcome.energies.strain();
        if counters.first_contact_time.is_none()
            && self.last_contact.as_ref().is_some_and(|c| c.active > 0)
        {
            counters.first_contact_time = Some(state.time);
        }
        (self.observer)(&StepInfo {
            step,
            time: state.time,
            end_time: self.end_time,
            scheduled_done,
            scheduled_total: self.scheduled_total,
            dt: h,
            iterations: outcome.newton.iterations,
            cutbacks,
            kinetic_energy: kinetic,
            strain_energy: outcome.energies.strain(),
            external_work: state.external_work,
        });
        // After the observer, which may read the step's counts.
        if let Some(p) = &self.ws.newton.progress {
            p.step_done();
        }
        counters.since_frame += 1;
        if counters.since_frame >= self.setup.output_every {
            let output_start = Instant::now();
            self.frame_writer
                .submit(Snapshot::of(step, state, self.last_contact.as_ref()))?;
            self.output_seconds += output_start.elapsed().as_secs_f64();
            self.written.push((state.time, step));
            counters.last_written = step;
            counters.since_frame = 0;
        }
        if let Some(watch) = &mut self.rest {
            let at_rest = watch.observe(state.time, fastest_node(&state.velocities));
            counters.still_steps = watch.still_steps();
            if at_rest {
                return Ok(Some(End::AtRest));
            }
        }
        Ok(None)
    }

    /// Between two steps, `count` steps into the schedule: a checkpoint
    /// every `checkpoint_every`, and when a stop is requested (then the
    /// run ends, interrupted).
    fn between_steps(&mut self, count: usize) -> Result<Option<End>, RunError> {
        let stop = self.stop.is_some_and(|s| s.load(Ordering::SeqCst));
        let every = self.setup.checkpoint_every;
        if stop || (every > 0 && count.is_multiple_of(every)) {
            self.checkpoint()?;
        }
        Ok(stop.then_some(End::Interrupted))
    }

    fn checkpoint(&mut self) -> Result<(), RunError> {
        // The checkpoint lists the frames as written: they must be, or a
        // resumed collection would name missing files.
        let output_start = Instant::now();
        self.frame_writer.flush()?;
        self.output_seconds += output_start.elapsed().as_secs_f64();
        let ck = Checkpoint {
            scenario_hash: self.setup.scenario_hash,
            inputs: Some(self.setup.inputs.clone()),
            counters: Counters {
                wall_seconds: self.counters.wall_seconds + self.start.elapsed().as_secs_f64(),
                linear: self.ws.newton.linear.stats,
                ..self.counters
            },
            state: self.state.clone(),
            external_forces: self.ws.f_ext.clone(),
            frames: self.written.clone(),
            kept_linear: self.ws.newton.linear.kept(),
            self_contact_layout: self.ws.layout_stencils(),
            levels: self.levels.clone(),
            pending: self.pending.clone(),
        };
        let path = checkpoint_path(self.out);
        write_atomic(&path, &ck.to_bytes()).map_err(io_err(&path))
    }

    /// The error of a step that failed at size `h` after `cutbacks` halvings.
    fn step_failure(&self, h: f64, cutbacks: usize, cause: NewtonError) -> RunError {
        if let NewtonError::MaterialInstability { element, stretch } = cause {
            return RunError::MaterialInstability {
                time: self.state.time + h,
                element,
                stretch,
                advice: compression_advice(self.setup),
                out: self.out.to_path_buf(),
            };
        }
        let (statics, from) = match self.setup.analysis {
            Analysis::Static { from, .. } => (true, from),
            Analysis::Dynamic { .. } => (false, 0.0),
        };
        let level = self.levels.marks.len();
        RunError::Step {
            step: self.counters.step,
            // A static increment by its load factor.
            time: self.state.time - from,
            dt: h,
            statics,
            cutbacks,
            cause,
            hint: if statics && level > 0 {
                format!(
                    "; this is refinement level {level}'s settle from the coarser level's shape, one increment at the full load ({} Newton iterations at most, relaxed in pseudo-time, then {} halvings): give it more ([solver] max_iterations, max_cutbacks), refine less at a time ([refine] fraction), or start from a finer coarse mesh",
                    self.setup.newton.max_iterations, self.setup.max_cutbacks
                )
            } else if statics {
                static_hint(&self.setup.model, self.ws.friction_shortfall())
            } else {
                self_contact_hint(self.setup)
            },
            out: self.out.to_path_buf(),
        }
    }

    /// Writes the last frame and the summary once the loop has ended.
    fn finish(mut self, end: End) -> Result<Finished, RunError> {
        let setup = self.setup;
        let interrupted = matches!(end, End::Interrupted);
        let output_start = Instant::now();
        // After an output error no more is written but the summary: the
        // last frame would not match the history.
        let output_failed = matches!(&end, End::Failed(RunError::Io { .. }));
        // The last frame is listed with the others: a multilevel settle's
        // next level starts its collection from `written`, which would
        // otherwise leave this level's final shape out of `fields.pvd`.
        let last_frame =
            if self.counters.last_written != self.counters.step && !interrupted && !output_failed {
                let submitted = self.frame_writer.submit(Snapshot::of(
                    self.counters.step,
                    &self.state,
                    self.last_contact.as_ref(),
                ));
                if submitted.is_ok() {
                    self.written.push((self.state.time, self.counters.step));
                    self.counters.last_written = self.counters.step;
                    self.counters.since_frame = 0;
                }
                submitted
            } else {
                Ok(())
            };
        // Every frame is on disk before the summary says how the run ended;
        // a frame that could not be written is the run's failure.
        let written = last_frame.and_then(|()| self.frame_writer.finish());
        let (output_thread_seconds, end) = match (written, end) {
            (Ok(busy), end) => (busy.as_secs_f64(), end),
            (Err(e), End::Failed(first)) => (0.0, End::Failed(e.after(&first))),
            (Err(e), _) => (0.0, End::Failed(e)),
        };
        let interrupted = matches!(end, End::Interrupted);
        let at_rest = matches!(end, End::AtRest);
        self.output_seconds += output_start.elapsed().as_secs_f64();
        let counters = &self.counters;
        // The summary reports the history's last row: the state itself,
        // unless its row could not be written.
        let figures = std::mem::take(&mut self.history.last);
        let interruption = interrupted.then(|| {
            format!(
                "interrupted after step {} at t = {:.6} s; resume with `drape run --resume {}`",
                counters.step,
                figures.time,
                self.out.display()
            )
        });
        let (failure, message) = match end {
            End::Failed(e) => {
                let message = e.to_string();
                (Some(e), Some(message))
            }
            _ => (None, interruption.clone()),
        };
        let mut summary = summary(
            setup,
            &figures,
            message,
            counters.step,
            counters.iterations,
            counters.cutback_steps,
            self.start,
        );
        summary.wall_seconds += counters.wall_seconds;
        summary.setup_seconds = self.setup_seconds;
        summary.output_seconds = self.output_seconds;
        summary.output_thread_seconds = output_thread_seconds;
        summary.first_step_seconds = self.first_step_seconds.unwrap_or(0.0);
        summary.linear = self.ws.newton.linear.stats;
        summary.first_contact_time = counters.first_contact_time;
        summary.newton_iterations_discarded = counters.discarded_iterations;
        summary.levels.clone_from(&self.levels.records);
        if interrupted {
            summary.status = "interrupted".into();
        }
        if let Some(watch) = self.rest.filter(|_| at_rest) {
            summary.message = watch.message(figures.time, counters.step);
            summary.at_rest = Some(true);
        }
        let deferred = self.multilevel && failure.is_none() && !interrupted;
        let recorded = if deferred {
            Ok(())
        } else {
            write_summary(self.out, &summary)
        };
        if let Err(e) = recorded {
            let RunError::Io { error, .. } = e else {
                return Err(e);
            };
            return Err(match failure {
                Some(cause) => RunError::Unrecorded {
                    cause: Box::new(cause),
                    error,
                },
                None => RunError::Io {
                    path: self.out.join("summary.json"),
                    error,
                },
            });
        }
        match (failure, interruption) {
            (Some(e), _) => Err(e),
            (None, Some(message)) => Err(RunError::Interrupted { message }),
            (None, None) => Ok(Finished {
                summary,
                state: self.state,
                counters: Counters {
                    wall_seconds: self.counters.wall_seconds + self.start.elapsed().as_secs_f64(),
                    linear: self.ws.newton.linear.stats,
                    ..self.counters
                },
                written: self.written,
            }),
        }
    }
}

/// Writes `summary` to `out/summary.json` again (the multilevel settle's
/// last word: the levels with the last one measured).
///
/// # Errors
/// [`RunError::Io`].
pub fn rewrite_summary(out: &Path, summary: &Summary) -> Result<(), RunError> {
    write_summary(out, summary)
}

/// Records in `out/summary.json` that the run failed with `message`
/// after what the summary there counts (a finer level that could not be
/// made); best effort — the error itself is what the caller returns.
pub fn record_level_failure(out: &Path, message: &str) {
    let _ = summary::mark_failed(out, message);
}

/// The contact report of `state`, if the model has contact.
fn contact_report(model: &Model, state: &State) -> Option<ContactReport> {
    model
        .contact()
        .zip(state.contact.as_ref())
        .map(|(c, s)| c.report(&state.positions, state.time, s))
}

/// Writes a failed summary for a run that could not start, and returns the error.
fn setup_failure(setup: &Setup, out: &Path, start: Instant, error: SetupError) -> RunError {
    let summary = initial_summary(setup, error.to_string(), start);
    match write_summary(out, &summary) {
        Ok(()) => RunError::Setup(error),
        Err(e) => e,
    }
}

/// The advice on a dynamic step that failed with self-contact on (starts
/// with "; "; empty without): the barrier at `self_distance` stiffens
/// without bound, and a step that does not resolve a landing on it fails
/// (issue 46: 1e-6 m failed at the impact after 6 cut-backs and passed
/// with 12); the `reuse` and `iterative` linear modes keep the model's
/// pattern, without the couplings of self-contact's pairs, which only the
/// direct solver's grown layout has.
fn self_contact_hint(setup: &Setup) -> String {
    let Some(sc) = setup.model.self_contact() else {
        return String::new();
    };
    let mut hint = format!(
        "; with self-contact, the barrier at contact.self_distance = {} m stiffens without bound as two layers close in: give smaller steps (the segment's dt, time.dt_max), more halvings ([solver] max_cutbacks, now {}) or a larger self_distance",
        crate::human::human(sc.distance()),
        setup.max_cutbacks
    );
    if matches!(setup.linear, LinearMode::Reuse | LinearMode::Iterative) {
        hint += "; [solver] linear = \"reuse\" and \"iterative\" solve on the model's own pattern, without the couplings of the pairs in contact (their Hessian moved to the diagonal), and converge slowly where layers press on each other: use linear = \"direct\"";
    }
    hint
}

/// What to change where Saint-Venant–Kirchhoff was compressed past its
/// stability limit: numerical damping where the run has none to speak of
/// (issue 46: the advice was offered to runs that already used it), else
/// what compresses.
fn compression_advice(setup: &Setup) -> String {
    let damped = match &setup.analysis {
        Analysis::Dynamic { newmark, .. } => newmark.gamma >= 1.0,
        Analysis::Static { .. } => true,
    };
    let driven = if setup.model.contact().is_some() {
        "an obstacle or a load that drives the fabric into itself or against an obstacle, or layers pressed together"
    } else {
        "a load or support that squeezes the fabric"
    };
    if damped {
        format!(
            "Something compresses the membrane beyond what it can carry: {driven}; use a wrinkling model (material.wrinkling), which gives compressed elements no stiffness, or bending with a mesh fine enough to fold"
        )
    } else {
        "Reduce the compression (numerical damping: time.beta = 1, time.gamma = 1.5), or use a wrinkling model".to_string()
    }
}

/// The advice on a static increment that failed (starts with "; "): what
/// stopped it, from what the model has.
fn static_hint(model: &Model, shortfall: Option<FrictionShortfall>) -> String {
    if let Some(FrictionShortfall { needed, limit }) = shortfall {
        // The increment stuck, and Coulomb's limit let it go.
        return format!(
            "; friction cannot hold the load: with the nodes in contact sticking, the load increment is in equilibrium with {needed:.3e} N of tangential force on them, and Coulomb's limit mu lambda there is {limit:.3e} N; a static analysis has no equilibrium where the fabric slides (run it dynamically to follow the slide), or give the contact more friction",
        );
    }
    if model.bending().is_some() {
        // A fabric with bending has stiffness across its plane; what
        // stalls is the loading path through its buckling.
        return "; a static settle of a fabric with bending follows one loading path through its folds, and Newton stalled on it: give it more increments ([analysis] steps), a looser increment test ([solver] tolerance) where the residual is already small (a specimen held by friction alone), or run it dynamically to rest (beta = 1, gamma = 1.5)".into();
    }
    if model.section().prestress > 0.0 && model.fixed_count() == 0 {
        // Tensioned, but free to move as a whole: its rigid motions have
        // no stiffness.
        let contact = match model.contact() {
            None => "and no obstacle touches it",
            Some(c) if !c.has_friction() => {
                "and frictionless contact pushes only along the obstacles' normals, so a load along them has nothing to balance it"
            }
            Some(_) => {
                "and friction holds only the nodes that touch an obstacle at an increment's start"
            }
        };
        return format!(
            "; the membrane is prestressed, but nothing holds its rigid motions: no [[fix]] holds a node, {contact}; hold it with supports or friction, or run it dynamically"
        );
    }
    if model.section().prestress > 0.0 {
        return String::new();
    }
    "; a static analysis needs a membrane in tension from the first increment on (prestress, or supports that stretch it): a slack membrane has no stiffness across its plane, so run it dynamically to rest instead (beta = 1, gamma = 1.5)".into()
}

/// The static increments that [`StaticStepper::relax`]es: those halved
/// at least this often (a halving that did not help), and every finer
/// level's settle.
const RELAX_DEPTH: usize = 1;

fn advance(
    setup: &Setup,
    state: &mut State,
    (h, depth): (f64, usize),
    length: f64,
    ws: &mut DynamicWorkspace,
) -> Result<StepOutcome, NewtonError> {
    match &setup.analysis {
        Analysis::Dynamic { newmark, .. } => {
            newmark.step(&setup.model, state, h, &setup.newton, length, ws)
        }
        Analysis::Static { from, .. } => {
            let relax = depth >= RELAX_DEPTH;
            StaticStepper { from: *from, relax }.step(
                &setup.model,
                state,
                h,
                &setup.newton,
                length,
                ws,
            )
        }
    }
}

/// `|X|` of the Newton test: the Euclidean norm of the initial positions
/// measured from their centroid (see [`crate::solver::newton`]); 1 m for a
/// single point.
pub fn reference_length(x: &[f64]) -> f64 {
    let n = (x.len() / 3).max(1) as f64;
    let mut c = [0.0; 3];
    for p in x.chunks(3) {
        for i in 0..3 {
            c[i] += p[i] / n;
        }
    }
    let l = x
        .chunks(3)
        .map(|p| (0..3).map(|i| (p[i] - c[i]).powi(2)).sum::<f64>())
        .sum::<f64>()
        .sqrt();
    if l > 0.0 { l } else { 1.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;

    fn setup(time: &str) -> Setup {
        let text = format!(
            "[mesh]\nshape = \"rectangle\"\nsize = [0.1, 0.1]\ndivisions = [2, 2]\n\
             [material]\nyoungs_modulus = 2.0e6\npoisson_ratio = 0.3\ndensity = 320.0\nthickness = 0.6e-3\n\
             [time]\n{time}segments = [{{ steps = 2, dt = 1.0e-3 }}]\n"
        );
        let path = Path::new("t.toml");
        Scenario::parse(&text, path)
            .and_then(|s| s.build(path, &text))
            .expect("a valid scenario")
    }

    /// Issue 46: a compression failure advises numerical damping only to a
    /// run without it (the trapezoidal rule); a run that has it (the
    /// default beta = 1, gamma = 1.5) is told what compresses instead.
    #[test]
    fn compression_advice_offers_damping_only_where_it_is_missing() {
        let damped = compression_advice(&setup(""));
        assert!(
            !damped.contains("gamma") && damped.contains("compresses the membrane"),
            "{damped}"
        );
        let undamped = compression_advice(&setup("beta = 0.25\ngamma = 0.5\n"));
        assert!(undamped.contains("time.gamma = 1.5"), "{undamped}");
    }
}
