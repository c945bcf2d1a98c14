//! Checks a parsed [`Scenario`] and builds the model, schedule and monitors.

use super::locate::line_of;
use super::{
    AnalysisKind, BoxSpec, FixSpec, LoadKindSpec, LoadSpec, MeshShape, MeshSpec, Scenario,
    ScenarioError, TimeSpec,
};
use crate::contact::{ContactMethod, ContactModel, RigidBody};
use crate::element::membrane::Section;
use crate::integrator::Newmark;
use crate::load::{Load, LoadKind};
use crate::material::{Material, SaintVenantKirchhoff, Wrinkling, WrinklingModel};
use crate::mesh::{ElementOrder, Mesh, generate};
use crate::model::Model;
use crate::simulation::schedule::{AdaptiveSteps, RestCriterion};
use crate::solver::NewtonSettings;
use std::path::{Path, PathBuf};

/// Most nodes a generated mesh may have: a guard against typos such as
/// `divisions = [20000, 20000]`, which would exhaust memory (a run needs
/// about 1.6 kB per node with a direct solver; 3 million nodes, 6 million
/// T3 elements, is ~5 GB).
const MAX_GENERATED_NODES: usize = 3_000_000;

/// A node whose position is recorded in the history.
#[derive(Debug, Clone, PartialEq)]
pub struct Monitor {
    /// Name from the scenario.
    pub name: String,
    /// Node index.
    pub node: usize,
}

/// How time (or load) advances.
#[derive(Debug, Clone, PartialEq)]
pub enum Analysis {
    /// Newmark dynamics over a schedule of `(steps, dt)` segments.
    Dynamic {
        /// Newmark parameters.
        newmark: Newmark,
        /// `(steps, dt)` segments.
        segments: Vec<(usize, f64)>,
    },
    /// Static load stepping in `steps` equal increments.
    Static {
        /// Increments.
        steps: usize,
    },
}

/// Everything needed to run a scenario.
#[derive(Debug)]
pub struct Setup {
    /// Title.
    pub title: String,
    /// The discrete model.
    pub model: Model,
    /// Dynamic or static.
    pub analysis: Analysis,
    /// Adaptive time steps (`[time] adaptive = true`); `None`: the
    /// segments' fixed steps (and always in statics).
    pub adaptive: Option<AdaptiveSteps>,
    /// The rest criterion (`[time] rest`), if any (dynamic analysis only).
    pub rest: Option<RestCriterion>,
    /// Newton settings.
    pub newton: NewtonSettings,
    /// Most halvings of a failing step.
    pub max_cutbacks: usize,
    /// Field output interval (steps).
    pub output_every: usize,
    /// Monitored nodes.
    pub monitors: Vec<Monitor>,
    /// Write a checkpoint every this many scheduled steps (with adaptive
    /// steps: converged steps; 0: never).
    pub checkpoint_every: usize,
    /// How linear systems are solved.
    pub linear: crate::solver::LinearMode,
    /// The scenario file (absolute when it could be resolved).
    pub scenario_path: PathBuf,
    /// FNV-1a hash of the scenario text: a resumed run refuses a changed scenario.
    pub scenario_hash: u64,
}

/// 64-bit FNV-1a of `bytes`: stable across platforms and Rust versions.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

struct Checker<'a> {
    file: &'a Path,
    source: &'a str,
}

impl Checker<'_> {
    fn invalid(
        &self,
        table: &str,
        index: Option<usize>,
        key: &str,
        message: String,
    ) -> ScenarioError {
        let path = match index {
            Some(i) => format!("{table}[{i}].{key}"),
            None if table.is_empty() => key.to_string(),
            None => format!("{table}.{key}"),
        };
        ScenarioError::Invalid {
            file: self.file.to_path_buf(),
            line: line_of(self.source, table, index, key),
            key: path,
            message,
        }
    }

    fn positive(
        &self,
        table: &str,
        index: Option<usize>,
        key: &str,
        v: f64,
    ) -> Result<f64, ScenarioError> {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(self.invalid(
                table,
                index,
                key,
                format!("must be a positive finite number, not {v}"),
            ))
        }
    }

    fn finite(
        &self,
        table: &str,
        index: Option<usize>,
        key: &str,
        v: &[f64],
    ) -> Result<(), ScenarioError> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(self.invalid(table, index, key, format!("must be finite, not {v:?}")))
        }
    }

    fn required<T: Clone>(
        &self,
        table: &str,
        index: Option<usize>,
        key: &str,
        v: &Option<T>,
        why: &str,
    ) -> Result<T, ScenarioError> {
        v.clone()
            .ok_or_else(|| self.invalid(table, index, key, format!("is required {why}")))
    }

    /// Rejects every key of `given` that is present: they do not apply (`why`).
    fn none_of(
        &self,
        table: &str,
        index: Option<usize>,
        given: &[(&str, bool)],
        why: &str,
    ) -> Result<(), ScenarioError> {
        match given.iter().find(|(_, present)| *present) {
            Some((key, _)) => Err(self.invalid(table, index, key, format!("does not apply {why}"))),
            None => Ok(()),
        }
    }

    /// As [`Self::invalid`] for `sub` inside the table `key` of `table`
    /// (`rest = { speed = ... }`, `rest.speed = ...` or `[time.rest]`):
    /// the key path `table.key.sub`, the line of `sub` in a `[table.key]`
    /// table, else the line of `key`.
    fn invalid_in(&self, table: &str, key: &str, sub: &str, message: String) -> ScenarioError {
        let nested = format!("{table}.{key}");
        ScenarioError::Invalid {
            file: self.file.to_path_buf(),
            line: line_of(self.source, &nested, None, sub)
                .or_else(|| line_of(self.source, table, None, key)),
            key: format!("{nested}.{sub}"),
            message,
        }
    }

    fn absent<T>(
        &self,
        table: &str,
        index: Option<usize>,
        key: &str,
        v: &Option<T>,
        why: &str,
    ) -> Result<(), ScenarioError> {
        match v {
            Some(_) => Err(self.invalid(table, index, key, format!("does not apply {why}"))),
            None => Ok(()),
        }
    }
}

impl Scenario {
    /// Checks every value and builds the [`Setup`]. `file` is the scenario's
    /// path (for messages and relative paths), `source` its text (for line
    /// numbers).
    pub fn build(&self, file: &Path, source: &str) -> Result<Setup, ScenarioError> {
        let c = Checker { file, source };
        let base = file.parent().map(Path::to_path_buf).unwrap_or_default();
        let mesh = build_mesh(&c, &self.mesh, &base)?;

        let m = &self.material;
        if m.model != "saint-venant-kirchhoff" {
            return Err(c.invalid(
                "material",
                None,
                "model",
                format!("must be \"saint-venant-kirchhoff\", not {:?}", m.model),
            ));
        }
        let young = c.positive("material", None, "youngs_modulus", m.youngs_modulus)?;
        if !(m.poisson_ratio.is_finite() && m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5) {
            return Err(c.invalid(
                "material",
                None,
                "poisson_ratio",
                format!("must lie in (-1, 0.5), not {}", m.poisson_ratio),
            ));
        }
        let thickness = c.positive("material", None, "thickness", m.thickness)?;
        let is_static = self.analysis.kind == AnalysisKind::Static;
        let density = if is_static && m.density == 0.0 {
            0.0
        } else {
            c.positive("material", None, "density", m.density)?
        };
        c.finite("material", None, "prestress", &[m.prestress])?;
        let wrinkling = match m.wrinkling.as_str() {
            "none" => None,
            "stress-projection" => Some(WrinklingModel::StressProjection),
            "relaxed-energy" => {
                if m.prestress != 0.0 {
                    return Err(c.invalid(
                        "material",
                        None,
                        "prestress",
                        format!(
                            "must be 0 with wrinkling = \"relaxed-energy\" (Pipkin's relaxed energy has no prestress), not {}",
                            m.prestress
                        ),
                    ));
                }
                Some(WrinklingModel::RelaxedEnergy)
            }
            other => {
                return Err(c.invalid(
                    "material",
                    None,
                    "wrinkling",
                    format!(
                        "must be \"none\", \"stress-projection\" or \"relaxed-energy\", not {other:?}"
                    ),
                ));
            }
        };

        let mut loads = Vec::new();
        for (i, l) in self.loads.iter().enumerate() {
            loads.push(build_load(&c, &mesh, i, l)?);
        }
        let mut fixed = vec![false; 3 * mesh.node_count()];
        for (i, f) in self.fixes.iter().enumerate() {
            build_fix(&c, &mesh, i, f, &mut fixed)?;
        }
        let contact = build_contact(&c, self, &base)?;

        let (mut adaptive, mut rest) = (None, None);
        let analysis = match self.analysis.kind {
            AnalysisKind::Dynamic => {
                c.absent(
                    "analysis",
                    None,
                    "steps",
                    &self.analysis.steps,
                    "to a dynamic analysis (use [time] segments)",
                )?;
                let time = c.required(
                    "time",
                    None,
                    "segments",
                    &self.time,
                    "for a dynamic analysis (a [time] table with segments)",
                )?;
                let segment_specs = c.required(
                    "time",
                    None,
                    "segments",
                    &time.segments,
                    "for a dynamic analysis ([{ steps = N, dt = h }, ...])",
                )?;
                if !(time.beta.is_finite() && time.beta > 0.0) {
                    return Err(c.invalid(
                        "time",
                        None,
                        "beta",
                        format!("must be positive, not {}", time.beta),
                    ));
                }
                if !(time.gamma.is_finite() && time.gamma >= 0.5) {
                    return Err(c.invalid(
                        "time",
                        None,
                        "gamma",
                        format!(
                            "must be >= 0.5 (below, Newmark amplifies), not {}",
                            time.gamma
                        ),
                    ));
                }
                if segment_specs.is_empty() {
                    return Err(c.invalid(
                        "time",
                        None,
                        "segments",
                        "must list at least one { steps, dt }".into(),
                    ));
                }
                let mut segments = Vec::new();
                for (k, s) in segment_specs.iter().enumerate() {
                    if s.steps == 0 {
                        return Err(c.invalid(
                            "time",
                            None,
                            "segments",
                            format!("segment {k}: steps must be at least 1"),
                        ));
                    }
                    if !(s.dt.is_finite() && s.dt > 0.0) {
                        return Err(c.invalid(
                            "time",
                            None,
                            "segments",
                            format!(
                                "segment {k}: dt must be a positive finite number, not {}",
                                s.dt
                            ),
                        ));
                    }
                    segments.push((s.steps, s.dt));
                }
                adaptive = build_adaptive(&c, &time, &segments)?;
                rest = build_rest(&c, &time)?;
                Analysis::Dynamic {
                    newmark: Newmark {
                        beta: time.beta,
                        gamma: time.gamma,
                    },
                    segments,
                }
            }
            AnalysisKind::Static => {
                if let Some(time) = &self.time {
                    c.none_of(
                        "time",
                        None,
                        &[
                            ("adaptive", time.adaptive.is_some()),
                            ("dt_max", time.dt_max.is_some()),
                            ("rest", time.rest.is_some()),
                        ],
                        "to a static analysis: adaptive steps and the rest criterion are for dynamic runs (to settle a fabric to rest, run it dynamically with beta = 1, gamma = 1.5)",
                    )?;
                    return Err(c.invalid(
                        "time",
                        None,
                        "segments",
                        "does not apply to a static analysis (use [analysis] steps)".into(),
                    ));
                }
                let steps = self.analysis.steps.unwrap_or(10);
                if steps == 0 {
                    return Err(c.invalid("analysis", None, "steps", "must be at least 1".into()));
                }
                Analysis::Static { steps }
            }
        };

        let s = &self.solver;
        if !(s.tolerance.is_finite() && s.tolerance > 0.0 && s.tolerance < 1.0) {
            return Err(c.invalid(
                "solver",
                None,
                "tolerance",
                format!("must lie in (0, 1), not {}", s.tolerance),
            ));
        }
        if !(s.residual_tolerance.is_finite()
            && s.residual_tolerance > 0.0
            && s.residual_tolerance < 1.0)
        {
            return Err(c.invalid(
                "solver",
                None,
                "residual_tolerance",
                format!("must lie in (0, 1), not {}", s.residual_tolerance),
            ));
        }
        if s.max_iterations == 0 {
            return Err(c.invalid(
                "solver",
                None,
                "max_iterations",
                "must be at least 1".into(),
            ));
        }
        if s.max_cutbacks > 30 {
            return Err(c.invalid(
                "solver",
                None,
                "max_cutbacks",
                format!("must be at most 30, not {}", s.max_cutbacks),
            ));
        }
        if s.chord_steps > 10 {
            return Err(c.invalid(
                "solver",
                None,
                "chord_steps",
                format!("must be at most 10, not {}", s.chord_steps),
            ));
        }
        if self.output.every == 0 {
            return Err(c.invalid("output", None, "every", "must be at least 1".into()));
        }

        let (lo, hi) = mesh.bounding_box();
        let size =
            ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt();
        let mut monitors = Vec::new();
        for (i, mon) in self.monitors.iter().enumerate() {
            if mon.name.is_empty()
                || !mon
                    .name
                    .chars()
                    .all(|ch| ch.is_ascii_alphanumeric() || ch == '_' || ch == '-')
            {
                return Err(c.invalid(
                    "monitor",
                    Some(i),
                    "name",
                    format!("must be letters, digits, '_' or '-', not {:?}", mon.name),
                ));
            }
            if monitors.iter().any(|m: &Monitor| m.name == mon.name) {
                return Err(c.invalid(
                    "monitor",
                    Some(i),
                    "name",
                    format!("{:?} is used twice", mon.name),
                ));
            }
            c.finite("monitor", Some(i), "at", &mon.at)?;
            let node = nearest(&c, &mesh, "monitor", i, mon.at, size)?;
            monitors.push(Monitor {
                name: mon.name.clone(),
                node,
            });
        }

        // With a wrinkling model the prestress is part of the stress that is
        // projected, so the material carries it.
        let (material, prestress): (Box<dyn Material>, f64) = match wrinkling {
            None => (
                Box::new(SaintVenantKirchhoff::new(young, m.poisson_ratio)),
                m.prestress,
            ),
            Some(model) => {
                let w = Wrinkling::new(young, m.poisson_ratio, m.prestress, model);
                let w = if is_static {
                    w.with_slack_tangent(1e-6)
                } else {
                    w
                };
                (Box::new(w), 0.0)
            }
        };
        let model = Model::new(
            mesh,
            material,
            Section {
                thickness,
                prestress,
            },
            density,
            loads,
            fixed,
            self.analysis.mass,
        )
        .map_err(|e| ScenarioError::Mesh {
            file: file.to_path_buf(),
            message: e.to_string(),
        })?;
        let mut model = model;
        if let Some(contact) = &contact {
            check_initial_penetration(&c, &model.mesh, contact)?;
        }
        model.contact = contact;
        let title = self.title.clone().unwrap_or_else(|| {
            file.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        Ok(Setup {
            title,
            model,
            analysis,
            adaptive,
            rest,
            newton: NewtonSettings {
                tolerance: s.tolerance,
                residual_tolerance: s.residual_tolerance,
                max_iterations: s.max_iterations,
                chord_steps: s.chord_steps,
            },
            max_cutbacks: s.max_cutbacks,
            output_every: self.output.every,
            monitors,
            checkpoint_every: self.output.checkpoint_every,
            linear: s.linear,
            scenario_path: std::fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf()),
            scenario_hash: fnv1a(source.as_bytes()),
        })
    }
}

/// The adaptive steps of `[time]`, or `None` without `adaptive = true`;
/// `dt_max` must be positive and at least every segment's `dt`.
fn build_adaptive(
    c: &Checker,
    time: &TimeSpec,
    segments: &[(usize, f64)],
) -> Result<Option<AdaptiveSteps>, ScenarioError> {
    if time.adaptive != Some(true) {
        c.absent(
            "time",
            None,
            "dt_max",
            &time.dt_max,
            "without adaptive = true (fixed steps are the segments' dt)",
        )?;
        return Ok(None);
    }
    let Some(dt_max) = time.dt_max else {
        return Ok(Some(AdaptiveSteps { dt_max: None }));
    };
    let dt_max = c.positive("time", None, "dt_max", dt_max)?;
    if let Some((k, (_, dt))) = segments.iter().enumerate().find(|(_, s)| s.1 > dt_max) {
        return Err(c.invalid(
            "time",
            None,
            "dt_max",
            format!(
                "= {dt_max} s is smaller than segment {k}'s dt = {dt} s: it must be at least every segment's dt"
            ),
        ));
    }
    Ok(Some(AdaptiveSteps {
        dt_max: Some(dt_max),
    }))
}

/// The rest criterion of `[time]`, if given: `speed` positive and finite,
/// `after` finite and >= 0.
fn build_rest(c: &Checker, time: &TimeSpec) -> Result<Option<RestCriterion>, ScenarioError> {
    let Some(r) = time.rest else {
        return Ok(None);
    };
    if !(r.speed.is_finite() && r.speed > 0.0) {
        return Err(c.invalid_in(
            "time",
            "rest",
            "speed",
            format!("must be a positive finite speed (m/s), not {}", r.speed),
        ));
    }
    if !(r.after.is_finite() && r.after >= 0.0) {
        return Err(c.invalid_in(
            "time",
            "rest",
            "after",
            format!("must be a finite time >= 0 (s), not {}", r.after),
        ));
    }
    Ok(Some(RestCriterion {
        speed: r.speed,
        after: r.after,
    }))
}

fn build_contact(
    c: &Checker,
    s: &Scenario,
    base: &Path,
) -> Result<Option<ContactModel>, ScenarioError> {
    use crate::contact::obstacle::{
        BoxObstacle, CylinderObstacle, PlaneObstacle, Rounded, SphereObstacle, read_mesh_obstacle,
    };
    if s.obstacles.is_empty() {
        if s.contact.is_some() {
            return Err(c.invalid(
                "contact",
                None,
                "method",
                "is given but there is no [[obstacle]]".into(),
            ));
        }
        return Ok(None);
    }
    let spec = c.required(
        "contact",
        None,
        "method",
        &s.contact,
        "when there are obstacles (a [contact] table with method = \"penalty\" or \"lagrange\")",
    )?;
    let method = match spec.method.as_str() {
        "penalty" => {
            let eta = c.required(
                "contact",
                None,
                "penalty",
                &spec.penalty,
                "for method = \"penalty\" (N/m)",
            )?;
            ContactMethod::Penalty {
                stiffness: c.positive("contact", None, "penalty", eta)?,
            }
        }
        "lagrange" => {
            c.absent(
                "contact",
                None,
                "penalty",
                &spec.penalty,
                "to method = \"lagrange\"",
            )?;
            ContactMethod::Lagrange
        }
        other => {
            return Err(c.invalid(
                "contact",
                None,
                "method",
                format!("must be \"penalty\" or \"lagrange\", not {other:?}"),
            ));
        }
    };
    let mut bodies = Vec::new();
    for (i, o) in s.obstacles.iter().enumerate() {
        let t = "obstacle";
        let ix = Some(i);
        let keys: [(&str, bool); 10] = [
            ("edge_radius", o.edge_radius.is_some()),
            ("min", o.min.is_some()),
            ("max", o.max.is_some()),
            ("point", o.point.is_some()),
            ("normal", o.normal.is_some()),
            ("center", o.center.is_some()),
            ("radius", o.radius.is_some()),
            ("axis", o.axis.is_some()),
            ("height", o.height.is_some()),
            ("path", o.path.is_some()),
        ];
        let allowed: &[&str] = match o.shape.as_str() {
            "plane" => &["point", "normal"],
            "box" => &["min", "max", "edge_radius"],
            "sphere" => &["center", "radius"],
            "cylinder" => &["center", "axis", "radius", "height", "edge_radius"],
            "mesh" => &["path"],
            other => {
                return Err(c.invalid(t, ix, "shape", format!(
                    "must be \"plane\", \"box\", \"sphere\", \"cylinder\" or \"mesh\", not {other:?}"
                )));
            }
        };
        for (key, given) in keys {
            if given && !allowed.contains(&key) {
                return Err(c.invalid(
                    t,
                    ix,
                    key,
                    format!("does not apply to shape = {:?}", o.shape),
                ));
            }
        }
        let why = format!("for shape = {:?}", o.shape);
        // The error's own key when it names one (a zero axis, a NaN centre),
        // else the key given here.
        let invalid = |key: &str, e: crate::contact::ObstacleError| {
            c.invalid(t, ix, e.key().unwrap_or(key), e.to_string())
        };
        let shape: Box<dyn crate::contact::Obstacle> = match o.shape.as_str() {
            "plane" => Box::new(
                PlaneObstacle::new(
                    c.required(t, ix, "point", &o.point, &why)?,
                    c.required(t, ix, "normal", &o.normal, &why)?,
                )
                .map_err(|e| invalid("normal", e))?,
            ),
            "box" => {
                let (lo, hi) = (
                    c.required(t, ix, "min", &o.min, &why)?,
                    c.required(t, ix, "max", &o.max, &why)?,
                );
                let sharp = BoxObstacle::new(lo, hi).map_err(|e| invalid("max", e))?;
                let smallest = (0..3).map(|k| hi[k] - lo[k]).fold(f64::INFINITY, f64::min);
                let r = edge_radius(c, ix, o.edge_radius, smallest)?;
                if r > 0.0 {
                    let inner = BoxObstacle::new(lo.map(|v| v + r), hi.map(|v| v - r))
                        .map_err(|e| invalid("edge_radius", e))?;
                    Box::new(Rounded::new(inner, r))
                } else {
                    Box::new(sharp)
                }
            }
            "sphere" => Box::new(
                SphereObstacle::new(
                    c.required(t, ix, "center", &o.center, &why)?,
                    c.required(t, ix, "radius", &o.radius, &why)?,
                )
                .map_err(|e| invalid("radius", e))?,
            ),
            "cylinder" => {
                let (center, axis) = (
                    c.required(t, ix, "center", &o.center, &why)?,
                    c.required(t, ix, "axis", &o.axis, &why)?,
                );
                let (radius, height) = (
                    c.required(t, ix, "radius", &o.radius, &why)?,
                    c.required(t, ix, "height", &o.height, &why)?,
                );
                let sharp = CylinderObstacle::new(center, axis, radius, height)
                    .map_err(|e| invalid("radius", e))?;
                let r = edge_radius(c, ix, o.edge_radius, radius.min(height))?;
                if r > 0.0 {
                    let a = sharp.axis();
                    let inner = CylinderObstacle::new(
                        [0, 1, 2].map(|k| center[k] - r * a[k]),
                        a,
                        radius - r,
                        height - 2.0 * r,
                    )
                    .map_err(|e| invalid("edge_radius", e))?;
                    Box::new(Rounded::new(inner, r))
                } else {
                    Box::new(sharp)
                }
            }
            _ => {
                let rel = c.required(t, ix, "path", &o.path, &why)?;
                Box::new(read_mesh_obstacle(&base.join(&rel)).map_err(|e| invalid("path", e))?)
            }
        };
        let velocity = o.velocity.unwrap_or([0.0; 3]);
        c.finite(t, ix, "velocity", &velocity)?;
        bodies.push(RigidBody { shape, velocity });
    }
    Ok(Some(ContactModel { bodies, method }))
}

/// Rejects a fabric that starts inside an obstacle by more than 1e-3 of
/// its size: contact would fling it out in the first step (a node sitting
/// on a surface, or a hair inside, is fine).
fn check_initial_penetration(
    c: &Checker,
    mesh: &Mesh,
    contact: &ContactModel,
) -> Result<(), ScenarioError> {
    let (lo, hi) = mesh.bounding_box();
    let size = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt();
    // Nodes, and the centroids and edge midpoints of the elements' vertex
    // triangles: an obstacle smaller than an element can sit between nodes.
    let mut probes: Vec<[f64; 3]> = mesh.nodes.clone();
    for el in mesh.elements() {
        let v = [mesh.nodes[el[0]], mesh.nodes[el[1]], mesh.nodes[el[2]]];
        probes.push([0, 1, 2].map(|i| (v[0][i] + v[1][i] + v[2][i]) / 3.0));
        for j in 0..3 {
            let (a, b) = (v[j], v[(j + 1) % 3]);
            probes.push([0, 1, 2].map(|i| 0.5 * (a[i] + b[i])));
        }
    }
    for (k, body) in contact.bodies.iter().enumerate() {
        let deepest = probes
            .iter()
            .map(|x| (*x, body.proximity(*x, 0.0, None).gap))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((x, gap)) = deepest
            && gap < -1e-3 * size
        {
            return Err(c.invalid(
                "obstacle",
                Some(k),
                "shape",
                format!(
                    "({}) starts interpenetrating the fabric: the fabric's point {x:?} is {:.4e} m inside it; move the obstacle or the mesh",
                    body.shape.describe(),
                    -gap
                ),
            ));
        }
    }
    Ok(())
}

/// The fillet radius of a box or cylinder whose smallest dimension is
/// `smallest`: the given one (>= 0, below half of it), or 1e-3 of it.
fn edge_radius(
    c: &Checker,
    ix: Option<usize>,
    given: Option<f64>,
    smallest: f64,
) -> Result<f64, ScenarioError> {
    match given {
        None => Ok(1e-3 * smallest),
        Some(r) if r.is_finite() && r >= 0.0 && r < 0.5 * smallest => Ok(r),
        Some(r) => Err(c.invalid(
            "obstacle",
            ix,
            "edge_radius",
            format!(
                "must lie in [0, {}) m (half the smallest dimension), not {r}",
                0.5 * smallest
            ),
        )),
    }
}

fn nearest(
    c: &Checker,
    mesh: &Mesh,
    table: &str,
    i: usize,
    at: [f64; 3],
    size: f64,
) -> Result<usize, ScenarioError> {
    let (node, distance) = mesh
        .nearest_node(at)
        .ok_or_else(|| c.invalid(table, Some(i), "at", "the mesh has no node".into()))?;
    if distance > 0.1 * size {
        return Err(c.invalid(table, Some(i), "at", format!(
            "{at:?} is {distance:.4} m from the nearest node ({:?}), more than 10 % of the mesh's size {size:.4} m",
            mesh.nodes[node]
        )));
    }
    Ok(node)
}

fn build_mesh(c: &Checker, spec: &MeshSpec, base: &Path) -> Result<Mesh, ScenarioError> {
    let t = "mesh";
    let order =
        match spec.order {
            None => None,
            Some(p) => Some(ElementOrder::from_degree(p).ok_or_else(|| {
                c.invalid(t, None, "order", format!("must be 1, 2 or 3, not {p}"))
            })?),
        };
    let center = spec.center.unwrap_or([0.0; 3]);
    c.finite(t, None, "center", &center)?;
    let mesh = match spec.shape {
        MeshShape::Rectangle => {
            c.none_of(
                t,
                None,
                &[
                    ("radius", spec.radius.is_some()),
                    ("rings", spec.rings.is_some()),
                    ("path", spec.path.is_some()),
                ],
                "to shape = \"rectangle\"",
            )?;
            let size = c.required(
                t,
                None,
                "size",
                &spec.size,
                "for shape = \"rectangle\" ([width, height] in m)",
            )?;
            for v in size {
                c.positive(t, None, "size", v)?;
            }
            let div = c.required(
                t,
                None,
                "divisions",
                &spec.divisions,
                "for shape = \"rectangle\" ([nx, ny])",
            )?;
            let p = order.unwrap_or(ElementOrder::Linear).degree();
            if div[0] == 0 || div[1] == 0 {
                return Err(c.invalid(
                    t,
                    None,
                    "divisions",
                    format!("must be at least 1 in each direction, not {div:?}"),
                ));
            }
            let nodes = (div[0].saturating_mul(p).saturating_add(1))
                .saturating_mul(div[1].saturating_mul(p).saturating_add(1));
            if nodes > MAX_GENERATED_NODES {
                return Err(c.invalid(t, None, "divisions", format!("{div:?} would make {nodes} nodes, more than the limit {MAX_GENERATED_NODES}")));
            }
            generate::rectangle(
                size,
                div,
                spec.pattern.unwrap_or(generate::Pattern::Right),
                center,
                order.unwrap_or(ElementOrder::Linear),
            )
        }
        MeshShape::Disc => {
            c.none_of(
                t,
                None,
                &[
                    ("size", spec.size.is_some()),
                    ("divisions", spec.divisions.is_some()),
                    ("pattern", spec.pattern.is_some()),
                    ("path", spec.path.is_some()),
                ],
                "to shape = \"disc\"",
            )?;
            let radius = c.positive(
                t,
                None,
                "radius",
                c.required(t, None, "radius", &spec.radius, "for shape = \"disc\" (m)")?,
            )?;
            let rings = c.required(t, None, "rings", &spec.rings, "for shape = \"disc\"")?;
            let p = order.unwrap_or(ElementOrder::Linear).degree();
            if rings == 0
                || rings.saturating_mul(rings).saturating_mul(3 * p * p) > MAX_GENERATED_NODES
            {
                return Err(c.invalid(
                    t,
                    None,
                    "rings",
                    format!(
                        "must lie in 1..={}, not {rings}",
                        ((MAX_GENERATED_NODES / (3 * p * p)) as f64).sqrt() as usize
                    ),
                ));
            }
            generate::disc(radius, rings, center, order.unwrap_or(ElementOrder::Linear))
        }
        MeshShape::File => {
            c.none_of(
                t,
                None,
                &[
                    ("size", spec.size.is_some()),
                    ("divisions", spec.divisions.is_some()),
                    ("pattern", spec.pattern.is_some()),
                    ("radius", spec.radius.is_some()),
                    ("rings", spec.rings.is_some()),
                    ("center", spec.center.is_some()),
                ],
                "to shape = \"file\"",
            )?;
            let rel = c.required(t, None, "path", &spec.path, "for shape = \"file\"")?;
            let path: PathBuf = base.join(&rel);
            let mesh =
                read_mesh_file(&path).map_err(|message| c.invalid(t, None, "path", message))?;
            mesh.validate()
                .map_err(|e| c.invalid(t, None, "path", format!("{}: {e}", path.display())))?;
            if let Some(o) = order
                && o != mesh.order
            {
                return Err(c.invalid(
                    t,
                    None,
                    "order",
                    format!(
                        "is {} but {} holds triangles of order {}",
                        o.degree(),
                        path.display(),
                        mesh.order.degree()
                    ),
                ));
            }
            mesh
        }
    };
    mesh.validate().map_err(|e| ScenarioError::Mesh {
        file: c.file.to_path_buf(),
        message: e.to_string(),
    })?;
    Ok(mesh)
}

/// Reads a `.msh` or `.obj` mesh file.
pub fn read_mesh_file(path: &Path) -> Result<Mesh, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("msh") => crate::mesh::gmsh::read_msh(path).map_err(|e| e.to_string()),
        Some("obj") => crate::mesh::obj::read_obj(path).map_err(|e| e.to_string()),
        _ => Err("unknown mesh format: expected a .msh (Gmsh) or .obj file".into()),
    }
}

fn select(
    c: &Checker,
    mesh: &Mesh,
    table: &str,
    i: usize,
    at: Option<[f64; 3]>,
    within: &Option<BoxSpec>,
    boundary: Option<bool>,
) -> Result<Vec<usize>, ScenarioError> {
    let (lo, hi) = mesh.bounding_box();
    let size = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt();
    let mut nodes: Vec<usize> = (0..mesh.node_count()).collect();
    let mut any = false;
    if let Some(at) = at {
        c.finite(table, Some(i), "at", &at)?;
        nodes = vec![nearest(c, mesh, table, i, at, size)?];
        any = true;
    }
    if let Some(b) = within {
        c.finite(table, Some(i), "within", &b.min)?;
        c.finite(table, Some(i), "within", &b.max)?;
        let tol = 1e-9 * size;
        nodes.retain(|&n| {
            (0..3).all(|k| mesh.nodes[n][k] >= b.min[k] - tol && mesh.nodes[n][k] <= b.max[k] + tol)
        });
        any = true;
    }
    if boundary == Some(true) {
        let edge = mesh.boundary_nodes();
        nodes.retain(|n| edge.binary_search(n).is_ok());
        any = true;
    }
    if !any {
        return Err(c.invalid(
            table,
            Some(i),
            "at",
            "no node selector: give `at`, `within` or `boundary = true`".into(),
        ));
    }
    if nodes.is_empty() {
        return Err(c.invalid(
            table,
            Some(i),
            if within.is_some() {
                "within"
            } else {
                "boundary"
            },
            "selects no node".into(),
        ));
    }
    Ok(nodes)
}

fn build_fix(
    c: &Checker,
    mesh: &Mesh,
    i: usize,
    f: &FixSpec,
    fixed: &mut [bool],
) -> Result<(), ScenarioError> {
    let nodes = select(c, mesh, "fix", i, f.at, &f.within, f.boundary)?;
    let components = match &f.components {
        None => vec![0, 1, 2],
        Some(list) if list.is_empty() => {
            return Err(c.invalid(
                "fix",
                Some(i),
                "components",
                "must list at least one of \"x\", \"y\", \"z\"".into(),
            ));
        }
        Some(list) => list
            .iter()
            .map(|s| match s.as_str() {
                "x" => Ok(0),
                "y" => Ok(1),
                "z" => Ok(2),
                other => Err(c.invalid(
                    "fix",
                    Some(i),
                    "components",
                    format!("must be \"x\", \"y\" or \"z\", not {other:?}"),
                )),
            })
            .collect::<Result<_, _>>()?,
    };
    for n in nodes {
        for &k in &components {
            fixed[3 * n + k] = true;
        }
    }
    Ok(())
}

fn build_load(c: &Checker, mesh: &Mesh, i: usize, l: &LoadSpec) -> Result<Load, ScenarioError> {
    let t = "load";
    let ix = Some(i);
    if let Some(r) = l.ramp {
        c.positive(t, ix, "ramp", r)?;
    }
    let no_selector = |why: &str| -> Result<(), ScenarioError> {
        c.absent(t, ix, "at", &l.at, why)?;
        c.absent(t, ix, "within", &l.within, why)?;
        c.absent(t, ix, "boundary", &l.boundary, why)
    };
    let kind = match l.kind {
        LoadKindSpec::Surface => {
            no_selector("to a surface load")?;
            c.absent(t, ix, "value", &l.value, "to a surface load (use force)")?;
            c.absent(
                t,
                ix,
                "acceleration",
                &l.acceleration,
                "to a surface load (use force)",
            )?;
            let force = c.required(t, ix, "force", &l.force, "for a surface load (N/m^2)")?;
            c.finite(t, ix, "force", &force)?;
            LoadKind::Surface { force }
        }
        LoadKindSpec::Gravity => {
            no_selector("to gravity")?;
            c.absent(t, ix, "value", &l.value, "to gravity")?;
            let acceleration = match (l.force, l.acceleration) {
                (Some(_), Some(_)) => {
                    return Err(c.invalid(
                        t,
                        ix,
                        "acceleration",
                        "is given together with force: give one".into(),
                    ));
                }
                (Some(a), None) | (None, Some(a)) => a,
                (None, None) => {
                    return Err(c.invalid(
                        t,
                        ix,
                        "acceleration",
                        "is required for gravity (m/s^2), e.g. [0, 0, -9.8]".into(),
                    ));
                }
            };
            c.finite(t, ix, "acceleration", &acceleration)?;
            LoadKind::Gravity { acceleration }
        }
        LoadKindSpec::Pressure => {
            no_selector("to a pressure")?;
            c.absent(t, ix, "force", &l.force, "to a pressure (use value)")?;
            c.absent(
                t,
                ix,
                "acceleration",
                &l.acceleration,
                "to a pressure (use value)",
            )?;
            let value = c.required(t, ix, "value", &l.value, "for a pressure (Pa)")?;
            c.finite(t, ix, "value", &[value])?;
            LoadKind::Pressure { value }
        }
        LoadKindSpec::Nodal => {
            c.absent(t, ix, "value", &l.value, "to a nodal load (use force)")?;
            c.absent(
                t,
                ix,
                "acceleration",
                &l.acceleration,
                "to a nodal load (use force)",
            )?;
            let force = c.required(t, ix, "force", &l.force, "for a nodal load (N per node)")?;
            c.finite(t, ix, "force", &force)?;
            let nodes = select(c, mesh, t, i, l.at, &l.within, l.boundary)?;
            LoadKind::Nodal { nodes, force }
        }
    };
    Ok(Load { kind, ramp: l.ramp })
}
