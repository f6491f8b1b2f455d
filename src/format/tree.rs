//! One spanned value tree for the three input formats, so that the model conversion can point
//! every error at the exact key or value. The readers of every format (`super::read`, and the
//! fast readers `super::fast_toml`, `super::fast_yaml`) build it; it calls none of them.

use super::error::{ErrorKind, Label, LoadError};
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
    /// A non-empty joint list whose items are parsed one at a time by [`super::read::Lazy::for_each`].
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

pub(crate) fn syntax(
    what: &str,
    message: impl Into<String>,
    at: Range<usize>,
    label: &str,
) -> LoadError {
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

pub(crate) fn too_deep(at: Range<usize>) -> LoadError {
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
pub(crate) fn push_entry<'a>(
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

/// A plain YAML scalar resolved by the YAML 1.2 core schema, when it is not a string
/// (`None`: a string).
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

pub(crate) fn int_or_big(n: Option<i64>, s: &str) -> Value<'static> {
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
