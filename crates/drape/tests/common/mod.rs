//! Helpers shared by the integration tests.
#![allow(dead_code)]

use drape::element::membrane::Section;
use drape::material::SaintVenantKirchhoff;
use drape::mesh::Mesh;
use drape::model::{Model, ModelBuilder};
use drape::scenario::Scenario;
use drape::setup::Setup;
use std::path::{Path, PathBuf};

/// A fresh, empty directory under the system's temp dir, unique to this
/// call (tests run in parallel threads of one process), removed when
/// dropped.
pub fn temp_dir(name: &str) -> TempDir {
    static COUNTER: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("drape-test-{}-{k}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

/// A directory removed when dropped.
pub struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Builds a setup from scenario text.
pub fn setup(text: &str) -> Setup {
    let path = Path::new("test.toml");
    Scenario::parse(text, path)
        .unwrap()
        .build(path, text)
        .unwrap()
}

/// The history as rows of numbers, with the header.
pub fn read_history(dir: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    (header, rows)
}

/// Column `name` of the history.
pub fn column(header: &[String], rows: &[Vec<f64>], name: &str) -> Vec<f64> {
    let k = header.iter().position(|h| h == name).unwrap();
    rows.iter().map(|r| r[k]).collect()
}

/// The model of `mesh` in the reference problem's material —
/// Saint-Venant–Kirchhoff, E = 2 MPa, nu = 0.3, 0.6 mm thick, no
/// prestress, 320 kg/m³ — to be completed by the caller (loads, supports,
/// bending, ...).
pub fn fabric_model(mesh: Mesh) -> ModelBuilder {
    Model::builder(
        mesh,
        Box::new(SaintVenantKirchhoff::new(2.0e6, 0.3)),
        Section {
            thickness: 6e-4,
            prestress: 0.0,
        },
        320.0,
    )
}

/// A 20 x 20 fabric of the reference problem's material, with extra TOML.
pub fn fabric(extra: &str) -> String {
    rectangle([0.2, 0.2], [20, 20], extra)
}

/// A rectangle of `size` (m) in `divisions` squares, of the reference
/// problem's material, with extra TOML.
pub fn rectangle(size: [f64; 2], divisions: [usize; 2], extra: &str) -> String {
    format!(
        r#"
[mesh]
shape = "rectangle"
size = {size:?}
divisions = {divisions:?}
[material]
youngs_modulus = 2.0e6
poisson_ratio = 0.3
density = 320.0
thickness = 0.6e-3
{extra}
"#
    )
}

/// Solves `F_int(Y) = 0` from `y0` with the fixed components held where
/// `y0` puts them (a static step to tolerance 1e-12), with up to
/// `chord_steps` chord steps after each Newton step; returns the
/// positions, Newton's report and the factorisations made.
pub fn equilibrium_with(
    model: &drape::model::Model,
    y0: Vec<f64>,
    chord_steps: usize,
) -> (Vec<f64>, drape::solver::NewtonReport, usize) {
    let mut ws = drape::integrator::newmark::DynamicWorkspace::new(model).unwrap();
    let mut state = drape::integrator::State::at_rest(model, y0);
    let settings = drape::solver::NewtonSettings {
        tolerance: 1e-12,
        residual_tolerance: 1e-10,
        max_iterations: 30,
        chord_steps,
        ..Default::default()
    };
    let length = drape::simulation::reference_length(&model.initial_positions());
    let report = drape::integrator::StaticStepper::default()
        .step(model, &mut state, 1.0, &settings, length, &mut ws)
        .unwrap();
    let stats = ws.newton.linear.stats;
    let factorisations =
        stats.block_lu_factorizations + stats.cholesky_factorizations + stats.lu_factorizations;
    (state.positions, report.newton, factorisations)
}

/// Parses and builds scenario `text` read from `path`; the error as text.
pub fn build(text: &str, path: &Path) -> Result<Setup, String> {
    Scenario::parse(text, path)
        .and_then(|s| s.build(path, text))
        .map_err(|e| e.to_string())
}

/// The error of `text`, which must contain `test.toml, line {line}:
/// `{key}`` and each of `fragments`.
pub fn assert_error(text: &str, line: usize, key: &str, fragments: &[&str]) {
    let message = match build(text, Path::new("test.toml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    };
    let located = format!("test.toml, line {line}: `{key}`");
    assert!(
        message.contains(&located),
        "expected {located:?} in\n{message}\nfor\n{text}"
    );
    for f in fragments {
        assert!(
            message.contains(f),
            "expected {f:?} in\n{message}\nfor\n{text}"
        );
    }
}

/// Static equilibrium of `s` (one step, Newton up to 50 iterations) with
/// its held nodes placed on the simple shear `x += gamma y` and the free
/// ones started off it (by up to 1 mm). Returns the positions and their
/// largest distance from the homogeneous shear (m).
pub fn sheared_equilibrium(s: &mut Setup, gamma: f64) -> (Vec<f64>, f64) {
    let x0 = s.model.initial_positions();
    let sheared: Vec<f64> = x0
        .chunks(3)
        .flat_map(|x| [x[0] + gamma * x[1], x[1], x[2]])
        .collect();
    let mut start = sheared.clone();
    for (i, v) in start.iter_mut().enumerate() {
        if !s.model.fixed()[i] {
            *v += 1e-3 * ((i * 7) as f64).sin();
        }
    }
    let mut ws = drape::integrator::newmark::DynamicWorkspace::new(&s.model).unwrap();
    let mut state = drape::integrator::State::at_rest(&s.model, start);
    let length = drape::simulation::reference_length(&x0);
    s.newton.max_iterations = 50;
    drape::integrator::StaticStepper::default()
        .step(&s.model, &mut state, 1.0, &s.newton, length, &mut ws)
        .unwrap();
    let off = state
        .positions
        .iter()
        .zip(&sheared)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    (state.positions, off)
}

/// `(time, position)` of one node after every step.
pub type Track = Vec<(f64, [f64; 3])>;

/// Steps scenario `text` (its scheme, Newton's settings) to `end` (s) from 1 ms steps, halving a step that
/// fails and growing it back after one that converges, and returns the
/// crossings after every step, the final positions, the steps taken, how
/// many times the Hessian's layout was built, and the track of `node`.
pub fn drive_through(
    text: &str,
    end: f64,
    node: Option<usize>,
) -> (Vec<usize>, Vec<f64>, usize, usize, Track) {
    use drape::integrator::newmark::DynamicWorkspace;
    let s = setup(text);
    let drape::setup::Analysis::Dynamic { newmark, .. } = &s.analysis else {
        panic!("dynamic")
    };
    // Curved elements by their linear sub-triangles, as self-contact
    // measures them.
    let (triangles, _) = drape::bending::triangulate(s.model.mesh());
    let edges = drape::contact::proximity::edges_of(&triangles);
    let mut ws = DynamicWorkspace::new(&s.model).unwrap();
    let mut state = newmark.initial_state(&s.model, &mut ws).unwrap();
    let length = drape::simulation::reference_length(&s.model.initial_positions());
    let (mut dt, mut seen, mut steps) = (1e-3f64, Vec::new(), 0);
    let mut track = Vec::new();
    while state.time < end - 1e-12 {
        let saved = state.clone();
        let h = dt.min(end - state.time);
        match newmark.step(&s.model, &mut state, h, &s.newton, length, &mut ws) {
            Ok(_) => {
                let x: Vec<[f64; 3]> = state
                    .positions
                    .chunks(3)
                    .map(|c| [c[0], c[1], c[2]])
                    .collect();
                seen.push(drape::contact::proximity::crossings(&x, &triangles, &edges));
                if let Some(a) = node {
                    track.push((state.time, x[a]));
                }
                steps += 1;
                dt = (2.0 * dt).min(1e-3);
            }
            Err(e) => {
                state = saved;
                dt *= 0.5;
                assert!(dt > 1e-7, "step from t = {} failed: {e}", state.time);
            }
        }
    }
    (seen, state.positions, steps, ws.layout_builds(), track)
}

/// Runs the scenario file `path` whole into `dir/whole`, and again into
/// `dir/out` stopped after step `stop_at` (an interrupted run with its
/// checkpoint); `check` sees that checkpoint; then resumes `dir/out` to the
/// end and asserts that both histories are byte for byte the same.
pub fn stops_and_resumes_bit_for_bit(
    path: &Path,
    dir: &Path,
    stop_at: usize,
    check: impl FnOnce(&drape::simulation::Checkpoint),
) {
    use drape::simulation::{RunControl, RunError, StepInfo};
    use std::sync::atomic::{AtomicBool, Ordering};
    let setup = || {
        let (scenario, source) = Scenario::read(path).unwrap();
        scenario.build(path, &source).unwrap()
    };
    let whole = dir.join("whole");
    drape::simulation::run(&setup(), &whole, &mut |_| {}).unwrap();
    let out = dir.join("out");
    let stop = AtomicBool::new(false);
    let mut observer = |info: &StepInfo| {
        if info.step == stop_at {
            stop.store(true, Ordering::SeqCst);
        }
    };
    let control = RunControl {
        stop: Some(&stop),
        resume: false,
        ..Default::default()
    };
    let stopped = drape::simulation::run_with(&setup(), &out, &mut observer, control);
    assert!(
        matches!(stopped, Err(RunError::Interrupted { .. })),
        "{stopped:?}"
    );
    let ck = drape::simulation::Checkpoint::read(
        &std::fs::read(drape::simulation::checkpoint_path(&out)).unwrap(),
        &setup(),
    )
    .unwrap();
    check(&ck);
    let control = RunControl {
        stop: None,
        resume: true,
        ..Default::default()
    };
    drape::simulation::run_with(&setup(), &out, &mut |_| {}, control).unwrap();
    let read = |d: &Path| std::fs::read(d.join("history.csv")).unwrap();
    assert_eq!(read(&whole), read(&out));
}

/// Steps a dynamic setup through its schedule (no cut-back), calling
/// `check` after every step.
pub fn drive(
    s: &drape::setup::Setup,
    mut check: impl FnMut(&drape::integrator::State),
) -> drape::integrator::State {
    use drape::integrator::newmark::DynamicWorkspace;
    let drape::setup::Analysis::Dynamic { newmark, segments } = &s.analysis else {
        panic!("dynamic only")
    };
    let mut ws = DynamicWorkspace::new(&s.model).unwrap();
    let mut state = newmark.initial_state(&s.model, &mut ws).unwrap();
    let length = drape::simulation::reference_length(&s.model.initial_positions());
    for (n, dt) in segments {
        for _ in 0..*n {
            newmark
                .step(&s.model, &mut state, *dt, &s.newton, length, &mut ws)
                .unwrap();
            check(&state);
        }
    }
    state
}
