//! The exact decision: a block's rank over GF(2^61 − 1) at a random realization, for blocks
//! too large for the dense SVD.

use crate::mechanism::Mechanism;
use crate::structure::count::Equations;
use nalgebra::DMatrix;

/// Largest block whose rank is decided by exact sparse elimination (random realizations). The
/// giant group of a planar Assur II-B linkage of 10^5 bodies (21,603 unknowns) takes about a
/// second; the under-determined part of a random spatial mechanism of 2·10^4 bodies (111,000
/// unknowns, a random graph with little sparsity to exploit) took 45 s, so such blocks stay
/// with the count.
pub(super) const MAX_EXACT_UNKNOWNS: usize = 50_000;

/// The exact rank, over GF(2^61 − 1) at the random realization `seed`, of a block's rows
/// (its pairs acting on the full B columns of its bodies; bodies outside the block known).
/// An isolated freedom of a body is a null direction of every pair touching it, so the rank is
/// the one on the reduced unknowns.
pub(super) fn exact_rank(
    m: &Mechanism,
    eqs: &Equations,
    block_eqs: &[usize],
    bodies: &[usize],
    seed: u64,
    work: &mut u64,
) -> usize {
    use crate::exact::{Fp, SparseMatrix, dense};
    use crate::motion::exact as models;
    let b = m.b() as usize;
    let col = |x: usize| bodies.binary_search(&x).ok().map(|k| k * b);
    let mut a = SparseMatrix::with_groups(vec![b; bodies.len()]);
    for &e in block_eqs {
        let ji = eqs.joint[e];
        let rows = if eqs.input_only[e] {
            // The inputs alone: the driven model's rows beyond the free model's.
            let free = models::joint_rows(m, ji, seed, 0);
            let own = models::joint_rows(m, ji, seed, eqs.driven[e]);
            let stacked = DMatrix::from_fn(free.nrows() + own.nrows(), b, |i, k| {
                if i < free.nrows() {
                    free[(i, k)]
                } else {
                    own[(i - free.nrows(), k)]
                }
            });
            let extra: Vec<usize> = dense::independent_rows(&stacked)
                .into_iter()
                .filter(|&i| i >= free.nrows())
                .collect();
            DMatrix::from_fn(extra.len(), b, |i, k| stacked[(extra[i], k)])
        } else {
            models::joint_rows(m, ji, seed, eqs.driven[e])
        };
        let [h, o] = eqs.bodies(e);
        for r in 0..rows.nrows() {
            let mut entries: Vec<(u32, Fp)> = Vec::with_capacity(2 * b);
            for (x, negate) in [(h, true), (o, false)] {
                if h == o {
                    break;
                }
                let Some(c) = col(x) else {
                    continue;
                };
                for k in 0..b {
                    let v = rows[(r, k)];
                    entries.push(((c + k) as u32, if negate { Fp::ZERO - v } else { v }));
                }
            }
            a.push_row(entries);
        }
    }
    let f = crate::exact::Factor::new(&a);
    let st = f.stats();
    *work = work.saturating_add((st.factor_entries + st.input_entries) as u64);
    f.rank()
}
