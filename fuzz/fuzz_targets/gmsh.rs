//! Gmsh reader: `parse_msh` then, on success, `Mesh::validate`. Neither may
//! panic, hang or allocate without bound on any bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = drape::mesh::gmsh::parse_msh(data, "fuzz.msh") {
        let _ = mesh.validate();
    }
});
