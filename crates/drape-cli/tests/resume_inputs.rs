//! Issue 19: `drape run --resume DIR` refuses an input file (here the
//! mesh) that changed or went missing since the checkpoint, naming it,
//! with exit 2 — before the scenario reads it — and says so in the
//! directory's summary.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const DRAPE: &str = env!("CARGO_BIN_EXE_drape");

/// A fresh scratch directory for `name`.
fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("drape-resume-inputs-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    dir
}

/// A 4 x 4 plate as an OBJ file.
fn plate() -> String {
    let n = 4;
    let mut text = String::new();
    for j in 0..=n {
        for i in 0..=n {
            text.push_str(&format!("v {} {} 0\n", 0.025 * i as f64, 0.025 * j as f64));
        }
    }
    let node = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (
                node(i, j),
                node(i + 1, j),
                node(i + 1, j + 1),
                node(i, j + 1),
            );
            text.push_str(&format!("f {a} {b} {c}\nf {a} {c} {d}\n"));
        }
    }
    text
}

/// The plate falling for 7 steps, a checkpoint every 5.
fn scenario(dir: &Path) -> PathBuf {
    std::fs::write(dir.join("plate.obj"), plate()).unwrap();
    let path = dir.join("fall.toml");
    std::fs::write(
        &path,
        r#"
[mesh]
shape = "file"
path = "plate.obj"
[material]
youngs_modulus = 2.0e6
poisson_ratio = 0.3
density = 320.0
thickness = 0.6e-3
[[load]]
kind = "gravity"
acceleration = [0.0, 0.0, -9.8]
[time]
segments = [{ steps = 7, dt = 1e-3 }]
[output]
checkpoint_every = 5
"#,
    )
    .unwrap();
    path
}

fn drape(args: &[&Path]) -> Output {
    let mut c = Command::new(DRAPE);
    c.arg("run");
    for a in args {
        c.arg(a);
    }
    c.arg("--quiet")
        .stdin(std::process::Stdio::null())
        .output()
        .expect("spawn drape")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Changed, then missing: exit 2 naming the mesh file and what to do, the
/// history untouched; restored: the resume runs.
#[test]
fn a_changed_or_missing_mesh_file_refuses_the_resume() {
    let dir = scratch("mesh");
    let scenario = scenario(&dir);
    let out = dir.join("out");
    let o = drape(&[&scenario, Path::new("--out"), &out]);
    assert!(o.status.success(), "{}", stderr(&o));
    // As if stopped at the checkpoint (a completed run's summary is left
    // alone by a refused resume).
    let summary_path = out.join("summary.json");
    let summary = |path: &Path| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
    };
    let mut s = summary(&summary_path);
    s["status"] = "interrupted".into();
    std::fs::write(&summary_path, s.to_string()).unwrap();
    let history = std::fs::read(out.join("history.csv")).unwrap();
    let mesh = dir.join("plate.obj");
    let named = std::fs::canonicalize(&mesh).unwrap().display().to_string();
    let original = std::fs::read(&mesh).unwrap();

    let mut changed = original.clone();
    changed.extend_from_slice(b"# edited\n");
    std::fs::write(&mesh, changed).unwrap();
    let o = drape(&[Path::new("--resume"), &out]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    for f in [
        named.as_str(),
        "(mesh.path) has changed since the checkpoint was written",
        "Restore the file as it was, or start a fresh run (without --resume)",
    ] {
        assert!(stderr(&o).contains(f), "expected {f:?} in\n{}", stderr(&o));
    }
    assert_eq!(std::fs::read(out.join("history.csv")).unwrap(), history);
    let s = summary(&summary_path);
    assert_eq!(s["status"], "failed", "{s}");
    let message = s["message"].as_str().unwrap();
    assert!(
        message.starts_with("cannot resume: ") && message.contains(&named),
        "{message}"
    );
    // Said once (the summary said "cannot resume: cannot resume: ..."),
    // with the command line's way to a fresh run.
    assert_eq!(message.matches("cannot resume").count(), 1, "{message}");
    assert!(message.ends_with("(without --resume)"), "{message}");

    std::fs::remove_file(&mesh).unwrap();
    let o = drape(&[Path::new("--resume"), &out]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    for f in [
        named.as_str(),
        "(mesh.path) recorded in the checkpoint cannot be read",
        "restore it as it was, or start a fresh run (without --resume)",
    ] {
        assert!(stderr(&o).contains(f), "expected {f:?} in\n{}", stderr(&o));
    }
    assert_eq!(std::fs::read(out.join("history.csv")).unwrap(), history);

    std::fs::write(&mesh, original).unwrap();
    let o = drape(&[Path::new("--resume"), &out]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(summary(&summary_path)["status"], "completed");
    assert_eq!(std::fs::read(out.join("history.csv")).unwrap(), history);
    let _ = std::fs::remove_dir_all(&dir);
}
