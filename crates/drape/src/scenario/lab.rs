//! `[material.kes]` and `[material.fast]`: a fabric given in a textile
//! laboratory's units (README, "Scenario reference", `[material]`;
//! docs/fabrics.md, "Conversions, derived"), turned into the SI keys they
//! replace when the scenario is parsed, so that everything after sees one
//! material.
//!
//! KES-FB (Kawabata), with `F_m` = 500 gf/cm and 1 gf = 9.80665e-3 N:
//!
//! ```text
//! W   mg/cm²      × 0.01                        → ρ t  (kg/m²)      density = W' / t
//! T   mm          × 1e-3                        → t    (m)          thickness
//! B   gf·cm²/cm   × 9.80665e-5                  → B    (N·m)        bending_rigidity = { warp, weft }
//! G   gf/(cm·deg) × 0.980665 × 180/π = × 56.188 → G t  (N/m)        shear_modulus = G' / t
//! EMT %  (strain at F_m = 490.3325 N/m)  E t = F_m / (EMT/100) (N/m)  warp_modulus, weft_modulus = E t / t
//! 2HB gf·cm/cm    × 9.80665e-3 / 2              → HB   (N·m/m)      bending_hysteresis = { warp, weft }
//! ```
//!
//! FAST (SiroFAST), with 1 gf/cm = 0.980665 N/m:
//!
//! ```text
//! W    g/m²   × 1e-3                → ρ t (kg/m²)
//! T    mm     × 1e-3                → t (m)
//! B    µN·m   × 1e-6                → B (N·m)
//! G    N/m                          → G t;  or EB5 % (bias strain at 5 gf/cm): G t = 123 / EB5 N/m
//! E100 %  (strain at 100 gf/cm = 98.0665 N/m)   E t = 98.0665 / (E100/100) (N/m)
//! ```
//!
//! Each lab key replaces its SI key, and giving both is refused; a key
//! of neither kind leaves the quantity to the other (a KES set without
//! EMT takes `warp_modulus` and `weft_modulus`).

use super::check::Checker;
use super::locate::line_of;
use super::{MaterialModel, MaterialSpec, ScenarioError};
use serde::Deserialize;

/// One gram-force (N): standard gravity's weight of a gram.
pub const GRAM_FORCE: f64 = 9.80665e-3;
/// KES-FB1's maximum load `F_m` for EMT: 500 gf/cm (N/m).
pub const KES_EMT_LOAD: f64 = 500.0 * GRAM_FORCE / 0.01;
/// KES-FB2's bending hysteresis unit, gf·cm/cm, in N·m/m.
pub const KES_HYSTERESIS: f64 = GRAM_FORCE;
/// FAST-3's load for E100: 100 gf/cm (N/m).
pub const FAST_E100_LOAD: f64 = 100.0 * GRAM_FORCE / 0.01;
/// KES B: 1 gf·cm²/cm in N·m.
pub const KES_BENDING: f64 = GRAM_FORCE * 0.01;
/// KES G: 1 gf/(cm·deg) in N/m per radian.
pub const KES_SHEAR: f64 = GRAM_FORCE / 0.01 * 180.0 / std::f64::consts::PI;
/// FAST's shear rigidity from the bias extension: `G = 123 / EB5` N/m
/// (EB5 in %; docs/fabrics.md derives it from the bias strip).
pub const FAST_SHEAR_FROM_EB5: f64 = 123.0;

/// A value measured along the warp and along the weft.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WarpWeft {
    /// Along the warp.
    pub warp: f64,
    /// Along the weft.
    pub weft: f64,
}

/// `[material.kes]`: KES-FB values.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct KesSpec {
    /// Areal mass `W` (mg/cm²), > 0: replaces `density` (`W × 0.01 / t`).
    pub W: Option<f64>,
    /// Thickness `T` (mm), > 0: replaces `thickness`.
    pub T: Option<f64>,
    /// Bending rigidity `B` (gf·cm²/cm) `{ warp, weft }`, >= 0: replaces
    /// `bending_rigidity`.
    pub B: Option<WarpWeft>,
    /// Shear stiffness `G` (gf/(cm·deg)), > 0: replaces `shear_modulus`.
    pub G: Option<f64>,
    /// Tensile strain at 500 gf/cm `EMT` (%) `{ warp, weft }`, > 0:
    /// replaces `warp_modulus` and `weft_modulus`.
    pub EMT: Option<WarpWeft>,
    /// Bending hysteresis `2HB` (gf·cm/cm) `{ warp, weft }`, >= 0, the
    /// width of the moment–curvature loop: replaces `bending_hysteresis`
    /// (its half, `HB`).
    #[serde(rename = "2HB")]
    pub HB2: Option<WarpWeft>,
}

/// `[material.fast]`: FAST values.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct FastSpec {
    /// Areal mass `W` (g/m²), > 0: replaces `density`.
    pub W: Option<f64>,
    /// Thickness `T` (mm, FAST's T2), > 0: replaces `thickness`.
    pub T: Option<f64>,
    /// Bending rigidity `B` (µN·m) `{ warp, weft }`, >= 0: replaces
    /// `bending_rigidity`.
    pub B: Option<WarpWeft>,
    /// Shear rigidity `G` (N/m), > 0: replaces `shear_modulus`.
    pub G: Option<f64>,
    /// Bias extension at 5 gf/cm `EB5` (%), > 0: `G = 123 / EB5` N/m,
    /// replaces `shear_modulus` (not with `G`).
    pub EB5: Option<f64>,
    /// Tensile strain at 100 gf/cm `E100` (%) `{ warp, weft }`, > 0:
    /// replaces `warp_modulus` and `weft_modulus`.
    pub E100: Option<WarpWeft>,
}

/// The SI values a lab table gives (each `None` where it gives none).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LabValues {
    /// Mass per area (kg/m²).
    pub mass_per_area: Option<f64>,
    /// Thickness (m).
    pub thickness: Option<f64>,
    /// Bending rigidity warp, weft (N·m).
    pub bending: Option<[f64; 2]>,
    /// Shear rigidity `G t` (N/m).
    pub shear: Option<f64>,
    /// Tensile stiffness warp, weft `E t` (N/m).
    pub tensile: Option<[f64; 2]>,
    /// Bending hysteresis warp, weft `HB` (N m/m).
    pub hysteresis: Option<[f64; 2]>,
}

impl KesSpec {
    /// The SI values of the KES set (unchecked).
    pub fn values(&self) -> LabValues {
        LabValues {
            mass_per_area: self.W.map(|w| w * 0.01),
            thickness: self.T.map(|t| t * 1e-3),
            bending: self.B.map(|b| [b.warp * KES_BENDING, b.weft * KES_BENDING]),
            shear: self.G.map(|g| g * KES_SHEAR),
            tensile: self.EMT.map(|e| {
                [
                    KES_EMT_LOAD / (e.warp / 100.0),
                    KES_EMT_LOAD / (e.weft / 100.0),
                ]
            }),
            hysteresis: self
                .HB2
                .map(|h| [h.warp, h.weft].map(|v| 0.5 * v * KES_HYSTERESIS)),
        }
    }
}

impl FastSpec {
    /// The SI values of the FAST set (unchecked).
    pub fn values(&self) -> LabValues {
        LabValues {
            mass_per_area: self.W.map(|w| w * 1e-3),
            thickness: self.T.map(|t| t * 1e-3),
            bending: self.B.map(|b| [b.warp * 1e-6, b.weft * 1e-6]),
            shear: self.G.or(self.EB5.map(|eb5| FAST_SHEAR_FROM_EB5 / eb5)),
            tensile: self.E100.map(|e| {
                [
                    FAST_E100_LOAD / (e.warp / 100.0),
                    FAST_E100_LOAD / (e.weft / 100.0),
                ]
            }),
            hysteresis: None,
        }
    }
}

/// A lab key's name, unit and values as written (for messages), and the
/// SI key it replaces.
struct Written {
    key: &'static str,
    unit: &'static str,
    values: Vec<(&'static str, f64)>,
    replaces: &'static [&'static str],
    /// 0 is allowed (a bending rigidity), else > 0.
    zero: bool,
}

impl Written {
    fn new(
        key: &'static str,
        unit: &'static str,
        values: Vec<(&'static str, f64)>,
        replaces: &'static [&'static str],
        zero: bool,
    ) -> Self {
        Self {
            key,
            unit,
            values,
            replaces,
            zero,
        }
    }
}

/// `material`'s lab tables turned into its SI keys: the material as the
/// rest of the scenario reads it.
///
/// # Errors
/// Both tables; a lab key beside the SI key it replaces; a value that is
/// not finite and > 0 (>= 0 for `B`); tensile or shear keys without
/// `model = "orthotropic"`; `thickness` or `density` given neither way.
/// Each names the key, its value and its unit.
pub(super) fn resolve(c: &Checker, m: &MaterialSpec) -> Result<MaterialSpec, ScenarioError> {
    let mut out = m.clone();
    let (table, values, written) = match (&m.kes, &m.fast) {
        (Some(_), Some(_)) => {
            return Err(c.invalid(
                "material",
                None,
                "fast",
                "and material.kes both describe the fabric: give one of them".into(),
            ));
        }
        (Some(k), None) => ("kes", k.values(), kes_written(k)),
        (None, Some(f)) => {
            if f.G.is_some() && f.EB5.is_some() {
                return Err(lab_error(
                    c,
                    "fast",
                    "EB5",
                    format!(
                        "= {} % and G = {} N/m both give the shear rigidity: give one",
                        f.EB5.unwrap_or_default(),
                        f.G.unwrap_or_default()
                    ),
                ));
            }
            ("fast", f.values(), fast_written(f))
        }
        (None, None) => return required(c, out),
    };
    for w in &written {
        for (part, v) in &w.values {
            let ok = v.is_finite() && (*v > 0.0 || (w.zero && *v == 0.0));
            if !ok {
                let key = if part.is_empty() {
                    w.key.to_string()
                } else {
                    format!("{}.{part}", w.key)
                };
                let range = if w.zero { ">= 0" } else { "> 0" };
                return Err(lab_error(
                    c,
                    table,
                    &key,
                    format!("must be a finite number {range} ({}), not {v}", w.unit),
                ));
            }
        }
        let given = |k: &str| match k {
            "density" => m.density.is_some(),
            "thickness" => m.thickness.is_some(),
            "bending_rigidity" => m.bending_rigidity.is_some(),
            "shear_modulus" => m.shear_modulus.is_some(),
            "warp_modulus" => m.warp_modulus.is_some(),
            "weft_modulus" => m.weft_modulus.is_some(),
            "bending_hysteresis" => m.bending_hysteresis.is_some(),
            _ => false,
        };
        if let Some(si) = w.replaces.iter().find(|k| given(k)) {
            return Err(lab_error(
                c,
                table,
                w.key,
                format!(
                    "({}) replaces material.{si}, which is given too: give one of them",
                    w.unit
                ),
            ));
        }
        let in_plane = matches!(w.replaces.first(), Some(&"shear_modulus" | &"warp_modulus"));
        if in_plane && m.model != MaterialModel::Orthotropic {
            return Err(lab_error(
                c,
                table,
                w.key,
                "gives a woven fabric's in-plane stiffness: set model = \"orthotropic\" (its warp_modulus, weft_modulus and shear_modulus come from the lab's values)".into(),
            ));
        }
    }
    let thickness = values.thickness.or(m.thickness);
    out.thickness = thickness;
    if let Some(mass) = values.mass_per_area {
        let Some(t) = thickness.filter(|t| t.is_finite() && *t > 0.0) else {
            return Err(lab_error(
                c,
                table,
                "W",
                "needs the thickness to give the density (W / t): give T (mm) or material.thickness (m)".into(),
            ));
        };
        out.density = Some(mass / t);
    }
    let per_thickness = |v: f64| thickness.map(|t| v / t);
    if let Some([warp, weft]) = values.bending {
        let mut b = toml::Table::new();
        b.insert("warp".into(), toml::Value::Float(warp));
        b.insert("weft".into(), toml::Value::Float(weft));
        out.bending_rigidity = Some(toml::Value::Table(b));
    }
    if let Some([warp, weft]) = values.hysteresis {
        let mut h = toml::Table::new();
        h.insert("warp".into(), toml::Value::Float(warp));
        h.insert("weft".into(), toml::Value::Float(weft));
        out.bending_hysteresis = Some(toml::Value::Table(h));
    }
    if let Some(g) = values.shear {
        out.shear_modulus = per_thickness(g);
    }
    if let Some([warp, weft]) = values.tensile {
        out.warp_modulus = per_thickness(warp);
        out.weft_modulus = per_thickness(weft);
    }
    required(c, out)
}

/// `thickness` and `density` present, one way or the other.
fn required(c: &Checker, m: MaterialSpec) -> Result<MaterialSpec, ScenarioError> {
    for (key, v, lab) in [
        (
            "thickness",
            m.thickness,
            "material.kes.T (mm) or material.fast.T (mm)",
        ),
        (
            "density",
            m.density,
            "material.kes.W (mg/cm²) or material.fast.W (g/m²)",
        ),
    ] {
        if v.is_none() {
            return Err(c.invalid(
                "material",
                None,
                key,
                format!("is required (the SI key, or {lab})"),
            ));
        }
    }
    Ok(m)
}

/// An error of `material.<table>.<key>` (a dotted `key` like `EMT.warp`
/// is found on the line of its first part).
fn lab_error(c: &Checker, table: &str, key: &str, message: String) -> ScenarioError {
    let nested = format!("material.{table}");
    let first = key.split('.').next().unwrap_or(key);
    ScenarioError::Invalid {
        file: c.file.to_path_buf(),
        line: line_of(c.source, &nested, None, first)
            .or_else(|| line_of(c.source, "material", None, table)),
        key: format!("{nested}.{key}"),
        message,
    }
}

fn pair(v: Option<WarpWeft>) -> Vec<(&'static str, f64)> {
    v.map_or(Vec::new(), |v| vec![("warp", v.warp), ("weft", v.weft)])
}

fn one(v: Option<f64>) -> Vec<(&'static str, f64)> {
    v.map_or(Vec::new(), |v| vec![("", v)])
}

/// What a KES set gives, as written.
fn kes_written(k: &KesSpec) -> Vec<Written> {
    let w = Written::new;
    [
        w("W", "mg/cm²", one(k.W), &["density"][..], false),
        w("T", "mm", one(k.T), &["thickness"], false),
        w("B", "gf·cm²/cm", pair(k.B), &["bending_rigidity"], true),
        w("G", "gf/(cm·deg)", one(k.G), &["shear_modulus"], false),
        w(
            "2HB",
            "gf·cm/cm",
            pair(k.HB2),
            &["bending_hysteresis"],
            true,
        ),
        w(
            "EMT",
            "% strain at 500 gf/cm",
            pair(k.EMT),
            &["warp_modulus", "weft_modulus"],
            false,
        ),
    ]
    .into_iter()
    .filter(|w| !w.values.is_empty())
    .collect()
}

/// What a FAST set gives, as written.
fn fast_written(f: &FastSpec) -> Vec<Written> {
    let w = Written::new;
    [
        w("W", "g/m²", one(f.W), &["density"][..], false),
        w("T", "mm", one(f.T), &["thickness"], false),
        w("B", "µN·m", pair(f.B), &["bending_rigidity"], true),
        w("G", "N/m", one(f.G), &["shear_modulus"], false),
        w(
            "EB5",
            "% bias strain at 5 gf/cm",
            one(f.EB5),
            &["shear_modulus"],
            false,
        ),
        w(
            "E100",
            "% strain at 100 gf/cm",
            pair(f.E100),
            &["warp_modulus", "weft_modulus"],
            false,
        ),
    ]
    .into_iter()
    .filter(|w| !w.values.is_empty())
    .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The conversion factors from their definitions: 1 gf = 9.80665e-3 N,
    /// 1 cm = 0.01 m, 1 deg = π/180 rad.
    #[test]
    fn factors() {
        assert!((KES_BENDING - 9.80665e-5).abs() < 1e-20);
        assert!((KES_SHEAR - 56.18799).abs() < 1e-4);
        assert!((KES_EMT_LOAD - 490.3325).abs() < 1e-10);
        assert!((FAST_E100_LOAD - 98.0665).abs() < 1e-10);
    }
}
