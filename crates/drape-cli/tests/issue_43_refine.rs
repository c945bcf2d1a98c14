//! Issue 43: a multilevel settle (`[refine]`) through the command line —
//! the same history on one thread and on two, and `drape measure`,
//! `render` and `plot` on its output directory, whose mesh changes between
//! frames.

mod issue_19_support;

use issue_19_support::{DRAPE, scratch, summary};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The multilevel drape tester of the library's tests (an 8-ring disc on
/// a pedestal, weight in 6 static increments, refined twice along its
/// folds).
fn tester() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../drape/tests/scenarios/multilevel-tester.toml")
}

/// `drape ARGS` with `RAYON_NUM_THREADS = threads`, which must succeed;
/// its standard output.
fn drape(args: &[&str], threads: usize) -> String {
    let out = Command::new(DRAPE)
        .args(args)
        .env("RAYON_NUM_THREADS", threads.to_string())
        .stdin(Stdio::null())
        .output()
        .expect("drape runs");
    assert!(
        out.status.success(),
        "drape {args:?}: {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn a_multilevel_run_is_the_same_on_one_thread_and_two_and_measures_renders_and_plots() {
    let dir = scratch("issue43-refine");
    let scenario = tester();
    let scenario = scenario.to_str().unwrap();
    let checked = drape(&["check", scenario], 2);
    assert!(
        checked.contains("refine    up to 2 levels, along the folds"),
        "{checked}"
    );
    // The marking's choices are said too.
    let chosen = dir.join("chosen.toml");
    let text = std::fs::read_to_string(scenario).unwrap().replace(
        "[refine]",
        "[refine]\nindicator = \"chord\"\nalso = [\"rim\", \"contact\"]",
    );
    std::fs::write(&chosen, text).unwrap();
    let checked = drape(&["check", chosen.to_str().unwrap()], 2);
    assert!(
        checked.contains("times the area (the sag)), and the rim and the contact line"),
        "{checked}"
    );
    let mut histories = Vec::new();
    for threads in [1, 2] {
        let out = dir.join(format!("out-{threads}"));
        drape(
            &["run", scenario, "--out", out.to_str().unwrap(), "--quiet"],
            threads,
        );
        histories.push(std::fs::read(out.join("history.csv")).unwrap());
    }
    assert!(histories[0] == histories[1], "one thread and two differ");
    let out = dir.join("out-2");
    let out_s = out.to_str().unwrap();
    let s = summary(&out);
    let levels = s["levels"].as_array().expect("levels").clone();
    assert_eq!(levels.len(), 3, "{s}");
    assert_eq!(s["elements"], levels[2]["elements"]);
    assert!(
        s["message"].as_str().unwrap().contains("3 levels"),
        "{}",
        s["message"]
    );
    // The last frame is on the last level's mesh: measured there, the
    // drape coefficient the summary lists.
    let measured: serde_json::Value =
        serde_json::from_str(&drape(&["measure", out_s], 2)).expect("JSON");
    let dc = measured["drape_coefficient"].as_f64().unwrap();
    let listed = levels[2]["drape_coefficient"].as_f64().unwrap();
    assert!((dc - listed).abs() < 1e-12, "{dc} against {listed}");
    // The first frame on the coarse mesh, measured too.
    drape(&["measure", out_s, "--step", "0"], 2);
    let png = dir.join("last.png");
    drape(
        &[
            "render",
            out_s,
            "--size",
            "200x150",
            "--output",
            png.to_str().unwrap(),
        ],
        2,
    );
    assert!(png.is_file());
    let gif = dir.join("all.gif");
    drape(
        &[
            "render",
            out_s,
            "--animate",
            "--size",
            "160x120",
            "--output",
            gif.to_str().unwrap(),
        ],
        2,
    );
    assert!(gif.is_file());
    drape(&["plot", out_s], 2);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A step that runs longer than `--progress-every` is reported while it
/// runs (a finer level's settle is one step): its number, its level and
/// Newton's counts; the run is the same as without.
#[test]
fn a_long_step_is_reported_while_it_runs() {
    let dir = scratch("issue43-progress");
    let scenario = tester();
    let scenario = scenario.to_str().unwrap();
    let mut histories = Vec::new();
    let mut reported = String::new();
    for every in ["0", "0.001"] {
        let out = dir.join(format!("out-{every}"));
        let run = Command::new(DRAPE)
            .args(["run", scenario, "--out", out.to_str().unwrap()])
            .args(["--progress-every", every])
            .env("RAYON_NUM_THREADS", "1")
            .stdin(Stdio::null())
            .output()
            .expect("drape runs");
        let err = String::from_utf8_lossy(&run.stderr).into_owned();
        assert!(run.status.success(), "{err}");
        histories.push(std::fs::read(out.join("history.csv")).unwrap());
        if every == "0" {
            assert!(!err.contains("running for"), "{err}");
        } else {
            reported = err;
        }
    }
    assert!(histories[0] == histories[1], "the counted run differs");
    // The finer levels' increments take tens of milliseconds at least.
    let line = reported
        .lines()
        .find(|l| l.contains("running for") && l.contains(", level "))
        .unwrap_or_else(|| panic!("no line on a finer level's step:\n{reported}"));
    assert!(
        line.contains(" T3): ") && line.contains("Newton iteration") && line.contains(" solve"),
        "{line}"
    );
    // A negative interval is refused by name.
    let refused = Command::new(DRAPE)
        .args(["run", scenario, "--progress-every", "-1"])
        .args(["--out", dir.join("refused").to_str().unwrap()])
        .stdin(Stdio::null())
        .output()
        .expect("drape runs");
    assert_eq!(refused.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&refused.stderr).contains("--progress-every -1"),
        "{}",
        String::from_utf8_lossy(&refused.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
