//! Bending stiffness, rotation-free: the unknowns stay the nodal positions.
//!
//! Each triangle of the mesh (each sub-triangle of a curved T6 or T10
//! element, [`triangulate`]) carries a constant curvature `kappa` (Voigt:
//! `kappa_11, kappa_22, 2 kappa_12`, in 1/m): the normal component of the
//! mean second derivative of the position field over the triangle, which
//! the divergence theorem turns into a sum over its edges of the
//! derivatives at their midpoints ([`patch`]); each edge's derivatives are
//! fitted once from the nodes around it — a quadratic through its two
//! triangles, least squares on the nodes beyond — and shared by the two
//! triangles ([`edge`]):
//!
//! ```text
//! kappa_ab = n . 1/A int_T x_,ab dA       (the second fundamental form)
//! W_bend   = sum_T 1/2 A_T (kappa - kappa_0) . D (kappa - kappa_0)
//! ```
//!
//! `A_T` is the reference area and `kappa_0` the curvature of the initial
//! mesh: a curved mesh is unbent, and stays at rest under no load. `D` is
//! the bending stiffness (N m), in the frame of the fabric's warp:
//!
//! ```text
//! scalar B:           D = B [1 0 0; 0 1 0; 0 0 1/2]
//! { warp, weft }:     D = [B_w 0 0; 0 B_f 0; 0 0 sqrt(B_w B_f)/2]
//! "plate":            D = E t^3 / (12 (1 - nu^2)) [1 nu 0; nu 1 0; 0 0 (1 - nu)/2]
//! ```
//!
//! A fabric's bending rigidity `B` is what a cantilever strip measures
//! (Peirce 1930; ASTM D1388), so a scalar `B` bends every strip with `B`:
//! no Poisson coupling between the two curvatures. The twist rigidity of a
//! woven fabric is Huber's geometric mean (Huber 1923: `D_12 + 2 D_66 =
//! sqrt(D_11 D_22)` with `D_12 = 0`). Edges without a neighbour rotate
//! freely (the moment normal to them vanishes): a free edge, or a simply
//! supported one where its nodes are held. An edge whose nodes a `[[fix]]
//! clamp = true` holds is clamped: the patch across it takes the mirror
//! slope across it at the reference surface's ([`patch`]; the triangles
//! it holds entirely carry no patch). Without it, an edge is clamped by holding two rows of
//! nodes, and bends as if clamped midway between them.
//!
//! The energy, gradient and Hessian of a patch are in [`kernel`], each
//! checked against finite differences in its tests.

pub mod edge;
pub mod hysteresis;
pub mod kernel;
pub mod patch;

use crate::element::geometry::AxisError;
use crate::mesh::Mesh;
use crate::par::Shared;
use crate::solver::SparsePattern;
use edge::{EdgeFit, EdgeNodes};
use patch::{Patch, PatchError};

/// The bending stiffness of the fabric (`[material] bending_rigidity`, docs/theory.md §1.10).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BendingRigidity {
    /// The same rigidity `B` (N m) for every direction, without Poisson
    /// coupling.
    Isotropic(f64),
    /// A woven fabric: `warp` for curvature along the warp (bending about
    /// the weft), `weft` for curvature along the weft (N m), with the warp
    /// along `direction` projected on each triangle.
    Woven {
        /// Rigidity for curvature along the warp (N m).
        warp: f64,
        /// Rigidity for curvature along the weft (N m).
        weft: f64,
        /// The warp direction in the initial configuration.
        direction: [f64; 3],
    },
    /// A plate of rigidity `D` (N m) and Poisson ratio `nu`: `E t^3 / (12
    /// (1 - nu^2))`.
    Plate {
        /// `D` (N m).
        rigidity: f64,
        /// Poisson's ratio.
        poisson_ratio: f64,
    },
}

impl BendingRigidity {
    /// The constitutive matrix `D` (Voigt, N m) in the warp's frame.
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        match *self {
            Self::Isotropic(b) => [[b, 0.0, 0.0], [0.0, b, 0.0], [0.0, 0.0, 0.5 * b]],
            Self::Woven { warp, weft, .. } => [
                [warp, 0.0, 0.0],
                [0.0, weft, 0.0],
                [0.0, 0.0, 0.5 * (warp * weft).sqrt()],
            ],
            Self::Plate {
                rigidity: d,
                poisson_ratio: nu,
            } => [
                [d, nu * d, 0.0],
                [nu * d, d, 0.0],
                [0.0, 0.0, 0.5 * (1.0 - nu) * d],
            ],
        }
    }

    /// The frame's first axis: the warp of a woven fabric, none (any) for
    /// an isotropic one.
    fn axis(&self) -> Option<[f64; 3]> {
        match *self {
            Self::Woven { direction, .. } => Some(direction),
            _ => None,
        }
    }
}

/// Why bending cannot be set up on a mesh.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BendingError {
    /// An edge is shared by more than two triangles.
    #[error(
        "bending needs a manifold mesh: the edge between nodes {} and {} is shared by elements {} (0-based, in the order read; a bending patch has at most one neighbour across each edge)",
        .nodes.0, .nodes.1, list(.elements)
    )]
    NonManifold {
        /// The edge's nodes (0-based).
        nodes: (usize, usize),
        /// The elements sharing it (0-based).
        elements: Vec<usize>,
    },
    /// The warp of a woven rigidity is normal to an element.
    #[error(transparent)]
    Axis(#[from] crate::element::geometry::AxisError),
    /// A patch cannot be fitted.
    #[error("bending patch of element {element} (0-based, in the order read): {reason}")]
    Patch {
        /// The element (0-based).
        element: usize,
        /// What is wrong with it.
        reason: String,
    },
}

fn list(v: &[usize]) -> String {
    v.iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The sub-triangles on which bending is measured: the elements of a
/// linear mesh; each T6 cut into 4 and each T10 into 9 along its nodes
/// (straight or curved). Returns the triangles and, for each, its element.
pub fn triangulate(mesh: &Mesh) -> (Vec<[usize; 3]>, Vec<usize>) {
    let p = mesh.order.degree();
    // Lattice node (b, c) (barycentric (p - b - c, b, c) times p) of an
    // element: vertices 0–2, then p - 1 nodes per edge 0-1, 1-2, 2-0 (from
    // its first vertex), then the interior node (order 3).
    let lattice = |el: &[usize], b: usize, c: usize| -> usize {
        let a = p - b - c;
        match (a, b, c) {
            (_, 0, 0) => el[0],
            (0, _, 0) => el[1],
            (0, 0, _) => el[2],
            (_, _, 0) => el[3 + (b - 1)],
            (0, _, _) => el[3 + (p - 1) + (c - 1)],
            (_, 0, _) => el[3 + 2 * (p - 1) + (a - 1)],
            _ => el[3 * p],
        }
    };
    let mut triangles = Vec::with_capacity(mesh.element_count() * p * p);
    let mut owner = Vec::with_capacity(mesh.element_count() * p * p);
    for (e, el) in mesh.elements().enumerate() {
        for b in 0..p {
            for c in 0..p - b {
                triangles.push([
                    lattice(el, b, c),
                    lattice(el, b + 1, c),
                    lattice(el, b, c + 1),
                ]);
                owner.push(e);
                if b + c + 2 <= p {
                    triangles.push([
                        lattice(el, b + 1, c),
                        lattice(el, b + 1, c + 1),
                        lattice(el, b, c + 1),
                    ]);
                    owner.push(e);
                }
            }
        }
    }
    (triangles, owner)
}

/// The (sub-)triangles of a mesh ([`triangulate`]) and, for each, the
/// node opposite each of its edges across the neighbouring triangle.
struct Neighbours {
    triangles: Vec<[usize; 3]>,
    /// The element of each triangle.
    owner: Vec<usize>,
    /// `opposite[t][m]`: the node opposite the edge of triangle `t` that
    /// is opposite its vertex `m`, `None` on a boundary.
    opposite: Vec<[Option<usize>; 3]>,
    /// `across[t][m]`: the triangle across that edge and the index of the
    /// edge's opposite vertex in it, `None` on a boundary.
    across: Vec<[Option<(usize, usize)>; 3]>,
}

impl Neighbours {
    /// The neighbours of `mesh`'s triangles; an edge of more than two
    /// triangles is refused.
    fn of(mesh: &Mesh) -> Result<Self, BendingError> {
        let (triangles, owner) = triangulate(mesh);
        let mut edges: std::collections::HashMap<(usize, usize), Vec<(usize, usize)>> =
            std::collections::HashMap::with_capacity(3 * triangles.len() / 2 + 1);
        for (t, tri) in triangles.iter().enumerate() {
            for m in 0..3 {
                let (a, b) = (tri[(m + 1) % 3], tri[(m + 2) % 3]);
                edges.entry((a.min(b), a.max(b))).or_default().push((t, m));
            }
        }
        let mut opposite = vec![[None; 3]; triangles.len()];
        let mut across = vec![[None; 3]; triangles.len()];
        for (key, list) in &edges {
            match list.as_slice() {
                [_] => {}
                &[(t, m), (s, k)] => {
                    opposite[t][m] = Some(triangles[s][k]);
                    opposite[s][k] = Some(triangles[t][m]);
                    across[t][m] = Some((s, k));
                    across[s][k] = Some((t, m));
                }
                _ => {
                    let mut elements: Vec<usize> = list.iter().map(|&(t, _)| owner[t]).collect();
                    elements.sort_unstable();
                    elements.dedup();
                    return Err(BendingError::NonManifold {
                        nodes: *key,
                        elements,
                    });
                }
            }
        }
        Ok(Self {
            triangles,
            owner,
            opposite,
            across,
        })
    }

    /// The nodes sharing a triangle with each node.
    fn adjacency(&self, nodes: usize) -> Vec<Vec<usize>> {
        let mut adjacent = vec![Vec::new(); nodes];
        for tri in &self.triangles {
            for &a in tri {
                for &b in tri {
                    if a != b && !adjacent[a].contains(&b) {
                        adjacent[a].push(b);
                    }
                }
            }
        }
        adjacent
    }

    /// The unit normal of triangle `t` at positions `x` (zero where it
    /// has no area: the patch refuses it).
    fn normal(&self, t: usize, x: &[[f64; 3]]) -> [f64; 3] {
        use crate::vec3::{cross, norm, scale, sub};
        let [a, b, c] = self.triangles[t].map(|v| x[v]);
        let m = cross(sub(b, a), sub(c, a));
        let r = norm(m);
        if r > 0.0 { scale(m, 1.0 / r) } else { [0.0; 3] }
    }

    /// The fit of every edge ([`edge`]) at reference positions `x`, and for
    /// each triangle the index of the fit of its edge opposite each vertex;
    /// `clamped(a)`: node `a` is held by a clamp.
    fn edge_fits(
        &self,
        x: &[[f64; 3]],
        clamped: impl Fn(usize) -> bool,
    ) -> (Vec<EdgeFit>, Vec<[usize; 3]>) {
        let adjacent = self.adjacency(x.len());
        let mut index = vec![[usize::MAX; 3]; self.triangles.len()];
        let mut fits = Vec::with_capacity(3 * self.triangles.len() / 2 + 1);
        for t in 0..self.triangles.len() {
            for m in 0..3 {
                if index[t][m] != usize::MAX {
                    continue;
                }
                let tri = self.triangles[t];
                let (a, b) = (tri[(m + 1) % 3], tri[(m + 2) % 3]);
                let ends = [a.min(b), a.max(b)];
                let other = self.across[t][m];
                let mut outer = Vec::with_capacity(4);
                for (u, k) in std::iter::once((t, m)).chain(other) {
                    for kk in (0..3).filter(|&kk| kk != k) {
                        outer.extend(self.opposite[u][kk]);
                    }
                }
                let opposite = [Some(tri[m]), other.map(|(u, k)| self.triangles[u][k])];
                // Further candidates: the neighbours of the four nodes,
                // nearest the midpoint first.
                let mid = crate::vec3::scale(crate::vec3::add(x[a], x[b]), 0.5);
                let mut further: Vec<usize> = Vec::new();
                if other.is_some() {
                    for &v in ends.iter().chain(opposite.iter().flatten()) {
                        for &w in &adjacent[v] {
                            if !further.contains(&w) {
                                further.push(w);
                            }
                        }
                    }
                    further.sort_by(|&p, &q| {
                        let d = |k: usize| crate::vec3::norm(crate::vec3::sub(x[k], mid));
                        d(p).total_cmp(&d(q)).then(p.cmp(&q))
                    });
                }
                let nodes = EdgeNodes {
                    ends,
                    opposite,
                    outer: &outer,
                    further: &further,
                    normals: [
                        Some(self.normal(t, x)),
                        other.map(|(u, _)| self.normal(u, x)),
                    ],
                };
                index[t][m] = fits.len();
                if let Some((u, k)) = other {
                    index[u][k] = fits.len();
                }
                fits.push(EdgeFit::new(&nodes, x, clamped(a) && clamped(b)));
            }
        }
        (fits, index)
    }
}

/// For each edge `[a, b]` (`a < b`), the nodes and weights of the
/// position of its midpoint ([`edge_midpoints`]).
pub type MidpointRules = std::collections::HashMap<[usize; 2], (Vec<usize>, Vec<f64>)>;

/// Where a refinement places the node halving each edge of `mesh` (a
/// linear mesh): for each edge `[a, b]` (`a < b`), the nodes and weights
/// of its fit's value at the midpoint ([`EdgeFit::middle`]) — on the
/// quadratic surface through the edge's two triangles and the nodes
/// around them, fitted on the reference positions, applied to any
/// positions (the current shape, the reference itself, the velocities).
/// A boundary edge's is the chord's midpoint.
///
/// # Errors
/// [`BendingError::NonManifold`]: an edge of more than two triangles.
pub fn edge_midpoints(mesh: &Mesh) -> Result<MidpointRules, BendingError> {
    let neighbours = Neighbours::of(mesh)?;
    let (fits, _) = neighbours.edge_fits(&mesh.nodes, |_| false);
    Ok(fits
        .into_iter()
        .map(|f| {
            let ends = [f.nodes[0], f.nodes[1]];
            let used = f.middle.len();
            (ends, (f.nodes[..used].to_vec(), f.middle))
        })
        .collect())
}

/// The stencils the bending patches of `mesh` have, in CSR form `(ptr,
/// nodes)`, found from the mesh's topology alone, without fitting the
/// patches: each (sub-)triangle with a neighbour, its three nodes, the
/// nodes opposite its edges and, beyond each neighbour, the nodes opposite
/// the neighbour's other two edges ([`edge`]) — what the Hessian's pattern
/// must hold, known before the model is built. The two further nodes an
/// edge's fit may add where the nodes around it do not fix its quadratic
/// (near corners, in strips one element wide) are not counted: the
/// pattern's size is an estimate there.
///
/// # Errors
/// [`BendingError::NonManifold`], as [`Bending::new`].
pub fn stencils_of(mesh: &Mesh) -> Result<(Vec<usize>, Vec<usize>), BendingError> {
    let n = Neighbours::of(mesh)?;
    let mut ptr = vec![0];
    let mut nodes = Vec::new();
    for (t, tri) in n.triangles.iter().enumerate() {
        if n.opposite[t].iter().all(Option::is_none) {
            continue;
        }
        let start = nodes.len();
        nodes.extend_from_slice(tri);
        let push = |a: usize, nodes: &mut Vec<usize>| {
            if !nodes[start..].contains(&a) {
                nodes.push(a);
            }
        };
        for a in n.opposite[t].iter().flatten() {
            push(*a, &mut nodes);
        }
        for &(u, k) in n.across[t].iter().flatten() {
            for kk in (0..3).filter(|&kk| kk != k) {
                if let Some(a) = n.opposite[u][kk] {
                    push(a, &mut nodes);
                }
            }
        }
        ptr.push(nodes.len());
    }
    Ok((ptr, nodes))
}

/// The bending term of a mesh: one patch per (sub-)triangle, with where
/// its Hessian blocks lie in the pattern.
#[derive(Debug, Clone)]
pub struct Bending {
    /// The constitutive law it was built with.
    pub rigidity: BendingRigidity,
    patches: Vec<Patch>,
    /// Stencils (the patches' nodes) in CSR form.
    ptr: Vec<usize>,
    nodes: Vec<usize>,
    /// Per patch, its `len^2` Hessian block bases
    /// ([`SparsePattern::block_layout`]), row-major in (k, l), set by
    /// [`Bending::attach`].
    blocks: Vec<usize>,
    /// Where each patch's blocks start in `blocks`.
    block_start: Vec<usize>,
    /// The order of the assembly: the patches in two halves that share no
    /// node, on two threads, then those at the interface colour by
    /// colour, each colour in two halves; from
    /// [`crate::model::PARALLEL_ABOVE`] elements on, each half split again
    /// into parts of fewer than [`crate::solver::pattern::ASSEMBLY_LEAF`] patches,
    /// on rayon's pool ([`crate::solver::pattern::Halves`]). `None` until
    /// [`Bending::attach`].
    halves: Option<crate::solver::pattern::Halves>,
}

impl Bending {
    /// The patches of `mesh` for `rigidity`, fitted on the mesh's
    /// (reference) positions; `clamped[a]` (empty: none) marks the nodes
    /// a `[[fix]] clamp = true` holds, whose edges are clamped (the module
    /// docs).
    pub fn new(
        mesh: &Mesh,
        rigidity: BendingRigidity,
        clamped: &[bool],
    ) -> Result<Self, BendingError> {
        let neighbours = Neighbours::of(mesh)?;
        let d = rigidity.matrix();
        let axis = rigidity.axis();
        let is_clamped = |a: usize| clamped.get(a).copied().unwrap_or(false);
        let (fits, index) = neighbours.edge_fits(&mesh.nodes, is_clamped);
        let mut patches = Vec::with_capacity(neighbours.triangles.len());
        for (t, tri) in neighbours.triangles.iter().enumerate() {
            if tri.iter().all(|&a| is_clamped(a)) {
                continue; // held, with its slope: it cannot bend
            }
            let edges = index[t].map(|i| &fits[i]);
            let patch = Patch::fit(*tri, edges, &mesh.nodes, &d, axis).map_err(|e| {
                let element = neighbours.owner[t];
                match e {
                    PatchError::Frame => BendingError::Axis(AxisError {
                        element,
                        axis: axis.unwrap_or_default(),
                    }),
                    PatchError::Degenerate => BendingError::Patch {
                        element,
                        reason: "the triangle has no area".into(),
                    },
                }
            })?;
            // None: all three edges free, a lone triangle cannot bend.
            patches.extend(patch.map(|mut p| {
                p.element = neighbours.owner[t];
                p
            }));
        }
        let mut ptr = Vec::with_capacity(patches.len() + 1);
        let mut nodes = Vec::new();
        ptr.push(0);
        for p in &patches {
            nodes.extend_from_slice(p.nodes());
            ptr.push(nodes.len());
        }
        Ok(Self {
            rigidity,
            patches,
            ptr,
            nodes,
            blocks: Vec::new(),
            block_start: Vec::new(),
            halves: None,
        })
    }

    /// The patches' node lists, for the pattern and the colouring.
    pub fn stencils(&self) -> impl Iterator<Item = &[usize]> + Clone {
        self.ptr.windows(2).map(|w| &self.nodes[w[0]..w[1]])
    }

    /// The stencils in CSR form `(ptr, nodes)`.
    pub fn stencil_lists(&self) -> (&[usize], &[usize]) {
        (&self.ptr, &self.nodes)
    }

    /// The patches.
    pub fn patches(&self) -> &[Patch] {
        &self.patches
    }

    /// Each patch's curvatures `kappa` (1/m, Voigt, in its frame) at the
    /// positions `y` (flattened).
    pub fn curvatures(&self, y: &[f64]) -> Vec<[f64; 3]> {
        let mut x = [[0.0; 3]; kernel::MAX_NODES];
        self.patches
            .iter()
            .map(|p| {
                p.positions(|a| [y[3 * a], y[3 * a + 1], y[3 * a + 2]], &mut x);
                p.curvature(&x[..p.len()])
            })
            .collect()
    }

    /// Records where each patch's Hessian blocks lie in `pattern` (which
    /// must include the stencils), and how the assembly runs: in two
    /// halves of the patches (at the reference positions `nodes`) on two
    /// threads, with `parallel` each half split again into parts on
    /// rayon's pool.
    pub(crate) fn attach(&mut self, pattern: &SparsePattern, parallel: bool, nodes: &[[f64; 3]]) {
        use crate::solver::pattern::{ASSEMBLY_LEAF, Halves, colour_elements};
        self.blocks.clear();
        self.block_start.clear();
        let colours = colour_elements(pattern.dimension() / 3, self.stencils());
        self.halves = Some(if parallel {
            Halves::nested(nodes, self.stencils(), &colours, ASSEMBLY_LEAF)
        } else {
            Halves::of(nodes, self.stencils(), &colours)
        });
        for p in &self.patches {
            self.block_start.push(self.blocks.len());
            for &a in p.nodes() {
                for &b in p.nodes() {
                    let pos = pattern
                        .node_block(a, b)
                        .expect("the pattern includes the bending stencils");
                    self.blocks.push(pattern.block_layout(pos, b).0);
                }
            }
        }
    }

    /// Adds the gradient of an energy of the patches' curvatures to `g`
    /// and, if given, its Hessian to `h` (values on `pattern`, the model's
    /// [`Model::pattern`](crate::model::Model::pattern) this term was
    /// attached to when the model was built); returns the energy (J).
    /// `law(k, kappa)` gives patch `k`'s energy, moments and their
    /// derivative as [`kernel::evaluate_law`] takes them; `None`, the
    /// elastic bending energy's (the bending term passes `None` for every
    /// patch, the hysteresis term its own). The patches run colour by
    /// colour (no two of a colour share a node): each colour in rayon's
    /// chunks on a mesh of [`crate::model::PARALLEL_ABOVE`] elements or
    /// more, else in two halves on `par`'s helper thread; the energies are
    /// summed in a fixed order, so the result does not depend on the
    /// number of threads.
    ///
    /// With `project`, the Hessian of every patch with a node flagged
    /// there (one flag per node) is replaced by its Gauss–Newton part `K^T
    /// (dM/dkappa) K` — `K^T (A D') K` for the elastic law —, positive
    /// semi-definite where `dM/dkappa` is, before it is added (the
    /// projected Newton of `solver::newton`; [`kernel::evaluate_with`]).
    pub(crate) fn add_law<L>(
        &self,
        pattern: &SparsePattern,
        y: &[f64],
        g: &mut [f64],
        h: Option<&mut [f64]>,
        project: Option<&[bool]>,
        law: &L,
    ) -> f64
    where
        L: Fn(usize, [f64; 3]) -> Option<kernel::LawValue> + Sync,
    {
        let (node_ptr, _) = pattern.node_graph();
        let want_h = h.is_some();
        let hp = Shared(h.map_or(std::ptr::null_mut(), |h| h.as_mut_ptr()));
        let gp = Shared(g.as_mut_ptr());
        let work = |local: &mut kernel::Local, list: &mut dyn Iterator<Item = usize>| -> f64 {
            let mut x = [[0.0; 3]; kernel::MAX_NODES];
            let mut energy = 0.0;
            for k in list {
                let p = &self.patches[k];
                let nodes = p.nodes();
                let len = nodes.len();
                p.positions(|a| [y[3 * a], y[3 * a + 1], y[3 * a + 2]], &mut x);
                let gauss_newton =
                    want_h && project.is_some_and(|flags| nodes.iter().any(|&a| flags[a]));
                energy +=
                    kernel::evaluate_law(p, &x[..len], want_h, gauss_newton, local, |kappa| {
                        law(k, kappa).unwrap_or_else(|| kernel::elastic(p, kappa))
                    });
                // SAFETY: patches that run at once (of one colour) share no
                // node, so the gradient entries and Hessian blocks written
                // below are disjoint across threads; the indices are those
                // of the patch's nodes and of its blocks in the pattern.
                unsafe {
                    for (k, &a) in nodes.iter().enumerate() {
                        for i in 0..3 {
                            gp.add(3 * a + i, local.gradient[3 * k + i]);
                        }
                    }
                    if want_h {
                        // Column node by column node: a column's blocks lie
                        // in its three scalar columns, close together.
                        let blocks = &self.blocks[self.block_start[k]..];
                        for (l, &b) in nodes.iter().enumerate() {
                            let stride = 3 * (node_ptr[b + 1] - node_ptr[b]);
                            for j in 0..3 {
                                for r in 0..len {
                                    let base = blocks[r * len + l] + j * stride;
                                    for i in 0..3 {
                                        hp.add(base + i, local.hessian[3 * r + i][3 * l + j]);
                                    }
                                }
                            }
                        }
                    }
                }
            }
            energy
        };
        // Each thread's scratch kept between assemblies (24 kB).
        thread_local! {
            static LOCAL: std::cell::RefCell<kernel::Local> =
                std::cell::RefCell::new(kernel::Local::new());
        }
        let halves = self
            .halves
            .as_ref()
            .expect("Bending::attach runs before the assembly");
        halves.run(&|part: &[usize]| {
            LOCAL.with(|l| work(&mut l.borrow_mut(), &mut part.iter().copied()))
        })
    }

    /// The bending energy at `y` (J).
    pub fn energy(&self, y: &[f64]) -> f64 {
        let mut x = [[0.0; 3]; kernel::MAX_NODES];
        self.patches
            .iter()
            .map(|p| {
                p.positions(|a| [y[3 * a], y[3 * a + 1], y[3 * a + 2]], &mut x);
                kernel::energy(p, &x[..p.len()])
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ElementOrder;
    use crate::mesh::generate::{Pattern, rectangle};

    /// A triangle of a 3 x 3 grid split at its centroid (node 16, with
    /// three neighbours): the patches through it are fitted (the fit of
    /// each edge takes further neighbours where it needs them), and the
    /// curvature of a quadratic surface is exact on them. The patch
    /// through a triangle's six nodes refused it (issue 35).
    #[test]
    fn a_node_with_three_neighbours_bends() {
        let mut mesh = rectangle(
            [0.3, 0.3],
            [3, 3],
            Pattern::Right,
            [0.0; 3],
            ElementOrder::Linear,
        );
        let e = 8;
        let [a, b, c] = [0, 1, 2].map(|k| mesh.connectivity[3 * e + k]);
        let g = mesh.nodes.len();
        let centroid =
            [0, 1, 2].map(|i| (mesh.nodes[a][i] + mesh.nodes[b][i] + mesh.nodes[c][i]) / 3.0);
        mesh.nodes.push(centroid);
        mesh.connectivity[3 * e..3 * e + 3].copy_from_slice(&[a, b, g]);
        mesh.connectivity.extend_from_slice(&[b, c, g, c, a, g]);
        let bending = Bending::new(&mesh, BendingRigidity::Isotropic(2e-5), &[]).unwrap();
        // z = 10 x^2 + 20 y^2 seen by each patch round the centroid (normal
        // +z there: a flat triangle's curvature is (20, 40, 0) in any frame
        // rotated about z, so compare the invariants).
        let x: Vec<[f64; 3]> = mesh
            .nodes
            .iter()
            .map(|p| [p[0], p[1], 10.0 * p[0] * p[0] + 20.0 * p[1] * p[1]])
            .collect();
        for p in bending
            .patches()
            .iter()
            .filter(|p| p.nodes()[..3].contains(&g))
        {
            let xl: Vec<[f64; 3]> = p.nodes().iter().map(|&a| x[a]).collect();
            let n = patch::normal(&xl).0;
            let k = p.curvature(&xl);
            let (trace, det) = (k[0] + k[1], k[0] * k[1] - 0.25 * k[2] * k[2]);
            let want = (60.0 * n[2], 800.0 * n[2] * n[2]);
            assert!((trace - want.0).abs() < 1e-9 * want.0, "{k:?}");
            assert!((det - want.1).abs() < 1e-8 * want.1, "{k:?}");
        }
    }

    /// The stencils found from the topology alone are the patches' own,
    /// in order, for every element order, but for the further nodes a fit
    /// adds near corners (node sets: the order inside a stencil may
    /// differ).
    #[test]
    fn stencils_of_are_the_patches_stencils() {
        for order in [
            ElementOrder::Linear,
            ElementOrder::Quadratic,
            ElementOrder::Cubic,
        ] {
            let mesh = rectangle([0.2, 0.1], [6, 3], Pattern::Alternate, [0.0; 3], order);
            let bending = Bending::new(&mesh, BendingRigidity::Isotropic(2e-5), &[]).unwrap();
            let (ptr, nodes) = stencils_of(&mesh).unwrap();
            let sorted = |s: &[usize]| {
                let mut v = s.to_vec();
                v.sort_unstable();
                v
            };
            let found: Vec<Vec<usize>> =
                ptr.windows(2).map(|w| sorted(&nodes[w[0]..w[1]])).collect();
            let fitted: Vec<Vec<usize>> = bending.stencils().map(sorted).collect();
            assert_eq!(found.len(), fitted.len(), "{order:?}");
            let mut further = 0;
            for (f, p) in found.iter().zip(&fitted) {
                assert!(f.iter().all(|a| p.contains(a)), "{order:?}: {f:?} {p:?}");
                further += p.len() - f.len();
            }
            assert!(
                further <= fitted.len() / 4,
                "{order:?}: {further} further nodes"
            );
        }
    }

    /// The large-mesh assembly (halves split again, on rayon's pool) adds
    /// the same gradient and Hessian as the small model's (one split), to
    /// round-off (the order of the sums differs), and to the bit whatever
    /// the number of threads.
    #[test]
    fn parallel_assembly_matches_the_serial_one() {
        let mesh = rectangle(
            [0.2, 0.2],
            [64, 64],
            Pattern::Alternate,
            [0.0; 3],
            ElementOrder::Linear,
        );
        let mut serial = Bending::new(&mesh, BendingRigidity::Isotropic(2e-5), &[]).unwrap();
        let pattern =
            SparsePattern::new(mesh.node_count(), mesh.elements().chain(serial.stencils()));
        let mut parallel = serial.clone();
        serial.attach(&pattern, false, &mesh.nodes);
        parallel.attach(&pattern, true, &mesh.nodes);
        let depth = |b: &Bending| b.halves.as_ref().unwrap().depth();
        assert!(depth(&parallel) > 1 && depth(&serial) == 1);
        let y: Vec<f64> = mesh
            .nodes
            .iter()
            .flat_map(|x| {
                [
                    x[0],
                    x[1] + 0.01 * x[0],
                    0.02 * (30.0 * x[0]).sin() * (20.0 * x[1]).cos(),
                ]
            })
            .collect();
        let run = |b: &Bending| {
            let mut g = vec![0.0; y.len()];
            let mut h = vec![0.0; pattern.nnz()];
            let e = b.add_law(&pattern, &y, &mut g, Some(&mut h), None, &|_, _| None);
            (e, g, h)
        };
        let (e0, g0, h0) = run(&serial);
        let (e1, g1, h1) = run(&parallel);
        let close = |a: &[f64], b: &[f64]| {
            let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-12 * scale)
        };
        assert!((e0 - e1).abs() <= 1e-12 * e0.abs(), "{e0} {e1}");
        assert!(close(&g0, &g1) && close(&h0, &h1));
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (e2, g2, h2) = pool.install(|| run(&parallel));
            assert_eq!(
                (e1.to_bits(), &g1, &h1),
                (e2.to_bits(), &g2, &h2),
                "{threads} threads"
            );
        }
    }
}
