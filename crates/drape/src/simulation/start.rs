//! How a session of a run starts — fresh, from the initial state, or
//! resumed from the checkpoint in its output directory — and why it may
//! not ([`SetupError`], [`ResumeError`]).

use super::checkpoint::{Checkpoint, CheckpointError, Counters};
use super::frames::Snapshot;
use super::schedule::{ScheduleMismatch, StepController};
use super::summary::Figures;
use super::{
    Front, History, RunError, StepRecord, checkpoint_path, contact_report, history_columns,
};
use super::{io_err, setup_failure};
use crate::input::InputFile;
use crate::integrator::newmark::DynamicWorkspace;
use crate::integrator::{State, StepEnergies};
use crate::output::history::HistoryWriter;
use crate::output::pvd::{PvdWriter, frame_relative_path};
use crate::setup::{Analysis, Setup};
use crate::solver::LinearSolveError;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Why a run could not start: nothing was stepped, and `summary.json`
/// says so (0 steps).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SetupError {
    /// The linear solver could not be set up on the model's pattern.
    #[error("{0}")]
    LinearSolver(LinearSolveError),
    /// The initial acceleration could not be solved for.
    #[error("the initial acceleration M^-1 (F_ext - F_int) cannot be computed: {0}")]
    InitialAcceleration(LinearSolveError),
    /// The adaptive step controller cannot start on the schedule.
    #[error("{0}")]
    Schedule(ScheduleMismatch),
    /// The thread writing the field frames could not be started.
    #[error("cannot start the thread writing the field frames: {0}")]
    FrameThread(std::io::Error),
}

/// Why a run cannot resume from its output directory; each names the
/// file at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ResumeError {
    /// The run in the directory completed (its summary says so) and kept
    /// no checkpoint: there is nothing to resume. (With a checkpoint, a
    /// resume computes the steps after it again.)
    #[error(
        "nothing to resume: the run completed ({}) and kept no checkpoint; to run it again, start a fresh run",
        summary.display()
    )]
    Completed {
        /// The summary that says the run completed.
        summary: PathBuf,
    },
    /// The checkpoint cannot be read, or does not fit the scenario, its
    /// input files or its model (the error names the field or the file).
    #[error("{}: {error}", path.display())]
    Checkpoint {
        /// The checkpoint file.
        path: PathBuf,
        /// What is wrong with it.
        error: CheckpointError,
    },
    /// The checkpoint's place in the adaptive schedule is not in the
    /// scenario's schedule.
    #[error("{}: {error}", path.display())]
    Schedule {
        /// The checkpoint file.
        path: PathBuf,
        /// The place that does not fit.
        error: ScheduleMismatch,
    },
    /// A frame the checkpoint lists is not on disk.
    #[error(
        "{}: the frame {} it lists is missing: the collection would name a file that is not there; restore the frames, or start a fresh run",
        checkpoint.display(),
        frame.display()
    )]
    MissingFrame {
        /// The checkpoint file.
        checkpoint: PathBuf,
        /// The missing frame.
        frame: PathBuf,
    },
    /// The history cannot be cut back to the checkpoint's rows.
    #[error("{}: {error}", path.display())]
    History {
        /// The history file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
}

impl ResumeError {
    /// Whether the message ends suggesting a fresh run (a changed or
    /// missing input file, a missing frame): a front end then says how
    /// to ask for one ([`Explained`](super::Explained)).
    pub fn suggests_fresh_run(&self) -> bool {
        matches!(
            self,
            ResumeError::Completed { .. }
                | ResumeError::MissingFrame { .. }
                | ResumeError::Checkpoint {
                    error: CheckpointError::InputChanged { .. }
                        | CheckpointError::InputMissing { .. },
                    ..
                }
        )
    }
}

/// Before a resume is set up: a run that completed must have kept a
/// checkpoint ([`ResumeError::Completed`]), and each input file the checkpoint in `out`
/// recorded (the mesh, the obstacles' meshes) must still hold the bytes it
/// had, or the resume is refused naming the file — changed, missing or
/// unreadable. A checkpoint that cannot be read, or one that recorded no
/// files (version 3), passes: [`run_with`](super::run_with) reports the
/// former, and checks the scenario's files again against the checkpoint
/// when it resumes.
///
/// The check comes before the scenario is built, so that a changed file
/// is reported as such rather than as an error of its contents (a mesh
/// that no longer reads) or of the model's sizes.
pub fn check_resume_inputs(out: &Path) -> Result<(), ResumeError> {
    completed(out)?;
    let path = checkpoint_path(out);
    let Ok(bytes) = std::fs::read(&path) else {
        return Ok(());
    };
    let Ok(Some(inputs)) = Checkpoint::recorded_inputs(&bytes) else {
        return Ok(());
    };
    for input in inputs {
        let error = match InputFile::hash_file(&input.path) {
            Ok(hash) if hash == input.hash => continue,
            Ok(_) => CheckpointError::InputChanged {
                key: input.key,
                recorded: input.path.clone(),
                path: input.path,
            },
            Err(error) => CheckpointError::InputMissing {
                key: input.key,
                path: input.path,
                error,
            },
        };
        return Err(ResumeError::Checkpoint { path, error });
    }
    Ok(())
}

/// [`ResumeError::Completed`] when `out` holds no checkpoint and its
/// summary says the run completed (a run without `checkpoint_every` keeps
/// none): said so rather than that the checkpoint cannot be read.
fn completed(out: &Path) -> Result<(), ResumeError> {
    if checkpoint_path(out).exists() {
        return Ok(());
    }
    let summary = out.join("summary.json");
    let status = std::fs::read(&summary)
        .ok()
        .and_then(|bytes| serde_json::from_slice::<serde_json::Value>(&bytes).ok())
        .and_then(|value| value.get("status").cloned());
    match status {
        Some(status) if status == "completed" => Err(ResumeError::Completed { summary }),
        _ => Ok(()),
    }
}

/// Where a session starts: the state, and what the loop keeps of the run
/// so far.
pub(super) struct Start<'a> {
    pub(super) state: State,
    pub(super) counters: Counters,
    /// The step controller of adaptive steps.
    pub(super) controller: Option<StepController>,
    pub(super) history: History<'a>,
    pub(super) pvd: PvdWriter,
    /// The frames handed to the writer thread, `(time, step)`.
    pub(super) written: Vec<(f64, usize)>,
    /// A fresh run's initial frame, still to hand to the writer thread.
    pub(super) initial_frame: Option<Snapshot>,
    /// The sub-steps a checkpoint left of its scheduled step.
    pub(super) pending: Vec<(f64, usize)>,
}

/// A resumed session: the checkpoint in `out` read and checked against
/// `setup` (and the frames it lists found on disk) before the history
/// and the collection are cut back to it; `ws` takes its external forces.
/// A refusal is said in `front`'s words.
pub(super) fn resume<'a>(
    setup: &'a Setup,
    out: &Path,
    ws: &mut DynamicWorkspace,
    front: Front,
) -> Result<Start<'a>, RunError> {
    let refused = |error| RunError::Resume { error, front };
    completed(out).map_err(refused)?;
    let path = checkpoint_path(out);
    let unusable = |error| {
        refused(ResumeError::Checkpoint {
            path: path.clone(),
            error,
        })
    };
    let bytes = std::fs::read(&path).map_err(|e| unusable(CheckpointError::Io(e)))?;
    let ck = Checkpoint::read(&bytes, setup).map_err(unusable)?;
    // Checked before the history and the collection are cut back.
    let controller = step_controller(setup, &ck.counters).map_err(|error| {
        refused(ResumeError::Schedule {
            path: path.clone(),
            error,
        })
    })?;
    if let Some((_, k)) = ck
        .frames
        .iter()
        .find(|(_, k)| !out.join(frame_relative_path(*k as u64)).is_file())
    {
        return Err(refused(ResumeError::MissingFrame {
            checkpoint: path,
            frame: out.join(frame_relative_path(*k as u64)),
        }));
    }
    ws.f_ext.copy_from_slice(&ck.external_forces);
    // The summary counts the linear solves of the whole run.
    ws.newton.linear.stats = ck.counters.linear;
    // The preconditioner kept across steps, made again from the matrix it
    // was made from: the run goes on as if it had not stopped.
    if !ws.newton.linear.restore(&ck.kept_linear) {
        return Err(unusable(CheckpointError::Invalid(
            "its kept linear-solver state (the matrix a preconditioner was made from) does not fit the scenario's Hessian, or cannot be factorised again".into(),
        )));
    }
    // Self-contact's Hessian layout as it was: the same pattern, the same
    // factorisations.
    if ws
        .restore_layout(&setup.model, &ck.self_contact_layout)
        .is_err()
    {
        return Err(unusable(CheckpointError::Invalid(
            "its self-contact layout cannot be factorised on this model".into(),
        )));
    }
    let (history, pvd) =
        going_on(setup, out, &ck.state, &ck.counters, &ck.frames).map_err(|e| match e {
            GoingOn::History(error) => refused(ResumeError::History {
                path: out.join("history.csv"),
                error,
            }),
            GoingOn::Collection(e) => e,
        })?;
    Ok(Start {
        state: ck.state,
        counters: ck.counters,
        controller,
        history,
        pvd,
        written: ck.frames,
        initial_frame: None,
        pending: ck.pending,
    })
}

/// A finer level's session of a multilevel settle: the carried state on
/// the level's mesh (a static analysis: no external force yet, as a fresh
/// static run has none), the history and the collection going on where
/// the coarser level left them. Nothing is written until the level's
/// first increment: its row and frame are the first on the new mesh.
pub(super) fn level<'a>(
    setup: &'a Setup,
    out: &Path,
    ws: &mut DynamicWorkspace,
    level: super::LevelStart,
) -> Result<Start<'a>, RunError> {
    ws.f_ext.fill(0.0);
    ws.newton.linear.stats = level.counters.linear;
    let (history, pvd) = going_on(setup, out, &level.state, &level.counters, &level.written)
        .map_err(|e| match e {
            GoingOn::History(error) => io_err(&out.join("history.csv"))(error),
            GoingOn::Collection(e) => e,
        })?;
    // The level's own schedule, from its start.
    let counters = Counters {
        scheduled_done: 0,
        segment: 0,
        step_size: 0.0,
        still_steps: 0,
        ..level.counters
    };
    Ok(Start {
        state: level.state,
        counters,
        controller: None,
        history,
        pvd,
        written: level.written,
        initial_frame: None,
        pending: Vec::new(),
    })
}

/// Why the outputs of a run cannot go on: the history (cut back to the
/// rows so far), or the collection.
enum GoingOn {
    History(std::io::Error),
    Collection(RunError),
}

/// The history and the collection of a run going on from `state` after
/// `counters.step` steps with the frames `written`: the history cut back
/// to its rows so far, its last row `state`'s until the session writes
/// one; the collection listing `written`.
fn going_on<'a>(
    setup: &'a Setup,
    out: &Path,
    state: &State,
    counters: &Counters,
    written: &[(f64, usize)],
) -> Result<(History<'a>, PvdWriter), GoingOn> {
    let mut scratch = vec![0.0; setup.model.dofs()];
    let kinetic = setup.model.kinetic_energy(&state.velocities, &mut scratch);
    let last = Figures::of(setup, state, kinetic, counters.last_strain);
    let writer = HistoryWriter::resume(
        &out.join("history.csv"),
        &history_columns(setup),
        counters.step.saturating_add(1),
    )
    .map_err(GoingOn::History)?;
    let history = History {
        setup,
        writer,
        scratch,
        last,
    };
    let entries = written
        .iter()
        .map(|(t, k)| (*t, frame_relative_path(*k as u64)))
        .collect();
    let pvd = PvdWriter::resume(out.join("fields.pvd"), entries)
        .map_err(|e| GoingOn::Collection(io_err(out)(e)))?;
    Ok((history, pvd))
}

/// A fresh session from the initial state `x` at rest (with its initial
/// acceleration in dynamics): the history's first row written, the
/// initial frame ready to hand over. A failure writes the summary of the
/// initial state (`start`: when the run began).
pub(super) fn fresh<'a>(
    setup: &'a Setup,
    out: &Path,
    ws: &mut DynamicWorkspace,
    x: &[f64],
    start: Instant,
) -> Result<Start<'a>, RunError> {
    let model = &setup.model;
    let state = match &setup.analysis {
        Analysis::Dynamic { newmark, .. } => newmark
            .initial_state(model, ws)
            .map_err(|e| setup_failure(setup, out, start, SetupError::InitialAcceleration(e)))?,
        Analysis::Static { .. } => {
            ws.f_ext.fill(0.0);
            State::at_rest(model, x.to_vec())
        }
    };
    let history_path = out.join("history.csv");
    let mut history = History {
        setup,
        writer: HistoryWriter::create(&history_path, &history_columns(setup))
            .map_err(io_err(&history_path))?,
        scratch: vec![0.0; model.dofs()],
        // Set by the first row, below.
        last: Figures::default(),
    };
    let energies0 = StepEnergies {
        membrane: model.strain_energy(&state.positions),
        bending: model.bending().map_or(0.0, |b| b.energy(&state.positions)),
        friction: 0.0,
        // No pair is closer than d̂ in the initial mesh (checked when the
        // model is built).
        self_contact: 0.0,
        obstacles: 0.0,
        features: features_energy(model, &state.positions),
    };
    let (stretch0, fractions0) = model.stretch_and_states(&state.positions);
    let contact0 = contact_report(model, &state);
    history.row(
        &state,
        &StepRecord {
            step: 0,
            dt: 0.0,
            iterations: 0,
            energies: energies0,
            cutbacks: 0,
            min_stretch: stretch0.0,
            contact: contact0.clone(),
            states: fractions0,
        },
    )?;
    let initial_frame = Snapshot::of(0, &state, contact0.as_ref());
    let counters = Counters {
        last_strain: energies0.strain(),
        ..Counters::default()
    };
    let controller = step_controller(setup, &counters)
        .map_err(|e| setup_failure(setup, out, start, SetupError::Schedule(e)))?;
    Ok(Start {
        state,
        counters,
        controller,
        history,
        pvd: PvdWriter::new(out.join("fields.pvd")),
        written: vec![(0.0, 0)],
        initial_frame: Some(initial_frame),
        pending: Vec::new(),
    })
}

/// The step controller of an adaptive run (`None` for fixed steps) where
/// `counters` left it: a fresh run's start in the first segment at its
/// `dt`, or a checkpoint's segment and step size, refused (`Err`) when
/// they do not fit the schedule.
fn step_controller(
    setup: &Setup,
    counters: &Counters,
) -> Result<Option<StepController>, ScheduleMismatch> {
    match (&setup.adaptive, &setup.analysis) {
        (Some(adaptive), Analysis::Dynamic { segments, .. }) => {
            StepController::new(segments, *adaptive, setup.max_cutbacks)
                .resume(counters.segment, counters.step_size)
                .map(Some)
        }
        _ => Ok(None),
    }
}

/// The obstacle features' penalty energy at `y`, `t = 0` (J; 0 without): a
/// feature may start a hair through the fabric (the gripped drape tester's
/// rims).
fn features_energy(model: &crate::model::Model, y: &[f64]) -> f64 {
    match (model.obstacle_features(), model.contact().map(|c| c.method)) {
        (Some(f), Some(crate::contact::ContactMethod::Penalty { stiffness })) => {
            let pairs = f.pairs(y, 0.0);
            f.add_penalty(stiffness, &pairs, y, 0.0, &mut vec![0.0; y.len()], None)
                .0
        }
        _ => 0.0,
    }
}
