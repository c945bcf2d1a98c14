//! Issue 46, "Obstacle corners and rims pass through the fabric between
//! its nodes": node-to-surface contact keeps the fabric's nodes out of an
//! obstacle, but a box's edge or corner could cross a coarse triangle
//! between them. `[contact] features = true` (with a penalty; default
//! false) keeps the obstacles' sharp features out of the triangles too.

mod common;

use common::{build, drive, read_history, temp_dir};
use drape::contact::features::ObstacleFeatures;
use drape::setup::Setup;
use std::path::Path;

/// A strip 20 cm long and 4 cm wide in 2.5 cm squares, 2 mm above a box
/// wider than the strip whose two top edges lie across it between the
/// strip's node lines (x = 0.06 and -0.07; the nodes are at multiples of
/// 2.5 cm), falling onto it under its weight for `steps` ms; `contact`
/// adds to `[contact]`.
fn strip_over_a_box(contact: &str, steps: usize) -> String {
    format!(
        r#"
[mesh]
shape = "rectangle"
size = [0.2, 0.04]
divisions = [8, 2]
[material]
youngs_modulus = 2.0e6
poisson_ratio = 0.3
density = 320.0
thickness = 0.6e-3
wrinkling = "stress-projection"
[[load]]
kind = "surface"
force = [0.0, 0.0, -1.8816]
[[obstacle]]
shape = "box"
min = [-0.07, -0.1, -0.3]
max = [0.06, 0.1, -0.002]
[contact]
method = "penalty"
penalty = 5.0e4
{contact}
[time]
beta = 1.0
gamma = 1.5
segments = [ {{ steps = {steps}, dt = 1.0e-3 }} ]
"#
    )
}

/// The deepest any sampled point of the setup's obstacles lies through the
/// fabric at `y` (m), measured with the features' own sampling whether or
/// not the run kept them out.
fn deepest(s: &Setup, y: &[f64]) -> f64 {
    let contact = s.model.contact().expect("obstacles");
    let mesh = s.model.mesh();
    let triangles = drape::bending::triangulate(mesh).0;
    let features = ObstacleFeatures::new(contact, triangles, &mesh.nodes.concat())
        .expect("a box has features");
    features.deepest(y, 0.0)
}

/// The pedestal example (examples/fabric-on-pedestal.toml: a 20 cm
/// sheet of 1 cm elements falling onto a 10 cm box and draping over it)
/// without and with `features`: without, the box's top corners pass
/// through the sheet between its nodes (the corner node slides down the
/// side, and the corner stands millimetres through the triangles beside
/// it); with them no sampled point of the box lies through any triangle
/// by more than one step's travel of the fabric, 0.1 mm (the pairs are
/// found at each step's start, so a point may cross a triangle it was not
/// paired with by what the fabric moves in one 0.1 ms step at the fall's
/// 1 m/s before the next step takes the pair in; the penalty's own scale,
/// the sheet's weight over eta, is 1.5 um).
#[test]
fn pedestal_corners_stay_out_of_the_fabric() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fabric-on-pedestal.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let step_travel = 1.0 * 1e-4;
    let mut depths = Vec::new();
    for features in [false, true] {
        let text = text.replace("features = true", &format!("features = {features}"));
        let s = build(&text, &path).unwrap();
        assert_eq!(s.model.obstacle_features().is_some(), features);
        let y = drive(&s, |_| {}).positions;
        let depth = deepest(&s, &y);
        let contact = s.model.contact().unwrap();
        let state = contact.initial_state(&y);
        let (_, min_gap) = contact.near_pairs(&y, 0.0, &state, 0.0, true);
        eprintln!(
            "features = {features}: deepest feature point {depth:e} m, smallest node gap {min_gap:e} m"
        );
        depths.push(depth);
    }
    assert!(depths[0] > 1e-3, "without features: {:e}", depths[0]);
    assert!(
        depths[1] <= step_travel,
        "with features: {:e} beyond {step_travel:e}",
        depths[1],
    );
}

/// A run whose obstacles have no sharp feature (a plane, a sphere) writes
/// the same history to the bit with and without `features`: the term is
/// not even built.
#[test]
fn runs_without_sharp_features_are_unchanged_to_the_bit() {
    let path = Path::new("test.toml");
    for obstacle in [
        "shape = \"plane\"\npoint = [0.0, 0.0, -0.01]\nnormal = [0.0, 0.0, 1.0]",
        "shape = \"sphere\"\ncenter = [0.0, 0.0, -0.06]\nradius = 0.05",
    ] {
        let mut histories = Vec::new();
        for contact in ["", "features = true"] {
            let text = strip_over_a_box(contact, 60).replace(
                "shape = \"box\"\nmin = [-0.07, -0.1, -0.3]\nmax = [0.06, 0.1, -0.002]",
                obstacle,
            );
            let s = build(&text, path).unwrap();
            assert!(s.model.obstacle_features().is_none(), "{obstacle}");
            let dir = temp_dir("features-bit-for-bit");
            let summary = drape::simulation::run(&s, &dir, &mut |_| {}).unwrap();
            assert_eq!(summary.status, "completed");
            let (_, rows) = read_history(&dir);
            assert_eq!(rows.len(), 61);
            histories.push(std::fs::read(dir.join("history.csv")).unwrap());
        }
        assert!(histories[0] == histories[1], "{obstacle}: histories differ");
    }
}

/// `features` must be a boolean, and exists with a penalty only: the
/// file, line and key are named.
#[test]
fn bad_features_values_are_refused_by_name() {
    let bad = strip_over_a_box("features = \"yes\"", 1);
    let line = bad.lines().position(|l| l.starts_with("features")).unwrap() + 1;
    common::assert_error(&bad, line, "contact.features", &["boolean"]);
    let lagrange = strip_over_a_box("features = true", 1).replace(
        "method = \"penalty\"\npenalty = 5.0e4",
        "method = \"lagrange\"",
    );
    let line = lagrange
        .lines()
        .position(|l| l.starts_with("features"))
        .unwrap()
        + 1;
    common::assert_error(&lagrange, line, "contact", &["features"]);
}
