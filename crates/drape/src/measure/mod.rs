//! Measuring a drape the way a textile laboratory does (README, "Measuring a drape"): the
//! shadow of a circular specimen draped over a circular pedestal, its
//! drape coefficient and its number of folds.
//!
//! In a drape tester (Cusick; ISO 9073-9, BS 5058) a disc of fabric of
//! radius `R` lies centred on a pedestal of radius `r_p` and hangs round
//! it in folds; a light above casts its shadow on a plane below. From
//! that shadow's area `A` (m²):
//!
//! ```text
//! DC = (A − π r_p²) / (π R² − π r_p²)
//! ```
//!
//! (ISO 9073-9:2008 §3, BS 5058:1973): 1 for a specimen that stays flat, 0
//! for one that hangs straight down round the pedestal. The number of
//! folds (the "nodes" of the standards) is the number of waves round the
//! shadow's rim.
//!
//! The measurement of one state of the fabric goes in three parts:
//!
//! - [`shadow`](mod@shadow): the area of the union of the elements'
//!   projections on the horizontal plane, folds that overlap counted once
//!   (an exact polygon union of the flat triangles; curved T6 and T10
//!   elements through sub-triangles, refined until a stated error bound is
//!   small), and the shadow's outline;
//! - [`folds`]: the outline's radius as a function of the angle round the
//!   shadow's centroid, smoothed, and its prominent maxima counted;
//! - [`tester`]: the geometry of the instrument — the vertical (opposite
//!   the scenario's resultant weight), the pedestal's axis and radius (a cylinder
//!   obstacle under the specimen) and the specimen's radius (a `disc`
//!   mesh, or a file mesh whose initial rim is a circle) — found from the
//!   scenario or given.
//!
//! [`measure`] puts them together. Reading a run's output directory is the
//! command line's part (`drape measure DIR`): the frames are read with the
//! output directory's reader of `drape-render`, the scenario with
//! [`crate::scenario::Scenario::read`].

pub mod ensemble;
pub mod folds;
pub mod shadow;
pub mod tester;

pub use crate::horizontal::Horizontal;
pub use folds::{count_folds, polar_profile};
pub use shadow::{Shadow, shadow};
pub use tester::{DrapeTester, Given};

use crate::mesh::ElementOrder;

/// The fabric's surface in one state: current node positions and the
/// elements' connectivity (the mesh's node order, [`crate::mesh`]).
#[derive(Debug, Clone, Copy)]
pub struct Surface<'a> {
    /// Current positions `y` (m).
    pub positions: &'a [[f64; 3]],
    /// `order.nodes_per_element()` node indices per element.
    pub connectivity: &'a [usize],
    /// Lagrange order of the elements.
    pub order: ElementOrder,
}

impl Surface<'_> {
    /// Checks that the connectivity is whole, every index names a node and
    /// every position used is finite.
    ///
    /// # Errors
    /// [`MeasureError::Connectivity`], [`MeasureError::NodeOutOfRange`],
    /// [`MeasureError::NotFinite`].
    pub fn check(&self) -> Result<(), MeasureError> {
        let n = self.order.nodes_per_element();
        if !self.connectivity.len().is_multiple_of(n) {
            return Err(MeasureError::Connectivity {
                len: self.connectivity.len(),
                nodes_per_element: n,
            });
        }
        for (e, el) in self.connectivity.chunks_exact(n).enumerate() {
            for &a in el {
                let Some(y) = self.positions.get(a) else {
                    return Err(MeasureError::NodeOutOfRange {
                        element: e,
                        node: a,
                        nodes: self.positions.len(),
                    });
                };
                if !y.iter().all(|c| c.is_finite()) {
                    return Err(MeasureError::NotFinite {
                        node: a,
                        position: *y,
                    });
                }
            }
        }
        Ok(())
    }
}

/// What [`measure`] finds.
#[derive(Debug, Clone, PartialEq)]
pub struct Measurement {
    /// Area of the shadow `A` (m²), overlaps counted once.
    pub shadow_area: f64,
    /// Bound on `|A − A_exact|` (m²) from the flat sub-triangles that stand
    /// for curved elements ([`Shadow::error_bound`]).
    pub shadow_area_error_bound: f64,
    /// `DC = (A − π r_p²) / (π R² − π r_p²)`, dimensionless.
    pub drape_coefficient: f64,
    /// Waves round the rim ([`count_folds`]).
    pub folds: usize,
    /// Sub-triangles per element edge the shadow was computed with.
    pub subdivisions: usize,
    /// Edges passing through a triangle they share no node with: the
    /// fabric crossing itself (0 for a fabric that never does;
    /// [`crate::contact::proximity::crossings`], on the elements' linear
    /// sub-triangles).
    pub crossings: usize,
    /// The shadow's outline in the plane's coordinates (m): its rings
    /// ([`Shadow::outline`]), for a picture of it.
    pub outline: Vec<Vec<[f64; 2]>>,
}

/// The drape coefficient `DC = (A − π r_p²) / (π R² − π r_p²)` of a shadow
/// of area `A` (m²) on a pedestal of radius `r_p` (m) under a specimen of
/// radius `R > r_p` (m) (ISO 9073-9, BS 5058).
pub fn drape_coefficient(shadow_area: f64, pedestal_radius: f64, specimen_radius: f64) -> f64 {
    let pedestal = std::f64::consts::PI * pedestal_radius * pedestal_radius;
    let specimen = std::f64::consts::PI * specimen_radius * specimen_radius;
    (shadow_area - pedestal) / (specimen - pedestal)
}

/// Measures the drape of `surface` in the drape tester `tester`: the
/// shadow on the plane normal to its vertical, the drape coefficient and
/// the folds round the pedestal's axis.
///
/// A flat disc of a generated mesh (a polygon of `n = 6 rings` sides
/// inscribed in the circle of radius `R`) measures
/// `DC = 1 − (π R² − A_n) / (π R² − π r_p²)` with
/// `A_n = n R² sin(2π / n) / 2`: 0.13 % under 1 for 15 rings on the
/// 30 cm / 18 cm tester.
///
/// # Errors
/// A surface that fails [`Surface::check`].
pub fn measure(surface: &Surface, tester: &DrapeTester) -> Result<Measurement, MeasureError> {
    let plane = tester.plane;
    let s = shadow(surface, &plane)?;
    let profile = polar_profile(&s.outline, folds::PROFILE_SAMPLES);
    Ok(Measurement {
        shadow_area: s.area,
        shadow_area_error_bound: s.error_bound,
        drape_coefficient: drape_coefficient(
            s.area,
            tester.pedestal_radius,
            tester.specimen_radius,
        ),
        folds: count_folds(&profile),
        subdivisions: s.subdivisions,
        crossings: crossings_of(surface),
        outline: s.outline,
    })
}

/// The crossings of `surface` (its elements cut into their linear
/// sub-triangles, as bending cuts them).
fn crossings_of(surface: &Surface) -> usize {
    use crate::contact::proximity::{crossings, edges_of};
    let mesh = crate::mesh::Mesh {
        nodes: surface.positions.to_vec(),
        order: surface.order,
        connectivity: surface.connectivity.to_vec(),
    };
    let (triangles, _) = crate::bending::triangulate(&mesh);
    crossings(surface.positions, &triangles, &edges_of(&triangles))
}

/// A measurement that cannot be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeasureError {
    /// The connectivity is not a whole number of elements.
    #[error(
        "{len} connectivity entries are not a whole number of {nodes_per_element}-node elements"
    )]
    Connectivity {
        /// Entries in the connectivity.
        len: usize,
        /// Nodes per element of the order.
        nodes_per_element: usize,
    },
    /// An element names a node that does not exist.
    #[error("element {element} names node {node}, but there are {nodes} nodes")]
    NodeOutOfRange {
        /// The element (0-based).
        element: usize,
        /// The node index it names.
        node: usize,
        /// Number of nodes.
        nodes: usize,
    },
    /// A node's position is NaN or infinite.
    #[error("node {node} is at {position:?}, not a finite position")]
    NotFinite {
        /// The node (0-based).
        node: usize,
        /// Its position.
        position: [f64; 3],
    },
    /// A radius that cannot be one.
    #[error("{which} {value} m is not a positive, finite length")]
    Radius {
        /// `"pedestal radius"` or `"specimen radius"`.
        which: &'static str,
        /// The value given or found.
        value: f64,
    },
    /// The pedestal is not smaller than the specimen.
    #[error(
        "the pedestal radius {pedestal} m is not smaller than the specimen radius {specimen} m: no drape coefficient"
    )]
    PedestalNotSmaller {
        /// Pedestal radius (m).
        pedestal: f64,
        /// Specimen radius (m).
        specimen: f64,
    },
    /// The specimen's radius cannot be found.
    #[error("no specimen radius: {reason}; give it (drape measure --specimen-radius R)")]
    NotADisc {
        /// Why not.
        reason: String,
    },
    /// The pedestal cannot be found.
    #[error("no pedestal: {reason}; give its radius (drape measure --pedestal-radius R)")]
    NoPedestal {
        /// Why not.
        reason: String,
    },
    /// Two vertical cylinders under the specimen have their tops at one
    /// height and different radii: which is the pedestal cannot be told.
    #[error(
        "which is the pedestal? obstacle[{}] and obstacle[{}] are both vertical cylinders under the specimen with their tops at one height and radii {} m and {} m; give its radius (drape measure --pedestal-radius R)",
        obstacles[0], obstacles[1], radii[0], radii[1]
    )]
    AmbiguousPedestal {
        /// The two obstacles' indices.
        obstacles: [usize; 2],
        /// Their radii (m).
        radii: [f64; 2],
    },
    /// The scenario's weight gives no direction: its loads weigh nothing,
    /// or cancel ([`tester::vertical_of`]).
    #[error("no vertical: {reason}, and which way is down cannot be told")]
    NoVertical {
        /// Why not.
        reason: String,
    },
    /// The vertical cannot be a direction.
    #[error("the vertical {vertical:?} is not a direction")]
    Vertical {
        /// The vector found.
        vertical: [f64; 3],
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drape_coefficient_is_one_flat_and_zero_hanging() {
        let (rp, r) = (0.09, 0.15);
        let pi = std::f64::consts::PI;
        assert!((drape_coefficient(pi * r * r, rp, r) - 1.0).abs() < 1e-15);
        assert!(drape_coefficient(pi * rp * rp, rp, r).abs() < 1e-15);
    }

    #[test]
    fn surface_check_names_the_problem() {
        let positions = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let s = Surface {
            positions: &positions,
            connectivity: &[0, 1],
            order: ElementOrder::Linear,
        };
        assert!(matches!(s.check(), Err(MeasureError::Connectivity { .. })));
        let s = Surface {
            connectivity: &[0, 1, 3],
            ..s
        };
        assert_eq!(
            s.check(),
            Err(MeasureError::NodeOutOfRange {
                element: 0,
                node: 3,
                nodes: 3
            })
        );
        let bad = [[0.0; 3], [f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let s = Surface {
            positions: &bad,
            connectivity: &[0, 1, 2],
            order: ElementOrder::Linear,
        };
        assert!(matches!(
            s.check(),
            Err(MeasureError::NotFinite { node: 1, .. })
        ));
    }
}
