//! Decisions kept across analyses of one mechanism: bodies' reduced unknowns and sound blocks'
//! verdicts, keyed by digests of the rows they depend on.

use super::rows::PairRows;
use crate::structure::Unchecked;
use crate::structure::count::{Equations, Part};
use nalgebra::{DMatrix, Dyn, RawStorage};
use std::collections::HashMap;
use std::hash::{DefaultHasher, Hasher};
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

impl Cache {
    pub(super) fn get_basis(&self, k: u128) -> Option<Option<DMatrix<f64>>> {
        let g = self.bases.lock().unwrap_or_else(|e| e.into_inner());
        g.get(&k).cloned()
    }
    pub(super) fn put_basis(&self, k: u128, v: &Option<DMatrix<f64>>) {
        let mut g = self.bases.lock().unwrap_or_else(|e| e.into_inner());
        if g.len() >= CACHE_ENTRIES {
            g.clear();
        }
        g.insert(k, v.clone());
    }
    pub(super) fn get_block(&self, k: u128) -> Option<Option<Unchecked>> {
        let g = self.blocks.lock().unwrap_or_else(|e| e.into_inner());
        g.get(&k).cloned()
    }
    pub(super) fn put_block(&self, k: u128, v: Option<Unchecked>) {
        let mut g = self.blocks.lock().unwrap_or_else(|e| e.into_inner());
        if g.len() >= CACHE_ENTRIES {
            g.clear();
        }
        g.insert(k, v);
    }
    pub(super) fn get_isolated(&self, k: u128) -> Option<Option<u64>> {
        let g = self.isolated.lock().unwrap_or_else(|e| e.into_inner());
        g.get(&k).copied()
    }
    pub(super) fn put_isolated(&self, k: u128, v: Option<u64>) {
        let mut g = self.isolated.lock().unwrap_or_else(|e| e.into_inner());
        if g.len() >= CACHE_ENTRIES {
            g.clear();
        }
        g.insert(k, v);
    }
}

/// Two independent 64-bit SipHash streams (fixed keys: deterministic) fed the same words.
pub(super) struct Digest(DefaultHasher, DefaultHasher);

impl Digest {
    pub(super) fn new(tag: u64) -> Digest {
        let mut d = Digest(DefaultHasher::new(), DefaultHasher::new());
        d.1.write_u64(0x9e37_79b9_7f4a_7c15);
        d.word(tag);
        d
    }
    pub(super) fn word(&mut self, v: u64) {
        self.0.write_u64(v);
        self.1.write_u64(v);
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
        (u128::from(self.0.finish()) << 64) | u128::from(self.1.finish())
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
