//! A drape test's directory (README, "The drape test"; SPEC §6.7):
//! `DIR/specimens/NNNN/`, one ordinary run directory a specimen, and the
//! test's `DIR/test.json` and `DIR/test.png`.
//!
//! The front ends run the specimens — the command line's local engine as
//! child `drape run` processes, Python's engines as a sweep's cases — and
//! both use this module to find what is left to run ([`prior`]), to lay a
//! specimen's scenario in its directory ([`place_scenario`]) and to report
//! ([`report`]): each specimen's final frame measured as `drape measure`
//! measures it ([`crate::measure::Run`]), the statistics of
//! [`drape::measure::ensemble`], the picture of `drape-render`.

use crate::measure::Run;
use anyhow::{Context, anyhow};
use drape::measure::Given;
use drape::measure::ensemble::{Ensemble, summarise};
use drape::output::atomic::write_atomic;
use drape::scenario::SpecimenPlan;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// The specimens' folder in the test's directory.
pub const SPECIMENS: &str = "specimens";
/// The test's results.
pub const TEST_JSON: &str = "test.json";
/// The test's picture.
pub const TEST_PNG: &str = "test.png";

/// The directory of specimen `plan` in the test's directory `out`.
pub fn specimen_dir(out: &Path, plan: &SpecimenPlan) -> PathBuf {
    out.join(SPECIMENS).join(plan.name())
}

/// Makes `out` and `out/specimens` where missing, refusing a file where
/// either goes and a `test.json` that is not a test's (it would be
/// replaced): an object with a `specimens` list, beside `specimens/`.
///
/// # Errors
/// As said, naming the path and what to do.
pub fn take_directory(out: &Path) -> anyhow::Result<()> {
    let specimens = out.join(SPECIMENS);
    for path in [out, specimens.as_path()] {
        if path.exists() && !path.is_dir() {
            return Err(anyhow!(
                "cannot use {} as the test's {}: it exists and is not a directory; choose another directory (--out)",
                path.display(),
                if path == out {
                    "directory"
                } else {
                    "specimens' directory"
                }
            ));
        }
    }
    let json = out.join(TEST_JSON);
    if (json.exists() || json.is_symlink()) && !is_tests(&json) {
        return Err(anyhow!(
            "{}: not a drape test's test.json (a test's holds a \"specimens\" list and lies beside its specimens directory), and the test would replace it: choose another directory (--out), or move it away",
            json.display()
        ));
    }
    std::fs::create_dir_all(&specimens)
        .with_context(|| format!("cannot make {}", specimens.display()))
}

/// Whether `json` is a file a drape test wrote.
fn is_tests(json: &Path) -> bool {
    let beside = json.parent().is_some_and(|d| d.join(SPECIMENS).is_dir());
    let value: Option<Value> = std::fs::read(json)
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok());
    beside && value.is_some_and(|v| v["specimens"].is_array())
}

/// What a specimen's directory holds of an earlier run of the same text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prior {
    /// A completed run: nothing to do.
    Completed,
    /// An interrupted run with its checkpoint, or a killed one (a
    /// checkpoint and no summary): resume it.
    Interrupted,
    /// Nothing usable (none, another text, a failure): run afresh.
    Nothing,
}

/// What `dir` holds of a run of `text`.
pub fn prior(dir: &Path, text: &str) -> Prior {
    let same = std::fs::read_to_string(dir.join("scenario.toml")).is_ok_and(|t| t == text);
    let checkpoint = dir.join("checkpoint.bin").is_file();
    match summary(dir) {
        Some(s) if same && s["status"] == "completed" => Prior::Completed,
        Some(s) if same && s["status"] == "interrupted" && checkpoint => Prior::Interrupted,
        // A run killed before it could say so (no summary yet, or a
        // multilevel settle's on a finer level) left its checkpoint.
        None if same && checkpoint => Prior::Interrupted,
        _ => Prior::Nothing,
    }
}

/// `dir/summary.json`, if it reads.
pub fn summary(dir: &Path) -> Option<Value> {
    let bytes = std::fs::read(dir.join("summary.json")).ok()?;
    serde_json::from_slice(&bytes).ok()
}

/// Writes `plan`'s text into its directory as `scenario.toml` (unless it
/// holds it already) and returns that path. The temporary copy is made
/// beside the directory, not in it: drape refuses a directory holding
/// files it did not write.
///
/// # Errors
/// The directory or the file cannot be written.
pub fn place_scenario(out: &Path, plan: &SpecimenPlan) -> anyhow::Result<PathBuf> {
    let dir = specimen_dir(out, plan);
    let path = dir.join("scenario.toml");
    if std::fs::read_to_string(&path).is_ok_and(|t| t == plan.text) {
        return Ok(path);
    }
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot make {}", dir.display()))?;
    let temporary = out.join(SPECIMENS).join(format!(
        ".{}.scenario.toml.tmp-{}",
        plan.name(),
        std::process::id()
    ));
    std::fs::write(&temporary, &plan.text)
        .and_then(|()| std::fs::rename(&temporary, &path))
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

/// How a specimen's run ended, as its front end saw it.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// The specimen's number.
    pub index: usize,
    /// `"completed"`, `"failed"` or `"interrupted"`.
    pub status: String,
    /// Why, for a specimen that did not complete.
    pub message: String,
}

/// What the test is, for `test.json`.
pub struct TestInfo<'a> {
    /// The scenario tested.
    pub scenario: &'a Path,
    /// Its title.
    pub title: &'a str,
    /// The test's seed.
    pub seed: u64,
    /// The specimens.
    pub plans: &'a [SpecimenPlan],
}

/// Measures the completed specimens of the test in `out`, and writes
/// `test.json` and `test.png`; returns `test.json`'s value.
///
/// A specimen without an outcome (a test interrupted before it started)
/// is `"interrupted"`; a completed one whose final frame cannot be
/// measured is `"unmeasured"`, with why. The statistics are over the
/// measured ones (`measured` of `count`).
///
/// # Errors
/// `test.json` or `test.png` cannot be written.
pub fn report(out: &Path, test: &TestInfo, outcomes: &[Outcome]) -> anyhow::Result<Value> {
    let mut rows = Vec::new();
    let mut samples = Vec::new();
    let mut shadows = Vec::new();
    let mut radii = None;
    // The measured specimens whose rest state crosses itself, and how often.
    let mut crossing = Vec::new();
    for plan in test.plans {
        let dir = specimen_dir(out, plan);
        let outcome = outcomes.iter().find(|o| o.index == plan.index);
        let (mut status, mut message) = match outcome {
            Some(o) => (o.status.clone(), o.message.clone()),
            None => ("interrupted".to_string(), "not started".to_string()),
        };
        let (mut dc, mut folds, mut crossings) = (Value::Null, Value::Null, Value::Null);
        if status == "completed" {
            match measure_last(&dir) {
                Ok(m) => {
                    let f = m.measurement.folds;
                    let d = m.measurement.drape_coefficient;
                    let c = m.measurement.crossings;
                    samples.push((d, f));
                    (dc, folds, crossings) = (json!(d), json!(f), json!(c));
                    if c > 0 {
                        crossing.push((plan.index, c));
                    }
                    radii.get_or_insert((m.tester.pedestal_radius, m.tester.specimen_radius));
                    shadows.push((plan.index, m.measurement.outline));
                }
                Err(e) => {
                    status = "unmeasured".into();
                    message = format!("completed, but its drape cannot be measured: {e:#}");
                }
            }
        }
        let run_summary = summary(&dir);
        let of_run = |key: &str| run_summary.as_ref().map_or(Value::Null, |s| s[key].clone());
        let wall = of_run("wall_seconds");
        if status == "completed" {
            // The run's own words ("at rest ...", "completed N steps"),
            // whichever front end ran it.
            message = (run_summary.as_ref())
                .and_then(|s| s["message"].as_str())
                .unwrap_or_default()
                .to_string();
        }
        rows.push(json!({
            "specimen": plan.index,
            "status": status,
            "drape_coefficient": dc,
            "folds": folds,
            "crossings": crossings,
            "wall_seconds": wall,
            "newton_iterations": of_run("newton_iterations"),
            "newton_iterations_discarded": of_run("newton_iterations_discarded"),
            "message": message,
            "seed": plan.spec.seed,
            "waviness": plan.spec.waviness,
            "cut_angle": plan.spec.cut_angle,
            "face": plan.spec.face.name(),
            "dir": Path::new(SPECIMENS).join(plan.name()),
        }));
    }
    let e = summarise(&samples);
    let value = json!({
        "scenario": test.scenario,
        "title": test.title,
        "seed": test.seed,
        "specimens": rows,
        "count": test.plans.len(),
        "measured": e.count,
        "mean": e.mean,
        "sd": e.sd,
        "ci95": e.ci95,
        "fold_histogram": e.fold_histogram.iter().map(|(k, v)| (k.to_string(), json!(v))).collect::<serde_json::Map<_, _>>(),
        "modal_folds": e.modal_folds,
        "dc_at_modal_folds": e.dc_at_modal_folds,
        "pedestal_radius": radii.map(|r| r.0),
        "specimen_radius": radii.map(|r| r.1),
        "message": words(&e, test.plans.len()) + &crossing_words(&crossing),
    });
    let json_path = out.join(TEST_JSON);
    let mut text = serde_json::to_string_pretty(&value)?;
    text.push('\n');
    write_atomic(&json_path, text.as_bytes())
        .with_context(|| format!("cannot write {}", json_path.display()))?;
    if let Some((pedestal_radius, specimen_radius)) = radii {
        let figure = drape_render::TestFigure {
            title: test.title.to_string(),
            note: words(&e, test.plans.len()),
            shadows,
            pedestal_radius,
            specimen_radius,
            histogram: e.fold_histogram.iter().map(|(k, v)| (*k, *v)).collect(),
        };
        let png = out.join(TEST_PNG);
        drape_render::test_figure(&figure, &png, 1600, 860)
            .with_context(|| format!("cannot draw {}", png.display()))?;
    }
    Ok(value)
}

/// The final frame of the run in `dir`, measured.
fn measure_last(dir: &Path) -> anyhow::Result<crate::measure::FrameMeasurement> {
    let run = Run::open(dir, Given::default())?;
    let last = run
        .out
        .frames
        .len()
        .checked_sub(1)
        .ok_or_else(|| anyhow!("{}: no frames", dir.display()))?;
    run.measure(last)
}

/// The statistics in words: `test.json`'s `message` and the picture's note.
pub fn words(e: &Ensemble, count: usize) -> String {
    let of = format!("{} of {count} specimens measured", e.count);
    match (e.mean, e.sd, e.ci95, e.modal_folds, e.dc_at_modal_folds) {
        (Some(mean), Some(sd), Some([lo, hi]), Some(folds), Some(dc)) => format!(
            "{of}: DC {mean:.3} ± {sd:.3} (sd), 95 % interval [{lo:.3}, {hi:.3}]; {folds} folds most often, DC {dc:.3} at them"
        ),
        (Some(mean), _, _, Some(folds), _) => {
            format!("{of}: DC {mean:.3}, {folds} folds (one specimen: no spread)")
        }
        _ => format!("{of}: no statistics"),
    }
}

/// The specimens `(number, crossings)` whose final frame crosses itself,
/// in words for `test.json`'s `message` (empty when none does): their
/// folds pass through each other, a rest state self-contact forbids.
fn crossing_words(crossing: &[(usize, usize)]) -> String {
    if crossing.is_empty() {
        return String::new();
    }
    let list: Vec<String> = crossing
        .iter()
        .map(|&(i, c)| format!("{i} ({c} crossing{})", if c == 1 { "" } else { "s" }))
        .collect();
    let (who, verb, whose) = if crossing.len() == 1 {
        ("specimen", "crosses itself", "its")
    } else {
        ("specimens", "cross themselves", "their")
    };
    format!(
        "; {who} {} {verb}: {whose} folds pass through each other (`[contact] self = true` forbids it)",
        list.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::{Prior, crossing_words, prior};

    /// A test whose specimens all stay clear of themselves says nothing
    /// more; one that crosses itself is named with its count.
    #[test]
    fn specimens_crossing_themselves_are_named() {
        assert_eq!(crossing_words(&[]), "");
        assert_eq!(
            crossing_words(&[(2, 24)]),
            "; specimen 2 (24 crossings) crosses itself: its folds pass through each other (`[contact] self = true` forbids it)"
        );
        assert_eq!(
            crossing_words(&[(0, 1), (3, 5)]),
            "; specimens 0 (1 crossing), 3 (5 crossings) cross themselves: their folds pass through each other (`[contact] self = true` forbids it)"
        );
    }

    /// What a specimen's directory holds decides what a test run again
    /// does with it: a completed run is kept, an interrupted one and a
    /// killed one (a checkpoint, no summary: a multilevel settle killed on
    /// a finer level) resume, anything else — another text, a failure, a
    /// killed run without a checkpoint — runs afresh.
    #[test]
    fn a_killed_specimen_with_a_checkpoint_is_resumed() {
        let dir = std::env::temp_dir().join(format!("drape-prior-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let text = "title = \"specimen\"\n";
        std::fs::write(dir.join("scenario.toml"), text).unwrap();
        let summary = |status: Option<&str>| match status {
            Some(s) => std::fs::write(dir.join("summary.json"), format!("{{\"status\": \"{s}\"}}"))
                .unwrap(),
            None => {
                let _ = std::fs::remove_file(dir.join("summary.json"));
            }
        };
        summary(None);
        assert_eq!(prior(&dir, text), Prior::Nothing);
        std::fs::write(dir.join("checkpoint.bin"), b"state").unwrap();
        assert_eq!(prior(&dir, text), Prior::Interrupted);
        assert_eq!(prior(&dir, "title = \"another\"\n"), Prior::Nothing);
        for (status, expected) in [
            ("interrupted", Prior::Interrupted),
            ("completed", Prior::Completed),
            ("failed", Prior::Nothing),
        ] {
            summary(Some(status));
            assert_eq!(prior(&dir, text), expected, "{status}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
