//! What the Gmsh reader collects from either format — nodes with their tags,
//! triangles with their node tags — and the mesh built from it: node tags
//! checked (none twice, every reference defined), the used nodes kept in
//! increasing tag order, the connectivity renumbered.

#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use super::cursor::Reader;
use super::element_types::{Action, action};
use super::{Location, MeshReadError};
use crate::mesh::{ElementOrder, Mesh};

/// A node as read from `$Nodes`.
pub(super) struct Node {
    pub(super) tag: u64,
    pub(super) x: [f64; 3],
    pub(super) at: Location,
}

/// Triangles read so far: their node tags, element tags and locations.
#[derive(Default)]
pub(super) struct Triangles {
    /// Order of the first triangle; all must share it.
    pub(super) order: Option<ElementOrder>,
    /// Node tags, `order.nodes_per_element()` per element.
    pub(super) node_tags: Vec<u64>,
    /// Element tag and location of each triangle.
    pub(super) elements: Vec<(u64, Location)>,
}

/// Minimal bytes of one ASCII node record (`"1 0 0 0\n"`), to cap
/// pre-allocation.
pub(super) const MIN_ASCII_NODE: usize = 8;

/// How a binary file writes the tags in an element record: as `int` in
/// MSH 2, as `size_t` in MSH 4.1.
#[derive(Debug, Clone, Copy)]
pub(super) enum BinaryInt {
    /// A 4-byte `int`, which must not be negative.
    Int,
    /// A `size_t` of the file's data size.
    SizeT,
}

/// A binary block of elements of one type, as its header announces it.
pub(super) struct BinaryBlock {
    /// Gmsh element type.
    pub(super) element_type: u64,
    /// Nodes per element of that type.
    pub(super) nodes: usize,
    /// Number of elements in the block.
    pub(super) count: u64,
    /// Bytes of one element record.
    pub(super) record: usize,
    /// Bytes between an element's tag and its nodes (MSH 2's tags).
    pub(super) padding: usize,
    /// How the tags are written.
    pub(super) int: BinaryInt,
}

impl Reader<'_> {
    pub(super) fn insert_node(
        &self,
        nodes: &mut Vec<Node>,
        tag: u64,
        x: [f64; 3],
        at: Location,
    ) -> Result<(), MeshReadError> {
        if let Some(&value) = x.iter().find(|v| !v.is_finite()) {
            return Err(MeshReadError::NonFiniteCoordinate {
                file: self.file.to_owned(),
                at: Some(at),
                node: tag,
                value,
            });
        }
        nodes.push(Node { tag, x, at });
        Ok(())
    }

    /// Reads a binary block of elements of one type (MSH 2 or 4.1): keeps
    /// its triangles, rejects the block at its first element if the type is
    /// another surface, and skips it otherwise.
    pub(super) fn binary_element_block(
        &mut self,
        block: &BinaryBlock,
        triangles: &mut Triangles,
    ) -> Result<(), MeshReadError> {
        const SECTION: &str = "$Elements";
        let ty = block.element_type;
        self.check_room(block.count, block.record, SECTION)?;
        match action(ty) {
            Action::Keep(order) => {
                for _ in 0..block.count {
                    let at = self.here();
                    let tag = self.read_tag(block.int, "element tag")?;
                    self.take(block.padding, SECTION)?;
                    self.push_triangle(triangles, order, tag, at)?;
                    for _ in 0..block.nodes {
                        let node = self.read_tag(block.int, "node tag")?;
                        triangles.node_tags.push(node);
                    }
                }
            }
            Action::Reject(description) => {
                if block.count > 0 {
                    let at = self.here();
                    let tag = self.read_tag(block.int, "element tag")?;
                    return Err(self.reject(tag, ty, description, at));
                }
            }
            Action::Skip => {
                let bytes = usize::try_from(block.count)
                    .ok()
                    .and_then(|n| n.checked_mul(block.record))
                    .ok_or_else(|| self.truncated(SECTION))?;
                self.take(bytes, SECTION)?;
            }
        }
        Ok(())
    }

    /// Reads a tag (`what`) of an element record in `$Elements`.
    fn read_tag(&mut self, int: BinaryInt, what: &str) -> Result<u64, MeshReadError> {
        const SECTION: &str = "$Elements";
        match int {
            BinaryInt::Int => self.read_int_u64(SECTION, what),
            BinaryInt::SizeT => self.read_size_t(SECTION),
        }
    }

    pub(super) fn push_triangle(
        &self,
        triangles: &mut Triangles,
        order: ElementOrder,
        tag: u64,
        at: Location,
    ) -> Result<(), MeshReadError> {
        match triangles.order {
            None => triangles.order = Some(order),
            Some(first) if first != order => {
                return Err(MeshReadError::MixedOrders {
                    file: self.file.to_owned(),
                    at: Some(at),
                    element: tag,
                    expected: first.degree(),
                    found: order.degree(),
                });
            }
            Some(_) => {}
        }
        triangles.elements.push((tag, at));
        Ok(())
    }

    pub(super) fn reject(
        &self,
        tag: u64,
        element_type: u64,
        description: String,
        at: Location,
    ) -> MeshReadError {
        MeshReadError::UnsupportedElement {
            file: self.file.to_owned(),
            at: Some(at),
            element: tag,
            element_type,
            description,
        }
    }
}

/// Builds the mesh: checks the node tags (no duplicates, every reference
/// defined), keeps the used nodes in increasing tag order and renumbers the
/// connectivity.
pub(super) fn finish(
    file: &str,
    nodes: Vec<Node>,
    triangles: Triangles,
) -> Result<Mesh, MeshReadError> {
    let Some(order) = triangles.order else {
        return Err(MeshReadError::NoTriangles {
            file: file.to_owned(),
        });
    };
    let duplicate = |node: &Node| MeshReadError::Syntax {
        file: file.to_owned(),
        at: Some(node.at),
        message: format!("node {} is defined twice", node.tag),
    };
    // The nodes' positions in `nodes`, in increasing tag order, and a way to
    // find a tag's position: a table indexed by tag when the tags are dense
    // enough (the usual case: 1..=n), else a sorted list.
    let max_tag = nodes.iter().map(|n| n.tag).max().unwrap_or(0);
    let dense_limit = u64::try_from(nodes.len())
        .unwrap_or(u64::MAX)
        .saturating_mul(4)
        .saturating_add(64);
    let table = if max_tag < dense_limit {
        let size = usize::try_from(max_tag).map_or(0, |m| m.saturating_add(1));
        let mut slots = vec![usize::MAX; size];
        for (i, node) in nodes.iter().enumerate() {
            let slot = usize::try_from(node.tag)
                .ok()
                .and_then(|t| slots.get_mut(t));
            match slot {
                Some(slot) if *slot == usize::MAX => *slot = i,
                _ => return Err(duplicate(node)),
            }
        }
        TagTable::Dense(slots)
    } else {
        let mut sorted: Vec<(u64, usize)> =
            nodes.iter().enumerate().map(|(i, n)| (n.tag, i)).collect();
        sorted.sort_unstable();
        for pair in sorted.windows(2) {
            if let [(a, _), (b, j)] = *pair
                && a == b
            {
                return Err(nodes.get(j).map_or_else(
                    || MeshReadError::Syntax {
                        file: file.to_owned(),
                        at: None,
                        message: format!("node {a} is defined twice"),
                    },
                    duplicate,
                ));
            }
        }
        TagTable::Sparse(sorted)
    };

    // Positions (in `nodes`) of the triangles' nodes, and which are used.
    let npe = order.nodes_per_element();
    let mut used = vec![false; nodes.len()];
    let mut positions = Vec::with_capacity(triangles.node_tags.len());
    for (el, &(element, at)) in triangles
        .node_tags
        .chunks_exact(npe)
        .zip(&triangles.elements)
    {
        for &tag in el {
            let found = table
                .find(tag)
                .and_then(|p| used.get_mut(p).map(|u| (p, u)));
            let Some((p, u)) = found else {
                return Err(MeshReadError::UnknownNode {
                    file: file.to_owned(),
                    at: Some(at),
                    element,
                    node_tag: tag,
                });
            };
            *u = true;
            positions.push(p);
        }
    }

    // Renumber the used nodes in increasing tag order.
    let mut new_index = vec![usize::MAX; nodes.len()];
    let mut out_nodes = Vec::new();
    for p in table.positions_by_tag() {
        if let (Some(true), Some(slot), Some(node)) =
            (used.get(p).copied(), new_index.get_mut(p), nodes.get(p))
        {
            *slot = out_nodes.len();
            out_nodes.push(node.x);
        }
    }
    let connectivity = positions
        .iter()
        .map(|&p| new_index.get(p).copied().unwrap_or(usize::MAX))
        .collect();
    Ok(Mesh {
        nodes: out_nodes,
        order,
        connectivity,
    })
}

/// Finds the position of a node tag in the list of nodes.
enum TagTable {
    /// Position by tag (`usize::MAX` for no node).
    Dense(Vec<usize>),
    /// `(tag, position)`, sorted by tag.
    Sparse(Vec<(u64, usize)>),
}

impl TagTable {
    fn find(&self, tag: u64) -> Option<usize> {
        match self {
            Self::Dense(slots) => usize::try_from(tag)
                .ok()
                .and_then(|t| slots.get(t))
                .copied()
                .filter(|&p| p != usize::MAX),
            Self::Sparse(sorted) => sorted
                .binary_search_by_key(&tag, |&(t, _)| t)
                .ok()
                .and_then(|k| sorted.get(k))
                .map(|&(_, p)| p),
        }
    }

    /// Positions of all nodes, in increasing tag order.
    fn positions_by_tag(&self) -> Box<dyn Iterator<Item = usize> + '_> {
        match self {
            Self::Dense(slots) => Box::new(slots.iter().copied().filter(|&p| p != usize::MAX)),
            Self::Sparse(sorted) => Box::new(sorted.iter().map(|&(_, p)| p)),
        }
    }
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]
mod tests {
    use crate::mesh::gmsh::fixtures::*;
    use crate::mesh::gmsh::{Location, MeshReadError, parse_msh};

    #[test]
    fn non_contiguous_tags_keep_used_nodes_in_tag_order() {
        let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n\
            100 0 1 0\n7 1 1 0\n50 9 9 9\n3 1 0 0\n10 0 0 0\n$EndNodes\n\
            $Elements\n2\n20 2 0 10 3 7\n30 2 0 10 7 100\n$EndElements\n";
        let m = parse(text).unwrap();
        // Used tags, sorted: 3, 7, 10, 100 (50 is unused and dropped).
        assert_eq!(m.nodes, vec![SQUARE[1], SQUARE[2], SQUARE[0], SQUARE[3]]);
        assert_eq!(m.connectivity, vec![2, 0, 1, 2, 1, 3]);
    }

    #[test]
    fn error_unknown_node_tag() {
        let text = V22_T3.replace("4 2 2 2 1 1 3 4", "4 2 2 2 1 1 3 99");
        let err = parse(&text).unwrap_err();
        assert!(
            matches!(
                err,
                MeshReadError::UnknownNode {
                    element: 4,
                    node_tag: 99,
                    at: Some(Location::Line(21)),
                    ..
                }
            ),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            "test.msh, line 21: element 4 refers to node 99, which is not defined"
        );
    }

    #[test]
    fn error_nan_coordinate() {
        let text = V22_T3.replace("2 1 0 0\n", "2 NaN 0 0\n");
        let err = parse(&text).unwrap_err();
        assert!(
            matches!(
                err,
                MeshReadError::NonFiniteCoordinate {
                    node: 2,
                    at: Some(Location::Line(12)),
                    ..
                }
            ),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            "test.msh, line 12: node 2 has a non-finite coordinate (NaN)"
        );
        let text = V41_T3.replace("1 0 0\n1 2 1 1", "1 0 inf\n1 2 1 1");
        let err = parse(&text).unwrap_err();
        assert!(
            matches!(err, MeshReadError::NonFiniteCoordinate { node: 2, .. }),
            "{err}"
        );
        // Binary.
        let mut bytes = v22_binary_t3(false);
        let nan = f64::NAN.to_le_bytes();
        let at = bytes
            .windows(8)
            .position(|w| w == 1.0f64.to_le_bytes())
            .unwrap();
        bytes[at..at + 8].copy_from_slice(&nan);
        let err = parse_msh(&bytes, "bin.msh").unwrap_err();
        assert!(
            matches!(
                err,
                MeshReadError::NonFiniteCoordinate {
                    node: 2,
                    at: Some(Location::Byte(_)),
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn error_mixed_orders() {
        let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n\
            1 0 0 0\n2 2 0 0\n3 0 2 0\n4 1 0 0\n5 1 1 0\n6 0 1 0\n$EndNodes\n\
            $Elements\n2\n1 2 0 1 2 3\n2 9 0 1 2 3 4 5 6\n$EndElements\n";
        let err = parse(text).unwrap_err();
        assert!(
            matches!(
                err,
                MeshReadError::MixedOrders {
                    element: 2,
                    expected: 1,
                    found: 2,
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn error_duplicate_node_and_bad_endianness_marker() {
        let text = V22_T3.replace("3 1 1 0\n", "2 1 1 0\n");
        let err = parse(&text).unwrap_err();
        assert_eq!(
            err.to_string(),
            "test.msh, line 13: node 2 is defined twice"
        );
        // Sparse tags take another path.
        let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n\
            1000 0 0 0\n5 1 0 0\n1000 0 1 0\n$EndNodes\n\
            $Elements\n1\n1 2 0 1000 5 1000\n$EndElements\n";
        let err = parse(text).unwrap_err();
        assert_eq!(
            err.to_string(),
            "test.msh, line 8: node 1000 is defined twice"
        );
        let mut bytes = v22_binary_t3(false);
        let at = bytes
            .windows(4)
            .position(|w| w == 1i32.to_le_bytes())
            .unwrap();
        bytes[at] = 7;
        let err = parse_msh(&bytes, "bin.msh").unwrap_err();
        assert!(
            err.to_string()
                .contains("expected the binary endianness marker 1, found 7"),
            "{err}"
        );
    }
}
