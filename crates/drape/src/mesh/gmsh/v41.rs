//! The `$Nodes` and `$Elements` sections of MSH 4.1, ASCII and binary: a
//! header, then entity blocks (of nodes, or of elements of one type).

#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use super::cursor::Reader;
use super::element_types::{Action, action, element_type};
use super::records::{BinaryBlock, BinaryInt, MIN_ASCII_NODE, Node, Triangles};
use super::{Location, MeshReadError};

const NODES: &str = "$Nodes";
const ELEMENTS: &str = "$Elements";

impl<'a> Reader<'a> {
    /// `$Nodes` of MSH 4.1: a header, then entity blocks of tags and
    /// coordinates.
    pub(super) fn nodes_v41(&mut self) -> Result<Vec<Node>, MeshReadError> {
        let header_at = self.here();
        let (blocks, count) = self.header_v41(NODES, "nodes")?;
        self.check_node_count(count, header_at)?;
        let min_record = if self.binary {
            self.size_t + 24
        } else {
            MIN_ASCII_NODE
        };
        let mut nodes = Vec::with_capacity(self.capacity(count, min_record));
        let mut total: u64 = 0;
        let mut tags = Vec::new();
        let mut fields = Vec::new();
        for b in 0..blocks {
            let n = self.node_block_v41(b, blocks, &mut tags, &mut fields, &mut nodes)?;
            total = total.saturating_add(n);
        }
        self.check_total_v41(NODES, "nodes", count, total, header_at)?;
        Ok(nodes)
    }

    /// `$Elements` of MSH 4.1: a header, then entity blocks of one element
    /// type.
    pub(super) fn elements_v41(&mut self, triangles: &mut Triangles) -> Result<(), MeshReadError> {
        let header_at = self.here();
        let (blocks, count) = self.header_v41(ELEMENTS, "elements")?;
        let mut total: u64 = 0;
        let mut fields = Vec::new();
        for b in 0..blocks {
            let n = self.element_block_v41(b, blocks, &mut fields, triangles)?;
            total = total.saturating_add(n);
        }
        self.check_total_v41(ELEMENTS, "elements", count, total, header_at)
    }

    /// The header of `$Nodes` or `$Elements` (`section`): the numbers of
    /// entity blocks and of `items` (`"nodes"` or `"elements"`); the
    /// smallest and largest tags that follow are not needed.
    fn header_v41(&mut self, section: &str, items: &str) -> Result<(u64, u64), MeshReadError> {
        if self.binary {
            let blocks = self.read_size_t(section)?;
            let count = self.read_size_t(section)?;
            self.read_size_t(section)?;
            self.read_size_t(section)?;
            return Ok((blocks, count));
        }
        let number_of_items = format!("the number of {items}");
        let ([blocks, count, _, _], at) = self.int_line(
            section,
            &format!("the {section} header (blocks, {items}, min tag, max tag)"),
            [
                "the number of blocks",
                &number_of_items,
                "the minimum tag",
                "the maximum tag",
            ],
        )?;
        let nonneg = |v: i64, what: &str| {
            u64::try_from(v).map_err(|_| self.syntax(at, format!("{what} is negative ({v})")))
        };
        Ok((
            nonneg(blocks, "the number of blocks")?,
            nonneg(count, &number_of_items)?,
        ))
    }

    /// Checks that the blocks held the `count` items the header announced.
    fn check_total_v41(
        &self,
        section: &str,
        items: &str,
        count: u64,
        total: u64,
        header_at: Location,
    ) -> Result<(), MeshReadError> {
        if total == count {
            Ok(())
        } else {
            Err(self.syntax(
                header_at,
                format!("{section} announces {count} {items}, but its blocks hold {total}"),
            ))
        }
    }

    /// Node block `b` of `blocks`: its header, the tags, then the
    /// coordinates (parametric ones skipped), added to `nodes`. Returns the
    /// number of nodes of the block.
    fn node_block_v41(
        &mut self,
        b: u64,
        blocks: u64,
        tags: &mut Vec<u64>,
        fields: &mut Vec<&'a [u8]>,
        nodes: &mut Vec<Node>,
    ) -> Result<u64, MeshReadError> {
        let block_at = self.here();
        let (dim, parametric, n) = if self.binary {
            let dim = self.read_i32(NODES)?;
            self.read_i32(NODES)?;
            let parametric = self.read_i32(NODES)?;
            let n = self.read_size_t(NODES)?;
            (i64::from(dim), i64::from(parametric), n)
        } else {
            let ([dim, _, parametric, n], at) = self.int_line(
                NODES,
                &format!("the header of node block {} of {blocks}", b + 1),
                [
                    "the entity dimension",
                    "the entity tag",
                    "the parametric flag",
                    "the number of nodes",
                ],
            )?;
            let n = u64::try_from(n)
                .map_err(|_| self.syntax(at, format!("the number of nodes is negative ({n})")))?;
            (dim, parametric, n)
        };
        if !(0..=3).contains(&dim) {
            return Err(self.syntax(
                block_at,
                format!("expected an entity dimension 0 to 3, found {dim}"),
            ));
        }
        let extra = match parametric {
            0 => 0,
            1 => usize::try_from(dim).unwrap_or(0),
            _ => {
                return Err(self.syntax(
                    block_at,
                    format!("expected a parametric flag 0 or 1, found {parametric}"),
                ));
            }
        };
        tags.clear();
        if self.binary {
            self.check_room(n, self.size_t + (3 + extra) * 8, NODES)?;
            tags.reserve(self.capacity(n, self.size_t));
            for _ in 0..n {
                tags.push(self.read_size_t(NODES)?);
            }
            for &tag in tags.iter() {
                let at = self.here();
                let x = self.read_xyz(NODES)?;
                self.take(extra * 8, NODES)?;
                self.insert_node(nodes, tag, x, at)?;
            }
        } else {
            tags.reserve(self.capacity(n, 2));
            for i in 0..n {
                let at = self.record(
                    NODES,
                    || format!("node tag {} of {n} in block {}", i + 1, b + 1),
                    fields,
                )?;
                if fields.len() == 3 + extra {
                    // A line of coordinates where a tag was due: the block
                    // holds fewer nodes than its header says (issue 35:
                    // "expected 1 number for a node tag, found 3").
                    return Err(self.syntax(
                        at,
                        format!(
                            "node block {} declares {n} nodes in its header, but after {i} node tags comes a line of {} numbers, coordinates by the look of it: the block holds fewer nodes than it declares",
                            b + 1,
                            fields.len()
                        ),
                    ));
                }
                self.expect_fields(fields, 1, "a node tag", at)?;
                tags.push(self.parse_u64(self.field(fields, 0, at)?, "a node tag", at)?);
            }
            for &tag in tags.iter() {
                let at = self.record(NODES, || format!("the coordinates of node {tag}"), fields)?;
                self.expect_fields(
                    fields,
                    3 + extra,
                    &format!("the coordinates of node {tag}"),
                    at,
                )?;
                let x = self.parse_xyz(fields, 0, at)?;
                self.insert_node(nodes, tag, x, at)?;
            }
        }
        Ok(n)
    }

    /// Element block `b` of `blocks`: its header, then its elements, whose
    /// triangles are added to `triangles`. Returns the number of elements
    /// of the block.
    fn element_block_v41(
        &mut self,
        b: u64,
        blocks: u64,
        fields: &mut Vec<&'a [u8]>,
        triangles: &mut Triangles,
    ) -> Result<u64, MeshReadError> {
        let block_at = self.here();
        let (ty, n) = if self.binary {
            self.read_i32(ELEMENTS)?;
            self.read_i32(ELEMENTS)?;
            let ty = self.read_int_u64(ELEMENTS, "element type")?;
            let n = self.read_size_t(ELEMENTS)?;
            (ty, n)
        } else {
            let ([_, _, ty, n], at) = self.int_line(
                ELEMENTS,
                &format!("the header of element block {} of {blocks}", b + 1),
                [
                    "the entity dimension",
                    "the entity tag",
                    "the element type",
                    "the number of elements",
                ],
            )?;
            let ty = u64::try_from(ty)
                .map_err(|_| self.syntax(at, format!("the element type is negative ({ty})")))?;
            let n = u64::try_from(n).map_err(|_| {
                self.syntax(at, format!("the number of elements is negative ({n})"))
            })?;
            (ty, n)
        };
        if self.binary {
            let Some((nn, _)) = element_type(ty) else {
                return Err(self.syntax(
                    block_at,
                    format!("unknown element type {ty}: its size in a binary file is unknown"),
                ));
            };
            let record = nn
                .checked_add(1)
                .and_then(|w| w.checked_mul(self.size_t))
                .ok_or_else(|| self.truncated(ELEMENTS))?;
            let block = BinaryBlock {
                element_type: ty,
                nodes: nn,
                count: n,
                record,
                padding: 0,
                int: BinaryInt::SizeT,
            };
            self.binary_element_block(&block, triangles)?;
            return Ok(n);
        }
        let act = action(ty);
        for i in 0..n {
            let at = self.record(
                ELEMENTS,
                || format!("element {} of {n} in block {}", i + 1, b + 1),
                fields,
            )?;
            match &act {
                Action::Keep(order) => {
                    let nn = order.nodes_per_element();
                    self.expect_fields(
                        fields,
                        nn + 1,
                        &format!("a {nn}-node triangle (tag and nodes)"),
                        at,
                    )?;
                    let tag = self.parse_u64(self.field(fields, 0, at)?, "an element tag", at)?;
                    self.push_triangle(triangles, *order, tag, at)?;
                    for tok in fields.iter().skip(1) {
                        let node = self.parse_u64(tok, "a node tag", at)?;
                        triangles.node_tags.push(node);
                    }
                }
                Action::Reject(description) => {
                    let tag = self.parse_u64(self.field(fields, 0, at)?, "an element tag", at)?;
                    return Err(self.reject(tag, ty, description.clone(), at));
                }
                Action::Skip => {}
            }
        }
        Ok(n)
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

    /// A node block whose header declares more nodes than it lists is
    /// refused naming the block, the count and what came instead of a
    /// tag (issue 35: "expected 1 number for a node tag, found 3").
    #[test]
    fn a_node_block_declaring_too_many_nodes_is_named() {
        let text = V41_T3.replace("0 1 0 2\n1\n2\n0 0 0", "0 1 0 3\n1\n2\n0 0 0");
        let e = parse(&text).unwrap_err().to_string();
        assert!(
            e.contains("node block 1 declares 3 nodes")
                && e.contains("after 2 node tags")
                && e.contains("line 25"),
            "{e}"
        );
    }

    #[test]
    fn v41_ascii_t3_with_entities_and_parametric_nodes() {
        let m = parse(V41_T3).unwrap();
        assert_eq!(m.order, ElementOrder::Linear);
        assert_eq!(m.nodes, SQUARE.to_vec());
        assert_eq!(m.connectivity, vec![0, 1, 2, 0, 2, 3]);
        no_panic_on_damage(V41_T3.as_bytes());
    }

    #[test]
    fn v41_ascii_t10() {
        // One cubic triangle with vertices (0,0), (3,0), (0,3); edge nodes
        // listed from their first vertex; interior node (1,1). Tags are
        // shuffled so that tag order differs from node order in the element.
        let mut text =
            String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 10 1 10\n2 1 0 10\n");
        let pts: [(u64, [f64; 3]); 10] = [
            (10, [0.0, 0.0, 0.0]),
            (9, [3.0, 0.0, 0.0]),
            (8, [0.0, 3.0, 0.0]),
            (7, [1.0, 0.0, 0.0]),
            (6, [2.0, 0.0, 0.0]),
            (5, [2.0, 1.0, 0.0]),
            (4, [1.0, 2.0, 0.0]),
            (3, [0.0, 2.0, 0.0]),
            (2, [0.0, 1.0, 0.0]),
            (1, [1.0, 1.0, 0.0]),
        ];
        for (t, _) in &pts {
            text += &format!("{t}\n");
        }
        for (_, x) in &pts {
            text += &format!("{} {} {}\n", x[0], x[1], x[2]);
        }
        text += "$EndNodes\n$Elements\n1 1 1 1\n2 1 21 1\n1 10 9 8 7 6 5 4 3 2 1\n$EndElements\n";
        let m = parse(&text).unwrap();
        assert_eq!(m.order, ElementOrder::Cubic);
        // Node i has the (i+1)-th smallest tag, i.e. tag i + 1.
        let mut by_tag = pts;
        by_tag.sort_by_key(|p| p.0);
        let expected: Vec<[f64; 3]> = by_tag.iter().map(|p| p.1).collect();
        assert_eq!(m.nodes, expected);
        assert_eq!(m.connectivity, vec![9, 8, 7, 6, 5, 4, 3, 2, 1, 0]);
    }

    #[test]
    fn v41_binary_t6() {
        let bytes = v41_binary_t6_bytes(None);
        let m = parse_msh(&bytes, "bin.msh").unwrap();
        assert_eq!(m.order, ElementOrder::Quadratic);
        assert_eq!(
            m.nodes,
            vec![
                [0.0, 0.0, 0.0],
                [2.0, 0.0, 0.0],
                [0.0, 2.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0]
            ]
        );
        assert_eq!(m.connectivity, vec![0, 1, 2, 3, 4, 5]);
        no_panic_on_damage(&bytes);
    }

    #[test]
    fn v41_binary_with_4_byte_size_t() {
        let mut b = Bin::new();
        let z = |b: &mut Bin, x: u32| {
            b.v.extend_from_slice(&x.to_le_bytes());
        };
        b.s("$MeshFormat\n4.1 1 4\n")
            .i(1)
            .s("\n$EndMeshFormat\n$Nodes\n");
        for x in [1, 3, 1, 3] {
            z(&mut b, x);
        }
        b.i(2).i(1).i(0);
        z(&mut b, 3);
        for t in [1, 2, 3] {
            z(&mut b, t);
        }
        for x in &SQUARE[..3] {
            b.f(x[0]).f(x[1]).f(x[2]);
        }
        b.s("\n$EndNodes\n$Elements\n");
        for x in [1, 1, 1, 1] {
            z(&mut b, x);
        }
        b.i(2).i(1).i(2);
        for x in [1, 1, 1, 2, 3] {
            z(&mut b, x);
        }
        b.s("\n$EndElements\n");
        let m = parse_msh(&b.v, "bin.msh").unwrap();
        assert_eq!(m.nodes, SQUARE[..3].to_vec());
        assert_eq!(m.connectivity, vec![0, 1, 2]);
    }
}
