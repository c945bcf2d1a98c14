//! Meshes of several disconnected pieces (issue 33): the two plies of a
//! Gmsh file (`tests/meshes/two-plies-t3.msh`, made by
//! `scripts/meshes/self_contact_meshes.py`) and the two groups of an OBJ file
//! are read whole, counted as pieces, and the selectors (`within`, `at`,
//! `boundary`) take nodes of both.

mod common;

use common::{setup, temp_dir};
use std::path::{Path, PathBuf};

fn two_plies() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/meshes/two-plies-t3.msh")
}

/// A scenario on the mesh file `mesh` with `fixes` (TOML tables).
fn scenario(mesh: &Path, fixes: &str) -> String {
    format!(
        r#"
[mesh]
shape = "file"
path = {mesh:?}
[material]
youngs_modulus = 2.0e6
poisson_ratio = 0.3
density = 320.0
thickness = 0.6e-3
[time]
segments = [{{ steps = 1, dt = 1.0e-3 }}]
{fixes}
"#
    )
}

/// The heights of the nodes of the fixed set of `text`.
fn fixed_heights(text: &str) -> Vec<f64> {
    let s = setup(text);
    let m = &s.model;
    (0..m.mesh().node_count())
        .filter(|&a| m.fixed()[3 * a])
        .map(|a| m.mesh().nodes[a][2])
        .collect()
}

/// The Gmsh file's two plies: 324 triangles in two pieces, one in the
/// plane z = 0 and one in z = 0.01 m (piece 0 the first element's).
#[test]
fn a_gmsh_file_of_two_plies_is_two_pieces() {
    let s = setup(&scenario(&two_plies(), ""));
    let mesh = s.model.mesh();
    assert_eq!(mesh.element_count(), 324);
    let (piece, count) = mesh.pieces();
    assert_eq!(count, 2);
    for (e, el) in mesh.elements().enumerate() {
        let z = mesh.nodes[el[0]][2];
        let expected = if z == mesh.nodes[mesh.element(0)[0]][2] {
            0
        } else {
            1
        };
        assert_eq!(piece[e], expected, "element {e} at z = {z}");
        assert!(
            el.iter().all(|&a| mesh.nodes[a][2] == z),
            "element {e} spans the plies"
        );
    }
}

/// `boundary`, `within` and `at` select across the pieces: both plies'
/// free edges, both plies' nodes in a box through them, the node of the
/// upper ply nearest a point on it.
#[test]
fn the_selectors_take_nodes_of_both_pieces() {
    let both = |heights: &[f64]| {
        heights.contains(&0.0) && heights.iter().any(|&z| (z - 0.01).abs() < 1e-12)
    };
    let boundary = fixed_heights(&scenario(&two_plies(), "[[fix]]\nboundary = true"));
    assert!(both(&boundary), "{boundary:?}");
    let edge = "[[fix]]\nwithin = { min = [-0.11, -1.0, -1.0], max = [-0.099, 1.0, 1.0] }";
    let within = fixed_heights(&scenario(&two_plies(), edge));
    assert!(both(&within), "{within:?}");
    let at = fixed_heights(&scenario(&two_plies(), "[[fix]]\nat = [0.1, 0.1, 0.01]"));
    assert_eq!(at, [0.01]);
}

/// An OBJ file of two groups (two squares apart, each two triangles) is
/// two pieces too.
#[test]
fn an_obj_file_of_two_groups_is_two_pieces() {
    let dir = temp_dir("obj-pieces");
    let path = dir.join("two.obj");
    let mut obj = String::new();
    for (g, z) in [("front", 0.0), ("back", 0.02)] {
        obj += &format!("g {g}\n");
        for (x, y) in [(0.0, 0.0), (0.1, 0.0), (0.1, 0.1), (0.0, 0.1)] {
            obj += &format!("v {x} {y} {z}\n");
        }
        obj += "f -4 -3 -2\nf -4 -2 -1\n";
    }
    std::fs::write(&path, obj).unwrap();
    let s = setup(&scenario(&path, ""));
    assert_eq!(s.model.mesh().element_count(), 4);
    assert_eq!(s.model.mesh().pieces(), (vec![0, 0, 1, 1], 2));
}
