//! [`LoadError`]: a located, renderable error of the mechanism reader.

use miette::{Diagnostic, LabeledSpan, NamedSource, SourceCode};
use serde::Serialize;
use std::fmt;
use std::ops::Range;

/// What went wrong while reading a mechanism file: one variant per kind of error
/// (`docs/format.md` lists them with examples).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum ErrorKind {
    /// Malformed TOML, YAML or JSON.
    Syntax,
    /// The file holds no keys at all.
    Empty,
    /// The bytes are not UTF-8 text.
    NotUtf8,
    /// The file is larger than the reader accepts.
    TooLarge,
    /// Values nested deeper than the reader accepts.
    TooDeep,
    /// YAML features the format does not use (aliases, custom tags, several documents,
    /// non-scalar keys).
    Unsupported,
    /// The same key twice in one table or mapping.
    DuplicateKey,
    /// A key the format does not know.
    UnknownKey,
    /// No `frame` key.
    MissingFrame,
    /// No joints (or bars) at all.
    NoJoints,
    /// A required key of a joint, body, point or bar is missing.
    MissingField,
    /// A value of the wrong type (a string where a number is expected, ...).
    WrongType,
    /// A number too large for the reader (an integer beyond 64 bits, a geometry number beyond
    /// 1e100 in magnitude), or a `precision` below 0.
    NumberOutOfRange,
    /// An empty string used as an id.
    EmptyId,
    /// `space` is not spatial, planar or spherical.
    InvalidSpace,
    /// Both a key and its alias (`joint` and `joints`, ...).
    BothAliases,
    /// A joint type that is neither a code nor a long name of the catalogue.
    UnknownJointType,
    /// A joint naming fewer than two bodies.
    TooFewBodies,
    /// A joint naming the same body twice.
    RepeatedBody,
    /// `driven` negative or above the joint's DOF.
    DrivenOutOfRange,
    /// A joint names a body that the `body` list does not declare.
    UndeclaredBody,
    /// Two joints with the same id.
    DuplicateJointId,
    /// Two bodies (or bars) with the same id.
    DuplicateBodyId,
    /// The frame is joined to nothing.
    FrameNotInJoint,
    /// A joint kind that does not exist in a planar or spherical mechanism.
    JointNotValidInSpace,
    /// A coordinate array of the wrong length.
    GeometryLength,
    /// An axis or normal of zero length.
    ZeroAxis,
    /// NaN or infinity in geometry (or in `precision`).
    NonFinite,
    /// Joints and a bar-joint framework in the same file.
    MixedFramework,
    /// A bar naming a point that is not declared.
    UnknownPoint,
    /// A bar that does not join exactly two distinct points.
    BarPoints,
    /// Two points with the same id.
    DuplicatePointId,
    /// A joint's `second` geometry where it makes no sense (a kind whose second body carries
    /// no such feature, a multiple joint, a framework).
    SecondNotApplicable,
}

/// Most source lines a label's span covers in a rendered snippet; longer spans are cut.
pub(crate) const MAX_SPAN_LINES: usize = 3;

/// One labelled span of the source.
#[derive(Clone, Debug)]
pub(crate) struct Label {
    pub span: Range<usize>,
    pub text: String,
}

/// A mechanism-file error with its location: renders with [`crate::diagnostic::render`]
/// as `file:line:col`, the source snippet, a label and (when one helps) a hint.
#[derive(Debug)]
pub struct LoadError(Box<Inner>);

/// The fields, boxed so that `Result<_, LoadError>` stays small.
#[derive(Debug)]
struct Inner {
    kind: ErrorKind,
    message: String,
    labels: Vec<Label>,
    help: Option<String>,
    line_col: Option<(usize, usize)>,
    source: Option<NamedSource<String>>,
}

impl LoadError {
    /// A new error; `labels[0]` (if any) is the primary location.
    pub(crate) fn new(
        kind: ErrorKind,
        message: impl Into<String>,
        labels: Vec<Label>,
        help: Option<String>,
    ) -> LoadError {
        LoadError(Box::new(Inner {
            kind,
            message: message.into(),
            labels,
            help,
            line_col: None,
            source: None,
        }))
    }

    /// Attach the source text (and compute the line and column of the primary label).
    pub(crate) fn with_source(mut self, name: &str, text: &str) -> LoadError {
        let text_len = text.len();
        for l in &mut self.0.labels {
            // Keep spans on char boundaries inside the text so that rendering never fails.
            l.span.start = floor_boundary(text, l.span.start.min(text_len));
            l.span.end = floor_boundary(text, l.span.end.clamp(l.span.start, text_len));
            // A span over a long value (a 200,000-line array) would echo every line: keep
            // its first lines only.
            if let Some((cut, _)) = text[l.span.start..l.span.end]
                .match_indices('\n')
                .nth(MAX_SPAN_LINES - 1)
            {
                l.span.end = l.span.start + cut;
            }
        }
        self.0.line_col = self.0.labels.first().map(|l| line_col(text, l.span.start));
        self.0.source = Some(NamedSource::new(name, text.to_string()));
        self
    }

    /// The kind of error (for tests and programmatic handling).
    pub fn kind(&self) -> ErrorKind {
        self.0.kind
    }

    /// The error message without location.
    pub fn message(&self) -> &str {
        &self.0.message
    }

    /// The hint, if any.
    pub fn hint(&self) -> Option<&str> {
        self.0.help.as_deref()
    }

    /// 1-based line and column (in characters) of the primary location, if the error has one.
    pub fn line_col(&self) -> Option<(usize, usize)> {
        self.0.line_col
    }

    /// Byte span of the primary location, if any.
    pub fn span(&self) -> Option<Range<usize>> {
        self.0.labels.first().map(|l| l.span.clone())
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0.message)
    }
}

impl std::error::Error for LoadError {}

impl Diagnostic for LoadError {
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
        if self.0.labels.is_empty() || self.0.source.is_none() {
            return None;
        }
        Some(Box::new(self.0.labels.iter().enumerate().map(|(i, l)| {
            let span = (l.span.start, l.span.end - l.span.start);
            let text = (!l.text.is_empty()).then(|| l.text.clone());
            if i == 0 {
                LabeledSpan::new_primary_with_span(text, span)
            } else {
                LabeledSpan::new_with_span(text, span)
            }
        })))
    }
}

/// The largest char boundary `<= i`.
pub(crate) fn floor_boundary(text: &str, mut i: usize) -> usize {
    while i > 0 && !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// 1-based line and column (in characters) of byte offset `at`.
pub(crate) fn line_col(text: &str, at: usize) -> (usize, usize) {
    let at = floor_boundary(text, at.min(text.len()));
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = text[line_start..at].chars().count() + 1;
    (line, col)
}

/// Byte offset of the 1-based `line` and 1-based byte `col` (as serde_json reports them).
pub(crate) fn offset_of(text: &str, line: usize, col: usize) -> usize {
    let mut start = 0;
    for _ in 1..line {
        match text[start..].find('\n') {
            Some(i) => start += i + 1,
            None => return text.len(),
        }
    }
    floor_boundary(text, (start + col.saturating_sub(1)).min(text.len()))
}
