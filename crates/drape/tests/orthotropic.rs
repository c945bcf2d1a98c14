//! The orthotropic (woven) membrane, issue 21: uniaxial tension along the
//! warp, the weft and off-axis against the closed-form moduli and Poisson
//! ratios, the picture-frame shear modulus, the isotropic limit, frame and
//! node-numbering invariance, finite-difference checks of the element
//! force and Hessian in every wrinkling state and warp orientation, and
//! bad input.

mod common;

use common::{
    assert_error, build, equilibrium_with, read_history, setup, sheared_equilibrium, temp_dir,
};
use drape::element::ElementGeometry;
use drape::element::membrane::{Section, element_energy, element_force_hessian};
use drape::fd::{gradient_error, jacobian_error};
use drape::material::{Material, Orthotropic, WrinkleState, WrinklingModel};
use drape::mesh::generate::{Pattern, rectangle};
use drape::mesh::{ElementOrder, Mesh};
use drape::model::Model;
use drape::quadrature::QuadratureRule;

const E1: f64 = 5.0e6;
const E2: f64 = 1.0e6;
const G12: f64 = 5.0e4;
const NU12: f64 = 0.3;
const T: f64 = 6e-4;
const SECTION: Section = Section {
    thickness: T,
    prestress: 0.0,
};

fn fabric(warp: [f64; 3]) -> Orthotropic {
    Orthotropic::new(E1, E2, G12, NU12, warp).unwrap()
}

fn model(mesh: Mesh, material: Box<dyn Material>, fixed: Vec<bool>) -> Model {
    Model::builder(mesh, material, SECTION, 320.0)
        .fixed(fixed)
        .build()
        .unwrap()
}

/// The uniaxial modulus at `phi` from the warp:
/// `1 / E(phi) = c^4 / E1 + s^4 / E2 + c^2 s^2 (1 / G12 - 2 nu12 / E1)`.
fn modulus_at(phi: f64) -> f64 {
    let (s, c) = phi.sin_cos();
    1.0 / (c.powi(4) / E1 + s.powi(4) / E2 + c * c * s * s * (1.0 / G12 - 2.0 * NU12 / E1))
}

/// A strip along x (0.4 m x 0.1 m) with the warp at `phi` to it, its ends
/// held along x at a small stretch `1 + eps` and free across (one node
/// held across, z held everywhere): uniaxial stress along x, whatever the
/// coupling of stretch and shear off the axes. Returns the measured
/// modulus (end force / (t w eps)) and the lateral contraction `-eps_yy /
/// eps`.
fn uniaxial(phi: f64, order: ElementOrder) -> (f64, f64) {
    let (l, w, eps) = (0.4, 0.1, 1e-6);
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
    for (i, x) in mesh.nodes.iter().enumerate() {
        y0[3 * i] = (1.0 + eps) * x[0];
        y0[3 * i + 1] = x[1];
        fixed[3 * i + 2] = true;
        if x[0] < 1e-12 || x[0] > l - 1e-12 {
            fixed[3 * i] = true;
        }
    }
    fixed[1] = true;
    let m = model(mesh, Box::new(fabric([phi.cos(), phi.sin(), 0.0])), fixed);
    let (y, _, _) = equilibrium_with(&m, y0, 0);
    let mut f = vec![0.0; 3 * nn];
    m.assemble(&y, &mut f, None);
    let nodes = &m.mesh().nodes;
    let end: f64 = (0..nn)
        .filter(|&i| nodes[i][0] > l - 1e-12)
        .map(|i| f[3 * i])
        .sum();
    // Width at mid-length: top minus bottom node at the same x.
    let top = (0..nn)
        .find(|&i| nodes[i][1] > w - 1e-12 && (nodes[i][0] - 0.2).abs() < 1e-12)
        .unwrap();
    let bottom = (0..nn)
        .find(|&i| nodes[i][1] < 1e-12 && (nodes[i][0] - 0.2).abs() < 1e-12)
        .unwrap();
    let width = y[3 * top + 1] - y[3 * bottom + 1];
    (end / (T * w * eps), -(width / w - 1.0) / eps)
}

/// Uniaxial tension along the warp, along the weft, at 45 and 30 degrees:
/// the measured modulus is E1, E2, `E45 = 1 / (1/4 (1/E1 + 1/E2 + 1/G12 -
/// 2 nu12 / E1))` and `E(30)` within 1e-4 (the issue asks 1 %; the rest is
/// the geometric nonlinearity of a 1e-6 stretch and round-off), and the
/// lateral contraction is nu12 along the warp, `nu21 = nu12 E2 / E1` along
/// the weft. Linear and quadratic triangles.
#[test]
fn uniaxial_tension_gives_the_moduli_and_poisson_ratios() {
    use std::f64::consts::PI;
    let e45 = 1.0 / (0.25 * (1.0 / E1 + 1.0 / E2 + 1.0 / G12 - 2.0 * NU12 / E1));
    assert!((modulus_at(PI / 4.0) - e45).abs() < 1e-9 * e45);
    for order in [ElementOrder::Linear, ElementOrder::Quadratic] {
        for (phi, expected, contraction) in [
            (0.0, E1, Some(NU12)),
            (PI / 2.0, E2, Some(NU12 * E2 / E1)),
            (PI / 4.0, e45, None),
            (PI / 6.0, modulus_at(PI / 6.0), None),
            (-PI / 3.0, modulus_at(PI / 3.0), None),
        ] {
            let (modulus, nu) = uniaxial(phi, order);
            eprintln!(
                "{order:?} phi = {:.0} deg: modulus {modulus:.6e} Pa vs {expected:.6e} ({:+.2e}), contraction {nu:.6}",
                phi.to_degrees(),
                modulus / expected - 1.0
            );
            assert!(
                (modulus / expected - 1.0).abs() < 1e-4,
                "{order:?} phi {phi}: modulus {modulus} vs {expected}"
            );
            if let Some(c) = contraction {
                assert!(
                    (nu - c).abs() < 1e-4 * c.max(0.1),
                    "{order:?} phi {phi}: nu {nu} vs {c}"
                );
            }
        }
    }
}

/// Picture-frame shear: the boundary of a 10 cm square held on a simple
/// shear `x += gamma y` (gamma = 1e-6, warp along x or along y): every
/// element's shear stress (in the warp's frame) is `G12 gamma` within 1e-6,
/// and the force on the top edge is `G12 gamma t L`.
#[test]
fn picture_frame_shear_gives_the_shear_modulus() {
    let (size, gamma) = (0.1, 1e-6);
    for warp in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        let mesh = rectangle(
            [size, size],
            [5, 5],
            Pattern::Alternate,
            [0.5 * size, 0.5 * size, 0.0],
            ElementOrder::Linear,
        );
        let nn = mesh.node_count();
        let boundary = mesh.boundary_nodes();
        let mut fixed = vec![false; 3 * nn];
        let mut y0 = vec![0.0; 3 * nn];
        for (i, x) in mesh.nodes.iter().enumerate() {
            y0[3 * i] = x[0] + gamma * x[1];
            y0[3 * i + 1] = x[1];
            fixed[3 * i + 2] = true;
            if boundary.binary_search(&i).is_ok() {
                fixed[3 * i] = true;
                fixed[3 * i + 1] = true;
            }
        }
        let m = model(mesh, Box::new(fabric(warp)), fixed);
        let (y, _, _) = equilibrium_with(&m, y0, 0);
        let worst = m
            .element_results(&y)
            .stress
            .iter()
            .map(|s| (s[2].abs() / (G12 * gamma) - 1.0).abs())
            .fold(0.0, f64::max);
        eprintln!("warp {warp:?}: |S12 / (G12 gamma) - 1| <= {worst:.1e} over the elements");
        for s in m.element_results(&y).stress {
            // The frame's second axis is the warp turned by +90 degrees
            // about the normal, so the shear stress has the same sign in
            // both frames only up to the normal's orientation: compare
            // magnitudes.
            assert!(
                (s[2].abs() / (G12 * gamma) - 1.0).abs() < 1e-6,
                "warp {warp:?}: S12 {} vs {}",
                s[2],
                G12 * gamma
            );
        }
        let mut f = vec![0.0; 3 * nn];
        m.assemble(&y, &mut f, None);
        let top: f64 = (0..nn)
            .filter(|&i| m.mesh().nodes[i][1] > size - 1e-12)
            .map(|i| f[3 * i])
            .sum();
        // Corner nodes carry part of the side's force too: the top edge's
        // nodes, corners included, carry the shear flow along the edge
        // plus half the side edges' share at the corners, which cancels
        // in the sum over the top.
        eprintln!(
            "warp {warp:?}: top edge force / (G12 gamma t L) = {:.6}",
            top / (G12 * gamma * T * size)
        );
        assert!(
            (top / (G12 * gamma * T * size) - 1.0).abs() < 1e-3,
            "warp {warp:?}: top force {top} vs {}",
            G12 * gamma * T * size
        );
    }
}

/// Rotating the mesh and the warp direction together rotates the
/// solution: a membrane in a tilted plane, its boundary held on a stretch
/// with a wave out of plane, relaxed to equilibrium, and the same problem
/// turned by a rotation R in space; the interior nodes agree after R to
/// 1e-10 m, with and without wrinkling.
#[test]
fn rotating_mesh_and_warp_together_rotates_the_solution() {
    let r = rotation([0.3, -0.5, 0.8], 1.1);
    let apply = |v: [f64; 3]| [0, 1, 2].map(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2]);
    let warp = [0.8, 0.6, 0.0];
    for wrinkling in [None, Some(WrinklingModel::StressProjection)] {
        let solve = |turn: bool| {
            let mut mesh = rectangle(
                [0.2, 0.1],
                [6, 3],
                Pattern::Alternate,
                [0.0; 3],
                ElementOrder::Quadratic,
            );
            let nn = mesh.node_count();
            let boundary = mesh.boundary_nodes();
            let mut y0 = vec![0.0; 3 * nn];
            let mut fixed = vec![false; 3 * nn];
            for (i, x) in mesh.nodes.iter().enumerate() {
                // Stretched along x, squeezed across (wrinkles), waved.
                let y = [1.02 * x[0], 0.97 * x[1], 0.01 * (20.0 * x[0]).sin()];
                let y = if turn { apply(y) } else { y };
                y0[3 * i..3 * i + 3].copy_from_slice(&y);
                if boundary.binary_search(&i).is_ok() {
                    fixed[3 * i..3 * i + 3].fill(true);
                }
            }
            if turn {
                for x in &mut mesh.nodes {
                    *x = apply(*x);
                }
            }
            let w = if turn { apply(warp) } else { warp };
            let material = match wrinkling {
                None => fabric(w),
                Some(model) => fabric(w).with_wrinkling(model, 0.0),
            };
            let m = model(mesh, Box::new(material), fixed);
            let (y, _, _) = equilibrium_with(&m, y0, 0);
            y
        };
        let (a, b) = (solve(false), solve(true));
        let worst = (0..a.len() / 3)
            .map(|i| {
                let ra = apply([a[3 * i], a[3 * i + 1], a[3 * i + 2]]);
                (0..3)
                    .map(|k| (ra[k] - b[3 * i + k]).abs())
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        assert!(worst < 1e-10, "{wrinkling:?}: {worst:e} m");
    }
}

/// The rotation by `angle` about `axis` (Rodrigues).
fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|v| v / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [c + x * x * t, x * y * t - z * s, x * z * t + y * s],
        [y * x * t + z * s, c + y * y * t, y * z * t - x * s],
        [z * x * t - y * s, z * y * t + x * s, c + z * z * t],
    ]
}

/// The material axes do not depend on the node numbering: an element's
/// nodes numbered from each vertex in turn, and in reverse order (the
/// normal flipped), give the same energy and the same nodal forces (to
/// round-off), T3 and T6, in a taut and a wrinkled state.
#[test]
fn renumbering_an_elements_nodes_changes_nothing() {
    // Vertex permutations, with the mid-side nodes (T6: 3 = 0-1, 4 = 1-2,
    // 5 = 2-0) following their edges.
    let t3: [&[usize]; 4] = [&[0, 1, 2], &[1, 2, 0], &[2, 0, 1], &[0, 2, 1]];
    let t6: [&[usize]; 4] = [
        &[0, 1, 2, 3, 4, 5],
        &[1, 2, 0, 4, 5, 3],
        &[2, 0, 1, 5, 3, 4],
        &[0, 2, 1, 5, 4, 3],
    ];
    let x: [[f64; 3]; 6] = [
        [0.0, 0.0, 0.0],
        [0.1, 0.01, 0.0],
        [0.03, 0.08, 0.01],
        [0.05, 0.005, 0.0],
        [0.065, 0.045, 0.005],
        [0.015, 0.04, 0.005],
    ];
    let material = fabric([0.9, 0.3, 0.1]).with_wrinkling(WrinklingModel::RelaxedEnergy, 0.0);
    for (order, perms) in [(ElementOrder::Linear, t3), (ElementOrder::Quadratic, t6)] {
        let n = perms[0].len();
        for (label, deform) in [("taut", [1.03, 1.02]), ("wrinkled", [1.04, 0.97])] {
            let y: Vec<[f64; 3]> = x[..n]
                .iter()
                .map(|p| [deform[0] * p[0] + 0.01 * p[1], deform[1] * p[1], p[2]])
                .collect();
            let mut reference: Option<(f64, Vec<f64>)> = None;
            for perm in perms {
                let mesh = Mesh {
                    nodes: perm.iter().map(|&a| x[a]).collect(),
                    order,
                    connectivity: (0..n).collect(),
                };
                let rule = QuadratureRule::of_degree(4 * (order.degree() - 1));
                let geo = ElementGeometry::with_axis(&mesh, &rule, material.axis()).unwrap();
                let (grad, weight) = geo.element(0);
                let yp: Vec<[f64; 3]> = perm.iter().map(|&a| y[a]).collect();
                let mut f = vec![0.0; 3 * n];
                let energy =
                    element_force_hessian(&material, SECTION, &yp, grad, weight, &mut f, None);
                // Back in the original numbering.
                let mut g = vec![0.0; 3 * n];
                for (k, &a) in perm.iter().enumerate() {
                    g[3 * a..3 * a + 3].copy_from_slice(&f[3 * k..3 * k + 3]);
                }
                match &reference {
                    None => reference = Some((energy, g)),
                    Some((e0, g0)) => {
                        let fmax = g0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                        assert!(
                            (energy - e0).abs() <= 1e-12 * e0,
                            "{order:?} {label} {perm:?}: {energy} vs {e0}"
                        );
                        for (u, v) in g.iter().zip(g0) {
                            assert!((u - v).abs() <= 1e-10 * fmax, "{order:?} {label} {perm:?}");
                        }
                    }
                }
            }
        }
    }
}

/// A curved, tilted element of `order` and a large deformation of it.
fn curved_element(order: ElementOrder, stretch: [f64; 2]) -> (Mesh, Vec<f64>) {
    let shape = drape::mesh::lagrange::ShapeFunctions::new(order);
    let nodes: Vec<[f64; 3]> = shape
        .nodes()
        .iter()
        .map(|xi| {
            let (u, v) = (0.08 * xi[0] + 0.03 * xi[1], 0.01 * xi[0] + 0.09 * xi[1]);
            [u + 0.2 * v, v - 0.1 * u, 3.0 * u * u - 2.0 * u * v + 0.01]
        })
        .collect();
    let n = nodes.len();
    let (c, s) = (0.7f64.cos(), 0.7f64.sin());
    let y = nodes
        .iter()
        .enumerate()
        .flat_map(|(a, x)| {
            let r = [c * x[0] - s * x[2], x[1], s * x[0] + c * x[2]];
            let wobble = 1e-3 * ((a * 7 % 5) as f64 - 2.0);
            [
                stretch[0] * r[0] + wobble,
                stretch[1] * r[1] + 0.05 * r[0],
                r[2] - wobble,
            ]
        })
        .collect();
    let mesh = Mesh {
        nodes,
        order,
        connectivity: (0..n).collect(),
    };
    (mesh, y)
}

/// The element force against central differences of the energy and the
/// Hessian against differences of the force, T3, T6 and T10 on a curved
/// element, with the warp at four orientations (one out of the plane), in
/// the taut, wrinkled and slack states of both tension-field models (the
/// stress projection's force has no energy: only its Hessian is checked).
#[test]
fn element_force_and_hessian_match_finite_differences() {
    let warps = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.6, 0.8, 0.0],
        [0.7, -0.2, 0.6],
    ];
    let mut seen = std::collections::HashSet::new();
    for order in [
        ElementOrder::Linear,
        ElementOrder::Quadratic,
        ElementOrder::Cubic,
    ] {
        for stretch in [[1.05, 1.04], [1.06, 0.9], [0.9, 0.92]] {
            let (mesh, y0) = curved_element(order, stretch);
            let rule = QuadratureRule::of_degree(4 * (order.degree() - 1));
            for warp in warps {
                for model in [
                    None,
                    Some(WrinklingModel::StressProjection),
                    Some(WrinklingModel::RelaxedEnergy),
                ] {
                    let material = match model {
                        None => fabric(warp),
                        Some(m) => fabric(warp).with_wrinkling(m, 0.0),
                    };
                    let geo = ElementGeometry::with_axis(&mesh, &rule, material.axis()).unwrap();
                    let (grad, weight) = geo.element(0);
                    let pts =
                        |y: &[f64]| y.chunks(3).map(|c| [c[0], c[1], c[2]]).collect::<Vec<_>>();
                    let force = |y: &[f64]| {
                        let mut f = vec![0.0; y.len()];
                        element_force_hessian(
                            &material,
                            SECTION,
                            &pts(y),
                            grad,
                            weight,
                            &mut f,
                            None,
                        );
                        f
                    };
                    let hessian = |y: &[f64]| {
                        let m = y.len();
                        let (mut f, mut k) = (vec![0.0; m], vec![f64::NAN; m * m]);
                        element_force_hessian(
                            &material,
                            SECTION,
                            &pts(y),
                            grad,
                            weight,
                            &mut f,
                            Some(&mut k),
                        );
                        k
                    };
                    // The states of the element's points.
                    for q in 0..weight.len() {
                        let n = y0.len() / 3;
                        let g = &grad[q * n..(q + 1) * n];
                        let f = drape::element::membrane::deformation_gradient(&pts(&y0), g);
                        let e = drape::element::membrane::green_lagrange(&f);
                        if let Some(state) = material.wrinkle_state(e) {
                            seen.insert((model.map(|m| m as u8), state as u8));
                        }
                    }
                    let scale = force(&y0).iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    if scale == 0.0 {
                        // Slack everywhere: nothing to differentiate but zero.
                        assert!(hessian(&y0).iter().all(|v| v.abs() == 0.0 || v.is_finite()));
                        continue;
                    }
                    let he = jacobian_error(force, hessian, &y0, 1e-7);
                    assert!(
                        he < 1e-5,
                        "{order:?} {stretch:?} warp {warp:?} {model:?}: Hessian {he:e}"
                    );
                    if model != Some(WrinklingModel::StressProjection) {
                        let energy =
                            |y: &[f64]| element_energy(&material, SECTION, &pts(y), grad, weight);
                        let ge = gradient_error(energy, force, &y0, 1e-7);
                        assert!(
                            ge < 1e-5,
                            "{order:?} {stretch:?} warp {warp:?} {model:?}: force {ge:e}"
                        );
                    }
                }
            }
        }
    }
    for model in [
        WrinklingModel::StressProjection,
        WrinklingModel::RelaxedEnergy,
    ] {
        for state in [
            WrinkleState::Taut,
            WrinkleState::Wrinkled,
            WrinkleState::Slack,
        ] {
            assert!(
                seen.contains(&(Some(model as u8), state as u8)),
                "{model:?} never {state:?}: {seen:?}"
            );
        }
    }
}

/// A scenario of a 10 cm square falling 24 steps onto a sphere (it
/// touches at step 15), with
/// `material` as the `[material]` lines.
fn falling_square(material: &str) -> String {
    format!(
        r#"
[mesh]
shape = "rectangle"
size = [0.1, 0.1]
divisions = [8, 8]
[material]
{material}
density = 320.0
thickness = 0.6e-3
[[load]]
kind = "surface"
force = [0.0, 0.0, -1.8816]
[contact]
method = "penalty"
penalty = 5.0e4
[[obstacle]]
shape = "sphere"
center = [0.0, 0.0, -0.031]
radius = 0.03
[time]
segments = [ {{ steps = 24, dt = 1.0e-3 }} ]
[solver]
tolerance = 1.0e-14
residual_tolerance = 1.0e-12
max_iterations = 60
[output]
every = 24
[[monitor]]
name = "corner"
at = [0.05, 0.05, 0.0]
"#
    )
}

/// An orthotropic material with `E1 = E2 = E`, `G12 = E / (2 (1 + nu))`
/// gives the isotropic results: a square falling onto a sphere for 24
/// steps, without wrinkling and with each model, has the same corner
/// history as Saint-Venant–Kirchhoff to 1e-10 of the square's size (the
/// two constitutive matrices differ by round-off only; Newton is run to
/// 1e-14 so that both runs take their steps to round-off). Further on, the
/// wrinkled fabric sliding on the sphere amplifies round-off by about 10
/// per step (1e-16 m at step 15, 4e-11 m at step 40 with stress
/// projection), in either material: a mechanical sensitivity, not a
/// difference of the models.
#[test]
fn isotropic_constants_reproduce_the_isotropic_run() {
    let (young, nu) = (2.0e6, 0.3);
    for wrinkling in ["none", "stress-projection", "relaxed-energy"] {
        let iso = format!(
            "youngs_modulus = {young:e}\npoisson_ratio = {nu}\nwrinkling = \"{wrinkling}\""
        );
        let ortho = format!(
            "model = \"orthotropic\"\nwarp_modulus = {young:e}\nweft_modulus = {young:e}\nshear_modulus = {:e}\npoisson_ratio = {nu}\nwarp_direction = [0.6, 0.8, 0.0]\nwrinkling = \"{wrinkling}\"",
            young / (2.0 * (1.0 + nu))
        );
        let histories: Vec<Vec<Vec<f64>>> = [iso, ortho]
            .iter()
            .map(|m| {
                let s = setup(&falling_square(m));
                let dir = temp_dir(&format!("ortho-iso-{wrinkling}"));
                drape::simulation::run(&s, &dir, &mut |_| {}).unwrap();
                let (header, rows) = read_history(&dir);
                let z = header.iter().position(|h| h == "corner_z").unwrap();
                rows.iter().map(|r| r[z - 2..=z].to_vec()).collect()
            })
            .collect();
        assert_eq!(histories[0].len(), histories[1].len());
        let drop = histories[0].last().unwrap()[2].abs();
        assert!(drop > 1e-3, "{wrinkling}: the corner fell {drop} m");
        for (a, b) in histories[0].iter().zip(&histories[1]) {
            for (u, v) in a.iter().zip(b) {
                assert!((u - v).abs() <= 1e-10 * 0.1, "{wrinkling}: {a:?} vs {b:?}");
            }
        }
    }
}

/// A 4 cm x 3 cm flat fabric whose `[material]` table is `lines` (from
/// line 6 on).
fn material_scenario(lines: &str) -> String {
    format!(
        "[mesh]
shape = \"rectangle\"
size = [0.04, 0.03]
divisions = [4, 3]
[material]
{lines}
density = 320.0
thickness = 0.6e-3
[time]
segments = [{{ steps = 1, dt = 1.0e-3 }}]
"
    )
}

const ORTHO: &str = "model = \"orthotropic\"
warp_modulus = 5.0e6
weft_modulus = 1.0e6
shear_modulus = 5.0e4
poisson_ratio = 0.3";

/// Bad orthotropic input names the key, its line and the value: a
/// missing or non-positive modulus, a Poisson ratio that makes `C`
/// indefinite, Young's modulus given to the orthotropic model, an
/// orthotropic modulus given to the isotropic one, `"plate"` bending with
/// the orthotropic model, a warp normal to the fabric (naming the element).
#[test]
fn bad_orthotropic_input_names_the_key_line_and_value() {
    let with = |key: &str, value: &str| {
        let lines: Vec<String> = ORTHO
            .lines()
            .map(|l| {
                if l.starts_with(key) {
                    format!("{key} = {value}")
                } else {
                    l.to_string()
                }
            })
            .collect();
        material_scenario(&lines.join("\n"))
    };
    for (key, line) in [
        ("warp_modulus", 7),
        ("weft_modulus", 8),
        ("shear_modulus", 9),
    ] {
        assert_error(
            &with(key, "0.0"),
            line,
            &format!("material.{key}"),
            &["positive finite", "not 0"],
        );
        assert_error(
            &with(key, "-3e5"),
            line,
            &format!("material.{key}"),
            &["not -300000"],
        );
        let without: Vec<&str> = ORTHO.lines().filter(|l| !l.starts_with(key)).collect();
        let message = build(
            &material_scenario(&without.join("\n")),
            std::path::Path::new("t.toml"),
        )
        .unwrap_err();
        assert!(
            message.contains(&format!("`material.{key}`"))
                && message.contains("is required with model = \"orthotropic\""),
            "{message}"
        );
    }
    // nu12^2 < E1 / E2 = 5: 2.2^2 = 4.84 is stable, 2.24^2 = 5.02 is not.
    assert!(
        build(
            &with("poisson_ratio", "2.2"),
            std::path::Path::new("t.toml")
        )
        .is_ok()
    );
    assert_error(
        &with("poisson_ratio", "2.24"),
        10,
        "material.poisson_ratio",
        &["nu12^2 < warp_modulus / weft_modulus = 5", "not 2.24"],
    );
    assert_error(
        &material_scenario(&format!("{ORTHO}\nyoungs_modulus = 2.0e6")),
        11,
        "material.youngs_modulus",
        &["does not apply to model = \"orthotropic\""],
    );
    assert_error(
        &material_scenario("youngs_modulus = 2.0e6\npoisson_ratio = 0.3\nshear_modulus = 5.0e4"),
        8,
        "material.shear_modulus",
        &[
            "does not apply to model = \"saint-venant-kirchhoff\"",
            "model = \"orthotropic\"",
        ],
    );
    assert_error(
        &material_scenario(&format!("{ORTHO}\nbending_rigidity = \"plate\"")),
        11,
        "material.bending_rigidity",
        &["isotropic material", "{ warp, weft }"],
    );
    assert_error(
        &material_scenario(&format!("{ORTHO}\nwarp_direction = [0.0, 0.0, 2.0]")),
        11,
        "material.warp_direction",
        &["[0.0, 0.0, 2.0] is normal to element 0"],
    );
    // A good one: the warp along y, with woven bending sharing it.
    let setup = build(
        &material_scenario(&format!(
            "{ORTHO}\nwarp_direction = [0.0, 1.0, 0.0]\nbending_rigidity = {{ warp = 2e-5, weft = 1e-5 }}\nwrinkling = \"stress-projection\""
        )),
        std::path::Path::new("t.toml"),
    )
    .unwrap();
    assert!(setup.model.bending().is_some());
}

/// In-plane shear of a woven square into a tension field: the boundary of
/// a 10 cm square held on a simple shear `x += gamma y` (gamma = 0.05), the
/// warp at 30 degrees to x. Every element is wrinkled, its stress uniaxial,
/// of the magnitude and along the direction that an independent
/// brute-force maximisation of the uniaxial energy `(n.E.n)^2 E(n)` gives
/// for the homogeneous strain (200,000 directions, then golden section) —
/// for both tension-field models — and that direction is 10 degrees and
/// more away from the principal strain direction an isotropic model would
/// take. (About 120 lines, kept whole: the reference computation and the
/// checks of each model read as one derivation.)
#[test]
fn in_plane_shear_wrinkles_along_the_anisotropic_tension_field() {
    use std::f64::consts::PI;
    let (gamma, phi) = (0.05f64, PI / 6.0);
    let warp = [phi.cos(), phi.sin(), 0.0];
    // The homogeneous Green-Lagrange strain, in x-y and in the warp's axes.
    let eg = [0.0, 0.5 * gamma * gamma, gamma];
    let (c, s) = (phi.cos(), phi.sin());
    let em = [
        eg[0] * c * c + eg[1] * s * s + eg[2] * c * s,
        eg[0] * s * s + eg[1] * c * c - eg[2] * c * s,
        2.0 * (eg[1] - eg[0]) * c * s + eg[2] * (c * c - s * s),
    ];
    let compliance = |t: [f64; 3]| {
        t[0] * t[0] / E1 + t[1] * t[1] / E2 - 2.0 * NU12 / E1 * t[0] * t[1] + t[2] * t[2] / G12
    };
    let t_of = |b: f64| [b.cos().powi(2), b.sin().powi(2), b.cos() * b.sin()];
    let g = |b: f64| {
        let t = t_of(b);
        let p = (t[0] * em[0] + t[1] * em[1] + t[2] * em[2]).max(0.0);
        p * p / compliance(t)
    };
    let n = 200_000;
    let best = (0..n)
        .map(|i| PI * i as f64 / n as f64)
        .fold(
            (0.0, 0.0),
            |acc, b| if g(b) > acc.1 { (b, g(b)) } else { acc },
        );
    let (mut lo, mut hi) = (best.0 - PI / n as f64, best.0 + PI / n as f64);
    let golden = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..100 {
        let (x1, x2) = (hi - golden * (hi - lo), lo + golden * (hi - lo));
        if g(x1) < g(x2) {
            lo = x1;
        } else {
            hi = x2;
        }
    }
    let beta = 0.5 * (lo + hi);
    let t = t_of(beta);
    let relaxed = (t[0] * em[0] + t[1] * em[1] + t[2] * em[2]) / compliance(t);
    let d = 1.0 - NU12 * NU12 * E2 / E1;
    let s_el = [
        (E1 * em[0] + NU12 * E2 * em[1]) / d,
        (NU12 * E2 * em[0] + E2 * em[1]) / d,
        G12 * em[2],
    ];
    let projected = t[0] * s_el[0] + t[1] * s_el[1] + 2.0 * t[2] * s_el[2];
    // The isotropic answer: the major principal strain direction.
    let principal = 0.5 * eg[2].atan2(eg[0] - eg[1]);
    let apart =
        ((phi + beta - principal).rem_euclid(PI)).min(PI - (phi + beta - principal).rem_euclid(PI));
    eprintln!(
        "wrinkles at {:.3} deg (isotropic: {:.3} deg); relaxed {relaxed:.3} Pa, projected {projected:.3} Pa",
        (phi + beta).to_degrees(),
        principal.to_degrees()
    );
    assert!(
        apart > 10f64.to_radians(),
        "{} deg apart",
        apart.to_degrees()
    );
    for (model, expected) in [
        ("relaxed-energy", relaxed),
        ("stress-projection", projected),
    ] {
        let text = format!(
            r#"
[mesh]
shape = "rectangle"
size = [0.1, 0.1]
divisions = [6, 6]
pattern = "alternate"
center = [0.05, 0.05, 0.0]
[material]
model = "orthotropic"
warp_modulus = {E1}
weft_modulus = {E2}
shear_modulus = {G12}
poisson_ratio = {NU12}
warp_direction = {warp:?}
density = 320.0
thickness = 0.6e-3
wrinkling = "{model}"
[[fix]]
boundary = true
[analysis]
kind = "static"
steps = 1
[output]
every = 1
"#
        );
        let mut s = setup(&text);
        let (positions, off) = sheared_equilibrium(&mut s, gamma);
        assert!(
            off < 1e-9,
            "{model}: interior off the homogeneous shear by {off:e} m"
        );
        let results = s.model.element_results(&positions);
        for (el, (p, st)) in results.principal.iter().zip(&results.stress).enumerate() {
            assert_eq!(results.state[el], 1, "{model}: element {el} not wrinkled");
            assert!(
                p[1].abs() < 1e-9 * expected,
                "{model}: minor principal stress {}",
                p[1]
            );
            assert!(
                (p[0] / expected - 1.0).abs() < 1e-8,
                "{model}: {} vs {expected}",
                p[0]
            );
            // The tension's direction in the warp's frame, against beta.
            let angle = 0.5 * (2.0 * st[2]).atan2(st[0] - st[1]);
            let diff = (angle - beta).rem_euclid(PI);
            assert!(
                diff.min(PI - diff) < 1e-7,
                "{model}: element {el} at {angle} vs {beta}"
            );
        }
    }
}
