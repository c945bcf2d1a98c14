//! Bending hysteresis: the frictional moment of a fabric's bending
//! (Grosberg 1966, "The mechanical properties of woven fabrics, part II:
//! the bending of woven fabrics", Textile Res. J. 36, 205–211; KES-FB's
//! 2HB, Kawabata 1980). Before its curvature changes, a fabric must
//! overcome a moment `HB` (N m/m) that the friction between its fibres and
//! yarns exerts, whichever way it bends: the moment–curvature loop
//! `M = B kappa ± HB` of width 2HB.
//!
//! As Coulomb friction in `integrator::terms::friction`, the moment is
//! lagged over the step (here it is constant: nothing to lag) and made a
//! potential of the step, smoothed where the curvature barely changes
//! (Li et al. 2020, "Incremental Potential Contact", ACM TOG 39(4), §5).
//! For each bending patch (docs/theory.md §1.10), with `kappa_s` its
//! curvatures (Voigt, `kappa_11, kappa_22, 2 kappa_12` in the warp's
//! frame) at the step's start:
//!
//! ```text
//! d        = kappa - kappa_s                           curvature change (1/m)
//! s        = sqrt(d . Q d),  Q = diag(HB_w^2, HB_f^2, HB_w HB_f / 2)      (N/m)
//! D(Y)     = sum_T A_T f0(s)                                            (J)
//! f0(s)    = -s^3 / (3 e^2) + s^2 / e + e / 3    s < e = HB kappa_e h
//!          = s                                   s >= e
//! M        = dD/dkappa = A f1(s) Q d / s
//! dM/dkappa = A [ f1(s)/s Q + (f1'(s) - f1(s)/s) (Q d)(Q d)^T / s^2 ]
//! ```
//!
//! (`HB = max(HB_w, HB_f)`, `h` the step, `kappa_e` the creep rate
//! `bending_hysteresis_rate`.) A curvature changing along the warp alone
//! meets `|M_11| = A HB_w` (per area, the moment HB_w), along the weft
//! `HB_f`; `Q`'s twist entry is Huber's mean, as the rigidity's is
//! (`D_66 = sqrt(B_w B_f) / 2`), so that an isotropic fabric's `s` is
//! `HB` times the curvature change's Frobenius norm, the same in every
//! frame. Below `e` the
//! curvature creeps (at most at `kappa_e`); above it the patch meets the
//! whole frictional moment, whatever the change's size. `f0` is C^1 and
//! convex on `s >= 0` and `s` is a norm of `d`, so `dM/dkappa` is positive
//! semi-definite: the patch's Gauss–Newton part `K^T (dM/dkappa) K` too.
//! The work `A f1(s) s` a patch does over the step is the energy it
//! dissipates (`history.csv`'s `friction_dissipation` counts it with
//! friction's).

use super::kernel::LawValue;

/// `[material] bending_hysteresis`: the frictional moment of bending.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hysteresis {
    /// `HB` (N m/m) for curvature along the warp and the weft (half
    /// KES-FB's 2HB).
    pub moment: [f64; 2],
    /// The curvature rate below which the curvature creeps (1/(m s); in a
    /// static analysis per unit load factor).
    pub rate: f64,
}

/// The default `bending_hysteresis_rate` (1/(m s)): where the frictional
/// moment holds it, a curvature creeps at most 1 1/m a second. Measured
/// on Matsudaira A's coarse drape (docs/validation.md, "Bending
/// hysteresis"): DC 84.8 % at 0.1, 84.7 % at 0.3, 85.3 % at 1, 67.8 % at
/// 10; below 1 the dynamic steps of a perturbed specimen shrink to 20–200
/// µs (at 0.1, t = 0.1 s in 9 minutes), where at 1 the coarse fall takes
/// about a minute. The creep keeps nodes moving faster than a rest
/// criterion's speed: such a run goes on to its schedule's end.
pub const DEFAULT_RATE: f64 = 1.0;

impl Hysteresis {
    /// `Q` (N^2), diagonal.
    fn metric(&self) -> [f64; 3] {
        let [w, f] = self.moment;
        [w * w, f * f, 0.5 * w * f]
    }

    /// The smoothing `e` (N/m) over a step of size `dt`.
    pub fn smoothing(&self, dt: f64) -> f64 {
        self.moment[0].max(self.moment[1]) * self.rate * dt
    }

    /// A patch's dissipation potential, its moments and their derivative
    /// (the module docs) at curvatures `kappa`, from `start`, over a step
    /// whose smoothing is `e`, on reference area `area`; and the energy it
    /// dissipates there, `A f1(s) s`.
    pub fn patch(&self, area: f64, start: [f64; 3], kappa: [f64; 3], e: f64) -> (LawValue, f64) {
        let q = self.metric();
        let d = [0, 1, 2].map(|j| kappa[j] - start[j]);
        let qd = [0, 1, 2].map(|j| q[j] * d[j]);
        let s = (d[0] * qd[0] + d[1] * qd[1] + d[2] * qd[2]).sqrt();
        // f0, f1 / s and (f1' - f1 / s) / s^2, finite at s = 0.
        let (f0, f1_s, curl) = if s < e {
            (
                -s * s * s / (3.0 * e * e) + s * s / e + e / 3.0,
                -s / (e * e) + 2.0 / e,
                if s > 0.0 { -1.0 / (e * e * s) } else { 0.0 },
            )
        } else {
            (s, 1.0 / s, -1.0 / (s * s * s))
        };
        let m = qd.map(|v| area * f1_s * v);
        let mut dm = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                dm[i][j] = area * curl * qd[i] * qd[j];
            }
            dm[i][i] += area * f1_s * q[i];
        }
        ((area * f0, m, dm), area * f1_s * s * s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> Hysteresis {
        Hysteresis {
            moment: [3e-4, 1e-4],
            rate: 0.5,
        }
    }

    /// The moments are the potential's derivatives, and theirs the
    /// moments', by central differences, below and above the smoothing
    /// curvature; the derivative is positive semi-definite.
    #[test]
    fn moments_match_finite_differences_and_are_monotone() {
        let h = law();
        let (area, start, e) = (2e-4, [10.0, -4.0, 3.0], h.smoothing(0.1));
        for scale in [1e-3, 0.3, 1.0, 3.0, 200.0] {
            let dir = [0.7, -0.4, 0.5];
            let kappa = [0, 1, 2].map(|j| start[j] + scale * dir[j] * e / 3e-4);
            let ((_, m, dm), _) = h.patch(area, start, kappa, e);
            for j in 0..3 {
                // A step small against the change `kappa - start`.
                let step = 1e-4 * scale * e / 3e-4;
                let at = |t: f64| {
                    let mut k = kappa;
                    k[j] += t;
                    h.patch(area, start, k, e).0
                };
                let (plus, minus) = (at(step), at(-step));
                let fd = (plus.0 - minus.0) / (2.0 * step);
                // (Relative to the largest moment: the potential's
                // constant `A e / 3` takes digits from its differences.)
                let largest = m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                assert!(
                    (fd - m[j]).abs() <= 1e-5 * largest,
                    "scale {scale}: M_{j} {} against {fd}",
                    m[j]
                );
                for i in 0..3 {
                    let fd = (plus.1[i] - minus.1[i]) / (2.0 * step);
                    let tol = 1e-5 * dm[i][i].abs().max(dm[j][j].abs());
                    assert!(
                        (fd - dm[i][j]).abs() <= tol,
                        "scale {scale}: dM_{i}{j} {} against {fd}",
                        dm[i][j]
                    );
                }
            }
            // Semi-definite: the 3 x 3 matrix's leading minors.
            let minor2 = dm[0][0] * dm[1][1] - dm[0][1] * dm[1][0];
            let det = dm[0][0] * (dm[1][1] * dm[2][2] - dm[1][2] * dm[2][1])
                - dm[0][1] * (dm[1][0] * dm[2][2] - dm[1][2] * dm[2][0])
                + dm[0][2] * (dm[1][0] * dm[2][1] - dm[1][1] * dm[2][0]);
            let size = dm[0][0].max(dm[1][1]).max(dm[2][2]);
            assert!(
                dm[0][0] >= 0.0 && minor2 >= -1e-12 * size * size,
                "scale {scale}"
            );
            assert!(
                det >= -1e-9 * size * size * size,
                "scale {scale}: det {det}"
            );
        }
    }

    /// Bending along the warp past the smoothing meets the moment `HB_w`
    /// per area, along the weft `HB_f`, whichever way; no change, none.
    #[test]
    fn a_change_along_a_yarn_meets_its_frictional_moment() {
        let h = law();
        let (area, e) = (1e-4, h.smoothing(0.01));
        for sign in [1.0, -1.0] {
            let ((_, m, _), dissipated) = h.patch(area, [0.0; 3], [sign * 5.0, 0.0, 0.0], e);
            assert!((m[0] - sign * area * 3e-4).abs() < 1e-15, "{m:?}");
            assert_eq!((m[1], m[2]), (0.0, 0.0));
            assert!((dissipated - area * 3e-4 * 5.0).abs() < 1e-15);
            let ((_, m, _), _) = h.patch(area, [0.0; 3], [0.0, sign * 5.0, 0.0], e);
            assert!((m[1] - sign * area * 1e-4).abs() < 1e-15, "{m:?}");
        }
        let ((psi, m, _), dissipated) = h.patch(area, [1.0, 2.0, 3.0], [1.0, 2.0, 3.0], e);
        assert_eq!((m, dissipated), ([0.0; 3], 0.0));
        assert!((psi - area * e / 3.0).abs() < 1e-20);
    }
}
