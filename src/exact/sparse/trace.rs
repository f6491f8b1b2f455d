//! The row operations of a tracked factorization and the left null vectors expanded from
//! them.

use super::super::field::Fp;
use super::factor::Factor;
use crate::rng::SplitMix64;

/// The row operations of a tracked factorization, for the left null space.
///
/// Every row the elimination handles has a working id: the input rows first (`orig` gives
/// each one's row in the matrix), then each row a front leaves over, in order. A front turns
/// its rows (its members' rows) by an invertible map into its pivot rows (kept in the
/// factor), the rows it leaves over (new working rows, on later fronts) and the rows that
/// became zero (dependent). For each row left over or dependent the trace keeps its
/// combination of the front's rows: its own row plus multiples of the rows chosen as pivots
/// (at most the group's size), composed with the compression of the rows left over. The
/// dependent rows, expanded back through the fronts to the input rows, are a basis of the
/// left null space; [`Factor::random_left_null_vector`] expands a random combination of
/// them in one backward pass.
#[derive(Clone, Debug, Default)]
pub(super) struct Trace {
    /// The matrix row of each input working id.
    pub(super) orig: Vec<u32>,
    /// Rows of the matrix without entries (each a left null vector of its own).
    pub(super) empty: Vec<u32>,
    /// Working ids in all.
    pub(super) nids: u32,
    /// Per output row: its working id ([`DEPENDENT`] for a zero row) and the end of its
    /// terms in `terms` (they start where the previous output's end).
    pub(super) outputs: Vec<(u32, u32)>,
    /// `(working id of a front row, coefficient)`.
    pub(super) terms: Vec<(u32, Fp)>,
}

impl Trace {
    /// Bytes it holds.
    pub(super) fn bytes(&self) -> u64 {
        ((self.orig.len() + self.empty.len() + 2 * self.outputs.len() + 3 * self.terms.len())
            as u64)
            .saturating_mul(4)
    }
}

/// The combination of a front's input rows that one output row is, being accumulated.
pub(super) struct Combo<'a> {
    /// The working ids of the front's input rows.
    pub(super) in_ids: &'a [u32],
    /// `(input position, coefficient)`, positions distinct.
    pub(super) terms: Vec<(u32, Fp)>,
}

impl<'a> Combo<'a> {
    pub(super) fn new(in_ids: &'a [u32]) -> Combo<'a> {
        Combo {
            in_ids,
            terms: Vec::new(),
        }
    }

    pub(super) fn add(&mut self, at: u32, c: Fp) {
        match self.terms.iter_mut().find(|e| e.0 == at) {
            Some(e) => e.1 += c,
            None => self.terms.push((at, c)),
        }
    }

    /// Add `c` times front row `ri` (its own input row, if not chosen, and its multiples
    /// of the chosen rows).
    pub(super) fn add_row(
        &mut self,
        ri: usize,
        c: Fp,
        own: &[u32],
        tr: &[Fp],
        sg: usize,
        chosen: &[u32],
    ) {
        if own[ri] != CHOSEN {
            self.add(own[ri], c);
        }
        for (k, &at) in chosen.iter().enumerate() {
            let v = tr[ri * sg + k];
            if !v.is_zero() {
                self.add(at, c * v);
            }
        }
    }

    /// Record it as the combination of output row `id` ([`DEPENDENT`] for a zero row).
    pub(super) fn emit(mut self, t: &mut Trace, id: u32) {
        self.terms.sort_unstable_by_key(|e| e.0);
        t.outputs.push((id, t.terms.len() as u32));
        let in_ids = self.in_ids;
        t.terms.extend(
            self.terms
                .into_iter()
                .filter(|e| !e.1.is_zero())
                .map(|(at, c)| (in_ids[at as usize], c)),
        );
    }
}

/// The id of an output row that became zero (a dependent row).
pub(super) const DEPENDENT: u32 = u32::MAX;

/// A front row taken as a pivot (it has no own term any more).
pub(super) const CHOSEN: u32 = u32::MAX;

impl Factor {
    /// A random vector of the left null space {y : yᵀ A = 0} of the factored matrix, dense
    /// over its rows, or `None` when the factorization was not tracked
    /// ([`Factor::new_tracked_within`]). Each dependent row (and each row without entries)
    /// gets a random coefficient and the combination is expanded back through the fronts,
    /// last first: one pass over the trace. Its support is the union of the supports of all
    /// left null vectors (the rows in some self-stress) except with probability at most
    /// (rows)/p.
    pub fn random_left_null_vector(&self, rng: &mut SplitMix64) -> Option<Vec<Fp>> {
        let t = self.trace.as_ref()?;
        let mut w = vec![Fp::ZERO; t.nids as usize];
        let mut end = t.terms.len();
        for &(id, start) in t.outputs.iter().rev() {
            let (start, stop) = (start as usize, end);
            end = start;
            let v = if id == DEPENDENT {
                Fp::random(rng)
            } else {
                w[id as usize]
            };
            if v.is_zero() {
                continue;
            }
            for &(k, c) in &t.terms[start..stop] {
                w[k as usize] += v * c;
            }
        }
        let nrows = t.orig.len() + t.empty.len();
        let mut y = vec![Fp::ZERO; nrows];
        for (k, &r) in t.orig.iter().enumerate() {
            y[r as usize] = w[k];
        }
        for &r in &t.empty {
            y[r as usize] = Fp::random(rng);
        }
        Some(y)
    }
}
