//! The global solve's QR steps, for systems whose normal equations are too ill-conditioned.
//!
//! [`super::sparse`] takes each Gauss–Newton step from the Cholesky factor of the normal
//! equations, which square the Jacobian's conditioning: a long chain of loops (a strip of dyads,
//! `κ(J)` growing as the square of its length) passes `10⁸` near 3·10^4 bodies, where `κ²`
//! reaches the rounding of double precision and the steps stop reducing the residual. Here the
//! step is the basic least-squares solution of `J δ = −e` by the multifrontal QR of
//! [`crate::elimination`]: `J`'s columns (body-local twists, see [`super::sparse`]) scaled to
//! unit norm, one group a body in the factor's elimination order, `e` carried as a last column
//! that is never eliminated. A column whose residual against the columns before it is under
//! [`QR_TOLERANCE`] (a redundant equation, an isolated spin, a singular configuration) gets
//! no step, so free unknowns do not move. QR's dense fronts cost far more than the block
//! Cholesky where the factor fills in (11 to 16 times on random spatial Assur linkages of 1,000
//! bodies), so it is used only where the fill is small ([`Sparse::qr_affordable`]).

use super::newton::NewtonOptions;
use super::sparse::Sparse;
use crate::budget::{BudgetExceeded, Limit, Meter};
use crate::elimination::{Block, Elimination, Stop};
use nalgebra::{DMatrix, DVector};

/// Residual norm (of a column scaled to unit norm) under which the QR of a step takes the
/// column for dependent on those before it.
const QR_TOLERANCE: f64 = 1e-12;

/// Most factor blocks in one column of the Cholesky factor for which the QR steps are tried:
/// chains and ladders of loops have 1 or 2, random Assur linkages over a hundred.
const MAX_FILL_COLUMN: usize = 8;

/// The pairs' Jacobians at one point: pair `p`'s rows are `start[p]..start[p + 1]`, each row
/// its `2B` entries (the first body's columns, then the second's).
#[derive(Default)]
pub(super) struct Jacobian {
    start: Vec<usize>,
    vals: Vec<f64>,
}

impl Jacobian {
    /// Forget every pair.
    pub(super) fn clear(&mut self) {
        self.start.clear();
        self.vals.clear();
        self.start.push(0);
    }

    /// The next pair's rows.
    pub(super) fn push(&mut self, j: &DMatrix<f64>) {
        for i in 0..j.nrows() {
            self.vals.extend(j.row(i).iter());
        }
        let last = self.start.last().copied().unwrap_or(0);
        self.start.push(last + j.nrows());
    }
}

impl Sparse<'_> {
    /// Whether the QR steps are worth trying: the factor's columns hold few blocks.
    pub(super) fn qr_affordable(&self) -> bool {
        self.symbolic().widest_column() <= MAX_FILL_COLUMN
    }

    /// The Gauss–Newton step (body-local twists, elimination order): the basic least-squares
    /// solution of `J δ = −e` by the multifrontal QR of `J`'s columns scaled to unit norm.
    /// `diag` holds each unknown's `‖J column‖²`, in elimination order.
    pub(super) fn qr_step(
        &self,
        jac: &Jacobian,
        e: &[f64],
        diag: &[f64],
        opts: &NewtonOptions,
        meter: &mut Meter,
    ) -> Result<Vec<f64>, BudgetExceeded> {
        let b = self.model_b();
        let n = diag.len() / b.max(1);
        let scale: Vec<f64> = diag
            .iter()
            .map(|&d| if d > 0.0 { 1.0 / d.sqrt() } else { 0.0 })
            .collect();
        let mut sizes = vec![b; n];
        sizes.push(1);
        let mut blocks = Vec::with_capacity(self.slots.len());
        for (p, slot) in self.slots.iter().enumerate() {
            let (lo, hi) = (jac.start[p], jac.start[p + 1]);
            // Each block's groups ascending; the residual's group `n` comes last.
            let mut sides: Vec<(usize, u32)> = [(0, slot.a), (1, slot.b)]
                .into_iter()
                .filter_map(|(side, k)| k.map(|k| (side, k)))
                .collect();
            sides.sort_by_key(|&(_, k)| k);
            if sides.is_empty() || hi == lo {
                continue;
            }
            let cols = sides.len() * b + 1;
            let mat = DMatrix::from_fn(hi - lo, cols, |i, c| {
                let row = lo + i;
                match sides.get(c / b) {
                    Some(&(side, k)) => {
                        jac.vals[row * 2 * b + side * b + c % b] * scale[k as usize * b + c % b]
                    }
                    None => e[row],
                }
            });
            let mut groups: Vec<usize> = sides.iter().map(|&(_, k)| k as usize).collect();
            groups.push(n);
            blocks.push(Block { groups, mat });
        }
        let order: Vec<usize> = (0..n).collect();
        let max = opts.budget.max_memory_bytes;
        let elim =
            Elimination::run_in_order_metered(&sizes, blocks, QR_TOLERANCE, max, &order, meter)
                .map_err(|stop| match stop {
                    Stop::Work(e) => e,
                    Stop::Memory(needed) => BudgetExceeded {
                        limit: Limit::Memory,
                        what: "the sparse QR factorization of the global solve".into(),
                        needed,
                        at_least: true,
                        allowed: max,
                    },
                })?;
        let mut x = DVector::zeros(n * b + 1);
        x[n * b] = 1.0;
        elim.back_substitute(&mut x);
        Ok((0..n * b).map(|i| x[i] * scale[i]).collect())
    }
}
