//! Helpers shared by the integration tests.
#![allow(dead_code)]

use drape::scenario::{Scenario, Setup};
use std::path::{Path, PathBuf};

/// A fresh, empty directory under the system's temp dir, unique to this
/// call (tests run in parallel threads of one process), removed when
/// dropped.
pub fn temp_dir(name: &str) -> TempDir {
    static COUNTER: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("drape-test-{}-{k}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

/// A directory removed when dropped.
pub struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Builds a setup from scenario text.
pub fn setup(text: &str) -> Setup {
    let path = Path::new("test.toml");
    Scenario::parse(text, path)
        .unwrap()
        .build(path, text)
        .unwrap()
}

/// The history as rows of numbers, with the header.
pub fn read_history(dir: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    (header, rows)
}

/// Column `name` of the history.
pub fn column(header: &[String], rows: &[Vec<f64>], name: &str) -> Vec<f64> {
    let k = header.iter().position(|h| h == name).unwrap();
    rows.iter().map(|r| r[k]).collect()
}

/// A 20 x 20 fabric of the reference problem's material, with extra TOML.
pub fn fabric(extra: &str) -> String {
    rectangle([0.2, 0.2], [20, 20], extra)
}

/// A rectangle of `size` (m) in `divisions` squares, of the reference
/// problem's material, with extra TOML.
pub fn rectangle(size: [f64; 2], divisions: [usize; 2], extra: &str) -> String {
    format!(
        r#"
[mesh]
shape = "rectangle"
size = {size:?}
divisions = {divisions:?}
[material]
youngs_modulus = 2.0e6
poisson_ratio = 0.3
density = 320.0
thickness = 0.6e-3
{extra}
"#
    )
}
