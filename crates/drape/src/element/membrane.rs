//! The positional membrane kernel: strain energy, internal force and
//! Hessian of one element (docs/theory.md §1.2–1.3).
//!
//! Symbols (per quadrature point, weight `w = w_q det J0`):
//!
//! * `F = sum_a Y^a (x) grad phi^a` — 3x2 deformation gradient;
//! * `E = 1/2 (F^T F - I)`, Voigt `e = [E11, E22, 2 E12]`;
//! * `s = S(e) + sigma0 [1, 1, 0]` — material stress plus the isotropic
//!   prestress `sigma0`, whose energy is `sigma0 (E11 + E22)`;
//! * energy `U = sum_q t w (W(e) + sigma0 (E11 + E22))`;
//! * force `f^a = sum_q t w F S grad phi^a`;
//! * `B^a_i = d e / d Y^a_i = [g_1 F_i1, g_2 F_i2, g_1 F_i2 + g_2 F_i1]` with
//!   `g = grad phi^a`;
//! * Hessian `K^ab_ij = sum_q t w (B^a_i . D B^b_j + (grad phi^a . S grad phi^b) delta_ij)`.
//!
//! Forces and Hessians are checked against central differences of the
//! energy for every order (tests in `tests/derivatives.rs`).

use crate::material::Material;

/// Section properties shared by the elements of a membrane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// Thickness `t` (m).
    pub thickness: f64,
    /// Isotropic in-plane prestress `sigma0` (Pa), added to `S`.
    pub prestress: f64,
}

/// Deformation gradient `F` (3x2) from nodal positions and material gradients.
#[allow(non_snake_case)]
#[inline]
pub fn deformation_gradient(y: &[[f64; 3]], grad: &[[f64; 2]]) -> [[f64; 2]; 3] {
    // (Called with fixed-size arrays from the kernel, so the loop unrolls.)
    let mut F = [[0.0; 2]; 3];
    for (ya, ga) in y.iter().zip(grad) {
        for i in 0..3 {
            F[i][0] += ya[i] * ga[0];
            F[i][1] += ya[i] * ga[1];
        }
    }
    F
}

/// Green–Lagrange strain in Voigt form `[E11, E22, 2 E12]`.
#[allow(non_snake_case)]
#[inline]
pub fn green_lagrange(F: &[[f64; 2]; 3]) -> [f64; 3] {
    let c11 = F[0][0] * F[0][0] + F[1][0] * F[1][0] + F[2][0] * F[2][0];
    let c22 = F[0][1] * F[0][1] + F[1][1] * F[1][1] + F[2][1] * F[2][1];
    let c12 = F[0][0] * F[0][1] + F[1][0] * F[1][1] + F[2][0] * F[2][1];
    [0.5 * (c11 - 1.0), 0.5 * (c22 - 1.0), c12]
}

/// Strain energy of one element (J).
///
/// `y`: current positions of the element's nodes; `grad`, `weight`: the
/// element's slices of [`super::ElementGeometry`].
#[allow(non_snake_case)]
pub fn element_energy(
    material: &dyn Material,
    section: Section,
    y: &[[f64; 3]],
    grad: &[[f64; 2]],
    weight: &[f64],
) -> f64 {
    let n = y.len();
    let mut energy = 0.0;
    for (q, w) in weight.iter().enumerate() {
        let F = deformation_gradient(y, &grad[q * n..(q + 1) * n]);
        let e = green_lagrange(&F);
        energy += section.thickness * w * (material.energy(e) + section.prestress * (e[0] + e[1]));
    }
    energy
}

/// Strain energy (returned), internal force `f` (length `3n`, `f[3a + i]`)
/// and, if given, the Hessian `k` (`3n x 3n`, row-major, `k[(3a + i) 3n +
/// 3b + j]`) of one element. `f` and `k` are overwritten.
///
/// Without `k` only the stress is asked of the material
/// ([`Material::energy_stress`]): force-only evaluations (Newton's line
/// search and chord steps) skip the tangent.
pub fn element_force_hessian(
    material: &dyn Material,
    section: Section,
    y: &[[f64; 3]],
    grad: &[[f64; 2]],
    weight: &[f64],
    f: &mut [f64],
    mut k: Option<&mut [f64]>,
) -> f64 {
    let (energy, zero) =
        element_force_hessian_or_zero(material, section, y, grad, weight, f, k.as_deref_mut());
    if let Some(k) = k
        && zero
    {
        let m = 3 * y.len();
        k[..m * m].fill(0.0);
    }
    energy
}

/// [`element_force_hessian`], and whether the Hessian is zero (no
/// quadrature point with stress or tangent: a slack element in
/// dynamics), which the assembly then need not add; `k`'s contents are
/// then unspecified.
pub(crate) fn element_force_hessian_or_zero(
    material: &dyn Material,
    section: Section,
    y: &[[f64; 3]],
    grad: &[[f64; 2]],
    weight: &[f64],
    f: &mut [f64],
    k: Option<&mut [f64]>,
) -> (f64, bool) {
    // One instance per element order: with the node count known at compile
    // time the loops over nodes unroll (a T3 force and Hessian is then a
    // few hundred straight-line instructions).
    match y.len() {
        3 => force_hessian::<3>(material, section, y, grad, weight, f, k),
        6 => force_hessian::<6>(material, section, y, grad, weight, f, k),
        // Orders are 1 to 3 by construction of `Mesh`: 3, 6 or 10 nodes.
        _ => force_hessian::<10>(material, section, y, grad, weight, f, k),
    }
}

/// [`element_force_hessian`] for `N` nodes.
//
// About 120 lines, kept whole: the kernel of the module docs' formulas,
// spelled in their letters, sharing `F`, `E`, `S`, `C` and `B` between
// the force and the Hessian in the order the element's results are
// checked bit for bit.
#[allow(non_snake_case)]
#[inline]
fn force_hessian<const N: usize>(
    material: &dyn Material,
    section: Section,
    y: &[[f64; 3]],
    grad: &[[f64; 2]],
    weight: &[f64],
    f: &mut [f64],
    k: Option<&mut [f64]>,
) -> (f64, bool) {
    let y: &[[f64; 3]; N] = y.try_into().expect("N nodes");
    let f: &mut [f64] = &mut f[..3 * N];
    f.fill(0.0);
    let t = section.thickness;
    let mut energy = 0.0;
    // K[a][i][b][j] = k[(3a + i) 3N + 3b + j]: `k` itself seen with sizes
    // the compiler knows (no bounds checks in the products). One point (a
    // T3) writes every entry it does not skip, so nothing is zeroed first;
    // more points add up, into zeros.
    let mut K = k.map(|k| {
        &mut k[..9 * N * N]
            .as_chunks_mut::<3>()
            .0
            .as_chunks_mut::<N>()
            .0
            .as_chunks_mut::<3>()
            .0
            .as_chunks_mut::<N>()
            .0[0]
    });
    let accumulate = weight.len() > 1;
    if accumulate && let Some(K) = K.as_deref_mut() {
        *K = [[[[0.0; 3]; N]; 3]; N];
    }
    let mut zero = true;
    for (q, w) in weight.iter().enumerate() {
        let g: &[[f64; 2]; N] = grad[q * N..(q + 1) * N].try_into().expect("N gradients");
        let F = deformation_gradient(y, g);
        let e = green_lagrange(&F);
        let tw = t * w;
        let Some(K) = K.as_deref_mut() else {
            let (u, s) = material.energy_stress(e);
            let S = [s[0] + section.prestress, s[1] + section.prestress, s[2]];
            energy += tw * (u + section.prestress * (e[0] + e[1]));
            add_force(&F, S, g, tw, f);
            continue;
        };
        let r = material.evaluate(e);
        let S = [
            r.stress[0] + section.prestress,
            r.stress[1] + section.prestress,
            r.stress[2],
        ];
        energy += tw * (r.energy + section.prestress * (e[0] + e[1]));
        add_force(&F, S, g, tw, f);
        let D = r.tangent;
        // A point with neither stress nor tangent (a slack membrane in
        // dynamics) adds nothing to the Hessian.
        if S == [0.0; 3] && D == [[0.0; 3]; 3] {
            continue;
        }
        zero = false;
        // A symmetric tangent (taut, slack with a tangent, SVK) gives
        // symmetric blocks, `K_ba = K_ab^T`: only the blocks `a <= b` are
        // computed, 6 of 9 for a T3, each entry put in both places.
        let symmetric = D[0][1] == D[1][0] && D[0][2] == D[2][0] && D[1][2] == D[2][1];
        // B[a][i] = d e / d Y^a_i, and DB[a][i] = tw D B[a][i].
        let mut B = [[[0.0; 3]; 3]; N];
        let mut DB = [[[0.0; 3]; 3]; N];
        for a in 0..N {
            let ga = g[a];
            for i in 0..3 {
                let b = [
                    ga[0] * F[i][0],
                    ga[1] * F[i][1],
                    ga[0] * F[i][1] + ga[1] * F[i][0],
                ];
                B[a][i] = b;
                for r in 0..3 {
                    DB[a][i][r] = tw * (D[r][0] * b[0] + D[r][1] * b[1] + D[r][2] * b[2]);
                }
            }
        }
        for a in 0..N {
            let ga = g[a];
            // tw S grad phi^a, for the geometric term.
            let sa = [
                tw * (S[0] * ga[0] + S[2] * ga[1]),
                tw * (S[2] * ga[0] + S[1] * ga[1]),
            ];
            for i in 0..3 {
                let bai = B[a][i];
                for b in 0..N {
                    if symmetric && b < a {
                        // Added with block (b, a).
                        continue;
                    }
                    let gb = g[b];
                    for j in 0..3 {
                        let dbj = DB[b][j];
                        let mut v = bai[0] * dbj[0] + bai[1] * dbj[1] + bai[2] * dbj[2];
                        if j == i {
                            v += sa[0] * gb[0] + sa[1] * gb[1];
                        }
                        if accumulate {
                            K[a][i][b][j] += v;
                            if symmetric && b > a {
                                K[b][j][a][i] += v;
                            }
                        } else {
                            K[a][i][b][j] = v;
                            if symmetric && b > a {
                                K[b][j][a][i] = v;
                            }
                        }
                    }
                }
            }
        }
    }
    (energy, zero)
}

/// `f^a += tw F S grad phi^a` for every node `a`.
#[allow(non_snake_case)]
#[inline]
fn add_force<const N: usize>(
    F: &[[f64; 2]; 3],
    S: [f64; 3],
    g: &[[f64; 2]; N],
    tw: f64,
    f: &mut [f64],
) {
    for a in 0..N {
        let ga = g[a];
        // (F S) grad phi^a with S = [[S0, S2], [S2, S1]].
        let sg = [
            tw * (S[0] * ga[0] + S[2] * ga[1]),
            tw * (S[2] * ga[0] + S[1] * ga[1]),
        ];
        for i in 0..3 {
            f[3 * a + i] += F[i][0] * sg[0] + F[i][1] * sg[1];
        }
    }
}

/// Mean second Piola–Kirchhoff stress `[S11, S22, S12]` over the element's
/// quadrature points (including prestress) and mean Green–Lagrange strain
/// `[E11, E22, 2 E12]`, in the element's local frame (`e1` along `G_1`, the
/// direction from its first to its second vertex).
pub fn element_stress(
    material: &dyn Material,
    section: Section,
    y: &[[f64; 3]],
    grad: &[[f64; 2]],
    weight: &[f64],
) -> ([f64; 3], [f64; 3]) {
    mean_stress(section, y, grad, weight, |e| material.stress(e))
}

/// [`element_stress`] and the element's wrinkling state
/// ([`Material::wrinkle_state`] of the mean strain): for a one-point
/// rule (linear triangles) by one material evaluation
/// ([`Material::stress_state`]), else by the state of the mean strain.
pub fn element_stress_state(
    material: &dyn Material,
    section: Section,
    y: &[[f64; 3]],
    grad: &[[f64; 2]],
    weight: &[f64],
) -> ([f64; 3], [f64; 3], Option<crate::material::WrinkleState>) {
    if weight.len() == 1 {
        let mut state = None;
        let (s, e) = mean_stress(section, y, grad, weight, |e| {
            let (s, st) = material.stress_state(e);
            state = st;
            s
        });
        return (s, e, state);
    }
    let (s, e) = element_stress(material, section, y, grad, weight);
    (s, e, material.wrinkle_state(e))
}

/// The means of [`element_stress`], with `stress` the material's stress
/// at a quadrature point's strain.
#[allow(non_snake_case)]
fn mean_stress(
    section: Section,
    y: &[[f64; 3]],
    grad: &[[f64; 2]],
    weight: &[f64],
    mut stress: impl FnMut([f64; 3]) -> [f64; 3],
) -> ([f64; 3], [f64; 3]) {
    let n = y.len();
    let mut s = [0.0; 3];
    let mut e = [0.0; 3];
    let area: f64 = weight.iter().sum();
    for (q, w) in weight.iter().enumerate() {
        let F = deformation_gradient(y, &grad[q * n..(q + 1) * n]);
        let eq = green_lagrange(&F);
        let sq = stress(eq);
        s[0] += w * (sq[0] + section.prestress);
        s[1] += w * (sq[1] + section.prestress);
        s[2] += w * sq[2];
        for i in 0..3 {
            e[i] += w * eq[i];
        }
    }
    (s.map(|v| v / area), e.map(|v| v / area))
}

/// Principal values `(s1, s2)`, `s1 >= s2`, of the symmetric 2x2 tensor
/// `[[s0, s2], [s2, s1]]` given as `[s0, s1, s2]`.
pub fn principal_values(s: [f64; 3]) -> (f64, f64) {
    let mean = 0.5 * (s[0] + s[1]);
    let radius = (0.25 * (s[0] - s[1]).powi(2) + s[2] * s[2]).sqrt();
    (mean + radius, mean - radius)
}
