//! The float decisions: the rank threshold, the padded SVD, and a block's rank by the cheapest
//! sound test (a small-block proof, the sparse screen, then the dense SVD).

use super::blocks::block_matrix;
use super::proof::surely_nonsingular;
use super::rows::PairRows;
use super::screen::screen;
use crate::structure::count::{Equations, Part};
use nalgebra::DMatrix;
use std::sync::atomic::{AtomicU64, Ordering};

/// Largest block (unknowns, equations) the rank check factorizes densely. A dense SVD costs
/// O(n^3) time and O(n^2) memory: 1,200 unknowns is about a second and 20 MB, while the giant
/// groups of some generated mechanisms (tens of thousands of unknowns) would need gigabytes
/// to terabytes. Larger blocks keep the count's verdict and are reported as unchecked (the
/// sparse screen is not a way out: on the giant groups of variant B its fill-in grows
/// without bound, 10 minutes and more at 22,000 unknowns).
pub(crate) const MAX_DENSE_UNKNOWNS: usize = 1200;

/// Relative tolerance on singular values (scaled by the largest one and the size). An exact
/// deficiency at random generic geometry leaves singular values near `n · ε` (numpy's
/// `matrix_rank` threshold, `ε` = 2.2e-16), 4,500 times below this; a long chain of loops is
/// nonsingular but can be badly conditioned: the 321-body group of a variant-B linkage of
/// 10^3 bodies has `σ_min / σ_max` below 1e-6, which a tolerance of 1e-9 took for a deficit.
pub(super) const REL_TOL: f64 = 1e-12;

/// The rank threshold of one analysis: singular values at most `max(rel · n · σ_max, abs)`
/// count as zero. Random geometry: `rel` = [`REL_TOL`],
/// `abs` = 0. File geometry: `rel` = 1e-9 (its numbers are decimals rounded to double
/// precision) and `abs` the perturbation its written precision allows (see
/// `docs/algorithms.md`, "Tolerance").
#[derive(Debug)]
pub(crate) struct Tol {
    pub rel: f64,
    pub abs: f64,
    /// At the file's geometry: where the decisions made with this threshold note how close
    /// they came to it.
    pub margins: Option<Margins>,
}

/// A decision within this factor of its threshold is close, and `analyze` says so in a note.
/// The threshold is twice the change the written precision may make to one unit row, so a
/// decision at 10 times it survives twenty times that change. `rigid --method geometric` flags
/// its own decisions within a factor 100 (one SVD of the whole Jacobian); with 100 here every
/// decision of a model whose threshold exceeds 1 % of a unit row was "close" (MuJoCo's
/// humanoid, numbers known to ±5e-4: a hinge pair's singular value of 0.65 at 32 times it).
pub(crate) const NEAR_FACTOR: f64 = 10.0;

/// How close the rank decisions of one check at the file's geometry came to their threshold:
/// the smallest value kept and the largest set aside, each divided by its threshold (only
/// those within [`NEAR_FACTOR`] are kept). A value
/// kept just above the threshold, or set aside just below, is a decision the written precision
/// barely makes: more digits, or a pose near a singular one, could turn it.
#[derive(Debug)]
pub(crate) struct Margins {
    /// `f64` bits of the smallest ratio above 1 (non-negative floats order as their bits).
    kept: AtomicU64,
    /// `f64` bits of the largest ratio at most 1.
    dropped: AtomicU64,
}

impl Default for Margins {
    fn default() -> Margins {
        Margins {
            kept: AtomicU64::new(f64::INFINITY.to_bits()),
            dropped: AtomicU64::new(0f64.to_bits()),
        }
    }
}

impl Margins {
    /// A value compared with `cut`: kept when above it.
    pub(super) fn note(&self, value: f64, cut: f64) {
        self.note_all(&[value], cut);
    }

    /// Values compared with `cut` (the singular values of one SVD): one atomic update of each
    /// extreme per call, however many values.
    pub(super) fn note_all(&self, values: &[f64], cut: f64) {
        if cut.is_nan() || cut <= 0.0 {
            return;
        }
        let (mut kept, mut dropped) = (f64::INFINITY, 0.0f64);
        for &v in values {
            let r = v.abs() / cut;
            if !r.is_finite() {
                continue;
            }
            if r > 1.0 {
                kept = kept.min(r);
            } else {
                dropped = dropped.max(r);
            }
        }
        // Only a close decision is ever reported: the others leave the shared state alone.
        if kept < NEAR_FACTOR {
            self.kept.fetch_min(kept.to_bits(), Ordering::Relaxed);
        }
        if dropped * NEAR_FACTOR > 1.0 {
            self.dropped.fetch_max(dropped.to_bits(), Ordering::Relaxed);
        }
    }

    /// The smallest kept and largest set-aside ratios when either lies within
    /// [`NEAR_FACTOR`] of 1.
    pub(super) fn near(&self) -> Option<(f64, f64)> {
        let kept = f64::from_bits(self.kept.load(Ordering::Relaxed));
        let dropped = f64::from_bits(self.dropped.load(Ordering::Relaxed));
        (kept < NEAR_FACTOR || dropped * NEAR_FACTOR > 1.0).then_some((kept, dropped))
    }
}

impl Tol {
    /// Note the singular values `sv` decided at `cut`, where this threshold keeps margins.
    pub(super) fn note_all(&self, sv: &[f64], cut: f64) {
        if let Some(m) = &self.margins {
            m.note_all(sv, cut);
        }
    }

    /// The threshold for a matrix of size `n` whose largest singular value is `smax`.
    pub(super) fn cut(&self, smax: f64, n: usize) -> f64 {
        (smax * n.max(1) as f64 * self.rel)
            .max(self.abs)
            .max(1e-300)
    }
}

/// Singular values and vectors of `a` padded with zeros to a square matrix, so that the thin
/// SVD holds full bases of both null spaces.
pub(super) struct Svd {
    pub(super) sv: Vec<f64>,
    pub(super) u: DMatrix<f64>,
    pub(super) tol: f64,
}

impl Svd {
    /// Full SVD (singular values and both bases).
    pub(super) fn of(a: &DMatrix<f64>, t: &Tol) -> Svd {
        // V as before, although unused: the deficit path stays exactly the original SVD.
        let (sv, tol, u, _) = svd_parts(a, true, true, t);
        t.note_all(&sv, tol);
        Svd {
            sv,
            u: u.expect("requested U"),
            tol,
        }
    }

    /// The singular values and the left basis only (the same values as [`Svd::of`]).
    pub(super) fn left(a: &DMatrix<f64>, t: &Tol) -> Svd {
        let (sv, tol, u, _) = svd_parts(a, true, false, t);
        t.note_all(&sv, tol);
        Svd {
            sv,
            u: u.expect("requested U"),
            tol,
        }
    }

    pub(super) fn rank(&self) -> usize {
        self.sv.iter().filter(|&&s| s > self.tol).count()
    }
}

/// The padded SVD behind [`Svd`]; `compute_u` / `compute_v` only decide which bases are
/// accumulated: the singular values come out bit for bit the same either way (the rotations
/// are computed regardless), so rank decisions agree with the full SVD.
#[allow(clippy::type_complexity)]
pub(super) fn svd_parts(
    a: &DMatrix<f64>,
    compute_u: bool,
    compute_v: bool,
    t: &Tol,
) -> (Vec<f64>, f64, Option<DMatrix<f64>>, Option<DMatrix<f64>>) {
    let n = a.nrows().max(a.ncols()).max(1);
    let p = if a.nrows() == n && a.ncols() == n {
        a.clone()
    } else {
        let mut p = DMatrix::<f64>::zeros(n, n);
        p.view_mut((0, 0), (a.nrows(), a.ncols())).copy_from(a);
        p
    };
    let svd = p.svd(compute_u, compute_v);
    let sv: Vec<f64> = svd.singular_values.iter().copied().collect();
    let max = sv.iter().copied().fold(0.0, f64::max);
    let tol = t.cut(max, n);
    (sv, tol, svd.u, svd.v_t)
}

/// Numerical rank (same decision as `Svd::of(a).rank()`), without the singular vectors.
pub(super) fn rank_of(a: &DMatrix<f64>, t: &Tol) -> usize {
    if a.nrows() == 0 || a.ncols() == 0 {
        return 0;
    }
    let (sv, tol, _, _) = svd_parts(a, false, false, t);
    t.note_all(&sv, tol);
    sv.iter().filter(|&&s| s > tol).count()
}

/// `n^3`, the work units of a dense factorization of `n` unknowns.
pub(super) fn cube(n: usize) -> u64 {
    (n as u64).saturating_mul(n as u64).saturating_mul(n as u64)
}

/// The rank of a block that is not too large for the dense check, and its work units: small
/// square blocks on the stack, then the sparse screen, then the dense SVD.
#[allow(clippy::too_many_arguments)]
pub(super) fn block_rank(
    b: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &PairRows,
    q: &[Option<DMatrix<f64>>],
    part: Part,
    tol: &Tol,
    (nrows, ncols): (usize, usize),
) -> (usize, u64) {
    if nrows == ncols && surely_nonsingular(b, block_eqs, bodies, eqs, rows, q, tol) {
        return (nrows, cube(nrows));
    }
    match screen(b, block_eqs, bodies, eqs, rows, q, part, tol) {
        Some(r) => (r, 64 * (nrows + ncols) as u64),
        None => (
            rank_of(&block_matrix(b, block_eqs, bodies, eqs, rows, q), tol),
            64 * (nrows + ncols) as u64 + cube(nrows.max(ncols)),
        ),
    }
}
