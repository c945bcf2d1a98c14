//! `[[cavity]]`: a gas in the volume the fabric encloses (SPEC §6.7,
//! docs/theory.md §1.16): the tables, their checks and the cavities built
//! from them.

use super::check::Checker;
use super::locate::line_of;
use super::{BoxSpec, ScenarioError};
use crate::load::cavity::Cavity;
use crate::load::gas::{Gas, GasCavity, GasLaw, Inflator, InitialGas, Vent};
use crate::mesh::Mesh;
use serde::Deserialize;

/// Standard atmospheric pressure (Pa): ambient unless `ambient` is given.
pub const STANDARD_ATMOSPHERE: f64 = 101_325.0;

/// Air's specific gas constant (J/(kg K)): `R / M` with `M = 28.965
/// g/mol` (dry air) and `R = 8.314462 J/(mol K)`.
pub const AIR_GAS_CONSTANT: f64 = 287.05;

/// Room temperature (K), the gas's unless `temperature` is given.
pub const ROOM_TEMPERATURE: f64 = 293.15;

/// `[[cavity]]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CavitySpec {
    /// The mesh pieces (numbers as `Mesh::pieces` counts them: in order of
    /// their first element) whose triangles enclose the cavity. Default:
    /// every triangle of the mesh.
    pub pieces: Option<Vec<usize>>,
    /// Only the triangles whose nodes all lie in this box (m), of those
    /// pieces.
    pub within: Option<BoxSpec>,
    /// `"isothermal"` or `"adiabatic"`. Required.
    pub gas: GasLawSpec,
    /// The adiabatic exponent `gamma = c_p / c_v` (also the vents'), in
    /// `(1, 3]`. Default 1.4 (air); with an inflator, its `cp / cv`.
    pub gamma: Option<f64>,
    /// The gas's specific gas constant `R` (J/(kg K)), > 0. Default
    /// 287.05 (dry air); with an inflator, its `cp - cv`.
    pub gas_constant: Option<f64>,
    /// The initial absolute pressure (Pa), > 0. Default: ambient. Not with
    /// `mass`.
    pub pressure: Option<f64>,
    /// The initial mass of gas (kg), > 0, instead of `pressure`.
    pub mass: Option<f64>,
    /// The initial temperature (K), > 0. Default 293.15.
    pub temperature: Option<f64>,
    /// Ambient pressure (Pa, absolute), >= 0. Default 101325. The fabric
    /// feels `p - ambient`.
    pub ambient: Option<f64>,
    /// The apex of the divergence theorem's cones (m): with it, a surface
    /// that is not closed is closed by the cone from here over its open
    /// edges, whose nodes must be held, or held on a symmetry plane
    /// through it (docs/theory.md §1.16). Default: none (the surface must
    /// be closed).
    pub origin: Option<[f64; 3]>,
    /// A rigid volume that belongs to the cavity (m^3), >= 0: the chamber
    /// under a bulge test's disc. Default 0.
    pub chamber: Option<f64>,
    /// A gas source (dynamic analysis only).
    pub inflator: Option<InflatorSpec>,
    /// Orifices to ambient (`[[cavity.vent]]`, dynamic analysis only).
    #[serde(default)]
    pub vent: Vec<VentSpec>,
}

/// `gas`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GasLawSpec {
    /// `p V = m R T`, `T` fixed.
    Isothermal,
    /// `p V^gamma` constant.
    Adiabatic,
}

/// `inflator = { ... }`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InflatorSpec {
    /// `[[t, mdot], ...]` (s, kg/s): times increasing, rates >= 0; linear
    /// between points, the end values held outside them.
    pub mass_flow: Vec<[f64; 2]>,
    /// The incoming gas's temperature (K), > 0.
    pub temperature: f64,
    /// Its `c_p` (J/(kg K)), > `cv`.
    pub cp: f64,
    /// Its `c_v` (J/(kg K)), > 0.
    pub cv: f64,
}

/// `[[cavity.vent]]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VentSpec {
    /// Orifice area (m^2), > 0; all of a cavity's vents together smaller
    /// than its surface.
    pub area: f64,
    /// Discharge coefficient, in `(0, 1]`. Default 0.6 (a sharp-edged
    /// orifice).
    pub discharge: Option<f64>,
}

/// Every `[[cavity]]` built on `mesh` with the supports `fixed`; `statics`:
/// whether the analysis is static (no inflator, no vents then).
pub(super) fn build_cavities(
    c: &Checker,
    specs: &[CavitySpec],
    mesh: &Mesh,
    fixed: &[bool],
    statics: bool,
) -> Result<Vec<GasCavity>, ScenarioError> {
    let mut vents_before = 0;
    let mut cavities = Vec::with_capacity(specs.len());
    for (i, spec) in specs.iter().enumerate() {
        cavities.push(build_cavity(
            c,
            i,
            spec,
            mesh,
            fixed,
            statics,
            vents_before,
        )?);
        vents_before += spec.vent.len();
    }
    Ok(cavities)
}

/// `[[cavity]]` number `i`; `vents_before`: the `[[cavity.vent]]` tables
/// of the cavities before it (their headers are counted through the file).
fn build_cavity(
    c: &Checker,
    i: usize,
    spec: &CavitySpec,
    mesh: &Mesh,
    fixed: &[bool],
    statics: bool,
    vents_before: usize,
) -> Result<GasCavity, ScenarioError> {
    let t = "cavity";
    let ix = Some(i);
    let elements = select_elements(c, i, spec, mesh)?;
    if let Some(o) = spec.origin {
        c.finite(t, ix, "origin", &o)?;
    }
    let chamber = match spec.chamber {
        Some(v) if !(v.is_finite() && v >= 0.0) => {
            return Err(c.invalid(
                t,
                ix,
                "chamber",
                format!("must be a finite volume >= 0 (m^3), not {v}"),
            ));
        }
        Some(v) => v,
        None => 0.0,
    };
    let surface = Cavity::new(mesh, elements, spec.origin, chamber, fixed).map_err(|e| {
        // At `pieces`' line, or the table's header without it.
        let what = match &spec.pieces {
            Some(p) => format!("= {p:?} selects a surface that"),
            None => "(none given: every triangle of the mesh) selects a surface that".into(),
        };
        c.invalid(t, ix, "pieces", format!("{what} {e}"))
    })?;
    let ambient = match spec.ambient {
        Some(v) if !(v.is_finite() && v >= 0.0) => {
            return Err(c.invalid(
                t,
                ix,
                "ambient",
                format!("must be a finite pressure >= 0 (Pa), not {v}"),
            ));
        }
        Some(v) => v,
        None => STANDARD_ATMOSPHERE,
    };
    let inflator = spec
        .inflator
        .as_ref()
        .map(|inf| build_inflator(c, i, inf, statics))
        .transpose()?;
    let (gamma, gas_constant) = match &inflator {
        Some(inf) => {
            c.none_of(
                t,
                ix,
                &[
                    ("gamma", spec.gamma.is_some()),
                    ("gas_constant", spec.gas_constant.is_some()),
                ],
                "with an inflator (its cp and cv set gamma = cp / cv and R = cp - cv)",
            )?;
            (inf.cp / inf.cv, inf.cp - inf.cv)
        }
        None => {
            let gamma = spec.gamma.unwrap_or(1.4);
            if !(gamma.is_finite() && gamma > 1.0 && gamma <= 3.0) {
                return Err(c.invalid(t, ix, "gamma", format!("must lie in (1, 3], not {gamma}")));
            }
            let r = c.positive(
                t,
                ix,
                "gas_constant",
                spec.gas_constant.unwrap_or(AIR_GAS_CONSTANT),
            )?;
            (gamma, r)
        }
    };
    if spec.pressure.is_some() && spec.mass.is_some() {
        return Err(c.invalid(
            t,
            ix,
            "mass",
            "and `pressure` cannot both set the initial gas: give one".into(),
        ));
    }
    let pressure = match spec.pressure {
        Some(p) => c.positive(t, ix, "pressure", p)?,
        None if ambient > 0.0 || spec.mass.is_some() => ambient,
        None => {
            return Err(c.invalid(
                t,
                ix,
                "pressure",
                "is required with ambient = 0 (a cavity needs gas): give `pressure` or `mass`"
                    .into(),
            ));
        }
    };
    let mass = spec
        .mass
        .map(|m| c.positive(t, ix, "mass", m))
        .transpose()?;
    let temperature = c.positive(
        t,
        ix,
        "temperature",
        spec.temperature.unwrap_or(ROOM_TEMPERATURE),
    )?;
    let mut vents = Vec::with_capacity(spec.vent.len());
    let area = surface.area(&mesh.nodes.concat());
    let mut total = 0.0;
    for (k, v) in spec.vent.iter().enumerate() {
        let vent_error = |key: &str, message: String| ScenarioError::Invalid {
            file: c.file.to_path_buf(),
            line: line_of(c.source, "cavity.vent", Some(vents_before + k), key),
            key: format!("cavity[{i}].vent[{k}].{key}"),
            message,
        };
        if statics {
            return Err(vent_error(
                "area",
                "needs a dynamic analysis: a vent's outflow is a rate in time (a static analysis keeps the gas fixed)".into(),
            ));
        }
        if !(v.area.is_finite() && v.area > 0.0) {
            return Err(vent_error(
                "area",
                format!("must be a positive finite area (m^2), not {}", v.area),
            ));
        }
        total += v.area;
        if total >= area {
            return Err(vent_error(
                "area",
                format!(
                    "= {} m^2 makes the vents ({total} m^2 in all) larger than the bag: its surface is {area} m^2",
                    v.area
                ),
            ));
        }
        let discharge = v.discharge.unwrap_or(0.6);
        if !(discharge.is_finite() && discharge > 0.0 && discharge <= 1.0) {
            return Err(vent_error(
                "discharge",
                format!("must lie in (0, 1], not {discharge}"),
            ));
        }
        vents.push(Vent {
            area: v.area,
            discharge,
        });
    }
    let law = match spec.gas {
        GasLawSpec::Isothermal => GasLaw::Isothermal,
        GasLawSpec::Adiabatic => GasLaw::Adiabatic,
    };
    Ok(GasCavity {
        surface,
        gas: Gas {
            law,
            gamma,
            gas_constant,
            ambient,
            inflator,
            vents,
        },
        initial: InitialGas {
            pressure,
            mass,
            temperature,
        },
    })
}

/// The triangles of `[[cavity]]` number `i`: those of its pieces (all
/// without `pieces`) whose nodes lie in `within`, if given.
fn select_elements(
    c: &Checker,
    i: usize,
    spec: &CavitySpec,
    mesh: &Mesh,
) -> Result<Vec<usize>, ScenarioError> {
    let (piece, count) = mesh.pieces();
    let mut chosen: Vec<usize> = (0..mesh.element_count()).collect();
    if let Some(pieces) = &spec.pieces {
        if pieces.is_empty() {
            return Err(c.invalid(
                "cavity",
                Some(i),
                "pieces",
                "must list at least one piece".into(),
            ));
        }
        if let Some(p) = pieces.iter().find(|&&p| p >= count) {
            return Err(c.invalid(
                "cavity",
                Some(i),
                "pieces",
                format!(
                    "= {pieces:?} names piece {p}, but the mesh has {count} pieces (0 to {})",
                    count - 1
                ),
            ));
        }
        chosen.retain(|&e| pieces.contains(&piece[e]));
    }
    if let Some(b) = &spec.within {
        c.finite("cavity", Some(i), "within", &b.min)?;
        c.finite("cavity", Some(i), "within", &b.max)?;
        let tol = 1e-9 * mesh.diagonal();
        let inside =
            |x: &[f64; 3]| (0..3).all(|k| x[k] >= b.min[k] - tol && x[k] <= b.max[k] + tol);
        chosen.retain(|&e| mesh.element(e).iter().all(|&a| inside(&mesh.nodes[a])));
        if chosen.is_empty() {
            return Err(c.invalid("cavity", Some(i), "within", "selects no triangle".into()));
        }
    }
    Ok(chosen)
}

/// `inflator` of `[[cavity]]` number `i`, each value in its range.
fn build_inflator(
    c: &Checker,
    i: usize,
    spec: &InflatorSpec,
    statics: bool,
) -> Result<Inflator, ScenarioError> {
    let err = |message: String| c.invalid("cavity", Some(i), "inflator", message);
    if statics {
        return Err(err(
            "needs a dynamic analysis: its mass flow is a rate in time (a static analysis keeps the gas fixed)".into(),
        ));
    }
    if spec.mass_flow.is_empty() {
        return Err(err(
            "mass_flow must have at least one [t, kg/s] point".into()
        ));
    }
    for (k, &[t, rate]) in spec.mass_flow.iter().enumerate() {
        if !(t.is_finite() && rate.is_finite()) {
            return Err(err(format!(
                "mass_flow[{k}] = [{t}, {rate}] must be finite"
            )));
        }
        if rate < 0.0 {
            return Err(err(format!(
                "mass_flow[{k}] = [{t}, {rate}] is a negative mass flow (kg/s): an inflator only fills; let gas out through a [[cavity.vent]]"
            )));
        }
        if k > 0 && t <= spec.mass_flow[k - 1][0] {
            return Err(err(format!(
                "mass_flow[{k}] = [{t}, {rate}]: times must increase, and {t} s does not follow {} s",
                spec.mass_flow[k - 1][0]
            )));
        }
    }
    if !(spec.temperature.is_finite() && spec.temperature > 0.0) {
        return Err(err(format!(
            "temperature must be a positive finite temperature (K), not {}",
            spec.temperature
        )));
    }
    if !(spec.cv.is_finite() && spec.cv > 0.0 && spec.cp.is_finite() && spec.cp > spec.cv) {
        return Err(err(format!(
            "cp = {} and cv = {} must be finite with cp > cv > 0 (J/(kg K))",
            spec.cp, spec.cv
        )));
    }
    if spec.cp / spec.cv > 3.0 {
        return Err(err(format!(
            "cp / cv = {} must not exceed 3",
            spec.cp / spec.cv
        )));
    }
    Ok(Inflator {
        mass_flow: spec.mass_flow.clone(),
        temperature: spec.temperature,
        cp: spec.cp,
        cv: spec.cv,
    })
}
