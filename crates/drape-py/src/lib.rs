//! `drape._drape`: the native half of the Python package `drape`
//! (`crates/drape-py/python/drape` is the other: the exceptions, the
//! sweeps and their engines, `python -m drape`).
//!
//! It calls the library as the command line does — [`drape::scenario`] to
//! read and check, [`drape::simulation::run_with`] to run, with the same
//! output directory, the same stop flag and the same checkpoints — and
//! hands the outputs to Python through the readers of `drape-render`.
//!
//! * `run::run`, `run::check`: `drape.run`, `drape.check`.
//! * `result::RunResult`: summary, history, positions of a frame.
//! * `input`: a scenario given as a path or as a dict.
//! * `errors`: the library's errors as the package's exceptions.
//! * `drape_test`: the specimens of `drape.test` and its report.

mod drape_test;
mod errors;
mod input;
mod result;
mod run;

use pyo3::prelude::*;

#[pymodule]
fn _drape(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add_function(wrap_pyfunction!(run::check, m)?)?;
    m.add_function(wrap_pyfunction!(run::_scenario_text, m)?)?;
    m.add_function(wrap_pyfunction!(drape_test::_specimens, m)?)?;
    m.add_function(wrap_pyfunction!(drape_test::_test_report, m)?)?;
    m.add_class::<result::RunResult>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
