//! STL reader: `parse_stl` then, on success, the obstacle built from it as
//! `read_mesh_obstacle` does (`TriMeshObstacle::new`) and closest-point
//! queries on it. None may panic, hang or allocate without bound on any
//! bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = drape::contact::obstacle::stl::parse_stl(data, "fuzz.stl") {
        drape_fuzz::obstacle_from("fuzz.stl", mesh);
    }
});
