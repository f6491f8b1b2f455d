//! One spanned value tree for the three input formats, so that the model conversion can point
//! every error at the exact key or value.

use super::error::{ErrorKind, Label, LoadError, floor_boundary, offset_of};
use std::borrow::Cow;
use std::ops::Range;

/// Deepest nesting accepted (the format itself needs 4 levels).
pub(crate) const MAX_DEPTH: usize = 64;

/// A value with the byte span it was read from.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Node<'a> {
    pub span: Range<usize>,
    pub value: Value<'a>,
}

/// A key with its span and value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Entry<'a> {
    pub key: Cow<'a, str>,
    pub key_span: Range<usize>,
    pub value: Node<'a>,
}

/// The values of the three formats, unified.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value<'a> {
    /// Table / mapping / object, in source order.
    Map(Vec<Entry<'a>>),
    /// Array / sequence.
    Seq(Vec<Node<'a>>),
    /// Borrowed from the text unless it had escapes.
    Str(Cow<'a, str>),
    Int(i64),
    /// An integer that does not fit in 64 bits, as written.
    BigInt(String),
    Float(f64),
    Bool(bool),
    Null,
    /// A TOML date-time (never valid in this format).
    DateTime,
    /// A non-empty joint list whose items are parsed one at a time by [`Lazy::for_each`].
    Deferred,
}

impl Value<'_> {
    /// The type name used in messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            Value::Map(_) => "a table",
            Value::Seq(_) | Value::Deferred => "an array",
            Value::Str(_) => "a string",
            Value::Int(_) | Value::BigInt(_) => "an integer",
            Value::Float(_) => "a float",
            Value::Bool(_) => "a boolean",
            Value::Null => "null",
            Value::DateTime => "a date-time",
        }
    }
}

fn syntax(what: &str, message: impl Into<String>, at: Range<usize>, label: &str) -> LoadError {
    LoadError::new(
        ErrorKind::Syntax,
        format!("malformed {what}: {}", message.into()),
        vec![Label {
            span: at,
            text: label.to_string(),
        }],
        None,
    )
}

fn too_deep(at: Range<usize>) -> LoadError {
    LoadError::new(
        ErrorKind::TooDeep,
        format!("values nested deeper than {MAX_DEPTH} levels"),
        vec![Label {
            span: at,
            text: "too deep here".into(),
        }],
        Some(
            "a mechanism file needs at most 4 levels (top level, joint list, joint, array)".into(),
        ),
    )
}

/// Keys whose list is read one item at a time (the largest list of a file, by far).
pub(crate) fn is_joint_list(key: &str) -> bool {
    key == "joint" || key == "joints"
}

/// Where the items of a [`Value::Deferred`] list come from.
pub(crate) enum Lazy<'a> {
    /// Nothing deferred.
    None,
    /// JSON: the list's text (from `[` to `]`), parsed item by item.
    Json {
        text: &'a str,
        span: Range<usize>,
        /// The objects directly in the list, counted while it was skipped.
        items: usize,
    },
    /// JSON whose joint list is the last top-level key ([`parse_json_resume`]): the items
    /// read from `pos` (just past the list's `[`), then the end of the text checked.
    JsonResume {
        text: &'a str,
        pos: usize,
        /// At least the objects in the list (every `{` from it on).
        items: usize,
    },
    /// TOML: the joints of the first piece, then later pieces of the text (each starts with a
    /// `[[joint]]` header and holds only joints), parsed in parallel a few at a time. A piece
    /// that holds anything else, or fails to parse, sets `fallback`: the caller then reads the
    /// whole text again without deferring.
    Toml {
        text: &'a str,
        first: Vec<Node<'a>>,
        rest: Vec<Range<usize>>,
        fallback: &'a std::sync::atomic::AtomicBool,
    },
    /// YAML: the text is read a second time, the items of the top-level joint list built
    /// one at a time (the first read built the rest, skipping them).
    Yaml { text: &'a str },
    /// YAML whose joint list is the last top-level key: the reader that stopped at the list
    /// reads on, item by item ([`parse_yaml_resume`]); anything after the list is an error
    /// (the caller then reads the text again).
    YamlResume(Box<YamlReader<'a>>),
    /// YAML whose joint list is the last top-level key, its items read by
    /// [`super::fast_yaml`] (a shape it does not read is an error: the caller then reads the
    /// text with saphyr).
    YamlLines {
        text: &'a str,
        items: super::fast_yaml::Items<'a>,
    },
    /// TOML read by [`super::fast_toml`]: its `[[joint]]` tables, read one at a time. A table
    /// it does not read is an error (the caller then reads the text with the toml crate).
    TomlLines {
        text: &'a str,
        joints: super::fast_toml::JointTables,
    },
}

impl<'a> Lazy<'a> {
    /// About how many items `list` holds (to size the joint vector once: growing a vector of
    /// a million joints by doubling holds both copies at once). Counted, not parsed: the
    /// `[[joint]]` headers of a TOML file, the `"bodies"` keys of a JSON list; bounded by the
    /// text's length, so a wrong guess costs little.
    pub(crate) fn len_hint(&self, list: &Value<'a>) -> usize {
        match (list, self) {
            (Value::Seq(items), _) => items.len(),
            (Value::Deferred, Lazy::Json { items, .. } | Lazy::JsonResume { items, .. }) => *items,
            (Value::Deferred, Lazy::TomlLines { joints, .. }) => joints.count,
            (Value::Deferred, Lazy::Yaml { text }) => text.matches("bodies").count(),
            (Value::Deferred, Lazy::YamlResume(r)) => r.index.text.matches("bodies").count(),
            (Value::Deferred, Lazy::YamlLines { text, .. }) => text.matches("bodies").count(),
            // Every header but one at the very start follows a line break.
            (Value::Deferred, Lazy::Toml { text, .. }) => text.matches(JOINT_HEADER).count() + 1,
            _ => 0,
        }
    }

    /// Whether an error of the model read from this source is thrown away: the fast readers'
    /// (the caller then reads the text again by a reader that reports every error, located).
    /// What only locates an error need not be kept then.
    pub(crate) fn errors_discarded(&self) -> bool {
        matches!(
            self,
            Lazy::TomlLines { .. }
                | Lazy::YamlLines { .. }
                | Lazy::YamlResume(_)
                | Lazy::JsonResume { .. }
        )
    }

    /// Call `f` on every item of `list` (a `Seq`, or the `Deferred` list), in order, each item
    /// dropped (or its memory reused) after its call; stops at the first error.
    pub(crate) fn for_each(
        self,
        list: Value<'a>,
        f: &mut dyn FnMut(&Node<'a>) -> Result<(), LoadError>,
    ) -> Result<(), LoadError> {
        match (list, self) {
            (Value::Seq(items), _) => items.into_iter().try_for_each(|item| f(&item)),
            (Value::Deferred, Lazy::Json { text, span, .. }) => {
                let mut p = JsonParser {
                    text,
                    bytes: text.as_bytes(),
                    pos: span.start + 1,
                    deferred: None,
                    resume: false,
                    stopped: false,
                };
                let mut failed = None;
                loop {
                    p.ws();
                    // The list's items are at depth 3 (top level 1, the list 2).
                    let item = p.value(3)?;
                    // After a model error, only the tree's own errors (found first when the
                    // whole tree was built before the model) can still take its place.
                    if failed.is_none()
                        && let Err(e) = f(&item)
                    {
                        failed = Some(e);
                    }
                    if p.list_end(b']')? {
                        return failed.map_or(Ok(()), Err);
                    }
                }
            }
            (Value::Deferred, Lazy::JsonResume { text, pos, .. }) => {
                let mut p = JsonParser {
                    text,
                    bytes: text.as_bytes(),
                    pos,
                    deferred: None,
                    resume: false,
                    stopped: false,
                };
                loop {
                    p.ws();
                    f(&p.value(3)?)?;
                    if p.list_end(b']')? {
                        break;
                    }
                }
                // The list was the last key: the object and the text end here.
                p.ws();
                p.eat(b'}')?;
                p.ws();
                if p.pos != p.bytes.len() {
                    return Err(p.error("read again"));
                }
                Ok(())
            }
            (
                Value::Deferred,
                Lazy::Toml {
                    text,
                    first,
                    rest,
                    fallback,
                },
            ) => {
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
            (Value::Deferred, Lazy::TomlLines { text, joints }) => {
                use super::fast_toml::{Stopped, for_each_table};
                for_each_table(text, joints, f).map_err(|stopped| match stopped {
                    Stopped::Failed(e) => e,
                    Stopped::Declined => syntax("TOML", "read again", 0..0, "here"),
                })
            }
            (Value::Deferred, Lazy::Yaml { text }) => yaml_joint_items(text, f),
            (Value::Deferred, Lazy::YamlLines { mut items, .. }) => loop {
                match items.next_item() {
                    Some(Some(item)) => f(&item)?,
                    Some(None) => return Ok(()),
                    None => return Err(syntax("YAML", "read again", 0..0, "here")),
                }
            },
            (Value::Deferred, Lazy::YamlResume(mut r)) => {
                use saphyr_parser::Event;
                loop {
                    let next = r.next()?;
                    if let Event::SequenceEnd = next.0 {
                        break;
                    }
                    f(&r.node(next, 3)?)?;
                }
                // Nothing after the list: the mapping, the document and the stream end.
                if !matches!(r.next()?.0, Event::MappingEnd) {
                    return Err(syntax("YAML", "read again", 0..0, "here"));
                }
                loop {
                    match r.next()?.0 {
                        Event::DocumentEnd | Event::Nothing => {}
                        Event::StreamEnd => return Ok(()),
                        _ => return Err(syntax("YAML", "read again", 0..0, "here")),
                    }
                }
            }
            (Value::Deferred, Lazy::None) => Ok(()),
            (_, _) => Ok(()),
        }
    }
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

fn duplicate_key(key: &str, first: Range<usize>, again: Range<usize>) -> LoadError {
    LoadError::new(
        ErrorKind::DuplicateKey,
        format!("duplicate key `{key}`"),
        vec![
            Label {
                span: again,
                text: "given again here".into(),
            },
            Label {
                span: first,
                text: "first given here".into(),
            },
        ],
        Some("each key may appear once per table; remove one of them".into()),
    )
}

/// Push an entry, rejecting duplicate keys (YAML and JSON parsers allow them; TOML does not).
/// Maps up to this many keys are checked for duplicates by a scan; larger ones by a hash index.
const SCAN_KEYS: usize = 8;

/// Add `entry` to a map, refusing a key already present. Linear over the whole map: a scan
/// while the map is small, then a hash index of the keys (`index`, built once the map grows
/// past [`SCAN_KEYS`]; a 300,000-key object was quadratic before).
fn push_entry<'a>(
    entries: &mut Vec<Entry<'a>>,
    index: &mut Option<std::collections::HashMap<Cow<'a, str>, usize>>,
    entry: Entry<'a>,
) -> Result<(), LoadError> {
    let prev = match index {
        Some(ix) => ix.get(&entry.key).copied(),
        None => entries.iter().position(|e| e.key == entry.key),
    };
    if let Some(prev) = prev {
        return Err(duplicate_key(
            &entry.key,
            entries[prev].key_span.clone(),
            entry.key_span.clone(),
        ));
    }
    match index {
        Some(ix) => {
            ix.insert(entry.key.clone(), entries.len());
        }
        None if entries.len() >= SCAN_KEYS => {
            let mut ix: std::collections::HashMap<Cow<'a, str>, usize> = entries
                .iter()
                .enumerate()
                .map(|(i, e)| (e.key.clone(), i))
                .collect();
            ix.insert(entry.key.clone(), entries.len());
            *index = Some(ix);
        }
        None => {}
    }
    entries.push(entry);
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// TOML

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
const JOINT_HEADER: &str = "\n[[joint]]";

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
fn parse_toml_chunked(text: &str, pieces: usize) -> Option<Node<'_>> {
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
    fallback: &'a std::sync::atomic::AtomicBool,
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

// ---------------------------------------------------------------------------------------------
// YAML

/// Maps saphyr's character indices to byte offsets (checkpoints every 64 chars).
struct CharIndex<'a> {
    text: &'a str,
    ascii: bool,
    checkpoints: Vec<usize>,
}

impl<'a> CharIndex<'a> {
    fn new(text: &'a str) -> CharIndex<'a> {
        let ascii = text.is_ascii();
        let checkpoints = if ascii {
            Vec::new()
        } else {
            text.char_indices().step_by(64).map(|(b, _)| b).collect()
        };
        CharIndex {
            text,
            ascii,
            checkpoints,
        }
    }

    fn byte(&self, char_index: usize) -> usize {
        if self.ascii {
            return char_index.min(self.text.len());
        }
        let Some(&start) = self.checkpoints.get(char_index / 64) else {
            return self.text.len();
        };
        self.text[start..]
            .char_indices()
            .nth(char_index % 64)
            .map_or(self.text.len(), |(b, _)| start + b)
    }

    fn span(&self, s: &saphyr_parser::Span) -> Range<usize> {
        let a = self.byte(s.start.index());
        let b = self.byte(s.end.index()).max(a);
        a..b
    }
}

pub(crate) struct YamlReader<'a> {
    parser: saphyr_parser::Parser<'a, saphyr_parser::StrInput<'a>>,
    index: CharIndex<'a>,
    /// Skip the first top-level joint list that is a sequence ([`parse_yaml_lazy`]).
    defer: bool,
}

type YamlEvent<'a> = (saphyr_parser::Event<'a>, Range<usize>);

impl<'a> YamlReader<'a> {
    fn next(&mut self) -> Result<YamlEvent<'a>, LoadError> {
        match self.parser.next_event() {
            Some(Ok((ev, span))) => Ok((ev, self.index.span(&span))),
            Some(Err(e)) => {
                let at = self.index.byte(e.marker().index());
                Err(syntax("YAML", e.info(), at..at, "here"))
            }
            None => {
                let end = self.index.text.len();
                Err(syntax("YAML", "unexpected end of input", end..end, "here"))
            }
        }
    }

    /// Consume the events of the node that starts with `ev`, building nothing.
    fn skip(&mut self, ev: YamlEvent<'a>) -> Result<(), LoadError> {
        use saphyr_parser::Event;
        let mut open = match ev.0 {
            Event::SequenceStart(..) | Event::MappingStart(..) => 1usize,
            _ => return Ok(()),
        };
        while open > 0 {
            match self.next()?.0 {
                Event::SequenceStart(..) | Event::MappingStart(..) => open += 1,
                Event::SequenceEnd | Event::MappingEnd => open -= 1,
                _ => {}
            }
        }
        Ok(())
    }

    fn node(&mut self, ev: YamlEvent<'a>, depth: usize) -> Result<Node<'a>, LoadError> {
        use saphyr_parser::{Event, ScalarStyle};
        let (ev, span) = ev;
        if depth > MAX_DEPTH {
            return Err(too_deep(span));
        }
        match ev {
            Event::Scalar(text, style, _anchor, tag) => {
                let value = match (&tag, style) {
                    (Some(t), _) if t.handle == "tag:yaml.org,2002:" || t.handle == "!!" => {
                        match t.suffix.as_str() {
                            "str" => Value::Str(text),
                            "int" | "float" | "bool" | "null" => resolve_plain(text),
                            _ => return Err(unsupported_tag(t, span)),
                        }
                    }
                    (Some(t), _) => return Err(unsupported_tag(t, span)),
                    (None, ScalarStyle::Plain) => resolve_plain(text),
                    (None, _) => Value::Str(text),
                };
                Ok(Node { span, value })
            }
            Event::SequenceStart(_, tag) => {
                if let Some(t) = tag
                    && t.suffix != "seq"
                {
                    return Err(unsupported_tag(&t, span));
                }
                let mut items = Vec::new();
                loop {
                    let next = self.next()?;
                    if let Event::SequenceEnd = next.0 {
                        let end = next.1.end.max(span.start);
                        return Ok(Node {
                            span: span.start..end,
                            value: Value::Seq(items),
                        });
                    }
                    items.push(self.node(next, depth + 1)?);
                }
            }
            Event::MappingStart(_, tag) => {
                if let Some(t) = tag
                    && t.suffix != "map"
                {
                    return Err(unsupported_tag(&t, span));
                }
                let mut entries = Vec::new();
                let mut index = None;
                loop {
                    let next = self.next()?;
                    let key_span = next.1.clone();
                    let key = match next.0 {
                        Event::MappingEnd => {
                            let end = next.1.end.max(span.start);
                            return Ok(Node {
                                span: span.start..end,
                                value: Value::Map(entries),
                            });
                        }
                        Event::Scalar(k, ..) => k,
                        Event::Alias(_) => return Err(alias(key_span)),
                        _ => {
                            return Err(LoadError::new(
                                ErrorKind::Unsupported,
                                "a mapping or sequence used as a key",
                                vec![Label {
                                    span: key_span,
                                    text: "complex key".into(),
                                }],
                                Some("keys are plain names like `frame` or `bodies`".into()),
                            ));
                        }
                    };
                    let value_ev = self.next()?;
                    let value = if depth == 1
                        && self.defer
                        && is_joint_list(&key)
                        && let Event::SequenceStart(..) = value_ev.0
                    {
                        // Skipped (read again item by item: `Lazy::Yaml`); its span is the
                        // start of the list (its items' spans locate everything after).
                        self.defer = false;
                        let at = value_ev.1.clone();
                        self.skip(value_ev)?;
                        Node {
                            span: at,
                            value: Value::Deferred,
                        }
                    } else {
                        self.node(value_ev, depth + 1)?
                    };
                    push_entry(
                        &mut entries,
                        &mut index,
                        Entry {
                            key,
                            key_span,
                            value,
                        },
                    )?;
                }
            }
            Event::Alias(_) => Err(alias(span)),
            _ => Err(syntax("YAML", "unexpected event", span, "here")),
        }
    }
}

fn alias(span: Range<usize>) -> LoadError {
    LoadError::new(
        ErrorKind::Unsupported,
        "YAML aliases (`*name`) are not supported",
        vec![Label {
            span,
            text: "alias".into(),
        }],
        Some("write the value out in full".into()),
    )
}

fn unsupported_tag(t: &saphyr_parser::Tag, span: Range<usize>) -> LoadError {
    LoadError::new(
        ErrorKind::Unsupported,
        format!("unsupported YAML tag `{}{}`", t.handle, t.suffix),
        vec![Label {
            span,
            text: "tagged value".into(),
        }],
        Some("remove the tag; only the core tags (!!str, !!int, ...) are accepted".into()),
    )
}

/// Resolve a plain YAML scalar by the YAML 1.2 core schema.
fn resolve_plain(text: Cow<'_, str>) -> Value<'_> {
    match resolve_plain_str(&text) {
        Some(v) => v,
        None => Value::Str(text),
    }
}

/// [`resolve_plain`] for the non-string values (`None`: a string).
pub(crate) fn resolve_plain_str(s: &str) -> Option<Value<'static>> {
    match s {
        "" | "~" | "null" | "Null" | "NULL" => return Some(Value::Null),
        "true" | "True" | "TRUE" => return Some(Value::Bool(true)),
        "false" | "False" | "FALSE" => return Some(Value::Bool(false)),
        ".nan" | ".NaN" | ".NAN" => return Some(Value::Float(f64::NAN)),
        _ => {}
    }
    let (sign, body) = match s.as_bytes()[0] {
        b'-' => (-1.0, &s[1..]),
        b'+' => (1.0, &s[1..]),
        _ => (1.0, s),
    };
    if matches!(body, ".inf" | ".Inf" | ".INF") {
        return Some(Value::Float(sign * f64::INFINITY));
    }
    let digits = |t: &str, radix: u32| !t.is_empty() && t.chars().all(|c| c.is_digit(radix));
    if let Some(h) = s.strip_prefix("0x")
        && digits(h, 16)
    {
        return Some(int_or_big(i64::from_str_radix(h, 16).ok(), s));
    }
    if let Some(o) = s.strip_prefix("0o")
        && digits(o, 8)
    {
        return Some(int_or_big(i64::from_str_radix(o, 8).ok(), s));
    }
    if digits(body, 10) {
        return Some(int_or_big(s.parse::<i64>().ok(), s));
    }
    if is_yaml_float(body)
        && let Ok(f) = s.parse::<f64>()
    {
        return Some(Value::Float(f));
    }
    None
}

fn int_or_big(n: Option<i64>, s: &str) -> Value<'static> {
    n.map_or_else(|| Value::BigInt(s.to_string()), Value::Int)
}

/// `(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?` (sign already stripped).
fn is_yaml_float(t: &str) -> bool {
    let (mantissa, exp) = match t.find(['e', 'E']) {
        Some(i) => (&t[..i], Some(&t[i + 1..])),
        None => (t, None),
    };
    let ok_mantissa = match mantissa.split_once('.') {
        Some((a, b)) => {
            a.chars().all(|c| c.is_ascii_digit())
                && b.chars().all(|c| c.is_ascii_digit())
                && (!a.is_empty() || !b.is_empty())
        }
        None => !mantissa.is_empty() && mantissa.chars().all(|c| c.is_ascii_digit()),
    };
    let ok_exp = exp.is_none_or(|e| {
        let e = e.strip_prefix(['-', '+']).unwrap_or(e);
        !e.is_empty() && e.chars().all(|c| c.is_ascii_digit())
    });
    ok_mantissa && ok_exp
}

/// Parse YAML (one document) into a tree; `None` for a stream without a document.
pub(crate) fn parse_yaml(text: &str) -> Result<Option<Node<'_>>, LoadError> {
    parse_yaml_with(text, false)
}

/// [`parse_yaml`] with the top-level joint list (if a sequence) left [`Value::Deferred`], its
/// items read by [`Lazy::Yaml`]. The caller reads the text again with [`parse_yaml`] after any
/// error: the order in which errors are found differs.
pub(crate) fn parse_yaml_lazy(text: &str) -> Result<Option<Node<'_>>, LoadError> {
    parse_yaml_with(text, true)
}

/// One read of YAML whose top-level joint list (a sequence) comes last: the top-level entries
/// before it and the list [`Value::Deferred`], with the reader stopped at the list's first
/// item. `None` at anything else (no such list, a document that is not a mapping, an error).
pub(crate) fn parse_yaml_resume(text: &str) -> Option<(Node<'_>, Lazy<'_>)> {
    use saphyr_parser::Event;
    let mut r = YamlReader {
        parser: saphyr_parser::Parser::new_from_str(text),
        index: CharIndex::new(text),
        defer: false,
    };
    let start = loop {
        let (ev, span) = r.next().ok()?;
        match ev {
            Event::StreamStart | Event::DocumentStart(_) | Event::Nothing => {}
            Event::MappingStart(_, None) => break span,
            _ => return None,
        }
    };
    let mut entries = Vec::new();
    let mut index = None;
    loop {
        let (ev, key_span) = r.next().ok()?;
        let Event::Scalar(key, ..) = ev else {
            return None;
        };
        let value_ev = r.next().ok()?;
        if is_joint_list(&key) && matches!(value_ev.0, Event::SequenceStart(_, None)) {
            let value = Node {
                span: value_ev.1,
                value: Value::Deferred,
            };
            push_entry(
                &mut entries,
                &mut index,
                Entry {
                    key,
                    key_span,
                    value,
                },
            )
            .ok()?;
            let root = Node {
                span: start.start..start.start,
                value: Value::Map(entries),
            };
            return Some((root, Lazy::YamlResume(Box::new(r))));
        }
        let value = r.node(value_ev, 2).ok()?;
        push_entry(
            &mut entries,
            &mut index,
            Entry {
                key,
                key_span,
                value,
            },
        )
        .ok()?;
    }
}

/// [`parse_yaml_resume`] with the joint list's items read by [`super::fast_yaml`]
/// ([`Lazy::YamlLines`]); `None` where that one gives `None` or the list is not a block
/// sequence starting on a line of its own.
pub(crate) fn parse_yaml_fast(text: &str) -> Option<(Node<'_>, Lazy<'_>)> {
    let (root, _) = parse_yaml_resume(text)?;
    let Value::Map(es) = &root.value else {
        return None;
    };
    let list = es
        .iter()
        .find(|e| matches!(e.value.value, Value::Deferred))?;
    let items = super::fast_yaml::Items::new(text, list.value.span.start)?;
    Some((root, Lazy::YamlLines { text, items }))
}

/// The second read of [`Lazy::Yaml`]: `f` on each item of the top-level joint list.
fn yaml_joint_items<'a>(
    text: &'a str,
    f: &mut dyn FnMut(&Node<'a>) -> Result<(), LoadError>,
) -> Result<(), LoadError> {
    use saphyr_parser::Event;
    let mut r = YamlReader {
        parser: saphyr_parser::Parser::new_from_str(text),
        index: CharIndex::new(text),
        defer: false,
    };
    let lost = || syntax("YAML", "read again", 0..0, "here");
    // Down to the top-level mapping.
    loop {
        match r.next()?.0 {
            Event::MappingStart(..) => break,
            Event::StreamStart | Event::DocumentStart(_) | Event::Nothing => {}
            _ => return Err(lost()),
        }
    }
    loop {
        let key = match r.next()?.0 {
            Event::Scalar(k, ..) => k,
            _ => return Err(lost()),
        };
        let value = r.next()?;
        if is_joint_list(&key) && matches!(value.0, Event::SequenceStart(..)) {
            loop {
                let next = r.next()?;
                if let Event::SequenceEnd = next.0 {
                    return Ok(());
                }
                f(&r.node(next, 3)?)?;
            }
        }
        r.skip(value)?;
    }
}

fn parse_yaml_with(text: &str, defer: bool) -> Result<Option<Node<'_>>, LoadError> {
    use saphyr_parser::Event;
    let mut r = YamlReader {
        parser: saphyr_parser::Parser::new_from_str(text),
        index: CharIndex::new(text),
        defer,
    };
    let mut root = None;
    loop {
        let (ev, span) = r.next()?;
        match ev {
            Event::StreamStart | Event::DocumentEnd | Event::Nothing => {}
            Event::StreamEnd => return Ok(root),
            Event::DocumentStart(_) => {
                if root.is_some() {
                    return Err(LoadError::new(
                        ErrorKind::Unsupported,
                        "several YAML documents in one file",
                        vec![Label {
                            span,
                            text: "second document starts here".into(),
                        }],
                        Some("put one mechanism per file".into()),
                    ));
                }
                let first = r.next()?;
                root = Some(r.node(first, 1)?);
            }
            _ => return Err(syntax("YAML", "unexpected event", span, "here")),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// JSON

/// Parse JSON into a tree: syntax checked by serde_json (good messages), tree built by a small
/// spanned parser.
#[cfg(test)]
pub(crate) fn parse_json(text: &str) -> Result<(Node<'_>, Lazy<'_>), LoadError> {
    json_check(text)?;
    parse_json_tree(text)
}

/// serde_json's syntax check of the whole text (its messages are better than the tree
/// parser's). The tree parser ([`parse_json_tree`]) refuses everything serde_json refuses, so
/// the reader runs this check only after an error, to report serde_json's first.
pub(crate) fn json_check(text: &str) -> Result<(), LoadError> {
    if let Err(e) = serde_json::from_str::<serde::de::IgnoredAny>(text) {
        let at = offset_of(text, e.line(), e.column());
        let msg = e.to_string();
        // serde_json appends " at line L column C": the rendered location says it already.
        let msg = msg
            .rfind(" at line ")
            .map_or(msg.as_str(), |i| &msg[..i])
            .to_string();
        return Err(syntax("JSON", msg, at..at, "here"));
    }
    Ok(())
}

/// The spanned tree of JSON text (its syntax errors are less precise than serde_json's).
pub(crate) fn parse_json_tree(text: &str) -> Result<(Node<'_>, Lazy<'_>), LoadError> {
    let mut p = JsonParser {
        text,
        bytes: text.as_bytes(),
        pos: 0,
        deferred: None,
        resume: false,
        stopped: false,
    };
    p.ws();
    let node = p.value(1)?;
    p.ws();
    if p.pos != p.bytes.len() {
        return Err(p.error("trailing characters"));
    }
    let lazy = match p.deferred {
        Some((span, items)) => Lazy::Json { text, span, items },
        None => Lazy::None,
    };
    Ok((node, lazy))
}

/// JSON whose joint list is the last top-level key (the common case): the text before the
/// list as a tree, and the list's items read one at a time after it ([`Lazy::JsonResume`]), in
/// one pass (no skip over the list first). `None` when there is no non-empty joint list at
/// the top level; anything after the list, or any error, is an error of the items' read (the
/// caller then reads the text again with [`parse_json_tree`], which finds and locates it).
pub(crate) fn parse_json_resume(text: &str) -> Option<(Node<'_>, Lazy<'_>)> {
    let mut p = JsonParser {
        text,
        bytes: text.as_bytes(),
        pos: 0,
        deferred: None,
        resume: true,
        stopped: false,
    };
    p.ws();
    let node = p.value(1).ok()?;
    if !p.stopped {
        return None;
    }
    // Objects from the list on: the joint vector's size (nested objects only add to it).
    let rest = &p.bytes[p.pos..];
    let items = rest.iter().filter(|&&b| b == b'{').count();
    Some((
        node,
        Lazy::JsonResume {
            text,
            pos: p.pos,
            items,
        },
    ))
}

struct JsonParser<'a> {
    text: &'a str,
    bytes: &'a [u8],
    pos: usize,
    /// The top-level joint list, skipped (see [`Lazy::Json`]), and its objects.
    deferred: Option<(Range<usize>, usize)>,
    /// Stop at the top-level joint list instead of skipping it ([`parse_json_resume`]);
    /// `stopped` once it did.
    resume: bool,
    stopped: bool,
}

impl<'a> JsonParser<'a> {
    /// After an element of an object or array: consume `,` (more follow: `false`) or the
    /// closing bracket (`true`).
    fn list_end(&mut self, close: u8) -> Result<bool, LoadError> {
        self.ws();
        match self.bytes.get(self.pos) {
            Some(b',') => {
                self.pos += 1;
                Ok(false)
            }
            Some(&c) if c == close => {
                self.pos += 1;
                Ok(true)
            }
            _ => Err(self.error(if close == b'}' {
                "expected `,` or `}`"
            } else {
                "expected `,` or `]`"
            })),
        }
    }

    fn error(&self, msg: &str) -> LoadError {
        let at = floor_boundary(self.text, self.pos.min(self.text.len()));
        syntax("JSON", msg, at..at, "here")
    }

    /// Whitespace; runs of spaces (indentation) eight bytes at a time.
    fn ws(&mut self) {
        loop {
            match self.bytes.get(self.pos) {
                Some(b' ') => match word(self.bytes, self.pos) {
                    Some(w) => {
                        let other = nonzero_bytes(w ^ splat(b' '));
                        if other == 0 {
                            self.pos += 8;
                        } else {
                            self.pos += (other.trailing_zeros() / 8) as usize;
                        }
                    }
                    None => self.pos += 1,
                },
                Some(b'\t' | b'\n' | b'\r') => self.pos += 1,
                _ => return,
            }
        }
    }

    /// At a non-empty array (`[` and, past whitespace, anything but `]`)?
    fn list_ahead(&self) -> bool {
        if self.bytes.get(self.pos) != Some(&b'[') {
            return false;
        }
        let mut i = self.pos + 1;
        while self
            .bytes
            .get(i)
            .is_some_and(|b| matches!(b, b' ' | b'\t' | b'\n' | b'\r'))
        {
            i += 1;
        }
        !matches!(self.bytes.get(i), None | Some(b']'))
    }

    fn eat(&mut self, b: u8) -> Result<(), LoadError> {
        if self.bytes.get(self.pos) == Some(&b) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.error(&format!("expected `{}`", b as char)))
        }
    }

    fn value(&mut self, depth: usize) -> Result<Node<'a>, LoadError> {
        let start = self.pos;
        if depth > MAX_DEPTH {
            return Err(too_deep(start..start + 1));
        }
        let value = match self.bytes.get(self.pos) {
            Some(b'{') => {
                self.pos += 1;
                let mut entries = Vec::new();
                let mut index = None;
                self.ws();
                if self.bytes.get(self.pos) == Some(&b'}') {
                    self.pos += 1;
                } else {
                    loop {
                        self.ws();
                        let key_start = self.pos;
                        let key = self.string()?;
                        let key_span = key_start..self.pos;
                        self.ws();
                        self.eat(b':')?;
                        self.ws();
                        if self.resume && depth == 1 && is_joint_list(&key) && self.list_ahead() {
                            // The items are read by `Lazy::JsonResume`, from after the `[`.
                            let at = self.pos;
                            self.pos += 1;
                            self.stopped = true;
                            push_entry(
                                &mut entries,
                                &mut index,
                                Entry {
                                    key,
                                    key_span,
                                    value: Node {
                                        span: at..self.bytes.len(),
                                        value: Value::Deferred,
                                    },
                                },
                            )?;
                            return Ok(Node {
                                span: start..self.bytes.len(),
                                value: Value::Map(entries),
                            });
                        }
                        let value = if depth == 1
                            && self.deferred.is_none()
                            && is_joint_list(&key)
                            && let Some((span, items)) = self.skip_list()?
                        {
                            self.deferred = Some((span.clone(), items));
                            Node {
                                span,
                                value: Value::Deferred,
                            }
                        } else {
                            self.value(depth + 1)?
                        };
                        push_entry(
                            &mut entries,
                            &mut index,
                            Entry {
                                key,
                                key_span,
                                value,
                            },
                        )?;
                        if self.list_end(b'}')? {
                            break;
                        }
                    }
                }
                Value::Map(entries)
            }
            Some(b'[') => {
                self.pos += 1;
                let mut items = Vec::new();
                self.ws();
                if self.bytes.get(self.pos) == Some(&b']') {
                    self.pos += 1;
                } else {
                    loop {
                        self.ws();
                        items.push(self.value(depth + 1)?);
                        if self.list_end(b']')? {
                            break;
                        }
                    }
                }
                Value::Seq(items)
            }
            Some(b'"') => Value::Str(self.string()?),
            Some(b't') if self.bytes[self.pos..].starts_with(b"true") => {
                self.pos += 4;
                Value::Bool(true)
            }
            Some(b'f') if self.bytes[self.pos..].starts_with(b"false") => {
                self.pos += 5;
                Value::Bool(false)
            }
            Some(b'n') if self.bytes[self.pos..].starts_with(b"null") => {
                self.pos += 4;
                Value::Null
            }
            Some(b'-' | b'0'..=b'9') => {
                // JSON's grammar exactly (`-?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?`),
                // as serde_json: the text is checked by this parser alone unless it fails
                // (`json_check`). `1e999` is infinite here (the model says so, located).
                let b = self.bytes;
                let digits = |mut i: usize| {
                    while b.get(i).is_some_and(u8::is_ascii_digit) {
                        i += 1;
                    }
                    i
                };
                let mut i = start + usize::from(b[start] == b'-');
                let int_end = digits(i);
                let mut float = false;
                let mut ok = int_end > i && (b[i] != b'0' || int_end == i + 1);
                i = int_end;
                if ok && b.get(i) == Some(&b'.') {
                    let e = digits(i + 1);
                    ok = e > i + 1;
                    (i, float) = (e, true);
                }
                if ok && matches!(b.get(i), Some(b'e' | b'E')) {
                    let from = i + 1 + usize::from(matches!(b.get(i + 1), Some(b'+' | b'-')));
                    let e = digits(from);
                    ok = e > from;
                    (i, float) = (e, true);
                }
                if !ok {
                    self.pos = i;
                    return Err(self.error("invalid number"));
                }
                self.pos = i;
                let s = &self.text[start..self.pos];
                if float {
                    match s.parse::<f64>() {
                        Ok(f) => Value::Float(f),
                        Err(_) => return Err(self.error("invalid number")),
                    }
                } else if s.len() <= 18 {
                    // At most 18 characters (sign and digits, checked above): fits in an i64.
                    let (neg, digits) = match s.strip_prefix('-') {
                        Some(d) => (true, d),
                        None => (false, s),
                    };
                    let n = digits
                        .bytes()
                        .fold(0i64, |n, d| n * 10 + i64::from(d - b'0'));
                    Value::Int(if neg { -n } else { n })
                } else {
                    int_or_big(s.parse::<i64>().ok(), s)
                }
            }
            _ => return Err(self.error("expected a value")),
        };
        Ok(Node {
            span: start..self.pos,
            value,
        })
    }

    /// At a non-empty array: move past it (brackets and strings matched, nothing else
    /// checked: the items are parsed later) and give its span and the number of objects
    /// directly in it; `None` (not moved) at anything else. Eight bytes at a time: only
    /// brackets, braces and quotes (and in strings, backslashes) stop the scan.
    fn skip_list(&mut self) -> Result<Option<(Range<usize>, usize)>, LoadError> {
        let start = self.pos;
        if self.bytes.get(start) != Some(&b'[') {
            return Ok(None);
        }
        let mut i = start + 1;
        while self
            .bytes
            .get(i)
            .is_some_and(|b| matches!(b, b' ' | b'\t' | b'\n' | b'\r'))
        {
            i += 1;
        }
        if matches!(self.bytes.get(i), None | Some(b']')) {
            return Ok(None);
        }
        // Inside the list's `[`.
        let mut depth = 1usize;
        let mut items = 0;
        loop {
            i = next_structural(self.bytes, i);
            let Some(&b) = self.bytes.get(i) else {
                break;
            };
            i += 1;
            match b {
                b'{' => {
                    items += usize::from(depth == 1);
                    depth += 1;
                }
                b'[' => depth += 1,
                b']' | b'}' => {
                    depth = depth.saturating_sub(1);
                    if depth == 0 {
                        self.pos = i;
                        return Ok(Some((start..i, items)));
                    }
                }
                _ => {
                    // A quote: to the closing one, past escapes.
                    loop {
                        i = next_quote_or_escape(self.bytes, i);
                        match self.bytes.get(i) {
                            Some(b'\\') => i += 2,
                            Some(_) => {
                                i += 1;
                                break;
                            }
                            None => break,
                        }
                    }
                }
            }
        }
        self.pos = self.bytes.len();
        Err(self.error("unterminated array"))
    }

    fn hex4(&mut self) -> Result<u32, LoadError> {
        let h = self
            .text
            .get(self.pos..self.pos + 4)
            .and_then(|h| u32::from_str_radix(h, 16).ok())
            .ok_or_else(|| self.error("invalid \\u escape"))?;
        self.pos += 4;
        Ok(h)
    }

    fn string(&mut self) -> Result<Cow<'a, str>, LoadError> {
        self.eat(b'"')?;
        let start = self.pos;
        // The common case: no escape, borrowed from the text. A control character is an
        // error (as in serde_json).
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|&b| b != b'"' && b != b'\\' && b >= 0x20)
        {
            self.pos += 1;
        }
        if self.bytes.get(self.pos) == Some(&b'"') {
            let s = self
                .text
                .get(start..self.pos)
                .ok_or_else(|| self.error("invalid string"))?;
            self.pos += 1;
            return Ok(Cow::Borrowed(s));
        }
        self.pos = start;
        let mut out = String::new();
        loop {
            let run = self.pos;
            while self
                .bytes
                .get(self.pos)
                .is_some_and(|&b| b != b'"' && b != b'\\' && b >= 0x20)
            {
                self.pos += 1;
            }
            out.push_str(
                self.text
                    .get(run..self.pos)
                    .ok_or_else(|| self.error("invalid string"))?,
            );
            match self.bytes.get(self.pos) {
                Some(b'"') => {
                    self.pos += 1;
                    return Ok(Cow::Owned(out));
                }
                Some(b'\\') => {
                    self.pos += 1;
                    let c = self.bytes.get(self.pos).copied();
                    self.pos += 1;
                    match c {
                        Some(b'"') => out.push('"'),
                        Some(b'\\') => out.push('\\'),
                        Some(b'/') => out.push('/'),
                        Some(b'b') => out.push('\u{8}'),
                        Some(b'f') => out.push('\u{c}'),
                        Some(b'n') => out.push('\n'),
                        Some(b'r') => out.push('\r'),
                        Some(b't') => out.push('\t'),
                        Some(b'u') => {
                            let hi = self.hex4()?;
                            let code = if (0xD800..0xDC00).contains(&hi)
                                && self.bytes[self.pos..].starts_with(b"\\u")
                            {
                                self.pos += 2;
                                let lo = self.hex4()?;
                                0x10000 + ((hi - 0xD800) << 10) + lo.wrapping_sub(0xDC00)
                            } else {
                                hi
                            };
                            out.push(char::from_u32(code).unwrap_or('\u{FFFD}'));
                        }
                        _ => return Err(self.error("invalid escape")),
                    }
                }
                _ => return Err(self.error("unterminated string")),
            }
        }
    }
}

/// Eight bytes of `bytes` from `i` as a little-endian word (`None` near the end).
fn word(bytes: &[u8], i: usize) -> Option<u64> {
    let chunk = bytes.get(i..i + 8)?;
    let mut w = [0u8; 8];
    w.copy_from_slice(chunk);
    Some(u64::from_le_bytes(w))
}

/// The high bit of each byte of `x` that is zero (exact in the lowest such byte, which is all
/// the callers use).
fn zero_bytes(x: u64) -> u64 {
    x.wrapping_sub(0x0101_0101_0101_0101) & !x & 0x8080_8080_8080_8080
}

/// The high bit of each byte of `x` that is not zero (exact in every byte).
fn nonzero_bytes(x: u64) -> u64 {
    const LOW7: u64 = 0x7F7F_7F7F_7F7F_7F7F;
    (((x & LOW7).wrapping_add(LOW7)) | x) & !LOW7
}

/// Each byte of a word equal to `b`.
const fn splat(b: u8) -> u64 {
    0x0101_0101_0101_0101 * b as u64
}

/// The position of the first `"`, `[`, `]`, `{` or `}` at or after `i` (`bytes.len()`: none).
fn next_structural(bytes: &[u8], mut i: usize) -> usize {
    while let Some(w) = word(bytes, i) {
        // `[` and `{` differ in one bit (0x20), as `]` and `}`: no other byte meets them.
        let folded = w | splat(0x20);
        let hits = zero_bytes(w ^ splat(b'"'))
            | zero_bytes(folded ^ splat(b'{'))
            | zero_bytes(folded ^ splat(b'}'));
        if hits != 0 {
            return i + (hits.trailing_zeros() / 8) as usize;
        }
        i += 8;
    }
    while bytes
        .get(i)
        .is_some_and(|b| !matches!(b, b'"' | b'[' | b']' | b'{' | b'}'))
    {
        i += 1;
    }
    i.min(bytes.len())
}

/// The position of the first `"` or `\\` at or after `i` (`bytes.len()`: none).
fn next_quote_or_escape(bytes: &[u8], mut i: usize) -> usize {
    while let Some(w) = word(bytes, i) {
        let hits = zero_bytes(w ^ splat(b'"')) | zero_bytes(w ^ splat(b'\\'));
        if hits != 0 {
            return i + (hits.trailing_zeros() / 8) as usize;
        }
        i += 8;
    }
    while bytes.get(i).is_some_and(|b| !matches!(b, b'"' | b'\\')) {
        i += 1;
    }
    i.min(bytes.len())
}

#[cfg(test)]
mod tests {
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

    /// The chunked TOML parse gives exactly the serial tree, or declines.
    fn chunked_agrees(text: &str, pieces: usize) -> bool {
        let chunked = parse_toml_chunked(text, pieces);
        let serial = parse_toml_serial(text).ok();
        match chunked {
            Some(c) => {
                assert_eq!(Some(c), serial, "chunked tree differs for {text:?}");
                true
            }
            None => false,
        }
    }

    #[test]
    fn chunked_toml_equals_the_serial_tree() {
        let m = crate::generate::random(60, false, 3).unwrap().0;
        let mut text = crate::generate::to_toml(&m);
        for pieces in [2, 3, 7, 50, 1000] {
            assert!(chunked_agrees(&text, pieces), "a generated file is cut");
        }
        // Geometry subtables, comments after headers, a table after the joints.
        text.push_str("\n[[joint]] # last\ntype = \"R\"\nbodies = [1, 2]\n[joint.geometry]\norigin = [0, 0, 1]\naxis = [0, 0, 1]\n\n[expect]\nmobility = 0\n");
        for pieces in [2, 5, 40] {
            assert!(chunked_agrees(&text, pieces));
        }
    }

    #[test]
    fn chunked_toml_declines_what_it_cannot_join() {
        let joint = "[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n";
        let cases = [
            // A header inside a multi-line string and inside a multi-line array.
            format!(
                "name = \"\"\"\n{}\"\"\"\nframe = 1\n{joint}{joint}",
                joint.repeat(20)
            ),
            format!("frame = 1\nx = [\n1,\n{joint}]\n{joint}"),
            // An inline joint array, and a table given twice in two pieces.
            format!("frame = 1\njoint = []\n{joint}{joint}"),
            format!("frame = 1\njoint = [{{type = \"R\", bodies = [1, 2]}}]\n{joint}{joint}"),
            format!("frame = 1\njoint = [[[1]], [[2]]]\n{joint}{joint}"),
            format!("frame = 1\n{joint}[expect]\nmobility = 1\n{joint}[expect]\ngroups = 1\n"),
            // `[[body]]` arrays in two pieces (valid TOML: the serial parse joins them).
            format!("frame = 1\n{joint}[[body]]\nid = 1\n{joint}[[body]]\nid = 2\n"),
            // A joint table redefined as a plain table.
            format!("frame = 1\n{joint}{joint}[joint]\nx = 1\n"),
        ];
        for text in &cases {
            for pieces in [2, 3, 8] {
                chunked_agrees(text, pieces);
            }
            assert!(parse_toml_chunked(text, 2).is_none(), "{text}");
        }
    }

    #[test]
    fn three_formats_give_the_same_tree() {
        let t = parse_toml("a = 1\nb = [\"x\", 2.5, true]\n[c]\nd = -3\n").unwrap();
        let y = parse_yaml("a: 1\nb: [x, 2.5, true]\nc: {d: -3}\n")
            .unwrap()
            .unwrap();
        let j = parse_json(r#"{"a": 1, "b": ["x", 2.5, true], "c": {"d": -3}}"#)
            .unwrap()
            .0;
        assert_eq!(strip(&t), strip(&y));
        assert_eq!(strip(&t), strip(&j));
    }

    #[test]
    fn spans_point_at_values() {
        let text = "x: 1\nname: \"é\"\nvalue: abc\n";
        let y = parse_yaml(text).unwrap().unwrap();
        let Value::Map(es) = &y.value else { panic!() };
        assert_eq!(&text[es[2].key_span.clone()], "value");
        assert_eq!(&text[es[2].value.span.clone()], "abc");
        let j = r#"{"a": [1, "b"]}"#;
        let n = parse_json(j).unwrap().0;
        let Value::Map(es) = &n.value else { panic!() };
        assert_eq!(&j[es[0].key_span.clone()], "\"a\"");
        assert_eq!(&j[es[0].value.span.clone()], "[1, \"b\"]");
    }

    #[test]
    fn yaml_core_schema() {
        assert_eq!(resolve_plain(Cow::Borrowed("~")), Value::Null);
        assert_eq!(resolve_plain(Cow::Borrowed("0x1F")), Value::Int(31));
        assert_eq!(resolve_plain(Cow::Borrowed("-12")), Value::Int(-12));
        assert_eq!(resolve_plain(Cow::Borrowed("1e3")), Value::Float(1000.0));
        assert_eq!(resolve_plain(Cow::Borrowed(".5")), Value::Float(0.5));
        assert_eq!(
            resolve_plain(Cow::Borrowed("-.inf")),
            Value::Float(f64::NEG_INFINITY)
        );
        assert!(matches!(resolve_plain(Cow::Borrowed(".nan")), Value::Float(f) if f.is_nan()));
        assert_eq!(
            resolve_plain(Cow::Borrowed("1-2")),
            Value::Str(Cow::Borrowed("1-2"))
        );
        assert_eq!(
            resolve_plain(Cow::Borrowed("e3")),
            Value::Str(Cow::Borrowed("e3"))
        );
        assert!(matches!(
            resolve_plain(Cow::Borrowed("100000000000000000000000")),
            Value::BigInt(_)
        ));
    }

    /// Mutated JSON: whatever serde_json refuses, the tree parser refuses too (the reader runs
    /// serde_json's check only after an error).
    #[test]
    fn json_tree_parser_is_as_strict_as_serde_json() {
        let base = r#"{"name": "a\u00e9", "frame": 1, "joints": [{"type": "R", "bodies": [1, 2], "axis": [0.5, -1e3, 2E+2]}, {"type": "P", "bodies": [2, 3], "driven": 1}], "expect": {"mobility": 0, "determined": true, "x": null}}"#;
        let alphabet = b" \t\n{}[]:,.\"\\-+0123456789eEtrufalsn\x01";
        let mut refused = 0;
        for text in crate::format::mutated_texts(base, alphabet, 0x2545_F491_4F6C_DD1D, 6000, 2) {
            if json_check(&text).is_ok() {
                continue;
            }
            refused += 1;
            let ours = parse_json_tree(&text).and_then(|(root, lazy)| {
                let list = match root.value {
                    Value::Map(es) => es
                        .into_iter()
                        .find(|e| matches!(e.value.value, Value::Deferred))
                        .map_or(Value::Null, |e| e.value.value),
                    _ => Value::Null,
                };
                lazy.for_each(list, &mut |_| Ok(()))
            });
            assert!(ours.is_err(), "accepted what serde_json refuses: {text:?}");
        }
        assert!(refused > 1000, "{refused}");
    }

    /// The tree with its deferred joint list read in (as `strip` shows it), by `parse`.
    fn with_items<'a>(parsed: Option<(Node<'a>, Lazy<'a>)>) -> Option<String> {
        let (root, lazy) = parsed?;
        let Value::Map(mut es) = root.value else {
            return Some(strip(&root));
        };
        let mut items = Vec::new();
        if let Some(e) = es
            .iter_mut()
            .find(|e| matches!(e.value.value, Value::Deferred))
        {
            let list = std::mem::replace(&mut e.value.value, Value::Null);
            lazy.for_each(list, &mut |n| {
                items.push(n.clone());
                Ok(())
            })
            .ok()?;
            e.value.value = Value::Seq(items);
        }
        Some(strip(&Node {
            span: root.span,
            value: Value::Map(es),
        }))
    }

    #[test]
    fn json_resumed_read_equals_the_whole_read() {
        let base = r#"{"name": "a\u00e9", "frame": 1, "expect": {"mobility": 0, "x": null}, "joints": [{"type": "R", "bodies": [1, 2], "axis": [0.5, -1e3, 2E+2]}, {"type": "P", "bodies": [2, 3], "driven": -12345678901234567}, {"id": 123456789012345678901, "bodies": [-0, 7]}]}"#;
        let alphabet = b" \t\n{}[]:,.\"\\-+0123456789eEtrufalsn\x01";
        let mut resumed = 0;
        let texts = crate::format::mutated_texts(base, alphabet, 0x9E37_79B9_7F4A_7C15, 6000, 2);
        for text in std::iter::once(base.to_string()).chain(texts) {
            let Some(r) = with_items(parse_json_resume(&text)) else {
                continue;
            };
            resumed += 1;
            assert!(
                json_check(&text).is_ok(),
                "accepted what serde_json refuses: {text:?}"
            );
            assert_eq!(Some(r), with_items(parse_json_tree(&text).ok()), "{text:?}");
        }
        assert!(resumed > 1000, "{resumed}");
    }

    #[test]
    fn json_escapes() {
        let n = parse_json(r#"["a\u00e9\ud83d\ude00\n"]"#).unwrap().0;
        assert_eq!(
            n.value,
            Value::Seq(vec![Node {
                span: 1..24,
                value: Value::Str(Cow::Owned("aé😀\n".into()))
            }])
        );
    }
}
