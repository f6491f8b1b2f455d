//! The rank check: the count decomposition evaluated at a random generic realization of the
//! joint geometry ([`crate::motion::realize`]).
//!
//! 1. Isolated freedoms: for each body, the nullity of the stacked constraint rows of every pair
//!    touching it, its neighbours held fixed (a bar between two S joints has 1). Its unknowns
//!    become the complement `Q_b` of that null space, so `u_b = B − iso_b`.
//! 2. The count decomposition with those capacities.
//! 3. Each well-determined group's own square system (rows of the pairs whose flow goes into
//!    the group, columns the group's reduced unknowns, earlier groups known), and the
//!    under-determined block, must have full row rank; the over-determined block must have
//!    full column rank. A deficit names redundant equations (the pairs with weight in the left
//!    null space); one of them loses rows (chosen so the block keeps its rank) and steps 2-3
//!    run again. In a tall over-determined block that hides a freedom, all dependent rows go,
//!    so the count then shows the freedom as missing DOF.
//!
//! The Jacobian is block lower triangular (over-determined part, groups, under-determined part
//! in that order). When the over block has full column rank, every group block is nonsingular
//! and the under block has full row rank, its rank is exactly `rows − surplus` =
//! `unknowns − missing`: the per-block checks decide the whole mechanism.
//!
//! Where it lives: [`check`] here draws realizations until its deficits are confirmed;
//! `attempt` is one realization from rows to result, `rows` the pairs' constraint rows,
//! `set_aside` the equations dependent at the file's configuration (`solve_order` the order
//! they are chosen in), `unknowns` each body's reduced unknowns, `blocks` and `round` the
//! blocks of a decomposition, `float`, `screen`, `proof` and `exact` the rank decisions,
//! `lowering` a deficit's explanation, `confirm` its second draw and `cache` what is kept
//! across analyses.

mod attempt;
mod blocks;
mod cache;
mod confirm;
mod exact;
mod float;
mod lowering;
mod proof;
mod round;
mod rows;
mod screen;
mod set_aside;
mod solve_order;
mod unknowns;

use crate::geometry::GeometryUsed;
use crate::mechanism::{Geometry, Mechanism};
use crate::structure::count::{Decomposition, Equations};
use crate::structure::{Isolated, Redundancy, Unchecked};
use attempt::check_at;
pub use cache::Cache;
pub(crate) use float::NEAR_FACTOR;
use nalgebra::DMatrix;
use rows::PairRows;
use std::collections::{HashMap, HashSet};

/// What the caller of [`check`] knows or needs beyond the plain check (`mbsa transform`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Shortcut {
    /// The plain rank check.
    None,
    /// The whole system is known to have full row rank: no factorization is needed when the
    /// count has no over-determined part.
    Certified,
    /// Only whether the mechanism is determined matters: when the count does not find it
    /// determined, the check ends at once (`deficient`); when it does, the groups up to
    /// [`MAX_DENSE_UNKNOWNS`](float::MAX_DENSE_UNKNOWNS) are checked first, and a deficient one
    /// ends the check, unexplained (the larger groups would have been factorized for nothing).
    Determined,
}

/// What the rank check found, with the final decomposition.
pub(crate) struct RankResult {
    /// [`Shortcut::Determined`] stopped at a deficient group: the mechanism is not determined
    /// (the rest of the result is not meaningful).
    pub deficient: bool,
    /// Work units of the blocks' rank decisions this check made (a dense factorization of
    /// `n` unknowns `n^3`, an exact sparse one its factor's entries, the sparse screen
    /// `64 (rows + columns)`); blocks taken from the cache or certified cost nothing.
    pub work: u64,
    pub decomposition: Decomposition,
    /// Constraint equations set aside at the file's configuration, per joint.
    pub set_aside: Vec<u32>,
    pub isolated: Vec<Isolated>,
    pub redundant: Vec<Redundancy>,
    pub unchecked: Vec<Unchecked>,
    /// Decompositions of the whole mechanism the check ran (its rounds): the scale test's
    /// work measure.
    #[cfg_attr(not(test), allow(dead_code))]
    pub rounds: usize,
    /// At the file's geometry, when a rank decision came within
    /// [`NEAR_FACTOR`] of its threshold: the smallest value kept and the
    /// largest set aside, each divided by its threshold.
    pub near: Option<(f64, f64)>,
    /// Joints of a deficit that a second realization did not confirm (the draw was
    /// degenerate there), with the seed of a draw without the deficit: [`check`] draws them
    /// at it and starts over. Empty in a final result.
    suspects: Vec<(usize, u64)>,
    /// With suspects: what the next attempt can take over.
    kept_rows: Option<Kept>,
}

/// Each body's reduced unknowns (`None`: all `B`).
type Bases = Vec<Option<DMatrix<f64>>>;

/// What an attempt of [`check`] leaves to the next one: the rows, each pair's first row
/// count, and the bodies' reduced unknowns (recomputed only where a pair changed).
struct Kept {
    rows: PairRows,
    first: Vec<u8>,
    bases: Bases,
}

/// Realizations a deficit may be drawn at before it is reported without confirmation.
const MAX_DRAWS: u64 = 8;

/// Which joints a random realization draws at another seed than the analysis's, and the attempt
/// whose draws confirm a deficit ([`confirm_seeds`](confirm::confirm_seeds); `None`: deficits are
/// reported as found).
#[derive(Default)]
struct Redraw {
    joints: HashMap<usize, u64>,
    confirm: Option<u64>,
    /// The joints drawn again since the last attempt, and that attempt's rows with each pair's
    /// first row count: only their pairs and the pairs it lowered are built again.
    fresh: HashSet<usize>,
    rows: Option<Kept>,
}

/// Run the check; `eqs.cap` and `u` are lowered in place. With a `cache`, bodies' reduced
/// unknowns and sound blocks seen in an earlier analysis (same rows, same tolerance) are
/// taken from it instead of being factorized again. `geoms` is the joints' geometry when the
/// file's is used; a random realization (`used.seed`) is drawn joint by joint instead.
///
/// At a random realization a deficit (an isolated freedom, a deficient block) is reported only
/// when a second, independent realization of the joints involved has it too: a generic rank is
/// the largest over realizations, and one draw can be degenerate (the synthetic contact lines
/// of the count-only kinds). Only the deficits are drawn again (a body's own rows, a block's
/// exact rank over GF(2^61 − 1) at another seed), so a check without deficits costs nothing
/// more. When the second draw has the larger rank, the joints involved are drawn at it and the
/// check starts over (at most [`MAX_DRAWS`] draws); everything stays a function of `--seed`.
pub(crate) fn check(
    m: &Mechanism,
    geoms: &[Geometry],
    used: &GeometryUsed,
    eqs: &mut Equations,
    u: &mut [u32],
    cache: Option<&Cache>,
    shortcut: Shortcut,
) -> RankResult {
    if used.seed.is_none() {
        return check_at(
            m,
            geoms,
            used,
            eqs,
            u,
            cache,
            shortcut,
            &mut Redraw::default(),
        );
    }
    let (cap0, u0) = (eqs.cap.clone(), u.to_vec());
    let mut redraw = Redraw::default();
    let mut work = 0u64;
    let mut attempt = 1;
    loop {
        redraw.confirm = (attempt < MAX_DRAWS).then_some(attempt);
        let mut r = check_at(m, geoms, used, eqs, u, cache, shortcut, &mut redraw);
        work = work.saturating_add(r.work);
        if redraw.confirm.is_none() || r.suspects.is_empty() {
            r.work = work;
            return r;
        }
        redraw.fresh.clear();
        for &(j, s) in &r.suspects {
            redraw.joints.insert(j, s);
            redraw.fresh.insert(j);
        }
        redraw.rows = r.kept_rows.take();
        eqs.cap.copy_from_slice(&cap0);
        u.copy_from_slice(&u0);
        attempt += 1;
    }
}
