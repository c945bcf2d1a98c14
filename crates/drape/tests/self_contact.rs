//! Self-contact (issue 33), each case checked after every step with the
//! crossing counter (an edge through a triangle it shares no node with):
//!
//! - two plies of one Gmsh file (`tests/meshes/two-plies-t3.msh`, two
//!   20 cm squares 1 cm apart, made by `scripts/meshes/self_contact_meshes.py`)
//!   dropped together onto a 10 cm pedestal: without self-contact the upper
//!   ply passes through the lower one as soon as the lower one lands; with
//!   `self = true` never, and the plies stay at least `self_distance / 2`
//!   apart;
//! - a 40 cm strip standing almost upright (`tests/meshes/leaning-strip-t3.msh`,
//!   `scripts/meshes/self_contact_meshes.py`) dropped onto a plane, where it
//!   buckles and piles up on itself;
//! - a cloth lying on a plane pushed into folds by two walls closing in.
//!
//! Bad keys are refused.

mod common;

use common::{assert_error, drive_through, setup};
use std::path::Path;

fn scenario(contact: &str) -> String {
    let (material, time) = (fabric("2.0e-5"), dissipative(100));
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/meshes/two-plies-t3.msh");
    format!(
        r#"[mesh]
shape = "file"
path = {mesh:?}
{material}
[[load]]
kind = "surface"
force = [0.0, 0.0, -1.8816]
[[obstacle]]
shape = "box"
min = [-0.05, -0.05, -0.25]
max = [0.05, 0.05, -0.02]
[contact]
method = "penalty"
penalty = 5.0e4
{contact}
{time}
"#
    )
}

/// Steps the plies to `end` (s) ([`drive`]).
fn drop_plies(contact: &str, end: f64) -> (Vec<usize>, Vec<f64>, usize, usize) {
    drive(&scenario(contact), end)
}

/// [`drive_through`] without the trajectory.
fn drive(text: &str, end: f64) -> (Vec<usize>, Vec<f64>, usize, usize) {
    let (crossings, y, steps, builds, _) = drive_through(text, end, None);
    (crossings, y, steps, builds)
}

/// Drives scenario `text(contact)` to `end` (s) with self-contact
/// (`self_distance` 1 mm) and without: no crossing after any step with it,
/// more than 10 after some step without (`what` names the case in the
/// printout).
fn crosses_only_without_self_contact(what: &str, text: &dyn Fn(&str) -> String, end: f64) {
    let (on, _, steps, builds) = drive(&text("self = true\nself_distance = 1.0e-3"), end);
    let worst = on.iter().copied().max().unwrap_or(0);
    eprintln!(
        "{what}, self-contact: {steps} steps, layout built {builds} times, most crossings {worst}"
    );
    assert_eq!(worst, 0, "crossings per step: {on:?}");
    let (off, _, _, _) = drive(&text(""), end);
    let most = off.iter().copied().max().unwrap_or(0);
    eprintln!("{what} without self-contact: up to {most} crossings");
    assert!(most > 10);
}

/// The plies landing on the pedestal (the lower at t = 64 ms, the upper on
/// it at about 80 ms) and their skirts bending down, to t = 0.1 s: with
/// self-contact no crossing after any step and the plies' centres at
/// least `self_distance / 2` apart; without, the upper ply passes through.
#[test]
fn two_plies_never_cross_with_self_contact() {
    let d_hat = 2.0e-3;
    let (on, y, steps, builds) = drop_plies(&format!("self = true\nself_distance = {d_hat}"), 0.1);
    let worst = on.iter().copied().max().unwrap_or(0);
    eprintln!(
        "self-contact: {steps} steps, layout built {builds} times, most crossings after a step {worst}"
    );
    // The layout grows with the pairs, rarely: not at every step.
    assert!(
        builds >= 1 && builds < steps / 4,
        "{builds} builds in {steps} steps"
    );
    assert_eq!(worst, 0, "crossings per step: {on:?}");
    // The two centre nodes (nearest (0, 0, 0) and (0, 0, 0.01) initially).
    let s = setup(&scenario("self = true"));
    let x0 = &s.model.mesh().nodes;
    let nearest = |p: [f64; 3]| {
        (0..x0.len())
            .min_by(|&a, &b| {
                let d = |n: usize| (0..3).map(|i| (x0[n][i] - p[i]).powi(2)).sum::<f64>();
                d(a).total_cmp(&d(b))
            })
            .unwrap()
    };
    let (lo, hi) = (nearest([0.0, 0.0, 0.0]), nearest([0.0, 0.0, 0.01]));
    let gap = y[3 * hi + 2] - y[3 * lo + 2];
    eprintln!("centres {gap:e} m apart");
    assert!(gap >= 0.5 * d_hat, "{gap}");
    // With multipliers against the pedestal (their elimination on the
    // grown layout): the same guarantee.
    let text = scenario(&format!("self = true\nself_distance = {d_hat}")).replace(
        "method = \"penalty\"\npenalty = 5.0e4",
        "method = \"lagrange\"",
    );
    assert!(text.contains("lagrange"));
    let (lagrange, _, steps, _) = drive(&text, 0.1);
    eprintln!(
        "with multipliers: {steps} steps, most crossings {:?}",
        lagrange.iter().max()
    );
    assert_eq!(lagrange.iter().max(), Some(&0));
    let (off, _, _, builds) = drop_plies("", 0.1);
    assert_eq!(builds, 0);
    let last = *off.last().unwrap();
    eprintln!("without self-contact: {last} crossings at t = 0.1 s");
    assert!(last > 0);
}

/// `self_distance` without `self = true`, a distance that is not positive,
/// and one the initial mesh already violates (the plies 1 cm apart) are
/// refused at the key's line with the value.
#[test]
fn bad_self_contact_keys_are_refused() {
    assert_error(
        &scenario("self_distance = 1.0e-3"),
        20,
        "contact.self_distance",
        &["self-contact is off"],
    );
    assert_error(
        &scenario("self = true\nself_distance = -1.0e-3"),
        21,
        "contact.self_distance",
        &["-0.001"],
    );
    assert_error(
        &scenario("self = true\nself_distance = 0.02"),
        21,
        "contact.self_distance",
        &["0.02", "larger than the distance"],
    );
}

/// The leaning strip dropped onto a plane with friction, to t = 0.3 s: it
/// lands at about 0.03 s, buckles and piles up in folds on itself. With
/// self-contact no crossing after any step; without, the folds pass
/// through each other.
#[test]
fn a_strip_folding_onto_itself_never_crosses() {
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/meshes/leaning-strip-t3.msh");
    let (material, time) = (fabric("2.0e-6"), dissipative(300));
    let text = |contact: &str| {
        format!(
            r#"[mesh]
shape = "file"
path = {mesh:?}
{material}
[[load]]
kind = "gravity"
acceleration = [0.0, 0.0, -9.81]
[[obstacle]]
shape = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[contact]
method = "penalty"
penalty = 5.0e4
friction = 0.5
{contact}
{time}
"#
        )
    };
    crosses_only_without_self_contact("strip", &text, 0.3);
}

/// A 20 cm x 6 cm cloth lying on a plane with friction, its short edges
/// pushed by two walls closing in at 0.3 m/s each (moving boxes), to
/// t = 0.25 s: the cloth, compressed to a quarter of its length, buckles
/// into folds pressed against each other. With self-contact no crossing
/// after any step; without, the folds pass through each other.
#[test]
fn a_cloth_pushed_into_folds_never_crosses() {
    pushed_cloth("divisions = [24, 6]\norder = 1");
    // Quadratic triangles, measured by their four sub-triangles each.
    pushed_cloth("divisions = [12, 3]\norder = 2");
}

/// [`a_cloth_pushed_into_folds_never_crosses`] on the mesh `mesh` (keys).
fn pushed_cloth(mesh: &str) {
    let (material, time) = (fabric("2.0e-6"), dissipative(250));
    let text = |contact: &str| {
        format!(
            r#"[mesh]
shape = "rectangle"
size = [0.2, 0.06]
{mesh}
pattern = "alternate"
center = [0.0, 0.0, 0.002]
{material}
[[load]]
kind = "gravity"
acceleration = [0.0, 0.0, -9.81]
[[obstacle]]
shape = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[obstacle]]
shape = "box"
min = [-0.13, -0.05, -0.01]
max = [-0.101, 0.05, 0.1]
velocity = [0.3, 0.0, 0.0]
[[obstacle]]
shape = "box"
min = [0.101, -0.05, -0.01]
max = [0.13, 0.05, 0.1]
velocity = [-0.3, 0.0, 0.0]
[contact]
method = "penalty"
penalty = 5.0e4
friction = 0.3
{contact}
{time}
"#
        )
    };
    crosses_only_without_self_contact("pushed cloth", &text, 0.25);
}

/// Friction between the layers: a 6 cm ply lying on a 20 cm one that is
/// held (`tests/meshes/ply-on-ply-t3.msh`, `scripts/meshes/self_contact_meshes.py`),
/// `friction = 0.4`, gravity tilted by θ (an incline). With tan θ = 0.25
/// the upper ply stays (its corner moves less than 1 mm in 0.15 s); with
/// θ = 35° it slides with the acceleration `g (sin θ − μ cos θ)` = 2.41
/// m/s² (the corner's second difference over 0.05 s steps, within 2 %),
/// and the dissipated energy never decreases. It rests on the barrier just
/// under `d̂`, and the lower ply is never crossed.
/// The 6 cm ply on the held 20 cm ply (`tests/meshes/ply-on-ply-t3.msh`),
/// `friction = mu`, gravity tilted by `theta` along +x, `steps` of 1 ms.
fn ply_on_ply(theta: f64, mu: f64, steps: usize) -> String {
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/meshes/ply-on-ply-t3.msh");
    let (material, time) = (fabric("1.0e-6"), dissipative(steps));
    let (s, c) = theta.sin_cos();
    format!(
        r#"[mesh]
shape = "file"
path = {mesh:?}
{material}
[[load]]
kind = "gravity"
acceleration = [{}, 0.0, {}]
[[fix]]
within = {{ min = [-0.2, -0.2, -0.0005], max = [0.2, 0.2, 0.0005] }}
[contact]
method = "penalty"
penalty = 5.0e4
friction = {mu}
self = true
self_distance = 1.0e-3
{time}
"#,
        G * s,
        -G * c
    )
}

/// Gravity (m/s²).
const G: f64 = 9.81;

#[test]
fn a_ply_on_a_ply_holds_below_the_friction_angle_and_slides_above() {
    let (g, mu) = (G, 0.4);
    let text = |theta: f64| ply_on_ply(theta, mu, 150);
    let s = setup(&text(0.0));
    let corner = (s.model.mesh().nodes.iter())
        .position(|p| (p[0] - 0.03).abs() < 1e-9 && (p[1] - 0.03).abs() < 1e-9 && p[2] > 0.001)
        .expect("the upper ply's corner");
    let stick = 0.25f64.atan();
    let (seen, _, _, _, track) = drive_through(&text(stick), 0.15, Some(corner));
    assert_eq!(seen.iter().max(), Some(&0));
    let moved = track.last().unwrap().1[0] - 0.03;
    let z = track.last().unwrap().1[2];
    eprintln!("tan θ = 0.25: the corner moved {moved:e} m, rests at z = {z:e} m");
    assert!(moved.abs() < 1e-3, "{moved}");
    assert!(z > 0.9e-3 && z < 1e-3, "{z}");
    let slide = 35f64.to_radians();
    let (seen, _, _, _, track) = drive_through(&text(slide), 0.15, Some(corner));
    assert_eq!(seen.iter().max(), Some(&0));
    let at = |t: f64| {
        track
            .iter()
            .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
            .unwrap()
            .1[0]
    };
    let a = (at(0.15) - 2.0 * at(0.10) + at(0.05)) / (0.05 * 0.05);
    let expected = g * (slide.sin() - mu * slide.cos());
    eprintln!("θ = 35°: acceleration {a:.4} m/s² against {expected:.4}");
    assert!((a / expected - 1.0).abs() < 0.02, "{a} vs {expected}");
}

/// Runs scenario `text` (written into a temporary directory named after
/// `name`) and returns its `history.csv`.
fn history_of(text: &str, name: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let dir = common::temp_dir(name);
    let path = dir.join("s.toml");
    std::fs::write(&path, text).unwrap();
    let (scenario, source) = drape::scenario::Scenario::read(&path).unwrap();
    let s = scenario.build(&path, &source).unwrap();
    let out = dir.join("out");
    drape::simulation::run(&s, &out, &mut |_| {}).expect("runs");
    let (header, rows) = common::read_history(&out);
    (header, rows)
}

/// The dissipation of friction between the layers reaches the history:
/// `friction_dissipation` never decreases and grows while the ply slides.
#[test]
fn friction_between_layers_dissipates() {
    let text = ply_on_ply(35f64.to_radians(), 0.4, 60);
    let (header, rows) = history_of(&text, "self-friction");
    let d = common::column(&header, &rows, "friction_dissipation");
    assert!(d.windows(2).all(|w| w[1] >= w[0]), "{d:?}");
    assert!(*d.last().unwrap() > 1e-6, "{d:?}");
}

/// The 6 cm ply dropped 0.5 mm onto the held one, frictionless, with the
/// default dissipative Newmark (β = 1, γ = 1.5): `total_energy` (the
/// kinetic, strain and contact energies, the barrier's included, less the
/// work of the loads) never increases from a step to the next (beyond Newton's tolerance),
/// the barrier's energy shows in `contact_energy`, and the ply comes to
/// rest. (The trapezoidal rule, β = 0.25, γ = 0.5, does not conserve
/// energy through this landing at steps of 0.1–0.2 ms, which do not
/// resolve the barrier's stiffening: the ply bounces higher than it fell.
/// README, "Self-contact".)
#[test]
fn energy_never_increases_through_a_landing() {
    let text = ply_on_ply(0.0, 0.0, 100);
    let (header, rows) = history_of(&text, "self-energy");
    let e = common::column(&header, &rows, "total_energy");
    let k = common::column(&header, &rows, "kinetic_energy");
    let c = common::column(&header, &rows, "contact_energy");
    let peak = k.iter().fold(0.0f64, |m, v| m.max(*v));
    let rise = e
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::NEG_INFINITY, f64::max);
    eprintln!(
        "peak kinetic {peak:e} J, largest rise of the total {rise:e} J, barrier up to {:e} J",
        c.iter().fold(0.0f64, |m, v| m.max(*v))
    );
    assert!(
        c.iter().any(|&v| v > 0.0),
        "the barrier's energy is in contact_energy"
    );
    // Up to the steps' convergence tolerance (a rise of 1e-8 of the peak
    // kinetic energy is Newton's, not the scheme's).
    assert!(rise <= 1e-7 * peak, "{rise:e} against {peak:e}");
    assert!(*k.last().unwrap() < 1e-6 * peak);
}

/// Friction between the layers of a scenario without obstacles (only
/// self-contact reads `[contact] friction` then) is checked as against
/// obstacles: a negative coefficient is refused at its line.
#[test]
fn a_bad_friction_between_the_layers_is_refused_at_its_line() {
    let text = ply_on_ply(0.0, -0.1, 1);
    let line = text
        .lines()
        .position(|l| l.starts_with("friction"))
        .unwrap()
        + 1;
    assert_error(
        &text,
        line,
        "contact.friction",
        &["must be a finite number >= 0", "-0.1"],
    );
}

/// Self-contact with the trapezoidal rule is warned about (naming
/// `time.gamma`); with the default dissipative scheme it is not.
#[test]
fn a_conservative_newmark_with_self_contact_is_warned_about() {
    let trapezoidal =
        ply_on_ply(0.0, 0.0, 10).replace("beta = 1.0\ngamma = 1.5", "beta = 0.25\ngamma = 0.5");
    assert!(trapezoidal.contains("gamma = 0.5"));
    let w = drape::simulation::warnings(&setup(&trapezoidal));
    assert!(
        w.iter()
            .any(|m| m.starts_with("time.gamma = 0.5 with contact.self = true")),
        "{w:?}"
    );
    assert!(drape::simulation::warnings(&setup(&ply_on_ply(0.0, 0.0, 10))).is_empty());
}

/// A self-contact run stopped (as by Ctrl-C) while the folds press on
/// each other and resumed ends with the same bytes as the uninterrupted
/// run: the checkpoint keeps the stencils the Hessian's layout was built
/// from, and each step forgets the broad phase kept by the one before.
#[test]
fn a_self_contact_run_resumes_bit_for_bit() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/folding-cloth.toml"),
    )
    .unwrap()
    .replace("steps = 350", "steps = 160")
    .replace("every = 10", "every = 40");
    let dir = common::temp_dir("self-resume");
    let path = dir.join("s.toml");
    std::fs::write(&path, &text).unwrap();
    common::stops_and_resumes_bit_for_bit(&path, &dir, 120, |ck| {
        assert!(
            !ck.self_contact_layout.is_empty(),
            "no layout kept at step 120"
        );
    });
}

/// The `[material]` table of every scenario here: 192 g/m² (320 kg/m³,
/// 0.6 mm), E = 2 MPa, ν = 0.3, the bending rigidity `bending` (N m).
fn fabric(bending: &str) -> String {
    format!(
        "[material]\nyoungs_modulus = 2.0e6\npoisson_ratio = 0.3\ndensity = 320.0\nthickness = 0.6e-3\nbending_rigidity = {bending}"
    )
}

/// The `[time]` table of every scenario here: `steps` of 1 ms, Newmark
/// with β = 1, γ = 1.5 (dissipative).
fn dissipative(steps: usize) -> String {
    format!("[time]\nbeta = 1.0\ngamma = 1.5\nsegments = [ {{ steps = {steps}, dt = 1.0e-3 }} ]")
}

/// Issue 46: two plies in one OBJ, the upper tilted through the lower at
/// a shallow angle, every node–triangle and edge–edge distance far above
/// `self_distance` (1e-6 m): the start-up check compared distances only
/// and accepted a mesh that crosses itself in every frame. It is refused
/// now, at `self_distance`'s line, naming a crossing edge and triangle.
#[test]
fn a_mesh_that_crosses_itself_is_refused_with_self_contact() {
    let dir = std::env::temp_dir().join(format!("drape-crossing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = dir.join("crossing.obj");
    std::fs::write(
        &obj,
        "v 0 0 0\nv 0.1 0 0\nv 0.1 0.1 0\nv 0 0.1 0\n\
         v 0.02 0.03 -0.01\nv 0.09 0.02 0.012\nv 0.08 0.09 0.011\nv 0.01 0.08 -0.012\n\
         f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n",
    )
    .unwrap();
    let text = |contact: &str| {
        format!(
            "[mesh]\nshape = \"file\"\npath = {obj:?}\n{}\n[[obstacle]]\nshape = \"plane\"\npoint = [0.0, 0.0, -0.5]\nnormal = [0.0, 0.0, 1.0]\n[contact]\nmethod = \"penalty\"\npenalty = 5.0e4\n{contact}\n{}\n",
            fabric("0.0"),
            dissipative(2)
        )
    };
    // Without self-contact the mesh is taken as it is.
    setup(&text(""));
    let refused = text("self = true\nself_distance = 1.0e-6");
    let line = 1 + refused
        .lines()
        .position(|l| l.starts_with("self_distance"))
        .unwrap();
    assert_error(
        &refused,
        line,
        "contact.self_distance",
        &[
            "passes through itself",
            "crosses the triangle of nodes",
            "cannot undo a crossing",
        ],
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 46: a dynamic step that fails with self-contact on says that the
/// barrier at `self_distance` stiffens without bound and what to change
/// (smaller steps, more halvings, a larger distance); with `linear =
/// "reuse"` also that that mode lacks the pairs' couplings. (Forced to
/// fail here by two Newton iterations and no halving: the mechanism is
/// any failure with self-contact, as a thin barrier's at the impact.)
#[test]
fn a_failed_step_with_self_contact_names_the_barrier() {
    let failure = |linear: &str| {
        let text = scenario("self = true\nself_distance = 1.0e-6")
            + &format!("[solver]\nmax_iterations = 2\nmax_cutbacks = 0\n{linear}\n");
        let out = std::env::temp_dir().join(format!(
            "drape-thin-barrier-{}-{}",
            std::process::id(),
            linear.len()
        ));
        let _ = std::fs::remove_dir_all(&out);
        let e = drape::simulation::run(&setup(&text), &out, &mut |_| {})
            .expect_err("two iterations cannot settle an impact");
        let _ = std::fs::remove_dir_all(&out);
        e.to_string()
    };
    let direct = failure("");
    for f in [
        "contact.self_distance = 1e-6 m stiffens without bound",
        "smaller steps",
        "max_cutbacks, now 0",
        "a larger self_distance",
    ] {
        assert!(direct.contains(f), "expected {f:?} in {direct}");
    }
    assert!(!direct.contains("linear = \"direct\""), "{direct}");
    let reuse = failure("linear = \"reuse\"");
    assert!(reuse.contains("use linear = \"direct\""), "{reuse}");
}
