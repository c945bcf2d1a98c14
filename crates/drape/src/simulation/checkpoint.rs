//! Checkpoints: the full state of a run in a versioned binary file, to
//! resume from (`drape run --resume DIR`).
//!
//! Format (little-endian), version 7 (the later versions' additions
//! below it):
//!
//! ```text
//! magic "DRAPECKP" · version u32 · scenario hash u64
//! input files u64, then each: key (u32 length, UTF-8), path (u32 length, bytes), FNV-1a of its bytes u64
//! dofs u64 · nodes u64 · bodies u64
//! counters: scheduled steps done, converged steps, Newton iterations, cut-back steps (u64 each),
//!           first contact time f64 (NaN: none), last strain energy f64,
//!           steps since the last frame u64, step of the last frame u64, wall seconds f64,
//!           segment u64, step size f64, still steps u64
//! state: time f64, external work f64, acceleration persistence f64,
//!        friction dissipation f64, the linear solver's counts (7 u64:
//!        solves, Cholesky, LU, Krylov iterations, block LU, chord solves,
//!        multigrid builds), positions, velocities, accelerations,
//!        external forces of the last step (dofs f64 each)
//! contact u8 (0/1), then hints (nodes x bodies u32), held (nodes x 2 u32, u32::MAX: none),
//!        multipliers (nodes f64)
//! frames u64, then (time f64, step u64) each
//! the linear solver's kept state (version 6; [`KeptLinear`]):
//!        multigrid u8 (0: none, 1: counters only, 2: with the matrix it was built from),
//!          then [values u64 and that many f64], fresh iterations, last iterations, skipped solves (u64 each);
//!        reuse factor u8 (0: none, 1: of a symmetric matrix, 2: of its symmetric part),
//!          then values u64 and that many f64
//! self-contact's Hessian layout (version 7): stencils u64, then 4 node
//!        indices (u64 each) per stencil — the pairs the stepper's grown
//!        layout was built from (`integrator::grown`; none without it)
//! FNV-1a of everything before, u64
//! ```
//!
//! The input files are those the scenario reads (its mesh, its obstacles'
//! meshes, [`Setup::inputs`]): a resume refuses one whose bytes have
//! changed, naming it. A path is kept as the bytes of the operating
//! system's string (Unix), so that any path survives.
//!
//! Version 12 ends, after the discarded iterations, with the bending
//! patches' plastic curvatures of a stick hysteresis (count u64, then 3
//! f64 each; [`State::plastic`]); an older file has none (and had no stick
//! hysteresis to keep).
//! Version 11 ends, after the gas, with the Newton iterations of the
//! solves the run threw away (u64; [`Counters::discarded_iterations`]);
//! an older file is read with 0 of them (the resumed summary then counts
//! the session's alone).
//! Version 10 has version 9's layout; its refinements replay with green
//! splits undone ([`crate::mesh::refine::refine_again`]). A file of
//! version 9 or older that refined twice or more is refused (its second
//! refinement would replay to another mesh); one that refined once
//! resumes as before.
//! Version 6 (drape before self-contact's layout) is read with no layout:
//! a run without self-contact resumes bit for bit, one with it grows its
//! layout again at its first step.
//! Version 5 (drape before the kept linear-solver state) is read with
//! none kept: a `direct` run, which keeps nothing across steps, resumes
//! bit for bit, an `iterative` or `reuse` one with a fresh preconditioner.
//! Version 4 (drape before friction) is read with no friction dissipated
//! and the linear solver's counts 0 (the resumed summary then counts the
//! session's alone, as before).
//! Version 3 (drape before the input files were recorded) is read too,
//! without them: it resumes as before, without checking the files.
//! Version 1 (drape before the predictor carried the persistence) resumes
//! with the persistence 1, the predictor it had. Versions 1 and 2 (drape
//! before adaptive steps and the rest criterion) have no segment, step
//! size and still steps: they resume with 0 for each (a fixed schedule's
//! values; adaptive runs did not exist).
//!
//! The trailing hash rejects a truncated or damaged file; it proves the
//! file's integrity, not its sense, so every value is checked too, and a
//! value that is wrong is refused by its field's name: every count against
//! the model before anything is allocated, the counters against each
//! other, the state's numbers finite, the frames in step order and ending
//! at the last frame's step; and, against the scenario
//! ([`Checkpoint::read`]), the counters within its schedule.

use super::summary::LevelRecord;
use crate::contact::ContactState;
use crate::contact::lagrange::MAX_ACTIVE_SET_ROUNDS;
use crate::input::{InputFile, fnv1a};
use crate::integrator::State;
use crate::load::gas::GasState;
use crate::setup::{Analysis, Setup};
use crate::simulation::schedule::REST_STEPS;
use crate::solver::{KeptFactor, KeptLinear, KeptMultigrid, LinearStats};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"DRAPECKP";
const VERSION: u32 = 12;

/// Longest key of an input file (bytes).
const MAX_KEY_BYTES: usize = 256;

/// Longest path of an input file (bytes).
const MAX_PATH_BYTES: usize = 1 << 20;

/// The run's counters at a checkpoint.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Counters {
    /// Scheduled steps completed (each may have been cut into sub-steps).
    pub scheduled_done: usize,
    /// Converged (sub-)steps: history rows after the initial one.
    pub step: usize,
    /// Newton iterations so far.
    pub iterations: usize,
    /// Steps that needed a cut-back.
    pub cutback_steps: usize,
    /// Time of the first step that ended in contact.
    pub first_contact_time: Option<f64>,
    /// Strain energy of the last step (J).
    pub last_strain: f64,
    /// Converged steps since the last frame.
    pub since_frame: usize,
    /// Step of the last frame written.
    pub last_written: usize,
    /// Wall time spent before this point (s).
    pub wall_seconds: f64,
    /// Adaptive steps: the schedule's segment the run is in (0 with fixed
    /// steps).
    pub segment: usize,
    /// Adaptive steps: the controller's step size for the next step (s;
    /// 0 with fixed steps).
    pub step_size: f64,
    /// Rest criterion: consecutive converged steps with every node slower
    /// than the rest speed (0 without a rest criterion), below
    /// [`REST_STEPS`].
    pub still_steps: usize,
    /// What the linear solver has done so far (version 5; zeros from an
    /// older checkpoint): a resumed run's summary counts the whole run.
    pub linear: LinearStats,
    /// The Newton iterations of the solves whose result the run threw
    /// away — an attempt that failed and was cut back, relaxed or
    /// refused, a pseudo-step repeated shorter — besides `iterations`,
    /// which counts the converged steps' (version 11; 0 from an older
    /// checkpoint).
    pub discarded_iterations: usize,
}

/// The counts of [`LinearStats`], in the file's order.
fn linear_counts(l: &LinearStats) -> [usize; 7] {
    [
        l.solves,
        l.cholesky_factorizations,
        l.lu_factorizations,
        l.krylov_iterations,
        l.block_lu_factorizations,
        l.chord_solves,
        l.multigrid_builds,
    ]
}

/// Everything a run needs to continue.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    /// Hash of the scenario text the run was started with.
    pub scenario_hash: u64,
    /// The files the scenario read, with the hashes of their bytes
    /// ([`Setup::inputs`]); `None` in a checkpoint of version 3 or older,
    /// which did not record them (written as an empty list).
    pub inputs: Option<Vec<InputFile>>,
    /// Counters.
    pub counters: Counters,
    /// The integrator's state.
    pub state: State,
    /// External forces at the end of the last step (the work integral's
    /// left end).
    pub external_forces: Vec<f64>,
    /// Frames written so far: `(time, step)`.
    pub frames: Vec<(f64, usize)>,
    /// What the linear solver carries across steps (version 6; none from
    /// an older checkpoint): a resumed `iterative` or `reuse` run rebuilds
    /// the same preconditioner from it.
    pub kept_linear: KeptLinear,
    /// The four-node stencils self-contact's grown Hessian layout was
    /// built from (version 7; empty without one): a resumed run builds the
    /// same layout, so that it factorises on the same pattern.
    pub self_contact_layout: Vec<[usize; 4]>,
    /// The multilevel settle so far (version 8; empty from an older
    /// checkpoint or without `[refine]`): the refinements that made the
    /// mesh the state lives on, and the levels finished.
    pub levels: Levels,
    /// The sub-steps still to take of the scheduled step under way
    /// (version 8; empty at a scheduled step's end, always with adaptive
    /// steps): `(size, halvings)`, the next last — a stop inside a
    /// cut-back step keeps its halves' progress.
    pub pending: Vec<(f64, usize)>,
}

/// The multilevel settle's record: what rebuilds the mesh of the level a
/// run is on from the scenario's own (a resume replays the refinements,
/// which are deterministic), and the levels finished.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Levels {
    /// For each refinement so far, the elements of the mesh before it
    /// that were marked for a red split (sorted).
    pub marks: Vec<Vec<usize>>,
    /// The levels finished, the coarse one first.
    pub records: Vec<LevelRecord>,
}

/// The most elements one refinement may mark in a checkpoint (the node
/// cap's triangles, twice over).
const MAX_MARKS: usize = 2 * crate::mesh::MAX_MESH_NODES;

/// Longest note of a level record (bytes).
const MAX_NOTE_BYTES: usize = 1 << 16;

/// Appends the levels section (version 8).
fn write_levels(b: &mut Vec<u8>, levels: &Levels) {
    let u = |b: &mut Vec<u8>, v: usize| b.extend_from_slice(&(v as u64).to_le_bytes());
    u(b, levels.marks.len());
    for marks in &levels.marks {
        u(b, marks.len());
        for &e in marks {
            u(b, e);
        }
    }
    u(b, levels.records.len());
    for l in &levels.records {
        for v in [l.elements, l.nodes, l.steps, l.newton_iterations] {
            u(b, v);
        }
        b.extend_from_slice(&l.drape_coefficient.unwrap_or(f64::NAN).to_le_bytes());
        b.extend_from_slice(&l.folds.map_or(u64::MAX, |f| f as u64).to_le_bytes());
        b.extend_from_slice(&l.wall_seconds.to_le_bytes());
        b.extend_from_slice(&l.time.to_le_bytes());
        let note = l.note.as_deref().unwrap_or_default().as_bytes();
        b.extend_from_slice(&(note.len() as u32).to_le_bytes());
        b.extend_from_slice(note);
    }
}

/// Reads what [`write_levels`] wrote.
fn read_levels(r: &mut Reader) -> Result<Levels, CheckpointError> {
    let refinements = r.usize("refinements")?;
    if refinements > crate::setup::MAX_REFINE_LEVELS {
        return Err(invalid(format!(
            "{refinements} refinements, more than the {} a run may make",
            crate::setup::MAX_REFINE_LEVELS
        )));
    }
    let mut marks = Vec::with_capacity(refinements);
    for i in 0..refinements {
        let count = r.usize("marked elements")?;
        if count > MAX_MARKS || count > r.remaining() / 8 {
            return Err(invalid(format!(
                "refinement {i} marks {count} elements, beyond the file"
            )));
        }
        let list = (0..count)
            .map(|_| r.usize("marked element"))
            .collect::<Result<Vec<_>, _>>()?;
        refuse(
            list.windows(2).all(|w| w[0] < w[1]),
            "its marked elements are not sorted".into(),
        )?;
        marks.push(list);
    }
    let count = r.usize("levels")?;
    if count > refinements + 1 {
        return Err(invalid(format!(
            "{count} levels finished after {refinements} refinements"
        )));
    }
    let mut records = Vec::with_capacity(count);
    for _ in 0..count {
        let (elements, nodes) = (r.usize("level elements")?, r.usize("level nodes")?);
        let (steps, newton_iterations) = (r.usize("level steps")?, r.usize("level iterations")?);
        let dc = r.f64("level drape coefficient")?;
        let folds = r.u64("level folds")?;
        let wall_seconds = r.f64("level wall seconds")?;
        let time = r.f64("level time")?;
        let note = r.bytes(MAX_NOTE_BYTES, "level note")?;
        let note = String::from_utf8(note.to_vec())
            .map_err(|_| invalid("a level's note is not UTF-8".into()))?;
        refuse(
            wall_seconds.is_finite() && wall_seconds >= 0.0,
            "a level's wall time is not a time".into(),
        )?;
        refuse(time.is_finite(), "a level's time is not finite".into())?;
        records.push(LevelRecord {
            elements,
            nodes,
            drape_coefficient: Some(dc).filter(|d| !d.is_nan()),
            folds: (folds != u64::MAX).then_some(folds as usize),
            steps,
            newton_iterations,
            wall_seconds,
            time,
            note: (!note.is_empty()).then_some(note),
        });
    }
    Ok(Levels { marks, records })
}

/// [`read_levels`] of a file of `version`: one before version 10 that
/// refined twice or more is refused — its second refinement halved green
/// halves again, where this drape undoes them ([`crate::mesh::refine`]),
/// so replaying it would make another mesh.
fn read_levels_of(r: &mut Reader, version: u32) -> Result<Levels, CheckpointError> {
    let levels = read_levels(r)?;
    if version < 10 && levels.marks.len() >= 2 {
        return Err(invalid(format!(
            "version {version} with {} refinements: its refinements after the first cannot be \
             replayed by this drape (it undoes green splits; issue 43); start the run afresh",
            levels.marks.len()
        )));
    }
    Ok(levels)
}

/// Reads the pending sub-steps (version 8): at most one per halving of a
/// scheduled step, each a positive finite size.
fn read_pending(r: &mut Reader) -> Result<Vec<(f64, usize)>, CheckpointError> {
    let count = r.usize("pending sub-steps")?;
    if count > 64 || count > r.remaining() / 16 {
        return Err(invalid(format!(
            "{count} pending sub-steps, beyond the file"
        )));
    }
    (0..count)
        .map(|_| {
            let h = r.f64("pending sub-step")?;
            let depth = r.usize("pending sub-step halvings")?;
            refuse(
                h.is_finite() && h > 0.0 && depth <= 64,
                format!("pending sub-step {h} after {depth} halvings"),
            )?;
            Ok((h, depth))
        })
        .collect()
}

/// A checkpoint that cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CheckpointError {
    /// Reading failed.
    #[error("cannot read the checkpoint: {0}")]
    Io(#[from] std::io::Error),
    /// Not a checkpoint, another version, damaged or truncated, or a value
    /// that cannot be (the message names the field).
    #[error("the checkpoint is unusable: {0}")]
    Invalid(String),
    /// The scenario has changed since the checkpoint was written.
    #[error(
        "the scenario has changed since the checkpoint was written (hash {found:016x}, the checkpoint's {expected:016x}): resuming would mix two different problems; start a new run instead"
    )]
    ScenarioChanged {
        /// The checkpoint's.
        expected: u64,
        /// The scenario's now.
        found: u64,
    },
    /// An input file (the mesh, an obstacle's mesh) has changed since the
    /// checkpoint was written.
    #[error(
        "the input file {path} ({key}) has changed since the checkpoint was written{moved}: resuming would go on with other inputs than the run started with. Restore the file as it was, or start a fresh run",
        path = path.display(),
        moved = moved_from(path, recorded)
    )]
    InputChanged {
        /// The scenario key naming the file (`mesh.path`, `obstacle[1].path`).
        key: String,
        /// The file as the scenario names it now.
        path: PathBuf,
        /// The file as the checkpoint recorded it.
        recorded: PathBuf,
    },
    /// An input file the checkpoint recorded cannot be read any more.
    #[error(
        "the input file {path} ({key}) recorded in the checkpoint cannot be read ({error}): restore it as it was, or start a fresh run",
        path = path.display()
    )]
    InputMissing {
        /// The scenario key naming the file.
        key: String,
        /// The file as the checkpoint recorded it.
        path: PathBuf,
        /// Why it cannot be read.
        error: std::io::Error,
    },
}

/// ` (the checkpoint recorded it as ...)` when the recorded path differs.
fn moved_from(path: &Path, recorded: &Path) -> String {
    if path == recorded {
        String::new()
    } else {
        format!(" (the checkpoint recorded it as {})", recorded.display())
    }
}

fn invalid(message: String) -> CheckpointError {
    CheckpointError::Invalid(message)
}

/// What a checkpoint must fit when it is read.
struct Expected<'a> {
    dofs: usize,
    bodies: usize,
    scenario_hash: u64,
    /// The scenario's input files now, to compare with the recorded ones
    /// (`None`: not compared).
    inputs: Option<&'a [InputFile]>,
}

impl Checkpoint {
    /// Serialises the checkpoint (as version 6; `inputs: None` as an empty
    /// list).
    pub fn to_bytes(&self) -> Vec<u8> {
        let s = &self.state;
        let dofs = s.positions.len();
        let nodes = dofs / 3;
        let bodies = s
            .contact
            .as_ref()
            .map_or(0, |c| c.hints.len() / nodes.max(1));
        let mut b = Vec::with_capacity(64 + 8 * 6 * dofs);
        b.extend_from_slice(MAGIC);
        b.extend_from_slice(&VERSION.to_le_bytes());
        b.extend_from_slice(&self.scenario_hash.to_le_bytes());
        let inputs = self.inputs.as_deref().unwrap_or_default();
        b.extend_from_slice(&(inputs.len() as u64).to_le_bytes());
        for input in inputs {
            for bytes in [input.key.as_bytes(), &path_to_bytes(&input.path)] {
                b.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
                b.extend_from_slice(bytes);
            }
            b.extend_from_slice(&input.hash.to_le_bytes());
        }
        write_levels(&mut b, &self.levels);
        b.extend_from_slice(&(self.pending.len() as u64).to_le_bytes());
        for (h, depth) in &self.pending {
            b.extend_from_slice(&h.to_le_bytes());
            b.extend_from_slice(&(*depth as u64).to_le_bytes());
        }
        for v in [dofs as u64, nodes as u64, bodies as u64] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let c = &self.counters;
        for v in [c.scheduled_done, c.step, c.iterations, c.cutback_steps] {
            b.extend_from_slice(&(v as u64).to_le_bytes());
        }
        b.extend_from_slice(&c.first_contact_time.unwrap_or(f64::NAN).to_le_bytes());
        b.extend_from_slice(&c.last_strain.to_le_bytes());
        b.extend_from_slice(&(c.since_frame as u64).to_le_bytes());
        b.extend_from_slice(&(c.last_written as u64).to_le_bytes());
        b.extend_from_slice(&c.wall_seconds.to_le_bytes());
        b.extend_from_slice(&(c.segment as u64).to_le_bytes());
        b.extend_from_slice(&c.step_size.to_le_bytes());
        b.extend_from_slice(&(c.still_steps as u64).to_le_bytes());
        b.extend_from_slice(&s.time.to_le_bytes());
        b.extend_from_slice(&s.external_work.to_le_bytes());
        b.extend_from_slice(&s.persistence.to_le_bytes());
        b.extend_from_slice(&s.friction_dissipation.to_le_bytes());
        for v in linear_counts(&c.linear) {
            b.extend_from_slice(&(v as u64).to_le_bytes());
        }
        for v in [
            &s.positions,
            &s.velocities,
            &s.accelerations,
            &self.external_forces,
        ] {
            for x in v.iter() {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        match &s.contact {
            None => b.push(0),
            Some(cs) => {
                b.push(1);
                for h in &cs.hints {
                    b.extend_from_slice(&h.to_le_bytes());
                }
                for held in &cs.active {
                    let (k, f) = held.unwrap_or((u32::MAX, u32::MAX));
                    b.extend_from_slice(&k.to_le_bytes());
                    b.extend_from_slice(&f.to_le_bytes());
                }
                for m in &cs.multipliers {
                    b.extend_from_slice(&m.to_le_bytes());
                }
            }
        }
        b.extend_from_slice(&(self.frames.len() as u64).to_le_bytes());
        for (t, step) in &self.frames {
            b.extend_from_slice(&t.to_le_bytes());
            b.extend_from_slice(&(*step as u64).to_le_bytes());
        }
        write_kept(&mut b, &self.kept_linear);
        b.extend_from_slice(&(self.self_contact_layout.len() as u64).to_le_bytes());
        for stencil in &self.self_contact_layout {
            for a in stencil {
                b.extend_from_slice(&(*a as u64).to_le_bytes());
            }
        }
        b.extend_from_slice(&(s.gas.len() as u64).to_le_bytes());
        for g in &s.gas {
            for v in [
                g.mass,
                g.temperature,
                g.volume,
                g.pressure,
                g.inflow,
                g.outflow,
            ] {
                b.extend_from_slice(&v.to_le_bytes());
            }
        }
        b.extend_from_slice(&(c.discarded_iterations as u64).to_le_bytes());
        b.extend_from_slice(&(s.plastic.len() as u64).to_le_bytes());
        for v in s.plastic.iter().flatten() {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let hash = fnv1a(&b);
        b.extend_from_slice(&hash.to_le_bytes());
        b
    }

    /// Reads a checkpoint to resume `setup` from: written by the same
    /// scenario text, from input files with the same bytes (when the
    /// checkpoint recorded them: version 4), for its model's sizes, with
    /// every value sound and its counters within the scenario's schedule.
    pub fn read(bytes: &[u8], setup: &Setup) -> Result<Self, CheckpointError> {
        let model = &setup.model;
        let expected = Expected {
            dofs: model.dofs(),
            bodies: model.contact().map_or(0, |c| c.bodies.len()),
            scenario_hash: setup.scenario_hash,
            inputs: Some(&setup.inputs),
        };
        let ck = Self::parse(bytes, &expected)?;
        ck.fits(setup)?;
        Ok(ck)
    }

    /// Reads a checkpoint written for a model of `dofs` unknowns and
    /// `bodies` obstacles, by the scenario whose hash is `scenario_hash`,
    /// and checks its values against each other (not the input files, nor
    /// the schedule: see [`Checkpoint::read`]).
    pub fn from_bytes(
        bytes: &[u8],
        dofs: usize,
        bodies: usize,
        scenario_hash: u64,
    ) -> Result<Self, CheckpointError> {
        let expected = Expected {
            dofs,
            bodies,
            scenario_hash,
            inputs: None,
        };
        Self::parse(bytes, &expected)
    }

    /// The input files a checkpoint recorded, read from its header alone
    /// (before any scenario is built): `None` for a version that did not
    /// record them.
    pub fn recorded_inputs(bytes: &[u8]) -> Result<Option<Vec<InputFile>>, CheckpointError> {
        let (mut r, version) = open(bytes)?;
        r.u64("scenario hash")?;
        let most = r.remaining() / 16;
        read_inputs(&mut r, version, most)
    }

    /// The multilevel record a checkpoint holds, read from its header
    /// alone (before the level's scenario is built: its refinements make
    /// the mesh); empty for a version that did not record it.
    pub fn recorded_levels(bytes: &[u8]) -> Result<Levels, CheckpointError> {
        let (mut r, version) = open(bytes)?;
        r.u64("scenario hash")?;
        let most = r.remaining() / 16;
        read_inputs(&mut r, version, most)?;
        if version >= 8 {
            read_levels_of(&mut r, version)
        } else {
            Ok(Levels::default())
        }
    }

    /// Compares the recorded input files with the scenario's `current`
    /// ones, in order: the first whose bytes differ is refused by name.
    fn check_inputs(recorded: &[InputFile], current: &[InputFile]) -> Result<(), CheckpointError> {
        let keys = |list: &[InputFile]| list.iter().map(|i| i.key.clone()).collect::<Vec<_>>();
        if keys(recorded) != keys(current) {
            return Err(invalid(format!(
                "input files {:?}, the scenario reads {:?}",
                keys(recorded),
                keys(current)
            )));
        }
        match recorded.iter().zip(current).find(|(r, c)| r.hash != c.hash) {
            Some((r, c)) => Err(CheckpointError::InputChanged {
                key: c.key.clone(),
                path: c.path.clone(),
                recorded: r.path.clone(),
            }),
            None => Ok(()),
        }
    }

    fn parse(bytes: &[u8], expected: &Expected) -> Result<Self, CheckpointError> {
        let (mut r, version) = open(bytes)?;
        let hash = r.u64("scenario hash")?;
        if hash != expected.scenario_hash {
            return Err(CheckpointError::ScenarioChanged {
                expected: hash,
                found: expected.scenario_hash,
            });
        }
        // The mesh and one file per obstacle at most.
        let inputs = read_inputs(&mut r, version, expected.bodies + 1)?;
        if let (Some(recorded), Some(current)) = (&inputs, expected.inputs) {
            Self::check_inputs(recorded, current)?;
        }
        let (levels, pending) = if version >= 8 {
            (read_levels_of(&mut r, version)?, read_pending(&mut r)?)
        } else {
            (Levels::default(), Vec::new())
        };
        let (dofs, bodies) = (expected.dofs, expected.bodies);
        let (d, nodes, b) = (r.usize("dofs")?, r.usize("nodes")?, r.usize("bodies")?);
        if d != dofs || nodes.checked_mul(3) != Some(dofs) || b != bodies {
            return Err(invalid(format!(
                "written for {d} unknowns and {b} obstacles, the scenario has {dofs} and {bodies}"
            )));
        }
        let mut counters = Counters {
            scheduled_done: r.usize("scheduled steps done")?,
            step: r.usize("converged steps")?,
            iterations: r.usize("Newton iterations")?,
            cutback_steps: r.usize("cut-back steps")?,
            first_contact_time: Some(r.f64("first contact time")?).filter(|t| !t.is_nan()),
            last_strain: r.f64("last strain energy")?,
            since_frame: r.usize("steps since the last frame")?,
            last_written: r.usize("step of the last frame")?,
            wall_seconds: r.f64("wall seconds")?,
            ..Counters::default()
        };
        if version >= 3 {
            counters.segment = r.usize("segment")?;
            counters.step_size = r.f64("step size")?;
            counters.still_steps = r.usize("still steps")?;
        }
        let time = r.f64("time")?;
        let external_work = r.f64("external work")?;
        let persistence = if version >= 2 {
            r.f64("acceleration persistence")?
        } else {
            1.0
        };
        // (Version 5: friction; none before.)
        let friction_dissipation = if version >= 5 {
            r.f64("friction dissipation")?
        } else {
            0.0
        };
        if version >= 5 {
            let mut n = [0usize; 7];
            for v in &mut n {
                *v = r.usize("linear-solver counts")?;
            }
            let [solves, cholesky, lu, krylov, block_lu, chord, multigrid] = n;
            counters.linear = LinearStats {
                solves,
                cholesky_factorizations: cholesky,
                lu_factorizations: lu,
                krylov_iterations: krylov,
                block_lu_factorizations: block_lu,
                chord_solves: chord,
                multigrid_builds: multigrid,
            };
        }
        let positions = r.f64s(dofs, "positions")?;
        let velocities = r.f64s(dofs, "velocities")?;
        let accelerations = r.f64s(dofs, "accelerations")?;
        let external_forces = r.f64s(dofs, "external forces")?;
        let contact = match r.u8("contact flag")? {
            0 if bodies > 0 => {
                return Err(invalid(format!(
                    "contact flag 0 (no contact state), but the scenario has {bodies} obstacles"
                )));
            }
            0 => None,
            1 => Some(read_contact(&mut r, nodes, bodies)?),
            flag => return Err(invalid(format!("contact flag {flag} is neither 0 nor 1"))),
        };
        let count = r.usize("frame count")?;
        // One frame per step at most, the initial one included.
        if count > r.remaining() / 16 || count > counters.step.saturating_add(1) {
            return Err(invalid(format!(
                "frame count {count} beyond the file or the {} converged steps",
                counters.step
            )));
        }
        let frames = (0..count)
            .map(|_| Ok((r.f64("frame time")?, r.usize("frame step")?)))
            .collect::<Result<_, CheckpointError>>()?;
        let kept_linear = if version >= 6 {
            read_kept(&mut r)?
        } else {
            KeptLinear::default()
        };
        let self_contact_layout = if version >= 7 {
            let count = r.usize("layout stencils")?;
            if count > r.remaining() / 32 {
                return Err(invalid(format!(
                    "layout stencil count {count} beyond the file"
                )));
            }
            let nodes = expected.dofs / 3;
            (0..count)
                .map(|_| {
                    let mut s = [0; 4];
                    for a in &mut s {
                        *a = r.usize("layout stencil node")?;
                        if *a >= nodes {
                            return Err(invalid(format!(
                                "layout stencil node {a} beyond the mesh's {nodes} nodes"
                            )));
                        }
                    }
                    Ok(s)
                })
                .collect::<Result<Vec<_>, CheckpointError>>()?
        } else {
            Vec::new()
        };
        // (Version 9: the cavities' gas; none before.)
        let gas = if version >= 9 {
            let count = r.usize("cavity count")?;
            if count > r.remaining() / 48 {
                return Err(invalid(format!("cavity count {count} beyond the file")));
            }
            (0..count)
                .map(|_| {
                    Ok(GasState {
                        mass: r.f64("gas mass")?,
                        temperature: r.f64("gas temperature")?,
                        volume: r.f64("cavity volume")?,
                        pressure: r.f64("gas pressure")?,
                        inflow: r.f64("gas inflow")?,
                        outflow: r.f64("gas outflow")?,
                    })
                })
                .collect::<Result<Vec<_>, CheckpointError>>()?
        } else {
            Vec::new()
        };
        // (Version 11: the discarded iterations; none counted before.)
        if version >= 11 {
            counters.discarded_iterations = r.usize("discarded Newton iterations")?;
        }
        // (Version 12: the plastic curvatures; none before.)
        let plastic = if version >= 12 {
            let count = r.usize("plastic curvature count")?;
            if count > r.remaining() / 24 {
                return Err(invalid(format!(
                    "plastic curvature count {count} beyond the file"
                )));
            }
            (0..count)
                .map(|_| {
                    Ok([
                        r.f64("plastic curvature")?,
                        r.f64("plastic curvature")?,
                        r.f64("plastic curvature")?,
                    ])
                })
                .collect::<Result<Vec<_>, CheckpointError>>()?
        } else {
            Vec::new()
        };
        if r.remaining() != 0 {
            return Err(invalid(format!("{} trailing bytes", r.remaining())));
        }
        let ck = Self {
            scenario_hash: hash,
            inputs,
            counters,
            state: State {
                time,
                positions,
                velocities,
                accelerations,
                persistence,
                external_work,
                friction_dissipation,
                contact,
                gas,
                plastic,
            },
            external_forces,
            frames,
            kept_linear,
            self_contact_layout,
            levels,
            pending,
        };
        ck.check_values()?;
        Ok(ck)
    }

    /// The values against each other: what a run can have written.
    fn check_values(&self) -> Result<(), CheckpointError> {
        let c = &self.counters;
        let s = &self.state;
        if let Some(k) = s
            .plastic
            .iter()
            .position(|p| !p.iter().all(|v| v.is_finite()))
        {
            return Err(invalid(format!(
                "patch {k}'s plastic curvature {:?} is not finite",
                s.plastic[k]
            )));
        }
        for (k, g) in s.gas.iter().enumerate() {
            let sound = [
                g.mass,
                g.temperature,
                g.volume,
                g.pressure,
                g.inflow,
                g.outflow,
            ]
            .iter()
            .all(|v| v.is_finite() && *v >= 0.0)
                && g.temperature > 0.0
                && g.volume > 0.0;
            refuse(
                sound,
                format!(
                    "cavity {k}'s gas (mass {}, temperature {}, volume {}, pressure {}, inflow {}, outflow {}) is not a gas: every value finite and >= 0, temperature and volume > 0",
                    g.mass, g.temperature, g.volume, g.pressure, g.inflow, g.outflow
                ),
            )?;
        }
        refuse(
            c.step_size.is_finite() && c.step_size >= 0.0,
            format!("step size {} is not a finite size >= 0", c.step_size),
        )?;
        refuse(
            c.still_steps < REST_STEPS,
            format!(
                "still steps {} not below {REST_STEPS} (the run would have ended at rest)",
                c.still_steps
            ),
        )?;
        refuse(
            (0.0..=1.0).contains(&s.persistence),
            format!("acceleration persistence {} outside [0, 1]", s.persistence),
        )?;
        refuse(
            s.time.is_finite() && s.time >= 0.0,
            format!("time {} is not a finite time >= 0", s.time),
        )?;
        let steps = c.step;
        for (name, value) in [
            ("scheduled steps done", c.scheduled_done),
            ("cut-back steps", c.cutback_steps),
            ("still steps", c.still_steps),
            ("step of the last frame", c.last_written),
        ] {
            refuse(
                value <= steps,
                format!("{name} {value} more than the {steps} converged steps"),
            )?;
        }
        refuse(
            c.since_frame == steps - c.last_written,
            format!(
                "steps since the last frame {} is not the converged steps {steps} less the step of the last frame {}",
                c.since_frame, c.last_written
            ),
        )?;
        if let Some(t) = c.first_contact_time {
            refuse(
                t.is_finite() && (0.0..=s.time).contains(&t),
                format!("first contact time {t} outside [0, {}] (the time)", s.time),
            )?;
        }
        for (name, value) in [
            ("last strain energy", c.last_strain),
            ("external work", s.external_work),
        ] {
            refuse(value.is_finite(), format!("{name} {value} is not finite"))?;
        }
        refuse(
            s.friction_dissipation.is_finite() && s.friction_dissipation >= 0.0,
            format!(
                "friction dissipation {} is not a finite energy >= 0",
                s.friction_dissipation
            ),
        )?;
        refuse(
            c.wall_seconds.is_finite() && c.wall_seconds >= 0.0,
            format!("wall seconds {} is not a finite time >= 0", c.wall_seconds),
        )?;
        for (name, values) in [
            ("positions", &s.positions),
            ("velocities", &s.velocities),
            ("accelerations", &s.accelerations),
            ("external forces", &self.external_forces),
        ] {
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(invalid(format!("{name}[{i}] {} is not finite", values[i])));
            }
        }
        if let Some(cs) = &s.contact
            && let Some(p) = cs
                .multipliers
                .iter()
                .position(|m| !(m.is_finite() && *m >= 0.0))
        {
            return Err(invalid(format!(
                "multipliers[{p}] {} is not a finite force >= 0",
                cs.multipliers[p]
            )));
        }
        // The frames: the initial one first, then in step order, at the
        // times of their steps, the last one at the last frame's step.
        match self.frames.first() {
            Some(&(t, 0)) if t.is_finite() && t >= 0.0 => {}
            first => {
                return Err(invalid(format!(
                    "frames[0] {first:?} is not the initial frame (a time >= 0, step 0)"
                )));
            }
        }
        for (i, pair) in self.frames.windows(2).enumerate() {
            let ((t0, k0), (t1, k1)) = (pair[0], pair[1]);
            refuse(
                k1 > k0 && t1.is_finite() && t1 >= t0 && t1 <= s.time,
                format!(
                    "frames[{}] (time {t1}, step {k1}) does not follow frames[{i}] (time {t0}, step {k0}) within the time {}",
                    i + 1,
                    s.time
                ),
            )?;
        }
        let last = self.frames.last().map_or(0, |f| f.1);
        refuse(
            last == c.last_written,
            format!(
                "step of the last frame {} is not the last listed frame's step {last}",
                c.last_written
            ),
        )
    }

    /// The counters against the scenario's schedule: the position in it,
    /// the converged steps and Newton iterations it allows, the time.
    fn fits(&self, setup: &Setup) -> Result<(), CheckpointError> {
        let cavities = setup.model.cavities().len();
        refuse(
            self.state.gas.len() == cavities,
            format!(
                "{} cavities' gas, the scenario has {cavities} cavities",
                self.state.gas.len()
            ),
        )?;
        let patches = crate::integrator::plastic_count(&setup.model);
        refuse(
            self.state.plastic.len() == patches,
            format!(
                "{} plastic curvatures, the scenario's stick hysteresis has {patches} patches",
                self.state.plastic.len()
            ),
        )?;
        let c = &self.counters;
        let time = self.state.time;
        let segments = setup.analysis.schedule();
        let end_time = setup.analysis.end_time();
        // Times are sums of steps: round-off, relative to the schedule.
        let slack = 1e-9 * end_time;
        let halvings = setup.max_cutbacks.min(1000);
        refuse(
            time <= end_time + slack,
            format!("time {time} beyond the schedule's end {end_time}"),
        )?;
        // Adaptive steps as the run loop has them (never in statics).
        let adaptive =
            setup.adaptive.is_some() && matches!(setup.analysis, Analysis::Dynamic { .. });
        if adaptive {
            self.fits_adaptive(&segments, slack, halvings)?;
        } else {
            // A finer level of a multilevel settle counts its load from
            // the coarser level's end, and its steps after theirs.
            let from = match setup.analysis {
                Analysis::Static { from, .. } => from,
                Analysis::Dynamic { .. } => 0.0,
            };
            let before: usize = self.levels.records.iter().map(|r| r.steps).sum();
            self.fits_fixed(&segments, (from, end_time), before, halvings)?;
        }
        if setup.rest.is_none() {
            refuse(
                c.still_steps == 0,
                format!(
                    "still steps {} without a rest criterion (always 0)",
                    c.still_steps
                ),
            )?;
        }
        refuse(
            c.since_frame < setup.output_every,
            format!(
                "steps since the last frame {} not below the frame interval {}",
                c.since_frame, setup.output_every
            ),
        )?;
        let most = c
            .step
            .saturating_mul(setup.newton.max_iterations)
            .saturating_mul(MAX_ACTIVE_SET_ROUNDS + 1);
        refuse(
            c.iterations <= most,
            format!(
                "Newton iterations {} more than {} converged steps allow ({most})",
                c.iterations, c.step
            ),
        )
    }

    /// [`Checkpoint::fits`] with adaptive steps over `segments`: no
    /// scheduled steps, at most the steps the segments allow with
    /// `halvings` halvings, the time within the checkpoint's segment
    /// (to `slack`).
    fn fits_adaptive(
        &self,
        segments: &[(usize, f64)],
        slack: f64,
        halvings: usize,
    ) -> Result<(), CheckpointError> {
        let c = &self.counters;
        let time = self.state.time;
        refuse(
            c.scheduled_done == 0,
            format!(
                "scheduled steps done {} with adaptive steps (always 0)",
                c.scheduled_done
            ),
        )?;
        refuse(
            self.pending.is_empty(),
            "pending sub-steps with adaptive steps (always none)".into(),
        )?;
        // A segment's steps are at least half its floor, dt / 2^halvings,
        // but its last one; twice that many with a margin.
        let most: f64 = segments
            .iter()
            .map(|(n, _)| 4.0 * *n as f64 * 2f64.powi(halvings as i32) + 2.0)
            .sum();
        refuse(
            (c.step as f64) <= most,
            format!(
                "converged steps {} more than the schedule's adaptive steps allow ({most:.0})",
                c.step
            ),
        )?;
        // The segment's own check is the step controller's; here its
        // span of time.
        let mut start = 0.0;
        for (k, (n, dt)) in segments.iter().enumerate() {
            let end = start + *n as f64 * dt;
            if k == c.segment {
                refuse(
                    time >= start - slack && time <= end + slack,
                    format!("time {time} outside segment {k}'s [{start}, {end}] s"),
                )?;
            }
            start = end;
        }
        Ok(())
    }

    /// [`Checkpoint::fits`] with the segments' fixed steps: the scheduled
    /// steps done within the schedule, each split into 1 to `2^halvings`
    /// steps, no controller state, and the time where those scheduled
    /// steps end (to `1e-6` of `end_time`).
    fn fits_fixed(
        &self,
        segments: &[(usize, f64)],
        (from, end_time): (f64, f64),
        before: usize,
        halvings: usize,
    ) -> Result<(), CheckpointError> {
        let c = &self.counters;
        let time = self.state.time;
        refuse(
            c.step >= before,
            format!(
                "converged steps {} fewer than the {before} of the levels finished",
                c.step
            ),
        )?;
        let steps = c.step - before;
        let total: usize = segments.iter().map(|(n, _)| n).sum();
        refuse(
            c.scheduled_done <= total,
            format!(
                "scheduled steps done {} beyond the schedule's {total}",
                c.scheduled_done
            ),
        )?;
        let per_step = 1usize.checked_shl(halvings as u32).unwrap_or(usize::MAX);
        refuse(
            steps >= c.scheduled_done
                && steps
                    <= (c.scheduled_done + usize::from(!self.pending.is_empty()))
                        .saturating_mul(per_step),
            format!(
                "converged steps {steps} do not fit {} scheduled steps done (each 1 to 2^{halvings} steps)",
                c.scheduled_done
            ),
        )?;
        refuse(
            c.segment == 0,
            format!("segment {} with fixed steps (always 0)", c.segment),
        )?;
        refuse(
            c.step_size == 0.0,
            format!("step size {} with fixed steps (always 0)", c.step_size),
        )?;
        // The time the scheduled steps done reach.
        // A stop inside a cut-back step: its pending halves end it.
        let pending: f64 = self.pending.iter().map(|(h, _)| h).sum();
        refuse(
            self.pending.iter().all(|(_, d)| *d <= halvings),
            format!(
                "pending sub-steps {:?} halved more than {halvings} times",
                self.pending
            ),
        )?;
        let mut left = c.scheduled_done + usize::from(!self.pending.is_empty());
        let mut reached = from - pending;
        for (n, dt) in segments {
            let k = left.min(*n);
            reached += k as f64 * dt;
            left -= k;
        }
        refuse(
            (time - reached).abs() <= 1e-6 * end_time,
            format!(
                "time {time} is not where {} scheduled steps end ({reached})",
                c.scheduled_done
            ),
        )
    }
}

/// `Ok` when `ok`, else the checkpoint is unusable for `message`.
fn refuse(ok: bool, message: String) -> Result<(), CheckpointError> {
    if ok { Ok(()) } else { Err(invalid(message)) }
}

/// Checks the magic, the checksum and the version: the reader after the
/// version, and the version.
fn open(bytes: &[u8]) -> Result<(Reader<'_>, u32), CheckpointError> {
    if bytes.len() < 8 + 4 + 8 + 8 || &bytes[..8] != MAGIC {
        return Err(invalid("not a drape checkpoint".into()));
    }
    let (body, tail) = bytes.split_at(bytes.len() - 8);
    let stored = u64::from_le_bytes(tail.try_into().expect("8 bytes"));
    if fnv1a(body) != stored {
        return Err(invalid(format!(
            "damaged or truncated (its checksum does not match; {} bytes)",
            bytes.len()
        )));
    }
    let mut r = Reader { bytes: body, at: 8 };
    let version = r.u32("version")?;
    if !(1..=VERSION).contains(&version) {
        return Err(invalid(format!(
            "version {version}, this drape reads versions 1 to {VERSION}"
        )));
    }
    Ok((r, version))
}

/// The input files of a version 4 file, at most `most` of them.
fn read_inputs(
    r: &mut Reader,
    version: u32,
    most: usize,
) -> Result<Option<Vec<InputFile>>, CheckpointError> {
    if version < 4 {
        return Ok(None);
    }
    let count = r.usize("input files")?;
    if count > most {
        return Err(invalid(format!(
            "input files {count}, more than the {most} the scenario can have"
        )));
    }
    let mut inputs = Vec::with_capacity(count);
    for i in 0..count {
        let key = r.bytes(MAX_KEY_BYTES, &format!("input files[{i}] key"))?;
        let key = String::from_utf8(key.to_vec())
            .map_err(|_| invalid(format!("input files[{i}] key is not UTF-8")))?;
        let path = path_from_bytes(r.bytes(MAX_PATH_BYTES, &format!("input files[{i}] path"))?);
        let hash = r.u64(&format!("input files[{i}] hash"))?;
        inputs.push(InputFile { key, path, hash });
    }
    Ok(Some(inputs))
}

/// The contact state of `nodes` nodes and `bodies` obstacles.
/// Appends the linear solver's kept state (the format in the module docs).
fn write_kept(b: &mut Vec<u8>, kept: &KeptLinear) {
    let values = |b: &mut Vec<u8>, v: &[f64]| {
        b.extend_from_slice(&(v.len() as u64).to_le_bytes());
        for x in v {
            b.extend_from_slice(&x.to_le_bytes());
        }
    };
    match &kept.multigrid {
        None => b.push(0),
        Some(m) => {
            b.push(if m.built_from.is_some() { 2 } else { 1 });
            if let Some(v) = &m.built_from {
                values(b, v);
            }
            for n in [m.fresh_iterations, m.last_iterations, m.skip] {
                b.extend_from_slice(&(n as u64).to_le_bytes());
            }
        }
    }
    match &kept.factor {
        None => b.push(0),
        Some(f) => {
            b.push(if f.symmetric { 1 } else { 2 });
            values(b, &f.values);
        }
    }
}

/// Reads what [`write_kept`] wrote; the matrices' lengths are checked
/// against the solver's pattern when the run restores them.
fn read_kept(r: &mut Reader) -> Result<KeptLinear, CheckpointError> {
    let values = |r: &mut Reader, field: &str| -> Result<Vec<f64>, CheckpointError> {
        let n = r.usize(field)?;
        let v = r.f64s(n, field)?;
        refuse(
            v.iter().all(|x| x.is_finite()),
            format!("{field}: a value that is not finite"),
        )?;
        Ok(v)
    };
    let multigrid = match r.u8("multigrid flag")? {
        0 => None,
        flag @ (1 | 2) => {
            let built_from = (flag == 2)
                .then(|| values(r, "multigrid matrix"))
                .transpose()?;
            Some(KeptMultigrid {
                built_from,
                fresh_iterations: r.usize("multigrid fresh iterations")?,
                last_iterations: r.usize("multigrid last iterations")?,
                skip: r.usize("multigrid skipped solves")?,
            })
        }
        flag => return Err(invalid(format!("multigrid flag {flag} is not 0, 1 or 2"))),
    };
    let factor = match r.u8("reuse factor flag")? {
        0 => None,
        flag @ (1 | 2) => Some(KeptFactor {
            values: values(r, "reuse factor matrix")?,
            symmetric: flag == 1,
        }),
        flag => {
            return Err(invalid(format!(
                "reuse factor flag {flag} is not 0, 1 or 2"
            )));
        }
    };
    Ok(KeptLinear { multigrid, factor })
}

fn read_contact(
    r: &mut Reader,
    nodes: usize,
    bodies: usize,
) -> Result<ContactState, CheckpointError> {
    let count = nodes
        .checked_mul(bodies)
        .filter(|&n| n <= r.remaining() / 4)
        .ok_or_else(|| invalid("truncated in contact hints".into()))?;
    // A hint that names no feature of its obstacle is ignored by it.
    let hints = (0..count)
        .map(|_| r.u32("contact hints"))
        .collect::<Result<_, _>>()?;
    if nodes > r.remaining() / 8 {
        return Err(invalid("truncated in held nodes".into()));
    }
    let active = (0..nodes)
        .map(|p| {
            let (k, f) = (r.u32("held body")?, r.u32("held feature")?);
            match (k, f) {
                (u32::MAX, u32::MAX) => Ok(None),
                (k, f) if (k as usize) < bodies && f != u32::MAX => Ok(Some((k, f))),
                _ => Err(invalid(format!(
                    "held[{p}] (body {k}, feature {f}) names no obstacle of the {bodies}"
                ))),
            }
        })
        .collect::<Result<_, CheckpointError>>()?;
    let multipliers = r.f64s(nodes, "multipliers")?;
    Ok(ContactState {
        hints,
        active,
        multipliers,
    })
}

#[cfg(unix)]
pub(super) fn path_to_bytes(path: &Path) -> Vec<u8> {
    use std::os::unix::ffi::OsStrExt;
    path.as_os_str().as_bytes().to_vec()
}

#[cfg(not(unix))]
pub(super) fn path_to_bytes(path: &Path) -> Vec<u8> {
    path.to_string_lossy().into_owned().into_bytes()
}

#[cfg(unix)]
pub(super) fn path_from_bytes(bytes: &[u8]) -> PathBuf {
    use std::os::unix::ffi::OsStrExt;
    std::ffi::OsStr::from_bytes(bytes).into()
}

#[cfg(not(unix))]
pub(super) fn path_from_bytes(bytes: &[u8]) -> PathBuf {
    String::from_utf8_lossy(bytes).into_owned().into()
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    /// The next `n` bytes, which hold `field`.
    fn take(&mut self, n: usize, field: &str) -> Result<&[u8], CheckpointError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| invalid(format!("truncated in {field}")))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn remaining(&self) -> usize {
        self.bytes.len() - self.at
    }
    fn u8(&mut self, field: &str) -> Result<u8, CheckpointError> {
        Ok(self.take(1, field)?[0])
    }
    fn u32(&mut self, field: &str) -> Result<u32, CheckpointError> {
        Ok(u32::from_le_bytes(
            self.take(4, field)?.try_into().expect("4 bytes"),
        ))
    }
    fn u64(&mut self, field: &str) -> Result<u64, CheckpointError> {
        Ok(u64::from_le_bytes(
            self.take(8, field)?.try_into().expect("8 bytes"),
        ))
    }
    fn usize(&mut self, field: &str) -> Result<usize, CheckpointError> {
        let v = self.u64(field)?;
        usize::try_from(v).map_err(|_| invalid(format!("{field} {v} too large")))
    }
    fn f64(&mut self, field: &str) -> Result<f64, CheckpointError> {
        Ok(f64::from_le_bytes(
            self.take(8, field)?.try_into().expect("8 bytes"),
        ))
    }
    fn f64s(&mut self, n: usize, field: &str) -> Result<Vec<f64>, CheckpointError> {
        if n > self.remaining() / 8 {
            return Err(invalid(format!("truncated in {field}")));
        }
        (0..n).map(|_| self.f64(field)).collect()
    }
    /// A length (u32, at most `most`) and that many bytes.
    fn bytes(&mut self, most: usize, field: &str) -> Result<&[u8], CheckpointError> {
        let n = self.u32(field)? as usize;
        if n > most {
            return Err(invalid(format!("{field} of {n} bytes, more than {most}")));
        }
        self.take(n, field)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(contact: bool) -> Checkpoint {
        let n = 6;
        let v = |k: f64| (0..n).map(|i| k + i as f64 * 0.1).collect::<Vec<f64>>();
        Checkpoint {
            scenario_hash: 0xdead_beef,
            inputs: Some(vec![InputFile {
                key: "mesh.path".into(),
                path: PathBuf::from("/tmp/some where/plate.msh"),
                hash: 0x1234_5678_9abc_def0,
            }]),
            counters: Counters {
                scheduled_done: 7,
                step: 9,
                iterations: 21,
                cutback_steps: 1,
                first_contact_time: Some(0.25),
                last_strain: 1e-3,
                since_frame: 2,
                last_written: 7,
                wall_seconds: 0.5,
                segment: 1,
                step_size: 2.5e-3,
                still_steps: 4,
                linear: LinearStats {
                    solves: 30,
                    block_lu_factorizations: 21,
                    chord_solves: 9,
                    ..LinearStats::default()
                },
                discarded_iterations: 13,
            },
            state: State {
                time: 0.3,
                positions: v(1.0),
                velocities: v(2.0),
                accelerations: v(3.0),
                persistence: 0.375,
                external_work: 0.01,
                friction_dissipation: 0.002,
                contact: contact.then(|| ContactState {
                    hints: vec![0, u32::MAX, 2, 1],
                    active: vec![Some((0, 2)), None],
                    multipliers: vec![0.5, 0.0],
                }),
                gas: vec![GasState {
                    mass: 1.2e-3,
                    temperature: 310.0,
                    volume: 1.1e-3,
                    pressure: 1.1e5,
                    inflow: 2e-4,
                    outflow: 1e-4,
                }],
                plastic: vec![[0.5, -2.0, 0.25], [0.0, 1e-3, -7.0]],
            },
            external_forces: v(4.0),
            frames: vec![(0.0, 0), (0.2, 7)],
            kept_linear: KeptLinear {
                multigrid: Some(KeptMultigrid {
                    built_from: Some(vec![4.0, -1.0, 0.5]),
                    fresh_iterations: 7,
                    last_iterations: usize::MAX,
                    skip: 2,
                }),
                factor: contact.then(|| KeptFactor {
                    values: vec![2.0, 0.25],
                    symmetric: false,
                }),
            },
            self_contact_layout: if contact {
                vec![[0, 1, 1, 0]]
            } else {
                Vec::new()
            },
            levels: Levels {
                marks: vec![vec![0, 2, 5]],
                records: vec![LevelRecord {
                    elements: 8,
                    nodes: 9,
                    drape_coefficient: Some(0.5),
                    folds: Some(6),
                    steps: 3,
                    newton_iterations: 17,
                    wall_seconds: 1.25,
                    time: 0.75,
                    note: None,
                }],
            },
            pending: vec![(5.0e-4, 1), (2.5e-4, 2)],
        }
    }

    /// The bytes of `c`'s self-contact layout (version 7), last before the
    /// checksum.
    fn layout_len(c: &Checkpoint) -> usize {
        8 + 32 * c.self_contact_layout.len()
    }

    /// The bytes of `c`'s gas (version 9): a count, six values a cavity.
    fn gas_len(c: &Checkpoint) -> usize {
        8 + 48 * c.state.gas.len()
    }

    /// The bytes of `c`'s levels and pending sub-steps (version 8), after
    /// the input files.
    fn levels_len(c: &Checkpoint) -> usize {
        let mut b = Vec::new();
        write_levels(&mut b, &c.levels);
        b.len() + 8 + 16 * c.pending.len()
    }

    fn bodies(c: &Checkpoint) -> usize {
        usize::from(c.state.contact.is_some()) * 2
    }

    #[test]
    fn round_trips_bit_for_bit_and_rejects_damage_and_other_scenarios() {
        for contact in [false, true] {
            let c = sample(contact);
            let bytes = c.to_bytes();
            let bodies = bodies(&c);
            assert_eq!(
                Checkpoint::from_bytes(&bytes, 6, bodies, 0xdead_beef).unwrap(),
                c
            );
            assert_eq!(
                Checkpoint::recorded_inputs(&bytes).unwrap(),
                c.inputs.clone()
            );
            assert!(matches!(
                Checkpoint::from_bytes(&bytes, 6, bodies, 1),
                Err(CheckpointError::ScenarioChanged { .. })
            ));
            assert!(Checkpoint::from_bytes(&bytes, 9, bodies, 0xdead_beef).is_err());
            for cut in [0, 10, bytes.len() / 2, bytes.len() - 1] {
                let e = Checkpoint::from_bytes(&bytes[..cut], 6, bodies, 0xdead_beef).unwrap_err();
                let says = if cut < 28 {
                    "not a drape checkpoint"
                } else {
                    "damaged or truncated"
                };
                assert!(e.to_string().contains(says), "{cut}: {e}");
            }
            let mut flipped = bytes.clone();
            flipped[40] ^= 1;
            assert!(Checkpoint::from_bytes(&flipped, 6, bodies, 0xdead_beef).is_err());
        }
    }

    /// A path that is not UTF-8 survives (Unix).
    #[cfg(unix)]
    #[test]
    fn keeps_paths_as_bytes() {
        use std::os::unix::ffi::OsStrExt;
        let mut c = sample(false);
        let path = PathBuf::from(std::ffi::OsStr::from_bytes(b"/tmp/caf\xe9/m.obj"));
        c.inputs.as_mut().unwrap()[0].path = path.clone();
        let back = Checkpoint::from_bytes(&c.to_bytes(), 6, 0, 0xdead_beef).unwrap();
        assert_eq!(back.inputs.unwrap()[0].path, path);
    }

    /// Re-seals `body` (a file without its trailing hash) as `version`.
    fn seal(mut body: Vec<u8>, version: u32) -> Vec<u8> {
        body[8..12].copy_from_slice(&version.to_le_bytes());
        let hash = fnv1a(&body);
        body.extend_from_slice(&hash.to_le_bytes());
        body
    }

    /// `c` as version 10 wrote it (without the discarded iterations),
    /// version 8 (without the gas too), version 7 (without the levels
    /// too), version 6 (without the self-contact layout too), version 5
    /// (without the kept linear-solver state too),
    /// version 4 (without the friction dissipation and the linear counts
    /// too), version 3 (without the input files too), version 2 (without
    /// segment, step size and still steps too) or version 1 (without the
    /// persistence too).
    fn as_version(c: &Checkpoint, version: u32) -> Vec<u8> {
        let bytes = c.to_bytes();
        // Version 11: without the plastic curvatures, last before the
        // checksum.
        let plastic = 8 + 24 * c.state.plastic.len();
        let bytes = seal(bytes[..bytes.len() - 8 - plastic].to_vec(), 11);
        if version == 11 {
            return bytes;
        }
        // Version 10: without the discarded iterations, last before the
        // checksum.
        let bytes = seal(bytes[..bytes.len() - 8 - 8].to_vec(), 10);
        if version == 10 {
            return bytes;
        }
        // Version 8: without the cavities' gas, last before the checksum.
        let bytes = seal(bytes[..bytes.len() - 8 - gas_len(c)].to_vec(), 8);
        if version == 8 {
            return bytes;
        }
        // Version 7: without the levels, after the input files.
        let mut at = 8 + 4 + 8 + 8;
        for _ in c.inputs.iter().flatten() {
            for _ in 0..2 {
                let n = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
                at += 4 + n as usize;
            }
            at += 8;
        }
        let mut v7 = bytes[..at].to_vec();
        v7.extend_from_slice(&bytes[at + levels_len(c)..bytes.len() - 8]);
        let bytes = seal(v7, 7);
        if version == 7 {
            return bytes;
        }
        let v6 = bytes.len() - 8 - layout_len(c);
        if version == 6 {
            return seal(bytes[..v6].to_vec(), 6);
        }
        let mut kept = Vec::new();
        write_kept(&mut kept, &c.kept_linear);
        let v5 = seal(bytes[..v6 - kept.len()].to_vec(), 5);
        if version == 5 {
            return v5;
        }
        let bytes = &v5[..];
        // Version 3: magic, version, scenario hash, then the sizes.
        let inputs = 8 + 4 + 8;
        let count = u64::from_le_bytes(bytes[inputs..inputs + 8].try_into().unwrap());
        let mut at = inputs + 8;
        for _ in 0..count {
            for _ in 0..2 {
                let n = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
                at += 4 + n as usize;
            }
            at += 8;
        }
        // Version 4: the sizes (3 u64), 4 counters u64, 5 counter fields,
        // segment, step size, still steps, time, external work and the
        // persistence, then (version 5) the friction dissipation.
        let friction = at + 8 * 3 + 8 * 4 + 8 * 5 + 8 * 3 + 8 * 2 + 8;
        let mut v4 = bytes[..friction].to_vec();
        v4.extend_from_slice(&bytes[friction + 8 + 8 * 7..]);
        if version == 4 {
            return seal(v4[..v4.len() - 8].to_vec(), 4);
        }
        let bytes = &v4[..];
        let mut v3 = bytes[..inputs].to_vec();
        v3.extend_from_slice(&bytes[at..]);
        let bytes = &v3[..];
        if version == 3 {
            return seal(bytes[..bytes.len() - 8].to_vec(), 3);
        }
        // magic, version, 4 header u64, 4 counters u64, 5 counter fields:
        // version 3's segment, step size and still steps follow; then
        // time and external work, and the persistence.
        let counters_end = 8 + 4 + 8 * 4 + 8 * 4 + 8 * 5;
        let persistence = counters_end + 8 * 3 + 8 * 2;
        let mut old = bytes[..counters_end].to_vec();
        let skip = if version == 1 {
            old.extend_from_slice(&bytes[counters_end + 24..persistence]);
            persistence + 8
        } else {
            counters_end + 24
        };
        old.extend_from_slice(&bytes[skip..bytes.len() - 8]);
        seal(old, version)
    }

    /// Version 11 resumes with no plastic curvatures; version 10 with no
    /// discarded iterations counted; version 8
    /// without gas (no cavities then); version 6 with no self-contact layout; version 5 with
    /// nothing kept by the linear solver; version 4
    /// with no friction dissipated; version 3 without
    /// input files (unchecked); versions 1 and 2
    /// with 0 for the adaptive steps' segment and step size and the rest
    /// criterion's still steps (a fixed schedule's values), version 1 with
    /// the persistence 1 (the predictor it was written with).
    #[test]
    fn reads_older_versions_with_defaults_for_the_new_fields() {
        let c = sample(true);
        let mut expected = c.clone();
        // Version 11: no plastic curvatures.
        expected.state.plastic = Vec::new();
        let v11 = Checkpoint::from_bytes(&as_version(&c, 11), 6, 2, 0xdead_beef).unwrap();
        assert_eq!(v11, expected);
        // Version 10: no discarded iterations counted.
        expected.counters.discarded_iterations = 0;
        let v10 = Checkpoint::from_bytes(&as_version(&c, 10), 6, 2, 0xdead_beef).unwrap();
        assert_eq!(v10, expected);
        // Version 8: no gas.
        expected.state.gas = Vec::new();
        let v8 = Checkpoint::from_bytes(&as_version(&c, 8), 6, 2, 0xdead_beef).unwrap();
        assert_eq!(v8, expected);
        // Version 7: no levels, no pending sub-steps.
        expected.levels = Levels::default();
        expected.pending = Vec::new();
        let v7 = Checkpoint::from_bytes(&as_version(&c, 7), 6, 2, 0xdead_beef).unwrap();
        assert_eq!(v7, expected);
        assert_eq!(
            Checkpoint::recorded_levels(&c.to_bytes()).unwrap(),
            c.levels
        );
        // Version 6: no self-contact layout.
        expected.self_contact_layout = Vec::new();
        let v6 = Checkpoint::from_bytes(&as_version(&c, 6), 6, 2, 0xdead_beef).unwrap();
        assert_eq!(v6, expected);
        // Version 5: nothing kept by the linear solver.
        expected.kept_linear = KeptLinear::default();
        let v5 = Checkpoint::from_bytes(&as_version(&c, 5), 6, 2, 0xdead_beef).unwrap();
        assert_eq!(v5, expected);
        // Version 4: no friction, none dissipated, no linear counts.
        expected.state.friction_dissipation = 0.0;
        expected.counters.linear = LinearStats::default();
        let v4 = Checkpoint::from_bytes(&as_version(&c, 4), 6, 2, 0xdead_beef).unwrap();
        assert_eq!(v4, expected);
        expected.inputs = None;
        let v3 = as_version(&c, 3);
        assert_eq!(Checkpoint::recorded_inputs(&v3).unwrap(), None);
        assert_eq!(
            Checkpoint::from_bytes(&v3, 6, 2, 0xdead_beef).unwrap(),
            expected
        );
        expected.counters.segment = 0;
        expected.counters.step_size = 0.0;
        expected.counters.still_steps = 0;
        let v2 = Checkpoint::from_bytes(&as_version(&c, 2), 6, 2, 0xdead_beef).unwrap();
        assert_eq!(v2, expected);
        expected.state.persistence = 1.0;
        let v1 = Checkpoint::from_bytes(&as_version(&c, 1), 6, 2, 0xdead_beef).unwrap();
        assert_eq!(v1, expected);
    }

    /// Values out of range are refused naming the field, whatever their
    /// checksum: each counter against the others, the state's numbers, the
    /// contact state, the frames; and a version this drape does not know.
    /// A version 9 file that refined once resumes as before; one that
    /// refined twice is refused, saying why: its second refinement halved
    /// green halves again, which this drape's refinement undoes.
    #[test]
    fn refuses_an_older_multilevel_record_it_would_replay_to_another_mesh() {
        let mut c = sample(true);
        let v9 = |c: &Checkpoint| {
            let bytes = c.to_bytes();
            seal(bytes[..bytes.len() - 8].to_vec(), 9)
        };
        assert_eq!(Checkpoint::recorded_levels(&v9(&c)).unwrap(), c.levels);
        c.levels.marks.push(vec![1, 4]);
        let e = Checkpoint::recorded_levels(&v9(&c))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("version 9 with 2 refinements") && e.contains("afresh"),
            "{e}"
        );
        // The same record written by this drape is read back.
        assert_eq!(
            Checkpoint::recorded_levels(&c.to_bytes()).unwrap(),
            c.levels
        );
    }

    #[test]
    fn refuses_values_out_of_range_and_unknown_versions() {
        let refused = |change: &dyn Fn(&mut Checkpoint), says: &str| {
            let mut bad = sample(true);
            change(&mut bad);
            let e = Checkpoint::from_bytes(&bad.to_bytes(), 6, 2, 0xdead_beef).unwrap_err();
            assert!(e.to_string().contains(says), "{says}: {e}");
        };
        refused(&|c| c.state.persistence = 1.5, "persistence 1.5");
        refused(
            &|c| c.state.friction_dissipation = -1.0,
            "friction dissipation -1 is not a finite energy",
        );
        refused(&|c| c.counters.step_size = f64::NAN, "step size NaN");
        refused(&|c| c.counters.step_size = -1e-3, "step size -0.001");
        refused(&|c| c.counters.step_size = f64::INFINITY, "step size inf");
        refused(&|c| c.counters.still_steps = REST_STEPS, "still steps 10");
        refused(
            &|c| c.counters.step = usize::MAX,
            "steps since the last frame 2 is not",
        );
        refused(
            &|c| c.counters.scheduled_done = 10,
            "scheduled steps done 10 more than the 9 converged steps",
        );
        refused(
            &|c| c.counters.cutback_steps = 12,
            "cut-back steps 12 more than",
        );
        refused(
            &|c| c.counters.last_written = 8,
            "steps since the last frame 2 is not",
        );
        refused(
            &|c| {
                c.counters.last_written = 8;
                c.counters.since_frame = 1;
            },
            "step of the last frame 8 is not the last listed frame's step 7",
        );
        refused(&|c| c.state.time = f64::NAN, "time NaN");
        refused(&|c| c.state.time = -1.0, "time -1");
        refused(
            &|c| c.counters.first_contact_time = Some(0.5),
            "first contact time 0.5 outside [0, 0.3]",
        );
        refused(&|c| c.counters.wall_seconds = -2.0, "wall seconds -2");
        refused(
            &|c| c.counters.last_strain = f64::INFINITY,
            "last strain energy inf",
        );
        refused(&|c| c.state.external_work = f64::NAN, "external work NaN");
        refused(&|c| c.state.positions[4] = f64::NAN, "positions[4] NaN");
        refused(
            &|c| c.state.velocities[0] = f64::INFINITY,
            "velocities[0] inf",
        );
        refused(&|c| c.state.accelerations[5] = f64::NAN, "accelerations[5]");
        refused(&|c| c.external_forces[1] = f64::NAN, "external forces[1]");
        let contact = |c: &mut Checkpoint| c.state.contact.as_mut().unwrap().clone();
        refused(
            &|c| {
                let mut cs = contact(c);
                cs.multipliers[1] = -1.0;
                c.state.contact = Some(cs);
            },
            "multipliers[1] -1",
        );
        refused(
            &|c| {
                let mut cs = contact(c);
                cs.active[1] = Some((2, 0));
                c.state.contact = Some(cs);
            },
            "held[1] (body 2, feature 0) names no obstacle of the 2",
        );
        refused(&|c| c.frames = vec![], "frames[0] None");
        refused(&|c| c.frames[0] = (0.0, 1), "frames[0] Some((0.0, 1))");
        refused(
            &|c| c.frames = vec![(0.0, 0), (0.2, 7), (0.1, 7)],
            "frames[2] (time 0.1, step 7) does not follow frames[1]",
        );
        refused(
            &|c| c.frames = vec![(0.0, 0), (0.4, 7)],
            "frames[1] (time 0.4, step 7)",
        );
        refused(
            &|c| c.frames = (0..=10).map(|k| (0.0, k)).collect(),
            "frame count 11 beyond the file or the 9 converged steps",
        );
        // No contact state where the scenario has obstacles.
        // (A file without contact, its header's bodies made 2.)
        let mut none = sample(false).to_bytes();
        none.truncate(none.len() - 8);
        let bodies_at = 8 + 4 + 8 + 8 + (4 + 9 + 4 + 25 + 8) + levels_len(&sample(false)) + 16;
        none[bodies_at..bodies_at + 8].copy_from_slice(&2u64.to_le_bytes());
        let e = Checkpoint::from_bytes(&seal(none, VERSION), 6, 2, 0xdead_beef).unwrap_err();
        assert!(e.to_string().contains("contact flag 0"), "{e}");
        // A later version is refused by name.
        let mut later = sample(true).to_bytes();
        later.truncate(later.len() - 8);
        let later = seal(later, VERSION + 1);
        let e = Checkpoint::from_bytes(&later, 6, 2, 0xdead_beef).unwrap_err();
        assert!(
            e.to_string().contains(&format!(
                "version {}, this drape reads versions 1 to {VERSION}",
                VERSION + 1
            )),
            "{e}"
        );
    }

    /// Counts and lengths read from the file are bounded before anything
    /// is allocated, and a file cut short (but sealed) names the field it
    /// ends in.
    #[test]
    fn refuses_absurd_counts_and_names_the_field_a_sealed_file_ends_in() {
        let c = sample(true);
        let bytes = c.to_bytes();
        let body = |b: &[u8]| b[..b.len() - 8].to_vec();
        let forge = |at: usize, value: &[u8]| {
            let mut b = body(&bytes);
            b[at..at + value.len()].copy_from_slice(value);
            seal(b, VERSION)
        };
        let says = |b: &[u8], says: &str| {
            let e = Checkpoint::from_bytes(b, 6, 2, 0xdead_beef).unwrap_err();
            assert!(e.to_string().contains(says), "{says}: {e}");
        };
        // The input files' count, right after the scenario hash.
        says(
            &forge(20, &u64::MAX.to_le_bytes()),
            "input files 18446744073709551615, more than the 3",
        );
        // The first key's length.
        says(
            &forge(28, &u32::MAX.to_le_bytes()),
            "input files[0] key of 4294967295 bytes",
        );
        // The kept linear-solver state, last before the checksum: the
        // multigrid flag, its matrix's length and values, its 3 counters;
        // the factor's flag, length and values.
        // The self-contact layout, last: a node beyond the mesh's two.
        // The plastic curvatures, last before the checksum.
        let plastic_at = bytes.len() - 8 - 8 - 24 * c.state.plastic.len();
        says(
            &forge(plastic_at, &u64::MAX.to_le_bytes()),
            "plastic curvature count 18446744073709551615 beyond the file",
        );
        says(
            &forge(plastic_at + 8 + 24 + 8, &f64::NAN.to_le_bytes()),
            "patch 1's plastic curvature [0.0, NaN, -7.0] is not finite",
        );
        // The gas, before the discarded iterations' count (u64).
        let gas_at = plastic_at - 8 - gas_len(&c);
        says(
            &forge(gas_at, &u64::MAX.to_le_bytes()),
            "cavity count 18446744073709551615 beyond the file",
        );
        says(
            &forge(gas_at + 8, &(-1.0f64).to_le_bytes()),
            "cavity 0's gas (mass -1",
        );
        let layout_at = gas_at - layout_len(&c);
        says(
            &forge(layout_at + 8 + 8, &7u64.to_le_bytes()),
            "layout stencil node 7 beyond the mesh's 2 nodes",
        );
        says(
            &forge(layout_at, &u64::MAX.to_le_bytes()),
            "layout stencil count 18446744073709551615 beyond the file",
        );
        let mut kept = Vec::new();
        write_kept(&mut kept, &c.kept_linear);
        let kept_at = layout_at - kept.len();
        says(&forge(kept_at, &[3]), "multigrid flag 3 is not 0, 1 or 2");
        says(
            &forge(kept_at + 1 + 8, &f64::NAN.to_le_bytes()),
            "multigrid matrix: a value that is not finite",
        );
        let factor_at = kept_at + 1 + 8 + 3 * 8 + 3 * 8;
        says(
            &forge(factor_at, &[9]),
            "reuse factor flag 9 is not 0, 1 or 2",
        );
        says(
            &forge(factor_at + 1, &u64::MAX.to_le_bytes()),
            "truncated in reuse factor matrix",
        );
        // The frame count, before the two frames.
        let frames = kept_at - 2 * 16 - 8;
        says(
            &forge(frames, &(u64::MAX / 2).to_le_bytes()),
            "frame count 9223372036854775807 beyond the file",
        );
        // A sealed file cut in the positions.
        let header = 8 + 4 + 8 + 8 + (4 + 9 + 4 + 25 + 8) + levels_len(&c) + 24;
        let counters = 8 * 12;
        // Time, external work, persistence, friction dissipation and the
        // linear solver's 7 counts.
        let state = 8 * 4 + 8 * 7;
        let cut = header + counters + state + 8 * 3;
        says(
            &seal(body(&bytes)[..cut].to_vec(), VERSION),
            "truncated in positions",
        );
        // The contact flag.
        let flag = header + counters + state + 8 * 6 * 4;
        says(&forge(flag, &[7]), "contact flag 7 is neither 0 nor 1");
    }

    /// The recorded files against the scenario's: a changed one is named
    /// with its path, a list of other keys is refused.
    #[test]
    fn compares_the_input_files_in_order() {
        let file = |key: &str, path: &str, hash: u64| InputFile {
            key: key.into(),
            path: path.into(),
            hash,
        };
        let recorded = [
            file("mesh.path", "/a/m.msh", 1),
            file("obstacle[1].path", "/a/o.stl", 2),
        ];
        assert!(Checkpoint::check_inputs(&recorded, &recorded).is_ok());
        let changed = [
            file("mesh.path", "/a/m.msh", 1),
            file("obstacle[1].path", "/b/o.stl", 3),
        ];
        let e = Checkpoint::check_inputs(&recorded, &changed).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("the input file /b/o.stl (obstacle[1].path) has changed")
                && text.contains("(the checkpoint recorded it as /a/o.stl)")
                && text.contains("Restore the file as it was, or start a fresh run"),
            "{text}"
        );
        let other = [file("mesh.path", "/a/m.msh", 1)];
        let e = Checkpoint::check_inputs(&recorded, &other).unwrap_err();
        assert!(e.to_string().contains("input files ["), "{e}");
    }
}
