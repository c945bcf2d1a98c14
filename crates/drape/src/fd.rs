//! Central finite-difference checks of derivatives, used by the test suite
//! for every energy term (strain, pressure, inertia, contact) and offered
//! to anyone adding a material or a load.
//!
//! With step `h`, central differences have truncation error `O(h^2)` and
//! round-off error `O(eps |f| / h)`; the checks use a relative step (`h =
//! 1e-6` times the scale of `x`) and compare with a tolerance relative to
//! the largest entry of the analytic derivative.

/// Largest `|J_ij - (f_i(x + h e_j) - f_i(x - h e_j)) / 2h|`, relative to
/// `max |J_ij|`, where `jacobian(x)` returns `J` row-major (`m x n`) and
/// `f(x)` returns `m` values.
pub fn jacobian_error(
    f: impl Fn(&[f64]) -> Vec<f64>,
    jacobian: impl Fn(&[f64]) -> Vec<f64>,
    x: &[f64],
    h: f64,
) -> f64 {
    let n = x.len();
    let j = jacobian(x);
    let m = j.len() / n;
    let scale = j
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    let mut worst = 0.0f64;
    let mut xp = x.to_vec();
    for c in 0..n {
        xp[c] = x[c] + h;
        let fp = f(&xp);
        xp[c] = x[c] - h;
        let fm = f(&xp);
        xp[c] = x[c];
        for r in 0..m {
            let fd = (fp[r] - fm[r]) / (2.0 * h);
            worst = worst.max((j[r * n + c] - fd).abs());
        }
    }
    worst / scale
}

/// Largest `|g_j - (E(x + h e_j) - E(x - h e_j)) / 2h|` relative to `max |g_j|`.
pub fn gradient_error(
    energy: impl Fn(&[f64]) -> f64,
    gradient: impl Fn(&[f64]) -> Vec<f64>,
    x: &[f64],
    h: f64,
) -> f64 {
    jacobian_error(|y| vec![energy(y)], gradient, x, h)
}
