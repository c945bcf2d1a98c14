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
//!
//! # The stick
//!
//! The smoothing above lets a held curvature creep (at up to `kappa_e`),
//! so a run with it never comes to rest. With `bending_hysteresis_stiffness`
//! the slider is in series with a stick spring instead (a Jenkins element:
//! Jenkins 1962, Br. J. Appl. Phys. 13, 30–32; the one-dimensional
//! frictional model and its return map of Simo & Hughes 1998,
//! "Computational Inelasticity", ch. 1): each patch keeps a plastic curvature
//! `kappa_p` from step to step (`State::plastic`), the spring's moment is
//! `(A/e) Q (kappa - kappa_p)`, and the slider lets `kappa_p` move only
//! once that moment's `Q^-1`-norm reaches `HB`. Eliminating the step's
//! plastic change by the backward-Euler return map leaves a potential of
//! `kappa` alone, the same norm `s` from `kappa_p` with Huber's function:
//!
//! ```text
//! d     = kappa - kappa_p,   s = sqrt(d . Q d),   e = HB^2 / k
//! psi   = A s^2 / (2 e)                 s < e   (the stick: stored)
//!       = A (s - e / 2)                 s >= e  (A e / 2 stored, A (s - e) dissipated)
//! kappa_p <- kappa_p + (1 - e / s) d    at the step's end, where s > e
//! ```
//!
//! `k` is the stick's stiffness along the direction of the larger `HB`:
//! a curvature along it rises on `(B + k)` until the moment `HB` and on
//! `B` after, the loop's slopes. `psi` is convex and C^1 (its second
//! derivative jumps at `s = e`, where the spring slips); the stored part
//! is counted with the bending energy, the dissipated with friction's.

use super::kernel::LawValue;

/// `[material] bending_hysteresis`: the frictional moment of bending.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hysteresis {
    /// `HB` (N m/m) for curvature along the warp and the weft (half
    /// KES-FB's 2HB).
    pub moment: [f64; 2],
    /// What holds the curvature below the frictional moment.
    pub hold: Hold,
}

/// What holds a patch's curvature while its moment is below `HB`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Hold {
    /// `bending_hysteresis_rate`: the dissipation is measured from the
    /// step's start and smoothed over a curvature change `rate dt`, so the
    /// curvature creeps at up to `rate` (1/(m s); in a static analysis per
    /// unit load factor). The default.
    Creep {
        /// The creep rate `kappa_e` (1/(m s)).
        rate: f64,
    },
    /// `bending_hysteresis_stiffness`: a stick spring in series with the
    /// slider (a Jenkins element), whose plastic curvature persists from
    /// step to step — nothing creeps (the module docs, "The stick").
    Stick {
        /// The spring's bending stiffness `k` (N m) along the direction of
        /// the larger `HB` (along the other, `k (HB_other / HB)^2`).
        stiffness: f64,
    },
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

/// What a patch's hysteresis gives at an evaluation ([`Hysteresis::patch`]).
pub struct PatchValue {
    /// The potential, the moments and their derivative.
    pub law: LawValue,
    /// The energy the slider dissipates over the step (J).
    pub dissipated: f64,
    /// The energy the stick spring stores at the step's end (J; 0 for a
    /// creeping hold).
    pub stored: f64,
}

impl Hysteresis {
    /// `Q` (N^2), diagonal.
    fn metric(&self) -> [f64; 3] {
        let [w, f] = self.moment;
        [w * w, f * f, 0.5 * w * f]
    }

    /// The smoothing `e` (N/m) of a step of size `dt`: `HB kappa_e dt`
    /// creeping, `HB^2 / k` with a stick (`dt` does not matter).
    pub fn smoothing(&self, dt: f64) -> f64 {
        let hb = self.moment[0].max(self.moment[1]);
        match self.hold {
            Hold::Creep { rate } => hb * rate * dt,
            Hold::Stick { stiffness } => hb * hb / stiffness,
        }
    }

    /// Whether the hold is a stick, whose plastic curvatures persist.
    pub fn sticks(&self) -> bool {
        matches!(self.hold, Hold::Stick { .. })
    }

    /// `s = sqrt(d . Q d)` and `Q d` of a change `d`.
    fn norm(&self, d: [f64; 3]) -> (f64, [f64; 3]) {
        let q = self.metric();
        let qd = [0, 1, 2].map(|j| q[j] * d[j]);
        ((d[0] * qd[0] + d[1] * qd[1] + d[2] * qd[2]).sqrt(), qd)
    }

    /// A patch's potential, its moments and their derivative (the module
    /// docs) at curvatures `kappa`, from `reference` (the step's start
    /// creeping, the plastic curvature with a stick), with smoothing `e`,
    /// on reference area `area`; and the energy it dissipates and stores.
    pub fn patch(&self, area: f64, reference: [f64; 3], kappa: [f64; 3], e: f64) -> PatchValue {
        let q = self.metric();
        let d = [0, 1, 2].map(|j| kappa[j] - reference[j]);
        let (s, qd) = self.norm(d);
        // f0, f1 / s and (f1' - f1 / s) / s^2, finite at s = 0; with a
        // stick, the energy dissipated and stored (per area).
        let (f0, f1_s, curl, stick) = match (self.hold, s < e) {
            (Hold::Creep { .. }, true) => (
                -s * s * s / (3.0 * e * e) + s * s / e + e / 3.0,
                -s / (e * e) + 2.0 / e,
                if s > 0.0 { -1.0 / (e * e * s) } else { 0.0 },
                None,
            ),
            (Hold::Creep { .. }, false) => (s, 1.0 / s, -1.0 / (s * s * s), None),
            (Hold::Stick { .. }, true) => {
                (0.5 * s * s / e, 1.0 / e, 0.0, Some((0.0, 0.5 * s * s / e)))
            }
            (Hold::Stick { .. }, false) => (
                s - 0.5 * e,
                1.0 / s,
                -1.0 / (s * s * s),
                Some((s - e, 0.5 * e)),
            ),
        };
        let m = qd.map(|v| area * f1_s * v);
        let mut dm = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                dm[i][j] = area * curl * qd[i] * qd[j];
            }
            dm[i][i] += area * f1_s * q[i];
        }
        // Creeping, the work the moments do over the change.
        let (dissipated, stored) =
            stick.map_or((area * f1_s * s * s, 0.0), |(d, w)| (area * d, area * w));
        PatchValue {
            law: (area * f0, m, dm),
            dissipated,
            stored,
        }
    }

    /// The return map of a stick at a step's end: the plastic curvature
    /// `plastic` moved toward `kappa` until the spring's moment is on the
    /// yield surface, `s = e` (unchanged where `s <= e`).
    pub fn slip(&self, plastic: &mut [f64; 3], kappa: [f64; 3], e: f64) {
        let d = [0, 1, 2].map(|j| kappa[j] - plastic[j]);
        let (s, _) = self.norm(d);
        if s > e {
            let t = 1.0 - e / s;
            for j in 0..3 {
                plastic[j] += t * d[j];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> Hysteresis {
        Hysteresis {
            moment: [3e-4, 1e-4],
            hold: Hold::Creep { rate: 0.5 },
        }
    }

    /// The same moments held by a stick of `e = HB^2 / k = 3e-4 * 0.05`,
    /// the creeping law's `e` over a step of 0.1 s.
    fn stick() -> Hysteresis {
        Hysteresis {
            moment: [3e-4, 1e-4],
            hold: Hold::Stick {
                stiffness: 3e-4 / 0.05,
            },
        }
    }

    /// The moments are the potential's derivatives, and theirs the
    /// moments', by central differences, below and above the smoothing
    /// curvature; the derivative is positive semi-definite.
    #[test]
    fn moments_match_finite_differences_and_are_monotone() {
        for h in [law(), stick()] {
            moments_match_finite_differences(h);
        }
    }

    fn moments_match_finite_differences(h: Hysteresis) {
        let (area, start, e) = (2e-4, [10.0, -4.0, 3.0], h.smoothing(0.1));
        assert!((e - 1.5e-5).abs() < 1e-18, "{e}");
        for scale in [1e-3, 0.3, 1.0, 3.0, 200.0] {
            let dir = [0.7, -0.4, 0.5];
            let kappa = [0, 1, 2].map(|j| start[j] + scale * dir[j] * e / 3e-4);
            let (_, m, dm) = h.patch(area, start, kappa, e).law;
            for j in 0..3 {
                // A step small against the change `kappa - start`.
                let step = 1e-4 * scale * e / 3e-4;
                let at = |t: f64| {
                    let mut k = kappa;
                    k[j] += t;
                    h.patch(area, start, k, e).law
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
            let v = h.patch(area, [0.0; 3], [sign * 5.0, 0.0, 0.0], e);
            let m = v.law.1;
            assert!((m[0] - sign * area * 3e-4).abs() < 1e-15, "{m:?}");
            assert_eq!((m[1], m[2]), (0.0, 0.0));
            assert!((v.dissipated - area * 3e-4 * 5.0).abs() < 1e-15);
            assert_eq!(v.stored, 0.0);
            let m = h.patch(area, [0.0; 3], [0.0, sign * 5.0, 0.0], e).law.1;
            assert!((m[1] - sign * area * 1e-4).abs() < 1e-15, "{m:?}");
        }
        let v = h.patch(area, [1.0, 2.0, 3.0], [1.0, 2.0, 3.0], e);
        assert_eq!((v.law.1, v.dissipated), ([0.0; 3], 0.0));
        assert!((v.law.0 - area * e / 3.0).abs() < 1e-20);
    }

    /// A stick along the warp: the moment rises as `k kappa` until `HB_w`
    /// at `kappa_y = HB_w / k`, and stays there; the potential is the
    /// spring's energy plus the slider's work, `1/2 HB kappa_y + HB
    /// (kappa - kappa_y)`; the return map leaves the spring on the yield
    /// surface, and a reversal unloads it on the spring's slope. Along the
    /// weft the stiffness is `k (HB_f / HB_w)^2`.
    #[test]
    fn a_stick_loads_on_its_spring_then_slips() {
        let h = stick();
        let (area, e) = (1e-4, h.smoothing(1.0));
        let (hb, k): (f64, f64) = (3e-4, 3e-4 / 0.05);
        let kappa_y = hb / k;
        assert!((kappa_y - 0.05).abs() < 1e-15);
        // On the spring: M = A k kappa, all stored.
        let v = h.patch(area, [0.0; 3], [0.5 * kappa_y, 0.0, 0.0], e);
        assert!((v.law.1[0] - area * k * 0.5 * kappa_y).abs() < 1e-18);
        assert!((v.law.2[0][0] - area * k).abs() < 1e-15 * area * k);
        assert!((v.stored - area * 0.5 * k * (0.5 * kappa_y).powi(2)).abs() < 1e-22);
        assert_eq!(v.dissipated, 0.0);
        assert_eq!(v.law.0, v.stored);
        // Slipping: M = A HB, the rest is the slider's work.
        let kappa = 0.4;
        let v = h.patch(area, [0.0; 3], [kappa, 0.0, 0.0], e);
        assert!((v.law.1[0] - area * hb).abs() < 1e-18, "{:?}", v.law.1);
        assert!((v.stored - area * 0.5 * hb * kappa_y).abs() < 1e-22);
        assert!((v.dissipated - area * hb * (kappa - kappa_y)).abs() < 1e-20);
        assert!((v.law.0 - v.stored - v.dissipated).abs() < 1e-22);
        // The return map: the plastic curvature kappa - kappa_y.
        let mut plastic = [0.0; 3];
        h.slip(&mut plastic, [kappa, 0.0, 0.0], e);
        assert!(
            (plastic[0] - (kappa - kappa_y)).abs() < 1e-15,
            "{plastic:?}"
        );
        assert_eq!((plastic[1], plastic[2]), (0.0, 0.0));
        // Now held: the same curvature is the spring at its yield moment;
        // a reversal by kappa_y unloads it on the spring, by 2 kappa_y
        // reaches -HB.
        let v = h.patch(area, plastic, [kappa, 0.0, 0.0], e);
        assert!((v.law.1[0] - area * hb).abs() < 1e-15 * area * hb);
        assert!(v.dissipated.abs() < 1e-22);
        let v = h.patch(area, plastic, [kappa - kappa_y, 0.0, 0.0], e);
        assert!(v.law.1[0].abs() < 1e-15 * area * hb, "{:?}", v.law.1);
        let v = h.patch(area, plastic, [kappa - 2.0 * kappa_y, 0.0, 0.0], e);
        assert!((v.law.1[0] + area * hb).abs() < 1e-12 * area * hb);
        // A held curvature leaves the plastic curvature where it is.
        let held = plastic;
        h.slip(&mut plastic, [kappa - 0.5 * kappa_y, 0.0, 0.0], e);
        assert_eq!(plastic, held);
        // Along the weft: the stiffness k (HB_f / HB_w)^2, the moment HB_f.
        let kf = k * (1.0 / 3.0f64).powi(2);
        let v = h.patch(area, [0.0; 3], [0.0, 1e-3, 0.0], e);
        assert!((v.law.1[1] - area * kf * 1e-3).abs() < 1e-12 * area * kf * 1e-3);
        let v = h.patch(area, [0.0; 3], [0.0, -5.0, 0.0], e);
        assert!((v.law.1[1] + area * 1e-4).abs() < 1e-18);
    }
}
