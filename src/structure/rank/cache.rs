//! Decisions kept across analyses of one mechanism: bodies' reduced unknowns and sound blocks'
//! verdicts, keyed by digests of the rows they depend on.

use super::rows::PairRows;
use crate::structure::Unchecked;
use crate::structure::count::{Equations, Part};
use nalgebra::{DMatrix, Dyn, RawStorage};
use std::collections::HashMap;
use std::sync::Mutex;

/// Decisions of the rank check kept across analyses of one mechanism under different inputs
/// (`mbsa transform` analyses many placements): a body's reduced unknowns and a sound block's
/// verdict are functions of the rows involved (and the tolerance), so they are keyed by a
/// 128-bit digest of exactly those rows and reused when the same rows come again. Deficient
/// blocks are never cached (their explanation is recomputed), so a hit only skips a
/// factorization whose result is known: the analysis is the same with or without a cache.
#[derive(Default)]
pub struct Cache {
    pub(super) bases: Mutex<HashMap<u128, Option<DMatrix<f64>>>>,
    pub(super) blocks: Mutex<HashMap<u128, Option<Unchecked>>>,
    /// An isolated freedom's confirmation: the seed of the first draw without it, if any.
    pub(super) isolated: Mutex<HashMap<u128, Option<u64>>>,
}

/// Entries a [`Cache`] keeps before it starts over (memory stays bounded).
const CACHE_ENTRIES: usize = 1 << 21;

/// The entry under `k`, if kept.
fn get<T: Clone>(map: &Mutex<HashMap<u128, T>>, k: u128) -> Option<T> {
    let g = map.lock().unwrap_or_else(|e| e.into_inner());
    g.get(&k).cloned()
}

/// Keep `v` under `k`, starting over once [`CACHE_ENTRIES`] are kept.
fn put<T>(map: &Mutex<HashMap<u128, T>>, k: u128, v: T) {
    let mut g = map.lock().unwrap_or_else(|e| e.into_inner());
    if g.len() >= CACHE_ENTRIES {
        g.clear();
    }
    g.insert(k, v);
}

impl Cache {
    pub(super) fn get_basis(&self, k: u128) -> Option<Option<DMatrix<f64>>> {
        get(&self.bases, k)
    }
    pub(super) fn put_basis(&self, k: u128, v: &Option<DMatrix<f64>>) {
        put(&self.bases, k, v.clone());
    }
    pub(super) fn get_block(&self, k: u128) -> Option<Option<Unchecked>> {
        get(&self.blocks, k)
    }
    pub(super) fn put_block(&self, k: u128, v: Option<Unchecked>) {
        put(&self.blocks, k, v);
    }
    pub(super) fn get_isolated(&self, k: u128) -> Option<Option<u64>> {
        get(&self.isolated, k)
    }
    pub(super) fn put_isolated(&self, k: u128, v: Option<u64>) {
        put(&self.isolated, k, v);
    }
}

/// Two independent 64-bit streams fed the same words, each word folded in by a 64 × 64 → 128-bit
/// multiply (the halves of the product xored, as wyhash and foldhash mix), with fixed keys: a
/// deterministic digest, a few times cheaper than SipHash on the many short words of pair rows.
/// A key only selects an entry whose value is recomputed identically on a miss, so the digest
/// decides no output; its 128 bits make a collision of two different keys negligible.
pub(super) struct Digest {
    lanes: [u64; 2],
    words: u64,
}

/// The keys of the two streams: the first 64 fractional bits of sqrt(2), sqrt(3), pi and e,
/// each made odd.
const KEYS: [u64; 4] = [
    0x6a09_e667_f3bc_c909,
    0xbb67_ae85_84ca_a73b,
    0x243f_6a88_85a3_08d3,
    0xb7e1_5162_8aed_2a6b,
];

/// The folded product of `x` and `k`: the low and high halves of the 128-bit product xored.
fn fold(x: u64, k: u64) -> u64 {
    let p = u128::from(x) * u128::from(k);
    (p as u64) ^ ((p >> 64) as u64)
}

impl Digest {
    pub(super) fn new(tag: u64) -> Digest {
        let mut d = Digest {
            lanes: [KEYS[2], KEYS[3]],
            words: 0,
        };
        d.word(tag);
        d
    }
    pub(super) fn word(&mut self, v: u64) {
        self.lanes[0] = fold(self.lanes[0] ^ v, KEYS[0]);
        self.lanes[1] = fold(self.lanes[1] ^ v.rotate_left(32), KEYS[1]);
        self.words = self.words.wrapping_add(1);
    }
    pub(super) fn wide(&mut self, v: u128) {
        self.word(v as u64);
        self.word((v >> 64) as u64);
    }
    pub(super) fn matrix<S: RawStorage<f64, Dyn, Dyn>>(
        &mut self,
        a: &nalgebra::Matrix<f64, Dyn, Dyn, S>,
    ) {
        self.word(a.nrows() as u64);
        self.word(a.ncols() as u64);
        for x in a.iter() {
            self.word(x.to_bits());
        }
    }
    pub(super) fn finish(&self) -> u128 {
        let a = fold(fold(self.lanes[0] ^ self.words, KEYS[1]), KEYS[2]);
        let b = fold(fold(self.lanes[1] ^ self.words, KEYS[0]), KEYS[3]);
        (u128::from(a) << 64) | u128::from(b)
    }
}

/// What a block's cache key is made of besides the block itself.
pub(super) struct KeyContext<'a> {
    pub(super) tol: &'a [u64; 3],
    pub(super) seed: Option<u64>,
    pub(super) qd: &'a [u128],
    pub(super) rd: &'a [u128],
    pub(super) orig_rows: &'a [u8],
}

impl KeyContext<'_> {
    /// The key of a block: everything its verdict depends on (its part, bodies with their
    /// unknowns, pairs with their bodies and rows, whether any pair was lowered).
    pub(super) fn block(
        &self,
        part: Part,
        bodies: &[usize],
        block_eqs: &[usize],
        eqs: &Equations,
        rows: &PairRows,
    ) -> u128 {
        let mut d = Digest::new(3);
        self.tol.iter().for_each(|&w| d.word(w));
        d.word(match part {
            Part::Over => 0,
            Part::Under => 1,
            _ => 2,
        });
        d.word(self.seed.unwrap_or(u64::MAX));
        d.word(bodies.len() as u64);
        for &x in bodies {
            d.word(x as u64);
            d.wide(self.qd[x]);
        }
        d.word(block_eqs.len() as u64);
        for &e in block_eqs {
            let [h, o] = eqs.bodies(e);
            d.word(e as u64);
            d.word(h as u64);
            d.word(o as u64);
            d.wide(self.rd[e]);
            d.word(u64::from(rows.nrows(e) == usize::from(self.orig_rows[e])));
        }
        d.finish()
    }
}

pub(super) fn matrix_digest<S: RawStorage<f64, Dyn, Dyn>>(
    a: &nalgebra::Matrix<f64, Dyn, Dyn, S>,
) -> u128 {
    let mut d = Digest::new(1);
    d.matrix(a);
    d.finish()
}

#[cfg(test)]
mod tests {
    use super::Digest;
    use std::collections::HashSet;

    fn digest(tag: u64, words: &[u64]) -> u128 {
        let mut d = Digest::new(tag);
        words.iter().for_each(|&w| d.word(w));
        d.finish()
    }

    #[test]
    fn digest_is_a_function_of_the_tag_and_the_words_in_order() {
        assert_eq!(digest(3, &[1, 2, 3]), digest(3, &[1, 2, 3]));
        assert_ne!(digest(3, &[1, 2, 3]), digest(3, &[3, 2, 1]));
        assert_ne!(digest(3, &[1, 2, 3]), digest(2, &[1, 2, 3]));
        assert_ne!(digest(3, &[0]), digest(3, &[0, 0]));
        assert_ne!(digest(3, &[]), digest(3, &[0]));
    }

    #[test]
    fn digests_of_nearby_rows_differ_in_both_halves() {
        // Rows one unit in the last place apart, and every single-bit change of one word.
        let base: Vec<u64> = [0.5f64, -0.25, 1.0, 0.0, 3.0, -1.5]
            .iter()
            .map(|x| x.to_bits())
            .collect();
        let mut seen = HashSet::new();
        let (mut lows, mut highs) = (HashSet::new(), HashSet::new());
        for i in 0..base.len() {
            for bit in 0..64 {
                let mut w = base.clone();
                w[i] ^= 1 << bit;
                let d = digest(1, &w);
                assert!(seen.insert(d));
                lows.insert(d as u64);
                highs.insert((d >> 64) as u64);
            }
        }
        assert_eq!(lows.len(), seen.len());
        assert_eq!(highs.len(), seen.len());
    }
}
