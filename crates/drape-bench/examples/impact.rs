//! Debug aid: Newton's residuals at the impact step of a scenario.
//! `cargo run --release -p drape-bench --example impact -- SCENARIO STEPS`
use drape::integrator::newmark::DynamicWorkspace;
use drape::scenario::Scenario;
use drape::setup::Analysis;
use drape::simulation::reference_length;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = Path::new(&args[1]);
    let (s, src) = Scenario::read(path).unwrap();
    let setup = s.build(path, &src).unwrap();
    let Analysis::Dynamic { newmark, segments } = &setup.analysis else {
        return;
    };
    let model = &setup.model;
    let mut ws = DynamicWorkspace::new(model).unwrap();
    let mut state = newmark.initial_state(model, &mut ws).unwrap();
    let length = reference_length(&model.initial_positions());
    let mut settings = setup.newton;
    settings.max_iterations = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(30);
    let dts: Vec<f64> = segments
        .iter()
        .flat_map(|(n, dt)| std::iter::repeat_n(*dt, *n))
        .collect();
    let upto: usize = args[2].parse().unwrap();
    for (k, dt) in dts.iter().enumerate().take(upto) {
        match newmark.step(model, &mut state, *dt, &settings, length, &mut ws) {
            Ok(o) => {
                if k + 1 >= upto - 2 {
                    println!(
                        "step {} t {:.6}: {} its, residuals {:?}",
                        k + 1,
                        state.time,
                        o.newton.iterations,
                        o.newton
                            .residuals
                            .iter()
                            .map(|r| format!("{r:.2e}"))
                            .collect::<Vec<_>>()
                    );
                }
            }
            Err(e) => {
                println!("step {} failed: {e}", k + 1);
                return;
            }
        }
    }
}
