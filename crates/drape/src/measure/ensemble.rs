//! The statistics of a drape test (README, "The drape test";
//! docs/theory.md, "The drape test's statistics"): a set of specimens'
//! drape coefficients and fold counts summarised as a laboratory reports
//! them.
//!
//! For `n` drape coefficients `DC_i`:
//!
//! ```text
//! mean  = Σ DC_i / n
//! sd    = √( Σ (DC_i − mean)² / (n − 1) )                 (n ≥ 2)
//! ci95  = mean ∓ t_{0.975, n−1} sd / √n                   (n ≥ 2)
//! ```
//!
//! the interval of Student's t with `n − 1` degrees of freedom (the
//! specimens a random sample of the fabric's drapes; Student 1908). The
//! fold counts go into a histogram; the modal fold count is the most
//! frequent (the smallest of those tied), and the drape coefficient at it
//! the mean over the specimens with that many folds — what Jeong &
//! Phillips (J. Textile Inst. 89, 1998) recommend reading, since the fold
//! count of one fabric varies between repeats and DC with it.

use std::collections::BTreeMap;

/// A drape test's summary of its measured specimens.
#[derive(Debug, Clone, PartialEq)]
pub struct Ensemble {
    /// Specimens measured, `n`.
    pub count: usize,
    /// Mean drape coefficient; `None` for `n = 0`.
    pub mean: Option<f64>,
    /// Sample standard deviation (`n − 1` in the denominator); `None` for
    /// `n < 2`.
    pub sd: Option<f64>,
    /// The 95 % interval of the mean, `[low, high]`; `None` for `n < 2`.
    pub ci95: Option<[f64; 2]>,
    /// How many specimens have each fold count.
    pub fold_histogram: BTreeMap<usize, usize>,
    /// The most frequent fold count (the smallest of a tie).
    pub modal_folds: Option<usize>,
    /// The mean drape coefficient of the specimens with `modal_folds`.
    pub dc_at_modal_folds: Option<f64>,
}

/// The summary of `specimens`, each `(drape coefficient, folds)`.
pub fn summarise(specimens: &[(f64, usize)]) -> Ensemble {
    let n = specimens.len();
    let mean_of = |dc: &mut dyn Iterator<Item = f64>| {
        let (sum, count) = dc.fold((0.0, 0usize), |(s, k), x| (s + x, k + 1));
        (count > 0).then(|| sum / count as f64)
    };
    let mean = mean_of(&mut specimens.iter().map(|s| s.0));
    let sd = mean.filter(|_| n >= 2).map(|m| {
        let ss: f64 = specimens.iter().map(|s| (s.0 - m).powi(2)).sum();
        (ss / (n - 1) as f64).sqrt()
    });
    let ci95 = match (mean, sd) {
        (Some(m), Some(s)) => {
            let half = student_t_quantile(0.975, (n - 1) as f64) * s / (n as f64).sqrt();
            Some([m - half, m + half])
        }
        _ => None,
    };
    let mut fold_histogram = BTreeMap::new();
    for s in specimens {
        *fold_histogram.entry(s.1).or_insert(0) += 1;
    }
    // The first (smallest) of the most frequent: `max_by_key` keeps the
    // last of equals, so the order is reversed.
    let modal_folds = (fold_histogram.iter().rev())
        .max_by_key(|(_, count)| **count)
        .map(|(folds, _)| *folds);
    let dc_at_modal_folds =
        modal_folds.and_then(|f| mean_of(&mut specimens.iter().filter(|s| s.1 == f).map(|s| s.0)));
    Ensemble {
        count: n,
        mean,
        sd,
        ci95,
        fold_histogram,
        modal_folds,
        dc_at_modal_folds,
    }
}

/// The `p`-quantile of Student's t with `dof > 0` degrees of freedom, for
/// `p` in `(0.5, 1)`: the `t > 0` with `F(t) = p`, found by bisection on
/// `F(t) = 1 − I_{dof/(dof+t²)}(dof/2, 1/2) / 2` (Abramowitz & Stegun
/// 26.7.1 with 26.5.27), to the last bit of `t`.
pub fn student_t_quantile(p: f64, dof: f64) -> f64 {
    let cdf = |t: f64| 1.0 - 0.5 * incomplete_beta(dof / (dof + t * t), 0.5 * dof, 0.5);
    // F(hi) ≥ p: double until it is (for dof = 1, p = 0.975: 12.7).
    let mut hi = 1.0;
    while cdf(hi) < p && hi < 1e300 {
        hi *= 2.0;
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if cdf(mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The regularised incomplete beta function `I_x(a, b)` for `x` in
/// `[0, 1]`, `a, b > 0`: its continued fraction (A&S 26.5.8) by the
/// modified Lentz method, on the side where it converges fast
/// (`x < (a + 1)/(a + b + 2)`, else `1 − I_{1−x}(b, a)`; Numerical Recipes
/// §6.4).
pub fn incomplete_beta(x: f64, a: f64, b: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front =
        (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_fraction(x, a, b) / a
    } else {
        1.0 - front * beta_fraction(1.0 - x, b, a) / b
    }
}

/// The continued fraction of [`incomplete_beta`] (modified Lentz).
fn beta_fraction(x: f64, a: f64, b: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut c = 1.0;
    let mut d = 1.0 - (a + b) * x / (a + 1.0);
    d = 1.0 / if d.abs() < TINY { TINY } else { d };
    let mut h = d;
    for m in 1..=300 {
        let m = m as f64;
        for numerator in [
            m * (b - m) * x / ((a + 2.0 * m - 1.0) * (a + 2.0 * m)),
            -(a + m) * (a + b + m) * x / ((a + 2.0 * m) * (a + 2.0 * m + 1.0)),
        ] {
            d = 1.0 + numerator * d;
            d = 1.0 / if d.abs() < TINY { TINY } else { d };
            c = 1.0 + numerator / c;
            c = if c.abs() < TINY { TINY } else { c };
            h *= d * c;
        }
        if (d * c - 1.0).abs() < 1e-16 {
            break;
        }
    }
    h
}

/// `ln Γ(x)` for `x > 0`: Lanczos' approximation (g = 7, 9 terms; relative
/// error below 1e-15), with the reflection-free shift for `x < 0.5`
/// (`Γ(x) = Γ(x + 1) / x`).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return ln_gamma(x + 1.0) - x.ln();
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * std::f64::consts::TAU.ln() + (x + 0.5) * t.ln() - t + a.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed forms: t_{p,1} = tan(π (p − 1/2)) (Cauchy), t_{p,2} =
    /// (2p − 1) / √(2 p (1 − p)); the normal's 1.959964 as dof grows
    /// (t_{0.975, 10^6} within 1e-5 of it: the t quantile exceeds the
    /// normal's by about (z³ + z)/(4 dof)).
    #[test]
    fn t_quantiles_in_closed_form() {
        let p: f64 = 0.975;
        let cauchy = (std::f64::consts::PI * (p - 0.5)).tan();
        assert!((student_t_quantile(p, 1.0) - cauchy).abs() < 1e-9 * cauchy);
        let two = (2.0 * p - 1.0) / (2.0 * p * (1.0 - p)).sqrt();
        assert!((student_t_quantile(p, 2.0) - two).abs() < 1e-9 * two);
        let z = 1.959_963_984_540_054;
        assert!((student_t_quantile(p, 1e6) - z).abs() < 1e-5);
        // Monotone in the degrees of freedom, down to the normal's.
        let mut last = f64::INFINITY;
        for dof in 1..60 {
            let t = student_t_quantile(p, dof as f64);
            assert!(t < last && t > z, "dof {dof}: {t}");
            last = t;
        }
    }

    /// Γ(n) = (n − 1)! and Γ(1/2) = √π.
    #[test]
    fn ln_gamma_of_factorials() {
        let mut factorial = 1.0f64;
        for n in 1..20 {
            assert!((ln_gamma(n as f64) - factorial.ln()).abs() < 1e-12 * factorial.ln().max(1.0));
            factorial *= n as f64;
        }
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-14);
    }

    /// I_x(a, 1) = x^a and I_x(1, b) = 1 − (1 − x)^b.
    #[test]
    fn incomplete_beta_closed_forms() {
        for &x in &[0.01, 0.3, 0.5, 0.77, 0.99] {
            for &a in &[0.5, 1.0, 2.5, 7.0] {
                let i = incomplete_beta(x, a, 1.0);
                assert!((i - x.powf(a)).abs() < 1e-13, "{x} {a}");
                let j = incomplete_beta(x, 1.0, a);
                assert!((j - (1.0 - (1.0 - x).powf(a))).abs() < 1e-13, "{x} {a}");
            }
        }
    }

    /// Mean, sd and the interval by their definitions; a tie of fold
    /// counts goes to the smaller; the DC at the modal count is its
    /// specimens' mean.
    #[test]
    fn summary_by_definition() {
        let s = [(0.5, 6), (0.6, 7), (0.55, 6), (0.7, 7), (0.4, 5)];
        let e = summarise(&s);
        let mean = (0.5 + 0.6 + 0.55 + 0.7 + 0.4) / 5.0;
        assert!((e.mean.unwrap() - mean).abs() < 1e-15);
        let var = s.iter().map(|x| (x.0 - mean).powi(2)).sum::<f64>() / 4.0;
        assert!((e.sd.unwrap() - var.sqrt()).abs() < 1e-15);
        let half = student_t_quantile(0.975, 4.0) * var.sqrt() / 5f64.sqrt();
        let [lo, hi] = e.ci95.unwrap();
        assert!((lo - (mean - half)).abs() < 1e-15 && (hi - (mean + half)).abs() < 1e-15);
        assert_eq!(e.fold_histogram, BTreeMap::from([(5, 1), (6, 2), (7, 2)]));
        assert_eq!(e.modal_folds, Some(6));
        assert!((e.dc_at_modal_folds.unwrap() - 0.525).abs() < 1e-15);
        // One specimen: a mean, no spread; none: nothing.
        let one = summarise(&[(0.5, 6)]);
        assert_eq!((one.mean, one.sd, one.ci95), (Some(0.5), None, None));
        let none = summarise(&[]);
        assert_eq!(
            (none.mean, none.modal_folds, none.dc_at_modal_folds),
            (None, None, None)
        );
    }
}
