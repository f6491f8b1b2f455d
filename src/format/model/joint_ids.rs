//! Joint ids: the default `a-b` (suffixed `#n` when taken), and the natural order of the ids
//! that the defaults give without a sort.

use super::bodies::Interner;
use super::values::label;
use crate::format::error::{ErrorKind, LoadError};
use crate::mechanism::{BodyId, Joint, short_natural_key};
use std::fmt::Write as _;
use std::ops::Range;

/// A one-hash Bloom filter over a set of ids: most default joint ids are no explicit id, and
/// one bit answers that without hashing them with the map's keyed (and slower) hasher. Its
/// hash is not keyed, but crafted ids can only make it answer "maybe" (the map lookup it
/// saves), never a wrong "no".
pub(super) struct MaybeTaken {
    bits: Vec<u64>,
    /// 64 minus the number of index bits.
    shift: u32,
}

impl MaybeTaken {
    /// The filter of `ids` (`count` of them): 16 bits per id, a "maybe" for about one id in 16
    /// that is not in the set.
    pub(super) fn new<'s>(ids: impl Iterator<Item = &'s str>, count: usize) -> MaybeTaken {
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
    pub(super) fn may_hold(&self, id: &str) -> bool {
        let i = self.index(id);
        self.bits[i / 64] & (1 << (i % 64)) != 0
    }
}

/// `a-b-c` for a joint's body list.
pub(super) fn joined_ids<'b>(bodies: impl IntoIterator<Item = &'b BodyId>) -> String {
    let mut base = String::new();
    for (i, b) in bodies.into_iter().enumerate() {
        push_id(&mut base, i, b);
    }
    base
}

/// Append the `i`-th id of a joint's default id `a-b-...`.
pub(super) fn push_id(out: &mut String, i: usize, b: &BodyId) {
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
pub(super) fn by_body_list(
    joints: &[Joint],
    keep: impl Fn(usize) -> bool,
    with_keys: bool,
) -> ByList {
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
pub(super) fn merged_natural_order(
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
pub(super) struct ByList {
    pub(super) order: Vec<u32>,
    pub(super) same: Vec<bool>,
    pub(super) pairs_only: bool,
    /// When asked for: the two-body lists in `order`'s order (first `<< 32 |` second), so
    /// that they are read in order, not from the joints at random.
    pub(super) pair_keys: Vec<u64>,
}

/// Default ids when no joint has an explicit one: the n-th joint of a body list `a-b` gets
/// `a-b#n` (the first plain `a-b`). A default that two joints would get (the second `[1, 2]`
/// and a `[1, "2#2"]` both give `1-2#2`) is an error naming both. With integer ids only, the
/// defaults are distinct by construction (`a-b` reads back into its list; no `#` in it), and
/// that check is skipped. Gives the joints sorted by body list when every joint has two
/// bodies (with bodies numbered by their integer ids, that is the natural order of the ids).
pub(super) fn default_joint_ids(
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

#[cfg(test)]
mod tests {
    use super::*;

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
