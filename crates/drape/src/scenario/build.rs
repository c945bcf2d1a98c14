//! Checks a parsed [`Scenario`] and builds the model, schedule and monitors.

use super::analysis::build_analysis;
use super::cavity::build_cavities;
use super::check::Checker;
use super::contact::{build_contact, build_self_contact, check_initial_penetration};
use super::material::{build_bending, build_hysteresis, build_material};
use super::specimen::{make_wavy, specimen_of};
use super::{
    AnalysisKind, BoxSpec, Component, FixSpec, LoadKindSpec, LoadSpec, MAX_REFINE_LEVELS,
    MeshShape, MeshSpec, MonitorSpec, RefineAlso, RefineIndicator, RefineWhere, Scenario,
    ScenarioError, SolverSpec,
};
use crate::bending::BendingError;
use crate::input::{InputFile, fnv1a};
use crate::load::{Load, LoadKind};
use crate::mesh::{ElementOrder, MAX_MESH_NODES, Mesh, MeshReadError, generate};
use crate::model::{Model, ModelError};
use crate::setup::{Analysis, Monitor, Refine, Setup};
use crate::solver::NewtonSettings;
use std::path::{Path, PathBuf};

/// The largest coordinate a mesh node may have (m): a fabric is not a
/// continent, and beyond it the mesh's areas, masses and forces lose their
/// digits (a node at 1e17 m cannot tell 0.025 m apart) or overflow.
pub const MAX_COORDINATE: f64 = 1.0e6;

/// The largest elastic modulus (Pa): a thousand times diamond's. Beyond
/// it the membrane's forces and the Newton residual's norm overflow.
pub const MAX_MODULUS: f64 = 1.0e15;

impl Scenario {
    /// Checks every value and builds the [`Setup`]. `file` is the scenario's
    /// path (for messages and relative paths), `source` its text (for line
    /// numbers). The sections are checked in the order of the reference:
    /// mesh, material, loads, supports, contact, analysis, solver, output,
    /// monitors.
    pub fn build(&self, file: &Path, source: &str) -> Result<Setup, ScenarioError> {
        let c = Checker { file, source };
        let base = file.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut inputs = Vec::new();
        let mesh = build_mesh(&c, &self.mesh, &base, &mut inputs)?;
        let refine = build_refine(&c, self, &mesh)?;
        let mut setup = self.build_on(file, source, mesh, inputs, None)?;
        if let Some(r) = refine.filter(|r| r.resolution > 0.0)
            && setup.model.bending_length().is_none()
        {
            return Err(c.invalid(
                "refine",
                None,
                "resolution",
                format!(
                    "= {} counts elements per gravity bending length (B / w)^(1/3), and this fabric has none: it needs a bending rigidity (material.bending_rigidity, or [material.kes] B) and a weight (a gravity or surface load); leave resolution out without them",
                    r.resolution
                ),
            ));
        }
        setup.refine = refine;
        Ok(setup)
    }

    /// The setup of a finer level of the multilevel settle (`[refine]`):
    /// the scenario built on `mesh` — a refinement of its own mesh — by
    /// the one path every term follows (supports, loads and monitors
    /// selected again on it), as a static analysis of one load increment
    /// from the state carried over, which is near equilibrium at the full
    /// load (the material as statics has it). The inputs recorded are
    /// `inputs`, the coarse level's: the files a resume checks.
    ///
    /// # Errors
    /// What [`Scenario::build`] finds on this mesh (its size, a selector
    /// that selects nothing).
    pub fn build_level(
        &self,
        file: &Path,
        source: &str,
        mesh: Mesh,
        inputs: Vec<InputFile>,
    ) -> Result<Setup, ScenarioError> {
        let mut setup = self.build_on(file, source, mesh, Vec::new(), Some(1))?;
        setup.inputs = inputs;
        Ok(setup)
    }

    /// The setup on `mesh`; `statics`: a finer level's static settle in
    /// that many increments, whatever the scenario's analysis.
    fn build_on(
        &self,
        file: &Path,
        source: &str,
        mesh: Mesh,
        mut inputs: Vec<InputFile>,
        statics: Option<usize>,
    ) -> Result<Setup, ScenarioError> {
        let c = Checker { file, source };
        let base = file.parent().map(Path::to_path_buf).unwrap_or_default();
        let is_static = statics.is_some() || self.analysis.kind == AnalysisKind::Static;
        // A drape test's specimen: its warp cut and turned over now, its
        // mesh made wavy once the obstacles that hold it flat are known
        // (its loads, supports and monitors are selected on the plain mesh;
        // a finer level's mesh is refined from the wavy one, made wavy once).
        let specimen = specimen_of(&c, self, &mesh)?;
        let material_spec = (specimen.as_ref())
            .and_then(|s| s.2.as_ref())
            .unwrap_or(&self.material);
        let (material, section, density) = build_material(&c, material_spec, is_static)?;
        check_moduli(&c, material_spec)?;
        let bending = build_bending(&c, material_spec)?;
        let hysteresis = build_hysteresis(&c, material_spec, bending.as_ref())?;
        let loads = (self.loads.iter().enumerate())
            .map(|(i, l)| build_load(&c, &mesh, i, l))
            .collect::<Result<Vec<_>, _>>()?;
        let mut fixed = vec![false; 3 * mesh.node_count()];
        let mut clamped = vec![false; mesh.node_count()];
        for (i, f) in self.fixes.iter().enumerate() {
            build_fix(&c, &mesh, i, f, (&mut fixed, &mut clamped))?;
        }
        let contact = build_contact(&c, self, &base, &mut inputs)?;
        let self_contact = build_self_contact(&c, self)?;
        let cavities = build_cavities(&c, &self.cavities, &mesh, &fixed, is_static)?;
        if !cavities.is_empty() {
            if matches!(self.contact, Some(super::ContactSpec::Lagrange(_))) {
                return Err(c.invalid(
                    "contact",
                    None,
                    "method",
                    "= \"lagrange\" does not work with a [[cavity]]: the gas's rank-one tangent is not eliminated with the multipliers; use method = \"penalty\"".into(),
                ));
            }
            if self.refine.is_some() {
                return Err(c.invalid(
                    "refine",
                    None,
                    "levels",
                    "does not work with a [[cavity]] (a refined level does not carry the gas over yet)".into(),
                ));
            }
        }
        let (mut analysis, mut adaptive, mut rest) = build_analysis(&c, self)?;
        if let Some(steps) = statics {
            (analysis, adaptive, rest) = (Analysis::Static { steps, from: 0.0 }, None, None);
        }
        let mut newton = build_newton(&c, &self.solver)?;
        newton.projection = newton.projection.resolve(bending.is_some());
        if self.output.every == 0 {
            return Err(c.invalid("output", None, "every", "must be at least 1".into()));
        }
        let monitors = build_monitors(&c, &mesh, &self.monitors)?;
        let mut mesh = mesh;
        if let Some((p, plane, _)) = specimen.as_ref().filter(|_| statics.is_none()) {
            make_wavy(&mut mesh, p, plane, contact.as_ref());
        }
        check_memory(&c, &self.mesh, mesh.node_count())?;
        check_pattern_memory(&c, &self.mesh, &mesh, bending.is_some())?;

        let model = Model::builder(mesh, material, section, density)
            .loads(loads)
            .fixed(fixed)
            .clamped(clamped)
            .mass(self.analysis.mass)
            .contact(contact)
            .bending(bending)
            .bending_hysteresis(hysteresis)
            .membrane(self.mesh.membrane)
            .self_contact(self_contact)
            .cavities(cavities)
            .build()
            .map_err(|e| match e {
                ModelError::SelfContact(e) => {
                    c.invalid("contact", None, "self_distance", e.to_string())
                }
                ModelError::Axis(e) | ModelError::Bending(BendingError::Axis(e)) => {
                    c.invalid("material", None, "warp_direction", e.to_string())
                }
                ModelError::Bending(e) => c.invalid(
                    "material",
                    None,
                    "bending_rigidity",
                    format!("cannot be set up on this mesh: {e}"),
                ),
                error => ScenarioError::Mesh {
                    file: file.to_path_buf(),
                    error,
                },
            })?;
        if let Some(contact) = model.contact() {
            check_initial_penetration(&c, model.mesh(), contact)?;
        }
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
            newton,
            max_cutbacks: self.solver.max_cutbacks,
            output_every: self.output.every,
            monitors,
            checkpoint_every: self.output.checkpoint_every,
            linear: self.solver.linear,
            scenario_path: std::fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf()),
            scenario_hash: fnv1a(source.as_bytes()),
            inputs,
            refine: None,
        })
    }
}

/// `[refine]`, each key in its range; refinement splits linear triangles
/// only.
fn build_refine(c: &Checker, s: &Scenario, mesh: &Mesh) -> Result<Option<Refine>, ScenarioError> {
    let Some(r) = &s.refine else {
        return Ok(None);
    };
    let t = "refine";
    if !(1..=MAX_REFINE_LEVELS).contains(&r.levels) {
        return Err(c.invalid(
            t,
            None,
            "levels",
            format!(
                "must be 1 to {MAX_REFINE_LEVELS} (each level splits a triangle into four), not {}",
                r.levels
            ),
        ));
    }
    if !(r.tolerance.is_finite() && r.tolerance >= 0.0) {
        return Err(c.invalid(
            t,
            None,
            "tolerance",
            format!(
                "must be a drape coefficient change >= 0, not {}",
                r.tolerance
            ),
        ));
    }
    if !(r.resolution.is_finite() && r.resolution >= 0.0) {
        return Err(c.invalid(
            t,
            None,
            "resolution",
            format!(
                "must be a number of elements per bending length >= 0 (0: none asked), not {}",
                r.resolution
            ),
        ));
    }
    if !(r.fraction > 0.0 && r.fraction <= 1.0) {
        return Err(c.invalid(
            t,
            None,
            "fraction",
            format!(
                "must be in (0, 1] (the share of the curvature indicator the split triangles hold), not {}",
                r.fraction
            ),
        ));
    }
    if mesh.order != ElementOrder::Linear && r.region != RefineWhere::All {
        return Err(c.invalid(
            t,
            None,
            "where",
            format!(
                "refinement along the folds splits linear triangles, and this mesh has order {} (mesh.order): refine it everywhere (where = \"all\"), or refine a linear mesh along the folds",
                mesh.order.degree()
            ),
        ));
    }
    Ok(Some(Refine {
        levels: r.levels,
        uniform: r.region == RefineWhere::All,
        tolerance: r.tolerance,
        resolution: r.resolution,
        fraction: r.fraction,
        chord: r.indicator == RefineIndicator::Chord,
        rim: r.also.contains(&RefineAlso::Rim),
        contact_line: r.also.contains(&RefineAlso::Contact),
    }))
}

/// The scenario `table`'s file paths (`mesh.path` and each
/// `obstacle[i].path`) joined to `folder` where relative, so that its
/// text means the same wherever it is saved (a Python dict's scenario, a
/// sweep's case, a drape test's specimen).
pub fn absolute_paths(table: &mut toml::Table, folder: &Path) {
    let join = |value: Option<&mut toml::Value>| {
        if let Some(toml::Value::String(path)) = value
            && Path::new(path.as_str()).is_relative()
        {
            *path = folder.join(path.as_str()).to_string_lossy().into_owned();
        }
    };
    if let Some(toml::Value::Table(mesh)) = table.get_mut("mesh") {
        join(mesh.get_mut("path"));
    }
    if let Some(toml::Value::Array(obstacles)) = table.get_mut("obstacle") {
        for obstacle in obstacles {
            if let toml::Value::Table(obstacle) = obstacle {
                join(obstacle.get_mut("path"));
            }
        }
    }
}

/// `[solver]`: Newton's settings, each in its range (`linear` and
/// `max_cutbacks`, once checked, are taken as they are).
fn build_newton(c: &Checker, s: &SolverSpec) -> Result<NewtonSettings, ScenarioError> {
    let t = "solver";
    if !(s.tolerance.is_finite() && s.tolerance > 0.0 && s.tolerance < 1.0) {
        return Err(c.invalid(
            t,
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
            t,
            None,
            "residual_tolerance",
            format!("must lie in (0, 1), not {}", s.residual_tolerance),
        ));
    }
    if s.max_iterations == 0 {
        return Err(c.invalid(t, None, "max_iterations", "must be at least 1".into()));
    }
    if s.max_cutbacks > 30 {
        return Err(c.invalid(
            t,
            None,
            "max_cutbacks",
            format!("must be at most 30, not {}", s.max_cutbacks),
        ));
    }
    if let Some(v) = s.speed_tolerance
        && !(v.is_finite() && v > 0.0)
    {
        return Err(c.invalid(
            t,
            None,
            "speed_tolerance",
            format!("must be a speed above 0 m/s, not {v}"),
        ));
    }
    if s.chord_steps > 10 {
        return Err(c.invalid(
            t,
            None,
            "chord_steps",
            format!("must be at most 10, not {}", s.chord_steps),
        ));
    }
    Ok(NewtonSettings {
        tolerance: s.tolerance,
        residual_tolerance: s.residual_tolerance,
        max_iterations: s.max_iterations,
        chord_steps: s.chord_steps,
        projection: s.projection,
        speed_tolerance: s.speed_tolerance,
        dt: None,
    })
}

/// `[[monitor]]`: each name valid and unique, each node near its `at`.
fn build_monitors(
    c: &Checker,
    mesh: &Mesh,
    specs: &[MonitorSpec],
) -> Result<Vec<Monitor>, ScenarioError> {
    let size = mesh.diagonal();
    let mut monitors = Vec::new();
    for (i, mon) in specs.iter().enumerate() {
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
        let node = nearest(c, mesh, "monitor", i, mon.at, size)?;
        monitors.push(Monitor {
            name: mon.name.clone(),
            node,
        });
    }
    Ok(monitors)
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

/// `[mesh]`; a file mesh is recorded in `inputs`.
fn build_mesh(
    c: &Checker,
    spec: &MeshSpec,
    base: &Path,
    inputs: &mut Vec<InputFile>,
) -> Result<Mesh, ScenarioError> {
    let order = match spec.order {
        None => None,
        Some(p) => Some(ElementOrder::from_degree(p).ok_or_else(|| {
            c.invalid("mesh", None, "order", format!("must be 1, 2 or 3, not {p}"))
        })?),
    };
    let center = spec.center.unwrap_or([0.0; 3]);
    c.finite("mesh", None, "center", &center)?;
    let mesh = match spec.shape {
        MeshShape::Rectangle => rectangle_mesh(c, spec, order, center)?,
        MeshShape::Disc => disc_mesh(c, spec, order, center)?,
        MeshShape::Sphere => sphere_mesh(c, spec, order, center)?,
        MeshShape::File => file_mesh(c, spec, order, base, inputs)?,
    };
    // The generators are refused from their counts before they generate,
    // a file by its reader before it reads more nodes than the cap. A file
    // is validated as it is read (`file_mesh`), a generated mesh is valid
    // by construction, and the model's builder checks again.
    check_extent(c, spec, &mesh)?;
    Ok(mesh)
}

/// Every node within [`MAX_COORDINATE`] of the origin, else an error of
/// the key that put it there: `mesh.center` (when it is that far itself),
/// `mesh.size` or `mesh.radius`, or the file's node and coordinate.
fn check_extent(c: &Checker, spec: &MeshSpec, mesh: &Mesh) -> Result<(), ScenarioError> {
    let far = |x: &f64| x.abs() > MAX_COORDINATE;
    let Some((node, x)) = mesh
        .nodes
        .iter()
        .enumerate()
        .find(|(_, x)| x.iter().any(far))
    else {
        return Ok(());
    };
    let bound = format!("{MAX_COORDINATE:e} m, the largest coordinate a mesh may have");
    let center = spec.center.unwrap_or([0.0; 3]);
    let (key, message) = match spec.shape {
        _ if center.iter().any(far) => (
            "center",
            format!("{center:?} lies beyond {bound}; move the problem near the origin"),
        ),
        MeshShape::Rectangle => (
            "size",
            format!(
                "{:?} puts nodes beyond {bound} (node {node} at {x:?})",
                spec.size.unwrap_or_default()
            ),
        ),
        MeshShape::Disc | MeshShape::Sphere => (
            "radius",
            format!(
                "{:e} puts nodes beyond {bound} (node {node} at {x:?})",
                spec.radius.unwrap_or_default()
            ),
        ),
        MeshShape::File => (
            "path",
            format!(
                "{}: node {node} (0-based, in the order read) at {x:?} lies beyond {bound}; is the file in metres?",
                spec.path.as_deref().unwrap_or(Path::new("")).display(),
            ),
        ),
    };
    Err(c.invalid("mesh", None, key, message))
}

/// The memory a run of `nodes` nodes needs ([`crate::memory::estimate`])
/// against what the process may have ([`crate::memory::available`]),
/// before the model's large allocations: over it, the mesh's key is
/// refused with both figures.
fn check_memory(c: &Checker, spec: &MeshSpec, nodes: usize) -> Result<(), ScenarioError> {
    let need = crate::memory::estimate(nodes);
    let Some((have, what)) = crate::memory::available() else {
        return Ok(());
    };
    if need <= have {
        return Ok(());
    }
    Err(c.invalid(
        "mesh",
        None,
        mesh_size_key(spec),
        format!(
            "{nodes} nodes need about {:.0} MB to run ({} bytes a node), more than the {:.0} MB {what}; use a coarser mesh or a larger machine",
            megabytes(need),
            crate::memory::BYTES_PER_NODE,
            megabytes(have)
        ),
    ))
}

/// The memory the Hessian's pattern needs ([`crate::memory::pattern_estimate`]
/// of its blocks: the elements', and the bending patches' stencils with
/// `bending`) against what the process may still allocate
/// ([`crate::memory::headroom`]), before the model allocates it: over it,
/// the mesh's key is refused with both figures. The pattern depends on the
/// elements' order and on bending (its stencils reach the nodes opposite a
/// triangle's edges), so it may not fit where the mesh's estimate did. A
/// bound of the blocks (every stencil's square) passes most meshes at
/// once; the exact count, which walks the mesh's topology, is made only
/// when the bound does not fit. A mesh whose bending stencils cannot be
/// found (a non-manifold edge) is left to the model, which says why.
fn check_pattern_memory(
    c: &Checker,
    spec: &MeshSpec,
    mesh: &Mesh,
    bending: bool,
) -> Result<(), ScenarioError> {
    use crate::memory::{BYTES_PER_BLOCK, headroom, pattern_estimate};
    let Some((have, what)) = headroom() else {
        return Ok(());
    };
    let n = mesh.order.nodes_per_element();
    let sub_triangles = mesh.element_count() * mesh.order.degree().pow(2);
    // A bending patch's blocks: the square of its most nodes.
    let patch_blocks = crate::bending::kernel::MAX_NODES.pow(2);
    let bound = mesh.node_count()
        + mesh.element_count() * n * n
        + usize::from(bending) * patch_blocks * sub_triangles;
    if pattern_estimate(bound) <= have {
        return Ok(());
    }
    let nodes = mesh.node_count();
    let (ptr, stencil_nodes) = if bending {
        let Ok(stencils) = crate::bending::stencils_of(mesh) else {
            return Ok(());
        };
        stencils
    } else {
        (vec![0], Vec::new())
    };
    let stencils = ptr.windows(2).map(|w| &stencil_nodes[w[0]..w[1]]);
    let blocks = crate::solver::pattern::block_count(nodes, mesh.elements().chain(stencils));
    let need = pattern_estimate(blocks);
    if need <= have {
        return Ok(());
    }
    let stencils = if bending {
        ", with bending's stencils"
    } else {
        ""
    };
    Err(c.invalid(
        "mesh",
        None,
        mesh_size_key(spec),
        format!(
            "the Hessian's sparse pattern of these {nodes} nodes (order {}{stencils}) has {blocks} blocks of 3x3 and needs about {:.0} MB for its values and indices ({BYTES_PER_BLOCK} bytes a block, before the linear solver's factor), more than the {:.0} MB {what}; use a coarser mesh, a lower order or a larger machine",
            mesh.order.degree(),
            megabytes(need),
            megabytes(have)
        ),
    ))
}

/// The `[mesh]` key that sets the mesh's size: `divisions`, `rings` or
/// `path`.
fn mesh_size_key(spec: &MeshSpec) -> &'static str {
    match spec.shape {
        MeshShape::Rectangle => "divisions",
        MeshShape::Disc => "rings",
        MeshShape::Sphere => "subdivisions",
        MeshShape::File => "path",
    }
}

/// Bytes in MB (10^6), for messages.
fn megabytes(bytes: u64) -> f64 {
    bytes as f64 / 1e6
}

/// `[material]` moduli at most [`MAX_MODULUS`] (their positivity is
/// checked where the material is built).
fn check_moduli(c: &Checker, m: &super::MaterialSpec) -> Result<(), ScenarioError> {
    for (key, value) in [
        ("youngs_modulus", m.youngs_modulus),
        ("warp_modulus", m.warp_modulus),
        ("weft_modulus", m.weft_modulus),
        ("shear_modulus", m.shear_modulus),
    ] {
        if let Some(v) = value.filter(|v| *v > MAX_MODULUS) {
            return Err(c.invalid(
                "material",
                None,
                key,
                format!(
                    "{v:e} Pa is above {MAX_MODULUS:e} Pa (a thousand times diamond's modulus), beyond which the membrane's forces overflow; is it in Pa?"
                ),
            ));
        }
    }
    Ok(())
}

/// `[mesh] shape = "rectangle"`: `size` and `divisions`, at most
/// [`MAX_MESH_NODES`] nodes.
fn rectangle_mesh(
    c: &Checker,
    spec: &MeshSpec,
    order: Option<ElementOrder>,
    center: [f64; 3],
) -> Result<Mesh, ScenarioError> {
    let t = "mesh";
    c.none_of(
        t,
        None,
        &[
            ("radius", spec.radius.is_some()),
            ("rings", spec.rings.is_some()),
            ("subdivisions", spec.subdivisions.is_some()),
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
    if nodes > MAX_MESH_NODES {
        return Err(c.invalid(
            t,
            None,
            "divisions",
            format!("{div:?} would make {nodes} nodes, more than the limit {MAX_MESH_NODES}"),
        ));
    }
    Ok(generate::rectangle(
        size,
        div,
        spec.pattern.unwrap_or(generate::Pattern::Right),
        center,
        order.unwrap_or(ElementOrder::Linear),
    ))
}

/// `[mesh] shape = "disc"`: `radius` and `rings`, at most
/// [`MAX_MESH_NODES`] nodes.
fn disc_mesh(
    c: &Checker,
    spec: &MeshSpec,
    order: Option<ElementOrder>,
    center: [f64; 3],
) -> Result<Mesh, ScenarioError> {
    let t = "mesh";
    c.none_of(
        t,
        None,
        &[
            ("size", spec.size.is_some()),
            ("divisions", spec.divisions.is_some()),
            ("pattern", spec.pattern.is_some()),
            ("path", spec.path.is_some()),
            ("subdivisions", spec.subdivisions.is_some()),
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
    // Ring k of node rings has 6k nodes: 1 + 3 n (n + 1) nodes for n = p
    // rings of nodes per ring of elements.
    let disc_nodes = |rings: usize| {
        let n = rings.saturating_mul(p);
        n.saturating_mul(n.saturating_add(1))
            .saturating_mul(3)
            .saturating_add(1)
    };
    let nodes = disc_nodes(rings);
    if rings == 0 || nodes > MAX_MESH_NODES {
        let mut most = ((MAX_MESH_NODES / (3 * p * p)) as f64).sqrt() as usize;
        while disc_nodes(most) > MAX_MESH_NODES {
            most -= 1;
        }
        let why = if rings == 0 {
            String::new()
        } else {
            format!(" ({nodes} nodes, more than the limit {MAX_MESH_NODES})")
        };
        return Err(c.invalid(
            t,
            None,
            "rings",
            format!("must lie in 1..={most}, not {rings}{why}"),
        ));
    }
    Ok(generate::disc(
        radius,
        rings,
        center,
        order.unwrap_or(ElementOrder::Linear),
    ))
}

/// The most times a sphere's icosahedron may be subdivided: 81,920
/// triangles, 40,962 nodes of order 1.
const MAX_SUBDIVISIONS: usize = 6;

/// `[mesh] shape = "sphere"`: a closed sphere (`generate::sphere`).
fn sphere_mesh(
    c: &Checker,
    spec: &MeshSpec,
    order: Option<ElementOrder>,
    center: [f64; 3],
) -> Result<Mesh, ScenarioError> {
    let t = "mesh";
    c.none_of(
        t,
        None,
        &[
            ("size", spec.size.is_some()),
            ("divisions", spec.divisions.is_some()),
            ("pattern", spec.pattern.is_some()),
            ("path", spec.path.is_some()),
            ("rings", spec.rings.is_some()),
        ],
        "to shape = \"sphere\"",
    )?;
    let radius = c.positive(
        t,
        None,
        "radius",
        c.required(
            t,
            None,
            "radius",
            &spec.radius,
            "for shape = \"sphere\" (m)",
        )?,
    )?;
    let subdivisions = c.required(
        t,
        None,
        "subdivisions",
        &spec.subdivisions,
        "for shape = \"sphere\"",
    )?;
    if subdivisions > MAX_SUBDIVISIONS {
        return Err(c.invalid(
            t,
            None,
            "subdivisions",
            format!("must lie in 0..={MAX_SUBDIVISIONS}, not {subdivisions}"),
        ));
    }
    Ok(generate::sphere(
        radius,
        subdivisions,
        center,
        order.unwrap_or(ElementOrder::Linear),
    ))
}

/// `[mesh] shape = "file"`: read and validated, its order the given one
/// if any.
fn file_mesh(
    c: &Checker,
    spec: &MeshSpec,
    order: Option<ElementOrder>,
    base: &Path,
    inputs: &mut Vec<InputFile>,
) -> Result<Mesh, ScenarioError> {
    let t = "mesh";
    c.none_of(
        t,
        None,
        &[
            ("size", spec.size.is_some()),
            ("divisions", spec.divisions.is_some()),
            ("pattern", spec.pattern.is_some()),
            ("radius", spec.radius.is_some()),
            ("rings", spec.rings.is_some()),
            ("subdivisions", spec.subdivisions.is_some()),
            ("center", spec.center.is_some()),
        ],
        "to shape = \"file\"",
    )?;
    let rel = c.required(t, None, "path", &spec.path, "for shape = \"file\"")?;
    let path: PathBuf = base.join(&rel);
    let (mesh, bytes) =
        read_mesh_file_bytes(&path).map_err(|e| c.invalid(t, None, "path", e.to_string()))?;
    inputs.push(InputFile::new("mesh.path".into(), &path, &bytes));
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
    Ok(mesh)
}

/// Reads a `.msh` (Gmsh) or `.obj` (Wavefront) mesh file, by its
/// extension.
pub fn read_mesh_file(path: &Path) -> Result<Mesh, MeshReadError> {
    read_mesh_file_bytes(path).map(|(mesh, _)| mesh)
}

/// [`read_mesh_file`], with the file's bytes as read (their hash is
/// recorded, for a resume to tell a changed file).
fn read_mesh_file_bytes(path: &Path) -> Result<(Mesh, Vec<u8>), MeshReadError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let parse = match ext.as_deref() {
        Some("msh") => crate::mesh::gmsh::parse_msh,
        Some("obj") => crate::mesh::obj::parse_obj,
        _ => {
            return Err(MeshReadError::UnknownFormat {
                file: path.display().to_string(),
            });
        }
    };
    let (bytes, file) = MeshReadError::read(path)?;
    let mesh = parse(&bytes, &file)?;
    Ok((mesh, bytes))
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
    let size = mesh.diagonal();
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

/// `[[fix]]` number `i` into `fixed` (per component) and, with `clamp =
/// true`, `clamped` (per node).
fn build_fix(
    c: &Checker,
    mesh: &Mesh,
    i: usize,
    f: &FixSpec,
    (fixed, clamped): (&mut [bool], &mut [bool]),
) -> Result<(), ScenarioError> {
    let nodes = select(c, mesh, "fix", i, f.at, &f.within, f.boundary)?;
    let components = match &f.components {
        None => &[Component::X, Component::Y, Component::Z][..],
        Some(list) if list.is_empty() => {
            return Err(c.invalid(
                "fix",
                Some(i),
                "components",
                "must list at least one of \"x\", \"y\", \"z\"".into(),
            ));
        }
        Some(list) => list,
    };
    let clamp = f.clamp.unwrap_or(false);
    let all = [Component::X, Component::Y, Component::Z];
    if clamp && !all.iter().all(|k| components.contains(k)) {
        let names: Vec<&str> = components
            .iter()
            .map(|k| ["x", "y", "z"][k.index()])
            .collect();
        return Err(c.invalid(
            "fix",
            Some(i),
            "clamp",
            format!(
                "= true needs the nodes held in all three components (a clamp holds the fabric's position and its slope), but components = {names:?}; drop `components` or `clamp`"
            ),
        ));
    }
    for n in nodes {
        for k in components {
            fixed[3 * n + k.index()] = true;
        }
        clamped[n] |= clamp;
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
