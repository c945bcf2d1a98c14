//! What a textile laboratory does with drape's run directories: measure a
//! drape as a drape tester does ([`measure`], `drape measure`), and test a
//! fabric on several specimens ([`drape_test`], `drape test` and
//! `drape.test` in Python: the specimens' directories, their measurement,
//! `test.json` and `test.png`).
//!
//! Between the library (which runs and measures states, and does not read
//! output directories) and the front ends (the command line, the Python
//! package), which both use it: it reads directories with `drape-render`,
//! measures with [`drape::measure`] and draws with `drape-render`.
#![warn(missing_docs)]

pub mod drape_test;
pub mod measure;
