//! Hencky's clamped circular membrane under uniform pressure.
//!
//! Hencky's (1915) solution of the Föppl membrane equations gives the
//! centre deflection `w0 = K a (q a / (E t))^(1/3)`. The constant used here,
//! `K = 0.65344` for `nu = 0.3`, is the corrected value: Hencky's original
//! series carried an arithmetic error (Chien 1948, Fichter 1997 NASA TP-3658)
//! which the `0.662` of older textbooks repeats; the project's notes record
//! 0.65344 checked three independent ways.
//!
//! drape solves the full geometrically nonlinear problem (Green strain,
//! follower pressure), which differs from Föppl's moderate-rotation theory
//! by terms of order `(w0/a)^2 ~ 1 %` at `w0/a = 0.1`, and reaches the
//! static state by heavily damped dynamics (`beta = 1, gamma = 1.5`, large
//! steps: a pseudo-transient continuation whose end state is the static
//! equilibrium).

mod common;

use common::{setup, temp_dir};
use drape::simulation::run;

const K_HENCKY: f64 = 0.65344;

fn centre_deflection(rings: usize, order: usize, pressure: f64) -> f64 {
    let text = format!(
        r#"
[mesh]
shape = "disc"
radius = 0.15
rings = {rings}
order = {order}
[material]
youngs_modulus = 2.0e6
poisson_ratio = 0.3
density = 320.0
thickness = 0.6e-3
[[load]]
kind = "pressure"
value = {pressure}
ramp = 0.1
[[fix]]
boundary = true
[time]
segments = [{{ steps = 30, dt = 2.0e-2 }}]
[output]
every = 1000
[[monitor]]
name = "center"
at = [0.0, 0.0, 0.0]
"#
    );
    let s = setup(&text);
    let dir = temp_dir(&format!("hencky-{rings}-{order}"));
    let summary = run(&s, &dir, &mut |_| {}).unwrap();
    assert!(
        summary.kinetic_energy < 1e-12,
        "not at rest: {}",
        summary.kinetic_energy
    );
    summary.monitors["center"][2]
}

fn hencky(q: f64) -> f64 {
    let (a, et): (f64, f64) = (0.15, 2.0e6 * 0.6e-3);
    K_HENCKY * a * (q * a / et).cbrt()
}

/// At `w0/a = 0.1` the converged solution (T6, 16 rings) lies within 2 %
/// of Hencky's (it is 0.22 % above); the difference is the model's
/// (Föppl vs. exact kinematics), not the mesh's: it scales as `(w0/a)^2`,
/// falling ninefold when the pressure drops 27-fold (`w0/a` threefold).
#[test]
fn hencky_centre_deflection_within_two_percent_and_model_difference_scales() {
    let q = 28.70;
    let w0 = hencky(q);
    assert!((w0 / 0.15 - 0.1).abs() < 1e-3);
    let fine = centre_deflection(16, 2, q);
    let d_high = (fine - w0) / w0;
    assert!(d_high.abs() < 0.02, "{d_high}");
    let d_low = (centre_deflection(16, 2, q / 27.0) - hencky(q / 27.0)) / hencky(q / 27.0);
    let ratio = d_high / d_low;
    eprintln!(
        "Hencky: relative difference {d_high:+.4e} at w0/a = 0.1, {d_low:+.4e} at 0.033 (ratio {ratio:.2}, (w0/a)^2 predicts 9)"
    );
    assert!((ratio - 9.0).abs() < 1.5, "ratio {ratio}");
    // Cubic elements agree with the quadratic reference.
    let cubic = centre_deflection(8, 3, q);
    assert!(
        (cubic - fine).abs() < 1e-4 * fine,
        "T10 {cubic} vs T6 {fine}"
    );
}

/// The discretisation error of T3 meshes (against the T6 16-ring
/// reference) falls under refinement at about the expected second order.
#[test]
fn hencky_t3_discretisation_error_falls_under_refinement() {
    let q = 28.70;
    let reference = centre_deflection(16, 2, q);
    let rings = [2usize, 4, 8];
    let errors: Vec<f64> = rings
        .iter()
        .map(|&r| ((centre_deflection(r, 1, q) - reference) / reference).abs())
        .collect();
    // Least-squares slope of log(error) against log(h), h ~ 1/rings.
    let xs: Vec<f64> = rings.iter().map(|&r| -(r as f64).ln()).collect();
    let ys: Vec<f64> = errors.iter().map(|e| e.ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / 3.0, ys.iter().sum::<f64>() / 3.0);
    let slope = xs
        .iter()
        .zip(&ys)
        .map(|(x, y)| (x - mx) * (y - my))
        .sum::<f64>()
        / xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>();
    eprintln!("Hencky T3 errors vs reference, rings 2/4/8: {errors:?}, fitted order {slope:.2}");
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "{errors:?}");
    assert!(slope > 1.5, "order {slope}");
}
