//! Reader for Gmsh MSH meshes: formats 2.2 and 4.1, ASCII and binary.
//!
//! [`read_msh`] reads a file, [`parse_msh`] parses bytes already in memory.
//! Both return a [`Mesh`] of Lagrange triangles, or a [`MeshReadError`]
//! whose message names the file and, in an ASCII file, the 1-based line
//! (in a binary file, the byte offset) where the problem was found.
//!
//! What is read:
//!
//! * `$MeshFormat`, which must come first: version 2.2 (2.0 and 2.1, whose
//!   `$Nodes` and `$Elements` are the same, are accepted too) or 4.1, file
//!   type 0 (ASCII) or 1 (binary). A binary file's endianness is taken from
//!   its marker integer `1`, so big-endian files are read too. In a binary
//!   4.1 file the data-size field gives the size of `size_t` (4 or 8 bytes);
//!   a binary 2.2 file must have data size 8.
//! * `$Nodes`: one section. Node tags may be any positive integers, in any
//!   order, with gaps; a tag defined twice is an error. In 4.1 the nodes come
//!   in entity blocks, whose parametric coordinates, if present, are skipped.
//!   A NaN or infinite coordinate is an error naming the node.
//! * `$Elements`: one section. Triangles of type 2 (3 nodes, order 1), 9
//!   (6 nodes, order 2) and 21 (10 nodes, order 3) are kept; all triangles of
//!   the file must be of the same order. Points, lines and volume elements
//!   (types 15, 1, 8, 26, 4, 11, ...) are skipped. Any other surface element
//!   (quadrangles, incomplete or higher-order triangles) is an error, rather
//!   than a hole silently left in the surface.
//! * Every other section (`$Entities`, `$PhysicalNames`, `$Periodic`,
//!   `$NodeData`, ...) is skipped up to its `$End...` line.
//!
//! The node order inside an element is the same in Gmsh and in [`Mesh`], so
//! the connectivity is taken over as it is.
//!
//! The mesh keeps only the nodes used by its triangles, in increasing order
//! of their Gmsh tags: node `i` of the mesh is the node with the `i`-th
//! smallest tag among those used (for a file whose tags are `1..=n`, all
//! used, node `i` has tag `i + 1`).
//!
//! The reader does not panic on any input and never reserves memory for
//! more records than the rest of the file could hold, so a corrupt count
//! gives an error, not an out-of-memory abort. A `$Nodes` section that
//! declares more nodes than a mesh may have ([`MAX_MESH_NODES`], or the cap
//! given to [`parse_msh_at_most`]) is refused from its count, before its
//! nodes are read — all the nodes the file holds count, used by its
//! triangles or not.
//!
//! The reader's files: this one holds the entry points and the
//! `$MeshFormat` header that tells the versions apart; `cursor` the byte
//! cursor with its ASCII and binary primitives; `v22` and `v41` the
//! `$Nodes` and `$Elements` sections of each format; `element_types` Gmsh's
//! table of element types; `records` the nodes and triangles read and the
//! mesh built from them. Each file keeps the house rules below: no
//! indexing, `unwrap`, `expect` or `panic!` on the file's bytes, and every
//! error names the file, the line (or byte) and the value.

#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use std::path::Path;

use super::{MAX_MESH_NODES, Mesh};
use cursor::{Reader, show};
use records::{Node, Triangles, finish};

pub use super::{Location, MeshReadError};

mod cursor;
mod element_types;
#[cfg(test)]
mod fixtures;
mod records;
mod v22;
mod v41;

/// Reads a Gmsh MSH file (2.2 or 4.1, ASCII or binary) into a [`Mesh`].
///
/// Error messages name the file as `path` displays. See the
/// [module documentation](self) for what is read and how nodes are numbered.
pub fn read_msh(path: &Path) -> Result<Mesh, MeshReadError> {
    let (bytes, file) = MeshReadError::read(path)?;
    parse_msh(&bytes, &file)
}

/// Parses the bytes of a Gmsh MSH file (2.2 or 4.1, ASCII or binary) into a
/// [`Mesh`]; `source` is the file name used in error messages. A file
/// whose `$Nodes` declares more than [`MAX_MESH_NODES`] nodes is refused
/// ([`MeshReadError::TooManyNodes`]).
///
/// See the [module documentation](self) for what is read and how nodes are
/// numbered.
pub fn parse_msh(bytes: &[u8], source: &str) -> Result<Mesh, MeshReadError> {
    parse_msh_at_most(bytes, source, MAX_MESH_NODES)
}

/// [`parse_msh`] with a cap of `max_nodes` nodes: a `$Nodes` section that
/// declares more is refused from its count, before its nodes are read or
/// memory is reserved for them.
pub fn parse_msh_at_most(
    bytes: &[u8],
    source: &str,
    max_nodes: usize,
) -> Result<Mesh, MeshReadError> {
    let mut reader = Reader::new(bytes, source);
    reader.max_nodes = max_nodes;
    let version = reader.read_format()?;
    let mut nodes: Option<Vec<Node>> = None;
    let mut triangles = Triangles::default();
    let mut elements_seen = false;
    while let Some((line, at)) = reader.next_content_line() {
        let Some(name) = line.strip_prefix(b"$") else {
            return Err(reader.syntax(
                at,
                format!(
                    "expected a section header such as $Nodes, found '{}'",
                    show(line)
                ),
            ));
        };
        match name {
            b"Nodes" => {
                if nodes.is_some() {
                    return Err(
                        reader.syntax(at, "a second $Nodes section (only one is supported)")
                    );
                }
                nodes = Some(match version {
                    Version::V2 => reader.nodes_v2()?,
                    Version::V41 => reader.nodes_v41()?,
                });
                reader.expect_end("Nodes")?;
            }
            b"Elements" => {
                if elements_seen {
                    return Err(
                        reader.syntax(at, "a second $Elements section (only one is supported)")
                    );
                }
                elements_seen = true;
                match version {
                    Version::V2 => reader.elements_v2(&mut triangles)?,
                    Version::V41 => reader.elements_v41(&mut triangles)?,
                }
                reader.expect_end("Elements")?;
            }
            b"MeshFormat" => {
                return Err(reader.syntax(at, "a second $MeshFormat section"));
            }
            _ if name.starts_with(b"End") => {
                return Err(reader.syntax(
                    at,
                    format!("'{}' closes a section that was not opened", show(line)),
                ));
            }
            _ => reader.skip_section(name)?,
        }
    }
    finish(source, nodes.unwrap_or_default(), triangles)
}

/// MSH format family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Version {
    /// 2.0, 2.1, 2.2.
    V2,
    /// 4.1.
    V41,
}

impl Reader<'_> {
    /// Reads `$MeshFormat`, which must open the file.
    fn read_format(&mut self) -> Result<Version, MeshReadError> {
        const SECTION: &str = "$MeshFormat";
        let Some((line, at)) = self.next_content_line() else {
            return Err(MeshReadError::Syntax {
                file: self.file.to_owned(),
                at: None,
                message: "the file is empty; a Gmsh file starts with $MeshFormat".to_owned(),
            });
        };
        if line != SECTION.as_bytes() {
            return Err(self.syntax(
                at,
                format!(
                    "expected $MeshFormat at the start of a Gmsh file, found '{}'",
                    show(line)
                ),
            ));
        }
        let mut fields = Vec::new();
        let at = self.record(
            SECTION,
            || "version, file type and data size".to_owned(),
            &mut fields,
        )?;
        self.expect_fields(&fields, 3, "the version, file type and data size", at)?;
        let version_tok = self.field(&fields, 0, at)?;
        let v = self.parse_f64(version_tok, "a version number", at)?;
        let tenths = (v * 10.0).round();
        let version = if (v * 10.0 - tenths).abs() > 1e-9 {
            None
        } else if (20.0..=22.0).contains(&tenths) {
            Some(Version::V2)
        } else if tenths == 41.0 {
            Some(Version::V41)
        } else {
            None
        };
        let Some(version) = version else {
            return Err(MeshReadError::UnsupportedVersion {
                file: self.file.to_owned(),
                at: Some(at),
                version: show(version_tok),
            });
        };
        let file_type = self.parse_u64(self.field(&fields, 1, at)?, "the file type", at)?;
        let data_size = self.parse_u64(self.field(&fields, 2, at)?, "the data size", at)?;
        match file_type {
            0 => {}
            1 => {
                match (version, data_size) {
                    (Version::V2, 8) => {}
                    (Version::V41, 4 | 8) => self.size_t = if data_size == 4 { 4 } else { 8 },
                    (Version::V2, _) => {
                        return Err(self.syntax(
                            at,
                            format!("binary MSH 2 needs data size 8, found {data_size}"),
                        ));
                    }
                    (Version::V41, _) => {
                        return Err(self.syntax(
                            at,
                            format!(
                                "binary MSH 4.1 needs data size (size of size_t) 4 or 8, found {data_size}"
                            ),
                        ));
                    }
                }
                self.binary = true;
                let at = self.here();
                let marker = self.take(4, SECTION)?;
                let marker: [u8; 4] = marker.try_into().map_err(|_| self.truncated(SECTION))?;
                if i32::from_le_bytes(marker) == 1 {
                    self.big_endian = false;
                } else if i32::from_be_bytes(marker) == 1 {
                    self.big_endian = true;
                } else {
                    return Err(self.syntax(
                        at,
                        format!(
                            "expected the binary endianness marker 1, found {}",
                            i32::from_le_bytes(marker)
                        ),
                    ));
                }
            }
            _ => {
                return Err(self.syntax(
                    at,
                    format!("expected file type 0 (ASCII) or 1 (binary), found {file_type}"),
                ));
            }
        }
        self.expect_end("MeshFormat")?;
        Ok(version)
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
    use super::*;
    use crate::mesh::gmsh::fixtures::*;

    #[test]
    fn skips_a_byte_order_mark() {
        let bytes = [b"\xEF\xBB\xBF".as_slice(), V22_T3.as_bytes()].concat();
        let m = parse_msh(&bytes, "bom.msh").unwrap();
        assert_eq!(m.nodes, SQUARE.to_vec());
    }

    #[test]
    fn skips_lines_points_and_unknown_sections() {
        let text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Comments\nanything $Nodes\n$EndComments\n\
            $PhysicalNames\n2\n1 5 \"seam\"\n2 6 \"panel\"\n$EndPhysicalNames\n\
            $Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n1 1 0\n$EndNodes\n\
            $Elements\n4 5 1 5\n0 1 15 1\n1 1\n1 1 1 1\n2 1 2\n1 2 8 1\n3 1 2 3\n2 1 2 2\n4 1 2 3\n5 3 1 2\n$EndElements\n\
            $Periodic\n0\n$EndPeriodic\n$NodeData\n1\n\"x\"\n0\n0\n$EndNodeData\n";
        let m = parse(text).unwrap();
        assert_eq!(m.nodes, SQUARE[..3].to_vec());
        assert_eq!(m.connectivity, vec![0, 1, 2, 2, 0, 1]);
    }

    #[test]
    fn reads_a_file_and_reports_io_errors_with_the_name() {
        let dir = std::env::temp_dir().join(format!("drape-gmsh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("square.msh");
        std::fs::write(&path, V22_T3).unwrap();
        let m = read_msh(&path).unwrap();
        assert_eq!(m.element_count(), 2);
        let missing = dir.join("missing.msh");
        let err = read_msh(&missing).unwrap_err();
        assert!(matches!(err, MeshReadError::Io { .. }));
        assert_eq!(err.file(), missing.display().to_string());
        assert!(err.to_string().starts_with(&missing.display().to_string()));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The cap on nodes, given small: a file declaring up to it is read,
    /// one declaring more is refused from its count — in 2.2 and 4.1,
    /// ASCII and binary — naming the file, the count's line (or byte) and
    /// the count, before any node is read: a count far beyond the file's
    /// records says the same.
    #[test]
    fn a_declared_node_count_above_the_cap_is_refused_before_reading() {
        for (text, line) in [(V22_T3, 10), (V41_T3, 21)] {
            let m = parse_msh_at_most(text.as_bytes(), "cap.msh", 4).unwrap();
            assert_eq!(m.node_count(), 4);
            let err = parse_msh_at_most(text.as_bytes(), "cap.msh", 3).unwrap_err();
            assert!(
                matches!(
                    &err,
                    MeshReadError::TooManyNodes {
                        count: 4,
                        declared: true,
                        limit: 3,
                        ..
                    }
                ),
                "{err:?}"
            );
            assert_eq!(
                err.to_string(),
                format!(
                    "cap.msh, line {line}: $Nodes declares 4 nodes, more than the 3 nodes a mesh may have; use a coarser mesh"
                )
            );
        }
        for bytes in [v22_binary_t3(false), v41_binary_t6_bytes(None)] {
            let err = parse_msh_at_most(&bytes, "cap.msh", 2).unwrap_err();
            assert!(
                matches!(
                    err,
                    MeshReadError::TooManyNodes {
                        at: Some(Location::Byte(_)),
                        ..
                    }
                ),
                "{err:?}"
            );
        }
        let huge = V22_T3.replace("$Nodes\n4\n", "$Nodes\n3000001\n");
        let err = parse(&huge).unwrap_err();
        assert_eq!(
            err.to_string(),
            "test.msh, line 10: $Nodes declares 3000001 nodes, more than the 3000000 nodes a mesh may have; use a coarser mesh"
        );
    }

    #[test]
    fn error_unsupported_version() {
        let err = parse("$MeshFormat\n3.0 0 8\n$EndMeshFormat\n").unwrap_err();
        assert!(
            matches!(&err, MeshReadError::UnsupportedVersion { version, .. } if version == "3.0"),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            "test.msh, line 2: unsupported MSH version 3.0 (supported: 2.2 and 4.1)"
        );
        for v in ["4", "4.0", "1.0", "4.2"] {
            let err = parse(&format!("$MeshFormat\n{v} 0 8\n$EndMeshFormat\n")).unwrap_err();
            assert!(
                matches!(err, MeshReadError::UnsupportedVersion { .. }),
                "{err}"
            );
        }
    }
}
