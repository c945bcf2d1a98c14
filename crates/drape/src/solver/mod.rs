//! Sparse linear algebra and the Newton–Raphson iteration (SPEC §1.7).

pub mod amg;
pub mod block_lu;
pub mod linear;
pub mod newton;
pub mod pattern;

pub use linear::{Factorization, LinearMode, LinearSolveError, LinearSolver, LinearStats};
pub use newton::{NewtonError, NewtonReport, NewtonSettings};
pub use pattern::SparsePattern;
