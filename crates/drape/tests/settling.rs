//! Settling to rest (the README's `[time]` reference): adaptive time steps and the rest
//! criterion on whole runs. The controller's own rules are unit-tested in
//! `simulation/schedule.rs`.

mod common;

use common::{column, read_history, rectangle, setup, temp_dir};
use drape::simulation::{self, Checkpoint, RunControl, RunError, Summary, checkpoint_path};
use std::path::Path;

/// The cloth of `scenarios/hanging-from-edge.toml` (10 x 10 cm hanging
/// from one edge, `beta = 1, gamma = 1.5`) with `time`, the rest of its
/// `[time]` table.
fn hanging_cloth(time: &str) -> String {
    hanging_cloth_with_output(time, "")
}

/// [`hanging_cloth`] with `output` in its `[output]` table too.
fn hanging_cloth_with_output(time: &str, output: &str) -> String {
    let cloth = include_str!("scenarios/hanging-from-edge.toml");
    format!("{cloth}{time}\n[output]\nevery = 1000\n{output}\n")
}

/// Runs scenario text into a fresh directory; returns the summary and the
/// history (header, rows).
fn run(text: &str, name: &str) -> (Summary, Vec<String>, Vec<Vec<f64>>) {
    let dir = temp_dir(name);
    let summary = simulation::run(&setup(text), &dir, &mut |_| {}).unwrap();
    let (header, rows) = read_history(&dir);
    (summary, header, rows)
}

/// The mass of a 10 x 10 cm cloth of 0.6 mm at 320 kg/m^3 (kg).
const CLOTH_MASS: f64 = 0.1 * 0.1 * 0.6e-3 * 320.0;

/// The damped hanging cloth comes to rest well before the schedule's end
/// (20 s): the run ends completed, says "at rest", and its last ten steps
/// carry at most the kinetic energy of every node at the rest speed,
/// `K = 1/2 V.M V <= 1/2 m max|V_a|^2` (the consistent mass matrix of
/// linear triangles has no negative entry, so `V.M V <= max|V_a|^2 sum
/// M_ab`): a bound from the mechanics, not from an earlier run. It gets
/// there with long steps, up to `dt_max`, once the swing has died out.
#[test]
fn damped_hanging_cloth_comes_to_rest() {
    let speed = 1.0e-4;
    let text = hanging_cloth(&format!(
        "segments = [{{ steps = 2000, dt = 0.01 }}]\nadaptive = true\ndt_max = 0.1\nrest = {{ speed = {speed:e}, after = 0.2 }}"
    ));
    let (summary, h, rows) = run(&text, "rest");
    eprintln!("{}", summary.message);
    assert_eq!(summary.status, "completed");
    assert_eq!(summary.at_rest, Some(true));
    assert!(summary.message.contains("at rest"), "{}", summary.message);
    assert!(summary.time < 20.0 - 1.0, "{}", summary.time);
    let time = column(&h, &rows, "time");
    let kinetic = column(&h, &rows, "kinetic_energy");
    let dt = column(&h, &rows, "dt");
    assert_eq!(*time.last().unwrap(), summary.time);
    let bound = 0.5 * CLOTH_MASS * speed * speed;
    for k in rows.len() - 10..rows.len() {
        assert!(
            kinetic[k] <= bound,
            "t = {}: K = {:e} J above {bound:e} J",
            time[k],
            kinetic[k]
        );
        assert!(time[k] >= 0.2);
    }
    // The steps grew to dt_max, ten times the segment's dt.
    let longest = dt.iter().fold(0.0f64, |a, &b| a.max(b));
    assert!(longest > 0.09 && longest <= 0.1, "longest step {longest}");
}

/// A strip pinned at one end swinging in its plane under gravity, with the
/// trapezoidal rule (`beta = 0.25, gamma = 0.5`, which conserves its
/// energy): at each end of its swing every node stops for an instant, but
/// never for ten consecutive steps, so the run goes to the schedule's end
/// and is not at rest, with adaptive steps as with fixed ones.
#[test]
fn swinging_pendulum_is_never_at_rest() {
    let text = |time: &str| {
        rectangle(
            [0.1, 0.02],
            [10, 2],
            &format!(
                r#"
[[load]]
kind = "gravity"
acceleration = [0.0, -9.8, 0.0]
[[fix]]
at = [-0.05, 0.0, 0.0]
[time]
beta = 0.25
gamma = 0.5
segments = [{{ steps = 1000, dt = 0.002 }}]
rest = {{ speed = 1.0e-3 }}
{time}
[output]
every = 1000
"#
            ),
        )
    };
    for (name, time) in [
        ("fixed", ""),
        ("adaptive", "adaptive = true\ndt_max = 0.004"),
    ] {
        let (summary, h, rows) = run(&text(time), name);
        assert_eq!(summary.status, "completed", "{name}: {}", summary.message);
        assert_eq!(summary.at_rest, Some(false), "{name}");
        assert!(!summary.message.contains("at rest"), "{}", summary.message);
        assert!(
            (summary.time - 2.0).abs() < 1e-12,
            "{name}: {}",
            summary.time
        );
        // It swung all along: its kinetic energy came back up to a third of
        // the largest within the last swing (period about 0.5 s).
        let time = column(&h, &rows, "time");
        let kinetic = column(&h, &rows, "kinetic_energy");
        let most = kinetic.iter().fold(0.0f64, |a, &b| a.max(b));
        let late = time
            .iter()
            .zip(&kinetic)
            .filter(|(t, _)| **t > 1.5)
            .fold(0.0f64, |a, (_, &k)| a.max(k));
        assert!(late > most / 3.0, "{name}: {late:e} J of {most:e} J");
    }
}

/// With adaptive steps every segment still ends at its own end time: the
/// hanging cloth over three segments, with rows at 6, 6.1 and 8.1 s (to
/// round-off) although the steps have grown long by 6 s; no step longer
/// than `dt_max` (default: 10 x each segment's dt), none across a
/// segment's end, and each segment starts again at its own dt.
#[test]
fn adaptive_steps_end_every_segment_on_time() {
    let text = hanging_cloth(
        "segments = [{ steps = 300, dt = 0.02 }, { steps = 10, dt = 0.01 }, { steps = 100, dt = 0.02 }]\nadaptive = true",
    );
    let (summary, h, rows) = run(&text, "segments");
    assert_eq!(summary.status, "completed");
    let time = column(&h, &rows, "time");
    let dt = column(&h, &rows, "dt");
    let ends = [6.0, 6.1, 8.1];
    let mut entered = 0;
    for k in 1..time.len() {
        let (t0, t1) = (time[k - 1], time[k]);
        let segment = ends
            .iter()
            .position(|&e| t0 < e * (1.0 - 1e-12))
            .expect("a step after the schedule's end");
        let (max, first) = ([0.2, 0.1, 0.2][segment], [0.02, 0.01, 0.02][segment]);
        assert!(dt[k] <= max, "step {k}: dt {} > {max}", dt[k]);
        let end = ends[segment];
        assert!(
            t1 <= end * (1.0 + 1e-12),
            "step {k}: {t0} -> {t1} crosses {end}"
        );
        if segment > 0 && (t0 - ends[segment - 1]).abs() <= 1e-12 * t0 {
            assert_eq!(dt[k], first, "step {k} enters segment {segment}");
            entered += 1;
        }
    }
    assert_eq!(entered, 2);
    for end in ends {
        assert!(
            time.iter().any(|t| (t - end).abs() <= 1e-12 * end),
            "no row at {end}"
        );
    }
    let before = dt
        .iter()
        .zip(&time)
        .filter(|(_, t)| **t <= 6.0)
        .fold(0.0f64, |a, (&d, _)| a.max(d));
    assert!(before > 0.1, "the steps did not grow ({before})");
}

/// The fabric-on-pedestal example (contact, stress projection) over its
/// free fall and 30 fine steps: `adaptive = false` written out gives the
/// same history, byte for byte, as the scenario without the key — the
/// fixed schedule is untouched — and `adaptive = true` another.
#[test]
fn adaptive_false_is_the_fixed_schedule_bit_for_bit() {
    let example =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fabric-on-pedestal.toml");
    let text = std::fs::read_to_string(example).unwrap().replace(
        "{ steps = 450, dt = 1.0e-4 }",
        "{ steps = 30, dt = 1.0e-4 }",
    );
    let with = |key: &str| {
        let edited = text.replace("gamma = 1.5\n", &format!("gamma = 1.5\n{key}\n"));
        assert_ne!(edited, text);
        edited
    };
    let history = |text: &str, name: &str| {
        let dir = temp_dir(name);
        simulation::run(&setup(text), &dir, &mut |_| {}).unwrap();
        std::fs::read(dir.join("history.csv")).unwrap()
    };
    let plain = history(&text, "plain");
    assert_eq!(plain, history(&with("adaptive = false"), "fixed"));
    assert_ne!(plain, history(&with("adaptive = true"), "adaptive"));
}

/// A checkpoint whose adaptive-step values do not fit the scenario's
/// schedule is refused, naming the value, before anything on disk is
/// touched: a segment the schedule does not have, a step size beyond
/// `dt_max`.
#[test]
fn a_checkpoint_that_does_not_fit_the_schedule_is_refused() {
    let text = hanging_cloth_with_output(
        "segments = [{ steps = 20, dt = 0.01 }]\nadaptive = true",
        "checkpoint_every = 10",
    );
    let s = setup(&text);
    let dir = temp_dir("refused");
    simulation::run(&s, &dir, &mut |_| {}).unwrap();
    let path = checkpoint_path(&dir);
    let bodies = 0;
    let good = std::fs::read(&path).unwrap();
    let history = std::fs::read(dir.join("history.csv")).unwrap();
    // (segment, step size) written into the checkpoint, and what the
    // refusal must say.
    for (segment, step_size, says) in [(3, 0.01, "segment 3"), (0, 0.5, "step size 0.5")] {
        let mut ck =
            Checkpoint::from_bytes(&good, s.model.dofs(), bodies, s.scenario_hash).unwrap();
        ck.counters.segment = segment;
        ck.counters.step_size = step_size;
        std::fs::write(&path, ck.to_bytes()).unwrap();
        let control = RunControl {
            stop: None,
            resume: true,
            ..Default::default()
        };
        match simulation::run_with(&s, &dir, &mut |_| {}, control) {
            Err(e @ RunError::Resume { .. }) => assert!(e.to_string().contains(says), "{e}"),
            other => panic!("{says}: {other:?}"),
        }
        assert!(std::fs::read(dir.join("history.csv")).unwrap() == history);
    }
}

/// Issue 44: `[solver] linear = "compact"` (CG preconditioned by the
/// factor of the Hessian's compact part, the mass term dominating) follows
/// the direct factorisation's trajectory of a swinging cloth with bending
/// (union jack, whose bending stencils reach beyond each node's
/// triangles) to the Newton tolerance: the same steps, and every energy
/// of the history within 1e-8 of the largest, after 0.3 s of swing.
#[test]
fn compact_solves_follow_the_direct_trajectory() {
    let cloth = include_str!("scenarios/hanging-from-edge.toml").replace(
        "thickness = 0.6e-3",
        "thickness = 0.6e-3\nbending_rigidity = 1.0e-5",
    );
    let text = |linear: &str| {
        format!(
            "{cloth}segments = [{{ steps = 60, dt = 0.005 }}]\n[output]\nevery = 1000\n[solver]\nlinear = \"{linear}\"\n"
        )
    };
    let (direct, header, rows_direct) = run(&text("direct"), "direct");
    let (compact, _, rows_compact) = run(&text("compact"), "compact");
    eprintln!(
        "Newton iterations: direct {}, compact {}; CG iterations {}",
        direct.newton_iterations, compact.newton_iterations, compact.linear.krylov_iterations
    );
    assert!(compact.linear.krylov_iterations > 0, "{:?}", compact.linear);
    assert_eq!(rows_direct.len(), rows_compact.len());
    for name in ["kinetic_energy", "strain_energy", "external_work"] {
        let (d, c) = (
            column(&header, &rows_direct, name),
            column(&header, &rows_compact, name),
        );
        let scale = d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let gap = d
            .iter()
            .zip(&c)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        eprintln!("{name}: largest {scale:.3e} J, largest difference {gap:.2e} J");
        assert!(gap <= 1e-8 * scale, "{name}: {gap:e} against {scale:e}");
    }
}
