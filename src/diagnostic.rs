//! Rendering diagnostics for people: `file:line:col`, the source snippet with its label, and
//! the hint, through miette's graphical handler at a fixed width (reproducible output).

use miette::{Diagnostic, GraphicalReportHandler, GraphicalTheme};

/// Output width of rendered diagnostics (fixed so that output does not depend on the terminal).
pub const WIDTH: usize = 100;

/// Render a diagnostic (a [`crate::format::LoadError`], ...) as text. `color` selects ANSI
/// colours; without it the output is plain Unicode, stable for snapshots and logs.
pub fn render(diag: &dyn Diagnostic, color: bool) -> String {
    let theme = if color {
        GraphicalTheme::unicode()
    } else {
        GraphicalTheme::unicode_nocolor()
    };
    let handler = GraphicalReportHandler::new_themed(theme)
        .with_width(WIDTH)
        .with_links(false);
    let mut out = String::new();
    if handler.render_report(&mut out, diag).is_err() {
        // Formatting into a String only fails if a Display impl fails: fall back to the message.
        out = format!("error: {diag}\n");
    }
    out
}

/// Render an error without a source location (e.g. [`crate::mechanism::InputSpecError`]) as
/// `error: <context>: <message>`, one line (plus its causes, if any).
pub fn render_plain(context: &str, err: &dyn std::error::Error) -> String {
    let mut out = if context.is_empty() {
        format!("error: {err}")
    } else {
        format!("error: {context}: {err}")
    };
    let mut cause = err.source();
    while let Some(c) = cause {
        out.push_str(&format!("\n  caused by: {c}"));
        cause = c.source();
    }
    out.push('\n');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_errors_have_one_line() {
        let e = crate::mechanism::InputSpec::parse("A:x").unwrap_err();
        assert_eq!(
            render_plain("--inputs", &e),
            "error: --inputs: invalid input spec `A:x`: `x` is not a non-negative whole number of DOF\n"
        );
    }
}
