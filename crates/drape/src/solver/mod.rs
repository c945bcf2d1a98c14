//! Sparse linear algebra and the Newton–Raphson iteration (docs/theory.md
//! §1.7).
//!
//! One file per verb: [`pattern`] lays out the Hessian; [`linear`]
//! chooses how to solve a system and checks the solution (its errors in
//! `linear_error`, faer's in `faer_failure`), with the
//! factorisations (`direct`, [`block_lu`]), the Krylov methods (`krylov`),
//! their preconditioners (`precondition`, [`amg`]) and the products by
//! the matrix (`product`) doing the work; [`newton`] iterates.

pub mod amg;
pub mod block_lu;
mod compact;
mod direct;
mod faer_failure;
mod krylov;
pub mod linear;
mod linear_error;
pub mod low_rank;
pub mod newton;
pub mod pattern;
mod precondition;
mod product;

pub use faer_failure::FaerFailure;
pub use linear::{
    Factorization, KeptFactor, KeptLinear, KeptMultigrid, LinearMode, LinearSolver, LinearStats,
};
pub use linear_error::{FactorStage, LinearSolveError, Matrix, SolveFailure};
pub use newton::{NewtonError, NewtonReport, NewtonSettings};
pub use pattern::SparsePattern;
