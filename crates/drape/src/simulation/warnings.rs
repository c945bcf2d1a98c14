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
//! * **A tension field with bending.** A tension-field wrinkling model
//!   (`stress-projection`, `relaxed-energy`) gives a compressed element no
//!   in-plane stiffness: it stands for wrinkles finer than the mesh. With
//!   a bending rigidity the folds are resolved by the mesh instead, and a
//!   compressed element, free to shrink, can collapse towards a line,
//!   where the bending patch's normal turns at will: the steps shrink to
//!   fractions of a millisecond (docs/performance.md, "Settling with
//!   bending"). With bending, `wrinkling = "none"` lets the folds carry
//!   the compression.
//! * **Self-contact with a conservative Newmark.** The trapezoidal rule
//!   (`gamma` = 1/2) conserves the energy of a quadratic potential, not of
//!   the self-contact barrier, which stiffens without bound: at steps
//!   that do not resolve a landing on it, the fabric bounces off higher
//!   than it fell (README, "Self-contact"); the default `beta` = 1,
//!   `gamma` = 1.5 dissipates instead.

use super::schedule::{DEFAULT_DT_MAX_FACTOR, END_TOLERANCE, REST_STEPS};
use crate::setup::{Analysis, Setup};
use crate::vec3::{norm, sub};

/// The largest motion of an obstacle in one step, as a fraction of the
/// fabric's smallest element edge, that is not warned about.
pub const MAX_MOTION_PER_STEP: f64 = 0.5;

/// A Green strain of uniform biaxial compression: every tension-field
/// model calls it slack, and a material without one reports no state.
const BIAXIAL_COMPRESSION: [f64; 3] = [-0.01, -0.01, 0.0];

/// The warnings of `setup` (none for most scenarios).
pub fn warnings(setup: &Setup) -> Vec<String> {
    let mut out = Vec::new();
    tension_field_with_bending(setup, &mut out);
    conservative_self_contact(setup, &mut out);
    rest_after_the_end(setup, &mut out);
    fast_obstacles(setup, &mut out);
    out
}

/// Self-contact with the trapezoidal rule (`gamma` below 0.6, where the
/// scheme's numerical damping is too small to take up a landing on the
/// barrier).
fn conservative_self_contact(setup: &Setup, out: &mut Vec<String>) {
    if let (Some(_), Analysis::Dynamic { newmark, .. }) =
        (setup.model.self_contact(), &setup.analysis)
        && newmark.gamma < 0.6
    {
        out.push(format!(
            "time.gamma = {} with contact.self = true: the self-contact barrier stiffens without bound, and a Newmark scheme that does not dissipate can make the fabric bounce off it higher than it fell (README, \"Self-contact\"); beta = 1.0, gamma = 1.5 (the default) dissipates instead",
            newmark.gamma
        ));
    }
}

/// A tension-field wrinkling model together with a bending rigidity.
fn tension_field_with_bending(setup: &Setup, out: &mut Vec<String>) {
    let model = &setup.model;
    if model.bending().is_some()
        && model
            .material()
            .wrinkle_state(BIAXIAL_COMPRESSION)
            .is_some()
    {
        out.push(
            "material.wrinkling is a tension-field model and material.bending_rigidity is set: compressed elements have no (or, with compression_ratio, little) in-plane stiffness and, with bending, contract instead of folding or collapse, which makes the steps tiny; with bending the mesh resolves the folds, so wrinkling = \"none\" is the model to use (README, \"Bending\")".to_string(),
        );
    }
}

/// A rest criterion that starts counting at or after the schedule's end,
/// so that it can never be met (a schedule shortened for a quick look
/// does that; the run then ends "completed" with no word of rest).
fn rest_after_the_end(setup: &Setup, out: &mut Vec<String>) {
    let (Some(rest), Analysis::Dynamic { segments, .. }) = (&setup.rest, &setup.analysis) else {
        return;
    };
    let end = setup.analysis.end_time();
    if rest.after >= end {
        out.push(format!(
            "time.rest.after = {} s is at or after the schedule's end (t = {end} s): the rest criterion can never be met, and the run will end at t = {end} s whether or not the fabric is at rest",
            rest.after
        ));
        return;
    }
    // With fixed steps, the rest criterion needs REST_STEPS steps that end
    // at or after `after`: the REST_STEPS-th last step must (adaptive
    // steps may shrink and add steps: not judged).
    if setup.adaptive.is_some() {
        return;
    }
    let mut t = end;
    let mut left = REST_STEPS - 1;
    for &(steps, dt) in segments.iter().rev() {
        let take = left.min(steps);
        t -= take as f64 * dt;
        left -= take;
        if left == 0 {
            break;
        }
    }
    if left > 0 || t < rest.after * (1.0 - END_TOLERANCE) {
        out.push(format!(
            "time.rest.after = {} s leaves fewer than the {REST_STEPS} steps the rest criterion needs before the schedule's end (t = {end} s): it can never be met, and the run will end at t = {end} s whether or not the fabric is at rest",
            rest.after
        ));
    }
}

/// Obstacles that move more than [`MAX_MOTION_PER_STEP`] of the smallest
/// element edge in a step.
fn fast_obstacles(setup: &Setup, out: &mut Vec<String>) {
    let Some(contact) = setup.model.contact() else {
        return;
    };
    // Load steps of a static analysis are not time: bodies do not move.
    let Analysis::Dynamic { segments, .. } = &setup.analysis else {
        return;
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;
    use std::path::Path;

    /// The warnings of a 4 x 4 square with `material` lines added to
    /// `[material]` and `time` lines to `[time]` (20 steps of 0.5 ms, to
    /// t = 0.01 s).
    fn warned_with(material: &str, time: &str) -> Vec<String> {
        let text = format!(
            "title = \"w\"\n[mesh]\nshape = \"rectangle\"\nsize = [0.1, 0.1]\ndivisions = [4, 4]\n\
             [material]\nyoungs_modulus = 2.0e6\npoisson_ratio = 0.3\ndensity = 320.0\nthickness = 0.6e-3\n{material}\n\
             [time]\nsegments = [{{ steps = 20, dt = 0.0005 }}]\n{time}\n"
        );
        let path = Path::new("w.toml");
        let setup = Scenario::parse(&text, path)
            .and_then(|s| s.build(path, &text))
            .expect("a valid scenario");
        warnings(&setup)
    }

    fn warned(material: &str) -> Vec<String> {
        warned_with(material, "")
    }

    #[test]
    fn a_tension_field_with_bending_is_warned_about() {
        for model in ["stress-projection", "relaxed-energy"] {
            let w = warned(&format!(
                "wrinkling = \"{model}\"\nbending_rigidity = 2.0e-5"
            ));
            assert_eq!(w.len(), 1, "{model}: {w:?}");
            assert!(w[0].contains("wrinkling = \"none\""), "{w:?}");
        }
        // Either alone is what it says.
        assert!(warned("wrinkling = \"none\"\nbending_rigidity = 2.0e-5").is_empty());
        assert!(warned("wrinkling = \"stress-projection\"").is_empty());
        assert!(warned("").is_empty());
    }

    /// Bending on a criss-cross mesh (a 4 x 4 grid with alternating
    /// diagonals, read from an OBJ file) is not warned about: since issue
    /// 42 it bends as any mesh does (until then it was 74 % too soft and
    /// warned about), nor is the same mesh without bending, nor a
    /// rectangle with bending.
    #[test]
    fn bending_on_a_criss_cross_mesh_is_not_warned_about() {
        let dir = std::env::temp_dir().join(format!("drape-criss-cross-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut obj = String::new();
        for j in 0..5 {
            for i in 0..5 {
                obj += &format!("v {} {} 0\n", 0.025 * i as f64, 0.025 * j as f64);
            }
        }
        let id = |i: usize, j: usize| j * 5 + i + 1;
        for j in 0..4 {
            for i in 0..4 {
                let (p00, p10, p11, p01) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                obj += &if (i + j) % 2 == 0 {
                    format!("f {p00} {p10} {p11}\nf {p00} {p11} {p01}\n")
                } else {
                    format!("f {p00} {p10} {p01}\nf {p10} {p11} {p01}\n")
                };
            }
        }
        let mesh = dir.join("criss-cross.obj");
        std::fs::write(&mesh, obj).unwrap();
        let run = |bending: &str| {
            let text = format!(
                "title = \"w\"\n[mesh]\nshape = \"file\"\npath = \"{}\"\n\
                 [material]\nyoungs_modulus = 2.0e6\npoisson_ratio = 0.3\ndensity = 320.0\nthickness = 0.6e-3\n{bending}\n\
                 [time]\nsegments = [{{ steps = 20, dt = 0.0005 }}]\n",
                mesh.display()
            );
            let path = dir.join("w.toml");
            let setup = Scenario::parse(&text, &path)
                .and_then(|s| s.build(&path, &text))
                .expect("a valid scenario");
            warnings(&setup)
        };
        let (with, without) = (run("bending_rigidity = 2.0e-5"), run(""));
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(with.is_empty(), "{with:?}");
        assert!(without.is_empty(), "{without:?}");
        assert!(warned("bending_rigidity = 2.0e-5").is_empty());
    }

    #[test]
    fn a_rest_criterion_after_the_end_is_warned_about() {
        // The square's schedule ends at t = 0.01 s.
        let rest =
            |after: f64| warned_with("", &format!("rest = {{ speed = 1e-4, after = {after} }}"));
        let w = rest(0.5);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].contains("time.rest.after = 0.5 s") && w[0].contains("never"),
            "{w:?}"
        );
        assert!(rest(0.0).is_empty());
        // The tenth-last step ends at 0.0055 s: from 0.0051 s ten steps
        // remain, from 0.0056 s nine (issue 35: not warned about).
        assert!(rest(0.0051).is_empty());
        let w = rest(0.0056);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].contains("fewer than the 10 steps") && w[0].contains("never"),
            "{w:?}"
        );
        // With adaptive steps the count is not known: not judged.
        let adaptive = warned_with(
            "",
            "adaptive = true\nrest = { speed = 1e-4, after = 0.0056 }",
        );
        assert!(adaptive.is_empty(), "{adaptive:?}");
    }
}
