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
