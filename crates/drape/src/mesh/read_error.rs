//! The error of the mesh readers — Gmsh ([`read_msh`](super::gmsh::read_msh)),
//! Wavefront OBJ ([`read_obj`](super::obj::read_obj)) and STL
//! ([`read_stl`](crate::contact::obstacle::stl::read_stl)) — and the
//! [`Location`] in a file that it names.
//!
//! Every message names the file and, where it is known, the line (text) or
//! byte offset (binary) and the value at fault.

#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use std::fmt;
use std::path::Path;

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

/// Error reading a mesh file, Gmsh MSH (see [`read_msh`](super::gmsh::read_msh)),
/// Wavefront OBJ (see [`read_obj`](super::obj::read_obj)) or STL.
///
/// Every variant carries the file name (as given to the reader) and, where
/// it is known, the [`Location`] of the problem; the message reads like
/// `fabric.msh, line 12: expected 4 numbers for node, found 3`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshReadError {
    /// The file's extension names no format drape reads.
    #[error("{file}: unknown mesh format: expected a .msh (Gmsh) or .obj file")]
    UnknownFormat {
        /// File name.
        file: String,
    },
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
    /// The file holds more nodes than a mesh may have
    /// ([`MAX_MESH_NODES`](super::MAX_MESH_NODES), or the reader's cap):
    /// refused from the count a Gmsh file declares, before its nodes are
    /// read, or at an OBJ file's first vertex past the cap.
    #[error(
        "{file}{}: {}, more than the {limit} nodes a mesh may have; use a coarser mesh",
        suffix(.at),
        if *.declared {
            format!("$Nodes declares {count} nodes")
        } else {
            format!("vertex {count}")
        }
    )]
    TooManyNodes {
        /// File name.
        file: String,
        /// Where the count (Gmsh) or the vertex (OBJ) was found.
        at: Option<Location>,
        /// The number of nodes the file declares (Gmsh), or the number of
        /// the first vertex past the cap (OBJ).
        count: u64,
        /// Whether `count` is the number the file declares.
        declared: bool,
        /// The cap.
        limit: usize,
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
            | Self::UnknownFormat { file }
            | Self::Truncated { file, .. }
            | Self::TooManyNodes { file, .. }
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
            | Self::UnsupportedElement { at, .. }
            | Self::TooManyNodes { at, .. } => *at,
            _ => None,
        }
    }
}

impl MeshReadError {
    /// Reads a whole mesh file, with its name as messages show it.
    pub(crate) fn read(path: &Path) -> Result<(Vec<u8>, String), MeshReadError> {
        let file = path.display().to_string();
        let bytes = crate::input::read(path).map_err(|source| MeshReadError::Io {
            file: file.clone(),
            source,
        })?;
        Ok((bytes, file))
    }
}
