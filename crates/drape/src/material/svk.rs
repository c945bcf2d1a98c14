//! Saint-Venant–Kirchhoff in plane stress (docs/theory.md §1.3).

use super::{Material, MaterialResponse};

/// The stretch below which Saint-Venant–Kirchhoff loses stability in
/// uniaxial compression: the nominal stress `Y lambda (lambda^2 - 1) / 2`
/// has its minimum at `lambda = 1/sqrt(3)`. A step that compresses an
/// element of a membrane without tension field below it is cut back
/// (`integrator::solve_step`).
pub const CRITICAL_STRETCH: f64 = 0.577_350_269_189_625_8;

/// Saint-Venant–Kirchhoff, plane stress: `s = C e`, `W = 1/2 e . C e`,
///
/// ```text
/// C = Y / (1 - nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]]
/// ```
///
/// with Young's modulus `Y` (Pa) and Poisson's ratio `nu`. It is stable in
/// compression only down to a stretch of `1/sqrt(3)` (uniaxial), after which
/// the stress–stretch curve turns down.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SaintVenantKirchhoff {
    /// The constitutive matrix `C` (Pa).
    c: [[f64; 3]; 3],
}

impl SaintVenantKirchhoff {
    /// From Young's modulus (Pa) and Poisson's ratio (`-1 < nu < 0.5`).
    pub fn new(youngs_modulus: f64, poisson_ratio: f64) -> Self {
        let k = youngs_modulus / (1.0 - poisson_ratio * poisson_ratio);
        Self {
            c: [
                [k, k * poisson_ratio, 0.0],
                [k * poisson_ratio, k, 0.0],
                [0.0, 0.0, k * (1.0 - poisson_ratio) / 2.0],
            ],
        }
    }

    /// The constitutive matrix `C` (Pa).
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        self.c
    }
}

impl Material for SaintVenantKirchhoff {
    fn energy(&self, e: [f64; 3]) -> f64 {
        let s = self.stress(e);
        0.5 * (s[0] * e[0] + s[1] * e[1] + s[2] * e[2])
    }

    #[allow(non_snake_case)]
    fn stress(&self, e: [f64; 3]) -> [f64; 3] {
        let C = &self.c;
        [
            C[0][0] * e[0] + C[0][1] * e[1],
            C[1][0] * e[0] + C[1][1] * e[1],
            C[2][2] * e[2],
        ]
    }

    fn tangent(&self, _e: [f64; 3]) -> [[f64; 3]; 3] {
        self.c
    }

    fn energy_stress(&self, e: [f64; 3]) -> (f64, [f64; 3]) {
        let s = self.stress(e);
        (0.5 * (s[0] * e[0] + s[1] * e[1] + s[2] * e[2]), s)
    }

    fn evaluate(&self, e: [f64; 3]) -> MaterialResponse {
        let s = self.stress(e);
        MaterialResponse {
            energy: 0.5 * (s[0] * e[0] + s[1] * e[1] + s[2] * e[2]),
            stress: s,
            tangent: self.c,
        }
    }
}
