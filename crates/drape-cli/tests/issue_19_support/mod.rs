//! What the issue 19 tests share: scratch directories, a small falling
//! plate, and running the `drape` binary.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

pub const DRAPE: &str = env!("CARGO_BIN_EXE_drape");

/// A fresh scratch directory `drape-issue19-{name}-{pid}`.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("drape-issue19-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    dir
}

/// `dir/fall.toml`: a 4 x 4 plate falling for `steps` steps of 1 ms,
/// followed by the TOML `extra`.
pub fn falling_plate(dir: &Path, steps: usize, extra: &str) -> PathBuf {
    falling_sheet(dir, [4, 4], steps, extra)
}

/// `dir/fall.toml`: a 10 cm sheet of `divisions` squares falling for
/// `steps` steps of 1 ms, followed by the TOML `extra`.
pub fn falling_sheet(dir: &Path, divisions: [usize; 2], steps: usize, extra: &str) -> PathBuf {
    let path = dir.join("fall.toml");
    std::fs::write(
        &path,
        format!(
            r#"
[mesh]
shape = "rectangle"
size = [0.1, 0.1]
divisions = {divisions:?}
[material]
youngs_modulus = 2.0e6
poisson_ratio = 0.3
density = 320.0
thickness = 0.6e-3
[[load]]
kind = "gravity"
acceleration = [0.0, 0.0, -9.8]
[time]
segments = [{{ steps = {steps}, dt = 1e-3 }}]
{extra}
"#
        ),
    )
    .expect("write the scenario");
    path
}

/// `drape ARGS`, standard input closed.
pub fn drape(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(DRAPE)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("spawn drape")
}

/// Bytes of a process's output as text.
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// `drape run SCENARIO --out OUT --quiet`.
pub fn run_into(scenario: &Path, out: &Path) -> Output {
    drape(&[
        "run".as_ref(),
        scenario.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--quiet".as_ref(),
    ])
}

/// `drape run SCENARIO --out OUT --quiet` started, its standard error
/// piped.
pub fn spawn_run(scenario: &Path, out: &Path) -> Child {
    spawn_run_with(scenario, out, &[])
}

/// [`spawn_run`] with the environment variables `env` set.
pub fn spawn_run_with(scenario: &Path, out: &Path, env: &[(&str, &str)]) -> Child {
    Command::new(DRAPE)
        .arg("run")
        .arg(scenario)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .envs(env.iter().copied())
        .stdin(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn drape")
}

/// Waits (at most a minute) until `out/history.csv` has `lines` lines.
pub fn wait_for_history(out: &Path, lines: usize) {
    let start = Instant::now();
    while std::fs::read_to_string(out.join("history.csv")).map_or(0, |t| t.lines().count()) < lines
    {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the run did not start"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Sends `signal` (`"TERM"`, `"INT"`, ...) to `child` with `kill`.
pub fn send(child: &Child, signal: &str) {
    let sent = Command::new("kill")
        .arg(format!("-{signal}"))
        .arg(child.id().to_string())
        .status()
        .expect("kill");
    assert!(sent.success());
}

/// `out/summary.json`.
pub fn summary(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

/// Rows of `out/history.csv` after its header.
pub fn history_rows(out: &Path) -> usize {
    std::fs::read_to_string(out.join("history.csv"))
        .expect("history.csv")
        .lines()
        .count()
        - 1
}
