//! The capped cylinder obstacle (a drape tester's pedestal).
//!
//! Given by `c`, the centre of the **top** face, the unit axis `a` pointing
//! from the bottom towards the top face, the radius `R` and the height `H`:
//! the solid is `-H <= h <= 0`, `rho <= R`, with the axial and radial
//! coordinates of a point `y`
//!
//! ```text
//! w = y - c,   h = w . a,   r = w - h a,   rho = |r|,   e_r = r / rho
//! ```
//!
//! Its three faces (features, in tie-breaking order) and their plane (or
//! radial) distances:
//!
//! | feature | face | `d_f(y)` | outward normal |
//! |---|---|---|---|
//! | 0 [`TOP`](CylinderObstacle::TOP) | top cap, `h = 0` | `h` | `a` |
//! | 1 [`BOTTOM`](CylinderObstacle::BOTTOM) | bottom cap, `h = -H` | `-H - h` | `-a` |
//! | 2 [`LATERAL`](CylinderObstacle::LATERAL) | lateral surface, `rho = R` | `rho - R` | `e_r` |
//!
//! With `D = max_f d_f` and the touching tolerance `tau` (see the [module
//! documentation](super) for the rule):
//!
//! * **outside** (`D > tau`), the true distance:
//!   * lateral region (`-H <= h <= 0`, `rho > R`): `g = rho - R`, `n = e_r`,
//!     `dn/dy = (I - a a^T - n n^T) / rho`;
//!   * cap region (`rho <= R`): `g = h` with `n = a` above, `g = -H - h` with
//!     `n = -a` below, `dn/dy = 0`;
//!   * rim region (beyond a cap and `rho > R`): the closest point is `q = c
//!     + h_c a + R e_r` on the rim circle (`h_c = 0` or `-H`), `g = |y - q|`,
//!     `n = (y - q) / g` and, with the circle's tangent `t = a x e_r`,
//!     `dn/dy = (I - n n^T - (R / rho) t t^T) / g` (the closest point slides
//!     along the circle as `y` moves: `dq/dy = (R / rho) t t^T`);
//!
//!   the feature is `argmax_f d_f`, the top cap for a point right above the
//!   rim.
//! * **inside or touching** (`D <= tau`): the face `f` is the hint if there
//!   is one, else `argmax_f d_f` (the nearest face, ties to the lower
//!   number: the top cap first); caps as planes (`g = d_f`, `dn/dy = 0`),
//!   the lateral surface with `g = rho - R`, `n = e_r`, `dn/dy = (I - a a^T -
//!   n n^T) / rho`. On the axis (`rho <= 1e-12 R`), where `e_r` is
//!   undefined, the lateral face uses a fixed radial direction
//!   ([`CylinderObstacle::reference_radial`]) and `dn/dy = 0`.

use super::{
    Obstacle, ObstacleError, Proximity, SharpPoint, TOUCH_TOLERANCE, ZERO3, check_finite,
    check_positive, cuboid::argmax, identity_minus, normalised, pieces, plane_proximity,
    show_point, unit,
};
use crate::vec3::{add, cross, dot, norm, scale, sub};

/// A solid capped cylinder (scenario `shape = "cylinder"`, keys `center` (of
/// the top face), `axis`, `radius`, `height`).
#[derive(Debug, Clone, PartialEq)]
pub struct CylinderObstacle {
    center: [f64; 3],
    axis: [f64; 3],
    radius: f64,
    height: f64,
    /// A unit vector perpendicular to the axis, the radial direction used on
    /// the axis itself.
    reference_radial: [f64; 3],
    /// Touching tolerance `tau` (m).
    tolerance: f64,
}

impl CylinderObstacle {
    /// Feature of the top cap (listed first: it wins ties).
    pub const TOP: u32 = 0;
    /// Feature of the bottom cap.
    pub const BOTTOM: u32 = 1;
    /// Feature of the lateral surface.
    pub const LATERAL: u32 = 2;

    /// The cylinder whose top face is centred on `center` (m), with axis
    /// `axis` (towards the top face; any length but zero, it is normalised),
    /// radius `radius` (m) and height `height` (m): it extends from the top
    /// face down to `center - height axis`.
    ///
    /// Errors: a non-finite value, a zero axis, a radius or height `<= 0`.
    pub fn new(
        center: [f64; 3],
        axis: [f64; 3],
        radius: f64,
        height: f64,
    ) -> Result<Self, ObstacleError> {
        check_finite("cylinder", "center", &center)?;
        let axis = unit("cylinder", "axis", axis)?;
        check_positive("cylinder", "radius", radius)?;
        check_positive("cylinder", "height", height)?;
        // The coordinate axis least aligned with `a`, made perpendicular to it.
        let k = (0..3)
            .min_by(|&i, &j| axis[i].abs().total_cmp(&axis[j].abs()))
            .unwrap_or(0);
        let mut e = [0.0; 3];
        e[k] = 1.0;
        let u = sub(e, scale(axis, axis[k]));
        let reference_radial = scale(u, 1.0 / norm(u));
        let size = (4.0 * radius * radius + height * height).sqrt();
        Ok(Self {
            center,
            axis,
            radius,
            height,
            reference_radial,
            tolerance: TOUCH_TOLERANCE * size,
        })
    }

    /// Centre of the top face (m).
    pub fn center(&self) -> [f64; 3] {
        self.center
    }

    /// Unit axis, pointing towards the top face.
    pub fn axis(&self) -> [f64; 3] {
        self.axis
    }

    /// Radius (m).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Height (m).
    pub fn height(&self) -> f64 {
        self.height
    }

    /// The unit radial direction used for points on the axis: the
    /// coordinate axis least aligned with the cylinder's axis, made
    /// perpendicular to it.
    pub fn reference_radial(&self) -> [f64; 3] {
        self.reference_radial
    }

    /// The lateral surface's answer for a point with axial coordinate `h`,
    /// radial vector `r` and `rho = |r|`.
    fn lateral(&self, h: f64, r: [f64; 3], rho: f64) -> Proximity {
        let axial = add(self.center, scale(self.axis, h));
        let (normal, normal_derivative) = if rho > 1e-12 * self.radius {
            let n = scale(r, 1.0 / rho);
            (n, identity_minus(&[(n, 1.0), (self.axis, 1.0)], 1.0 / rho))
        } else {
            (self.reference_radial, ZERO3)
        };
        Proximity {
            gap: rho - self.radius,
            closest: add(axial, scale(normal, self.radius)),
            normal,
            normal_derivative,
            feature: Self::LATERAL,
        }
    }
}

impl Obstacle for CylinderObstacle {
    /// See the [module documentation](self): true distance outside, the
    /// hinted face (else the nearest) inside.
    /// The cap's plane or the lateral surface of the held face while the
    /// node's projection lies on it.
    fn constraint(&self, y: [f64; 3], feature: u32) -> (Proximity, bool) {
        if feature > Self::LATERAL || !super::is_finite(y) {
            return (self.proximity(y, None), false);
        }
        let a = self.axis;
        let w = sub(y, self.center);
        let h = dot(w, a);
        let r = sub(w, scale(a, h));
        let rho = norm(r);
        let tol = self.tolerance;
        match feature {
            Self::TOP => (
                plane_proximity(y, h, a, Self::TOP),
                rho <= self.radius + tol,
            ),
            Self::BOTTOM => (
                plane_proximity(y, -self.height - h, scale(a, -1.0), Self::BOTTOM),
                rho <= self.radius + tol,
            ),
            _ => (self.lateral(h, r, rho), h <= tol && h >= -self.height - tol),
        }
    }

    fn proximity(&self, y: [f64; 3], hint: Option<u32>) -> Proximity {
        if !super::is_finite(y) {
            return super::undefined();
        }
        let a = self.axis;
        let w = sub(y, self.center);
        let h = dot(w, a);
        let r = sub(w, scale(a, h));
        let rho = norm(r);
        let d = [h, -self.height - h, rho - self.radius];
        let arg = argmax(&d);
        let face = |f: usize| match f {
            0 => plane_proximity(y, d[0], a, Self::TOP),
            1 => plane_proximity(y, d[1], scale(a, -1.0), Self::BOTTOM),
            _ => self.lateral(h, r, rho),
        };
        if d[arg] <= self.tolerance {
            let f = match hint {
                Some(f) if (f as usize) < d.len() => f as usize,
                _ => arg,
            };
            return face(f);
        }
        let above = h > 0.0;
        let below = h < -self.height;
        let mut p = if rho <= self.radius {
            face(if above { 0 } else { 1 })
        } else if !above && !below {
            face(2)
        } else {
            let e_r = scale(r, 1.0 / rho);
            let h_c = if above { 0.0 } else { -self.height };
            let q = add(self.center, add(scale(a, h_c), scale(e_r, self.radius)));
            let diff = sub(y, q);
            let gap = norm(diff);
            let n = scale(diff, 1.0 / gap);
            let t = cross(a, e_r);
            Proximity {
                gap,
                closest: q,
                normal: n,
                normal_derivative: identity_minus(&[(n, 1.0), (t, self.radius / rho)], 1.0 / gap),
                feature: 0,
            }
        };
        p.feature = arg as u32;
        p
    }

    /// The box around the two end discs: a disc of radius `R` with normal
    /// `a` spans `R sqrt(1 - a_k^2)` about its centre along axis `k`.
    fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let bottom = sub(self.center, scale(self.axis, self.height));
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for k in 0..3 {
            let extent = self.radius * (1.0 - self.axis[k] * self.axis[k]).max(0.0).sqrt();
            lo[k] = self.center[k].min(bottom[k]) - extent;
            hi[k] = self.center[k].max(bottom[k]) + extent;
        }
        (lo, hi)
    }

    fn describe(&self) -> String {
        format!(
            "cylinder top centre {} axis {} radius {} height {}",
            show_point(self.center),
            show_point(self.axis),
            self.radius,
            self.height
        )
    }

    /// The two rim circles, each cut into equal arcs no longer than
    /// `spacing`: outward the mean of the cap's normal and the radial
    /// direction.
    fn sharp_points(&self, spacing: f64) -> Vec<SharpPoint> {
        let u = self.reference_radial;
        let w = cross(self.axis, u);
        let n = pieces(std::f64::consts::TAU * self.radius, spacing).max(3);
        let bottom = sub(self.center, scale(self.axis, self.height));
        let mut out = Vec::with_capacity(2 * n);
        for (centre, cap) in [(self.center, self.axis), (bottom, scale(self.axis, -1.0))] {
            for i in 0..n {
                let phi = std::f64::consts::TAU * i as f64 / n as f64;
                let radial = add(scale(u, phi.cos()), scale(w, phi.sin()));
                out.push(SharpPoint {
                    position: add(centre, scale(radial, self.radius)),
                    outward: normalised(add(cap, radial)),
                });
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::obstacle::testing::check_derivatives;

    const R: f64 = 0.1;
    const H: f64 = 0.05;

    /// Axis +z, top face centred on the origin.
    fn pedestal() -> CylinderObstacle {
        CylinderObstacle::new([0.0; 3], [0.0, 0.0, 1.0], R, H).unwrap()
    }

    /// A tilted cylinder and the frame `(u, v, a)` that maps the upright
    /// one's local coordinates onto it.
    fn tilted() -> (CylinderObstacle, [[f64; 3]; 3]) {
        let c = CylinderObstacle::new([0.3, -0.1, 0.2], [2.0, 2.0, 1.0], R, H).unwrap();
        let a = c.axis();
        let u = c.reference_radial();
        let v = cross(a, u);
        (c, [u, v, a])
    }

    #[test]
    fn known_values() {
        let c = pedestal();
        let p = c.proximity([0.01, 0.02, 0.02], None);
        assert!((p.gap - 0.02).abs() < 1e-15);
        assert_eq!(p.feature, CylinderObstacle::TOP);
        assert_eq!(p.normal, [0.0, 0.0, 1.0]);
        let p = c.proximity([0.15, 0.0, -0.02], None);
        assert!((p.gap - 0.05).abs() < 1e-15);
        assert_eq!(p.feature, CylinderObstacle::LATERAL);
        assert_eq!(p.normal, [1.0, 0.0, 0.0]);
        assert_eq!(p.closest, [R, 0.0, -0.02]);
        let p = c.proximity([0.03, 0.0, -0.08], None);
        assert!((p.gap - 0.03).abs() < 1e-15);
        assert_eq!(p.feature, CylinderObstacle::BOTTOM);
        assert_eq!(p.normal, [0.0, 0.0, -1.0]);
        let p = c.proximity([0.02, 0.0, -0.01], None);
        assert!((p.gap + 0.01).abs() < 1e-15);
        assert_eq!(p.feature, CylinderObstacle::TOP);
        let p = c.proximity([0.0, 0.095, -0.025], None);
        assert!((p.gap + 0.005).abs() < 1e-15);
        assert_eq!(p.feature, CylinderObstacle::LATERAL);
        // Rim region: distance to the circle.
        let p = c.proximity([0.13, 0.0, 0.04], None);
        assert!((p.gap - 0.05).abs() < 1e-15);
        assert_eq!(p.feature, CylinderObstacle::TOP);
        let p = c.proximity([0.0, -0.14, -0.08], None);
        assert!((p.gap - 0.05).abs() < 1e-15);
        assert_eq!(p.feature, CylinderObstacle::LATERAL);
        assert_eq!(p.closest, [0.0, -R, -H]);
    }

    #[test]
    fn rim_trap() {
        let c = pedestal();
        let above = c.proximity([R, 0.0, 1e-3], None);
        assert_eq!(above.feature, CylinderObstacle::TOP);
        assert!((above.gap - 1e-3).abs() < 1e-15);
        assert_eq!(above.normal, [0.0, 0.0, 1.0]);
        let y = [R, 0.0, -1e-4];
        let lost = c.proximity(y, None);
        assert_eq!(lost.feature, CylinderObstacle::LATERAL);
        assert_eq!(lost.gap, 0.0);
        let held = c.proximity(y, Some(above.feature));
        assert_eq!(held.feature, CylinderObstacle::TOP);
        assert!((held.gap + 1e-4).abs() < 1e-15);
        assert_eq!(held.normal, [0.0, 0.0, 1.0]);
        // On the rim at 40 degrees `rho` carries round-off: the touching band
        // absorbs it.
        let (s, co) = 40f64.to_radians().sin_cos();
        let y = [R * co, R * s, -1e-4];
        let above = c.proximity([R * co, R * s, 1e-3], None);
        assert_eq!(above.feature, CylinderObstacle::TOP);
        let held = c.proximity(y, Some(above.feature));
        assert!((held.gap + 1e-4).abs() < 1e-15);
        assert_eq!(c.proximity(y, None).feature, CylinderObstacle::LATERAL);
        assert!(c.proximity(y, None).gap.abs() < 1e-15);
    }

    #[test]
    fn on_the_axis_is_safe() {
        // A long cylinder, so that the lateral surface is the nearest.
        let c = CylinderObstacle::new([0.0; 3], [0.0, 0.0, 1.0], 0.1, 1.0).unwrap();
        let p = c.proximity([0.0, 0.0, -0.5], None);
        assert_eq!(p.feature, CylinderObstacle::LATERAL);
        assert_eq!(p.gap, -0.1);
        assert!((norm(p.normal) - 1.0).abs() < 1e-15 && p.normal[2] == 0.0);
        assert_eq!(p.normal_derivative, ZERO3);
    }

    #[test]
    fn tilted_cylinder_matches_the_upright_one() {
        let upright = pedestal();
        let (c, [u, v, a]) = tilted();
        let mut state: u64 = 99;
        let mut rand = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..1000 {
            let local = [0.2 * rand(), 0.2 * rand(), -0.025 + 0.1 * rand()];
            let world = add(
                c.center(),
                add(
                    scale(u, local[0]),
                    add(scale(v, local[1]), scale(a, local[2])),
                ),
            );
            for hint in [None, Some(0), Some(1), Some(2)] {
                let p = upright.proximity(local, hint);
                let q = c.proximity(world, hint);
                assert!((p.gap - q.gap).abs() < 1e-14, "{local:?}: {p:?} vs {q:?}");
                assert_eq!(p.feature, q.feature);
                let n = add(
                    scale(u, p.normal[0]),
                    add(scale(v, p.normal[1]), scale(a, p.normal[2])),
                );
                assert!(norm(sub(n, q.normal)) < 1e-12, "{local:?}: {p:?} vs {q:?}");
            }
        }
    }

    #[test]
    fn derivatives_outside() {
        let c = pedestal();
        let points = [
            // Caps.
            [0.02, -0.03, 0.01],
            [0.05, 0.06, 0.03],
            [-0.02, 0.01, -0.09],
            // Lateral surface.
            [0.12, 0.03, -0.02],
            [-0.1, -0.09, -0.04],
            [0.0, 0.103, -0.001],
            // Rims (outside, curved field).
            [0.11, 0.02, 0.01],
            [0.09, 0.09, 0.004],
            [-0.12, 0.05, -0.06],
            [0.0, -0.103, 0.002],
        ];
        for y in points {
            check_derivatives(&c, y, None, R);
        }
        let (t, [u, v, a]) = tilted();
        for y in points {
            let world = add(
                t.center(),
                add(scale(u, y[0]), add(scale(v, y[1]), scale(a, y[2]))),
            );
            check_derivatives(&t, world, None, R);
        }
    }

    #[test]
    fn derivatives_inside() {
        let c = pedestal();
        for y in [
            [0.01, 0.02, -0.005],
            [0.03, -0.04, -0.045],
            [0.08, 0.04, -0.025],
            [-0.02, -0.085, -0.03],
        ] {
            check_derivatives(&c, y, None, R);
        }
        // Entered through the top near the rim; entered through the side
        // near the top (the lateral face keeps its curvature).
        for (y, f) in [
            ([0.099, 0.0, -1e-3], CylinderObstacle::TOP),
            ([0.06, 0.078, -4e-3], CylinderObstacle::TOP),
            ([0.08, 0.05, -1e-4], CylinderObstacle::LATERAL),
            ([0.0, -0.095, -0.049], CylinderObstacle::LATERAL),
            ([0.0, -0.095, -0.0499], CylinderObstacle::BOTTOM),
        ] {
            check_derivatives(&c, y, Some(f), R);
        }
        let (t, [u, v, a]) = tilted();
        let y = [0.08, 0.05, -1e-4];
        let world = add(
            t.center(),
            add(scale(u, y[0]), add(scale(v, y[1]), scale(a, y[2]))),
        );
        check_derivatives(&t, world, Some(CylinderObstacle::LATERAL), R);
    }

    #[test]
    fn bounding_box_and_describe() {
        let (lo, hi) = pedestal().bounding_box();
        assert_eq!(lo, [-R, -R, -H]);
        assert_eq!(hi, [R, R, 0.0]);
        let c = CylinderObstacle::new([0.0; 3], [1.0, 0.0, 0.0], 0.5, 2.0).unwrap();
        assert_eq!(c.bounding_box(), ([-2.0, -0.5, -0.5], [0.0, 0.5, 0.5]));
        assert_eq!(
            pedestal().describe(),
            "cylinder top centre [0,0,0] axis [0,0,1] radius 0.1 height 0.05"
        );
        // The tilted box contains points of the surface.
        let (t, [u, _, a]) = tilted();
        let (lo, hi) = t.bounding_box();
        for p in [
            add(t.center(), scale(u, R)),
            sub(add(t.center(), scale(u, -R)), scale(a, H)),
        ] {
            assert!((0..3).all(|k| p[k] >= lo[k] - 1e-15 && p[k] <= hi[k] + 1e-15));
        }
    }

    #[test]
    fn constructor_errors() {
        let e = CylinderObstacle::new([0.0; 3], [0.0; 3], 1.0, 1.0).unwrap_err();
        assert_eq!(e.to_string(), "cylinder: axis must not be the zero vector");
        let e = CylinderObstacle::new([0.0; 3], [0.0, 0.0, 1.0], -1.0, 1.0).unwrap_err();
        assert!(
            matches!(e, ObstacleError::NonPositive { key: "radius", .. }),
            "{e}"
        );
        let e = CylinderObstacle::new([0.0; 3], [0.0, 0.0, 1.0], 1.0, 0.0).unwrap_err();
        assert_eq!(e.to_string(), "cylinder: height must be positive, found 0");
        let e = CylinderObstacle::new([0.0, f64::NAN, 0.0], [0.0, 0.0, 1.0], 1.0, 1.0).unwrap_err();
        assert!(
            matches!(e, ObstacleError::NonFinite { key: "center", .. }),
            "{e}"
        );
        // The axis is normalised.
        let c = CylinderObstacle::new([0.0; 3], [0.0, 0.0, 3.0], 1.0, 1.0).unwrap();
        assert_eq!(c.axis(), [0.0, 0.0, 1.0]);
    }
}
