//! Tension-field wrinkling: a membrane that cannot carry compression
//! (docs/theory.md §1.4). Two models on top of Saint-Venant–Kirchhoff, in the Voigt
//! convention of [`super`].
//!
//! # `stress-projection`
//!
//! The elastic stress `S = C E + sigma0 I` is split into principal values
//! `s1 >= s2` and directions `n1, n2`; negative principal stresses are set
//! to zero:
//!
//! | state | condition | projected stress `P(S)` |
//! |---|---|---|
//! | taut | `s2 >= 0` | `S` |
//! | wrinkled | `s1 > 0 > s2` | `s1 n1 (x) n1` |
//! | slack | `s1 <= 0` | `0` |
//!
//! `P` is an isotropic function `sum_i f(s_i) n_i (x) n_i` with `f(s) =
//! max(s, 0)`, so its derivative follows from the Daleckii–Krein formula:
//! in the principal basis, `dP'_ij = f[s_i, s_j] dS'_ij` with the divided
//! differences `f[s1, s1] = 1`, `f[s2, s2] = 0` and, for the shear-like
//! component, `f[s1, s2] = s1 / (s1 - s2)` when wrinkled. The tangent is
//! `D = dP/dS . C`: the product of two symmetric operators, not symmetric
//! itself (`P` is not the gradient of an energy). drape then factorises the
//! Hessian by sparse LU; this is the true derivative, not a frozen
//! wrinkle direction, so Newton keeps converging quadratically within a
//! state.
//!
//! # `relaxed-energy`
//!
//! Pipkin's relaxed strain energy (Pipkin 1986, "The relaxed energy
//! density for isotropic elastic membranes", IMA J. Appl. Math. 36), with
//! a strain criterion on the principal Green–Lagrange strains `E1 >= E2`:
//!
//! | state | condition | relaxed energy `W` | stress |
//! |---|---|---|---|
//! | taut | `E2 > -nu E1` | `1/2 E : C : E` | `C E` |
//! | wrinkled | `E1 > 0`, `E2 <= -nu E1` | `1/2 Y E1^2` | `Y E1 n1 (x) n1` |
//! | slack | `E1 <= 0` | `0` | `0` |
//!
//! (`Y` Young's modulus.) In the wrinkled state the material is in
//! uniaxial tension along the major strain direction. `W` is continuously
//! differentiable, its tangent is the (symmetric) Hessian of `W`: in the
//! principal basis `dS'_11 = Y dE'_11`, `dS'_22 = 0`, `dS'_12 = Y E1 / (E1 -
//! E2) dE'_12`, so Cholesky applies.
//!
//! # Slack membranes
//!
//! A slack region has no stiffness at all. In dynamics the mass term
//! `M / (beta dt^2)` keeps the Hessian regular. In statics the tangent (not
//! the stress) of slack points is given a small fraction of the elastic
//! stiffness ([`Wrinkling::with_slack_tangent`], `1e-6 C` from the scenario):
//! Newton then still has a regular matrix, the equilibrium it converges to
//! is unchanged (the residual uses the exact stress), at the price of
//! slower convergence near slack regions.

use super::{Material, MaterialResponse, SaintVenantKirchhoff};

/// Which tension-field model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WrinklingModel {
    /// Project the stress onto its non-negative principal part.
    StressProjection,
    /// Pipkin's relaxed energy with a strain criterion.
    RelaxedEnergy,
}

/// Taut, wrinkled or slack.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WrinkleState {
    /// Tension in both principal directions.
    Taut = 0,
    /// Tension in one direction only: wrinkles along it.
    Wrinkled = 1,
    /// No tension.
    Slack = 2,
}

/// Saint-Venant–Kirchhoff with a tension-field wrinkling model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wrinkling {
    elastic: SaintVenantKirchhoff,
    young: f64,
    nu: f64,
    prestress: f64,
    model: WrinklingModel,
    slack_tangent: f64,
}

/// Principal values `(l1, l2)`, `l1 >= l2`, and the unit direction `n1` of
/// the symmetric tensor `[[a, c], [c, b]]`.
pub(super) fn eigen(a: f64, b: f64, c: f64) -> (f64, f64, [f64; 2]) {
    let m = 0.5 * (a + b);
    let h = 0.5 * (a - b);
    let r = (h * h + c * c).sqrt();
    // The eigenvector of l1 = m + r is (l1 - b, c) = (h + r, c), or
    // equally (c, r - h): take the one whose large component is h + r or
    // r - h, whichever is >= r, so no cancellation (no trigonometry: this
    // is on the assembly's hot path). An isotropic tensor (r = 0) takes
    // n1 = e1.
    let v = if h >= 0.0 { [h + r, c] } else { [c, r - h] };
    let len = (v[0] * v[0] + v[1] * v[1]).sqrt();
    let n1 = if len > 0.0 {
        [v[0] / len, v[1] / len]
    } else {
        [1.0, 0.0]
    };
    (m + r, m - r, n1)
}

/// Applies, in the principal basis `(n1, n2)`, the diagonal scaling
/// `dX'_11 *= k11, dX'_22 *= k22, dX'_12 *= k12` to the symmetric tensor
/// given in Voigt *stress* form `[X11, X22, X12]`, and returns it rotated
/// back.
fn scale_in_basis(x: [f64; 3], n1: [f64; 2], k11: f64, k22: f64, k12: f64) -> [f64; 3] {
    let n2 = [-n1[1], n1[0]];
    let q = |u: [f64; 2], v: [f64; 2]| {
        u[0] * (x[0] * v[0] + x[2] * v[1]) + u[1] * (x[2] * v[0] + x[1] * v[1])
    };
    let (p11, p22, p12) = (k11 * q(n1, n1), k22 * q(n2, n2), k12 * q(n1, n2));
    [
        p11 * n1[0] * n1[0] + p22 * n2[0] * n2[0] + 2.0 * p12 * n1[0] * n2[0],
        p11 * n1[1] * n1[1] + p22 * n2[1] * n2[1] + 2.0 * p12 * n1[1] * n2[1],
        p11 * n1[0] * n1[1] + p22 * n2[0] * n2[1] + p12 * (n1[0] * n2[1] + n1[1] * n2[0]),
    ]
}

impl Wrinkling {
    /// The model `model` on Saint-Venant–Kirchhoff (`young` Pa, `nu`) with
    /// isotropic prestress `prestress` (Pa, stress projection only: it is
    /// part of the stress that is projected).
    pub fn new(young: f64, nu: f64, prestress: f64, model: WrinklingModel) -> Self {
        Self {
            elastic: SaintVenantKirchhoff::new(young, nu),
            young,
            nu,
            prestress,
            model,
            slack_tangent: 0.0,
        }
    }

    /// Gives slack points a tangent `fraction C` (statics; see the module docs).
    pub fn with_slack_tangent(mut self, fraction: f64) -> Self {
        self.slack_tangent = fraction;
        self
    }

    /// The model.
    pub fn model(&self) -> WrinklingModel {
        self.model
    }

    fn elastic_stress(&self, e: [f64; 3]) -> [f64; 3] {
        let s = self.elastic.stress(e);
        [s[0] + self.prestress, s[1] + self.prestress, s[2]]
    }

    /// The state at strain `e` (Voigt, engineering shear).
    pub fn state_of(&self, e: [f64; 3]) -> WrinkleState {
        match self.model {
            WrinklingModel::StressProjection => {
                let s = self.elastic_stress(e);
                let (s1, s2, _) = eigen(s[0], s[1], s[2]);
                if s2 >= 0.0 {
                    WrinkleState::Taut
                } else if s1 > 0.0 {
                    WrinkleState::Wrinkled
                } else {
                    WrinkleState::Slack
                }
            }
            WrinklingModel::RelaxedEnergy => {
                let (e1, e2, _) = eigen(e[0], e[1], 0.5 * e[2]);
                if e1 <= 0.0 {
                    WrinkleState::Slack
                } else if e2 > -self.nu * e1 {
                    WrinkleState::Taut
                } else {
                    WrinkleState::Wrinkled
                }
            }
        }
    }

    fn slack_response(&self, e: [f64; 3]) -> MaterialResponse {
        let c = self.elastic.matrix();
        let _ = e;
        MaterialResponse {
            energy: 0.0,
            stress: [0.0; 3],
            tangent: c.map(|row| row.map(|v| self.slack_tangent * v)),
        }
    }
}

impl Wrinkling {
    /// Energy, stress and (with `TANGENT`) the tangent at strain `e`; the
    /// principal decomposition that decides the state is computed once and
    /// serves the response too.
    fn respond<const TANGENT: bool>(&self, e: [f64; 3]) -> (MaterialResponse, WrinkleState) {
        let c = self.elastic.matrix();
        let slack = || MaterialResponse {
            energy: 0.0,
            stress: [0.0; 3],
            tangent: if TANGENT {
                self.slack_response(e).tangent
            } else {
                [[0.0; 3]; 3]
            },
        };
        match self.model {
            WrinklingModel::StressProjection => {
                let s = self.elastic_stress(e);
                let (s1, s2, n1) = eigen(s[0], s[1], s[2]);
                if s2 >= 0.0 {
                    // Taut.
                    let w = self.elastic.energy(e) + self.prestress * (e[0] + e[1]);
                    let r = MaterialResponse {
                        energy: w,
                        stress: s,
                        tangent: c,
                    };
                    return (r, WrinkleState::Taut);
                }
                if s1 <= 0.0 {
                    return (slack(), WrinkleState::Slack);
                }
                // Wrinkled.
                let stress = scale_in_basis(s, n1, 1.0, 0.0, 0.0);
                let mut tangent = [[0.0; 3]; 3];
                if TANGENT {
                    let k = s1 / (s1 - s2);
                    // D = dP/dS . C, column by column.
                    for col in 0..3 {
                        let ds = [c[0][col], c[1][col], c[2][col]];
                        let dp = scale_in_basis(ds, n1, 1.0, 0.0, k);
                        for row in 0..3 {
                            tangent[row][col] = dp[row];
                        }
                    }
                }
                // Reported energy: 1/2 P : E (the model has no energy).
                let energy = 0.5 * (stress[0] * e[0] + stress[1] * e[1] + stress[2] * e[2]);
                let r = MaterialResponse {
                    energy,
                    stress,
                    tangent,
                };
                (r, WrinkleState::Wrinkled)
            }
            WrinklingModel::RelaxedEnergy => {
                let (e1, e2, n1) = eigen(e[0], e[1], 0.5 * e[2]);
                if e1 <= 0.0 {
                    return (slack(), WrinkleState::Slack);
                }
                if e2 > -self.nu * e1 {
                    return (self.elastic.evaluate(e), WrinkleState::Taut);
                }
                // Wrinkled.
                let y = self.young;
                let stress = [
                    y * e1 * n1[0] * n1[0],
                    y * e1 * n1[1] * n1[1],
                    y * e1 * n1[0] * n1[1],
                ];
                let mut tangent = [[0.0; 3]; 3];
                if TANGENT {
                    let k = y * e1 / (e1 - e2);
                    for col in 0..3 {
                        // Unit engineering strain component -> tensor strain (Voigt stress form).
                        let mut de = [0.0; 3];
                        de[col] = if col == 2 { 0.5 } else { 1.0 };
                        let ds = scale_in_basis(de, n1, y, 0.0, k);
                        for row in 0..3 {
                            tangent[row][col] = ds[row];
                        }
                    }
                }
                let r = MaterialResponse {
                    energy: 0.5 * y * e1 * e1,
                    stress,
                    tangent,
                };
                (r, WrinkleState::Wrinkled)
            }
        }
    }
}

impl Material for Wrinkling {
    fn energy(&self, e: [f64; 3]) -> f64 {
        self.respond::<false>(e).0.energy
    }

    fn stress(&self, e: [f64; 3]) -> [f64; 3] {
        self.respond::<false>(e).0.stress
    }

    fn tangent(&self, e: [f64; 3]) -> [[f64; 3]; 3] {
        self.respond::<true>(e).0.tangent
    }

    fn energy_stress(&self, e: [f64; 3]) -> (f64, [f64; 3]) {
        let r = self.respond::<false>(e).0;
        (r.energy, r.stress)
    }

    fn stress_state(&self, e: [f64; 3]) -> ([f64; 3], Option<WrinkleState>) {
        let (r, state) = self.respond::<false>(e);
        (r.stress, Some(state))
    }

    fn has_symmetric_tangent(&self) -> bool {
        self.model == WrinklingModel::RelaxedEnergy
    }

    /// The relaxed energy is a potential; the projected stress is not the
    /// derivative of any energy (the module docs).
    fn is_hyperelastic(&self) -> bool {
        self.model == WrinklingModel::RelaxedEnergy
    }

    fn wrinkle_state(&self, e: [f64; 3]) -> Option<WrinkleState> {
        Some(self.state_of(e))
    }

    fn evaluate(&self, e: [f64; 3]) -> MaterialResponse {
        self.respond::<true>(e).0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `stress_state` gives what `stress` and `wrinkle_state` give
    /// apart, bit for bit, in every state of both models.
    #[test]
    fn stress_state_is_stress_and_wrinkle_state() {
        for model in [
            WrinklingModel::StressProjection,
            WrinklingModel::RelaxedEnergy,
        ] {
            let m = Wrinkling::new(2.0e6, 0.3, 0.0, model);
            let mut seen = [false; 3];
            for i in 0..9 {
                for j in 0..9 {
                    for k in 0..3 {
                        let e = [
                            (i as f64 - 4.0) * 0.003,
                            (j as f64 - 4.0) * 0.003,
                            (k as f64 - 1.0) * 0.004,
                        ];
                        let (s, state) = m.stress_state(e);
                        assert_eq!(s.map(f64::to_bits), m.stress(e).map(f64::to_bits));
                        assert_eq!(state, m.wrinkle_state(e));
                        seen[state.expect("a wrinkling model") as usize] = true;
                    }
                }
            }
            assert_eq!(seen, [true; 3], "{model:?}");
        }
    }
    use crate::fd::{gradient_error, jacobian_error};

    const Y: f64 = 2.0e6;
    const NU: f64 = 0.3;

    fn models() -> [Wrinkling; 2] {
        [
            Wrinkling::new(Y, NU, 0.0, WrinklingModel::StressProjection),
            Wrinkling::new(Y, NU, 0.0, WrinklingModel::RelaxedEnergy),
        ]
    }

    /// Strains well inside each state (away from the boundaries, where
    /// the stress is only continuous).
    fn samples() -> [([f64; 3], WrinkleState); 4] {
        [
            ([0.02, 0.015, 0.004], WrinkleState::Taut),
            ([0.03, -0.02, 0.01], WrinkleState::Wrinkled),
            ([0.01, -0.03, 0.04], WrinkleState::Wrinkled),
            ([-0.02, -0.01, 0.003], WrinkleState::Slack),
        ]
    }

    /// The tangent is the derivative of the stress in every state, for
    /// both models; the relaxed energy's stress is the derivative of its
    /// energy. Central differences with h = 1e-8 on strains of 1e-2:
    /// truncation ~1e-12 relative.
    #[test]
    fn tangents_match_finite_differences_in_every_state() {
        for m in models() {
            for (e, state) in samples() {
                assert_eq!(m.state_of(e), state, "{:?} at {e:?}", m.model());
                let stress = |x: &[f64]| m.stress([x[0], x[1], x[2]]).to_vec();
                let tangent = |x: &[f64]| m.tangent([x[0], x[1], x[2]]).concat();
                if state != WrinkleState::Slack {
                    let err = jacobian_error(stress, tangent, &e, 1e-8);
                    assert!(err < 1e-6, "{:?} {state:?}: tangent {err:e}", m.model());
                }
                if m.model() == WrinklingModel::RelaxedEnergy && state != WrinkleState::Slack {
                    let energy = |x: &[f64]| m.energy([x[0], x[1], x[2]]);
                    let err = gradient_error(energy, stress, &e, 1e-8);
                    assert!(err < 1e-6, "relaxed {state:?}: stress vs energy {err:e}");
                }
            }
        }
    }

    /// Uniaxial tension (`E22 = -nu E11`, the boundary of the taut state)
    /// leaves the stress unchanged: `S = [Y E11, 0, 0]`.
    #[test]
    fn uniaxial_tension_is_unchanged() {
        for m in models() {
            let e = [0.01, -NU * 0.01, 0.0];
            let s = m.stress(e);
            let svk = SaintVenantKirchhoff::new(Y, NU).stress(e);
            for i in 0..3 {
                assert!(
                    (s[i] - svk[i]).abs() < 1e-9 * Y,
                    "{:?}: {s:?} vs {svk:?}",
                    m.model()
                );
            }
            assert!((s[0] - Y * 0.01).abs() < 1e-9 * Y);
        }
    }

    /// A strip compressed along its length (free across: `E = [-eps, 0, 0]`)
    /// and an equal biaxial compression carry no stress and store no energy:
    /// both are slack.
    #[test]
    fn compression_is_slack_with_no_stress_and_no_energy() {
        for m in models() {
            for e in [[-0.01, 0.0, 0.0], [-0.01, -0.01, 0.0]] {
                assert_eq!(m.state_of(e), WrinkleState::Slack, "{:?} {e:?}", m.model());
                assert_eq!(m.stress(e), [0.0; 3]);
                assert_eq!(m.energy(e), 0.0);
            }
        }
    }

    /// The relaxed energy is continuous across the taut/wrinkled boundary
    /// (its stress too): at `E2 = -nu E1` both branches give `1/2 Y E1^2`.
    #[test]
    fn relaxed_energy_is_continuous_at_the_state_boundary() {
        let m = Wrinkling::new(Y, NU, 0.0, WrinklingModel::RelaxedEnergy);
        let e1 = 0.02;
        let inside = m.energy([e1, -NU * e1 + 1e-12, 0.0]);
        let outside = m.energy([e1, -NU * e1 - 1e-12, 0.0]);
        assert!((inside - outside).abs() < 1e-9 * inside);
        assert!((inside - 0.5 * Y * e1 * e1).abs() < 1e-6 * inside);
    }
}
