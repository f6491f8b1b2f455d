//! The working blocks of an elimination: the input rows merged by the set of column groups
//! they touch, each block a dense row-major array.

use super::super::field::Fp;
use super::limits::FP_BYTES;
use super::matrix::{Rows, SparseMatrix, SparseRow};

/// Working block: row-major, never empty.
pub(super) struct Blk {
    pub(super) groups: Vec<usize>,
    pub(super) nrows: usize,
    pub(super) data: Vec<Fp>,
    /// The working id of its first row (its rows are `id..id + nrows`; see [`Trace`]).
    pub(super) id: u32,
}

impl Blk {
    /// Bytes it holds (entries and group list).
    pub(super) fn bytes(&self) -> u64 {
        ((self.data.len() + self.groups.len()) as u64).saturating_mul(FP_BYTES)
    }

    /// Its number of columns.
    pub(super) fn width(&self) -> usize {
        self.data.len().checked_div(self.nrows).unwrap_or(0)
    }
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
pub(super) fn blocks_of(a: &SparseMatrix) -> (Vec<Blk>, Vec<u32>) {
    let split = split_rows(a);
    (split.blocks, split.orig)
}

/// What [`split_rows`] gives: the blocks, the row of each working id, the rows without
/// entries and the entries in all.
pub(super) struct Split {
    pub(super) blocks: Vec<Blk>,
    pub(super) orig: Vec<u32>,
    pub(super) empty: Vec<u32>,
    pub(super) entries: usize,
}

/// Each row's set of groups (its columns are increasing, so the set is sorted and the
/// groups of a row are consecutive), all in one flat array: `sets[start[i]..start[i + 1]]`
/// for row `i`. One vector of groups per row, sorted with its row index, held 64 bytes a
/// row and its sort chased a pointer per comparison.
struct RowGroupSets {
    start: Vec<usize>,
    sets: Vec<u32>,
    /// The most groups of a row.
    longest: usize,
    /// The entries of the rows in all.
    entries: usize,
}

impl RowGroupSets {
    /// The groups of row `i`.
    fn set(&self, i: u32) -> &[u32] {
        &self.sets[self.start[i as usize]..self.start[i as usize + 1]]
    }

    /// The rows without entries, the nonempty rows sorted by set with their prefix keys,
    /// and whether equal keys are equal sets (out of `ngroups` groups, `nrows` rows).
    ///
    /// The nonempty rows by set, then by index: the order of the former sort of `(set, row)`
    /// pairs (the keys are distinct, so an unstable sort gives that order). Each row is
    /// sorted with a prefix key of its set, its first group and one more than its second
    /// (zero without), which orders sets of one or two groups as their lexicographic order
    /// does; longer sets (or more groups than a `u32` holds) are compared in full where the
    /// keys tie. With sets of at most two groups, equal keys are equal sets.
    #[allow(clippy::type_complexity)]
    fn rows_by_set(&self, ngroups: usize, nrows: usize) -> (Vec<u32>, Vec<(u64, u32)>, bool) {
        let start = &self.start;
        let set = |i: u32| self.set(i);
        let narrow = ngroups < u32::MAX as usize;
        let exact = narrow && self.longest <= 2;
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
        (empty, order, exact)
    }
}

/// The [`RowGroupSets`] of `a`, given each column's group.
fn row_group_sets<R: Rows + ?Sized>(
    a: &R,
    group_of: &[usize],
    buf: &mut SparseRow,
) -> RowGroupSets {
    let nrows = a.nrows();
    let mut entries = 0;
    let mut start: Vec<usize> = Vec::with_capacity(nrows + 1);
    let mut sets: Vec<u32> = Vec::new();
    start.push(0);
    let mut longest = 0;
    for i in 0..nrows {
        let r = a.row(i, buf);
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
    RowGroupSets {
        start,
        sets,
        longest,
        entries,
    }
}

/// [`blocks_of`] for any [`Rows`], with the rows without entries and the count of entries.
pub(super) fn split_rows<R: Rows + ?Sized>(a: &R) -> Split {
    let (sizes, offsets, group_of) = group_columns(a);
    let nrows = a.nrows();
    let mut buf: SparseRow = Vec::new();
    let rs = row_group_sets(a, &group_of, &mut buf);
    let entries = rs.entries;
    let (empty, order, exact) = rs.rows_by_set(sizes.len(), nrows);
    let set = |i: u32| rs.set(i);
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
pub(super) fn blocks_of_reference(a: &SparseMatrix) -> (Vec<Blk>, Vec<u32>) {
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
