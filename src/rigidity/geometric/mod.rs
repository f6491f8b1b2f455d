//! Geometric rigidity: true mobility, redundant constraints, isolated DOF and rigid clusters
//! from the constraint Jacobian in twist form (see [`crate::motion`] for the conventions).
//!
//! # Method
//! 1. Every binary pair (a multiple joint is n − 1 pairs hub→other) contributes the rows of its
//!    [`JointModel`] acting on `t_other − t_hub`; the frame's twist is 0.
//! 2. Fully isolated DOF of body b: the null space of the rows of b's pairs acting on `t_b`
//!    alone (neighbours fixed). These motions are set aside by restricting each body's twist
//!    to the orthogonal complement of its isolated space (the null space of the Jacobian is
//!    the direct sum of both parts, so nothing is lost).
//! 3. The reduced Jacobian is never formed densely: its rank, null space and left null space
//!    come from a block-sparse QR elimination, body by body in a greedy minimum-front order
//!    (multifrontal QR): the rows touching a body are merged, a Householder QR with column
//!    pivoting on that body's columns decides its rank, the remaining rows become a new row
//!    block on its neighbours. A pivot is kept when it exceeds `tol · σ_max` with
//!    `tol = 1e-9 · max(rows, cols)` and `σ_max` from a power iteration; the smallest kept and
//!    the largest dropped pivot give the gap, and a decision within a factor 100 of the
//!    threshold is reported as ill-conditioned. The left null space (self-stresses) comes from
//!    the same elimination on the transpose, with the pairs as unknowns.
//! 4. Rigid clusters: bodies whose twists agree for every motion of the reduced null space.
//!    Structurally isolated DOF: for each cluster of two or more bodies without the frame, the
//!    rigid motions allowed by its boundary joints (the rest fixed), counted modulo its bodies'
//!    fully isolated motions.
//! 5. Loops: a minimum cycle basis (Horton's algorithm) of the body graph in which a multiple
//!    joint is a node; spatiality = rank of the loop's joint twists (driven DOF included);
//!    overconstraint = B − spatiality (= the loop's rows minus the rank of its own system).
//!
//! Results hold for the configuration analysed (instantaneous, first order).

use crate::budget::{Budget, BudgetExceeded};
use crate::exact::Fp;
use crate::geometry::GeometryUsed;
use crate::mechanism::Mechanism;
use crate::motion::{self, MotionError};
use nalgebra::DMatrix;

pub use crate::geometry::GeometrySource;

mod analysis;
mod clusters;
mod dense;
mod dense_part;
mod exact_part;
mod isolated;
mod jacobian;
mod loops;
mod redundancy;
mod report;
mod sparse_float;
#[cfg(test)]
mod tests;

use analysis::analyze_models;
use exact_part::EXACT_PART_COLUMNS;
pub use redundancy::STRESS_RESIDUAL;
pub use report::{
    Axis, GeometricReport, IsolatedMotion, JointCount, JointWeight, LoopInfo, Numeric, RigidCluster,
};
#[doc(hidden)]
pub use sparse_float::with_sparse_from;

/// Options of [`analyze`].
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct GeometricOptions {
    /// Geometry source.
    pub geometry: GeometrySource,
    /// File geometry: how precisely its numbers are known (±); default: from the digits
    /// written ([`crate::motion::written_precision`]).
    pub precision: Option<f64>,
    /// Tell finite from instantaneous mobility (not implemented yet: reported as skipped).
    pub check_finite: bool,
}

/// Mechanisms with at most this many unknowns are analysed as one part (the whole Jacobian);
/// larger ones block by block ([`jacobian::biconnected_parts`]).
const ONE_PART_COLUMNS: usize = 1200;

/// Why [`analyze_within`] gave no report.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeometricError {
    /// The joint geometry cannot be modelled.
    #[error(transparent)]
    Motion(#[from] MotionError),
    /// The analysis would exceed the budget (a rigid block too large for its dense motions).
    #[error(transparent)]
    Budget(#[from] BudgetExceeded),
}

/// The geometric rigidity analysis of `m`, without a budget (see [`analyze_within`]).
pub fn analyze(m: &Mechanism, opts: &GeometricOptions) -> Result<GeometricReport, MotionError> {
    match analyze_within(m, opts, &Budget::UNLIMITED) {
        Ok(r) => Ok(r),
        Err(GeometricError::Motion(e)) => Err(e),
        // An unlimited budget is never exceeded (charges saturate at u64::MAX, which it
        // allows).
        Err(GeometricError::Budget(e)) => unreachable!("unlimited budget exceeded: {e}"),
    }
}

/// The geometric rigidity analysis of `m` within `budget`: the work is charged to a meter and
/// the memory of the dense motions of each rigid block is estimated before it is allocated.
pub fn analyze_within(
    m: &Mechanism,
    opts: &GeometricOptions,
    budget: &Budget,
) -> Result<GeometricReport, GeometricError> {
    analyze_split(m, opts, budget, ONE_PART_COLUMNS, EXACT_PART_COLUMNS)
}

/// [`analyze_within`], analysing mechanisms of at most `one_part` unknowns as one part.
fn analyze_split(
    m: &Mechanism,
    opts: &GeometricOptions,
    budget: &Budget,
    one_part: usize,
    exact_from: usize,
) -> Result<GeometricReport, GeometricError> {
    let real = crate::geometry::realization(m, opts.geometry, opts.precision)?;
    // Full (undriven) twists for loop spatiality, at the same geometry: built only when the
    // loops are listed (a copy of the mechanism and a model per joint, hundreds of megabytes
    // at 10^6 bodies, where the loops are too many to list).
    let seed = real.used.seed;
    let full_twists = || -> Vec<DMatrix<f64>> {
        let mut free = m.clone();
        for j in &mut free.joints {
            j.driven = 0;
        }
        let full_models = match seed {
            Some(seed) => motion::realize(&free, seed),
            None => motion::configure(&free).unwrap_or_default(),
        };
        drop(free);
        full_models.into_iter().map(|jm| jm.twists).collect()
    };
    // At a random realization, every joint's exact rows (once per joint, shared by the pairs
    // of a multiple joint).
    let exact_rows: Option<Vec<DMatrix<Fp>>> = real.used.seed.map(|seed| {
        m.joints
            .iter()
            .enumerate()
            .map(|(ji, j)| crate::motion::exact::joint_rows(m, ji, seed, j.driven))
            .collect()
    });
    let mut meter = budget.meter("the geometric rigidity analysis");
    analyze_models(
        m,
        &real.models,
        &full_twists,
        real.used,
        exact_rows.as_deref(),
        opts.check_finite,
        budget,
        &mut meter,
        one_part,
        exact_from,
    )
    .map_err(GeometricError::Budget)
}

/// Rank threshold of the analysis: relative to σ_max at random geometry; at the file's
/// geometry also the perturbation its rounded numbers allow ([`crate::geometry::file_threshold`]).
fn threshold(m: &Mechanism, used: &GeometryUsed, smax: f64, n: usize) -> (f64, f64) {
    let rel = 1e-9 * n.max(1) as f64;
    let mut abs = rel * smax.max(f64::MIN_POSITIVE);
    if let Some(t) = crate::geometry::file_threshold(m, used) {
        abs = abs.max(t);
    }
    (abs / smax.max(f64::MIN_POSITIVE), abs)
}
