//! Orthotropic Saint-Venant–Kirchhoff in plane stress: a woven fabric
//! (docs/theory.md §1.11), with its tension field.
//!
//! # Elastic law
//!
//! In the material axes (1 = warp, 2 = weft, in the fabric's plane) the
//! stress is `s = C e` (Voigt, engineering shear, as in [`super`]), with
//!
//! ```text
//! C = 1 / (1 - nu12 nu21) [[E1, nu12 E2, 0], [nu12 E2, E2, 0], [0, 0, (1 - nu12 nu21) G12]]
//! A = C^-1 = [[1/E1, -nu12/E1, 0], [-nu12/E1, 1/E2, 0], [0, 0, 1/G12]]
//! ```
//!
//! `nu21 = nu12 E2 / E1` (Maxwell–Betti). `C` is positive definite iff the
//! moduli are positive and `nu12^2 < E1 / E2`. The strain handed to the
//! material is in the material axes: each element's local frame has its
//! first axis along the warp direction projected on the element's plane
//! ([`Material::axis`]), so `C` is never rotated at run time and the
//! response does not depend on the element's node numbering.
//!
//! # Tension field (wrinkling)
//!
//! A membrane that cannot carry compression wrinkles: its mid-surface
//! strain `E` is the elastic strain minus a wrinkling strain `a m (x) m`
//! (`a >= 0`) across the wrinkles, and the stress is uniaxial along them,
//! `S = sigma n (x) n`, `n . m = 0` (Roddeman, Drukker, Oomens & Janssen
//! 1987, "The wrinkling of thin membranes", J. Appl. Mech. 54). For an
//! anisotropic `C` the wrinkle direction `n` is *not* a principal
//! direction of `E` or of `C E`; it is fixed by the two conditions
//! `m . S(E + a m m) . m = 0` and `n . S(E + a m m) . m = 0`.
//!
//! drape finds it from the relaxed energy (Pipkin 1986's construction for
//! any `C`): the least energy over the wrinkling strains,
//! `W_rel(E) = min_{a >= 0, m} W(E + a m (x) m)`. With `t(theta) = [c^2,
//! s^2, c s]` (`n = (c, s)` at angle `theta` to the warp; `t . e = n . E .
//! n`, and `t` is also the Voigt stress form of `n (x) n`) and the uniaxial
//! modulus `E_n = 1 / (t . A t)` along `n`:
//!
//! ```text
//! W_rel(E) = 1/2 e . C e                              taut:     s2(C e) >= 0
//!          = max_theta 1/2 (t . e)^2 / (t . A t)       wrinkled: otherwise, E1 > 0
//!          = 0                                         slack:    E1 <= 0
//! ```
//!
//! (`s2` the smaller principal stress, `E1` the larger principal strain.)
//! The wrinkled line holds because any elastic strain `E + a m m` has
//! `n . (E + a m m) . n >= n . E . n` for every `n`, and the least energy
//! of a strain with a given normal component `eps` along `n` is the
//! uniaxial one, `1/2 E_n eps^2`: so `W_rel >= max_n 1/2 E_n (n . E . n)^2`,
//! with equality at the tension-field state, whose stationarity in `theta`
//! is exactly Roddeman's shear condition. The maximising `theta*` is the
//! wrinkle direction; the stress is `sigma t*`, `sigma = (t* . e) / (t* .
//! A t*)`. For an isotropic `C` this is Pipkin's energy `1/2 Y E1^2` along
//! the major principal strain.
//!
//! `theta*` is found by sampling `1/2 (t . e)^2 / (t . A t)` on a grid
//! fine enough for the narrowest peak of `E_n` (spacing a sixth of
//! `sqrt(min modulus / max modulus)` radians; at least 64 points), plus the
//! major principal strain direction, then Newton on
//! `h = 2 p' q - p q'` (`p = t . e`, `q = t . A t`; `h` has the sign of
//! `d W / d theta`) safeguarded by bisection in the bracket around the best
//! sample, to `|d theta| <= 1e-15`.
//!
//! Tangents, with `W_te = dW_theta/de` and `W_tt = d^2 W / d theta^2` at
//! `theta*` (implicit differentiation of `W_theta(theta*(e), e) = 0`,
//! `d theta*/de = -W_te / W_tt`):
//!
//! * `relaxed-energy`: `W_rel`'s Hessian, `D = t t^T / q - W_te W_te^T /
//!   W_tt` (symmetric, positive semi-definite: `W_tt < 0` at a maximum),
//!   with `W_te = sigma t' - sigma (t' . A t) t / q` and `W_tt = sigma^2
//!   (t' . A t)^2 / q + sigma (t'' . e) - sigma^2 (t'' . A t + t' . A t')`.
//! * `stress-projection`: the elastic stress `S_el = C e + sigma0 [1, 1,
//!   0]` (with the prestress `sigma0`) is projected on the wrinkle
//!   direction: `S = (n* . S_el . n*) n* (x) n*`, with `n*` the tension-field
//!   direction of the strain `A S_el` that would carry `S_el`. Taut when
//!   `s2(S_el) >= 0`, slack when no `n*` has `n* . S_el . n* > 0`.
//!   `D = t (x) C t_s + (sigma t' + (t_s' . S_el) t) (x) d theta*/de`, `t_s
//!   = [c^2, s^2, 2 c s]` (so that `t_s . S = n . S . n`): not symmetric.
//!   For an isotropic `C`, `n*` is the principal direction of `S_el` and
//!   this is release 1's projection `s1 n1 (x) n1`.
//!
//! Every tangent is checked against central differences of the stress
//! (and the relaxed stress against the energy) in taut, wrinkled and slack
//! states for several strains and anisotropies (tests below), and the
//! relaxed energy against a brute-force minimisation over `(a, m)`.

use super::wrinkling::eigen;
use super::{Material, MaterialResponse, WrinkleState, WrinklingModel};

/// Why the orthotropic constants give no material.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OrthotropicError {
    /// A modulus is not a positive finite number.
    #[error("{name} must be a positive finite number (Pa), not {value}")]
    Modulus {
        /// `warp_modulus`, `weft_modulus` or `shear_modulus`.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// `nu12^2 >= E1 / E2`: `C` is not positive definite.
    #[error(
        "poisson_ratio {nu12} makes the material unstable: nu12^2 must be below warp_modulus / weft_modulus = {limit} (nu12 nu21 < 1)"
    )]
    PoissonRatio {
        /// The value given.
        nu12: f64,
        /// `E1 / E2`.
        limit: f64,
    },
    /// The warp direction is zero or not finite.
    #[error("the warp direction {direction:?} must be a finite non-zero vector")]
    Direction {
        /// The value given.
        direction: [f64; 3],
    },
}

/// One sampled wrinkle direction: `t(theta)` and `1 / (t . A t)`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sample {
    t: [f64; 3],
    modulus: f64,
}

/// The tension-field direction at a strain, with what the tangents need.
#[derive(Debug, Clone, Copy)]
struct Tension {
    /// `t(theta*)`, `t'`, `t''`.
    t: [[f64; 3]; 3],
    /// `sigma = (t . e) / (t . A t)` (Pa).
    sigma: f64,
    /// `q = t . A t` (1/Pa).
    q: f64,
    /// `d W_theta / d e` at `theta*`.
    w_te: [f64; 3],
    /// `d^2 W / d theta^2` at `theta*` (< 0 at a strict maximum).
    w_tt: f64,
}

/// Orthotropic Saint-Venant–Kirchhoff, optionally with a tension-field
/// model (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Orthotropic {
    c: [[f64; 3]; 3],
    a: [[f64; 3]; 3],
    warp: [f64; 3],
    wrinkling: Option<WrinklingModel>,
    prestress: f64,
    slack_tangent: f64,
    grid: Vec<Sample>,
}

fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    let row = |r: &[f64; 3]| r[0] * v[0] + r[1] * v[1] + r[2] * v[2];
    [row(&m[0]), row(&m[1]), row(&m[2])]
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `t(theta) = [c^2, s^2, c s]` and its first two derivatives.
fn directions(theta: f64) -> [[f64; 3]; 3] {
    let (s, c) = theta.sin_cos();
    directions_of(c, s)
}

/// [`directions`] from `c = cos theta`, `s = sin theta`.
fn directions_of(c: f64, s: f64) -> [[f64; 3]; 3] {
    let (cc, ss, cs) = (c * c, s * s, c * s);
    [
        [cc, ss, cs],
        [-2.0 * cs, 2.0 * cs, cc - ss],
        [-2.0 * (cc - ss), 2.0 * (cc - ss), -4.0 * cs],
    ]
}

impl Orthotropic {
    /// From the warp modulus `E1`, the weft modulus `E2`, the in-plane
    /// shear modulus `G12` (Pa), the Poisson ratio `nu12` (weft contraction
    /// per unit warp stretch) and the warp direction in the initial
    /// configuration (any length; projected on each element's plane).
    pub fn new(
        warp_modulus: f64,
        weft_modulus: f64,
        shear_modulus: f64,
        poisson_ratio: f64,
        warp_direction: [f64; 3],
    ) -> Result<Self, OrthotropicError> {
        for (name, value) in [
            ("warp_modulus", warp_modulus),
            ("weft_modulus", weft_modulus),
            ("shear_modulus", shear_modulus),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(OrthotropicError::Modulus { name, value });
            }
        }
        let (e1, e2, g, nu) = (warp_modulus, weft_modulus, shear_modulus, poisson_ratio);
        let limit = e1 / e2;
        if !(nu.is_finite() && nu * nu < limit) {
            return Err(OrthotropicError::PoissonRatio { nu12: nu, limit });
        }
        if !warp_direction.iter().all(|v| v.is_finite()) || warp_direction == [0.0; 3] {
            return Err(OrthotropicError::Direction {
                direction: warp_direction,
            });
        }
        let d = 1.0 - nu * nu * (e2 / e1);
        let c = [
            [e1 / d, nu * e2 / d, 0.0],
            [nu * e2 / d, e2 / d, 0.0],
            [0.0, 0.0, g],
        ];
        let a = [
            [1.0 / e1, -nu / e1, 0.0],
            [-nu / e1, 1.0 / e2, 0.0],
            [0.0, 0.0, 1.0 / g],
        ];
        // The narrowest peak of the uniaxial modulus E_n(theta) is about
        // sqrt(min / max) radians wide (of the moduli E1, E2, G12 and the
        // 45-degree one): sample six times finer.
        let moduli = [e1, e2, g];
        let lo = moduli.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = moduli.iter().copied().fold(0.0, f64::max);
        let spacing = (lo / hi).sqrt() / 6.0;
        let count = ((std::f64::consts::PI / spacing).ceil() as usize).clamp(64, 8192);
        let grid = (0..count)
            .map(|i| {
                let t = directions(std::f64::consts::PI * i as f64 / count as f64)[0];
                Sample {
                    t,
                    modulus: 1.0 / dot3(t, mat_vec(&a, t)),
                }
            })
            .collect();
        Ok(Self {
            c,
            a,
            warp: warp_direction,
            wrinkling: None,
            prestress: 0.0,
            slack_tangent: 0.0,
            grid,
        })
    }

    /// With the tension-field model `model` and, for the stress
    /// projection, the isotropic prestress `prestress` (Pa) that is part
    /// of the projected stress (it must be 0 with the relaxed energy).
    pub fn with_wrinkling(mut self, model: WrinklingModel, prestress: f64) -> Self {
        self.wrinkling = Some(model);
        self.prestress = prestress;
        self
    }

    /// Gives slack points a tangent `fraction C` (statics; see
    /// [`super::Wrinkling::with_slack_tangent`]).
    pub fn with_slack_tangent(mut self, fraction: f64) -> Self {
        self.slack_tangent = fraction;
        self
    }

    /// The constitutive matrix `C` in the material axes (Pa).
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        self.c
    }

    /// The tension-field model, if any.
    pub fn wrinkling(&self) -> Option<WrinklingModel> {
        self.wrinkling
    }

    /// The wrinkle direction of strain `e` (module docs): `None` when no
    /// direction carries tension (`E1 <= 0`).
    fn tension(&self, e: [f64; 3]) -> Option<Tension> {
        let a = &self.a;
        let (e1, _, n1) = eigen(e[0], e[1], 0.5 * e[2]);
        if e1 <= 0.0 {
            return None;
        }
        // The best sample, and the major principal strain direction
        // (where t . e = E1 > 0, so there is always a candidate).
        let step = std::f64::consts::PI / self.grid.len() as f64;
        let value = |t: [f64; 3], modulus: f64| {
            let p = dot3(t, e);
            if p > 0.0 { p * p * modulus } else { 0.0 }
        };
        let pt = directions_of(n1[0], n1[1])[0];
        let mut best = (None, value(pt, 1.0 / dot3(pt, mat_vec(a, pt))));
        for (i, s) in self.grid.iter().enumerate() {
            let g = value(s.t, s.modulus);
            if g > best.1 {
                best = (Some(i), g);
            }
        }
        // The start: the principal direction, or the vertex of the
        // parabola through the best sample and its neighbours (which
        // brackets a maximum).
        let (mut theta, mut cs, centre) = match best.0 {
            None => {
                let theta = n1[1].atan2(n1[0]).rem_euclid(std::f64::consts::PI);
                (theta, (n1[0], n1[1]), theta)
            }
            Some(i) => {
                let n = self.grid.len();
                let at = |k: usize| value(self.grid[k].t, self.grid[k].modulus);
                let (gm, gp) = (at((i + n - 1) % n), at((i + 1) % n));
                let curvature = gm - 2.0 * best.1 + gp;
                let shift = 0.5 * step * (gm - gp) / curvature;
                let shift = if shift.is_finite() {
                    shift.clamp(-step, step)
                } else {
                    0.0
                };
                let theta = step * i as f64 + shift;
                let (s, c) = theta.sin_cos();
                (theta, (c, s), step * i as f64)
            }
        };
        // Newton on h(theta) = 2 p' q - p q' (the sign of dW/dtheta),
        // kept inside the bracket of the neighbouring samples and
        // bisected there when it steps out; h > 0 left of the maximum.
        let (mut lo, mut hi) = (centre - step, centre + step);
        let mut dirs;
        let mut iterations = 0;
        loop {
            dirs = directions_of(cs.0, cs.1);
            let [t, t1, t2] = dirs;
            let (at, at1) = (mat_vec(a, t), mat_vec(a, t1));
            let (p, p1, p2) = (dot3(t, e), dot3(t1, e), dot3(t2, e));
            let q = dot3(t, at);
            let q1 = 2.0 * dot3(t1, at);
            let q2 = 2.0 * (dot3(t2, at) + dot3(t1, at1));
            let f = 2.0 * p1 * q - p * q1;
            let df = 2.0 * p2 * q + p1 * q1 - p * q2;
            iterations += 1;
            if f == 0.0 || iterations > 100 {
                break;
            }
            if f > 0.0 {
                lo = theta;
            } else {
                hi = theta;
            }
            let mut next = theta - f / df;
            if !(next > lo && next < hi && next.is_finite()) {
                next = 0.5 * (lo + hi);
            }
            if (next - theta).abs() <= 2e-15 || hi - lo <= 2e-15 {
                break;
            }
            theta = next;
            let (s, c) = theta.sin_cos();
            cs = (c, s);
        }
        let [t, t1, t2] = dirs;
        let (at, at1) = (mat_vec(a, t), mat_vec(a, t1));
        let q = dot3(t, at);
        let sigma = dot3(t, e) / q;
        let t1at = dot3(t1, at);
        let w_te = [
            sigma * t1[0] - sigma * t1at * t[0] / q,
            sigma * t1[1] - sigma * t1at * t[1] / q,
            sigma * t1[2] - sigma * t1at * t[2] / q,
        ];
        let w_tt = sigma * sigma * t1at * t1at / q + sigma * dot3(t2, e)
            - sigma * sigma * (dot3(t2, at) + dot3(t1, at1));
        Some(Tension {
            t: [t, t1, t2],
            sigma,
            q,
            w_te,
            w_tt,
        })
    }

    fn slack(&self, tangent: bool) -> MaterialResponse {
        MaterialResponse {
            energy: 0.0,
            stress: [0.0; 3],
            tangent: if tangent {
                self.c.map(|row| row.map(|v| self.slack_tangent * v))
            } else {
                [[0.0; 3]; 3]
            },
        }
    }

    /// Energy, stress and (with `TANGENT`) the tangent at strain `e`, and
    /// the state (`None` without a tension-field model).
    fn respond<const TANGENT: bool>(
        &self,
        e: [f64; 3],
    ) -> (MaterialResponse, Option<WrinkleState>) {
        // The elastic stress C e + sigma0 [1, 1, 0], one product with C.
        let ce = mat_vec(&self.c, e);
        let s = [ce[0] + self.prestress, ce[1] + self.prestress, ce[2]];
        let elastic = MaterialResponse {
            energy: 0.5 * dot3(ce, e) + self.prestress * (e[0] + e[1]),
            stress: s,
            tangent: self.c,
        };
        let Some(model) = self.wrinkling else {
            return (elastic, None);
        };
        if eigen(s[0], s[1], s[2]).1 >= 0.0 {
            return (elastic, Some(WrinkleState::Taut));
        }
        let slack = || (self.slack(TANGENT), Some(WrinkleState::Slack));
        match model {
            WrinklingModel::RelaxedEnergy => {
                let Some(f) = self.tension(e) else {
                    return slack();
                };
                let t = f.t[0];
                let mut tangent = [[0.0; 3]; 3];
                if TANGENT {
                    let drop = if f.w_tt < 0.0 { -1.0 / f.w_tt } else { 0.0 };
                    for r in 0..3 {
                        for c in 0..3 {
                            tangent[r][c] = t[r] * t[c] / f.q + drop * f.w_te[r] * f.w_te[c];
                        }
                    }
                }
                let r = MaterialResponse {
                    energy: 0.5 * f.sigma * f.sigma * f.q,
                    stress: t.map(|v| f.sigma * v),
                    tangent,
                };
                (r, Some(WrinkleState::Wrinkled))
            }
            WrinklingModel::StressProjection => {
                // The strain that would carry S_el elastically.
                let carried = mat_vec(&self.a, s);
                let Some(f) = self.tension(carried) else {
                    return slack();
                };
                let [t, t1, _] = f.t;
                let ts = [t[0], t[1], 2.0 * t[2]];
                let sigma = dot3(ts, s);
                if sigma <= 0.0 {
                    return slack();
                }
                let stress = t.map(|v| sigma * v);
                let mut tangent = [[0.0; 3]; 3];
                if TANGENT {
                    let cts = mat_vec(&self.c, ts);
                    let ts1 = [t1[0], t1[1], 2.0 * t1[2]];
                    let turn = [0, 1, 2].map(|i| sigma * t1[i] + dot3(ts1, s) * t[i]);
                    // d theta*/de = -W_te / W_tt at the carried strain,
                    // whose derivative in e is the identity.
                    let dtheta = if f.w_tt < 0.0 {
                        f.w_te.map(|v| -v / f.w_tt)
                    } else {
                        [0.0; 3]
                    };
                    for r in 0..3 {
                        for c in 0..3 {
                            tangent[r][c] = t[r] * cts[c] + turn[r] * dtheta[c];
                        }
                    }
                }
                let r = MaterialResponse {
                    // Reported energy: 1/2 P : E (the model has no energy).
                    energy: 0.5 * dot3(stress, e),
                    stress,
                    tangent,
                };
                (r, Some(WrinkleState::Wrinkled))
            }
        }
    }
}

impl Material for Orthotropic {
    fn energy(&self, e: [f64; 3]) -> f64 {
        self.respond::<false>(e).0.energy
    }

    fn stress(&self, e: [f64; 3]) -> [f64; 3] {
        self.respond::<false>(e).0.stress
    }

    fn tangent(&self, e: [f64; 3]) -> [[f64; 3]; 3] {
        self.respond::<true>(e).0.tangent
    }

    fn evaluate(&self, e: [f64; 3]) -> MaterialResponse {
        self.respond::<true>(e).0
    }

    fn energy_stress(&self, e: [f64; 3]) -> (f64, [f64; 3]) {
        let r = self.respond::<false>(e).0;
        (r.energy, r.stress)
    }

    fn stress_state(&self, e: [f64; 3]) -> ([f64; 3], Option<WrinkleState>) {
        let (r, state) = self.respond::<false>(e);
        (r.stress, state)
    }

    fn wrinkle_state(&self, e: [f64; 3]) -> Option<WrinkleState> {
        self.respond::<false>(e).1
    }

    fn has_symmetric_tangent(&self) -> bool {
        self.wrinkling != Some(WrinklingModel::StressProjection)
    }

    fn is_hyperelastic(&self) -> bool {
        self.wrinkling != Some(WrinklingModel::StressProjection)
    }

    fn axis(&self) -> Option<[f64; 3]> {
        Some(self.warp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fd::{gradient_error, jacobian_error};
    use crate::material::{SaintVenantKirchhoff, Wrinkling};

    const MODELS: [WrinklingModel; 2] = [
        WrinklingModel::StressProjection,
        WrinklingModel::RelaxedEnergy,
    ];

    /// A woven fabric (E1/E2 = 5, G12 = E1/100), a mild orthotropy, a
    /// weft-stiff one with a negative nu12, and one stiffer in shear than
    /// along its yarns (its E_n peaks on the bias).
    fn materials() -> Vec<Orthotropic> {
        [
            (5.0e6, 1.0e6, 5.0e4, 0.3),
            (2.0e6, 1.5e6, 6.0e5, 0.25),
            (1.0e6, 4.0e6, 2.0e4, -0.2),
            (1.0e6, 1.2e6, 3.0e6, 0.1),
        ]
        .iter()
        .map(|&(e1, e2, g, nu)| Orthotropic::new(e1, e2, g, nu, [1.0, 0.0, 0.0]).unwrap())
        .collect()
    }

    /// Strains on a grid of principal values (including compression) and
    /// orientations: every state occurs.
    fn strains() -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        for (e1, e2) in [
            (0.02, 0.01),
            (0.03, -0.02),
            (0.01, -0.03),
            (0.02, -0.005),
            (-0.01, -0.02),
            (0.004, -0.04),
        ] {
            for k in 0..7 {
                let a = 0.37 + k as f64 * std::f64::consts::PI / 7.0;
                let (s, c) = f64::sin_cos(a);
                // E = e1 n n + e2 m m, n = (c, s), m = (-s, c).
                out.push([
                    e1 * c * c + e2 * s * s,
                    e1 * s * s + e2 * c * c,
                    2.0 * (e1 - e2) * c * s,
                ]);
            }
        }
        out
    }

    /// The tangent is the derivative of the stress in every state, for
    /// both models and every material; the relaxed energy's stress is the
    /// derivative of its energy. Central differences, h = 1e-9 on strains
    /// of 1e-2 (strains within 1e-6 of a state boundary, where the stress
    /// is only continuous, are skipped).
    #[test]
    fn tangents_match_finite_differences() {
        let mut seen = std::collections::HashSet::new();
        for base in materials() {
            for model in MODELS {
                for prestress in [0.0, 2.0e3] {
                    if model == WrinklingModel::RelaxedEnergy && prestress != 0.0 {
                        continue;
                    }
                    let m = base.clone().with_wrinkling(model, prestress);
                    for e in strains() {
                        let state = m.wrinkle_state(e).unwrap();
                        let near_boundary = (0..3).any(|i| {
                            [-1e-6, 1e-6].iter().any(|d| {
                                let mut x = e;
                                x[i] += d;
                                m.wrinkle_state(x) != Some(state)
                            })
                        });
                        if near_boundary {
                            continue;
                        }
                        seen.insert((model as u8, state as u8));
                        let stress = |x: &[f64]| m.stress([x[0], x[1], x[2]]).to_vec();
                        let tangent = |x: &[f64]| m.tangent([x[0], x[1], x[2]]).concat();
                        let scale = m.matrix()[0][0].max(m.matrix()[1][1]);
                        let err = jacobian_error(stress, tangent, &e, 1e-9);
                        assert!(
                            err < 1e-6 * scale,
                            "{model:?} {state:?} {e:?} {:?}: tangent error {err:e}",
                            m.matrix()
                        );
                        if model == WrinklingModel::RelaxedEnergy {
                            let energy = |x: &[f64]| m.energy([x[0], x[1], x[2]]);
                            let err = gradient_error(energy, stress, &e, 1e-9);
                            assert!(err < 1e-6 * scale * 0.03, "{state:?} {e:?}: {err:e}");
                        }
                    }
                }
            }
        }
        assert_eq!(seen.len(), 6, "every state of both models: {seen:?}");
    }

    /// With `E1 = E2 = E`, `G12 = E / (2 (1 + nu))` the orthotropic
    /// material is the isotropic one to 1e-10 (relative to its largest
    /// value): energy, stress, tangent and state, without wrinkling and with
    /// either model, at every strain.
    #[test]
    fn isotropic_constants_give_the_isotropic_material() {
        let (y, nu) = (2.0e6, 0.3);
        let ortho = Orthotropic::new(y, y, y / (2.0 * (1.0 + nu)), nu, [1.0, 0.0, 0.0]).unwrap();
        let pairs: Vec<(Orthotropic, Box<dyn Material>)> = vec![
            (ortho.clone(), Box::new(SaintVenantKirchhoff::new(y, nu))),
            (
                ortho.clone().with_wrinkling(MODELS[0], 1.5e3),
                Box::new(Wrinkling::new(y, nu, 1.5e3, MODELS[0])),
            ),
            (
                ortho.clone().with_wrinkling(MODELS[1], 0.0),
                Box::new(Wrinkling::new(y, nu, 0.0, MODELS[1])),
            ),
        ];
        for (o, iso) in &pairs {
            for e in strains() {
                let (a, b) = (o.evaluate(e), iso.evaluate(e));
                let close = |u: f64, v: f64, scale: f64| (u - v).abs() <= 1e-10 * scale;
                let s_scale = b.stress.iter().fold(1.0, |m: f64, v| m.max(v.abs()));
                assert!(
                    close(a.energy, b.energy, b.energy.abs().max(1e-30)),
                    "{e:?}: {a:?} vs {b:?}"
                );
                for i in 0..3 {
                    assert!(
                        close(a.stress[i], b.stress[i], s_scale),
                        "{e:?}: {a:?} vs {b:?}"
                    );
                    for j in 0..3 {
                        assert!(
                            close(a.tangent[i][j], b.tangent[i][j], y),
                            "{e:?}: {a:?} vs {b:?}"
                        );
                    }
                }
                assert_eq!(o.wrinkle_state(e), iso.wrinkle_state(e), "{e:?}");
            }
        }
    }

    /// The relaxed energy is the least energy over the wrinkling strains
    /// `a m (x) m`, `a >= 0`: compared with a brute-force minimisation
    /// (every 1/4000 of a half turn of `m`, then the best `a` in closed
    /// form, then golden-section on the angle), to 1e-9 relative.
    #[test]
    fn relaxed_energy_is_the_least_energy_over_wrinkling_strains() {
        let mut wrinkled = 0;
        for base in materials() {
            let m = base
                .clone()
                .with_wrinkling(WrinklingModel::RelaxedEnergy, 0.0);
            let c = base.matrix();
            let elastic = |e: [f64; 3]| 0.5 * dot3(mat_vec(&c, e), e);
            // min over a >= 0 of W(E + a m m) at angle phi of m.
            let best_a = |e: [f64; 3], phi: f64| {
                let (s, co) = phi.sin_cos();
                let mm = [co * co, s * s, 2.0 * co * s];
                let a = (-dot3(mat_vec(&c, e), mm) / dot3(mat_vec(&c, mm), mm)).max(0.0);
                elastic([0, 1, 2].map(|i| e[i] + a * mm[i]))
            };
            for e in strains() {
                if m.wrinkle_state(e) != Some(WrinkleState::Wrinkled) {
                    continue;
                }
                wrinkled += 1;
                let n = 4000;
                let step = std::f64::consts::PI / n as f64;
                let (mut lo_phi, mut lo) = (0.0, f64::INFINITY);
                for i in 0..n {
                    let v = best_a(e, step * i as f64);
                    if v < lo {
                        (lo_phi, lo) = (step * i as f64, v);
                    }
                }
                let (mut a, mut b) = (lo_phi - step, lo_phi + step);
                let g = 0.5 * (5f64.sqrt() - 1.0);
                for _ in 0..80 {
                    let (x1, x2) = (b - g * (b - a), a + g * (b - a));
                    if best_a(e, x1) < best_a(e, x2) {
                        b = x2;
                    } else {
                        a = x1;
                    }
                }
                let brute = best_a(e, 0.5 * (a + b));
                let w = m.energy(e);
                assert!(
                    (w - brute).abs() <= 1e-9 * brute,
                    "{e:?}: {w} vs brute force {brute}"
                );
            }
        }
        assert!(wrinkled >= 20, "{wrinkled} wrinkled samples");
    }

    /// Roddeman's tension field: in a wrinkled state of the relaxed model
    /// the stress is uniaxial, `sigma n (x) n` with `sigma > 0`, and the
    /// strain that carries it elastically exceeds the mid-surface strain by
    /// a wrinkling strain `a m (x) m` across `n` (`a >= 0`): their
    /// difference has rank one, is positive, and annihilates `n`.
    #[test]
    fn the_tension_field_is_uniaxial_with_a_wrinkling_strain_across_it() {
        for base in materials() {
            let m = base
                .clone()
                .with_wrinkling(WrinklingModel::RelaxedEnergy, 0.0);
            for e in strains() {
                if m.wrinkle_state(e) != Some(WrinkleState::Wrinkled) {
                    continue;
                }
                let s = m.stress(e);
                let (s1, s2, n) = eigen(s[0], s[1], s[2]);
                assert!(
                    s1 > 0.0 && s2.abs() <= 1e-12 * s1,
                    "{e:?}: {s:?} is not uniaxial"
                );
                let carried = mat_vec(&base.a, s);
                let d = [0, 1, 2].map(|i| carried[i] - e[i]);
                // As a tensor: [[d0, d2/2], [d2/2, d1]].
                let (l1, l2, _) = eigen(d[0], d[1], 0.5 * d[2]);
                let size = e.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                assert!(
                    l1 > 0.0 && l2.abs() <= 1e-10 * size,
                    "{e:?}: wrinkling strain {d:?}"
                );
                let dn = [
                    d[0] * n[0] + 0.5 * d[2] * n[1],
                    0.5 * d[2] * n[0] + d[1] * n[1],
                ];
                assert!(dn[0].hypot(dn[1]) <= 1e-10 * size, "{e:?}: not across n");
            }
        }
    }

    /// Taut (both principal stresses >= 0) is the elastic law, and a
    /// strain with no stretch in any direction is slack, in both models.
    #[test]
    fn taut_is_elastic_and_compression_is_slack() {
        for base in materials() {
            for model in MODELS {
                let m = base.clone().with_wrinkling(model, 0.0);
                let e = [0.02, 0.01, 0.001];
                assert_eq!(m.wrinkle_state(e), Some(WrinkleState::Taut));
                assert_eq!(m.stress(e), base.stress(e));
                for e in [[-0.01, -0.02, 0.003], [-0.01, 0.0, 0.0]] {
                    assert_eq!(m.wrinkle_state(e), Some(WrinkleState::Slack), "{e:?}");
                    assert_eq!((m.stress(e), m.energy(e)), ([0.0; 3], 0.0));
                }
            }
        }
    }

    /// Bad constants are refused with their name and value.
    #[test]
    fn bad_constants_are_refused() {
        let err = |e1, e2, g, nu, d| Orthotropic::new(e1, e2, g, nu, d).unwrap_err().to_string();
        assert!(err(0.0, 1.0, 1.0, 0.3, [1.0, 0.0, 0.0]).contains("warp_modulus must be"));
        assert!(err(1.0, f64::NAN, 1.0, 0.3, [1.0, 0.0, 0.0]).contains("weft_modulus"));
        assert!(err(1.0, 1.0, -1.0, 0.3, [1.0, 0.0, 0.0]).contains("shear_modulus"));
        // nu12^2 < E1 / E2 = 0.25.
        assert!(err(1.0, 4.0, 1.0, 0.5, [1.0, 0.0, 0.0]).contains("poisson_ratio 0.5"));
        assert!(Orthotropic::new(1.0, 4.0, 1.0, 0.49, [1.0, 0.0, 0.0]).is_ok());
        assert!(err(1.0, 1.0, 1.0, 0.3, [0.0; 3]).contains("warp direction"));
    }
}
