//! STL reader: `parse_stl` then, on success, the obstacle built from it as
//! `read_mesh_obstacle` does (`TriMeshObstacle::new`). Neither may panic,
//! hang or allocate without bound on any bytes.
#![no_main]

use drape::contact::obstacle::TriMeshObstacle;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = drape::contact::obstacle::stl::parse_stl(data, "fuzz.stl") {
        let triangles = mesh
            .elements()
            .filter_map(|e| <[usize; 3]>::try_from(e.get(..3)?).ok())
            .collect();
        let _ = TriMeshObstacle::new("fuzz.stl", mesh.nodes, triangles);
    }
});
