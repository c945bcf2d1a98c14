//! Warnings about a scenario that runs but may not mean what it says:
//! printed by the command line before the run and recorded in
//! `summary.json` (`warnings`).
//!
//! * **An obstacle faster than the mesh.** Contact is found at the ends
//!   of the steps only, at the nodes. An obstacle that moves more than
//!   [`MAX_MOTION_PER_STEP`] of the fabric's smallest element edge in one
//!   step can pass between nodes, or through the whole fabric, without a
//!   contact ever being seen (1 m per step goes through a 20 cm cloth
//!   unnoticed).

use super::schedule::DEFAULT_DT_MAX_FACTOR;
use crate::scenario::{Analysis, Setup};
use crate::vec3::{norm, sub};

/// The largest motion of an obstacle in one step, as a fraction of the
/// fabric's smallest element edge, that is not warned about.
pub const MAX_MOTION_PER_STEP: f64 = 0.5;

/// The warnings of `setup` (none for most scenarios).
pub fn warnings(setup: &Setup) -> Vec<String> {
    let mut out = Vec::new();
    let Some(contact) = setup.model.contact() else {
        return out;
    };
    // Load steps of a static analysis are not time: bodies do not move.
    let Analysis::Dynamic { segments, .. } = &setup.analysis else {
        return out;
    };
    let largest_dt = segments
        .iter()
        .map(|&(_, dt)| match &setup.adaptive {
            Some(a) => a.dt_max.unwrap_or(DEFAULT_DT_MAX_FACTOR * dt),
            None => dt,
        })
        .fold(0.0, f64::max);
    let mesh = setup.model.mesh();
    let edge = mesh
        .elements()
        .flat_map(|el| {
            let x = [mesh.nodes[el[0]], mesh.nodes[el[1]], mesh.nodes[el[2]]];
            (0..3).map(move |k| norm(sub(x[(k + 1) % 3], x[k])))
        })
        .fold(f64::INFINITY, f64::min);
    for (i, body) in contact.bodies.iter().enumerate() {
        let speed = norm(body.velocity);
        let motion = speed * largest_dt;
        if motion > MAX_MOTION_PER_STEP * edge {
            out.push(format!(
                "obstacle[{i}] moves {motion:.3e} m in a step ({speed:e} m/s over dt = {largest_dt:e} s), more than {MAX_MOTION_PER_STEP} of the fabric's smallest element edge ({edge:.3e} m): contact is found at the nodes at the ends of steps, so the obstacle may pass through the fabric unseen; take steps below {:.3e} s",
                MAX_MOTION_PER_STEP * edge / speed
            ));
        }
    }
    out
}
