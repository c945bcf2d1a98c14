//! Adaptive time steps and the rest criterion (the README's `[time]` reference): the step-size
//! controller of `[time] adaptive = true` and the watch of `[time] rest`.
//!
//! Both are pure: they see times, Newton iteration counts, failures and the
//! nodes' speeds, never the model, so that the run loop
//! ([`super::run_with`]) decides with them and they are tested alone.

use crate::setup::{AdaptiveSteps, RestCriterion};

/// Consecutive converged steps the rest criterion needs.
pub const REST_STEPS: usize = 10;

/// `dt_max` without the key: this many times the segment's `dt`.
pub const DEFAULT_DT_MAX_FACTOR: f64 = 10.0;

/// A step that took at most this many Newton iterations is easy: `h` grows.
pub const EASY_ITERATIONS: usize = 3;

/// A step that took at least this many Newton iterations is hard: `h` shrinks.
pub const HARD_ITERATIONS: usize = 8;

/// Factor on `h` after an easy step.
pub const GROWTH: f64 = 1.5;

/// Factor on `h` after a hard step, and on a failed step's size.
pub const SHRINK: f64 = 0.5;

/// A time within this fraction of a segment's end time is at the end:
/// step sizes are summed in floating point, so the last step of a segment
/// ends at `t1` only up to round-off.
pub const END_TOLERANCE: f64 = 1e-12;

/// One segment of the schedule as the controller sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Segment {
    /// End time `t1 = t0 + steps dt` (s).
    end: f64,
    /// The segment's `dt` (s): its first step, and the scale of its floor.
    dt: f64,
    /// Largest step (s).
    dt_max: f64,
    /// Smallest step (s): `dt / 2^max_cutbacks`, as in the fixed schedule.
    floor: f64,
}

/// The step-size controller of adaptive time steps.
///
/// The schedule's segments keep their meaning: segment `k` spans `[t0, t1
/// = t0 + steps dt]` (`t0` the previous segment's end, 0 for the first),
/// and only the steps inside it change. On entering a segment `h = dt`.
/// From time `t`, with `r = t1 - t` left, the next step is
///
/// ```text
/// c = min(h, dt_max)
/// step = r       if r <= c              (the rest of the segment fits)
///        r / 2   if c < r < 1.5 c       (the remainder would be a sliver)
///        c       otherwise
/// ```
///
/// so no step crosses `t1`, a segment's last step ends at `t1` (up to
/// round-off; a time within [`END_TOLERANCE`] `t1` of it is at it), and no
/// step leaves behind a remainder smaller than half a step — a sliver
/// would cost a whole Newton solve for almost no time, and a tiny `dt`
/// makes the Newmark Hessian's mass term `M / (beta dt^2)` swamp the
/// stiffness for that step.
///
/// After a converged step that needed no cut-back, with `n` Newton
/// iterations:
///
/// ```text
/// h = min(1.5 h, dt_max)   if n <= 3  (easy)
/// h = max(0.5 h, floor)    if n >= 8  (hard)
/// h unchanged              otherwise
/// ```
///
/// with `floor = dt / 2^max_cutbacks`, the smallest step of the fixed
/// schedule. A failed step of size `s` is retried at `max(s / 2, floor)`,
/// and the controller goes on from that `h` (a step that needed a cut-back
/// does not change it further); a failure at or below the floor (a
/// segment's remainder can be smaller) ends the run. Cut-back stays the
/// safety net; the growth is what makes the steps long.
///
/// Why Newton iteration counts and not a local error estimate: adaptive
/// steps serve settling to rest, where the transient's accuracy matters
/// little and the cost is Newton's — the count says directly whether a
/// step was cheap, and the Newmark scheme with `beta = 1, gamma = 1.5` is
/// unconditionally stable, so long steps damp but do not blow up. A
/// Newmark local error estimate (from the difference between the
/// predictor and the converged step) may be added later for transients.
#[derive(Debug, Clone, PartialEq)]
pub struct StepController {
    segments: Vec<Segment>,
    /// The segment the run is in.
    segment: usize,
    /// The step size the controller aims at (s).
    h: f64,
    /// The size of the step handed out last (s).
    last: f64,
    /// Halvings of the step being attempted.
    halvings: usize,
}

/// A checkpoint's place in an adaptive schedule that the scenario's
/// schedule does not have ([`StepController::resume`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ScheduleMismatch {
    /// No such segment.
    #[error("segment {segment}, but the schedule has {segments} segments")]
    Segment {
        /// The checkpoint's segment.
        segment: usize,
        /// Segments of the schedule.
        segments: usize,
    },
    /// A step size the segment's controller cannot take.
    #[error("step size {h} s outside segment {segment}'s [{floor}, {dt_max}] s")]
    StepSize {
        /// The checkpoint's step size (s).
        h: f64,
        /// Its segment.
        segment: usize,
        /// The smallest step of the segment (s).
        floor: f64,
        /// The largest (s).
        dt_max: f64,
    },
}

impl StepController {
    /// A controller at `t = 0` for the `(steps, dt)` segments of the
    /// schedule; each `dt` must lie in `(0, dt_max]` (the scenario checks).
    pub fn new(segments: &[(usize, f64)], adaptive: AdaptiveSteps, max_cutbacks: usize) -> Self {
        let mut end = 0.0;
        let segments: Vec<Segment> = segments
            .iter()
            .map(|&(steps, dt)| {
                end += steps as f64 * dt;
                Segment {
                    end,
                    dt,
                    dt_max: adaptive.dt_max.unwrap_or(DEFAULT_DT_MAX_FACTOR * dt),
                    floor: dt / 2f64.powi(max_cutbacks.min(1000) as i32),
                }
            })
            .collect();
        let h = segments.first().map_or(0.0, |s| s.dt);
        Self {
            segments,
            segment: 0,
            h,
            last: h,
            halvings: 0,
        }
    }

    /// The controller as a checkpoint left it: in segment `segment`, aiming
    /// at `h` (s; 0: the segment's `dt`, as on entering it). `Err` names
    /// the value that does not fit this schedule.
    pub fn resume(mut self, segment: usize, h: f64) -> Result<Self, ScheduleMismatch> {
        let Some(s) = self.segments.get(segment).copied() else {
            if segment == self.segments.len() {
                // At the schedule's end: nothing is left to step.
                self.segment = segment;
                return Ok(self);
            }
            return Err(ScheduleMismatch::Segment {
                segment,
                segments: self.segments.len(),
            });
        };
        let h = if h == 0.0 { s.dt } else { h };
        if !(h.is_finite() && h >= s.floor * (1.0 - END_TOLERANCE) && h <= s.dt_max) {
            return Err(ScheduleMismatch::StepSize {
                h,
                segment,
                floor: s.floor,
                dt_max: s.dt_max,
            });
        }
        self.segment = segment;
        self.h = h;
        self.last = h;
        self.halvings = 0;
        Ok(self)
    }

    /// The segment the run is in (the number of segments once done).
    pub fn segment(&self) -> usize {
        self.segment
    }

    /// The step size the controller aims at (s).
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// End time of the schedule (s).
    pub fn end_time(&self) -> f64 {
        self.segments.last().map_or(0.0, |s| s.end)
    }

    /// End time of segment `k` (s).
    pub fn segment_end(&self, k: usize) -> Option<f64> {
        self.segments.get(k).map(|s| s.end)
    }

    /// Largest step of segment `k` (s).
    pub fn dt_max(&self, k: usize) -> Option<f64> {
        self.segments.get(k).map(|s| s.dt_max)
    }

    /// Smallest step of segment `k` (s).
    pub fn floor(&self, k: usize) -> Option<f64> {
        self.segments.get(k).map(|s| s.floor)
    }

    /// Halvings of the step being attempted.
    pub fn halvings(&self) -> usize {
        self.halvings
    }

    /// The size of the next step from time `t` (s), entering the next
    /// segment when `t` is at the current one's end; `None` when the
    /// schedule is done.
    pub fn next_step(&mut self, t: f64) -> Option<f64> {
        loop {
            let s = *self.segments.get(self.segment)?;
            let left = s.end - t;
            if left <= END_TOLERANCE * s.end.abs() {
                self.segment += 1;
                if let Some(next) = self.segments.get(self.segment) {
                    self.h = next.dt;
                    self.halvings = 0;
                }
                continue;
            }
            let c = self.h.min(s.dt_max);
            let step = if left <= c * (1.0 + END_TOLERANCE) {
                left
            } else if left < 1.5 * c {
                0.5 * left
            } else {
                c
            };
            self.last = step;
            return Some(step);
        }
    }

    /// The step handed out last converged in `iterations` Newton
    /// iterations: adapts `h` (see the type's docs). Returns the halvings
    /// this step needed.
    pub fn converged(&mut self, iterations: usize) -> usize {
        let halvings = std::mem::take(&mut self.halvings);
        if let Some(s) = self.segments.get(self.segment)
            && halvings == 0
        {
            if iterations <= EASY_ITERATIONS {
                self.h = (GROWTH * self.h).min(s.dt_max);
            } else if iterations >= HARD_ITERATIONS {
                self.h = (SHRINK * self.h).max(s.floor);
            }
        }
        halvings
    }

    /// The step handed out last failed: `true` if it is to be retried
    /// smaller (ask [`Self::next_step`] again), `false` if it was at the
    /// floor already and the run cannot go on.
    pub fn failed(&mut self) -> bool {
        let Some(s) = self.segments.get(self.segment) else {
            return false;
        };
        if self.last <= s.floor * (1.0 + END_TOLERANCE) {
            return false;
        }
        self.h = (SHRINK * self.last).max(s.floor);
        self.halvings += 1;
        true
    }
}

/// The watch of the rest criterion: counts the consecutive converged steps
/// ending at `t >= after` with every node slower than `speed`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestWatch {
    criterion: RestCriterion,
    still: usize,
}

impl RestWatch {
    /// A watch that has already counted `still` steps (0 for a new run; a
    /// checkpoint's count on resuming).
    pub fn new(criterion: RestCriterion, still: usize) -> Self {
        Self { criterion, still }
    }

    /// The criterion watched.
    pub fn criterion(&self) -> RestCriterion {
        self.criterion
    }

    /// Consecutive still steps counted so far.
    pub fn still_steps(&self) -> usize {
        self.still
    }

    /// After a converged step ending at `time` (s) whose fastest node moves
    /// at `fastest` (m/s): `true` once the run is at rest. A step before
    /// `after`, or with a node as fast as `speed` (or a NaN), starts the
    /// count again.
    pub fn observe(&mut self, time: f64, fastest: f64) -> bool {
        if time >= self.criterion.after && fastest < self.criterion.speed {
            self.still += 1;
        } else {
            self.still = 0;
        }
        self.still >= REST_STEPS
    }

    /// What a run that ended at rest says (`summary.json`'s message).
    pub fn message(&self, time: f64, steps: usize) -> String {
        format!(
            "at rest at t = {time:.6} s after {steps} steps: every node slower than {:e} m/s for {REST_STEPS} consecutive steps",
            self.criterion.speed
        )
    }
}

/// The largest node speed `max_a |V_a|` (m/s) of velocities flattened by
/// node; NaN if any is NaN, 0 for no node.
pub fn fastest_node(velocities: &[f64]) -> f64 {
    velocities
        .chunks_exact(3)
        .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
        .fold(0.0, |m, s| if s > m || s.is_nan() { s } else { m })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SplitMix64: a small deterministic generator, so that a failing
    /// case can be replayed from its seed.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
        /// Uniform in [0, 1).
        fn unit(&mut self) -> f64 {
            (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }
        /// Uniform in `lo..=hi`.
        fn int(&mut self, lo: usize, hi: usize) -> usize {
            lo + (self.next() % (hi - lo + 1) as u64) as usize
        }
        /// Log-uniform in [lo, hi).
        fn log(&mut self, lo: f64, hi: f64) -> f64 {
            lo * (hi / lo).powf(self.unit())
        }
    }

    /// What one random run of the controller did.
    #[derive(Default)]
    struct Tally {
        steps: usize,
        grew: usize,
        shrank: usize,
        failures: usize,
        gave_up: usize,
    }

    /// Runs the controller over a random schedule with random Newton
    /// iteration counts and failures, checking every step.
    fn random_run(seed: u64) -> Tally {
        let mut rng = Rng(seed);
        let segments: Vec<(usize, f64)> = (0..rng.int(1, 5))
            .map(|_| (rng.int(1, 40), rng.log(1e-5, 1e-1)))
            .collect();
        let largest = segments.iter().map(|s| s.1).fold(0.0, f64::max);
        let dt_max = (rng.unit() < 0.5).then(|| largest * rng.log(1.0, 30.0));
        let max_cutbacks = rng.int(0, 8);
        let fail_rate = [0.0, 0.05, 0.3][rng.int(0, 2)];
        let mut c = StepController::new(&segments, AdaptiveSteps { dt_max }, max_cutbacks);
        let mut tally = Tally::default();
        let mut t = 0.0;
        let mut segment = 0;
        let what = format!("seed {seed}: {segments:?}, dt_max {dt_max:?}");
        while let Some(step) = c.next_step(t) {
            // Entering a segment happens only at the previous one's end.
            while segment < c.segment() {
                let end = c.segment_end(segment).unwrap();
                assert!((t - end).abs() <= 1e-12 * end, "{what}: left {end} at {t}");
                segment += 1;
                assert_eq!(c.step_size(), segments[segment].1, "{what}: h on entry");
            }
            let (end, max, floor) = (
                c.segment_end(segment).unwrap(),
                c.dt_max(segment).unwrap(),
                c.floor(segment).unwrap(),
            );
            assert!(step > 0.0, "{what}: step {step}");
            assert!(step <= max, "{what}: step {step} > dt_max {max}");
            assert!(c.step_size() <= max, "{what}: h {} > {max}", c.step_size());
            assert!(c.step_size() >= floor, "{what}: h below the floor {floor}");
            assert!(
                t + step <= end * (1.0 + 1e-12),
                "{what}: {t} + {step} crosses {end}"
            );
            let h = c.step_size();
            if rng.unit() < fail_rate {
                tally.failures += 1;
                if c.failed() {
                    assert!(c.step_size() < step, "{what}: a retry no smaller");
                    continue;
                }
                // A run would end here; the test takes the step as
                // converged to go on checking the schedule.
                assert!(
                    step <= floor * (1.0 + 1e-12),
                    "{what}: gave up above the floor"
                );
                tally.gave_up += 1;
            }
            let iterations = rng.int(1, 12);
            let halvings = c.halvings();
            assert_eq!(c.converged(iterations), halvings);
            let after = c.step_size();
            if halvings > 0 {
                assert_eq!(after, h, "{what}: h changed after a cut-back step");
            } else if iterations <= EASY_ITERATIONS {
                assert_eq!(after, (1.5 * h).min(max), "{what}: no growth");
                tally.grew += usize::from(after > h);
            } else if iterations >= HARD_ITERATIONS {
                assert_eq!(after, (0.5 * h).max(floor), "{what}: no shrinking");
                tally.shrank += usize::from(after < h);
            } else {
                assert_eq!(after, h, "{what}: h changed after a middling step");
            }
            t += step;
            tally.steps += 1;
        }
        let end = c.end_time();
        assert!(
            (t - end).abs() <= 1e-12 * end,
            "{what}: ended at {t}, not {end}"
        );
        assert_eq!(c.segment(), segments.len());
        tally
    }

    /// Over many random schedules and random runs, no step crosses a
    /// segment's end, every segment ends at its end time (to 1e-12
    /// relative: the steps are summed in floating point), `h` stays within
    /// `[floor, dt_max]`, grows after easy steps and shrinks after hard
    /// ones. A failure at the floor, where a run would end, is taken as
    /// converged to go on. The tallies make sure the random runs exercised
    /// each rule.
    #[test]
    fn random_schedules_end_every_segment_on_time_and_adapt_h() {
        let mut total = Tally::default();
        for seed in 0..2000 {
            let t = random_run(seed);
            total.steps += t.steps;
            total.grew += t.grew;
            total.shrank += t.shrank;
            total.failures += t.failures;
            total.gave_up += t.gave_up;
        }
        assert!(
            total.grew > 1000 && total.shrank > 1000,
            "{} {}",
            total.grew,
            total.shrank
        );
        assert!(
            total.failures > 1000 && total.gave_up > 100,
            "{} {}",
            total.failures,
            total.gave_up
        );
    }

    /// The sliver rule: `dt = 0.01`, `dt_max = 0.016` over 0.22 s: 0.01,
    /// 0.015, eleven steps of 0.016, and the 0.019 s left in two halves of
    /// 0.0095 (not 0.016 and a sliver of 0.003).
    #[test]
    fn a_remainder_is_never_a_sliver() {
        let dt_max = Some(0.016);
        let mut c = StepController::new(&[(22, 0.01)], AdaptiveSteps { dt_max }, 3);
        let mut t = 0.0;
        let mut steps = Vec::new();
        while let Some(s) = c.next_step(t) {
            c.converged(1);
            t += s;
            steps.push(s);
        }
        let mut expected = vec![0.01, 0.015];
        expected.extend([0.016; 11]);
        expected.extend([0.0095; 2]);
        assert_eq!(steps.len(), expected.len(), "{steps:?}");
        for (s, e) in steps.iter().zip(&expected) {
            assert!((s - e).abs() < 1e-15, "{steps:?}");
        }
        assert!((t - 0.22).abs() < 1e-15, "{t}");
    }

    /// A failed step is retried at half its size down to the floor `dt /
    /// 2^max_cutbacks`, then the controller gives up; a failure at a grown
    /// `h` still reaches the floor.
    #[test]
    fn failures_halve_down_to_the_floor_then_give_up() {
        let mut c = StepController::new(&[(100, 0.01)], AdaptiveSteps { dt_max: None }, 2);
        let mut sizes = vec![c.next_step(0.0).unwrap()];
        while c.failed() {
            sizes.push(c.next_step(0.0).unwrap());
        }
        assert_eq!(sizes, [0.01, 0.005, 0.0025]);
        assert_eq!(c.halvings(), 2);
        // Grown to 0.03375 (three easy steps), a failure goes 0.016875,
        // 0.0084375, 0.00421875, then the floor 0.0025.
        let mut c = StepController::new(&[(100, 0.01)], AdaptiveSteps { dt_max: None }, 2);
        let mut t = 0.0;
        for _ in 0..3 {
            t += c.next_step(t).unwrap();
            c.converged(2);
        }
        assert!((c.step_size() - 0.03375).abs() < 1e-15);
        let mut sizes = vec![c.next_step(t).unwrap()];
        while c.failed() {
            sizes.push(c.next_step(t).unwrap());
        }
        assert_eq!(sizes.len(), 5, "{sizes:?}");
        assert_eq!(*sizes.last().unwrap(), 0.0025);
        // The step that converged after the cut-backs leaves h there.
        assert_eq!(c.converged(1), 4);
        assert_eq!(c.step_size(), 0.0025);
    }

    /// A checkpoint's segment and `h` are taken back, and values that do
    /// not fit the schedule are refused by name.
    #[test]
    fn resume_checks_segment_and_step_size() {
        let c = StepController::new(
            &[(10, 0.01), (10, 0.001)],
            AdaptiveSteps { dt_max: None },
            3,
        );
        let r = c.clone().resume(1, 0.004).unwrap();
        assert_eq!((r.segment(), r.step_size()), (1, 0.004));
        assert_eq!(c.clone().resume(1, 0.0).unwrap().step_size(), 0.001);
        assert!(c.clone().resume(2, 0.0).is_ok());
        let e = c.clone().resume(3, 0.001).unwrap_err();
        assert_eq!(
            e,
            ScheduleMismatch::Segment {
                segment: 3,
                segments: 2
            }
        );
        assert!(e.to_string().contains("segment 3"), "{e}");
        let e = c.clone().resume(1, 0.5).unwrap_err();
        assert!(matches!(
            e,
            ScheduleMismatch::StepSize {
                h: 0.5,
                segment: 1,
                ..
            }
        ));
        assert!(e.to_string().contains("step size 0.5"), "{e}");
        assert!(c.resume(0, f64::NAN).is_err());
    }

    /// The rest watch fires on the tenth consecutive still step at or after
    /// `after`, and a fast step (or a NaN) or one before `after` restarts
    /// the count.
    #[test]
    fn rest_needs_ten_consecutive_still_steps_after_the_start() {
        let mut w = RestWatch::new(
            RestCriterion {
                speed: 1e-3,
                after: 1.0,
            },
            0,
        );
        for k in 0..20 {
            assert!(!w.observe(0.5 + 0.01 * k as f64, 0.0), "before `after`");
        }
        for k in 0..9 {
            assert!(!w.observe(1.0 + k as f64, 5e-4));
        }
        assert!(!w.observe(10.0, 1e-3), "as fast as the speed");
        assert_eq!(w.still_steps(), 0);
        for k in 0..9 {
            assert!(!w.observe(11.0 + k as f64, 5e-4));
        }
        assert!(!w.observe(20.0, f64::NAN));
        for k in 0..9 {
            assert!(!w.observe(21.0 + k as f64, 5e-4));
        }
        assert!(w.observe(30.0, 5e-4));
        assert!(
            w.message(30.0, 99)
                .starts_with("at rest at t = 30.000000 s after 99 steps")
        );
    }

    #[test]
    fn fastest_node_is_the_largest_speed_and_propagates_nan() {
        assert_eq!(fastest_node(&[3.0, 4.0, 0.0, 0.0, -1.0, 0.0]), 5.0);
        assert_eq!(fastest_node(&[]), 0.0);
        assert!(fastest_node(&[f64::NAN, 0.0, 0.0, 9.0, 0.0, 0.0]).is_nan());
        assert!(fastest_node(&[9.0, 0.0, 0.0, f64::NAN, 0.0, 0.0]).is_nan());
    }
}
