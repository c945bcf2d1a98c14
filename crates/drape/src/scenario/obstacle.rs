//! `[[obstacle]]`: a rigid body, whose keys are chosen by its `shape`
//! (each shape's own struct, read by [`super::tagged`]), and its
//! construction.

use super::ScenarioError;
use super::check::Checker;
use crate::contact::obstacle::{
    BoxObstacle, CylinderObstacle, PlaneObstacle, Rounded, SphereObstacle,
    read_mesh_obstacle_with_bytes,
};
use crate::contact::{Obstacle, ObstacleError, RigidBody};
use crate::input::InputFile;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::de::ValueDeserializer;

/// The values of `[[obstacle]] shape`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ObstacleShape {
    /// A half-space.
    Plane,
    /// An axis-aligned box.
    Box,
    /// A sphere.
    Sphere,
    /// A closed cylinder.
    Cylinder,
    /// A closed triangle mesh read from a file.
    Mesh,
}

/// `[[obstacle]]`: one rigid body, with the keys of its `shape` (a key of
/// another shape is an unknown key).
#[derive(Debug, Clone, PartialEq)]
pub enum ObstacleSpec {
    /// `shape = "plane"`.
    Plane(PlaneObstacleSpec),
    /// `shape = "box"`.
    Box(BoxObstacleSpec),
    /// `shape = "sphere"`.
    Sphere(SphereObstacleSpec),
    /// `shape = "cylinder"`.
    Cylinder(CylinderObstacleSpec),
    /// `shape = "mesh"`.
    Mesh(MeshObstacleSpec),
}

/// `shape = "plane"`: the half-space behind a plane.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneObstacleSpec {
    /// A point on the plane (m), finite. Required.
    pub point: [f64; 3],
    /// Outward normal, any length but not zero. Required.
    pub normal: [f64; 3],
    /// Rigid velocity (m/s), finite. Default 0.
    pub velocity: Option<[f64; 3]>,
    /// This obstacle's Coulomb friction coefficient, >= 0 and finite, in
    /// place of `[contact] friction`. Default: that one.
    pub friction: Option<f64>,
}

/// `shape = "box"`: an axis-aligned box.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxObstacleSpec {
    /// Lower corner (m), finite. Required.
    pub min: [f64; 3],
    /// Upper corner (m), above `min` in every direction. Required.
    pub max: [f64; 3],
    /// Radius (m) to which the edges are rounded, keeping the faces in
    /// place; 0 for sharp edges; in [0, half the shortest side). Default:
    /// 1e-3 of the shortest side.
    pub edge_radius: Option<f64>,
    /// Rigid velocity (m/s), finite. Default 0.
    pub velocity: Option<[f64; 3]>,
    /// This obstacle's Coulomb friction coefficient, >= 0 and finite, in
    /// place of `[contact] friction`. Default: that one.
    pub friction: Option<f64>,
}

/// `shape = "sphere"`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereObstacleSpec {
    /// Centre (m), finite. Required.
    pub center: [f64; 3],
    /// Radius (m), > 0. Required.
    pub radius: f64,
    /// Rigid velocity (m/s), finite. Default 0.
    pub velocity: Option<[f64; 3]>,
    /// This obstacle's Coulomb friction coefficient, >= 0 and finite, in
    /// place of `[contact] friction`. Default: that one.
    pub friction: Option<f64>,
}

/// `shape = "cylinder"`: a closed cylinder.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CylinderObstacleSpec {
    /// Centre of the top face (m), finite. Required.
    pub center: [f64; 3],
    /// Direction from the bottom to the top face, any length but not zero.
    /// Required.
    pub axis: [f64; 3],
    /// Radius (m), > 0. Required.
    pub radius: f64,
    /// Height (m), > 0. Required.
    pub height: f64,
    /// Radius (m) to which the rims are rounded, keeping the faces in
    /// place; 0 for sharp rims; in [0, half the smaller of radius and
    /// height). Default: 1e-3 of the smaller of radius and height.
    pub edge_radius: Option<f64>,
    /// Rigid velocity (m/s), finite. Default 0.
    pub velocity: Option<[f64; 3]>,
    /// This obstacle's Coulomb friction coefficient, >= 0 and finite, in
    /// place of `[contact] friction`. Default: that one.
    pub friction: Option<f64>,
}

/// `shape = "mesh"`: a closed, consistently oriented triangle mesh.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshObstacleSpec {
    /// OBJ or STL (ASCII or binary) file, relative to the scenario's
    /// folder. Required.
    pub path: PathBuf,
    /// Rigid velocity (m/s), finite. Default 0.
    pub velocity: Option<[f64; 3]>,
    /// This obstacle's Coulomb friction coefficient, >= 0 and finite, in
    /// place of `[contact] friction`. Default: that one.
    pub friction: Option<f64>,
}

impl ObstacleSpec {
    /// The obstacle's `shape`.
    pub fn shape(&self) -> ObstacleShape {
        match self {
            Self::Plane(_) => ObstacleShape::Plane,
            Self::Box(_) => ObstacleShape::Box,
            Self::Sphere(_) => ObstacleShape::Sphere,
            Self::Cylinder(_) => ObstacleShape::Cylinder,
            Self::Mesh(_) => ObstacleShape::Mesh,
        }
    }

    /// The rigid velocity (m/s), if given.
    pub fn velocity(&self) -> Option<[f64; 3]> {
        match self {
            Self::Plane(o) => o.velocity,
            Self::Box(o) => o.velocity,
            Self::Sphere(o) => o.velocity,
            Self::Cylinder(o) => o.velocity,
            Self::Mesh(o) => o.velocity,
        }
    }

    /// The obstacle's own friction coefficient, if given.
    pub fn friction(&self) -> Option<f64> {
        match self {
            Self::Plane(o) => o.friction,
            Self::Box(o) => o.friction,
            Self::Sphere(o) => o.friction,
            Self::Cylinder(o) => o.friction,
            Self::Mesh(o) => o.friction,
        }
    }

    /// The keys of an obstacle table but `shape`, into the struct of `shape`.
    pub(super) fn read(
        shape: ObstacleShape,
        keys: ValueDeserializer<'_>,
    ) -> Result<Self, toml::de::Error> {
        Ok(match shape {
            ObstacleShape::Plane => Self::Plane(Deserialize::deserialize(keys)?),
            ObstacleShape::Box => Self::Box(Deserialize::deserialize(keys)?),
            ObstacleShape::Sphere => Self::Sphere(Deserialize::deserialize(keys)?),
            ObstacleShape::Cylinder => Self::Cylinder(Deserialize::deserialize(keys)?),
            ObstacleShape::Mesh => Self::Mesh(Deserialize::deserialize(keys)?),
        })
    }
}

/// The rigid body of `[[obstacle]]` number `i`; a mesh's path is relative
/// to `base`, and the file is recorded in `inputs`.
pub(super) fn build_body(
    c: &Checker,
    i: usize,
    spec: &ObstacleSpec,
    base: &Path,
    inputs: &mut Vec<InputFile>,
) -> Result<RigidBody, ScenarioError> {
    let (t, ix) = ("obstacle", Some(i));
    // The error's own key when it names one (a zero axis, a NaN centre),
    // else the key given here.
    let invalid =
        |key: &str, e: ObstacleError| c.invalid(t, ix, e.key().unwrap_or(key), e.to_string());
    let shape: Box<dyn Obstacle> = match spec {
        ObstacleSpec::Plane(o) => {
            Box::new(PlaneObstacle::new(o.point, o.normal).map_err(|e| invalid("normal", e))?)
        }
        ObstacleSpec::Box(o) => {
            let (lo, hi) = (o.min, o.max);
            let sharp = BoxObstacle::new(lo, hi).map_err(|e| invalid("max", e))?;
            let smallest = (0..3).map(|k| hi[k] - lo[k]).fold(f64::INFINITY, f64::min);
            let r = edge_radius(c, ix, o.edge_radius, smallest)?;
            if r > 0.0 {
                let inner = BoxObstacle::new(lo.map(|v| v + r), hi.map(|v| v - r))
                    .map_err(|e| invalid("edge_radius", e))?;
                Box::new(Rounded::new(inner, r))
            } else {
                Box::new(sharp)
            }
        }
        ObstacleSpec::Sphere(o) => {
            Box::new(SphereObstacle::new(o.center, o.radius).map_err(|e| invalid("radius", e))?)
        }
        ObstacleSpec::Cylinder(o) => {
            let (center, radius, height) = (o.center, o.radius, o.height);
            let sharp = CylinderObstacle::new(center, o.axis, radius, height)
                .map_err(|e| invalid("radius", e))?;
            let r = edge_radius(c, ix, o.edge_radius, radius.min(height))?;
            if r > 0.0 {
                let a = sharp.axis();
                let inner = CylinderObstacle::new(
                    [0, 1, 2].map(|k| center[k] - r * a[k]),
                    a,
                    radius - r,
                    height - 2.0 * r,
                )
                .map_err(|e| invalid("edge_radius", e))?;
                Box::new(Rounded::new(inner, r))
            } else {
                Box::new(sharp)
            }
        }
        ObstacleSpec::Mesh(o) => {
            let path = base.join(&o.path);
            let (mesh, bytes) =
                read_mesh_obstacle_with_bytes(&path).map_err(|e| invalid("path", e))?;
            inputs.push(InputFile::new(format!("obstacle[{i}].path"), &path, &bytes));
            Box::new(mesh)
        }
    };
    let velocity = spec.velocity().unwrap_or([0.0; 3]);
    c.finite(t, ix, "velocity", &velocity)?;
    Ok(RigidBody { shape, velocity })
}

/// The fillet radius of a box or cylinder whose smallest dimension is
/// `smallest`: the given one (>= 0, below half of it), or 1e-3 of it.
fn edge_radius(
    c: &Checker,
    ix: Option<usize>,
    given: Option<f64>,
    smallest: f64,
) -> Result<f64, ScenarioError> {
    match given {
        None => Ok(1e-3 * smallest),
        Some(r) if r.is_finite() && r >= 0.0 && r < 0.5 * smallest => Ok(r),
        Some(r) => Err(c.invalid(
            "obstacle",
            ix,
            "edge_radius",
            format!(
                "must lie in [0, {}) m (half the smallest dimension), not {r}",
                0.5 * smallest
            ),
        )),
    }
}
