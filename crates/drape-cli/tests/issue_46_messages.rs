//! Issue 46: a refused run leaves nothing behind, and the small messages —
//! negative numbers reach the commands' own checks, obstacles are numbered
//! as `check` numbers them, a missing path is called missing.

mod issue_19_support;

use issue_19_support::{DRAPE, falling_plate, run_into as run, scratch, text};
use std::process::{Command, Stdio};

/// A fresh run refused for a file of the user's leaves the directory as it
/// found it: no `drape.lock` (it made one before it looked).
#[test]
fn a_refused_run_leaves_no_lock_behind() {
    let dir = scratch("i46-refused");
    let scenario = falling_plate(&dir, 3, "");
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let o = run(&scenario, &out);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("notes.txt"), "{}", text(&o.stderr));
    let left: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["notes.txt"]);
    // Moved away, the run goes through (the directory is not taken for
    // drape's by a lock file left from the refusal).
    std::fs::remove_file(out.join("notes.txt")).unwrap();
    let o = run(&scenario, &out);
    assert!(o.status.success(), "{}", text(&o.stderr));
    // A directory drape wrote into before keeps its lock file when a
    // later run is refused: it is drape's.
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let o = run(&scenario, &out);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(out.join("drape.lock").is_file() && out.join("summary.json").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// An empty output directory is refused by the library before anything is
/// created (from the command line clap refuses `--out ""` first; Python
/// reaches the library with `out=""`).
#[test]
fn an_empty_output_directory_is_refused_naming_it() {
    use drape::output::directory::{DirectoryError, lock, lock_resume};
    let dir = scratch("i46-empty");
    for taken in [
        lock(std::path::Path::new("")),
        lock_resume(std::path::Path::new("")),
    ] {
        match taken {
            Err(e @ DirectoryError::Empty) => {
                assert!(e.to_string().contains(r#""" is an empty path"#), "{e}")
            }
            other => panic!("{other:?}"),
        }
    }
    let o = Command::new(DRAPE)
        .args(["run", "fall.toml", "--out", ""])
        .current_dir(&dir)
        .stdin(Stdio::null())
        .output()
        .expect("spawn drape");
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(!dir.join("drape.lock").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `drape ARGS` with the output directory `out` where the arguments say
/// `DIR`; its exit code and standard error.
fn drape_on(out: &std::path::Path, args: &[&str]) -> (Option<i32>, String) {
    let args: Vec<&std::ffi::OsStr> = args
        .iter()
        .map(|a| {
            if *a == "DIR" {
                out.as_os_str()
            } else {
                a.as_ref()
            }
        })
        .collect();
    let o = issue_19_support::drape(&args);
    (o.status.code(), text(&o.stderr))
}

/// Negative numbers reach the commands' own checks (clap took `-0.01` for
/// an option and said "unexpected argument '-0'"); `--step -1` is the last
/// frame, as `positions(step=-1)` in Python.
#[test]
fn negative_numbers_reach_the_commands_checks() {
    let dir = scratch("i46-negative");
    let scenario = falling_plate(&dir, 4, "[output]\nevery = 2\n");
    let out = dir.join("out");
    assert!(run(&scenario, &out).status.success());
    for (args, said) in [
        (
            &[
                "measure",
                "DIR",
                "--pedestal-radius",
                "-0.01",
                "--specimen-radius",
                "0.05",
            ][..],
            "pedestal radius",
        ),
        (
            &[
                "measure",
                "DIR",
                "--pedestal-radius",
                "0.01",
                "--specimen-radius",
                "-1",
            ][..],
            "specimen radius",
        ),
        (&["measure", "DIR", "--step", "-2"][..], "-2 is not a step"),
        (&["render", "DIR", "--step", "-2"][..], "-2 is not a step"),
        (
            &["render", "DIR", "--panels", "-1", "--grid"][..],
            "invalid digit",
        ),
    ] {
        let (code, e) = drape_on(&out, args);
        assert_eq!(code, Some(2), "{args:?}: {e}");
        assert!(!e.contains("unexpected argument"), "{args:?}: {e}");
        assert!(e.contains(said), "{args:?}: {e}");
    }
    // -1: the last frame, the one written without --step.
    let png = dir.join("last.png");
    let (code, e) = drape_on(
        &out,
        &["render", "DIR", "--step", "-1", "-o", png.to_str().unwrap()],
    );
    assert_eq!(code, Some(0), "{e}");
    let default = dir.join("default.png");
    let (code, e) = drape_on(&out, &["render", "DIR", "-o", default.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{e}");
    assert_eq!(
        std::fs::read(&png).unwrap(),
        std::fs::read(&default).unwrap()
    );
    let (code, e) = drape_on(
        &out,
        &["render", "DIR", "--step", "4", "-o", png.to_str().unwrap()],
    );
    assert_eq!(code, Some(0), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// measure, render and plot of a path that does not exist say so (they
/// said "not a directory"); of a file, that it is not a directory.
#[test]
fn a_missing_output_directory_is_called_missing() {
    let dir = scratch("i46-missing");
    let missing = dir.join("nowhere");
    let file = dir.join("a-file");
    std::fs::write(&file, "mine").unwrap();
    for command in ["measure", "render", "plot"] {
        let (code, e) = drape_on(&missing, &[command, "DIR"]);
        assert_eq!(code, Some(2), "{command}: {e}");
        assert!(e.contains("does not exist"), "{command}: {e}");
        assert!(!e.contains("not a directory"), "{command}: {e}");
        let (code, e) = drape_on(&file, &[command, "DIR"]);
        assert_eq!(code, Some(2), "{command}: {e}");
        assert!(e.contains("not a directory"), "{command}: {e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--resume` of a completed run that kept no checkpoint says there is
/// nothing to resume (it said "cannot read the checkpoint: No such file"),
/// and leaves the run's outputs as they were. With a checkpoint a resume
/// computes the steps after it again (tests/resume.rs).
#[test]
fn resuming_a_completed_run_without_a_checkpoint_says_nothing_is_left() {
    let dir = scratch("i46-completed");
    let scenario = falling_plate(&dir, 4, "");
    let out = dir.join("out");
    assert!(run(&scenario, &out).status.success());
    let summary = std::fs::read(out.join("summary.json")).unwrap();
    let history = std::fs::read(out.join("history.csv")).unwrap();
    let (code, e) = drape_on(&out, &["run", "--resume", "DIR"]);
    assert_eq!(code, Some(2), "{e}");
    assert!(
        e.contains("nothing to resume: the run completed") && e.contains("(without --resume)"),
        "{e}"
    );
    assert!(!e.contains("cannot read"), "{e}");
    assert_eq!(std::fs::read(out.join("summary.json")).unwrap(), summary);
    assert_eq!(std::fs::read(out.join("history.csv")).unwrap(), history);
    let _ = std::fs::remove_dir_all(&dir);
}
