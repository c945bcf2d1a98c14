//! OBJ reader: `parse_obj` then, on success, `Mesh::validate` (the OBJ as
//! a fabric mesh) and `TriMeshObstacle::new` as `read_mesh_obstacle` calls
//! it (the OBJ as an obstacle). None may panic, hang or allocate without
//! bound on any bytes.
#![no_main]

use drape::contact::obstacle::TriMeshObstacle;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = drape::mesh::obj::parse_obj(data, "fuzz.obj") {
        let _ = mesh.validate();
        let triangles = mesh
            .elements()
            .filter_map(|e| <[usize; 3]>::try_from(e.get(..3)?).ok())
            .collect();
        let _ = TriMeshObstacle::new("fuzz.obj", mesh.nodes, triangles);
    }
});
