//! YAML text into the value tree by saphyr's event parser (which finds and locates every
//! error): read whole, with the joint list deferred, or stopped at a last joint list and resumed
//! item by item.

use super::Lazy;
use crate::format::error::{ErrorKind, Label, LoadError};
use crate::format::tree::{
    Entry, MAX_DEPTH, Node, Value, is_joint_list, push_entry, resolve_plain_str, syntax, too_deep,
};
use std::borrow::Cow;
use std::ops::Range;

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

impl YamlReader<'_> {
    /// The text being read.
    pub(super) fn text(&self) -> &str {
        self.index.text
    }
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
        use saphyr_parser::Event;
        let (ev, span) = ev;
        if depth > MAX_DEPTH {
            return Err(too_deep(span));
        }
        match ev {
            Event::Scalar(text, style, _anchor, tag) => {
                let value = scalar(text, style, tag.as_deref(), &span)?;
                Ok(Node { span, value })
            }
            Event::SequenceStart(_, tag) => {
                if let Some(t) = tag
                    && t.suffix != "seq"
                {
                    return Err(unsupported_tag(&t, span));
                }
                self.sequence(span, depth)
            }
            Event::MappingStart(_, tag) => {
                if let Some(t) = tag
                    && t.suffix != "map"
                {
                    return Err(unsupported_tag(&t, span));
                }
                self.mapping(span, depth)
            }
            Event::Alias(_) => Err(alias(span)),
            _ => Err(syntax("YAML", "unexpected event", span, "here")),
        }
    }

    /// The items of the sequence that started at `span`, to its end.
    fn sequence(&mut self, span: Range<usize>, depth: usize) -> Result<Node<'a>, LoadError> {
        use saphyr_parser::Event;
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

    /// The entries of the mapping that started at `span`, to its end; the top-level joint list
    /// skipped when deferring.
    fn mapping(&mut self, span: Range<usize>, depth: usize) -> Result<Node<'a>, LoadError> {
        use saphyr_parser::Event;
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
}

/// The value of a scalar, by its tag, else by its style (plain scalars by the core schema).
fn scalar<'a>(
    text: Cow<'a, str>,
    style: saphyr_parser::ScalarStyle,
    tag: Option<&saphyr_parser::Tag>,
    span: &Range<usize>,
) -> Result<Value<'a>, LoadError> {
    use saphyr_parser::ScalarStyle;
    Ok(match (tag, style) {
        (Some(t), _) if t.handle == "tag:yaml.org,2002:" || t.handle == "!!" => {
            match t.suffix.as_str() {
                "str" => Value::Str(text),
                "int" | "float" | "bool" | "null" => resolve_plain(text),
                _ => return Err(unsupported_tag(t, span.clone())),
            }
        }
        (Some(t), _) => return Err(unsupported_tag(t, span.clone())),
        (None, ScalarStyle::Plain) => resolve_plain(text),
        (None, _) => Value::Str(text),
    })
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
pub(super) fn resolve_plain(text: Cow<'_, str>) -> Value<'_> {
    match resolve_plain_str(&text) {
        Some(v) => v,
        None => Value::Str(text),
    }
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

/// [`parse_yaml_resume`] with the joint list's items read by [`crate::format::fast_yaml`]
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
    let items = crate::format::fast_yaml::Items::new(text, list.value.span.start)?;
    Some((root, Lazy::YamlLines { text, items }))
}

/// The second read of [`Lazy::Yaml`]: `f` on each item of the top-level joint list.
pub(super) fn yaml_joint_items<'a>(
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

/// The items of a joint list the reader stopped at ([`Lazy::YamlResume`]), then the check that
/// nothing follows the list.
pub(super) fn for_each_resumed_item<'a>(
    mut r: YamlReader<'a>,
    f: &mut dyn FnMut(&Node<'a>) -> Result<(), LoadError>,
) -> Result<(), LoadError> {
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
