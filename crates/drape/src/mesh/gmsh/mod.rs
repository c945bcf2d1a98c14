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
//! gives an error, not an out-of-memory abort.

#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use std::fmt;
use std::path::Path;

use super::{ElementOrder, Mesh};

/// Where in a file a problem was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// 1-based line number, in a text file.
    Line(usize),
    /// 0-based byte offset, in a binary file.
    Byte(usize),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Line(n) => write!(f, "line {n}"),
            Self::Byte(n) => write!(f, "byte {n}"),
        }
    }
}

/// `", line 12"`, or nothing without a location.
fn suffix(at: &Option<Location>) -> String {
    match at {
        Some(at) => format!(", {at}"),
        None => String::new(),
    }
}

/// Error reading a mesh file, Gmsh MSH (see [`read_msh`]) or Wavefront OBJ
/// (see [`read_obj`](super::obj::read_obj)).
///
/// Every variant carries the file name (as given to the reader) and, where
/// it is known, the [`Location`] of the problem; the message reads like
/// `fabric.msh, line 12: expected 4 numbers for node, found 3`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshReadError {
    /// The file could not be read.
    #[error("{file}: cannot read the file: {source}")]
    Io {
        /// File name.
        file: String,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// The file is not well formed.
    #[error("{file}{}: {message}", suffix(.at))]
    Syntax {
        /// File name.
        file: String,
        /// Where the problem was found.
        at: Option<Location>,
        /// What is wrong, e.g. `expected 4 numbers for node, found 3`.
        message: String,
    },
    /// The `$MeshFormat` version is neither 2.2 nor 4.1.
    #[error(
        "{file}{}: unsupported MSH version {version} (supported: 2.2 and 4.1)",
        suffix(.at)
    )]
    UnsupportedVersion {
        /// File name.
        file: String,
        /// Where the version was found.
        at: Option<Location>,
        /// The version as written in the file, e.g. `3.0`.
        version: String,
    },
    /// An element refers to a node that the file does not define.
    #[error(
        "{file}{}: element {element} refers to node {node_tag}, which is not defined",
        suffix(.at)
    )]
    UnknownNode {
        /// File name.
        file: String,
        /// Where the element was found.
        at: Option<Location>,
        /// Tag (Gmsh) or 1-based number (OBJ face) of the element.
        element: u64,
        /// Tag (Gmsh) or 1-based index (OBJ vertex) of the missing node.
        node_tag: u64,
    },
    /// A node has a NaN or infinite coordinate.
    #[error(
        "{file}{}: node {node} has a non-finite coordinate ({value})",
        suffix(.at)
    )]
    NonFiniteCoordinate {
        /// File name.
        file: String,
        /// Where the node was found.
        at: Option<Location>,
        /// Tag (Gmsh) or 1-based index (OBJ vertex) of the node.
        node: u64,
        /// The offending coordinate.
        value: f64,
    },
    /// The triangles of the file are not all of the same order.
    #[error(
        "{file}{}: element {element} is a triangle of order {found}, but earlier \
         triangles are of order {expected}; all triangles must have the same order",
        suffix(.at)
    )]
    MixedOrders {
        /// File name.
        file: String,
        /// Where the first element of another order was found.
        at: Option<Location>,
        /// Tag of that element.
        element: u64,
        /// Order of the first triangle of the file.
        expected: usize,
        /// Order of this element.
        found: usize,
    },
    /// A surface element that is not a 3-, 6- or 10-node triangle, such as a
    /// quadrangle.
    #[error(
        "{file}{}: element {element} is a {description} (Gmsh type {element_type}); \
         only 3-, 6- and 10-node triangles (types 2, 9, 21) are supported",
        suffix(.at)
    )]
    UnsupportedElement {
        /// File name.
        file: String,
        /// Where the element was found.
        at: Option<Location>,
        /// Tag of the element.
        element: u64,
        /// Gmsh element type number.
        element_type: u64,
        /// What the element is, e.g. `4-node quadrangle`.
        description: String,
    },
    /// The file holds no triangles.
    #[error("{file}: the file holds no triangles")]
    NoTriangles {
        /// File name.
        file: String,
    },
    /// The file ends before a section is complete.
    #[error("{file}: the file ends inside {section}, which is incomplete")]
    Truncated {
        /// File name.
        file: String,
        /// The incomplete section, e.g. `$Nodes`.
        section: String,
    },
    /// The OBJ parser (`tobj`) rejected the file.
    #[error("{file}: invalid OBJ data: {source}")]
    Obj {
        /// File name.
        file: String,
        /// The parser's error.
        source: tobj::LoadError,
    },
}

impl MeshReadError {
    /// Name of the file the error is about.
    pub fn file(&self) -> &str {
        match self {
            Self::Io { file, .. }
            | Self::Syntax { file, .. }
            | Self::UnsupportedVersion { file, .. }
            | Self::UnknownNode { file, .. }
            | Self::NonFiniteCoordinate { file, .. }
            | Self::MixedOrders { file, .. }
            | Self::UnsupportedElement { file, .. }
            | Self::NoTriangles { file }
            | Self::Truncated { file, .. }
            | Self::Obj { file, .. } => file,
        }
    }

    /// Where in the file the problem was found, when that is known.
    pub fn location(&self) -> Option<Location> {
        match self {
            Self::Syntax { at, .. }
            | Self::UnsupportedVersion { at, .. }
            | Self::UnknownNode { at, .. }
            | Self::NonFiniteCoordinate { at, .. }
            | Self::MixedOrders { at, .. }
            | Self::UnsupportedElement { at, .. } => *at,
            _ => None,
        }
    }
}

impl MeshReadError {
    /// Reads a whole mesh file, with its name as messages show it.
    pub(crate) fn read(path: &Path) -> Result<(Vec<u8>, String), MeshReadError> {
        let file = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|source| MeshReadError::Io {
            file: file.clone(),
            source,
        })?;
        Ok((bytes, file))
    }
}

/// Reads a Gmsh MSH file (2.2 or 4.1, ASCII or binary) into a [`Mesh`].
///
/// Error messages name the file as `path` displays. See the
/// [module documentation](self) for what is read and how nodes are numbered.
pub fn read_msh(path: &Path) -> Result<Mesh, MeshReadError> {
    let (bytes, file) = MeshReadError::read(path)?;
    parse_msh(&bytes, &file)
}

/// Parses the bytes of a Gmsh MSH file (2.2 or 4.1, ASCII or binary) into a
/// [`Mesh`]; `source` is the file name used in error messages.
///
/// See the [module documentation](self) for what is read and how nodes are
/// numbered.
pub fn parse_msh(bytes: &[u8], source: &str) -> Result<Mesh, MeshReadError> {
    // A UTF-8 byte-order mark, which some editors write, is skipped.
    let start = if bytes.starts_with(b"\xEF\xBB\xBF") {
        3
    } else {
        0
    };
    let mut reader = Reader {
        bytes,
        pos: start,
        line: 1,
        file: source,
        binary: false,
        big_endian: false,
        size_t: 8,
    };
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

/// A node as read from `$Nodes`.
struct Node {
    tag: u64,
    x: [f64; 3],
    at: Location,
}

/// Triangles read so far: their node tags, element tags and locations.
#[derive(Default)]
struct Triangles {
    /// Order of the first triangle; all must share it.
    order: Option<ElementOrder>,
    /// Node tags, `order.nodes_per_element()` per element.
    node_tags: Vec<u64>,
    /// Element tag and location of each triangle.
    elements: Vec<(u64, Location)>,
}

/// Minimal bytes of one ASCII node record (`"1 0 0 0\n"`), to cap
/// pre-allocation.
const MIN_ASCII_NODE: usize = 8;

/// Kinds of Gmsh elements, to describe them and tell surfaces apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Point,
    Line,
    Triangle,
    Quadrangle,
    Tetrahedron,
    Hexahedron,
    Prism,
    Pyramid,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Self::Point => "point",
            Self::Line => "line",
            Self::Triangle => "triangle",
            Self::Quadrangle => "quadrangle",
            Self::Tetrahedron => "tetrahedron",
            Self::Hexahedron => "hexahedron",
            Self::Prism => "prism",
            Self::Pyramid => "pyramid",
        }
    }

    fn is_surface(self) -> bool {
        matches!(self, Self::Triangle | Self::Quadrangle)
    }
}

/// Number of nodes and kind of a Gmsh element type (from Gmsh's
/// `GmshDefines.h`); `None` for types of no fixed size or unknown.
fn element_type(t: u64) -> Option<(usize, Kind)> {
    use Kind::*;
    let r = match t {
        1 => (2, Line),
        2 => (3, Triangle),
        3 => (4, Quadrangle),
        4 => (4, Tetrahedron),
        5 => (8, Hexahedron),
        6 => (6, Prism),
        7 => (5, Pyramid),
        8 => (3, Line),
        9 => (6, Triangle),
        10 => (9, Quadrangle),
        11 => (10, Tetrahedron),
        12 => (27, Hexahedron),
        13 => (18, Prism),
        14 => (14, Pyramid),
        15 => (1, Point),
        16 => (8, Quadrangle),
        17 => (20, Hexahedron),
        18 => (15, Prism),
        19 => (13, Pyramid),
        20 => (9, Triangle),
        21 => (10, Triangle),
        22 => (12, Triangle),
        23 => (15, Triangle),
        24 => (15, Triangle),
        25 => (21, Triangle),
        26 => (4, Line),
        27 => (5, Line),
        28 => (6, Line),
        29 => (20, Tetrahedron),
        30 => (35, Tetrahedron),
        31 => (56, Tetrahedron),
        32 => (34, Tetrahedron),
        33 => (52, Tetrahedron),
        36 => (16, Quadrangle),
        37 => (25, Quadrangle),
        38 => (36, Quadrangle),
        39 => (12, Quadrangle),
        40 => (16, Quadrangle),
        41 => (20, Quadrangle),
        42 => (28, Triangle),
        43 => (36, Triangle),
        44 => (45, Triangle),
        45 => (55, Triangle),
        46 => (66, Triangle),
        47 => (49, Quadrangle),
        48 => (64, Quadrangle),
        49 => (81, Quadrangle),
        50 => (100, Quadrangle),
        51 => (121, Quadrangle),
        52 => (18, Triangle),
        53 => (21, Triangle),
        54 => (24, Triangle),
        55 => (27, Triangle),
        56 => (30, Triangle),
        57 => (24, Quadrangle),
        58 => (28, Quadrangle),
        59 => (32, Quadrangle),
        60 => (36, Quadrangle),
        61 => (40, Quadrangle),
        62 => (7, Line),
        63 => (8, Line),
        64 => (9, Line),
        65 => (10, Line),
        66 => (11, Line),
        71 => (84, Tetrahedron),
        72 => (120, Tetrahedron),
        73 => (165, Tetrahedron),
        74 => (220, Tetrahedron),
        75 => (286, Tetrahedron),
        79 => (74, Tetrahedron),
        80 => (100, Tetrahedron),
        81 => (130, Tetrahedron),
        82 => (164, Tetrahedron),
        83 => (202, Tetrahedron),
        90 => (40, Prism),
        91 => (75, Prism),
        92 => (64, Hexahedron),
        93 => (125, Hexahedron),
        94 => (216, Hexahedron),
        95 => (343, Hexahedron),
        96 => (512, Hexahedron),
        97 => (729, Hexahedron),
        98 => (1000, Hexahedron),
        99 => (56, Hexahedron),
        100 => (98, Hexahedron),
        101 => (152, Hexahedron),
        102 => (222, Hexahedron),
        103 => (296, Hexahedron),
        104 => (386, Hexahedron),
        105 => (488, Hexahedron),
        106 => (126, Prism),
        107 => (196, Prism),
        108 => (288, Prism),
        109 => (405, Prism),
        110 => (550, Prism),
        111 => (38, Prism),
        112 => (66, Prism),
        113 => (102, Prism),
        114 => (146, Prism),
        115 => (198, Prism),
        116 => (258, Prism),
        117 => (326, Prism),
        118 => (30, Pyramid),
        119 => (55, Pyramid),
        120 => (91, Pyramid),
        121 => (140, Pyramid),
        122 => (204, Pyramid),
        123 => (285, Pyramid),
        124 => (385, Pyramid),
        125 => (29, Pyramid),
        126 => (50, Pyramid),
        127 => (77, Pyramid),
        128 => (110, Pyramid),
        129 => (149, Pyramid),
        130 => (194, Pyramid),
        131 => (245, Pyramid),
        _ => return None,
    };
    Some(r)
}

/// Order of the supported triangle types.
fn triangle_order(t: u64) -> Option<ElementOrder> {
    match t {
        2 => Some(ElementOrder::Linear),
        9 => Some(ElementOrder::Quadratic),
        21 => Some(ElementOrder::Cubic),
        _ => None,
    }
}

/// What to do with an element of a type.
enum Action {
    /// Keep: a supported triangle.
    Keep(ElementOrder),
    /// Reject: an unsupported surface element.
    Reject(String),
    /// Skip: points, lines, volumes and unknown types.
    Skip,
}

fn action(t: u64) -> Action {
    if let Some(order) = triangle_order(t) {
        return Action::Keep(order);
    }
    match element_type(t) {
        Some((n, kind)) if kind.is_surface() => Action::Reject(format!("{n}-node {}", kind.name())),
        _ => Action::Skip,
    }
}

/// Shows a token or line of the file in a message: lossy UTF-8, at most 40
/// characters.
fn show(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(bytes);
    let mut out: String = text.chars().take(40).collect();
    if text.chars().nth(40).is_some() {
        out.push('…');
    }
    out
}

/// Splits a line into whitespace-separated fields.
fn split_fields<'a>(line: &'a [u8], out: &mut Vec<&'a [u8]>) {
    out.clear();
    out.extend(
        line.split(|b| b.is_ascii_whitespace())
            .filter(|t| !t.is_empty()),
    );
}

/// Cursor over the bytes of an MSH file.
struct Reader<'a> {
    bytes: &'a [u8],
    /// Offset of the next unread byte.
    pos: usize,
    /// 1-based number of the line that starts at `pos` (text parts).
    line: usize,
    file: &'a str,
    binary: bool,
    big_endian: bool,
    /// Size of `size_t` in a binary 4.1 file.
    size_t: usize,
}

impl<'a> Reader<'a> {
    fn here(&self) -> Location {
        if self.binary {
            Location::Byte(self.pos)
        } else {
            Location::Line(self.line)
        }
    }

    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    fn syntax(&self, at: Location, message: impl Into<String>) -> MeshReadError {
        MeshReadError::Syntax {
            file: self.file.to_owned(),
            at: Some(at),
            message: message.into(),
        }
    }

    fn truncated(&self, section: &str) -> MeshReadError {
        MeshReadError::Truncated {
            file: self.file.to_owned(),
            section: section.to_owned(),
        }
    }

    /// The next line without its line end, and where it starts; `None` at
    /// the end of the file.
    fn next_line(&mut self) -> Option<(&'a [u8], Location)> {
        let rest = self.bytes.get(self.pos..).filter(|r| !r.is_empty())?;
        let at = self.here();
        let line = rest.split(|&b| b == b'\n').next().unwrap_or(rest);
        self.pos = self
            .pos
            .saturating_add(line.len().saturating_add(1))
            .min(self.bytes.len());
        self.line = self.line.saturating_add(1);
        Some((line.strip_suffix(b"\r").unwrap_or(line), at))
    }

    /// The next line that is not blank, trimmed.
    fn next_content_line(&mut self) -> Option<(&'a [u8], Location)> {
        loop {
            let (line, at) = self.next_line()?;
            let line = line.trim_ascii();
            if !line.is_empty() {
                return Some((line, at));
            }
        }
    }

    /// Reads the next record line of a section into `fields`. A line that
    /// starts a new section (`$...`) means the section has fewer records
    /// than it announced.
    fn record(
        &mut self,
        section: &str,
        what: impl FnOnce() -> String,
        fields: &mut Vec<&'a [u8]>,
    ) -> Result<Location, MeshReadError> {
        let (line, at) = self
            .next_content_line()
            .ok_or_else(|| self.truncated(section))?;
        if line.starts_with(b"$") {
            return Err(self.syntax(
                at,
                format!(
                    "{section} ends early: expected {}, found '{}'",
                    what(),
                    show(line)
                ),
            ));
        }
        split_fields(line, fields);
        Ok(at)
    }

    /// Checks that a record has `n` fields.
    fn expect_fields(
        &self,
        fields: &[&[u8]],
        n: usize,
        what: &str,
        at: Location,
    ) -> Result<(), MeshReadError> {
        if fields.len() == n {
            Ok(())
        } else {
            Err(self.syntax(
                at,
                format!(
                    "expected {n} number{} for {what}, found {}",
                    if n == 1 { "" } else { "s" },
                    fields.len()
                ),
            ))
        }
    }

    fn field<'f>(
        &self,
        fields: &[&'f [u8]],
        i: usize,
        at: Location,
    ) -> Result<&'f [u8], MeshReadError> {
        fields
            .get(i)
            .copied()
            .ok_or_else(|| self.syntax(at, format!("missing field {}", i + 1)))
    }

    fn parse_u64(&self, tok: &[u8], what: &str, at: Location) -> Result<u64, MeshReadError> {
        std::str::from_utf8(tok)
            .ok()
            .and_then(|s| s.parse::<u64>().ok())
            .ok_or_else(|| {
                self.syntax(
                    at,
                    format!(
                        "expected {what} (a non-negative integer), found '{}'",
                        show(tok)
                    ),
                )
            })
    }

    fn parse_i64(&self, tok: &[u8], what: &str, at: Location) -> Result<i64, MeshReadError> {
        std::str::from_utf8(tok)
            .ok()
            .and_then(|s| s.parse::<i64>().ok())
            .ok_or_else(|| {
                self.syntax(
                    at,
                    format!("expected {what} (an integer), found '{}'", show(tok)),
                )
            })
    }

    fn parse_usize(&self, tok: &[u8], what: &str, at: Location) -> Result<usize, MeshReadError> {
        let v = self.parse_u64(tok, what, at)?;
        usize::try_from(v).map_err(|_| self.syntax(at, format!("{what} {v} is too large")))
    }

    fn parse_f64(&self, tok: &[u8], what: &str, at: Location) -> Result<f64, MeshReadError> {
        std::str::from_utf8(tok)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .ok_or_else(|| {
                self.syntax(
                    at,
                    format!("expected {what} (a number), found '{}'", show(tok)),
                )
            })
    }

    /// Parses three coordinates from `fields[first..first + 3]`.
    fn parse_xyz(
        &self,
        fields: &[&[u8]],
        first: usize,
        at: Location,
    ) -> Result<[f64; 3], MeshReadError> {
        let mut x = [0.0; 3];
        for (k, (xk, name)) in x.iter_mut().zip(["x", "y", "z"]).enumerate() {
            let tok = self.field(fields, first + k, at)?;
            *xk = self.parse_f64(tok, &format!("coordinate {name}"), at)?;
        }
        Ok(x)
    }

    /// Reads a line holding a single count.
    fn count_line(&mut self, section: &str, what: &str) -> Result<(u64, Location), MeshReadError> {
        let mut fields = Vec::new();
        let at = self.record(section, || what.to_owned(), &mut fields)?;
        self.expect_fields(&fields, 1, what, at)?;
        let tok = self.field(&fields, 0, at)?;
        Ok((self.parse_u64(tok, what, at)?, at))
    }

    /// Reads a line of `N` integers (`N` named in `names`).
    fn int_line<const N: usize>(
        &mut self,
        section: &str,
        what: &str,
        names: [&str; N],
    ) -> Result<([i64; N], Location), MeshReadError> {
        let mut fields = Vec::new();
        let at = self.record(section, || what.to_owned(), &mut fields)?;
        self.expect_fields(&fields, N, what, at)?;
        let mut out = [0i64; N];
        for (k, (o, name)) in out.iter_mut().zip(names).enumerate() {
            *o = self.parse_i64(self.field(&fields, k, at)?, name, at)?;
        }
        Ok((out, at))
    }

    /// Skips to the end of section `$name`.
    fn skip_section(&mut self, name: &[u8]) -> Result<(), MeshReadError> {
        let end = [b"$End".as_slice(), name].concat();
        loop {
            let Some((line, _)) = self.next_line() else {
                return Err(self.truncated(&format!("${}", show(name))));
            };
            if line.trim_ascii() == end.as_slice() {
                return Ok(());
            }
        }
    }

    /// Reads the `$End{name}` line that closes a section.
    fn expect_end(&mut self, name: &str) -> Result<(), MeshReadError> {
        let (line, at) = self
            .next_content_line()
            .ok_or_else(|| self.truncated(&format!("${name}")))?;
        if line.strip_prefix(b"$End") == Some(name.as_bytes()) {
            Ok(())
        } else {
            Err(self.syntax(at, format!("expected $End{name}, found '{}'", show(line))))
        }
    }

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

    // ----- binary -----

    fn take(&mut self, n: usize, section: &str) -> Result<&'a [u8], MeshReadError> {
        let end = self
            .pos
            .checked_add(n)
            .ok_or_else(|| self.truncated(section))?;
        let bytes = self
            .bytes
            .get(self.pos..end)
            .ok_or_else(|| self.truncated(section))?;
        self.pos = end;
        Ok(bytes)
    }

    fn take_array<const N: usize>(&mut self, section: &str) -> Result<[u8; N], MeshReadError> {
        let bytes = self.take(N, section)?;
        bytes.try_into().map_err(|_| self.truncated(section))
    }

    fn read_i32(&mut self, section: &str) -> Result<i32, MeshReadError> {
        let b = self.take_array::<4>(section)?;
        Ok(if self.big_endian {
            i32::from_be_bytes(b)
        } else {
            i32::from_le_bytes(b)
        })
    }

    /// Reads a non-negative `int` (a tag or count).
    fn read_int_u64(&mut self, section: &str, what: &str) -> Result<u64, MeshReadError> {
        let at = self.here();
        let v = self.read_i32(section)?;
        u64::try_from(v).map_err(|_| self.syntax(at, format!("{what} is negative ({v})")))
    }

    fn read_size_t(&mut self, section: &str) -> Result<u64, MeshReadError> {
        if self.size_t == 4 {
            let b = self.take_array::<4>(section)?;
            Ok(u64::from(if self.big_endian {
                u32::from_be_bytes(b)
            } else {
                u32::from_le_bytes(b)
            }))
        } else {
            let b = self.take_array::<8>(section)?;
            Ok(if self.big_endian {
                u64::from_be_bytes(b)
            } else {
                u64::from_le_bytes(b)
            })
        }
    }

    fn read_f64(&mut self, section: &str) -> Result<f64, MeshReadError> {
        let b = self.take_array::<8>(section)?;
        Ok(if self.big_endian {
            f64::from_be_bytes(b)
        } else {
            f64::from_le_bytes(b)
        })
    }

    fn read_xyz(&mut self, section: &str) -> Result<[f64; 3], MeshReadError> {
        Ok([
            self.read_f64(section)?,
            self.read_f64(section)?,
            self.read_f64(section)?,
        ])
    }

    /// Checks that `count` records of `record` bytes fit in the rest of the
    /// file, before reading (or reserving memory for) them.
    fn check_room(&self, count: u64, record: usize, section: &str) -> Result<(), MeshReadError> {
        let need = u64::try_from(record)
            .ok()
            .and_then(|r| count.checked_mul(r));
        let have = u64::try_from(self.remaining()).unwrap_or(u64::MAX);
        if need.is_none_or(|need| need > have) {
            Err(self.truncated(section))
        } else {
            Ok(())
        }
    }

    /// Capacity to reserve for `count` records of at least `min_record`
    /// bytes each: no more than the rest of the file can hold.
    fn capacity(&self, count: u64, min_record: usize) -> usize {
        let fit = self.remaining() / min_record.max(1);
        usize::try_from(count).map_or(fit, |c| c.min(fit))
    }

    // ----- nodes -----

    fn insert_node(
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

    /// `$Nodes` of MSH 2: a count, then `tag x y z` records.
    fn nodes_v2(&mut self) -> Result<Vec<Node>, MeshReadError> {
        const SECTION: &str = "$Nodes";
        let (count, _) = self.count_line(SECTION, "the number of nodes")?;
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

    /// `$Nodes` of MSH 4.1: a header, then entity blocks of tags and
    /// coordinates.
    fn nodes_v41(&mut self) -> Result<Vec<Node>, MeshReadError> {
        const SECTION: &str = "$Nodes";
        let header_at = self.here();
        let (blocks, count) = if self.binary {
            let blocks = self.read_size_t(SECTION)?;
            let count = self.read_size_t(SECTION)?;
            self.read_size_t(SECTION)?;
            self.read_size_t(SECTION)?;
            (blocks, count)
        } else {
            let ([blocks, count, _, _], at) = self.int_line(
                SECTION,
                "the $Nodes header (blocks, nodes, min tag, max tag)",
                [
                    "the number of blocks",
                    "the number of nodes",
                    "the minimum tag",
                    "the maximum tag",
                ],
            )?;
            let nonneg = |v: i64, what: &str| {
                u64::try_from(v).map_err(|_| self.syntax(at, format!("{what} is negative ({v})")))
            };
            (
                nonneg(blocks, "the number of blocks")?,
                nonneg(count, "the number of nodes")?,
            )
        };
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
            let block_at = self.here();
            let (dim, parametric, n) = if self.binary {
                let dim = self.read_i32(SECTION)?;
                self.read_i32(SECTION)?;
                let parametric = self.read_i32(SECTION)?;
                let n = self.read_size_t(SECTION)?;
                (i64::from(dim), i64::from(parametric), n)
            } else {
                let ([dim, _, parametric, n], at) = self.int_line(
                    SECTION,
                    &format!("the header of node block {} of {blocks}", b + 1),
                    [
                        "the entity dimension",
                        "the entity tag",
                        "the parametric flag",
                        "the number of nodes",
                    ],
                )?;
                let n = u64::try_from(n).map_err(|_| {
                    self.syntax(at, format!("the number of nodes is negative ({n})"))
                })?;
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
                self.check_room(n, self.size_t + (3 + extra) * 8, SECTION)?;
                tags.reserve(self.capacity(n, self.size_t));
                for _ in 0..n {
                    tags.push(self.read_size_t(SECTION)?);
                }
                for &tag in &tags {
                    let at = self.here();
                    let x = self.read_xyz(SECTION)?;
                    self.take(extra * 8, SECTION)?;
                    self.insert_node(&mut nodes, tag, x, at)?;
                }
            } else {
                tags.reserve(self.capacity(n, 2));
                for i in 0..n {
                    let at = self.record(
                        SECTION,
                        || format!("node tag {} of {n} in block {}", i + 1, b + 1),
                        &mut fields,
                    )?;
                    self.expect_fields(&fields, 1, "a node tag", at)?;
                    tags.push(self.parse_u64(self.field(&fields, 0, at)?, "a node tag", at)?);
                }
                for &tag in &tags {
                    let at = self.record(
                        SECTION,
                        || format!("the coordinates of node {tag}"),
                        &mut fields,
                    )?;
                    self.expect_fields(
                        &fields,
                        3 + extra,
                        &format!("the coordinates of node {tag}"),
                        at,
                    )?;
                    let x = self.parse_xyz(&fields, 0, at)?;
                    self.insert_node(&mut nodes, tag, x, at)?;
                }
            }
            total = total.saturating_add(n);
        }
        if total != count {
            return Err(self.syntax(
                header_at,
                format!("$Nodes announces {count} nodes, but its blocks hold {total}"),
            ));
        }
        Ok(nodes)
    }

    // ----- elements -----

    fn push_triangle(
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

    fn reject(
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

    /// `$Elements` of MSH 2: a count, then `tag type ntags tags... nodes...`
    /// records (in binary, in blocks of one type).
    fn elements_v2(&mut self, triangles: &mut Triangles) -> Result<(), MeshReadError> {
        const SECTION: &str = "$Elements";
        let (count, _) = self.count_line(SECTION, "the number of elements")?;
        if self.binary {
            let mut read: u64 = 0;
            while read < count {
                let at = self.here();
                let ty = self.read_int_u64(SECTION, "element type")?;
                let num = self.read_int_u64(SECTION, "number of elements")?;
                let ntags = self.read_int_u64(SECTION, "number of tags")?;
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
                    .ok_or_else(|| self.truncated(SECTION))?;
                self.check_room(num, record, SECTION)?;
                match action(ty) {
                    Action::Keep(order) => {
                        for _ in 0..num {
                            let at = self.here();
                            let tag = self.read_int_u64(SECTION, "element tag")?;
                            self.take(ntags * 4, SECTION)?;
                            self.push_triangle(triangles, order, tag, at)?;
                            for _ in 0..nn {
                                let node = self.read_int_u64(SECTION, "node tag")?;
                                triangles.node_tags.push(node);
                            }
                        }
                    }
                    Action::Reject(description) => {
                        let at = self.here();
                        let tag = self.read_int_u64(SECTION, "element tag")?;
                        return Err(self.reject(tag, ty, description, at));
                    }
                    Action::Skip => {
                        let bytes = usize::try_from(num)
                            .ok()
                            .and_then(|n| n.checked_mul(record))
                            .ok_or_else(|| self.truncated(SECTION))?;
                        self.take(bytes, SECTION)?;
                    }
                }
            }
        } else {
            let mut fields = Vec::new();
            for i in 0..count {
                let at = self.record(
                    SECTION,
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
                        let ntags = self.parse_usize(
                            self.field(&fields, 2, at)?,
                            "the number of tags",
                            at,
                        )?;
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
        }
        Ok(())
    }

    /// `$Elements` of MSH 4.1: a header, then entity blocks of one element
    /// type.
    fn elements_v41(&mut self, triangles: &mut Triangles) -> Result<(), MeshReadError> {
        const SECTION: &str = "$Elements";
        let header_at = self.here();
        let (blocks, count) = if self.binary {
            let blocks = self.read_size_t(SECTION)?;
            let count = self.read_size_t(SECTION)?;
            self.read_size_t(SECTION)?;
            self.read_size_t(SECTION)?;
            (blocks, count)
        } else {
            let ([blocks, count, _, _], at) = self.int_line(
                SECTION,
                "the $Elements header (blocks, elements, min tag, max tag)",
                [
                    "the number of blocks",
                    "the number of elements",
                    "the minimum tag",
                    "the maximum tag",
                ],
            )?;
            let nonneg = |v: i64, what: &str| {
                u64::try_from(v).map_err(|_| self.syntax(at, format!("{what} is negative ({v})")))
            };
            (
                nonneg(blocks, "the number of blocks")?,
                nonneg(count, "the number of elements")?,
            )
        };
        let mut total: u64 = 0;
        let mut fields = Vec::new();
        for b in 0..blocks {
            let block_at = self.here();
            let (ty, n) = if self.binary {
                self.read_i32(SECTION)?;
                self.read_i32(SECTION)?;
                let ty = self.read_int_u64(SECTION, "element type")?;
                let n = self.read_size_t(SECTION)?;
                (ty, n)
            } else {
                let ([_, _, ty, n], at) = self.int_line(
                    SECTION,
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
            let act = action(ty);
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
                    .ok_or_else(|| self.truncated(SECTION))?;
                self.check_room(n, record, SECTION)?;
                match act {
                    Action::Keep(order) => {
                        for _ in 0..n {
                            let at = self.here();
                            let tag = self.read_size_t(SECTION)?;
                            self.push_triangle(triangles, order, tag, at)?;
                            for _ in 0..nn {
                                let node = self.read_size_t(SECTION)?;
                                triangles.node_tags.push(node);
                            }
                        }
                    }
                    Action::Reject(description) => {
                        if n > 0 {
                            let at = self.here();
                            let tag = self.read_size_t(SECTION)?;
                            return Err(self.reject(tag, ty, description, at));
                        }
                    }
                    Action::Skip => {
                        let bytes = usize::try_from(n)
                            .ok()
                            .and_then(|n| n.checked_mul(record))
                            .ok_or_else(|| self.truncated(SECTION))?;
                        self.take(bytes, SECTION)?;
                    }
                }
            } else {
                for i in 0..n {
                    let at = self.record(
                        SECTION,
                        || format!("element {} of {n} in block {}", i + 1, b + 1),
                        &mut fields,
                    )?;
                    match &act {
                        Action::Keep(order) => {
                            let nn = order.nodes_per_element();
                            self.expect_fields(
                                &fields,
                                nn + 1,
                                &format!("a {nn}-node triangle (tag and nodes)"),
                                at,
                            )?;
                            let tag =
                                self.parse_u64(self.field(&fields, 0, at)?, "an element tag", at)?;
                            self.push_triangle(triangles, *order, tag, at)?;
                            for tok in fields.iter().skip(1) {
                                let node = self.parse_u64(tok, "a node tag", at)?;
                                triangles.node_tags.push(node);
                            }
                        }
                        Action::Reject(description) => {
                            let tag =
                                self.parse_u64(self.field(&fields, 0, at)?, "an element tag", at)?;
                            return Err(self.reject(tag, ty, description.clone(), at));
                        }
                        Action::Skip => {}
                    }
                }
            }
            total = total.saturating_add(n);
        }
        if total != count {
            return Err(self.syntax(
                header_at,
                format!("$Elements announces {count} elements, but its blocks hold {total}"),
            ));
        }
        Ok(())
    }
}

/// Builds the mesh: checks the node tags (no duplicates, every reference
/// defined), keeps the used nodes in increasing tag order and renumbers the
/// connectivity.
fn finish(file: &str, nodes: Vec<Node>, triangles: Triangles) -> Result<Mesh, MeshReadError> {
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
    use super::*;

    fn parse(text: &str) -> Result<Mesh, MeshReadError> {
        parse_msh(text.as_bytes(), "test.msh")
    }

    /// Little- (or big-) endian binary file builder.
    struct Bin {
        v: Vec<u8>,
        big: bool,
    }

    impl Bin {
        fn new() -> Self {
            Self {
                v: Vec::new(),
                big: false,
            }
        }
        fn s(&mut self, text: &str) -> &mut Self {
            self.v.extend_from_slice(text.as_bytes());
            self
        }
        fn i(&mut self, x: i32) -> &mut Self {
            let b = if self.big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            };
            self.v.extend_from_slice(&b);
            self
        }
        fn z(&mut self, x: u64) -> &mut Self {
            let b = if self.big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            };
            self.v.extend_from_slice(&b);
            self
        }
        fn f(&mut self, x: f64) -> &mut Self {
            let b = if self.big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            };
            self.v.extend_from_slice(&b);
            self
        }
    }

    const SQUARE: [[f64; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];

    const V22_T3: &str = "$MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
1 1 \"edge\"
2 2 \"cloth\"
$EndPhysicalNames
$Nodes
4
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
$EndNodes
$Elements
4
1 15 2 0 1 1
2 1 2 1 1 1 2
3 2 2 2 1 1 2 3
4 2 2 2 1 1 3 4
$EndElements
";

    /// Every prefix and a set of corrupted copies of `bytes` parse without
    /// panicking.
    fn no_panic_on_damage(bytes: &[u8]) {
        for n in 0..bytes.len() {
            let _ = parse_msh(&bytes[..n], "cut.msh");
        }
        let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
        for _ in 0..2000 {
            let mut copy = bytes.to_vec();
            for _ in 0..3 {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                let i = (state >> 33) as usize % copy.len();
                copy[i] = (state >> 17) as u8;
            }
            let _ = parse_msh(&copy, "damaged.msh");
        }
    }

    #[test]
    fn v22_ascii_t3_with_physical_names_point_and_line() {
        let m = parse(V22_T3).unwrap();
        assert_eq!(m.order, ElementOrder::Linear);
        assert_eq!(m.nodes, SQUARE.to_vec());
        assert_eq!(m.connectivity, vec![0, 1, 2, 0, 2, 3]);
        no_panic_on_damage(V22_T3.as_bytes());
    }

    #[test]
    fn skips_a_byte_order_mark() {
        let bytes = [b"\xEF\xBB\xBF".as_slice(), V22_T3.as_bytes()].concat();
        let m = parse_msh(&bytes, "bom.msh").unwrap();
        assert_eq!(m.nodes, SQUARE.to_vec());
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

    const V41_T3: &str = "$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
1
2 1 \"cloth\"
$EndPhysicalNames
$Entities
4 4 1 0
1 0 0 0 0
2 1 0 0 0
3 1 1 0 0
4 0 1 0 0
1 0 0 0 1 0 0 0 2 1 -2
2 1 0 0 1 1 0 0 2 2 -3
3 0 1 0 1 1 0 0 2 3 -4
4 0 0 0 0 1 0 0 2 4 -1
1 0 0 0 1 1 0 1 1 4 1 2 3 4
$EndEntities
$Nodes
3 4 1 4
0 1 0 2
1
2
0 0 0
1 0 0
1 2 1 1
3
1 1 0 0.5
2 1 0 1
4
0 1 0
$EndNodes
$Elements
2 3 1 3
1 1 1 1
1 1 2
2 1 2 2
2 1 2 3
3 1 3 4
$EndElements
";

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

    fn v22_binary_t3(big: bool) -> Vec<u8> {
        let mut b = Bin::new();
        b.big = big;
        b.s("$MeshFormat\n2.2 1 8\n").i(1).s("\n$EndMeshFormat\n");
        b.s("$Nodes\n4\n");
        for (k, x) in SQUARE.iter().enumerate() {
            b.i(k as i32 + 1).f(x[0]).f(x[1]).f(x[2]);
        }
        b.s("\n$EndNodes\n$Elements\n3\n");
        // A block of one 2-node line with 2 tags.
        b.i(1).i(1).i(2).i(5).i(1).i(1).i(1).i(2);
        // A block of two triangles with 2 tags.
        b.i(2).i(2).i(2);
        b.i(6).i(1).i(1).i(1).i(2).i(3);
        b.i(7).i(1).i(1).i(1).i(3).i(4);
        b.s("\n$EndElements\n");
        b.v
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

    /// A binary 4.1 file with one T6 (and a point element, a parametric
    /// node block and an `$Entities` section to skip).
    fn v41_binary_t6_bytes(nodes_claimed: Option<u64>) -> Vec<u8> {
        let mut b = Bin::new();
        b.s("$MeshFormat\n4.1 1 8\n").i(1).s("\n$EndMeshFormat\n");
        b.s("$Entities\n")
            .z(1)
            .z(0)
            .z(0)
            .z(0)
            .i(1)
            .f(0.0)
            .f(0.0)
            .f(0.0)
            .z(0);
        b.s("\n$EndEntities\n");
        b.s("$Nodes\n");
        b.z(2).z(nodes_claimed.unwrap_or(6)).z(1).z(6);
        // Block 1: the 3 vertices, on a point/surface entity, not parametric.
        b.i(2).i(1).i(0).z(3);
        b.z(1).z(2).z(3);
        b.f(0.0).f(0.0).f(0.0);
        b.f(2.0).f(0.0).f(0.0);
        b.f(0.0).f(2.0).f(0.0);
        // Block 2: the 3 mid-edge nodes, on a surface, parametric (u, v).
        b.i(2).i(1).i(1).z(nodes_claimed.unwrap_or(3));
        b.z(4).z(5).z(6);
        b.f(1.0).f(0.0).f(0.0).f(0.5).f(0.0);
        b.f(1.0).f(1.0).f(0.0).f(0.5).f(0.5);
        b.f(0.0).f(1.0).f(0.0).f(0.0).f(0.5);
        b.s("\n$EndNodes\n$Elements\n");
        b.z(2).z(2).z(1).z(2);
        b.i(0).i(1).i(15).z(1).z(1).z(1);
        b.i(2).i(1).i(9).z(1).z(2).z(1).z(2).z(3).z(4).z(5).z(6);
        b.s("\n$EndElements\n");
        b.v
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

    #[test]
    fn error_truncated_file() {
        let cut = &V22_T3[..V22_T3.find("3 1 1 0").unwrap()];
        let err = parse(cut).unwrap_err();
        assert!(
            matches!(&err, MeshReadError::Truncated { section, .. } if section == "$Nodes"),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            "test.msh: the file ends inside $Nodes, which is incomplete"
        );
        let bytes = v41_binary_t6_bytes(None);
        let err = parse_msh(&bytes[..bytes.len() - 40], "bin.msh").unwrap_err();
        assert!(
            matches!(&err, MeshReadError::Truncated { section, .. } if section == "$Elements"),
            "{err}"
        );
        let err = parse("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Elements\n1\n").unwrap_err();
        assert!(matches!(err, MeshReadError::Truncated { .. }), "{err}");
    }

    #[test]
    fn error_garbage_bytes() {
        let garbage: Vec<u8> = (0..4096u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        let err = parse_msh(&garbage, "junk.msh").unwrap_err();
        assert!(matches!(err, MeshReadError::Syntax { .. }), "{err}");
        assert!(err.to_string().starts_with("junk.msh"));
        let err = parse_msh(b"", "empty.msh").unwrap_err();
        assert!(
            matches!(err, MeshReadError::Syntax { at: None, .. }),
            "{err}"
        );
        let err = parse("$MeshFormat\n4.1 0 8\n$EndMeshFormat\nhello\n").unwrap_err();
        assert_eq!(
            err.to_string(),
            "test.msh, line 4: expected a section header such as $Nodes, found 'hello'"
        );
        let err = parse("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 zero 0\n$EndNodes\n")
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "test.msh, line 6: expected coordinate y (a number), found 'zero'"
        );
    }

    #[test]
    fn error_message_names_file_line_and_counts() {
        let text = V22_T3.replace("2 1 0 0\n", "2 1 0\n");
        let err = parse_msh(text.as_bytes(), "fabric.msh").unwrap_err();
        assert_eq!(
            err.to_string(),
            "fabric.msh, line 12: expected 4 numbers for node, found 3"
        );
        assert_eq!(err.location(), Some(Location::Line(12)));
        let text = V22_T3.replace("4\n1 15", "5\n1 15");
        let err = parse(&text).unwrap_err();
        assert_eq!(
            err.to_string(),
            "test.msh, line 22: $Elements ends early: expected element 5 of 5, found '$EndElements'"
        );
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
    fn error_huge_counts_fail_fast_without_allocating() {
        let start = std::time::Instant::now();
        // ASCII 2.2.
        let text = V22_T3.replace("$Nodes\n4\n", "$Nodes\n1000000000000\n");
        assert!(parse(&text).is_err());
        let text = V22_T3.replace("$Elements\n4\n", "$Elements\n1000000000000\n");
        assert!(parse(&text).is_err());
        // ASCII 4.1, in the header and in a block.
        let text = V41_T3.replace("$Nodes\n3 4 1 4\n", "$Nodes\n3 1000000000000 1 4\n");
        assert!(parse(&text).is_err());
        let text = V41_T3.replace("0 1 0 2\n", "0 1 0 1000000000000\n");
        assert!(parse(&text).is_err());
        // Binary 2.2: the count line.
        let bytes = v22_binary_t3(false);
        let text = String::from_utf8_lossy(&bytes).into_owned();
        assert!(text.contains("$Nodes\n4\n"));
        let mut bytes2 = Vec::new();
        let at = bytes.windows(9).position(|w| w == b"$Nodes\n4\n").unwrap();
        bytes2.extend_from_slice(&bytes[..at]);
        bytes2.extend_from_slice(b"$Nodes\n1000000000000\n");
        bytes2.extend_from_slice(&bytes[at + 9..]);
        let err = parse_msh(&bytes2, "bin.msh").unwrap_err();
        assert!(matches!(err, MeshReadError::Truncated { .. }), "{err}");
        // Binary 4.1: the header and a block.
        let err = parse_msh(&v41_binary_t6_bytes(Some(1_000_000_000_000)), "bin.msh").unwrap_err();
        assert!(matches!(err, MeshReadError::Truncated { .. }), "{err}");
        let mut b = Bin::new();
        b.s("$MeshFormat\n4.1 1 8\n")
            .i(1)
            .s("\n$EndMeshFormat\n$Nodes\n");
        b.z(1)
            .z(u64::MAX)
            .z(1)
            .z(u64::MAX)
            .i(2)
            .i(1)
            .i(0)
            .z(u64::MAX);
        let err = parse_msh(&b.v, "bin.msh").unwrap_err();
        assert!(matches!(err, MeshReadError::Truncated { .. }), "{err}");
        assert!(start.elapsed() < std::time::Duration::from_secs(2));
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

    #[test]
    fn error_quadrangles_and_no_triangles() {
        let text = V22_T3.replace("4 2 2 2 1 1 3 4", "4 3 2 2 1 1 2 3 4");
        let err = parse(&text).unwrap_err();
        assert!(
            matches!(
                err,
                MeshReadError::UnsupportedElement {
                    element: 4,
                    element_type: 3,
                    ..
                }
            ),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            "test.msh, line 21: element 4 is a 4-node quadrangle (Gmsh type 3); \
             only 3-, 6- and 10-node triangles (types 2, 9, 21) are supported"
        );
        let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n2 1 0 0\n$EndNodes\n\
            $Elements\n1\n1 1 0 1 2\n$EndElements\n";
        let err = parse(text).unwrap_err();
        assert!(matches!(err, MeshReadError::NoTriangles { .. }), "{err}");
        assert_eq!(err.to_string(), "test.msh: the file holds no triangles");
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
