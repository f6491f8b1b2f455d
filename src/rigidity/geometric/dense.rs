//! Dense linear algebra on small matrices (one body's or one joint's few columns): null
//! spaces, ranks and orthonormal bases.

use nalgebra::{DMatrix, DVector};

/// Null space basis (orthonormal columns) of a small matrix `a` (r × c): right singular
/// vectors with σ ≤ rel · σ_max (absolute `abs` when σ_max is 0).
pub(super) fn small_null(a: &DMatrix<f64>, rel: f64) -> DMatrix<f64> {
    let c = a.ncols();
    if c == 0 {
        return DMatrix::zeros(0, 0);
    }
    let padded = if a.nrows() < c {
        a.clone().insert_rows(a.nrows(), c - a.nrows(), 0.0)
    } else {
        a.clone()
    };
    let svd = padded.svd(false, true);
    let vt = svd.v_t.expect("v_t was requested");
    let smax = svd.singular_values.max();
    let thr = rel * smax.max(f64::MIN_POSITIVE);
    let cols: Vec<DVector<f64>> = svd
        .singular_values
        .iter()
        .enumerate()
        .filter(|(_, s)| **s <= thr || smax == 0.0)
        .map(|(i, _)| vt.row(i).transpose())
        .collect();
    if cols.is_empty() {
        DMatrix::zeros(c, 0)
    } else {
        DMatrix::from_columns(&cols)
    }
}

/// Numerical rank with an absolute threshold.
pub(super) fn small_rank(a: &DMatrix<f64>, abs: f64) -> usize {
    if a.nrows() == 0 || a.ncols() == 0 {
        return 0;
    }
    a.clone()
        .svd(false, false)
        .singular_values
        .iter()
        .filter(|s| **s > abs)
        .count()
}

/// Modified Gram-Schmidt on dense vectors; near-zero ones dropped.
pub(super) fn orthonormalize(vs: Vec<DVector<f64>>) -> Vec<DVector<f64>> {
    let mut out: Vec<DVector<f64>> = Vec::new();
    for mut v in vs {
        let n0 = v.norm();
        for _ in 0..2 {
            for q in &out {
                let d = q.dot(&v);
                v.axpy(-d, q, 1.0);
            }
        }
        if v.norm() > 1e-8 * n0.max(1e-300) {
            let n = v.norm();
            out.push(v / n);
        }
    }
    out
}
