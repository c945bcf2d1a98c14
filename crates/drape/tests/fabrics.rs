//! The fabric library (`examples/fabrics/`, issue 22): every file parses
//! and builds, with the orthotropic material and woven bending, on the
//! drape tester's disc and pedestal.

mod common;

use std::path::Path;

#[test]
fn every_fabric_of_the_library_builds() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fabrics");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 3,
        "{} fabrics in {}",
        files.len(),
        dir.display()
    );
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        let setup = common::build(&text, &file).unwrap_or_else(|e| panic!("{e}"));
        let model = &setup.model;
        assert!(
            model.material().axis().is_some(),
            "{}: not orthotropic",
            file.display()
        );
        assert!(model.bending().is_some(), "{}: no bending", file.display());
        assert!(model.contact().is_some(), "{}: no pedestal", file.display());
    }
}
