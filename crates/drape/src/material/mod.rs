//! Constitutive models of the membrane (plane stress).
//!
//! Convention (Voigt, engineering shear), used everywhere in drape:
//! strain `e = [E11, E22, 2 E12]` (Green–Lagrange, in the element's local
//! frame), stress `s = [S11, S22, S12]` (second Piola–Kirchhoff, Pa), so
//! that the energy increment is `dW = s . de`. A material gives the strain
//! energy per unit initial volume `W(e)` (J/m^3), the stress `s = dW/de`
//! and the tangent `D = ds/de` (3x3, Pa).

mod compression;
mod orthotropic;
mod svk;
pub mod wrinkling;

pub use compression::CompressionSoft;
pub use orthotropic::{Orthotropic, OrthotropicError};
pub use svk::{CRITICAL_STRETCH, SaintVenantKirchhoff};
pub use wrinkling::{WrinkleState, Wrinkling, WrinklingModel};

/// The energy, stress and tangent at one strain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialResponse {
    /// Strain energy per unit initial volume `W` (J/m^3).
    pub energy: f64,
    /// `s = [S11, S22, S12]` (Pa).
    pub stress: [f64; 3],
    /// `D[r][c] = d s_r / d e_c` (Pa); not symmetric for every model.
    pub tangent: [[f64; 3]; 3],
}

/// A plane-stress constitutive model in the Voigt convention above.
pub trait Material: Send + Sync + std::fmt::Debug {
    /// Strain energy per unit initial volume `W(e)` (J/m^3).
    fn energy(&self, strain: [f64; 3]) -> f64;
    /// Second Piola–Kirchhoff stress `s = dW/de` (Pa).
    fn stress(&self, strain: [f64; 3]) -> [f64; 3];
    /// Tangent `D = ds/de` (Pa).
    fn tangent(&self, strain: [f64; 3]) -> [[f64; 3]; 3];
    /// All three at once (override when sharing work pays).
    fn evaluate(&self, strain: [f64; 3]) -> MaterialResponse {
        MaterialResponse {
            energy: self.energy(strain),
            stress: self.stress(strain),
            tangent: self.tangent(strain),
        }
    }
    /// Energy and stress without the tangent: what a force-only
    /// evaluation (Newton's line search, chord steps) needs. Override when
    /// the tangent costs more than the stress (the wrinkling models).
    fn energy_stress(&self, strain: [f64; 3]) -> (f64, [f64; 3]) {
        let r = self.evaluate(strain);
        (r.energy, r.stress)
    }
    /// Whether [`Material::tangent`] is always symmetric (then the Hessian
    /// is symmetric and Cholesky applies).
    fn has_symmetric_tangent(&self) -> bool {
        true
    }
    /// Whether [`Material::stress`] is the derivative of
    /// [`Material::energy`] (a hyperelastic material: the strain energy is
    /// then a potential of the internal forces, and Newton may judge its
    /// steps by the energy). Default: yes.
    fn is_hyperelastic(&self) -> bool {
        true
    }
    /// The wrinkling state at a strain, for models that have one; `None`
    /// for models that carry compression (the output then classifies the
    /// stress itself).
    fn wrinkle_state(&self, _strain: [f64; 3]) -> Option<WrinkleState> {
        None
    }
    /// [`Material::stress`] and [`Material::wrinkle_state`] at once
    /// (override when they share work: the wrinkling models decide the
    /// state by the decomposition that gives the stress).
    fn stress_state(&self, strain: [f64; 3]) -> ([f64; 3], Option<WrinkleState>) {
        (self.stress(strain), self.wrinkle_state(strain))
    }
    /// The material's first axis in the initial configuration (the warp
    /// of a woven fabric): each element's local frame then has `e1` along
    /// its projection on the element's plane, and the strain handed to the
    /// material is in those axes. `None` (the default) for an isotropic
    /// material, whose elements keep `e1 = G_1 / |G_1|`.
    fn axis(&self) -> Option<[f64; 3]> {
        None
    }
}
