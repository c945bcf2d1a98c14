//! `[contact]`: how contact with the obstacles is enforced, whose keys are
//! chosen by its `method` (each method's own struct, read by
//! [`super::tagged`]); the contact model built from it and the obstacles.

use super::check::Checker;
use super::obstacle::build_body;
use super::{Scenario, ScenarioError};
use crate::contact::self_contact::SelfContactSpec;
use crate::contact::{ContactMethod, ContactModel};
use crate::input::InputFile;
use crate::mesh::Mesh;
use serde::Deserialize;
use std::path::Path;
use toml::de::ValueDeserializer;

/// The values of `[contact] method`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ContactMethodName {
    /// A penalty potential on penetration.
    Penalty,
    /// Lagrange multipliers on an active set.
    Lagrange,
}

/// `[contact]`, with the keys of its `method` (a key of another method is
/// an unknown key).
#[derive(Debug, Clone, PartialEq)]
pub enum ContactSpec {
    /// `method = "penalty"`.
    Penalty(PenaltySpec),
    /// `method = "lagrange"`.
    Lagrange(LagrangeSpec),
}

/// `method = "penalty"`: the potential `1/2 eta g^2` for `g < 0`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PenaltySpec {
    /// Penalty stiffness `eta` (N/m per node), > 0. Required.
    pub penalty: f64,
    /// Coulomb's friction coefficient `mu` against every obstacle, >= 0
    /// and finite. Default 0 (frictionless).
    #[serde(default)]
    pub friction: f64,
    /// The slip speed (m/s, > 0) below which friction is a stiff viscous
    /// resistance: the creep of a fabric that sticks. Default 1e-3.
    #[serde(default = "default_stick_speed")]
    pub stick_speed: f64,
    /// Self-contact (SPEC §6.3): the fabric against itself, within and
    /// between its pieces. Default false.
    #[serde(default, rename = "self")]
    pub self_contact: bool,
    /// How close two pieces of fabric may come (m), > 0; default the
    /// thickness. Only with `self = true`.
    #[serde(default)]
    pub self_distance: Option<f64>,
    /// Whether the obstacles' sharp features — a box's corners and edges,
    /// a cylinder's rims — are kept out of the fabric's triangles too
    /// (issue 46, [`crate::contact::features`]), with the same penalty:
    /// `true` or `false`. Default false: the nodes alone are kept out of
    /// the obstacles (node-to-surface), as in release 1.
    #[serde(default)]
    pub features: bool,
}

fn default_stick_speed() -> f64 {
    crate::contact::DEFAULT_STICK_SPEED
}

/// `method = "lagrange"`: `g = 0` exactly on an active set.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LagrangeSpec {
    /// Coulomb's friction coefficient `mu` against every obstacle, >= 0
    /// and finite, the normal force being the multiplier. Default 0
    /// (frictionless).
    #[serde(default)]
    pub friction: f64,
    /// The slip speed (m/s, > 0) below which friction is a stiff viscous
    /// resistance, as with a penalty. Default 1e-3.
    #[serde(default = "default_stick_speed")]
    pub stick_speed: f64,
    /// Self-contact (SPEC §6.3): the fabric against itself, within and
    /// between its pieces. Default false.
    #[serde(default, rename = "self")]
    pub self_contact: bool,
    /// How close two pieces of fabric may come (m), > 0; default the
    /// thickness. Only with `self = true`.
    #[serde(default)]
    pub self_distance: Option<f64>,
}

impl ContactSpec {
    /// `self = true`.
    pub fn self_contact(&self) -> bool {
        match self {
            Self::Penalty(p) => p.self_contact,
            Self::Lagrange(l) => l.self_contact,
        }
    }

    /// `self_distance`.
    fn self_distance(&self) -> Option<f64> {
        match self {
            Self::Penalty(p) => p.self_distance,
            Self::Lagrange(l) => l.self_distance,
        }
    }

    /// The keys of the contact table but `method`, into the struct of `method`.
    pub(super) fn read(
        method: ContactMethodName,
        keys: ValueDeserializer<'_>,
    ) -> Result<Self, toml::de::Error> {
        Ok(match method {
            ContactMethodName::Penalty => Self::Penalty(Deserialize::deserialize(keys)?),
            ContactMethodName::Lagrange => Self::Lagrange(Deserialize::deserialize(keys)?),
        })
    }
}

/// The obstacles and the contact method, `None` without obstacles (and
/// then without a `[contact]` table).
pub(super) fn build_contact(
    c: &Checker,
    s: &Scenario,
    base: &Path,
    inputs: &mut Vec<InputFile>,
) -> Result<Option<ContactModel>, ScenarioError> {
    if s.obstacles.is_empty() {
        if s.contact.is_some() && !s.contact.as_ref().is_some_and(ContactSpec::self_contact) {
            return Err(c.invalid(
                "contact",
                None,
                "method",
                "is given but there is no [[obstacle]]".into(),
            ));
        }
        return Ok(None);
    }
    let spec = c.required(
        "contact",
        None,
        "method",
        &s.contact,
        "when there are obstacles (a [contact] table with method = \"penalty\" or \"lagrange\")",
    )?;
    let t = "contact";
    let friction_of = |mu: f64| {
        if mu.is_finite() && mu >= 0.0 {
            Ok(mu)
        } else {
            Err(c.invalid(
                t,
                None,
                "friction",
                format!("must be a finite number >= 0 (Coulomb's coefficient), not {mu}"),
            ))
        }
    };
    let (method, friction, stick_speed, features) = match spec {
        ContactSpec::Penalty(p) => (
            ContactMethod::Penalty {
                stiffness: c.positive(t, None, "penalty", p.penalty)?,
            },
            friction_of(p.friction)?,
            c.positive(t, None, "stick_speed", p.stick_speed)?,
            p.features,
        ),
        ContactSpec::Lagrange(l) => (
            ContactMethod::Lagrange,
            friction_of(l.friction)?,
            c.positive(t, None, "stick_speed", l.stick_speed)?,
            false,
        ),
    };
    let bodies = (s.obstacles.iter().enumerate())
        .map(|(i, o)| build_body(c, i, o, base, inputs))
        .collect::<Result<_, _>>()?;
    let mut body_friction = Vec::new();
    for (i, o) in s.obstacles.iter().enumerate() {
        let mu = match o.friction() {
            Some(mu) if !(mu.is_finite() && mu >= 0.0) => {
                return Err(c.invalid(
                    "obstacle",
                    Some(i),
                    "friction",
                    format!("must be a finite number >= 0 (Coulomb's coefficient), not {mu}"),
                ));
            }
            mu => mu,
        };
        body_friction.push(mu);
    }
    Ok(Some(ContactModel {
        bodies,
        method,
        friction,
        body_friction,
        stick_speed,
        features,
    }))
}

/// Rejects a fabric that starts inside an obstacle by more than 1e-3 of
/// its size: contact would fling it out in the first step (a node sitting
/// on a surface, or a hair inside, is fine).
pub(super) fn check_initial_penetration(
    c: &Checker,
    mesh: &Mesh,
    contact: &ContactModel,
) -> Result<(), ScenarioError> {
    let size = mesh.diagonal();
    // Nodes, and the centroids and edge midpoints of the elements' vertex
    // triangles: an obstacle smaller than an element can sit between nodes.
    let mut probes: Vec<[f64; 3]> = mesh.nodes.clone();
    for el in mesh.elements() {
        let v = [mesh.nodes[el[0]], mesh.nodes[el[1]], mesh.nodes[el[2]]];
        probes.push([0, 1, 2].map(|i| (v[0][i] + v[1][i] + v[2][i]) / 3.0));
        for j in 0..3 {
            let (a, b) = (v[j], v[(j + 1) % 3]);
            probes.push([0, 1, 2].map(|i| 0.5 * (a[i] + b[i])));
        }
    }
    for (k, body) in contact.bodies.iter().enumerate() {
        let deepest = probes
            .iter()
            .map(|x| (*x, body.proximity(*x, 0.0, None).gap))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((x, gap)) = deepest
            && gap < -1e-3 * size
        {
            return Err(c.invalid(
                "obstacle",
                Some(k),
                "shape",
                format!(
                    "({}) starts interpenetrating the fabric: the fabric's point {x:?} is {:.4e} m inside it; move the obstacle or the mesh",
                    body.shape.describe(),
                    -gap
                ),
            ));
        }
    }
    Ok(())
}

/// `[contact] self` and `self_distance`: with self-contact, its distance
/// (by default the thickness), the penalty its stiffness derives from
/// (`[contact] penalty`, or
/// [`crate::contact::self_contact::DEFAULT_STIFFNESS`]) and the friction
/// between the layers (`[contact] friction` and `stick_speed`).
pub(super) fn build_self_contact(
    c: &Checker,
    s: &Scenario,
) -> Result<Option<SelfContactSpec>, ScenarioError> {
    let t = "contact";
    let Some(spec) = &s.contact else {
        return Ok(None);
    };
    if !spec.self_contact() {
        if let Some(d) = spec.self_distance() {
            return Err(c.invalid(
                t,
                None,
                "self_distance",
                format!("= {d} is given but self-contact is off (set self = true, or remove it)"),
            ));
        }
        return Ok(None);
    }
    let distance = match spec.self_distance() {
        Some(d) => c.positive(t, None, "self_distance", d)?,
        None => s.material.thickness(),
    };
    // Friction and the slip speed as for the obstacles (build_contact
    // checks both when there are obstacles; here for when there are none).
    let (stiffness, friction, stick_speed) = match spec {
        ContactSpec::Penalty(p) => (p.penalty, p.friction, p.stick_speed),
        ContactSpec::Lagrange(l) => (
            crate::contact::self_contact::DEFAULT_STIFFNESS,
            l.friction,
            l.stick_speed,
        ),
    };
    if !(friction.is_finite() && friction >= 0.0) {
        return Err(c.invalid(
            t,
            None,
            "friction",
            format!("must be a finite number >= 0 (Coulomb's coefficient), not {friction}"),
        ));
    }
    Ok(Some(SelfContactSpec {
        distance,
        stiffness: c.positive(t, None, "penalty", stiffness)?,
        friction,
        stick_speed: c.positive(t, None, "stick_speed", stick_speed)?,
    }))
}
