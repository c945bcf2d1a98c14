//! Mass, free fall, energy behaviour of Newmark, and the assembled Hessian.

mod common;

use common::{column, fabric, read_history, setup, temp_dir};
use drape::fd::jacobian_error;
use drape::integrator::Newmark;
use drape::integrator::newmark::DynamicWorkspace;
use drape::load::{Load, LoadKind};
use drape::mesh::generate::{Pattern, rectangle};
use drape::mesh::{ElementOrder, Mesh};
use drape::model::{MassKind, Model};
use drape::simulation::{reference_length, run};
use drape::solver::NewtonSettings;

fn model(mesh: Mesh, loads: Vec<Load>, fixed: Vec<bool>, mass: MassKind) -> Model {
    common::fabric_model(mesh)
        .loads(loads)
        .fixed(fixed)
        .mass(mass)
        .build()
        .unwrap()
}

/// Consistent T3 mass: `rho t A / 12 [[2, 1, 1], [1, 2, 1], [1, 1, 2]]`
/// (each block times I3); lumped: `rho t A / 3` on the diagonal.
#[test]
fn t3_mass_matrices_match_the_closed_form() {
    let mesh = Mesh {
        nodes: vec![[0.0, 0.0, 0.0], [0.3, 0.1, 0.05], [0.05, 0.2, -0.02]],
        order: ElementOrder::Linear,
        connectivity: vec![0, 1, 2],
    };
    let area: f64 = {
        let (u, v): ([f64; 3], [f64; 3]) = ([0.3, 0.1, 0.05], [0.05, 0.2, -0.02]);
        let c = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
    };
    let rho_t = 320.0 * 6e-4;
    for kind in [MassKind::Consistent, MassKind::Lumped] {
        let m = model(mesh.clone(), vec![], vec![], kind);
        for b in 0..3 {
            for j in 0..3 {
                let mut e = vec![0.0; 9];
                e[3 * b + j] = 1.0;
                let mut col = vec![0.0; 9];
                m.mass_times(&e, &mut col);
                for a in 0..3 {
                    for i in 0..3 {
                        let expected = match kind {
                            MassKind::Consistent if i == j => {
                                rho_t * area / 12.0 * if a == b { 2.0 } else { 1.0 }
                            }
                            MassKind::Lumped if i == j && a == b => rho_t * area / 3.0,
                            _ => 0.0,
                        };
                        assert!(
                            (col[3 * a + i] - expected).abs() < 1e-15,
                            "{kind:?} ({a},{i}),({b},{j})"
                        );
                    }
                }
            }
        }
    }
}

/// A free membrane under a uniform load falls exactly as `z = -g t^2 / 2`,
/// `v = -g t`, for any Newmark parameters, when `A_0 = M^-1 (F_ext - F_int)`
/// (consistent mass and consistent loads give a uniform `A_0 = -g`).
#[test]
fn free_fall_is_exact_for_any_newmark_parameters() {
    let q = 1.8816;
    let g = q / (320.0 * 6e-4);
    for order in [
        ElementOrder::Linear,
        ElementOrder::Quadratic,
        ElementOrder::Cubic,
    ] {
        for (beta, gamma) in [(0.25, 0.5), (1.0, 1.5), (0.3025, 0.6), (0.5, 0.5)] {
            let mesh = rectangle([0.2, 0.2], [4, 4], Pattern::Alternate, [0.0; 3], order);
            let m = model(
                mesh,
                vec![Load {
                    kind: LoadKind::Surface {
                        force: [0.0, 0.0, -q],
                    },
                    ramp: None,
                }],
                vec![],
                MassKind::Consistent,
            );
            let newmark = Newmark { beta, gamma };
            let mut ws = DynamicWorkspace::new(&m).unwrap();
            let mut state = newmark.initial_state(&m, &mut ws).unwrap();
            let length = reference_length(&m.initial_positions());
            let dt = 0.01;
            for _ in 0..10 {
                newmark
                    .step(
                        &m,
                        &mut state,
                        dt,
                        &NewtonSettings::default(),
                        length,
                        &mut ws,
                    )
                    .unwrap();
                // The acceleration persists (to round-off), so the
                // predictor stays the exact constant-acceleration one.
                assert!(1.0 - state.persistence < 1e-12, "{order:?} beta {beta}");
            }
            let t = state.time;
            for (i, x) in m.mesh().nodes.iter().enumerate() {
                let z = state.positions[3 * i + 2];
                assert!(
                    (z - (x[2] - 0.5 * g * t * t)).abs() < 1e-13,
                    "{order:?} beta {beta}: z {z}"
                );
                assert!((state.velocities[3 * i + 2] + g * t).abs() < 1e-12);
                assert!((state.positions[3 * i] - x[0]).abs() < 1e-14);
            }
        }
    }
}

/// The assembled Hessian (internal forces, follower pressure, on the
/// sparse pattern through the scatter map) equals the derivative of the
/// assembled residual `F_int - F_p`.
#[test]
fn assembled_hessian_matches_finite_differences_of_the_residual() {
    for order in [ElementOrder::Linear, ElementOrder::Quadratic] {
        let mesh = rectangle([0.2, 0.1], [3, 2], Pattern::Alternate, [0.0; 3], order);
        let n = 3 * mesh.node_count();
        let m = model(
            mesh,
            vec![Load {
                kind: LoadKind::Pressure { value: 40.0 },
                ramp: None,
            }],
            vec![],
            MassKind::Consistent,
        );
        let y0: Vec<f64> = m
            .initial_positions()
            .iter()
            .enumerate()
            .map(|(i, x)| 1.1 * x + 0.01 * ((i * 7) as f64).sin())
            .collect();
        let residual = |y: &[f64]| {
            let (mut fi, mut fe) = (vec![0.0; n], vec![0.0; n]);
            m.assemble(y, &mut fi, None);
            m.add_pressure(y, 40.0, &mut fe, None);
            fi.iter().zip(&fe).map(|(a, b)| a - b).collect::<Vec<f64>>()
        };
        let dense = |y: &[f64]| {
            let (mut fi, mut fe) = (vec![0.0; n], vec![0.0; n]);
            let mut h = vec![0.0; m.pattern().nnz()];
            m.assemble(y, &mut fi, Some(&mut h));
            m.add_pressure(y, 40.0, &mut fe, Some(&mut h));
            let mut d = vec![0.0; n * n];
            for c in 0..n {
                for k in m.pattern().col_ptr[c]..m.pattern().col_ptr[c + 1] {
                    d[m.pattern().row_idx[k] * n + c] = h[k];
                }
            }
            d
        };
        let e = jacobian_error(residual, dense, &y0, 1e-7);
        assert!(e < 1e-6, "{order:?}: {e:e}");
    }
}

/// The hanging cloth's weight and pins, and a single output frame.
const PINNED_UNDER_WEIGHT: &str = r#"
[[load]]
kind = "surface"
force = [0.0, 0.0, -1.8816]
[[fix]]
at = [-0.1, 0.1, 0.0]
[[fix]]
at = [0.1, 0.1, 0.0]
[output]
every = 1000
"#;

/// Hanging cloth (the example): trapezoidal rule over the first 0.2 s
/// keeps the total energy `K + U - W` within 1 % of the work done by the
/// weight (the trapezoidal rule conserves energy exactly only for linear
/// problems; for this geometrically nonlinear one the error is O(dt^2)),
/// while `beta = 1, gamma = 1.5` dissipates it at every step (0.25 s).
///
/// Why the undamped run stops at 0.2 s (the energy is checked over the
/// part of the swing that stays clear of compression past the stretch
/// 1/sqrt(3), docs/theory.md §1.3): the
/// trapezoidal rule keeps the high frequencies that the swing excites, and
/// from about 0.2 s Newton needs 10 to 26 iterations per step and the path
/// depends on round-off — two builds that differ only in the order in
/// which element forces are summed agree to 4e-7 in kinetic energy at
/// 0.2 s, to 1e-4 at 0.21 s, and then one of them drives an element past
/// SVK's compressive instability at 0.235 s, the other at about 0.30 s.
#[test]
fn hanging_cloth_energy_trapezoidal_conserves_damped_decays() {
    let pins = PINNED_UNDER_WEIGHT;
    for (beta, gamma, steps) in [(0.25, 0.5, 200), (1.0, 1.5, 250)] {
        let text = fabric(&format!(
            "{pins}\n[time]\nbeta = {beta}\ngamma = {gamma}\nsegments = [{{ steps = {steps}, dt = 1.0e-3 }}]\n"
        ));
        let s = setup(&text);
        let dir = temp_dir(&format!("hanging-{beta}"));
        run(&s, &dir, &mut |_| {}).unwrap();
        let (h, rows) = read_history(&dir);
        let total = column(&h, &rows, "total_energy");
        let work = column(&h, &rows, "external_work");
        let w_max = work.iter().fold(0.0f64, |a, w| a.max(w.abs()));
        if beta == 0.25 {
            let drift = total.iter().fold(0.0f64, |a, e| a.max(e.abs()));
            eprintln!("trapezoidal: max |K + U - W| = {drift:e} J, W = {w_max:e} J");
            assert!(
                drift < 0.01 * w_max,
                "drift {drift:e} J vs work {w_max:e} J"
            );
        } else {
            for k in 1..total.len() {
                // Round-off allowance: 1e-12 of the work.
                assert!(
                    total[k] <= total[k - 1] + 1e-12 * w_max,
                    "energy rose at step {k}: {} -> {}",
                    total[k - 1],
                    total[k]
                );
            }
            assert!(total.last().unwrap() < &(-0.01 * w_max));
        }
    }
}

/// A cantilever strip with bending (10 x 2 cm, B = 1e-3 N m, held by its
/// first two node columns, released flat under its weight) swinging for
/// a quarter second with the trapezoidal rule: the energy balance `K +
/// U_membrane + U_bending - W` holds to O(dt^2) — its largest drift
/// shrinks about fourfold when the step is halved (between 2.5 and 6
/// times: the rate's constant moves with the amplitude) and stays below
/// 2 % of the work at 1 ms — while the bending energy is a fifth or more
/// of that work: a balance that left bending out (as `strain_energy` did
/// before, issue 31) would be off by it. The history's parts sum to its
/// `strain_energy` in every row.
#[test]
fn bending_energy_is_in_the_balance_and_conserved() {
    let mut drifts = Vec::new();
    for dt in [2.0e-3, 1.0e-3] {
        let steps = (0.25 / dt) as usize;
        let text = common::rectangle(
            [0.1, 0.02],
            [20, 4],
            &format!(
                r#"bending_rigidity = 1.0e-3
[[load]]
kind = "gravity"
acceleration = [0.0, 0.0, -9.8]
[[fix]]
within = {{ min = [-0.051, -0.011, -0.001], max = [-0.0449, 0.011, 0.001] }}
[time]
beta = 0.25
gamma = 0.5
segments = [{{ steps = {steps}, dt = {dt} }}]
[solver]
tolerance = 1e-10
[output]
every = 10000
"#
            ),
        );
        let dir = temp_dir(&format!("bending-energy-{dt}"));
        run(&setup(&text), &dir, &mut |_| {}).unwrap();
        let (h, rows) = read_history(&dir);
        let total = column(&h, &rows, "total_energy");
        let work = column(&h, &rows, "external_work");
        let strain = column(&h, &rows, "strain_energy");
        let membrane = column(&h, &rows, "membrane_energy");
        let bending = column(&h, &rows, "bending_energy");
        for k in 0..rows.len() {
            assert_eq!(membrane[k] + bending[k], strain[k], "row {k}");
        }
        let w_max = work.iter().fold(0.0f64, |a, w| a.max(w.abs()));
        let b_max = bending.iter().fold(0.0f64, |a, b| a.max(*b));
        assert!(
            b_max > 0.2 * w_max,
            "bending {b_max:e} J of work {w_max:e} J"
        );
        let drift = total.iter().fold(0.0f64, |a, e| a.max(e.abs()));
        eprintln!(
            "dt = {dt}: max |K + U - W| = {drift:e} J, W = {w_max:e} J, max U_b = {b_max:e} J"
        );
        drifts.push((drift, w_max));
    }
    let ratio = drifts[0].0 / drifts[1].0;
    assert!(
        (2.5..6.0).contains(&ratio),
        "drift ratio {ratio} for dt / 2"
    );
    assert!(drifts[1].0 < 0.02 * drifts[1].1, "{drifts:?}");
}

/// The linear-solver modes give the same motion to the Newton tolerance
/// (issue 7): a 30 x 30 hanging cloth with the stress-projection wrinkling
/// model (non-symmetric Hessians), 150 steps of 0.1 ms (the pedestal's
/// fine phase; the cloth stretches and wrinkles around its pins), solved with `direct` (node-block LU, as 2,883 unknowns
/// are below its limit), `iterative` (multigrid GMRES / CG, two levels)
/// and `reuse` (GMRES with a reused Cholesky factor). Each step's solution
/// is fixed to `tolerance * |X|` (1e-8 x 2.5 m); 150 steps of damped
/// dynamics (beta = 1) cannot take the runs further apart than 150 times
/// that, 4e-6 m.
#[test]
fn linear_solver_modes_agree_to_the_newton_tolerance() {
    let scenario = |linear: &str| {
        fabric(&format!(
            r#"wrinkling = "stress-projection"
{PINNED_UNDER_WEIGHT}
[time]
segments = [{{ steps = 150, dt = 1.0e-4 }}]
[solver]
linear = "{linear}"
[[monitor]]
name = "free_corner"
at = [0.1, -0.1, 0.0]
[[monitor]]
name = "center"
at = [0.0, 0.0, 0.0]
"#
        ))
        .replace("divisions = [20, 20]", "divisions = [30, 30]")
    };
    let mut results = Vec::new();
    for linear in ["direct", "iterative", "reuse"] {
        let s = setup(&scenario(linear));
        let dir = temp_dir(&format!("modes-{linear}"));
        let summary = run(&s, &dir, &mut |_| {}).unwrap();
        eprintln!(
            "{linear}: {} Newton iterations, {:?}, corner {:?}",
            summary.newton_iterations, summary.linear, summary.monitors["free_corner"]
        );
        results.push((linear, summary));
    }
    let (_, reference) = &results[0];
    assert!(reference.linear.block_lu_factorizations > 0);
    assert!(results[1].1.linear.multigrid_builds > 0);
    // The cloth has moved (15 ms of fall, ~1 mm at the free corner) and
    // Newton has worked (more than one iteration in some steps).
    assert!(reference.monitors["free_corner"][2] < -5e-4);
    assert!(reference.newton_iterations > 150);
    for (linear, summary) in &results[1..] {
        for name in ["free_corner", "center"] {
            let (a, b) = (reference.monitors[name], summary.monitors[name]);
            let d = (0..3).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max);
            assert!(d < 4e-6, "{linear} {name}: {d:e} m from direct");
        }
    }
}
