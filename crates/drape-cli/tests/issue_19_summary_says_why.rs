//! Issue 19: once a run holds its output directory, every failure leaves a
//! `summary.json` that says `"failed"` and why — a frame that cannot be
//! written, a resume refused for a changed scenario (for a changed input
//! file: `resume_inputs.rs`) — and a
//! resume that is refused never creates or takes over a directory that is
//! not a run's.

mod issue_19_support;

use issue_19_support::{DRAPE, drape as drape_args, falling_plate, scratch, text};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The plate of [`falling_plate`], a frame every step and a checkpoint
/// every 5.
fn scenario(dir: &Path, steps: usize) -> PathBuf {
    falling_plate(dir, steps, "[output]\nevery = 1\ncheckpoint_every = 5")
}

/// `drape ARGS --quiet`.
fn drape(args: &[&std::ffi::OsStr]) -> Output {
    let mut all = args.to_vec();
    all.push("--quiet".as_ref());
    drape_args(&all)
}

fn stderr(o: &Output) -> String {
    text(&o.stderr)
}

/// Makes the summary of a completed run in `out` say "interrupted", as
/// if the run had been stopped at its last checkpoint.
fn mark_interrupted(out: &Path) {
    let mut s = summary(out);
    s["status"] = "interrupted".into();
    std::fs::write(out.join("summary.json"), s.to_string()).unwrap();
}

fn summary(out: &Path) -> Value {
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

/// Rows of `history.csv` after its header.
fn history_rows(out: &Path) -> usize {
    std::fs::read_to_string(out.join("history.csv"))
        .expect("history.csv")
        .lines()
        .count()
        - 1
}

/// `fields/` replaced by a file while the run writes its frames: the run
/// exits 1 and its summary says "failed", names the frame it could not
/// write and counts the steps the history holds. (Running as root, a
/// directory made read-only would still be written; a file in its place
/// fails for everybody.)
#[test]
fn a_frame_that_cannot_be_written_is_in_the_summary() {
    let dir = scratch("why-frame");
    let scenario = scenario(&dir, 1_000_000);
    let out = dir.join("out");
    let child = Command::new(DRAPE)
        .arg("run")
        .arg(&scenario)
        .arg("--out")
        .arg(&out)
        .arg("--quiet")
        .stdin(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn drape");
    // Wait for a few steps, then take the frames' folder away.
    let start = Instant::now();
    while std::fs::read_to_string(out.join("history.csv")).map_or(0, |t| t.lines().count()) < 20 {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the run did not start"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    std::fs::rename(out.join("fields"), dir.join("fields.moved")).unwrap();
    std::fs::write(out.join("fields"), "not a folder").unwrap();
    let o = child.wait_with_output().expect("wait for drape");
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    let s = summary(&out);
    assert_eq!(s["status"], "failed", "{s}");
    let message = s["message"].as_str().unwrap();
    assert!(message.contains("fields/step_"), "{message}");
    assert!(message.contains("Not a directory"), "{message}");
    assert!(
        e.contains(message),
        "stderr {e:?} says what the summary says"
    );
    // The summary counts what the history holds (step 0 is a row too).
    assert_eq!(
        s["steps"].as_u64().unwrap() as usize + 1,
        history_rows(&out)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// An interrupted run whose scenario is edited: the resume is refused
/// (exit 2) and the summary says so, keeping the interrupted session's
/// counts; with the scenario restored the resume goes through and the
/// summary says "completed".
#[test]
fn a_refused_resume_is_in_the_summary_and_a_good_one_replaces_it() {
    let dir = scratch("why-scenario");
    let scenario = scenario(&dir, 12);
    let out = dir.join("out");
    // Stop the run at its checkpoint: a run of 10 steps is the first 10
    // steps of the run of 12, and a summary "interrupted" is forged.
    let text = std::fs::read_to_string(&scenario).unwrap();
    std::fs::write(&scenario, text.replace("steps = 12", "steps = 10")).unwrap();
    let o = drape(&[
        "run".as_ref(),
        scenario.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::write(&scenario, &text).unwrap();
    // The checkpoint (at step 10) is of the 10-step scenario: refused.
    let o = drape(&["run".as_ref(), "--resume".as_ref(), out.as_os_str()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // A completed run's summary stays as it is.
    assert_eq!(summary(&out)["status"], "completed");

    mark_interrupted(&out);
    let o = drape(&["run".as_ref(), "--resume".as_ref(), out.as_os_str()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["status"], "failed", "{s}");
    let message = s["message"].as_str().unwrap();
    assert!(message.starts_with("cannot resume"), "{message}");
    assert!(message.contains("the scenario has changed"), "{message}");
    assert_eq!(s["steps"], 10, "the interrupted session's counts are kept");
    assert_eq!(history_rows(&out), 11, "the history is left as it was");

    // The scenario of the checkpoint again: resumed to the end.
    std::fs::write(&scenario, text.replace("steps = 12", "steps = 10")).unwrap();
    let o = drape(&["run".as_ref(), "--resume".as_ref(), out.as_os_str()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(summary(&out)["status"], "completed");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--resume` of a directory that does not exist, or that holds no run,
/// is refused (exit 2) and leaves nothing behind.
#[test]
fn a_resume_of_no_run_writes_nothing() {
    let dir = scratch("why-none");
    let missing = dir.join("missing");
    let o = drape(&["run".as_ref(), "--resume".as_ref(), missing.as_os_str()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("no such directory"), "{}", stderr(&o));
    assert!(!missing.exists(), "--resume created {}", missing.display());
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let scenario = scenario(&dir, 3);
    let o = drape(&[
        "run".as_ref(),
        scenario.as_os_str(),
        "--resume".as_ref(),
        empty.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("holds no drape run"), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_dir(&empty).unwrap().count(),
        0,
        "a file written into a directory that held no run"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
