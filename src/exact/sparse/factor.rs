//! The factorization: its constructors over the input forms and budgets, and its rank and
//! statistics.

use super::blocks::{Blk, split_rows};
use super::limits::Limits;
use super::matrix::{FpBlock, Rows, SparseMatrix};
use super::record::Record;
use super::trace::Trace;
use crate::budget::BudgetExceeded;

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
    pub(super) sizes: Vec<usize>,
    pub(super) offsets: Vec<usize>,
    pub(super) records: Vec<Record>,
    pub(super) rank: usize,
    pub(super) stats: FactorStats,
    /// How the dependent rows combine the input rows ([`Factor::new_tracked_within`]).
    pub(super) trace: Option<Trace>,
}

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
    /// transpose of a mechanism's Jacobian (see [`crate::motion::exact::pairs_stress_support`]).
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
}
