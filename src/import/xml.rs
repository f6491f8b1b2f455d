//! The source XML: the text with its name (for `file:line:column` errors), numbers read from
//! attributes and text (their rounding noted), child elements by tag, and the tolerated
//! `<? xml` declarations.

use super::error::ImportError;
use std::cell::Cell;
use std::ops::Range;
use std::path::Path;

/// OpenSim's own serialization names some elements by their class and property,
/// `<HuntCrossleyForce::ContactParametersSet>` (eight models of opensim-org/opensim-models,
/// the DynamicJumper and the Walker among them). XML 1.0 allows `:` in a name, but a reader of
/// XML namespaces (roxmltree) refuses two in one name. Such tag names get `__` for `::`: the
/// same length, so every `file:line:column` is unchanged; the importer reads no such element.
/// `None` when no tag name has `::`.
pub(crate) fn qualified_osim_tags(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out: Option<Vec<u8>> = None;
    let mut i = 0;
    while let Some(k) = bytes[i..].iter().position(|&b| b == b'<') {
        let mut j = i + k + 1;
        if bytes.get(j) == Some(&b'/') {
            j += 1;
        }
        let start = j;
        while j < bytes.len()
            && !matches!(bytes[j], b' ' | b'\t' | b'\r' | b'\n' | b'>' | b'/' | b'<')
        {
            j += 1;
        }
        let name = &bytes[start..j];
        // Comments, declarations and CDATA start with `!` or `?`: not names.
        if !name.starts_with(b"!") && !name.starts_with(b"?") {
            let mut c = 0;
            while c + 1 < name.len() {
                if name[c] == b':' && name[c + 1] == b':' {
                    let o = out.get_or_insert_with(|| bytes.to_vec());
                    o[start + c] = b'_';
                    o[start + c + 1] = b'_';
                    c += 2;
                } else {
                    c += 1;
                }
            }
        }
        i = j.max(i + k + 1);
    }
    // Only ASCII `:` became ASCII `_`: still UTF-8.
    out.map(|o| String::from_utf8(o).expect("ASCII replaced by ASCII"))
}

/// The declarations at the start of `text` written `<?` + white space (`<? xml version="1.0"?>`,
/// as the published Stewart platform SDF begins), which no XML parser that checks
/// well-formedness accepts (a processing instruction's target must follow `<?` at once). The
/// models' reference loaders all read them: tinyxml2 (sdformat, MuJoCo, newer urdfdom) takes
/// any `<?` … `?>` before the first other node as a declaration and never reads its content;
/// TinyXML 1 (older urdfdom, OpenSim's SimTK Xml) keeps it as an unknown node. So these
/// declarations, and only these (at the document's start, before any other node), are
/// blanked: replaced by spaces of the same length, line breaks kept, so every later
/// `file:line:column` is unchanged. Returns the blanked text and one warning per declaration
/// (with its location), or `None` when there is nothing to tolerate; a `<?` + white space
/// anywhere else stays an error (tinyxml2 rejects a declaration after another node too).
pub(crate) fn tolerate_spaced_declarations(
    name: &str,
    text: &str,
) -> Option<(String, Vec<String>)> {
    let file = Path::new(name)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| name.to_string());
    let mut spans: Vec<Range<usize>> = Vec::new();
    let mut at = text.len() - text.trim_start_matches('\u{FEFF}').len();
    loop {
        at += text[at..].len() - text[at..].trim_start_matches(is_xml_space).len();
        let rest = &text[at..];
        let Some(after) = rest.strip_prefix("<?") else {
            break;
        };
        if after.starts_with(is_xml_space) {
            // tinyxml2 ends a declaration at the first `?>`; without one it is an error.
            let end = at + 2 + after.find("?>")? + 2;
            spans.push(at..end);
            at = end;
        } else if after.starts_with("xml") && spans.is_empty() {
            // A well-formed declaration first: a spaced one after it is still tolerated.
            at += 2 + after.find("?>")? + 2;
        } else {
            break;
        }
    }
    if spans.is_empty() {
        return None;
    }
    let mut out = String::with_capacity(text.len());
    let mut warnings = Vec::with_capacity(spans.len());
    let mut last = 0;
    for r in spans {
        out.push_str(&text[last..r.start]);
        let decl = &text[r.clone()];
        out.extend(
            decl.chars()
                .map(|c| if c == '\n' || c == '\r' { c } else { ' ' }),
        );
        // Blanking keeps byte offsets only if every blanked character is one byte.
        out.extend(std::iter::repeat_n(' ', decl.len() - decl.chars().count()));
        let line = text[..r.start].matches('\n').count() + 1;
        let col = text[..r.start]
            .rsplit('\n')
            .next()
            .map_or(0, |l| l.chars().count())
            + 1;
        let shown: String = decl.chars().take(80).collect();
        let shown = shown.replace(['\n', '\r'], " ");
        warnings.push(format!(
            "{file}:{line}:{col}: `{shown}` is not a well-formed XML declaration (no space may \
             follow `<?`): read as a declaration with its content ignored, as the TinyXML parsers \
             of Gazebo (sdformat), MuJoCo, urdfdom and OpenSim read it; write `<?xml` to silence this"
        ));
        last = r.end;
    }
    out.push_str(&text[last..]);
    Some((out, warnings))
}

/// XML white space (`S` in the XML grammar).
fn is_xml_space(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\n' | '\r')
}

/// One source file: its display name and text (for located errors).
pub(crate) struct Src<'a> {
    pub name: &'a str,
    pub text: &'a str,
    /// Byte offsets of the line starts (for `file:line:col` in warnings and comments).
    lines: Vec<usize>,
    /// The coarsest rounding ([`crate::numbers::rounding_of`]) of the numbers read so far that
    /// enter the geometry: what the imported file's `precision` key says
    /// ([`Builder::source_rounding`]).
    rounding: Cell<f64>,
}

pub(crate) type Node<'a> = roxmltree::Node<'a, 'a>;

impl<'a> Src<'a> {
    /// A source file.
    pub fn new(name: &'a str, text: &'a str) -> Src<'a> {
        let lines = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Src {
            name,
            text,
            lines,
            rounding: Cell::new(0.0),
        }
    }

    /// Note numbers that enter the geometry, each known to ±its rounding times `unit` (π/180
    /// for an angle in degrees: the geometry sees radians).
    pub fn note(&self, xs: &[f64], unit: f64) {
        let r = xs
            .iter()
            .map(|&x| crate::numbers::rounding_of(x) * unit)
            .fold(self.rounding.get(), f64::max);
        self.rounding.set(r);
    }

    /// The coarsest rounding noted ([`Src::note`]); 0 when every number read is exact.
    pub fn rounding(&self) -> f64 {
        self.rounding.get()
    }

    /// Parse the text (DTDs allowed, entities expanded by roxmltree's limits; an element with
    /// more than [`MAX_ATTRIBUTES`] attributes refused first).
    pub fn parse(&self) -> Result<roxmltree::Document<'a>, ImportError> {
        if let Some(at) = crowded_element(self.text) {
            let name_len = self.text[at + 1..]
                .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
                .unwrap_or(0);
            return Err(ImportError::at(
                self.name,
                self.text,
                at..at + 1 + name_len,
                "too many attributes",
                format!("an element with more than {MAX_ATTRIBUTES} attributes"),
            )
            .with_help(format!(
                "no element of MJCF, SDFormat, URDF or OpenSim has more than {MAX_ATTRIBUTES} \
                 attributes; this one is malformed or generated by mistake"
            )));
        }
        let opts = roxmltree::ParsingOptions {
            allow_dtd: true,
            ..roxmltree::ParsingOptions::default()
        };
        roxmltree::Document::parse_with_options(self.text, opts).map_err(|e| {
            let pos = e.pos();
            let at = offset_of(self.text, pos.row as usize, pos.col as usize);
            ImportError::at(
                self.name,
                self.text,
                at..at,
                "here",
                format!("malformed XML: {e}"),
            )
            .with_help("the file must be well-formed XML")
        })
    }

    /// `file:line:col` of an element.
    pub fn loc(&self, n: Node) -> String {
        let at = n.range().start.min(self.text.len());
        let line = self.lines.partition_point(|&s| s <= at).max(1);
        let start = self.lines[line - 1];
        // Columns count characters; on very long lines (minified files) bytes, to stay linear.
        let col = match self.text.get(start..at) {
            Some(t) if t.len() <= 4096 => t.chars().count() + 1,
            _ => at - start + 1,
        };
        let file = Path::new(self.name)
            .file_name()
            .and_then(|f| f.to_str())
            .unwrap_or(self.name);
        format!("{file}:{line}:{col}")
    }

    /// The span of an element's start tag name (`<joint`).
    pub fn tag_span(n: Node) -> Range<usize> {
        let s = n.range().start;
        let len = n.tag_name().name().len() + 1;
        s..(s + len).min(n.range().end)
    }

    /// An error on an element's tag.
    pub fn err(
        &self,
        n: Node,
        label: impl Into<String>,
        message: impl Into<String>,
    ) -> ImportError {
        ImportError::at(self.name, self.text, Self::tag_span(n), label, message)
    }

    /// An error on an attribute's value (or the element's tag if the attribute is absent).
    pub fn err_attr(
        &self,
        n: Node,
        attr: &str,
        label: impl Into<String>,
        message: impl Into<String>,
    ) -> ImportError {
        let span = n
            .attributes()
            .find(|a| a.name() == attr)
            .map(|a| a.range_value())
            .unwrap_or_else(|| Self::tag_span(n));
        ImportError::at(self.name, self.text, span, label, message)
    }

    /// An error on the text of an element (or its tag if it has none).
    pub fn err_text(
        &self,
        n: Node,
        label: impl Into<String>,
        message: impl Into<String>,
    ) -> ImportError {
        let span = n
            .children()
            .find(|c| c.is_text())
            .map(|t| t.range())
            .unwrap_or_else(|| Self::tag_span(n));
        ImportError::at(self.name, self.text, span, label, message)
    }

    /// An attribute parsed as `len` numbers (`None` if absent; `len` 0 = any count), noted as
    /// geometry numbers ([`Src::note`]): the importers read no others.
    pub fn nums_attr(
        &self,
        n: Node,
        attr: &str,
        len: usize,
    ) -> Result<Option<Vec<f64>>, ImportError> {
        let v = self.nums_attr_unnoted(n, attr, len)?;
        if let Some(v) = &v {
            self.note(v, 1.0);
        }
        Ok(v)
    }

    /// [`Src::nums_attr`] without noting the numbers: for angles in degrees and for numbers
    /// that enter the geometry only when used (the caller notes them then).
    pub fn nums_attr_unnoted(
        &self,
        n: Node,
        attr: &str,
        len: usize,
    ) -> Result<Option<Vec<f64>>, ImportError> {
        let Some(v) = n.attribute(attr) else {
            return Ok(None);
        };
        parse_nums(v, len).map(Some).map_err(|what| {
            self.err_attr(
                n,
                attr,
                what.clone(),
                format!("`{attr}` of <{}>: {what}", n.tag_name().name()),
            )
            .with_help(if len > 0 {
                format!("`{attr}` takes {len} numbers separated by spaces")
            } else {
                format!("`{attr}` takes numbers separated by spaces")
            })
        })
    }

    /// An element's text parsed as `len` numbers (`len` 0 = any count), noted as geometry
    /// numbers ([`Src::nums_attr`]).
    pub fn nums_text(&self, n: Node, len: usize) -> Result<Vec<f64>, ImportError> {
        let v = self.nums_text_unnoted(n, len)?;
        self.note(&v, 1.0);
        Ok(v)
    }

    /// [`Src::nums_text`] without noting the numbers ([`Src::nums_attr_unnoted`]).
    pub fn nums_text_unnoted(&self, n: Node, len: usize) -> Result<Vec<f64>, ImportError> {
        let text = n.text().unwrap_or("");
        parse_nums(text, len).map_err(|what| {
            self.err_text(
                n,
                what.clone(),
                format!("<{}>: {what}", n.tag_name().name()),
            )
        })
    }
}

/// Largest magnitude of a number in the imported geometry (the builder checks it): beyond it
/// a number is no size of a model, and the imported file could not be read back. The numbers
/// read may be larger (a quaternion or an axis is only a direction).
pub(crate) const MAX_MAGNITUDE: f64 = 1e18;

/// Parse whitespace-separated finite numbers, exactly `len` of them (`len` 0 = any count).
fn parse_nums(text: &str, len: usize) -> Result<Vec<f64>, String> {
    let mut out = Vec::new();
    for w in text.split_whitespace() {
        match w.parse::<f64>() {
            Ok(x) if x.is_finite() => out.push(x),
            _ => return Err(format!("`{w}` is not a finite number")),
        }
    }
    if len != 0 && out.len() != len {
        return Err(format!("expected {len} numbers, found {}", out.len()));
    }
    Ok(out)
}

/// Most attributes one element may have. The XML parser checks each attribute against the
/// element's others (its work grows with the square of their number); bounded, its work is
/// linear in the text. The models' schemas have fewer than 50 attributes on any element.
pub(crate) const MAX_ATTRIBUTES: usize = 128;

/// The byte offset of the first start tag with more than [`MAX_ATTRIBUTES`] attributes (each
/// `=` outside quotes counted), found in one pass: comments, CDATA sections and processing
/// instructions are skipped; start tags inside a DTD's entity values are counted too (they
/// become elements where the entity is used). Malformed text ends the scan (the parser then
/// says where it is malformed).
fn crowded_element(text: &str) -> Option<usize> {
    let b = text.as_bytes();
    let find = |from: usize, what: &[u8]| -> Option<usize> {
        memchr::memmem::find(&b[from..], what).map(|k| from + k + what.len())
    };
    let mut i = 0;
    while let Some(k) = memchr::memchr(b'<', &b[i..]) {
        let at = i + k;
        let rest = &b[at..];
        i = if rest.starts_with(b"<!--") {
            find(at + 4, b"-->")?
        } else if rest.starts_with(b"<![CDATA[") {
            find(at + 9, b"]]>")?
        } else if rest.starts_with(b"<?") {
            find(at + 2, b"?>")?
        } else if rest
            .get(1)
            .is_some_and(|&c| c.is_ascii_alphabetic() || c == b'_' || c == b':' || c >= 0x80)
        {
            let mut j = at + 1;
            let mut count = 0;
            loop {
                match *b.get(j)? {
                    b'>' => break,
                    q @ (b'"' | b'\'') => j += memchr::memchr(q, &b[j + 1..])? + 1,
                    b'=' => {
                        count += 1;
                        if count > MAX_ATTRIBUTES {
                            return Some(at);
                        }
                    }
                    _ => {}
                }
                j += 1;
            }
            j + 1
        } else {
            at + 1
        };
    }
    None
}

/// Child elements of `n` with local name `tag`.
pub(crate) fn children<'a>(n: Node<'a>, tag: &'a str) -> impl Iterator<Item = Node<'a>> + 'a {
    n.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == tag)
}

/// The first child element of `n` with local name `tag`.
pub(crate) fn child<'a>(n: Node<'a>, tag: &str) -> Option<Node<'a>> {
    n.children()
        .find(|c| c.is_element() && c.tag_name().name() == tag)
}

/// Byte offset of a 1-based line and 1-based column (in characters).
fn offset_of(text: &str, line: usize, col: usize) -> usize {
    let mut start = 0;
    for _ in 1..line {
        match text[start..].find('\n') {
            Some(i) => start += i + 1,
            None => return text.len(),
        }
    }
    let line_text = &text[start..];
    let mut at = start;
    for (i, (b, _)) in line_text.char_indices().enumerate() {
        if i + 1 >= col {
            return start + b;
        }
        at = start + b;
    }
    at.min(text.len())
}

#[cfg(test)]
mod tests {
    use super::qualified_osim_tags;

    /// Start and end tags named `Class::Property` get `__` (a tag written inside a comment
    /// too, which nothing reads); text and attribute values keep their `::`; the length stays.
    #[test]
    fn only_tag_names_lose_their_double_colons() {
        let text = "<a x=\"b::c\"><!-- <K::P> --><K::P n=\"1\">t::u</K::P><K::P/></a>";
        let out = qualified_osim_tags(text).expect("a tag to rename");
        assert_eq!(
            out,
            "<a x=\"b::c\"><!-- <K__P> --><K__P n=\"1\">t::u</K__P><K__P/></a>"
        );
        assert_eq!(out.len(), text.len());
        assert_eq!(qualified_osim_tags("<a x=\"b::c\">t::u</a>"), None);
    }
}
