//! The exceptions: `InputError` carries where the input is wrong (file, line, column, as the
//! command line shows it), `BudgetExceeded` a limit of the budget, `SolveError` a position
//! solve that did not converge.

use mbsa::budget::BudgetExceeded as Exceeded;
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(_mbsa, Error, PyException, "Base class of mbsa's errors.");
create_exception!(
    _mbsa,
    InputError,
    Error,
    "An input mbsa cannot read or use: `file`, `line`, `column` (1-based; None without a \
     location), `message`, `help` and `rendered` (the command line's diagnostic)."
);
create_exception!(
    _mbsa,
    BudgetExceeded,
    Error,
    "An analysis would pass a limit of the budget (work, memory, input size)."
);
create_exception!(
    _mbsa,
    SolveError,
    Error,
    "A position solve did not converge (the command line exits with code 1)."
);

/// An `InputError` with its attributes.
pub fn input_error(
    file: Option<&str>,
    line: Option<usize>,
    column: Option<usize>,
    message: &str,
    help: Option<String>,
    rendered: String,
) -> PyErr {
    let text = match (file, line, column) {
        (Some(f), Some(l), Some(c)) => format!("{f}:{l}:{c}: {message}"),
        (Some(f), _, _) => format!("{f}: {message}"),
        _ => message.to_string(),
    };
    let err = InputError::new_err(text);
    Python::attach(|py| {
        let v = err.value(py);
        let _ = v.setattr("file", file);
        let _ = v.setattr("line", line);
        let _ = v.setattr("column", column);
        let _ = v.setattr("message", message);
        let _ = v.setattr("help", help);
        let _ = v.setattr("rendered", rendered);
    });
    err
}

/// A located diagnostic (a mechanism file or a model file that cannot be read).
pub fn diagnostic(diag: &dyn miette::Diagnostic) -> PyErr {
    let at = mbsa::diagnostic::location(diag);
    input_error(
        at.as_ref().map(|l| l.file.as_str()),
        at.as_ref().map(|l| l.line),
        at.as_ref().map(|l| l.column),
        &diag.to_string(),
        diag.help().map(|h| h.to_string()),
        mbsa::diagnostic::render(diag, false),
    )
}

/// An error without a location, in the context `file` (a file name or an option).
pub fn plain(file: &str, e: &dyn std::error::Error) -> PyErr {
    input_error(
        Some(file),
        None,
        None,
        &e.to_string(),
        None,
        mbsa::diagnostic::render_plain(file, e),
    )
}

/// A budget limit passed.
pub fn budget(e: &Exceeded) -> PyErr {
    BudgetExceeded::new_err(format!("{e}\n  help: {}", e.help()))
}
