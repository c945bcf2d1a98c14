//! `[analysis]` and `[time]`: how time (or load) advances — Newmark's
//! parameters and the schedule's segments of a dynamic analysis, with its
//! adaptive steps and rest criterion, or the increments of a static one.

use super::check::Checker;
use super::{AnalysisKind, Scenario, ScenarioError, SegmentSpec, TimeSpec};
use crate::integrator::Newmark;
use crate::setup::{AdaptiveSteps, Analysis, RestCriterion};

/// `[analysis]` and `[time]`: how time (or load) advances, with the
/// adaptive steps and the rest criterion of a dynamic analysis.
pub(super) fn build_analysis(
    c: &Checker,
    s: &Scenario,
) -> Result<(Analysis, Option<AdaptiveSteps>, Option<RestCriterion>), ScenarioError> {
    match s.analysis.kind {
        AnalysisKind::Dynamic => {
            c.absent(
                "analysis",
                None,
                "steps",
                &s.analysis.steps,
                "to a dynamic analysis (use [time] segments)",
            )?;
            let time = c.required(
                "time",
                None,
                "segments",
                &s.time,
                "for a dynamic analysis (a [time] table with segments)",
            )?;
            let specs = c.required(
                "time",
                None,
                "segments",
                &time.segments,
                "for a dynamic analysis ([{ steps = N, dt = h }, ...])",
            )?;
            let newmark = build_newmark(c, &time)?;
            let segments = build_segments(c, &specs)?;
            let analysis = Analysis::Dynamic { newmark, segments };
            check_totals(c, &analysis)?;
            let adaptive = build_adaptive(c, &time, &analysis.schedule())?;
            let rest = build_rest(c, &time)?;
            Ok((analysis, adaptive, rest))
        }
        AnalysisKind::Static => {
            if let Some(time) = &s.time {
                c.none_of(
                    "time",
                    None,
                    &[
                        ("adaptive", time.adaptive.is_some()),
                        ("dt_max", time.dt_max.is_some()),
                        ("rest", time.rest.is_some()),
                    ],
                    "to a static analysis: adaptive steps and the rest criterion are for dynamic runs (to settle a fabric to rest, run it dynamically with beta = 1, gamma = 1.5)",
                )?;
                return Err(c.invalid(
                    "time",
                    None,
                    "segments",
                    "does not apply to a static analysis (use [analysis] steps)".into(),
                ));
            }
            let steps = s.analysis.steps.unwrap_or(10);
            if steps == 0 {
                return Err(c.invalid("analysis", None, "steps", "must be at least 1".into()));
            }
            Ok((Analysis::Static { steps, from: 0.0 }, None, None))
        }
    }
}

/// `[time] beta, gamma`: Newmark's parameters.
fn build_newmark(c: &Checker, time: &TimeSpec) -> Result<Newmark, ScenarioError> {
    if !(time.beta.is_finite() && time.beta > 0.0) {
        return Err(c.invalid(
            "time",
            None,
            "beta",
            format!("must be positive, not {}", time.beta),
        ));
    }
    if !(time.gamma.is_finite() && time.gamma >= 0.5) {
        return Err(c.invalid(
            "time",
            None,
            "gamma",
            format!(
                "must be >= 0.5 (below, Newmark amplifies), not {}",
                time.gamma
            ),
        ));
    }
    Ok(Newmark {
        beta: time.beta,
        gamma: time.gamma,
    })
}

/// `[time] segments`: at least one, each of `steps >= 1` steps of a
/// positive finite `dt`.
fn build_segments(c: &Checker, specs: &[SegmentSpec]) -> Result<Vec<(usize, f64)>, ScenarioError> {
    if specs.is_empty() {
        return Err(c.invalid(
            "time",
            None,
            "segments",
            "must list at least one { steps, dt }".into(),
        ));
    }
    let mut segments = Vec::new();
    for (k, s) in specs.iter().enumerate() {
        if s.steps == 0 {
            return Err(c.invalid(
                "time",
                None,
                "segments",
                format!("segment {k}: steps must be at least 1"),
            ));
        }
        if !(s.dt.is_finite() && s.dt > 0.0) {
            return Err(c.invalid(
                "time",
                None,
                "segments",
                format!(
                    "segment {k}: dt must be a positive finite number, not {}",
                    s.dt
                ),
            ));
        }
        segments.push((s.steps, s.dt));
    }
    Ok(segments)
}

/// The schedule's totals must exist: the step count in an integer, the
/// end time in a finite number (1e308 s steps add up to infinity).
fn check_totals(c: &Checker, analysis: &Analysis) -> Result<(), ScenarioError> {
    let segments = analysis.schedule();
    let steps = segments
        .iter()
        .try_fold(0usize, |n, (steps, _)| n.checked_add(*steps));
    let end = analysis.end_time();
    if steps.is_none() || !end.is_finite() {
        return Err(c.invalid(
            "time",
            None,
            "segments",
            format!(
                "the schedule's {} cannot be represented: the segments add up to {} steps to t = {end:e} s; shorten the steps or their number",
                if steps.is_none() { "step count" } else { "end time" },
                segments.iter().map(|(n, _)| *n as f64).sum::<f64>()
            ),
        ));
    }
    Ok(())
}

/// The adaptive steps of `[time]`, or `None` without `adaptive = true`;
/// `dt_max` must be positive and at least every segment's `dt`.
fn build_adaptive(
    c: &Checker,
    time: &TimeSpec,
    segments: &[(usize, f64)],
) -> Result<Option<AdaptiveSteps>, ScenarioError> {
    if time.adaptive != Some(true) {
        c.absent(
            "time",
            None,
            "dt_max",
            &time.dt_max,
            "without adaptive = true (fixed steps are the segments' dt)",
        )?;
        return Ok(None);
    }
    let Some(dt_max) = time.dt_max else {
        return Ok(Some(AdaptiveSteps { dt_max: None }));
    };
    let dt_max = c.positive("time", None, "dt_max", dt_max)?;
    if let Some((k, (_, dt))) = segments.iter().enumerate().find(|(_, s)| s.1 > dt_max) {
        return Err(c.invalid(
            "time",
            None,
            "dt_max",
            format!(
                "= {dt_max} s is smaller than segment {k}'s dt = {dt} s: it must be at least every segment's dt"
            ),
        ));
    }
    Ok(Some(AdaptiveSteps {
        dt_max: Some(dt_max),
    }))
}

/// The rest criterion of `[time]`, if given: `speed` positive and finite,
/// `after` finite and >= 0 (one at or after the schedule's end is a
/// warning, `simulation::warnings`, so that a schedule cut short still runs).
fn build_rest(c: &Checker, time: &TimeSpec) -> Result<Option<RestCriterion>, ScenarioError> {
    let Some(r) = time.rest else {
        return Ok(None);
    };
    if !(r.speed.is_finite() && r.speed > 0.0) {
        return Err(c.invalid_in(
            "time",
            "rest",
            "speed",
            format!("must be a positive finite speed (m/s), not {}", r.speed),
        ));
    }
    if !(r.after.is_finite() && r.after >= 0.0) {
        return Err(c.invalid_in(
            "time",
            "rest",
            "after",
            format!("must be a finite time >= 0 (s), not {}", r.after),
        ));
    }
    Ok(Some(RestCriterion {
        speed: r.speed,
        after: r.after,
    }))
}
