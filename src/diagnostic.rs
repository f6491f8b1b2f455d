//! Rendering diagnostics for people: `file:line:col`, the source snippet with its label, and
//! the hint, through miette's graphical handler at a fixed width (reproducible output).

use miette::{Diagnostic, GraphicalReportHandler, GraphicalTheme};

/// Output width of rendered diagnostics (fixed so that output does not depend on the terminal).
pub const WIDTH: usize = 100;

/// Render a diagnostic (a [`crate::format::LoadError`], ...) as text. `color` selects ANSI
/// colours; without it the output is plain Unicode, stable for snapshots and logs.
pub fn render(diag: &dyn Diagnostic, color: bool) -> String {
    if let Some(out) = render_long_line(diag) {
        return out;
    }
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

/// Longest source line shown as a snippet, in bytes. miette panics on columns past 65535
/// (a format width) and would print the whole line: minified JSON has megabyte lines.
const MAX_SNIPPET_LINE: usize = 1000;

/// `error: file:line:col: message` (and the hint) when a label sits on a line, or beside a
/// line (miette shows one line of context), too long for a snippet; `None` otherwise.
fn render_long_line(diag: &dyn Diagnostic) -> Option<String> {
    let src = diag.source_code()?;
    let mut labels = diag.labels()?;
    let long = labels.find_map(|l| {
        let shown = src.read_span(l.inner(), 1, 1).ok()?;
        let widest = shown.data().split(|&b| b == b'\n').map(<[u8]>::len).max();
        let at = src.read_span(l.inner(), 0, 0).ok()?;
        (widest.unwrap_or(0) > MAX_SNIPPET_LINE || at.column() > MAX_SNIPPET_LINE).then_some(at)
    })?;
    let name = long.name().unwrap_or("<input>");
    let (line, col) = (long.line() + 1, long.column() + 1);
    let mut out = format!("error: {name}:{line}:{col}: {diag}\n");
    if let Some(help) = diag.help() {
        out.push_str(&format!("  help: {help}\n"));
    }
    Some(out)
}

/// Where a diagnostic points: its source's name and the 1-based line and column of its first
/// label (what `file:line:col` shows, and the `file`, `line`, `column` of `mbsa check --format
/// json`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The source's name (a path, `<stdin>`, `@name (file.toml)`).
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
}

/// The [`Location`] of `diag`, if it has a source and a label.
pub fn location(diag: &dyn Diagnostic) -> Option<Location> {
    let src = diag.source_code()?;
    let label = diag.labels()?.next()?;
    let span = src.read_span(label.inner(), 0, 0).ok()?;
    Some(Location {
        file: span.name().unwrap_or("<input>").to_string(),
        line: span.line() + 1,
        column: span.column() + 1,
    })
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
    fn location_is_the_first_labels_line_and_column() {
        // A label on `Q`, the 5th byte of the 3rd line.
        let diag = miette::MietteDiagnostic::new("unknown joint type")
            .with_label(miette::LabeledSpan::at(10..11, "here"));
        let report = miette::Report::new(diag).with_source_code(miette::NamedSource::new(
            "bad.toml",
            "a\nbcd\nxyz Q\n".to_string(),
        ));
        let at = location(report.as_ref()).expect("located");
        assert_eq!((at.file.as_str(), at.line, at.column), ("bad.toml", 3, 5));
        assert!(render(report.as_ref(), false).contains("[bad.toml:3:5]"));
    }

    #[test]
    fn plain_errors_have_one_line() {
        let e = crate::mechanism::InputSpec::parse("A:x").unwrap_err();
        assert_eq!(
            render_plain("--inputs", &e),
            "error: --inputs: invalid input spec `A:x`: `x` is not a non-negative whole number of DOF\n"
        );
    }
}
