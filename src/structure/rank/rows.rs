//! Every pair's constraint rows, stored flat in chunks of consecutive pairs, and how they are
//! built at the file's geometry or a random realization.

use crate::mechanism::{Geometry, Mechanism};
use crate::motion;
use crate::structure::count::Equations;
use nalgebra::{DMatrix, Dyn, MatrixView};
use std::collections::HashMap;

/// A pair's rows as [`PairRows`] stores them (row-major).
pub(super) type RowsView<'a> = MatrixView<'a, f64, Dyn, Dyn, Dyn, Dyn>;

/// Rows of every pair at the given joint geometry: its constraint rows with its share of the
/// driven DOF fixed, and (when `with_free`, for the file's configuration) its constraint rows
/// alone (no input; empty otherwise).
pub(super) fn pair_rows(
    m: &Mechanism,
    geoms: &[Geometry],
    seed: Option<u64>,
    redrawn: &HashMap<usize, u64>,
    eqs: &Equations,
    with_free: bool,
) -> (PairRows, PairRows) {
    use rayon::prelude::*;
    let b = m.b() as usize;
    let n = eqs.len();
    let at = Realization {
        m,
        geoms,
        seed,
        redrawn,
        eqs,
        with_free,
    };
    let chunks = n.div_ceil(PAIRS_PER_CHUNK);
    let built: Vec<(Chunk, Chunk)> = if n >= 2 * PAIRS_PER_CHUNK {
        (0..chunks).into_par_iter().map(|c| at.chunk(c)).collect()
    } else {
        (0..chunks).map(|c| at.chunk(c)).collect()
    };
    let (rows, free): (Vec<Chunk>, Vec<Chunk>) = built.into_iter().unzip();
    let free = if with_free {
        PairRows::from_chunks(b, free)
    } else {
        PairRows::from_chunks(b, Vec::new())
    };
    (PairRows::from_chunks(b, rows), free)
}

/// The joint geometry [`pair_rows`] builds the rows at: the file's (`geoms`) or a random
/// realization (`seed`, the joints in `redrawn` at their own seeds).
struct Realization<'a> {
    m: &'a Mechanism,
    geoms: &'a [Geometry],
    seed: Option<u64>,
    redrawn: &'a HashMap<usize, u64>,
    eqs: &'a Equations,
    with_free: bool,
}

impl Realization<'_> {
    /// Chunk `c` of consecutive pairs, built on its own (in parallel): a joint's models are
    /// built once per chunk (its pairs are consecutive), on the stack, all of a chunk's
    /// together ([`motion::pair_rows_many`] runs several joints' Gram-Schmidt in lockstep).
    /// The pairs' rows, and their rows without input (`with_free`).
    fn chunk(&self, c: usize) -> (Chunk, Chunk) {
        let (m, eqs, with_free) = (self.m, self.eqs, self.with_free);
        let b = m.b() as usize;
        let pairs = c * PAIRS_PER_CHUNK..eqs.len().min((c + 1) * PAIRS_PER_CHUNK);
        let (jobs, reads) = self.models(pairs.clone());
        // Room for the rows the count gives each pair (the models give that many): a chunk
        // grown by doubling copied its rows about twice over.
        let expected: usize = eqs.cap[pairs.clone()].iter().map(|&k| k as usize).sum();
        let mut rows = Chunk::with_capacity(pairs.len(), expected * b);
        let mut free = if with_free {
            Chunk::with_capacity(pairs.len(), expected * b)
        } else {
            Chunk::default()
        };
        SCRATCH.with_borrow_mut(|scratch| {
            let models = match self.seed {
                Some(seed) => motion::pair_rows_many(
                    m,
                    &jobs,
                    |ji| {
                        let seed = self.redrawn.get(&ji).copied().unwrap_or(seed);
                        motion::random_pair_geometry(m, seed, ji)
                    },
                    scratch,
                ),
                None => motion::pair_rows_many(m, &jobs, |ji| &self.geoms[ji], scratch),
            };
            for (e, [own, f]) in pairs.zip(reads) {
                let own = models.get(own);
                if eqs.input_only[e] {
                    // A multiple joint's inputs between two of its bodies: the driven rows alone.
                    let f = models.get(f);
                    let flat = |v: &[[f64; 6]]| -> Vec<f64> {
                        v.iter().flat_map(|r| r[..b].iter().copied()).collect()
                    };
                    let (dv, fv) = (flat(own), flat(f));
                    let r = input_rows(
                        RowsView::from_slice_with_strides(&dv, own.len(), b, b, 1),
                        RowsView::from_slice_with_strides(&fv, f.len(), b, b, 1),
                    );
                    rows.push_matrix(&r);
                    if with_free {
                        free.push_rows(&[], b);
                    }
                } else {
                    // A pair's rows with its own share of the driven DOF fixed; without input.
                    rows.push_rows(own, b);
                    if with_free {
                        free.push_rows(models.get(f), b);
                    }
                }
            }
        });
        (rows, free)
    }

    /// The models the pairs need (joint, driven), and which of them each pair reads: a pair's
    /// own, and the free one (nothing driven) where it needs it (`usize::MAX` otherwise).
    #[allow(clippy::type_complexity)]
    fn models(&self, pairs: std::ops::Range<usize>) -> (Vec<(usize, u32)>, Vec<[usize; 2]>) {
        let eqs = self.eqs;
        let mut jobs: Vec<(usize, u32)> = Vec::with_capacity(pairs.len());
        let mut reads: Vec<[usize; 2]> = Vec::with_capacity(pairs.len());
        let mut memo: [Option<(usize, u32, usize)>; 2] = [None, None];
        let mut model = |ji: usize, driven: u32| {
            let slot = usize::from(driven == 0);
            match memo[slot] {
                Some((j, d, k)) if j == ji && d == driven => k,
                _ => {
                    jobs.push((ji, driven));
                    memo[slot] = Some((ji, driven, jobs.len() - 1));
                    jobs.len() - 1
                }
            }
        };
        for e in pairs {
            let ji = eqs.joint[e];
            let own = model(ji, eqs.driven[e]);
            let free = if eqs.input_only[e] || self.with_free {
                model(ji, 0)
            } else {
                usize::MAX
            };
            reads.push([own, free]);
        }
        (jobs, reads)
    }
}

thread_local! {
    /// [`pair_rows`]' model buffers, one per thread, reused from chunk to chunk.
    static SCRATCH: std::cell::RefCell<motion::Scratch> = std::cell::RefCell::default();
}

/// Pairs per chunk of [`PairRows`].
pub(super) const PAIRS_PER_CHUNK: usize = 1024;

/// The rows of consecutive pairs, as they are built.
#[derive(Default)]
pub(super) struct Chunk {
    pub(super) values: Vec<f64>,
    counts: Vec<u32>,
}

impl Chunk {
    /// A chunk with room for `pairs` pairs and `values` values.
    pub(super) fn with_capacity(pairs: usize, values: usize) -> Chunk {
        Chunk {
            values: Vec::with_capacity(values),
            counts: Vec::with_capacity(pairs),
        }
    }

    fn push_rows(&mut self, rows: &[[f64; 6]], b: usize) {
        if b == 6 {
            // Full rows lie back to back: one copy for all of them (a copy call a row was
            // the larger part of the copies of the rank check's rows at 10^6 bodies).
            self.values.extend_from_slice(rows.as_flattened());
        } else {
            for r in rows {
                self.values.extend_from_slice(&r[..b]);
            }
        }
        self.counts.push(rows.len() as u32);
    }

    pub(super) fn push_matrix(&mut self, a: &DMatrix<f64>) {
        for i in 0..a.nrows() {
            self.values.extend(a.row(i).iter().copied());
        }
        self.counts.push(a.nrows() as u32);
    }
}

/// Every pair's constraint rows (`n × B`, row-major), stored flat in chunks of
/// [`PAIRS_PER_CHUNK`] consecutive pairs: a small heap matrix per pair cost seconds at 10^6
/// pairs. A pair keeps the room of its first rows; rows that replace them and need more room
/// move to the end of its chunk.
pub(crate) struct PairRows {
    pub(super) b: usize,
    /// Per pair: its first value within its chunk, its rows now, the rows its room holds.
    pub(super) start: Vec<u32>,
    pub(super) n: Vec<u32>,
    room: Vec<u32>,
    pub(super) chunks: Vec<Vec<f64>>,
}

impl PairRows {
    pub(super) fn from_chunks(b: usize, built: Vec<Chunk>) -> PairRows {
        let total: usize = built.iter().map(|c| c.counts.len()).sum();
        let mut start = Vec::with_capacity(total);
        let mut n = Vec::with_capacity(total);
        let mut chunks = Vec::with_capacity(built.len());
        for c in built {
            let mut at = 0u32;
            for &k in &c.counts {
                start.push(at);
                n.push(k);
                at += k * b as u32;
            }
            chunks.push(c.values);
        }
        PairRows {
            b,
            start,
            room: n.clone(),
            n,
            chunks,
        }
    }

    /// Number of pairs.
    pub(super) fn len(&self) -> usize {
        self.n.len()
    }

    /// Rows of pair `e`.
    pub(super) fn nrows(&self, e: usize) -> usize {
        self.n[e] as usize
    }

    pub(super) fn values(&self, e: usize) -> &[f64] {
        let s = self.start[e] as usize;
        &self.chunks[e / PAIRS_PER_CHUNK][s..s + self.nrows(e) * self.b]
    }

    /// Pair `e`'s rows as a matrix.
    pub(super) fn get(&self, e: usize) -> RowsView<'_> {
        RowsView::from_slice_with_strides(self.values(e), self.nrows(e), self.b, self.b, 1)
    }

    /// [`PairRows::get`], `None` past the last pair.
    pub(super) fn try_get(&self, e: usize) -> Option<RowsView<'_>> {
        (e < self.len()).then(|| self.get(e))
    }

    /// Replace pair `e`'s rows by those of `a` (`B` columns).
    pub(super) fn set(&mut self, e: usize, a: &DMatrix<f64>) {
        let b = self.b;
        let k = a.nrows();
        let chunk = &mut self.chunks[e / PAIRS_PER_CHUNK];
        if k > self.room[e] as usize {
            self.start[e] = chunk.len() as u32;
            self.room[e] = k as u32;
            chunk.resize(chunk.len() + k * b, 0.0);
        }
        let s = self.start[e] as usize;
        for i in 0..k {
            for j in 0..b {
                chunk[s + i * b + j] = a[(i, j)];
            }
        }
        self.n[e] = k as u32;
    }

    /// Remove row `r` of pair `e`.
    pub(super) fn remove_row(&mut self, e: usize, r: usize) {
        let b = self.b;
        let (s, k) = (self.start[e] as usize, self.nrows(e));
        if r >= k {
            return;
        }
        self.chunks[e / PAIRS_PER_CHUNK].copy_within(s + (r + 1) * b..s + k * b, s + r * b);
        self.n[e] -= 1;
    }
}

/// Pair `e`'s rows as [`pair_rows`] builds them at a random realization, its joint drawn at
/// `seed`.
pub(super) fn pair_rows_at(m: &Mechanism, eqs: &Equations, e: usize, seed: u64) -> DMatrix<f64> {
    let b = m.b() as usize;
    let ji = eqs.joint[e];
    let g = motion::random_joint_geometry(m, seed, ji);
    let flat = |driven: u32| -> (Vec<f64>, usize) {
        let v = motion::pair_stack_model(m, ji, &g, driven).rows;
        let n = v.len();
        let values = v
            .as_slice()
            .iter()
            .flat_map(|r| r[..b].iter().copied())
            .collect();
        (values, n)
    };
    let (own, n) = flat(eqs.driven[e]);
    let own = RowsView::from_slice_with_strides(&own, n, b, b, 1);
    if eqs.input_only[e] {
        let (free, k) = flat(0);
        input_rows(own, RowsView::from_slice_with_strides(&free, k, b, b, 1))
    } else {
        own.into_owned()
    }
}

/// The rows of `own` (a pair's rows with its driven DOF fixed) outside the span of `free` (its
/// rows with no input): its input rows, orthonormal.
pub(super) fn input_rows(own: RowsView<'_>, free: RowsView<'_>) -> DMatrix<f64> {
    let b = own.ncols();
    let mut basis: Vec<Vec<f64>> = (0..free.nrows())
        .map(|i| free.row(i).iter().copied().collect())
        .collect();
    let base = basis.len();
    for i in 0..own.nrows() {
        let mut v: Vec<f64> = own.row(i).iter().copied().collect();
        for _ in 0..2 {
            for q in &basis {
                let d: f64 = q.iter().zip(&v).map(|(a, c)| a * c).sum();
                for (x, qk) in v.iter_mut().zip(q) {
                    *x -= d * qk;
                }
            }
        }
        let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if n > 1e-8 {
            basis.push(v.iter().map(|x| x / n).collect());
        }
    }
    let extra = basis.len() - base;
    DMatrix::from_fn(extra, b, |i, k| basis[base + i][k])
}

#[cfg(test)]
/// A column-major matrix as a row view (the tests' matrices).
pub(super) fn view(a: &DMatrix<f64>) -> RowsView<'_> {
    RowsView::from_slice_with_strides(a.as_slice(), a.nrows(), a.ncols(), 1, a.nrows())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::GeometrySource;
    use crate::joint::JointType;

    /// The flat rows of every pair (built chunk by chunk, each joint's model once per chunk,
    /// the random geometry drawn where it is used) are exactly the rows of the pair's own
    /// model, the heap matrix per pair they replaced: random mechanisms of mixed joint types,
    /// and a shared joint with inputs (element pairs and input-only pairs).
    #[test]
    fn pair_rows_are_the_pair_models() {
        let mut cases = Vec::new();
        for (planar, seed) in [(false, 2), (true, 5)] {
            cases.push(
                crate::generate::random(3000, planar, seed)
                    .expect("valid")
                    .0,
            );
        }
        cases.push(crate::generate::star(2500, JointType::S, false, true, true).expect("valid"));
        for m in &cases {
            let eqs = Equations::of(m);
            let (geoms, used) =
                crate::geometry::geometries(m, GeometrySource::Random { seed: 3 }, None)
                    .expect("random");
            assert!(eqs.len() > 2 * PAIRS_PER_CHUNK, "several chunks");
            let (rows, free) = pair_rows(m, &[], used.seed, &HashMap::new(), &eqs, false);
            assert_eq!(rows.len(), eqs.len());
            assert_eq!(free.len(), 0);
            // The file's geometry (here the same values, given), with the rows without input.
            let (file_rows, free) = pair_rows(m, &geoms, None, &HashMap::new(), &eqs, true);
            assert_eq!(free.len(), eqs.len());
            for e in 0..eqs.len() {
                let ji = eqs.joint[e];
                let want = if eqs.input_only[e] {
                    let own = motion::pair_model(m, ji, &geoms[ji], eqs.driven[e]).rows;
                    let f = motion::pair_model(m, ji, &geoms[ji], 0).rows;
                    input_rows(view(&own), view(&f))
                } else {
                    motion::pair_model(m, ji, &geoms[ji], eqs.driven[e]).rows
                };
                // Bit for bit (the rows are built several joints at a time).
                let bits = |a: &DMatrix<f64>| a.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(rows.get(e).into_owned(), want, "pair {e}");
                assert_eq!(bits(&rows.get(e).into_owned()), bits(&want), "pair {e}");
                assert_eq!(
                    bits(&file_rows.get(e).into_owned()),
                    bits(&want),
                    "pair {e}"
                );
                let want_free = if eqs.input_only[e] {
                    DMatrix::zeros(0, m.b() as usize)
                } else {
                    motion::pair_model(m, ji, &geoms[ji], 0).rows
                };
                assert_eq!(free.get(e).into_owned(), want_free, "pair {e}");
            }
        }
    }

    /// Every chunk of rows is built in the room the count gives its pairs (its equations: the
    /// models give as many rows at a random realization), never grown: grown by doubling, the
    /// chunks of a 10^6-body mechanism copied their 330 MB of rows about once more and held up
    /// to twice the room.
    #[test]
    fn pair_rows_chunks_are_sized_once() {
        let cases = [
            crate::generate::random(3000, false, 2).expect("valid").0,
            crate::generate::random(3000, true, 5).expect("valid").0,
            crate::generate::star(2500, JointType::S, false, true, true).expect("valid"),
        ];
        for m in &cases {
            let eqs = Equations::of(m);
            let (_, used) =
                crate::geometry::geometries(m, GeometrySource::Random { seed: 3 }, None)
                    .expect("random");
            let (rows, _) = pair_rows(m, &[], used.seed, &HashMap::new(), &eqs, false);
            assert!(rows.chunks.len() > 2, "several chunks");
            for (c, chunk) in rows.chunks.iter().enumerate() {
                assert!(!chunk.is_empty());
                assert_eq!(chunk.capacity(), chunk.len(), "chunk {c} of {}", m.name);
            }
        }
    }

    /// A chunk holds each pair's rows row by row, the first `b` values of each (full rows
    /// copied at once, narrower ones a row at a time), and reads them back as they were.
    #[test]
    fn chunk_rows_are_row_major() {
        let r = |k: f64| [k, k + 0.5, k + 1.0, k + 1.5, k + 2.0, k + 2.5];
        for b in [6, 3, 5] {
            let mut c = Chunk::default();
            c.push_rows(&[r(1.0), r(10.0)], b);
            c.push_rows(&[], b);
            c.push_rows(&[r(20.0)], b);
            let want: Vec<f64> = [r(1.0), r(10.0), r(20.0)]
                .iter()
                .flat_map(|x| x[..b].to_vec())
                .collect();
            assert_eq!(c.values, want, "b = {b}");
            assert_eq!(c.counts, [2, 0, 1]);
            let rows = PairRows::from_chunks(b, vec![c]);
            assert_eq!(rows.get(0).nrows(), 2);
            assert_eq!(rows.get(0)[(1, b - 1)], r(10.0)[b - 1]);
            assert_eq!(rows.get(2)[(0, 0)], 20.0);
        }
    }

    /// Rows replaced by more than their room, and rows removed, read back as a matrix would.
    #[test]
    fn pair_rows_set_and_remove() {
        let mut c = Chunk::default();
        c.push_rows(&[[1.0, 2.0, 3.0, 0.0, 0.0, 0.0]], 3);
        c.push_rows(
            &[
                [4.0, 5.0, 6.0, 0.0, 0.0, 0.0],
                [7.0, 8.0, 9.0, 0.0, 0.0, 0.0],
            ],
            3,
        );
        let mut rows = PairRows::from_chunks(3, vec![c]);
        let bigger = DMatrix::from_row_slice(3, 3, &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        rows.set(0, &bigger);
        assert_eq!(rows.get(0).into_owned(), bigger);
        assert_eq!(
            rows.get(1).into_owned(),
            DMatrix::from_row_slice(2, 3, &[4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
        );
        rows.remove_row(0, 1);
        assert_eq!(rows.get(0).into_owned(), bigger.clone().remove_row(1));
        rows.remove_row(1, 0);
        assert_eq!(
            rows.get(1).into_owned(),
            DMatrix::from_row_slice(1, 3, &[7.0, 8.0, 9.0])
        );
        assert_eq!(rows.nrows(1), 1);
        assert!(rows.try_get(2).is_none());
    }
}
