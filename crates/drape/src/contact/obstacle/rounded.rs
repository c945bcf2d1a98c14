//! Rounded edges: a sharp convex shape grown by a radius `r` (its Minkowski
//! sum with a ball), with the gap measured to the grown surface.
//!
//! A box `[min, max]` with edges rounded to `r` is the inner box `[min + r,
//! max - r]` grown by `r`: its faces stay where the sharp box's were, and
//! every edge and corner becomes a quarter-cylinder or an eighth-sphere of
//! radius `r` (a capped cylinder likewise gets a rounded rim). The gap is
//!
//! ```text
//! g(y) = g_inner(y) - r
//! ```
//!
//! with the normal and its derivative of the inner shape: outside the inner
//! shape (every point within `r` of the surface, so every contact with less
//! penetration than `r`) this is the Euclidean distance field, continuously
//! differentiable everywhere — the normal turns smoothly round an edge,
//! over a distance `r` instead of none. Newton then converges on nodes
//! that meet an edge, with penalty and multipliers alike.
//!
//! A node exactly above an edge meets the fillet at its outer point, where
//! the normal is horizontal: it gets no vertical support and slides down
//! the side, as a fabric hung over a real (never perfectly sharp) edge
//! does; a node a fillet radius or more inside the edge rests on the top.

use super::{Obstacle, Proximity, SharpPoint};
use crate::vec3::{add, scale};

/// A sharp shape grown by a radius.
#[derive(Debug)]
pub struct Rounded<O: Obstacle> {
    inner: O,
    radius: f64,
}

impl<O: Obstacle> Rounded<O> {
    /// The shape `inner` grown by `radius` (m, >= 0).
    pub fn new(inner: O, radius: f64) -> Self {
        Self { inner, radius }
    }

    /// The fillet radius (m).
    pub fn radius(&self) -> f64 {
        self.radius
    }
}

impl<O: Obstacle> Obstacle for Rounded<O> {
    fn proximity(&self, y: [f64; 3], hint: Option<u32>) -> Proximity {
        let p = self.inner.proximity(y, hint);
        Proximity {
            gap: p.gap - self.radius,
            closest: add(p.closest, scale(p.normal, self.radius)),
            ..p
        }
    }

    fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let (lo, hi) = self.inner.bounding_box();
        (lo.map(|v| v - self.radius), hi.map(|v| v + self.radius))
    }

    fn describe(&self) -> String {
        format!(
            "{} grown by {} m (rounded edges)",
            self.inner.describe(),
            self.radius
        )
    }

    /// The inner shape's sharp points moved out by the radius along their
    /// outward directions: the outermost points of the fillets, which a
    /// fillet smaller than the fabric's elements pushes between nodes as a
    /// sharp edge would.
    fn sharp_points(&self, spacing: f64) -> Vec<SharpPoint> {
        let mut points = self.inner.sharp_points(spacing);
        for p in &mut points {
            p.position = add(p.position, scale(p.outward, self.radius));
        }
        points
    }
}

#[cfg(test)]
mod tests {
    use super::super::BoxObstacle;
    use super::*;
    use crate::fd::jacobian_error;

    fn rounded_pedestal() -> Rounded<BoxObstacle> {
        let r = 1e-3;
        Rounded::new(
            BoxObstacle::new(
                [-0.05 + r, -0.05 + r, -0.25 + r],
                [0.05 - r, 0.05 - r, -0.05 - r],
            )
            .unwrap(),
            r,
        )
    }

    /// Faces stay in place; an edge is a quarter-cylinder of radius r.
    #[test]
    fn faces_stay_and_edges_are_round() {
        let b = rounded_pedestal();
        let top = b.proximity([0.0, 0.0, -0.04], None);
        assert!((top.gap - 0.01).abs() < 1e-15 && top.normal == [0.0, 0.0, 1.0]);
        // Exactly above the edge: the fillet's outer point, horizontal normal.
        let edge = b.proximity([0.05, 0.0, -0.051], None);
        assert!(edge.gap.abs() < 1e-12);
        assert!((edge.normal[0] - 1.0).abs() < 1e-12);
        // 45 degrees round the edge.
        let c = [0.049, 0.0, -0.051];
        let s = 0.5f64.sqrt();
        let p = b.proximity([c[0] + 2e-3 * s, 0.0, c[2] + 2e-3 * s], None);
        assert!((p.gap - 1e-3).abs() < 1e-12);
        assert!((p.normal[0] - s).abs() < 1e-12 && (p.normal[2] - s).abs() < 1e-12);
    }

    /// Gap, normal and normal derivative are consistent round the fillet,
    /// inside it too (within r of the surface): d g/dy = n, d n/dy = dn.
    #[test]
    fn derivatives_round_the_fillet_match_finite_differences() {
        let b = rounded_pedestal();
        for y in [
            [0.0495, 0.01, -0.0498],
            [0.0499, 0.0493, -0.0497],
            [0.02, 0.0, -0.0504],
            [0.0503, 0.0, -0.06],
        ] {
            let gap = |v: &[f64]| vec![b.proximity([v[0], v[1], v[2]], None).gap];
            let normal = |v: &[f64]| b.proximity([v[0], v[1], v[2]], None).normal.to_vec();
            let dn = |v: &[f64]| {
                b.proximity([v[0], v[1], v[2]], None)
                    .normal_derivative
                    .concat()
            };
            assert!(jacobian_error(gap, normal, &y, 1e-8) < 1e-6, "{y:?}");
            assert!(jacobian_error(normal, dn, &y, 1e-8) < 1e-5, "{y:?}");
        }
    }
}
