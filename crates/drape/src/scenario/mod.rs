//! The scenario file (TOML): its keys, their defaults and ranges, and the
//! construction of a [`Setup`](crate::setup::Setup) (model, schedule, monitors) from it.
//!
//! Every key is documented on its field (here, in `obstacle` for the
//! `[[obstacle]]` shapes and in `contact` for the `[contact]` methods); the
//! README's scenario reference is checked against the parser both ways by
//! a test (every accepted key documented, every documented key accepted).
//! Where a key means one of a few choices it is an enum: the mesh's
//! `shape`, the material's `model` and `wrinkling` (`"none"`,
//! `"stress-projection"`, `"relaxed-energy"`), the obstacle's `shape`, the
//! contact's `method`, the load's `kind`, the analysis' `kind` and `mass`,
//! the solver's `linear`. An obstacle's and the contact's keys depend on
//! their tag: those tables are read apart, each into the struct of its
//! choice (`tagged` says why serde's tagged enums are not used).
//!
//! Unknown keys, wrong types, out-of-range values and missing required keys
//! are errors that name the file, the key and, where it can be found, the
//! line. `build` checks the values section by section (with `check`;
//! `locate` finds their lines).

mod analysis;
mod build;
mod cavity;
mod check;
mod contact;
mod lab;
mod locate;
mod material;
mod obstacle;
mod specimen;
mod tagged;

pub use build::{absolute_paths, read_mesh_file};
pub use cavity::{CavitySpec, GasLawSpec, InflatorSpec, VentSpec};
pub use contact::{ContactMethodName, ContactSpec, LagrangeSpec, PenaltySpec};
pub use lab::{FastSpec, KesSpec, LabValues, WarpWeft};
pub use obstacle::{
    BoxObstacleSpec, CylinderObstacleSpec, MeshObstacleSpec, ObstacleShape, ObstacleSpec,
    PlaneObstacleSpec, SphereObstacleSpec,
};
pub use specimen::{Faces, SpecimenPlan, SpecimenSpec, TestSpec};

use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A scenario file that cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("{file}: cannot read: {error}")]
    Io {
        /// The scenario file.
        file: PathBuf,
        /// The I/O error.
        error: std::io::Error,
    },
    /// TOML syntax, unknown key, wrong type or missing key.
    #[error("{file}{}: {message}", line.map(|l| format!(", line {l}")).unwrap_or_default())]
    Parse {
        /// The scenario file.
        file: PathBuf,
        /// 1-based line, when known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// A value out of range or inconsistent with others.
    #[error("{file}{}: `{key}` {message}", line.map(|l| format!(", line {l}")).unwrap_or_default())]
    Invalid {
        /// The scenario file.
        file: PathBuf,
        /// 1-based line, when known.
        line: Option<usize>,
        /// Dotted key path, e.g. `material.thickness` or `load[2].ramp`.
        key: String,
        /// What is wrong, with the value.
        message: String,
    },
    /// A mesh the model cannot be built on (its elements, the lumped
    /// mass of a node).
    #[error("{file}: mesh: {error}")]
    Mesh {
        /// The scenario file.
        file: PathBuf,
        /// What is wrong with the mesh.
        error: crate::model::ModelError,
    },
}

/// A whole scenario file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Free text shown in the summary. Default: the file stem.
    pub title: Option<String>,
    /// The membrane's reference mesh.
    pub mesh: MeshSpec,
    /// Material and section.
    pub material: MaterialSpec,
    /// Loads (`[[load]]`), any number.
    #[serde(default, rename = "load")]
    pub loads: Vec<LoadSpec>,
    /// Supports (`[[fix]]`), any number.
    #[serde(default, rename = "fix")]
    pub fixes: Vec<FixSpec>,
    /// Rigid obstacles (`[[obstacle]]`), any number. Each table is read on
    /// its own, dispatched on its `shape` (see [`Scenario::parse`]).
    #[serde(default, rename = "obstacle", deserialize_with = "tagged::read_apart")]
    pub obstacles: Vec<ObstacleSpec>,
    /// Contact enforcement; required when there are obstacles. Read on its
    /// own, dispatched on its `method` (see [`Scenario::parse`]).
    #[serde(default, deserialize_with = "tagged::read_apart")]
    pub contact: Option<ContactSpec>,
    /// Dynamic or static analysis.
    #[serde(default)]
    pub analysis: AnalysisSpec,
    /// Time integration and schedule (required for dynamic analysis).
    pub time: Option<TimeSpec>,
    /// Newton settings.
    #[serde(default)]
    pub solver: SolverSpec,
    /// Output settings.
    #[serde(default)]
    pub output: OutputSpec,
    /// Nodes whose positions go into the history (`[[monitor]]`).
    #[serde(default, rename = "monitor")]
    pub monitors: Vec<MonitorSpec>,
    /// How the specimens of a drape test differ (`drape test`); a run
    /// ignores it.
    pub test: Option<TestSpec>,
    /// This scenario is a specimen of a drape test, so perturbed.
    pub specimen: Option<SpecimenSpec>,
    /// Refinement during the run (`[refine]`, none without it): the
    /// multilevel settle.
    pub refine: Option<RefineSpec>,
    /// Gas in the volumes the fabric encloses (`[[cavity]]`), any number.
    #[serde(default, rename = "cavity")]
    pub cavities: Vec<CavitySpec>,
}

/// `[mesh]`: which mesh and of which order.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// `"rectangle"`, `"disc"`, `"sphere"` or `"file"`. Required.
    pub shape: MeshShape,
    /// Rectangle: width (x) and height (y), m, > 0; every node within
    /// 1e6 m of the origin.
    pub size: Option<[f64; 2]>,
    /// Rectangle: squares along x and y (each cut in two triangles), >= 1.
    pub divisions: Option<[usize; 2]>,
    /// Rectangle: diagonal pattern `"right"` (default), `"left"`, `"alternate"`.
    pub pattern: Option<crate::mesh::generate::Pattern>,
    /// Rectangle and disc: centre; the mesh lies in the plane `z = center[2]`. Default `[0, 0, 0]`;
    /// finite, each coordinate within ±1e6 m.
    pub center: Option<[f64; 3]>,
    /// Lagrange order of the triangles: 1 (default), 2 or 3. For a file, the
    /// file's order is used and this key, if given, must agree.
    pub order: Option<usize>,
    /// Disc and sphere: radius, m, > 0; every node within 1e6 m of the origin.
    pub radius: Option<f64>,
    /// Disc: number of rings, >= 1.
    pub rings: Option<usize>,
    /// Sphere: how many times the icosahedron's edges are halved, 0–6
    /// (`20 4^s` triangles). A sphere is closed: a balloon's `[[cavity]]`.
    pub subdivisions: Option<usize>,
    /// File: path of a Gmsh `.msh` (2.2 or 4.1, ASCII or binary) or `.obj`,
    /// relative to the scenario file's folder.
    pub path: Option<PathBuf>,
    /// Where curved elements (order 2 and 3) measure their membrane strain:
    /// `"auto"` (default: `"sub-triangles"` with bending, `"curved"`
    /// without), `"curved"` or `"sub-triangles"`. No effect on order 1.
    #[serde(default)]
    pub membrane: crate::element::geometry::MembraneIntegration,
}

/// Mesh shapes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MeshShape {
    /// Structured rectangle.
    Rectangle,
    /// Structured disc.
    Disc,
    /// Closed sphere (a subdivided icosahedron, nodes on the sphere).
    Sphere,
    /// Read from a file.
    File,
}

/// `[material]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// `"saint-venant-kirchhoff"` (isotropic, the default) or
    /// `"orthotropic"` (a woven fabric, docs/theory.md §1.11).
    #[serde(default)]
    pub model: MaterialModel,
    /// Young's modulus `E` (Pa), > 0, <= 1e15. Required by the isotropic model, not
    /// allowed with the orthotropic one.
    #[serde(default)]
    pub youngs_modulus: Option<f64>,
    /// Orthotropic: the warp modulus `E1` (Pa, along the warp), > 0, <= 1e15.
    #[serde(default)]
    pub warp_modulus: Option<f64>,
    /// Orthotropic: the weft modulus `E2` (Pa, in-plane normal to the
    /// warp), > 0, <= 1e15.
    #[serde(default)]
    pub weft_modulus: Option<f64>,
    /// Orthotropic: the in-plane shear modulus `G12` (Pa), > 0, <= 1e15.
    #[serde(default)]
    pub shear_modulus: Option<f64>,
    /// Poisson's ratio: isotropic `nu` in (-1, 0.5); orthotropic `nu12`
    /// (weft contraction per unit warp stretch, `nu21 = nu12 E2 / E1`)
    /// with `nu12^2 < E1 / E2`. Required.
    pub poisson_ratio: f64,
    /// Density `rho` (kg/m^3), > 0 (>= 0 in static analysis). Required,
    /// unless a lab table gives `W`; after parsing, always given.
    #[serde(default)]
    pub density: Option<f64>,
    /// Thickness `t` (m), > 0. Required, unless a lab table gives `T`;
    /// after parsing, always given.
    #[serde(default)]
    pub thickness: Option<f64>,
    /// Wrinkling model: `"none"` (default), `"stress-projection"` or
    /// `"relaxed-energy"`.
    #[serde(default)]
    pub wrinkling: WrinklingSpec,
    /// Isotropic in-plane prestress added to `S` (Pa), finite, default 0;
    /// with `"stress-projection"` added before the projection; must be 0
    /// with `"relaxed-energy"`.
    #[serde(default)]
    pub prestress: f64,
    /// With `wrinkling = "relaxed-energy"`: the fraction `r` of the elastic
    /// compressive stiffness the membrane keeps where it is wrinkled or
    /// slack (`W = r W_el + (1 - r) W_relaxed`, docs/theory.md §1.4), in
    /// [0, 1], default 0 (Pipkin's relaxed energy). Not allowed with the
    /// other wrinkling models.
    #[serde(default)]
    pub compression_ratio: Option<f64>,
    /// Bending rigidity (docs/theory.md §1.10): a number `B` (N m, >= 0), a table
    /// `{ warp, weft }` (N m each) or `"plate"`; default 0, a pure
    /// membrane. Read by hand for messages naming the inner key.
    #[serde(default)]
    pub bending_rigidity: Option<toml::Value>,
    /// Bending hysteresis `HB` (`crate::bending::hysteresis`): a number
    /// (N m/m, >= 0) or a table `{ warp, weft }`; default none. Needs a
    /// bending rigidity. Read by hand for messages naming the inner key.
    #[serde(default)]
    pub bending_hysteresis: Option<toml::Value>,
    /// The curvature rate below which bending hysteresis lets the
    /// curvature creep (1/(m s), > 0), default
    /// [`crate::bending::hysteresis::DEFAULT_RATE`].
    #[serde(default)]
    pub bending_hysteresis_rate: Option<f64>,
    /// The bending stiffness of bending hysteresis's stick spring (N m, a
    /// number above 0), along the direction of the larger `HB`: a Jenkins element,
    /// whose curvature does not creep (`crate::bending::hysteresis`, "The
    /// stick"); instead of `bending_hysteresis_rate`. Default none.
    #[serde(default)]
    pub bending_hysteresis_stiffness: Option<f64>,
    /// The warp direction in the initial configuration (projected on each
    /// element's plane), default `[1, 0, 0]`: the axes of the orthotropic
    /// model and of a woven `bending_rigidity`.
    #[serde(default)]
    pub warp_direction: Option<[f64; 3]>,
    /// `[material.kes]`: the fabric's KES-FB values, in KES units, each
    /// replacing an SI key (`lab`).
    #[serde(default)]
    pub kes: Option<KesSpec>,
    /// `[material.fast]`: the fabric's FAST values, in FAST units, each
    /// replacing an SI key (`lab`).
    #[serde(default)]
    pub fast: Option<FastSpec>,
}

impl MaterialSpec {
    /// `thickness` (m): given after parsing (NaN, which every check
    /// refuses, in a struct made by hand without it).
    pub fn thickness(&self) -> f64 {
        self.thickness.unwrap_or(f64::NAN)
    }

    /// `density` (kg/m³): given after parsing (NaN, which every check
    /// refuses, in a struct made by hand without it).
    pub fn density(&self) -> f64 {
        self.density.unwrap_or(f64::NAN)
    }
}

/// The values of `[material] model`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MaterialModel {
    /// Saint Venant–Kirchhoff: `S = lambda tr(E) I + 2 mu E`.
    #[default]
    SaintVenantKirchhoff,
    /// Orthotropic Saint Venant–Kirchhoff in the warp/weft axes.
    Orthotropic,
}

/// The values of `[material] wrinkling`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WrinklingSpec {
    /// No tension-field model: the membrane carries compression.
    #[default]
    None,
    /// Negative principal stresses set to zero.
    StressProjection,
    /// Pipkin's relaxed strain energy.
    RelaxedEnergy,
}

impl WrinklingSpec {
    /// The material's wrinkling model, `None` for `"none"`.
    pub fn model(self) -> Option<crate::material::WrinklingModel> {
        use crate::material::WrinklingModel;
        match self {
            Self::None => None,
            Self::StressProjection => Some(WrinklingModel::StressProjection),
            Self::RelaxedEnergy => Some(WrinklingModel::RelaxedEnergy),
        }
    }

    /// The value as the scenario spells it.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::StressProjection => "stress-projection",
            Self::RelaxedEnergy => "relaxed-energy",
        }
    }
}

/// Node selection shared by `[[fix]]` and nodal loads. With several
/// selectors, a node must satisfy all of them.
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Lower corner (m).
    pub min: [f64; 3],
    /// Upper corner (m).
    pub max: [f64; 3],
}

/// `[[load]]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// `"surface"`, `"gravity"`, `"pressure"` or `"nodal"`. Required.
    pub kind: LoadKindSpec,
    /// Surface: force per unit initial area (N/m^2); gravity: the
    /// acceleration (m/s^2); nodal: force per selected node (N).
    pub force: Option<[f64; 3]>,
    /// Gravity: the acceleration (m/s^2), an alias of `force`.
    pub acceleration: Option<[f64; 3]>,
    /// Pressure (Pa), along the current normal (right-hand rule over the
    /// node order: +z for a generated flat mesh).
    pub value: Option<f64>,
    /// Rise time (s), > 0: the load grows linearly from 0 at `t = 0`.
    pub ramp: Option<f64>,
    /// Nodal: the node nearest this initial position.
    pub at: Option<[f64; 3]>,
    /// Nodal: every node inside this box.
    pub within: Option<BoxSpec>,
    /// Nodal: every node on the mesh's free edge.
    pub boundary: Option<bool>,
}

/// Load kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LoadKindSpec {
    /// Dead force per initial area.
    Surface,
    /// Weight `rho t g`.
    Gravity,
    /// Follower pressure.
    Pressure,
    /// Nodal forces.
    Nodal,
}

/// `[[fix]]`: fixed position components.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FixSpec {
    /// The node nearest this initial position (m).
    pub at: Option<[f64; 3]>,
    /// Every node inside this box (m).
    pub within: Option<BoxSpec>,
    /// Every node on the mesh's free edge (combine with `within` to take part of it).
    pub boundary: Option<bool>,
    /// Which components are fixed: any of `"x"`, `"y"`, `"z"`. Default: all three.
    pub components: Option<Vec<Component>>,
    /// A clamp (SPEC §6.6): the held nodes also hold the fabric's slope
    /// across the boundary between them and the free nodes, so that a
    /// cantilever's free length starts at the last held node. Needs all
    /// three components. Default false.
    pub clamp: Option<bool>,
}

/// A component of a node's position, as `[[fix]] components` names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Component {
    /// `"x"`.
    X,
    /// `"y"`.
    Y,
    /// `"z"`.
    Z,
}

impl Component {
    /// Its index in a node's position `[x, y, z]`.
    pub fn index(self) -> usize {
        match self {
            Component::X => 0,
            Component::Y => 1,
            Component::Z => 2,
        }
    }
}

/// `[analysis]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnalysisSpec {
    /// `"dynamic"` (default) or `"static"`.
    #[serde(default = "default_kind")]
    pub kind: AnalysisKind,
    /// Static: number of equal load increments (>= 1, default 10).
    pub steps: Option<usize>,
    /// Mass matrix: `"consistent"` (default) or `"lumped"`.
    #[serde(default = "default_mass")]
    pub mass: crate::model::MassKind,
}

impl Default for AnalysisSpec {
    fn default() -> Self {
        Self {
            kind: AnalysisKind::Dynamic,
            steps: None,
            mass: crate::model::MassKind::Consistent,
        }
    }
}

fn default_kind() -> AnalysisKind {
    AnalysisKind::Dynamic
}
fn default_mass() -> crate::model::MassKind {
    crate::model::MassKind::Consistent
}

/// Analysis kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AnalysisKind {
    /// Newmark-beta dynamics.
    Dynamic,
    /// Load stepping to equilibrium.
    Static,
}

/// `[time]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// Newmark `beta` (> 0). Default 1.0 (with `gamma = 1.5`: strongly
    /// damped, recommended for contact; `0.25, 0.5` is the trapezoidal rule).
    #[serde(default = "default_beta")]
    pub beta: f64,
    /// Newmark `gamma` (>= 0.5). Default 1.5.
    #[serde(default = "default_gamma")]
    pub gamma: f64,
    /// The schedule: segments of `steps` steps of size `dt` (s). Required.
    pub segments: Option<Vec<SegmentSpec>>,
    /// Adaptive steps: `dt` grows after easy steps (few Newton iterations,
    /// up to `dt_max`) and shrinks after hard ones; each segment still ends
    /// at its own end time (`steps` x `dt`) and no step crosses it. Default
    /// false: the segments' fixed steps. Dynamic analysis only.
    pub adaptive: Option<bool>,
    /// Adaptive steps: the largest step (s), >= every segment's `dt`.
    /// Default: 10 x each segment's `dt`. Only with `adaptive = true`.
    pub dt_max: Option<f64>,
    /// Rest criterion, optional: the run ends (status "completed", a
    /// message saying "at rest") once every node's speed has stayed below
    /// `rest.speed` for 10 consecutive steps, not counting steps before
    /// `rest.after`. Dynamic analysis only.
    pub rest: Option<RestSpec>,
}

/// `[time] rest = { speed, after }`: when a dynamic run is at rest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestSpec {
    /// Every node slower than this (m/s), > 0 and finite. Required.
    pub speed: f64,
    /// Steps ending before this time (s) do not count, >= 0. Default 0.
    pub after: f64,
}

/// [`RestSpec`]'s table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RestTable {
    speed: f64,
    #[serde(default)]
    after: f64,
}

impl<'de> Deserialize<'de> for RestSpec {
    /// The table, or an error that shows how to write it (`rest = 1e-4`
    /// was refused as "expected struct RestSpec").
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Table;
        impl<'de> serde::de::Visitor<'de> for Table {
            type Value = RestSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a table { speed = <m/s>, after = <s> }, e.g. rest = { speed = 1.0e-4, after = 0.2 }",
                )
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<RestSpec, A::Error> {
                let t = RestTable::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(RestSpec {
                    speed: t.speed,
                    after: t.after,
                })
            }
        }
        d.deserialize_map(Table)
    }
}

fn default_beta() -> f64 {
    1.0
}
fn default_gamma() -> f64 {
    1.5
}

/// One segment of the time schedule.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentSpec {
    /// Number of steps, >= 1.
    pub steps: usize,
    /// Step size (s), > 0.
    pub dt: f64,
}

/// `[solver]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Newton tolerance on `|dY| / |X|`, in (0, 1). Default 1e-8.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// Newton tolerance on `|G|` relative to the forces at play, in (0, 1). Default 1e-6.
    #[serde(default = "default_residual_tolerance")]
    pub residual_tolerance: f64,
    /// Most Newton iterations per step, >= 1. Default 30.
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// How many times a failing step may be halved, >= 0. Default 6.
    #[serde(default = "default_max_cutbacks")]
    pub max_cutbacks: usize,
    /// Linear solver: `"auto"` (default: `direct` up to 300,000 unknowns,
    /// with `compact` first where there is bending; `reuse` above), `"direct"` (a fresh sparse factorisation every
    /// solve), `"iterative"` (block-Jacobi GMRES, no factorisation),
    /// `"reuse"` (GMRES preconditioned by an earlier factorisation) or
    /// `"compact"` (with bending, CG preconditioned by the factor of the
    /// Hessian's compact part: [`crate::solver::LinearMode::Compact`]).
    #[serde(default)]
    pub linear: crate::solver::LinearMode,
    /// Most chord steps after each Newton step that contracted fast (the
    /// increment shrank fourfold or the residual a hundredfold), 0–10 (0:
    /// plain Newton): solves with the factorisation just made, kept while
    /// each shrinks the increment at least fourfold. Default 2.
    #[serde(default = "default_chord_steps")]
    pub chord_steps: usize,
    /// What Newton does where the Hessian of a step whose terms are all
    /// potentials is not positive definite (a fabric folding): `"progressive"`
    /// (default: the stencil Hessians round the nodes of largest residual
    /// projected to their positive semi-definite part, more until it is),
    /// `"always"` (every stencil, every iteration) or `"never"` (the exact
    /// Hessian, and a diagonal shift where its direction goes uphill).
    #[serde(default)]
    pub projection: crate::solver::newton::Projection,
    /// Newton's increment test as a speed (m/s, > 0): in a dynamic step,
    /// the largest nodal correction divided by the step, `max_a |dY_a| /
    /// dt`, must be at most this (instead of `|dY| / |X| <= tolerance`);
    /// the residual test stays. Statics keep `tolerance`. Default: none.
    #[serde(default)]
    pub speed_tolerance: Option<f64>,
}

impl Default for SolverSpec {
    fn default() -> Self {
        Self {
            tolerance: default_tolerance(),
            residual_tolerance: default_residual_tolerance(),
            max_iterations: default_max_iterations(),
            max_cutbacks: default_max_cutbacks(),
            linear: crate::solver::LinearMode::default(),
            chord_steps: default_chord_steps(),
            projection: Default::default(),
            speed_tolerance: None,
        }
    }
}

fn default_tolerance() -> f64 {
    1e-8
}
fn default_residual_tolerance() -> f64 {
    1e-6
}
fn default_max_iterations() -> usize {
    30
}
fn default_max_cutbacks() -> usize {
    6
}
fn default_chord_steps() -> usize {
    2
}

/// `[output]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Write the fields every `every` steps (>= 1, default 10); the initial
    /// and the last step are always written.
    #[serde(default = "default_every")]
    pub every: usize,
    /// Write a checkpoint (the full state, to resume from) every N
    /// scheduled steps (with adaptive steps: every N converged steps); 0
    /// (default): only when interrupted.
    #[serde(default)]
    pub checkpoint_every: usize,
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            every: default_every(),
            checkpoint_every: 0,
        }
    }
}

fn default_every() -> usize {
    10
}

/// `[refine]`: the multilevel settle. The scenario runs as written on
/// its mesh (level 0); then, up to `levels` times, the mesh's triangles
/// are split (`where`), the state carried onto the finer mesh and settled
/// statically there at the full load, until the drape coefficient changes
/// by less than `tolerance` between two levels.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RefineSpec {
    /// How many times the triangles may be split (each split: one into
    /// four), 1 to [`MAX_REFINE_LEVELS`]. Default 2.
    #[serde(default = "default_levels")]
    pub levels: usize,
    /// `"all"` (every triangle) or `"folds"` (default: where the
    /// curvature indicator says, with a conforming closure).
    #[serde(default, rename = "where")]
    pub region: RefineWhere,
    /// Stop refining when the drape coefficient changes by less than this
    /// between two levels, >= 0 (default 0.01); a run without a pedestal
    /// refines `levels` times.
    #[serde(default = "default_refine_tolerance")]
    pub tolerance: f64,
    /// Elements per gravity bending length `l = (B / w)^(1/3)` (`B` the
    /// smaller bending rigidity, `w` the weight per area) that a level's
    /// mesh must have before `tolerance` may stop the refinement: its
    /// mean edge at most `l / resolution`. >= 0; default 0 (no such
    /// condition). A mesh too coarse to fold the fabric changes its drape
    /// coefficient little from one level to the next and would otherwise
    /// pass for converged (docs/validation.md, Matsudaira F).
    #[serde(default)]
    pub resolution: f64,
    /// `"folds"`: the triangles split are the fewest that hold this
    /// share of the curvature indicator (Dörfler's bulk criterion), in
    /// (0, 1]; default 0.7.
    #[serde(default = "default_fraction")]
    pub fraction: f64,
    /// `"folds"`: what the marking ranks the triangles by (default
    /// `"bending"`, the curvature's energy; `"chord"`, that energy times
    /// the triangle's area: the flat triangles' distance from the curved
    /// surface).
    #[serde(default)]
    pub indicator: RefineIndicator,
    /// `"folds"`: regions split besides the marked triangles: `"rim"`
    /// (every triangle with an edge on the free boundary) and
    /// `"contact"` (every triangle with corners both touching an obstacle
    /// and not: the contact line). Default none.
    #[serde(default)]
    pub also: Vec<RefineAlso>,
}

/// `[refine] also`: a region split on every finer level whatever the
/// indicator says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RefineAlso {
    /// The triangles with an edge on the free boundary: the specimen's
    /// outline, which the drape coefficient's shadow is.
    Rim,
    /// The triangles across the contact line: some corners pressed on an
    /// obstacle, some not.
    Contact,
}

pub use crate::setup::MAX_REFINE_LEVELS;

/// `[refine] where`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RefineWhere {
    /// Every triangle.
    All,
    /// Where the folds are (the curvature indicator), closed conformingly.
    #[default]
    Folds,
}

/// `[refine] indicator`: what Dörfler's marking ranks the triangles by
/// ([`crate::levels::indicator`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RefineIndicator {
    /// The discrete shell's bending energy of each triangle: where the
    /// folds are, however fine the mesh already is there.
    #[default]
    Bending,
    /// That energy times the triangle's reference area, the square of
    /// how far the flat triangle lies from the curved surface: it falls
    /// fourfold where a triangle is split, so each level refines where
    /// the mesh resolves the curvature worst.
    Chord,
}

fn default_levels() -> usize {
    2
}

fn default_refine_tolerance() -> f64 {
    0.01
}

fn default_fraction() -> f64 {
    0.7
}

/// `[[monitor]]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MonitorSpec {
    /// Name; columns `<name>_x, <name>_y, <name>_z` in the history. Letters,
    /// digits, `_` and `-`; unique.
    pub name: String,
    /// The node nearest this initial position (m); it must lie within 10 %
    /// of the mesh's size from it.
    pub at: [f64; 3],
}

/// Adds the array index to a key path such as `load.kind` (an array of
/// tables) from the error's line: the number of `[[load]]` headers before it.
fn index_key(source: &str, key: &str, line: Option<usize>) -> String {
    let (Some(line), Some((table, rest))) = (line, key.split_once('.')) else {
        return key.to_string();
    };
    let header = format!("[[{table}]]");
    let count = source
        .lines()
        .take(line)
        .filter(|l| l.trim_start().starts_with(&header))
        .count();
    if count == 0 || !["load", "fix", "obstacle", "monitor"].contains(&table) {
        return key.to_string();
    }
    format!("{table}[{}].{rest}", count - 1)
}

impl Scenario {
    /// Reads and parses a scenario file (types and unknown keys checked;
    /// ranges are checked by [`Scenario::build`]).
    pub fn read(path: &Path) -> Result<(Self, String), ScenarioError> {
        let bytes = crate::input::read(path).map_err(|e| ScenarioError::Io {
            file: path.to_path_buf(),
            error: e,
        })?;
        let source = String::from_utf8(bytes).map_err(|e| {
            let at = e.utf8_error().valid_up_to();
            let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
            ScenarioError::Parse {
                file: path.to_path_buf(),
                line: Some(line),
                message: format!("the file is not UTF-8 text (invalid byte at offset {at})"),
            }
        })?;
        let scenario = Self::parse(&source, path)?;
        Ok((scenario, source))
    }

    /// Parses scenario text; `path` is used in messages.
    ///
    /// The `[[obstacle]]` tables and the `[contact]` table are taken out of
    /// the parsed document and read apart, each dispatched on its tag
    /// (`shape`, `method`) into the struct of that choice, whose
    /// `deny_unknown_fields` then rejects another choice's keys at their
    /// own line (the private module `tagged`); serde reads the rest in one go.
    pub fn parse(source: &str, path: &Path) -> Result<Self, ScenarioError> {
        let parse_error = |e| parse_error(source, path, e);
        let mut document = toml::de::DeTable::parse(source).map_err(parse_error)?;
        let obstacles = document.get_mut().remove_entry("obstacle");
        let contact = document.get_mut().remove_entry("contact");
        let mut scenario =
            Self::deserialize(toml::de::Deserializer::from(document)).map_err(parse_error)?;
        let located = |e| located_error(source, path, e);
        if let Some((_, tables)) = obstacles {
            scenario.obstacles =
                tagged::read_tagged_array(tables, "obstacle", "shape", ObstacleSpec::read)
                    .map_err(located)?;
        }
        if let Some((_, table)) = contact {
            scenario.contact = Some(
                tagged::read_tagged(table, "contact", "method", ContactSpec::read)
                    .map_err(located)?,
            );
        }
        // A fabric in a laboratory's units becomes the SI keys here.
        let c = check::Checker { file: path, source };
        scenario.material = lab::resolve(&c, &scenario.material)?;
        Ok(scenario)
    }
}

/// 1-based line of the byte `span` starts at.
fn line_at(source: &str, span: Option<std::ops::Range<usize>>) -> Option<usize> {
    span.map(|s| source[..s.start.min(source.len())].matches('\n').count() + 1)
}

/// The dotted key path of `error` (`table.key`), when serde knows it.
fn error_key(error: &mut toml::de::Error) -> Option<String> {
    // The error's full text ends with "in `table.key`" when serde knows
    // where it was.
    error.set_input(None);
    error
        .to_string()
        .lines()
        .rev()
        .find_map(|l| l.trim().strip_prefix("in `"))
        .and_then(|k| k.strip_suffix('`'))
        .filter(|k| !k.is_empty())
        .map(str::to_string)
}

/// A TOML or serde error of the whole file: the key named, as for range
/// errors, with the array index found from the line.
fn parse_error(source: &str, path: &Path, mut e: toml::de::Error) -> ScenarioError {
    let line = line_at(source, e.span());
    let mut message = plain_message(source, &e);
    if let Some(key) = error_key(&mut e) {
        if message.starts_with("expected one table") && !key.contains('.') {
            message = format!(
                "expected one table [{key}], found an array of tables [[{key}]] (or an array): write [{key}]"
            );
        }
        message = format!("`{}`: {message}", index_key(source, &key, line));
    }
    ScenarioError::Parse {
        file: path.to_path_buf(),
        line,
        message,
    }
}

/// serde's message of `e`, said in TOML's terms where serde's would
/// mislead: a TOML date-time reaches serde as a map, and a table written
/// as an array of tables (`[[mesh]]`) as a sequence.
fn plain_message(source: &str, e: &toml::de::Error) -> String {
    let message = e.message().trim();
    let text = e
        .span()
        .and_then(|s| source.get(s))
        .map(str::trim)
        .unwrap_or_default();
    if let Some(rest) = message.strip_prefix("invalid type: map")
        && text.parse::<toml::value::Datetime>().is_ok()
    {
        return format!("invalid type: the date-time {text}{rest}");
    }
    if message.starts_with("wanted exactly 1 element") {
        return "expected one table, found an array of tables (`[[...]]`) or an array: write the table's header with single brackets".into();
    }
    message.to_string()
}

/// An error inside a table read apart: its key path, and the choice of tag
/// that decided which keys it takes.
fn located_error(source: &str, path: &Path, e: tagged::Located) -> ScenarioError {
    let choice = e.choice.map(|c| format!(" ({c})")).unwrap_or_default();
    ScenarioError::Parse {
        file: path.to_path_buf(),
        line: line_at(source, e.span),
        message: format!("`{}`{choice}: {}", e.key, e.message),
    }
}
