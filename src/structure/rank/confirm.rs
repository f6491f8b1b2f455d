//! Confirmation of a deficit at a random realization: the joints involved drawn again at
//! independent seeds.

use super::attempt::{Attempt, Touching};
use super::blocks::width;
use super::cache::Digest;
use super::exact::{MAX_EXACT_UNKNOWNS, exact_rank};
use super::float::{MAX_DENSE_UNKNOWNS, REL_TOL, Tol, cube, rank_of};
use super::rows::{Chunk, PAIRS_PER_CHUNK, PairRows, pair_rows_at};
use super::unknowns::reduced_basis;
use crate::mechanism::Mechanism;
use crate::structure::count::{Equations, Part};
use nalgebra::DMatrix;

/// The seed of the `attempt`-th independent redraw of a random realization `seed`.
fn fresh_seed(seed: u64, attempt: u64) -> u64 {
    seed ^ attempt.wrapping_mul(0x9e37_79b9_7f4a_7c15)
}

/// Draws a deficit is confirmed at (each independent of the analysis's and of the others).
const CONFIRM_DRAWS: u64 = 4;

/// The seeds of the draws that confirm a deficit in attempt `attempt` of [`check`](super::check).
pub(super) fn confirm_seeds(seed: u64, attempt: u64) -> impl Iterator<Item = u64> {
    (0..CONFIRM_DRAWS).map(move |i| fresh_seed(seed, attempt * CONFIRM_DRAWS + i))
}

/// A draw at which a block found deficient has full rank (`needed`: its rows, or its columns
/// for the over-determined block), among [`CONFIRM_DRAWS`] independent ones: then the first
/// draw was degenerate there. Each draw builds the block's pairs with their joints drawn at
/// its seed, on every body's `B` columns (an isolated freedom is a null direction of every
/// pair touching the body, so the rank is the one on the reduced unknowns), rank by the dense
/// SVD, or exactly ([`exact_rank`]) beyond [`MAX_DENSE_UNKNOWNS`]. A lowered pair keeps its
/// first rows at the other draw; beyond [`MAX_DENSE_UNKNOWNS`] a block with a lowered pair
/// keeps its deficit (the exact path builds whole pairs).
#[allow(clippy::too_many_arguments)]
pub(super) fn unconfirmed(
    m: &Mechanism,
    eqs: &Equations,
    block_eqs: &[usize],
    bodies: &[usize],
    rows: &PairRows,
    orig_rows: &[u8],
    (nrows, ncols): (usize, usize),
    needed: usize,
    seeds: impl Iterator<Item = u64>,
    work: &mut u64,
) -> Option<u64> {
    let untouched = block_eqs
        .iter()
        .all(|&e| rows.nrows(e) == usize::from(orig_rows[e]));
    if needed > nrows.min(ncols) {
        return None;
    }
    let b = m.b() as usize;
    let full = b * bodies.len();
    let col = |x: usize| bodies.binary_search(&x).ok().map(|k| k * b);
    for second in seeds {
        let rank = if full.max(nrows) <= MAX_DENSE_UNKNOWNS {
            // A lowered pair keeps as many rows at the other draw as it has here: lowering
            // drops rows from the end, so its first ones (a block can hold a pair an earlier
            // redundancy lowered, and its deficit is then as much a draw's as any other).
            let drawn: Vec<DMatrix<f64>> = block_eqs
                .iter()
                .map(|&e| {
                    let r = pair_rows_at(m, eqs, e, second);
                    let k = rows.nrows(e).min(r.nrows());
                    if k < r.nrows() {
                        r.rows(0, k).into_owned()
                    } else {
                        r
                    }
                })
                .collect();
            let n: usize = drawn.iter().map(|r| r.nrows()).sum();
            let mut a = DMatrix::<f64>::zeros(n, full);
            let mut r0 = 0;
            for (&e, r) in block_eqs.iter().zip(&drawn) {
                let [h, o] = eqs.bodies(e);
                if h != o {
                    for (x, sign) in [(h, -1.0), (o, 1.0)] {
                        if let Some(c) = col(x) {
                            let mut v = a.view_mut((r0, c), (r.nrows(), b));
                            v += r * sign;
                        }
                    }
                }
                r0 += r.nrows();
            }
            *work = work.saturating_add(cube(n.max(full)));
            rank_of(
                &a,
                &Tol {
                    margins: None,
                    rel: REL_TOL,
                    abs: 0.0,
                },
            )
        } else if untouched && ncols <= MAX_EXACT_UNKNOWNS {
            exact_rank(m, eqs, block_eqs, bodies, second, work)
        } else {
            return None;
        };
        if rank >= needed {
            return Some(second);
        }
    }
    None
}

impl Attempt<'_> {
    /// An isolated freedom at a random realization is confirmed at a second one: the body's
    /// pairs drawn again (a generic nullity is the smallest over realizations). The joints of
    /// the bodies whose freedom a second draw does not have, with that draw's seed (sorted;
    /// empty without confirmation).
    pub(super) fn unconfirmed_isolated(
        &self,
        eqs: &Equations,
        touching: &Touching,
    ) -> Vec<(usize, u64)> {
        let (Some(attempt), Some(seed)) = (self.confirm, self.used.seed) else {
            return Vec::new();
        };
        let (m, b, q) = (self.m, self.b, &self.q);
        let iso_bodies: Vec<usize> = (0..eqs.nodes)
            .filter(|&x| x != m.frame && !eqs.is_element(x) && width(b, q, x) < b)
            .collect();
        let spurious = crate::par::map(iso_bodies.len(), |i| {
            let x = iso_bodies[i];
            let mine = touching.pairs(x);
            let key = self
                .cache
                .map(|_| self.isolated_key(eqs, x, mine, seed, attempt));
            if let (Some(c), Some(k)) = (self.cache, key)
                && let Some(hit) = c.get_isolated(k)
            {
                return hit;
            }
            let found = confirm_seeds(seed, attempt).find(|&second| {
                let fresh = PairRows::from_chunks(
                    b,
                    mine.chunks(PAIRS_PER_CHUNK)
                        .map(|c| {
                            let mut chunk = Chunk::default();
                            c.iter().for_each(|&e| {
                                chunk.push_matrix(&pair_rows_at(m, eqs, e as usize, second))
                            });
                            chunk
                        })
                        .collect(),
                );
                let again = reduced_basis(b, (0..mine.len()).map(|i| fresh.get(i)), &self.tol);
                again.as_ref().map_or(b, |a| a.ncols()) > width(b, q, x)
            });
            if let (Some(c), Some(k)) = (self.cache, key) {
                c.put_isolated(k, found);
            }
            found
        });
        let joint = &eqs.joint;
        let mut suspects: Vec<(usize, u64)> = iso_bodies
            .iter()
            .zip(spurious)
            .filter_map(|(&x, s)| s.map(|s| (x, s)))
            .flat_map(|(x, s)| {
                touching
                    .pairs(x)
                    .iter()
                    .map(move |&e| (joint[e as usize], s))
            })
            .collect();
        suspects.sort_unstable();
        suspects.dedup();
        suspects
    }

    /// The cache key of body `x`'s confirmation ([`unconfirmed_isolated`]): everything it
    /// depends on (the tolerance, the draws' seeds, the body's width, and each pair touching
    /// it: its joint, that joint's inputs and its rows at this draw).
    fn isolated_key(
        &self,
        eqs: &Equations,
        x: usize,
        mine: &[u32],
        seed: u64,
        attempt: u64,
    ) -> u128 {
        let mut d = Digest::new(4);
        self.tol_words.iter().for_each(|&w| d.word(w));
        d.word(seed);
        d.word(attempt);
        d.word(width(self.b, &self.q, x) as u64);
        d.word(mine.len() as u64);
        for &e in mine {
            let e = e as usize;
            d.word(eqs.joint[e] as u64);
            d.word(u64::from(eqs.driven[e]));
            d.word(u64::from(eqs.input_only[e]));
            d.wide(self.rd[e]);
        }
        d.finish()
    }

    /// A draw at which the deficient block (`shape`: rows, columns) has full rank, when this
    /// attempt confirms deficits ([`unconfirmed`]); `None` confirms the deficit.
    pub(super) fn unconfirmed_deficit(
        &mut self,
        eqs: &Equations,
        block_eqs: &[usize],
        bodies: &[usize],
        part: Part,
        shape: (usize, usize),
    ) -> Option<u64> {
        let (Some(attempt), Some(seed)) = (self.confirm, self.used.seed) else {
            return None;
        };
        let needed = if part == Part::Over { shape.1 } else { shape.0 };
        unconfirmed(
            self.m,
            eqs,
            block_eqs,
            bodies,
            &self.rows,
            &self.orig_rows,
            shape,
            needed,
            confirm_seeds(seed, attempt),
            &mut self.work,
        )
    }
}
