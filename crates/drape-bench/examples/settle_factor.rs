//! The settle benchmark's factorisation: `cargo run --release -p
//! drape-bench --example settle_factor [SCENARIO]` builds the model of
//! `crates/drape-bench/scenarios/settle-bending-t3.toml` (or SCENARIO),
//! assembles its membrane Hessian at the initial positions plus the mass
//! term of a 1 ms step (positive definite, on the pattern with bending's
//! stencils), and reports the node-block factor's size and flops and the
//! best and median time of 50 symmetric factorisations; then faer's
//! supernodal Cholesky of the same matrix (AMD ordering, as
//! `drape::solver` analyses it) on one thread (`Par::Seq`, as drape runs
//! it) and on rayon's pool: the factor's entries and the best and median
//! of 20 numeric factorisations. `RAYON_NUM_THREADS=1` for one thread
//! throughout.

use drape::scenario::Scenario;
use drape::solver::block_lu::BlockLu;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Par, Side};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn main() {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/settle-bending-t3.toml")
        });
    let (scenario, text) = Scenario::read(&path).unwrap();
    let s = scenario.build(&path, &text).unwrap();
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
    let pattern = model.pattern();
    let n = pattern.col_ptr.len() - 1;
    let symbolic =
        SymbolicSparseColMatRef::new_checked(n, n, &pattern.col_ptr, None, &pattern.row_idx);
    for (name, par) in [("one thread", Par::Seq), ("rayon", Par::rayon(0))] {
        let t = Instant::now();
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symb =
            factorize_symbolic_cholesky(symbolic, Side::Lower, SymmetricOrdering::Amd, params)
                .unwrap();
        let analysis = t.elapsed().as_secs_f64();
        let mut l = vec![0.0; symb.len_val()];
        let mut mem =
            MemBuffer::new(symb.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
        let a = SparseColMatRef::new(symbolic, &h);
        let mut times: Vec<f64> = (0..20)
            .map(|_| {
                let t = Instant::now();
                symb.factorize_numeric_llt::<f64>(
                    &mut l,
                    a,
                    Side::Lower,
                    LltRegularization::default(),
                    par,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .unwrap();
                t.elapsed().as_secs_f64()
            })
            .collect();
        times.sort_by(f64::total_cmp);
        println!(
            "faer Cholesky (AMD), {name}: {} entries in L, analysis {:.1} ms, factorise best {:.2} ms, median {:.2} ms",
            symb.len_val(),
            1e3 * analysis,
            1e3 * times[0],
            1e3 * times[10]
        );
    }
}
