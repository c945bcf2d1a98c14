//! Checks that a mesh can be used: indices in range, finite coordinates,
//! no repeated nodes, no degenerate, folded or inconsistently oriented
//! triangles.

use super::Mesh;
use super::lagrange::ShapeFunctions;
use crate::vec3::{cross, dot, norm, sub};

/// Why a mesh cannot be used. Element and node numbers are 0-based indices
/// into the mesh as read (the messages say so).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The mesh has no element.
    #[error("the mesh has no triangle")]
    Empty,
    /// A connectivity entry names a node that does not exist.
    #[error(
        "element {element} (0-based, in the order read) refers to node {node}, but the mesh has {count} nodes"
    )]
    NodeOutOfRange {
        /// Element index.
        element: usize,
        /// Offending node index.
        node: usize,
        /// Number of nodes.
        count: usize,
    },
    /// A node coordinate is NaN or infinite.
    #[error("node {node} (0-based) has a non-finite coordinate {coordinates:?}")]
    NonFinite {
        /// Node index.
        node: usize,
        /// Its coordinates.
        coordinates: [f64; 3],
    },
    /// The same node appears twice in one element.
    #[error("element {element} (0-based, in the order read) uses node {node} more than once")]
    RepeatedNode {
        /// Element index.
        element: usize,
        /// Repeated node.
        node: usize,
    },
    /// The element's vertices are (nearly) collinear.
    #[error(
        "element {element} (0-based, in the order read) is degenerate: its area {area:.3e} m^2 is below 1e-10 of its longest edge squared"
    )]
    Degenerate {
        /// Element index.
        element: usize,
        /// Area of the vertex triangle (m^2).
        area: f64,
    },
    /// A curved element folds over itself: its tangent plane turns against
    /// the plane of its vertices.
    #[error(
        "element {element} (0-based, in the order read) is inverted: its Jacobian changes sign inside the element"
    )]
    Inverted {
        /// Element index.
        element: usize,
    },
    /// More than two elements share an edge: the mesh is not a surface
    /// there (a T-junction of panels).
    #[error(
        "the edge between nodes {} and {} is shared by elements {} (0-based, in the order read): a surface has at most two elements on an edge (join panels at a T-junction as separate pieces)",
        .nodes.0, .nodes.1, .elements.iter().map(usize::to_string).collect::<Vec<_>>().join(", ")
    )]
    NonManifold {
        /// The edge's end nodes (0-based).
        nodes: (usize, usize),
        /// The elements on it.
        elements: Vec<usize>,
    },
    /// One triangle listed twice: two elements on the same corner nodes
    /// (in either orientation).
    #[error(
        "elements {first} and {element} (0-based, in the order read) have the same corner nodes {nodes:?}: a triangle listed twice"
    )]
    Duplicate {
        /// The first element on these nodes.
        first: usize,
        /// The element that repeats it.
        element: usize,
        /// Its corner nodes (0-based), as `element` lists them.
        nodes: [usize; 3],
    },
    /// Two neighbouring elements have opposite orientations (normals).
    #[error(
        "elements {element} and {neighbour} (0-based, in the order read) share an edge but are oriented oppositely (one of them is inverted)"
    )]
    InconsistentOrientation {
        /// One element.
        element: usize,
        /// Its neighbour across the shared edge.
        neighbour: usize,
    },
}

impl Mesh {
    /// Checks the mesh; the first problem found is returned.
    ///
    /// A triangle is degenerate when `2 A < 1e-10 l_max^2` (with `A` the
    /// area of its vertex triangle and `l_max` its longest edge); a curved
    /// element is inverted when `(G_1 x G_2) . n_v <= 0` at one of its nodes
    /// or quadrature points (`n_v` the normal of the vertex triangle);
    /// neighbours must traverse their shared edge in opposite directions.
    pub fn validate(&self) -> Result<(), MeshError> {
        let npe = self.order.nodes_per_element();
        if self.connectivity.is_empty() || !self.connectivity.len().is_multiple_of(npe) {
            return Err(MeshError::Empty);
        }
        for (i, x) in self.nodes.iter().enumerate() {
            if !x.iter().all(|c| c.is_finite()) {
                return Err(MeshError::NonFinite {
                    node: i,
                    coordinates: *x,
                });
            }
        }
        for (e, el) in self.elements().enumerate() {
            for (k, &n) in el.iter().enumerate() {
                if n >= self.nodes.len() {
                    return Err(MeshError::NodeOutOfRange {
                        element: e,
                        node: n,
                        count: self.nodes.len(),
                    });
                }
                if el[..k].contains(&n) {
                    return Err(MeshError::RepeatedNode {
                        element: e,
                        node: n,
                    });
                }
            }
        }
        let shape = ShapeFunctions::new(self.order);
        for (e, el) in self.elements().enumerate() {
            let (x0, x1, x2) = (self.nodes[el[0]], self.nodes[el[1]], self.nodes[el[2]]);
            let nv = cross(sub(x1, x0), sub(x2, x0));
            let l2 = [sub(x1, x0), sub(x2, x1), sub(x0, x2)]
                .iter()
                .map(|d| dot(*d, *d))
                .fold(0.0, f64::max);
            if norm(nv) < 1e-10 * l2 {
                return Err(MeshError::Degenerate {
                    element: e,
                    area: 0.5 * norm(nv),
                });
            }
            if npe > 3 {
                for xi in shape.nodes().iter().chain(shape.check_points()) {
                    let (_, dn) = shape.evaluate(*xi);
                    let mut g = [[0.0; 3]; 2];
                    for (a, &n) in el.iter().enumerate() {
                        for k in 0..2 {
                            for i in 0..3 {
                                g[k][i] += self.nodes[n][i] * dn[a][k];
                            }
                        }
                    }
                    if dot(cross(g[0], g[1]), nv) <= 0.0 {
                        return Err(MeshError::Inverted { element: e });
                    }
                }
            }
        }
        // A triangle listed twice would be reported below as two elements
        // oriented oppositely (or as a T-junction): name it for what it is.
        let mut corners: std::collections::HashMap<[usize; 3], usize> =
            std::collections::HashMap::with_capacity(self.element_count());
        for (e, el) in self.elements().enumerate() {
            let nodes = [el[0], el[1], el[2]];
            let mut key = nodes;
            key.sort_unstable();
            if let Some(&first) = corners.get(&key) {
                return Err(MeshError::Duplicate {
                    first,
                    element: e,
                    nodes,
                });
            }
            corners.insert(key, e);
        }
        drop(corners);
        // Every edge on at most two elements (checked before orientation:
        // on a third, two of them would run along it the same way).
        let mut on_edge: std::collections::HashMap<(usize, usize), Vec<usize>> =
            std::collections::HashMap::with_capacity(self.element_count() * 2);
        for (e, el) in self.elements().enumerate() {
            for k in 0..3 {
                let (a, b) = (el[k], el[(k + 1) % 3]);
                on_edge.entry((a.min(b), a.max(b))).or_default().push(e);
            }
        }
        if let Some((&nodes, elements)) = on_edge
            .iter()
            .filter(|(_, list)| list.len() > 2)
            .min_by_key(|(edge, _)| **edge)
        {
            return Err(MeshError::NonManifold {
                nodes,
                elements: elements.clone(),
            });
        }
        drop(on_edge);
        let mut edge_owner: std::collections::HashMap<(usize, usize), usize> =
            std::collections::HashMap::with_capacity(self.element_count() * 2);
        for (e, el) in self.elements().enumerate() {
            for k in 0..3 {
                let (a, b) = (el[k], el[(k + 1) % 3]);
                // An edge traversed a -> b twice means two elements with
                // opposite normals.
                if let Some(&other) = edge_owner.get(&(a, b)) {
                    return Err(MeshError::InconsistentOrientation {
                        element: other,
                        neighbour: e,
                    });
                }
                edge_owner.insert((a, b), e);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ElementOrder;

    fn square(connectivity: Vec<usize>) -> Mesh {
        Mesh {
            nodes: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            order: ElementOrder::Linear,
            connectivity,
        }
    }

    /// A triangle listed twice, the same way round or flipped, is named as
    /// a duplicate (it was "oriented oppositely"); an element flipped
    /// against a different neighbour still is.
    #[test]
    fn a_triangle_listed_twice_is_a_duplicate() {
        for (second, nodes) in [([0, 1, 2], [0, 1, 2]), ([2, 1, 0], [2, 1, 0])] {
            let mut c = vec![0, 1, 2, 0, 2, 3];
            c.extend(second);
            assert_eq!(
                square(c).validate(),
                Err(MeshError::Duplicate {
                    first: 0,
                    element: 2,
                    nodes
                })
            );
        }
        assert_eq!(
            square(vec![0, 1, 2, 0, 3, 2]).validate(),
            Err(MeshError::InconsistentOrientation {
                element: 0,
                neighbour: 1
            })
        );
        square(vec![0, 1, 2, 0, 2, 3])
            .validate()
            .expect("a good square");
    }
}
