//! Issue 31: curved elements (T6, T10) with bending measure their membrane
//! on their flat sub-triangles (`[mesh] membrane`, default `"auto"`), so
//! that they bend as accurately as T3 on the same nodes at every membrane
//! stiffness. Here: that membrane equals the T3 membrane of the
//! sub-triangles (energy, forces, Hessian), the key's default and its
//! errors. The cantilever against the elastica is in tests/bending.rs.

mod common;

use drape::bending::triangulate;
use drape::element::geometry::MembraneIntegration;
use drape::mesh::generate::{Pattern, rectangle};
use drape::mesh::{ElementOrder, Mesh};
use drape::model::Model;

/// A membrane model of `mesh` (E = 2 MPa, 0.6 mm, no load) whose curved
/// elements measure their membrane as `membrane`.
fn membrane(mesh: Mesh, membrane: MembraneIntegration) -> Model {
    common::fabric_model(mesh)
        .membrane(membrane)
        .build()
        .unwrap()
}

/// Positions `x` moved by a smooth out-of-plane bend and an in-plane
/// stretch plus a deterministic scatter of up to `amplitude` (m).
fn deformed(x: &[[f64; 3]], amplitude: f64) -> Vec<f64> {
    let mut y = Vec::with_capacity(3 * x.len());
    for (a, p) in x.iter().enumerate() {
        let s = |k: usize| amplitude * (((a * 7 + k * 13) % 17) as f64 / 8.0 - 1.0);
        y.push(1.01 * p[0] + s(0));
        y.push(0.995 * p[1] + 0.2 * p[0] * p[0] + s(1));
        y.push(p[2] + 3.0 * p[0] * p[0] - p[1] * p[1] + s(2));
    }
    y
}

/// The curved mesh's membrane on its sub-triangles is the T3 membrane of
/// those sub-triangles: the same energy, forces and Hessian (entries of
/// node pairs that share no sub-triangle are zero), for T6 and T10.
#[test]
fn sub_triangle_membrane_is_the_t3_membrane_of_the_sub_triangles() {
    for order in [ElementOrder::Quadratic, ElementOrder::Cubic] {
        let curved = rectangle([0.12, 0.09], [4, 3], Pattern::Alternate, [0.0; 3], order);
        let (triangles, _) = triangulate(&curved);
        let flat = Mesh {
            nodes: curved.nodes.clone(),
            order: ElementOrder::Linear,
            connectivity: triangles.concat(),
        };
        let sub = membrane(curved.clone(), MembraneIntegration::SubTriangles);
        let t3 = membrane(flat, MembraneIntegration::Curved);
        assert_eq!(sub.geometry().points_per_element(), order.degree().pow(2));
        let y = deformed(&curved.nodes, 2e-4);
        let n = y.len();
        let (mut f_sub, mut f_t3) = (vec![0.0; n], vec![0.0; n]);
        let mut h_sub = vec![0.0; sub.pattern().nnz()];
        let mut h_t3 = vec![0.0; t3.pattern().nnz()];
        let e_sub = sub.assemble(&y, &mut f_sub, Some(&mut h_sub));
        let e_t3 = t3.assemble(&y, &mut f_t3, Some(&mut h_t3));
        assert!(e_t3 > 1e-6, "{order:?}: the state strains the membrane");
        assert!(
            (e_sub - e_t3).abs() <= 1e-12 * e_t3,
            "{order:?}: energy {e_sub:e} against {e_t3:e}"
        );
        let f_scale = f_t3.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (i, (a, b)) in f_sub.iter().zip(&f_t3).enumerate() {
            assert!(
                (a - b).abs() <= 1e-11 * f_scale,
                "{order:?}: force {i}: {a} against {b}"
            );
        }
        let h_scale = h_t3.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let (mut compared, mut zero) = (0, 0);
        for row in 0..n {
            for col in 0..n {
                let Some(k) = sub.pattern().find(row, col) else {
                    assert!(t3.pattern().find(row, col).is_none());
                    continue;
                };
                let want = t3.pattern().find(row, col).map_or(0.0, |k| h_t3[k]);
                assert!(
                    (h_sub[k] - want).abs() <= 1e-11 * h_scale,
                    "{order:?}: Hessian ({row}, {col}): {} against {want}",
                    h_sub[k]
                );
                compared += 1;
                zero += usize::from(want == 0.0);
            }
        }
        assert!(
            compared > 0 && zero > 0,
            "{order:?}: {compared} entries, {zero} zero"
        );
        // The curved element's own membrane differs on the same state.
        let own = membrane(curved, MembraneIntegration::Curved);
        let e_own = own.assemble(&y, &mut f_sub, None);
        assert!((e_own - e_t3).abs() > 1e-6 * e_t3, "{order:?}: {e_own:e}");
    }
}

/// `"auto"` measures a curved fabric with bending on its sub-triangles
/// and a pure membrane on its own interpolation; the key overrides it; on
/// T3 it changes nothing.
#[test]
fn auto_is_sub_triangles_with_bending_and_curved_without() {
    let points = |extra: &str, mesh_extra: &str| {
        let text = common::rectangle([0.1, 0.1], [2, 2], extra)
            .replace("[material]", &format!("{mesh_extra}\n[material]"))
            + "[analysis]\nkind = \"static\"\n";
        common::setup(&text).model.geometry().points_per_element()
    };
    assert_eq!(points("bending_rigidity = 1e-5", "order = 2"), 4);
    assert_eq!(points("", "order = 2"), 6);
    assert_eq!(points("bending_rigidity = 1e-5", "order = 3"), 9);
    let exact = |degree| drape::quadrature::QuadratureRule::of_degree(degree).len();
    assert_eq!(points("", "order = 3"), exact(8));
    assert_eq!(exact(4), 6);
    assert_eq!(
        points(
            "bending_rigidity = 1e-5",
            "order = 2\nmembrane = \"curved\""
        ),
        6
    );
    assert_eq!(points("", "order = 2\nmembrane = \"sub-triangles\""), 4);
    assert_eq!(
        points("bending_rigidity = 1e-5", "membrane = \"sub-triangles\""),
        1
    );
}

/// An unknown value is refused at its line, naming the key and the
/// values it takes.
#[test]
fn an_unknown_membrane_value_is_refused_at_its_line() {
    let text = common::rectangle([0.1, 0.1], [2, 2], "")
        .replace("[material]", "membrane = \"flat\"\n[material]");
    let message = common::build(&text, std::path::Path::new("test.toml")).unwrap_err();
    for fragment in ["test.toml", "line 6", "flat", "sub-triangles", "curved"] {
        assert!(message.contains(fragment), "{fragment:?} not in {message}");
    }
}
