//! # drape
//!
//! Membranes and fabrics in large displacement with the positional finite
//! element method: the unknowns are the nodal positions, every measure is
//! total Lagrangian. Triangular membrane elements of order 1–3,
//! Saint-Venant–Kirchhoff in plane stress, implicit Newmark-beta dynamics
//! solved by Newton–Raphson on a sparse Hessian.
//!
//! Data flows one way: [`scenario`] (a TOML file) → [`setup::Setup`]
//! (with its [`model::Model`]) →
//! [`integrator`] (one time step) → [`solver`] (Newton, sparse linear
//! solves) → [`output`] (history, fields, summary); [`simulation`] drives
//! the loop. See `ARCHITECTURE.md` for the map.
#![warn(missing_docs)]
// Kernels index arrays the way the equations do (`F[i][c]`, `phi[a]`).
#![allow(clippy::needless_range_loop)]

pub mod bending;
pub mod block3;
pub mod contact;
pub mod element;
pub mod fd;
pub mod horizontal;
pub mod human;
pub mod input;
pub mod integrator;
pub mod levels;
pub mod load;
pub mod material;
pub mod measure;
pub mod memory;
pub mod mesh;
pub mod model;
pub mod output;
pub mod par;
pub mod progress;
pub mod psd;
pub mod quadrature;
pub mod scenario;
pub mod setup;
pub mod simulation;
pub mod solver;
pub mod specimen;
pub mod vec3;
pub mod vecn;
