//! A single-pass reader for the items of a YAML joint list in the shapes large files are
//! written in: each item a block mapping whose first key follows the `- `, one
//! `key: value` a line, values plain scalars, one-line flow sequences of plain scalars
//! (`[1, 2]`) or block sequences of plain scalars (`- 1` a line). The head of the file (every
//! top-level key before the joint list) is read by saphyr as before; only the items, nearly
//! all of the text, are read here, one at a time ([`super::read::Lazy::YamlLines`]), into the
//! same tree saphyr gives (tested equal on generated and mutated texts).
//!
//! It declines (`None`) at anything else: quotes, comments, anchors, aliases, tags, tabs,
//! flow mappings, nested sequences, multi-line scalars, a scalar with a character outside
//! `[A-Za-z0-9_.+-]`, a line it cannot place (another top-level key after the list, a document
//! marker). The caller then reads the text with saphyr, which also finds every error; so every
//! error (and its location) is saphyr's, as before.

use super::tree::{Entry, Node, Value, resolve_plain_str};
use std::borrow::Cow;
use std::ops::Range;

/// A reader of the items of a block sequence whose first `- ` is at `pos`, indented `indent`.
pub(crate) struct Items<'a> {
    text: &'a str,
    pos: usize,
    indent: usize,
}

impl<'a> Items<'a> {
    /// At the `-` of the first item of a block sequence (only spaces before it on its line).
    pub(crate) fn new(text: &'a str, pos: usize) -> Option<Items<'a>> {
        let bytes = text.as_bytes();
        let line = text[..pos].rfind('\n').map_or(0, |i| i + 1);
        let before = &bytes[line..pos];
        // saphyr's span starts at the first item's content, past the `- `; or at the `-`.
        let dash = if before.ends_with(b"- ") {
            pos - 2
        } else if bytes[pos..].starts_with(b"- ") {
            pos
        } else {
            return None;
        };
        if !bytes[line..dash].iter().all(|&b| b == b' ') {
            return None;
        }
        Some(Items {
            text,
            pos: line,
            indent: dash - line,
        })
    }

    /// The next item (`Some(None)` at the end of the text; `None`: declined).
    pub(crate) fn next_item(&mut self) -> Option<Option<Node<'a>>> {
        let bytes = self.text.as_bytes();
        let (text, d) = (self.text, self.indent);
        // Blank lines before the item.
        loop {
            if self.pos >= bytes.len() {
                return Some(None);
            }
            let end = line_end(bytes, self.pos);
            if bytes[self.pos..end].iter().all(|&b| b == b' ') {
                self.pos = (end + 1).min(bytes.len());
            } else {
                break;
            }
        }
        let start = self.pos + d;
        // A line shorter than the indentation is no item either.
        let prefix = bytes.get(self.pos..start)?;
        if !prefix.iter().all(|&b| b == b' ') || !bytes[start..].starts_with(b"- ") {
            return None;
        }
        // The mapping's keys are at column m.
        let m = d + 2;
        let mut entries: Vec<Entry<'a>> = Vec::with_capacity(4);
        let mut line = self.pos;
        let mut first = true;
        let mut last = start + 1;
        loop {
            if line >= bytes.len() {
                break;
            }
            let end = line_end(bytes, line);
            let lead = bytes[line..end].iter().take_while(|&&b| b == b' ').count();
            if lead == end - line {
                // Blank.
                line = (end + 1).min(bytes.len());
                continue;
            }
            let key_line = lead == m && bytes[line + lead] != b'-';
            if !first && !key_line {
                // The next item (checked there) or anything else: the item ends here.
                break;
            }
            first = false;
            let k0 = line + m;
            let (key, after) = key(text, k0, end)?;
            if entries.iter().any(|e| e.key == key) {
                return None;
            }
            let key_span = k0..after;
            let v0 = skip_spaces(bytes, after + 1, end);
            line = (end + 1).min(bytes.len());
            let value = if v0 == end {
                // `key:` then a block sequence of scalars, at column m or m + 2.
                let (node, next) = block_seq(text, line, m)?;
                line = next;
                node
            } else if bytes[v0] == b'[' {
                flow_seq(text, v0, end)?
            } else {
                let s = scalar(text, v0, end)?;
                if s.span.end != trim_end(bytes, v0, end) {
                    return None;
                }
                s
            };
            last = value.span.end;
            entries.push(Entry {
                key: Cow::Borrowed(key),
                key_span,
                value,
            });
        }
        self.pos = line;
        Some(Some(Node {
            span: start + 2..last,
            value: Value::Map(entries),
        }))
    }
}

/// The end of the line at `pos` (its `\n`, or the end of the text).
fn line_end(bytes: &[u8], pos: usize) -> usize {
    bytes[pos..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |i| pos + i)
}

fn skip_spaces(bytes: &[u8], mut i: usize, end: usize) -> usize {
    while i < end && bytes[i] == b' ' {
        i += 1;
    }
    i.min(end)
}

fn trim_end(bytes: &[u8], start: usize, mut end: usize) -> usize {
    while end > start && bytes[end - 1] == b' ' {
        end -= 1;
    }
    end
}

/// A key `[A-Za-z0-9_]+` at `k0` followed by `:` and a space or the line's end: the key and
/// the position of the `:`.
fn key(text: &str, k0: usize, end: usize) -> Option<(&str, usize)> {
    let bytes = text.as_bytes();
    let mut i = k0;
    while i < end && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
        i += 1;
    }
    if i == k0 || bytes.get(i) != Some(&b':') || !(i + 1 == end || bytes[i + 1] == b' ') {
        return None;
    }
    Some((&text[k0..i], i))
}

fn plain_char(b: u8) -> bool {
    b.is_ascii_alphanumeric() || matches!(b, b'_' | b'.' | b'+' | b'-')
}

/// A plain scalar of `[A-Za-z0-9_.+-]` at `at` (not a lone `-`), resolved by the core schema.
fn scalar(text: &str, at: usize, end: usize) -> Option<Node<'_>> {
    let bytes = text.as_bytes();
    let mut i = at;
    while i < end && plain_char(bytes[i]) {
        i += 1;
    }
    let s = &text[at..i];
    if s.is_empty() || s == "-" {
        return None;
    }
    Some(Node {
        span: at..i,
        value: resolve_plain_str(s).unwrap_or(Value::Str(Cow::Borrowed(s))),
    })
}

/// `[a, b, ...]` of plain scalars, alone on the rest of the line.
fn flow_seq(text: &str, open: usize, end: usize) -> Option<Node<'_>> {
    let bytes = text.as_bytes();
    let mut items = Vec::new();
    let mut i = skip_spaces(bytes, open + 1, end);
    if bytes.get(i) == Some(&b']') {
        i += 1;
    } else {
        loop {
            let s = scalar(text, i, end)?;
            i = skip_spaces(bytes, s.span.end, end);
            items.push(s);
            match bytes.get(i) {
                Some(b',') if i < end => i = skip_spaces(bytes, i + 1, end),
                Some(b']') if i < end => {
                    i += 1;
                    break;
                }
                _ => return None,
            }
        }
    }
    if trim_end(bytes, i, end) != i {
        return None;
    }
    Some(Node {
        span: open..i,
        value: Value::Seq(items),
    })
}

/// The block sequence of plain scalars from the line at `line` (`- x` a line at column `m` or
/// `m + 2`): the node and the first line after it.
fn block_seq(text: &str, mut line: usize, m: usize) -> Option<(Node<'_>, usize)> {
    let bytes = text.as_bytes();
    let mut items = Vec::new();
    let mut col = None;
    let mut span: Option<Range<usize>> = None;
    while line < bytes.len() {
        let end = line_end(bytes, line);
        let lead = bytes[line..end].iter().take_while(|&&b| b == b' ').count();
        if lead == end - line {
            line = (end + 1).min(bytes.len());
            continue;
        }
        let dash = line + lead;
        let here = col.map_or(lead == m || lead == m + 2, |c| c == lead);
        if !here || !bytes[dash..end].starts_with(b"- ") {
            break;
        }
        col = Some(lead);
        let s = scalar(text, skip_spaces(bytes, dash + 2, end), end)?;
        if s.span.end != trim_end(bytes, s.span.start, end) {
            return None;
        }
        span = Some(span.map_or(dash..s.span.end, |r| r.start..s.span.end));
        items.push(s);
        line = (end + 1).min(bytes.len());
    }
    // `key:` with nothing under it is null in YAML: left to saphyr.
    let span = span?;
    Some((
        Node {
            span,
            value: Value::Seq(items),
        },
        line,
    ))
}

#[cfg(test)]
mod tests {
    use super::super::read::{Lazy, parse_yaml, parse_yaml_fast};
    use super::*;

    fn strip(n: &Node) -> String {
        match &n.value {
            Value::Map(es) => format!(
                "{{{}}}",
                es.iter()
                    .map(|e| format!("{}:{}", e.key, strip(&e.value)))
                    .collect::<Vec<_>>()
                    .join(",")
            ),
            Value::Seq(xs) => format!("[{}]", xs.iter().map(strip).collect::<Vec<_>>().join(",")),
            v => format!("{v:?}"),
        }
    }

    /// The joint list's items as read here, when every one is (`None`: declined).
    fn fast_items(text: &str) -> Option<Vec<String>> {
        let (_, lazy) = parse_yaml_fast(text)?;
        let Lazy::YamlLines { mut items, .. } = lazy else {
            return None;
        };
        let mut out = Vec::new();
        while let Some(item) = items.next_item()? {
            out.push(strip(&item));
        }
        Some(out)
    }

    /// The joint list's items as saphyr reads the whole text.
    fn saphyr_items(text: &str) -> Option<Vec<String>> {
        let root = parse_yaml(text).ok()??;
        let Value::Map(es) = root.value else {
            return None;
        };
        let list = es.into_iter().find(|e| e.key == "joint")?;
        match list.value.value {
            Value::Seq(items) => Some(items.iter().map(strip).collect()),
            _ => None,
        }
    }

    const BASE: &str = "name: t\nspace: planar\nframe: 1\njoint:\n- type: R\n  bodies:\n  - 1\n  - 2\n  driven: 1\n- type: P\n  bodies: [2, -3]\n  axis: [1.5, 0, 2e3]\n- id: a_b\n  type: R\n  bodies:\n    - x.y\n    - +7\n  origin: [.5, -0.25]\n";

    #[test]
    fn reads_the_generated_shapes_as_saphyr_does() {
        let got = fast_items(BASE).expect("read");
        assert_eq!(got.len(), 3);
        assert_eq!(Some(got), saphyr_items(BASE));
        // Indented list items, blank lines, trailing spaces.
        // A last line shorter than the list's indentation: declined, not a panic.
        let short = "frame: 1\njoint:\n    - type: R\n      bodies: [1, 2]\nab";
        assert!(Items::new(short, short.find("type").unwrap_or(0)).is_some());
        assert!(fast_items(short).is_none());
        let indented = BASE
            .replace("\n- ", "\n  - ")
            .replace("\n  bodies", "\n    bodies");
        let indented = indented
            .replace("\n  driven", "\n    driven")
            .replace("\n  axis", "\n    axis");
        let indented = indented
            .replace("\n  type", "\n    type")
            .replace("\n  origin", "\n    origin");
        let indented = indented.replace("\n  - 1\n  - 2", "\n    - 1\n    - 2");
        let indented = indented.replace("\n    - x.y\n    - +7", "\n      - x.y\n      - +7");
        let read = fast_items(&indented);
        assert!(read.is_some(), "{indented}");
        assert_eq!(read, saphyr_items(&indented));
    }

    #[test]
    fn mutated_texts_agree_with_saphyr() {
        let alphabet = b" \n-:[],#'\"&*!\t.01279abRxe~";
        let mut read = 0;
        for text in crate::format::mutated_texts(BASE, alphabet, 0x5DEE_CE66_D1CE_4E5B, 6000, 2) {
            let Some(ours) = fast_items(&text) else {
                continue;
            };
            read += 1;
            assert_eq!(Some(ours), saphyr_items(&text), "{text:?}");
        }
        assert!(read > 500, "{read}");
    }
}
