//! Gmsh's element types: how many nodes each has, which are the triangles
//! the reader keeps, which surfaces it rejects and which elements it skips.

#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use crate::mesh::ElementOrder;

/// Kinds of Gmsh elements, to describe them and tell surfaces apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
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
///
/// Long because it is a table, one arm per type in Gmsh's list, read
/// against that list: kept whole.
pub(super) fn element_type(t: u64) -> Option<(usize, Kind)> {
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
pub(super) enum Action {
    /// Keep: a supported triangle.
    Keep(ElementOrder),
    /// Reject: an unsupported surface element.
    Reject(String),
    /// Skip: points, lines, volumes and unknown types.
    Skip,
}

pub(super) fn action(t: u64) -> Action {
    if let Some(order) = triangle_order(t) {
        return Action::Keep(order);
    }
    match element_type(t) {
        Some((n, kind)) if kind.is_surface() => Action::Reject(format!("{n}-node {}", kind.name())),
        _ => Action::Skip,
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
    use crate::mesh::gmsh::MeshReadError;
    use crate::mesh::gmsh::fixtures::*;

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
}
