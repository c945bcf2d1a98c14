//! Checkpoints, resumption, interruption and crash safety (issue 5).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn drape() -> Command {
    Command::new(env!("CARGO_BIN_EXE_drape"))
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("drape-resume-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The pedestal example (penalty, stress projection) shortened to the
/// impact and 60 steps after it, with checkpoints every 20 scheduled steps.
fn scenario(dir: &Path, steps: usize) -> PathBuf {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let text = std::fs::read_to_string(examples.join("fabric-on-pedestal.toml")).unwrap();
    let text = text
        .replace(
            "{ steps = 450, dt = 1.0e-4 }",
            &format!("{{ steps = {steps}, dt = 1.0e-4 }}"),
        )
        .replace("every = 10 ", "every = 10\ncheckpoint_every = 20 ");
    assert!(text.contains("checkpoint_every = 20"));
    let path = dir.join("pedestal.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn run(args: &[&str]) -> std::process::Output {
    drape().args(args).output().unwrap()
}

fn history(out: &Path) -> String {
    std::fs::read_to_string(out.join("history.csv")).unwrap()
}

fn final_vtu(out: &Path) -> Vec<u8> {
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    let last = pvd
        .lines()
        .filter_map(|l| l.split("file=\"").nth(1))
        .next_back()
        .unwrap();
    std::fs::read(out.join(last.split('"').next().unwrap())).unwrap()
}

/// A run resumed from a checkpoint gives the same history and final state
/// as the uninterrupted run, to the last bit: the history's text (17
/// significant digits) and the last VTU frame's bytes are identical.
#[test]
fn resumed_run_reproduces_the_uninterrupted_one_bit_for_bit() {
    let dir = temp("bits");
    resumes_bit_for_bit(&dir, &scenario(&dir, 60));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A linear solver that keeps a preconditioner from step to step — the
/// multigrid hierarchy of `iterative`, the Cholesky factor of `reuse` —
/// resumes bit for bit too: the checkpoint holds the matrix each was made
/// from, and the resumed run makes it again (issue 34; a fresh one would
/// change the Krylov iterates in their last bits).
#[test]
fn resumed_iterative_and_reuse_runs_reproduce_the_uninterrupted_ones() {
    let dir = temp("kept");
    for (mode, uses) in [
        ("iterative", "\"multigrid_builds\": "),
        ("reuse", "\"krylov_iterations\": "),
    ] {
        let text = std::fs::read_to_string(scenario(&dir, 60)).unwrap();
        let text = text.replace("[solver]\n", &format!("[solver]\nlinear = \"{mode}\"\n"));
        assert!(text.contains(mode));
        let sc = dir.join(format!("{mode}.toml"));
        std::fs::write(&sc, text).unwrap();
        let summary = resumes_bit_for_bit(&dir.join(mode), &sc);
        // The kept path was used (its count is not 0).
        let count = summary.split(uses).nth(1).unwrap_or("0");
        assert!(!count.starts_with('0'), "{mode}: {summary}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `sc` into `dir/a` and `dir/b`, resumes `b` from its last
/// checkpoint, and checks both histories and last frames are identical;
/// returns a's summary.
fn resumes_bit_for_bit(dir: &Path, sc: &Path) -> String {
    let (a, b) = (dir.join("a"), dir.join("b"));
    let o = run(&[
        "run",
        sc.to_str().unwrap(),
        "--out",
        a.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&[
        "run",
        sc.to_str().unwrap(),
        "--out",
        b.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success());
    // b's last checkpoint is at scheduled step 60 of 70: resuming cuts the
    // history back to it and recomputes the rest.
    assert!(b.join("checkpoint.bin").exists());
    let o = run(&["run", "--resume", b.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        history(&a) == history(&b),
        "{}: the resumed history differs",
        sc.display()
    );
    assert!(
        final_vtu(&a) == final_vtu(&b),
        "{}: last frame",
        sc.display()
    );
    std::fs::read_to_string(a.join("summary.json")).unwrap()
}

/// The cloth hanging from one edge of the library's settling tests,
/// settling to rest with adaptive steps over two segments, checkpoints
/// every `every` converged steps.
fn settling(dir: &Path, every: usize) -> PathBuf {
    let cloth = include_str!("../../drape/tests/scenarios/hanging-from-edge.toml");
    let text = format!(
        r#"{cloth}segments = [{{ steps = 30, dt = 0.005 }}, {{ steps = 2000, dt = 0.01 }}]
adaptive = true
dt_max = 0.1
rest = {{ speed = 1.0e-4, after = 0.2 }}
[output]
every = 25
checkpoint_every = {every}
"#
    );
    let path = dir.join(format!("settling-{every}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// Adaptive steps and the rest criterion resume bit for bit: from a
/// checkpoint in the middle of the second segment (every 150 converged
/// steps: the controller's segment and step size come back), and from the
/// one just before the run came to rest (every step: the nine still steps
/// counted come back, so the run ends at rest one step later, as the
/// uninterrupted one did).
#[test]
fn adaptive_run_with_rest_resumes_bit_for_bit() {
    let dir = temp("adaptive");
    for every in [150, 1] {
        let sc = settling(&dir, every);
        let out = dir.join(format!("out-{every}"));
        let o = run(&[
            "run",
            sc.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
        assert!(summary.contains("\"at_rest\": true"), "{summary}");
        let (whole, vtu) = (history(&out), final_vtu(&out));
        let steps = whole.lines().count() - 2;
        assert!(steps > 150 + 10, "{steps} steps");
        let o = run(&["run", "--resume", out.to_str().unwrap(), "--quiet"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        // Compared without printing both histories when they differ.
        let resumed = history(&out);
        assert!(
            resumed == whole,
            "checkpoints every {every}: the resumed history differs ({} rows, not {})",
            resumed.lines().count() - 1,
            whole.lines().count() - 1
        );
        assert!(
            final_vtu(&out) == vtu,
            "checkpoints every {every}: last frame"
        );
        let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
        assert!(summary.contains("\"at_rest\": true"), "{summary}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// SIGINT ends the current step, writes a checkpoint and the summary
/// ("interrupted") and exits with 130; the run then resumes to the same
/// result as an uninterrupted one. A changed scenario is refused.
#[test]
fn interrupted_run_resumes_and_a_changed_scenario_is_refused() {
    let dir = temp("interrupt");
    let sc = scenario(&dir, 300);
    let (a, b) = (dir.join("a"), dir.join("b"));
    let o = run(&[
        "run",
        sc.to_str().unwrap(),
        "--out",
        a.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success());
    let child = drape()
        .args([
            "run",
            sc.to_str().unwrap(),
            "--out",
            b.to_str().unwrap(),
            "--quiet",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Interrupt once the run is well under way (after the first frames).
    let t0 = Instant::now();
    while !b.join("fields/step_000030.vtu").exists() && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(20));
    }
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(err.contains("--resume"), "{err}");
    let summary = std::fs::read_to_string(b.join("summary.json")).unwrap();
    assert!(summary.contains("\"interrupted\""), "{summary}");
    assert!(b.join("checkpoint.bin").exists());
    // A changed scenario is refused with a clear message, exit 2.
    let changed = dir.join("changed.toml");
    std::fs::write(
        &changed,
        std::fs::read_to_string(&sc)
            .unwrap()
            .replace("penalty = 5.0e4", "penalty = 6.0e4"),
    )
    .unwrap();
    let o = run(&[
        "run",
        changed.to_str().unwrap(),
        "--resume",
        b.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("scenario has changed"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // The original resumes to the uninterrupted result.
    let o = run(&["run", "--resume", b.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(history(&a), history(&b));
    assert_eq!(final_vtu(&a), final_vtu(&b));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Checks that every output file present is complete and readable.
fn check_readable(out: &Path) {
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let columns = lines.next().unwrap().split(',').count();
    for (k, line) in lines.enumerate() {
        let values: Vec<&str> = line.split(',').collect();
        assert_eq!(values.len(), columns, "history row {k} incomplete: {line}");
        for v in values {
            assert!(v.parse::<f64>().is_ok(), "history row {k}: {v:?}");
        }
        assert!(text.ends_with('\n'), "history ends mid-row");
    }
    if let Ok(pvd) = std::fs::read_to_string(out.join("fields.pvd")) {
        assert!(
            pvd.trim_end().ends_with("</VTKFile>"),
            "fields.pvd incomplete"
        );
        for file in pvd
            .lines()
            .filter_map(|l| l.split("file=\"").nth(1))
            .map(|f| f.split('"').next().unwrap())
        {
            let bytes = std::fs::read(out.join(file)).unwrap();
            let head = String::from_utf8_lossy(&bytes[..bytes.len().min(4000)]).to_string();
            assert!(head.contains("<AppendedData encoding=\"raw\">"), "{file}");
            // The appended block ends the file's XML.
            assert!(
                bytes.ends_with(b"</VTKFile>\n") || bytes.ends_with(b"</VTKFile>"),
                "{file} truncated"
            );
        }
    }
    if let Ok(summary) = std::fs::read_to_string(out.join("summary.json")) {
        assert!(summary.trim_end().ends_with('}'), "summary.json incomplete");
    }
}

/// A process killed (SIGKILL) at arbitrary moments leaves every output
/// file readable: the history lacks at most the step in progress, the
/// collection lists only complete frames, nothing is half-written.
#[test]
fn killed_runs_leave_readable_outputs() {
    let dir = temp("kill");
    let sc = scenario(&dir, 300);
    // Kill times spread over the run (it takes about 2 s here).
    for (k, ms) in [37u64, 180, 420, 777, 1300].into_iter().enumerate() {
        let out = dir.join(format!("k{k}"));
        let mut child = drape()
            .args([
                "run",
                sc.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
                "--quiet",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(ms));
        let _ = child.kill();
        let _ = child.wait();
        if out.join("history.csv").exists() {
            check_readable(&out);
        }
        if out.join("checkpoint.bin").exists() {
            // And the run resumes from what was left.
            let o = run(&["run", "--resume", out.to_str().unwrap(), "--quiet"]);
            assert!(
                o.status.success(),
                "resume after kill at {ms} ms: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            check_readable(&out);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
