//! The sparse matrix over GF(p) with its columns grouped by body, the dense blocks of the
//! floating-point interface, rows read one at a time ([`Rows`]) and a random test pattern.

use super::super::field::Fp;
use crate::rng::SplitMix64;
use nalgebra::DMatrix;

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

/// Rows read one at a time, by index: what [`split_rows`] needs of a matrix. A
/// [`SparseMatrix`] lends its rows; a compact description of the rows (the joints of a
/// mechanism's pairs, [`crate::motion::exact::pairs_factor`]) makes each when asked, so
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
