//! `drape.run` and `drape.check`: what `drape run` and `drape check` do,
//! called from Python.
//!
//! The run holds the output directory as the command line does, through
//! the library's [`Session`] (its lock, a fresh run's clean slate,
//! `scenario.toml` and `scenario.path` for a resume and for readers, a
//! refused resume recorded in its words: `resume=False`), and runs with
//! the GIL released. Ctrl-C
//! reaches a Rust loop only through Python: the interpreter's own handler
//! records the signal, and only its main thread is told. So the run goes
//! on a thread of its own while the calling thread waits for it with the
//! GIL released and asks for signals (`PyErr_CheckSignals`) every
//! [`SIGNAL_INTERVAL`], wherever the run is — inside a step too; a pending
//! `KeyboardInterrupt` sets the stop flag the command line's handler sets,
//! so the run ends as it does there — inside a step, its Newton solve
//! interrupted at its next iteration; a checkpoint; the summary
//! (`"interrupted"`) — and then the `KeyboardInterrupt` is raised.

use crate::errors::{output_error, run_error, scenario_error};
use crate::input::Source;
use crate::result::{RunResult, absolute, json_to_py};
use drape::output::directory::DirectoryError;
use drape::simulation::{Front, RunError, Session, StepInfo};
use pyo3::exceptions::{PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// How often a run asks Python whether a signal came: attaching to the
/// interpreter costs about a microsecond when no other thread holds it,
/// and at most a switch interval (5 ms) when one does.
const SIGNAL_INTERVAL: Duration = Duration::from_millis(50);

/// Runs a scenario and writes its outputs, as `drape run` does.
///
/// Args:
///     scenario: the path of a scenario file (TOML), or a dict with the
///         TOML's structure (its relative paths are taken from the working
///         directory).
///     out: the output directory; default ``out/<scenario stem>`` for a
///         file (as the command line), required for a dict.
///     resume: continue the interrupted run in ``out`` from its checkpoint
///         (the same scenario and input files), as ``drape run --resume``;
///         a refused resume is recorded in ``out/summary.json`` (status
///         ``"failed"``, the message), as the command line records it.
///
/// Returns:
///     RunResult: the summary, the history and the frames written in ``out``.
///
/// Raises:
///     ScenarioError: the scenario is invalid (with its file, key and line).
///     RunError: the run failed (``result`` holds what it wrote up to then),
///         or a resume was refused: an input file or the scenario changed
///         since the checkpoint, or the checkpoint cannot be used (the
///         message starts "cannot resume"; ``result`` holds the directory,
///         whose summary says why).
///     OutputError: ``out`` is in use by another run or holds other files;
///         with ``resume``, ``out`` is not the directory of a run.
///     KeyboardInterrupt: Ctrl-C; the run stopped within its step (the
///         step's Newton solve ends at its next iteration, the step is not
///         taken) and wrote a checkpoint of its last step and its summary
///         (status ``"interrupted"``) first.
///         (Python handles signals on its main thread: a run on another
///         thread goes on.)
#[pyfunction]
#[pyo3(signature = (scenario, out = None, *, resume = false))]
pub fn run(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    out: Option<PathBuf>,
    resume: bool,
) -> PyResult<RunResult> {
    let source = Source::from_py(scenario)?;
    let out = match (out, &source) {
        (Some(out), _) => out,
        (None, Source::File(path)) => default_out(path),
        (None, Source::Dict(_)) => {
            return Err(PyValueError::new_err(
                "a scenario given as a dict needs out=: there is no file name to name the output directory after",
            ));
        }
    };
    // Absolute from here on: the run, its messages and the result it
    // returns name one directory whatever the working directory becomes.
    let out = absolute(out);
    let from_dict = matches!(source, Source::Dict(_));
    let directory_error = |e: DirectoryError| output_error(py, e.to_string(), &out);
    let (session, loaded) = if resume {
        // As the command line: the directory (which must hold a run) is
        // held before anything is read, and a refusal from then on is
        // recorded in its summary.
        let session = Session::resume(&out, Front::Python).map_err(directory_error)?;
        // A changed or missing input file is named as such, before the
        // scenario reads it.
        session
            .check_inputs()
            .map_err(|message| run_error(py, message, &out))?;
        match py.detach(|| source.load()) {
            Ok(loaded) => (session, loaded),
            Err(e) => {
                // The scenario's own error is raised; the summary says it
                // too (or could not).
                let _ = session.refuse(&e);
                return Err(scenario_error(py, &e, from_dict));
            }
        }
    } else {
        let loaded = py
            .detach(|| source.load())
            .map_err(|e| scenario_error(py, &e, from_dict))?;
        let session = Session::fresh(&out, Front::Python).map_err(directory_error)?;
        let (file, text) = match &source {
            Source::File(path) => (Some(path.as_path()), loaded.text.as_str()),
            Source::Dict(text) => (None, text.as_str()),
        };
        session.start_fresh(file).map_err(directory_error)?;
        session
            .keep_scenario(file, text, &loaded.setup)
            .map_err(|message| output_error(py, message, &out))?;
        (session, loaded)
    };

    let stop = AtomicBool::new(false);
    let control = session.control(Some(&stop));
    let (loaded, source, dir) = (&loaded, &source, out.as_path());
    let (result, signal) = std::thread::scope(|scope| {
        // The run goes on a thread of its own, so that this thread — the
        // interpreter's main thread, the only one Python tells of a signal
        // — can ask for signals while a step is under way, however long.
        let waiting = std::thread::current();
        let worker = scope.spawn(move || {
            let result = drape::levels::run_with(
                &loaded.scenario,
                (source.file(), &loaded.text),
                &loaded.setup,
                dir,
                &mut |_: &StepInfo| {},
                control,
            );
            waiting.unpark();
            result
        });
        let mut signal: Option<PyErr> = None;
        // Sleeps with the GIL released; wakes when the run ends or every
        // SIGNAL_INTERVAL to ask Python whether a signal came.
        while !worker.is_finished() {
            py.detach(|| std::thread::park_timeout(SIGNAL_INTERVAL));
            if signal.is_none()
                && let Err(e) = py.check_signals()
            {
                signal = Some(e);
                stop.store(true, Ordering::SeqCst);
            }
        }
        match worker.join() {
            Ok(result) => (result, signal),
            Err(panic) => std::panic::resume_unwind(panic),
        }
    });
    drop(session);
    match result {
        Ok(summary) => {
            let value = serde_json::to_value(&summary)
                .map_err(|e| PyValueError::new_err(format!("summary: {e}")))?;
            let summary = json_to_py(py, &value)?.cast_into::<PyDict>()?;
            Ok(RunResult::new(out, Some(summary.unbind())))
        }
        Err(RunError::Interrupted { message }) => {
            let hint = format!(
                "{message}, or from Python with drape.run(scenario, out={:?}, resume=True)",
                out.display().to_string()
            );
            match signal {
                // A handler of the caller's own raised something else:
                // that is what it wanted raised.
                Some(e) if !e.is_instance_of::<PyKeyboardInterrupt>(py) => Err(e),
                _ => Err(PyKeyboardInterrupt::new_err(hint)),
            }
        }
        Err(e) => Err(run_error(py, e.to_string(), &out)),
    }
}

/// Validates a scenario and builds its model without running it, as
/// `drape check` does.
///
/// Args:
///     scenario: the path of a scenario file (TOML), or a dict with the
///         TOML's structure.
///
/// Returns:
///     dict: ``title``, ``nodes``, ``elements``, ``pieces`` (the mesh's
///     disconnected pieces), ``order``, ``dofs``, ``fixed_dofs``, ``mass``
///     (kg) and ``monitors`` (name -> node index).
///
/// Raises:
///     ScenarioError: with the file, the key and the line of what is wrong.
#[pyfunction]
pub fn check<'py>(py: Python<'py>, scenario: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
    let source = Source::from_py(scenario)?;
    let loaded = py
        .detach(|| source.load())
        .map_err(|e| scenario_error(py, &e, matches!(source, Source::Dict(_))))?;
    let setup = &loaded.setup;
    let m = &setup.model;
    let info = PyDict::new(py);
    info.set_item("title", &setup.title)?;
    info.set_item("nodes", m.mesh().node_count())?;
    info.set_item("pieces", m.mesh().pieces().1)?;
    info.set_item("elements", m.mesh().element_count())?;
    info.set_item("order", m.mesh().order.degree())?;
    info.set_item("dofs", m.dofs())?;
    info.set_item("fixed_dofs", m.fixed_count())?;
    info.set_item("mass", m.total_mass())?;
    let monitors = PyDict::new(py);
    for mon in &setup.monitors {
        monitors.set_item(&mon.name, mon.node)?;
    }
    info.set_item("monitors", monitors)?;
    Ok(info)
}

/// Checks a scenario dict's structure (keys, types, choices) without
/// building it, and returns its TOML text, relative paths joined to
/// `folder`: the sweeps' cases are made with it.
///
/// Raises ScenarioError (file `name`, no line) for what the parser refuses.
#[pyfunction]
#[pyo3(signature = (scenario, folder, name))]
pub fn _scenario_text(
    py: Python<'_>,
    scenario: &Bound<'_, PyDict>,
    folder: PathBuf,
    name: &str,
) -> PyResult<String> {
    let text = crate::input::scenario_text(scenario, &folder)?;
    drape::scenario::Scenario::parse(&text, Path::new(name))
        .map_err(|e| scenario_error(py, &e, true))?;
    Ok(text)
}

/// `out/<stem>`, as the command line.
fn default_out(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    PathBuf::from("out").join(stem)
}
