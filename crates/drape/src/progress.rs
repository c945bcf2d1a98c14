//! What a step in progress has done so far, for a front end to show while
//! a long step runs. A finer level of the multilevel settle is one static
//! increment, and on a fine mesh it can take an hour (docs/performance.md,
//! "Where a relaxed level's time goes (session 13)"), through which the
//! step's observer hears nothing. The solver and the static stepper count
//! into a [`StepProgress`] shared with the front end, which reads it from
//! a thread of its own ([`crate::simulation::RunControl::progress`]).
//!
//! Counting changes no arithmetic: a run with a `StepProgress` attached
//! computes what it computes without one, bit for bit.

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

/// Counters of the step in progress (module docs), each written by the run
/// and read by anyone; the counts of one step are reset when it converges.
#[derive(Debug)]
pub struct StepProgress {
    /// Converged steps of the run (of this session: a resumed run counts
    /// from its resumption).
    steps: AtomicUsize,
    /// Newton iterations since the last converged step, in every solve
    /// (attempts that failed and were cut back or relaxed included); each
    /// with a new Hessian, as `history.csv` counts them (chord steps are
    /// not iterations).
    iterations: AtomicUsize,
    /// Newton solves since the last converged step.
    solves: AtomicUsize,
    /// The residual `|G|` (N) at the last iteration, as its bits.
    residual: AtomicU64,
    /// Pseudo-steps of the static increment being relaxed since the last
    /// converged step (`integrator::statics`).
    pseudo_steps: AtomicUsize,
    /// The static increment's friction round (0: the stick round, or no
    /// friction).
    friction_round: AtomicUsize,
    /// The level of the multilevel settle (0: the coarse level, or no
    /// `[refine]`), and its triangle count.
    level: AtomicUsize,
    elements: AtomicUsize,
}

/// A reading of [`StepProgress`], its counters at one moment.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ProgressReading {
    /// Converged steps of the run so far (this session's).
    pub steps: usize,
    /// Newton iterations of the step in progress, every solve included.
    pub iterations: usize,
    /// Newton solves of the step in progress.
    pub solves: usize,
    /// The last iteration's residual `|G|` (N); NaN before the first.
    pub residual: f64,
    /// Pseudo-steps of the relaxed increment in progress (0: not relaxed).
    pub pseudo_steps: usize,
    /// The friction round of the static increment in progress.
    pub friction_round: usize,
    /// The level of a multilevel settle (0: the first).
    pub level: usize,
    /// The level's triangles (0: not told).
    pub elements: usize,
}

impl Default for StepProgress {
    /// [`StepProgress::new`].
    fn default() -> Self {
        Self::new()
    }
}

impl StepProgress {
    /// Counters at zero, the residual not yet known (NaN).
    pub fn new() -> Self {
        Self {
            steps: AtomicUsize::new(0),
            iterations: AtomicUsize::new(0),
            solves: AtomicUsize::new(0),
            residual: AtomicU64::new(f64::NAN.to_bits()),
            pseudo_steps: AtomicUsize::new(0),
            friction_round: AtomicUsize::new(0),
            level: AtomicUsize::new(0),
            elements: AtomicUsize::new(0),
        }
    }

    /// The counters now.
    pub fn read(&self) -> ProgressReading {
        ProgressReading {
            steps: self.steps.load(Ordering::Relaxed),
            iterations: self.iterations.load(Ordering::Relaxed),
            solves: self.solves.load(Ordering::Relaxed),
            residual: f64::from_bits(self.residual.load(Ordering::Relaxed)),
            pseudo_steps: self.pseudo_steps.load(Ordering::Relaxed),
            friction_round: self.friction_round.load(Ordering::Relaxed),
            level: self.level.load(Ordering::Relaxed),
            elements: self.elements.load(Ordering::Relaxed),
        }
    }

    /// A Newton solve starts.
    pub(crate) fn solve_started(&self) {
        self.solves.fetch_add(1, Ordering::Relaxed);
    }

    /// A Newton iterate with residual `residual`.
    pub(crate) fn iterate(&self, residual: f64) {
        self.residual.store(residual.to_bits(), Ordering::Relaxed);
    }

    /// A Newton iteration (with a new Hessian: a chord step is not one,
    /// as `history.csv` counts them) was made.
    pub(crate) fn iterated(&self) {
        self.iterations.fetch_add(1, Ordering::Relaxed);
    }

    /// A pseudo-step of a relaxed increment starts.
    pub(crate) fn pseudo_step(&self) {
        self.pseudo_steps.fetch_add(1, Ordering::Relaxed);
    }

    /// The static increment's friction round `round` starts.
    pub(crate) fn friction_round(&self, round: usize) {
        self.friction_round.store(round, Ordering::Relaxed);
    }

    /// Level `level` of the multilevel settle, on `elements` triangles,
    /// starts.
    pub(crate) fn level(&self, level: usize, elements: usize) {
        self.level.store(level, Ordering::Relaxed);
        self.elements.store(elements, Ordering::Relaxed);
    }

    /// A step converged: the step's counts start again.
    pub(crate) fn step_done(&self) {
        self.steps.fetch_add(1, Ordering::Relaxed);
        self.iterations.store(0, Ordering::Relaxed);
        self.solves.store(0, Ordering::Relaxed);
        self.pseudo_steps.store(0, Ordering::Relaxed);
        self.friction_round.store(0, Ordering::Relaxed);
    }
}
