//! The self-stresses of a mechanism at the file's geometry, as a dense orthonormal basis, and
//! what each one loads a joint with.
//!
//! The constraint Jacobian `J` (one row block per binary pair, acting on `t_other − t_hub`,
//! the frame's twist 0; [`crate::motion`] conventions) has a left null space of dimension
//! `rows − rank`: the self-stresses. A stress `w` loads joint `j` with the wrench
//! `λ_j = W_jᵀ w_j`, `W_j` the joint's orthonormal constraint rows. Removing from the joint the
//! rows of a subspace `Q ⊂ span W_j` keeps the rank (so the motion, to first order) exactly
//! when the stresses reach every direction of `Q`: `rank(Q Λ_j) = dim Q`. Every stress that
//! survives the change has no component along `Q`: the new basis is `Σ N`, `N` the null space
//! of `Q Λ_j`. The search ([`super::search`]) works on this basis alone; the result is then
//! checked by the library's own analyses.

use crate::budget::{BudgetExceeded, Meter};
use crate::mechanism::Mechanism;
use crate::motion::JointModel;
use nalgebra::DMatrix;

/// A self-stress basis and the joints' constraint rows.
#[derive(Clone)]
pub(super) struct Stresses {
    /// Per joint: its first row in `J` (binary joints only: `None` for multiple joints).
    pub offset: Vec<Option<usize>>,
    /// Per joint: its constraint rows (`c × B`, orthonormal).
    pub rows: Vec<DMatrix<f64>>,
    /// The basis, `rows(J) × r`, orthonormal columns.
    pub basis: DMatrix<f64>,
}

/// The self-stresses of `m` with the joint `models` (driven DOF released), `redundant` of
/// them (the geometric analysis's count: the same decision). Dense: work `~rows³`, charged.
pub(super) fn stresses(
    m: &Mechanism,
    models: &[JointModel],
    redundant: usize,
    meter: &mut Meter,
) -> Result<Stresses, BudgetExceeded> {
    let b = m.b() as usize;
    let mut col = vec![None; m.bodies.len()];
    let mut n = 0;
    for (i, c) in col.iter_mut().enumerate() {
        if i != m.frame {
            *c = Some(n);
            n += b;
        }
    }
    let mut offset = Vec::with_capacity(m.joints.len());
    let mut rows_total = 0;
    for (j, jm) in m.joints.iter().zip(models) {
        offset.push((j.bodies.len() == 2).then_some(rows_total));
        rows_total += jm.rows.nrows() * (j.bodies.len() - 1);
    }
    let size = rows_total.max(n);
    meter.charge((size as u64).saturating_pow(3))?;
    // Zero columns pad J to a square matrix, so that the SVD's U is complete.
    let mut a = DMatrix::<f64>::zeros(rows_total, size);
    let mut r0 = 0;
    for (j, jm) in m.joints.iter().zip(models) {
        let hub = j.bodies[0];
        for &other in &j.bodies[1..] {
            let c = jm.rows.nrows();
            for (body, sign) in [(other, 1.0), (hub, -1.0)] {
                if let Some(c0) = col[body] {
                    let mut block = a.view_mut((r0, c0), (c, b));
                    block += &jm.rows * sign;
                }
            }
            r0 += c;
        }
    }
    let basis = left_null(a, redundant);
    Ok(Stresses {
        offset,
        rows: models.iter().map(|jm| jm.rows.clone()).collect(),
        basis,
    })
}

/// The `k` left singular vectors of `a` (square) with the smallest singular values.
fn left_null(a: DMatrix<f64>, k: usize) -> DMatrix<f64> {
    let m = a.nrows();
    if k == 0 || m == 0 {
        return DMatrix::zeros(m, 0);
    }
    let svd = a.svd(true, false);
    let u = svd.u.expect("U was asked for");
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&x, &y| svd.singular_values[x].total_cmp(&svd.singular_values[y]));
    let cols: Vec<_> = order[..k.min(order.len())]
        .iter()
        .map(|&i| u.column(i).into_owned())
        .collect();
    DMatrix::from_columns(&cols)
}

impl Stresses {
    /// The wrenches the stresses load joint `j` with, `B × r` (`None`: a multiple joint).
    pub fn loads(&self, j: usize) -> Option<DMatrix<f64>> {
        let off = self.offset[j]?;
        let w = &self.rows[j];
        let block = self.basis.rows(off, w.nrows());
        Some(w.transpose() * block)
    }

    /// How much joint `j` carries the stresses (Frobenius norm of its stress rows).
    pub fn weight(&self, j: usize) -> f64 {
        match self.offset[j] {
            Some(off) => self.basis.rows(off, self.rows[j].nrows()).norm(),
            None => 0.0,
        }
    }

    /// Keep the stresses with no component along `q` (`d × B`) at joint `j`'s loads `loads`.
    pub fn restrict(&mut self, q_loads: &DMatrix<f64>) {
        let r = self.basis.ncols();
        let d = q_loads.nrows();
        let null = right_null(q_loads, r.saturating_sub(d));
        self.basis = &self.basis * null;
    }
}

/// The smallest singular value of `a` (`d × r`, `d ≤ r`): `rank(a) = d` when it is clear of 0.
pub(super) fn smallest_singular(a: &DMatrix<f64>) -> f64 {
    if a.nrows() == 0 {
        return f64::INFINITY;
    }
    if a.nrows() > a.ncols() {
        return 0.0;
    }
    let s = a.clone().svd(false, false).singular_values;
    s.iter().copied().fold(f64::INFINITY, f64::min)
}

/// An orthonormal basis (`r × k`) of the `k` directions of `R^r` that `a` (`d × r`) maps
/// least: its null space when `rank(a) = r − k`.
fn right_null(a: &DMatrix<f64>, k: usize) -> DMatrix<f64> {
    let r = a.ncols();
    // Pad to a square matrix so that V is complete.
    let mut sq = DMatrix::<f64>::zeros(r.max(a.nrows()), r);
    sq.view_mut((0, 0), (a.nrows(), r)).copy_from(a);
    let svd = sq.svd(false, true);
    let vt = svd.v_t.expect("V was asked for");
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&x, &y| svd.singular_values[x].total_cmp(&svd.singular_values[y]));
    let cols: Vec<_> = order[..k.min(order.len())]
        .iter()
        .map(|&i| vt.row(i).transpose())
        .collect();
    if cols.is_empty() {
        DMatrix::zeros(r, 0)
    } else {
        DMatrix::from_columns(&cols)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn left_null_of_a_rank_one_matrix() {
        let a = DMatrix::from_row_slice(3, 3, &[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        let y = left_null(a.clone(), 2);
        assert_eq!(y.ncols(), 2);
        assert!((y.transpose() * &a).norm() < 1e-12);
    }

    #[test]
    fn right_null_keeps_what_a_does_not_see() {
        let a = DMatrix::from_row_slice(1, 3, &[0.0, 1.0, 0.0]);
        let n = right_null(&a, 2);
        assert!((&a * &n).norm() < 1e-12);
        assert!((n.transpose() * &n - DMatrix::identity(2, 2)).norm() < 1e-12);
        assert!(smallest_singular(&a) > 0.5);
    }
}
