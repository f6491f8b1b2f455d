//! The joint list of a joint-and-body file, read one joint at a time: type, bodies, driven
//! DOF, id and geometry of each, then the default ids.

use super::bodies::{Declared, Interner, in_dense_id_order, in_id_order, parse_bodies, undeclared};
use super::geometry::{parse_geometry, parse_second};
use super::joint_ids::{
    ByList, MaybeTaken, by_body_list, default_joint_ids, merged_natural_order, push_id, push_int,
};
use super::values::{as_id, as_int, as_map, as_seq, as_str, check_keys, err, label, required};
use super::{frame_not_in_joint, no_joints};
use crate::format::error::{ErrorKind, LoadError};
use crate::format::read::Lazy;
use crate::format::tree::{Entry, Node, Value};
use crate::joint::{CATALOGUE, JointType};
use crate::mechanism::{BodyId, Joint, JointBodies, JointGeometry, Mechanism, Space};
use std::borrow::Cow;
use std::collections::{HashMap, HashSet, hash_map};
use std::ops::Range;

const JOINT_KEYS: &[&str] = &[
    "id", "type", "bodies", "driven", "origin", "origin2", "axis", "axis2", "normal", "pitch",
    "second",
];

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

/// Body lists up to this long are checked for a repeated body by a scan.
const SCAN_BODIES: usize = 16;

/// A joint list: its entry (for locations), its value taken out of the tree, and where its
/// deferred items come from.
pub(super) type JointList<'e, 'a> = (&'e Entry<'a>, Option<Value<'a>>, Lazy<'a>);

/// The mechanism of a joint-and-body file: the declared bodies, then the joints read one at a
/// time, their default ids, and the bodies in id order.
pub(super) fn build_joints<'a>(
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
    let (mut interner, labels, n_declared) = number_declared(declared, hint);
    let frame_index = interner.get(frame.clone());
    // A frame that leaves the dense numbering: no index was handed out before it.
    interner.renumbered = None;
    let mut r = JointsRead::new(space, interner, n_declared, frame_index, hint, &lazy);
    lazy.for_each(list, &mut |j: &Node<'a>| r.joint(j))?;
    if !r.read.iter().any(|j| j.bodies.contains(&r.frame_index)) {
        return Err(frame_not_in_joint(&frame, frame_node));
    }
    let in_order = r.default_ids()?;
    let JointsRead {
        interner,
        frame_index,
        read,
        ..
    } = r;
    if interner.dense {
        return Ok(in_dense_id_order(
            name,
            space,
            &interner,
            frame_index,
            read,
            in_order,
        ));
    }
    Ok(in_id_order(
        name,
        space,
        interner,
        labels,
        frame_index,
        read,
    ))
}

/// The body numbering, sized for about `hint` joints, with the declared bodies first: their
/// labels by index, and how many there are (`None`: no bodies declared).
fn number_declared(
    declared: Option<Declared>,
    hint: usize,
) -> (Interner, Vec<Option<String>>, Option<usize>) {
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
    (interner, labels, n_declared)
}

/// The joints read so far, and what their ids and bodies need while the list is read.
struct JointsRead<'a> {
    space: Space,
    interner: Interner,
    /// How many bodies were declared (their indices come first), if any were.
    n_declared: Option<usize>,
    frame_index: usize,
    read: Vec<Joint>,
    /// The span that locates each joint in later errors.
    /// Not kept when the error would be thrown away (`Lazy::errors_discarded`): 16 bytes a
    /// joint, written for every joint of a large file and needed only by the error.
    keep_spans: bool,
    joint_spans: Vec<Range<usize>>,
    /// Explicit ids and where each is: a hash map (looked up once per joint below; the
    /// standard keyed hasher, so crafted ids cannot make it quadratic), keys borrowed from the
    /// text where the reader could.
    explicit: HashMap<Cow<'a, str>, Range<usize>>,
    /// Whether any body id is a name.
    any_name: bool,
    /// Per body: the last joint of more than SCAN_BODIES bodies that named it, and where.
    seen: Vec<(u32, u32)>,
    /// Per joint: whether its id is the default `a-b` (suffixed later).
    defaulted: Vec<bool>,
    /// One buffer for every joint: a binary joint keeps its two bodies inline.
    ids_buf: Vec<usize>,
}

/// The entries of one joint that are looked up, found in one pass over its keys.
struct JointKeys<'n, 'a> {
    type_entry: Option<&'n Entry<'a>>,
    bodies_entry: Option<&'n Entry<'a>>,
    id_entry: Option<&'n Entry<'a>>,
    driven_entry: Option<&'n Entry<'a>>,
    second_entry: Option<&'n Entry<'a>>,
    any_geometry: bool,
}

impl<'n, 'a> JointKeys<'n, 'a> {
    /// One pass over the keys: the entries looked up, and whether any is unknown (then
    /// `check_keys` names it, as it would have first).
    fn of(es: &'n [Entry<'a>]) -> Result<JointKeys<'n, 'a>, LoadError> {
        let mut k = JointKeys {
            type_entry: None,
            bodies_entry: None,
            id_entry: None,
            driven_entry: None,
            second_entry: None,
            any_geometry: false,
        };
        let mut unknown = false;
        for e in es {
            match e.key.as_ref() {
                "type" => k.type_entry = Some(e),
                "bodies" => k.bodies_entry = Some(e),
                "id" => k.id_entry = Some(e),
                "driven" => k.driven_entry = Some(e),
                "second" => k.second_entry = Some(e),
                "origin" | "origin2" | "axis" | "axis2" | "normal" | "pitch" => {
                    k.any_geometry = true
                }
                _ => unknown = true,
            }
        }
        if unknown {
            check_keys(es, JOINT_KEYS, "joint")?;
        }
        Ok(k)
    }
}

impl<'a> JointsRead<'a> {
    fn new(
        space: Space,
        interner: Interner,
        n_declared: Option<usize>,
        frame_index: usize,
        hint: usize,
        lazy: &Lazy<'a>,
    ) -> JointsRead<'a> {
        let read: Vec<Joint> = Vec::with_capacity(hint);
        let keep_spans = !lazy.errors_discarded();
        let joint_spans = Vec::with_capacity(if keep_spans { hint } else { 0 });
        let defaulted = Vec::with_capacity(read.capacity());
        JointsRead {
            space,
            interner,
            n_declared,
            frame_index,
            read,
            keep_spans,
            joint_spans,
            explicit: HashMap::new(),
            any_name: false,
            seen: Vec::new(),
            defaulted,
            ids_buf: Vec::new(),
        }
    }

    /// Read one joint of the list.
    fn joint(&mut self, j: &Node<'a>) -> Result<(), LoadError> {
        let es = as_map(j, "a joint")?;
        let keys = JointKeys::of(es)?;
        let type_entry = match keys.type_entry {
            Some(e) => e,
            None => required(es, "type", j, "joint")?,
        };
        let kind = joint_kind(type_entry, self.space)?;
        let bodies_entry = match keys.bodies_entry {
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
        let mut ids = std::mem::take(&mut self.ids_buf);
        // The default id `a-b` when no `id` is given, written while the ids are at hand.
        // 24 bytes: the smallest heap block holds them anyway, and `a-b#n` then fits at once.
        let mut base = if keys.id_entry.is_none() {
            String::with_capacity(24)
        } else {
            String::new()
        };
        let default_id = keys.id_entry.is_none().then_some(&mut base);
        self.joint_bodies(items, &mut ids, default_id)?;
        let driven = match keys.driven_entry {
            None => 0,
            Some(e) => joint_driven(e, kind, ids.len())?,
        };
        self.defaulted.push(keys.id_entry.is_none());
        let id = match keys.id_entry {
            None => base,
            Some(e) => self.explicit_id(e)?,
        };
        // Most large files give no geometry: no `Geometry` built, moved and compared then.
        let geometry = if keys.any_geometry || keys.second_entry.is_some() {
            let mut geometry = parse_geometry(es, self.space)?;
            if let Some(e) = keys.second_entry {
                geometry.second = Some(parse_second(e, kind, self.space, ids.len())?);
            }
            geometry.into()
        } else {
            JointGeometry::default()
        };
        if self.keep_spans {
            self.joint_spans
                .push(es.first().map_or(j.span.clone(), |e| e.key_span.clone()));
        }
        self.read.push(Joint {
            id,
            kind,
            bodies: JointBodies::from(&ids[..]),
            driven,
            geometry,
        });
        self.ids_buf = ids;
        Ok(())
    }

    /// The body indices of one joint's `bodies` into `ids` (cleared first), each declared (if
    /// bodies are declared) and named once; the default id written into `default_id`.
    fn joint_bodies(
        &mut self,
        items: &[Node<'a>],
        ids: &mut Vec<usize>,
        mut default_id: Option<&mut String>,
    ) -> Result<(), LoadError> {
        ids.clear();
        // A body named twice in one joint: a scan for short lists, else a mark per body (the
        // joint's number and the item's position), so that one joint of n bodies is linear.
        let stamp = self.read.len() as u32;
        for (i, b) in items.iter().enumerate() {
            let id = as_id(b, "a body id")?;
            self.any_name |= matches!(id, BodyId::Name(_));
            if let Some(base) = default_id.as_deref_mut() {
                push_id(base, i, &id);
            }
            let k = self.interner.get(id);
            if let Some(renumber) = self.interner.renumbered.take() {
                self.renumber(&renumber, ids, items.len(), stamp);
            }
            let again = if items.len() <= SCAN_BODIES {
                ids.iter().position(|x| *x == k)
            } else {
                let seen = &mut self.seen;
                if seen.len() <= k {
                    let len = self.interner.len().max(k + 1).max(2 * seen.len());
                    seen.resize(len, (u32::MAX, 0));
                }
                let (joint, at) = seen[k];
                seen[k] = (stamp, i as u32);
                (joint == stamp).then_some(at as usize)
            };
            if let Some(first) = again {
                return Err(LoadError::new(
                    ErrorKind::RepeatedBody,
                    format!("body `{}` appears twice in one joint", self.interner.id(k)),
                    vec![
                        label(&b.span, "again here"),
                        label(&items[first].span, "first here"),
                    ],
                    Some("a joint joins distinct bodies".into()),
                ));
            }
            if let Some(n) = self.n_declared
                && k >= n
            {
                return Err(undeclared(
                    &self.interner.ids[k],
                    &items[i].span,
                    self.interner.ids[..n].iter(),
                    "body",
                    "declared bodies",
                ));
            }
            ids.push(k);
        }
        Ok(())
    }

    /// Out of the dense numbering (once): the indices handed out so far follow `renumber`,
    /// those of the joint being read (`ids`, of a list of `n_items`) too.
    fn renumber(&mut self, renumber: &[u32], ids: &mut [usize], n_items: usize, stamp: u32) {
        let to = |k: &mut usize| *k = renumber[*k] as usize;
        self.read
            .iter_mut()
            .flat_map(|j| j.bodies.iter_mut())
            .for_each(to);
        ids.iter_mut().for_each(to);
        to(&mut self.frame_index);
        self.seen.clear();
        if n_items > SCAN_BODIES {
            self.seen.resize(self.interner.len(), (u32::MAX, 0));
            for (at, &x) in ids.iter().enumerate() {
                self.seen[x] = (stamp, at as u32);
            }
        }
    }

    /// An explicit joint id: never empty, never given twice.
    fn explicit_id(&mut self, e: &Entry<'a>) -> Result<String, LoadError> {
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
        match self.explicit.entry(id) {
            hash_map::Entry::Occupied(first) => {
                return Err(LoadError::new(
                    ErrorKind::DuplicateJointId,
                    format!("two joints have the id `{owned}`"),
                    vec![
                        label(&e.value.span, "again here"),
                        label(first.get(), "first here"),
                    ],
                    Some(
                        "joint ids must be unique; `--inputs` and reports name joints by id".into(),
                    ),
                ));
            }
            hash_map::Entry::Vacant(v) => {
                v.insert(e.value.span.clone());
            }
        }
        Ok(owned)
    }

    /// Default ids: `a-b`, suffixed `#2`, `#3`... when taken (by an explicit id too). Without
    /// explicit ids, the n-th joint of a body list gets `#n` (as `Mechanism::from_parts` does),
    /// and a default that another joint's body list gives too is an error naming both. Gives
    /// the joints' natural order, when the default ids give it at once.
    fn default_ids(&mut self) -> Result<Option<Vec<u32>>, LoadError> {
        let mut in_order: Option<Vec<u32>> = None;
        // The spans locate only a clash of default ids, which integer bodies never give: freed
        // before the sorts that follow.
        if !self.any_name {
            self.joint_spans = Vec::new();
        }
        if self.explicit.is_empty() {
            let by_list = default_joint_ids(
                &mut self.read,
                &self.interner,
                &self.joint_spans,
                !self.any_name,
            )?;
            // Every id `a-b` or `a-b#n` with integer bodies numbered by their ids: the order
            // by body list (then position, the suffix) is the natural order of the ids.
            if self.interner.dense {
                in_order = by_list;
            }
        } else if !self.any_name {
            in_order = self.defaults_past_explicit_ids();
        } else {
            let explicit = std::mem::take(&mut self.explicit);
            let mut taken: HashSet<String> = explicit.into_keys().map(Cow::into_owned).collect();
            for (j, _) in self
                .read
                .iter_mut()
                .zip(&self.defaulted)
                .filter(|(_, d)| **d)
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
        self.joint_spans = Vec::new();
        Ok(in_order)
    }

    /// Integer bodies with explicit ids: a default `a-b` or `a-b#n` has no other `#`, so
    /// defaults of two body lists never meet; the k-th default of a list takes the k-th suffix
    /// not taken by an explicit id (as the general case, without a set of every id). Gives the
    /// joints' natural order when the bodies are numbered by their ids and every default has
    /// two bodies.
    fn defaults_past_explicit_ids(&mut self) -> Option<Vec<u32>> {
        let merge = self.interner.dense;
        let defaulted = &self.defaulted;
        let ByList {
            order,
            same,
            pairs_only,
            pair_keys,
        } = by_body_list(&self.read, |k| defaulted[k], merge);
        let explicit = &self.explicit;
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
                let j = &mut self.read[order[k] as usize];
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
        let suffixes = suffixes?;
        merged_natural_order(&self.read, &order, &pair_keys, &suffixes, |k| defaulted[k])
    }
}

/// The joint type of a `type` entry, valid in `space`.
fn joint_kind(type_entry: &Entry, space: Space) -> Result<JointType, LoadError> {
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
    Ok(kind)
}

/// The `driven` DOF of a joint of `kind` joining `n_bodies` bodies: 0 to its grade per pair.
fn joint_driven(e: &Entry, kind: JointType, n_bodies: usize) -> Result<u32, LoadError> {
    let max = u32::from(kind.grade()) * (n_bodies as u32 - 1);
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
                if n_bodies > 2 {
                    format!(" per pair, {max} for its {} pairs", n_bodies - 1)
                } else {
                    String::new()
                }
            )),
        ));
    }
    Ok(n as u32)
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

pub(super) fn c_name(code: &str) -> &'static str {
    CATALOGUE
        .iter()
        .find(|i| i.code == code)
        .and_then(|i| i.names.first().copied())
        .unwrap_or("")
}

#[cfg(test)]
mod tests {
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
}
