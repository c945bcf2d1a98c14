//! Static closed-form checks: patch test, rigid motion, uniaxial and
//! equibiaxial Saint-Venant–Kirchhoff stretch, and Newton's quadratic
//! convergence.

use drape::element::membrane::Section;

mod common;
use common::equilibrium_with;
use drape::material::SaintVenantKirchhoff;
use drape::mesh::generate::{Pattern, rectangle};
use drape::mesh::{ElementOrder, Mesh};
use drape::model::Model;

const ORDERS: [ElementOrder; 3] = [
    ElementOrder::Linear,
    ElementOrder::Quadratic,
    ElementOrder::Cubic,
];
const YOUNG: f64 = 2.0e6;
const NU: f64 = 0.3;
const T: f64 = 6e-4;

fn model(mesh: Mesh, fixed: Vec<bool>) -> Model {
    Model::builder(
        mesh,
        Box::new(SaintVenantKirchhoff::new(YOUNG, NU)),
        Section {
            thickness: T,
            prestress: 0.0,
        },
        320.0,
    )
    .fixed(fixed)
    .build()
    .unwrap()
}

/// Solves `F_int(Y) = 0` from `y0` with the fixed components held where
/// `y0` puts them, by plain Newton; returns the positions and Newton's
/// residual history.
fn equilibrium(model: &Model, y0: Vec<f64>) -> (Vec<f64>, Vec<f64>) {
    let (y, report, _) = equilibrium_with(model, y0, 0);
    (y, report.residuals)
}

/// A distorted rectangle: interior nodes moved in-plane by up to 20 % of
/// the element size, so that the patch test is not passed by symmetry.
fn distorted(order: ElementOrder) -> Mesh {
    let mut mesh = rectangle([1.0, 0.8], [4, 3], Pattern::Alternate, [0.0; 3], order);
    if order == ElementOrder::Linear {
        let boundary = mesh.boundary_nodes();
        for (i, x) in mesh.nodes.iter_mut().enumerate() {
            if boundary.binary_search(&i).is_err() {
                x[0] += 0.05 * (i as f64 * 1.7).sin();
                x[1] += 0.05 * (i as f64 * 2.3).cos();
            }
        }
    }
    mesh
}

/// Patch test: with the boundary placed on a uniform in-plane stretch `Y =
/// F0 X` and the interior started off it, equilibrium puts every interior
/// node back on `F0 X` to solver precision (for every order).
#[test]
fn patch_test_uniform_stretch_is_reproduced_exactly() {
    let f0 = [[1.12, 0.04], [0.03, 1.07]];
    for order in ORDERS {
        let mesh = distorted(order);
        let boundary = mesh.boundary_nodes();
        let mut fixed = vec![false; 3 * mesh.node_count()];
        let exact: Vec<f64> = mesh
            .nodes
            .iter()
            .flat_map(|x| {
                [
                    f0[0][0] * x[0] + f0[0][1] * x[1],
                    f0[1][0] * x[0] + f0[1][1] * x[1],
                    0.0,
                ]
            })
            .collect();
        for &b in &boundary {
            fixed[3 * b..3 * b + 3].fill(true);
        }
        for i in 0..mesh.node_count() {
            fixed[3 * i + 2] = true; // a flat patch: in-plane problem
        }
        let m = model(mesh, fixed);
        let mut y0 = exact.clone();
        for i in 0..m.mesh().node_count() {
            if boundary.binary_search(&i).is_err() {
                y0[3 * i] += 0.02 * (i as f64).sin();
                y0[3 * i + 1] -= 0.015 * (i as f64).cos();
            }
        }
        let (y, _) = equilibrium(&m, y0);
        let err = y
            .iter()
            .zip(&exact)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        // Newton's tolerance 1e-12 relative to |X| ~ 3 m.
        assert!(
            err < 1e-10,
            "{order:?}: interior off the uniform stretch by {err:e} m"
        );
    }
}

/// Rigid translation and a large rotation give zero strain energy and zero
/// internal force, for every order, on a curved mesh.
#[test]
fn rigid_motion_gives_zero_strain_and_force() {
    for order in ORDERS {
        let mut mesh = rectangle([0.3, 0.2], [3, 2], Pattern::Right, [0.0; 3], order);
        for x in &mut mesh.nodes {
            x[2] = 0.4 * x[0] * x[0] - 0.3 * x[1] * x[0];
        }
        let n = mesh.node_count();
        let m = model(mesh, vec![]);
        // Rotation by 75 degrees about the unit axis (1, 2, 2)/3, then a translation.
        let (a, th) = ([1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0], 75f64.to_radians());
        let (c, s) = (th.cos(), th.sin());
        let r = |v: [f64; 3]| {
            let d = a[0] * v[0] + a[1] * v[1] + a[2] * v[2];
            let x = [
                a[1] * v[2] - a[2] * v[1],
                a[2] * v[0] - a[0] * v[2],
                a[0] * v[1] - a[1] * v[0],
            ];
            [0, 1, 2].map(|i| v[i] * c + x[i] * s + a[i] * d * (1.0 - c))
        };
        let y: Vec<f64> = m
            .mesh()
            .nodes
            .iter()
            .flat_map(|x| {
                let v = r(*x);
                [v[0] + 0.7, v[1] - 1.1, v[2] + 2.5]
            })
            .collect();
        let mut fi = vec![0.0; 3 * n];
        let u = m.assemble(&y, &mut fi, None);
        let fmax = fi.iter().fold(0.0f64, |acc, v| acc.max(v.abs()));
        // Scale: E t L ~ 2e6 * 6e-4 * 0.3 = 360 N; round-off ~1e-16 of it times the nodes.
        assert!(u.abs() < 1e-16, "{order:?}: strain energy {u:e} J");
        assert!(fmax < 1e-10, "{order:?}: internal force {fmax:e} N");
    }
}

/// A strip `L x W` stretched to `lambda L`, ends held in x, free across:
/// the closed form of plane-stress SVK is `S11 = E (lambda^2 - 1) / 2`,
/// `S22 = 0`, transverse stretch `sqrt(1 - nu (lambda^2 - 1))`, and an end
/// force `lambda S11 t W`. Equibiaxial `lambda` in both directions:
/// `S11 = S22 = E / (1 - nu) (lambda^2 - 1) / 2`, edge force `lambda S t L`.
#[test]
fn uniaxial_and_equibiaxial_stretch_match_the_closed_form() {
    let (l, w) = (0.4, 0.1);
    for order in ORDERS {
        for (lambda, biaxial) in [(1.5, false), (1.3, true), (0.9, false)] {
            if lambda < 1.0 && order != ElementOrder::Linear {
                continue;
            }
            let mesh = rectangle(
                [l, w],
                [8, 2],
                Pattern::Alternate,
                [0.5 * l, 0.5 * w, 0.0],
                order,
            );
            let nn = mesh.node_count();
            let mut fixed = vec![false; 3 * nn];
            let mut y0 = vec![0.0; 3 * nn];
            let tol = 1e-12;
            for (i, x) in mesh.nodes.iter().enumerate() {
                y0[3 * i] = lambda * x[0];
                y0[3 * i + 1] = if biaxial { lambda * x[1] } else { x[1] };
                fixed[3 * i + 2] = true;
                if x[0] < tol || x[0] > l - tol {
                    fixed[3 * i] = true;
                }
                if biaxial && (x[1] < tol || x[1] > w - tol) {
                    fixed[3 * i + 1] = true;
                }
            }
            // Rigid motion across the strip is blocked at one node.
            fixed[1] = true;
            let m = model(mesh, fixed);
            let (y, _) = equilibrium(&m, y0);
            let e11 = 0.5 * (lambda * lambda - 1.0);
            let results = m.element_results(&y);
            let (s11, s22) = if biaxial {
                (YOUNG / (1.0 - NU) * e11, YOUNG / (1.0 - NU) * e11)
            } else {
                (YOUNG * e11, 0.0)
            };
            for s in &results.stress {
                // The local frame's e1 is along x for these elements'
                // first edges (v0 -> v1 is along +x or the diagonal): rotate.
                let (p1, p2) = drape::element::membrane::principal_values(*s);
                let (big, small) = (s11.max(s22), s11.min(s22));
                assert!(
                    (p1 - big).abs() < 1e-8 * YOUNG,
                    "{order:?} {lambda}: {p1} vs {big}"
                );
                assert!(
                    (p2 - small).abs() < 1e-8 * YOUNG,
                    "{order:?} {lambda}: {p2} vs {small}"
                );
            }
            // End force: sum of internal forces on the nodes at x = L.
            let nn = m.mesh().node_count();
            let mut fi = vec![0.0; 3 * nn];
            m.assemble(&y, &mut fi, None);
            let end: f64 = (0..nn)
                .filter(|&i| m.mesh().nodes[i][0] > l - 1e-12)
                .map(|i| fi[3 * i])
                .sum();
            let expected = lambda * s11 * T * w;
            assert!(
                (end - expected).abs() < 1e-8 * expected.abs(),
                "{order:?} {lambda}: end force {end} vs {expected}"
            );
            if !biaxial {
                let width_stretch = (1.0 - NU * (lambda * lambda - 1.0)).sqrt();
                let top = (0..nn)
                    .find(|&i| m.mesh().nodes[i][1] > w - 1e-12 && m.mesh().nodes[i][0] > 0.4 * l)
                    .unwrap();
                let bottom = (0..nn)
                    .find(|&i| {
                        m.mesh().nodes[i][1] < 1e-12
                            && (m.mesh().nodes[i][0] - m.mesh().nodes[top][0]).abs() < 1e-12
                    })
                    .unwrap();
                let width = y[3 * top + 1] - y[3 * bottom + 1];
                assert!(
                    (width - width_stretch * w).abs() < 1e-10,
                    "{order:?}: width {width} vs {}",
                    width_stretch * w
                );
            }
        }
    }
}

/// Newton converges quadratically on a smooth problem: the estimated order
/// `log(r_{k+1}/r_k) / log(r_k/r_{k-1})` of the residuals above round-off
/// approaches 2 (asserted > 1.8 on the last estimate).
#[test]
fn newton_converges_quadratically() {
    let (m, y0) = stretched_strip();
    let (_, r) = equilibrium(&m, y0);
    let r0 = r[0];
    let useful: Vec<f64> = r.iter().copied().filter(|&x| x > 1e-11 * r0).collect();
    assert!(useful.len() >= 4, "too few iterations to judge: {r:?}");
    let orders: Vec<f64> = useful
        .windows(3)
        .map(|w| (w[2] / w[1]).ln() / (w[1] / w[0]).ln())
        .collect();
    let last = *orders.last().unwrap();
    assert!(
        last > 1.8,
        "convergence orders {orders:?} (residuals {r:?})"
    );
}

/// The stretched strip of `newton_converges_quadratically`: quadratic
/// elements, stretched to 1.5 times its length, held at both ends.
fn stretched_strip() -> (Model, Vec<f64>) {
    let mesh = rectangle(
        [0.4, 0.1],
        [8, 2],
        Pattern::Alternate,
        [0.2, 0.05, 0.0],
        ElementOrder::Quadratic,
    );
    let nn = mesh.node_count();
    let mut fixed = vec![false; 3 * nn];
    let mut y0 = vec![0.0; 3 * nn];
    for (i, x) in mesh.nodes.iter().enumerate() {
        y0[3 * i] = 1.5 * x[0];
        y0[3 * i + 1] = x[1];
        fixed[3 * i + 2] = true;
        if x[0] < 1e-12 || x[0] > 0.4 - 1e-12 {
            fixed[3 * i] = true;
        }
    }
    fixed[1] = true;
    (model(mesh, fixed), y0)
}

/// Chord steps (Shamanskii's method) reach the same equilibrium as plain
/// Newton, to the tolerance (1e-12 of the reference length, so 1e-10 m
/// allows for the two iterations stopping at different points below it),
/// with fewer factorisations: near the solution a solve with the last
/// factor gains nearly as much as a new Newton step.
#[test]
fn chord_steps_reach_the_same_solution_with_fewer_factorisations() {
    let (m, y0) = stretched_strip();
    let (y_newton, newton, f_newton) = equilibrium_with(&m, y0.clone(), 0);
    let (y_chord, chord, f_chord) = equilibrium_with(&m, y0, 2);
    let diff = y_newton
        .iter()
        .zip(&y_chord)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-10, "solutions differ by {diff:e} m");
    assert_eq!(newton.chord_steps, 0);
    assert!(chord.chord_steps >= 1, "{chord:?}");
    assert!(
        f_chord < f_newton,
        "factorisations: chord {f_chord}, Newton {f_newton} ({chord:?})"
    );
    // The residual still falls at every accepted step.
    assert!(chord.residuals.windows(2).all(|w| w[1] < w[0]), "{chord:?}");
    eprintln!("factorisations: Newton {f_newton}, with chord steps {f_chord}; {chord:?}");
}
