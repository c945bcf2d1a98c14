//! The positional membrane element: the per-element reference geometry
//! and the internal-force / Hessian kernel (docs/theory.md §1.2–1.3), on
//! the shape functions of the mesh's triangles ([`crate::mesh::lagrange`])
//! and the rules of [`crate::quadrature`].

pub mod geometry;
pub mod membrane;

pub use geometry::ElementGeometry;
