//! `[material]`: the constitutive law (isotropic or orthotropic, with its
//! tension field), the section, the density, and the bending rigidity with
//! the warp direction they share.

use super::check::Checker;
use super::{MaterialModel, MaterialSpec, ScenarioError, WrinklingSpec};
use crate::bending::BendingRigidity;
use crate::element::membrane::Section;
use crate::material::{CompressionSoft, Material, Orthotropic, SaintVenantKirchhoff, Wrinkling};

/// `[material]`: the constitutive law, the section and the density (which
/// may be 0 in a static analysis). With a wrinkling model the prestress is
/// part of the stress that is projected, so the material carries it, and
/// the section none.
pub(super) fn build_material(
    c: &Checker,
    m: &MaterialSpec,
    is_static: bool,
) -> Result<(Box<dyn Material>, Section, f64), ScenarioError> {
    let t = "material";
    let elastic: Elastic = match m.model {
        MaterialModel::SaintVenantKirchhoff => {
            c.none_of(
                t,
                None,
                &[
                    ("warp_modulus", m.warp_modulus.is_some()),
                    ("weft_modulus", m.weft_modulus.is_some()),
                    ("shear_modulus", m.shear_modulus.is_some()),
                ],
                "to model = \"saint-venant-kirchhoff\" (an isotropic material has youngs_modulus; set model = \"orthotropic\" for a woven fabric)",
            )?;
            let why = "with model = \"saint-venant-kirchhoff\" (Pa)";
            let young = c.required(t, None, "youngs_modulus", &m.youngs_modulus, why)?;
            let young = c.positive(t, None, "youngs_modulus", young)?;
            if !(m.poisson_ratio.is_finite() && m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5) {
                return Err(c.invalid(
                    t,
                    None,
                    "poisson_ratio",
                    format!("must lie in (-1, 0.5), not {}", m.poisson_ratio),
                ));
            }
            Elastic::Isotropic(young)
        }
        MaterialModel::Orthotropic => {
            c.absent(
                t,
                None,
                "youngs_modulus",
                &m.youngs_modulus,
                "to model = \"orthotropic\" (give warp_modulus, weft_modulus and shear_modulus)",
            )?;
            let modulus = |key: &str, v: &Option<f64>| {
                let v = c.required(t, None, key, v, "with model = \"orthotropic\" (Pa)")?;
                c.positive(t, None, key, v)
            };
            let e1 = modulus("warp_modulus", &m.warp_modulus)?;
            let e2 = modulus("weft_modulus", &m.weft_modulus)?;
            let g12 = modulus("shear_modulus", &m.shear_modulus)?;
            let nu = m.poisson_ratio;
            if !(nu.is_finite() && nu * nu < e1 / e2) {
                return Err(c.invalid(
                    t,
                    None,
                    "poisson_ratio",
                    format!(
                        "must satisfy nu12^2 < warp_modulus / weft_modulus = {} (nu12 nu21 < 1, a positive definite material), not {nu}",
                        e1 / e2
                    ),
                ));
            }
            let material = Orthotropic::new(e1, e2, g12, nu, warp_direction(c, m)?)
                .map_err(|e| c.invalid(t, None, "model", e.to_string()))?;
            Elastic::Orthotropic(Box::new(material))
        }
    };
    let thickness = c.positive(t, None, "thickness", m.thickness())?;
    let density = if is_static && m.density() == 0.0 {
        0.0
    } else {
        c.positive(t, None, "density", m.density())?
    };
    c.finite(t, None, "prestress", &[m.prestress])?;
    if m.wrinkling == WrinklingSpec::RelaxedEnergy && m.prestress != 0.0 {
        return Err(c.invalid(
            t,
            None,
            "prestress",
            format!(
                "must be 0 with wrinkling = \"relaxed-energy\" (Pipkin's relaxed energy has no prestress), not {}",
                m.prestress
            ),
        ));
    }
    let ratio = compression_ratio(c, m)?;
    let slack = if is_static { 1e-6 } else { 0.0 };
    let (material, prestress): (Box<dyn Material>, f64) = match (elastic, m.wrinkling.model()) {
        (Elastic::Isotropic(young), None) => (
            Box::new(SaintVenantKirchhoff::new(young, m.poisson_ratio)),
            m.prestress,
        ),
        (Elastic::Isotropic(young), Some(model)) => {
            let w = Wrinkling::new(young, m.poisson_ratio, m.prestress, model);
            let w = if is_static {
                w.with_slack_tangent(slack)
            } else {
                w
            };
            let material: Box<dyn Material> = match ratio {
                Some(r) if r > 0.0 => Box::new(CompressionSoft::new(
                    Box::new(SaintVenantKirchhoff::new(young, m.poisson_ratio)),
                    Box::new(w),
                    r,
                )),
                _ => Box::new(w),
            };
            (material, 0.0)
        }
        (Elastic::Orthotropic(o), None) => (o, m.prestress),
        (Elastic::Orthotropic(o), Some(model)) => {
            let w = (*o)
                .clone()
                .with_wrinkling(model, m.prestress)
                .with_slack_tangent(slack);
            let material: Box<dyn Material> = match ratio {
                Some(r) if r > 0.0 => Box::new(CompressionSoft::new(o, Box::new(w), r)),
                _ => Box::new(w),
            };
            (material, 0.0)
        }
    };
    let section = Section {
        thickness,
        prestress,
    };
    Ok((material, section, density))
}

/// `[material] compression_ratio`: in [0, 1], and only with
/// `wrinkling = "relaxed-energy"` (the relaxed energy it blends with the
/// elastic one).
fn compression_ratio(c: &Checker, m: &MaterialSpec) -> Result<Option<f64>, ScenarioError> {
    let t = "material";
    let Some(r) = m.compression_ratio else {
        return Ok(None);
    };
    if m.wrinkling != WrinklingSpec::RelaxedEnergy {
        return Err(c.invalid(
            t,
            None,
            "compression_ratio",
            format!(
                "applies only with wrinkling = \"relaxed-energy\" (the fraction of the elastic compressive stiffness the relaxed energy keeps), not with wrinkling = \"{}\"; remove it or set wrinkling = \"relaxed-energy\"",
                m.wrinkling.name()
            ),
        ));
    }
    if !(r.is_finite() && (0.0..=1.0).contains(&r)) {
        return Err(c.invalid(
            t,
            None,
            "compression_ratio",
            format!(
                "must lie in [0, 1] (0: no compressive stiffness, 1: the elastic material), not {r}"
            ),
        ));
    }
    Ok(Some(r))
}

/// The elastic law of `[material] model`, before wrinkling.
enum Elastic {
    /// Saint-Venant–Kirchhoff with this Young's modulus (Pa).
    Isotropic(f64),
    /// The orthotropic material.
    Orthotropic(Box<Orthotropic>),
}

/// Whether the material has a warp: the orthotropic model, or a woven
/// fabric's `bending_rigidity = { warp, weft }` (judged on what was
/// written: `{ warp = 0, weft = 0 }` keeps its direction).
pub(super) fn has_axis(m: &MaterialSpec) -> bool {
    m.model == MaterialModel::Orthotropic
        || matches!(m.bending_rigidity, Some(toml::Value::Table(_)))
}

/// `[material] warp_direction`, default `[1, 0, 0]`: finite and not zero.
fn warp_direction(c: &Checker, m: &MaterialSpec) -> Result<[f64; 3], ScenarioError> {
    let t = "material";
    match m.warp_direction {
        None => Ok([1.0, 0.0, 0.0]),
        Some(d) => {
            c.finite(t, None, "warp_direction", &d)?;
            if d == [0.0; 3] {
                return Err(c.invalid(
                    t,
                    None,
                    "warp_direction",
                    "must not be the zero vector".into(),
                ));
            }
            Ok(d)
        }
    }
}

/// The largest `bending_rigidity` accepted (N m): a steel plate 40 cm
/// thick (E = 2e11 Pa: `E t^3 / (12 (1 - nu^2))` = 1.2e9 N m), ten times
/// over; a fabric's is 1e-6 to 1e-4.
pub const MAX_BENDING_RIGIDITY: f64 = 1.0e10;

/// Why a rigidity `b` above [`MAX_BENDING_RIGIDITY`] is refused.
fn too_stiff(b: f64) -> String {
    format!(
        "{b:e} N m is above {MAX_BENDING_RIGIDITY:e} N m (ten times a steel plate 40 cm thick), beyond which the bending forces overflow; is it in N m?"
    )
}

/// `[material] bending_rigidity` and `warp_direction` (README, "Scenario reference", `[material]`): `None`
/// for no bending (the default, or a rigidity of 0).
pub(super) fn build_bending(
    c: &Checker,
    m: &MaterialSpec,
) -> Result<Option<BendingRigidity>, ScenarioError> {
    let t = "material";
    let key = "bending_rigidity";
    // A rigidity (N m): a finite number >= 0, or `None` (with what to say).
    let number = |v: &toml::Value| -> Result<f64, String> {
        let b = match v {
            toml::Value::Float(f) => *f,
            toml::Value::Integer(i) => *i as f64,
            other => return Err(format!("must be a number (N m), not {other}")),
        };
        if !(b.is_finite() && b >= 0.0) {
            Err(format!("must be a finite number >= 0 (N m), not {b}"))
        } else if b > MAX_BENDING_RIGIDITY {
            Err(too_stiff(b))
        } else {
            Ok(b)
        }
    };
    let direction = warp_direction(c, m)?;
    let value = match &m.bending_rigidity {
        None => None,
        Some(toml::Value::String(s)) if s == "plate" => {
            let Some(young) = m
                .youngs_modulus
                .filter(|_| m.model == MaterialModel::SaintVenantKirchhoff)
            else {
                return Err(c.invalid(
                    t,
                    None,
                    key,
                    "= \"plate\" is E t^3 / (12 (1 - nu^2)) of an isotropic material; with model = \"orthotropic\" give { warp, weft } (N m)".into(),
                ));
            };
            let d = young * m.thickness().powi(3) / (12.0 * (1.0 - m.poisson_ratio.powi(2)));
            Some(BendingRigidity::Plate {
                rigidity: d,
                poisson_ratio: m.poisson_ratio,
            })
        }
        Some(toml::Value::String(s)) => {
            return Err(c.invalid(
                t,
                None,
                key,
                format!(
                    "must be a number (N m), a table {{ warp, weft }} or \"plate\", not \"{s}\""
                ),
            ));
        }
        Some(toml::Value::Table(table)) => {
            let [warp, weft] = warp_weft(c, (key, "N m"), table, number)?;
            (warp > 0.0 || weft > 0.0).then_some(BendingRigidity::Woven {
                warp,
                weft,
                direction,
            })
        }
        Some(v) => {
            let b = number(v).map_err(|why| {
                if let Some(b) = v.as_float().or(v.as_integer().map(|i| i as f64))
                    && b.is_finite()
                    && b > MAX_BENDING_RIGIDITY
                {
                    return c.invalid(t, None, key, why);
                }
                c.invalid(
                    t,
                    None,
                    key,
                    format!(
                        "must be a finite number >= 0 (N m), a table {{ warp, weft }} or \"plate\", not {v}"
                    ),
                )
            })?;
            (b > 0.0).then_some(BendingRigidity::Isotropic(b))
        }
    };
    // Judged on what was written: a woven `{ warp = 0, weft = 0 }` is no
    // bending, but its warp direction is still in place.
    if m.warp_direction.is_some() && !has_axis(m) {
        return Err(c.invalid(
            t,
            None,
            "warp_direction",
            "applies only to model = \"orthotropic\" and to a woven fabric's bending_rigidity = { warp, weft }".into(),
        ));
    }
    Ok(value)
}

/// `[material] bending_hysteresis`, `bending_hysteresis_rate` and
/// `bending_hysteresis_stiffness` (README, "Scenario reference",
/// `[material]`): `None` for none (the default, or `HB` 0). Needs a
/// bending rigidity (`bending`).
pub(super) fn build_hysteresis(
    c: &Checker,
    m: &MaterialSpec,
    bending: Option<&BendingRigidity>,
) -> Result<Option<crate::bending::hysteresis::Hysteresis>, ScenarioError> {
    use crate::bending::hysteresis::{DEFAULT_RATE, Hold, Hysteresis};
    let t = "material";
    let key = "bending_hysteresis";
    let positive = |name: &str, v: f64, unit: &str| {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(c.invalid(
                t,
                None,
                name,
                format!("must be a finite number > 0 ({unit}), not {v}"),
            ))
        }
    };
    let hold = match (m.bending_hysteresis_rate, m.bending_hysteresis_stiffness) {
        (Some(_), Some(_)) => {
            return Err(c.invalid(
                t,
                None,
                "bending_hysteresis_stiffness",
                "and bending_hysteresis_rate are two holds of the frictional moment (a stick spring, a creep): give one".into(),
            ));
        }
        (rate, None) => Hold::Creep {
            rate: positive(
                "bending_hysteresis_rate",
                rate.unwrap_or(DEFAULT_RATE),
                "1/(m s)",
            )?,
        },
        (None, Some(k)) => Hold::Stick {
            stiffness: positive("bending_hysteresis_stiffness", k, "N m")?,
        },
    };
    let Some(value) = &m.bending_hysteresis else {
        for (given, name) in [
            (m.bending_hysteresis_rate, "bending_hysteresis_rate"),
            (
                m.bending_hysteresis_stiffness,
                "bending_hysteresis_stiffness",
            ),
        ] {
            if given.is_some() {
                return Err(c.invalid(
                    t,
                    None,
                    name,
                    "applies only with a bending_hysteresis (N m/m)".into(),
                ));
            }
        }
        return Ok(None);
    };
    let number = |v: &toml::Value| -> Result<f64, String> {
        let h = match v {
            toml::Value::Float(f) => *f,
            toml::Value::Integer(i) => *i as f64,
            other => return Err(format!("must be a number (N m/m), not {other}")),
        };
        if h.is_finite() && h >= 0.0 {
            Ok(h)
        } else {
            Err(format!("must be a finite number >= 0 (N m/m), not {h}"))
        }
    };
    let moment = match value {
        toml::Value::Table(table) => warp_weft(c, (key, "N m/m"), table, number)?,
        v => {
            let h = number(v).map_err(|why| {
                c.invalid(
                    t,
                    None,
                    key,
                    format!("{why}; or give a table {{ warp, weft }}"),
                )
            })?;
            [h, h]
        }
    };
    if moment == [0.0, 0.0] {
        return Ok(None);
    }
    if bending.is_none() {
        return Err(c.invalid(
            t,
            None,
            key,
            "is the frictional moment of bending, and this fabric does not bend: give a bending_rigidity (N m) too".into(),
        ));
    }
    Ok(Some(Hysteresis { moment, hold }))
}

/// `[material] key = { warp, weft }` (in `unit`), each read by `number`:
/// `[warp, weft]`; another key, or one missing, refused by name.
fn warp_weft(
    c: &Checker,
    (key, unit): (&str, &str),
    table: &toml::Table,
    number: impl Fn(&toml::Value) -> Result<f64, String>,
) -> Result<[f64; 2], ScenarioError> {
    let t = "material";
    if let Some(k) = table
        .keys()
        .find(|k| !matches!(k.as_str(), "warp" | "weft"))
    {
        return Err(c.invalid_in(
            t,
            key,
            k,
            format!("is not a key of {key} (expected warp and weft, {unit})"),
        ));
    }
    let get = |name: &str| match table.get(name) {
        Some(v) => number(v).map_err(|why| c.invalid_in(t, key, name, why)),
        None => Err(c.invalid_in(
            t,
            key,
            name,
            format!(
                "is required in a woven fabric's {{ warp, weft }} {}",
                key.replace('_', " ")
            ),
        )),
    };
    Ok([get("warp")?, get("weft")?])
}
