//! OBJ reader: `parse_obj` then, on success, `Mesh::validate` (the OBJ as
//! a fabric mesh), and the obstacle `read_mesh_obstacle` builds from it
//! (`TriMeshObstacle::new`) with closest-point queries on it (the OBJ as
//! an obstacle). None may panic, hang or allocate without bound on any
//! bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = drape::mesh::obj::parse_obj(data, "fuzz.obj") {
        let _ = mesh.validate();
        drape_fuzz::obstacle_from("fuzz.obj", mesh);
    }
});
