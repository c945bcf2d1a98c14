//! Issue 19: once a run holds its output directory, every failure leaves a
//! `summary.json` that says `"failed"` and why — a frame or a history row
//! that cannot be written (the summary then describes the history on
//! disk), a resume refused for a changed scenario (for a changed input
//! file: `resume_inputs.rs`) — and a
//! resume that is refused never creates or takes over a directory that is
//! not a run's.

mod issue_19_support;

use issue_19_support::{
    DRAPE, drape as drape_args, falling_plate, history_rows, scratch, send, spawn_run, summary,
    text, wait_for_history,
};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

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
    let child = spawn_run(&scenario, &out);
    // Wait for a few steps, then take the frames' folder away.
    wait_for_history(&out, 20);
    std::fs::rename(out.join("fields"), dir.join("fields.moved")).unwrap();
    std::fs::write(out.join("fields"), "not a folder").unwrap();
    let o = child.wait_with_output().expect("wait for drape");
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    let s = summary(&out);
    assert_eq!(s["status"], "failed", "{s}");
    let message = s["message"].as_str().unwrap();
    assert!(message.contains("fields/step_"), "{message}");
    // The frame written between the rename and the file's creation finds
    // no folder at all: either error is the frame's.
    assert!(
        message.contains("Not a directory") || message.contains("No such file or directory"),
        "{message}"
    );
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

/// The rows of `history.csv` after its header, as numbers by column name.
fn history_table(out: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(out.join("history.csv")).expect("history.csv");
    let mut lines = text.lines();
    let columns = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (columns, rows)
}

/// The number of the top-level `key` in a summary's text, parsed by Rust:
/// serde_json's own float parsing (without its `float_roundtrip` feature)
/// may be one unit in the last place off.
fn number(summary: &str, key: &str) -> f64 {
    let at = summary.find(&format!("\"{key}\": ")).expect(key) + key.len() + 4;
    let rest = &summary[at..];
    rest[..rest.find([',', '\n']).unwrap()].parse().unwrap()
}

/// A history row that cannot be written (here: the file would pass the
/// process's file-size limit, `RLIMIT_FSIZE`, with `SIGXFSZ` ignored, so
/// the write fails with "File too large" as on a full disk): the run exits
/// 1 and its summary says "failed", names the history, counts the rows the
/// history holds — the step whose row failed is not counted — and reports
/// the last row's time and energies; the part of the row that was written
/// is cut off again.
#[cfg(unix)]
#[test]
fn a_history_row_that_cannot_be_written_is_in_the_summary() {
    let dir = scratch("why-history");
    // A frame only at the start (and the end): the history is the file
    // that grows, about 300 bytes a row.
    let scenario = falling_plate(&dir, 1000, "[output]\nevery = 100000");
    let out = dir.join("out");
    const LIMIT: u64 = 16 * 1024;
    let o = drape_with_file_limit(
        &[
            "run".as_ref(),
            scenario.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ],
        LIMIT,
    );
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    let s = summary(&out);
    assert_eq!(s["status"], "failed", "{s}");
    let message = s["message"].as_str().unwrap();
    assert!(message.contains("history.csv"), "{message}");
    assert!(message.contains("File too large"), "{message}");
    let bytes = std::fs::read(out.join("history.csv")).unwrap();
    assert!(
        bytes.len() as u64 <= LIMIT && bytes.ends_with(b"\n"),
        "the history ends in part of a row"
    );
    let (columns, rows) = history_table(&out);
    assert!(rows.len() > 10 && rows.len() < 1001, "{} rows", rows.len());
    // The summary describes the history's last row: its step, its time
    // and its energies, to the last bit.
    assert_eq!(s["steps"].as_u64().unwrap() as usize + 1, rows.len());
    let last = rows.last().unwrap();
    let column = |name: &str| last[columns.iter().position(|c| c == name).unwrap()];
    assert_eq!(column("step"), s["steps"].as_f64().unwrap());
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    for key in ["time", "kinetic_energy", "strain_energy", "external_work"] {
        assert_eq!(number(&text, key), column(key), "{key}");
    }
    assert_eq!(
        s["newton_iterations"].as_f64().unwrap(),
        rows.iter()
            .map(|r| r[columns.iter().position(|c| c == "iterations").unwrap()])
            .sum::<f64>()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `drape ARGS --quiet` with files limited to `limit` bytes
/// (`RLIMIT_FSIZE`; SIGXFSZ ignored, so a write past it fails with EFBIG).
fn drape_with_file_limit(args: &[&OsStr], limit: u64) -> Output {
    use std::os::unix::process::CommandExt;
    let mut command = Command::new(DRAPE);
    command.args(args).arg("--quiet").stdin(Stdio::null());
    // SAFETY: between fork and exec the closure only calls signal(2) and
    // setrlimit(2), which are async-signal-safe.
    unsafe {
        command.pre_exec(move || {
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            let limit = libc::rlimit {
                rlim_cur: limit as libc::rlim_t,
                rlim_max: limit as libc::rlim_t,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    command.output().expect("spawn drape")
}

/// A resumed session whose first history row cannot be written: the
/// summary describes the history's last row — the checkpoint's, where the
/// interrupted session stopped — not the step the resumed session
/// computed and could not record.
#[test]
fn a_resume_whose_first_row_cannot_be_written_reports_the_checkpoint() {
    let dir = scratch("why-resume-row");
    let scenario = falling_plate(&dir, 1_000_000, "[output]\nevery = 100000");
    let out = dir.join("out");
    let child = spawn_run(&scenario, &out);
    wait_for_history(&out, 20);
    send(&child, "TERM");
    let o = child.wait_with_output().expect("wait for drape");
    assert_eq!(o.status.code(), Some(143), "{}", stderr(&o));
    let (_, before) = history_table(&out);
    // Room for less than a row: the resumed session's first row fails.
    let size = std::fs::metadata(out.join("history.csv")).unwrap().len();
    let o = drape_with_file_limit(
        &["run".as_ref(), "--resume".as_ref(), out.as_os_str()],
        size + 10,
    );
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    let s = summary(&out);
    assert_eq!(s["status"], "failed", "{s}");
    assert!(
        s["message"].as_str().unwrap().contains("history.csv"),
        "{s}"
    );
    let (columns, rows) = history_table(&out);
    assert_eq!(rows.len(), before.len(), "the history is the checkpoint's");
    assert_eq!(s["steps"].as_u64().unwrap() as usize + 1, rows.len());
    let last = rows.last().unwrap();
    let column = |name: &str| last[columns.iter().position(|c| c == name).unwrap()];
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    for key in ["time", "kinetic_energy", "strain_energy", "external_work"] {
        assert_eq!(number(&text, key), column(key), "{key}");
    }
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
