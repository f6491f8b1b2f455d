//! The incremental row basis for greedy redundancy removal, and the dependent rows and left
//! null space computed with it.

use super::super::field::Fp;
use super::factor::Factor;
use super::matrix::{SparseMatrix, SparseRow};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

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
    pub(super) ncols: usize,
    /// Position of each column in the pivot order (empty: the identity).
    rank_of: Vec<u32>,
    /// The kept rows, reduced: leading entry 1, all other columns after it.
    pub(super) rows: Vec<SparseRow>,
    /// The kept row leading at each column.
    pub(super) pivot: Vec<u32>,
    pub(super) acc: Vec<Fp>,
    pub(super) mark: Vec<bool>,
    /// Rows inserted so far (the next row's id).
    inserted: u32,
    /// Whether combinations are tracked ([`RowBasis::with_tracking`]).
    pub(super) track: bool,
    /// Per kept row, its combination of the inserted rows (by id).
    combos: Vec<SparseRow>,
    cacc: Vec<Fp>,
    cmark: Vec<bool>,
    pub(super) last_dependency: Option<SparseRow>,
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
            self.start_combination(id, &mut ctouched);
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
                self.keep_remainder(c, v, heap, &mut ctouched);
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
            self.finish_combination(ctouched, kept);
        }
        kept
    }

    /// Tracking: the combination of the row being inserted (id `id`) starts as itself.
    fn start_combination(&mut self, id: u32, ctouched: &mut Vec<u32>) {
        if self.cacc.len() <= id as usize {
            let n = (2 * self.cacc.len()).max(id as usize + 1);
            self.cacc.resize(n, Fp::ZERO);
            self.cmark.resize(n, false);
        }
        self.cacc[id as usize] = Fp::ONE;
        self.cmark[id as usize] = true;
        ctouched.push(id);
    }

    /// Tracking: the combination of the row just inserted (over the ids `ctouched`) is its
    /// dependency if it was not kept; then cleared.
    fn finish_combination(&mut self, mut ctouched: Vec<u32>, kept: bool) {
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

    /// The row being inserted is independent: its remainder in `acc` (leading value `v` at
    /// column `c`, the other columns left in `heap`) becomes a kept row leading at `c`.
    fn keep_remainder(
        &mut self,
        c: u32,
        v: Fp,
        heap: BinaryHeap<Reverse<u32>>,
        ctouched: &mut [u32],
    ) {
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
    }

    /// Entries stored in the tracked combinations.
    pub fn combination_entries(&self) -> usize {
        self.combos.iter().map(|r| r.len()).sum()
    }
}
