//! A single-pass reader for the TOML that large mechanism files are written in (issue 16):
//! one `key = value` per line, bare keys, scalars and one-line arrays of scalars, top-level
//! `[table]` headers and `[[joint]]` tables. It builds the same spanned tree as the toml crate
//! (tested equal) without the crate's token vector, maps and per-value allocations, and reads
//! the joints one at a time ([`super::tree::Lazy::TomlLines`]).
//!
//! It accepts a strict subset of TOML and declines (`None`) at anything else: escapes,
//! literal or multi-line strings, dotted or quoted keys, inline tables, nested arrays,
//! underscores in numbers, non-decimal integers, `inf`/`nan`, date-times, a duplicate key,
//! a control character. The caller then reads the text with the toml crate, which also finds
//! every error; so every error (and its location) is the toml crate's, as before.

use super::tree::{Entry, Node, Value};
use std::borrow::Cow;
use std::ops::Range;

/// The joint table header.
const JOINT: &str = "[[joint]]";

/// The top-level tree with the joint list [`Value::Deferred`] (when there are `[[joint]]`
/// tables), and the byte range of each joint table: from its header to the next header.
pub(crate) fn parse(text: &str) -> Option<(Node<'_>, Vec<Range<usize>>)> {
    let bytes = text.as_bytes();
    let mut top: Vec<Entry<'_>> = Vec::new();
    // The table being filled: `None` the top level, `Some(i)` the `[name]` table top[i].
    let mut table: Option<usize> = None;
    let mut in_joints = false;
    let mut joints: Vec<Range<usize>> = Vec::new();
    let mut joint_entry: Option<Entry<'_>> = None;
    let mut pos = 0;
    while pos < bytes.len() {
        let end = text[pos..].find('\n').map_or(bytes.len(), |i| pos + i);
        let first = skip_ws(bytes, pos, end);
        if bytes.get(first) == Some(&b'[') {
            // A header closes the joint table before it.
            if in_joints && let Some(last) = joints.last_mut() {
                last.end = pos;
            }
            if bytes[first..end].starts_with(JOINT.as_bytes()) {
                line_end(bytes, first + JOINT.len(), end)?;
                if joint_entry.is_none() {
                    if top.iter().any(|e| e.key == "joint") {
                        return None;
                    }
                    joint_entry = Some(Entry {
                        key: Cow::Borrowed("joint"),
                        key_span: first + 2..first + 7,
                        value: Node {
                            span: first..first + JOINT.len(),
                            value: Value::Deferred,
                        },
                    });
                }
                joints.push(first..bytes.len());
                in_joints = true;
            } else {
                let (name, after) = bare_key(bytes, first + 1, end)?;
                if bytes.get(after) != Some(&b']') {
                    return None;
                }
                line_end(bytes, after + 1, end)?;
                let key = &text[name.clone()];
                if key == "joint" || top.iter().any(|e| e.key == key) {
                    return None;
                }
                top.push(Entry {
                    key: Cow::Borrowed(key),
                    key_span: name,
                    value: Node {
                        span: first..after + 1,
                        value: Value::Map(Vec::new()),
                    },
                });
                table = Some(top.len() - 1);
                in_joints = false;
            }
        } else if !in_joints {
            // Lines of the joint tables are read later, one table at a time.
            if let Some(entry) = line(text, pos, end)? {
                let entries = match table {
                    None => &mut top,
                    Some(i) => match &mut top[i].value.value {
                        Value::Map(es) => es,
                        _ => return None,
                    },
                };
                if entries.iter().any(|e| e.key == entry.key)
                    || (table.is_none() && is_joint_key(&entry.key))
                {
                    return None;
                }
                entries.push(entry);
            }
        }
        pos = end + 1;
    }
    if let Some(e) = joint_entry {
        top.push(e);
    }
    top.sort_by_key(|e| e.key_span.start);
    Some((
        Node {
            span: 0..0,
            value: Value::Map(top),
        },
        joints,
    ))
}

/// `joint` (also the header's key: both in one file is an error the toml crate reports) or
/// `joints` (allowed next to `[[joint]]` tables by TOML; the model reports both).
fn is_joint_key(key: &str) -> bool {
    key == "joint"
}

/// One joint table: `range` from its `[[joint]]` header to the next header.
pub(crate) fn joint(text: &str, range: Range<usize>) -> Option<Node<'_>> {
    let header = range.start..range.start + JOINT.len();
    let mut pos = text[range.clone()]
        .find('\n')
        .map_or(range.end, |i| range.start + i)
        + 1;
    let mut entries: Vec<Entry<'_>> = Vec::with_capacity(4);
    while pos < range.end {
        let end = text[pos..range.end]
            .find('\n')
            .map_or(range.end, |i| pos + i);
        if let Some(entry) = line(text, pos, end)? {
            if entries.iter().any(|e| e.key == entry.key) {
                return None;
            }
            entries.push(entry);
        }
        pos = end + 1;
    }
    Some(Node {
        span: header,
        value: Value::Map(entries),
    })
}

fn skip_ws(bytes: &[u8], mut i: usize, end: usize) -> usize {
    while i < end && matches!(bytes[i], b' ' | b'\t') {
        i += 1;
    }
    i
}

/// A comment's characters: no control character but tab (a `\r` only before the `\n`).
fn comment_ok(bytes: &[u8], from: usize, end: usize) -> bool {
    let body = match bytes[from..end].split_last() {
        Some((b'\r', rest)) => rest,
        _ => &bytes[from..end],
    };
    body.iter().all(|&b| (b >= 0x20 || b == b'\t') && b != 0x7F)
}

/// The rest of a line after a value or header: blanks, then nothing or a comment.
fn line_end(bytes: &[u8], from: usize, end: usize) -> Option<()> {
    let i = skip_ws(bytes, from, end);
    match bytes.get(i) {
        _ if i == end => Some(()),
        Some(b'\r') if i + 1 == end => Some(()),
        Some(b'#') => comment_ok(bytes, i + 1, end).then_some(()),
        _ => None,
    }
}

/// A bare key at `from`: its span and where it ends.
fn bare_key(bytes: &[u8], from: usize, end: usize) -> Option<(Range<usize>, usize)> {
    let mut i = from;
    while i < end && matches!(bytes[i], b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'_' | b'-') {
        i += 1;
    }
    (i > from).then_some((from..i, i))
}

/// A blank line, a comment line, or `key = value` (`Some(None)`, `Some(Some(entry))`).
fn line(text: &str, start: usize, end: usize) -> Option<Option<Entry<'_>>> {
    let bytes = text.as_bytes();
    let i = skip_ws(bytes, start, end);
    if i == end || (i + 1 == end && bytes[i] == b'\r') {
        return Some(None);
    }
    if bytes[i] == b'#' {
        return comment_ok(bytes, i + 1, end).then_some(None);
    }
    let (key_span, after) = bare_key(bytes, i, end)?;
    let eq = skip_ws(bytes, after, end);
    if bytes.get(eq) != Some(&b'=') || eq >= end {
        return None;
    }
    let at = skip_ws(bytes, eq + 1, end);
    let (value, after) = match bytes.get(at) {
        Some(b'[') if at < end => array(text, at, end)?,
        _ => scalar(text, at, end)?,
    };
    line_end(bytes, after, end)?;
    Some(Some(Entry {
        key: Cow::Borrowed(&text[key_span.clone()]),
        key_span,
        value,
    }))
}

/// A one-line array of scalars at `at` (its `[`), trailing comma allowed.
fn array(text: &str, at: usize, end: usize) -> Option<(Node<'_>, usize)> {
    let bytes = text.as_bytes();
    let mut items = Vec::new();
    let mut i = skip_ws(bytes, at + 1, end);
    loop {
        if i >= end {
            return None;
        }
        if bytes[i] == b']' {
            break;
        }
        let (item, after) = scalar(text, i, end)?;
        items.push(item);
        i = skip_ws(bytes, after, end);
        match bytes.get(i) {
            Some(b',') if i < end => i = skip_ws(bytes, i + 1, end),
            Some(b']') if i < end => break,
            _ => return None,
        }
    }
    Some((
        Node {
            span: at..i + 1,
            value: Value::Seq(items),
        },
        i + 1,
    ))
}

/// A scalar at `at`: a basic string without escapes, an integer, a float or a boolean.
fn scalar(text: &str, at: usize, end: usize) -> Option<(Node<'_>, usize)> {
    let bytes = text.as_bytes();
    if at >= end {
        return None;
    }
    if bytes[at] == b'"' {
        let mut i = at + 1;
        while i < end {
            match bytes[i] {
                b'"' => break,
                b'\\' | 0x7F => return None,
                b if b < 0x20 && b != b'\t' => return None,
                _ => i += 1,
            }
        }
        if i >= end || bytes.get(i + 1) == Some(&b'"') {
            // Unterminated, or `""` opening a multi-line string.
            return None;
        }
        return Some((
            Node {
                span: at..i + 1,
                value: Value::Str(Cow::Borrowed(&text[at + 1..i])),
            },
            i + 1,
        ));
    }
    let mut i = at;
    while i < end && !matches!(bytes[i], b' ' | b'\t' | b',' | b']' | b'#' | b'\r') {
        i += 1;
    }
    let token = &text[at..i];
    let value = match token {
        "true" => Value::Bool(true),
        "false" => Value::Bool(false),
        _ => number(token)?,
    };
    Some((Node { span: at..i, value }, i))
}

/// A decimal integer (fitting in 64 bits) or a float in TOML's grammar, without underscores.
fn number(t: &str) -> Option<Value<'static>> {
    let b = t.as_bytes();
    let mut i = usize::from(matches!(b.first(), Some(b'+' | b'-')));
    let digits = |from: usize| {
        let mut j = from;
        while j < b.len() && b[j].is_ascii_digit() {
            j += 1;
        }
        j
    };
    let int_end = digits(i);
    // `0` or digits without a leading zero.
    if int_end == i || (b[i] == b'0' && int_end > i + 1) {
        return None;
    }
    i = int_end;
    if i == b.len() {
        return t.parse::<i64>().ok().map(Value::Int);
    }
    if b[i] == b'.' {
        let frac_end = digits(i + 1);
        if frac_end == i + 1 {
            return None;
        }
        i = frac_end;
    }
    if i < b.len() && matches!(b[i], b'e' | b'E') {
        let from = i + 1 + usize::from(matches!(b.get(i + 1), Some(b'+' | b'-')));
        let exp_end = digits(from);
        if exp_end == from {
            return None;
        }
        i = exp_end;
    }
    if i != b.len() {
        return None;
    }
    t.parse::<f64>().ok().map(Value::Float)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast tree with its joints read, or `None` where the fast path declines.
    pub(crate) fn whole(text: &str) -> Option<Node<'_>> {
        let (mut root, joints) = parse(text)?;
        let mut items = Vec::with_capacity(joints.len());
        for r in joints {
            items.push(joint(text, r)?);
        }
        if let Value::Map(es) = &mut root.value
            && let Some(e) = es.iter_mut().find(|e| e.key == "joint")
        {
            e.value.value = Value::Seq(items);
        }
        Some(root)
    }

    /// Where the fast path reads a text, the toml crate reads it and gives the same tree.
    fn agrees(text: &str) -> bool {
        let fast = whole(text);
        let serial = super::super::tree::parse_toml_serial(text).ok();
        match fast {
            Some(f) => {
                assert_eq!(Some(f), serial, "fast tree differs for {text:?}");
                true
            }
            None => false,
        }
    }

    const SAMPLE: &str = "# c\nname = \"x é\" # k\n  frame = 1\nspace=\"planar\"\n\n[[joint]]\ntype = \"R\"\t\nbodies = [1, 2 , ] \ndriven = 1\n\n  [[joint]] # h\r\nid = \"A\"\r\ntype = \"R\"\nbodies = [1, 3]\norigin = [0.5, -1e3, 2E+2, 0.0, -0]\nx = [true, false, \"s\"]\n\n[expect]\nmobility = 1\ndetermined = true\n";

    #[test]
    fn fast_toml_gives_the_toml_crate_tree() {
        assert!(agrees(SAMPLE));
        assert!(agrees("frame = 1\n"));
        assert!(agrees(
            "\n\n# only\nframe = 1\n[[joint]]\n[[joint]]\ntype = \"R\"\n"
        ));
        assert!(agrees("[expect]\nmobility = 2\n[[joint]]\nbodies = []\n"));
        assert!(agrees(
            "frame = 1\n[[joint]]\nbodies = [9223372036854775807, -9223372036854775808]\n"
        ));
        for m in [
            crate::generate::random(60, false, 3).unwrap().0,
            crate::generate::random(40, true, 5).unwrap().0,
            crate::generate::assur(2, 5, 364, crate::generate::Variant::A).unwrap(),
        ] {
            assert!(agrees(&crate::generate::to_toml(&m)));
        }
        for (_, _, text) in crate::examples::EXAMPLES {
            agrees(text);
        }
    }

    #[test]
    fn fast_toml_declines_what_it_does_not_read() {
        let cases = [
            "frame = 1\nname = \"a\\tb\"\n",
            "frame = 1\nname = 'lit'\n",
            "frame = 1\nname = \"\"\"\nx\"\"\"\n",
            "frame = 1\na.b = 1\n",
            "frame = 1\n\"q\" = 1\n",
            "frame = 1\nx = {a = 1}\n",
            "frame = 1\nx = [[1], [2]]\n",
            "frame = 1\nx = [1,\n2]\n",
            "frame = 1\nx = 1_000\n",
            "frame = 1\nx = 0x10\n",
            "frame = 1\nx = inf\n",
            "frame = 1\nx = nan\n",
            "frame = 1\nx = 1979-05-27\n",
            "frame = 1\nx = 01\n",
            "frame = 1\nx = .5\n",
            "frame = 1\nx = 5.\n",
            "frame = 1\nx = 1e\n",
            "frame = 1\nx = 99999999999999999999\n",
            "frame = 1\nframe = 2\n",
            "frame = 1\n[[joint]]\ntype = \"R\"\ntype = \"S\"\n",
            "frame = 1\n[e]\n[e]\n",
            "frame = 1\n[joint]\nx = 1\n",
            "frame = 1\njoint = 1\n[[joint]]\n",
            "frame = 1\n[[ joint ]]\n",
            "frame = 1\n[[body]]\nid = 1\n",
            "frame = 1\n[a.b]\n",
            "frame = 1\nx = \"a\u{1}b\"\n",
            "frame = 1 # a\u{7f}\n",
            "frame = 1\rx = 2\n",
            "frame = 1\nx = \n",
            "frame = 1\nx = [1 2]\n",
            "frame = 1\nx = [1,,2]\n",
            "frame = 1\nx = \"a\n",
            "frame = 1\n[[joint]] x\n",
            "frame = 1\n= 1\n",
            "frame = 1\nx = truex\n",
        ];
        for text in cases {
            assert!(whole(text).is_none(), "{text:?}");
        }
    }

    /// Single-byte changes of a sample: wherever the fast path still reads the text, the
    /// toml crate reads it too, into the same tree.
    #[test]
    fn fast_toml_mutations_agree() {
        let m = crate::generate::random(4, false, 7).unwrap().0;
        let generated = crate::generate::to_toml(&m);
        let joints = generated.find("[[joint]]").unwrap_or(0);
        let base = format!("{SAMPLE}{}", &generated[joints..]);
        assert!(agrees(&base));
        let alphabet = b" \t\n\r#[]{}=,.\"'\\-+_0123456789eExjointrue";
        let mut read = 0;
        for text in crate::format::mutated_texts(&base, alphabet, 0x9E37_79B9_7F4A_7C15, 4000, 3) {
            if agrees(&text) {
                read += 1;
            }
        }
        assert!(read > 500, "only {read} mutated texts read");
    }
}
