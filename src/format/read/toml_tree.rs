//! TOML text into the value tree by the toml crate (which finds and locates every error): read
//! whole, in parallel pieces cut before `[[joint]]` headers, or with the joints deferred.

use super::Lazy;
use crate::format::error::LoadError;
use crate::format::tree::{Entry, MAX_DEPTH, Node, Value, syntax, too_deep};
use std::ops::Range;
use std::sync::atomic::AtomicBool;

/// The joints of a deferred TOML list ([`Lazy::Toml`]): `first`, then those of the later
/// pieces `rest`, parsed in parallel a few at a time. A piece that does not parse sets
/// `fallback` and ends the read.
pub(super) fn for_each_piece_joint<'a>(
    text: &'a str,
    first: Vec<Node<'a>>,
    rest: &[Range<usize>],
    fallback: &AtomicBool,
    f: &mut dyn FnMut(&Node<'a>) -> Result<(), LoadError>,
) -> Result<(), LoadError> {
    use rayon::prelude::*;
    let batch = 2 * rayon::current_num_threads();
    let again = || {
        fallback.store(true, std::sync::atomic::Ordering::Relaxed);
        Err(syntax("TOML", "read again", 0..0, "here"))
    };
    let mut failed = first.into_iter().try_for_each(|item| f(&item)).err();
    for pieces in rest.chunks(batch) {
        let parsed: Vec<Option<Vec<Node<'a>>>> = pieces
            .par_iter()
            .map(|r| toml_joint_piece(text, r.clone()))
            .collect();
        for items in parsed {
            // A piece that does not parse: the serial parse says why (a syntax
            // error comes before any model error, as when the tree came first).
            let Some(items) = items else {
                return again();
            };
            if failed.is_none() {
                failed = items.into_iter().try_for_each(|item| f(&item)).err();
            }
        }
    }
    failed.map_or(Ok(()), Err)
}

/// The joints of one later TOML piece, `None` unless the piece parses and holds nothing but
/// `[[joint]]` tables.
fn toml_joint_piece(text: &str, r: Range<usize>) -> Option<Vec<Node<'_>>> {
    let piece = text.get(r.clone())?;
    let table = toml::de::DeTable::parse(piece).ok()?;
    let tree = toml_table(table.get_ref(), shift(table.span(), r.start), 1, r.start).ok()?;
    let Value::Map(mut entries) = tree.value else {
        return None;
    };
    if entries.len() != 1 || entries[0].key != "joint" {
        return None;
    }
    let e = entries.pop()?;
    let header = |span: &Range<usize>| text.get(span.clone()).is_some_and(|t| t.starts_with("[["));
    let Value::Seq(items) = e.value.value else {
        return None;
    };
    (header(&e.value.span)
        && items
            .iter()
            .all(|t| matches!(t.value, Value::Map(_)) && header(&t.span)))
    .then_some(items)
}

/// Files at least this large are parsed in pieces on all cores ([`parse_toml_chunked`]).
const CHUNKED_TOML_BYTES: usize = 1 << 20;

/// Parse TOML into a tree.
pub(crate) fn parse_toml(text: &str) -> Result<Node<'_>, LoadError> {
    // Pieces of about 1 MiB: the toml parser holds tens of times its input while parsing.
    let pieces = (4 * rayon::current_num_threads()).max(text.len() / CHUNKED_TOML_BYTES);
    if text.len() >= CHUNKED_TOML_BYTES
        && let Some(root) = parse_toml_chunked(text, pieces)
    {
        return Ok(root);
    }
    parse_toml_serial(text)
}

pub(crate) fn parse_toml_serial(text: &str) -> Result<Node<'_>, LoadError> {
    let table = toml::de::DeTable::parse(text).map_err(|e| {
        let span = e.span().unwrap_or(0..0);
        let msg = e.message().trim().to_string();
        syntax("TOML", msg, span, "here")
    })?;
    let span = table.span();
    toml_table(table.get_ref(), span, 1, 0)
}

/// The header that starts every joint of a large generated or exported file.
pub(super) const JOINT_HEADER: &str = "\n[[joint]]";

/// Parse a large TOML file as about `pieces` documents cut before `[[joint]]` header lines, in
/// parallel, and join them; `None` (the caller then parses the whole text serially, which also
/// finds any error) unless the join is exactly the serial tree. Why that holds:
/// - a cut inside a multi-line string or array leaves the piece before it unterminated, so
///   that piece fails to parse: if every piece parses, every cut is a real header line;
/// - every later piece starts with `[[joint]]`, so its `joint` array holds its own joints
///   (and its `[joint.geometry]` tables belong to them): arrays of tables made by headers
///   concatenate in order (an inline `joint = [...]` is left to the serial parse);
/// - any other top-level key in two pieces (a duplicate table, or `[[body]]` arrays split
///   across pieces) is left to the serial parse;
/// - spans are shifted by each piece's offset; the joint entry's spans come from the first
///   header, as in the serial tree.
pub(super) fn parse_toml_chunked(text: &str, pieces: usize) -> Option<Node<'_>> {
    let mut cuts = toml_cuts(text, pieces);
    if cuts.len() < 2 {
        return None;
    }
    cuts.push(text.len());
    chunked_join(text, &cuts)
}

/// Parse a large TOML file for a one-joint-at-a-time read: the first piece (cut as in
/// [`parse_toml_chunked`]) as a tree whose joint list is [`Value::Deferred`], the later
/// pieces left to [`Lazy::for_each`]. `None` (read the file whole) for a small file, a
/// first piece that does not parse or has no `[[joint]]` table, or a later piece with a
/// line that starts another table (`[body]`, `[[point]]`, `[expect]`...).
pub(crate) fn parse_toml_lazy<'a>(
    text: &'a str,
    fallback: &'a AtomicBool,
) -> Option<(Node<'a>, Lazy<'a>)> {
    if text.len() < CHUNKED_TOML_BYTES {
        return None;
    }
    let mut cuts = toml_cuts(text, text.len() / CHUNKED_TOML_BYTES);
    if cuts.len() < 2 {
        return None;
    }
    cuts.push(text.len());
    // Later pieces: table headers of the joints only (a line of a multi-line string or array
    // that starts with `[` is refused too: the whole read then decides).
    let later = &text[cuts[1]..];
    let other_table = later.split('\n').any(|line| {
        let t = line.trim_start_matches([' ', '\t']);
        t.starts_with('[') && !t.starts_with("[[joint]]")
    });
    if other_table {
        return None;
    }
    let table = toml::de::DeTable::parse(&text[..cuts[1]]).ok()?;
    let mut root = toml_table(table.get_ref(), table.span(), 1, 0).ok()?;
    drop(table);
    let Value::Map(entries) = &mut root.value else {
        return None;
    };
    let joint = entries.iter_mut().find(|e| e.key == "joint")?;
    let header = |span: &Range<usize>| text.get(span.clone()).is_some_and(|t| t.starts_with("[["));
    if !header(&joint.value.span) {
        return None;
    }
    let Value::Seq(first) = std::mem::replace(&mut joint.value.value, Value::Deferred) else {
        return None;
    };
    if first.is_empty() || !first.iter().all(|t| header(&t.span)) {
        return None;
    }
    let rest = cuts[1..].windows(2).map(|w| w[0]..w[1]).collect();
    Some((
        root,
        Lazy::Toml {
            text,
            first,
            rest,
            fallback,
        },
    ))
}

/// Where to cut `text` into about `pieces` TOML documents: before `[[joint]]` header lines
/// (alone on their line) after the first one; starts with 0.
fn toml_cuts(text: &str, pieces: usize) -> Vec<usize> {
    let mut cuts = vec![0usize];
    let Some(first) = text.find(JOINT_HEADER) else {
        return cuts;
    };
    for k in 1..pieces {
        let mut from = (text.len() * k / pieces)
            .max(cuts[cuts.len() - 1])
            .max(first + 1);
        while !text.is_char_boundary(from) {
            from += 1;
        }
        let Some(at) = text.get(from..).and_then(|t| t.find(JOINT_HEADER)) else {
            break;
        };
        let cut = from + at + 1;
        // Only a header alone on its line (a comment may follow).
        let rest = text[cut + JOINT_HEADER.len() - 1..].trim_start_matches([' ', '\t']);
        if (rest.is_empty() || rest.starts_with(['\n', '\r', '#'])) && cut > cuts[cuts.len() - 1] {
            cuts.push(cut);
        }
    }
    cuts
}

/// Parse the pieces between `cuts` in parallel and join them (see [`parse_toml_chunked`]).
fn chunked_join<'a>(text: &'a str, cuts: &[usize]) -> Option<Node<'a>> {
    use rayon::prelude::*;
    let trees: Vec<Option<Node<'_>>> = cuts
        .par_windows(2)
        .map(|w| {
            let table = toml::de::DeTable::parse(&text[w[0]..w[1]]).ok()?;
            toml_table(table.get_ref(), shift(table.span(), w[0]), 1, w[0]).ok()
        })
        .collect();
    let mut span = None;
    let mut top: Vec<Entry<'_>> = Vec::new();
    let mut joint: Option<Entry<'_>> = None;
    for tree in trees {
        let tree = tree?;
        span.get_or_insert(tree.span);
        let Value::Map(entries) = tree.value else {
            return None;
        };
        for e in entries {
            if e.key == "joint" {
                // Only arrays of tables made by headers join (not `joint = [...]`).
                let Value::Seq(items) = e.value.value else {
                    return None;
                };
                let header = |span: &Range<usize>| {
                    text.get(span.clone()).is_some_and(|t| t.starts_with("[["))
                };
                if !header(&e.value.span)
                    || !items
                        .iter()
                        .all(|t| matches!(t.value, Value::Map(_)) && header(&t.span))
                {
                    return None;
                }
                match &mut joint {
                    None => {
                        joint = Some(Entry {
                            value: Node {
                                span: e.value.span,
                                value: Value::Seq(items),
                            },
                            ..e
                        })
                    }
                    Some(Entry {
                        value:
                            Node {
                                value: Value::Seq(all),
                                ..
                            },
                        ..
                    }) => all.extend(items),
                    Some(_) => return None,
                }
            } else if top.iter().any(|t| t.key == e.key) {
                return None;
            } else {
                top.push(e);
            }
        }
    }
    top.extend(joint);
    top.sort_by_key(|e| e.key_span.start);
    Some(Node {
        span: span?,
        value: Value::Map(top),
    })
}

fn shift(span: Range<usize>, off: usize) -> Range<usize> {
    span.start + off..span.end + off
}

fn toml_table<'a>(
    table: &toml::de::DeTable<'a>,
    span: Range<usize>,
    depth: usize,
    off: usize,
) -> Result<Node<'a>, LoadError> {
    if depth > MAX_DEPTH {
        return Err(too_deep(span));
    }
    let mut entries = Vec::with_capacity(table.len());
    for (k, v) in table.iter() {
        entries.push(Entry {
            key: k.get_ref().clone(),
            key_span: shift(k.span(), off),
            value: toml_value(v.get_ref(), shift(v.span(), off), depth + 1, off)?,
        });
    }
    // The toml map is sorted by key; the source order reads better in error sequences.
    entries.sort_by_key(|e| e.key_span.start);
    Ok(Node {
        span,
        value: Value::Map(entries),
    })
}

fn toml_value<'a>(
    v: &toml::de::DeValue<'a>,
    span: Range<usize>,
    depth: usize,
    off: usize,
) -> Result<Node<'a>, LoadError> {
    use toml::de::DeValue;
    if depth > MAX_DEPTH {
        return Err(too_deep(span));
    }
    let value = match v {
        DeValue::String(s) => Value::Str(s.clone()),
        DeValue::Integer(i) => match i64::from_str_radix(i.as_str(), i.radix()) {
            Ok(n) => Value::Int(n),
            Err(_) => Value::BigInt(i.to_string()),
        },
        DeValue::Float(f) => Value::Float(parse_float_lenient(f.as_str())),
        DeValue::Boolean(b) => Value::Bool(*b),
        DeValue::Datetime(_) => Value::DateTime,
        DeValue::Array(a) => {
            let mut items = Vec::with_capacity(a.len());
            for item in a.iter() {
                items.push(toml_value(
                    item.get_ref(),
                    shift(item.span(), off),
                    depth + 1,
                    off,
                )?);
            }
            Value::Seq(items)
        }
        DeValue::Table(t) => return toml_table(t, span, depth, off),
    };
    Ok(Node { span, value })
}

/// A TOML float literal (already validated by the parser) as f64; `nan`/`inf` with signs.
fn parse_float_lenient(s: &str) -> f64 {
    let t = s.replace('_', "");
    if let Ok(f) = t.parse::<f64>() {
        return f;
    }
    if t.contains("nan") {
        f64::NAN
    } else if t.starts_with('-') {
        f64::NEG_INFINITY
    } else {
        f64::INFINITY
    }
}
