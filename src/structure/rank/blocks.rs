//! The blocks checked together (a decomposition's over-determined part, each group, the
//! under-determined part): their signatures, shapes and matrices on the reduced unknowns.

use super::rows::{PairRows, RowsView};
use crate::structure::count::{Equations, Part};
use nalgebra::{DMatrix, DMatrixViewMut};
use std::collections::HashSet;
use std::hash::Hasher;

/// A block to check: its pairs, its bodies (ascending), its part, its signature and its
/// matrix's (rows, columns).
pub(super) type Pending<'a> = (&'a [usize], &'a [usize], Part, Vec<u32>, (usize, usize));

/// Signatures of the blocks found sound (bodies, then pairs with their rows), hashed word by
/// word: the under- and over-determined blocks' signatures have millions of words at 10^6
/// bodies, and SipHash over them (again at every growth of the set) was 2 % of `analyze`.
pub(super) type Signatures = HashSet<Vec<u32>, std::hash::BuildHasherDefault<SignatureHasher>>;

/// A block's signature: its bodies, a separator, then each pair with its row count, four
/// bytes a word (every index fits: the flow network numbers its nodes and edges in `u32`).
/// The sound blocks' signatures are held through the next rounds' decompositions.
pub(super) fn block_signature(bodies: &[usize], block_eqs: &[usize], rows: &PairRows) -> Vec<u32> {
    let word = |x: usize| {
        debug_assert!(x < u32::MAX as usize);
        x as u32
    };
    let mut signature = Vec::with_capacity(bodies.len() + 1 + 2 * block_eqs.len());
    signature.extend(bodies.iter().map(|&x| word(x)));
    signature.push(u32::MAX);
    for &e in block_eqs {
        signature.push(word(e));
        signature.push(word(rows.nrows(e)));
    }
    signature
}

/// A multiplicative hash of 64-bit words (Fx-like; the keys are our own indices, not input
/// an attacker chooses to collide).
#[derive(Default)]
pub(super) struct SignatureHasher(u64);

impl SignatureHasher {
    pub(super) fn word(&mut self, w: u64) {
        self.0 = (self.0.rotate_left(5) ^ w).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl Hasher for SignatureHasher {
    fn write(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.word(u64::from_le_bytes(w.try_into().expect("8 bytes")));
        }
        let rest = words.remainder();
        if !rest.is_empty() {
            let mut w = [0u8; 8];
            w[..rest.len()].copy_from_slice(rest);
            self.word(u64::from_le_bytes(w));
        }
    }

    fn write_usize(&mut self, x: usize) {
        self.word(x as u64);
    }

    fn finish(&self) -> u64 {
        // The high bits mixed into the low ones (the table indexes by the low bits).
        self.0 ^ (self.0 >> 29)
    }
}

/// Rows and columns of the block's matrix ([`block_matrix`]) without building it.
pub(super) fn block_shape(
    b: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    rows: &PairRows,
    q: &[Option<DMatrix<f64>>],
) -> (usize, usize) {
    let nrows = block_eqs.iter().map(|&e| rows.nrows(e)).sum();
    let ncols = bodies.iter().map(|&x| width(b, q, x)).sum();
    (nrows, ncols)
}

/// Body `x`'s reduced unknowns: its basis's columns, all `b` for the identity.
pub(super) fn width(b: usize, q: &[Option<DMatrix<f64>>], x: usize) -> usize {
    q[x].as_ref().map_or(b, |m| m.ncols())
}

/// A pair's rows acting on one body's reduced unknowns (`rows · Q_x`, the rows themselves for
/// the identity basis), times `sign`, written into `dst`.
pub(super) fn put(
    dst: &mut DMatrixViewMut<'_, f64>,
    rows: RowsView<'_>,
    qx: &Option<DMatrix<f64>>,
    sign: f64,
) {
    match qx {
        None => dst.copy_from(&rows),
        // An owned copy: nalgebra's product reads a row-major view's columns past the slice it
        // makes of them (a debug build's bounds check stops it); the same product as before.
        Some(qx) => dst.copy_from(&(rows.into_owned() * qx)),
    }
    *dst *= sign;
}

/// The block's matrix: rows of `block_eqs`, columns the reduced unknowns of `bodies`
/// (ascending body indices).
pub(super) fn block_matrix(
    b: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &PairRows,
    q: &[Option<DMatrix<f64>>],
) -> DMatrix<f64> {
    debug_assert!(bodies.is_sorted());
    let width = |x: usize| width(b, q, x);
    let mut col = Vec::with_capacity(bodies.len());
    let mut ncols = 0;
    for &x in bodies {
        col.push(ncols);
        ncols += width(x);
    }
    let nrows: usize = block_eqs.iter().map(|&e| rows.nrows(e)).sum();
    let mut a = DMatrix::<f64>::zeros(nrows, ncols);
    let mut r0 = 0;
    for &e in block_eqs {
        let [h, o] = eqs.bodies(e);
        let n = rows.nrows(e);
        if h != o {
            for (x, sign) in [(h, -1.0), (o, 1.0)] {
                let Ok(k) = bodies.binary_search(&x) else {
                    continue;
                };
                if width(x) == 0 {
                    continue;
                }
                put(
                    &mut a.view_mut((r0, col[k]), (n, width(x))),
                    rows.get(e),
                    &q[x],
                    sign,
                );
            }
        }
        r0 += n;
    }
    a
}
