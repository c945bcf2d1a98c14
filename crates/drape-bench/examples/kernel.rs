//! The pedestal's per-iteration work at a draped state: `cargo run
//! --release -p drape-bench --example kernel` advances the reference
//! problem 300 steps, then times, at that state, assemblies with and
//! without the Hessian, the per-step element statistics (state fractions,
//! smallest stretch), the block LU's factorisation and solve, and the
//! linear solver's overhead around them (the residual check), each
//! repeated; `RAYON_NUM_THREADS=1` for one thread. On this machine's
//! noisy virtual CPUs, compare builds by alternating runs.

use drape::scenario::Scenario;
use std::path::Path;
use std::time::Instant;

fn main() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fabric-on-pedestal.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let s = Scenario::parse(&text, &path)
        .unwrap()
        .build(&path, &text)
        .unwrap();
    let drape::scenario::Analysis::Dynamic { newmark, segments } = &s.analysis else {
        panic!("dynamic")
    };
    let model = &s.model;
    let mut ws = drape::integrator::newmark::DynamicWorkspace::new(model).unwrap();
    let mut state = newmark.initial_state(model, &mut ws).unwrap();
    let length = drape::simulation::reference_length(&model.initial_positions());
    let mut left = 300;
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
    let y = &state.positions;
    let dofs = model.dofs();
    let (mut fi, mut fe) = (vec![0.0; dofs], vec![0.0; dofs]);
    let mut h = vec![0.0; model.pattern.nnz()];
    println!("states: {:?}", model.state_fractions(y));
    for _ in 0..3 {
        let reps = 3000;
        let t = Instant::now();
        for _ in 0..reps {
            std::hint::black_box(model.assemble(y, 0.0, &mut fi, &mut fe, Some(&mut h)));
        }
        let th = t.elapsed().as_secs_f64() / reps as f64;
        let t = Instant::now();
        for _ in 0..reps {
            std::hint::black_box(model.assemble(y, 0.0, &mut fi, &mut fe, None));
        }
        let tf = t.elapsed().as_secs_f64() / reps as f64;
        println!(
            "force+hessian {:.1} us ({:.0} ns/element), force {:.1} us ({:.0} ns/element)",
            th * 1e6,
            th * 1e9 / model.mesh.element_count() as f64,
            tf * 1e6,
            tf * 1e9 / model.mesh.element_count() as f64
        );
    }
    for _ in 0..3 {
        let reps = 3000;
        let time = |f: &dyn Fn()| {
            let t = Instant::now();
            for _ in 0..reps {
                f();
            }
            t.elapsed().as_secs_f64() / reps as f64 * 1e6
        };
        let fractions = time(&|| {
            std::hint::black_box(model.state_fractions(y));
        });
        let stretch = time(&|| {
            std::hint::black_box(model.min_stretch(y));
        });
        let both = time(&|| {
            std::hint::black_box(model.stretch_and_states(y));
        });
        println!(
            "state fractions {fractions:.1} us, min stretch {stretch:.1} us, both in one pass {both:.1} us"
        );
    }
    {
        let reps = 20000;
        let mut out = vec![0.0; dofs];
        for _ in 0..3 {
            let t = Instant::now();
            for _ in 0..reps {
                model.mass_times(y, &mut out);
                std::hint::black_box(&out);
            }
            println!(
                "mass times {:.2} us",
                t.elapsed().as_secs_f64() / reps as f64 * 1e6
            );
            let t = Instant::now();
            for _ in 0..reps {
                model.add_mass_to_hessian(1.0, &mut h);
                std::hint::black_box(&h);
            }
            println!(
                "add mass to Hessian {:.2} us",
                t.elapsed().as_secs_f64() / reps as f64 * 1e6
            );
        }
    }
    {
        use drape::solver::block_lu::BlockLu;
        model.assemble(y, 0.0, &mut fi, &mut fe, Some(&mut h));
        model.add_mass_to_hessian(1e8, &mut h);
        let (ptr, rows) = model.pattern.node_graph();
        let mut lu = BlockLu::new(ptr, rows).unwrap();
        lu.factorize(&h, false).unwrap();
        let b: Vec<f64> = (0..dofs).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut x = b.clone();
        for _ in 0..3 {
            let reps = 5000;
            let t = Instant::now();
            for _ in 0..reps {
                x.copy_from_slice(&b);
                lu.solve_in_place(&mut x);
                std::hint::black_box(&x);
            }
            let ts = t.elapsed().as_secs_f64() / reps as f64;
            let t = Instant::now();
            for _ in 0..reps / 5 {
                lu.factorize(&h, false).unwrap();
            }
            let tf = t.elapsed().as_secs_f64() / (reps / 5) as f64;
            println!(
                "block LU: solve {:.1} us, factorize {:.1} us",
                ts * 1e6,
                tf * 1e6
            );
        }
        println!(
            "solution checksum {:e}",
            x.iter().map(|v| v.abs()).sum::<f64>()
        );
        let (node_ptr, node_rows) = model.pattern.node_graph();
        let mut linear =
            drape::solver::LinearSolver::new(&model.pattern.col_ptr, &model.pattern.row_idx)
                .unwrap()
                .with_transpose(model.pattern.transpose_map().to_vec())
                .with_node_blocks(node_ptr, node_rows);
        for _ in 0..3 {
            let reps = 1000;
            let t = Instant::now();
            for _ in 0..reps {
                x.copy_from_slice(&b);
                linear.solve(&h, false, &mut x).unwrap();
            }
            let tl = t.elapsed().as_secs_f64() / reps as f64;
            println!(
                "LinearSolver::solve (factorise, solve, check) {:.1} us",
                tl * 1e6
            );
        }
        for _ in 0..3 {
            let reps = 1000;
            let (mut ta, mut tb) = (0.0, 0.0);
            let mut diffs = Vec::new();
            for _ in 0..reps {
                x.copy_from_slice(&b);
                let t = Instant::now();
                linear.solve(&h, false, &mut x).unwrap();
                let a = t.elapsed().as_secs_f64();
                x.copy_from_slice(&b);
                let t = Instant::now();
                lu.factorize(&h, false).unwrap();
                lu.solve_in_place(&mut x);
                let c = t.elapsed().as_secs_f64();
                ta += a;
                tb += c;
                diffs.push(a - c);
            }
            diffs.sort_by(f64::total_cmp);
            println!("median overhead {:.1} us", diffs[reps / 2] * 1e6);
            println!(
                "LinearSolver::solve {:.1} us, bare factorize + solve {:.1} us: overhead {:.1} us",
                ta / reps as f64 * 1e6,
                tb / reps as f64 * 1e6,
                (ta - tb) / reps as f64 * 1e6
            );
        }
        let mut h2 = h.clone();
        for _ in 0..3 {
            let reps = 1000;
            let mut tf = 0.0;
            for _ in 0..reps {
                model.assemble(y, 0.0, &mut fi, &mut fe, Some(&mut h2));
                let t = Instant::now();
                lu.factorize(&h, false).unwrap();
                tf += t.elapsed().as_secs_f64();
            }
            println!(
                "factorize after an assembly {:.1} us",
                tf / reps as f64 * 1e6
            );
        }
    }
    let s: f64 = h.iter().map(|v| v.abs()).sum();
    println!(
        "checksum {s:e} {:e}",
        fi.iter().map(|v| v.abs()).sum::<f64>()
    );
}
