//! `mbsa._mbsa`: the Python extension module of mbsa. Each method is the library call a
//! command of the `mbsa` binary makes, with the same defaults, and returns the text that
//! command prints with `--format json` (or `jsonl`): `report::json` of the same report, so the
//! keys have one source (docs/json.md). The package `mbsa` (python/mbsa/) parses it and adds
//! numpy arrays. Every analysis runs with the interpreter released (`Python::detach`).

mod errors;
mod load;
mod mechanism;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _mbsa(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<errors::Error>())?;
    m.add("InputError", py.get_type::<errors::InputError>())?;
    m.add("BudgetExceeded", py.get_type::<errors::BudgetExceeded>())?;
    m.add("SolveError", py.get_type::<errors::SolveError>())?;
    m.add("FORMAT_VERSION", mbsa::report::FORMAT_VERSION)?;
    m.add_class::<mechanism::RawMechanism>()?;
    m.add_function(wrap_pyfunction!(load::load, m)?)?;
    m.add_function(wrap_pyfunction!(load::examples, m)?)?;
    Ok(())
}
