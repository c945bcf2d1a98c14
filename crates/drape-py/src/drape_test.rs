//! The native half of `drape.test` (the Python half is
//! `python/drape/_specimens.py`): the specimens a test runs and its report,
//! made by the same code as `drape test`'s (`Scenario::specimens`,
//! `drape_lab::drape_test`), so that a test can be run or completed by
//! either front end.

use crate::errors::{output_error, scenario_error};
use drape::scenario::{Scenario, SpecimenPlan};
use drape_lab::drape_test::{self as lab, Outcome};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};

/// The scenario's title (its file stem without one) and its specimens,
/// the first built to check it.
fn plans(
    py: Python<'_>,
    scenario: &Path,
    count: usize,
    seed: u64,
) -> PyResult<(String, Vec<SpecimenPlan>)> {
    let err = |e: drape::scenario::ScenarioError| scenario_error(py, &e, false);
    let (s, text) = Scenario::read(scenario).map_err(err)?;
    let plans = s.specimens(scenario, &text, count, seed).map_err(err)?;
    let title = s.title.clone().unwrap_or_else(|| {
        scenario
            .file_stem()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned())
    });
    Ok((title, plans))
}

/// The specimens of a drape test of `scenario`: a list of dicts `index`,
/// `name` (`NNNN`), `text` (its scenario), `done` (a completed run of that
/// text is in `out/specimens/NNNN`) and `resume` (an interrupted one with
/// its checkpoint is). Makes `out/specimens`, refusing a `test.json` in
/// `out` that is not a test's. The first specimen is built, so that a bad
/// scenario is refused before anything runs.
///
/// Raises:
///     ScenarioError: the scenario, its `[test]` table.
///     OutputError: `out` cannot be used.
#[pyfunction]
pub fn _specimens<'py>(
    py: Python<'py>,
    scenario: PathBuf,
    count: usize,
    seed: u64,
    out: PathBuf,
) -> PyResult<Bound<'py, PyList>> {
    if count == 0 {
        return Err(PyValueError::new_err(
            "specimens=0: a drape test has at least one specimen",
        ));
    }
    let (_, plans) = plans(py, &scenario, count, seed)?;
    if let Some(first) = plans.first() {
        Scenario::parse(&first.text, &scenario)
            .and_then(|s| s.build(&scenario, &first.text).map(|_| ()))
            .map_err(|e| scenario_error(py, &e, false))?;
    }
    lab::take_directory(&out).map_err(|e| output_error(py, format!("{e:#}"), &out))?;
    let list = PyList::empty(py);
    for plan in &plans {
        let prior = lab::prior(&lab::specimen_dir(&out, plan), &plan.text);
        let d = PyDict::new(py);
        d.set_item("index", plan.index)?;
        d.set_item("name", plan.name())?;
        d.set_item("text", &plan.text)?;
        d.set_item("done", prior == lab::Prior::Completed)?;
        d.set_item("resume", prior == lab::Prior::Interrupted)?;
        list.append(d)?;
    }
    Ok(list)
}

/// Measures the completed specimens of the test in `out` and writes
/// `test.json` and `test.png`; returns `test.json`'s text. `outcomes`: a
/// list of dicts `index`, `status`, `message` (a specimen without one was
/// not started).
#[pyfunction]
pub fn _test_report(
    py: Python<'_>,
    scenario: PathBuf,
    count: usize,
    seed: u64,
    out: PathBuf,
    outcomes: Vec<Bound<'_, PyDict>>,
) -> PyResult<String> {
    let (title, plans) = plans(py, &scenario, count, seed)?;
    let mut list = Vec::new();
    for d in &outcomes {
        let index: usize = match d.get_item("index")? {
            Some(v) => v.extract()?,
            None => return Err(PyValueError::new_err("an outcome without its index")),
        };
        let status: String = match d.get_item("status")? {
            Some(v) => v.extract()?,
            None => "failed".into(),
        };
        let message: String = match d.get_item("message")? {
            Some(v) if !v.is_none() => v.extract()?,
            _ => String::new(),
        };
        list.push(Outcome {
            index,
            status,
            message,
        });
    }
    let info = lab::TestInfo {
        scenario: &scenario,
        title: &title,
        seed,
        plans: &plans,
    };
    let value = py
        .detach(|| lab::report(&out, &info, &list))
        .map_err(|e| output_error(py, format!("{e:#}"), &out))?;
    serde_json::to_string(&value).map_err(|e| PyValueError::new_err(e.to_string()))
}
