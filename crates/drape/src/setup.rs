//! What a run needs, built from a scenario: the [`Setup`] (model, schedule,
//! Newton's settings, monitors, the inputs read) and its small types.
//!
//! It stands between the scenario, which builds it
//! ([`Scenario::build`](crate::scenario::Scenario::build)), and the
//! simulation, which runs it ([`crate::simulation::run`]): neither of the two
//! knows the other.

use crate::input::InputFile;
use crate::integrator::Newmark;
use crate::model::Model;
use crate::solver::{LinearMode, NewtonSettings};
use std::path::PathBuf;

/// A node whose position is recorded in the history.
#[derive(Debug, Clone, PartialEq)]
pub struct Monitor {
    /// Name from the scenario.
    pub name: String,
    /// Node index.
    pub node: usize,
}

/// How time (or load) advances.
#[derive(Debug, Clone, PartialEq)]
pub enum Analysis {
    /// Newmark dynamics over a schedule of `(steps, dt)` segments.
    Dynamic {
        /// Newmark parameters.
        newmark: Newmark,
        /// `(steps, dt)` segments.
        segments: Vec<(usize, f64)>,
    },
    /// Static load stepping in `steps` equal increments.
    Static {
        /// Increments.
        steps: usize,
        /// The "time" the load factor is counted from (0, but a finer
        /// level's of a multilevel settle: the coarser level's end, so
        /// that the history's time and the frames' go on rising): the
        /// load factor is `time - from`.
        from: f64,
    },
}

impl Analysis {
    /// The schedule as `(steps, dt)` segments: a dynamic analysis' own; a
    /// static one's `steps` increments of `1 / steps`, its "time" being
    /// the load factor from 0 to 1.
    pub fn schedule(&self) -> Vec<(usize, f64)> {
        match self {
            Analysis::Dynamic { segments, .. } => segments.clone(),
            Analysis::Static { steps, .. } => vec![(*steps, 1.0 / *steps as f64)],
        }
    }

    /// The schedule's end time (s): the sum over the segments of `steps
    /// dt`; 1 in statics (the full load).
    pub fn end_time(&self) -> f64 {
        match self {
            Analysis::Dynamic { segments, .. } => {
                segments.iter().map(|(n, dt)| *n as f64 * dt).sum()
            }
            Analysis::Static { from, .. } => from + 1.0,
        }
    }
}

/// Everything needed to run a scenario.
#[derive(Debug)]
pub struct Setup {
    /// Title.
    pub title: String,
    /// The discrete model.
    pub model: Model,
    /// Dynamic or static.
    pub analysis: Analysis,
    /// Adaptive time steps (`[time] adaptive = true`); `None`: the
    /// segments' fixed steps (and always in statics).
    pub adaptive: Option<AdaptiveSteps>,
    /// The rest criterion (`[time] rest`), if any (dynamic analysis only).
    pub rest: Option<RestCriterion>,
    /// Newton settings.
    pub newton: NewtonSettings,
    /// Most halvings of a failing step.
    pub max_cutbacks: usize,
    /// Field output interval (steps).
    pub output_every: usize,
    /// Monitored nodes.
    pub monitors: Vec<Monitor>,
    /// Write a checkpoint every this many scheduled steps (with adaptive
    /// steps: converged steps; 0: never).
    pub checkpoint_every: usize,
    /// How linear systems are solved.
    pub linear: LinearMode,
    /// The scenario file (absolute when it could be resolved).
    pub scenario_path: PathBuf,
    /// FNV-1a hash of the scenario text: a resumed run refuses a changed scenario.
    pub scenario_hash: u64,
    /// The files the scenario reads (the mesh, the obstacles' meshes), in
    /// scenario order, with the hash of the bytes read: a resumed run
    /// refuses a changed one.
    pub inputs: Vec<InputFile>,
    /// `[refine]`: the multilevel settle, if asked for.
    pub refine: Option<Refine>,
}

/// The most levels `[refine] levels` may ask for: four splits make 256
/// triangles of one.
pub const MAX_REFINE_LEVELS: usize = 4;

/// `[refine]`, checked: how a run refines its mesh between levels
/// (`crate::levels`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Refine {
    /// The most splits (levels after the first), >= 1.
    pub levels: usize,
    /// Every triangle (`where = "all"`), else where the folds are.
    pub uniform: bool,
    /// The drape coefficient change between two levels below which the
    /// run stops refining.
    pub tolerance: f64,
    /// Elements per gravity bending length a level's mesh must have
    /// before `tolerance` may stop the refinement (its mean edge at most
    /// `l / resolution`, [`crate::levels::resolved`]); 0: no such
    /// condition.
    pub resolution: f64,
    /// Dörfler's bulk share of the curvature indicator, in (0, 1].
    pub fraction: f64,
    /// The marking ranks the triangles by the chord indicator (the
    /// bending indicator times the area), not the bending indicator.
    pub chord: bool,
    /// Split the triangles on the free boundary too.
    pub rim: bool,
    /// Split the triangles across the contact line too.
    pub contact_line: bool,
}

/// `[time] adaptive = true`: the settings of the [`StepController`](crate::simulation::schedule::StepController).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveSteps {
    /// Largest step (s); `None`: [`DEFAULT_DT_MAX_FACTOR`](crate::simulation::schedule::DEFAULT_DT_MAX_FACTOR) times each
    /// segment's own `dt`.
    pub dt_max: Option<f64>,
}

/// `[time] rest`: the run ends, completed, once every node has been slower
/// than `speed` for [`REST_STEPS`](crate::simulation::schedule::REST_STEPS) consecutive converged steps ending at
/// `t >= after`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestCriterion {
    /// Speed (m/s) every node must stay below, > 0.
    pub speed: f64,
    /// Steps ending before this time (s) do not count, >= 0.
    pub after: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The end time is the segments' steps times their dt, summed (in
    /// binary fractions, so exactly); statics end at the full load, in
    /// `steps` increments.
    #[test]
    fn end_time_and_schedule() {
        let dynamic = Analysis::Dynamic {
            newmark: Newmark {
                beta: 0.25,
                gamma: 0.5,
            },
            segments: vec![(3, 0.5), (2, 0.25), (4, 0.125)],
        };
        assert_eq!(dynamic.end_time(), 2.5);
        assert_eq!(dynamic.schedule(), vec![(3, 0.5), (2, 0.25), (4, 0.125)]);
        let statics = Analysis::Static {
            steps: 4,
            from: 0.0,
        };
        assert_eq!(statics.end_time(), 1.0);
        assert_eq!(statics.schedule(), vec![(4, 0.25)]);
    }
}
