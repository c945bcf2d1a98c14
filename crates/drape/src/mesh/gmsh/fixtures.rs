//! MSH files shared by the Gmsh reader's tests: small meshes in each format
//! (ASCII and binary, 2.2 and 4.1), a builder for binary files, and a check
//! that damaged copies of a file never make the reader panic.

#![allow(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use super::{MeshReadError, parse_msh};
use crate::mesh::Mesh;

pub(super) fn parse(text: &str) -> Result<Mesh, MeshReadError> {
    parse_msh(text.as_bytes(), "test.msh")
}

/// Little- (or big-) endian binary file builder.
pub(super) struct Bin {
    pub(super) v: Vec<u8>,
    pub(super) big: bool,
}

impl Bin {
    pub(super) fn new() -> Self {
        Self {
            v: Vec::new(),
            big: false,
        }
    }
    pub(super) fn s(&mut self, text: &str) -> &mut Self {
        self.v.extend_from_slice(text.as_bytes());
        self
    }
    /// Appends a number in the builder's byte order.
    fn put<const N: usize>(&mut self, little: [u8; N], big: [u8; N]) -> &mut Self {
        self.v
            .extend_from_slice(if self.big { &big } else { &little });
        self
    }
    pub(super) fn i(&mut self, x: i32) -> &mut Self {
        self.put(x.to_le_bytes(), x.to_be_bytes())
    }
    pub(super) fn z(&mut self, x: u64) -> &mut Self {
        self.put(x.to_le_bytes(), x.to_be_bytes())
    }
    pub(super) fn f(&mut self, x: f64) -> &mut Self {
        self.put(x.to_le_bytes(), x.to_be_bytes())
    }
}

pub(super) const SQUARE: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
];

pub(super) const V22_T3: &str = "$MeshFormat
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

pub(super) const V41_T3: &str = "$MeshFormat
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

/// Every prefix and a set of corrupted copies of `bytes` parse without
/// panicking.
pub(super) fn no_panic_on_damage(bytes: &[u8]) {
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

pub(super) fn v22_binary_t3(big: bool) -> Vec<u8> {
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

/// A binary 4.1 file with one T6 (and a point element, a parametric
/// node block and an `$Entities` section to skip).
pub(super) fn v41_binary_t6_bytes(nodes_claimed: Option<u64>) -> Vec<u8> {
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
