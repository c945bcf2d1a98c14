//! A specimen of a drape test (README, "The drape test"; docs/theory.md,
//! "The drape test's specimens"): how it differs from the other specimens
//! cut from the same fabric, as real specimens differ.
//!
//! Three differences, each seeded or chosen by the test and written into
//! the specimen's scenario (`[specimen]`), so that the specimen's run
//! directory reproduces it alone:
//!
//! - **waviness**: the specimen does not lie perfectly flat; its reference
//!   (stress-free) shape is offset along its plane's normal by a smooth
//!   random field of a few low Fourier modes ([`waviness`]) whose largest
//!   offset is the amplitude `A`. Where the specimen is held flat — its
//!   nodes within `A` of an obstacle, the drape tester's grip — the field
//!   is zero, and it rises to its full value over the taper length
//!   `ℓ = L / (2K)` (half the shortest wavelength) by a smoothstep of the
//!   in-plane distance `d` from the nearest held node,
//!   `s = 3 (d/ℓ)² − 2 (d/ℓ)³` (1 beyond `ℓ`): the specimen is pressed
//!   flat in the grip, as in the instrument, and no node starts inside an
//!   obstacle;
//! - **the cut's angle to the warp**: the warp direction is turned by `θ`
//!   about the plane's normal (counter-clockwise seen from it);
//! - **the face**: a specimen face down is the face-up one turned over
//!   about the plane's first axis `e1`, `(ξ, η, ζ) → (ξ, −η, −ζ)`: its
//!   waviness becomes `−w(ξ, −η)` and its (cut) warp direction is
//!   mirrored, `θ → −θ` about `e1`.
//!
//! The plane is the mesh's: its normal is the sum of the triangles'
//! area vectors (the corner nodes'), its origin the nodes' centroid, its
//! axes those of [`crate::measure::Horizontal`] (`e1 = x`, `e2 = y` for
//! a mesh in a plane `z = c` seen from +z). A perturbation that changes
//! nothing (`A = 0`, `θ = 0`, face up) is not applied at all: the run is
//! the plain scenario's, bit for bit.

pub mod random;
pub mod waviness;

use crate::horizontal::Horizontal;
use crate::mesh::Mesh;
use crate::vec3;
use waviness::Waviness;

/// Which face of the fabric is up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Face {
    /// As the mesh lies.
    #[default]
    Up,
    /// Turned over about the plane's first axis.
    Down,
}

impl Face {
    /// The value as a scenario spells it.
    pub fn name(self) -> &'static str {
        match self {
            Face::Up => "up",
            Face::Down => "down",
        }
    }
}

/// One specimen's perturbation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Perturbation {
    /// The waviness field's seed.
    pub seed: u64,
    /// The waviness' amplitude `A` (m): the largest offset of a node.
    pub waviness: f64,
    /// The waviness' largest wave number `K`.
    pub modes: usize,
    /// The cut's angle to the warp `θ` (degrees).
    pub cut_angle: f64,
    /// Which face is up.
    pub face: Face,
}

impl Perturbation {
    /// Whether it changes nothing.
    pub fn is_identity(&self) -> bool {
        self.waviness == 0.0 && self.cut_angle == 0.0 && self.face == Face::Up
    }
}

/// Why a mesh cannot take a perturbation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpecimenError {
    /// The triangles' area vectors sum to nothing (a closed surface, or
    /// none): there is no plane to be wavy across.
    #[error(
        "the mesh has no plane (its triangles' area vectors sum to {0:e} m²): a drape test's specimen is a flat sheet"
    )]
    NoPlane(f64),
}

/// The specimen's plane (see the module's documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpecimenPlane {
    /// Origin, normal and axes.
    pub plane: Horizontal,
    /// `L`: the largest distance of a node from the origin in the plane (m).
    pub half_size: f64,
}

impl SpecimenPlane {
    /// The plane of `mesh`.
    ///
    /// # Errors
    /// [`SpecimenError::NoPlane`] where the area vectors cancel (to 1e-9 of
    /// their magnitudes' sum) or the mesh has no nodes.
    pub fn of(mesh: &Mesh) -> Result<Self, SpecimenError> {
        let n = mesh.order.nodes_per_element();
        let (mut sum, mut total) = ([0.0; 3], 0.0);
        for el in mesh.connectivity.chunks_exact(n) {
            let [a, b, c] = [el[0], el[1], el[2]].map(|i| mesh.nodes[i]);
            let area = vec3::cross(vec3::sub(b, a), vec3::sub(c, a));
            sum = vec3::add(sum, area);
            total += vec3::norm(area);
        }
        let count = mesh.nodes.len() as f64;
        let origin = mesh.nodes.iter().fold([0.0; 3], |s, &x| vec3::add(s, x));
        let origin = vec3::scale(origin, 1.0 / count);
        let plane = Horizontal::new(origin, sum)
            .filter(|_| vec3::norm(sum) > 1e-9 * total)
            .ok_or(SpecimenError::NoPlane(0.5 * vec3::norm(sum)))?;
        let half_size = mesh
            .nodes
            .iter()
            .map(|&x| {
                let [xi, eta] = plane.project(x);
                xi.hypot(eta)
            })
            .fold(0.0, f64::max);
        Ok(Self { plane, half_size })
    }

    /// The waviness' offset of every node of `mesh` along the normal (m):
    /// `A s f / max |s f|`, face down `f(ξ, η)` replaced by `−f(ξ, −η)`;
    /// `s` the taper from the nodes `held` flat (see the module's
    /// documentation; all 1 where none is held).
    pub fn offsets(&self, mesh: &Mesh, p: &Perturbation, held: &[bool]) -> Vec<f64> {
        if p.waviness == 0.0 || self.half_size <= 0.0 {
            return vec![0.0; mesh.nodes.len()];
        }
        let field = Waviness::new(p.seed, p.modes, self.half_size);
        let sign = match p.face {
            Face::Up => 1.0,
            Face::Down => -1.0,
        };
        let taper = self.taper(mesh, held, self.half_size / (2.0 * p.modes as f64));
        let raw: Vec<f64> = (mesh.nodes.iter().zip(taper))
            .map(|(&x, s)| {
                let [xi, eta] = self.plane.project(x);
                s * sign * field.value([xi, sign * eta])
            })
            .collect();
        let largest = raw.iter().fold(0.0f64, |m, f| m.max(f.abs()));
        if largest == 0.0 {
            return raw;
        }
        raw.iter().map(|f| p.waviness * f / largest).collect()
    }

    /// The smoothstep `s(d / ℓ)` of every node's in-plane distance `d`
    /// from the nearest held node (0 at a held node, 1 with none held);
    /// the distance is taken to the held nodes that share an element with
    /// a free one, which are the nearest held nodes of every free node
    /// outside the held region.
    fn taper(&self, mesh: &Mesh, held: &[bool], length: f64) -> Vec<f64> {
        let n = mesh.order.nodes_per_element();
        let mut edge = vec![false; mesh.nodes.len()];
        for el in mesh.connectivity.chunks_exact(n) {
            if el.iter().any(|&a| held[a]) && el.iter().any(|&a| !held[a]) {
                for &a in el.iter().filter(|&&a| held[a]) {
                    edge[a] = true;
                }
            }
        }
        let rim: Vec<[f64; 2]> = (mesh.nodes.iter().zip(&edge))
            .filter(|(_, e)| **e)
            .map(|(&x, _)| self.plane.project(x))
            .collect();
        (mesh.nodes.iter().zip(held))
            .map(|(&x, &h)| {
                if h {
                    return 0.0;
                }
                let [xi, eta] = self.plane.project(x);
                let d = (rim.iter())
                    .map(|r| (r[0] - xi).hypot(r[1] - eta))
                    .fold(f64::INFINITY, f64::min);
                let u = (d / length).min(1.0);
                u * u * (3.0 - 2.0 * u)
            })
            .collect()
    }

    /// `d` cut at `θ` (turned about the normal) and, face down, turned over
    /// about `e1` (its `e2` and normal components negated).
    pub fn turn(&self, d: [f64; 3], p: &Perturbation) -> [f64; 3] {
        let k = self.plane.vertical();
        let (s, c) = p.cut_angle.to_radians().sin_cos();
        // Rodrigues: d cos θ + (k × d) sin θ + k (k · d)(1 − cos θ).
        let turned = vec3::add(
            vec3::add(vec3::scale(d, c), vec3::scale(vec3::cross(k, d), s)),
            vec3::scale(k, vec3::dot(k, d) * (1.0 - c)),
        );
        match p.face {
            Face::Up => turned,
            Face::Down => {
                let e2 = self.plane.e2();
                let t = vec3::sub(turned, vec3::scale(e2, 2.0 * vec3::dot(e2, turned)));
                vec3::sub(t, vec3::scale(k, 2.0 * vec3::dot(k, t)))
            }
        }
    }
}

/// `mesh` with the waviness of `p` in its initial positions, zero at the
/// nodes `held` flat and tapered from them.
pub fn perturb_mesh(mesh: &mut Mesh, plane: &SpecimenPlane, p: &Perturbation, held: &[bool]) {
    if p.waviness != 0.0 {
        let k = plane.plane.vertical();
        let offsets = plane.offsets(mesh, p, held);
        for (x, w) in mesh.nodes.iter_mut().zip(offsets) {
            *x = vec3::add(*x, vec3::scale(k, w));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    fn disc() -> Mesh {
        generate::disc(0.15, 6, [0.0, 0.0, 0.0], crate::mesh::ElementOrder::Linear)
    }

    fn perturbation(face: Face) -> Perturbation {
        Perturbation {
            seed: 3,
            waviness: 1e-3,
            modes: 3,
            cut_angle: 10.0,
            face,
        }
    }

    /// The largest offset is the amplitude; the nodes move along z only.
    #[test]
    fn amplitude_is_the_largest_offset() {
        let flat = disc();
        let mut wavy = flat.clone();
        let plane = SpecimenPlane::of(&flat).unwrap();
        perturb_mesh(
            &mut wavy,
            &plane,
            &perturbation(Face::Up),
            &vec![false; flat.nodes.len()],
        );
        let mut largest: f64 = 0.0;
        for (a, b) in flat.nodes.iter().zip(&wavy.nodes) {
            assert_eq!((a[0], a[1]), (b[0], b[1]));
            largest = largest.max((b[2] - a[2]).abs());
        }
        assert!((largest - 1e-3).abs() <= 1e-18, "{largest}");
    }

    /// Face down is face up turned over about x: w_down(x, y) = −w_up(x, −y).
    /// The disc's nodes are symmetric about y = 0 (ring k's nodes at
    /// angles 2πj/6k), so each node's mirror is a node.
    #[test]
    fn face_down_is_face_up_turned_over() {
        let mesh = disc();
        let plane = SpecimenPlane::of(&mesh).unwrap();
        let free = vec![false; mesh.nodes.len()];
        let up = plane.offsets(&mesh, &perturbation(Face::Up), &free);
        let down = plane.offsets(&mesh, &perturbation(Face::Down), &free);
        for (i, x) in mesh.nodes.iter().enumerate() {
            let j = (mesh.nodes.iter())
                .position(|y| (y[0] - x[0]).abs() < 1e-12 && (y[1] + x[1]).abs() < 1e-12)
                .unwrap();
            // The two fields are scaled by the same max |f| (the node set
            // is mirror symmetric), so they agree to round-off.
            assert!((down[i] + up[j]).abs() < 1e-15, "node {i}");
        }
    }

    /// Held nodes stay where they are; the others are `A s f / max |s f|`
    /// with the smoothstep `s` of their distance from the held disc's rim
    /// (K = 1: ℓ = L / 2 = 0.075 m; the 6-ring disc's rings lie 0.025 m
    /// apart, the held ones at 0.025 and 0.05 m).
    #[test]
    fn held_nodes_stay_flat() {
        let mesh = disc();
        let plane = SpecimenPlane::of(&mesh).unwrap();
        let held: Vec<bool> = mesh.nodes.iter().map(|x| x[0].hypot(x[1]) < 0.06).collect();
        let p = Perturbation {
            modes: 1,
            ..perturbation(Face::Up)
        };
        let w = plane.offsets(&mesh, &p, &held);
        let f = Waviness::new(p.seed, 1, 0.15);
        let step = |d: f64| {
            let u = (d / 0.075).min(1.0);
            u * u * (3.0 - 2.0 * u)
        };
        let sf: Vec<f64> = (mesh.nodes.iter().zip(&held))
            .map(|(x, &h)| {
                let r = x[0].hypot(x[1]);
                // The nearest held node of a node on ring r lies on the
                // rim ring 0.05 at the node's own angle (6k nodes a ring:
                // ring 2's angles are among ring k's for even k, and the
                // distance is r − 0.05 to round-off for those).
                if h {
                    0.0
                } else {
                    step(r - 0.05) * f.value([x[0], x[1]])
                }
            })
            .collect();
        let largest = sf.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (i, x) in mesh.nodes.iter().enumerate() {
            let on_rim_angle = {
                let a = x[1].atan2(x[0]).rem_euclid(std::f64::consts::TAU);
                let k = a / (std::f64::consts::TAU / 12.0);
                (k - k.round()).abs() < 1e-9
            };
            if held[i] {
                assert_eq!(w[i], 0.0);
            } else if on_rim_angle {
                let expected = p.waviness * sf[i] / largest;
                assert!((w[i] - expected).abs() < 1e-9 * p.waviness, "node {i}");
            }
        }
    }

    /// The warp cut at θ lies at θ from x; face down at −θ.
    #[test]
    fn cut_and_turned_over() {
        let mesh = disc();
        let plane = SpecimenPlane::of(&mesh).unwrap();
        let d = [1.0, 0.0, 0.0];
        let up = plane.turn(d, &perturbation(Face::Up));
        let down = plane.turn(d, &perturbation(Face::Down));
        let theta = 10f64.to_radians();
        assert!((up[0] - theta.cos()).abs() < 1e-15 && (up[1] - theta.sin()).abs() < 1e-15);
        assert!((down[0] - theta.cos()).abs() < 1e-15 && (down[1] + theta.sin()).abs() < 1e-15);
        assert!(up[2].abs() < 1e-15 && down[2].abs() < 1e-15);
    }

    /// A closed surface has no plane.
    #[test]
    fn no_plane_is_an_error() {
        // Two copies of one triangle, opposite orientations.
        let mesh = Mesh {
            nodes: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            order: crate::mesh::ElementOrder::Linear,
            connectivity: vec![0, 1, 2, 0, 2, 1],
        };
        assert!(matches!(
            SpecimenPlane::of(&mesh),
            Err(SpecimenError::NoPlane(_))
        ));
    }
}
