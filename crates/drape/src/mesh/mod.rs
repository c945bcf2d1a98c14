//! Triangle meshes of the membrane's initial (reference) surface.
//!
//! A [`Mesh`] holds the initial nodal positions `X` and the connectivity of
//! Lagrange triangles of order 1, 2 or 3. Node order inside an element
//! follows Gmsh and VTK (which agree for these elements):
//!
//! * order 1 (3 nodes): the vertices `v0 v1 v2`, counter-clockwise about the
//!   element normal;
//! * order 2 (6 nodes): the vertices, then the mid-edge nodes of edges
//!   `v0-v1`, `v1-v2`, `v2-v0`;
//! * order 3 (10 nodes): the vertices, then two nodes per edge (edges
//!   `v0-v1`, `v1-v2`, `v2-v0`, each listed from its first vertex on), then
//!   the interior node.
//!
//! Meshes come from the generators in [`generate`] or the readers in
//! [`gmsh`] and [`obj`]; every mesh is checked by [`Mesh::validate`] before
//! use. The shape functions of its triangles, which map the reference
//! triangle onto each element, are in [`lagrange`].

pub mod generate;
pub mod gmsh;
pub mod lagrange;
pub mod obj;
pub mod polygon;
mod read_error;
pub mod refine;
mod validate;

pub use read_error::{Location, MeshReadError};
pub use validate::MeshError;

/// Most nodes a mesh may have, generated or read: a guard against typos
/// such as `divisions = [20000, 20000]` and against files too large to
/// run, whose model would exhaust memory. The generators are refused from
/// their counts before they generate, the readers from the count a Gmsh
/// file declares before its nodes are read, and an OBJ file's at the
/// vertex past it ([`gmsh::parse_msh_at_most`], [`obj::parse_obj_at_most`]
/// take another cap).
pub const MAX_MESH_NODES: usize = 3_000_000;

/// Refuses `count` nodes in `file` (found at `at`) when they are more than
/// the cap `limit`: a Gmsh `$Nodes` section's declared count (`declared`,
/// before any node is read) or the number of an OBJ vertex past it.
pub(crate) fn check_node_cap(
    file: &str,
    at: Location,
    count: u64,
    declared: bool,
    limit: usize,
) -> Result<(), MeshReadError> {
    if usize::try_from(count).is_ok_and(|n| n <= limit) {
        return Ok(());
    }
    Err(MeshReadError::TooManyNodes {
        file: file.to_owned(),
        at: Some(at),
        count,
        declared,
        limit,
    })
}

/// Lagrange order of the triangles of a mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum ElementOrder {
    /// 3-node linear triangle (T3).
    Linear,
    /// 6-node quadratic triangle (T6).
    Quadratic,
    /// 10-node cubic triangle (T10).
    Cubic,
}

impl ElementOrder {
    /// Builds an order from its degree `1`, `2` or `3`.
    pub fn from_degree(degree: usize) -> Option<Self> {
        match degree {
            1 => Some(Self::Linear),
            2 => Some(Self::Quadratic),
            3 => Some(Self::Cubic),
            _ => None,
        }
    }

    /// Polynomial degree `p` of the shape functions (1, 2 or 3).
    pub fn degree(self) -> usize {
        match self {
            Self::Linear => 1,
            Self::Quadratic => 2,
            Self::Cubic => 3,
        }
    }

    /// Nodes per element: `(p + 1)(p + 2) / 2`.
    pub fn nodes_per_element(self) -> usize {
        let p = self.degree();
        (p + 1) * (p + 2) / 2
    }
}

/// A triangle mesh of the reference surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// Initial nodal positions `X` (m).
    pub nodes: Vec<[f64; 3]>,
    /// Element order, the same for every element.
    pub order: ElementOrder,
    /// Connectivity, `order.nodes_per_element()` node indices per element,
    /// element after element.
    pub connectivity: Vec<usize>,
}

impl Mesh {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of elements.
    pub fn element_count(&self) -> usize {
        self.connectivity.len() / self.order.nodes_per_element()
    }

    /// Node indices of element `e`.
    pub fn element(&self, e: usize) -> &[usize] {
        let n = self.order.nodes_per_element();
        &self.connectivity[e * n..(e + 1) * n]
    }

    /// Iterates over the elements' node lists.
    pub fn elements(&self) -> std::slice::ChunksExact<'_, usize> {
        self.connectivity
            .chunks_exact(self.order.nodes_per_element())
    }

    /// The mesh's disconnected pieces: for each element, the number of its
    /// piece (0 for the piece of element 0, then in order of first
    /// element), and the number of pieces. Elements are in one piece when
    /// a chain of elements sharing nodes joins them (a mesh file of
    /// several Gmsh surfaces or OBJ groups: plies, a garment's panels).
    pub fn pieces(&self) -> (Vec<usize>, usize) {
        let mut parent: Vec<usize> = (0..self.nodes.len()).collect();
        fn root(parent: &mut [usize], mut a: usize) -> usize {
            while parent[a] != a {
                parent[a] = parent[parent[a]];
                a = parent[a];
            }
            a
        }
        for el in self.elements() {
            let first = root(&mut parent, el[0]);
            for &b in &el[1..] {
                let rb = root(&mut parent, b);
                parent[rb] = first;
            }
        }
        let mut number = vec![usize::MAX; self.nodes.len()];
        let mut count = 0;
        let piece = (self.elements())
            .map(|el| {
                let r = root(&mut parent, el[0]);
                if number[r] == usize::MAX {
                    number[r] = count;
                    count += 1;
                }
                number[r]
            })
            .collect();
        (piece, count)
    }

    /// Indices of every node on the free edge (boundary) of the mesh,
    /// sorted: the nodes of element edges that belong to one element only,
    /// including the high-order nodes on those edges.
    pub fn boundary_nodes(&self) -> Vec<usize> {
        let p = self.order.degree();
        let count = self.edge_counts();
        let mut on_boundary = vec![false; self.nodes.len()];
        for el in self.elements() {
            for k in 0..3 {
                let (a, b) = (el[k], el[(k + 1) % 3]);
                if count[&(a.min(b), a.max(b))] == 1 {
                    on_boundary[a] = true;
                    on_boundary[b] = true;
                    for j in 0..p.saturating_sub(1) {
                        on_boundary[el[3 + k * (p - 1) + j]] = true;
                    }
                }
            }
        }
        (0..self.nodes.len()).filter(|&i| on_boundary[i]).collect()
    }

    /// The free edges (those of one element only) by their corner nodes
    /// `[a, b]`, `a < b`, sorted.
    pub fn boundary_edges(&self) -> Vec<[usize; 2]> {
        let mut edges: Vec<[usize; 2]> = (self.edge_counts().into_iter())
            .filter(|&(_, n)| n == 1)
            .map(|((a, b), _)| [a, b])
            .collect();
        edges.sort_unstable();
        edges
    }

    /// How many elements each edge `(a, b)` (corner nodes, `a < b`) has.
    fn edge_counts(&self) -> std::collections::HashMap<(usize, usize), usize> {
        let mut count = std::collections::HashMap::new();
        for el in self.elements() {
            for k in 0..3 {
                let (a, b) = (el[k], el[(k + 1) % 3]);
                *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        count
    }

    /// Axis-aligned bounding box `(min, max)` of the initial positions.
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for x in &self.nodes {
            for i in 0..3 {
                lo[i] = lo[i].min(x[i]);
                hi[i] = hi[i].max(x[i]);
            }
        }
        (lo, hi)
    }

    /// The length of the diagonal of the bounding box (m): the mesh's size
    /// in tolerances and messages.
    pub fn diagonal(&self) -> f64 {
        let (lo, hi) = self.bounding_box();
        ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt()
    }

    /// Index of the node whose initial position is nearest to `point`, and
    /// its distance (m). `None` for a mesh without nodes.
    pub fn nearest_node(&self, point: [f64; 3]) -> Option<(usize, f64)> {
        self.nodes
            .iter()
            .enumerate()
            .map(|(i, x)| {
                let d2: f64 = (0..3).map(|k| (x[k] - point[k]).powi(2)).sum();
                (i, d2)
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, d2)| (i, d2.sqrt()))
    }
}
