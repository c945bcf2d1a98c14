//! Issue 46: a stop asked for reaches the step under way. The run's stop
//! flag is watched while a step is solved, and Newton's interrupt ends the
//! solve at its next iteration or line-search trial — not at the end of a
//! step that may never end. An interrupted run keeps a checkpoint of a
//! state a resume can start from, and goes on to the uninterrupted run's
//! history, byte for byte.

mod common;

use common::{setup, temp_dir};
use drape::simulation::{self, RunControl, RunError};
use std::sync::atomic::AtomicBool;

/// A pinned sheet falling, with fixed steps or adaptive ones.
fn sheet(time: &str) -> String {
    common::rectangle(
        [0.1, 0.1],
        [6, 6],
        &format!(
            "[[load]]\nkind = \"gravity\"\nacceleration = [0.0, 0.0, -9.81]\n\
             [[fix]]\nat = [0.05, 0.05, 0.0]\n[time]\n{time}"
        ),
    )
}

/// With the stop asked for before the first step, the first step's solve
/// is interrupted (not stepped, not cut back): 0 steps, `"interrupted"`,
/// a checkpoint of the initial state; resumed, the run ends with the
/// uninterrupted history.
#[test]
fn a_stop_reaches_the_step_under_way_and_the_run_resumes_bit_for_bit() {
    for time in [
        "segments = [{ steps = 8, dt = 1.0e-3 }]\n",
        "segments = [{ steps = 8, dt = 1.0e-3 }]\nadaptive = true\n",
    ] {
        let text = sheet(time);
        let whole = temp_dir("interrupt-whole");
        simulation::run(&setup(&text), &whole, &mut |_| {}).unwrap();
        let cut = temp_dir("interrupt-cut");
        let stop = AtomicBool::new(true);
        let control = RunControl {
            stop: Some(&stop),
            ..RunControl::default()
        };
        let mut steps = 0;
        let e =
            simulation::run_with(&setup(&text), &cut, &mut |_| steps += 1, control).unwrap_err();
        assert!(matches!(e, RunError::Interrupted { .. }), "{e}");
        assert_eq!(steps, 0, "{time}");
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(cut.join("summary.json")).unwrap()).unwrap();
        assert_eq!(summary["status"], "interrupted");
        assert_eq!(summary["steps"], 0);
        assert!(cut.join("checkpoint.bin").is_file());
        let control = RunControl {
            resume: true,
            ..RunControl::default()
        };
        simulation::run_with(&setup(&text), &cut, &mut |_| {}, control).unwrap();
        assert_eq!(
            std::fs::read(whole.join("history.csv")).unwrap(),
            std::fs::read(cut.join("history.csv")).unwrap(),
            "{time}"
        );
    }
}
