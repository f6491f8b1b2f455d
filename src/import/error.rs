//! [`ImportError`]: a located, renderable error of the importers (file:line:column of the
//! XML element, what was expected, a hint).

use miette::{Diagnostic, LabeledSpan, NamedSource, SourceCode};
use std::fmt;
use std::ops::Range;

/// Why an import failed: the message, the element or attribute it is about (a byte span of
/// the file that holds it) and a hint. Render it with [`crate::diagnostic::render`].
#[derive(Debug)]
pub struct ImportError(Box<Inner>);

#[derive(Debug)]
struct Inner {
    message: String,
    help: Option<String>,
    label: Option<(Range<usize>, String)>,
    line_col: Option<(usize, usize)>,
    file: Option<String>,
    source: Option<NamedSource<String>>,
}

impl ImportError {
    /// An error without a location.
    pub fn new(message: impl Into<String>) -> ImportError {
        ImportError(Box::new(Inner {
            message: super::names::cap_quoted(message.into()),
            help: None,
            label: None,
            line_col: None,
            file: None,
            source: None,
        }))
    }

    /// An error at `span` of the file `name` whose text is `text`.
    pub fn at(
        name: &str,
        text: &str,
        span: Range<usize>,
        label: impl Into<String>,
        message: impl Into<String>,
    ) -> ImportError {
        let start = floor_boundary(text, span.start.min(text.len()));
        let end = floor_boundary(text, span.end.clamp(start, text.len()));
        let mut e = ImportError::new(message);
        e.0.line_col = Some(line_col(text, start));
        e.0.label = Some((start..end, super::names::cap_quoted(label.into())));
        e.0.file = Some(name.to_string());
        e.0.source = Some(NamedSource::new(name, text.to_string()));
        e
    }

    /// The same error with a hint.
    pub fn with_help(mut self, help: impl Into<String>) -> ImportError {
        self.0.help = Some(super::names::cap_quoted(help.into()));
        self
    }

    /// The message without location.
    pub fn message(&self) -> &str {
        &self.0.message
    }

    /// The hint, if any.
    pub fn hint(&self) -> Option<&str> {
        self.0.help.as_deref()
    }

    /// File name and 1-based line and column of the location, if the error has one.
    pub fn location(&self) -> Option<(&str, usize, usize)> {
        let (l, c) = self.0.line_col?;
        Some((self.0.file.as_deref()?, l, c))
    }
}

impl fmt::Display for ImportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0.message)
    }
}

impl std::error::Error for ImportError {}

impl Diagnostic for ImportError {
    fn help<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        self.0
            .help
            .as_ref()
            .map(|h| Box::new(h) as Box<dyn fmt::Display>)
    }

    fn source_code(&self) -> Option<&dyn SourceCode> {
        self.0.source.as_ref().map(|s| s as &dyn SourceCode)
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = LabeledSpan> + '_>> {
        let (span, text) = self.0.label.as_ref()?;
        self.0.source.as_ref()?;
        let text = (!text.is_empty()).then(|| text.clone());
        Some(Box::new(std::iter::once(
            LabeledSpan::new_primary_with_span(text, (span.start, span.end - span.start)),
        )))
    }
}

/// The largest char boundary `<= i`.
fn floor_boundary(text: &str, mut i: usize) -> usize {
    while i > 0 && !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// 1-based line and column (in characters) of byte offset `at`.
fn line_col(text: &str, at: usize) -> (usize, usize) {
    let at = floor_boundary(text, at.min(text.len()));
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = text[line_start..at].chars().count() + 1;
    (line, col)
}
