//! The discrete model: mesh, element geometry, material, mass, loads and
//! supports, with the parallel assembly of forces and the Hessian.
//!
//! Degrees of freedom are the nodal positions, `3a + i` for component `i`
//! of node `a`. Fixed components are eliminated: their rows and columns of
//! the Hessian are replaced by the identity and their residual by zero, so
//! their increment is exactly zero (no penalty).

mod assemble;

pub use assemble::ElementResults;
mod mass;

pub use mass::MassKind;

use crate::bending::hysteresis::Hysteresis;
use crate::bending::{Bending, BendingRigidity};
use crate::contact::features::ObstacleFeatures;
use crate::contact::self_contact::{SelfContact, SelfContactSpec};
use crate::contact::{ContactMethod, ContactModel};
use crate::element::ElementGeometry;
use crate::element::geometry::MembraneIntegration;
use crate::element::membrane::Section;
use crate::load::gas::GasCavity;
use crate::load::pressure::PressureQuadrature;
use crate::load::{Load, LoadKind};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::quadrature::QuadratureRule;
use crate::solver::SparsePattern;
use crate::solver::pattern::colour_elements;
use crate::solver::pattern::{ASSEMBLY_LEAF, Halves};

/// Everything that defines the discrete problem, independent of time.
///
/// Built in one step by [`ModelBuilder::build`] ([`Model::builder`]), and
/// read-only afterwards: the sparse pattern, the element blocks' places in
/// it, the bending patches' places and the mass matrix on it are made
/// together from the mesh, the bending stencils and the mass's kind, and
/// none of them can change without the others.
#[derive(Debug)]
pub struct Model {
    /// The reference mesh.
    mesh: Mesh,
    /// Element geometry at the stiffness quadrature points.
    geometry: ElementGeometry,
    /// Constitutive model.
    material: Box<dyn Material>,
    /// Thickness and prestress.
    section: Section,
    /// Mass density `rho` (kg/m^3).
    density: f64,
    /// External loads.
    loads: Vec<Load>,
    /// `fixed[3a + i]`: component `i` of node `a` is held at its initial value.
    fixed: Vec<bool>,
    /// How the mass matrix is built.
    mass_kind: MassKind,
    /// Sparsity pattern of the Hessian.
    pattern: SparsePattern,
    /// Where the element blocks start in the Hessian's values: for block
    /// `(a, b)` of element `e`, at `n^2 e + n a + b`, the value index of
    /// its entry (0, 0) ([`SparsePattern::block_layout`] of its node-graph
    /// position, [`SparsePattern::element_blocks`]).
    element_blocks: Vec<usize>,
    /// Whether element block `n^2 e + n a + b` is the first to be added
    /// into its Hessian block in the assembly's order (colour by colour):
    /// it then writes its values rather than adding them, and the Hessian
    /// is not zeroed first.
    element_block_first: Vec<bool>,
    /// Layouts `(base, stride)` ([`SparsePattern::block_layout`]) of the
    /// Hessian blocks no element adds into (the diagonal blocks of nodes
    /// outside every element), zeroed at each assembly.
    untouched_blocks: Vec<(usize, usize)>,
    /// The order of the assembly ([`Model::assemble`]): two halves of the
    /// mesh that share no node, one per thread, then the elements at
    /// their interface by colour; from [`PARALLEL_ABOVE`] elements on,
    /// each half split again into parts of fewer than [`ASSEMBLY_LEAF`]
    /// elements, on rayon's pool.
    halves: Halves,
    /// Mass matrix on the node graph, `M^ab = m[p_ab] I3` (kg).
    mass: Vec<f64>,
    /// `integral phi^a dA0` per node (m^2): consistent dead surface loads.
    area_weights: Vec<f64>,
    /// Pressure quadrature (shared by all elements).
    pressure_quadrature: PressureQuadrature,
    /// Rigid obstacles and contact enforcement, if any.
    contact: Option<ContactModel>,
    /// Bending stiffness, if any, attached to `pattern`.
    bending: Option<Bending>,
    /// Bending hysteresis, if any (with bending only).
    hysteresis: Option<Hysteresis>,
    /// Self-contact, if any.
    self_contact: Option<SelfContact>,
    /// The obstacles' sharp features kept out of the triangles, if any.
    features: Option<ObstacleFeatures>,
    /// The cavities filled with gas (none: no gas term).
    cavities: Vec<GasCavity>,
}

/// The parts of a [`Model`] ([`Model::builder`]), built into it at once by
/// [`ModelBuilder::build`]. Mesh, material, section and density are
/// required; the rest defaults to no loads, no supports, a consistent
/// mass, no contact and no bending.
#[derive(Debug)]
#[must_use = "a model builder does nothing until `build` is called"]
pub struct ModelBuilder {
    mesh: Mesh,
    material: Box<dyn Material>,
    section: Section,
    density: f64,
    loads: Vec<Load>,
    fixed: Vec<bool>,
    mass_kind: MassKind,
    contact: Option<ContactModel>,
    bending: Option<BendingRigidity>,
    hysteresis: Option<Hysteresis>,
    clamped: Vec<bool>,
    self_contact: Option<SelfContactSpec>,
    membrane: MembraneIntegration,
    cavities: Vec<GasCavity>,
}

impl ModelBuilder {
    /// The cavities filled with gas (default none), built on this
    /// builder's mesh.
    pub fn cavities(mut self, cavities: Vec<GasCavity>) -> Self {
        self.cavities = cavities;
        self
    }

    /// Where curved elements measure their membrane strain (default
    /// [`MembraneIntegration::Auto`]: on their sub-triangles with bending,
    /// on their own interpolation without).
    pub fn membrane(mut self, membrane: MembraneIntegration) -> Self {
        self.membrane = membrane;
        self
    }

    /// External loads.
    pub fn loads(mut self, loads: Vec<Load>) -> Self {
        self.loads = loads;
        self
    }

    /// Supports: `fixed[3a + i]` holds component `i` of node `a` at its
    /// initial value (missing entries are free).
    pub fn fixed(mut self, fixed: Vec<bool>) -> Self {
        self.fixed = fixed;
        self
    }

    /// How the mass matrix is built (default [`MassKind::Consistent`]).
    pub fn mass(mut self, kind: MassKind) -> Self {
        self.mass_kind = kind;
        self
    }

    /// Rigid obstacles and how contact with them is enforced, if any.
    pub fn contact(mut self, contact: impl Into<Option<ContactModel>>) -> Self {
        self.contact = contact.into();
        self
    }

    /// Bending stiffness of `rigidity`, if any (docs/theory.md §1.10): its
    /// patches are fitted on the reference mesh and their stencils join
    /// the Hessian's pattern (the couplings between a triangle's nodes and
    /// the nodes opposite its edges).
    pub fn bending(mut self, rigidity: impl Into<Option<BendingRigidity>>) -> Self {
        self.bending = rigidity.into();
        self
    }

    /// Bending hysteresis, if any ([`crate::bending::hysteresis`]): the
    /// frictional moment of the bending patches (ignored without
    /// bending).
    pub fn bending_hysteresis(mut self, hysteresis: Option<Hysteresis>) -> Self {
        self.hysteresis = hysteresis;
        self
    }

    /// Self-contact, if any ([`crate::contact::self_contact`]): on the
    /// mesh's (sub-)triangles.
    pub fn self_contact(mut self, spec: Option<SelfContactSpec>) -> Self {
        self.self_contact = spec;
        self
    }

    /// Clamps (`[[fix]] clamp = true`): `clamped[a]` marks node `a`, held
    /// in all three components, whose slope the bending patches hold too
    /// ([`crate::bending`]; missing entries are not clamped). Nothing
    /// without bending.
    pub fn clamped(mut self, clamped: Vec<bool>) -> Self {
        self.clamped = clamped;
        self
    }

    /// Builds the model. The mesh is validated first, then the element
    /// geometry (in the material's axes), the bending patches, the sparse
    /// pattern of the elements and patches with the assembly's layout on
    /// it, and the mass matrix.
    pub fn build(self) -> Result<Model, ModelError> {
        let Self {
            mesh,
            material,
            section,
            density,
            loads,
            mut fixed,
            mass_kind,
            contact,
            bending,
            hysteresis,
            clamped,
            self_contact,
            membrane,
            cavities,
        } = self;
        mesh.validate()?;
        let self_contact = match self_contact {
            Some(spec) => Some(
                SelfContact::new(
                    crate::bending::triangulate(&mesh).0,
                    &mesh.nodes.concat(),
                    spec.distance,
                    spec.stiffness,
                )?
                .with_friction(spec.friction, spec.stick_speed),
            ),
            None => None,
        };
        let features = contact
            .as_ref()
            .filter(|c| c.features && matches!(c.method, ContactMethod::Penalty { .. }))
            .and_then(|c| {
                ObstacleFeatures::new(
                    c,
                    crate::bending::triangulate(&mesh).0,
                    &mesh.nodes.concat(),
                )
            });
        let p = mesh.order.degree();
        let geometry = match membrane.resolve(bending.is_some()) {
            MembraneIntegration::SubTriangles if p > 1 => ElementGeometry::on_sub_triangles(
                &mesh,
                &crate::bending::triangulate(&mesh).0,
                material.axis(),
            )?,
            _ => ElementGeometry::with_axis(
                &mesh,
                &QuadratureRule::of_degree(4 * (p - 1)),
                material.axis(),
            )?,
        };
        let colours = colour_elements(mesh.node_count(), mesh.elements());
        let parallel = parallel_for(&mesh);
        let halves = if parallel {
            Halves::nested(&mesh.nodes, mesh.elements(), &colours, ASSEMBLY_LEAF)
        } else {
            Halves::of(&mesh.nodes, mesh.elements(), &colours)
        };
        let mut bending = match bending {
            Some(rigidity) => Some(Bending::new(&mesh, rigidity, &clamped)?),
            None => None,
        };
        let layout = Layout::new(&mesh, &halves, bending.as_ref());
        if let Some(b) = &mut bending {
            b.attach(&layout.pattern, parallel, &mesh.nodes);
        }
        let mass = mass::assemble_mass(
            &mesh,
            &layout.pattern,
            density * section.thickness,
            mass_kind,
        )?;
        let area_weights = mass::area_weights(&mesh);
        let pressure_quadrature = PressureQuadrature::new(mesh.order);
        fixed.resize(3 * mesh.node_count(), false);
        Ok(Model {
            mesh,
            geometry,
            material,
            section,
            density,
            loads,
            fixed,
            mass_kind,
            pattern: layout.pattern,
            element_blocks: layout.element_blocks,
            element_block_first: layout.element_block_first,
            untouched_blocks: layout.untouched_blocks,
            halves,
            mass,
            area_weights,
            pressure_quadrature,
            contact,
            hysteresis: hysteresis.filter(|_| bending.is_some()),
            bending,
            self_contact,
            features,
            cavities,
        })
    }
}

/// Where the Hessian's entries are and which element blocks write first:
/// everything that depends on the pattern.
struct Layout {
    pattern: SparsePattern,
    element_blocks: Vec<usize>,
    element_block_first: Vec<bool>,
    untouched_blocks: Vec<(usize, usize)>,
}

impl Layout {
    /// The layout of `mesh`'s elements assembled in the order of
    /// `halves`, on a pattern that also holds `bending`'s stencils.
    fn new(mesh: &Mesh, halves: &Halves, bending: Option<&Bending>) -> Self {
        let pattern = match bending {
            None => SparsePattern::new(mesh.node_count(), mesh.elements()),
            Some(b) => SparsePattern::new(mesh.node_count(), mesh.elements().chain(b.stencils())),
        };
        let positions = pattern.element_blocks(mesh.elements());
        let element_blocks: Vec<usize> = {
            let n = mesh.order.nodes_per_element();
            mesh.elements()
                .zip(positions.chunks(n * n))
                .flat_map(|(el, p)| (0..n * n).map(move |ab| (p[ab], el[ab % n])))
                .map(|(p, b)| pattern.block_layout(p, b).0)
                .collect()
        };
        let (element_block_first, untouched_blocks) = {
            let n2 = mesh.order.nodes_per_element().pow(2);
            let mut first = vec![false; element_blocks.len()];
            // Blocks by node-graph position.
            let (ptr, _) = pattern.node_graph();
            let mut touched = vec![false; ptr[mesh.node_count()]];
            // The assembly's order (see `Model::assemble`).
            for e in halves.order() {
                for k in n2 * e..n2 * (e + 1) {
                    first[k] = !touched[positions[k]];
                    touched[positions[k]] = true;
                }
            }
            let untouched = (0..mesh.node_count())
                .flat_map(|b| (ptr[b]..ptr[b + 1]).map(move |p| (p, b)))
                .filter(|&(p, _)| !touched[p])
                .map(|(p, b)| pattern.block_layout(p, b))
                .collect();
            (first, untouched)
        };
        Self {
            pattern,
            element_blocks,
            element_block_first,
            untouched_blocks,
        }
    }
}

/// Why a model cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// The mesh is unusable.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// Bending cannot be set up on the mesh.
    #[error(transparent)]
    Bending(#[from] crate::bending::BendingError),
    /// The material's axis (the warp) is normal to an element.
    #[error(transparent)]
    Axis(#[from] crate::element::geometry::AxisError),
    /// Self-contact's distance is larger than the initial mesh allows.
    #[error(transparent)]
    SelfContact(#[from] crate::contact::self_contact::TooClose),
    /// A lumped mass came out non-positive at a node.
    #[error("the lumped mass of node {node} is {mass:e} kg (not positive)")]
    NonPositiveMass {
        /// Node index.
        node: usize,
        /// Its lumped mass.
        mass: f64,
    },
}

/// Meshes with fewer elements run their loops on one thread
/// ([`Model::parallel`]).
pub const PARALLEL_ABOVE: usize = 4096;

/// Whether a model of `mesh` assembles on rayon's pool ([`Model::parallel`]).
fn parallel_for(mesh: &Mesh) -> bool {
    mesh.element_count() >= PARALLEL_ABOVE
}

impl Model {
    /// The parts of a model over `mesh` of `material`, with `section` and
    /// mass density `density` (kg/m^3); [`ModelBuilder::build`] makes it.
    pub fn builder(
        mesh: Mesh,
        material: Box<dyn Material>,
        section: Section,
        density: f64,
    ) -> ModelBuilder {
        ModelBuilder {
            mesh,
            material,
            section,
            density,
            loads: Vec::new(),
            fixed: Vec::new(),
            mass_kind: MassKind::Consistent,
            contact: None,
            bending: None,
            hysteresis: None,
            clamped: Vec::new(),
            self_contact: None,
            membrane: MembraneIntegration::Auto,
            cavities: Vec::new(),
        }
    }

    /// The cavities filled with gas.
    pub fn cavities(&self) -> &[GasCavity] {
        &self.cavities
    }

    /// Where element `e`'s `n x n` blocks start in the Hessian's values
    /// (row-major in `(a, b)`: see the field `element_blocks`).
    pub(crate) fn element_bases(&self, e: usize) -> &[usize] {
        let n2 = self.mesh.order.nodes_per_element().pow(2);
        &self.element_blocks[n2 * e..n2 * (e + 1)]
    }

    /// Adds the `3n x 3n` matrix `k` (row-major) of element `e` to the
    /// Hessian values `h` on [`Model::pattern`], on the calling thread.
    pub(crate) fn add_element_matrix(&self, e: usize, k: &[f64], h: &mut [f64]) {
        let el = self.mesh.element(e);
        let n = el.len();
        let m = 3 * n;
        let bases = self.element_bases(e);
        let (ptr, _) = self.pattern.node_graph();
        for (b, &node_b) in el.iter().enumerate() {
            let stride = 3 * (ptr[node_b + 1] - ptr[node_b]);
            for a in 0..n {
                let base = bases[a * n + b];
                for j in 0..3 {
                    for i in 0..3 {
                        h[base + j * stride + i] += k[(3 * a + i) * m + 3 * b + j];
                    }
                }
            }
        }
    }

    /// The reference mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Element geometry at the stiffness quadrature points.
    pub fn geometry(&self) -> &ElementGeometry {
        &self.geometry
    }

    /// The constitutive model.
    pub fn material(&self) -> &dyn Material {
        self.material.as_ref()
    }

    /// Thickness and prestress.
    pub fn section(&self) -> Section {
        self.section
    }

    /// The membrane's stiffness scale `E t` (N/m): the larger diagonal
    /// entry of the material's tangent at zero strain times the thickness
    /// — a node's in-plane stiffness, whatever the element size, to order
    /// one.
    pub fn membrane_stiffness(&self) -> f64 {
        let d = self.material.tangent([0.0; 3]);
        d[0][0].max(d[1][1]) * self.section.thickness
    }

    /// Mass density `rho` (kg/m^3).
    pub fn density(&self) -> f64 {
        self.density
    }

    /// The gravity bending length `l = (B / w)^(1/3)` of the fabric (m;
    /// Peirce 1930, the length over which the fabric's weight bends it, and
    /// the scale of a fold's crest: Cerda, Mahadevan & Pasini 2004): `B` its
    /// smaller bending rigidity (N m; a woven fabric's warp or weft, a
    /// plate's `D`), `w` the magnitude of its dead weight per area (N/m²:
    /// `rho t g` of the gravity loads plus the surface loads). `None` without
    /// bending or without such a load.
    pub fn bending_length(&self) -> Option<f64> {
        use crate::bending::BendingRigidity;
        use crate::load::LoadKind;
        let b = match self.bending()?.rigidity {
            BendingRigidity::Isotropic(b) => b,
            BendingRigidity::Woven { warp, weft, .. } => warp.min(weft),
            BendingRigidity::Plate { rigidity, .. } => rigidity,
        };
        let areal_mass = self.density * self.section.thickness;
        let mut q = [0.0; 3];
        for load in &self.loads {
            let (scale, v) = match &load.kind {
                LoadKind::Gravity { acceleration } => (areal_mass, acceleration),
                LoadKind::Surface { force } => (1.0, force),
                _ => continue,
            };
            for (qi, vi) in q.iter_mut().zip(v) {
                *qi += scale * vi;
            }
        }
        let w = crate::vec3::norm(q);
        (b > 0.0 && w > 0.0).then(|| (b / w).cbrt())
    }

    /// External loads.
    pub fn loads(&self) -> &[Load] {
        &self.loads
    }

    /// `fixed[3a + i]`: component `i` of node `a` is held at its initial
    /// value (`dofs` long).
    pub fn fixed(&self) -> &[bool] {
        &self.fixed
    }

    /// How the mass matrix is built.
    pub fn mass_kind(&self) -> MassKind {
        self.mass_kind
    }

    /// Sparsity pattern of the Hessian (the elements' and the bending
    /// patches' couplings).
    pub fn pattern(&self) -> &SparsePattern {
        &self.pattern
    }

    /// Rigid obstacles and contact enforcement, if any.
    pub fn contact(&self) -> Option<&ContactModel> {
        self.contact.as_ref()
    }

    /// Self-contact, if any.
    pub fn self_contact(&self) -> Option<&SelfContact> {
        self.self_contact.as_ref()
    }

    /// The obstacles' sharp features kept out of the fabric's triangles
    /// (penalty contact with `[contact] features`, obstacles with
    /// corners, edges or rims), if any.
    pub fn obstacle_features(&self) -> Option<&ObstacleFeatures> {
        self.features.as_ref()
    }

    /// Bending stiffness, if any.
    pub fn bending(&self) -> Option<&Bending> {
        self.bending.as_ref()
    }

    /// The bending hysteresis, if any (only with bending).
    pub fn bending_hysteresis(&self) -> Option<Hysteresis> {
        self.hysteresis
    }

    /// Whether loops over elements and nodes go to rayon's pool. Below
    /// [`PARALLEL_ABOVE`] elements they run in two halves on the calling
    /// thread and [`crate::par`]'s helper instead: waking a sleeping rayon
    /// worker for a colour of ~120 elements or a loop over ~400 nodes
    /// costs more than the loop, a spinning helper does not
    /// (docs/performance.md, "The round before"). Results do not depend on the thread count:
    /// the splits are fixed and partial sums are added in order.
    pub fn parallel(&self) -> bool {
        parallel_for(&self.mesh)
    }

    /// Number of degrees of freedom (3 per node, fixed ones included).
    pub fn dofs(&self) -> usize {
        3 * self.mesh.node_count()
    }

    /// Number of fixed components.
    pub fn fixed_count(&self) -> usize {
        self.fixed.iter().filter(|&&f| f).count()
    }

    /// Initial positions `X`, flattened.
    pub fn initial_positions(&self) -> Vec<f64> {
        self.mesh.nodes.iter().flatten().copied().collect()
    }

    /// Total mass (kg): `sum_ab M^ab`.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Total follower pressure `sum_k p_k r_k(t)` at time `t` (Pa).
    pub fn pressure_at(&self, t: f64, static_factor: Option<f64>) -> f64 {
        self.loads
            .iter()
            .map(|l| match l.kind {
                LoadKind::Pressure { value } => value * self.factor(l, t, static_factor),
                _ => 0.0,
            })
            .sum()
    }

    fn factor(&self, load: &Load, t: f64, static_factor: Option<f64>) -> f64 {
        static_factor.unwrap_or_else(|| load.factor(t))
    }

    /// Whether the Hessian is symmetric by construction (no follower
    /// pressure, symmetric material tangent).
    pub fn symmetric_by_construction(&self) -> bool {
        self.material.has_symmetric_tangent()
            && !self
                .loads
                .iter()
                .any(|l| matches!(l.kind, LoadKind::Pressure { .. }))
    }

    /// Dead external forces (surface, gravity, nodal) at time `t`, written
    /// into `f` (`dofs` long). `static_factor`: the load factor of a static
    /// analysis, replacing the ramps.
    pub fn dead_forces(&self, t: f64, static_factor: Option<f64>, f: &mut [f64]) {
        f.fill(0.0);
        let rho_t = self.density * self.section.thickness;
        for load in &self.loads {
            let s = self.factor(load, t, static_factor);
            match &load.kind {
                LoadKind::Surface { force } => self.add_surface(f, *force, s),
                LoadKind::Gravity { acceleration } => {
                    self.add_surface(f, acceleration.map(|g| rho_t * g), s)
                }
                LoadKind::Nodal { nodes, force } => {
                    for &a in nodes {
                        for i in 0..3 {
                            f[3 * a + i] += s * force[i];
                        }
                    }
                }
                LoadKind::Pressure { .. } => {}
            }
        }
    }

    fn add_surface(&self, f: &mut [f64], q: [f64; 3], s: f64) {
        for (a, w) in self.area_weights.iter().enumerate() {
            for i in 0..3 {
                f[3 * a + i] += s * q[i] * w;
            }
        }
    }

    /// `out = M v` (consistent or lumped mass).
    pub fn mass_times(&self, v: &[f64], out: &mut [f64]) {
        let (ptr, rows) = self.pattern.node_graph();
        use rayon::prelude::*;
        let row = |(b, o): (usize, &mut [f64])| {
            // M is symmetric: row b of M v = column b of M dotted with v.
            let mut s = [0.0; 3];
            for p in ptr[b]..ptr[b + 1] {
                let a = rows[p];
                let m = self.mass[p];
                s[0] += m * v[3 * a];
                s[1] += m * v[3 * a + 1];
                s[2] += m * v[3 * a + 2];
            }
            o.copy_from_slice(&s);
        };
        if self.parallel() {
            out.par_chunks_mut(3).enumerate().for_each(row);
        } else {
            // Two halves, the second on the helper thread (`crate::par`).
            let mid = out.len() / 6;
            let (first, second) = out.split_at_mut(3 * mid);
            crate::par::join(
                || first.chunks_mut(3).enumerate().for_each(row),
                || {
                    second
                        .chunks_mut(3)
                        .enumerate()
                        .for_each(|(b, o)| row((b + mid, o)))
                },
            );
        }
    }

    /// Kinetic energy `1/2 V . M V` (J). `scratch`: `dofs` long.
    pub fn kinetic_energy(&self, v: &[f64], scratch: &mut [f64]) -> f64 {
        self.mass_times(v, scratch);
        0.5 * crate::vecn::dot(v, scratch)
    }

    /// Adds `c M` to Hessian values on the pattern.
    pub fn add_mass_to_hessian(&self, c: f64, h: &mut [f64]) {
        let (ptr, _) = self.pattern.node_graph();
        let nodes = self.mesh.node_count();
        // Node column b's blocks are the values 9 ptr[b] .. 9 ptr[b + 1]:
        // two halves of the columns, the second on the helper thread.
        let add = |h: &mut [f64], columns: std::ops::Range<usize>| {
            let offset = 9 * ptr[columns.start];
            for b in columns {
                for p in ptr[b]..ptr[b + 1] {
                    let m = c * self.mass[p];
                    for i in 0..3 {
                        h[self.pattern.entry(p, b, i, i) - offset] += m;
                    }
                }
            }
        };
        if self.parallel() {
            add(h, 0..nodes);
        } else {
            let mid = nodes / 2;
            let (first, second) = h.split_at_mut(9 * ptr[mid]);
            crate::par::join(|| add(first, 0..mid), || add(second, mid..nodes));
        }
    }

    /// Eliminates the fixed components: zero residual, identity rows and
    /// columns in the Hessian (if given).
    pub fn apply_supports(&self, g: &mut [f64], h: Option<&mut [f64]>) {
        let mut h = h;
        for (d, _) in self.fixed.iter().enumerate().filter(|(_, f)| **f) {
            g[d] = 0.0;
            if let Some(h) = h.as_deref_mut() {
                for k in self.pattern.col_ptr[d]..self.pattern.col_ptr[d + 1] {
                    h[k] = 0.0;
                    h[self.pattern.transpose_of(k)] = 0.0;
                }
                h[self.pattern.diagonal_of(d)] = 1.0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Wrinkling, WrinklingModel};
    use crate::mesh::ElementOrder;
    use crate::mesh::generate::{Pattern, disc, rectangle};

    fn wrinkling_model(mesh: Mesh) -> Model {
        Model::builder(
            mesh,
            Box::new(Wrinkling::new(
                2.0e6,
                0.3,
                0.0,
                WrinklingModel::StressProjection,
            )),
            Section {
                thickness: 6e-4,
                prestress: 0.0,
            },
            320.0,
        )
        .build()
        .expect("a valid mesh")
    }

    /// A 20 cm square of quadratic triangles below [`PARALLEL_ABOVE`] and
    /// one of linear triangles above it.
    fn small_and_large_meshes() -> [Mesh; 2] {
        [(12, ElementOrder::Quadratic), (48, ElementOrder::Linear)].map(|(divisions, order)| {
            let mesh = rectangle(
                [0.2, 0.2],
                [divisions, divisions],
                Pattern::Right,
                [0.0; 3],
                order,
            );
            assert_eq!(mesh.element_count() >= PARALLEL_ABOVE, divisions == 48);
            mesh
        })
    }

    /// Assembly gives the same bits on one thread and on two, on a small
    /// mesh (the calling thread's loop) and on one above
    /// [`PARALLEL_ABOVE`] (colours in fixed chunks, summed in order).
    #[test]
    fn assembly_does_not_depend_on_the_thread_count() {
        for mesh in small_and_large_meshes() {
            assembly_on_one_and_two_threads_agrees(wrinkling_model(mesh));
        }
    }

    /// The Hessian is overwritten, not added to: assembled into a buffer
    /// full of NaN (a diverged evaluation's leftovers) it is the one
    /// assembled into zeros, bit for bit — on a mesh with a node outside
    /// every element too, whose diagonal block no element writes.
    #[test]
    fn assembly_overwrites_every_hessian_entry() {
        for orphan in [false, true] {
            let mut mesh = rectangle(
                [0.2, 0.2],
                [6, 6],
                Pattern::Right,
                [0.0; 3],
                ElementOrder::Linear,
            );
            if orphan {
                mesh.nodes.push([0.5, 0.5, 0.0]);
            }
            let model = wrinkling_model(mesh);
            assert_eq!(!model.untouched_blocks.is_empty(), orphan);
            let y: Vec<f64> = model
                .initial_positions()
                .chunks(3)
                .flat_map(|x| [1.02 * x[0], 0.97 * x[1], 0.02 * (9.0 * x[0]).cos() * x[1]])
                .collect();
            let n = model.dofs();
            let mut f = vec![0.0; n];
            let mut zeros = vec![0.0; model.pattern.nnz()];
            let mut nans = vec![f64::NAN; model.pattern.nnz()];
            model.assemble(&y, &mut f, Some(&mut zeros));
            model.assemble(&y, &mut f, Some(&mut nans));
            assert!(
                zeros
                    .iter()
                    .zip(&nans)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
        }
    }

    /// The two halves of the assembly share no node, every element is
    /// assembled once, and the interface is a thin strip (the 20x20
    /// pedestal mesh: 80 of 800 elements, two rows); on a mesh of
    /// [`PARALLEL_ABOVE`] elements or more every split does the same, down
    /// to parts of fewer than [`ASSEMBLY_LEAF`] elements.
    #[test]
    fn assembly_halves_share_no_node_and_cover_the_mesh() {
        use crate::solver::pattern::{Halves, Part};
        let rectangles = [
            ([20, 20], ElementOrder::Linear),
            ([9, 4], ElementOrder::Cubic),
            ([48, 48], ElementOrder::Linear),
        ]
        .map(|(divisions, order)| {
            let mesh = rectangle([0.2, 0.1], divisions, Pattern::Alternate, [0.0; 3], order);
            (mesh, Some(divisions))
        });
        // And a disc with curved quadratic elements.
        let meshes = rectangles
            .into_iter()
            .chain([(disc(0.15, 9, [0.0; 3], ElementOrder::Quadratic), None)]);
        for (mesh, divisions) in meshes {
            let model = wrinkling_model(mesh);
            let halves = &model.halves;
            // The nodes of some elements, once each, and how many times
            // the elements name a node.
            let nodes_of = |list: &mut dyn Iterator<Item = usize>| {
                let mut nodes: Vec<usize> =
                    list.flat_map(|e| model.mesh.element(e).to_vec()).collect();
                let named = nodes.len();
                nodes.sort_unstable();
                nodes.dedup();
                (nodes, named)
            };
            let mut all: Vec<usize> = halves.order().collect();
            all.sort_unstable();
            assert_eq!(all, (0..model.mesh.element_count()).collect::<Vec<_>>());
            // Every split: the sides share no node, each interface colour
            // shares none within itself; the leaves are small.
            type NodesOf<'a> = dyn Fn(&mut dyn Iterator<Item = usize>) -> (Vec<usize>, usize) + 'a;
            fn check(h: &Halves, nodes_of: &NodesOf, leaves: &mut Vec<usize>) {
                let (a, b) = (
                    nodes_of(&mut h.first.order()).0,
                    nodes_of(&mut h.second.order()).0,
                );
                assert!(a.iter().all(|v| b.binary_search(v).is_err()));
                for c in &h.interface {
                    let (unique, named) = nodes_of(&mut c.iter().copied());
                    assert_eq!(unique.len(), named);
                }
                for part in [&h.first, &h.second] {
                    match part {
                        Part::Leaf(list) => leaves.push(list.len()),
                        Part::Split(inner) => check(inner, nodes_of, leaves),
                    }
                }
            }
            let mut leaves = Vec::new();
            check(halves, &nodes_of, &mut leaves);
            if model.parallel() {
                assert!(halves.depth() > 1);
                assert!(leaves.iter().all(|&l| l < ASSEMBLY_LEAF), "{leaves:?}");
            } else {
                assert_eq!(halves.depth(), 1);
            }
            let interface: usize = halves.interface.iter().map(Vec::len).sum();
            match divisions {
                Some(divisions) => {
                    let (first, second) = (halves.first.len(), halves.second.len());
                    assert!(first.abs_diff(second) <= divisions[1] * 2);
                    if divisions == [20, 20] {
                        assert_eq!(interface, 80, "{interface}");
                    }
                }
                None => {
                    // A median cut: each side keeps a third of the elements.
                    let third = model.mesh.element_count() / 3;
                    assert!(halves.first.len() >= third && halves.second.len() >= third);
                }
            }
        }
    }

    fn assembly_on_one_and_two_threads_agrees(model: Model) {
        // A deformed state with taut, wrinkled and slack points.
        let y: Vec<f64> = model
            .initial_positions()
            .chunks(3)
            .flat_map(|x| {
                [
                    1.02 * x[0] + 0.01 * (7.0 * x[1]).sin(),
                    0.97 * x[1],
                    0.02 * (9.0 * x[0]).cos() * x[1],
                ]
            })
            .collect();
        let assemble_on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a thread pool");
            pool.install(|| {
                let n = model.dofs();
                let (mut f, mut h) = (vec![0.0; n], vec![0.0; model.pattern.nnz()]);
                let u = model.assemble(&y, &mut f, Some(&mut h));
                (u, f, h)
            })
        };
        let (u1, f1, h1) = assemble_on(1);
        let (u2, f2, h2) = assemble_on(2);
        assert_eq!(u1.to_bits(), u2.to_bits());
        assert!(f1.iter().zip(&f2).all(|(a, b)| a.to_bits() == b.to_bits()));
        assert!(h1.iter().zip(&h2).all(|(a, b)| a.to_bits() == b.to_bits()));
        assert!(u1 > 0.0 && h1.iter().any(|&v| v != 0.0));
    }

    /// The run loop's one-pass statistics are `min_stretch` and
    /// `state_fractions`, bit for bit, on a small mesh (two halves) and on
    /// one above [`PARALLEL_ABOVE`] (rayon), orders 1 and 2, with taut,
    /// wrinkled and slack elements.
    #[test]
    fn one_pass_statistics_are_min_stretch_and_state_fractions() {
        for mesh in small_and_large_meshes() {
            let model = wrinkling_model(mesh);
            for amplitude in [0.0, 0.01, 0.03] {
                let y: Vec<f64> = model
                    .initial_positions()
                    .chunks(3)
                    .flat_map(|x| {
                        // Stretches from 0.94 to 1.06 across the mesh.
                        [
                            x[0] * (1.0 + 0.3 * x[0]) + amplitude * (7.0 * x[1]).sin(),
                            x[1] * (1.0 + 0.3 * x[1]),
                            2.0 * amplitude * (9.0 * x[0]).cos() * x[1],
                        ]
                    })
                    .collect();
                let ((stretch, element), fractions) = model.stretch_and_states(&y);
                let (s, e) = model.min_stretch(&y);
                assert_eq!((stretch.to_bits(), element), (s.to_bits(), e));
                assert_eq!(fractions, model.state_fractions(&y));
                if amplitude > 0.0 {
                    assert!(
                        fractions.iter().filter(|&&f| f > 0.0).count() >= 2,
                        "{fractions:?}"
                    );
                }
            }
        }
    }
}
