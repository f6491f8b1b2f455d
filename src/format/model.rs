//! From the spanned tree to a validated [`Mechanism`]: every check of format v1, each error
//! located at the key or value it is about.

use super::error::{ErrorKind, Label, LoadError};
use super::tree::{Entry, Lazy, Node, Value};
use crate::joint::{CATALOGUE, JointType};
use crate::mechanism::{
    Body, BodyId, Expect, Geometry, Joint, JointBodies, JointGeometry, JointSpec, Mechanism,
    Second, Space, short_natural_key,
};
use std::borrow::Cow;
use std::collections::hash_map;
use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::fmt::Write as _;
use std::ops::Range;

const TOP_KEYS: &[&str] = &[
    "name",
    "description",
    "space",
    "frame",
    "body",
    "bodies",
    "joint",
    "joints",
    "point",
    "points",
    "bar",
    "bars",
    "expect",
    "precision",
    "$schema",
];
const JOINT_KEYS: &[&str] = &[
    "id", "type", "bodies", "driven", "origin", "origin2", "axis", "axis2", "normal", "pitch",
    "second",
];
const SECOND_KEYS: &[&str] = &["origin", "axis", "axis2", "normal"];
const BODY_KEYS: &[&str] = &["id", "label"];
const POINT_KEYS: &[&str] = &["id", "at"];
const BAR_KEYS: &[&str] = &["id", "points"];

fn label(span: &Range<usize>, text: impl Into<String>) -> Label {
    Label {
        span: span.clone(),
        text: text.into(),
    }
}

fn err(
    kind: ErrorKind,
    message: impl Into<String>,
    span: &Range<usize>,
    text: impl Into<String>,
    help: Option<String>,
) -> LoadError {
    LoadError::new(kind, message, vec![label(span, text)], help)
}

/// The candidate closest to `word`, if close enough to be a plausible typo.
fn nearest<'c>(word: &str, candidates: impl IntoIterator<Item = &'c str>) -> Option<&'c str> {
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

fn wrong_type(node: &Node, expected: &str, what: &str) -> LoadError {
    err(
        ErrorKind::WrongType,
        format!("{what} must be {expected}, not {}", node.value.type_name()),
        &node.span,
        format!("{} here", node.value.type_name()),
        None,
    )
}

fn out_of_range(node: &Node, what: &str) -> LoadError {
    err(
        ErrorKind::NumberOutOfRange,
        format!("{what} is too large a number"),
        &node.span,
        "out of range",
        Some("integers must fit in 64 bits".into()),
    )
}

fn as_map<'n, 'a>(node: &'n Node<'a>, what: &str) -> Result<&'n [Entry<'a>], LoadError> {
    match &node.value {
        Value::Map(es) => Ok(es),
        _ => Err(wrong_type(node, "a table", what)),
    }
}

fn as_seq<'n, 'a>(node: &'n Node<'a>, what: &str) -> Result<&'n [Node<'a>], LoadError> {
    match &node.value {
        Value::Seq(xs) => Ok(xs),
        _ => Err(wrong_type(node, "an array", what)),
    }
}

fn as_str<'n>(node: &'n Node, what: &str) -> Result<&'n str, LoadError> {
    match &node.value {
        Value::Str(s) => Ok(s),
        _ => Err(wrong_type(node, "a string", what)),
    }
}

fn as_int(node: &Node, what: &str) -> Result<i64, LoadError> {
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
fn as_number(node: &Node, what: &str) -> Result<f64, LoadError> {
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
fn as_id(node: &Node, what: &str) -> Result<BodyId, LoadError> {
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
fn check_keys(entries: &[Entry], allowed: &[&str], context: &str) -> Result<(), LoadError> {
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

fn get<'n, 'a>(entries: &'n [Entry<'a>], key: &str) -> Option<&'n Entry<'a>> {
    entries.iter().find(|e| e.key == key)
}

/// The entry under `a` or its alias `b` (not both).
fn get_alias<'n, 'a>(
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

fn required<'n, 'a>(
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

/// Read the whole document.
pub(crate) fn build<'a>(
    mut root: Node<'a>,
    default_name: &str,
    lazy: Lazy<'a>,
) -> Result<Mechanism, LoadError> {
    // The joint lists leave the tree (a placeholder stays), to be read and freed one joint at
    // a time: the largest part of a large file.
    let mut lists: [Option<Value<'a>>; 2] = [None, None];
    if let Value::Map(es) = &mut root.value {
        for e in es.iter_mut() {
            let slot = match e.key.as_ref() {
                "joint" => 0,
                "joints" => 1,
                _ => continue,
            };
            if matches!(e.value.value, Value::Seq(_) | Value::Deferred) {
                lists[slot] = Some(std::mem::replace(&mut e.value.value, Value::Deferred));
            }
        }
    }
    let root = &root;
    let top = as_map(root, "the top level")?;
    if top.is_empty() {
        return Err(empty(root));
    }
    check_keys(top, TOP_KEYS, "top-level")?;
    let name = match get(top, "name") {
        Some(e) => as_str(&e.value, "`name`")?.to_string(),
        None => default_name.to_string(),
    };
    let description = match get(top, "description") {
        Some(e) => Some(as_str(&e.value, "`description`")?.to_string()),
        None => None,
    };
    if let Some(e) = get(top, "$schema") {
        as_str(&e.value, "`$schema`")?;
    }
    let space = match get(top, "space") {
        Some(e) => parse_space(&e.value)?,
        None => Space::Spatial,
    };
    let joints = get_alias(top, "joint", "joints")?;
    let bodies = get_alias(top, "body", "bodies")?;
    let points = get_alias(top, "point", "points")?;
    let bars = get_alias(top, "bar", "bars")?;
    let classic = joints.or(bodies);
    let framework = points.or(bars);
    if let (Some(c), Some(f)) = (classic, framework) {
        return Err(LoadError::new(
            ErrorKind::MixedFramework,
            "joints and a bar-joint framework in one file",
            vec![
                label(&f.key_span, "framework"),
                label(&c.key_span, "joint-and-body description"),
            ],
            Some("describe the mechanism either with `joint`/`body` or with `point`/`bar`".into()),
        ));
    }
    let frame_entry = get(top, "frame").ok_or_else(|| {
        let at = top[0].key_span.clone();
        err(
            ErrorKind::MissingFrame,
            "no `frame`: the fixed body is required",
            &at,
            "the top level has no `frame`",
            Some(
                "add `frame = <body id>` (TOML) or `frame: <body id>` (YAML), e.g. frame = 1"
                    .into(),
            ),
        )
    })?;
    let frame = as_id(&frame_entry.value, "`frame`")?;

    let mut m = if framework.is_some() {
        build_framework(
            top,
            root,
            &name,
            space,
            frame,
            &frame_entry.value,
            points,
            bars,
        )?
    } else {
        let list = joints.and_then(|j| lists[usize::from(j.key != "joint")].take());
        build_joints(
            root,
            &name,
            space,
            frame,
            &frame_entry.value,
            joints.map(|j| (j, list, lazy)),
            bodies,
        )?
    };
    m.description = description;
    if let Some(e) = get(top, "expect") {
        m.expect = parse_expect(&e.value)?;
    }
    if let Some(e) = get(top, "precision") {
        m.precision = Some(parse_precision(&e.value)?);
    }
    Ok(m)
}

/// The `precision` key: how precisely every geometry number is known (±, file units), a
/// geometry number ([`as_number`]: finite, at most [`MAX_GEOMETRY_NUMBER`]) that is >= 0.
fn parse_precision(node: &Node) -> Result<f64, LoadError> {
    let x = as_number(node, "`precision`")?;
    if x < 0.0 {
        return Err(err(
            ErrorKind::NumberOutOfRange,
            format!("`precision` must be a number >= 0, not {x:e}"),
            &node.span,
            "negative",
            Some(
                "`precision` is how precisely the geometry numbers are known (±, in file units), \
                 e.g. precision = 5e-7; leave it out to judge the numbers by their written digits"
                    .into(),
            ),
        ));
    }
    Ok(x)
}

fn empty(root: &Node) -> LoadError {
    err(
        ErrorKind::Empty,
        "the file is empty",
        &(root.span.start..root.span.start),
        "nothing here",
        Some("a mechanism needs at least `frame` and one joint; see docs/format.md".into()),
    )
}

/// A root that is absent (YAML stream without a document).
pub(crate) fn empty_document() -> LoadError {
    empty(&Node {
        span: 0..0,
        value: Value::Null,
    })
}

fn parse_space(node: &Node) -> Result<Space, LoadError> {
    let s = as_str(node, "`space`")?;
    match s.trim().to_ascii_lowercase().as_str() {
        "spatial" => Ok(Space::Spatial),
        "planar" => Ok(Space::Planar),
        "spherical" => Ok(Space::Spherical),
        _ => {
            let names = ["spatial", "planar", "spherical"];
            let help = match nearest(s, names) {
                Some(n) => {
                    format!("did you mean `{n}`? space is one of spatial, planar, spherical")
                }
                None => "space is one of spatial (B = 6), planar (B = 3), spherical (B = 3)".into(),
            };
            Err(err(
                ErrorKind::InvalidSpace,
                format!("invalid space `{s}`"),
                &node.span,
                "not a space",
                Some(help),
            ))
        }
    }
}

fn no_joints(at: &Range<usize>, label_text: &str) -> LoadError {
    err(
        ErrorKind::NoJoints,
        "the mechanism has no joints",
        at,
        label_text,
        Some(
            "add at least one joint: [[joint]] with `type` and `bodies` (or points and bars)"
                .into(),
        ),
    )
}

/// Declared bodies: id -> (label, id span).
type Declared = BTreeMap<BodyId, (Option<String>, Range<usize>)>;

fn parse_bodies(entry: &Entry) -> Result<Declared, LoadError> {
    let mut declared = Declared::new();
    for b in as_seq(&entry.value, "the body list")? {
        let es = as_map(b, "a body")?;
        check_keys(es, BODY_KEYS, "body")?;
        let id_entry = required(es, "id", b, "body")?;
        let id = as_id(&id_entry.value, "a body id")?;
        let label_text = match get(es, "label") {
            Some(e) => Some(as_str(&e.value, "a body label")?.to_string()),
            None => None,
        };
        if let Some((_, first)) = declared.get(&id) {
            return Err(LoadError::new(
                ErrorKind::DuplicateBodyId,
                format!("body `{id}` is declared twice"),
                vec![
                    label(&id_entry.value.span, "declared again here"),
                    label(first, "first declared here"),
                ],
                Some("body ids must be unique".into()),
            ));
        }
        declared.insert(id, (label_text, id_entry.value.span.clone()));
    }
    Ok(declared)
}

fn undeclared<'a>(
    id: &BodyId,
    span: &Range<usize>,
    known: impl Iterator<Item = &'a BodyId>,
    what: &str,
    list: &str,
) -> LoadError {
    let names: Vec<String> = known.map(|b| b.to_string()).collect();
    let text = id.to_string();
    let help = match nearest(&text, names.iter().map(String::as_str)) {
        Some(n) => format!("did you mean `{n}`? {list}: {}", names.join(", ")),
        None => format!("{list}: {}", names.join(", ")),
    };
    err(
        ErrorKind::UndeclaredBody,
        format!("{what} `{id}` is not declared"),
        span,
        "not declared",
        Some(help),
    )
}

fn joint_grade_help(space: Space) -> String {
    let ok: Vec<&str> = CATALOGUE
        .iter()
        .filter(|i| i.kind.valid_in(space))
        .map(|i| i.code)
        .collect();
    format!(
        "a {} mechanism accepts {}; use `space = \"spatial\"` for the others",
        space.name(),
        ok.join(", ")
    )
}

/// Body ids to indices. While every id is a non-negative integer of moderate size (`dense`),
/// an id is its own index and only a bitmap of the ids met is kept: no table lookup per body
/// (random lookups into a table of a million entries were 8 % of reading a 10^6-body file).
/// The first other id switches to the general table, indices in order of first appearance;
/// the renumbering of the indices handed out so far is then left in `renumbered` for the
/// caller.
struct Interner {
    dense: bool,
    /// Dense: bit `i` set once id `i` was met.
    present: Vec<u64>,
    /// Dense: how many ids were met.
    count: usize,
    /// Dense: about how many joints the file has (ids up to `4 * (hint + count + 4096)` stay
    /// dense, so that the bitmap and the tables indexed by id stay proportional to the file).
    hint: usize,
    /// Set once, when the dense numbering is left: old index -> new index (`u32::MAX`: none).
    renumbered: Option<Vec<u32>>,
    /// General: index by small non-negative integer id (`u32::MAX`: none yet).
    small: Vec<u32>,
    map: std::collections::HashMap<BodyId, u32>,
    ids: Vec<BodyId>,
}

impl Interner {
    /// Dense numbering when `dense` (no declared bodies), sized for about `hint` joints.
    fn new(dense: bool, hint: usize) -> Interner {
        Interner {
            dense,
            // Sized for ids up to the joint count (a file's bodies are about that many or
            // fewer): grown by doubling only past it.
            present: if dense {
                vec![0; hint / 64 + 1]
            } else {
                Vec::new()
            },
            count: 0,
            hint,
            renumbered: None,
            small: Vec::new(),
            map: std::collections::HashMap::new(),
            ids: Vec::new(),
        }
    }

    /// How many distinct ids were met.
    fn len(&self) -> usize {
        if self.dense {
            self.count
        } else {
            self.ids.len()
        }
    }

    /// The id of index `k`.
    fn id(&self, k: usize) -> BodyId {
        if self.dense {
            BodyId::Int(k as i64)
        } else {
            self.ids[k].clone()
        }
    }

    /// The index of `id`, added if new.
    #[inline]
    fn get(&mut self, id: BodyId) -> usize {
        // The common case inline (a dense id within the bitmap); the rest in `get_slow`.
        if self.dense
            && let BodyId::Int(i) = id
            && let Ok(i) = usize::try_from(i)
            && i / 4 < self.hint + self.count + 4096
            && let Some(word) = self.present.get_mut(i / 64)
        {
            let bit = 1u64 << (i % 64);
            if *word & bit == 0 {
                *word |= bit;
                self.count += 1;
            }
            return i;
        }
        self.get_slow(id)
    }

    /// [`Interner::get`] in every case.
    #[inline(never)]
    fn get_slow(&mut self, id: BodyId) -> usize {
        if self.dense {
            if let BodyId::Int(i) = id
                && let Ok(i) = usize::try_from(i)
                && i / 4 < self.hint + self.count + 4096
            {
                let (w, bit) = (i / 64, 1u64 << (i % 64));
                if w >= self.present.len() {
                    let len = (w + 1).max(2 * self.present.len());
                    self.present.resize(len, 0);
                }
                if self.present[w] & bit == 0 {
                    self.present[w] |= bit;
                    self.count += 1;
                }
                return i;
            }
            self.leave_dense();
        }
        let next = self.ids.len() as u32;
        if let BodyId::Int(i) = id
            && let Ok(i) = usize::try_from(i)
            && (i < self.small.len() || i < 8 * (self.ids.len() + 4096))
        {
            if i >= self.small.len() {
                let len = (i + 1).max(2 * self.small.len());
                self.small.resize(len, u32::MAX);
            }
            if self.small[i] == u32::MAX {
                // An integer first met above the small range may come back within it.
                self.small[i] = match self.map.get(&id) {
                    Some(&k) => k,
                    None => {
                        self.ids.push(id);
                        next
                    }
                };
            }
            return self.small[i] as usize;
        }
        // Not in the small range now, so never in it before (the range only grows).
        if let Some(&k) = self.map.get(&id) {
            return k as usize;
        }
        self.map.insert(id.clone(), next);
        self.ids.push(id);
        next as usize
    }

    /// Dense ids met, ascending.
    fn dense_ids(&self) -> Vec<usize> {
        let mut out = Vec::with_capacity(self.count);
        for (w, &word) in self.present.iter().enumerate() {
            let mut x = word;
            while x != 0 {
                out.push(64 * w + x.trailing_zeros() as usize);
                x &= x - 1;
            }
        }
        out
    }

    /// To the general table: the ids met so far numbered in ascending order (the small table
    /// is that renumbering itself).
    fn leave_dense(&mut self) {
        let met = self.dense_ids();
        let mut renumber = vec![u32::MAX; met.last().map_or(0, |&i| i + 1)];
        for (k, &i) in met.iter().enumerate() {
            renumber[i] = k as u32;
            self.ids.push(BodyId::Int(i as i64));
        }
        self.small = renumber.clone();
        self.renumbered = Some(renumber);
        self.present = Vec::new();
        self.dense = false;
    }
}

/// Body lists up to this long are checked for a repeated body by a scan.
const SCAN_BODIES: usize = 16;

/// A joint list: its entry (for locations), its value taken out of the tree, and where its
/// deferred items come from.
type JointList<'e, 'a> = (&'e Entry<'a>, Option<Value<'a>>, Lazy<'a>);

fn build_joints<'a>(
    root: &Node<'a>,
    name: &str,
    space: Space,
    frame: BodyId,
    frame_node: &Node<'a>,
    joints: Option<JointList<'_, 'a>>,
    bodies: Option<&Entry<'a>>,
) -> Result<Mechanism, LoadError> {
    let declared = bodies.map(parse_bodies).transpose()?;
    if let Some(d) = &declared
        && !d.contains_key(&frame)
    {
        return Err(undeclared(
            &frame,
            &frame_node.span,
            d.keys(),
            "frame",
            "declared bodies",
        ));
    }
    let Some((joints, list, lazy)) = joints else {
        let at = root.span.start..root.span.start;
        return Err(no_joints(&at, "no `joint` list in this file"));
    };
    let list = match list {
        Some(list) => list,
        None => {
            as_seq(&joints.value, "the joint list")?;
            return Err(no_joints(&joints.value.span, "empty list"));
        }
    };
    if matches!(&list, Value::Seq(items) if items.is_empty()) {
        return Err(no_joints(&joints.value.span, "empty list"));
    }
    // Bodies: the declared ones first (so that `index < n_declared` means declared), then the
    // frame, then in order of appearance.
    let hint = lazy.len_hint(&list);
    let mut interner = Interner::new(declared.is_none(), hint);
    let mut labels: Vec<Option<String>> = Vec::new();
    let n_declared = match declared {
        Some(d) => {
            for (id, (label, _)) in d {
                interner.get(id);
                labels.push(label);
            }
            Some(interner.len())
        }
        None => None,
    };
    let mut frame_index = interner.get(frame.clone());
    // A frame that leaves the dense numbering: no index was handed out before it.
    interner.renumbered = None;
    let mut read: Vec<Joint> = Vec::with_capacity(hint);
    // The span that locates each joint in later errors.
    // Not kept when the error would be thrown away (`Lazy::errors_discarded`): 16 bytes a
    // joint, written for every joint of a large file and needed only by the error.
    let keep_spans = !lazy.errors_discarded();
    let mut joint_spans: Vec<Range<usize>> = Vec::with_capacity(if keep_spans { hint } else { 0 });
    // Explicit ids and where each is: a hash map (looked up once per joint below; the
    // standard keyed hasher, so crafted ids cannot make it quadratic), keys borrowed from the
    // text where the reader could.
    let mut explicit: HashMap<Cow<'a, str>, Range<usize>> = HashMap::new();
    let mut any_name = false;
    // Per body: the last joint of more than SCAN_BODIES bodies that named it, and where.
    let mut seen: Vec<(u32, u32)> = Vec::new();
    // Per joint: whether its id is the default `a-b` (suffixed below).
    let mut defaulted: Vec<bool> = Vec::with_capacity(read.capacity());
    let mut ids_buf: Vec<usize> = Vec::new();
    lazy.for_each(list, &mut |j: &Node<'a>| {
        let es = as_map(j, "a joint")?;
        // One pass over the keys: the entries looked up below, and whether any is unknown
        // (then `check_keys` names it, as it would have first).
        let (mut type_entry, mut bodies_entry, mut id_entry, mut driven_entry, mut second_entry) =
            (None, None, None, None, None);
        let (mut unknown, mut any_geometry) = (false, false);
        for e in es {
            match e.key.as_ref() {
                "type" => type_entry = Some(e),
                "bodies" => bodies_entry = Some(e),
                "id" => id_entry = Some(e),
                "driven" => driven_entry = Some(e),
                "second" => second_entry = Some(e),
                "origin" | "origin2" | "axis" | "axis2" | "normal" | "pitch" => any_geometry = true,
                _ => unknown = true,
            }
        }
        if unknown {
            check_keys(es, JOINT_KEYS, "joint")?;
        }
        // Type.
        let type_entry = match type_entry {
            Some(e) => e,
            None => required(es, "type", j, "joint")?,
        };
        let type_text = as_str(&type_entry.value, "a joint `type`")?;
        // A code as written (`R`, `SPSP`) first: `JointType::parse` normalizes every spelling.
        let kind = exact_code(type_text).or_else(|| JointType::parse(type_text)).ok_or_else(|| {
            err(
                ErrorKind::UnknownJointType,
                format!("unknown joint type `{type_text}`"),
                &type_entry.value.span,
                "not a joint type",
                Some(match JointType::suggest(type_text) {
                    Some(c) => format!(
                        "did you mean `{c}` ({})? `mbsa joints` lists every code and name",
                        c_name(c)
                    ),
                    None => "use a code such as R, P, C, U, S or a long name (revolute, ...); `mbsa joints` lists them".into(),
                }),
            )
        })?;
        if !kind.valid_in(space) {
            return Err(err(
                ErrorKind::JointNotValidInSpace,
                format!(
                    "joint type {} ({}) cannot be used in a {} mechanism",
                    kind.code(),
                    c_name(kind.code()),
                    space.name()
                ),
                &type_entry.value.span,
                format!("not a {} joint", space.name()),
                Some(joint_grade_help(space)),
            ));
        }
        // Bodies.
        let bodies_entry = match bodies_entry {
            Some(e) => e,
            None => required(es, "bodies", j, "joint")?,
        };
        let items = as_seq(&bodies_entry.value, "a joint's `bodies`")?;
        if items.len() < 2 {
            return Err(err(
                ErrorKind::TooFewBodies,
                format!(
                    "a joint joins at least two bodies; this one names {}",
                    items.len()
                ),
                &bodies_entry.value.span,
                "fewer than two bodies",
                Some("write both bodies, e.g. bodies = [1, 2]".into()),
            ));
        }
        // One buffer for every joint: a binary joint keeps its two bodies inline.
        let ids = &mut ids_buf;
        ids.clear();
        // A body named twice in one joint: a scan for short lists, else a mark per body (the
        // joint's number and the item's position), so that one joint of n bodies is linear.
        let stamp = read.len() as u32;
        // The default id `a-b` when no `id` is given, written while the ids are at hand.
        // 24 bytes: the smallest heap block holds them anyway, and `a-b#n` then fits at once.
        let mut base = if id_entry.is_none() {
            String::with_capacity(24)
        } else {
            String::new()
        };
        for (i, b) in items.iter().enumerate() {
            let id = as_id(b, "a body id")?;
            any_name |= matches!(id, BodyId::Name(_));
            if id_entry.is_none() {
                push_id(&mut base, i, &id);
            }
            let k = interner.get(id);
            if let Some(renumber) = interner.renumbered.take() {
                // Out of the dense numbering (once): the indices handed out so far follow.
                let to = |k: &mut usize| *k = renumber[*k] as usize;
                read.iter_mut().flat_map(|j| j.bodies.iter_mut()).for_each(to);
                ids.iter_mut().for_each(to);
                to(&mut frame_index);
                seen.clear();
                if items.len() > SCAN_BODIES {
                    seen.resize(interner.len(), (u32::MAX, 0));
                    for (at, &x) in ids.iter().enumerate() {
                        seen[x] = (stamp, at as u32);
                    }
                }
            }
            let again = if items.len() <= SCAN_BODIES {
                ids.iter().position(|x| *x == k)
            } else {
                if seen.len() <= k {
                    seen.resize(interner.len().max(k + 1).max(2 * seen.len()), (u32::MAX, 0));
                }
                let (joint, at) = seen[k];
                seen[k] = (stamp, i as u32);
                (joint == stamp).then_some(at as usize)
            };
            if let Some(first) = again {
                return Err(LoadError::new(
                    ErrorKind::RepeatedBody,
                    format!("body `{}` appears twice in one joint", interner.id(k)),
                    vec![
                        label(&b.span, "again here"),
                        label(&items[first].span, "first here"),
                    ],
                    Some("a joint joins distinct bodies".into()),
                ));
            }
            if let Some(n) = n_declared
                && k >= n
            {
                return Err(undeclared(
                    &interner.ids[k],
                    &items[i].span,
                    interner.ids[..n].iter(),
                    "body",
                    "declared bodies",
                ));
            }
            ids.push(k);
        }
        // Driven DOF.
        let max = u32::from(kind.grade()) * (ids.len() as u32 - 1);
        let driven = match driven_entry {
            None => 0,
            Some(e) => {
                let n = match as_int(&e.value, "`driven`") {
                    Err(er) if er.kind() == ErrorKind::NumberOutOfRange => i64::MAX,
                    r => r?,
                };
                if n < 0 || n > i64::from(max) {
                    return Err(err(
                        ErrorKind::DrivenOutOfRange,
                        format!(
                            "`driven` must be between 0 and {max} for this {} joint, not {}",
                            kind.code(),
                            match &e.value.value {
                                Value::BigInt(s) => s.clone(),
                                _ => n.to_string(),
                            }
                        ),
                        &e.value.span,
                        "out of range",
                        Some(format!(
                            "{} has {} DOF{}",
                            kind.code(),
                            kind.grade(),
                            if ids.len() > 2 {
                                format!(" per pair, {max} for its {} pairs", ids.len() - 1)
                            } else {
                                String::new()
                            }
                        )),
                    ));
                }
                n as u32
            }
        };
        // Id (an explicit id is never empty).
        defaulted.push(id_entry.is_none());
        let id = match id_entry {
            None => base,
            Some(e) => {
                let id: Cow<'a, str> = match &e.value.value {
                    Value::Int(i) => Cow::Owned(i.to_string()),
                    Value::Str(Cow::Borrowed(s)) => Cow::Borrowed(*s),
                    _ => Cow::Owned(as_str(&e.value, "a joint `id`")?.to_string()),
                };
                if id.trim().is_empty() {
                    return Err(err(
                        ErrorKind::EmptyId,
                        "a joint `id` is empty",
                        &e.value.span,
                        "empty id",
                        Some("omit `id` for the default `<a>-<b>`".into()),
                    ));
                }
                let owned = id.to_string();
                match explicit.entry(id) {
                    hash_map::Entry::Occupied(first) => {
                        return Err(LoadError::new(
                            ErrorKind::DuplicateJointId,
                            format!("two joints have the id `{owned}`"),
                            vec![
                                label(&e.value.span, "again here"),
                                label(first.get(), "first here"),
                            ],
                            Some(
                                "joint ids must be unique; `--inputs` and reports name joints by id"
                                    .into(),
                            ),
                        ));
                    }
                    hash_map::Entry::Vacant(v) => {
                        v.insert(e.value.span.clone());
                    }
                }
                owned
            }
        };
        // Most large files give no geometry: no `Geometry` built, moved and compared then.
        let geometry = if any_geometry || second_entry.is_some() {
            let mut geometry = parse_geometry(es, space)?;
            if let Some(e) = second_entry {
                geometry.second = Some(parse_second(e, kind, space, ids.len())?);
            }
            geometry.into()
        } else {
            JointGeometry::default()
        };
        if keep_spans {
            joint_spans.push(es.first().map_or(j.span.clone(), |e| e.key_span.clone()));
        }
        read.push(Joint {
            id,
            kind,
            bodies: JointBodies::from(&ids[..]),
            driven,
            geometry,
        });
        Ok(())
    })?;
    if !read.iter().any(|j| j.bodies.contains(&frame_index)) {
        return Err(frame_not_in_joint(&frame, frame_node));
    }
    // The joints' natural order, when the default ids give it at once (see below).
    let mut in_order: Option<Vec<u32>> = None;
    // Default ids: `a-b`, suffixed `#2`, `#3`... when taken (by an explicit id too). Without
    // explicit ids, the n-th joint of a body list gets `#n` (as `Mechanism::from_parts` does),
    // and a default that another joint's body list gives too is an error naming both.
    // The spans locate only a clash of default ids, which integer bodies never give: freed
    // before the sorts below.
    if !any_name {
        joint_spans = Vec::new();
    }
    if explicit.is_empty() {
        let by_list = default_joint_ids(&mut read, &interner, &joint_spans, !any_name)?;
        // Every id `a-b` or `a-b#n` with integer bodies numbered by their ids: the order by
        // body list (then position, the suffix) is the natural order of the ids.
        if interner.dense {
            in_order = by_list;
        }
    } else if !any_name {
        // Integer bodies: a default `a-b` or `a-b#n` has no other `#`, so defaults of two body
        // lists never meet; the k-th default of a list takes the k-th suffix not taken by an
        // explicit id (as the general loop below, without a set of every id).
        let merge = interner.dense;
        let ByList {
            order,
            same,
            pairs_only,
            pair_keys,
        } = by_body_list(&read, |k| defaulted[k], merge);
        let maybe = MaybeTaken::new(explicit.keys().map(|id| id.as_ref()), explicit.len());
        // With integer bodies numbered by their ids and two bodies a default, the defaults in
        // `order` are in natural order already: the suffix each took is kept, and the natural
        // order is a merge with the explicit ids (no key parsed back from 10^6 id texts).
        let mut suffixes: Option<Vec<u32>> =
            (merge && pairs_only).then(|| Vec::with_capacity(order.len()));
        let mut k = 0;
        while k < order.len() {
            let mut n = 1i64;
            while k < order.len() && (n == 1 || same[k]) {
                let j = &mut read[order[k] as usize];
                let base = j.id.len();
                loop {
                    j.id.truncate(base);
                    if n > 1 {
                        j.id.push('#');
                        push_int(&mut j.id, n);
                    }
                    n += 1;
                    if !(maybe.may_hold(&j.id) && explicit.contains_key(j.id.as_str())) {
                        break;
                    }
                }
                if let Some(s) = &mut suffixes {
                    match u32::try_from(n - 1) {
                        Ok(n) => s.push(n),
                        Err(_) => suffixes = None,
                    }
                }
                k += 1;
            }
        }
        if let Some(suffixes) = suffixes {
            in_order = merged_natural_order(&read, &order, &pair_keys, &suffixes, |k| defaulted[k]);
        }
    } else {
        let mut taken: HashSet<String> = explicit.into_keys().map(Cow::into_owned).collect();
        for (j, _) in read.iter_mut().zip(&defaulted).filter(|(_, d)| **d) {
            {
                let base = std::mem::take(&mut j.id);
                let mut id = base.clone();
                let mut n = 1;
                while taken.contains(&id) {
                    n += 1;
                    id = format!("{base}#{n}");
                }
                taken.insert(id.clone());
                j.id = id;
            }
        }
    }
    drop(joint_spans);
    // Bodies sorted by id; the joints' indices follow.
    if interner.dense {
        // The ids are the indices: ascending already; a contiguous run needs no table.
        let met = interner.dense_ids();
        let (lo, hi) = (
            met.first().copied().unwrap_or(0),
            met.last().copied().unwrap_or(0),
        );
        let bodies: Vec<Body> = met
            .iter()
            .map(|&i| Body {
                id: BodyId::Int(i as i64),
                label: None,
            })
            .collect();
        let frame = if hi - lo + 1 == met.len() {
            if lo > 0 {
                // Plain loops: a `flat_map` over the joints' bodies showed in profiles.
                for j in &mut read {
                    for b in j.bodies.iter_mut() {
                        *b -= lo;
                    }
                }
            }
            frame_index - lo
        } else {
            let mut rank = vec![0u32; hi + 1];
            for (r, &i) in met.iter().enumerate() {
                rank[i] = r as u32;
            }
            for j in &mut read {
                for b in j.bodies.iter_mut() {
                    *b = rank[*b] as usize;
                }
            }
            rank[frame_index] as usize
        };
        drop(met);
        return Ok(match in_order {
            Some(order) => {
                Mechanism::from_indexed_in_order(name, space, frame, bodies, read, order)
            }
            None => Mechanism::from_indexed(name, space, frame, bodies, read),
        });
    }
    let Interner { ids, .. } = interner;
    let order: Vec<u32> = if ids.iter().all(|b| matches!(b, BodyId::Int(_))) {
        let mut keyed: Vec<(i64, u32)> = ids
            .iter()
            .enumerate()
            .map(|(k, b)| (if let BodyId::Int(i) = b { *i } else { 0 }, k as u32))
            .collect();
        keyed.sort_unstable();
        keyed.into_iter().map(|(_, k)| k).collect()
    } else {
        let mut order: Vec<u32> = (0..ids.len() as u32).collect();
        order.sort_unstable_by(|&a, &b| ids[a as usize].cmp(&ids[b as usize]));
        order
    };
    let mut rank = vec![0usize; ids.len()];
    for (r, &k) in order.iter().enumerate() {
        rank[k as usize] = r;
    }
    labels.resize(ids.len(), None);
    let mut ids: Vec<Option<BodyId>> = ids.into_iter().map(Some).collect();
    let bodies: Vec<Body> = order
        .iter()
        .map(|&k| Body {
            id: ids[k as usize].take().unwrap_or(BodyId::Int(0)),
            label: labels[k as usize].take(),
        })
        .collect();
    drop(ids);
    for j in &mut read {
        for b in &mut j.bodies {
            *b = rank[*b];
        }
    }
    Ok(Mechanism::from_indexed(
        name,
        space,
        rank[frame_index],
        bodies,
        read,
    ))
}

/// A one-hash Bloom filter over a set of ids: most default joint ids are no explicit id, and
/// one bit answers that without hashing them with the map's keyed (and slower) hasher. Its
/// hash is not keyed, but crafted ids can only make it answer "maybe" (the map lookup it
/// saves), never a wrong "no".
struct MaybeTaken {
    bits: Vec<u64>,
    /// 64 minus the number of index bits.
    shift: u32,
}

impl MaybeTaken {
    /// The filter of `ids` (`count` of them): 16 bits per id, a "maybe" for about one id in 16
    /// that is not in the set.
    fn new<'s>(ids: impl Iterator<Item = &'s str>, count: usize) -> MaybeTaken {
        let bits = count
            .saturating_mul(16)
            .min(1 << 40)
            .next_power_of_two()
            .max(64);
        let mut f = MaybeTaken {
            bits: vec![0; bits / 64],
            shift: 64 - bits.trailing_zeros(),
        };
        for id in ids {
            let i = f.index(id);
            f.bits[i / 64] |= 1 << (i % 64);
        }
        f
    }

    fn index(&self, id: &str) -> usize {
        // Eight bytes a step, mixed by a multiplication; the high bits index the table.
        let mut h = id.len() as u64;
        for c in id.as_bytes().chunks(8) {
            // The chunk's bytes little-endian, zero-padded (a loop: a copy call for a few
            // bytes, once per default id of a large file, showed in profiles).
            let w = c
                .iter()
                .enumerate()
                .fold(0u64, |w, (k, &b)| w | u64::from(b) << (8 * k));
            h = (h.rotate_left(5) ^ w).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
        (h >> self.shift) as usize
    }

    /// Whether `id` may be in the set (`false`: it is not).
    fn may_hold(&self, id: &str) -> bool {
        let i = self.index(id);
        self.bits[i / 64] & (1 << (i % 64)) != 0
    }
}

/// `a-b-c` for a joint's body list.
fn joined_ids<'b>(bodies: impl IntoIterator<Item = &'b BodyId>) -> String {
    let mut base = String::new();
    for (i, b) in bodies.into_iter().enumerate() {
        push_id(&mut base, i, b);
    }
    base
}

/// Append the `i`-th id of a joint's default id `a-b-...`.
fn push_id(out: &mut String, i: usize, b: &BodyId) {
    if i > 0 {
        out.push('-');
    }
    match b {
        // Integers by hand: the formatting machinery, a million times, showed in profiles.
        BodyId::Int(n) => push_int(out, *n),
        BodyId::Name(s) => out.push_str(s),
    }
}

/// `00` to `99`, two digits an entry.
const PAIRS: &str = "0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// Append the decimal digits of `n` (as `n.to_string()`).
pub(crate) fn push_int(out: &mut String, n: i64) {
    // Two digits a step, least significant first (half the divisions; body ids have about
    // six digits), then written most significant first as slices of `PAIRS`: no check of
    // the digits as UTF-8 (`from_utf8` of a few bytes cost more than making them).
    let mut pairs = [0u8; 10];
    let mut k = 0;
    let mut m = n.unsigned_abs();
    while m >= 100 {
        pairs[k] = (m % 100) as u8;
        m /= 100;
        k += 1;
    }
    if n < 0 {
        out.push('-');
    }
    // `m` < 100: one digit or two.
    let top = usize::try_from(m).unwrap_or_default();
    out.push_str(&PAIRS[2 * top + usize::from(top < 10)..2 * top + 2]);
    for &p in pairs[..k].iter().rev() {
        let p = usize::from(p);
        out.push_str(&PAIRS[2 * p..2 * p + 2]);
    }
}

/// The positions of the joints `keep` selects, sorted by body list, then by position: equal
/// lists next to each other, in file order; and for each whether its list is the one before
/// it. Two-body lists (nearly all) come first, sorted and compared by a packed key (not by
/// their vectors: a million scattered reads), then the others, by list; `pairs_only` when
/// there are no others.
fn by_body_list(joints: &[Joint], keep: impl Fn(usize) -> bool, with_keys: bool) -> ByList {
    // Sized for every joint (a vector of 10^6 pairs grown by doubling copies itself about
    // once more, and holds both copies at each step).
    let mut pairs: Vec<(u64, u32)> = Vec::with_capacity(joints.len());
    let mut others: Vec<u32> = Vec::new();
    for (k, j) in joints.iter().enumerate().filter(|(k, _)| keep(*k)) {
        match j.bodies[..] {
            [a, b] if a <= u32::MAX as usize && b <= u32::MAX as usize => {
                pairs.push((((a as u64) << 32) | b as u64, k as u32));
            }
            _ => others.push(k as u32),
        }
    }
    pairs.sort_unstable();
    others.sort_unstable_by(|&a, &b| {
        joints[a as usize]
            .bodies
            .cmp(&joints[b as usize].bodies)
            .then(a.cmp(&b))
    });
    let mut same = Vec::with_capacity(pairs.len() + others.len());
    same.extend((0..pairs.len()).map(|w| w > 0 && pairs[w - 1].0 == pairs[w].0));
    same.extend((0..others.len()).map(|w| {
        w > 0 && joints[others[w - 1] as usize].bodies == joints[others[w] as usize].bodies
    }));
    let pairs_only = others.is_empty();
    let mut order: Vec<u32> = Vec::with_capacity(pairs.len() + others.len());
    order.extend(pairs.iter().map(|&(_, k)| k));
    let pair_keys = if with_keys {
        pairs.iter().map(|&(key, _)| key).collect()
    } else {
        Vec::new()
    };
    drop(pairs);
    order.extend(others);
    ByList {
        order,
        same,
        pairs_only,
        pair_keys,
    }
}

/// The joints' natural order (as [`Mechanism::from_indexed`] sorts them) when every default
/// id is `a-b` or `a-b#s` of two integer bodies numbered by their ids, listed in natural order
/// by `order` (positions of the joints `defaulted` selects) with their bodies `pair_keys`
/// (`a << 32 | b`, from [`by_body_list`]) and their suffixes `s` (1: none),
/// and every explicit id is a short numeric id (`mechanism::short_natural_key`): the explicit
/// ids sorted by that key, then merged with the defaults' keys, made from the bodies. `None`
/// otherwise (the caller sorts every id). The ids are distinct, so the order is the sort's.
fn merged_natural_order(
    read: &[Joint],
    order: &[u32],
    pair_keys: &[u64],
    suffixes: &[u32],
    defaulted: impl Fn(usize) -> bool,
) -> Option<Vec<u32>> {
    if pair_keys.len() != order.len() || suffixes.len() != order.len() {
        return None;
    }
    let mut buf = Vec::with_capacity(8);
    let mut explicit: Vec<([u64; 3], u32)> = Vec::with_capacity(read.len() - order.len());
    for (k, j) in read.iter().enumerate().filter(|(k, _)| !defaulted(*k)) {
        explicit.push((short_natural_key(&j.id, &mut buf)?, k as u32));
    }
    explicit.sort_unstable();
    let mut merged = Vec::with_capacity(read.len());
    let mut rest = explicit.iter().peekable();
    for ((&k, &s), &pair) in order.iter().zip(suffixes).zip(pair_keys) {
        // The key of `a-b` / `a-b#s`: a first, `-` rank 2 above b, `#` rank 1 above s (as
        // `short_natural_key` packs the tokens; a and b below 2^32 here).
        let (a, b) = (pair >> 32, pair & u64::from(u32::MAX));
        let key = [
            a,
            (2 << 56) | b,
            if s > 1 { (1 << 56) | u64::from(s) } else { 0 },
        ];
        while let Some(&&(e, i)) = rest.peek()
            && (e, i) < (key, k)
        {
            merged.push(i);
            rest.next();
        }
        merged.push(k);
    }
    merged.extend(rest.map(|&(_, i)| i));
    Some(merged)
}

/// Joint positions by body list ([`by_body_list`]).
struct ByList {
    order: Vec<u32>,
    same: Vec<bool>,
    pairs_only: bool,
    /// When asked for: the two-body lists in `order`'s order (first `<< 32 |` second), so
    /// that they are read in order, not from the joints at random.
    pair_keys: Vec<u64>,
}

/// Default ids when no joint has an explicit one: the n-th joint of a body list `a-b` gets
/// `a-b#n` (the first plain `a-b`). A default that two joints would get (the second `[1, 2]`
/// and a `[1, "2#2"]` both give `1-2#2`) is an error naming both. With integer ids only, the
/// defaults are distinct by construction (`a-b` reads back into its list; no `#` in it), and
/// that check is skipped. Gives the joints sorted by body list when every joint has two
/// bodies (with bodies numbered by their integer ids, that is the natural order of the ids).
fn default_joint_ids(
    joints: &mut [Joint],
    names: &Interner,
    spans: &[Range<usize>],
    all_integers: bool,
) -> Result<Option<Vec<u32>>, LoadError> {
    // The rank of each joint among the joints of its body list (1 for the first): joints
    // sorted by body list, then by position (a sort, not a hash map: no hash flooding). The
    // joints hold their base `a-b` already (written as they were read); only the repeated
    // lists get a suffix.
    let by_list = by_body_list(joints, |_| true, false);
    let mut n = 1u32;
    for (&k, &same) in by_list.order.iter().zip(&by_list.same) {
        n = if same { n + 1 } else { 1 };
        if n > 1 {
            let _ = write!(joints[k as usize].id, "#{n}");
        }
    }
    if !all_integers {
        let mut owner: std::collections::HashMap<&str, usize> =
            std::collections::HashMap::with_capacity(joints.len());
        for (k, j) in joints.iter().enumerate() {
            let id = j.id.as_str();
            if let Some(&first) = owner.get(id) {
                let (a, b) = (first.min(k), first.max(k));
                let list = |i: usize| {
                    let ids: Vec<BodyId> = joints[i].bodies.iter().map(|&k| names.id(k)).collect();
                    joined_ids(&ids)
                };
                return Err(LoadError::new(
                    ErrorKind::DuplicateJointId,
                    format!(
                        "two joints get the default id `{id}`: joint {} (bodies {}) and joint {} (bodies {})",
                        a + 1,
                        list(a),
                        b + 1,
                        list(b)
                    ),
                    // No spans: the error is thrown away (see `Lazy::errors_discarded`).
                    vec![
                        label(&spans.get(a).cloned().unwrap_or_default(), format!("joint {} gets `{id}`", a + 1)),
                        label(&spans.get(b).cloned().unwrap_or_default(), format!("joint {} gets `{id}` too", b + 1)),
                    ],
                    Some(
                        "give one of them an explicit `id`; `--inputs` and reports name joints by id"
                            .into(),
                    ),
                ));
            }
            owner.insert(id, k);
        }
    }
    Ok(by_list.pairs_only.then_some(by_list.order))
}

/// The joint type whose code is exactly `text` (as [`JointType::parse`] reads it).
fn exact_code(text: &str) -> Option<JointType> {
    // Codes are 1 to 4 bytes: compared as one packed integer each (a call to compare bytes
    // per catalogue entry, a million joints over, showed in profiles).
    let key = packed_code(text.as_bytes())?;
    CODE_KEYS
        .iter()
        .position(|&k| k == key)
        .and_then(|i| CATALOGUE.get(i))
        .map(|c| c.kind)
}

/// The bytes of a code of 1 to 4 bytes in one integer, its length in the top byte (`None`
/// for other lengths).
const fn packed_code(b: &[u8]) -> Option<u64> {
    if b.is_empty() || b.len() > 4 {
        return None;
    }
    let mut key = (b.len() as u64) << 32;
    let mut i = 0;
    while i < b.len() {
        key |= (b[i] as u64) << (8 * i);
        i += 1;
    }
    Some(key)
}

/// [`packed_code`] of each catalogue code, in catalogue order.
const CODE_KEYS: [u64; CATALOGUE.len()] = {
    let mut keys = [u64::MAX; CATALOGUE.len()];
    let mut i = 0;
    while i < CATALOGUE.len() {
        if let Some(k) = packed_code(CATALOGUE[i].code.as_bytes()) {
            keys[i] = k;
        }
        i += 1;
    }
    keys
};

fn c_name(code: &str) -> &'static str {
    CATALOGUE
        .iter()
        .find(|i| i.code == code)
        .and_then(|i| i.names.first().copied())
        .unwrap_or("")
}

fn frame_not_in_joint(frame: &BodyId, frame_node: &Node) -> LoadError {
    err(
        ErrorKind::FrameNotInJoint,
        format!("the frame `{frame}` is not joined to anything"),
        &frame_node.span,
        "no joint names this body",
        Some("the frame must appear in the `bodies` of at least one joint".into()),
    )
}

/// A coordinate array: 3 numbers, or 2 in a planar mechanism when `planar2` (z = 0).
fn parse_vector(e: &Entry, space: Space, axis: bool) -> Result<[f64; 3], LoadError> {
    let items = as_seq(&e.value, &format!("`{}`", e.key))?;
    let planar = space == Space::Planar;
    if !(items.len() == 3 || (planar && items.len() == 2)) {
        let want = if planar {
            "[x, y] or [x, y, z]"
        } else {
            "[x, y, z]"
        };
        return Err(err(
            ErrorKind::GeometryLength,
            format!(
                "`{}` must have {} coordinates, not {}",
                e.key,
                if planar { "2 or 3" } else { "3" },
                items.len()
            ),
            &e.value.span,
            format!("{} numbers", items.len()),
            Some(format!("write `{}` as {want}", e.key)),
        ));
    }
    let mut v = [0.0; 3];
    for (i, x) in items.iter().enumerate() {
        v[i] = as_number(x, &format!("a coordinate of `{}`", e.key))?;
    }
    if axis && v.iter().map(|x| x * x).sum::<f64>().sqrt() < 1e-12 {
        return Err(err(
            ErrorKind::ZeroAxis,
            format!("`{}` is the zero vector", e.key),
            &e.value.span,
            "zero length",
            Some("an axis or normal needs a direction, e.g. [0, 0, 1]".into()),
        ));
    }
    Ok(v)
}

fn parse_geometry(es: &[Entry], space: Space) -> Result<Geometry, LoadError> {
    let mut g = Geometry::default();
    for e in es {
        match e.key.as_ref() {
            "origin" => g.origin = Some(parse_vector(e, space, false)?),
            "origin2" => g.origin2 = Some(parse_vector(e, space, false)?),
            "axis" => g.axis = Some(parse_vector(e, space, true)?),
            "axis2" => g.axis2 = Some(parse_vector(e, space, true)?),
            "normal" => g.normal = Some(parse_vector(e, space, true)?),
            "pitch" => g.pitch = Some(as_number(&e.value, "`pitch`")?),
            _ => {}
        }
    }
    Ok(g)
}

/// `second = { origin = [...], axis = [...] }`: the joint as carried by its second body at a
/// configuration that is not closed. Only the features the kind's second body carries
/// ([`Second::fields`]); not on a multiple joint.
fn parse_second(
    e: &Entry,
    kind: JointType,
    space: Space,
    bodies: usize,
) -> Result<Box<Second>, LoadError> {
    let es = as_map(&e.value, "`second`")?;
    check_keys(es, SECOND_KEYS, "`second`")?;
    let fields = Second::fields(kind, space);
    let not_here = |span: &Range<usize>, message: String, text: &str, help: String| {
        err(
            ErrorKind::SecondNotApplicable,
            message,
            span,
            text,
            Some(help),
        )
    };
    if bodies > 2 {
        return Err(not_here(
            &e.key_span,
            format!("a multiple joint ({bodies} bodies) has no `second` geometry"),
            "not on a multiple joint",
            "split it into binary joints to give each its second body's geometry".into(),
        ));
    }
    if fields.is_empty() {
        return Err(not_here(
            &e.key_span,
            format!(
                "joint type {} ({}) has no `second` geometry in a {} mechanism",
                kind.code(),
                c_name(kind.code()),
                space.name()
            ),
            "not for this joint type",
            match kind {
                JointType::SPSP => {
                    "SPSP carries its second body's centre in `origin2` already".into()
                }
                _ => "its second body carries no point or axis the constraints compare; remove `second`"
                    .into(),
            },
        ));
    }
    let mut s = Second::default();
    for x in es {
        let key = x.key.as_ref();
        if !fields.contains(&key) {
            return Err(not_here(
                &x.key_span,
                format!(
                    "joint type {}: its second body carries no `{key}`",
                    kind.code()
                ),
                "not carried by the second body",
                format!(
                    "`second` of joint type {} in a {} mechanism takes {}",
                    kind.code(),
                    space.name(),
                    fields
                        .iter()
                        .map(|f| format!("`{f}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        let v = Some(parse_vector(x, space, key != "origin")?);
        match key {
            "origin" => s.origin = v,
            "axis" => s.axis = v,
            "axis2" => s.axis2 = v,
            _ => s.normal = v,
        }
    }
    Ok(Box::new(s))
}

/// `[expect]`: keys and types from [`Expect`] itself, so the two stay in sync.
fn parse_expect(node: &Node) -> Result<Expect, LoadError> {
    let es = as_map(node, "`expect`")?;
    let schema = schemars::schema_for!(Expect);
    let keys: Vec<&str> = schema
        .get("properties")
        .and_then(|p| p.as_object())
        .map(|p| p.keys().map(String::as_str).collect())
        .unwrap_or_default();
    check_keys(es, &keys, "expect")?;
    let mut object = serde_json::Map::new();
    for e in es {
        let v = to_json(&e.value)?;
        let one = serde_json::Value::Object([(e.key.to_string(), v.clone())].into_iter().collect());
        if let Err(x) = serde_json::from_value::<Expect>(one) {
            let msg = x.to_string();
            return Err(err(
                ErrorKind::WrongType,
                format!("`expect.{}`: {msg}", e.key),
                &e.value.span,
                "wrong type",
                Some(match e.key.as_ref() {
                    "determined" => "write true or false".to_string(),
                    "mobility" | "generic_dof" | "true_mobility" => "write an integer".to_string(),
                    _ => "write a non-negative integer".to_string(),
                }),
            ));
        }
        object.insert(e.key.to_string(), v);
    }
    serde_json::from_value(serde_json::Value::Object(object)).map_err(|x| {
        err(
            ErrorKind::WrongType,
            format!("`expect`: {x}"),
            &node.span,
            "here",
            None,
        )
    })
}

fn to_json(node: &Node) -> Result<serde_json::Value, LoadError> {
    use serde_json::Value as J;
    Ok(match &node.value {
        Value::Map(es) => {
            let mut m = serde_json::Map::new();
            for e in es {
                m.insert(e.key.to_string(), to_json(&e.value)?);
            }
            J::Object(m)
        }
        Value::Seq(xs) => J::Array(xs.iter().map(to_json).collect::<Result<_, _>>()?),
        Value::Str(s) => J::String(s.to_string()),
        Value::Int(i) => J::from(*i),
        Value::BigInt(_) => return Err(out_of_range(node, "this number")),
        Value::Float(f) => serde_json::Number::from_f64(*f).map_or(J::Null, J::Number),
        Value::Bool(b) => J::Bool(*b),
        Value::Null | Value::DateTime | Value::Deferred => J::Null,
    })
}

// ---------------------------------------------------------------------------------------------
// Bar-joint frameworks

#[allow(clippy::too_many_arguments)]
fn build_framework(
    top: &[Entry],
    root: &Node,
    name: &str,
    space: Space,
    frame: BodyId,
    frame_node: &Node,
    points: Option<&Entry>,
    bars: Option<&Entry>,
) -> Result<Mechanism, LoadError> {
    let _ = top;
    // Points: id -> (position, id span), in file order.
    let mut point_ids: Vec<BodyId> = Vec::new();
    let mut point_info: BTreeMap<BodyId, (Option<[f64; 3]>, Range<usize>)> = BTreeMap::new();
    if let Some(p) = points {
        for pt in as_seq(&p.value, "the point list")? {
            let es = as_map(pt, "a point")?;
            check_keys(es, POINT_KEYS, "point")?;
            let id_entry = required(es, "id", pt, "point")?;
            let id = as_id(&id_entry.value, "a point id")?;
            if let Some((_, first)) = point_info.get(&id) {
                return Err(LoadError::new(
                    ErrorKind::DuplicatePointId,
                    format!("point `{id}` is declared twice"),
                    vec![
                        label(&id_entry.value.span, "declared again here"),
                        label(first, "first declared here"),
                    ],
                    Some("point ids must be unique".into()),
                ));
            }
            let at = match get(es, "at") {
                Some(e) => Some(parse_vector(e, space, false)?),
                None => None,
            };
            point_ids.push(id.clone());
            point_info.insert(id, (at, id_entry.value.span.clone()));
        }
    }
    let Some(bars) = bars else {
        let at = root.span.start..root.span.start;
        return Err(no_joints(&at, "no `bar` list in this file"));
    };
    let list = as_seq(&bars.value, "the bar list")?;
    if list.is_empty() {
        return Err(no_joints(&bars.value.span, "empty list"));
    }
    // Bars: (explicit id or None, its two points).
    let mut bar_specs: Vec<(Option<BodyId>, [BodyId; 2])> = Vec::new();
    let mut explicit: BTreeMap<BodyId, Range<usize>> = BTreeMap::new();
    for b in list {
        let es = as_map(b, "a bar")?;
        check_keys(es, BAR_KEYS, "bar")?;
        let pe = required(es, "points", b, "bar")?;
        let items = as_seq(&pe.value, "a bar's `points`")?;
        if items.len() != 2 {
            return Err(err(
                ErrorKind::BarPoints,
                format!(
                    "a bar joins exactly two points; this one names {}",
                    items.len()
                ),
                &pe.value.span,
                format!("{} points", items.len()),
                Some("write its two end points, e.g. points = [1, 2]".into()),
            ));
        }
        let mut ends = Vec::with_capacity(2);
        for p in items {
            let id = as_id(p, "a point id")?;
            if !point_info.contains_key(&id) {
                let names: Vec<String> = point_ids.iter().map(|p| p.to_string()).collect();
                let text = id.to_string();
                let help = match nearest(&text, names.iter().map(String::as_str)) {
                    Some(n) => format!("did you mean `{n}`? declared points: {}", names.join(", ")),
                    None if names.is_empty() => "declare the points with [[point]] id = ...".into(),
                    None => format!("declared points: {}", names.join(", ")),
                };
                return Err(err(
                    ErrorKind::UnknownPoint,
                    format!("point `{id}` is not declared"),
                    &p.span,
                    "unknown point",
                    Some(help),
                ));
            }
            ends.push(id);
        }
        if ends[0] == ends[1] {
            return Err(err(
                ErrorKind::BarPoints,
                format!("a bar joins point `{}` to itself", ends[0]),
                &pe.value.span,
                "the same point twice",
                Some("a bar joins two distinct points".into()),
            ));
        }
        let id = match get(es, "id") {
            None => None,
            Some(e) => {
                let id = as_id(&e.value, "a bar id")?;
                if let Some(first) = explicit.get(&id) {
                    return Err(LoadError::new(
                        ErrorKind::DuplicateBodyId,
                        format!("two bars have the id `{id}`"),
                        vec![
                            label(&e.value.span, "again here"),
                            label(first, "first here"),
                        ],
                        Some("bar ids must be unique".into()),
                    ));
                }
                explicit.insert(id.clone(), e.value.span.clone());
                Some(id)
            }
        };
        let [p, q]: [BodyId; 2] = ends
            .try_into()
            .expect("exactly two ends were checked above");
        bar_specs.push((id, [p, q]));
    }
    // Default bar ids `p-q`, suffixed when taken.
    let mut taken: BTreeSet<BodyId> = explicit.keys().cloned().collect();
    let mut bar_ids: Vec<BodyId> = Vec::with_capacity(bar_specs.len());
    for (id, [p, q]) in &bar_specs {
        let id = match id {
            Some(id) => id.clone(),
            None => {
                let base = format!("{p}-{q}");
                let mut id = BodyId::Name(base.clone());
                let mut n = 1;
                while taken.contains(&id) {
                    n += 1;
                    id = BodyId::Name(format!("{base}#{n}"));
                }
                taken.insert(id.clone());
                id
            }
        };
        bar_ids.push(id);
    }
    if !bar_ids.contains(&frame) {
        return Err(undeclared(
            &frame,
            &frame_node.span,
            bar_ids.iter(),
            "frame bar",
            "bars",
        ));
    }
    // One joint per point where two or more bars meet.
    let kind = if space == Space::Spatial {
        JointType::S
    } else {
        JointType::R
    };
    let mut specs = Vec::new();
    for pid in &point_ids {
        let meeting: Vec<BodyId> = bar_specs
            .iter()
            .zip(&bar_ids)
            .filter(|((_, ends), _)| ends.contains(pid))
            .map(|(_, id)| id.clone())
            .collect();
        if meeting.len() < 2 {
            continue;
        }
        let origin = point_info.get(pid).and_then(|(at, _)| *at);
        specs.push(JointSpec {
            id: Some(pid.to_string()),
            kind,
            bodies: meeting,
            driven: 0,
            geometry: Geometry {
                origin,
                axis: (space == Space::Planar).then_some([0.0, 0.0, 1.0]),
                ..Geometry::default()
            },
        });
    }
    if !specs.iter().any(|s| s.bodies.contains(&frame)) {
        return Err(frame_not_in_joint(&frame, frame_node));
    }
    let extra = bar_ids
        .into_iter()
        .map(|id| Body { id, label: None })
        .collect();
    Ok(Mechanism::from_parts(name, space, frame, extra, specs))
}

#[cfg(test)]
mod fast_tests {
    use super::*;

    #[test]
    fn exact_codes_read_as_parse_reads_them() {
        for i in CATALOGUE.iter() {
            assert_eq!(exact_code(i.code), JointType::parse(i.code), "{}", i.code);
        }
        assert_eq!(exact_code("r"), None);
        for t in ["", "RR", "SPSPS", "S\0", "SPS", "Rx"] {
            assert_eq!(exact_code(t), None, "{t:?}");
        }
        assert!(CODE_KEYS.iter().all(|&k| k != u64::MAX));
    }

    #[test]
    fn push_int_is_to_string() {
        let around_powers = (0..19).flat_map(|e| {
            let p = 10i64.pow(e);
            [p - 1, p, p + 1, -p, p.saturating_mul(11)]
        });
        let values = [0, 1, -1, 9, 10, -10, 12345, i64::MAX, i64::MIN, 1_000_000];
        for n in values.into_iter().chain(around_powers).chain(-1000..1000) {
            let mut s = String::from("x");
            push_int(&mut s, n);
            assert_eq!(s, format!("x{n}"));
        }
    }
}
