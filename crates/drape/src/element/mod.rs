//! The positional membrane element: shape functions, quadrature, the
//! per-element reference geometry and the internal-force / Hessian kernel
//! (docs/theory.md §1.2–1.3).

pub mod geometry;
pub mod lagrange;
pub mod membrane;
pub mod quadrature;

pub use geometry::ElementGeometry;
