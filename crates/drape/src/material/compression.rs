//! A compression-soft membrane: the relaxed (tension-field) energy with a
//! residual fraction `r` of the elastic compressive stiffness
//! (docs/theory.md §1.4, "Compression-soft membrane").
//!
//! A woven fabric resists stretching through its yarns, but in-plane
//! compression first takes up the yarns' crimp and then buckles them out
//! of the plane in folds far shorter than any affordable element: its
//! compressive stiffness at the scale of an element is a small fraction of
//! its tensile one. Tension-field theory takes that fraction to zero
//! (Pipkin 1986, the `relaxed-energy` model), which leaves a collapsing
//! element with no stiffness at all. This model keeps a fraction of it:
//!
//! ```text
//! W_r(E) = r W_el(E) + (1 - r) W_rel(E),      0 < r <= 1,
//! S_r    = r S_el    + (1 - r) S_rel,
//! D_r    = r C       + (1 - r) D_rel,
//! ```
//!
//! with `W_el = 1/2 E : C : E` the elastic (Saint-Venant–Kirchhoff,
//! isotropic or orthotropic) energy and `W_rel` its relaxed energy. Where
//! the membrane is taut the two agree (`W_r = W_el`: tension is unchanged);
//! in a wrinkled state the stiffness across the wrinkles is `r` times the
//! elastic one; slack, `r W_el`. A convex combination of two potentials is
//! a potential with the combined exact tangent, symmetric, so Newton keeps
//! its line search on the energy and its Cholesky; `r = 1` is the elastic
//! material, `r -> 0` the relaxed energy. This is the "compression ratio"
//! of the scenario's `[material] compression_ratio`.
//!
//! Cf. the no-compression and compression-modulus models of cloth
//! simulators (Choi & Ko 2002, "Stable but responsive cloth", who give
//! compression its own, buckled response) and the bilinear tension /
//! compression yarn laws of woven-fabric models (Kawabata's biaxial
//! curves: compression stiffness one to two orders below tension).

use super::{Material, MaterialResponse, WrinkleState};

/// The relaxed energy with a fraction `r` of the elastic energy added back
/// (the module doc).
#[derive(Debug)]
pub struct CompressionSoft {
    /// The elastic law (`W_el`, `C`).
    elastic: Box<dyn Material>,
    /// Its relaxed energy (`W_rel`): the same law under Pipkin's tension
    /// field.
    relaxed: Box<dyn Material>,
    /// The compression ratio `r` in (0, 1].
    ratio: f64,
}

impl CompressionSoft {
    /// `relaxed` must be the relaxed energy of `elastic` (both hyperelastic,
    /// the same axis); `ratio` in (0, 1].
    pub fn new(elastic: Box<dyn Material>, relaxed: Box<dyn Material>, ratio: f64) -> Self {
        assert!(
            ratio > 0.0 && ratio <= 1.0,
            "compression ratio {ratio} outside (0, 1]"
        );
        assert!(elastic.is_hyperelastic() && relaxed.is_hyperelastic());
        assert_eq!(elastic.axis(), relaxed.axis());
        Self {
            elastic,
            relaxed,
            ratio,
        }
    }

    fn mix(&self, a: f64, b: f64) -> f64 {
        self.ratio * a + (1.0 - self.ratio) * b
    }

    fn mix3(&self, a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| self.mix(a[i], b[i]))
    }
}

impl Material for CompressionSoft {
    fn energy(&self, e: [f64; 3]) -> f64 {
        self.mix(self.elastic.energy(e), self.relaxed.energy(e))
    }

    fn stress(&self, e: [f64; 3]) -> [f64; 3] {
        self.mix3(self.elastic.stress(e), self.relaxed.stress(e))
    }

    fn tangent(&self, e: [f64; 3]) -> [[f64; 3]; 3] {
        let (a, b) = (self.elastic.tangent(e), self.relaxed.tangent(e));
        std::array::from_fn(|i| self.mix3(a[i], b[i]))
    }

    fn evaluate(&self, e: [f64; 3]) -> MaterialResponse {
        let (a, b) = (self.elastic.evaluate(e), self.relaxed.evaluate(e));
        MaterialResponse {
            energy: self.mix(a.energy, b.energy),
            stress: self.mix3(a.stress, b.stress),
            tangent: std::array::from_fn(|i| self.mix3(a.tangent[i], b.tangent[i])),
        }
    }

    fn energy_stress(&self, e: [f64; 3]) -> (f64, [f64; 3]) {
        let (wa, sa) = self.elastic.energy_stress(e);
        let (wb, sb) = self.relaxed.energy_stress(e);
        (self.mix(wa, wb), self.mix3(sa, sb))
    }

    fn has_symmetric_tangent(&self) -> bool {
        self.elastic.has_symmetric_tangent() && self.relaxed.has_symmetric_tangent()
    }

    /// The relaxed energy's state: where the fabric is wrinkled or slack,
    /// it carries only the fraction `r` of its elastic compression.
    fn wrinkle_state(&self, e: [f64; 3]) -> Option<WrinkleState> {
        self.relaxed.wrinkle_state(e)
    }

    fn stress_state(&self, e: [f64; 3]) -> ([f64; 3], Option<WrinkleState>) {
        let (sb, state) = self.relaxed.stress_state(e);
        (self.mix3(self.elastic.stress(e), sb), state)
    }

    fn axis(&self) -> Option<[f64; 3]> {
        self.elastic.axis()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fd::{gradient_error, jacobian_error};
    use crate::material::{Orthotropic, SaintVenantKirchhoff, Wrinkling, WrinklingModel};

    const Y: f64 = 2.0e6;
    const NU: f64 = 0.3;

    fn isotropic(r: f64) -> CompressionSoft {
        CompressionSoft::new(
            Box::new(SaintVenantKirchhoff::new(Y, NU)),
            Box::new(Wrinkling::new(Y, NU, 0.0, WrinklingModel::RelaxedEnergy)),
            r,
        )
    }

    fn woven(r: f64) -> CompressionSoft {
        let o = || Orthotropic::new(5.0e6, 1.0e6, 5.0e4, 0.3, [1.0, 1.0, 0.0]).unwrap();
        CompressionSoft::new(
            Box::new(o()),
            Box::new(o().with_wrinkling(WrinklingModel::RelaxedEnergy, 0.0)),
            r,
        )
    }

    /// Taut, wrinkled (either way round) and slack strains, away from the
    /// state boundaries where the tangent jumps.
    const SAMPLES: [[f64; 3]; 5] = [
        [0.02, 0.015, 0.004],
        [0.03, -0.02, 0.01],
        [0.01, -0.03, 0.04],
        [-0.03, 0.02, -0.01],
        [-0.02, -0.01, 0.003],
    ];

    /// The stress is the energy's gradient and the tangent the stress's
    /// Jacobian in every state, isotropic and woven (central differences,
    /// h = 1e-8 on strains of 1e-2).
    #[test]
    fn stress_and_tangent_match_finite_differences() {
        for m in [isotropic(0.05), woven(0.05), isotropic(0.5)] {
            for e in SAMPLES {
                let energy = |x: &[f64]| m.energy([x[0], x[1], x[2]]);
                let stress = |x: &[f64]| m.stress([x[0], x[1], x[2]]).to_vec();
                let tangent = |x: &[f64]| m.tangent([x[0], x[1], x[2]]).concat();
                let g = gradient_error(energy, stress, &e, 1e-8);
                let j = jacobian_error(stress, tangent, &e, 1e-8);
                assert!(g < 1e-6 && j < 1e-6, "{e:?}: stress {g:e}, tangent {j:e}");
                let r = m.evaluate(e);
                assert_eq!(r.energy, m.energy(e));
                assert_eq!(r.stress, m.stress(e));
                assert_eq!(r.tangent, m.tangent(e));
                assert_eq!(m.energy_stress(e), (r.energy, r.stress));
                assert_eq!(m.stress_state(e).0, r.stress);
            }
        }
    }

    /// Tension is unchanged (the taut state is the elastic material), a
    /// strip compressed along its length free across (`E = [-eps, 0, 0]`,
    /// slack) carries exactly `r` times the elastic stress and energy, and
    /// across the wrinkles of a wrinkled state the tangent is `r` times the
    /// elastic one. `r = 1` is the elastic material exactly.
    #[test]
    fn tension_is_elastic_and_compression_is_the_ratio() {
        let svk = SaintVenantKirchhoff::new(Y, NU);
        let r = 0.03;
        let m = isotropic(r);
        let taut = [0.02, 0.015, 0.004];
        assert_eq!(m.wrinkle_state(taut), Some(WrinkleState::Taut));
        for (a, b) in m.stress(taut).iter().zip(svk.stress(taut)) {
            assert!((a - b).abs() <= 1e-12 * Y);
        }
        let slack = [-0.01, 0.0, 0.0];
        assert_eq!(m.wrinkle_state(slack), Some(WrinkleState::Slack));
        for (a, b) in m.stress(slack).iter().zip(svk.stress(slack)) {
            assert!((a - r * b).abs() <= 1e-12 * Y);
        }
        assert!((m.energy(slack) - r * svk.energy(slack)).abs() <= 1e-12 * svk.energy(slack));
        // Wrinkled along e1 (tension along e1, compression along e2): the
        // relaxed tangent has no e2-e2 stiffness, so D_22 = r C_22.
        let wrinkled = [0.03, -0.02, 0.0];
        assert_eq!(m.wrinkle_state(wrinkled), Some(WrinkleState::Wrinkled));
        let d = m.tangent(wrinkled);
        assert!(
            (d[1][1] - r * svk.matrix()[1][1]).abs() <= 1e-9 * Y,
            "{d:?}"
        );
        let one = isotropic(1.0);
        for e in SAMPLES {
            assert_eq!(one.evaluate(e), svk.evaluate(e));
        }
    }

    /// Positive definite in every state for `r > 0` (the relaxed energy
    /// alone is only semi-definite: zero when slack), so a slack element
    /// keeps a stiffness.
    #[test]
    fn tangent_is_positive_definite_in_every_state() {
        for m in [isotropic(0.01), woven(0.01)] {
            for e in SAMPLES {
                let d = m.tangent(e);
                let minor2 = d[0][0] * d[1][1] - d[0][1] * d[1][0];
                let det = d[0][0] * (d[1][1] * d[2][2] - d[1][2] * d[2][1])
                    - d[0][1] * (d[1][0] * d[2][2] - d[1][2] * d[2][0])
                    + d[0][2] * (d[1][0] * d[2][1] - d[1][1] * d[2][0]);
                assert!(d[0][0] > 0.0 && minor2 > 0.0 && det > 0.0, "{e:?}: {d:?}");
            }
        }
    }
}
