//! What the elimination keeps of each group: its pivot rows, reduced, for back substitution.

use super::super::field::Fp;
use super::matrix::SparseRow;

/// The eliminated rows of one group: pivots reduced to the identity on the group's columns.
#[derive(Clone, Debug)]
pub(super) struct Record {
    /// The group eliminated.
    pub(super) group: u32,
    /// Entries per row of `rows`: `free`'s count + the others' sizes.
    pub(super) width: u32,
    /// How many of `cols` are pivots, and how many after them are free columns.
    pub(super) npiv: u32,
    pub(super) nfree: u32,
    /// One allocation for three lists (a record per group: 10^6 of them at 10^6 bodies):
    /// the local columns of the pivots, in the order of the rows; the local columns left
    /// free (each gives a null vector); the other groups of the front, in column order
    /// after the group's own. Local columns and groups fit in `u32` (a front that wide
    /// would not fit in memory).
    pub(super) cols: Box<[u32]>,
    /// The pivot rows without their pivot columns (in reduced echelon form those are the
    /// identity, and nothing reads them once the front is done): `npiv × width` row-major,
    /// each row its entries on the free columns (in that order), then on the others'
    /// columns.
    pub(super) rows: Box<[Fp]>,
    /// Rows set aside by earlier tiers that took one of the group's free columns as their
    /// pivot ([`Carried`]), in that order: each is `x[col] = −Σ row · x` (global columns,
    /// the group's later free columns and groups eliminated after it). Their columns are in
    /// `free` (the pivot rows read them) but are not free in the null space.
    pub(super) extra: Box<[(usize, SparseRow)]>,
}

impl Record {
    pub(super) fn group(&self) -> usize {
        self.group as usize
    }

    pub(super) fn width(&self) -> usize {
        self.width as usize
    }

    pub(super) fn pivots(&self) -> &[u32] {
        &self.cols[..self.npiv as usize]
    }

    pub(super) fn free(&self) -> &[u32] {
        &self.cols[self.npiv as usize..(self.npiv + self.nfree) as usize]
    }

    pub(super) fn others(&self) -> &[u32] {
        &self.cols[(self.npiv + self.nfree) as usize..]
    }

    /// The local columns that are free in the null space (`free` minus the columns the
    /// set-aside rows took).
    pub(super) fn open(&self) -> impl Iterator<Item = usize> + '_ {
        self.free()
            .iter()
            .map(|&q| q as usize)
            .filter(|&q| self.extra.iter().all(|e| e.0 != q))
    }
}

/// The columns a record's set-aside rows took as pivots, last first (each may read the
/// later ones): `x[col] = −Σ row · x`. Whether any came out nonzero.
pub(super) fn solve_extra(rec: &Record, off: usize, x: &mut [Fp]) -> bool {
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
