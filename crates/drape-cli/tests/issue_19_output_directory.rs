//! Issue 19: the output directory is drape's own — one writer at a time, a
//! fresh run that clears its previous outputs, and nobody else's files
//! touched.

mod issue_19_support;

use issue_19_support::{DRAPE, falling_plate, run_into as run, scratch, text};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A tiny scenario (a 4 x 4 patch falling for 3 steps) written into `dir`.
fn tiny_scenario(dir: &Path) -> PathBuf {
    falling_plate(dir, 3, "")
}

fn stderr(o: &Output) -> String {
    text(&o.stderr)
}

/// While another process holds the directory (here the test itself, a
/// process other than the drape it starts), a run and a resume are refused
/// at once with exit 2, naming the directory and the holder's process id;
/// once it lets go, the run goes through.
#[test]
fn a_second_process_on_one_directory_is_refused() {
    let dir = scratch("busy");
    let scenario = tiny_scenario(&dir);
    let out = dir.join("out");
    assert!(run(&scenario, &out).status.success());
    let held = drape::output::directory::lock(&out).expect("the directory is free");
    let o = run(&scenario, &out);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("in use by another drape process"), "{e}");
    assert!(
        e.contains(&format!("process {}", std::process::id())),
        "{e}"
    );
    assert!(e.contains(&out.display().to_string()), "{e}");
    let resume = Command::new(DRAPE)
        .args(["run", "--resume"])
        .arg(&out)
        .stdin(std::process::Stdio::null())
        .output()
        .expect("spawn drape");
    assert_eq!(resume.status.code(), Some(2), "{}", stderr(&resume));
    assert!(
        stderr(&resume).contains("in use by another drape process"),
        "{}",
        stderr(&resume)
    );
    drop(held);
    let o = run(&scenario, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A fresh run into a directory with somebody else's file — or with a
/// `scenario.toml` drape did not write — is refused with exit 2 naming the
/// file, and leaves it alone; `--out` naming a regular file is an input
/// error too.
#[test]
fn a_directory_with_foreign_files_is_refused() {
    let dir = scratch("foreign");
    let scenario = tiny_scenario(&dir);
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("scenario.toml"), "my own notes").unwrap();
    let o = run(&scenario, &out);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("scenario.toml"), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(out.join("scenario.toml")).unwrap(),
        "my own notes"
    );
    // The scenario's own folder, holding the scenario only, is fine.
    let alone = scratch("alone");
    let s = tiny_scenario(&alone);
    let o = run(&s, &alone);
    assert!(o.status.success(), "{}", stderr(&o));
    // A regular file as --out.
    let o = run(&scenario, &scenario);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&alone);
}

/// A fresh run into its own earlier output removes that run's summary,
/// checkpoint and frames before it starts: nothing of the older run is
/// left beside the newer history.
#[test]
fn a_fresh_run_clears_its_previous_outputs() {
    let dir = scratch("fresh");
    let scenario = tiny_scenario(&dir);
    let out = dir.join("out");
    assert!(run(&scenario, &out).status.success());
    std::fs::write(out.join("checkpoint.bin"), "an older run's").unwrap();
    std::fs::write(out.join("fields/step_000999.vtu"), "an older frame").unwrap();
    let o = run(&scenario, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!out.join("checkpoint.bin").exists());
    assert!(!out.join("fields/step_000999.vtu").exists());
    assert!(out.join("summary.json").exists() && out.join("history.csv").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
