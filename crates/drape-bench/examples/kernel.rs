//! The pedestal's per-iteration work at a draped state: `cargo run
//! --release -p drape-bench --example kernel` advances the reference
//! problem 300 steps, then times, at that state, assemblies with and
//! without the Hessian, the per-step element statistics (state fractions,
//! smallest stretch), the block LU's factorisation and solve, and the
//! linear solver's overhead around them (the residual check), each
//! repeated; `RAYON_NUM_THREADS=1` for one thread. On this machine's
//! noisy virtual CPUs, compare builds by alternating runs.

use drape::integrator::State;
use drape::model::Model;
use drape::scenario::Scenario;
use drape::setup::Setup;
use drape::solver::LinearSolver;
use drape::solver::block_lu::BlockLu;
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

fn main() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fabric-on-pedestal.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let s = Scenario::parse(&text, &path)
        .unwrap()
        .build(&path, &text)
        .unwrap();
    let model = &s.model;
    let state = draped(&s, 300);
    let y = &state.positions;
    let dofs = model.dofs();
    let mut fi = vec![0.0; dofs];
    let mut h = vec![0.0; model.pattern().nnz()];
    println!("states: {:?}", model.state_fractions(y));
    time_assembly(model, y, &mut fi, &mut h);
    time_statistics(model, y);
    time_mass(model, y, &mut h);
    // The block LU of the Hessian with the mass term of a 1e-4 s step.
    model.assemble(y, &mut fi, Some(&mut h));
    model.add_mass_to_hessian(1e8, &mut h);
    let (ptr, rows) = model.pattern().node_graph();
    let mut lu = BlockLu::new(ptr, rows).unwrap();
    lu.factorize(&h, false).unwrap();
    let b: Vec<f64> = (0..dofs).map(|i| (i as f64 * 0.37).sin()).collect();
    let mut x = b.clone();
    time_block_lu(&mut lu, &h, &b, &mut x);
    time_solver_overhead(model, &mut lu, &h, &b, &mut x);
    // A factorisation right after an assembly, as in a Newton iteration.
    let mut h2 = h.clone();
    for _ in 0..3 {
        let mut total = 0.0;
        for _ in 0..1000 {
            model.assemble(y, &mut fi, Some(&mut h2));
            total += per_call_us(1, || lu.factorize(&h, false).unwrap());
        }
        println!("factorize after an assembly {:.1} us", total / 1000.0);
    }
    println!(
        "checksums {:e} {:e} {:e}",
        h.iter().map(|v| v.abs()).sum::<f64>(),
        fi.iter().map(|v| v.abs()).sum::<f64>(),
        x.iter().map(|v| v.abs()).sum::<f64>()
    );
}

/// The state of the scenario `s` (dynamic) after `steps` steps.
fn draped(s: &Setup, steps: usize) -> State {
    let drape::setup::Analysis::Dynamic { newmark, segments } = &s.analysis else {
        panic!("dynamic")
    };
    let model = &s.model;
    let mut ws = drape::integrator::newmark::DynamicWorkspace::new(model).unwrap();
    let mut state = newmark.initial_state(model, &mut ws).unwrap();
    let length = drape::simulation::reference_length(&model.initial_positions());
    let mut left = steps;
    'outer: for &(steps, dt) in segments {
        for _ in 0..steps {
            newmark
                .step(model, &mut state, dt, &s.newton, length, &mut ws)
                .unwrap();
            left -= 1;
            if left == 0 {
                break 'outer;
            }
        }
    }
    state
}

/// Assemblies at `y` with and without the Hessian.
fn time_assembly(model: &Model, y: &[f64], fi: &mut [f64], h: &mut [f64]) {
    let elements = model.mesh().element_count() as f64;
    for _ in 0..3 {
        let with = per_call_us(3000, || {
            black_box(model.assemble(y, fi, Some(h)));
        });
        let without = per_call_us(3000, || {
            black_box(model.assemble(y, fi, None));
        });
        println!(
            "force+hessian {with:.1} us ({:.0} ns/element), force {without:.1} us ({:.0} ns/element)",
            with * 1e3 / elements,
            without * 1e3 / elements
        );
    }
}

/// The per-step element statistics at `y`, apart and in one pass.
fn time_statistics(model: &Model, y: &[f64]) {
    for _ in 0..3 {
        let fractions = per_call_us(3000, || {
            black_box(model.state_fractions(y));
        });
        let stretch = per_call_us(3000, || {
            black_box(model.min_stretch(y));
        });
        let both = per_call_us(3000, || {
            black_box(model.stretch_and_states(y));
        });
        println!(
            "state fractions {fractions:.1} us, min stretch {stretch:.1} us, both in one pass {both:.1} us"
        );
    }
}

/// The mass matrix's product and its addition to the Hessian `h`.
fn time_mass(model: &Model, y: &[f64], h: &mut [f64]) {
    let mut out = vec![0.0; model.dofs()];
    for _ in 0..3 {
        let product = per_call_us(20000, || model.mass_times(y, black_box(&mut out)));
        let term = per_call_us(20000, || model.add_mass_to_hessian(1.0, black_box(&mut *h)));
        println!("mass times {product:.2} us, add mass to Hessian {term:.2} us");
    }
}

/// The block LU's solve for `b` and its factorisation of `h`.
fn time_block_lu(lu: &mut BlockLu, h: &[f64], b: &[f64], x: &mut [f64]) {
    for _ in 0..3 {
        let solve = per_call_us(5000, || {
            x.copy_from_slice(b);
            lu.solve_in_place(black_box(&mut *x));
        });
        let factorize = per_call_us(1000, || lu.factorize(black_box(h), false).unwrap());
        println!("block LU: solve {solve:.1} us, factorize {factorize:.1} us");
    }
}

/// The linear solver's overhead around factorisation and solve (the
/// residual check): both timed alternately, the median difference.
fn time_solver_overhead(model: &Model, lu: &mut BlockLu, h: &[f64], b: &[f64], x: &mut [f64]) {
    let (ptr, rows) = model.pattern().node_graph();
    let mut linear = LinearSolver::new(&model.pattern().col_ptr, &model.pattern().row_idx)
        .unwrap()
        .with_transpose(model.pattern().transpose_map().to_vec())
        .with_node_blocks(ptr, rows);
    for _ in 0..3 {
        let mut differences: Vec<f64> = (0..1000)
            .map(|_| {
                let solver = per_call_us(1, || {
                    x.copy_from_slice(b);
                    linear.solve(h, false, x).unwrap();
                });
                let bare = per_call_us(1, || {
                    x.copy_from_slice(b);
                    lu.factorize(h, false).unwrap();
                    lu.solve_in_place(x);
                });
                solver - bare
            })
            .collect();
        differences.sort_by(f64::total_cmp);
        println!(
            "LinearSolver::solve's overhead: median {:.1} us",
            differences[differences.len() / 2]
        );
    }
}

/// Mean wall time of `f` over `reps` calls (µs).
fn per_call_us(reps: usize, mut f: impl FnMut()) -> f64 {
    let t = Instant::now();
    for _ in 0..reps {
        f();
    }
    t.elapsed().as_secs_f64() / reps as f64 * 1e6
}
