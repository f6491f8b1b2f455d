//! Bodies: the declared `body` list, the numbering of body ids met in the joints (dense while
//! they are small integers), and the bodies put in id order at the end.

use super::values::{
    as_id, as_map, as_seq, as_str, check_keys, err, get, label, nearest, required,
};
use crate::format::error::{ErrorKind, LoadError};
use crate::format::tree::Entry;
use crate::mechanism::{Body, BodyId, Joint, Mechanism, Space};
use std::collections::BTreeMap;
use std::ops::Range;

const BODY_KEYS: &[&str] = &["id", "label"];

/// Declared bodies: id -> (label, id span).
pub(super) type Declared = BTreeMap<BodyId, (Option<String>, Range<usize>)>;

pub(super) fn parse_bodies(entry: &Entry) -> Result<Declared, LoadError> {
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

pub(super) fn undeclared<'a>(
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

/// Body ids to indices. While every id is a non-negative integer of moderate size (`dense`),
/// an id is its own index and only a bitmap of the ids met is kept: no table lookup per body
/// (random lookups into a table of a million entries were 8 % of reading a 10^6-body file).
/// The first other id switches to the general table, indices in order of first appearance;
/// the renumbering of the indices handed out so far is then left in `renumbered` for the
/// caller.
pub(super) struct Interner {
    pub(super) dense: bool,
    /// Dense: bit `i` set once id `i` was met.
    present: Vec<u64>,
    /// Dense: how many ids were met.
    count: usize,
    /// Dense: about how many joints the file has (ids up to `4 * (hint + count + 4096)` stay
    /// dense, so that the bitmap and the tables indexed by id stay proportional to the file).
    hint: usize,
    /// Set once, when the dense numbering is left: old index -> new index (`u32::MAX`: none).
    pub(super) renumbered: Option<Vec<u32>>,
    /// General: index by small non-negative integer id (`u32::MAX`: none yet).
    small: Vec<u32>,
    map: std::collections::HashMap<BodyId, u32>,
    pub(super) ids: Vec<BodyId>,
}

impl Interner {
    /// Dense numbering when `dense` (no declared bodies), sized for about `hint` joints.
    pub(super) fn new(dense: bool, hint: usize) -> Interner {
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
    pub(super) fn len(&self) -> usize {
        if self.dense {
            self.count
        } else {
            self.ids.len()
        }
    }

    /// The id of index `k`.
    pub(super) fn id(&self, k: usize) -> BodyId {
        if self.dense {
            BodyId::Int(k as i64)
        } else {
            self.ids[k].clone()
        }
    }

    /// The index of `id`, added if new.
    #[inline]
    pub(super) fn get(&mut self, id: BodyId) -> usize {
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
    pub(super) fn dense_ids(&self) -> Vec<usize> {
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

/// The mechanism with its bodies sorted by id, the joints' indices following, when the ids
/// are the indices (`interner.dense`): ascending already; a contiguous run needs no table.
pub(super) fn in_dense_id_order(
    name: &str,
    space: Space,
    interner: &Interner,
    frame_index: usize,
    mut read: Vec<Joint>,
    in_order: Option<Vec<u32>>,
) -> Mechanism {
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
    match in_order {
        Some(order) => Mechanism::from_indexed_in_order(name, space, frame, bodies, read, order),
        None => Mechanism::from_indexed(name, space, frame, bodies, read),
    }
}

/// The mechanism with its bodies sorted by id (their `labels` by index), the joints' indices
/// following, for the general table of ids.
pub(super) fn in_id_order(
    name: &str,
    space: Space,
    interner: Interner,
    mut labels: Vec<Option<String>>,
    frame_index: usize,
    mut read: Vec<Joint>,
) -> Mechanism {
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
    Mechanism::from_indexed(name, space, rank[frame_index], bodies, read)
}
