//! The library's errors as the package's Python exceptions (defined in
//! `drape/_errors.py`, where their docstrings and attributes are).

use drape::scenario::ScenarioError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};

/// An instance of `drape.<class>(message, **attributes)` as a `PyErr`.
fn drape_error(
    py: Python<'_>,
    class: &str,
    message: String,
    attributes: &[(&str, Py<PyAny>)],
) -> PyErr {
    let build = || -> PyResult<Bound<'_, PyAny>> {
        let kwargs = PyDict::new(py);
        for (name, value) in attributes {
            kwargs.set_item(name, value)?;
        }
        py.import("drape._errors")?
            .getattr(class)?
            .call((message,), Some(&kwargs))
    };
    match build() {
        Ok(instance) => PyErr::from_value(instance),
        Err(e) => e,
    }
}

/// `drape.ScenarioError` carrying the file, the key and the line of `e`.
///
/// A scenario given as a dict has no lines of its own (the text it was
/// written to is not a file the caller has), so its errors have no line,
/// and its file is [`crate::input::DICT_NAME`].
pub fn scenario_error(py: Python<'_>, e: &ScenarioError, from_dict: bool) -> PyErr {
    let (file, line, key, detail): (Option<&Path>, _, _, _) = match e {
        ScenarioError::Io { file, error } => {
            (Some(file), None, None, format!("cannot read: {error}"))
        }
        ScenarioError::Parse {
            file,
            line,
            message,
        } => (Some(file), *line, leading_key(message), message.clone()),
        ScenarioError::Invalid {
            file,
            line,
            key,
            message,
        } => (
            Some(file),
            *line,
            Some(key.clone()),
            format!("`{key}` {message}"),
        ),
        ScenarioError::Mesh { file, error } => (Some(file), None, None, format!("mesh: {error}")),
        other => (None, None, None, other.to_string()),
    };
    let line = line.filter(|_| !from_dict);
    let message = match file {
        Some(file) => format!(
            "{}{}: {detail}",
            file.display(),
            line.map(|l| format!(", line {l}")).unwrap_or_default()
        ),
        None => detail,
    };
    let file = file.map(|f| f.display().to_string());
    drape_error(
        py,
        "ScenarioError",
        message,
        &[
            (
                "file",
                file.into_pyobject(py)
                    .map(|o| o.unbind())
                    .unwrap_or_else(|_| py.None()),
            ),
            (
                "key",
                key.into_pyobject(py)
                    .map(|o| o.unbind())
                    .unwrap_or_else(|_| py.None()),
            ),
            (
                "line",
                line.into_pyobject(py)
                    .map(|o| o.unbind())
                    .unwrap_or_else(|_| py.None()),
            ),
        ],
    )
}

/// The key a parse error's message starts with: "`material.density`: …".
fn leading_key(message: &str) -> Option<String> {
    let (key, _) = message.strip_prefix('`')?.split_once('`')?;
    (!key.is_empty()).then(|| key.to_string())
}

/// `drape.RunError`: the run stopped; `result` opens what it wrote, when
/// it wrote anything (its summary None if that could not be written).
pub fn run_error(py: Python<'_>, message: String, out: &Path) -> PyErr {
    let result = crate::result::RunResult::open(py, out.to_path_buf())
        .ok()
        .and_then(|r| Py::new(py, r).ok())
        .map(|r| r.into_any())
        .unwrap_or_else(|| py.None());
    drape_error(
        py,
        "RunError",
        message,
        &[("out", path_object(py, out)), ("result", result)],
    )
}

/// `drape.OutputError`: an output directory that cannot be used or read.
pub fn output_error(py: Python<'_>, message: String, path: &Path) -> PyErr {
    drape_error(
        py,
        "OutputError",
        message,
        &[("path", path_object(py, path))],
    )
}

fn path_object(py: Python<'_>, path: &Path) -> Py<PyAny> {
    PathBuf::from(path)
        .into_pyobject(py)
        .map(|o| o.unbind())
        .unwrap_or_else(|_| py.None())
}
