//! Issue 30: the drape tester settled quasi-statically
//! (`crates/drape-bench/scenarios/settle-bending-t3-static.toml`: the
//! weight put on in 20 static increments, the projected Newton leading
//! each downhill) folds and measures a drape coefficient within the spread
//! that the dynamic settles of the same disc show (docs/validation.md:
//! 0.536–0.600, widened by 0.02), in fewer than 1,000 Newton iterations.

use serde_json::Value;
use std::path::Path;
use std::process::Command;

#[test]
fn the_drape_tester_settles_quasi_statically_into_folds() {
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../drape-bench/scenarios/settle-bending-t3-static.toml");
    let out = std::env::temp_dir().join(format!("drape-quasi-static-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let run = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args([
            "run",
            scenario.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "completed");
    let iterations = summary["newton_iterations"].as_u64().unwrap();
    let measure = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["measure", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        measure.status.success(),
        "{}",
        String::from_utf8_lossy(&measure.stderr)
    );
    let m: Value = serde_json::from_slice(&measure.stdout).unwrap();
    let dc = m["drape_coefficient"].as_f64().unwrap();
    let folds = m["folds"].as_u64().unwrap();
    eprintln!("quasi-static settle: {iterations} Newton iterations, DC {dc:.3}, {folds} folds");
    assert!(iterations <= 1000, "{iterations} Newton iterations");
    assert!((0.516..=0.620).contains(&dc), "DC {dc}");
    assert!(folds >= 3, "{folds} folds");
    std::fs::remove_dir_all(&out).unwrap();
}
