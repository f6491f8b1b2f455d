//! Sparse exact elimination over GF(p) for large block-structured matrices.
//!
//! The columns are grouped in consecutive blocks (a body's B columns); rows are sparse. A
//! [`Factor`] eliminates one column group at a time (multifrontal Gaussian elimination): the
//! rows touching the group are gathered into a dense front, its columns are eliminated with
//! any nonzero pivot (exact, so pivot choice is only about sparsity), and the remaining rows,
//! compressed to echelon form, become a new block on the group's neighbours.
//!
//! Order: first the block triangular form. A maximum matching of the rows to the column
//! groups (a b-matching: a group takes as many rows as it has columns) and the strongly
//! connected components of "the rows matched to `k` touch `h`" order the groups so that,
//! when a group is eliminated, the only rows left on it are its own matched rows (and rows
//! the matching left over): a mechanism built body by body onto earlier bodies (every
//! generated random mechanism, an Assur linkage) is eliminated last body first with no fill
//! at all. Within a component the next group is the one with the smallest front (greedy
//! minimum degree over the groups, ties by index), as in the floating-point elimination of
//! the rank check.
//!
//! Rows a tier leaves over (its diagonal block is singular at this matrix: a square
//! mechanism Jacobian with its inputs, where a body's block loses rank) are set aside as
//! sparse rows rather than carried through the fronts of every later group they reach (each
//! such front was as wide as the union of the pivot rows the row had met: 19 × 7,470 on a
//! random spatial mechanism of 10^4 bodies). Each is reduced by a later group's pivot rows
//! once that group is eliminated, and becomes the pivot of the first free column it meets
//! or a dependent row (see `Carried`).
//!
//! Budget: [`Factor::new_within`] charges the real work (every front's rows × width per
//! pivot, the compression of the rows left over) to a work [`Meter`] and checks the real
//! memory (live blocks, the front being eliminated and the records kept) against the memory
//! limit before each front, so that a matrix whose fill explodes stops with a
//! [`BudgetExceeded`] instead of running on.
//!
//! [`RowBasis`] is the incremental counterpart for greedy redundancy removal: insert sparse
//! rows one at a time and learn whether each is independent of the rows kept so far.
//!
//! Everything is deterministic: no hash maps, ties broken by index.

use super::field::{Fp, axpy_sub, scale};
use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::rng::SplitMix64;
use nalgebra::DMatrix;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A sparse row: `(column, value)` pairs, columns increasing, values nonzero.
pub type SparseRow = Vec<(u32, Fp)>;

/// A sparse matrix by rows, with its columns grouped in consecutive blocks.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SparseMatrix {
    /// Number of columns.
    pub ncols: usize,
    /// The rows (normalized by [`SparseMatrix::push_row`]: columns increasing, no zeros).
    pub rows: Vec<SparseRow>,
    /// Sizes of the consecutive column groups (summing to `ncols`); empty means one group
    /// per column.
    pub group_sizes: Vec<usize>,
}

impl SparseMatrix {
    /// An empty matrix (no rows) with `ncols` columns, one group per column.
    pub fn new(ncols: usize) -> SparseMatrix {
        SparseMatrix {
            ncols,
            rows: Vec::new(),
            group_sizes: Vec::new(),
        }
    }

    /// An empty matrix whose columns are grouped in consecutive blocks of the given sizes
    /// (for a mechanism, B columns per movable body).
    pub fn with_groups(group_sizes: Vec<usize>) -> SparseMatrix {
        SparseMatrix {
            ncols: group_sizes.iter().sum(),
            rows: Vec::new(),
            group_sizes,
        }
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.rows.len()
    }

    /// Append a row given as `(column, value)` pairs in any order; repeated columns are
    /// added, zeros dropped.
    ///
    /// # Panics
    /// If a column is not below `ncols` (a caller's indexing error).
    pub fn push_row(&mut self, entries: impl IntoIterator<Item = (u32, Fp)>) {
        let mut row: SparseRow = entries.into_iter().collect();
        assert!(
            row.iter().all(|&(c, _)| (c as usize) < self.ncols),
            "sparse row column out of range"
        );
        row.sort_by_key(|e| e.0);
        let mut out: SparseRow = Vec::with_capacity(row.len());
        for (c, v) in row {
            match out.last_mut() {
                Some(last) if last.0 == c => last.1 += v,
                _ => out.push((c, v)),
            }
        }
        out.retain(|e| !e.1.is_zero());
        self.rows.push(out);
    }

    /// The sizes of the column groups (one per column when none were given).
    pub fn groups(&self) -> Vec<usize> {
        if self.group_sizes.is_empty() {
            vec![1; self.ncols]
        } else {
            self.group_sizes.clone()
        }
    }

    /// `A x` for a dense `x` of length `ncols`.
    pub fn mul_dense(&self, x: &[Fp]) -> Vec<Fp> {
        self.rows
            .iter()
            .map(|r| r.iter().map(|&(c, v)| v * x[c as usize]).sum())
            .collect()
    }

    /// `A x` for a sparse `x`.
    pub fn mul_sparse(&self, x: &[(u32, Fp)]) -> Vec<Fp> {
        let mut d = vec![Fp::ZERO; self.ncols];
        for &(c, v) in x {
            d[c as usize] = v;
        }
        self.mul_dense(&d)
    }

    /// `yᵀ A` for a sparse `y` over the rows.
    pub fn left_mul_sparse(&self, y: &[(u32, Fp)]) -> Vec<Fp> {
        let mut out = vec![Fp::ZERO; self.ncols];
        for &(r, w) in y {
            for &(c, v) in &self.rows[r as usize] {
                out[c as usize] += w * v;
            }
        }
        out
    }

    /// The transpose. Its column groups are the maximal runs of consecutive rows touching
    /// the same set of column groups (a joint's rows over its two bodies), so that
    /// factoring it is again block-structured.
    pub fn transpose(&self) -> SparseMatrix {
        let sizes = self.groups();
        let mut group_of = Vec::with_capacity(self.ncols);
        for (g, &s) in sizes.iter().enumerate() {
            group_of.extend(std::iter::repeat_n(g as u32, s));
        }
        let mut row_groups: Vec<usize> = Vec::new();
        let mut prev: Option<Vec<u32>> = None;
        for r in &self.rows {
            let mut set: Vec<u32> = r.iter().map(|&(c, _)| group_of[c as usize]).collect();
            set.dedup();
            match (&prev, row_groups.last_mut()) {
                (Some(p), Some(last)) if *p == set => *last += 1,
                _ => row_groups.push(1),
            }
            prev = Some(set);
        }
        let mut cols: Vec<SparseRow> = vec![Vec::new(); self.ncols];
        for (i, r) in self.rows.iter().enumerate() {
            for &(c, v) in r {
                cols[c as usize].push((i as u32, v));
            }
        }
        SparseMatrix {
            ncols: self.rows.len(),
            rows: cols,
            group_sizes: row_groups,
        }
    }

    /// The dense matrix (for tests and small cases).
    pub fn to_dense(&self) -> DMatrix<Fp> {
        let mut m = DMatrix::zeros(self.rows.len(), self.ncols);
        for (i, r) in self.rows.iter().enumerate() {
            for &(c, v) in r {
                m[(i, c as usize)] = v;
            }
        }
        m
    }

    /// The sparse matrix of a dense one, one group per column.
    pub fn from_dense(a: &DMatrix<Fp>) -> SparseMatrix {
        let mut s = SparseMatrix::new(a.ncols());
        for i in 0..a.nrows() {
            s.push_row((0..a.ncols()).map(|j| (j as u32, a[(i, j)])));
        }
        s
    }
}

/// A dense block of rows over some column groups, side by side in the order of `groups`
/// (the exact counterpart of the floating-point elimination's block).
#[derive(Clone, Debug, PartialEq)]
pub struct FpBlock {
    /// The column groups, distinct.
    pub groups: Vec<usize>,
    /// The rows: the groups' columns side by side.
    pub mat: DMatrix<Fp>,
}

/// Working block: row-major, never empty.
struct Blk {
    groups: Vec<usize>,
    nrows: usize,
    data: Vec<Fp>,
    /// The working id of its first row (its rows are `id..id + nrows`; see [`Trace`]).
    id: u32,
}

/// Bytes of one field element (and of one index) in the memory estimates.
const FP_BYTES: u64 = 8;

impl Blk {
    /// Bytes it holds (entries and group list).
    fn bytes(&self) -> u64 {
        ((self.data.len() + self.groups.len()) as u64).saturating_mul(FP_BYTES)
    }

    /// Its number of columns.
    fn width(&self) -> usize {
        self.data.len().checked_div(self.nrows).unwrap_or(0)
    }
}

/// The eliminated rows of one group: pivots reduced to the identity on the group's columns.
#[derive(Clone, Debug)]
struct Record {
    /// The group eliminated.
    group: u32,
    /// Entries per row of `rows`: `free`'s count + the others' sizes.
    width: u32,
    /// How many of `cols` are pivots, and how many after them are free columns.
    npiv: u32,
    nfree: u32,
    /// One allocation for three lists (a record per group: 10^6 of them at 10^6 bodies):
    /// the local columns of the pivots, in the order of the rows; the local columns left
    /// free (each gives a null vector); the other groups of the front, in column order
    /// after the group's own. Local columns and groups fit in `u32` (a front that wide
    /// would not fit in memory).
    cols: Box<[u32]>,
    /// The pivot rows without their pivot columns (in reduced echelon form those are the
    /// identity, and nothing reads them once the front is done): `npiv × width` row-major,
    /// each row its entries on the free columns (in that order), then on the others'
    /// columns.
    rows: Box<[Fp]>,
    /// Rows set aside by earlier tiers that took one of the group's free columns as their
    /// pivot ([`Carried`]), in that order: each is `x[col] = −Σ row · x` (global columns,
    /// the group's later free columns and groups eliminated after it). Their columns are in
    /// `free` (the pivot rows read them) but are not free in the null space.
    extra: Box<[(usize, SparseRow)]>,
}

impl Record {
    fn group(&self) -> usize {
        self.group as usize
    }

    fn width(&self) -> usize {
        self.width as usize
    }

    fn pivots(&self) -> &[u32] {
        &self.cols[..self.npiv as usize]
    }

    fn free(&self) -> &[u32] {
        &self.cols[self.npiv as usize..(self.npiv + self.nfree) as usize]
    }

    fn others(&self) -> &[u32] {
        &self.cols[(self.npiv + self.nfree) as usize..]
    }

    /// The local columns that are free in the null space (`free` minus the columns the
    /// set-aside rows took).
    fn open(&self) -> impl Iterator<Item = usize> + '_ {
        self.free()
            .iter()
            .map(|&q| q as usize)
            .filter(|&q| self.extra.iter().all(|e| e.0 != q))
    }
}

/// A row a square tier left over (its diagonal block is singular at this matrix), set aside
/// instead of joining the fronts of every later group it reaches (which made those fronts as
/// wide as the union of the pivot rows it met). It is reduced by each later group's pivot rows
/// once that group is eliminated (adding their other columns to it) until it either becomes
/// zero (a dependent row) or meets a free column of that group, whose pivot it becomes (an
/// extra row of the group's [`Record`]). The result is the same row space as carrying it in
/// the fronts, with work proportional to the records it meets, not to the front widths.
struct Carried {
    /// Its entries by group (each the group's columns), groups not yet eliminated.
    parts: std::collections::BTreeMap<usize, Vec<Fp>>,
    /// When tracking: its combination of working rows (ids ascending): its own working id
    /// and the rows of the group being met (a new working id after each group).
    combo: std::collections::BTreeMap<u32, Fp>,
    /// Entries of `parts`.
    len: usize,
}

impl Carried {
    fn entries(&self) -> usize {
        self.len + self.combo.len()
    }
}

/// Sizes measured during a factorization.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FactorStats {
    /// Largest front (rows, columns).
    pub max_front: (usize, usize),
    /// Entries kept in the factor (the eliminated rows), the fill measure.
    pub factor_entries: usize,
    /// Entries of the input.
    pub input_entries: usize,
    /// Rows found dependent (dropped as zero rows) during the elimination.
    pub dependent_rows: usize,
}

/// An exact sparse factorization of a matrix over GF(p): its rank and a null-space basis.
#[derive(Clone, Debug)]
pub struct Factor {
    sizes: Vec<usize>,
    offsets: Vec<usize>,
    records: Vec<Record>,
    rank: usize,
    stats: FactorStats,
    /// How the dependent rows combine the input rows ([`Factor::new_tracked_within`]).
    trace: Option<Trace>,
}

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
struct Trace {
    /// The matrix row of each input working id.
    orig: Vec<u32>,
    /// Rows of the matrix without entries (each a left null vector of its own).
    empty: Vec<u32>,
    /// Working ids in all.
    nids: u32,
    /// Per output row: its working id ([`DEPENDENT`] for a zero row) and the end of its
    /// terms in `terms` (they start where the previous output's end).
    outputs: Vec<(u32, u32)>,
    /// `(working id of a front row, coefficient)`.
    terms: Vec<(u32, Fp)>,
}

impl Trace {
    /// Bytes it holds.
    fn bytes(&self) -> u64 {
        ((self.orig.len() + self.empty.len() + 2 * self.outputs.len() + 3 * self.terms.len())
            as u64)
            .saturating_mul(4)
    }
}

/// The combination of a front's input rows that one output row is, being accumulated.
struct Combo<'a> {
    /// The working ids of the front's input rows.
    in_ids: &'a [u32],
    /// `(input position, coefficient)`, positions distinct.
    terms: Vec<(u32, Fp)>,
}

impl<'a> Combo<'a> {
    fn new(in_ids: &'a [u32]) -> Combo<'a> {
        Combo {
            in_ids,
            terms: Vec::new(),
        }
    }

    fn add(&mut self, at: u32, c: Fp) {
        match self.terms.iter_mut().find(|e| e.0 == at) {
            Some(e) => e.1 += c,
            None => self.terms.push((at, c)),
        }
    }

    /// Add `c` times front row `ri` (its own input row, if not chosen, and its multiples
    /// of the chosen rows).
    fn add_row(&mut self, ri: usize, c: Fp, own: &[u32], tr: &[Fp], sg: usize, chosen: &[u32]) {
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
    fn emit(mut self, t: &mut Trace, id: u32) {
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

/// A group's pivot rows just eliminated, for the rows set aside that reach it.
struct PivotRows<'a> {
    g: usize,
    /// Local pivot columns, one per row.
    pivots: &'a [usize],
    /// Local non-pivot columns.
    free: &'a [usize],
    /// The other groups of the rows, in column order after the group's own.
    others: &'a [usize],
    /// Row-major, `width` per row (the record's layout).
    rows: &'a [Fp],
    width: usize,
    /// When tracking: each pivot row's coefficients on the chosen rows (`sg` per row, the
    /// front's first rows), the chosen rows' front positions and the front's working ids.
    tr: Option<(&'a [Fp], &'a [u32], &'a [u32])>,
}

/// The rows set aside during a factorization ([`Carried`]).
struct CarriedSet<'a> {
    carried: &'a mut Vec<Option<Carried>>,
    carried_on: &'a mut Vec<Vec<u32>>,
    carried_len: &'a mut usize,
    sizes: &'a [usize],
    offsets: &'a [usize],
}

impl CarriedSet<'_> {
    /// `w -= f · (row over the groups of `others` from column `c0`)`, registering the
    /// groups it newly touches.
    fn sub_parts(&mut self, c: u32, f: Fp, others: &[usize], row: &[Fp]) {
        let Some(w) = self.carried[c as usize].as_mut() else {
            return;
        };
        let mut c0 = 0;
        for &h in others {
            let s = self.sizes[h];
            let src = &row[c0..c0 + s];
            c0 += s;
            if src.iter().all(|x| x.is_zero()) {
                continue;
            }
            let part = w.parts.entry(h).or_insert_with(|| {
                self.carried_on[h].push(c);
                w.len += s;
                vec![Fp::ZERO; s]
            });
            axpy_sub(part, f, src);
        }
    }

    /// The rows set aside that touch group `p.g` (ids `touching`), reduced by its pivot
    /// rows; then, free column by free column, one of those nonzero there (the shortest)
    /// becomes its pivot and is eliminated from the others. Returns the extra rows of the
    /// group's record (its pivots), how many rows became zero (dependent; emitted to the
    /// trace) and the work done.
    fn meet(
        &mut self,
        touching: &[u32],
        p: &PivotRows<'_>,
        mut trace: Option<&mut Trace>,
    ) -> (Vec<(usize, SparseRow)>, usize, u64) {
        let g = p.g;
        let sg = self.sizes[g];
        let mut work = 0u64;
        let before: usize = touching
            .iter()
            .filter_map(|&c| self.carried[c as usize].as_ref())
            .map(Carried::entries)
            .sum();
        // Each one's entries on the group after the reduction (zero on the pivot columns).
        let mut res: Vec<(u32, Vec<Fp>)> = Vec::with_capacity(touching.len());
        for &c in touching {
            let Some(mut vals) = self.carried[c as usize].as_mut().and_then(|w| {
                let v = w.parts.remove(&g)?;
                w.len -= v.len();
                Some(v)
            }) else {
                continue;
            };
            for (k, &pc) in p.pivots.iter().enumerate() {
                let f = vals[pc];
                if f.is_zero() {
                    continue;
                }
                let row = &p.rows[k * p.width..(k + 1) * p.width];
                axpy_sub(&mut vals, f, &row[..sg]);
                self.sub_parts(c, f, p.others, &row[sg..]);
                work += p.width as u64;
                if let (Some((tr, chosen, in_ids)), Some(w)) =
                    (p.tr, self.carried[c as usize].as_mut())
                {
                    for (m, &at) in chosen.iter().enumerate() {
                        let v = tr[k * sg + m];
                        if !v.is_zero() {
                            *w.combo.entry(in_ids[at as usize]).or_insert(Fp::ZERO) -= f * v;
                        }
                    }
                    work += chosen.len() as u64;
                }
            }
            res.push((c, vals));
        }
        // The groups whose entries changed: the pivot rows' and the absorbed rows'.
        let mut changed: Vec<usize> = p.others.to_vec();
        let mut extra = Vec::new();
        for &q in p.free {
            let best = res
                .iter()
                .enumerate()
                .filter(|(_, (_, v))| !v[q].is_zero())
                .min_by_key(|(i, (c, _))| {
                    let len = self.carried[*c as usize]
                        .as_ref()
                        .map_or(0, Carried::entries);
                    (len, *i)
                })
                .map(|(i, _)| i);
            let Some(b) = best else {
                continue;
            };
            let (cb, vb) = res.remove(b);
            let Some(wb) = self.carried[cb as usize].take() else {
                continue;
            };
            let inv = vb[q].inv();
            // Flatten its other groups once, for the eliminations below.
            let mut hs: Vec<usize> = Vec::with_capacity(wb.parts.len());
            let mut flat: Vec<Fp> = Vec::new();
            for (&h, part) in &wb.parts {
                hs.push(h);
                flat.extend_from_slice(part);
            }
            changed.extend_from_slice(&hs);
            for (ci, vi) in res.iter_mut() {
                let f = vi[q];
                if f.is_zero() {
                    continue;
                }
                let f = f * inv;
                axpy_sub(vi, f, &vb);
                self.sub_parts(*ci, f, &hs, &flat);
                work += (sg + flat.len() + wb.combo.len()) as u64;
                if let Some(wi) = self.carried[*ci as usize].as_mut() {
                    for (&id, &v) in &wb.combo {
                        *wi.combo.entry(id).or_insert(Fp::ZERO) -= f * v;
                    }
                }
            }
            // Its equation, normalized: x[q] = −Σ row · x.
            let mut row: SparseRow = vb
                .iter()
                .enumerate()
                .filter(|&(k, v)| k != q && !v.is_zero())
                .map(|(k, &v)| ((self.offsets[g] + k) as u32, v * inv))
                .collect();
            let mut c0 = 0;
            for &h in &hs {
                for k in 0..self.sizes[h] {
                    let v = flat[c0 + k];
                    if !v.is_zero() {
                        row.push(((self.offsets[h] + k) as u32, v * inv));
                    }
                }
                c0 += self.sizes[h];
            }
            row.sort_unstable_by_key(|e| e.0);
            work += row.len() as u64;
            extra.push((q, row));
        }
        // The rest are zero on the group: zero everywhere means dependent.
        changed.sort_unstable();
        changed.dedup();
        work += (res.len() * (changed.len() + 1)) as u64;
        let mut dependent = 0;
        for (c, _) in res {
            let Some(w) = self.carried[c as usize].as_mut() else {
                continue;
            };
            // Groups whose entries cancelled (only those changed here can have).
            for h in &changed {
                if w.parts
                    .get(h)
                    .is_some_and(|v| v.iter().all(|x| x.is_zero()))
                {
                    w.len -= self.sizes[*h];
                    w.parts.remove(h);
                }
            }
            if !w.parts.is_empty() {
                // Still carried: its combination becomes a working row of its own, so that
                // it stays as short as this front's (the trace chains, as for the fronts).
                if let Some(t) = trace.as_deref_mut()
                    && !(w.combo.len() == 1 && w.combo.values().all(|&v| v == Fp::ONE))
                {
                    t.outputs.push((t.nids, t.terms.len() as u32));
                    let combo = std::mem::take(&mut w.combo);
                    t.terms.extend(combo.into_iter().filter(|e| !e.1.is_zero()));
                    w.combo.insert(t.nids, Fp::ONE);
                    t.nids += 1;
                }
            } else {
                dependent += 1;
                if let (Some(t), Some(w)) = (trace.as_deref_mut(), self.carried[c as usize].take())
                {
                    t.outputs.push((DEPENDENT, t.terms.len() as u32));
                    t.terms
                        .extend(w.combo.into_iter().filter(|e| !e.1.is_zero()));
                } else {
                    self.carried[c as usize] = None;
                }
            }
        }
        let after: usize = touching
            .iter()
            .filter_map(|&c| self.carried[c as usize].as_ref())
            .map(Carried::entries)
            .sum();
        *self.carried_len = self.carried_len.saturating_sub(before) + after;
        (extra, dependent, work + touching.len() as u64)
    }
}

/// The id of an output row that became zero (a dependent row).
const DEPENDENT: u32 = u32::MAX;

/// A front row taken as a pivot (it has no own term any more).
const CHOSEN: u32 = u32::MAX;

impl Factor {
    /// Factor a sparse matrix, eliminating by its column groups. Rows touching the same
    /// set of groups are merged into one block first. No budget: see
    /// [`Factor::new_within`].
    pub fn new(a: &SparseMatrix) -> Factor {
        let Ok(f) = Factor::build(a, None, &mut |_, _| Ok::<(), std::convert::Infallible>(()));
        f
    }

    /// [`Factor::new`] within a budget: the elimination's work (each front's rows × width per
    /// pivot, the ordering, the compression of leftover rows) is charged to the meter, and
    /// before each front the memory then held (live blocks, the front, the records kept) is
    /// checked against the memory limit.
    pub fn new_within(a: &SparseMatrix, limits: &mut Limits<'_>) -> Result<Factor, BudgetExceeded> {
        Factor::build(a, None, &mut |work, bytes| limits.charge(work, bytes))
    }

    /// [`Factor::new_within`] with the groups' elimination tiers given (lower first; within a
    /// tier the greedy minimum-front order) instead of found from the matrix's block
    /// triangular form ([`elimination_tiers`]); `tiers` has one entry per column group.
    /// For a matrix whose own structure says little about a good order, such as the
    /// transpose of a mechanism's Jacobian (see [`crate::exact::models::pairs_stress_support`]).
    pub fn new_ordered_within(
        a: &SparseMatrix,
        tiers: &[u32],
        limits: &mut Limits<'_>,
    ) -> Result<Factor, BudgetExceeded> {
        Factor::build(a, Some(tiers), &mut |work, bytes| {
            limits.charge(work, bytes)
        })
    }

    /// [`Factor::new_within`], keeping the row operations that express each dependent row
    /// as a combination of the input rows ([`Trace`]), for
    /// [`Factor::random_left_null_vector`]: the left null space from this factorization,
    /// without factoring the transpose. The extra work is small: a front's rows carry their
    /// combination of its pivot rows (at most the group's size of coefficients each).
    pub fn new_tracked_within(
        a: &SparseMatrix,
        limits: &mut Limits<'_>,
    ) -> Result<Factor, BudgetExceeded> {
        Factor::build_tracked(a, None, true, &mut |work, bytes| limits.charge(work, bytes))
    }

    /// [`Factor::new_within`] (`track`: [`Factor::new_tracked_within`]) taking the matrix,
    /// which is dropped once split into its blocks, before the elimination: its rows are a
    /// vector each (hundreds of megabytes at 10^6 bodies) and nothing reads them afterwards.
    pub fn from_matrix_within(
        a: SparseMatrix,
        track: bool,
        limits: &mut Limits<'_>,
    ) -> Result<Factor, BudgetExceeded> {
        let (groups, blocks, input, trace) = Factor::prepare(&a, track);
        drop(a);
        let charge = &mut |work, bytes| limits.charge(work, bytes);
        charge(input.1, 0)?;
        Factor::run(groups, blocks, input.0, None, trace, true, charge)
    }

    /// The blocks of `a` and what [`Factor::run`] needs besides: the column groups, (the
    /// input's entries, the work of reading it) and the trace to start from.
    #[allow(clippy::type_complexity)]
    fn prepare<R: Rows + ?Sized>(
        a: &R,
        track: bool,
    ) -> (Vec<usize>, Vec<Blk>, (usize, u64), Option<Trace>) {
        let split = split_rows(a);
        let (blocks, orig, input) = (split.blocks, split.orig, split.entries);
        let trace = track.then(|| Trace {
            nids: orig.len() as u32,
            empty: split.empty,
            orig,
            outputs: Vec::new(),
            terms: Vec::new(),
        });
        let read = (input + a.ncols() + a.nrows()) as u64;
        (a.group_sizes(), blocks, (input, read), trace)
    }

    /// [`Factor::from_matrix_within`] for rows made one at a time ([`Rows`]) instead of
    /// held in a [`SparseMatrix`]: the same blocks, the same elimination, the same factor,
    /// without a vector per row alive beside the blocks (the peak of the geometric
    /// analysis at 10^6 bodies).
    pub(crate) fn from_rows_within<R: Rows + ?Sized>(
        a: &R,
        track: bool,
        limits: &mut Limits<'_>,
    ) -> Result<Factor, BudgetExceeded> {
        let (groups, blocks, input, trace) = Factor::prepare(a, track);
        let charge = &mut |work, bytes| limits.charge(work, bytes);
        charge(input.1, 0)?;
        Factor::run(groups, blocks, input.0, None, trace, true, charge)
    }

    fn build<E>(
        a: &SparseMatrix,
        tiers: Option<&[u32]>,
        charge: &mut dyn FnMut(u64, u64) -> Result<(), E>,
    ) -> Result<Factor, E> {
        Factor::build_tracked(a, tiers, false, charge)
    }

    fn build_tracked<E>(
        a: &SparseMatrix,
        tiers: Option<&[u32]>,
        track: bool,
        charge: &mut dyn FnMut(u64, u64) -> Result<(), E>,
    ) -> Result<Factor, E> {
        let (groups, blocks, input, trace) = Factor::prepare(a, track);
        charge(input.1, 0)?;
        Factor::run(groups, blocks, input.0, tiers, trace, true, charge)
    }

    /// Factor a matrix given as dense blocks over column groups of the given sizes (the
    /// interface of the floating-point elimination). Groups repeated within a block, or
    /// out of range, are a caller's error.
    pub fn from_blocks(sizes: &[usize], blocks: Vec<FpBlock>) -> Factor {
        let Ok(f) = Factor::from_blocks_charged(sizes, blocks, &mut |_, _| {
            Ok::<(), std::convert::Infallible>(())
        });
        f
    }

    fn from_blocks_charged<E>(
        sizes: &[usize],
        blocks: Vec<FpBlock>,
        charge: &mut dyn FnMut(u64, u64) -> Result<(), E>,
    ) -> Result<Factor, E> {
        let mut input = 0;
        let mut next_id = 0u32;
        let blks = blocks
            .into_iter()
            .filter(|b| !b.groups.is_empty() && b.mat.nrows() > 0)
            .map(|b| {
                let (m, n) = b.mat.shape();
                let mut data = Vec::with_capacity(m * n);
                for i in 0..m {
                    for j in 0..n {
                        data.push(b.mat[(i, j)]);
                    }
                }
                input += data.iter().filter(|x| !x.is_zero()).count();
                // Groups in increasing order (the elimination's invariant).
                let mut starts = Vec::with_capacity(b.groups.len());
                let mut c = 0;
                for &g in &b.groups {
                    starts.push(c);
                    c += sizes[g];
                }
                let mut order: Vec<usize> = (0..b.groups.len()).collect();
                order.sort_by_key(|&k| b.groups[k]);
                let mut sorted = Vec::with_capacity(m * n);
                for i in 0..m {
                    for &k in &order {
                        let s0 = i * n + starts[k];
                        sorted.extend_from_slice(&data[s0..s0 + sizes[b.groups[k]]]);
                    }
                }
                let id = next_id;
                next_id += m as u32;
                Blk {
                    groups: order.iter().map(|&k| b.groups[k]).collect(),
                    nrows: m,
                    data: sorted,
                    id,
                }
            })
            .collect();
        Factor::run(sizes.to_vec(), blks, input, None, None, true, charge)
    }

    /// The rank of [`Factor::from_rows_within`]'s factorization (untracked), taking the
    /// rows (dropped once split into blocks, as in [`Factor::from_matrix_within`]) and
    /// without keeping the records: the pivot rows, read only by the null-space
    /// functions, are the largest part of a factor (75 MB at 10^5 random spatial bodies).
    /// The same elimination, charged the same work, and checked against the memory limit
    /// with the records' bytes counted as if kept, so that a budget stops it where it
    /// stops the full factorization.
    pub(crate) fn rank_of_rows_within<R: Rows>(
        a: R,
        limits: &mut Limits<'_>,
    ) -> Result<usize, BudgetExceeded> {
        let (groups, blocks, input, trace) = Factor::prepare(&a, false);
        drop(a);
        let charge = &mut |work, bytes| limits.charge(work, bytes);
        charge(input.1, 0)?;
        Factor::run(groups, blocks, input.0, None, trace, false, charge).map(|f| f.rank)
    }

    /// The elimination. `charge(work, bytes)` is called with the work of each step and the
    /// memory held at its start (live blocks, the front about to be built, the records).
    /// Without `keep`, no record is kept (the factor then gives its rank and statistics,
    /// not its null space: for [`Factor::rank_of_rows_within`] only).
    #[allow(clippy::too_many_arguments)]
    fn run<E>(
        sizes: Vec<usize>,
        blocks: Vec<Blk>,
        input_entries: usize,
        given_tiers: Option<&[u32]>,
        mut trace: Option<Trace>,
        keep: bool,
        charge: &mut dyn FnMut(u64, u64) -> Result<(), E>,
    ) -> Result<Factor, E> {
        let n = sizes.len();
        let mut offsets = Vec::with_capacity(n);
        let mut acc = 0;
        for &s in &sizes {
            offsets.push(acc);
            acc += s;
        }
        let (tier, order_work) = match given_tiers {
            Some(t) => {
                let mut t = t.to_vec();
                t.resize(n, u32::MAX);
                (t, n as u64)
            }
            None => tiers(&sizes, &blocks),
        };
        charge(order_work, 0)?;
        let mut pool = Pool::new(&sizes, blocks.len() * 2);
        for b in blocks {
            pool.add(b);
        }
        // Bytes of the records kept so far.
        let mut record_bytes = 0u64;
        // Scratch: a stamp per group (dedup) and the front column of each group.
        let mut stamp = vec![0usize; n];
        let mut clock = 0usize;
        let mut pos = vec![0usize; n];
        let mut stamp_rescore = vec![0usize; n];
        let mut queue = GroupQueue::new(n);
        for (g, &tg) in tier.iter().enumerate().take(n) {
            let s = pool.score(g, &mut stamp, &mut clock);
            queue.set(g, (tg, s.0, s.1));
        }
        let mut done = vec![false; n];
        let mut records = Vec::with_capacity(if keep { n } else { 0 });
        let mut rank = 0;
        let mut stats = FactorStats {
            input_entries,
            ..FactorStats::default()
        };
        // Rows set aside ([`Carried`]; only in the block triangular order found here: a
        // caller's tiers say nothing about square diagonal blocks), the ids of those touching
        // each group (stale ids skipped), and their entries in all.
        let set_aside = given_tiers.is_none() && set_aside_enabled();
        let mut carried: Vec<Option<Carried>> = Vec::new();
        let mut carried_on: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut carried_len = 0usize;
        // Scratch vectors of one front, kept from front to front (a dozen allocations per
        // front were a tenth of the elimination at 10^6 bodies).
        let mut sc_others: Vec<usize> = Vec::new();
        let mut sc_front: Vec<Fp> = Vec::new();
        let mut sc_masks: Vec<u64> = Vec::new();
        let mut sc_order: Vec<usize> = Vec::new();
        let mut sc_in: Vec<u32> = Vec::new();
        let mut sc_own: Vec<u32> = Vec::new();
        let mut sc_tr: Vec<Fp> = Vec::new();
        let mut sc_chosen: Vec<u32> = Vec::new();
        let mut sc_rows: Vec<Fp> = Vec::new();
        while let Some(g) = queue.pop() {
            done[g] = true;
            let mut members = pool.take(g);
            let mut touching = std::mem::take(&mut carried_on[g]);
            touching.sort_unstable();
            touching.dedup();
            touching.retain(|&c| {
                carried[c as usize]
                    .as_ref()
                    .is_some_and(|w| w.parts.contains_key(&g))
            });
            // Neighbours to rescore: those on a narrow block of this front (a group reached
            // only through a wide block keeps its score, a heuristic that keeps long
            // carried rows from costing a pass over all their groups at every step).
            clock += 1;
            let rescore_mark = clock;
            for b in &members {
                if b.groups.len() <= WIDE_BLOCK {
                    for &h in &b.groups {
                        stamp_rescore[h] = rescore_mark;
                    }
                }
            }
            // Narrow blocks first: their rows are preferred as pivots, so that the rows
            // left over (and the pivot rows kept) stay narrow.
            members.sort_by_key(Blk::width);
            clock += 1;
            stamp[g] = clock;
            let mut others = std::mem::take(&mut sc_others);
            others.clear();
            for b in &members {
                for &h in &b.groups {
                    if stamp[h] != clock {
                        stamp[h] = clock;
                        others.push(h);
                    }
                }
            }
            others.sort_unstable();
            let sg = sizes[g];
            pos[g] = 0;
            let mut width = sg;
            for &h in &others {
                pos[h] = width;
                width += sizes[h];
            }
            let nrows: usize = members.iter().map(|b| b.nrows).sum();
            // The real cost of this front: the pivot loop passes over every row for each of
            // the group's columns (`sg` passes of nrows × width at most), and the memory
            // held while it is built (the blocks still live, the members and the front).
            let front_len = (nrows as u64).saturating_mul(width as u64);
            let member_bytes: u64 = members.iter().map(Blk::bytes).sum();
            charge(
                front_len.saturating_mul(sg as u64 + 1),
                pool.bytes
                    .saturating_add(member_bytes)
                    .saturating_add(record_bytes)
                    .saturating_add(trace.as_ref().map_or(0, Trace::bytes))
                    .saturating_add((carried_len as u64).saturating_mul(FP_BYTES))
                    .saturating_add(front_len.saturating_mul(FP_BYTES)),
            )?;
            let mut front = std::mem::take(&mut sc_front);
            front.clear();
            front.resize(nrows * width, Fp::ZERO);
            // Tracking: each front row's input position (`own`, until it is chosen as a
            // pivot) and its coefficients on the rows chosen so far (`tr`, `sg` per row).
            let tracking = trace.is_some();
            let mut in_ids = std::mem::take(&mut sc_in);
            let mut own = std::mem::take(&mut sc_own);
            let mut tr = std::mem::take(&mut sc_tr);
            let mut chosen = std::mem::take(&mut sc_chosen);
            in_ids.clear();
            own.clear();
            tr.clear();
            chosen.clear();
            if tracking {
                charge((nrows as u64).saturating_mul((sg * (sg + 2)) as u64), 0)?;
                for b in &members {
                    in_ids.extend(b.id..b.id + b.nrows as u32);
                }
                own.extend(0..nrows as u32);
                tr.resize(nrows * sg, Fp::ZERO);
            }
            let mut r0 = 0;
            for b in &members {
                let bw = b.width();
                for i in 0..b.nrows {
                    let src = &b.data[i * bw..(i + 1) * bw];
                    let dst = &mut front[(r0 + i) * width..(r0 + i + 1) * width];
                    let mut c0 = 0;
                    for &h in &b.groups {
                        let s = sizes[h];
                        dst[pos[h]..pos[h] + s].copy_from_slice(&src[c0..c0 + s]);
                        c0 += s;
                    }
                }
                r0 += b.nrows;
            }
            drop(members);
            stats.max_front = (stats.max_front.0.max(nrows), stats.max_front.1.max(width));
            // Eliminate the group's columns: reduced echelon on them among the pivot rows.
            let mut pivots = Vec::new();
            let mut free = Vec::new();
            let mut r = 0;
            for c in 0..sg {
                let Some(p) = (r..nrows).find(|&i| !front[i * width + c].is_zero()) else {
                    free.push(c);
                    continue;
                };
                // Keep the row order otherwise (narrow rows stay first).
                front[r * width..(p + 1) * width].rotate_right(width);
                let inv = front[r * width + c].inv();
                scale(&mut front[r * width + c..(r + 1) * width], inv);
                if tracking {
                    tr[r * sg..(p + 1) * sg].rotate_right(sg);
                    own[r..=p].rotate_right(1);
                    tr[r * sg + chosen.len()] = Fp::ONE;
                    chosen.push(own[r]);
                    own[r] = CHOSEN;
                    scale(&mut tr[r * sg..(r + 1) * sg], inv);
                }
                for i in 0..nrows {
                    if i == r {
                        continue;
                    }
                    let f = front[i * width + c];
                    if !f.is_zero() {
                        let (dst, src) = two_rows(&mut front, width, i, r);
                        axpy_sub(&mut dst[c..], f, &src[c..]);
                        // Rows above are pivot rows: their combinations are needed only
                        // to reduce the rows set aside that reach this group.
                        if tracking && (i > r || !touching.is_empty()) {
                            let (dst, src) = two_rows(&mut tr, sg, i, r);
                            axpy_sub(dst, f, src);
                        }
                    }
                }
                pivots.push(c);
                r += 1;
            }
            rank += r;
            // Which of the others' groups each row touches.
            let words = others.len().div_ceil(64);
            let mut masks = std::mem::take(&mut sc_masks);
            masks.clear();
            masks.resize(nrows * words, 0);
            for i in 0..nrows {
                let row = &front[i * width..(i + 1) * width];
                for (k, &h) in others.iter().enumerate() {
                    if row[pos[h]..pos[h] + sizes[h]].iter().any(|x| !x.is_zero()) {
                        masks[i * words + k / 64] |= 1 << (k % 64);
                    }
                }
            }
            // The rest: rows r.. split by the groups they touch, each part compressed.
            if r < nrows {
                let mut order = std::mem::take(&mut sc_order);
                order.clear();
                order.extend(r..nrows);
                order.sort_by(|&a, &b| {
                    masks[a * words..(a + 1) * words].cmp(&masks[b * words..(b + 1) * words])
                });
                let mut i = 0;
                while i < order.len() {
                    let key = &masks[order[i] * words..(order[i] + 1) * words];
                    let mut j = i;
                    while j < order.len() && masks[order[j] * words..(order[j] + 1) * words] == *key
                    {
                        j += 1;
                    }
                    let groups: Vec<usize> = (0..others.len())
                        .filter(|&k| key[k / 64] >> (k % 64) & 1 == 1)
                        .map(|k| others[k])
                        .collect();
                    let bw: usize = groups.iter().map(|&h| sizes[h]).sum();
                    let n_in = j - i;
                    if bw == 0 {
                        stats.dependent_rows += n_in;
                        if let Some(t) = trace.as_mut() {
                            for &ri in &order[i..j] {
                                let mut combo = Combo::new(&in_ids);
                                combo.add_row(ri, Fp::ONE, &own, &tr, sg, &chosen);
                                combo.emit(t, DEPENDENT);
                            }
                        }
                        i = j;
                        continue;
                    }
                    let mut data = Vec::with_capacity(n_in * bw);
                    for &ri in &order[i..j] {
                        let row = &front[ri * width..(ri + 1) * width];
                        for &h in &groups {
                            data.extend_from_slice(&row[pos[h]..pos[h] + sizes[h]]);
                        }
                    }
                    let kept = if n_in > bw {
                        charge(
                            (n_in as u64).saturating_mul(bw as u64).saturating_mul(
                                bw as u64 + if tracking { sg as u64 + 2 } else { 0 },
                            ),
                            0,
                        )?;
                        if let Some(t) = trace.as_mut() {
                            // The compression tracked as the front: each output row is a
                            // combination of the group's rows, each of those one of the
                            // front's rows.
                            let mut own2: Vec<u32> = (0..n_in as u32).collect();
                            let mut tr2 = vec![Fp::ZERO; n_in * bw];
                            let mut chosen2 = Vec::new();
                            let kept =
                                echelon_tracked(&mut data, bw, &mut own2, &mut tr2, &mut chosen2);
                            for o in 0..n_in {
                                let mut combo = Combo::new(&in_ids);
                                if own2[o] != CHOSEN {
                                    let ri = order[i + own2[o] as usize];
                                    combo.add_row(ri, Fp::ONE, &own, &tr, sg, &chosen);
                                }
                                for (k, &l) in chosen2.iter().enumerate() {
                                    let c = tr2[o * bw + k];
                                    if !c.is_zero() {
                                        let ri = order[i + l as usize];
                                        combo.add_row(ri, c, &own, &tr, sg, &chosen);
                                    }
                                }
                                let id = if o < kept {
                                    t.nids + o as u32
                                } else {
                                    DEPENDENT
                                };
                                combo.emit(t, id);
                            }
                            t.nids += kept as u32;
                            kept
                        } else {
                            echelon(&mut data, bw)
                        }
                    } else {
                        if let Some(t) = trace.as_mut() {
                            for (o, &ri) in order[i..j].iter().enumerate() {
                                let mut combo = Combo::new(&in_ids);
                                combo.add_row(ri, Fp::ONE, &own, &tr, sg, &chosen);
                                combo.emit(t, t.nids + o as u32);
                            }
                            t.nids += n_in as u32;
                        }
                        n_in
                    };
                    stats.dependent_rows += n_in - kept;
                    data.truncate(kept * bw);
                    let id = trace.as_ref().map_or(0, |t| t.nids - kept as u32);
                    if kept > 0 && set_aside && groups.iter().all(|&h| tier[h] > tier[g]) {
                        // Left over by a square tier (the rows on its groups are all
                        // eliminated): set aside rather than carried through the fronts.
                        for o in 0..kept {
                            let row = &data[o * bw..(o + 1) * bw];
                            let mut w = Carried {
                                parts: std::collections::BTreeMap::new(),
                                combo: std::collections::BTreeMap::new(),
                                len: 0,
                            };
                            let c = carried.len() as u32;
                            let mut c0 = 0;
                            for &h in &groups {
                                let part = &row[c0..c0 + sizes[h]];
                                c0 += sizes[h];
                                if part.iter().any(|x| !x.is_zero()) {
                                    w.len += part.len();
                                    w.parts.insert(h, part.to_vec());
                                    carried_on[h].push(c);
                                }
                            }
                            if tracking {
                                w.combo.insert(id + o as u32, Fp::ONE);
                            }
                            carried_len += w.entries();
                            carried.push(Some(w));
                        }
                    } else if kept > 0 {
                        if groups.len() <= WIDE_BLOCK {
                            for &h in &groups {
                                stamp_rescore[h] = rescore_mark;
                            }
                        }
                        pool.add(Blk {
                            groups,
                            nrows: kept,
                            data,
                            id,
                        });
                    }
                    i = j;
                }
                sc_order = order;
            }
            // The pivot rows, over the group's columns and the others they touch.
            let mut used = vec![0u64; words];
            for i in 0..r {
                for w in 0..words {
                    used[w] |= masks[i * words + w];
                }
            }
            let rec_others: Vec<usize> = (0..others.len())
                .filter(|&k| used[k / 64] >> (k % 64) & 1 == 1)
                .map(|k| others[k])
                .collect();
            let rec_width = sg + rec_others.iter().map(|&h| sizes[h]).sum::<usize>();
            let mut rows = std::mem::take(&mut sc_rows);
            rows.clear();
            rows.reserve(r * rec_width);
            for i in 0..r {
                let row = &front[i * width..(i + 1) * width];
                rows.extend_from_slice(&row[..sg]);
                for &h in &rec_others {
                    rows.extend_from_slice(&row[pos[h]..pos[h] + sizes[h]]);
                }
            }
            sc_front = front;
            // What the record keeps: the columns after the pivots' (`row[..sg]` is read only
            // by `meet` below, through `rows`).
            let kept_width = free.len() + rec_width - sg;
            let mut kept = Vec::with_capacity(if keep { r * kept_width } else { 0 });
            for i in 0..if keep { r } else { 0 } {
                let row = &rows[i * rec_width..(i + 1) * rec_width];
                kept.extend(free.iter().map(|&q| row[q]));
                kept.extend_from_slice(&row[sg..]);
            }
            let extra = if touching.is_empty() {
                Vec::new()
            } else {
                let mut set = CarriedSet {
                    carried: &mut carried,
                    carried_on: &mut carried_on,
                    carried_len: &mut carried_len,
                    sizes: &sizes,
                    offsets: &offsets,
                };
                let front_rows = PivotRows {
                    g,
                    pivots: &pivots,
                    free: &free,
                    others: &rec_others,
                    rows: &rows,
                    width: rec_width,
                    tr: tracking.then_some((&tr[..], &chosen[..], &in_ids[..])),
                };
                let (extra, dependent, work) = set.meet(&touching, &front_rows, trace.as_mut());
                charge(work, 0)?;
                rank += extra.len();
                stats.dependent_rows += dependent;
                stats.factor_entries += extra.iter().map(|e| e.1.len() + 1).sum::<usize>();
                extra
            };
            stats.factor_entries += rows.len();
            record_bytes = record_bytes.saturating_add(
                ((rows.len()
                    + pivots.len()
                    + free.len()
                    + rec_others.len()
                    + extra.iter().map(|e| 2 * e.1.len() + 1).sum::<usize>())
                    as u64)
                    .saturating_mul(FP_BYTES),
            );
            for &h in &others {
                if !done[h] && stamp_rescore[h] == rescore_mark {
                    let s = pool.score(h, &mut stamp, &mut clock);
                    queue.set(h, (tier[h], s.0, s.1));
                }
            }
            sc_rows = rows;
            if keep {
                let mut cols = Vec::with_capacity(pivots.len() + free.len() + rec_others.len());
                cols.extend(
                    pivots
                        .iter()
                        .chain(&free)
                        .chain(&rec_others)
                        .map(|&c| c as u32),
                );
                records.push(Record {
                    group: g as u32,
                    width: kept_width as u32,
                    npiv: pivots.len() as u32,
                    nfree: free.len() as u32,
                    cols: cols.into_boxed_slice(),
                    rows: kept.into_boxed_slice(),
                    extra: extra.into_boxed_slice(),
                });
            }
            (sc_others, sc_masks) = (others, masks);
            (sc_in, sc_own, sc_tr, sc_chosen) = (in_ids, own, tr, chosen);
        }
        Ok(Factor {
            sizes,
            offsets,
            records,
            rank,
            stats,
            trace,
        })
    }

    /// Entries of the trace of a tracked factorization (0 if not tracked): the cost of
    /// [`Factor::random_left_null_vector`].
    pub fn trace_len(&self) -> usize {
        self.trace.as_ref().map_or(0, |t| {
            t.terms.len() + t.outputs.len() + t.orig.len() + t.empty.len()
        })
    }

    /// Whether the factorization kept its row operations ([`Factor::new_tracked_within`]).
    pub fn is_tracked(&self) -> bool {
        self.trace.is_some()
    }

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

    /// The rank.
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// The number of columns.
    pub fn ncols(&self) -> usize {
        self.sizes.iter().sum()
    }

    /// The dimension of the null space, `ncols − rank`.
    pub fn nullity(&self) -> usize {
        self.ncols() - self.rank
    }

    /// Fill and front sizes of the factorization.
    pub fn stats(&self) -> FactorStats {
        self.stats
    }

    /// The columns in elimination order (group by group, each group's columns in order):
    /// a fill-reducing order for [`RowBasis::with_column_order`].
    pub fn column_order(&self) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.ncols());
        let mut seen = vec![false; self.sizes.len()];
        for rec in &self.records {
            seen[rec.group()] = true;
            let off = self.offsets[rec.group()];
            out.extend((off..off + self.sizes[rec.group()]).map(|c| c as u32));
        }
        for (g, &s) in self.sizes.iter().enumerate() {
            if !seen[g] {
                let off = self.offsets[g];
                out.extend((off..off + s).map(|c| c as u32));
            }
        }
        out
    }

    /// The free columns (global indices), one per null-space vector, in the order of
    /// [`Factor::null_space`]: vector k is 1 on free column k and 0 on the other free
    /// columns.
    pub fn free_columns(&self) -> Vec<u32> {
        self.records
            .iter()
            .flat_map(|rec| rec.open().map(|f| (self.offsets[rec.group()] + f) as u32))
            .collect()
    }

    /// `k` random vectors of the null space {x : A x = 0}, dense: each free column gets a
    /// random field element and the pivots follow by back substitution, record by record in
    /// reverse elimination order (a record's rows involve its own group and groups
    /// eliminated after it). The cost is `k` passes over the factor, whatever the nullity;
    /// a linear map on the null space has the rank of its values on `k` such vectors (for
    /// `k` at least that rank) except with probability at most `k / p`.
    pub fn random_null_vectors(&self, k: usize, rng: &mut SplitMix64) -> Vec<Vec<Fp>> {
        let total = self.ncols();
        let mut out = Vec::with_capacity(k);
        for _ in 0..k {
            let mut x = vec![Fp::ZERO; total];
            for rec in self.records.iter().rev() {
                let off = self.offsets[rec.group()];
                for q in rec.open() {
                    x[off + q] = Fp::random(rng);
                }
                solve_extra(rec, off, &mut x);
                for (i, &pc) in rec.pivots().iter().enumerate() {
                    let row = &rec.rows[i * rec.width()..(i + 1) * rec.width()];
                    let mut s = Fp::ZERO;
                    for (j, &q) in rec.free().iter().enumerate() {
                        s += row[j] * x[off + q as usize];
                    }
                    let mut c = rec.free().len();
                    for &o in rec.others() {
                        let o = o as usize;
                        let so = self.sizes[o];
                        let oo = self.offsets[o];
                        for kk in 0..so {
                            s += row[c + kk] * x[oo + kk];
                        }
                        c += so;
                    }
                    x[off + pc as usize] = -s;
                }
            }
            out.push(x);
        }
        out
    }

    /// A basis of the null space {x : A x = 0}: `nullity()` sparse vectors, by back
    /// substitution from each free column through the groups it reaches. The vectors are
    /// as dense as the motions they describe (a serial chain's are long), so the cost is
    /// that of the output.
    pub fn null_space(&self) -> Vec<SparseRow> {
        let n = self.sizes.len();
        let total = self.ncols();
        // Records whose front used group h as a neighbour (those are solved after h).
        let mut users: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut rec_of = vec![usize::MAX; n];
        for (ri, rec) in self.records.iter().enumerate() {
            rec_of[rec.group()] = ri;
            for &h in rec.others() {
                users[h as usize].push(ri);
            }
            // A set-aside row's columns on groups outside the record's front.
            let mut hs: Vec<usize> = rec
                .extra
                .iter()
                .flat_map(|e| e.1.iter())
                .map(|&(col, _)| self.offsets.partition_point(|&o| o <= col as usize) - 1)
                .filter(|&h| h != rec.group() && !rec.others().contains(&(h as u32)))
                .collect();
            hs.sort_unstable();
            hs.dedup();
            for h in hs {
                users[h].push(ri);
            }
        }
        let mut x = vec![Fp::ZERO; total];
        let mut touched_groups: Vec<usize> = Vec::new();
        let mut group_seen = vec![false; n];
        let mut queued = vec![false; self.records.len()];
        let mut out = Vec::with_capacity(self.nullity());
        for (ri, rec) in self.records.iter().enumerate() {
            for f in rec.open() {
                let col = self.offsets[rec.group()] + f;
                x[col] = Fp::ONE;
                let mut heap: BinaryHeap<usize> = BinaryHeap::new();
                heap.push(ri);
                queued[ri] = true;
                let mut queued_list = vec![ri];
                let mark = |g: usize, seen: &mut Vec<bool>, list: &mut Vec<usize>| {
                    if !seen[g] {
                        seen[g] = true;
                        list.push(g);
                    }
                };
                mark(rec.group(), &mut group_seen, &mut touched_groups);
                while let Some(hi) = heap.pop() {
                    let h = &self.records[hi];
                    let off = self.offsets[h.group()];
                    let mut any = solve_extra(h, off, &mut x);
                    for (i, &pc) in h.pivots().iter().enumerate() {
                        let row = &h.rows[i * h.width()..(i + 1) * h.width()];
                        let mut s = Fp::ZERO;
                        for (j, &q) in h.free().iter().enumerate() {
                            let v = x[off + q as usize];
                            if !v.is_zero() {
                                s += row[j] * v;
                            }
                        }
                        let mut c = h.free().len();
                        for &o in h.others() {
                            let o = o as usize;
                            let so = self.sizes[o];
                            let xo = &x[self.offsets[o]..self.offsets[o] + so];
                            for (k, &v) in xo.iter().enumerate() {
                                if !v.is_zero() {
                                    s += row[c + k] * v;
                                }
                            }
                            c += so;
                        }
                        let val = -s;
                        x[off + pc as usize] = val;
                        any |= !val.is_zero();
                    }
                    if any {
                        mark(h.group(), &mut group_seen, &mut touched_groups);
                    }
                    if any || hi == ri {
                        for &u in &users[h.group()] {
                            if !queued[u] {
                                queued[u] = true;
                                queued_list.push(u);
                                heap.push(u);
                            }
                        }
                    }
                }
                touched_groups.sort_unstable();
                let mut v: SparseRow = Vec::new();
                for &g in &touched_groups {
                    let off = self.offsets[g];
                    for (k, e) in x[off..off + self.sizes[g]].iter_mut().enumerate() {
                        if !e.is_zero() {
                            v.push(((off + k) as u32, *e));
                            *e = Fp::ZERO;
                        }
                    }
                    group_seen[g] = false;
                }
                touched_groups.clear();
                for q in queued_list {
                    queued[q] = false;
                }
                out.push(v);
            }
        }
        out
    }
}

#[cfg(test)]
thread_local! {
    /// Tests compare with the former carrying of the rows a square tier leaves over.
    static SET_ASIDE: std::cell::Cell<bool> = const { std::cell::Cell::new(true) };
}

#[cfg(test)]
fn set_aside_enabled() -> bool {
    SET_ASIDE.with(|c| c.get())
}

#[cfg(not(test))]
fn set_aside_enabled() -> bool {
    true
}

/// The columns a record's set-aside rows took as pivots, last first (each may read the
/// later ones): `x[col] = −Σ row · x`. Whether any came out nonzero.
fn solve_extra(rec: &Record, off: usize, x: &mut [Fp]) -> bool {
    let mut any = false;
    for (q, row) in rec.extra.iter().rev() {
        let mut s = Fp::ZERO;
        for &(col, v) in row {
            s += v * x[col as usize];
        }
        x[off + q] = -s;
        any |= !s.is_zero();
    }
    any
}

/// Each group's size and first column, and each column's group.
fn group_columns<R: Rows + ?Sized>(a: &R) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let sizes = a.group_sizes();
    let mut offsets = Vec::with_capacity(sizes.len());
    let mut group_of = Vec::with_capacity(a.ncols());
    let mut acc = 0;
    for (g, &s) in sizes.iter().enumerate() {
        offsets.push(acc);
        acc += s;
        group_of.extend(std::iter::repeat_n(g, s));
    }
    (sizes, offsets, group_of)
}

/// The rows of `a` merged into blocks (rows on the same set of groups, in the order of their
/// sorted group sets: deterministic), with the matrix row of each row of the blocks in order
/// (the blocks' rows are the working ids `0..`, see [`Trace`]). Rows without entries are left
/// out.
fn blocks_of(a: &SparseMatrix) -> (Vec<Blk>, Vec<u32>) {
    let split = split_rows(a);
    (split.blocks, split.orig)
}

/// Rows read one at a time, by index: what [`split_rows`] needs of a matrix. A
/// [`SparseMatrix`] lends its rows; a compact description of the rows (the joints of a
/// mechanism's pairs, [`crate::exact::models::pairs_factor`]) makes each when asked, so
/// that the rows never exist all at once as a vector each (about 230 bytes a row, more than
/// the blocks made from them).
pub(crate) trait Rows {
    /// Number of columns.
    fn ncols(&self) -> usize;
    /// Number of rows.
    fn nrows(&self) -> usize;
    /// The sizes of the column groups (consecutive, summing to `ncols`).
    fn group_sizes(&self) -> Vec<usize>;
    /// Row `i` as [`SparseMatrix::push_row`] leaves it (columns increasing, no zeros),
    /// made in `buf` if it is not stored.
    fn row<'a>(&'a self, i: usize, buf: &'a mut SparseRow) -> &'a [(u32, Fp)];
}

impl Rows for SparseMatrix {
    fn ncols(&self) -> usize {
        self.ncols
    }
    fn nrows(&self) -> usize {
        self.rows.len()
    }
    fn group_sizes(&self) -> Vec<usize> {
        self.groups()
    }
    fn row<'a>(&'a self, i: usize, _: &'a mut SparseRow) -> &'a [(u32, Fp)] {
        &self.rows[i]
    }
}

/// What [`split_rows`] gives: the blocks, the row of each working id, the rows without
/// entries and the entries in all.
struct Split {
    blocks: Vec<Blk>,
    orig: Vec<u32>,
    empty: Vec<u32>,
    entries: usize,
}

/// [`blocks_of`] for any [`Rows`], with the rows without entries and the count of entries.
fn split_rows<R: Rows + ?Sized>(a: &R) -> Split {
    let (sizes, offsets, group_of) = group_columns(a);
    let nrows = a.nrows();
    let mut buf: SparseRow = Vec::new();
    let mut entries = 0;
    // Each row's set of groups (its columns are increasing, so the set is sorted and the
    // groups of a row are consecutive), all in one flat array: `sets[start[i]..start[i + 1]]`
    // for row `i`. One vector of groups per row, sorted with its row index, held 64 bytes a
    // row and its sort chased a pointer per comparison.
    let mut start: Vec<usize> = Vec::with_capacity(nrows + 1);
    let mut sets: Vec<u32> = Vec::new();
    start.push(0);
    let mut longest = 0;
    for i in 0..nrows {
        let r = a.row(i, &mut buf);
        entries += r.len();
        let from = sets.len();
        for &(c, _) in r {
            let g = group_of[c as usize] as u32;
            if sets.len() == from || sets[sets.len() - 1] != g {
                sets.push(g);
            }
        }
        longest = longest.max(sets.len() - from);
        start.push(sets.len());
    }
    let set = |i: u32| &sets[start[i as usize]..start[i as usize + 1]];
    // The nonempty rows by set, then by index: the order of the former sort of `(set, row)`
    // pairs (the keys are distinct, so an unstable sort gives that order). Each row is
    // sorted with a prefix key of its set, its first group and one more than its second
    // (zero without), which orders sets of one or two groups as their lexicographic order
    // does; longer sets (or more groups than a `u32` holds) are compared in full where the
    // keys tie. With sets of at most two groups, equal keys are equal sets.
    let narrow = sizes.len() < u32::MAX as usize;
    let exact = narrow && longest <= 2;
    let prefix = |s: &[u32]| match (narrow, s) {
        (true, [a, b, ..]) => (u64::from(*a) << 32) | (u64::from(*b) + 1),
        (true, [a]) => u64::from(*a) << 32,
        _ => 0,
    };
    // A row without entries has no groups.
    let empty: Vec<u32> = (0..nrows as u32)
        .filter(|&i| start[i as usize] == start[i as usize + 1])
        .collect();
    let mut order: Vec<(u64, u32)> = Vec::with_capacity(nrows - empty.len());
    order.extend(
        (0..nrows as u32)
            .filter(|&i| start[i as usize] != start[i as usize + 1])
            .map(|i| (prefix(set(i)), i)),
    );
    if exact {
        order.sort_unstable();
    } else {
        order.sort_unstable_by(|x, y| {
            x.0.cmp(&y.0)
                .then_with(|| set(x.1).cmp(set(y.1)))
                .then(x.1.cmp(&y.1))
        });
    }
    let same = |x: &(u64, u32), y: &(u64, u32)| x.0 == y.0 && (exact || set(x.1) == set(y.1));
    let nblocks = order
        .iter()
        .enumerate()
        .filter(|&(i, k)| i == 0 || !same(&order[i - 1], k))
        .count();
    let mut blocks = Vec::with_capacity(nblocks);
    let mut orig = Vec::with_capacity(order.len());
    let mut i = 0;
    let mut local = vec![0usize; sizes.len()];
    while i < order.len() {
        let groups = set(order[i].1);
        let mut j = i;
        while j < order.len() && same(&order[j], &order[i]) {
            j += 1;
        }
        let mut width = 0;
        for &g in groups {
            local[g as usize] = width;
            width += sizes[g as usize];
        }
        let mut data = vec![Fp::ZERO; (j - i) * width];
        for (k, &(_, ri)) in order[i..j].iter().enumerate() {
            for &(c, v) in a.row(ri as usize, &mut buf) {
                let g = group_of[c as usize];
                data[k * width + local[g] + c as usize - offsets[g]] = v;
            }
        }
        blocks.push(Blk {
            groups: groups.iter().map(|&g| g as usize).collect(),
            nrows: j - i,
            data,
            id: orig.len() as u32,
        });
        orig.extend(order[i..j].iter().map(|&(_, ri)| ri));
        i = j;
    }
    Split {
        blocks,
        orig,
        empty,
        entries,
    }
}

/// The former [`blocks_of`] (a vector of groups per row, sorted with the row's index), kept
/// to check the new one block for block.
#[cfg(test)]
fn blocks_of_reference(a: &SparseMatrix) -> (Vec<Blk>, Vec<u32>) {
    let (sizes, offsets, group_of) = group_columns(a);
    let mut keyed: Vec<(Vec<usize>, usize)> = a
        .rows
        .iter()
        .enumerate()
        .filter(|(_, r)| !r.is_empty())
        .map(|(i, r)| {
            let mut set: Vec<usize> = r.iter().map(|&(c, _)| group_of[c as usize]).collect();
            set.dedup();
            (set, i)
        })
        .collect();
    keyed.sort();
    let mut blocks = Vec::new();
    let mut orig = Vec::with_capacity(keyed.len());
    let mut i = 0;
    let mut local = vec![0usize; sizes.len()];
    while i < keyed.len() {
        let mut j = i;
        while j < keyed.len() && keyed[j].0 == keyed[i].0 {
            j += 1;
        }
        let groups = keyed[i].0.clone();
        let mut width = 0;
        for &g in &groups {
            local[g] = width;
            width += sizes[g];
        }
        let mut data = vec![Fp::ZERO; (j - i) * width];
        for (k, (_, ri)) in keyed[i..j].iter().enumerate() {
            for &(c, v) in &a.rows[*ri] {
                let g = group_of[c as usize];
                data[k * width + local[g] + c as usize - offsets[g]] = v;
            }
        }
        blocks.push(Blk {
            groups,
            nrows: j - i,
            data,
            id: orig.len() as u32,
        });
        orig.extend(keyed[i..j].iter().map(|&(_, ri)| ri as u32));
        i = j;
    }
    (blocks, orig)
}

/// The elimination tier of each column group of `a` that [`Factor::new`] uses (lower
/// first): its block triangular order (module docs).
pub fn elimination_tiers(a: &SparseMatrix) -> Vec<u32> {
    let (blocks, _) = blocks_of(a);
    tiers(&a.groups(), &blocks).0
}

/// The budget of one factorization: work charged to a meter, memory checked against the
/// budget's limit, `what` naming the matrix in the message.
pub struct Limits<'a> {
    /// The memory limit.
    pub budget: &'a Budget,
    /// The work meter of the analysis.
    pub meter: &'a mut Meter,
    /// What is being factorized, for the message.
    pub what: &'a dyn Fn() -> String,
}

impl Limits<'_> {
    fn charge(&mut self, work: u64, bytes: u64) -> Result<(), BudgetExceeded> {
        self.meter.charge(work)?;
        self.budget.check_memory(bytes, self.what)
    }
}

/// The elimination tier of every group (lower first) and the work spent finding it: the
/// block triangular order. A maximum b-matching of the blocks' rows to the groups (a group
/// takes at most as many rows as it has columns; [`crate::structure::flow`]) gives each
/// group its own rows; group `k` must go before group `h` when rows matched to `k` touch
/// `h` (otherwise they would still be live when `h` is eliminated, join its front and be
/// left over onto its neighbours). The strongly connected components of that relation, in
/// topological order, are the tiers: for a square generic matrix the blocks of its block
/// triangular form, within which the greedy minimum-front order decides.
fn tiers(sizes: &[usize], blocks: &[Blk]) -> (Vec<u32>, u64) {
    use crate::structure::flow::{INF, Network};
    let n = sizes.len();
    let nb = blocks.len();
    if n == 0 || nb == 0 {
        return (vec![0; n], 0);
    }
    let (s, t) = (0usize, nb + n + 1);
    let group_node = |g: usize| (nb + 1 + g) as u32;
    let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(nb + n + 2 * nb);
    for (i, b) in blocks.iter().enumerate() {
        let u = (i + 1) as u32;
        edges.push((s as u32, u, b.nrows.min(INF as usize) as u32));
        // The last group first: a block of rows on a body and earlier bodies is then
        // matched to its body by the greedy start.
        for &g in b.groups.iter().rev() {
            edges.push((u, group_node(g), INF));
        }
    }
    for (g, &sz) in sizes.iter().enumerate() {
        edges.push((group_node(g), t as u32, sz.min(INF as usize) as u32));
    }
    let mut net = Network::new(t + 1, &edges);
    net.max_flow(s, t);
    let mut work = edges.len() as u64 * 4;
    // k -> h: rows matched to k touch h.
    let mut adj_start = vec![0usize; n + 1];
    let mut owners_of: Vec<Vec<usize>> = Vec::with_capacity(nb);
    for (i, b) in blocks.iter().enumerate() {
        let mut owners = Vec::new();
        for e in net.edges(i + 1) {
            let v = net.head(e);
            if v > nb && v <= nb + n && net.reverse_residual(e) > 0 {
                owners.push(v - nb - 1);
            }
        }
        for &k in &owners {
            adj_start[k + 1] += b.groups.len().saturating_sub(1);
        }
        owners_of.push(owners);
    }
    for g in 0..n {
        adj_start[g + 1] += adj_start[g];
    }
    let mut adj = vec![0u32; adj_start[n]];
    let mut fill = adj_start.clone();
    for (b, owners) in blocks.iter().zip(&owners_of) {
        for &k in owners {
            for &h in &b.groups {
                if h != k {
                    adj[fill[k]] = h as u32;
                    fill[k] += 1;
                }
            }
        }
    }
    work += adj.len() as u64 * 4;
    drop(owners_of);
    // Tarjan's strongly connected components; a component is completed only after every
    // component it reaches, so completion order is reverse topological.
    let (members, bounds) = crate::structure::tarjan_flat(&adj_start, &adj, &vec![true; n]);
    let ncomp = (bounds.len() - 1) as u32;
    let mut comp = vec![0u32; n];
    for (c, span) in bounds.windows(2).enumerate() {
        for &w in &members[span[0]..span[1]] {
            comp[w as usize] = c as u32;
        }
    }
    drop(members);
    // The over-determined part: groups reachable from rows the matching left over (in the
    // residual network: a row to any group it touches, a group to the rows matched to it).
    // Left-over rows join every front they touch whatever the order, so there the order
    // within is left to the greedy: one last tier.
    let over = net.reachable_from(s);
    for (g, c) in comp.iter_mut().enumerate() {
        *c = if over[nb + 1 + g] {
            ncomp
        } else {
            ncomp - 1 - *c
        };
    }
    (comp, work)
}

/// The groups waiting to be eliminated, least key first: `(tier, estimated fill, front
/// width)`, ties by group. An indexed 4-ary heap holding one entry per group, its key changed
/// in place when the group is rescored. It pops the groups in the very order of the former
/// `BinaryHeap` of `Reverse((tier, score, group, version))` that took a new entry at every
/// rescore and skipped the stale ones (the keys are distinct, so the order is the keys' order
/// whatever the heap), without the stale entries: at 10^6 bodies they were tens of megabytes
/// and every pop walked down a heap several times the size of the live one.
struct GroupQueue {
    /// `(tier, fill, width, group)`, a 4-ary min-heap.
    heap: Vec<(u32, usize, usize, usize)>,
    /// Each group's place in `heap` ([`GroupQueue::NONE`]: not in it).
    pos: Vec<usize>,
}

impl GroupQueue {
    const NONE: usize = usize::MAX;

    fn new(n: usize) -> GroupQueue {
        GroupQueue {
            heap: Vec::with_capacity(n),
            pos: vec![Self::NONE; n],
        }
    }

    /// Put `g` in the queue with `key`, or change its key.
    fn set(&mut self, g: usize, key: (u32, usize, usize)) {
        let e = (key.0, key.1, key.2, g);
        let i = self.pos[g];
        if i == Self::NONE {
            self.heap.push(e);
            let i = self.heap.len() - 1;
            self.pos[g] = i;
            self.up(i);
        } else {
            let old = self.heap[i];
            self.heap[i] = e;
            if e < old {
                self.up(i);
            } else {
                self.down(i);
            }
        }
    }

    /// The group of least key, taken out of the queue.
    fn pop(&mut self) -> Option<usize> {
        let top = *self.heap.first()?;
        let last = self.heap.pop()?;
        self.pos[top.3] = Self::NONE;
        if !self.heap.is_empty() {
            self.heap[0] = last;
            self.pos[last.3] = 0;
            self.down(0);
        }
        Some(top.3)
    }

    fn up(&mut self, mut i: usize) {
        let e = self.heap[i];
        while i > 0 {
            let p = (i - 1) / 4;
            if self.heap[p] <= e {
                break;
            }
            self.heap[i] = self.heap[p];
            self.pos[self.heap[i].3] = i;
            i = p;
        }
        self.heap[i] = e;
        self.pos[e.3] = i;
    }

    fn down(&mut self, mut i: usize) {
        let e = self.heap[i];
        let n = self.heap.len();
        loop {
            let c0 = 4 * i + 1;
            if c0 >= n {
                break;
            }
            let mut m = c0;
            for c in c0 + 1..(c0 + 4).min(n) {
                if self.heap[c] < self.heap[m] {
                    m = c;
                }
            }
            if self.heap[m] >= e {
                break;
            }
            self.heap[i] = self.heap[m];
            self.pos[self.heap[i].3] = i;
            i = m;
        }
        self.heap[i] = e;
        self.pos[e.3] = i;
    }
}

/// The live blocks of an elimination, indexed by group, with per-group row and width sums
/// kept up to date for the pivot order.
struct Pool<'a> {
    sizes: &'a [usize],
    store: Vec<Option<Blk>>,
    /// Block ids per group (dead ids pruned lazily).
    of_group: Vec<Vec<usize>>,
    /// Live blocks, their rows and the sum of their widths, per group.
    nblk: Vec<usize>,
    rsum: Vec<usize>,
    wsum: Vec<usize>,
    /// Bytes held by the live blocks.
    bytes: u64,
    /// Scratch of [`Pool::score`]: the group's blocks and the groups of `U`.
    sc_blocks: Vec<(usize, usize, usize)>,
    sc_u: Vec<usize>,
}

/// Blocks on more groups than this are "wide" (a carried row): the pivot order treats them
/// approximately.
const WIDE_BLOCK: usize = 64;

/// Groups with more live blocks than this get the width bound instead of the exact union.
const EXACT_SCORE_BLOCKS: usize = 32;

impl<'a> Pool<'a> {
    fn new(sizes: &'a [usize], cap: usize) -> Pool<'a> {
        let n = sizes.len();
        Pool {
            sizes,
            store: Vec::with_capacity(cap),
            of_group: vec![Vec::new(); n],
            nblk: vec![0; n],
            rsum: vec![0; n],
            wsum: vec![0; n],
            bytes: 0,
            sc_blocks: Vec::new(),
            sc_u: Vec::new(),
        }
    }

    fn width(&self, b: &Blk) -> usize {
        b.width()
    }

    fn add(&mut self, b: Blk) {
        let id = self.store.len();
        let w = self.width(&b);
        self.bytes = self.bytes.saturating_add(b.bytes());
        for &g in &b.groups {
            self.of_group[g].push(id);
            self.nblk[g] += 1;
            self.rsum[g] += b.nrows;
            self.wsum[g] += w;
        }
        self.store.push(Some(b));
    }

    /// Remove and return the live blocks on group `g`.
    fn take(&mut self, g: usize) -> Vec<Blk> {
        let ids = std::mem::take(&mut self.of_group[g]);
        let mut out = Vec::with_capacity(ids.len());
        for id in ids {
            if let Some(b) = self.store[id].take() {
                let w = self.width(&b);
                self.bytes = self.bytes.saturating_sub(b.bytes());
                for &h in &b.groups {
                    self.nblk[h] -= 1;
                    self.rsum[h] -= b.nrows;
                    self.wsum[h] -= w;
                }
                out.push(b);
            }
        }
        out
    }

    /// The cost of eliminating `g` now, as (estimated new entries, front width). The
    /// estimate takes the pivots from the narrowest blocks (as the elimination does), lets
    /// `U` be the columns those pivot rows span, and counts the pivot rows (`|U|` each) and,
    /// for every row left over, the columns of `U` its block lacks (its fill). A group whose
    /// front has no more rows than columns leaves nothing behind (a tip of a chain, a leaf
    /// of a star, the last body of a determined group); a row crossing many groups that is
    /// only carried along adds little. Groups on more than [`EXACT_SCORE_BLOCKS`] blocks
    /// get a bound instead (they go late).
    fn score(&mut self, g: usize, stamp: &mut [usize], clock: &mut usize) -> (usize, usize) {
        let sg = self.sizes[g];
        let ids = &mut self.of_group[g];
        if ids.len() > 2 * self.nblk[g] + 8 {
            let store = &self.store;
            ids.retain(|&id| store[id].is_some());
        }
        if self.nblk[g] > EXACT_SCORE_BLOCKS {
            let width = (self.wsum[g] + sg).saturating_sub(self.nblk[g] * sg);
            return (self.rsum[g].saturating_mul(width), width);
        }
        let mut blocks = std::mem::take(&mut self.sc_blocks);
        blocks.clear();
        blocks.extend(self.of_group[g].iter().filter_map(|&id| {
            let b = self.store[id].as_ref()?;
            Some((self.width(b), b.nrows, id))
        }));
        blocks.sort_unstable();
        // U: the union of the narrowest blocks supplying sg rows.
        *clock += 1;
        let mark = *clock;
        stamp[g] = mark;
        let mut u_groups = std::mem::take(&mut self.sc_u);
        u_groups.clear();
        let mut uw = sg;
        let mut need = sg;
        for &(_, nr, id) in &blocks {
            if need == 0 {
                break;
            }
            if let Some(b) = &self.store[id] {
                for &h in &b.groups {
                    if stamp[h] != mark {
                        stamp[h] = mark;
                        uw += self.sizes[h];
                        u_groups.push(h);
                    }
                }
            }
            need = need.saturating_sub(nr);
        }
        let pivots = sg - need;
        let mut fill = pivots * uw;
        // Rows left over gain the columns of U their block lacks; the width counts the
        // narrow blocks' groups exactly and the wide ones' by their width.
        let mut left = pivots;
        *clock += 1;
        let wmark = *clock;
        stamp[g] = wmark;
        let mut width = uw;
        for &(bw, nr, id) in &blocks {
            let used = left.min(nr);
            left -= used;
            let rest = nr - used;
            let Some(b) = &self.store[id] else { continue };
            let mut inside = sg;
            if b.groups.len() <= WIDE_BLOCK {
                for &h in &b.groups {
                    if stamp[h] == mark {
                        inside += self.sizes[h];
                    } else if stamp[h] != wmark {
                        stamp[h] = wmark;
                        width += self.sizes[h];
                    }
                }
            } else {
                for &h in &u_groups {
                    if b.groups.binary_search(&h).is_ok() {
                        inside += self.sizes[h];
                    }
                }
                width += bw - inside;
            }
            fill += rest * uw.saturating_sub(inside);
        }
        (self.sc_blocks, self.sc_u) = (blocks, u_groups);
        (fill, width)
    }
}

fn swap_rows(m: &mut [Fp], w: usize, i: usize, k: usize) {
    if i != k {
        let (a, b) = (i.min(k), i.max(k));
        let (lo, hi) = m.split_at_mut(b * w);
        lo[a * w..(a + 1) * w].swap_with_slice(&mut hi[..w]);
    }
}

/// Row `i` (mutable) and row `k` (shared) of a row-major matrix of width `w`, `i != k`.
fn two_rows(m: &mut [Fp], w: usize, i: usize, k: usize) -> (&mut [Fp], &[Fp]) {
    if i < k {
        let (lo, hi) = m.split_at_mut(k * w);
        (&mut lo[i * w..(i + 1) * w], &hi[..w])
    } else {
        let (lo, hi) = m.split_at_mut(i * w);
        (&mut hi[..w], &lo[k * w..(k + 1) * w])
    }
}

/// Row echelon form in place (row-major, width `w`); returns the rank (rows `0..rank` span
/// the row space).
fn echelon(m: &mut [Fp], w: usize) -> usize {
    let nr = m.len() / w;
    let mut r = 0;
    for c in 0..w {
        if r == nr {
            break;
        }
        let Some(p) = (r..nr).find(|&i| !m[i * w + c].is_zero()) else {
            continue;
        };
        swap_rows(m, w, r, p);
        let inv = m[r * w + c].inv();
        scale(&mut m[r * w + c..(r + 1) * w], inv);
        for i in r + 1..nr {
            let f = m[i * w + c];
            if !f.is_zero() {
                let (dst, src) = two_rows(m, w, i, r);
                axpy_sub(&mut dst[c..], f, &src[c..]);
            }
        }
        r += 1;
    }
    r
}

/// [`echelon`] keeping each row's combination of the input rows: `own[i]` its own input row
/// (until chosen as a pivot, then [`CHOSEN`]), `tr` (`w` per row) its coefficients on the
/// rows chosen so far, listed in `chosen` (input rows).
fn echelon_tracked(
    m: &mut [Fp],
    w: usize,
    own: &mut [u32],
    tr: &mut [Fp],
    chosen: &mut Vec<u32>,
) -> usize {
    let nr = m.len() / w;
    let mut r = 0;
    for c in 0..w {
        if r == nr {
            break;
        }
        let Some(p) = (r..nr).find(|&i| !m[i * w + c].is_zero()) else {
            continue;
        };
        swap_rows(m, w, r, p);
        swap_rows(tr, w, r, p);
        own.swap(r, p);
        tr[r * w + chosen.len()] = Fp::ONE;
        chosen.push(own[r]);
        own[r] = CHOSEN;
        let inv = m[r * w + c].inv();
        scale(&mut m[r * w + c..(r + 1) * w], inv);
        scale(&mut tr[r * w..(r + 1) * w], inv);
        for i in r + 1..nr {
            let f = m[i * w + c];
            if !f.is_zero() {
                let (dst, src) = two_rows(m, w, i, r);
                axpy_sub(&mut dst[c..], f, &src[c..]);
                let (dst, src) = two_rows(tr, w, i, r);
                axpy_sub(dst, f, src);
            }
        }
        r += 1;
    }
    r
}

/// A row that the earlier rows make redundant, with the rows taking part in its dependency.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DependentRow {
    /// The row.
    pub row: usize,
    /// Rows with a nonzero coefficient in the left null vector that expresses the
    /// dependency (this row, coefficient one, and earlier rows), increasing.
    pub support: Vec<usize>,
    /// That left null vector over the rows: `Σ y_i row_i = 0`.
    pub vector: SparseRow,
}

impl Factor {
    /// The rows of `a` (the matrix this factor was computed from) that are combinations of
    /// the rows before them, greedy in row order, each with its dependency. Removing them
    /// all keeps the rank; their vectors are a basis of the left null space. Computed with
    /// a tracked [`RowBasis`] in this factor's column order.
    pub fn dependent_rows(&self, a: &SparseMatrix) -> Vec<DependentRow> {
        if self.rank == a.nrows() {
            return Vec::new();
        }
        let mut basis = RowBasis::with_column_order(&self.column_order()).with_tracking();
        let mut out = Vec::new();
        for (i, r) in a.rows.iter().enumerate() {
            if !basis.insert(r) {
                let vector = basis.last_dependency().cloned().unwrap_or_default();
                out.push(DependentRow {
                    row: i,
                    support: vector.iter().map(|&(k, _)| k as usize).collect(),
                    vector,
                });
            }
        }
        out
    }

    /// A basis of the left null space {y : yᵀ A = 0} of `a` (the matrix this factor was
    /// computed from), as vectors over the rows: the dependencies of
    /// [`Factor::dependent_rows`]. Empty at once when the rows are independent.
    pub fn left_null_space(&self, a: &SparseMatrix) -> Vec<SparseRow> {
        self.dependent_rows(a)
            .into_iter()
            .map(|d| d.vector)
            .collect()
    }
}

/// A basis of the left null space {y : yᵀ A = 0} (vectors over the rows); see
/// [`Factor::left_null_space`].
pub fn left_null_space(a: &SparseMatrix) -> Vec<SparseRow> {
    Factor::new(a).left_null_space(a)
}

/// The rows dependent on the rows before them, with their dependencies; see
/// [`Factor::dependent_rows`].
pub fn dependent_rows(a: &SparseMatrix) -> Vec<DependentRow> {
    Factor::new(a).dependent_rows(a)
}

/// An incremental row basis in echelon form with respect to the column order: insert
/// sparse rows one at a time; each is reduced by the kept rows and kept iff something
/// remains. Inserting the rows of a matrix in order keeps exactly the rows independent of
/// the earlier ones (greedy redundancy removal). Number the columns so that rows of
/// neighbouring bodies have nearby columns (for a mechanism, bodies in a breadth-first
/// order) to keep the kept rows short.
#[derive(Clone, Debug)]
pub struct RowBasis {
    ncols: usize,
    /// Position of each column in the pivot order (empty: the identity).
    rank_of: Vec<u32>,
    /// The kept rows, reduced: leading entry 1, all other columns after it.
    rows: Vec<SparseRow>,
    /// The kept row leading at each column.
    pivot: Vec<u32>,
    acc: Vec<Fp>,
    mark: Vec<bool>,
    /// Rows inserted so far (the next row's id).
    inserted: u32,
    /// Whether combinations are tracked ([`RowBasis::with_tracking`]).
    track: bool,
    /// Per kept row, its combination of the inserted rows (by id).
    combos: Vec<SparseRow>,
    cacc: Vec<Fp>,
    cmark: Vec<bool>,
    last_dependency: Option<SparseRow>,
}

const NO_PIVOT: u32 = u32::MAX;

impl RowBasis {
    /// An empty basis over `ncols` columns.
    pub fn new(ncols: usize) -> RowBasis {
        RowBasis {
            ncols,
            rank_of: Vec::new(),
            rows: Vec::new(),
            pivot: vec![NO_PIVOT; ncols],
            acc: vec![Fp::ZERO; ncols],
            mark: vec![false; ncols],
            inserted: 0,
            track: false,
            combos: Vec::new(),
            cacc: Vec::new(),
            cmark: Vec::new(),
            last_dependency: None,
        }
    }

    /// Track, for every kept row, which inserted rows it combines, so that a dependent row
    /// comes with its dependency ([`RowBasis::last_dependency`]). Costs memory and time in
    /// proportion to those combinations (the inverse of the triangular factor, denser than
    /// the kept rows); call on an empty basis.
    pub fn with_tracking(mut self) -> RowBasis {
        self.track = true;
        self
    }

    /// With tracking, after an [`insert`](RowBasis::insert) that returned `false`: the left
    /// null vector over the inserted rows (by insertion index, from 0) in which the last row
    /// has coefficient one and only rows inserted before it take part: `Σ y_i row_i = 0`.
    /// `None` after a kept row or without tracking.
    pub fn last_dependency(&self) -> Option<&SparseRow> {
        self.last_dependency.as_ref()
    }

    /// An empty basis whose pivots follow the given column order (`order[k]` is the k-th
    /// column; a permutation of `0..ncols`), for example [`Factor::column_order`]: rows
    /// are then reduced as the factorization would eliminate them, which keeps the kept
    /// rows short where the natural order fills in (the hub of a star numbered first).
    ///
    /// # Panics
    /// If `order` is not a permutation (a caller's error).
    pub fn with_column_order(order: &[u32]) -> RowBasis {
        let ncols = order.len();
        let mut rank_of = vec![u32::MAX; ncols];
        for (k, &c) in order.iter().enumerate() {
            assert!(
                (c as usize) < ncols && rank_of[c as usize] == u32::MAX,
                "column order is not a permutation"
            );
            rank_of[c as usize] = k as u32;
        }
        let mut b = RowBasis::new(ncols);
        b.rank_of = rank_of;
        b
    }

    /// The number of rows kept (the rank of the rows inserted so far).
    pub fn rank(&self) -> usize {
        self.rows.len()
    }

    /// The number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Entries stored in the kept rows (the fill measure).
    pub fn entries(&self) -> usize {
        self.rows.iter().map(|r| r.len()).sum()
    }

    /// Insert a row (`(column, value)` pairs, any order, repeats added); returns whether it
    /// was independent of the rows inserted before (then it is kept).
    ///
    /// # Panics
    /// If a column is not below `ncols` (a caller's indexing error).
    pub fn insert(&mut self, row: &[(u32, Fp)]) -> bool {
        let id = self.inserted;
        self.inserted += 1;
        self.last_dependency = None;
        let mut ctouched: Vec<u32> = Vec::new();
        if self.track {
            if self.cacc.len() <= id as usize {
                let n = (2 * self.cacc.len()).max(id as usize + 1);
                self.cacc.resize(n, Fp::ZERO);
                self.cmark.resize(n, false);
            }
            self.cacc[id as usize] = Fp::ONE;
            self.cmark[id as usize] = true;
            ctouched.push(id);
        }
        let mut heap: BinaryHeap<Reverse<u32>> = BinaryHeap::with_capacity(row.len() * 2);
        let mut touched: Vec<u32> = Vec::with_capacity(row.len() * 2);
        for &(c, v) in row {
            let c = if self.rank_of.is_empty() {
                c
            } else {
                self.rank_of[c as usize]
            };
            let cu = c as usize;
            self.acc[cu] += v;
            if !self.mark[cu] {
                self.mark[cu] = true;
                touched.push(c);
                heap.push(Reverse(c));
            }
        }
        let mut kept = false;
        while let Some(Reverse(c)) = heap.pop() {
            let v = self.acc[c as usize];
            if v.is_zero() {
                continue;
            }
            let p = self.pivot[c as usize];
            if p == NO_PIVOT {
                // Independent: the remainder (columns ≥ c) becomes a kept row leading at c.
                let inv = v.inv();
                let mut new_row: SparseRow = vec![(c, Fp::ONE)];
                let mut rest: Vec<u32> = heap.into_iter().map(|r| r.0).collect();
                rest.sort_unstable();
                for k in rest {
                    let w = self.acc[k as usize];
                    if !w.is_zero() {
                        new_row.push((k, w * inv));
                    }
                }
                self.pivot[c as usize] = self.rows.len() as u32;
                self.rows.push(new_row);
                if self.track {
                    ctouched.sort_unstable();
                    let combo = ctouched
                        .iter()
                        .map(|&i| (i, self.cacc[i as usize] * inv))
                        .filter(|e| !e.1.is_zero())
                        .collect();
                    self.combos.push(combo);
                }
                kept = true;
                break;
            }
            if self.track {
                for &(i, w) in &self.combos[p as usize] {
                    let iu = i as usize;
                    self.cacc[iu] -= v * w;
                    if !self.cmark[iu] {
                        self.cmark[iu] = true;
                        ctouched.push(i);
                    }
                }
            }
            let prow = &self.rows[p as usize];
            for &(k, w) in &prow[1..] {
                let ku = k as usize;
                self.acc[ku] -= v * w;
                if !self.mark[ku] {
                    self.mark[ku] = true;
                    touched.push(k);
                    heap.push(Reverse(k));
                }
            }
            self.acc[c as usize] = Fp::ZERO;
        }
        for c in touched {
            self.acc[c as usize] = Fp::ZERO;
            self.mark[c as usize] = false;
        }
        if self.track {
            ctouched.sort_unstable();
            if !kept {
                self.last_dependency = Some(
                    ctouched
                        .iter()
                        .map(|&i| (i, self.cacc[i as usize]))
                        .filter(|e| !e.1.is_zero())
                        .collect(),
                );
            }
            for i in ctouched {
                self.cacc[i as usize] = Fp::ZERO;
                self.cmark[i as usize] = false;
            }
        }
        kept
    }

    /// Entries stored in the tracked combinations.
    pub fn combination_entries(&self) -> usize {
        self.combos.iter().map(|r| r.len()).sum()
    }
}

/// The constraint Jacobian pattern of a mechanism with random entries, for tests and
/// benchmarks: bodies `0..nbodies` with body 0 the fixed frame (no columns), `b` columns per
/// movable body (grouped), and for each pair `(i, j, rows)` that many rows with random
/// entries over the two bodies' columns (the frame's side omitted).
pub fn random_pair_matrix(
    nbodies: usize,
    b: usize,
    pairs: &[(usize, usize, usize)],
    seed: u64,
) -> SparseMatrix {
    let mut rng = SplitMix64::new(seed);
    let mut a = SparseMatrix::with_groups(vec![b; nbodies.saturating_sub(1)]);
    for &(i, j, rows) in pairs {
        for _ in 0..rows {
            let mut e = Vec::with_capacity(2 * b);
            for body in [i, j] {
                if body > 0 {
                    let off = (body - 1) * b;
                    for k in 0..b {
                        e.push(((off + k) as u32, Fp::random_nonzero(&mut rng)));
                    }
                }
            }
            a.push_row(e);
        }
    }
    a
}

#[cfg(test)]
mod tests {
    use super::super::dense;
    use super::*;

    /// The working blocks from the flat group sets are those of the former vector-per-row
    /// sort, block for block and row for row: groups of 1 to 6 columns (or one group per
    /// column), rows on 0 to 3 groups drawn from a few sets (so that blocks merge rows), a
    /// few rows with their columns out of order (kept by hand, not by `push_row`).
    #[test]
    fn blocks_from_flat_group_sets_are_the_former_ones() {
        let mut rng = SplitMix64::new(0x626c_6b73);
        let same = |a: &SparseMatrix| {
            let (nb, no) = blocks_of(a);
            let (ob, oo) = blocks_of_reference(a);
            assert_eq!(no, oo);
            assert_eq!(nb.len(), ob.len());
            for (x, y) in nb.iter().zip(&ob) {
                assert_eq!(
                    (&x.groups, x.nrows, &x.data, x.id),
                    (&y.groups, y.nrows, &y.data, y.id)
                );
            }
            nb.len()
        };
        let mut merged = 0;
        for round in 0..80 {
            let ng = 1 + rng.below(40) as usize;
            let sizes: Vec<usize> = (0..ng).map(|_| 1 + rng.below(6) as usize).collect();
            let mut a = if round % 4 == 0 {
                SparseMatrix::new(sizes.iter().sum())
            } else {
                SparseMatrix::with_groups(sizes.clone())
            };
            let gsizes = a.groups();
            let offsets: Vec<usize> = gsizes
                .iter()
                .scan(0, |acc, &s| {
                    *acc += s;
                    Some(*acc - s)
                })
                .collect();
            let nsets = 1 + rng.below(8) as usize;
            let sets: Vec<Vec<usize>> = (0..nsets)
                .map(|_| {
                    let mut s: Vec<usize> = (0..rng.below(4))
                        .map(|_| rng.below(gsizes.len() as u64) as usize)
                        .collect();
                    s.sort_unstable();
                    s.dedup();
                    s
                })
                .collect();
            for _ in 0..rng.below(60) {
                let set = &sets[rng.below(nsets as u64) as usize];
                let mut row: SparseRow = Vec::new();
                for &g in set {
                    for c in offsets[g]..offsets[g] + gsizes[g] {
                        if rng.below(3) > 0 {
                            row.push((c as u32, Fp::random_nonzero(&mut rng)));
                        }
                    }
                }
                if rng.below(10) == 0 {
                    row.reverse();
                }
                a.rows.push(row);
            }
            merged += a.rows.len() - same(&a);
        }
        assert!(merged > 100, "too few merged rows: {merged}");
        same(&random_pair_matrix(
            30,
            3,
            &[
                (0, 1, 2),
                (1, 2, 2),
                (2, 0, 1),
                (5, 7, 3),
                (7, 5, 2),
                (9, 9, 1),
            ],
            7,
        ));
        same(&square_dag(200, 3, 9, 4, 11));
    }

    /// The indexed queue of the elimination pops the groups in the order of the heap it
    /// replaced (a new entry per rescore, stale ones skipped), ties in the key included.
    #[test]
    fn group_queue_pops_in_the_order_of_the_versioned_heap() {
        let mut rng = SplitMix64::new(0x0071_7565_7565);
        for _ in 0..60 {
            let n = 1 + rng.below(200) as usize;
            let key = |rng: &mut SplitMix64| {
                (
                    rng.below(3) as u32,
                    rng.below(20) as usize,
                    rng.below(20) as usize,
                )
            };
            let mut queue = GroupQueue::new(n);
            let mut heap = BinaryHeap::new();
            let mut version = vec![0usize; n];
            let mut done = vec![false; n];
            for g in 0..n {
                let k = key(&mut rng);
                queue.set(g, k);
                heap.push(Reverse((k.0, (k.1, k.2), g, 0usize)));
            }
            loop {
                let want = loop {
                    match heap.pop() {
                        None => break None,
                        Some(Reverse((_, _, g, v))) if !done[g] && v == version[g] => {
                            break Some(g);
                        }
                        Some(_) => {}
                    }
                };
                assert_eq!(queue.pop(), want);
                let Some(g) = want else { break };
                done[g] = true;
                for _ in 0..rng.below(5) {
                    let h = rng.below(n as u64) as usize;
                    if !done[h] {
                        version[h] += 1;
                        let k = key(&mut rng);
                        queue.set(h, k);
                        heap.push(Reverse((k.0, (k.1, k.2), h, version[h])));
                    }
                }
            }
        }
    }

    fn tracked(a: &SparseMatrix) -> Factor {
        let budget = Budget::UNLIMITED;
        let mut meter = budget.meter("test");
        let what = || "test".to_string();
        Factor::new_tracked_within(
            a,
            &mut Limits {
                budget: &budget,
                meter: &mut meter,
                what: &what,
            },
        )
        .expect("unlimited")
    }

    fn check(a: &SparseMatrix) {
        let d = a.to_dense();
        let f = Factor::new(a);
        let r = dense::rank(&d);
        assert_eq!(f.rank(), r);
        let ns = f.null_space();
        assert_eq!(ns.len(), a.ncols - r);
        // Random null vectors: in the null space, and spanning it (k = nullity of them).
        let mut rng = SplitMix64::new(17);
        let rv = f.random_null_vectors(ns.len(), &mut rng);
        for x in &rv {
            assert!(a.mul_dense(x).iter().all(|v| v.is_zero()));
        }
        if !rv.is_empty() {
            let m = DMatrix::from_fn(a.ncols, rv.len(), |i, j| rv[j][i]);
            assert_eq!(dense::rank(&m), rv.len());
        }
        for x in &ns {
            assert!(a.mul_sparse(x).iter().all(|v| v.is_zero()));
        }
        // Independence: the free columns carry an identity.
        let free = f.free_columns();
        for (k, x) in ns.iter().enumerate() {
            for (l, &fc) in free.iter().enumerate() {
                let v = x.iter().find(|e| e.0 == fc).map_or(Fp::ZERO, |e| e.1);
                assert_eq!(v, if k == l { Fp::ONE } else { Fp::ZERO });
            }
        }
        let ln = left_null_space(a);
        assert_eq!(ln.len(), a.nrows() - r);
        for y in &ln {
            assert!(a.left_mul_sparse(y).iter().all(|v| v.is_zero()));
        }
        // The tracked factorization: same rank, and a random left null vector whose
        // support is that of the whole left null space.
        let t = tracked(a);
        assert_eq!(t.rank(), r);
        assert!(!f.is_tracked() && t.is_tracked());
        let y = t
            .random_left_null_vector(&mut SplitMix64::new(3))
            .expect("tracked");
        assert_eq!(y.len(), a.nrows());
        let ys: Vec<(u32, Fp)> = (0..y.len() as u32).map(|i| (i, y[i as usize])).collect();
        assert!(a.left_mul_sparse(&ys).iter().all(|v| v.is_zero()));
        let mut support = vec![false; a.nrows()];
        for v in &ln {
            for &(i, _) in v {
                support[i as usize] = true;
            }
        }
        let got: Vec<bool> = y.iter().map(|v| !v.is_zero()).collect();
        assert_eq!(got, support);
        let deps = dependent_rows(a);
        assert_eq!(deps.len(), a.nrows() - r);
        let greedy = dense::independent_rows(&d);
        for dep in &deps {
            assert!(!greedy.contains(&dep.row));
            assert_eq!(dep.support.last(), Some(&dep.row));
        }
        let keep: Vec<usize> = (0..a.nrows())
            .filter(|i| !deps.iter().any(|d| d.row == *i))
            .collect();
        let sub = DMatrix::from_fn(keep.len(), a.ncols, |i, j| d[(keep[i], j)]);
        assert_eq!(dense::rank(&sub), r);
        let mut basis = RowBasis::new(a.ncols);
        let kept: Vec<usize> = (0..a.nrows())
            .filter(|&i| basis.insert(&a.rows[i]))
            .collect();
        assert_eq!(kept, dense::independent_rows(&d));
        let mut ordered = RowBasis::with_column_order(&f.column_order());
        let kept2: Vec<usize> = (0..a.nrows())
            .filter(|&i| ordered.insert(&a.rows[i]))
            .collect();
        assert_eq!(kept2, kept);
        let mut tracked = RowBasis::with_column_order(&f.column_order()).with_tracking();
        for i in 0..a.nrows() {
            let k = tracked.insert(&a.rows[i]);
            assert_eq!(k, kept.contains(&i));
            match tracked.last_dependency() {
                Some(y) => {
                    assert!(!k);
                    assert_eq!(y.last(), Some(&(i as u32, Fp::ONE)));
                    assert!(a.left_mul_sparse(y).iter().all(|v| v.is_zero()));
                }
                None => assert!(k),
            }
        }
    }

    #[test]
    fn chain_and_loop() {
        // Planar: 4 movable bodies on R joints (2 rows per pair), a chain to the frame.
        let chain = [(0, 1, 2), (1, 2, 2), (2, 3, 2), (3, 4, 2)];
        let a = random_pair_matrix(5, 3, &chain, 1);
        check(&a);
        assert_eq!(Factor::new(&a).nullity(), 4);
        // Close the loop twice over: a redundant pair.
        let looped = [(0, 1, 2), (1, 2, 2), (2, 0, 2), (1, 2, 2)];
        let a = random_pair_matrix(3, 3, &looped, 2);
        check(&a);
        let f = Factor::new(&a);
        assert_eq!(f.rank(), 6);
        assert_eq!(f.stats().dependent_rows, 2);
    }

    /// Random mechanism-like patterns (trees with extra pairs, repeated pairs, pairs to the
    /// frame): fronts with rows left over, compressions with dependent rows, rows on no
    /// group; the tracked factorization's left null vector against the basis.
    #[test]
    fn tracked_left_null_space_on_random_patterns() {
        for seed in 0..40u64 {
            let mut rng = SplitMix64::new(seed);
            let nb = 2 + rng.below(30) as usize;
            let b = 1 + rng.below(6) as usize;
            let mut pairs = Vec::new();
            for x in 1..nb {
                pairs.push((
                    rng.below(x as u64) as usize,
                    x,
                    1 + rng.below(b as u64) as usize,
                ));
            }
            for _ in 0..rng.below(2 * nb as u64) {
                let (i, j) = (rng.below(nb as u64) as usize, rng.below(nb as u64) as usize);
                pairs.push((i, j, 1 + rng.below(b as u64 + 2) as usize));
            }
            let a = random_pair_matrix(nb, b, &pairs, seed);
            check(&a);
        }
    }

    /// A square block triangular pattern like `generate random` with its inputs: body `x`
    /// (a group of `b` columns) has `b` rows on itself and one or two earlier bodies; one
    /// body in `every` has a singular diagonal block (its last row's part on itself a
    /// combination of its other rows' parts), so the tier leaves a row over. Parents are
    /// among the `reach` bodies before.
    fn square_dag(nb: usize, b: usize, every: u64, reach: u64, seed: u64) -> SparseMatrix {
        let mut rng = SplitMix64::new(seed);
        let mut a = SparseMatrix::with_groups(vec![b; nb]);
        for x in 0..nb {
            let parents: Vec<usize> = match x {
                0 => vec![],
                1 => vec![0],
                _ => {
                    // Near earlier bodies: long chains of ancestors, as `generate random`.
                    let near = (x as u64).min(reach);
                    let p1 = x - 1 - rng.below(near) as usize;
                    let p2 = x - 1 - rng.below(near) as usize;
                    if p1 == p2 { vec![p1] } else { vec![p1, p2] }
                }
            };
            let singular = x > 0 && b > 1 && rng.below(every) == 0;
            let mut own: Vec<Vec<Fp>> = Vec::new();
            for k in 0..b {
                let v: Vec<Fp> = if singular && k == b - 1 {
                    let mut v = vec![Fp::ZERO; b];
                    for o in &own {
                        let c = Fp::random(&mut rng);
                        for (vi, oi) in v.iter_mut().zip(o) {
                            *vi += c * *oi;
                        }
                    }
                    v
                } else {
                    (0..b).map(|_| Fp::random(&mut rng)).collect()
                };
                own.push(v.clone());
                let mut e: Vec<(u32, Fp)> = Vec::new();
                for (c, &val) in v.iter().enumerate() {
                    e.push(((x * b + c) as u32, val));
                }
                if !parents.is_empty() {
                    let p = parents[k % parents.len()];
                    for c in 0..b {
                        e.push(((p * b + c) as u32, Fp::random(&mut rng)));
                    }
                }
                a.push_row(e);
            }
        }
        a
    }

    /// Rows left over by singular square tiers, set aside and met by later groups: the
    /// rank, null vectors, free columns and the tracked left null vector against dense
    /// elimination, and the same rank as carrying them through the fronts.
    #[test]
    fn square_tiers_with_singular_blocks() {
        for seed in 0..30u64 {
            let mut rng = SplitMix64::new(100 + seed);
            let nb = 2 + rng.below(40) as usize;
            let b = 1 + rng.below(4) as usize;
            let every = 1 + rng.below(4);
            let a = square_dag(nb, b, every, 1 + rng.below(nb as u64), seed);
            check(&a);
            check(&a.transpose());
            let r = Factor::new(&a).rank();
            SET_ASIDE.with(|c| c.set(false));
            let carried = Factor::new(&a).rank();
            SET_ASIDE.with(|c| c.set(true));
            assert_eq!(r, carried, "seed {seed}");
        }
    }

    /// The rank without the records is the factorization's rank, and under a budget it
    /// stops (or not) where the full factorization stops, having charged the same work:
    /// random pair matrices with dependent rows, empty rows and a square block triangular
    /// matrix whose set-aside rows meet records, under no limit and under memory and work
    /// limits around what the factorization needs.
    #[test]
    fn rank_without_records_is_the_factor_rank_within_the_same_budget() {
        let mut mats = vec![square_dag(300, 3, 7, 300, 3)];
        for seed in 0..6u64 {
            let mut rng = SplitMix64::new(seed);
            let nb = 30 + rng.below(40) as usize;
            let pairs: Vec<(usize, usize, usize)> = (0..2 * nb)
                .map(|_| {
                    let i = rng.below(nb as u64) as usize;
                    let j = rng.below(nb as u64) as usize;
                    (i, j, 1 + rng.below(5) as usize)
                })
                .collect();
            let mut a = random_pair_matrix(nb, 3 + (seed % 4) as usize, &pairs, seed);
            a.push_row([]);
            mats.push(a);
        }
        let run = |a: &SparseMatrix, budget: &Budget, records: bool| {
            let mut meter = budget.meter("test");
            let what = || "test".to_string();
            let mut limits = Limits {
                budget,
                meter: &mut meter,
                what: &what,
            };
            let r = if records {
                Factor::new_within(a, &mut limits).map(|f| f.rank())
            } else {
                Factor::rank_of_rows_within(a.clone(), &mut limits)
            };
            (r.map_err(|e| e.limit), meter.used())
        };
        let mut stopped = 0;
        for a in &mats {
            let full = run(a, &Budget::UNLIMITED, true);
            assert_eq!(full, run(a, &Budget::UNLIMITED, false));
            assert_eq!(full.0, Ok(dense::rank(&a.to_dense())));
            let work = full.1;
            for k in [1u64, 2, 3, 5, 8] {
                for budget in [
                    Budget {
                        max_memory_bytes: 400 * k * a.nrows() as u64,
                        ..Budget::UNLIMITED
                    },
                    Budget {
                        max_work: work * k / 8,
                        ..Budget::UNLIMITED
                    },
                ] {
                    let got = run(a, &budget, true);
                    stopped += usize::from(got.0.is_err());
                    assert_eq!(got, run(a, &budget, false));
                }
            }
        }
        assert!(stopped >= 10, "{stopped} stopped");
    }

    /// The work of factoring a square block triangular matrix whose singular diagonal blocks
    /// leave rows over (issue 16 item 4, `rigid --with-inputs` on a random spatial mechanism):
    /// carried through the fronts, such a row met every earlier body it reached, each front
    /// as wide as their union; set aside, it costs the records it meets.
    #[test]
    fn rows_left_over_by_square_tiers_cost_the_records_they_meet() {
        let a = square_dag(20000, 3, 500, 20000, 7);
        let work = |set_aside: bool| {
            SET_ASIDE.with(|c| c.set(set_aside));
            let budget = Budget::UNLIMITED;
            let mut meter = budget.meter("test");
            let what = || "test".to_string();
            let f = Factor::new_tracked_within(
                &a,
                &mut Limits {
                    budget: &budget,
                    meter: &mut meter,
                    what: &what,
                },
            )
            .expect("unlimited");
            SET_ASIDE.with(|c| c.set(true));
            (f.rank(), f.stats(), meter.used())
        };
        let (r0, s0, w0) = work(false);
        let (r1, s1, w1) = work(true);
        eprintln!("carried: rank {r0} {s0:?} work {w0}; set aside: rank {r1} {s1:?} work {w1}");
        assert_eq!(r0, r1);
        assert!(r1 < a.nrows());
        assert!(w1 < 30 * s1.input_entries as u64, "{w1} units");
        assert!(s1.max_front.1 <= 9 * 3, "{:?}", s1.max_front);
    }

    #[test]
    fn planted_dependencies() {
        let mut rng = SplitMix64::new(5);
        let mut a = SparseMatrix::with_groups(vec![2, 3, 1, 2]);
        for _ in 0..5 {
            let mut e: Vec<(u32, Fp)> = Vec::new();
            for c in 0..8 {
                if rng.below(3) == 0 {
                    e.push((c, Fp::random(&mut rng)));
                }
            }
            a.push_row(e);
        }
        let (r0, r1) = (a.rows[0].clone(), a.rows[1].clone());
        let k = Fp::from_i64(-3);
        a.push_row(r0.iter().map(|&(c, v)| (c, v * k)).chain(r1));
        a.push_row(vec![]);
        check(&a);
        check(&a.transpose());
    }

    #[test]
    fn blocks_interface() {
        let mut rng = SplitMix64::new(4);
        let mat = DMatrix::from_fn(2, 6, |_, _| Fp::random(&mut rng));
        let f = Factor::from_blocks(
            &[3, 3],
            vec![FpBlock {
                groups: vec![1, 0],
                mat,
            }],
        );
        assert_eq!(f.rank(), 2);
        assert_eq!(f.null_space().len(), 4);
    }

    #[test]
    fn row_basis_greedy() {
        let mut b = RowBasis::new(4);
        let one = Fp::ONE;
        assert!(b.insert(&[(1, one), (2, one)]));
        assert!(!b.insert(&[(2, Fp::from_i64(2)), (1, Fp::from_i64(2))]));
        assert!(b.insert(&[(2, one), (3, one)]));
        assert!(!b.insert(&[(1, one), (3, -one)]));
        assert!(!b.insert(&[]));
        assert!(b.insert(&[(0, one), (0, one)]));
        assert_eq!(b.rank(), 3);
    }
}
