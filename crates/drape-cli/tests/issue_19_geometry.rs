//! Issue 19: geometry that was silently wrong. An obstacle that moves
//! more than half the fabric's smallest element edge in one step (it can
//! pass through the fabric between two steps unseen) is warned about by
//! `check` and `run`, and the warning is recorded in `summary.json`.

mod issue_19_support;

use issue_19_support::{drape, falling_plate, run_into, scratch, text};
use serde_json::Value;

/// A sphere above the 4 x 4 plate (edges of 2.5 cm) falling at `speed`
/// m/s, steps of 1 ms.
fn sphere(speed: f64) -> String {
    format!(
        "[[obstacle]]\nshape = \"sphere\"\ncenter = [0.05, 0.05, 0.5]\nradius = 0.05\nvelocity = [0.0, 0.0, {}]\n[contact]\nmethod = \"penalty\"\npenalty = 1.0e4",
        -speed
    )
}

#[test]
fn an_obstacle_faster_than_the_mesh_is_warned_about_and_recorded() {
    let dir = scratch("geometry-fast");
    // 1000 m/s x 1 ms = 1 m a step against 0.5 x 0.025 m.
    let scenario = falling_plate(&dir, 3, &sphere(1000.0));
    let o = drape(&["check".as_ref(), scenario.as_os_str()]);
    let said = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    for f in [
        "warning",
        "obstacle[0] moves 1.000e0 m in a step",
        "2.500e-2 m",
        "pass through the fabric",
    ] {
        assert!(said.contains(f), "expected {f:?} in {said}");
    }
    let out = dir.join("out");
    let o = run_into(&scenario, &out);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("warning: obstacle[0] moves"));
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let warnings = s["warnings"].as_array().expect("warnings in the summary");
    assert_eq!(warnings.len(), 1, "{s}");
    assert!(warnings[0].as_str().unwrap().contains("obstacle[0] moves"));

    // 10 m/s: 1 cm a step, below 1.25 cm: no warning, no key.
    let slow = falling_plate(&dir, 3, &sphere(10.0));
    let o = drape(&["check".as_ref(), slow.as_os_str()]);
    assert!(!text(&o.stdout).contains("warning"), "{}", text(&o.stdout));
    let o = run_into(&slow, &out);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(s.get("warnings").is_none(), "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}
