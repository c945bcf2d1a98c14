//! Finite-difference checks of every derivative: internal force and
//! Hessian of the membrane for orders 1–3 on random, distorted, curved 3D
//! configurations; the follower pressure and its tangent; the assembled
//! global Hessian. All go through the one checker in `drape::fd`.
//!
//! Tolerances: central differences with `h = 1e-6` (positions of order 1)
//! have truncation error `~h^2 |f'''| ~ 1e-12` relative and round-off
//! `~eps |f| / h ~ 1e-10` relative; `1e-6` leaves a wide margin while any
//! wrong term (a missing geometric stiffness, a transposed block) shows up
//! at order 1e-2 or more.

use drape::element::ElementGeometry;
use drape::element::membrane::{Section, element_energy, element_force_hessian};
use drape::fd::{gradient_error, jacobian_error};
use drape::load::pressure::{PressureQuadrature, add_pressure_force};
use drape::material::SaintVenantKirchhoff;
use drape::mesh::lagrange::ShapeFunctions;
use drape::mesh::{ElementOrder, Mesh};
use drape::quadrature::QuadratureRule;

const ORDERS: [ElementOrder; 3] = [
    ElementOrder::Linear,
    ElementOrder::Quadratic,
    ElementOrder::Cubic,
];
const TOL: f64 = 1e-6;

/// A tiny deterministic generator (no dependency needed for test noise).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// One element of `order` on a curved, rotated initial surface, and a
/// random, large deformation of it.
fn curved_element(order: ElementOrder, seed: u64) -> (Mesh, Vec<f64>) {
    let mut rng = Lcg(seed);
    let shape = ShapeFunctions::new(order);
    let nodes: Vec<[f64; 3]> = shape
        .nodes()
        .iter()
        .map(|xi| {
            let (u, v) = (0.8 * xi[0] + 0.3 * xi[1], 0.1 * xi[0] + 0.9 * xi[1]);
            // A bent surface, tilted in space.
            [u + 0.2 * v, v - 0.1 * u, 0.3 * u * u - 0.2 * u * v + 0.1]
        })
        .collect();
    let n = nodes.len();
    let mesh = Mesh {
        nodes: nodes.clone(),
        order,
        connectivity: (0..n).collect(),
    };
    // Large rotation + stretch + noise.
    let (c, s) = (0.7f64.cos(), 0.7f64.sin());
    let y = nodes
        .iter()
        .flat_map(|x| {
            let r = [c * x[0] - s * x[2], x[1], s * x[0] + c * x[2]];
            [1.3 * r[0] + 0.05, 0.9 * r[1] + 0.2 * r[0], r[2] - 0.1]
        })
        .map(|v| v + 0.08 * rng.next())
        .collect();
    (mesh, y)
}

fn as_points(y: &[f64]) -> Vec<[f64; 3]> {
    y.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// The element force at `y` (flattened).
fn element_force(
    material: &dyn drape::material::Material,
    section: Section,
    grad: &[[f64; 2]],
    weight: &[f64],
    y: &[f64],
) -> Vec<f64> {
    let mut f = vec![0.0; y.len()];
    element_force_hessian(material, section, &as_points(y), grad, weight, &mut f, None);
    f
}

/// The element Hessian at `y` (flattened), row-major; written over NaN,
/// so an entry the kernel leaves unwritten shows.
fn element_hessian(
    material: &dyn drape::material::Material,
    section: Section,
    grad: &[[f64; 2]],
    weight: &[f64],
    y: &[f64],
) -> Vec<f64> {
    let m = y.len();
    let (mut f, mut k) = (vec![0.0; m], vec![f64::NAN; m * m]);
    element_force_hessian(
        material,
        section,
        &as_points(y),
        grad,
        weight,
        &mut f,
        Some(&mut k),
    );
    k
}

#[test]
fn internal_force_and_hessian_match_finite_differences_for_every_order() {
    let material = SaintVenantKirchhoff::new(2.0e6, 0.3);
    let section = Section {
        thickness: 6e-4,
        prestress: 150.0,
    };
    for order in ORDERS {
        for seed in 1..4 {
            let (mesh, y0) = curved_element(order, seed);
            let p = order.degree();
            let geo = ElementGeometry::new(&mesh, &QuadratureRule::of_degree(4 * (p - 1)));
            let (grad, weight) = geo.element(0);
            let m = y0.len();
            let energy =
                |y: &[f64]| element_energy(&material, section, &as_points(y), grad, weight);
            let force = |y: &[f64]| element_force(&material, section, grad, weight, y);
            let hessian = |y: &[f64]| element_hessian(&material, section, grad, weight, y);
            let ge = gradient_error(energy, force, &y0, 1e-6);
            let he = jacobian_error(force, hessian, &y0, 1e-6);
            assert!(ge < TOL, "{order:?} seed {seed}: force vs energy {ge:e}");
            assert!(he < TOL, "{order:?} seed {seed}: Hessian vs force {he:e}");
            // SVK's Hessian is symmetric.
            let k = hessian(&y0);
            let kmax = k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for r in 0..m {
                for c in 0..m {
                    assert!((k[r * m + c] - k[c * m + r]).abs() <= 1e-12 * kmax);
                }
            }
        }
    }
}

#[test]
fn follower_pressure_tangent_matches_finite_differences_for_every_order() {
    for order in ORDERS {
        let (_, y0) = curved_element(order, 7);
        let quadrature = PressureQuadrature::new(order);
        let m = y0.len();
        let force = |y: &[f64]| {
            let mut f = vec![0.0; m];
            add_pressure_force(250.0, &as_points(y), &quadrature, &mut f, None, 1.0);
            f
        };
        let tangent = |y: &[f64]| {
            let (mut f, mut k) = (vec![0.0; m], vec![0.0; m * m]);
            add_pressure_force(250.0, &as_points(y), &quadrature, &mut f, Some(&mut k), 1.0);
            k
        };
        let e = jacobian_error(force, tangent, &y0, 1e-6);
        assert!(e < TOL, "{order:?}: pressure tangent {e:e}");
    }
}

/// The pressure force on a flat element is `p A n` in total, along the
/// right-hand normal of the node order.
#[test]
fn pressure_on_a_flat_element_totals_p_times_area_along_the_normal() {
    for order in ORDERS {
        let shape = ShapeFunctions::new(order);
        let y: Vec<[f64; 3]> = shape
            .nodes()
            .iter()
            .map(|x| [2.0 * x[0], 3.0 * x[1], 0.5])
            .collect();
        let mut f = vec![0.0; 3 * y.len()];
        add_pressure_force(10.0, &y, &PressureQuadrature::new(order), &mut f, None, 1.0);
        let total: Vec<f64> = (0..3).map(|i| f.iter().skip(i).step_by(3).sum()).collect();
        assert!(total[0].abs() < 1e-12 && total[1].abs() < 1e-12);
        assert!(
            (total[2] - 10.0 * 3.0).abs() < 1e-12,
            "{order:?}: {total:?}"
        );
    }
}

/// The element Hessian with each wrinkling model against finite
/// differences of the force, for every order, in each state and with the
/// quadrature points of one element in different states: the kernel
/// computes half the blocks at points with a symmetric tangent, every
/// block at the others, and nothing at slack points (no stress, no
/// tangent), so every mixture is checked. (Stress projection's force is
/// not the gradient of an energy: only the Hessian is checked.)
#[test]
fn wrinkling_element_hessians_match_finite_differences_in_every_state_and_mixture() {
    use drape::material::{Material, WrinkleState, Wrinkling, WrinklingModel};
    let section = Section {
        thickness: 6e-4,
        prestress: 0.0,
    };
    // Stretches along the initial x and y, and a gradient of the x
    // stretch along x that changes the state across a larger element.
    let cases: [(&str, f64, f64, f64); 4] = [
        ("taut", 1.05, 1.03, 0.0),
        ("wrinkled", 1.05, 0.97, 0.0),
        ("slack", 0.97, 0.98, 0.0),
        ("mixed", 0.985, 1.01, 0.08),
    ];
    for model in [
        WrinklingModel::StressProjection,
        WrinklingModel::RelaxedEnergy,
    ] {
        let material = Wrinkling::new(2.0e6, 0.3, 0.0, model);
        for order in ORDERS {
            let (mesh, _) = curved_element(order, 1);
            let p = order.degree();
            let geo = ElementGeometry::new(&mesh, &QuadratureRule::of_degree(4 * (p - 1)));
            let (grad, weight) = geo.element(0);
            for (name, sx, sy, gradient) in cases {
                let y0: Vec<f64> = mesh
                    .nodes
                    .iter()
                    .flat_map(|x| {
                        let stretch = sx + gradient * (x[0] - 0.4);
                        [stretch * x[0], sy * x[1] + 0.01 * x[0], x[2]]
                    })
                    .collect();
                let force = |y: &[f64]| element_force(&material, section, grad, weight, y);
                let hessian = |y: &[f64]| element_hessian(&material, section, grad, weight, y);
                // The states of the quadrature points.
                let n = mesh.nodes.len();
                let points = as_points(&y0);
                let states: Vec<WrinkleState> = (0..weight.len())
                    .map(|q| {
                        let f = drape::element::membrane::deformation_gradient(
                            &points,
                            &grad[q * n..(q + 1) * n],
                        );
                        let e = drape::element::membrane::green_lagrange(&f);
                        material.wrinkle_state(e).unwrap()
                    })
                    .collect();
                let distinct = |s: WrinkleState| states.contains(&s);
                match name {
                    "taut" => assert!(states.iter().all(|&s| s == WrinkleState::Taut)),
                    "wrinkled" => assert!(states.iter().all(|&s| s == WrinkleState::Wrinkled)),
                    "slack" => assert!(states.iter().all(|&s| s == WrinkleState::Slack)),
                    _ if order != ElementOrder::Linear => assert!(
                        [
                            WrinkleState::Taut,
                            WrinkleState::Wrinkled,
                            WrinkleState::Slack
                        ]
                        .into_iter()
                        .filter(|&s| distinct(s))
                        .count()
                            >= 2,
                        "{model:?} {order:?}: the mixed case has points in one state: {states:?}"
                    ),
                    _ => {}
                }
                let k = hessian(&y0);
                assert!(
                    k.iter().all(|v| v.is_finite()),
                    "{model:?} {order:?} {name}"
                );
                if name == "slack" {
                    assert!(k.iter().all(|&v| v == 0.0), "{model:?} {order:?}: slack");
                    continue;
                }
                let he = jacobian_error(force, hessian, &y0, 1e-7);
                assert!(
                    he < TOL,
                    "{model:?} {order:?} {name}: Hessian vs force {he:e}"
                );
            }
        }
    }
}
