//! The settle benchmark's factorisation: `cargo run --release -p
//! drape-bench --example settle_factor [SCENARIO]` builds the model of
//! `crates/drape-bench/scenarios/settle-bending-t3.toml` (or SCENARIO),
//! assembles its membrane Hessian at the initial positions plus the mass
//! term of a 1 ms step (positive definite, on the pattern with bending's
//! stencils), and reports the node-block factor's size and flops and the
//! best and median time of 50 symmetric factorisations.

use drape::scenario::Scenario;
use drape::solver::block_lu::BlockLu;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn main() {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/settle-bending-t3.toml")
        });
    let text = std::fs::read_to_string(&path).unwrap();
    let s = Scenario::parse(&text, &path)
        .unwrap()
        .build(&path, &text)
        .unwrap();
    let model = &s.model;
    let y = model.initial_positions();
    let mut f = vec![0.0; model.dofs()];
    let mut h = vec![0.0; model.pattern().nnz()];
    model.assemble(&y, &mut f, Some(&mut h));
    model.add_mass_to_hessian(1.0 / 1e-6, &mut h);
    let (ptr, rows) = model.pattern().node_graph();
    let mut lu = BlockLu::new(ptr, rows).unwrap();
    let flops = lu.flops(true);
    println!(
        "{}: {} nodes, {} blocks in A, {} blocks in L, {:.1} Mflop (symmetric), split {}",
        path.display(),
        lu.nodes(),
        rows.len(),
        lu.factor_blocks(),
        flops / 1e6,
        lu.is_split()
    );
    let mut times: Vec<f64> = (0..50)
        .map(|_| {
            let t = Instant::now();
            lu.factorize(&h, true).unwrap();
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    println!(
        "factorise: best {:.3} ms, median {:.3} ms ({:.1} Gflop/s at the best)",
        1e3 * times[0],
        1e3 * times[25],
        flops / times[0] / 1e9
    );
}
