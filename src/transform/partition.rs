//! The groups' bodies of a placement as indices into the mechanism's body ids, and their
//! fingerprint (families are made by it).

use crate::mechanism::Mechanism;
use serde::Serialize;
use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

/// The groups' bodies of a placement, in canonical order, kept as body indices into the
/// mechanism's body ids (shared by every placement): four bytes a body instead of a string
/// each. A listed placement of a 10^5-body linkage held 10^5 strings (about 6 MB; 100 of them
/// and their families' copies were 2.3 GB of `transform --limit 100`). It serializes as the
/// list of lists of body ids it stands for.
#[derive(Clone, Debug)]
pub struct Partition(pub(super) Repr);

#[derive(Clone, Debug)]
pub(super) enum Repr {
    /// Group `g` is `bodies[ends[g - 1]..ends[g]]`, each an index into `ids`.
    Indexed {
        ids: Arc<Vec<String>>,
        bodies: Vec<u32>,
        ends: Vec<u32>,
    },
    /// The ids themselves: an analysis named a body the id table lacks (never expected).
    Text(Vec<Vec<String>>),
}

impl Partition {
    /// Groups of bodies given as indices into `ids`.
    pub(super) fn indexed(
        ids: &Arc<Vec<String>>,
        groups: impl Iterator<Item = Vec<u32>>,
    ) -> Partition {
        let mut bodies = Vec::new();
        let mut ends = Vec::new();
        for g in groups {
            bodies.extend_from_slice(&g);
            ends.push(bodies.len() as u32);
        }
        bodies.shrink_to_fit();
        ends.shrink_to_fit();
        Partition(Repr::Indexed {
            ids: Arc::clone(ids),
            bodies,
            ends,
        })
    }

    /// Number of groups.
    pub fn len(&self) -> usize {
        match &self.0 {
            Repr::Indexed { ends, .. } => ends.len(),
            Repr::Text(v) => v.len(),
        }
    }

    /// The bytes the partition holds on the heap (the id table it shares not counted).
    pub(super) fn bytes(&self) -> usize {
        match &self.0 {
            Repr::Indexed { bodies, ends, .. } => 4 * (bodies.capacity() + ends.capacity()),
            Repr::Text(v) => v
                .iter()
                .map(|g| {
                    std::mem::size_of::<Vec<String>>()
                        + g.iter()
                            .map(|b| std::mem::size_of::<String>() + b.capacity())
                            .sum::<usize>()
                })
                .sum(),
        }
    }

    /// Whether there are no groups.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub(super) fn range(ends: &[u32], g: usize) -> std::ops::Range<usize> {
        let start = if g == 0 { 0 } else { ends[g - 1] as usize };
        start..ends[g] as usize
    }

    /// Body ids of group `g` (empty past the last group).
    pub fn group(&self, g: usize) -> Vec<&str> {
        match &self.0 {
            Repr::Indexed { ids, bodies, ends } if g < ends.len() => bodies[Self::range(ends, g)]
                .iter()
                .map(|&x| ids.get(x as usize).map_or("", String::as_str))
                .collect(),
            Repr::Text(v) => v
                .get(g)
                .map(|grp| grp.iter().map(String::as_str).collect())
                .unwrap_or_default(),
            _ => Vec::new(),
        }
    }

    /// Number of bodies of group `g`.
    pub(super) fn group_len(&self, g: usize) -> usize {
        match &self.0 {
            Repr::Indexed { ends, .. } if g < ends.len() => Self::range(ends, g).len(),
            Repr::Text(v) => v.get(g).map_or(0, Vec::len),
            _ => 0,
        }
    }

    /// Every group's body ids.
    pub fn to_vec(&self) -> Vec<Vec<String>> {
        (0..self.len())
            .map(|g| self.group(g).into_iter().map(str::to_string).collect())
            .collect()
    }

    /// An order-independent fingerprint of the groups (the number of groups and two 64-bit
    /// sums of a SipHash of each group's bodies in order): equal partitions (the same groups,
    /// each with its bodies in the same order, in any group order) have equal fingerprints,
    /// and different ones equal fingerprints with probability about 2^-128. Families are
    /// made by it, so a listed placement's partition need not be held.
    pub(super) fn fingerprint(&self) -> Fingerprint {
        use std::hash::{DefaultHasher, Hash, Hasher};
        let mut sums = [0u64; 2];
        for g in 0..self.len() {
            for (lane, sum) in sums.iter_mut().enumerate() {
                let mut h = DefaultHasher::new();
                (lane as u8).hash(&mut h);
                match &self.0 {
                    Repr::Indexed { bodies, ends, .. } => {
                        0u8.hash(&mut h);
                        bodies[Self::range(ends, g)].hash(&mut h);
                    }
                    Repr::Text(v) => {
                        1u8.hash(&mut h);
                        v[g].hash(&mut h);
                    }
                }
                *sum = sum.wrapping_add(h.finish());
            }
        }
        (self.len(), sums[0], sums[1])
    }
}

/// [`Partition::fingerprint`].
pub(super) type Fingerprint = (usize, u64, u64);

impl PartialEq for Partition {
    fn eq(&self, other: &Partition) -> bool {
        self.len() == other.len() && (0..self.len()).all(|g| self.group(g) == other.group(g))
    }
}

impl Eq for Partition {}

impl Serialize for Partition {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        /// One group's body ids, written without collecting them.
        struct Group<'a>(&'a Partition, usize);
        impl Serialize for Group<'_> {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                match &self.0.0 {
                    Repr::Indexed { ids, bodies, ends } if self.1 < ends.len() => s.collect_seq(
                        bodies[Partition::range(ends, self.1)]
                            .iter()
                            .map(|&x| ids.get(x as usize).map_or("", String::as_str)),
                    ),
                    _ => s.collect_seq(self.0.group(self.1)),
                }
            }
        }
        let mut seq = s.serialize_seq(Some(self.len()))?;
        for g in 0..self.len() {
            seq.serialize_element(&Group(self, g))?;
        }
        seq.end()
    }
}

impl<'de> serde::Deserialize<'de> for Partition {
    /// The lists of body ids a report wrote (read back from `transform` shards).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Partition, D::Error> {
        Vec::<Vec<String>>::deserialize(d).map(|v| Partition(Repr::Text(v)))
    }
}

/// The body ids of a mechanism as the analysis writes them, shared by its placements'
/// partitions, and (made on first use, by the full analyses only) the index of each.
pub(super) struct BodyNames {
    pub(super) ids: Arc<Vec<String>>,
    index: OnceLock<HashMap<String, u32>>,
}

impl BodyNames {
    pub(super) fn of(m: &Mechanism) -> BodyNames {
        BodyNames {
            ids: Arc::new(m.bodies.iter().map(|b| b.id.to_string()).collect()),
            index: OnceLock::new(),
        }
    }

    /// The partition of groups given by their body ids.
    pub(super) fn partition(&self, groups: &[&[String]]) -> Partition {
        let index = self.index.get_or_init(|| {
            let mut h = HashMap::with_capacity(self.ids.len());
            for (i, id) in self.ids.iter().enumerate() {
                h.entry(id.clone()).or_insert(i as u32);
            }
            h
        });
        let mut out: Vec<Vec<u32>> = Vec::with_capacity(groups.len());
        for g in groups {
            let mut v = Vec::with_capacity(g.len());
            for id in g.iter() {
                match index.get(id) {
                    Some(&x) => v.push(x),
                    None => {
                        return Partition(Repr::Text(groups.iter().map(|g| g.to_vec()).collect()));
                    }
                }
            }
            out.push(v);
        }
        Partition::indexed(&self.ids, out.into_iter())
    }
}
