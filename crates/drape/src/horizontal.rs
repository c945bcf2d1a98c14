//! A plane normal to a given direction, with an orthonormal pair of axes
//! in it: the horizontal plane of a drape measurement
//! ([`crate::measure`]), the plane of a drape test's specimen
//! ([`crate::specimen`]).

use crate::vec3;

/// The horizontal plane of a measurement: the unit vertical `k` and an
/// orthonormal pair `e1, e2` with `e1 × e2 = k`, about an origin `c` (a
/// point on the pedestal's axis). A point `x` projects to
/// `(e1 · (x − c), e2 · (x − c))`; for `k = +z`, `e1 = x`, `e2 = y`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Horizontal {
    origin: [f64; 3],
    vertical: [f64; 3],
    e1: [f64; 3],
    e2: [f64; 3],
}

impl Horizontal {
    /// The plane normal to `vertical` (any length) through `origin`;
    /// `None` for a zero or non-finite `vertical` or a non-finite origin.
    pub fn new(origin: [f64; 3], vertical: [f64; 3]) -> Option<Self> {
        let length = vec3::norm(vertical);
        if !length.is_finite() || length <= 0.0 || !origin.iter().all(|c| c.is_finite()) {
            return None;
        }
        let k = vec3::scale(vertical, 1.0 / length);
        // The coordinate axis least aligned with k, made normal to it.
        let axis = (0..3)
            .min_by(|&i, &j| k[i].abs().total_cmp(&k[j].abs()))
            .unwrap_or(0);
        let mut a = [0.0; 3];
        a[axis] = 1.0;
        let a = vec3::sub(a, vec3::scale(k, vec3::dot(a, k)));
        let e1 = vec3::scale(a, 1.0 / vec3::norm(a));
        let e2 = vec3::cross(k, e1);
        Some(Self {
            origin,
            vertical: k,
            e1,
            e2,
        })
    }

    /// The unit vertical `k`.
    pub fn vertical(&self) -> [f64; 3] {
        self.vertical
    }

    /// The origin `c`.
    pub fn origin(&self) -> [f64; 3] {
        self.origin
    }

    /// The plane's first axis `e1`.
    pub fn e1(&self) -> [f64; 3] {
        self.e1
    }

    /// The plane's second axis `e2 = k × e1`.
    pub fn e2(&self) -> [f64; 3] {
        self.e2
    }

    /// Plane coordinates `(e1 · (x − c), e2 · (x − c))` of `x`.
    pub fn project(&self, x: [f64; 3]) -> [f64; 2] {
        let d = vec3::sub(x, self.origin);
        [vec3::dot(self.e1, d), vec3::dot(self.e2, d)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horizontal_frame_is_orthonormal_and_right_handed() {
        for v in [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -3.0],
            [0.0, 2.0, 0.0],
            [1.0, -2.0, 0.5],
        ] {
            let h = Horizontal::new([0.1, 0.2, 0.3], v).unwrap();
            let k = h.vertical();
            assert!((vec3::norm(h.e1()) - 1.0).abs() < 1e-15);
            assert!((vec3::norm(h.e2()) - 1.0).abs() < 1e-15);
            assert!(vec3::dot(h.e1(), k).abs() < 1e-15);
            assert!(vec3::dot(h.e1(), h.e2()).abs() < 1e-15);
            let c = vec3::cross(h.e1(), h.e2());
            assert!(vec3::norm(vec3::sub(c, k)) < 1e-15);
            // A point on the axis projects to the origin.
            let on_axis = vec3::add(h.origin(), vec3::scale(k, 0.7));
            let p = h.project(on_axis);
            assert!(p[0].abs() < 1e-15 && p[1].abs() < 1e-15);
        }
        let z = Horizontal::new([0.0; 3], [0.0, 0.0, 1.0]).unwrap();
        assert_eq!(z.project([0.3, -0.2, 5.0]), [0.3, -0.2]);
        assert!(Horizontal::new([0.0; 3], [0.0; 3]).is_none());
        assert!(Horizontal::new([0.0; 3], [f64::NAN, 0.0, 1.0]).is_none());
    }
}
