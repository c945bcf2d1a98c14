//! Where the time of one Newton iteration goes, by phase, for a fabric of
//! `N x N` divisions: `cargo run --release -p drape-bench --example
//! breakdown -- N` (default 100).

use drape::element::membrane::Section;
use drape::load::{Load, LoadKind};
use drape::material::SaintVenantKirchhoff;
use drape::mesh::ElementOrder;
use drape::mesh::generate::{Pattern, rectangle};
use drape::model::Model;
use drape::solver::LinearSolver;
use std::time::Instant;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(100);
    let t0 = Instant::now();
    let mesh = rectangle(
        [0.2, 0.2],
        [n, n],
        Pattern::Right,
        [0.0; 3],
        ElementOrder::Linear,
    );
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
    .build()
    .unwrap();
    println!(
        "{n}x{n}: {} DOF, nnz {}, model set-up {:.3} s",
        model.dofs(),
        model.pattern().nnz(),
        t0.elapsed().as_secs_f64()
    );
    let y: Vec<f64> = model
        .initial_positions()
        .chunks(3)
        .flat_map(|x| [x[0] * 1.01, x[1] * 1.01, -0.05 * (x[1] - 0.1).powi(2)])
        .collect();
    let dofs = model.dofs();
    let (mut fi, fe) = (vec![0.0; dofs], vec![0.0; dofs]);
    let mut h = vec![0.0; model.pattern().nnz()];
    let t = Instant::now();
    let mut linear = LinearSolver::new(&model.pattern().col_ptr, &model.pattern().row_idx).unwrap();
    println!(
        "  solver set-up            {:.4} s",
        t.elapsed().as_secs_f64()
    );
    model.assemble(&y, &mut fi, Some(&mut h));
    model.add_mass_to_hessian(1e6, &mut h);
    bare(&model.pattern().col_ptr, &model.pattern().row_idx, &h);
    block_lu(&model, &h);
    for round in 0..3 {
        let t = Instant::now();
        model.assemble(&y, &mut fi, Some(&mut h));
        let ta = t.elapsed().as_secs_f64();
        let t = Instant::now();
        model.add_mass_to_hessian(1e6, &mut h);
        let tm = t.elapsed().as_secs_f64();
        let mut g: Vec<f64> = fi.iter().zip(&fe).map(|(a, b)| b - a).collect();
        let t = Instant::now();
        linear.solve(&h, true, &mut g).unwrap();
        let ts = t.elapsed().as_secs_f64();
        println!("  nnz(L) = {:?}", linear.cholesky_nnz());
        println!(
            "  round {round}: assemble {ta:.4} s, add mass {tm:.4} s, factorise+solve {ts:.4} s (first includes the symbolic analysis)"
        );
    }
}

/// The node-block LU on the same matrix: symbolic analysis, numeric
/// factorisation with symmetric and general values, one solve.
fn block_lu(model: &Model, h: &[f64]) {
    use drape::solver::block_lu::BlockLu;
    let (ptr, rows) = model.pattern().node_graph();
    let t = Instant::now();
    let mut lu = BlockLu::new(ptr, rows).unwrap();
    println!(
        "  block LU: symbolic {:.4} s, split in two halves: {}, {} blocks in L ({} scalars), {:.1} / {:.1} Mflop (sym / general), {} MB",
        t.elapsed().as_secs_f64(),
        lu.is_split(),
        lu.factor_blocks(),
        9 * lu.factor_blocks() + 6 * lu.nodes(),
        2e-6 * lu.flops(true),
        2e-6 * lu.flops(false),
        lu.bytes() >> 20
    );
    for symmetric in [true, false] {
        // The fastest of 30 factorisations (the machine is noisy).
        let tf = (0..30)
            .map(|_| {
                let t = Instant::now();
                lu.factorize(h, symmetric).unwrap();
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min);
        let mut x = vec![1.0; h.len().min(3 * lu.nodes())];
        let t = Instant::now();
        lu.solve_in_place(&mut x);
        println!(
            "  block LU ({}): numeric {tf:.5} s ({:.2} Gflop/s), solve {:.5} s",
            if symmetric { "symmetric" } else { "general" },
            2e-9 * lu.flops(symmetric) / tf,
            t.elapsed().as_secs_f64()
        );
    }
}

/// Bare faer on the same matrix: lower triangle only vs. the full matrix.
#[allow(dead_code)]
pub fn bare(col_ptr: &[usize], row_idx: &[usize], values: &[f64]) {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::llt::factor::LltRegularization;
    use faer::sparse::linalg::cholesky::{SymmetricOrdering, factorize_symbolic_cholesky};
    use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
    use faer::{Par, Side};
    let n = col_ptr.len() - 1;
    for lower_only in [false, true] {
        let (mut cp, mut ri, mut v) = (vec![0usize], vec![], vec![]);
        for c in 0..n {
            for k in col_ptr[c]..col_ptr[c + 1] {
                if !lower_only || row_idx[k] >= c {
                    ri.push(row_idx[k]);
                    v.push(values[k]);
                }
            }
            cp.push(ri.len());
        }
        let sym = SymbolicSparseColMat::new_checked(n, n, cp, None, ri);
        let t = Instant::now();
        let symb = factorize_symbolic_cholesky(
            sym.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .unwrap();
        let ts = t.elapsed().as_secs_f64();
        let mut l = vec![0.0; symb.len_val()];
        let par = Par::Seq;
        let mut mem =
            MemBuffer::new(symb.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
        let a = SparseColMatRef::new(sym.as_ref(), &v);
        for _ in 0..2 {
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
            println!(
                "  bare faer (lower only: {lower_only}): symbolic {ts:.4} s, numeric {:.4} s",
                t.elapsed().as_secs_f64()
            );
        }
    }
}
