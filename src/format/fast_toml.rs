//! A single-pass reader for the TOML that large mechanism files are written in:
//! one `key = value` per line, bare keys, scalars and one-line arrays of scalars, top-level
//! `[table]` headers and `[[joint]]` tables. It builds the same spanned tree as the toml crate
//! (tested equal) without the crate's token vector, maps and per-value allocations, and reads
//! the joints one at a time ([`super::read::Lazy::TomlLines`]).
//!
//! It accepts a strict subset of TOML and declines (`None`) at anything else: escapes,
//! literal or multi-line strings, dotted or quoted keys, inline tables, nested arrays,
//! underscores in numbers, non-decimal integers, `inf`/`nan`, date-times, a duplicate key,
//! a control character. The caller then reads the text with the toml crate, which also finds
//! every error; so every error (and its location) is the toml crate's, as before.

use super::tree::{Entry, Node, Value};
use std::borrow::Cow;
use std::collections::HashSet;
use std::ops::Range;

/// The joint table header.
const JOINT: &str = "[[joint]]";

/// The `[[joint]]` tables [`parse`] found: where the first header is and how many there are.
/// Their lines are read later, one table at a time, by a [`JointReader`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct JointTables {
    /// The `[` of the first `[[joint]]` header (meaningless when `count` is 0).
    pub first: usize,
    /// How many `[[joint]]` headers the text has.
    pub count: usize,
}

/// The top-level tree with the joint list [`Value::Deferred`] (when there are `[[joint]]`
/// tables), and where the joint tables are. The lines of the joint tables are only looked at
/// for headers here (a scan for line starts, no vector per table).
pub(crate) fn parse(text: &str) -> Option<(Node<'_>, JointTables)> {
    let bytes = text.as_bytes();
    let mut top: Vec<Entry<'_>> = Vec::new();
    // The keys met, by table (0 the top level, i + 1 the table top[i]): the duplicate check
    // in constant time. A scan of the table's entries per line was quadratic (10^5 unknown
    // top-level keys: 23 s).
    let mut seen: HashSet<(usize, &str)> = HashSet::new();
    // The table being filled: `None` the top level, `Some(i)` the `[name]` table top[i].
    let mut table: Option<usize> = None;
    let mut in_joints = false;
    let mut joints = JointTables { first: 0, count: 0 };
    let mut joint_entry: Option<Entry<'_>> = None;
    // Top-level arrays are few: no pool of vectors to reuse.
    let mut no_pool = Vec::new();
    let mut pos = 0;
    while pos < bytes.len() {
        let first = if in_joints {
            // The joints' own lines are read later: only the next header matters here.
            match next_header(bytes, pos) {
                Some(first) => first,
                None => break,
            }
        } else {
            skip_ws(bytes, pos, bytes.len())
        };
        let end = line_break(bytes, first);
        if bytes.get(first) == Some(&b'[') {
            if bytes[first..end].starts_with(JOINT.as_bytes()) {
                line_end(bytes, first + JOINT.len(), end)?;
                if joint_entry.is_none() {
                    if seen.contains(&(0, "joint")) {
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
                    joints.first = first;
                }
                joints.count += 1;
                in_joints = true;
            } else {
                table = Some(table_header(text, first, end, &mut top, &mut seen)?);
                in_joints = false;
            }
        } else if let Some(entry) = line_entry(text, pos, end, &mut no_pool)? {
            let entries = match table {
                None => &mut top,
                Some(i) => match &mut top[i].value.value {
                    Value::Map(es) => es,
                    _ => return None,
                },
            };
            // Bare keys borrow from the text; anything else is left to the toml crate.
            let Cow::Borrowed(key) = entry.key else {
                return None;
            };
            if !seen.insert((table.map_or(0, |i| i + 1), key))
                || (table.is_none() && is_joint_key(key))
            {
                return None;
            }
            entries.push(entry);
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

/// A `[name]` header line from `first` to `end`: a new empty table pushed onto `top` (a
/// repeated or `joint` name, or one of `seen`'s top-level keys, declined; the name added to
/// them); gives its index.
fn table_header<'a>(
    text: &'a str,
    first: usize,
    end: usize,
    top: &mut Vec<Entry<'a>>,
    seen: &mut HashSet<(usize, &'a str)>,
) -> Option<usize> {
    let bytes = text.as_bytes();
    let (name, after) = bare_key(bytes, first + 1, end)?;
    if bytes.get(after) != Some(&b']') {
        return None;
    }
    line_end(bytes, after + 1, end)?;
    let key = &text[name.clone()];
    if key == "joint" || !seen.insert((0, key)) {
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
    Some(top.len() - 1)
}

/// `joint` (also the header's key: both in one file is an error the toml crate reports) or
/// `joints` (allowed next to `[[joint]]` tables by TOML; the model reports both).
fn is_joint_key(key: &str) -> bool {
    key == "joint"
}

/// The `[[joint]]` tables of a text [`parse`] read, one at a time: each table's lines, from
/// its header to the next header line (lines of other tables are skipped: `parse` read them).
/// One node is reused for every table (and the arrays of one table for the next): a million
/// joints are then read without a million allocations.
pub(crate) struct JointReader<'a> {
    text: &'a str,
    /// The `[` of the next `[[joint]]` header; `None` after the last.
    next: Option<usize>,
    /// The table last read (its entries are cleared before the next one is read).
    node: Node<'a>,
    /// Emptied arrays of earlier tables.
    pool: Vec<Vec<Node<'a>>>,
}

/// An empty table node (its entries' vector sized for a joint's few keys).
fn table_node<'a>() -> Node<'a> {
    Node {
        span: 0..0,
        value: Value::Map(Vec::with_capacity(4)),
    }
}

impl<'a> JointReader<'a> {
    /// A reader of the tables `joints` of `text` (as [`parse`] found them).
    pub(crate) fn new(text: &'a str, joints: JointTables) -> JointReader<'a> {
        JointReader {
            text,
            next: (joints.count > 0).then_some(joints.first),
            node: table_node(),
            pool: Vec::new(),
        }
    }

    /// The next joint table (`Some(None)` after the last); `None` at a line the fast path
    /// does not read, or a key given twice.
    pub(crate) fn next_table(&mut self) -> Option<Option<&Node<'a>>> {
        let mut node = std::mem::replace(
            &mut self.node,
            Node {
                span: 0..0,
                value: Value::Null,
            },
        );
        let read = self.read_into(&mut node);
        self.node = node;
        match read? {
            true => Some(Some(&self.node)),
            false => Some(None),
        }
    }

    /// The next joint table read into `node` (a table node from [`table_node`], maybe holding
    /// an earlier table: its arrays go to the pool): `Some(true)`, or `Some(false)` after the
    /// last table; `None` as in [`JointReader::next_table`].
    fn read_into(&mut self, node: &mut Node<'a>) -> Option<bool> {
        let Value::Map(entries) = &mut node.value else {
            return None;
        };
        for e in entries.drain(..) {
            if let Value::Seq(mut items) = e.value.value {
                items.clear();
                self.pool.push(items);
            }
        }
        let Some(header) = self.next else {
            return Some(false);
        };
        let text = self.text;
        let bytes = text.as_bytes();
        node.span = header..header + JOINT.len();
        let mut pos = line_break(bytes, header) + 1;
        self.next = loop {
            if pos >= bytes.len() {
                break None;
            }
            let first = skip_ws(bytes, pos, bytes.len());
            if bytes.get(first) == Some(&b'[') {
                break if bytes[first..].starts_with(JOINT.as_bytes()) {
                    Some(first)
                } else {
                    // Another table (read by `parse`): the next joint is after it.
                    next_joint_header(bytes, first)
                };
            }
            // The line's end is found by reading it (no separate search for the line break).
            // The entry is written in place (not returned: moving it showed in profiles).
            let before = entries.len();
            let end = line(text, first, bytes.len(), &mut self.pool, entries)?;
            if entries.len() > before
                && let Some((entry, earlier)) = entries.split_last()
                && earlier.iter().any(|e| same_key(&e.key, &entry.key))
            {
                return None;
            }
            pos = end + 1;
        };
        Some(true)
    }
}

/// Files with at least this many joint tables are read on two threads ([`for_each_table`]):
/// below it the thread and its batches (about 0.7 MB of nodes) cost more than they save.
const PIPELINE_MIN: usize = 1 << 16;

/// Tables handed from the reading thread to the model at a time (larger batches wake the
/// other thread less often, but their nodes leave the cache before they are read).
const BATCH: usize = 512;

/// Batches in flight (filled or being filled, handed back empty).
const BATCHES: usize = 3;

/// How a batch ends.
#[derive(Clone, Copy, PartialEq, Eq)]
enum BatchEnd {
    /// More tables follow in the next batch.
    More,
    /// The last table is in this batch.
    Last,
    /// The reader declined after the tables of this batch.
    Declined,
}

/// Tables read by the reading thread: `nodes[..len]`, in file order.
struct Batch<'a> {
    nodes: Vec<Node<'a>>,
    len: usize,
    end: BatchEnd,
}

/// Why [`for_each_table`] stopped early.
pub(crate) enum Stopped<E> {
    /// The reader declined a table (the caller reads the text again).
    Declined,
    /// `f` gave an error.
    Failed(E),
}

/// `f` on every `[[joint]]` table of `text` (as [`parse`] found them), in order; stops at
/// `f`'s first error or where the reader declines. With many tables and two cores the tables
/// are read (the line reader: about half of the read) on a second thread while `f` runs on
/// this one, in batches of [`BATCH`] nodes that go back and forth, so that no node or array
/// is allocated per table. The outcome is the serial one: the same tables in the same order,
/// and a decline anywhere before `f`'s first error declines (`f` is never called past the
/// declined table, nor past its own error).
pub(crate) fn for_each_table<'a, E>(
    text: &'a str,
    joints: JointTables,
    f: &mut dyn FnMut(&Node<'a>) -> Result<(), E>,
) -> Result<(), Stopped<E>> {
    for_each_table_from(text, joints, PIPELINE_MIN, f)
}

/// [`for_each_table`], on two threads from `min_tables` tables on.
fn for_each_table_from<'a, E>(
    text: &'a str,
    joints: JointTables,
    min_tables: usize,
    f: &mut dyn FnMut(&Node<'a>) -> Result<(), E>,
) -> Result<(), Stopped<E>> {
    let parallel = joints.count >= min_tables
        && std::thread::available_parallelism().is_ok_and(|n| n.get() > 1);
    if !parallel {
        return for_each_serial(text, joints, f);
    }
    use std::sync::mpsc::sync_channel;
    let (full_tx, full_rx) = sync_channel::<Batch<'a>>(BATCHES);
    let (empty_tx, empty_rx) = sync_channel::<Batch<'a>>(BATCHES);
    for _ in 0..BATCHES {
        let batch = Batch {
            nodes: Vec::with_capacity(BATCH),
            len: 0,
            end: BatchEnd::More,
        };
        if empty_tx.send(batch).is_err() {
            return for_each_serial(text, joints, f);
        }
    }
    std::thread::scope(|s| {
        let reading = std::thread::Builder::new()
            .name("mbsa-toml".into())
            .spawn_scoped(s, move || read_batches(text, joints, &empty_rx, &full_tx));
        if reading.is_err() {
            // No thread (resources): read here.
            return for_each_serial(text, joints, f);
        }
        // Both channel ends owned here: dropped when the model stops, which ends the reading
        // thread wherever it waits (a send or a receive then fails).
        consume_batches(full_rx, empty_tx, f)
    })
}

/// The tables read on this thread.
fn for_each_serial<'a, E>(
    text: &'a str,
    joints: JointTables,
    f: &mut dyn FnMut(&Node<'a>) -> Result<(), E>,
) -> Result<(), Stopped<E>> {
    let mut reader = JointReader::new(text, joints);
    loop {
        match reader.next_table() {
            Some(Some(table)) => f(table).map_err(Stopped::Failed)?,
            Some(None) => return Ok(()),
            None => return Err(Stopped::Declined),
        }
    }
}

/// The reading thread of [`for_each_table`]: empty batches in, filled batches out, until the
/// last table, a decline, or the model's side hangs up.
fn read_batches<'a>(
    text: &'a str,
    joints: JointTables,
    empty: &std::sync::mpsc::Receiver<Batch<'a>>,
    full: &std::sync::mpsc::SyncSender<Batch<'a>>,
) {
    let mut reader = JointReader::new(text, joints);
    while let Ok(mut batch) = empty.recv() {
        batch.len = 0;
        batch.end = BatchEnd::More;
        while batch.len < BATCH {
            if batch.len == batch.nodes.len() {
                batch.nodes.push(table_node());
            }
            match reader.read_into(&mut batch.nodes[batch.len]) {
                Some(true) => batch.len += 1,
                Some(false) => {
                    batch.end = BatchEnd::Last;
                    break;
                }
                None => {
                    batch.end = BatchEnd::Declined;
                    break;
                }
            }
        }
        let end = batch.end;
        if full.send(batch).is_err() || end != BatchEnd::More {
            return;
        }
    }
}

/// The model's side of [`for_each_table`]: `f` on the tables of each filled batch, the batch
/// handed back to be filled again.
fn consume_batches<'a, E>(
    full: std::sync::mpsc::Receiver<Batch<'a>>,
    empty: std::sync::mpsc::SyncSender<Batch<'a>>,
    f: &mut dyn FnMut(&Node<'a>) -> Result<(), E>,
) -> Result<(), Stopped<E>> {
    loop {
        // The reading thread gone without its last batch: cannot happen short of a panic
        // there; read again by the caller's other readers.
        let Ok(batch) = full.recv() else {
            return Err(Stopped::Declined);
        };
        for table in &batch.nodes[..batch.len] {
            f(table).map_err(Stopped::Failed)?;
        }
        match batch.end {
            BatchEnd::More => {}
            BatchEnd::Last => return Ok(()),
            BatchEnd::Declined => return Err(Stopped::Declined),
        }
        // The reading thread may have stopped already (it never does before `Last`).
        let _ = empty.send(batch);
    }
}

/// Whether two keys are equal: lengths and first bytes first (`bodies` and `driven` have one
/// length: a call to compare bytes for each pair of keys of each table showed in profiles).
fn same_key(a: &str, b: &str) -> bool {
    a.len() == b.len() && a.as_bytes().first() == b.as_bytes().first() && a == b
}

/// Where the line holding `at` ends: its `\n`, or the text's length.
fn line_break(bytes: &[u8], at: usize) -> usize {
    // Lines are short: a plain loop beats a search call per line.
    bytes[at.min(bytes.len())..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |i| at + i)
}

/// The first non-blank byte of the first line from `pos` (a line start) on that starts (after
/// blanks) with `[`; `None` when no line does.
fn next_header(bytes: &[u8], pos: usize) -> Option<usize> {
    // Every `[` from `pos` on (a vectorized search: two a joint table, its header's and its
    // `bodies`'), not every line: a `[` starts its line when only blanks come before it on
    // the line (or from `pos`, itself a line start).
    let from = pos.min(bytes.len());
    memchr::memchr_iter(b'[', &bytes[from..])
        .map(|i| from + i)
        .find(|&i| {
            let mut j = i;
            while j > from && matches!(bytes[j - 1], b' ' | b'\t') {
                j -= 1;
            }
            j == from || bytes[j - 1] == b'\n'
        })
}

/// The `[` of the first `[[joint]]` header after the header line at `at`.
fn next_joint_header(bytes: &[u8], mut at: usize) -> Option<usize> {
    loop {
        at = next_header(bytes, line_break(bytes, at) + 1)?;
        if bytes[at..].starts_with(JOINT.as_bytes()) {
            return Some(at);
        }
    }
}

/// Byte classes for the scans below: one table lookup a byte instead of a chain of
/// comparisons (the key and token scans were a fifth of the line reader's instructions).
const KEY: u8 = 1;
/// Ends a bare scalar token: blank, `,`, `]`, `#`, `\r`, `\n`.
const TOKEN_END: u8 = 2;
/// A blank: space or tab.
const BLANK: u8 = 4;

static CLASS: [u8; 256] = {
    let mut t = [0u8; 256];
    let mut b = 0;
    while b < 256 {
        let c = b as u8;
        if c.is_ascii_alphanumeric() || c == b'_' || c == b'-' {
            t[b] |= KEY;
        }
        if matches!(c, b' ' | b'\t' | b',' | b']' | b'#' | b'\r' | b'\n') {
            t[b] |= TOKEN_END;
        }
        if matches!(c, b' ' | b'\t') {
            t[b] |= BLANK;
        }
        b += 1;
    }
    t
};

/// Whether byte `i` (below `end`) is of class `class`; `false` at or past `end`.
#[inline]
fn is(bytes: &[u8], i: usize, end: usize, class: u8) -> bool {
    i < end
        && bytes
            .get(i)
            .is_some_and(|&b| CLASS[usize::from(b)] & class != 0)
}

fn skip_ws(bytes: &[u8], mut i: usize, end: usize) -> usize {
    while is(bytes, i, end, BLANK) {
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

/// The rest of a line after a value or header: blanks, then nothing or a comment. Gives the
/// line's end: its `\n`, or `end` (the line's end, or the text's when the caller has not
/// looked for the line break).
fn line_end(bytes: &[u8], from: usize, end: usize) -> Option<usize> {
    let i = skip_ws(bytes, from, end);
    match bytes.get(i) {
        _ if i == end => Some(end),
        Some(b'\n') => Some(i),
        Some(b'\r') if i + 1 == end || bytes.get(i + 1) == Some(&b'\n') => Some(i + 1),
        Some(b'#') => {
            let end = line_break(bytes, i).min(end);
            comment_ok(bytes, i + 1, end).then_some(end)
        }
        _ => None,
    }
}

/// A bare key at `from`: its span and where it ends.
fn bare_key(bytes: &[u8], from: usize, end: usize) -> Option<(Range<usize>, usize)> {
    let mut i = from;
    while is(bytes, i, end, KEY) {
        i += 1;
    }
    (i > from).then_some((from..i, i))
}

/// A blank line, a comment line, or `key = value` (its entry pushed on `out`); gives where
/// the line ends (its `\n`, or the text's length). `end` is the line's end, or the text's
/// length: then the line ends at its first `\n` (every part of a line stops at one). An
/// array's vector comes from `pool` when it has one.
fn line<'a>(
    text: &'a str,
    start: usize,
    end: usize,
    pool: &mut Vec<Vec<Node<'a>>>,
    out: &mut Vec<Entry<'a>>,
) -> Option<usize> {
    let bytes = text.as_bytes();
    let i = skip_ws(bytes, start, end);
    if i == end || bytes[i] == b'\n' {
        return Some(i);
    }
    if bytes[i] == b'\r' && (i + 1 == end || bytes[i + 1] == b'\n') {
        return Some(i + 1);
    }
    if bytes[i] == b'#' {
        let end = line_break(bytes, i).min(end);
        return comment_ok(bytes, i + 1, end).then_some(end);
    }
    let (key_span, after) = bare_key(bytes, i, end)?;
    let eq = skip_ws(bytes, after, end);
    if bytes.get(eq) != Some(&b'=') || eq >= end {
        return None;
    }
    let at = skip_ws(bytes, eq + 1, end);
    let (value, after) = match bytes.get(at) {
        Some(b'[') if at < end => array(text, at, end, pool.pop().unwrap_or_default())?,
        _ => scalar(text, at, end)?,
    };
    let end = line_end(bytes, after, end)?;
    out.push(Entry {
        key: Cow::Borrowed(&text[key_span.clone()]),
        key_span,
        value,
    });
    Some(end)
}

/// [`line`] for a line of the top level (a few lines): its entry, if it has one.
fn line_entry<'a>(
    text: &'a str,
    start: usize,
    end: usize,
    pool: &mut Vec<Vec<Node<'a>>>,
) -> Option<Option<Entry<'a>>> {
    let mut one = Vec::new();
    line(text, start, end, pool, &mut one)?;
    Some(one.pop())
}

/// A one-line array of scalars at `at` (its `[`), trailing comma allowed, its items pushed on
/// `items` (empty).
fn array<'a>(
    text: &'a str,
    at: usize,
    end: usize,
    mut items: Vec<Node<'a>>,
) -> Option<(Node<'a>, usize)> {
    let bytes = text.as_bytes();
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
    while i < end && !is(bytes, i, end, TOKEN_END) {
        i += 1;
    }
    let token = &text[at..i];
    // Numbers (nearly every token) go straight to `number`: not compared with the booleans.
    let value = match token.as_bytes().first() {
        Some(b't') if token == "true" => Value::Bool(true),
        Some(b'f') if token == "false" => Value::Bool(false),
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
    if int_end == b.len() {
        // Up to 18 digits cannot overflow: summed here (nearly every integer of a file).
        if int_end - i <= 18 {
            let n = b[i..]
                .iter()
                .fold(0i64, |n, &d| 10 * n + i64::from(d - b'0'));
            return Some(Value::Int(if b[0] == b'-' { -n } else { n }));
        }
        return t.parse::<i64>().ok().map(Value::Int);
    }
    i = int_end;
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
        let mut items = Vec::with_capacity(joints.count);
        let mut reader = JointReader::new(text, joints);
        while let Some(table) = reader.next_table()? {
            items.push(table.clone());
        }
        assert_eq!(items.len(), joints.count);
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
        let serial = super::super::read::parse_toml_serial(text).ok();
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
        // Tables between and after the joint tables, indented headers, comments and blank
        // lines between tables: each joint ends at the next header of any kind.
        assert!(agrees(
            "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n[expect]\nmobility = 1\n\n  [[joint]]\n# c\nbodies = [2, 3]\n[[joint]]\n[e2]\nx = 1\n[e3]\n[[joint]]\nid = 7\n"
        ));
        assert!(agrees(
            "frame = 1\n[[joint]]\n\t[e]\ny = [1]\n[[joint]]\nbodies = [4, 5]\n"
        ));
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

    /// Every table [`for_each_table`] hands over, cloned, and how it stopped (`Err(None)`: a
    /// decline; `Err(Some(k))`: `f` failed at table `k`, when `fail_at` is `Some(k)`).
    fn tables(text: &str, fail_at: Option<usize>) -> (Vec<Node<'_>>, Result<(), Option<usize>>) {
        let (_, joints) = parse(text).expect("the fast path reads the head");
        let mut seen = Vec::new();
        // A low threshold: the test's file need not have 65,536 joints.
        let stopped = for_each_table_from(text, joints, 2 * BATCH, &mut |t: &Node<'_>| {
            if fail_at == Some(seen.len()) {
                return Err(seen.len());
            }
            seen.push(t.clone());
            Ok(())
        });
        let stopped = stopped.map_err(|s| match s {
            Stopped::Declined => None,
            Stopped::Failed(k) => Some(k),
        });
        (seen, stopped)
    }

    /// The serial reader's tables, and where it declines (its table count then).
    fn serial_tables(text: &str) -> (Vec<Node<'_>>, bool) {
        let (_, joints) = parse(text).expect("the fast path reads the head");
        let mut reader = JointReader::new(text, joints);
        let mut out = Vec::new();
        loop {
            match reader.next_table() {
                Some(Some(t)) => out.push(t.clone()),
                Some(None) => return (out, false),
                None => return (out, true),
            }
        }
    }

    /// Many tables are read on a second thread: the same tables in the same order as the
    /// serial reader, the same decline at the same table, and a stop at the model's error
    /// (without waiting on the reading thread, which may be ahead).
    #[test]
    fn two_threads_read_what_one_reads() {
        let m = crate::generate::random(2500, false, 11).unwrap().0;
        let text = crate::generate::to_toml(&m);
        let (_, joints) = parse(&text).unwrap();
        assert!(joints.count >= 8 * BATCH, "{} joints", joints.count);
        let (serial, declined) = serial_tables(&text);
        assert!(!declined);
        assert_eq!(tables(&text, None), (serial.clone(), Ok(())));
        // The model's error at the first table, inside a batch, at a batch's end, the last.
        for k in [0, 7, BATCH - 1, BATCH, joints.count - 1] {
            let (seen, stopped) = tables(&text, Some(k));
            assert_eq!(stopped, Err(Some(k)));
            assert_eq!(seen[..], serial[..k]);
        }
        // A line the fast path does not read, in the first, a middle and the last table.
        let starts: Vec<usize> = text.match_indices("[[joint]]\n").map(|(i, _)| i).collect();
        for k in [0, BATCH, BATCH + 1, 3 * BATCH - 1, starts.len() - 1] {
            let at = starts[k] + "[[joint]]\n".len();
            let bad = format!("{}x = 'literal'\n{}", &text[..at], &text[at..]);
            let (serial_bad, declined) = serial_tables(&bad);
            assert!(declined);
            assert_eq!(serial_bad.len(), k);
            let (seen, stopped) = tables(&bad, None);
            assert_eq!(stopped, Err(None));
            assert_eq!(seen, serial_bad);
            // The model's error before the decline comes first; after it, the decline.
            if k > 0 {
                assert_eq!(tables(&bad, Some(k - 1)).1, Err(Some(k - 1)));
            }
            assert_eq!(tables(&bad, Some(k + 1)).1, Err(None));
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
