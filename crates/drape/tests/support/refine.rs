//! Local refinement of a T3 mesh for the tests, by region: the elements
//! whose centroid a predicate accepts split red, with the library's green
//! closure ([`drape::mesh::refine`]).

use drape::mesh::Mesh;

/// `mesh` with the triangles whose centroid `inside` accepts split in four
/// and a conforming closure around them.
pub fn split(mesh: &Mesh, inside: impl Fn([f64; 3]) -> bool) -> Mesh {
    let marked: Vec<bool> = mesh
        .elements()
        .map(|t| inside([0, 1, 2].map(|i| t.iter().map(|&a| mesh.nodes[a][i]).sum::<f64>() / 3.0)))
        .collect();
    let refined = drape::mesh::refine::refine(mesh, &marked)
        .expect("a linear mesh")
        .mesh;
    refined.validate().expect("a valid refined mesh");
    refined
}
