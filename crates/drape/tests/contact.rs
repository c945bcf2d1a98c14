//! Contact: finite-difference checks of the penalty terms for every
//! obstacle, resting on a plane, Lagrange exactness, penalty scaling,
//! behaviour at edges and corners, sphere, cylinder, moving plane, and the
//! fabric-on-pedestal reference problem with both methods.

mod common;

use common::{column, drive, fabric, read_history, setup, temp_dir};
use drape::contact::obstacle::{
    BoxObstacle, CylinderObstacle, PlaneObstacle, Rounded, SphereObstacle, TriMeshObstacle,
};
use drape::contact::{ContactMethod, ContactModel, Obstacle, RigidBody};
use drape::fd::{gradient_error, jacobian_error};
use drape::solver::SparsePattern;
use std::path::Path;

/// A closed octahedron-based sphere mesh (icosahedron refined once would do
/// too): a convex, curved triangle mesh of radius ~`r` about `c`.
fn octasphere(c: [f64; 3], r: f64) -> TriMeshObstacle {
    let mut v: Vec<[f64; 3]> = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let mut t: Vec<[usize; 3]> = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    for _ in 0..2 {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::new();
        for tri in &t {
            let mut m = [0; 3];
            for k in 0..3 {
                let (a, b) = (tri[k].min(tri[(k + 1) % 3]), tri[k].max(tri[(k + 1) % 3]));
                m[k] = *mid.entry((a, b)).or_insert_with(|| {
                    let p = [0, 1, 2].map(|i| 0.5 * (v[a][i] + v[b][i]));
                    let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                    v.push(p.map(|x| x / n));
                    v.len() - 1
                });
            }
            next.extend([
                [tri[0], m[0], m[2]],
                [m[0], tri[1], m[1]],
                [m[2], m[1], tri[2]],
                [m[0], m[1], m[2]],
            ]);
        }
        t = next;
    }
    let v = v
        .into_iter()
        .map(|p| [0, 1, 2].map(|i| c[i] + r * p[i]))
        .collect();
    TriMeshObstacle::new("octasphere", v, t).unwrap()
}

/// The penalty energy, force and Hessian of one node against one obstacle.
fn penalty_terms(
    body: &RigidBody,
    y: [f64; 3],
    hints: &drape::contact::ContactState,
    eta: f64,
) -> (f64, Vec<f64>, Vec<f64>) {
    let model = ContactModel {
        bodies: vec![RigidBody {
            shape: clone_shape(body),
            velocity: body.velocity,
        }],
        method: ContactMethod::Penalty { stiffness: eta },
        friction: 0.0,
        body_friction: Vec::new(),
        stick_speed: drape::contact::DEFAULT_STICK_SPEED,
        features: false,
    };
    let pattern = SparsePattern::new(1, std::iter::once(&[0usize][..]));
    let mut g = vec![0.0; 3];
    let mut h = vec![0.0; pattern.nnz()];
    let e = model.add_penalty(
        eta,
        &y,
        0.3,
        hints,
        &mut g,
        Some(drape::contact::PenaltyHessian {
            values: &mut h,
            pattern: &pattern,
            project: None,
        }),
    );
    let mut dense = vec![0.0; 9];
    for c in 0..3 {
        for k in pattern.col_ptr[c]..pattern.col_ptr[c + 1] {
            dense[pattern.row_idx[k] * 3 + c] = h[k];
        }
    }
    (e, g, dense)
}

/// Shapes are not Clone; rebuild by description for the tests' bodies.
fn clone_shape(body: &RigidBody) -> Box<dyn Obstacle> {
    shapes()
        .into_iter()
        .find(|s| s.describe() == body.shape.describe())
        .unwrap()
}

fn shapes() -> Vec<Box<dyn Obstacle>> {
    let r = 2e-3;
    vec![
        Box::new(PlaneObstacle::new([0.0, 0.0, -0.05], [0.1, 0.2, 1.0]).unwrap()),
        Box::new(BoxObstacle::new([-0.05, -0.05, -0.25], [0.05, 0.05, -0.05]).unwrap()),
        Box::new(Rounded::new(
            BoxObstacle::new(
                [-0.05 + r, -0.05 + r, -0.25 + r],
                [0.05 - r, 0.05 - r, -0.05 - r],
            )
            .unwrap(),
            r,
        )),
        Box::new(SphereObstacle::new([0.0, 0.0, -0.1], 0.05).unwrap()),
        Box::new(Rounded::new(
            CylinderObstacle::new(
                [0.0, 0.0, -0.05 - r],
                [0.0, 0.0, 1.0],
                0.09 - r,
                0.2 - 2.0 * r,
            )
            .unwrap(),
            r,
        )),
        Box::new(octasphere([0.0, 0.0, -0.1], 0.05)),
    ]
}

/// Penetrating points for each shape (same order as `shapes`): faces,
/// points near the edges and corners of the box (inside) and round the
/// fillets of the rounded box and cylinder, the sphere and a curved mesh.
fn points(k: usize) -> Vec<[f64; 3]> {
    match k {
        0 => vec![[0.0, 0.0, -0.051], [-0.03, -0.01, -0.05]],
        1 => vec![
            [0.0, 0.01, -0.0502],
            [0.0497, 0.0, -0.0501],
            [0.0498, 0.0496, -0.0502],
            [0.0499, 0.02, -0.07],
        ],
        2 => vec![
            [0.0, 0.0, -0.0502],
            [0.049, 0.01, -0.051],
            [0.049, 0.049, -0.051],
            [0.0499, 0.0, -0.06],
        ],
        3 => vec![
            [0.0, 0.0, -0.0502],
            [0.03, 0.02, -0.07],
            [-0.02, 0.04, -0.11],
        ],
        4 => vec![
            [0.0, 0.0, -0.0502],
            [0.0893, 0.0, -0.0508],
            [0.0, 0.0895, -0.1],
        ],
        _ => vec![[0.001, 0.002, -0.0508], [0.015, 0.005, -0.062]],
    }
}

/// Force = d(energy)/dy and Hessian = d(force)/dy for every obstacle shape,
/// at penetrating points on faces, near box edges and corners, round
/// fillets, on the sphere and on a curved mesh. Tolerance as in
/// `derivatives.rs` (central differences, h = 1e-8 m against mm-scale
/// features: relative error ~1e-9 expected).
#[test]
fn penalty_force_and_hessian_match_finite_differences_for_every_obstacle() {
    let eta = 5e4;
    for (k, shape) in shapes().into_iter().enumerate() {
        let body = RigidBody {
            shape,
            velocity: [0.01, -0.02, 0.005],
        };
        for y0 in points(k) {
            // Hints from the point itself (fixed during the check).
            let model = ContactModel {
                bodies: vec![RigidBody {
                    shape: clone_shape(&body),
                    velocity: body.velocity,
                }],
                method: ContactMethod::Penalty { stiffness: eta },
                friction: 0.0,
                body_friction: Vec::new(),
                stick_speed: drape::contact::DEFAULT_STICK_SPEED,
                features: false,
            };
            let hints = model.initial_state(&y0);
            let moved = [0, 1, 2].map(|i| y0[i] + 0.3 * body.velocity[i]);
            let (e0, _, _) = penalty_terms(&body, moved, &hints, eta);
            assert!(
                e0 > 0.0,
                "{}: {y0:?} does not penetrate",
                body.shape.describe()
            );
            let energy = |y: &[f64]| penalty_terms(&body, [y[0], y[1], y[2]], &hints, eta).0;
            let force = |y: &[f64]| penalty_terms(&body, [y[0], y[1], y[2]], &hints, eta).1;
            let hess = |y: &[f64]| penalty_terms(&body, [y[0], y[1], y[2]], &hints, eta).2;
            let ge = gradient_error(energy, force, &moved, 1e-8);
            let he = jacobian_error(force, hess, &moved, 1e-8);
            assert!(
                ge < 1e-6,
                "{} at {y0:?}: force {ge:e}",
                body.shape.describe()
            );
            assert!(
                he < 1e-5,
                "{} at {y0:?}: Hessian {he:e}",
                body.shape.describe()
            );
        }
    }
}

fn drop_on_plane(
    method: &str,
    eta: f64,
    steps: usize,
) -> (Vec<String>, Vec<Vec<f64>>, drape::simulation::Summary) {
    let contact = if method == "penalty" {
        format!("method = \"penalty\"\npenalty = {eta}")
    } else {
        "method = \"lagrange\"".into()
    };
    let text = fabric(&format!(
        r#"
[[load]]
kind = "surface"
force = [0.0, 0.0, -1.8816]
[[obstacle]]
shape = "plane"
point = [0.0, 0.0, -0.001]
normal = [0.0, 0.0, 1.0]
[contact]
{contact}
[time]
segments = [{{ steps = {steps}, dt = 2.0e-3 }}]
[output]
every = 100000
"#
    ));
    let text = text.replace("divisions = [20, 20]", "divisions = [8, 8]");
    let s = setup(&text);
    let dir = temp_dir(&format!("plane-{method}-{eta}"));
    let summary = drape::simulation::run(&s, &dir, &mut |_| {}).unwrap();
    let (h, rows) = read_history(&dir);
    (h, rows, summary)
}

/// A membrane dropped flat onto a plane comes to rest carrying its weight:
/// total contact force = rho t g A = 0.075264 N, to 1e-6 relative once the
/// kinetic energy has decayed (beta = 1 damps it; what remains of the
/// inertial force is below that).
#[test]
fn membrane_resting_on_a_plane_carries_its_weight_with_both_methods() {
    let weight = 1.8816 * 0.2 * 0.2;
    for method in ["penalty", "lagrange"] {
        let (h, rows, summary) = drop_on_plane(method, 5e4, 150);
        assert!(
            summary.kinetic_energy < 1e-14,
            "{method}: not at rest, KE {}",
            summary.kinetic_energy
        );
        let force = *column(&h, &rows, "contact_force").last().unwrap();
        assert!(
            (force - weight).abs() < 1e-6 * weight,
            "{method}: contact force {force} vs weight {weight}"
        );
        let active = *column(&h, &rows, "active_contacts").last().unwrap();
        assert_eq!(active, 81.0, "{method}: every node in contact");
        let gap = *column(&h, &rows, "min_gap").last().unwrap();
        if method == "lagrange" {
            assert!(gap.abs() < 1e-12, "lagrange gap {gap}");
        } else {
            // Each node carries about weight / 64 (interior) over eta.
            assert!(
                gap < 0.0 && -gap < 2.0 * weight / 64.0 / 5e4,
                "penalty gap {gap}"
            );
        }
    }
}

/// The penetration at rest scales as 1/eta: the fitted slope of
/// log(penetration) against log(eta) over three decades is -1.
#[test]
fn penalty_penetration_scales_as_one_over_eta() {
    let etas = [1e3, 1e4, 1e5];
    let pen: Vec<f64> = etas
        .iter()
        .map(|&eta| {
            let (h, rows, _) = drop_on_plane("penalty", eta, 150);
            -column(&h, &rows, "min_gap").last().unwrap()
        })
        .collect();
    let xs: Vec<f64> = etas.iter().map(|e: &f64| e.ln()).collect();
    let ys: Vec<f64> = pen.iter().map(|p| p.ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / 3.0, ys.iter().sum::<f64>() / 3.0);
    let slope = xs
        .iter()
        .zip(&ys)
        .map(|(x, y)| (x - mx) * (y - my))
        .sum::<f64>()
        / xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>();
    eprintln!("penetrations {pen:?} for eta {etas:?}: slope {slope:.4}");
    assert!((slope + 1.0).abs() < 0.01, "slope {slope}");
}

fn pedestal_run(
    example: &str,
) -> (
    Vec<String>,
    Vec<Vec<f64>>,
    drape::simulation::Summary,
    drape::setup::Setup,
) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(example);
    let (scenario, source) = drape::scenario::Scenario::read(&path).unwrap();
    let s = scenario.build(&path, &source).unwrap();
    let dir = temp_dir(example);
    let summary = drape::simulation::run(&s, &dir, &mut |_| {}).unwrap();
    let (h, rows) = read_history(&dir);
    let _ = std::fs::remove_dir_all(&dir);
    (h, rows, summary, s)
}

/// The reference problem with both methods: all 460 steps; the first
/// contact at the first step boundary after the free-fall time
/// sqrt(2 * 0.05 / 9.8) = 0.101015 s, i.e. t = 0.1011 s; the centre node on
/// the pedestal's top (penalty: within its penetration; multipliers:
/// exactly); no node inside the pedestal by more than the penalty's own
/// penetration (multipliers: by 1e-9 m at most).
#[test]
fn fabric_on_pedestal_runs_with_both_methods() {
    let fall = (2.0f64 * 0.05 / 9.8).sqrt();
    for (example, eta) in [
        ("fabric-on-pedestal.toml", Some(5e4)),
        ("fabric-on-pedestal-lagrange.toml", None),
    ] {
        let (h, rows, summary, _) = pedestal_run(example);
        assert_eq!(summary.status, "completed");
        let t = column(&h, &rows, "time");
        assert_eq!(
            rows.len(),
            461,
            "{example}: 460 steps and the initial state"
        );
        let first = summary.first_contact_time.unwrap();
        let boundary = t.iter().copied().find(|&x| x > fall).unwrap();
        assert!(
            (first - boundary).abs() < 1e-12 && (first - 0.1011).abs() < 1e-9,
            "{example}: first contact {first}"
        );
        let cz = summary.monitors["center"][2];
        let min_gap = column(&h, &rows, "min_gap")
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let max_force = column(&h, &rows, "contact_force")
            .iter()
            .copied()
            .fold(0.0, f64::max);
        match eta {
            Some(eta) => {
                assert!(
                    cz < -0.05 && cz > -0.05 - max_force / eta,
                    "{example}: centre at {cz}"
                );
                assert!(
                    -min_gap <= max_force / eta,
                    "{example}: penetration {} beyond {}",
                    -min_gap,
                    max_force / eta
                );
            }
            None => {
                assert!((cz + 0.05).abs() < 1e-12, "{example}: centre at {cz}");
                assert!(min_gap >= -1e-9, "{example}: penetration {min_gap}");
            }
        }
        eprintln!(
            "{example}: {} Newton iterations, {} cut-back steps, min gap {min_gap:e} m, centre {:?}",
            summary.newton_iterations, summary.cutbacks, summary.monitors["center"]
        );
    }
}

fn example_setup(example: &str) -> drape::setup::Setup {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(example);
    let (scenario, source) = drape::scenario::Scenario::read(&path).unwrap();
    scenario.build(&path, &source).unwrap()
}

/// Largest distance between a node's final position mapped by a symmetry
/// of the mesh pattern and the final position of the node it maps to.
fn asymmetry(s: &drape::setup::Setup, y: &[f64], map: impl Fn([f64; 3]) -> [f64; 3]) -> f64 {
    let nodes = &s.model.mesh().nodes;
    let mut worst = 0.0f64;
    for (p, x) in nodes.iter().enumerate() {
        let (q, d) = s.model.mesh().nearest_node(map(*x)).unwrap();
        assert!(d < 1e-12, "the pattern is not symmetric under this map");
        let image = map([y[3 * p], y[3 * p + 1], y[3 * p + 2]]);
        let e = (0..3)
            .map(|i| (image[i] - y[3 * q + i]).powi(2))
            .sum::<f64>()
            .sqrt();
        worst = worst.max(e);
    }
    worst
}

/// Multipliers: after every step each active pair has |g| <= 1e-9 m and a
/// non-negative multiplier. Also reports (without asserting) the
/// asymmetry of the final drape under the symmetries of the `right`
/// pattern (rotation by 180 degrees about z; mirror in the plane x = y):
/// the scheme, the data and the mesh are symmetric, so any asymmetry
/// grows from round-off (summation order in the parallel assembly and the
/// sparse factorisation) through the physical instability of a membrane
/// in compression.
#[test]
fn lagrange_keeps_every_active_gap_closed_and_reports_symmetry() {
    for example in [
        "fabric-on-pedestal-lagrange.toml",
        "fabric-on-pedestal.toml",
    ] {
        let s = example_setup(example);
        let contact = s.model.contact().unwrap();
        let mut worst_gap = 0.0f64;
        let mut steps_with_contact = 0;
        let state = drive(&s, |st| {
            let cs = st.contact.as_ref().unwrap();
            if contact.method != ContactMethod::Lagrange {
                return;
            }
            let mut any = false;
            for (p, held) in cs.active.iter().enumerate() {
                if let Some((k, f)) = held {
                    any = true;
                    let y = [
                        st.positions[3 * p],
                        st.positions[3 * p + 1],
                        st.positions[3 * p + 2],
                    ];
                    let (prox, _) = contact.bodies[*k as usize].constraint(y, st.time, *f);
                    worst_gap = worst_gap.max(prox.gap.abs());
                    assert!(cs.multipliers[p] >= 0.0);
                }
            }
            steps_with_contact += usize::from(any);
        });
        if contact.method == ContactMethod::Lagrange {
            assert!(steps_with_contact > 400, "{steps_with_contact}");
            assert!(worst_gap <= 1e-9, "largest active gap {worst_gap:e} m");
        }
        let y = &state.positions;
        let rot = asymmetry(&s, y, |x| [-x[0], -x[1], x[2]]);
        let mirror = asymmetry(&s, y, |x| [x[1], x[0], x[2]]);
        eprintln!(
            "{example}: asymmetry at t = {:.4} s: rotation by 180 deg {rot:.3e} m, mirror x = y {mirror:.3e} m",
            state.time
        );
    }
}

#[test]
#[ignore = "exploration: growth of the asymmetry over the run"]
fn asymmetry_growth() {
    let s = example_setup("fabric-on-pedestal.toml");
    let mut k = 0;
    drive(&s, |st| {
        k += 1;
        if k % 20 == 0 {
            let rot = asymmetry(&s, &st.positions, |x| [-x[0], -x[1], x[2]]);
            let mirror = asymmetry(&s, &st.positions, |x| [x[1], x[0], x[2]]);
            eprintln!("t {:.5} rot {rot:.3e} mirror {mirror:.3e}", st.time);
        }
    });
}

fn patch_over(center: [f64; 2], method: &str) -> (drape::setup::Setup, Vec<f64>) {
    let contact = if method == "penalty" {
        "method = \"penalty\"\npenalty = 5.0e4"
    } else {
        "method = \"lagrange\""
    };
    let text = format!(
        r#"
[mesh]
shape = "rectangle"
size = [0.02, 0.02]
divisions = [8, 8]
center = [{}, {}, -0.0499]
[material]
youngs_modulus = 2.0e6
poisson_ratio = 0.3
density = 320.0
thickness = 0.6e-3
[[load]]
kind = "surface"
force = [0.0, 0.0, -1.8816]
[[obstacle]]
shape = "box"
min = [-0.05, -0.05, -0.25]
max = [0.05, 0.05, -0.05]
[contact]
{contact}
[time]
segments = [{{ steps = 60, dt = 1.0e-4 }}]
"#,
        center[0], center[1]
    );
    let s = setup(&text);
    let y = drive(&s, |_| {}).positions;
    (s, y)
}

/// A patch of fabric laid over an edge and over a corner of the pedestal
/// (the node at its centre exactly above the edge or corner), dropped the
/// last 0.1 mm: penalty and multipliers give the same motion — to the
/// penalty's penetration, ~1e-7 m here — because both see the same
/// contact surface: the box with edges rounded to 1e-3 of its smallest
/// side, where a node exactly above an edge meets the fillet at its outer
/// point, whose normal is horizontal: it gets no vertical support and
/// slides down the fillet, held by its neighbours. Over the edge it stays
/// on the fillet (gap 0); over the corner, pulled by neighbours on two
/// sides, it leaves it. It is never inside.
#[test]
fn node_on_an_edge_and_a_corner_behaves_the_same_with_both_methods() {
    for center in [[0.05, 0.0], [0.05, 0.05]] {
        let (sp, yp) = patch_over(center, "penalty");
        let (sl, yl) = patch_over(center, "lagrange");
        let diff = yp
            .iter()
            .zip(&yl)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            diff < 2e-6,
            "{center:?}: penalty and multipliers differ by {diff:e} m"
        );
        let (c, _) = sl
            .model
            .mesh()
            .nearest_node([center[0], center[1], -0.0499])
            .unwrap();
        let yc = [yl[3 * c], yl[3 * c + 1], yl[3 * c + 2]];
        let prox = sl.model.contact().unwrap().bodies[0].proximity(yc, 0.0, None);
        assert!(
            prox.gap >= -1e-9,
            "{center:?}: centre node gap {}",
            prox.gap
        );
        if center[1] == 0.0 {
            assert!(prox.gap.abs() < 1e-9, "edge: centre node gap {}", prox.gap);
        }
        assert!(
            yc[2] < -0.05 && yc[2] > -0.05 - 1e-4,
            "{center:?}: centre node at {yc:?}"
        );
        let _ = sp;
    }
}

fn drop_on(
    obstacle: &str,
    method: &str,
    mesh: &str,
) -> (Vec<String>, Vec<Vec<f64>>, drape::simulation::Summary) {
    let contact = if method == "penalty" {
        "method = \"penalty\"\npenalty = 5.0e4"
    } else {
        "method = \"lagrange\""
    };
    let text = format!(
        r#"
{mesh}
[material]
youngs_modulus = 2.0e6
poisson_ratio = 0.3
density = 320.0
thickness = 0.6e-3
[[load]]
kind = "surface"
force = [0.0, 0.0, -1.8816]
{obstacle}
[contact]
{contact}
[time]
segments = [{{ steps = 10, dt = 0.01 }}, {{ steps = 150, dt = 1.0e-4 }}]
[output]
every = 100000
[[monitor]]
name = "center"
at = [0.0, 0.0, 0.0]
"#
    );
    let s = setup(&text);
    let dir = temp_dir("drop");
    let summary = drape::simulation::run(&s, &dir, &mut |_| {}).unwrap();
    let (h, rows) = read_history(&dir);
    let _ = std::fs::remove_dir_all(&dir);
    (h, rows, summary)
}

/// A fabric dropped 5 cm onto a sphere and onto a cylindrical pedestal
/// (the drape tester), with both methods: every step converges without
/// cut-back in few Newton iterations (the curvature term of the sphere's
/// constraint keeps Newton quadratic), the centre node ends on the top of
/// the obstacle, nothing penetrates beyond the penalty's penetration, and
/// the resultant contact force is vertical (the problem is symmetric; the
/// horizontal part is round-off).
#[test]
fn fabric_on_a_sphere_and_on_a_cylinder() {
    let square = "[mesh]\nshape = \"rectangle\"\nsize = [0.2, 0.2]\ndivisions = [16, 16]\npattern = \"alternate\"";
    let disc = "[mesh]\nshape = \"disc\"\nradius = 0.15\nrings = 10";
    let sphere = "[[obstacle]]\nshape = \"sphere\"\ncenter = [0.0, 0.0, -0.1]\nradius = 0.05";
    let cylinder = "[[obstacle]]\nshape = \"cylinder\"\ncenter = [0.0, 0.0, -0.05]\naxis = [0.0, 0.0, 1.0]\nradius = 0.09\nheight = 0.2";
    for (obstacle, mesh, name) in [(sphere, square, "sphere"), (cylinder, disc, "cylinder")] {
        for method in ["penalty", "lagrange"] {
            let (h, rows, summary) = drop_on(obstacle, method, mesh);
            assert_eq!(summary.cutbacks, 0, "{name} {method}");
            let its = column(&h, &rows, "iterations");
            let max_its = its.iter().copied().fold(0.0, f64::max);
            assert!(
                max_its <= 8.0,
                "{name} {method}: {max_its} Newton iterations in a step"
            );
            let cz = summary.monitors["center"][2];
            let min_gap = column(&h, &rows, "min_gap")
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min);
            let f = column(&h, &rows, "contact_force");
            let fmax = f.iter().copied().fold(0.0, f64::max);
            if method == "penalty" {
                assert!((cz + 0.05).abs() <= fmax / 5e4, "{name}: centre {cz}");
                assert!(-min_gap <= fmax / 5e4, "{name}: penetration {min_gap}");
            } else {
                assert!((cz + 0.05).abs() < 1e-9, "{name}: centre {cz}");
                assert!(min_gap >= -1e-9, "{name}: penetration {min_gap}");
            }
            eprintln!(
                "{name} {method}: {} Newton iterations, max {max_its} per step, centre z {cz:.9}",
                summary.newton_iterations
            );
        }
    }
}

/// A fabric resting on a plane that moves up at 0.1 m/s: once the plane
/// has caught it and the transient has been damped, the fabric rides along
/// at the plane's speed and the contact force equals its weight (a
/// constant velocity needs no extra force).
#[test]
fn fabric_rides_on_a_moving_plane() {
    let weight = 1.8816 * 0.2 * 0.2;
    for method in ["penalty", "lagrange"] {
        let contact = if method == "penalty" {
            "method = \"penalty\"\npenalty = 5.0e4"
        } else {
            "method = \"lagrange\""
        };
        let text = fabric(&format!(
            r#"
[[load]]
kind = "surface"
force = [0.0, 0.0, -1.8816]
[[obstacle]]
shape = "plane"
point = [0.0, 0.0, -0.001]
normal = [0.0, 0.0, 1.0]
velocity = [0.0, 0.0, 0.1]
[contact]
{contact}
[time]
segments = [{{ steps = 200, dt = 1.0e-3 }}]
[output]
every = 100000
[[monitor]]
name = "center"
at = [0.0, 0.0, 0.0]
"#
        ))
        .replace("divisions = [20, 20]", "divisions = [8, 8]");
        let s = setup(&text);
        let dir = temp_dir("moving");
        drape::simulation::run(&s, &dir, &mut |_| {}).unwrap();
        let (h, rows) = read_history(&dir);
        let (t, z) = (column(&h, &rows, "time"), column(&h, &rows, "center_z"));
        let n = t.len();
        let v = (z[n - 1] - z[n - 11]) / (t[n - 1] - t[n - 11]);
        let force = *column(&h, &rows, "contact_force").last().unwrap();
        assert!((v - 0.1).abs() < 1e-6, "{method}: fabric speed {v}");
        assert!(
            (force - weight).abs() < 1e-3 * weight,
            "{method}: contact force {force}"
        );
        // The plane has reached z = -0.001 + 0.1 t; the fabric sits on it.
        let plane_z = -0.001 + 0.1 * t[n - 1];
        assert!(
            (z[n - 1] - plane_z).abs() < 1e-5,
            "{method}: fabric at {} vs plane at {plane_z}",
            z[n - 1]
        );
    }
}
