//! The scenario a Python caller hands over: the path of a TOML file, or a
//! dict with the TOML's structure, which becomes TOML text here.
//!
//! A dict has no folder of its own, so the files it names (`mesh.path`,
//! `obstacle[i].path`) are taken relative to a folder the caller chooses
//! (the working directory for `drape.run`, the base scenario's folder for
//! a sweep's cases) and written out absolute: the text then means the same
//! wherever it is saved — in `OUT/scenario.toml`, or in a sweep's case.

use drape::scenario::{Scenario, ScenarioError};
use drape::setup::Setup;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::path::{Path, PathBuf};

/// The name a dict scenario goes by in messages: it has no file.
pub const DICT_NAME: &str = "<dict>";

/// Where a scenario comes from.
pub enum Source {
    /// A scenario file.
    File(PathBuf),
    /// A dict, as TOML text with absolute paths.
    Dict(String),
}

/// A scenario read and built.
pub struct Loaded {
    /// Everything the run needs.
    pub setup: Setup,
    /// The scenario's text (for a dict: the text written to `OUT/scenario.toml`).
    pub text: String,
    /// The scenario (what a `[refine]` run builds its levels from).
    pub scenario: Scenario,
}

impl Source {
    /// A path (`str` or `os.PathLike`) or a dict; relative paths in a dict
    /// are taken from the working directory.
    pub fn from_py(obj: &Bound<'_, PyAny>) -> PyResult<Self> {
        if let Ok(dict) = obj.cast::<PyDict>() {
            let folder = std::env::current_dir()?;
            return Ok(Source::Dict(scenario_text(dict, &folder)?));
        }
        obj.extract::<PathBuf>().map(Source::File).map_err(|_| {
            PyTypeError::new_err(format!(
                "a scenario is the path of a TOML file (str or os.PathLike) or a dict with the TOML's structure, not {}",
                type_name(obj)
            ))
        })
    }

    /// The name in messages: the file, or [`DICT_NAME`].
    pub fn file(&self) -> &Path {
        match self {
            Source::File(path) => path,
            Source::Dict(_) => Path::new(DICT_NAME),
        }
    }

    /// Reads, parses and checks the scenario and builds the model (no
    /// Python object is touched: callers release the GIL around it).
    pub fn load(&self) -> Result<Loaded, ScenarioError> {
        let (scenario, text) = match self {
            Source::File(path) => Scenario::read(path)?,
            Source::Dict(text) => (Scenario::parse(text, self.file())?, text.clone()),
        };
        let setup = scenario.build(self.file(), &text)?;
        Ok(Loaded {
            setup,
            text,
            scenario,
        })
    }
}

/// TOML text of the scenario `dict`, its relative file paths joined to
/// `folder`.
pub fn scenario_text(dict: &Bound<'_, PyDict>, folder: &Path) -> PyResult<String> {
    let mut table = table(dict, "", 0)?;
    drape::scenario::absolute_paths(&mut table, folder);
    toml::to_string(&table)
        .map_err(|e| PyTypeError::new_err(format!("the scenario cannot be written as TOML: {e}")))
}

/// The deepest nesting of tables and lists a scenario may have: drape's
/// own go four deep (`obstacle[0].within.min`); deeper is a dict or list
/// that contains itself, or no scenario.
const MAX_DEPTH: usize = 32;

/// A value nested deeper than [`MAX_DEPTH`] at `key`: a `ValueError`
/// naming the key path (the conversion recursed without a limit and
/// crashed the interpreter on a dict that contained itself).
fn too_deep(key: &str) -> PyErr {
    PyValueError::new_err(format!(
        "scenario key `{key}`: nested more than {MAX_DEPTH} tables or lists deep (a dict or list that contains itself?)"
    ))
}

fn table(dict: &Bound<'_, PyDict>, key: &str, depth: usize) -> PyResult<toml::Table> {
    if depth > MAX_DEPTH {
        return Err(too_deep(key));
    }
    let mut out = toml::Table::new();
    for (k, v) in dict.iter() {
        let name = k.cast::<PyString>().map_err(|_| {
            PyTypeError::new_err(format!(
                "scenario {}: keys are strings, not {}",
                at(key),
                type_name(&k)
            ))
        })?;
        let name = name.to_str()?.to_owned();
        let path = if key.is_empty() {
            name.clone()
        } else {
            format!("{key}.{name}")
        };
        out.insert(name, value(&v, &path, depth + 1)?);
    }
    Ok(out)
}

/// The TOML value of `obj` (at `key`, for messages): bool, int, float,
/// str, list or tuple, dict; NumPy arrays and scalars through `tolist()`.
fn value(obj: &Bound<'_, PyAny>, key: &str, depth: usize) -> PyResult<toml::Value> {
    if depth > MAX_DEPTH {
        return Err(too_deep(key));
    }
    // bool before int: Python's bool is an int.
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(toml::Value::Boolean(b.is_true()));
    }
    if obj.cast::<PyInt>().is_ok() {
        return obj.extract::<i64>().map(toml::Value::Integer).map_err(|_| {
            PyTypeError::new_err(format!(
                "scenario key `{key}`: {} does not fit a TOML integer (64 bits)",
                obj
            ))
        });
    }
    if let Ok(f) = obj.cast::<PyFloat>() {
        return Ok(toml::Value::Float(f.value()));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(toml::Value::String(s.to_str()?.to_owned()));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        return table(d, key, depth).map(toml::Value::Table);
    }
    let items: Option<Vec<Bound<'_, PyAny>>> = if let Ok(l) = obj.cast::<PyList>() {
        Some(l.iter().collect())
    } else if let Ok(t) = obj.cast::<PyTuple>() {
        Some(t.iter().collect())
    } else {
        None
    };
    if let Some(items) = items {
        return items
            .iter()
            .enumerate()
            .map(|(i, item)| value(item, &format!("{key}[{i}]"), depth + 1))
            .collect::<PyResult<Vec<_>>>()
            .map(toml::Value::Array);
    }
    if obj.hasattr("tolist")? {
        return value(&obj.call_method0("tolist")?, key, depth + 1);
    }
    Err(PyTypeError::new_err(format!(
        "scenario key `{key}`: a value of type {} has no TOML value (use bool, int, float, str, list or dict{})",
        type_name(obj),
        if obj.is_none() {
            "; leave the key out for its default"
        } else {
            ""
        }
    )))
}

fn at(key: &str) -> String {
    if key.is_empty() {
        "top level".into()
    } else {
        format!("table `{key}`")
    }
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "object".into())
}
