//! The `$Nodes` and `$Elements` sections of MSH 2 (2.0, 2.1, 2.2), ASCII
//! and binary: one count, then one record per node or element.

#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use super::MeshReadError;
use super::cursor::Reader;
use super::element_types::{Action, action, element_type};
use super::records::{BinaryBlock, BinaryInt, MIN_ASCII_NODE, Node, Triangles};

/// The section the element functions read.
const ELEMENTS: &str = "$Elements";

impl Reader<'_> {
    /// `$Nodes` of MSH 2: a count, then `tag x y z` records.
    pub(super) fn nodes_v2(&mut self) -> Result<Vec<Node>, MeshReadError> {
        const SECTION: &str = "$Nodes";
        let (count, at) = self.count_line(SECTION, "the number of nodes")?;
        self.check_node_count(count, at)?;
        let mut nodes = Vec::new();
        if self.binary {
            const RECORD: usize = 4 + 3 * 8;
            self.check_room(count, RECORD, SECTION)?;
            nodes.reserve(self.capacity(count, RECORD));
            for _ in 0..count {
                let at = self.here();
                let tag = self.read_int_u64(SECTION, "node tag")?;
                let x = self.read_xyz(SECTION)?;
                self.insert_node(&mut nodes, tag, x, at)?;
            }
        } else {
            nodes.reserve(self.capacity(count, MIN_ASCII_NODE));
            let mut fields = Vec::new();
            for i in 0..count {
                let at = self.record(
                    SECTION,
                    || format!("node {} of {count}", i + 1),
                    &mut fields,
                )?;
                self.expect_fields(&fields, 4, "node", at)?;
                let tag = self.parse_u64(self.field(&fields, 0, at)?, "a node tag", at)?;
                let x = self.parse_xyz(&fields, 1, at)?;
                self.insert_node(&mut nodes, tag, x, at)?;
            }
        }
        Ok(nodes)
    }

    /// `$Elements` of MSH 2: a count, then `tag type ntags tags... nodes...`
    /// records (in binary, in blocks of one type).
    pub(super) fn elements_v2(&mut self, triangles: &mut Triangles) -> Result<(), MeshReadError> {
        let (count, _) = self.count_line(ELEMENTS, "the number of elements")?;
        if self.binary {
            self.elements_v2_binary(count, triangles)
        } else {
            self.elements_v2_ascii(count, triangles)
        }
    }

    /// The binary records of `$Elements`: blocks of elements of one type,
    /// each opened by its type, number of elements and number of tags.
    fn elements_v2_binary(
        &mut self,
        count: u64,
        triangles: &mut Triangles,
    ) -> Result<(), MeshReadError> {
        let mut read: u64 = 0;
        while read < count {
            let at = self.here();
            let ty = self.read_int_u64(ELEMENTS, "element type")?;
            let num = self.read_int_u64(ELEMENTS, "number of elements")?;
            let ntags = self.read_int_u64(ELEMENTS, "number of tags")?;
            if num == 0 {
                return Err(self.syntax(at, "element block of 0 elements"));
            }
            read = read.saturating_add(num);
            if read > count {
                return Err(self.syntax(
                    at,
                    format!("element blocks hold more than the {count} elements announced"),
                ));
            }
            let Some((nn, _)) = element_type(ty) else {
                return Err(self.syntax(
                    at,
                    format!("unknown element type {ty}: its size in a binary file is unknown"),
                ));
            };
            let ntags = usize::try_from(ntags).unwrap_or(usize::MAX);
            let record = ntags
                .checked_add(1 + nn)
                .and_then(|w| w.checked_mul(4))
                .ok_or_else(|| self.truncated(ELEMENTS))?;
            let block = BinaryBlock {
                element_type: ty,
                nodes: nn,
                count: num,
                record,
                padding: ntags.saturating_mul(4),
                int: BinaryInt::Int,
            };
            self.binary_element_block(&block, triangles)?;
        }
        Ok(())
    }

    /// The ASCII records of `$Elements`, `count` of them.
    fn elements_v2_ascii(
        &mut self,
        count: u64,
        triangles: &mut Triangles,
    ) -> Result<(), MeshReadError> {
        let mut fields = Vec::new();
        for i in 0..count {
            let at = self.record(
                ELEMENTS,
                || format!("element {} of {count}", i + 1),
                &mut fields,
            )?;
            if fields.len() < 3 {
                return Err(self.syntax(
                    at,
                    format!(
                        "expected at least 3 numbers for element (tag, type, number of tags), found {}",
                        fields.len()
                    ),
                ));
            }
            let tag = self.parse_u64(self.field(&fields, 0, at)?, "an element tag", at)?;
            let ty = self.parse_u64(self.field(&fields, 1, at)?, "an element type", at)?;
            match action(ty) {
                Action::Keep(order) => {
                    let ntags =
                        self.parse_usize(self.field(&fields, 2, at)?, "the number of tags", at)?;
                    let nn = order.nodes_per_element();
                    let first = ntags.saturating_add(3);
                    let expected = first.saturating_add(nn);
                    if fields.len() != expected {
                        return Err(self.syntax(
                            at,
                            format!(
                                "expected {expected} numbers for a {nn}-node triangle with {ntags} tags, found {}",
                                fields.len()
                            ),
                        ));
                    }
                    self.push_triangle(triangles, order, tag, at)?;
                    for tok in fields.iter().skip(first) {
                        let node = self.parse_u64(tok, "a node tag", at)?;
                        triangles.node_tags.push(node);
                    }
                }
                Action::Reject(description) => {
                    return Err(self.reject(tag, ty, description, at));
                }
                Action::Skip => {}
            }
        }
        Ok(())
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
    use crate::mesh::ElementOrder;
    use crate::mesh::gmsh::fixtures::*;
    use crate::mesh::gmsh::parse_msh;

    #[test]
    fn v22_ascii_t3_with_physical_names_point_and_line() {
        let m = parse(V22_T3).unwrap();
        assert_eq!(m.order, ElementOrder::Linear);
        assert_eq!(m.nodes, SQUARE.to_vec());
        assert_eq!(m.connectivity, vec![0, 1, 2, 0, 2, 3]);
        no_panic_on_damage(V22_T3.as_bytes());
    }

    #[test]
    fn v22_ascii_t6() {
        let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n\
            1 0 0 0\n2 2 0 0\n3 0 2 0\n4 1 0 0\n5 1 1 0.5\n6 0 1 0\n$EndNodes\n\
            $Elements\n2\n1 8 2 1 1 1 2 4\n2 9 2 3 7 1 2 3 4 5 6\n$EndElements\n";
        let m = parse(text).unwrap();
        assert_eq!(m.order, ElementOrder::Quadratic);
        assert_eq!(
            m.nodes,
            vec![
                [0.0, 0.0, 0.0],
                [2.0, 0.0, 0.0],
                [0.0, 2.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.5],
                [0.0, 1.0, 0.0]
            ]
        );
        assert_eq!(m.connectivity, vec![0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn v22_binary_t3_both_endians() {
        for big in [false, true] {
            let bytes = v22_binary_t3(big);
            let m = parse_msh(&bytes, "bin.msh").unwrap();
            assert_eq!(m.order, ElementOrder::Linear);
            assert_eq!(m.nodes, SQUARE.to_vec());
            assert_eq!(m.connectivity, vec![0, 1, 2, 0, 2, 3]);
        }
        no_panic_on_damage(&v22_binary_t3(false));
    }
}
