//! JSON text into the value tree by a small spanned parser (as strict as serde_json, whose
//! check runs after an error for its better message): read whole with the joint list skipped,
//! or stopped at a last joint list and resumed item by item.

use super::Lazy;
use crate::format::error::{LoadError, floor_boundary, offset_of};
use crate::format::tree::{
    Entry, MAX_DEPTH, Node, Value, int_or_big, is_joint_list, push_entry, syntax, too_deep,
};
use std::borrow::Cow;
use std::ops::Range;

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

/// The items of a joint list skipped by the whole read ([`Lazy::Json`]), parsed from its `[`.
pub(super) fn for_each_skipped_item<'a>(
    text: &'a str,
    span: Range<usize>,
    f: &mut dyn FnMut(&Node<'a>) -> Result<(), LoadError>,
) -> Result<(), LoadError> {
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

/// The items of a joint list the parser stopped at ([`Lazy::JsonResume`]), read from `pos`,
/// then the check that the object and the text end after the list.
pub(super) fn for_each_resumed_item<'a>(
    text: &'a str,
    pos: usize,
    f: &mut dyn FnMut(&Node<'a>) -> Result<(), LoadError>,
) -> Result<(), LoadError> {
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

/// An object read by [`JsonParser::object`].
enum Object<'a> {
    /// Read to its `}`.
    Whole(Vec<Entry<'a>>),
    /// Stopped at the top-level joint list ([`parse_json_resume`]): the object as far as read,
    /// its span to the end of the text.
    StoppedAtJoints(Node<'a>),
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
            Some(b'{') => match self.object(start, depth)? {
                Object::Whole(entries) => Value::Map(entries),
                Object::StoppedAtJoints(node) => return Ok(node),
            },
            Some(b'[') => Value::Seq(self.array(depth)?),
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
            Some(b'-' | b'0'..=b'9') => self.number(start)?,
            _ => return Err(self.error("expected a value")),
        };
        Ok(Node {
            span: start..self.pos,
            value,
        })
    }

    /// The entries of the object at `{` (which starts at `start`); the top-level joint list
    /// deferred (skipped, or stopped at).
    fn object(&mut self, start: usize, depth: usize) -> Result<Object<'a>, LoadError> {
        self.pos += 1;
        let mut entries = Vec::new();
        let mut index = None;
        self.ws();
        if self.bytes.get(self.pos) == Some(&b'}') {
            self.pos += 1;
            return Ok(Object::Whole(entries));
        }
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
                return Ok(Object::StoppedAtJoints(Node {
                    span: start..self.bytes.len(),
                    value: Value::Map(entries),
                }));
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
                return Ok(Object::Whole(entries));
            }
        }
    }

    /// The items of the array at `[`.
    fn array(&mut self, depth: usize) -> Result<Vec<Node<'a>>, LoadError> {
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
        Ok(items)
    }

    /// The number that starts at `start`: JSON's grammar exactly
    /// (`-?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?`), as serde_json: the text is checked
    /// by this parser alone unless it fails (`json_check`). `1e999` is infinite here (the
    /// model says so, located).
    fn number(&mut self, start: usize) -> Result<Value<'a>, LoadError> {
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
                Ok(f) => Ok(Value::Float(f)),
                Err(_) => Err(self.error("invalid number")),
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
            Ok(Value::Int(if neg { -n } else { n }))
        } else {
            Ok(int_or_big(s.parse::<i64>().ok(), s))
        }
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
