//! The axis-aligned box obstacle (`box` is a Rust keyword, hence the file's
//! name).
//!
//! The box `min <= y <= max` has six faces, numbered (the feature) in this
//! order, which is also the order that breaks ties:
//!
//! | feature | face | outward normal `n_f` | plane distance `d_f(y)` |
//! |---|---|---|---|
//! | 0 [`TOP`](BoxObstacle::TOP) | `z = max_z` | `+z` | `y_z - max_z` |
//! | 1 [`BOTTOM`](BoxObstacle::BOTTOM) | `z = min_z` | `-z` | `min_z - y_z` |
//! | 2 [`PLUS_X`](BoxObstacle::PLUS_X) | `x = max_x` | `+x` | `y_x - max_x` |
//! | 3 [`MINUS_X`](BoxObstacle::MINUS_X) | `x = min_x` | `-x` | `min_x - y_x` |
//! | 4 [`PLUS_Y`](BoxObstacle::PLUS_Y) | `y = max_y` | `+y` | `y_y - max_y` |
//! | 5 [`MINUS_Y`](BoxObstacle::MINUS_Y) | `y = min_y` | `-y` | `min_y - y_y` |
//!
//! With `D = max_f d_f` and the touching tolerance `tau` (see the [module
//! documentation](super) for the rule and its reasons):
//!
//! * **outside** (`D > tau`): the closest point is `y' = clamp(y, min,
//!   max)`, `g = |y - y'|`, `n = (y - y') / g`. With `k` the number of
//!   clamped coordinates: `k = 1`, a face, `dn/dy = 0`; `k = 2`, an edge of
//!   direction `e` (the unclamped axis), `dn/dy = (I - n n^T - e e^T) / g`;
//!   `k = 3`, a corner, `dn/dy = (I - n n^T) / g`. The feature is `argmax_f
//!   d_f` (the top face for a point above a top edge or corner).
//! * **inside or touching** (`D <= tau`): the face `f` is the hint if there
//!   is one, else `argmax_f d_f` (the nearest face; ties to the lower
//!   number, so the top face first); `g = d_f`, `n = n_f`, `y' = y - g n`,
//!   `dn/dy = 0`.

use super::{
    Obstacle, ObstacleError, Proximity, SharpPoint, TOUCH_TOLERANCE, check_finite, diagonal,
    identity_minus, normalised, plane_proximity, sample_segment, show_point,
};
use crate::vec3::{norm, scale, sub};

/// An axis-aligned box (scenario `shape = "box"`, keys `min` and `max`).
#[derive(Debug, Clone, PartialEq)]
pub struct BoxObstacle {
    min: [f64; 3],
    max: [f64; 3],
    /// Touching tolerance `tau` (m).
    tolerance: f64,
}

impl BoxObstacle {
    /// Feature of the top face `z = max_z` (listed first: it wins ties).
    pub const TOP: u32 = 0;
    /// Feature of the bottom face `z = min_z`.
    pub const BOTTOM: u32 = 1;
    /// Feature of the face `x = max_x`.
    pub const PLUS_X: u32 = 2;
    /// Feature of the face `x = min_x`.
    pub const MINUS_X: u32 = 3;
    /// Feature of the face `y = max_y`.
    pub const PLUS_Y: u32 = 4;
    /// Feature of the face `y = min_y`.
    pub const MINUS_Y: u32 = 5;
    /// Outward unit normals of the faces, indexed by feature.
    pub const FACE_NORMALS: [[f64; 3]; 6] = [
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
    ];

    /// The box `min <= y <= max` (m).
    ///
    /// Errors: a non-finite value, `min >= max` in some component.
    pub fn new(min: [f64; 3], max: [f64; 3]) -> Result<Self, ObstacleError> {
        check_finite("box", "min", &min)?;
        check_finite("box", "max", &max)?;
        for (k, axis) in ['x', 'y', 'z'].into_iter().enumerate() {
            if min[k] >= max[k] {
                return Err(ObstacleError::EmptyBox {
                    axis,
                    min: min[k],
                    max: max[k],
                });
            }
        }
        Ok(Self {
            min,
            max,
            tolerance: TOUCH_TOLERANCE * diagonal(min, max),
        })
    }

    /// Lower corner (m).
    pub fn min(&self) -> [f64; 3] {
        self.min
    }

    /// Upper corner (m).
    pub fn max(&self) -> [f64; 3] {
        self.max
    }

    /// Plane signed distances `d_f(y) = n_f . (y - p_f)` of the six faces,
    /// indexed by feature.
    pub fn plane_distances(&self, y: [f64; 3]) -> [f64; 6] {
        [
            y[2] - self.max[2],
            self.min[2] - y[2],
            y[0] - self.max[0],
            self.min[0] - y[0],
            y[1] - self.max[1],
            self.min[1] - y[1],
        ]
    }
}

/// Index of the largest entry, the first one on ties.
pub(super) fn argmax(values: &[f64]) -> usize {
    let mut best = 0;
    for (i, &v) in values.iter().enumerate().skip(1) {
        if v > values[best] {
            best = i;
        }
    }
    best
}

impl Obstacle for BoxObstacle {
    /// The plane of face `feature` while the node's projection lies on the face.
    fn constraint(&self, y: [f64; 3], feature: u32) -> (Proximity, bool) {
        let f = feature as usize;
        if f >= 6 || !super::is_finite(y) {
            return (self.proximity(y, None), false);
        }
        // The axis normal to face f, and the other two.
        let axis = [2, 2, 0, 0, 1, 1][f];
        let on_face = (0..3)
            .filter(|&k| k != axis)
            .all(|k| y[k] >= self.min[k] - self.tolerance && y[k] <= self.max[k] + self.tolerance);
        let plane = plane_proximity(
            y,
            self.plane_distances(y)[f],
            Self::FACE_NORMALS[f],
            feature,
        );
        (plane, on_face)
    }

    /// See the [module documentation](self): true distance outside, the
    /// hinted face (else the nearest) inside.
    fn proximity(&self, y: [f64; 3], hint: Option<u32>) -> Proximity {
        if !super::is_finite(y) {
            return super::undefined();
        }
        let d = self.plane_distances(y);
        let arg = argmax(&d);
        if d[arg] > self.tolerance {
            let mut closest = y;
            let mut free_axis = None;
            let mut clamped = 0;
            for k in 0..3 {
                if y[k] > self.max[k] {
                    closest[k] = self.max[k];
                    clamped += 1;
                } else if y[k] < self.min[k] {
                    closest[k] = self.min[k];
                    clamped += 1;
                } else {
                    free_axis = Some(k);
                }
            }
            let diff = sub(y, closest);
            let gap = norm(diff);
            // One clamped coordinate: a face region, whose normal is the
            // face's, exactly (diff / |diff| can be off by an ulp).
            let n = if clamped == 1 {
                diff.map(|c| if c == 0.0 { 0.0 } else { c.signum() })
            } else {
                scale(diff, 1.0 / gap)
            };
            let normal_derivative = match (clamped, free_axis) {
                (1, _) => super::ZERO3,
                (2, Some(k)) => {
                    let mut e = [0.0; 3];
                    e[k] = 1.0;
                    identity_minus(&[(n, 1.0), (e, 1.0)], 1.0 / gap)
                }
                _ => identity_minus(&[(n, 1.0)], 1.0 / gap),
            };
            Proximity {
                gap,
                closest,
                normal: n,
                normal_derivative,
                feature: arg as u32,
            }
        } else {
            let f = match hint {
                Some(h) if (h as usize) < d.len() => h as usize,
                _ => arg,
            };
            plane_proximity(y, d[f], Self::FACE_NORMALS[f], f as u32)
        }
    }

    fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        (self.min, self.max)
    }

    fn describe(&self) -> String {
        format!("box {}..{}", show_point(self.min), show_point(self.max))
    }

    /// The eight corners (outward `(±1, ±1, ±1)/√3`) and the points inside
    /// the twelve edges (outward the mean of the two faces' normals).
    fn sharp_points(&self, spacing: f64) -> Vec<SharpPoint> {
        let corner = |c: usize| -> [f64; 3] {
            std::array::from_fn(|k| {
                if c >> k & 1 == 1 {
                    self.max[k]
                } else {
                    self.min[k]
                }
            })
        };
        let sign = |c: usize, k: usize| if c >> k & 1 == 1 { 1.0 } else { -1.0 };
        let mut out: Vec<SharpPoint> = (0..8)
            .map(|c| SharpPoint {
                position: corner(c),
                outward: normalised([sign(c, 0), sign(c, 1), sign(c, 2)]),
            })
            .collect();
        // Edge along axis k from corner c (bit k clear) to c + 2^k.
        for k in 0..3 {
            for c in (0..8).filter(|c| c >> k & 1 == 0) {
                let mut m = [sign(c, 0), sign(c, 1), sign(c, 2)];
                m[k] = 0.0;
                sample_segment(
                    corner(c),
                    corner(c | 1 << k),
                    normalised(m),
                    spacing,
                    &mut out,
                );
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::obstacle::testing::check_derivatives;
    use crate::vec3::dot;

    const TOP_Z: f64 = -0.05;

    /// The pedestal of the canonical example.
    fn pedestal() -> BoxObstacle {
        BoxObstacle::new([-0.05, -0.05, -0.25], [0.05, 0.05, TOP_Z]).unwrap()
    }

    #[test]
    fn known_values() {
        let b = pedestal();
        let p = b.proximity([0.0, 0.0, TOP_Z + 0.02], None);
        assert!((p.gap - 0.02).abs() < 1e-15);
        assert_eq!(p.normal, [0.0, 0.0, 1.0]);
        assert_eq!(p.feature, BoxObstacle::TOP);
        assert_eq!(p.closest, [0.0, 0.0, TOP_Z]);
        let q = b.proximity([0.01, 0.02, TOP_Z - 0.01], None);
        assert!((q.gap + 0.01).abs() < 1e-15);
        assert_eq!(q.feature, BoxObstacle::TOP);
        // Nearer the side than the top: the side decides without a hint.
        let s = b.proximity([0.045, 0.0, TOP_Z - 0.01], None);
        assert!((s.gap + 0.005).abs() < 1e-15);
        assert_eq!(s.feature, BoxObstacle::PLUS_X);
        assert_eq!(s.normal, [1.0, 0.0, 0.0]);
        // Below the bottom, in a face region.
        let u = b.proximity([0.0, 0.01, -0.3], None);
        assert!((u.gap - 0.05).abs() < 1e-15);
        assert_eq!(u.feature, BoxObstacle::BOTTOM);
    }

    #[test]
    fn outside_an_edge_the_distance_is_euclidean_and_the_feature_is_the_top() {
        let b = pedestal();
        let p = b.proximity([0.06, 0.0, TOP_Z + 0.01], None);
        assert!((p.gap - 0.01 * 2f64.sqrt()).abs() < 1e-15);
        let s = std::f64::consts::FRAC_1_SQRT_2;
        assert!((p.normal[0] - s).abs() < 1e-15 && (p.normal[2] - s).abs() < 1e-15);
        // d_top = d_+x = 0.01 (up to round-off); the tie goes to the top.
        assert_eq!(p.feature, BoxObstacle::TOP);
        let q = b.proximity([0.07, 0.0, TOP_Z + 0.01], None);
        assert_eq!(q.feature, BoxObstacle::PLUS_X);
    }

    /// The trap of the 20 x 20 grid over the pedestal: a node exactly above
    /// the edge `x = 0.05`.
    #[test]
    fn edge_trap() {
        let b = pedestal();
        // Approach from above: the top face, at the true distance.
        let above = b.proximity([0.05, 0.0, TOP_Z + 1e-3], None);
        assert_eq!(above.feature, BoxObstacle::TOP);
        assert!((above.gap - 1e-3).abs() < 1e-15);
        assert_eq!(above.normal, [0.0, 0.0, 1.0]);
        // Sunk by 1e-4 with no history: the nearest face is the side, at
        // distance 0 (argmax of d = (-1e-4, .., 0, ..)).
        let y = [0.05, 0.0, TOP_Z - 1e-4];
        let lost = b.proximity(y, None);
        assert_eq!(lost.feature, BoxObstacle::PLUS_X);
        assert_eq!(lost.gap, 0.0);
        // With the feature it had above, the top pushes it back out.
        let held = b.proximity(y, Some(above.feature));
        assert_eq!(held.feature, BoxObstacle::TOP);
        assert!((held.gap + 1e-4).abs() < 1e-15);
        assert_eq!(held.normal, [0.0, 0.0, 1.0]);
        assert_eq!(held.normal_derivative, [[0.0; 3]; 3]);
        // Round-off a hair outside the side (one ulp) is still touching.
        let hair = [f64::from_bits(0.05f64.to_bits() + 1), 0.0, TOP_Z - 1e-4];
        let held = b.proximity(hair, Some(BoxObstacle::TOP));
        assert!((held.gap + 1e-4).abs() < 1e-15);
        // Beyond the touching band the node is outside the side: free.
        let off = b.proximity([0.05 + 1e-6, 0.0, TOP_Z - 1e-4], Some(BoxObstacle::TOP));
        assert_eq!(off.feature, BoxObstacle::PLUS_X);
        assert!((off.gap - 1e-6).abs() < 1e-15);
    }

    #[test]
    fn corner_trap() {
        let b = pedestal();
        let above = b.proximity([0.05, 0.05, TOP_Z + 1e-3], None);
        assert_eq!(above.feature, BoxObstacle::TOP);
        assert!((above.gap - 1e-3).abs() < 1e-15);
        assert_eq!(above.normal, [0.0, 0.0, 1.0]);
        let y = [0.05, 0.05, TOP_Z - 1e-4];
        // Tie between +x and +y (both 0): +x, listed first.
        let lost = b.proximity(y, None);
        assert_eq!(lost.feature, BoxObstacle::PLUS_X);
        assert_eq!(lost.gap, 0.0);
        let held = b.proximity(y, Some(BoxObstacle::TOP));
        assert_eq!(held.feature, BoxObstacle::TOP);
        assert!((held.gap + 1e-4).abs() < 1e-15);
        // The same on the -x, -y corner, exactly representable.
        let lost = b.proximity([-0.05, -0.05, TOP_Z - 1e-4], None);
        assert_eq!(lost.feature, BoxObstacle::MINUS_X);
    }

    #[test]
    fn ties_inside_prefer_the_top() {
        let b = BoxObstacle::new([-1.0; 3], [1.0; 3]).unwrap();
        // At the centre every face is at distance 1.
        assert_eq!(b.proximity([0.0; 3], None).feature, BoxObstacle::TOP);
        // Equidistant from +x and +y: +x.
        assert_eq!(
            b.proximity([0.5, 0.5, 0.0], None).feature,
            BoxObstacle::PLUS_X
        );
        // An invalid hint is ignored.
        assert_eq!(b.proximity([0.0; 3], Some(6)).feature, BoxObstacle::TOP);
        assert_eq!(
            b.proximity([0.9, 0.0, 0.0], Some(99)).feature,
            BoxObstacle::PLUS_X
        );
    }

    #[test]
    fn without_hint_the_closest_point_is_on_the_surface() {
        let b = pedestal();
        let mut state: u64 = 7;
        let mut rand = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..2000 {
            let y = [
                -0.1 + 0.2 * rand(),
                -0.1 + 0.2 * rand(),
                -0.3 + 0.3 * rand(),
            ];
            let p = b.proximity(y, None);
            let c = p.closest;
            let inside = (0..3).all(|k| c[k] >= b.min[k] - 1e-15 && c[k] <= b.max[k] + 1e-15);
            let on_face =
                (0..3).any(|k| (c[k] - b.min[k]).abs() < 1e-15 || (c[k] - b.max[k]).abs() < 1e-15);
            assert!(inside && on_face, "{y:?} -> {p:?}");
            // |g| is the distance to the surface: no face point is nearer.
            let dist = norm(sub(y, c));
            assert!((dist - p.gap.abs()).abs() < 1e-15);
            let d = b.plane_distances(y);
            if p.gap < 0.0 {
                assert!((p.gap - d.iter().fold(f64::MIN, |m, v| m.max(*v))).abs() < 1e-15);
            }
            assert!((dot(sub(y, c), p.normal) - p.gap).abs() < 1e-15);
        }
    }

    #[test]
    fn derivatives_outside_faces_edges_corners() {
        let b = pedestal();
        let size = 0.1;
        // Off the diagonals where the argmax face switches (d_f = d_g).
        let points = [
            // Face regions.
            [0.01, 0.02, TOP_Z + 0.03],
            [0.08, -0.01, -0.1],
            [-0.02, -0.07, -0.2],
            [0.0, 0.01, -0.27],
            // Edge regions (curved field).
            [0.075, 0.01, TOP_Z + 0.02],
            [0.065, 0.0, TOP_Z + 0.04],
            [-0.063, 0.03, -0.26],
            [0.06, 0.07, -0.12],
            [0.02, -0.058, TOP_Z + 0.003],
            // Corner regions.
            [0.07, 0.06, TOP_Z + 0.025],
            [-0.06, -0.08, -0.27],
            [0.051, -0.052, TOP_Z + 0.003],
        ];
        for y in points {
            check_derivatives(&b, y, None, size);
        }
    }

    #[test]
    fn derivatives_inside_with_and_without_hint() {
        let b = pedestal();
        for y in [
            [0.01, 0.0, TOP_Z - 0.01],
            [0.04, 0.01, TOP_Z - 0.03],
            [-0.03, 0.02, -0.22],
            [0.0, -0.045, -0.15],
        ] {
            check_derivatives(&b, y, None, 0.1);
        }
        // With the top face as hint, near the side and the edge.
        for y in [
            [0.049, 0.0, TOP_Z - 1e-3],
            [0.0499, 0.03, TOP_Z - 2e-3],
            [0.0499, 0.0499, TOP_Z - 5e-3],
        ] {
            check_derivatives(&b, y, Some(BoxObstacle::TOP), 0.1);
        }
    }

    #[test]
    fn describe_and_bounding_box() {
        let b = pedestal();
        assert_eq!(b.describe(), "box [-0.05,-0.05,-0.25]..[0.05,0.05,-0.05]");
        assert_eq!(
            b.bounding_box(),
            ([-0.05, -0.05, -0.25], [0.05, 0.05, -0.05])
        );
    }

    #[test]
    fn constructor_errors() {
        let e = BoxObstacle::new([0.0, 0.0, 0.0], [1.0, 1.0, 0.0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "box: min must be less than max in every component, but min z = 0 >= max z = 0"
        );
        let e = BoxObstacle::new([0.0, 2.0, 0.0], [1.0, 1.0, 1.0]).unwrap_err();
        assert!(
            matches!(e, ObstacleError::EmptyBox { axis: 'y', .. }),
            "{e}"
        );
        let e = BoxObstacle::new([0.0, 0.0, f64::NAN], [1.0; 3]).unwrap_err();
        assert!(
            matches!(e, ObstacleError::NonFinite { key: "min", .. }),
            "{e}"
        );
        let e = BoxObstacle::new([0.0; 3], [1.0, f64::INFINITY, 1.0]).unwrap_err();
        assert!(
            matches!(e, ObstacleError::NonFinite { key: "max", .. }),
            "{e}"
        );
    }

    #[test]
    fn non_finite_point_does_not_panic() {
        let p = pedestal().proximity([f64::NAN, 0.0, 0.0], Some(0));
        assert!(p.gap.is_nan());
        let p = pedestal().proximity([f64::INFINITY, 0.0, 0.0], None);
        assert!(p.gap.is_nan());
    }
}
