//! Tension-field wrinkling at the structural level: the classical in-plane
//! shear test against each model's closed form, and the fabric on the
//! pedestal with wrinkling (both contact methods, Newton's effort).

mod common;

use common::{column, read_history, setup, sheared_equilibrium, temp_dir};
use std::path::Path;

/// A square membrane whose whole edge is held on a homogeneous simple
/// shear `x' = x + gamma y, y' = y` (the classical tension-field shear
/// test, with a rigid shearing frame), solved statically.
///
/// # Closed forms
///
/// The deformation is homogeneous and so is any equilibrium state: `F =
/// [[1, gamma], [0, 1]]`, `E = 1/2 (F^T F - I) = [[0, gamma/2], [gamma/2,
/// gamma^2/2]]`. Without wrinkling, SVK gives principal stresses of
/// opposite signs (about `+-G gamma`, `G = Y / (2 (1 + nu))`) along the
/// diagonals: the membrane is wrinkled.
///
/// * `stress-projection`: `S = C E` has principal values `s1 > 0 > s2`; the
///   projection keeps `s1 n1 (x) n1`: a uniaxial stress of magnitude
///   `s1 = (S11 + S22)/2 + sqrt(((S11 - S22)/2)^2 + S12^2)` along `n1`,
///   to first order `G gamma` at 45 degrees.
/// * `relaxed-energy`: the principal strains `E1,2 = gamma^2/4 +-
///   sqrt(gamma^4/16 + gamma^2/4)` satisfy `E2 < -nu E1`: wrinkled, with a
///   uniaxial stress `Y E1` along the major strain direction, to first
///   order `Y gamma / 2` at 45 degrees — larger than the projection's by
///   the factor `1 + nu`: the stress criterion lets the Poisson effect of
///   the (suppressed) compression act, the strain criterion does not.
///
/// The test checks every element: wrinkled, uniaxial (minor principal
/// stress zero), major principal stress equal to the model's closed form,
/// and the interior nodes on the homogeneous field.
#[test]
fn in_plane_shear_wrinkles_at_45_degrees_with_each_models_closed_form() {
    let (young, nu, gamma) = (2.0e6f64, 0.3f64, 0.05f64);
    for model in ["stress-projection", "relaxed-energy"] {
        let text = format!(
            r#"
[mesh]
shape = "rectangle"
size = [0.1, 0.1]
divisions = [6, 6]
pattern = "alternate"
center = [0.05, 0.05, 0.0]
[material]
youngs_modulus = {young}
poisson_ratio = {nu}
density = 320.0
thickness = 0.6e-3
wrinkling = "{model}"
[[fix]]
boundary = true
[analysis]
kind = "static"
steps = 1
[output]
every = 1
"#
        );
        let mut s = setup(&text);
        // The held edge on the sheared field, the interior started off it.
        let (positions, err) = sheared_equilibrium(&mut s, gamma);
        assert!(
            err < 1e-9,
            "{model}: interior off the homogeneous shear by {err:e} m"
        );
        // Closed forms.
        let e = [0.0, 0.5 * gamma * gamma, gamma];
        let expected = if model == "stress-projection" {
            let k = young / (1.0 - nu * nu);
            let (s11, s22, s12) = (
                k * (e[0] + nu * e[1]),
                k * (e[1] + nu * e[0]),
                young / (2.0 * (1.0 + nu)) * e[2],
            );
            0.5 * (s11 + s22) + (0.25 * (s11 - s22).powi(2) + s12 * s12).sqrt()
        } else {
            let (a, b, c) = (e[0], e[1], 0.5 * e[2]);
            young * (0.5 * (a + b) + (0.25 * (a - b).powi(2) + c * c).sqrt())
        };
        let results = s.model.element_results(&positions);
        for (el, p) in results.principal.iter().enumerate() {
            assert_eq!(results.state[el], 1, "{model}: element {el} not wrinkled");
            assert!(
                p[1].abs() < 1e-9 * expected,
                "{model}: minor principal stress {}",
                p[1]
            );
            assert!(
                (p[0] - expected).abs() < 1e-9 * expected,
                "{model}: {} vs closed form {expected}",
                p[0]
            );
        }
        // Wrinkles (the tension direction) at 45 degrees, to O(gamma): the
        // stress in the element frame of an element whose first edge is
        // along x.
        let s0 = results.stress[0];
        let angle = 0.5 * (2.0 * s0[2]).atan2(s0[0] - s0[1]);
        eprintln!(
            "{model}: uniaxial stress {expected:.2} Pa at {:.2} degrees",
            angle.to_degrees()
        );
        assert!(
            (angle.abs().to_degrees() - 45.0).abs() < gamma.to_degrees(),
            "{model}: {}",
            angle.to_degrees()
        );
    }
}

/// The bundled `example` with `wrinkling`, node to surface (`[contact]
/// features = false`, as its multipliers' twin), the side and corner
/// monitors added if `extra_monitors`: its history and summary.
fn run(
    example: &str,
    wrinkling: &str,
    extra_monitors: bool,
) -> (Vec<String>, Vec<Vec<f64>>, drape::simulation::Summary) {
    run_with(example, wrinkling, extra_monitors, None)
}

/// [`run`], optionally with `[solver] chord_steps` set.
fn run_with(
    example: &str,
    wrinkling: &str,
    extra_monitors: bool,
    chord_steps: Option<usize>,
) -> (Vec<String>, Vec<Vec<f64>>, drape::simulation::Summary) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(example);
    let mut text = std::fs::read_to_string(&path).unwrap();
    text = text
        .lines()
        .map(|l| {
            if l.starts_with("wrinkling") {
                format!("wrinkling = \"{wrinkling}\"")
            } else if l.starts_with("features") {
                // Node to surface, as with multipliers (which keep no
                // obstacle features): the methods are compared alike.
                "features = false".to_string()
            } else if let (Some(c), true) = (chord_steps, l.starts_with("max_iterations")) {
                format!("{l}\nchord_steps = {c}")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    if extra_monitors {
        text.push_str("\n[[monitor]]\nname = \"fabric_corner\"\nat = [0.1, 0.1, 0.0]\n");
        for (name, at) in [
            ("side_px", "[0.1, 0.0, 0.0]"),
            ("side_py", "[0.0, 0.1, 0.0]"),
            ("side_mx", "[-0.1, 0.0, 0.0]"),
            ("side_my", "[0.0, -0.1, 0.0]"),
        ] {
            text.push_str(&format!("[[monitor]]\nname = \"{name}\"\nat = {at}\n"));
        }
    }
    text.push('\n');
    let text = text.replace("every = 10 ", "every = 100000 ");
    let s = setup(&text);
    let dir = temp_dir(&format!("wr-{example}-{wrinkling}"));
    let summary = drape::simulation::run(&s, &dir, &mut |_| {}).unwrap();
    let (h, rows) = read_history(&dir);
    let _ = std::fs::remove_dir_all(&dir);
    (h, rows, summary)
}

/// The pedestal with stress projection, penalty and multipliers: the free
/// edges hang down over the sides — at 0.145 s the side midpoints are a
/// little over 5 cm below the top (tension-field statics: 5 cm at rest)
/// and the corners too (5 sqrt 2 cm at rest, not reached yet) — and the
/// two methods agree within 1 mm at the centre and the side midpoints.
#[test]
fn pedestal_with_stress_projection_drapes_and_both_methods_agree() {
    let (_, rows_p, pen) = run("fabric-on-pedestal.toml", "stress-projection", true);
    let (h, rows_l, lag) = run(
        "fabric-on-pedestal-lagrange.toml",
        "stress-projection",
        true,
    );
    for (name, m) in [("penalty", &pen), ("lagrange", &lag)] {
        for side in ["side_px", "side_py", "side_mx", "side_my"] {
            let z = m.monitors[side][2];
            assert!(z < -0.10 && z > -0.11, "{name} {side}: z = {z}");
        }
        let corner = m.monitors["fabric_corner"][2];
        assert!(
            corner < -0.10 && corner > -0.05 - 0.05 * 2f64.sqrt(),
            "{name} corner z = {corner}"
        );
    }
    for name in ["center", "side_px", "side_py", "side_mx", "side_my"] {
        let (a, b) = (pen.monitors[name], lag.monitors[name]);
        let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        assert!(d < 1e-3, "{name}: penalty and multipliers {d:e} m apart");
    }
    let slack = column(&h, &rows_l, "slack_fraction");
    let wrinkled = column(&h, &rows_l, "wrinkled_fraction");
    assert!(
        wrinkled.last().unwrap() + slack.last().unwrap() > 0.1,
        "the draped fabric wrinkles"
    );
    let _ = rows_p;
}

/// Newton's effort with and without wrinkling: the mean and largest
/// iterations per step of the pedestal (penalty and multipliers) with
/// `none`, `stress-projection` and `relaxed-energy`; stress projection must
/// not need more than 1.5 times the iterations without wrinkling. Plain
/// Newton (no chord steps): this measures how the wrinkling tangent serves
/// Newton, not how often a factorisation can be reused.
#[test]
fn newton_effort_with_wrinkling_is_at_most_one_and_a_half_times() {
    for example in [
        "fabric-on-pedestal.toml",
        "fabric-on-pedestal-lagrange.toml",
    ] {
        let mut totals = Vec::new();
        for model in ["none", "stress-projection", "relaxed-energy"] {
            let (h, rows, summary) = run_with(example, model, false, Some(0));
            let its = column(&h, &rows, "iterations");
            let steps = its.len() - 1;
            let max = its.iter().copied().fold(0.0, f64::max);
            eprintln!(
                "{example} {model}: {} iterations in {steps} steps, mean {:.2}, max {max}, {:.2} s",
                summary.newton_iterations,
                summary.newton_iterations as f64 / steps as f64,
                summary.wall_seconds
            );
            totals.push(summary.newton_iterations as f64);
        }
        assert!(totals[1] <= 1.5 * totals[0], "{example}: {totals:?}");
    }
}

/// Chord steps on the wrinkling pedestal (penalty): the same drape as
/// plain Newton (centre and side midpoints within 1 mm, the bound of the
/// test above: the fold of the corners may take the mirror branch through
/// round-off), with at most 82 % of its factorisations. Both gates matter
/// here: tried only after a Newton step that shrank the increment
/// fourfold, chord steps save 17 % (1,324 factorisations against plain
/// Newton's 1,587); tried also after one that cut the residual a
/// hundredfold — the step that follows a linear phase where wrinkling
/// states switched — they save 29 % (1,133). The bound sits between the
/// two (checked: the test fails with the increment gate alone).
#[test]
fn chord_steps_save_a_fifth_of_the_factorisations_on_the_wrinkling_pedestal() {
    let (_, _, plain) = run_with(
        "fabric-on-pedestal.toml",
        "stress-projection",
        true,
        Some(0),
    );
    let (_, _, chord) = run_with("fabric-on-pedestal.toml", "stress-projection", true, None);
    let (p, c) = (
        plain.linear.block_lu_factorizations as f64,
        chord.linear.block_lu_factorizations as f64,
    );
    eprintln!(
        "factorisations: plain Newton {p}, with chord steps {c} ({:.3})",
        c / p
    );
    assert!(c <= 0.82 * p, "plain {p}, chord {c}");
    for name in ["center", "side_px", "side_py", "side_mx", "side_my"] {
        let (a, b) = (plain.monitors[name], chord.monitors[name]);
        let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        assert!(d < 1e-3, "{name}: plain and chord {d:e} m apart");
    }
}

/// The pedestal's steps (penalty, stress projection) advanced with
/// `Newmark::step`, the predictor's acceleration persistence either as
/// measured (`adaptive`) or held at 1 (the constant-acceleration
/// predictor); returns the Newton iterations and the final positions.
fn pedestal_steps(adaptive: bool) -> (usize, Vec<f64>, drape::model::Model) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fabric-on-pedestal.toml");
    let s = setup(&std::fs::read_to_string(path).unwrap());
    let drape::setup::Analysis::Dynamic { newmark, segments } = &s.analysis else {
        panic!("the pedestal is dynamic");
    };
    let model = &s.model;
    let mut ws = drape::integrator::newmark::DynamicWorkspace::new(model).unwrap();
    let mut state = newmark.initial_state(model, &mut ws).unwrap();
    let length = drape::simulation::reference_length(&model.initial_positions());
    let mut iterations = 0;
    for &(steps, dt) in segments {
        for _ in 0..steps {
            if !adaptive {
                state.persistence = 1.0;
            }
            let outcome = newmark
                .step(model, &mut state, dt, &s.newton, length, &mut ws)
                .unwrap();
            assert!((0.0..=1.0).contains(&state.persistence));
            iterations += outcome.newton.iterations;
        }
    }
    (iterations, state.positions, s.model)
}

/// The predictor that carries over only the acceleration that persisted
/// (`drape::integrator::newmark`'s module docs) needs at most 97 % of the
/// Newton iterations of the constant-acceleration predictor on the
/// wrinkling pedestal (measured: 1,077 against 1,133), with the same drape:
/// the centre and side midpoints within 1 mm, the bound of the tests above
/// (the corners' fold may take its mirror branch through round-off).
#[test]
fn the_persistence_predictor_saves_newton_iterations_on_the_pedestal() {
    let (adaptive, y_a, model) = pedestal_steps(true);
    let (constant, y_c, _) = pedestal_steps(false);
    eprintln!(
        "Newton iterations: persistence predictor {adaptive}, constant acceleration {constant}"
    );
    assert!(
        adaptive as f64 <= 0.97 * constant as f64,
        "persistence {adaptive}, constant acceleration {constant}"
    );
    for at in [[0.0, 0.0], [0.1, 0.0], [0.0, 0.1], [-0.1, 0.0], [0.0, -0.1]] {
        let node = (0..model.mesh().nodes.len())
            .min_by(|&a, &b| {
                let d = |n: usize| {
                    let x = &model.mesh().nodes[n];
                    (x[0] - at[0]).powi(2) + (x[1] - at[1]).powi(2)
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let d = (0..3)
            .map(|i| (y_a[3 * node + i] - y_c[3 * node + i]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(d < 1e-3, "node at {at:?}: the two predictors {d:e} m apart");
    }
}
