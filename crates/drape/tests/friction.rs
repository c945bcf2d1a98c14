//! Coulomb friction against obstacles (issue 32), penalty contact, on
//! whole runs against closed forms: a patch on an incline sticks below
//! the friction angle and slides above it with `a = g (sin θ - μ cos θ)`;
//! a patch on a moving plane is dragged along with it, and left behind
//! without friction; the dissipated energy never decreases. The term's
//! derivatives are checked against finite differences beside it
//! (`integrator/terms/friction.rs`).

mod common;

use common::{column, read_history, rectangle, setup, temp_dir};
use drape::simulation::run;

/// A 5 cm patch (4 x 4 squares) lying on the plane z = 0 (moving at
/// `velocity`), under gravity `g` at `angle` (radians) from the
/// vertical, tilted towards +x — an incline of that angle — with
/// friction `mu` (the plane's own `plane_mu` where given), for 0.5 s of
/// 1 ms steps; the history.
fn on_plane(
    angle: f64,
    (mu, plane_mu): (f64, Option<f64>),
    velocity: f64,
    name: &str,
) -> (Vec<String>, Vec<Vec<f64>>) {
    let own = plane_mu.map_or(String::new(), |m| format!("friction = {m}"));
    let (s, c) = angle.sin_cos();
    let text = rectangle(
        [0.05, 0.05],
        [4, 4],
        &format!(
            r#"
[[load]]
kind = "gravity"
acceleration = [{gx}, 0.0, {gz}]
[[obstacle]]
shape = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
velocity = [{velocity}, 0.0, 0.0]
{own}
[contact]
method = "penalty"
penalty = 5.0e4
friction = {mu}
[time]
segments = [{{ steps = 500, dt = 1.0e-3 }}]
[output]
every = 1000
[[monitor]]
name = "c"
at = [0.0, 0.0, 0.0]
"#,
            gx = 9.8 * s,
            gz = -9.8 * c,
        ),
    );
    let dir = temp_dir(name);
    run(&setup(&text), &dir, &mut |_| {}).unwrap();
    read_history(&dir)
}

/// Below the friction angle (tan θ = 0.2 < μ = 0.4) the patch holds: it
/// creeps at most at the stick speed (1 mm/s), so it moves less than 1 mm
/// in 0.5 s (the issue's bound). Above it (tan θ = 0.6) it slides with
/// `a = g (sin θ - μ cos θ)`: the distance at 0.5 s within 2 % of `a t^2
/// / 2`.
#[test]
fn an_incline_holds_below_the_friction_angle_and_slides_above() {
    let mu = 0.4;
    for (tan, name) in [(0.2, "incline-stick"), (0.6, "incline-slide")] {
        let angle = f64::atan(tan);
        let (h, rows) = on_plane(angle, (mu, None), 0.0, name);
        let x = column(&h, &rows, "c_x");
        let t = column(&h, &rows, "time");
        let moved = x.last().unwrap() - x[0];
        let end = *t.last().unwrap();
        if tan < mu {
            assert!(moved.abs() < 1e-3, "tan {tan}: moved {moved:e} m");
        } else {
            let a = 9.8 * (angle.sin() - mu * angle.cos());
            let expected = 0.5 * a * end * end;
            let error = (moved - expected) / expected;
            eprintln!("tan {tan}: slid {moved:.6} m, a t^2 / 2 = {expected:.6} m ({error:+.2e})");
            assert!(error.abs() < 0.02, "slid {moved} m against {expected} m");
        }
        let d = column(&h, &rows, "friction_dissipation");
        assert!(d.windows(2).all(|w| w[1] >= w[0]), "dissipation decreased");
        assert!(*d.last().unwrap() > 0.0);
    }
}

/// A plane moving at 0.1 m/s under the patch drags it along (μ = 0.5:
/// it catches up within a few hundredths of a second and then moves with
/// the plane, its speed within the stick speed of the plane's); without
/// friction the patch stays where it was.
#[test]
fn a_moving_plane_drags_the_fabric_that_sticks_to_it() {
    for (mu, name) in [(0.5, "drag"), (0.0, "no-drag")] {
        let (h, rows) = on_plane(0.0, (mu, None), 0.1, name);
        let x = column(&h, &rows, "c_x");
        let t = column(&h, &rows, "time");
        let n = rows.len();
        let speed = (x[n - 1] - x[n - 11]) / (t[n - 1] - t[n - 11]);
        if mu > 0.0 {
            assert!((speed - 0.1).abs() < 2e-3, "mu {mu}: speed {speed} m/s");
        } else {
            assert!(speed.abs() < 1e-9 && x[n - 1].abs() < 1e-9, "speed {speed}");
        }
    }
}

/// An obstacle's own `friction` takes the place of `[contact] friction`:
/// the plane's 0.4 holds the patch on the incline of tan θ = 0.2 although
/// `[contact]` says 0, and the plane's 0 lets it slide freely (`g sin θ
/// t^2 / 2`, to 2 %) although `[contact]` says 0.4.
#[test]
fn an_obstacles_own_friction_takes_the_place_of_the_contacts() {
    let angle = f64::atan(0.2);
    for ((mu, plane_mu), holds) in [((0.0, Some(0.4)), true), ((0.4, Some(0.0)), false)] {
        let (h, rows) = on_plane(angle, (mu, plane_mu), 0.0, &format!("own-{holds}"));
        let x = column(&h, &rows, "c_x");
        let t = column(&h, &rows, "time");
        let moved = x.last().unwrap() - x[0];
        if holds {
            assert!(moved.abs() < 1e-3, "moved {moved:e} m");
        } else {
            let end = *t.last().unwrap();
            let expected = 0.5 * 9.8 * angle.sin() * end * end;
            assert!(
                (moved - expected).abs() < 0.02 * expected,
                "{moved} against {expected}"
            );
        }
    }
}
