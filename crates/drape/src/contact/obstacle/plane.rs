//! The half-space obstacle: everything on the far side of a plane.
//!
//! With a point `p` of the plane and the outward unit normal `n` (pointing
//! away from the solid, towards the fabric):
//!
//! ```text
//! g = (y - p) . n,    y' = y - g n,    dg/dy = n,    dn/dy = 0
//! ```
//!
//! The solid is `{ y : g(y) < 0 }`. One feature, `0`; the hint is ignored.

use super::{Obstacle, ObstacleError, Proximity, check_finite, plane_proximity, show_point, unit};
use crate::vec3::{dot, sub};

/// The half-space `{ y : (y - point) . normal <= 0 }` (scenario `shape =
/// "plane"`, keys `point` and `normal`).
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneObstacle {
    point: [f64; 3],
    normal: [f64; 3],
}

impl PlaneObstacle {
    /// The half-space below the plane through `point` (m) with outward
    /// normal `normal` (any length but zero; it is normalised).
    ///
    /// Errors: a non-finite component, a zero normal.
    pub fn new(point: [f64; 3], normal: [f64; 3]) -> Result<Self, ObstacleError> {
        check_finite("plane", "point", &point)?;
        let normal = unit("plane", "normal", normal)?;
        Ok(Self { point, normal })
    }

    /// A point of the plane (m).
    pub fn point(&self) -> [f64; 3] {
        self.point
    }

    /// The outward unit normal.
    pub fn normal(&self) -> [f64; 3] {
        self.normal
    }
}

impl Obstacle for PlaneObstacle {
    /// `g = (y - p) . n`, `n`, `dn/dy = 0`, feature `0`; the hint is ignored.
    fn proximity(&self, y: [f64; 3], _hint: Option<u32>) -> Proximity {
        if !super::is_finite(y) {
            return super::undefined();
        }
        let g = dot(sub(y, self.point), self.normal);
        plane_proximity(y, g, self.normal, 0)
    }

    /// Infinite, except that a normal along a coordinate axis bounds that
    /// coordinate on the solid's side (e.g. `max z = p_z` for `n = +z`).
    fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::NEG_INFINITY; 3];
        let mut hi = [f64::INFINITY; 3];
        let axis = (0..3).find(|&k| self.normal[k].abs() == 1.0);
        if let Some(k) = axis {
            if self.normal[k] > 0.0 {
                hi[k] = self.point[k];
            } else {
                lo[k] = self.point[k];
            }
        }
        (lo, hi)
    }

    fn describe(&self) -> String {
        format!(
            "plane through {} with normal {}",
            show_point(self.point),
            show_point(self.normal)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::obstacle::testing::check_derivatives;
    use crate::vec3::norm;

    #[test]
    fn gap_normal_and_closest_point() {
        let plane = PlaneObstacle::new([0.0, 0.0, -0.1], [0.0, 0.0, 2.0]).unwrap();
        let p = plane.proximity([0.3, -0.2, 0.05], None);
        assert_eq!(p.normal, [0.0, 0.0, 1.0]);
        assert!((p.gap - 0.15).abs() < 1e-15);
        assert!(norm(sub(p.closest, [0.3, -0.2, -0.1])) < 1e-15);
        assert_eq!(p.feature, 0);
        let q = plane.proximity([0.0, 0.0, -0.3], Some(7));
        assert!((q.gap + 0.2).abs() < 1e-15);
        assert!(q.is_penetrating());
    }

    #[test]
    fn tilted_plane_derivatives() {
        let plane = PlaneObstacle::new([0.1, 0.2, 0.3], [1.0, -2.0, 0.5]).unwrap();
        for y in [[0.5, 0.1, -0.2], [-1.0, 2.0, 0.3], [0.1, 0.2, 0.3]] {
            check_derivatives(&plane, y, None, 1.0);
        }
    }

    #[test]
    fn bounding_box_is_bounded_only_along_an_axis_normal() {
        let floor = PlaneObstacle::new([0.0, 0.0, -0.5], [0.0, 0.0, 1.0]).unwrap();
        let (lo, hi) = floor.bounding_box();
        assert_eq!(hi[2], -0.5);
        assert_eq!(lo[2], f64::NEG_INFINITY);
        assert_eq!(hi[0], f64::INFINITY);
        let wall = PlaneObstacle::new([0.2, 0.0, 0.0], [-1.0, 0.0, 0.0]).unwrap();
        assert_eq!(wall.bounding_box().0[0], 0.2);
        let tilted = PlaneObstacle::new([0.0; 3], [1.0, 1.0, 0.0]).unwrap();
        let (lo, hi) = tilted.bounding_box();
        assert!(lo.iter().all(|v| v.is_infinite()) && hi.iter().all(|v| v.is_infinite()));
    }

    #[test]
    fn constructor_errors() {
        let e = PlaneObstacle::new([0.0; 3], [0.0; 3]).unwrap_err();
        assert!(
            matches!(e, ObstacleError::ZeroVector { key: "normal", .. }),
            "{e}"
        );
        assert_eq!(e.to_string(), "plane: normal must not be the zero vector");
        let e = PlaneObstacle::new([f64::NAN, 0.0, 0.0], [0.0, 0.0, 1.0]).unwrap_err();
        assert!(
            matches!(e, ObstacleError::NonFinite { key: "point", .. }),
            "{e}"
        );
        let e = PlaneObstacle::new([0.0; 3], [0.0, f64::INFINITY, 1.0]).unwrap_err();
        assert!(
            matches!(e, ObstacleError::NonFinite { key: "normal", .. }),
            "{e}"
        );
        // A huge but finite normal is normalised without overflow.
        let p = PlaneObstacle::new([0.0; 3], [1e300, 1e300, 0.0]).unwrap();
        assert!((p.normal()[0] - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15);
    }

    #[test]
    fn describe_names_point_and_normal() {
        let p = PlaneObstacle::new([0.0, 0.0, -0.05], [0.0, 0.0, 1.0]).unwrap();
        assert_eq!(
            p.describe(),
            "plane through [0,0,-0.05] with normal [0,0,1]"
        );
    }
}
