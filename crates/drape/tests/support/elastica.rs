//! Reference solution: a cantilever bending under its own weight, with large
//! deflection (the heavy elastica).
//!
//! A strip of length `L` is clamped horizontally at arc length `s = 0` and
//! carries a uniform weight `q` (N per metre of arc length); its bending
//! rigidity is `EI` (N·m²). For a fabric strip of width `W`, bending rigidity
//! `B` per unit width (N·m), density `rho` and thickness `t`, that is
//! `EI = B W` and `q = rho t g W`.
//!
//! With `theta(s)` the angle of the tangent below the horizontal, `x(s)` the
//! horizontal and `z(s)` the downward position, equilibrium of the part
//! `[s, L]` gives
//!
//! ```text
//! EI theta'(s) = q ∫_s^L (x(σ) − x(s)) dσ          (moment of the weight beyond s)
//! ```
//!
//! equivalently
//!
//! ```text
//! EI theta''(s) = −q (L − s) cos theta(s),   theta(0) = 0,   theta'(L) = 0,
//! x' = cos theta,  z' = sin theta,  x(0) = z(0) = 0.
//! ```
//!
//! In the arc length `u = s / L` the problem depends on the single number
//! `k = q L³ / EI`: `theta_uu = −k (1 − u) cos theta`.
//!
//! It is solved by shooting from the tip rather than from the clamp. For
//! large `k` the strip hangs close to vertical, near `theta = π/2`, which is a
//! saddle of the equation (`phi = theta − π/2` obeys `phi_uu = k (1 − u) sin phi`,
//! growing like `exp(∫ sqrt(k (1 − u)) du)`, i.e. by up to `exp(⅔ sqrt(k))`): a
//! shot on the root curvature `theta'(0)` then needs more than double
//! precision (at `k ≈ 750`, the two neighbouring doubles of the root
//! curvature already fall back or roll over). From the tip, with the unknown
//! `delta = π/2 − theta(L)` and the state carried as `phi = theta − π/2`, the
//! same growth works for us: `phi` scales with `delta` while it is small, so
//! the root angle is a well-conditioned function of `ln delta`, and tiny
//! values of `delta` keep their full relative precision.
//!
//! With `tau = 1 − u` (from the tip), `phi_tautau = k tau sin phi`,
//! `phi(0) = −delta`, `phi_tau(0) = 0`; the clamp condition is
//! `phi(tau = 1) = −π/2`. Fixed-step classical Runge–Kutta (RK4) integrates
//! the state `(phi, phi_tau, x/L, z/L)` (the positions measured from the tip,
//! shifted to the clamp afterwards), and `delta` is found by bisection in
//! `(0, π/2)`, first on `ln delta`, then on `delta`, until no representable
//! number lies between the bounds. The bisection is monotone: for
//! `−π/2 ≤ phi ≤ 0`, `sin phi` increases with `phi`, so by the comparison
//! theorem a smaller `delta` gives a larger `phi` at every `tau`; a trial whose
//! `phi` passes `−π/2` before the clamp has `delta` too large, one that ends
//! above `−π/2` too small. `delta = π/2` (a horizontal tip) is too large for
//! any `k > 0`, `delta → 0` too small.
//!
//! Limits: for `k → 0`, tip deflection `q L⁴ / (8 EI)`, tip angle
//! `q L³ / (6 EI)`, root curvature `q L² / (2 EI)`; for `k → ∞` the strip
//! hangs vertically (deflection → `L`).
//!
//! References: K. E. Bisshopp and D. C. Drucker, "Large deflection of
//! cantilever beams", Q. Appl. Math. 3 (1945) 272–275 (point load, a different
//! problem); R. Frisch-Fay, *Flexible Bars*, Butterworths, 1962 (uniform load);
//! F. T. Peirce, "The 'handle' of cloth as a measurable quantity",
//! J. Textile Inst. 21 (1930) T377–T416 (cantilever test, bending length
//! `c = (EI / q)^(1/3)`, chord at 41.5° when `c ≈ L / 2`).

// Each integration test uses a subset of these items.
#![allow(dead_code)]

use std::f64::consts::FRAC_PI_2;

/// Number of fixed RK4 steps over the length used by [`cantilever`].
pub const STEPS: usize = 2000;

/// The tip of a cantilever under its own weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Elastica {
    /// Downward tip displacement `z(L) = ∫_0^L sin theta ds` (m), positive down.
    pub tip_deflection: f64,
    /// Horizontal tip position `x(L) = ∫_0^L cos theta ds` (m).
    pub tip_horizontal: f64,
    /// Tangent angle at the tip below the horizontal, `theta(L)` (rad).
    pub tip_angle: f64,
    /// Curvature at the clamp, `theta'(0)` (1/m); the root moment is `EI theta'(0)`.
    pub root_curvature: f64,
}

impl Elastica {
    /// Angle of the clamp-to-tip chord below the horizontal (rad), the angle
    /// read in Peirce's cantilever test.
    pub fn chord_angle(&self) -> f64 {
        self.tip_deflection.atan2(self.tip_horizontal)
    }
}

/// One arc-length station of the deflected strip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Station {
    /// Arc length from the clamp (m).
    pub s: f64,
    /// Horizontal position (m).
    pub x: f64,
    /// Downward position (m), positive down.
    pub z: f64,
    /// Tangent angle below the horizontal (rad).
    pub theta: f64,
    /// Curvature `theta'(s)` (1/m); the bending moment is `EI theta'(s)`.
    pub curvature: f64,
}

/// Dimensionless state `(phi, phi_tau, X, Z)` at `tau = 1 − s/L`, with
/// `phi = theta − π/2` and `(X, Z)` the position relative to the tip, over `L`.
type State = [f64; 4];

fn derivative(k: f64, tau: f64, y: &State) -> State {
    let (sin, cos) = y[0].sin_cos();
    // x_u = cos theta = −sin phi and z_u = sin theta = cos phi; d/dtau = −d/du.
    [y[1], k * tau * sin, sin, -cos]
}

fn rk4_step(k: f64, tau: f64, h: f64, y: &State) -> State {
    let add = |a: &State, b: &State, c: f64| -> State {
        [
            a[0] + c * b[0],
            a[1] + c * b[1],
            a[2] + c * b[2],
            a[3] + c * b[3],
        ]
    };
    let k1 = derivative(k, tau, y);
    let k2 = derivative(k, tau + 0.5 * h, &add(y, &k1, 0.5 * h));
    let k3 = derivative(k, tau + 0.5 * h, &add(y, &k2, 0.5 * h));
    let k4 = derivative(k, tau + h, &add(y, &k3, h));
    let mut next = *y;
    for i in 0..4 {
        next[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    next
}

/// Integrates from the tip to the clamp with `phi(tip) = −delta` in `steps`
/// RK4 steps. Returns `None` as soon as `phi` passes `−π/2` (`delta` too
/// large), else the state at the clamp. Every `every` steps (and at the tip)
/// the state is pushed to `record`, if given.
fn shoot(
    k: f64,
    delta: f64,
    steps: usize,
    mut record: Option<(&mut Vec<State>, usize)>,
) -> Option<State> {
    let h = 1.0 / steps as f64;
    let mut y: State = [-delta, 0.0, 0.0, 0.0];
    if let Some((states, _)) = record.as_mut() {
        states.push(y);
    }
    for i in 0..steps {
        y = rk4_step(k, i as f64 * h, h, &y);
        if y[0] < -FRAC_PI_2 {
            return None;
        }
        let due = |(_, every): &&mut (&mut Vec<State>, usize)| (i + 1).is_multiple_of(*every);
        if let Some((states, _)) = record.as_mut().filter(due) {
            states.push(y);
        }
    }
    Some(y)
}

/// `delta = π/2 − theta(L)` for `k = q L³ / EI > 0`: the largest double whose
/// shot does not pass `−π/2` before the clamp.
fn tip_gap(k: f64, steps: usize) -> f64 {
    let reaches = |delta: f64| shoot(k, delta, steps, None).is_some();
    let (mut lo, mut hi) = (f64::MIN_POSITIVE, FRAC_PI_2);
    assert!(
        reaches(lo),
        "q L³ / EI = {k} is beyond double precision: the tip is within 1e-308 of vertical"
    );
    debug_assert!(!reaches(hi));
    while hi > 2.0 * lo {
        let mid = (0.5 * (lo.ln() + hi.ln())).exp();
        if reaches(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return lo;
        }
        if reaches(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
}

/// The solution at `n + 1` evenly spaced stations from the clamp (`u = 0`)
/// to the tip, as `(theta, theta_u, x/L, z/L)`, with `steps` a multiple of `n`.
fn solve(k: f64, n: usize, steps: usize) -> Vec<State> {
    debug_assert!(n > 0 && steps.is_multiple_of(n));
    if k == 0.0 {
        return (0..=n)
            .map(|i| [0.0, 0.0, i as f64 / n as f64, 0.0])
            .collect();
    }
    let delta = tip_gap(k, steps);
    let mut states = Vec::with_capacity(n + 1);
    let clamp = shoot(k, delta, steps, Some((&mut states, steps / n)))
        .expect("the tip gap found reaches the clamp");
    debug_assert_eq!(states.len(), n + 1);
    states
        .iter()
        .rev()
        .map(|y| [y[0] + FRAC_PI_2, -y[1], y[2] - clamp[2], y[3] - clamp[3]])
        .collect()
}

fn check_input(length: f64, weight_per_length: f64, rigidity: f64) {
    assert!(
        length.is_finite() && length > 0.0,
        "length {length} must be positive"
    );
    assert!(
        weight_per_length.is_finite() && weight_per_length >= 0.0,
        "weight per length {weight_per_length} must be non-negative"
    );
    assert!(
        rigidity.is_finite() && rigidity > 0.0,
        "rigidity {rigidity} must be positive"
    );
}

/// The heavy elastica with `steps` fixed RK4 steps over the length (see the
/// module documentation for the equations).
pub fn cantilever_with_steps(
    length: f64,
    weight_per_length: f64,
    rigidity: f64,
    steps: usize,
) -> Elastica {
    check_input(length, weight_per_length, rigidity);
    assert!(steps > 0, "steps must be positive");
    let k = weight_per_length * length.powi(3) / rigidity;
    let states = solve(k, 1, steps);
    let (clamp, tip) = (states[0], states[1]);
    Elastica {
        tip_deflection: tip[3] * length,
        tip_horizontal: tip[2] * length,
        tip_angle: tip[0],
        root_curvature: clamp[1] / length,
    }
}

/// Tip of a strip of length `length` (m), weight per length
/// `weight_per_length` (N/m) and bending rigidity `rigidity` (N·m²), clamped
/// horizontally, hanging under its own weight:
/// `EI theta'' = −q (L − s) cos theta`, `theta(0) = 0`, `theta'(L) = 0`,
/// solved with [`STEPS`] RK4 steps.
pub fn cantilever(length: f64, weight_per_length: f64, rigidity: f64) -> Elastica {
    cantilever_with_steps(length, weight_per_length, rigidity, STEPS)
}

/// The deflected strip at `n + 1` evenly spaced arc-length stations
/// `s = i L / n`, `i = 0..=n` (integrated with at least [`STEPS`] RK4 steps, a
/// multiple of `n`).
pub fn stations(length: f64, weight_per_length: f64, rigidity: f64, n: usize) -> Vec<Station> {
    check_input(length, weight_per_length, rigidity);
    assert!(n > 0, "n must be positive");
    let k = weight_per_length * length.powi(3) / rigidity;
    let steps = STEPS.div_ceil(n) * n;
    let states = solve(k, n, steps);
    states
        .iter()
        .enumerate()
        .map(|(i, y)| Station {
            s: length * i as f64 / n as f64,
            x: y[2] * length,
            z: y[3] * length,
            theta: y[0],
            curvature: y[1] / length,
        })
        .collect()
}

/// The deflected strip as `(x, z)` (m, `z` positive down) at `n + 1` evenly
/// spaced arc-length stations from the clamp to the tip.
pub fn profile(length: f64, weight_per_length: f64, rigidity: f64, n: usize) -> Vec<(f64, f64)> {
    stations(length, weight_per_length, rigidity, n)
        .iter()
        .map(|station| (station.x, station.z))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn relative(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn small_deflection_limit() {
        // k = q L³ / EI = 1e-4: the linear cantilever under uniform load.
        let (length, q) = (1.3_f64, 2.0);
        let ei = q * length.powi(3) / 1e-4;
        let e = cantilever(length, q, ei);
        let deflection = q * length.powi(4) / (8.0 * ei);
        let angle = q * length.powi(3) / (6.0 * ei);
        let curvature = q * length.powi(2) / (2.0 * ei);
        assert!(
            relative(e.tip_deflection, deflection) < 1e-4,
            "{e:?} vs {deflection}"
        );
        assert!(relative(e.tip_angle, angle) < 1e-4, "{e:?} vs {angle}");
        assert!(
            relative(e.root_curvature, curvature) < 1e-4,
            "{e:?} vs {curvature}"
        );
        assert!(relative(e.tip_horizontal, length) < 1e-8, "{e:?}");
    }

    #[test]
    fn moment_equation_in_integral_form_holds_at_all_stations() {
        // EI theta'(s) = q ∫_s^L (x(σ) − x(s)) dσ, the integral taken from the
        // profile by the trapezoid rule with its end correction
        // −h²/12 (x'(b) − x'(a)), x' = cos theta (fourth order).
        let (length, q) = (0.2_f64, 0.0376704);
        for k in [0.5, 3.0, 8.0, 40.0, 200.0, 753.408, 2000.0] {
            let ei = q * length.powi(3) / k;
            let n = 4000;
            let st = stations(length, q, ei, n);
            // The clamp condition, which the shot from the tip aims at.
            assert!(
                st[0].theta.abs() < 1e-12,
                "k {k}: theta(0) = {:e}",
                st[0].theta
            );
            assert_eq!((st[0].x, st[0].z), (0.0, 0.0));
            assert!(st[n].curvature == 0.0, "k {k}: the tip carries no moment");
            let h = length / n as f64;
            // tail[i] = ∫_{s_i}^L x dσ
            let mut tail = vec![0.0; n + 1];
            for i in (0..n).rev() {
                let (a, b) = (&st[i], &st[i + 1]);
                tail[i] = tail[i + 1] + 0.5 * h * (a.x + b.x)
                    - h * h / 12.0 * (b.theta.cos() - a.theta.cos());
            }
            let scale = ei * st[0].curvature;
            for (i, station) in st.iter().enumerate() {
                let moment = q * (tail[i] - (length - station.s) * station.x);
                let error = (ei * station.curvature - moment).abs() / scale;
                assert!(error < 1e-6, "k {k}, s {}: error {error:e}", station.s);
            }
            // The stations agree with the tip solution.
            let e = cantilever(length, q, ei);
            let tip = st[n];
            assert!(
                (tip.z - e.tip_deflection).abs() < 1e-10 * length,
                "{tip:?} {e:?}"
            );
            assert!(
                (tip.x - e.tip_horizontal).abs() < 1e-10 * length,
                "{tip:?} {e:?}"
            );
            let pairs = profile(length, q, ei, 10);
            assert_eq!(pairs.len(), 11);
            assert_eq!(pairs[0], (0.0, 0.0));
            assert!((pairs[10].1 - e.tip_deflection).abs() < 1e-10 * length);
        }
    }

    #[test]
    fn deflection_grows_with_load_towards_the_length() {
        let (length, ei) = (1.0, 1.0);
        let mut previous = cantilever(length, 0.0, ei);
        assert_eq!(previous.tip_deflection, 0.0);
        let mut k = 0.01;
        while k <= 1000.0 * 1.0001 {
            let e = cantilever(length, k, ei);
            assert!(
                e.tip_deflection > previous.tip_deflection,
                "k {k}: {e:?} {previous:?}"
            );
            assert!(
                e.tip_horizontal < previous.tip_horizontal,
                "k {k}: {e:?} {previous:?}"
            );
            assert!(
                e.tip_angle > previous.tip_angle && e.tip_angle < FRAC_PI_2,
                "k {k}: {e:?}"
            );
            // Inextensible: the tip stays within the length.
            assert!(
                e.tip_deflection.hypot(e.tip_horizontal) < length,
                "k {k}: {e:?}"
            );
            previous = e;
            k *= 10.0_f64.powf(0.25);
        }
        let e = cantilever(length, 1000.0, ei);
        assert!(e.tip_deflection / length > 0.9, "{e:?}");
    }

    #[test]
    fn solution_depends_on_k_only_and_is_converged_in_steps() {
        let a = cantilever(1.0, 8.0, 1.0);
        let b = cantilever(0.2, 8.0 * 0.7, 0.7 * 0.2_f64.powi(3));
        assert!(relative(b.tip_deflection / 0.2, a.tip_deflection) < 1e-12);
        assert!(relative(b.root_curvature * 0.2, a.root_curvature) < 1e-12);
        for k in [8.0, 750.0] {
            let coarse = cantilever_with_steps(1.0, k, 1.0, STEPS);
            let fine = cantilever_with_steps(1.0, k, 1.0, 4 * STEPS);
            assert!(
                (coarse.tip_deflection - fine.tip_deflection).abs() < 1e-9,
                "k {k}"
            );
            assert!(
                (coarse.tip_horizontal - fine.tip_horizontal).abs() < 1e-9,
                "k {k}"
            );
            assert!((coarse.tip_angle - fine.tip_angle).abs() < 1e-9, "k {k}");
        }
    }

    #[test]
    fn peirce_chord_angle_at_bending_length_half_the_strip() {
        // Peirce (1930): the strip is pushed out until its chord is at 41.5°
        // below the horizontal, and then the bending length (EI/q)^(1/3) is
        // close to L/2, i.e. q L³ / EI = 8.
        let e = cantilever(1.0, 8.0, 1.0);
        let chord = e.chord_angle().to_degrees();
        println!("q L³ / EI = 8: chord angle {chord:.4}°");
        assert!((chord - 41.5).abs() < 0.5, "chord angle {chord}°");
    }
}
