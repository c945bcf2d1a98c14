//! Newton's residual history step by step: `cargo run --release -p
//! drape-bench --example newton_trace -- SCENARIO.toml FIRST LAST` runs
//! the scenario's schedule (fixed steps, cut-back by halving) and prints,
//! for the converged steps FIRST..=LAST, each Newton iterate's residual
//! `|G|` and relative increment, and the elements whose wrinkling state
//! changed between the step's first guess and its solution. For
//! diagnosing slow convergence (docs/performance.md).

use drape::scenario::Scenario;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = Path::new(&args[1]);
    let first: usize = args[2].parse().unwrap();
    let last: usize = args[3].parse().unwrap();
    let text = std::fs::read_to_string(path).unwrap();
    let s = Scenario::parse(&text, path)
        .unwrap()
        .build(path, &text)
        .unwrap();
    let drape::setup::Analysis::Dynamic { newmark, segments } = &s.analysis else {
        panic!("dynamic")
    };
    let model = &s.model;
    let mut ws = drape::integrator::newmark::DynamicWorkspace::new(model).unwrap();
    let mut state = newmark.initial_state(model, &mut ws).unwrap();
    let length = drape::simulation::reference_length(&model.initial_positions());
    let mut step = 0;
    for &(steps, dt) in segments {
        for _ in 0..steps {
            let mut pending = vec![(dt, 0)];
            while let Some((h, depth)) = pending.pop() {
                let before = state.clone();
                match newmark.step(model, &mut state, h, &s.newton, length, &mut ws) {
                    Ok(out) => {
                        step += 1;
                        if step >= first {
                            let (f0, f1) = (
                                model.state_fractions(&before.positions),
                                model.state_fractions(&state.positions),
                            );
                            println!(
                                "step {step} t {:.4} dt {h:.2e} depth {depth} newton {} chord {} states {:.3?} -> {:.3?}",
                                state.time, out.newton.iterations, out.newton.chord_steps, f0, f1
                            );
                            for (k, r) in out.newton.residuals.iter().enumerate() {
                                let inc = out.newton.increments.get(k).copied().unwrap_or(f64::NAN);
                                println!("   {k:2} |G| {r:.3e}  |dY|/|X| {inc:.3e}");
                            }
                        }
                        if step >= last {
                            return;
                        }
                    }
                    Err(e) => {
                        if step >= first {
                            println!(
                                "step {} t {:.4} dt {h:.2e} FAILED: {e}",
                                step + 1,
                                state.time
                            );
                        }
                        pending.push((h / 2.0, depth + 1));
                        pending.push((h / 2.0, depth + 1));
                    }
                }
            }
        }
    }
}
