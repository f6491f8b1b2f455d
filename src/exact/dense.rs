//! Dense exact linear algebra on `DMatrix<Fp>`: rank, null spaces, the annihilator of a
//! column space, and greedy independent rows, all by Gaussian elimination (any nonzero pivot
//! is exact, so the first one found is taken).
//!
//! Results are deterministic functions of the input: the pivot in each column is the first
//! nonzero entry in row order, and bases come out in the reduced-row-echelon normal form.

use super::field::{Fp, axpy_sub, scale};
use nalgebra::DMatrix;

/// A row-major copy of a matrix, the working form of the eliminations.
struct Rows {
    ncols: usize,
    data: Vec<Fp>,
}

impl Rows {
    fn of(a: &DMatrix<Fp>) -> Rows {
        let (m, n) = a.shape();
        let mut data = Vec::with_capacity(m * n);
        for i in 0..m {
            for j in 0..n {
                data.push(a[(i, j)]);
            }
        }
        Rows { ncols: n, data }
    }

    fn nrows(&self) -> usize {
        self.data.len().checked_div(self.ncols).unwrap_or(0)
    }

    fn row(&self, i: usize) -> &[Fp] {
        &self.data[i * self.ncols..(i + 1) * self.ncols]
    }

    /// Rows `i` (mutable) and `k` (shared), `i != k`.
    fn pair(&mut self, i: usize, k: usize) -> (&mut [Fp], &[Fp]) {
        let n = self.ncols;
        if i < k {
            let (lo, hi) = self.data.split_at_mut(k * n);
            (&mut lo[i * n..(i + 1) * n], &hi[..n])
        } else {
            let (lo, hi) = self.data.split_at_mut(i * n);
            (&mut hi[..n], &lo[k * n..(k + 1) * n])
        }
    }

    fn swap_rows(&mut self, i: usize, k: usize) {
        if i != k {
            let n = self.ncols;
            for j in 0..n {
                self.data.swap(i * n + j, k * n + j);
            }
        }
    }
}

/// Gaussian elimination in place. Returns the pivot columns, in order; afterwards rows
/// `0..rank` are the echelon rows (pivots scaled to one). With `reduced`, entries above the
/// pivots are cleared too (reduced row echelon form).
fn eliminate(m: &mut Rows, reduced: bool) -> Vec<usize> {
    let (nr, nc) = (m.nrows(), m.ncols);
    let mut pivots = Vec::new();
    let mut r = 0;
    for c in 0..nc {
        if r == nr {
            break;
        }
        let Some(p) = (r..nr).find(|&i| !m.data[i * nc + c].is_zero()) else {
            continue;
        };
        m.swap_rows(r, p);
        let inv = m.data[r * nc + c].inv();
        scale(&mut m.data[r * nc + c..(r + 1) * nc], inv);
        let start = if reduced { 0 } else { r + 1 };
        for i in start..nr {
            if i == r {
                continue;
            }
            let f = m.data[i * nc + c];
            if !f.is_zero() {
                let (dst, src) = m.pair(i, r);
                axpy_sub(&mut dst[c..], f, &src[c..]);
            }
        }
        pivots.push(c);
        r += 1;
    }
    pivots
}

/// The rank of `a`.
pub fn rank(a: &DMatrix<Fp>) -> usize {
    let mut m = if a.nrows() >= a.ncols() {
        Rows::of(a)
    } else {
        Rows::of(&a.transpose())
    };
    eliminate(&mut m, false).len()
}

/// The columns of `a` that are independent of the earlier columns (greedy in column order:
/// the pivot columns of the echelon form).
pub fn independent_columns(a: &DMatrix<Fp>) -> Vec<usize> {
    let mut m = Rows::of(a);
    eliminate(&mut m, false)
}

/// A basis of the null space {x : A x = 0}, as the columns of an `ncols × (ncols − rank)`
/// matrix: one vector per free column of the reduced echelon form, 1 on that column and 0
/// on the other free columns.
pub fn null_space(a: &DMatrix<Fp>) -> DMatrix<Fp> {
    let n = a.ncols();
    let mut m = Rows::of(a);
    let pivots = eliminate(&mut m, true);
    let mut is_pivot = vec![false; n];
    for &c in &pivots {
        is_pivot[c] = true;
    }
    let free: Vec<usize> = (0..n).filter(|&c| !is_pivot[c]).collect();
    let mut out = DMatrix::zeros(n, free.len());
    for (k, &f) in free.iter().enumerate() {
        out[(f, k)] = Fp::ONE;
        for (i, &c) in pivots.iter().enumerate() {
            out[(c, k)] = -m.row(i)[f];
        }
    }
    out
}

/// A basis of the left null space {y : yᵀ A = 0}, as the columns of an
/// `nrows × (nrows − rank)` matrix (the [`null_space`] of `Aᵀ`).
pub fn left_null_space(a: &DMatrix<Fp>) -> DMatrix<Fp> {
    null_space(&a.transpose())
}

/// A basis, as rows, of the annihilator of the column space of `twists` (b × k): a
/// `(b − rank) × b` matrix `R` of full row rank with `R · twists = 0`. For a joint whose
/// allowed motions are the columns of `twists`, these are its constraint rows.
pub fn complement_rows(twists: &DMatrix<Fp>) -> DMatrix<Fp> {
    left_null_space(twists).transpose()
}

/// The rows of `a` independent of the rows kept before them (greedy in row order: row `i`
/// is kept iff it is not a combination of the kept earlier rows). The kept rows are a basis
/// of the row space; their number is the rank.
pub fn independent_rows(a: &DMatrix<Fp>) -> Vec<usize> {
    independent_columns(&a.transpose())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mat(rows: &[&[i64]]) -> DMatrix<Fp> {
        let n = rows.first().map_or(0, |r| r.len());
        DMatrix::from_fn(rows.len(), n, |i, j| Fp::from_i64(rows[i][j]))
    }

    #[test]
    fn small_ranks() {
        assert_eq!(rank(&mat(&[&[1, 2], &[2, 4]])), 1);
        assert_eq!(rank(&mat(&[&[1, 2, 3], &[4, 5, 6], &[7, 8, 9]])), 2);
        assert_eq!(rank(&mat(&[&[0, 0], &[0, 0]])), 0);
        assert_eq!(rank(&DMatrix::<Fp>::zeros(0, 4)), 0);
        assert_eq!(rank(&DMatrix::<Fp>::identity(5, 5)), 5);
    }

    #[test]
    fn null_spaces() {
        let a = mat(&[&[1, 2, 3], &[4, 5, 6], &[7, 8, 9]]);
        let n = null_space(&a);
        assert_eq!(n.ncols(), 1);
        assert!((&a * &n).iter().all(|x| x.is_zero()));
        // x = (1, -2, 1).
        assert_eq!(
            n.column(0).iter().map(|x| x.to_i64()).collect::<Vec<_>>(),
            [1, -2, 1]
        );
        let l = left_null_space(&a);
        assert_eq!(l.ncols(), 1);
        assert!((l.transpose() * &a).iter().all(|x| x.is_zero()));
        let z = DMatrix::<Fp>::zeros(2, 3);
        assert_eq!(null_space(&z).ncols(), 3);
        assert_eq!(left_null_space(&z).ncols(), 2);
        assert_eq!(null_space(&DMatrix::<Fp>::zeros(0, 2)).ncols(), 2);
    }

    #[test]
    fn complement_of_a_revolute_twist() {
        // Planar revolute about the origin: twist (ω, vx, vy) = (1, 0, 0) and a slider.
        let t = mat(&[&[1, 0], &[0, 1], &[0, 0]]);
        let r = complement_rows(&t);
        assert_eq!(r.shape(), (1, 3));
        assert!((&r * &t).iter().all(|x| x.is_zero()));
        assert_eq!(rank(&r), 1);
        // Dependent twists: rank 1, two complement rows.
        let t = mat(&[&[1, 2], &[1, 2], &[0, 0]]);
        let r = complement_rows(&t);
        assert_eq!(r.shape(), (2, 3));
        assert!((&r * &t).iter().all(|x| x.is_zero()));
    }

    #[test]
    fn greedy_rows() {
        let a = mat(&[
            &[0, 0, 0],
            &[1, 1, 0],
            &[2, 2, 0],
            &[0, 1, 0],
            &[1, 0, 0],
            &[0, 0, 5],
        ]);
        assert_eq!(independent_rows(&a), [1, 3, 5]);
        assert_eq!(independent_columns(&a.transpose()), [1, 3, 5]);
    }
}
