//! The drape tester of a measurement: which way is up, where the pedestal
//! stands and how large it and the specimen are — found from the
//! scenario, or given.
//!
//! - **Vertical**: opposite the scenario's weight, the resultant of its
//!   `surface` and `gravity` loads per unit area at full ramp,
//!   `k = −w / |w|` with `w = Σ q_i + Σ ρ t g_j` (a surface load's force
//!   per area `q_i`, a gravity load's acceleration `g_j` times the mass
//!   per area `ρ t`): a negligible load tilts it negligibly. `+z` without
//!   such loads (or without a scenario). Loads that weigh nothing, or whose
//!   resultant is at most [`CANCEL_TOLERANCE`] of the sum of their sizes
//!   (they cancel, and the direction left is their rounding's), leave no
//!   vertical: an error.
//! - **Pedestal**: an `[[obstacle]]` of shape `cylinder` whose axis is
//!   vertical (within [`VERTICAL_TOLERANCE_DEGREES`]) and passes under the
//!   specimen (within the initial rim's reach of its centre), moved by its
//!   velocity to the frame's time; of several, the one whose top face is
//!   highest — the one the specimen comes to rest on (a wider base
//!   cylinder below the pedestal is not it, whatever its place in the
//!   list). Its top face is the higher of its two faces along the
//!   vertical, whichever way its axis points: `center` for an axis up,
//!   `center − height · axis` for an axis down (the scenario's `center` is
//!   the face the axis points out of). A cylinder whose top face is above
//!   the specimen's initial plane (beyond [`ABOVE_TOLERANCE`] of the rim's
//!   reach) is not under it: the top disc that grips the specimen on the
//!   pedestal, as in the instrument. Two under the specimen with their
//!   tops at one height and different radii are ambiguous: an error that
//!   asks for the radius. Its radius is `r_p`, the centre of its top face
//!   the centre of the measurement.
//! - **Specimen**: the `radius` of a `[mesh] shape = "disc"` (which must
//!   then lie in a horizontal plane); for `shape = "file"` the initial
//!   mesh's rim, whose nodes must all lie within [`RIM_TOLERANCE`] of one
//!   radius `R` about their centroid; `R` is the largest.
//!
//! Either radius can be given instead ([`Given`]); what cannot be found
//! nor was given is an error that says why.

use super::{Horizontal, MeasureError};
use crate::human::{human, human_point};
use crate::mesh::Mesh;
use crate::scenario::{LoadKindSpec, MeshShape, ObstacleSpec, Scenario};
use crate::vec3;

/// Largest angle (degrees) between a cylinder's axis and the vertical for
/// it to stand as a pedestal.
pub const VERTICAL_TOLERANCE_DEGREES: f64 = 1.0;

/// Largest spread of the initial rim's radii, as a fraction of the
/// largest, for a file mesh to be a disc: 2 % (the mid-edge nodes of a T6
/// on the chords of a 60-gon lie 0.14 % inside the circle).
pub const RIM_TOLERANCE: f64 = 0.02;

/// Largest resultant of the scenario's weights, as a fraction of the sum
/// of their sizes, that counts as none: 1e-6. Below it the loads cancel
/// to about the digits a scenario gives them with, and what is left
/// points wherever those last digits do (a weight of 1.8816 N/m² lifted
/// by 1.8816 N/m² beside a sideways 1e-6 N/m² leaves 2.7e-7 of 3.76 N/m²,
/// all of it sideways).
pub const CANCEL_TOLERANCE: f64 = 1e-6;

/// Tops of two cylinders closer than this fraction of the specimen's
/// reach are at one height.
const TOP_TIE: f64 = 1e-9;

/// A cylinder whose top face is above the specimen's initial plane (its
/// highest initial node) by
/// more than this fraction of the specimen's reach is above it, not under
/// it (a top disc): 1e-3, 0.15 mm for a 30 cm specimen — a top disc
/// pressing into the fabric by a few micrometres still counts as above,
/// a pedestal the fabric starts on as under.
pub const ABOVE_TOLERANCE: f64 = 1e-3;

/// Radii given instead of found (m).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Given {
    /// The pedestal's radius `r_p`.
    pub pedestal_radius: Option<f64>,
    /// The specimen's radius `R`.
    pub specimen_radius: Option<f64>,
}

/// The geometry of a drape tester.
#[derive(Debug, Clone, PartialEq)]
pub struct DrapeTester {
    /// The horizontal plane, about a point on the pedestal's axis.
    pub plane: Horizontal,
    /// Pedestal radius `r_p` (m).
    pub pedestal_radius: f64,
    /// Specimen radius `R` (m).
    pub specimen_radius: f64,
    /// Where `r_p` came from: `"given"` or the obstacle, e.g. `"obstacle[1]"`.
    pub pedestal_source: String,
    /// Where `R` came from: `"given"`, `"mesh.radius"` or `"initial rim"`.
    pub specimen_source: String,
}

impl DrapeTester {
    /// A tester about `center` with the vertical `vertical` (any length)
    /// and the radii `r_p < R`, given.
    ///
    /// # Errors
    /// [`MeasureError::Vertical`] for a zero or non-finite vertical (or a
    /// non-finite centre), [`MeasureError::Radius`] for a radius that is
    /// not positive and finite, [`MeasureError::PedestalNotSmaller`].
    pub fn new(
        center: [f64; 3],
        vertical: [f64; 3],
        pedestal_radius: f64,
        specimen_radius: f64,
    ) -> Result<Self, MeasureError> {
        let plane = Horizontal::new(center, vertical).ok_or(MeasureError::Vertical { vertical })?;
        for (which, value) in [
            ("pedestal radius", pedestal_radius),
            ("specimen radius", specimen_radius),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(MeasureError::Radius { which, value });
            }
        }
        if pedestal_radius >= specimen_radius {
            return Err(MeasureError::PedestalNotSmaller {
                pedestal: pedestal_radius,
                specimen: specimen_radius,
            });
        }
        Ok(Self {
            plane,
            pedestal_radius,
            specimen_radius,
            pedestal_source: "given".into(),
            specimen_source: "given".into(),
        })
    }

    /// The tester of a run of `scenario` (if there is one) whose initial
    /// mesh is `initial`, at time `time` (s, for a moving pedestal), with
    /// the radii of `given` taking the place of those found (module
    /// documentation).
    ///
    /// # Errors
    /// [`MeasureError::NoVertical`] for a scenario whose loads weigh
    /// nothing ([`vertical_of`]); [`MeasureError::NoPedestal`],
    /// [`MeasureError::AmbiguousPedestal`] and [`MeasureError::NotADisc`]
    /// saying why a radius that was not given cannot be found; those of
    /// [`DrapeTester::new`].
    pub fn find(
        scenario: Option<&Scenario>,
        initial: &Mesh,
        time: f64,
        given: Given,
    ) -> Result<Self, MeasureError> {
        let vertical = match scenario {
            Some(s) => vertical_of(s)?,
            None => [0.0, 0.0, 1.0],
        };
        let up = Horizontal::new([0.0; 3], vertical).ok_or(MeasureError::Vertical { vertical })?;
        let rim: Vec<[f64; 3]> = initial
            .boundary_nodes()
            .into_iter()
            .map(|a| initial.nodes[a])
            .collect();
        let rim_center = mean(if rim.is_empty() { &initial.nodes } else { &rim });
        let reach = rim
            .iter()
            .map(|&x| horizontal_distance(&up, x, rim_center))
            .fold(0.0, f64::max);
        // The specimen's highest initial point: a cylinder whose top is
        // above it is above the specimen (a flat specimen's plane; a
        // drape test's wavy specimen at its highest wave).
        let highest = (initial.nodes.iter())
            .map(|&x| vec3::dot(x, up.vertical()))
            .fold(f64::NEG_INFINITY, f64::max);
        let pedestal = match scenario {
            Some(s) => find_pedestal(s, &up, (rim_center, highest), reach, time),
            None => Err(MeasureError::NoPedestal {
                reason: "no scenario to find it in".to_owned(),
            }),
        };
        let (pedestal_radius, pedestal_source) = match (given.pedestal_radius, &pedestal) {
            (Some(r), _) => (r, "given".to_owned()),
            (None, Ok(p)) => (p.radius, format!("obstacle[{}]", p.index)),
            (None, Err(e)) => return Err(e.clone()),
        };
        let axis = pedestal.as_ref().ok().map(|p| p.axis_point);
        let (specimen_radius, specimen_source, disc_center) = match given.specimen_radius {
            Some(r) => (r, "given".to_owned(), None),
            None => {
                let s = scenario.ok_or_else(|| MeasureError::NotADisc {
                    reason: "no scenario to find it in".into(),
                })?;
                specimen_of(s, &up, &rim, rim_center)?
            }
        };
        let center = axis.or(disc_center).unwrap_or(rim_center);
        let mut tester = Self::new(center, vertical, pedestal_radius, specimen_radius)?;
        tester.pedestal_source = pedestal_source;
        tester.specimen_source = specimen_source;
        Ok(tester)
    }
}

/// The scenario's vertical, opposite its weight per unit area at full
/// ramp: `k = −w / |w|`, `w = Σ q_i + Σ ρ t g_j` over its `surface` loads
/// (force per area `q_i`, N/m²) and `gravity` loads (acceleration `g_j`,
/// m/s², times the mass per area `ρ t`, kg/m²); `+z` if it has no such
/// load.
///
/// # Errors
/// [`MeasureError::NoVertical`] where `w` is not finite, or
/// `|w| <= CANCEL_TOLERANCE · Σ |w_i|` (the loads weigh nothing or cancel).
pub fn vertical_of(scenario: &Scenario) -> Result<[f64; 3], MeasureError> {
    let mass_per_area = scenario.material.density() * scenario.material.thickness();
    let weights: Vec<[f64; 3]> = scenario
        .loads
        .iter()
        .filter_map(|load| match load.kind {
            LoadKindSpec::Surface => load.force,
            LoadKindSpec::Gravity => load
                .force
                .or(load.acceleration)
                .map(|g| vec3::scale(g, mass_per_area)),
            LoadKindSpec::Pressure | LoadKindSpec::Nodal => None,
        })
        .collect();
    if weights.is_empty() {
        return Ok([0.0, 0.0, 1.0]);
    }
    let w = weights.iter().fold([0.0; 3], |s, &w| vec3::add(s, w));
    let sizes: f64 = weights.iter().map(|&w| vec3::norm(w)).sum();
    let length = vec3::norm(w);
    let no_vertical = |reason: String| MeasureError::NoVertical { reason };
    if !(length.is_finite() && sizes.is_finite()) {
        return Err(no_vertical(format!(
            "the scenario's surface and gravity loads add up to {} N/m², not a finite weight",
            human_point(w)
        )));
    }
    if sizes == 0.0 {
        return Err(no_vertical(format!(
            "the scenario's surface and gravity loads weigh nothing (a gravity load weighs its acceleration times the mass per area ρ t, here {} kg/m²)",
            human(mass_per_area)
        )));
    }
    if length <= CANCEL_TOLERANCE * sizes {
        let part = if length == 0.0 {
            String::new()
        } else {
            format!(
                ", {:.1e} of the sum of their sizes {} N/m² ({CANCEL_TOLERANCE:e} or less counts as none)",
                length / sizes,
                human(sizes)
            )
        };
        return Err(no_vertical(format!(
            "the scenario's surface and gravity loads cancel: they add up to {} N/m²{part}",
            human_point(w)
        )));
    }
    // (+ 0.0: no negative zeros in the report.)
    Ok(w.map(|c| -c / length + 0.0))
}

/// The pedestal found in a scenario.
struct Pedestal {
    /// Its index among the `[[obstacle]]` tables.
    index: usize,
    /// The centre of its top face at the frame's time (m).
    axis_point: [f64; 3],
    /// Its radius (m).
    radius: f64,
}

/// The vertical cylinder under the specimen (its axis within `reach` of
/// `rim_center`, its top no more than [`ABOVE_TOLERANCE`] `reach` above
/// the specimen's `highest` initial point) whose top face is highest along the vertical (the
/// nearest axis of equal tops and radii); or why there is none ([`MeasureError::NoPedestal`]), or why
/// the choice is ambiguous ([`MeasureError::AmbiguousPedestal`]).
fn find_pedestal(
    scenario: &Scenario,
    up: &Horizontal,
    (rim_center, highest): ([f64; 3], f64),
    reach: f64,
    time: f64,
) -> Result<Pedestal, MeasureError> {
    let cos_tolerance = VERTICAL_TOLERANCE_DEGREES.to_radians().cos();
    let mut cylinders = 0;
    let mut vertical = 0;
    let mut best: Option<(f64, f64, Pedestal)> = None;
    for (index, obstacle) in scenario.obstacles.iter().enumerate() {
        let ObstacleSpec::Cylinder(c) = obstacle else {
            continue;
        };
        cylinders += 1;
        let length = vec3::norm(c.axis);
        if length.is_nan()
            || length <= 0.0
            || vec3::dot(c.axis, up.vertical()).abs() < cos_tolerance * length
        {
            continue;
        }
        vertical += 1;
        let moved = vec3::add(c.center, vec3::scale(c.velocity.unwrap_or([0.0; 3]), time));
        let distance = horizontal_distance(up, moved, rim_center);
        if distance > reach {
            continue;
        }
        // `center` is the face the axis points out of, the other face
        // `height` back along the axis: the top face is the higher of the
        // two along the vertical, the other one for an axis pointing down.
        let other = vec3::sub(moved, vec3::scale(c.axis, c.height / length));
        let top_face = if vec3::dot(other, up.vertical()) > vec3::dot(moved, up.vertical()) {
            other
        } else {
            moved
        };
        let top = vec3::dot(top_face, up.vertical());
        if top > highest + ABOVE_TOLERANCE * reach {
            // Above the specimen: a top disc.
            continue;
        }
        let pedestal = Pedestal {
            index,
            axis_point: top_face,
            radius: c.radius,
        };
        best = match best {
            None => Some((top, distance, pedestal)),
            Some((t, d, p)) => {
                if (top - t).abs() <= TOP_TIE * reach.max(f64::MIN_POSITIVE) {
                    if pedestal.radius != p.radius {
                        return Err(MeasureError::AmbiguousPedestal {
                            obstacles: [p.index, index],
                            radii: [p.radius, pedestal.radius],
                        });
                    }
                    if distance < d {
                        Some((top, distance, pedestal))
                    } else {
                        Some((t, d, p))
                    }
                } else if top > t {
                    Some((top, distance, pedestal))
                } else {
                    Some((t, d, p))
                }
            }
        };
    }
    let k = up.vertical();
    let reason = match best {
        Some((_, _, p)) => return Ok(p),
        None if cylinders == 0 => "the scenario has no [[obstacle]] of shape \"cylinder\"".into(),
        None if vertical == 0 => format!(
            "no cylinder obstacle has its axis along the vertical {} (within {VERTICAL_TOLERANCE_DEGREES} degree)",
            human_point(k)
        ),
        None => format!(
            "no vertical cylinder obstacle stands under the specimen (its axis within {} m of the initial rim's centre {})",
            human(reach),
            human_point(rim_center)
        ),
    };
    Err(MeasureError::NoPedestal { reason })
}

/// The specimen's radius from the scenario's mesh, its source and the
/// centre of a generated disc; `rim` are the initial mesh's boundary nodes
/// and `center` their centroid (the specimen's radius is its own, wherever
/// it lies on the pedestal).
fn specimen_of(
    scenario: &Scenario,
    up: &Horizontal,
    rim: &[[f64; 3]],
    center: [f64; 3],
) -> Result<(f64, String, Option<[f64; 3]>), MeasureError> {
    let not_a_disc = |reason: String| MeasureError::NotADisc { reason };
    match scenario.mesh.shape {
        MeshShape::Disc => {
            let radius = scenario
                .mesh
                .radius
                .ok_or_else(|| not_a_disc("the [mesh] disc has no radius".into()))?;
            let cos_tolerance = VERTICAL_TOLERANCE_DEGREES.to_radians().cos();
            let k = up.vertical();
            if k[2].abs() < cos_tolerance {
                return Err(not_a_disc(format!(
                    "the [mesh] disc lies in a plane z = constant, which is not horizontal for the vertical {}",
                    human_point(k)
                )));
            }
            let disc_center = scenario.mesh.center.unwrap_or([0.0; 3]);
            Ok((radius, "mesh.radius".into(), Some(disc_center)))
        }
        MeshShape::File => {
            if rim.is_empty() {
                return Err(not_a_disc("the initial mesh has no free edge".into()));
            }
            let radii: Vec<f64> = rim
                .iter()
                .map(|&x| horizontal_distance(up, x, center))
                .collect();
            let largest = radii.iter().copied().fold(0.0, f64::max);
            let smallest = radii.iter().copied().fold(f64::INFINITY, f64::min);
            if largest.is_nan() || largest <= 0.0 || largest - smallest > RIM_TOLERANCE * largest {
                return Err(not_a_disc(format!(
                    "the initial mesh's rim is not a circle: its nodes lie {} m to {} m from their centroid {}",
                    human(smallest),
                    human(largest),
                    human_point(center)
                )));
            }
            Ok((largest, "initial rim".into(), None))
        }
        MeshShape::Rectangle => Err(not_a_disc("the [mesh] is a rectangle, not a disc".into())),
        MeshShape::Sphere => Err(not_a_disc("the [mesh] is a sphere, not a disc".into())),
    }
}

/// The distance between `a` and `b` in the horizontal plane.
fn horizontal_distance(up: &Horizontal, a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = vec3::sub(a, b);
    let k = up.vertical();
    vec3::norm(vec3::sub(d, vec3::scale(k, vec3::dot(d, k))))
}

/// The mean of the points (the origin for none).
fn mean(points: &[[f64; 3]]) -> [f64; 3] {
    if points.is_empty() {
        return [0.0; 3];
    }
    let sum = points.iter().fold([0.0; 3], |s, &x| vec3::add(s, x));
    vec3::scale(sum, 1.0 / points.len() as f64)
}
