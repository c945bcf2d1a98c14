//! `drape.RunResult`: an output directory seen from Python — the summary
//! as a dict, the history as NumPy arrays, the frames' positions.
//!
//! Arrays are made from the vectors the readers return, which NumPy then
//! owns: no copy after the file is parsed. The history is read once, on
//! first use (a run from Python that only wants the summary never parses
//! it); the frames are read when asked for.

use crate::errors::output_error;
use drape::output::directory::SCENARIO_PATH;
use drape_render::{FrameSelect, History, OutputDir, RenderError};
use numpy::ndarray::Array2;
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};

/// The summary a run writes when it ends, however it ends.
const SUMMARY: &str = "summary.json";

/// The outputs of which one marks a directory as a run's when it has no
/// summary: a run in progress, or one killed before it wrote its summary
/// (`scenario.path` is written before the first step).
const RUN_OUTPUTS: [&str; 3] = ["history.csv", "fields.pvd", SCENARIO_PATH];

/// The outputs of a run: ``summary``, ``history`` and ``positions(step)``.
///
/// ``drape.run`` returns one; ``RunResult(out)`` opens the output
/// directory of an earlier run (of ``drape run`` too), or of a sweep's
/// case (``DIR/cases/NNNN``).
#[pyclass(module = "drape", name = "RunResult", frozen)]
pub struct RunResult {
    /// Absolute: the history and the frames are read lazily, and must be
    /// this run's even after the caller changes its working directory.
    out: PathBuf,
    /// None for a run without `summary.json`: in progress, or killed.
    summary: Option<Py<PyDict>>,
    history: PyOnceLock<Py<PyDict>>,
}

impl RunResult {
    /// The result of the run that wrote `out`, with its summary; `out` is
    /// made absolute against the working directory of now.
    pub fn new(out: PathBuf, summary: Option<Py<PyDict>>) -> Self {
        Self {
            out: absolute(out),
            summary,
            history: PyOnceLock::new(),
        }
    }

    /// Opens `out`, reading its `summary.json`; a run in progress, or one
    /// killed before it wrote its summary (SIGKILL, the OOM killer), has
    /// none and opens with `summary` None, from its other outputs.
    pub fn open(py: Python<'_>, out: PathBuf) -> PyResult<Self> {
        let out = absolute(out);
        let path = out.join(SUMMARY);
        let not_a_run = |why: String| {
            let message = format!(
                "{why}; is {} the output directory of a drape run?",
                out.display()
            );
            output_error(py, message, &out)
        };
        let text = match std::fs::read_to_string(&path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound && out.is_dir() => {
                if !RUN_OUTPUTS.iter().any(|f| out.join(f).is_file()) {
                    let [a, b, c] = RUN_OUTPUTS;
                    return Err(not_a_run(format!(
                        "{}: no {SUMMARY}, {a}, {b} or {c}",
                        out.display()
                    )));
                }
                return Ok(Self::new(out, None));
            }
            Err(e) => return Err(not_a_run(format!("{}: {e}", path.display()))),
        };
        // Python's own parser: serde_json's default one may round the last
        // bit of a float (its exact parser is a feature of its own).
        let summary = py
            .import("json")?
            .call_method1("loads", (text,))
            .map_err(|e| output_error(py, format!("{}: not JSON: {e}", path.display()), &out))?
            .cast_into::<PyDict>()
            .map_err(|_| {
                output_error(py, format!("{}: not a JSON object", path.display()), &out)
            })?;
        Ok(Self::new(out, Some(summary.unbind())))
    }
}

#[pymethods]
impl RunResult {
    #[new]
    fn py_new(py: Python<'_>, out: PathBuf) -> PyResult<Self> {
        Self::open(py, out)
    }

    /// The output directory (pathlib.Path), absolute: made so against the
    /// working directory when the run started or the result was opened.
    #[getter]
    fn out(&self) -> PathBuf {
        self.out.clone()
    }

    /// ``summary.json`` as a dict: ``status``, ``message``, ``steps``,
    /// ``time``, ``first_contact_time``, ``newton_iterations``,
    /// ``wall_seconds``, ``nodes``, ``elements``, ``dofs``, ``monitors``
    /// (name -> final ``[x, y, z]``) and more (README, "Outputs"); None
    /// when the directory has no ``summary.json``: a run still in
    /// progress, or one killed (SIGKILL, out of memory) before it could
    /// write it. As the file was when the result was made: open the
    /// directory again to see a later summary.
    #[getter]
    fn summary(&self, py: Python<'_>) -> Option<Py<PyDict>> {
        self.summary.as_ref().map(|s| s.clone_ref(py))
    }

    /// ``history.csv`` as a dict: column name -> 1-D float64 array, one
    /// entry per converged step, step 0 (the initial state) first.
    /// Columns: ``step``, ``time``, ``dt``, ``iterations``, the energies,
    /// the contact's, ``<monitor>_x``/``_y``/``_z`` and more (README,
    /// "Outputs"). Read on first use.
    #[getter]
    fn history(&self, py: Python<'_>) -> PyResult<Py<PyDict>> {
        self.history
            .get_or_try_init(py, || {
                let out = &self.out;
                let history = py
                    .detach(|| History::read(out))
                    .map_err(|e| render_error(py, e, out))?;
                let dict = PyDict::new(py);
                for (name, column) in history.names.into_iter().zip(history.columns) {
                    dict.set_item(name, PyArray1::from_vec(py, column))?;
                }
                Ok::<_, PyErr>(dict.unbind())
            })
            .map(|d| d.clone_ref(py))
    }

    /// The steps whose frames were written (``fields.pvd``), in order.
    #[getter]
    fn frames(&self, py: Python<'_>) -> PyResult<Vec<u64>> {
        let dir = OutputDir::open(&self.out).map_err(|e| render_error(py, e, &self.out))?;
        Ok(dir.frames.iter().map(|f| f.step).collect())
    }

    /// The node positions of a written frame, as a (nodes, 3) float64
    /// array (m).
    ///
    /// Args:
    ///     step: the step of the frame (one of ``frames``); -1, the
    ///         default, is the last frame written.
    ///
    /// Raises:
    ///     ValueError: no frame was written at that step (the message lists
    ///         those that were).
    #[pyo3(signature = (step = -1))]
    fn positions<'py>(&self, py: Python<'py>, step: i64) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let select = match step {
            -1 => FrameSelect::Last,
            s if s >= 0 => FrameSelect::Step(s as u64),
            s => {
                return Err(PyValueError::new_err(format!(
                    "step {s}: a step number (>= 0), or -1 for the last frame written"
                )));
            }
        };
        let out = &self.out;
        let points = py
            .detach(|| -> Result<Vec<[f64; 3]>, RenderError> {
                let dir = OutputDir::open(out)?;
                let frame = &dir.frames[dir.select(select)?];
                Ok(drape_render::vtu::read_vtu(&frame.path)?.points)
            })
            .map_err(|e| render_error(py, e, out))?;
        let nodes = points.len();
        let array = Array2::from_shape_vec((nodes, 3), points.into_flattened())
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(PyArray2::from_owned_array(py, array))
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let out = format!("{:?}", self.out.display().to_string());
        let Some(summary) = &self.summary else {
            return format!("RunResult(out={out}, summary=None)");
        };
        let summary = summary.bind(py);
        let item = |key: &str| {
            summary
                .get_item(key)
                .ok()
                .flatten()
                .and_then(|v| v.repr().ok().map(|r| r.to_string()))
                .unwrap_or_else(|| "None".into())
        };
        format!(
            "RunResult(out={out}, status={}, steps={}, time={})",
            item("status"),
            item("steps"),
            item("time")
        )
    }
}

/// `path` joined to the working directory if relative (not resolved: a
/// symbolic link stays as named); as given if that fails (an empty path,
/// or no working directory), to be refused by whoever opens it.
pub fn absolute(path: PathBuf) -> PathBuf {
    std::path::absolute(&path).unwrap_or(path)
}

/// A reader's error: a missing file is an `OSError`, a step without a
/// frame a `ValueError`, anything else an `OutputError`.
fn render_error(py: Python<'_>, e: RenderError, out: &Path) -> PyErr {
    match e {
        RenderError::Io { .. } => PyOSError::new_err(e.to_string()),
        RenderError::StepNotFound { .. } => PyValueError::new_err(e.to_string()),
        e => output_error(py, e.to_string(), out),
    }
}

/// A JSON value as the Python object `json.loads` would make.
pub fn json_to_py<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(json_to_py(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, v) in map {
                dict.set_item(k, json_to_py(py, v)?)?;
            }
            dict.into_any()
        }
    })
}
