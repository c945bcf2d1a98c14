//! Scenario files: `Scenario::parse` then, when it parses and the mesh it
//! asks for is small, `Scenario::build`. Neither may panic, hang or
//! allocate without bound on any text.
//!
//! Guards, in this target only (the library's own cap, 2e7 generated
//! nodes, is far too slow for one fuzz iteration):
//! * `build` is skipped when a generated mesh would have more than
//!   `MAX_NODES` nodes;
//! * mesh and obstacle `path`s are redirected to the small files in
//!   `fuzz/fixtures/` (by extension), so that the fuzzer never opens a file
//!   of its choosing (`/dev/zero`, a FIFO, ...).
#![no_main]

use std::path::{Path, PathBuf};

use drape::scenario::{MeshShape, Scenario};
use libfuzzer_sys::fuzz_target;

/// Most nodes of a generated mesh for which `build` runs.
const MAX_NODES: usize = 2_000;

/// The fixture standing for `path`: `fixtures/<stem>.<ext>` for a known
/// extension, else a file that does not exist with the same extension.
fn fixture(path: &Path, stem: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some(e @ ("msh" | "obj" | "stl")) => dir.join(format!("{stem}.{e}")),
        Some(e) => dir.join(format!("missing.{}", e.escape_default())),
        None => dir.join("missing"),
    }
}

/// Nodes of the mesh `build` would generate (0 for a file).
fn generated_nodes(s: &Scenario) -> usize {
    let p = s.mesh.order.unwrap_or(1).clamp(1, 3);
    match s.mesh.shape {
        MeshShape::Rectangle => s.mesh.divisions.map_or(0, |[nx, ny]| {
            nx.saturating_mul(p)
                .saturating_add(1)
                .saturating_mul(ny.saturating_mul(p).saturating_add(1))
        }),
        MeshShape::Disc => s.mesh.rings.map_or(0, |r| {
            r.saturating_mul(r)
                .saturating_mul(3 * p * p)
                .saturating_add(1)
        }),
        MeshShape::File => 0,
    }
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let file = Path::new("fuzz.toml");
    let Ok(mut scenario) = Scenario::parse(text, file) else {
        return;
    };
    if generated_nodes(&scenario) > MAX_NODES {
        return;
    }
    if let Some(path) = &scenario.mesh.path {
        scenario.mesh.path = Some(fixture(path, "mesh"));
    }
    for o in &mut scenario.obstacles {
        if let Some(path) = &o.path {
            o.path = Some(fixture(path, "obstacle"));
        }
    }
    let _ = scenario.build(file, text);
});
