//! Issue 45: `drape test` (README, "The drape test"; SPEC §6.7) on a small
//! drape tester (the example's, 5 rings, 30 fixed steps of 2 ms: the
//! skirt drops and folds; a specimen takes a fraction of a second).
//!
//! What is checked: zero waviness and angle face up reproduce the plain
//! run byte for byte; the same seed gives the same specimens and
//! different seeds different ones; test.json has SPEC's keys with
//! statistics that follow from its own specimens; a second run completes
//! only what is missing; a failed specimen is reported and not dropped;
//! bad input is refused before anything runs, naming key, line and value.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn drape(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

/// A fresh directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("drape-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The example drape tester on 5 rings, 30 steps of 2 ms, with `test`
/// appended (a `[test]` table, or nothing).
fn tester(test: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/drape-tester.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let mut out: Vec<String> = text
        .lines()
        .filter(|l| {
            !["adaptive", "dt_max", "rest ="]
                .iter()
                .any(|k| l.starts_with(k))
        })
        .map(|l| match l {
            l if l.starts_with("rings") => "rings = 5".into(),
            l if l.starts_with("segments") => "segments = [ { steps = 30, dt = 2.0e-3 } ]".into(),
            l => l.to_owned(),
        })
        .collect();
    out.push(test.to_owned());
    out.join("\n") + "\n"
}

fn json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// SPEC §6.7: zero amplitude, zero angle, face up is the plain run, bit
/// for bit (every specimen's history.csv equals the plain run's).
#[test]
fn zero_perturbation_is_the_plain_run() {
    let dir = scratch("zero");
    std::fs::write(
        dir.join("s.toml"),
        tester("[test]\nwaviness = 0.0\ncut_angle = 0.0\nfaces = \"up\"\n"),
    )
    .unwrap();
    ok(&drape(&["run", "s.toml", "--out", "plain", "-q"], &dir));
    ok(&drape(
        &["test", "s.toml", "--specimens", "2", "--out", "t", "-q"],
        &dir,
    ));
    let plain = std::fs::read(dir.join("plain/history.csv")).unwrap();
    for s in ["0000", "0001"] {
        let h = std::fs::read(dir.join(format!("t/specimens/{s}/history.csv"))).unwrap();
        assert!(
            h == plain,
            "specimen {s}'s history differs from the plain run's"
        );
    }
}

/// The same seed gives the same specimens (scenarios and results);
/// another seed other ones; test.json's statistics are those of its own
/// specimens; test.png is a PNG.
#[test]
fn seeds_and_statistics() {
    let dir = scratch("seeds");
    std::fs::write(
        dir.join("s.toml"),
        tester("[test]\nwaviness = 1.0e-3\ncut_angle = 5.0\n"),
    )
    .unwrap();
    for (out, seed) in [("a", "7"), ("b", "7"), ("c", "8")] {
        ok(&drape(
            &[
                "test",
                "s.toml",
                "--specimens",
                "3",
                "--jobs",
                "2",
                "--seed",
                seed,
                "--out",
                out,
                "-q",
            ],
            &dir,
        ));
    }
    let (a, b, c) = (
        json(&dir.join("a/test.json")),
        json(&dir.join("b/test.json")),
        json(&dir.join("c/test.json")),
    );
    let results = |v: &Value| -> Vec<(f64, u64)> {
        v["specimens"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| {
                (
                    s["drape_coefficient"].as_f64().unwrap(),
                    s["folds"].as_u64().unwrap(),
                )
            })
            .collect()
    };
    assert_eq!(results(&a), results(&b));
    assert_ne!(results(&a), results(&c));
    for s in ["0000", "0001", "0002"] {
        let text = |d: &str| {
            std::fs::read_to_string(dir.join(format!("{d}/specimens/{s}/scenario.toml"))).unwrap()
        };
        assert_eq!(text("a"), text("b"));
        assert_ne!(text("a"), text("c"));
    }
    // SPEC's keys, and statistics that follow from the specimens listed.
    for key in [
        "specimens",
        "mean",
        "sd",
        "ci95",
        "fold_histogram",
        "modal_folds",
        "dc_at_modal_folds",
    ] {
        assert!(a.get(key).is_some(), "test.json lacks {key}");
    }
    for s in a["specimens"].as_array().unwrap() {
        for key in [
            "specimen",
            "status",
            "drape_coefficient",
            "folds",
            "crossings",
            "wall_seconds",
        ] {
            assert!(s.get(key).is_some(), "a specimen lacks {key}");
        }
        assert_eq!(s["status"], "completed");
        // Its run's iteration counts, as its summary has them.
        let run = json(
            &dir.join("a")
                .join(s["dir"].as_str().unwrap())
                .join("summary.json"),
        );
        for key in ["newton_iterations", "newton_iterations_discarded"] {
            assert!(s[key].as_u64().is_some(), "a specimen lacks {key}");
            assert_eq!(s[key], run[key], "{key}");
        }
    }
    // A specimen crossing itself is named in the message, and only then.
    let crossing = a["specimens"]
        .as_array()
        .unwrap()
        .iter()
        .any(|s| s["crossings"].as_u64().unwrap() > 0);
    let message = a["message"].as_str().unwrap();
    assert_eq!(
        message.contains("through each other"),
        crossing,
        "{message}"
    );
    let r = results(&a);
    let n = r.len() as f64;
    let mean = r.iter().map(|x| x.0).sum::<f64>() / n;
    assert!((a["mean"].as_f64().unwrap() - mean).abs() < 1e-12);
    let sd = (r.iter().map(|x| (x.0 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    assert!((a["sd"].as_f64().unwrap() - sd).abs() < 1e-12);
    // t_{0.975, 2} = 4.3027 in closed form, (2p − 1) / sqrt(2 p (1 − p)).
    let t = 0.95 / (2.0f64 * 0.975 * 0.025).sqrt();
    let ci = a["ci95"].as_array().unwrap();
    assert!((ci[0].as_f64().unwrap() - (mean - t * sd / n.sqrt())).abs() < 1e-9);
    assert!((ci[1].as_f64().unwrap() - (mean + t * sd / n.sqrt())).abs() < 1e-9);
    let total: u64 = a["fold_histogram"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(total, 3);
    let modal = a["modal_folds"].as_u64().unwrap();
    let at: Vec<f64> = r.iter().filter(|x| x.1 == modal).map(|x| x.0).collect();
    assert!(a["fold_histogram"][modal.to_string()].as_u64().unwrap() as usize == at.len());
    let dc = at.iter().sum::<f64>() / at.len() as f64;
    assert!((a["dc_at_modal_folds"].as_f64().unwrap() - dc).abs() < 1e-12);
    let png = std::fs::read(dir.join("a/test.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // A specimen's directory reproduces it alone: `drape run` on its
    // scenario.toml (face down, its waviness and cut) writes the same
    // history, byte for byte.
    let alone = dir.join("alone");
    ok(&drape(
        &[
            "run",
            "a/specimens/0001/scenario.toml",
            "--out",
            alone.to_str().unwrap(),
            "-q",
        ],
        &dir,
    ));
    let history = |d: &Path| std::fs::read(d.join("history.csv")).unwrap();
    assert!(history(&alone) == history(&dir.join("a/specimens/0001")));
}

/// A second run completes what is missing (a specimen whose directory
/// was removed runs, the others do not), and a specimen that cannot run
/// is reported with its status and message, never dropped (exit 1).
#[test]
fn resumes_and_reports_failures() {
    let dir = scratch("resume");
    std::fs::write(dir.join("s.toml"), tester("")).unwrap();
    ok(&drape(
        &["test", "s.toml", "--specimens", "3", "--out", "t", "-q"],
        &dir,
    ));
    let first = json(&dir.join("t/test.json"));
    std::fs::remove_dir_all(dir.join("t/specimens/0001")).unwrap();
    let again = drape(&["test", "s.toml", "--specimens", "3", "--out", "t"], &dir);
    ok(&again);
    let said = String::from_utf8_lossy(&again.stderr);
    assert!(said.contains("2 done before, 1 to run"), "{said}");
    let second = json(&dir.join("t/test.json"));
    assert_eq!(first["mean"], second["mean"]);

    // A directory drape did not write is refused by its specimen's run.
    let foreign = dir.join("t2/specimens/0002");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let o = drape(
        &["test", "s.toml", "--specimens", "3", "--out", "t2", "-q"],
        &dir,
    );
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v = json(&dir.join("t2/test.json"));
    let rows = v["specimens"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[2]["status"], "failed");
    assert!(!rows[2]["message"].as_str().unwrap().is_empty());
    assert_eq!(v["measured"], 2);
    assert_eq!(v["count"], 3);
}

/// Bad input: an unknown key of `[test]` (named with its line), a value
/// out of range (named with its value and unit), a scenario that is
/// already a specimen, --address without a cluster engine, a cluster
/// engine without Python: exit 2, nothing run.
#[test]
fn bad_input_is_refused() {
    let dir = scratch("bad");
    let cases = [
        ("[test]\nwavines = 1.0e-3\n", "wavines"),
        ("[test]\nwaviness = -1.0\n", "test.waviness"),
        ("[test]\ncut_angle = 120.0\n", "test.cut_angle"),
        ("[test]\nfaces = \"sideways\"\n", "sideways"),
        ("[specimen]\nseed = 3\n", "specimen"),
    ];
    for (i, (table, says)) in cases.iter().enumerate() {
        let name = format!("s{i}.toml");
        std::fs::write(dir.join(&name), tester(table)).unwrap();
        let o = drape(
            &["test", &name, "--specimens", "2", "--out", "t", "-q"],
            &dir,
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{table}: {err}");
        assert!(err.contains(says) && err.contains(&name), "{table}: {err}");
        assert!(
            !dir.join("t/specimens/0000").exists(),
            "{table}: a specimen ran"
        );
    }
    // A test.json that is not a test's would be replaced: refused.
    std::fs::create_dir_all(dir.join("theirs")).unwrap();
    std::fs::write(dir.join("theirs/test.json"), "{\"mine\": 1}").unwrap();
    std::fs::write(dir.join("ok.toml"), tester("")).unwrap();
    let o = drape(
        &[
            "test",
            "ok.toml",
            "--specimens",
            "1",
            "--out",
            "theirs",
            "-q",
        ],
        &dir,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("theirs/test.json") && err.contains("not a drape test's"),
        "{err}"
    );
    assert!(!dir.join("theirs/specimens/0000").exists());
    let o = drape(
        &["test", "s0.toml", "--specimens", "1", "--address", "x:1"],
        &dir,
    );
    assert_eq!(o.status.code(), Some(2));
    let o = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["test", "s0.toml", "--specimens", "1", "--engine", "ray"])
        .env("DRAPE_PYTHON", "/nonexistent/python3")
        .current_dir(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("Python") && err.contains("DRAPE_PYTHON"),
        "{err}"
    );
}

/// Ctrl-C (SIGINT to `drape test` alone: it passes it on to its running
/// specimens) ends the running specimens after their step with a
/// checkpoint, starts no more, writes test.json with what was done and
/// exits 130; the same command then resumes them and completes the rest,
/// to the uninterrupted test's results.
#[test]
fn an_interrupted_test_resumes() {
    let dir = scratch("interrupt");
    let text = tester("").replace(
        "segments = [ { steps = 30, dt = 2.0e-3 } ]",
        "segments = [ { steps = 300, dt = 2.0e-3 } ]",
    );
    std::fs::write(dir.join("s.toml"), text).unwrap();
    let args = ["test", "s.toml", "--specimens", "3", "--jobs", "2", "-q"];
    ok(&drape(&[&args[..], &["--out", "whole"]].concat(), &dir));
    let child = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args([&args[..], &["--out", "cut"]].concat())
        .current_dir(&dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    let frame = dir.join("cut/specimens/0000/fields/step_000030.vtu");
    while !frame.exists() && started.elapsed() < std::time::Duration::from_secs(60) {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    let cut = json(&dir.join("cut/test.json"));
    let statuses: Vec<&str> = (cut["specimens"].as_array().unwrap().iter())
        .map(|s| s["status"].as_str().unwrap())
        .collect();
    assert_eq!(statuses.len(), 3);
    assert!(statuses.contains(&"interrupted"), "{statuses:?}");
    assert!(dir.join("cut/specimens/0000/checkpoint.bin").exists());
    ok(&drape(&[&args[..], &["--out", "cut"]].concat(), &dir));
    let (whole, cut) = (
        json(&dir.join("whole/test.json")),
        json(&dir.join("cut/test.json")),
    );
    for key in ["mean", "sd", "ci95", "fold_histogram", "modal_folds"] {
        assert_eq!(whole[key], cut[key], "{key}");
    }
}
