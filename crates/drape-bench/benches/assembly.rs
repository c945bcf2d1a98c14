//! Assembly and Newton-iteration benchmarks (issue 2).
//!
//! `cargo bench -p drape-bench` — a fabric of the reference material,
//! order 1, at 20x20, 100x100 and 300x300 divisions, in the shape of the
//! hanging cloth's first step (gravity, two pinned corners, consistent mass,
//! dt = 1e-3 s, beta = 1):
//!
//! * `assemble/force+hessian/N`: internal forces and the sparse Hessian;
//! * `assemble/force/N`: internal forces only;
//! * `newton_iteration/N`: assemble, add `M/(beta dt^2)`, eliminate
//!   supports, Cholesky factorisation (symbolic analysis reused) and solve.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use drape::element::membrane::Section;
use drape::load::{Load, LoadKind};
use drape::material::SaintVenantKirchhoff;
use drape::mesh::ElementOrder;
use drape::mesh::generate::{Pattern, rectangle};
use drape::model::Model;
use drape::solver::LinearSolver;
use std::hint::black_box;

fn fabric(n: usize) -> (Model, Vec<f64>) {
    let mesh = rectangle(
        [0.2, 0.2],
        [n, n],
        Pattern::Right,
        [0.0; 3],
        ElementOrder::Linear,
    );
    let mut fixed = vec![false; 3 * mesh.node_count()];
    for corner in [[-0.1, 0.1, 0.0], [0.1, 0.1, 0.0]] {
        let (node, _) = mesh.nearest_node(corner).unwrap();
        fixed[3 * node..3 * node + 3].fill(true);
    }
    let model = Model::builder(
        mesh,
        Box::new(SaintVenantKirchhoff::new(2.0e6, 0.3)),
        Section {
            thickness: 6e-4,
            prestress: 0.0,
        },
        320.0,
    )
    .loads(vec![Load {
        kind: LoadKind::Surface {
            force: [0.0, 0.0, -1.8816],
        },
        ramp: None,
    }])
    .fixed(fixed)
    .build()
    .unwrap();
    // A deformed state: the cloth stretched 1 % and sagging, so every term
    // is non-trivial and the Hessian is positive definite (Cholesky).
    let y: Vec<f64> = model
        .initial_positions()
        .chunks(3)
        .flat_map(|x| [x[0] * 1.01, x[1] * 1.01, -0.05 * (x[1] - 0.1).powi(2)])
        .collect();
    (model, y)
}

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("assemble");
    group.sample_size(20);
    for n in [20usize, 100, 300] {
        let (model, y) = fabric(n);
        let mut fi = vec![0.0; model.dofs()];
        let mut h = vec![0.0; model.pattern().nnz()];
        group.bench_with_input(BenchmarkId::new("force+hessian", n), &n, |b, _| {
            b.iter(|| black_box(model.assemble(&y, &mut fi, Some(&mut h))))
        });
        group.bench_with_input(BenchmarkId::new("force", n), &n, |b, _| {
            b.iter(|| black_box(model.assemble(&y, &mut fi, None)))
        });
    }
    group.finish();
    let mut group = c.benchmark_group("newton_iteration");
    group.sample_size(10);
    for n in [20usize, 100, 300] {
        let (model, y) = fabric(n);
        let dofs = model.dofs();
        let (mut fi, fe) = (vec![0.0; dofs], vec![0.0; dofs]);
        let mut h = vec![0.0; model.pattern().nnz()];
        let mut linear =
            LinearSolver::new(&model.pattern().col_ptr, &model.pattern().row_idx).unwrap();
        let c_mass = 1.0 / (1.0 * 1e-3 * 1e-3);
        group.bench_with_input(
            BenchmarkId::new("assemble+factorise+solve", n),
            &n,
            |b, _| {
                b.iter(|| {
                    model.assemble(&y, &mut fi, Some(&mut h));
                    model.add_mass_to_hessian(c_mass, &mut h);
                    let mut g: Vec<f64> = fi.iter().zip(&fe).map(|(a, b)| b - a).collect();
                    model.apply_supports(&mut g, Some(&mut h));
                    linear.solve(&h, true, &mut g).unwrap();
                    black_box(g[0])
                })
            },
        );
    }
    group.finish();
}

criterion_group!(drape_benches, benches);
criterion_main!(drape_benches);
