//! What the issue 19 tests share: scratch directories, a small falling
//! plate, and running the `drape` binary.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

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
    let path = dir.join("fall.toml");
    std::fs::write(
        &path,
        format!(
            r#"
[mesh]
shape = "rectangle"
size = [0.1, 0.1]
divisions = [4, 4]
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
