//! The solid ball obstacle.
//!
//! With centre `c`, radius `R` and `r = |y - c|`:
//!
//! ```text
//! g = r - R,    n = (y - c) / r,    y' = c + R n,    dn/dy = (I - n n^T) / r
//! ```
//!
//! At the centre (`r <= 1e-12 R`) the normal is undefined; the answer is
//! then `n = +z`, `g = -R` and `dn/dy = 0` (finite, so a Hessian built from
//! it stays finite). One feature, `0`; the hint is ignored.
//!
//! Inside, `g dn/dy = (1 - R/r)(I - n n^T)` is negative semi-definite and
//! grows without bound towards the centre: the penalty Hessian `eta (n n^T +
//! g dn/dy)` of a deeply penetrating node is indefinite.

use super::{
    Obstacle, ObstacleError, Proximity, ZERO3, check_finite, check_positive, identity_minus,
    show_point,
};
use crate::vec3::{add, norm, scale, sub};

/// A solid ball (scenario `shape = "sphere"`, keys `center` and `radius`).
#[derive(Debug, Clone, PartialEq)]
pub struct SphereObstacle {
    center: [f64; 3],
    radius: f64,
}

impl SphereObstacle {
    /// The ball of centre `center` (m) and radius `radius` (m).
    ///
    /// Errors: a non-finite value, a radius `<= 0`.
    pub fn new(center: [f64; 3], radius: f64) -> Result<Self, ObstacleError> {
        check_finite("sphere", "center", &center)?;
        check_positive("sphere", "radius", radius)?;
        Ok(Self { center, radius })
    }

    /// Centre (m).
    pub fn center(&self) -> [f64; 3] {
        self.center
    }

    /// Radius (m).
    pub fn radius(&self) -> f64 {
        self.radius
    }
}

impl Obstacle for SphereObstacle {
    /// `g = |y - c| - R`, `n = (y - c)/|y - c|`, `dn/dy = (I - n n^T)/|y - c|`;
    /// feature `0`, hint ignored.
    fn proximity(&self, y: [f64; 3], _hint: Option<u32>) -> Proximity {
        if !super::is_finite(y) {
            return super::undefined();
        }
        let d = sub(y, self.center);
        let r = norm(d);
        let (normal, normal_derivative) = if r > 1e-12 * self.radius {
            let n = scale(d, 1.0 / r);
            (n, identity_minus(&[(n, 1.0)], 1.0 / r))
        } else {
            ([0.0, 0.0, 1.0], ZERO3)
        };
        let gap = if r > 1e-12 * self.radius {
            r - self.radius
        } else {
            -self.radius
        };
        Proximity {
            gap,
            closest: add(self.center, scale(normal, self.radius)),
            normal,
            normal_derivative,
            feature: 0,
        }
    }

    fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let r = [self.radius; 3];
        (sub(self.center, r), add(self.center, r))
    }

    fn describe(&self) -> String {
        format!(
            "sphere centre {} radius {}",
            show_point(self.center),
            self.radius
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::obstacle::testing::check_derivatives;

    fn ball() -> SphereObstacle {
        SphereObstacle::new([0.1, -0.2, 0.3], 0.25).unwrap()
    }

    #[test]
    fn known_values() {
        let s = ball();
        let p = s.proximity([0.1, -0.2, 0.6], None);
        assert!((p.gap - 0.05).abs() < 1e-15);
        assert_eq!(p.normal, [0.0, 0.0, 1.0]);
        assert!((p.closest[2] - 0.55).abs() < 1e-15);
        let q = s.proximity([0.2, -0.2, 0.3], None);
        assert!((q.gap + 0.15).abs() < 1e-15);
        assert_eq!(q.normal, [1.0, 0.0, 0.0]);
        // dn/dy = (I - n n^T)/r with r = 0.1.
        assert!((q.normal_derivative[1][1] - 10.0).abs() < 1e-12);
        assert_eq!(q.normal_derivative[0][0], 0.0);
    }

    #[test]
    fn centre_is_safe() {
        let p = ball().proximity([0.1, -0.2, 0.3], Some(3));
        assert_eq!(p.gap, -0.25);
        assert_eq!(p.normal, [0.0, 0.0, 1.0]);
        assert_eq!(p.normal_derivative, ZERO3);
        assert!(p.closest.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn derivatives_inside_and_outside() {
        let s = ball();
        for y in [
            [0.5, 0.1, 0.2],
            [0.1, -0.2, 0.7],
            [0.2, -0.1, 0.35],
            [0.0, -0.3, 0.2],
            [0.1, -0.2, 0.31],
            [-0.04, -0.33, 0.12],
        ] {
            check_derivatives(&s, y, None, 0.25);
        }
    }

    #[test]
    fn bounding_box_and_describe() {
        let s = ball();
        let (lo, hi) = s.bounding_box();
        assert_eq!(lo, [0.1 - 0.25, -0.2 - 0.25, 0.3 - 0.25]);
        assert_eq!(hi, [0.1 + 0.25, -0.2 + 0.25, 0.3 + 0.25]);
        assert_eq!(s.describe(), "sphere centre [0.1,-0.2,0.3] radius 0.25");
    }

    #[test]
    fn constructor_errors() {
        let e = SphereObstacle::new([0.0; 3], 0.0).unwrap_err();
        assert_eq!(e.to_string(), "sphere: radius must be positive, found 0");
        assert!(SphereObstacle::new([0.0; 3], -1.0).is_err());
        assert!(matches!(
            SphereObstacle::new([0.0; 3], f64::NAN).unwrap_err(),
            ObstacleError::NonFinite { key: "radius", .. }
        ));
        assert!(matches!(
            SphereObstacle::new([0.0, f64::INFINITY, 0.0], 1.0).unwrap_err(),
            ObstacleError::NonFinite { key: "center", .. }
        ));
    }
}
