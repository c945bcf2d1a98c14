//! Reference solutions the tests compare with.
pub mod elastica;
pub mod refine;
