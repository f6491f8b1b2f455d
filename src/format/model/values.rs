//! Typed values out of the tree (maps, lists, strings, numbers, body ids, keys), each refusal
//! located at the value it is about.

use crate::format::error::{ErrorKind, Label, LoadError};
use crate::format::tree::{Entry, Node, Value};
use crate::mechanism::BodyId;
use std::ops::Range;

pub(super) fn label(span: &Range<usize>, text: impl Into<String>) -> Label {
    Label {
        span: span.clone(),
        text: text.into(),
    }
}

pub(super) fn err(
    kind: ErrorKind,
    message: impl Into<String>,
    span: &Range<usize>,
    text: impl Into<String>,
    help: Option<String>,
) -> LoadError {
    LoadError::new(kind, message, vec![label(span, text)], help)
}

/// The candidate closest to `word`, if close enough to be a plausible typo.
pub(super) fn nearest<'c>(
    word: &str,
    candidates: impl IntoIterator<Item = &'c str>,
) -> Option<&'c str> {
    candidates
        .into_iter()
        .map(|c| {
            (
                strsim::jaro_winkler(&word.to_lowercase(), &c.to_lowercase()),
                c,
            )
        })
        .filter(|(s, _)| *s >= 0.75)
        .max_by(|a, b| a.0.total_cmp(&b.0).then_with(|| b.1.cmp(a.1)))
        .map(|(_, c)| c)
}

pub(super) fn wrong_type(node: &Node, expected: &str, what: &str) -> LoadError {
    err(
        ErrorKind::WrongType,
        format!("{what} must be {expected}, not {}", node.value.type_name()),
        &node.span,
        format!("{} here", node.value.type_name()),
        None,
    )
}

pub(super) fn out_of_range(node: &Node, what: &str) -> LoadError {
    err(
        ErrorKind::NumberOutOfRange,
        format!("{what} is too large a number"),
        &node.span,
        "out of range",
        Some("integers must fit in 64 bits".into()),
    )
}

pub(super) fn as_map<'n, 'a>(node: &'n Node<'a>, what: &str) -> Result<&'n [Entry<'a>], LoadError> {
    match &node.value {
        Value::Map(es) => Ok(es),
        _ => Err(wrong_type(node, "a table", what)),
    }
}

pub(super) fn as_seq<'n, 'a>(node: &'n Node<'a>, what: &str) -> Result<&'n [Node<'a>], LoadError> {
    match &node.value {
        Value::Seq(xs) => Ok(xs),
        _ => Err(wrong_type(node, "an array", what)),
    }
}

pub(super) fn as_str<'n>(node: &'n Node, what: &str) -> Result<&'n str, LoadError> {
    match &node.value {
        Value::Str(s) => Ok(s),
        _ => Err(wrong_type(node, "a string", what)),
    }
}

pub(super) fn as_int(node: &Node, what: &str) -> Result<i64, LoadError> {
    match &node.value {
        Value::Int(i) => Ok(*i),
        Value::BigInt(_) => Err(out_of_range(node, what)),
        _ => Err(wrong_type(node, "an integer", what)),
    }
}

/// Largest magnitude of a geometry number. Beyond it the analyses would overflow: the norm
/// of `[1e308, 1e308, 1e308]` is infinite, and products of coordinates (moments, squared
/// norms, elimination) must stay finite.
pub(crate) const MAX_GEOMETRY_NUMBER: f64 = 1e100;

/// A finite geometry number (integers accepted), at most [`MAX_GEOMETRY_NUMBER`] in magnitude.
pub(super) fn as_number(node: &Node, what: &str) -> Result<f64, LoadError> {
    let x = match &node.value {
        Value::Int(i) => *i as f64,
        Value::Float(f) => *f,
        Value::BigInt(_) => return Err(out_of_range(node, what)),
        _ => return Err(wrong_type(node, "a number", what)),
    };
    if !x.is_finite() {
        return Err(err(
            ErrorKind::NonFinite,
            format!("{what} must be a finite number, not {x}"),
            &node.span,
            "not finite",
            Some("geometry takes ordinary numbers; NaN and infinity have no position".into()),
        ));
    }
    if x.abs() > MAX_GEOMETRY_NUMBER {
        return Err(err(
            ErrorKind::NumberOutOfRange,
            format!("{what} is {x:e}, too large: geometry numbers are at most 1e100 in magnitude"),
            &node.span,
            "too large",
            Some(
                "the analyses square and multiply coordinates; scale the model to ordinary units"
                    .into(),
            ),
        ));
    }
    Ok(x)
}

/// A body (or point, or bar) id: an integer or a non-empty string. A string that is a plain
/// integer (`"12"`) is the integer, so that `--inputs 1-12` finds it.
pub(super) fn as_id(node: &Node, what: &str) -> Result<BodyId, LoadError> {
    match &node.value {
        Value::Int(i) => Ok(BodyId::Int(*i)),
        Value::Str(s) if s.trim().is_empty() => Err(err(
            ErrorKind::EmptyId,
            format!("{what} is empty"),
            &node.span,
            "empty id",
            Some("ids are integers or non-empty names".into()),
        )),
        Value::Str(s) => Ok(match s.parse::<i64>() {
            Ok(i) if i.to_string() == *s => BodyId::Int(i),
            _ => BodyId::Name(s.to_string()),
        }),
        Value::BigInt(_) => Err(out_of_range(node, what)),
        _ => Err(wrong_type(node, "an integer or a string", what)),
    }
}

/// Reject keys outside `allowed`, suggesting the nearest one.
pub(super) fn check_keys(
    entries: &[Entry],
    allowed: &[&str],
    context: &str,
) -> Result<(), LoadError> {
    for e in entries {
        if !allowed.contains(&e.key.as_ref()) {
            let listed: Vec<&str> = allowed
                .iter()
                .copied()
                .filter(|k| *k != "$schema")
                .collect();
            let help = match nearest(&e.key, listed.iter().copied()) {
                Some(k) => format!("did you mean `{k}`? {context} keys: {}", listed.join(", ")),
                None => format!("{context} keys: {}", listed.join(", ")),
            };
            return Err(err(
                ErrorKind::UnknownKey,
                format!("unknown {context} key `{}`", e.key),
                &e.key_span,
                "unknown key",
                Some(help),
            ));
        }
    }
    Ok(())
}

pub(super) fn get<'n, 'a>(entries: &'n [Entry<'a>], key: &str) -> Option<&'n Entry<'a>> {
    entries.iter().find(|e| e.key == key)
}

/// The entry under `a` or its alias `b` (not both).
pub(super) fn get_alias<'n, 'a>(
    entries: &'n [Entry<'a>],
    a: &str,
    b: &str,
) -> Result<Option<&'n Entry<'a>>, LoadError> {
    match (get(entries, a), get(entries, b)) {
        (Some(x), Some(y)) => {
            let (first, second) = if x.key_span.start <= y.key_span.start {
                (x, y)
            } else {
                (y, x)
            };
            Err(LoadError::new(
                ErrorKind::BothAliases,
                format!("both `{a}` and `{b}` given"),
                vec![
                    label(&second.key_span, "second list"),
                    label(&first.key_span, "first list"),
                ],
                Some(format!(
                    "`{b}` is another spelling of `{a}`: use one of them"
                )),
            ))
        }
        (x, y) => Ok(x.or(y)),
    }
}

pub(super) fn required<'n, 'a>(
    entries: &'n [Entry<'a>],
    key: &str,
    owner: &Node,
    what: &str,
) -> Result<&'n Entry<'a>, LoadError> {
    get(entries, key).ok_or_else(|| {
        // Point at the table's first key: the table's own span may be its whole body.
        let at = entries
            .first()
            .map_or(owner.span.start..owner.span.start, |e| e.key_span.clone());
        err(
            ErrorKind::MissingField,
            format!("{what} has no `{key}`"),
            &at,
            format!("in this {what}"),
            Some(match key {
                "type" => "add `type`, a joint code such as R, P, S or a long name".to_string(),
                "bodies" => "add `bodies`, the ids of the bodies it joins, e.g. [1, 2]".to_string(),
                "points" => "add `points`, the ids of its two end points, e.g. [1, 2]".to_string(),
                _ => format!("add `{key}`"),
            }),
        )
    })
}
