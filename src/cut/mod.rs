//! Deterministic loop cuts: a spanning tree of the joint graph rooted at the frame, and the
//! joints cut to open every independent loop, with each cut's closure rows and whether they
//! are independent. What a tree-based simulator needs (`mbsa export` writes it), by a rule
//! that does not depend on a click (docs/cut.md).
//!
//! # The rule
//! Every binary pair (a multiple joint of n bodies is n − 1 pairs hub→other) is an edge of
//! the joint graph. The tree is grown by Kruskal's algorithm, the pairs taken in this order:
//! 1. driven joints (an actuator acts on a tree joint), then the other joints, then the
//!    spherical ones; within a class the joint order (ids in natural order, as every report
//!    lists them). A pair that would close a loop is a cut: so a loop is cut at a spherical
//!    joint when it has one (a ball closure is a point constraint, which every simulator
//!    has), else at its last joint in that order.
//! 2. Independence: a cut's closure is independent when none of its rows is a combination of
//!    its other rows and the rows of the closures listed before it. A cut whose loop alone is
//!    independent but whose closure is not (its rows repeat rows of other loops' closures) is
//!    exchanged for another joint of its loop in the same class (in joint order), when that
//!    lowers the number of dependent closures. A loop overconstrained by itself (a planar loop
//!    written in space) stays dependent wherever it is cut: its redundant rows are the
//!    mechanism's, not the cut's.
//! 3. What is left is decided by the order of step 1: the result is the same for the same
//!    file, byte for byte.
//!
//! The rows are those of the joint models at the file's geometry, or at a seeded random
//! realization of the joint types when joints lack theirs ([`crate::geometry`]), with the
//! driven inputs released (as `mbsa rigid` counts them). The redundant rows of all closures
//! add up to the mechanism's redundant constraints, and the tree coordinates less the
//! closures' rank are its true mobility.

mod choose;
mod rank;
mod tree;

pub use rank::Ranks;
pub use tree::{Link, Pair, Plan, Step, closed_loop, pairs_of};

use crate::budget::{Budget, BudgetExceeded};
use crate::geometry::{GeometrySource, GeometryUsed};
use crate::mechanism::{Mechanism, Space};
use crate::motion::MotionError;

/// Options of [`analyze_within`].
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct CutOptions {
    /// Where the joint geometry comes from.
    pub geometry: GeometrySource,
    /// File geometry: how precisely its numbers are known (default: from the digits written).
    pub precision: Option<f64>,
}

/// Why [`analyze_within`] gave no report.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CutError {
    /// The joint geometry cannot be modelled.
    #[error(transparent)]
    Motion(#[from] MotionError),
    /// The analysis would exceed the budget.
    #[error(transparent)]
    Budget(#[from] BudgetExceeded),
}

/// A tree joint: which body it joins to which parent.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TreeJoint {
    /// The joint's id.
    pub joint: String,
    /// Its kind (code).
    pub kind: &'static str,
    /// The parent body.
    pub parent: String,
    /// The child body.
    pub child: String,
    /// The freedoms it gives the child (its grade).
    pub dof: usize,
}

/// A cut joint and its closure.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Cut {
    /// The joint's id.
    pub joint: String,
    /// Its kind (code).
    pub kind: &'static str,
    /// The pair's bodies (the joint's first body, the other).
    pub bodies: [String; 2],
    /// Which step of the rule chose it: `spherical`, `independent` or `order`.
    pub why: &'static str,
    /// The loop's bodies, from the first body through the tree to the other.
    pub loop_bodies: Vec<String>,
    /// The loop's joints: the tree joints along it, then this one.
    pub loop_joints: Vec<String>,
    /// The closure's rows (the constraint rows of the joint).
    pub rows: usize,
    /// The rank they add to the closures before it.
    pub rank: usize,
    /// Rows implied by the closures before it and its other rows.
    pub redundant: usize,
    /// Whether no row is redundant.
    pub independent: bool,
}

/// The report of `mbsa cut`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CutReport {
    /// The mechanism's name.
    pub name: String,
    /// Its motion space.
    pub space: Space,
    /// DOF of a free body.
    pub b: u32,
    /// The frame (the tree's root).
    pub frame: String,
    /// Bodies, the frame included.
    pub bodies: usize,
    /// Joints.
    pub joints: usize,
    /// Binary pairs.
    pub pairs: usize,
    /// Independent loops (= cuts).
    pub loops: usize,
    /// Tree coordinates: the tree joints' freedoms, and B for each part not joined to the frame.
    pub coordinates: usize,
    /// Closure rows of all cuts.
    pub rows: usize,
    /// Their rank.
    pub rank: usize,
    /// Rows implied by others: the mechanism's redundant constraints.
    pub redundant: usize,
    /// Coordinates less rank: the true mobility (frame fixed, inputs released).
    pub mobility: usize,
    /// Cuts whose closure is independent.
    pub independent: usize,
    /// The geometry the rows were taken at.
    pub geometry_used: GeometryUsed,
    /// The tree joints, each body after its parent (depth first from the frame).
    pub tree: Vec<TreeJoint>,
    /// The first body of each part not joined to the frame (free in a simulator).
    pub floating: Vec<String>,
    /// The cuts, in joint order.
    pub cuts: Vec<Cut>,
    /// What stopped the exchange step early, if anything did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// The tree and cuts of a mechanism, with the report.
#[derive(Clone, Debug)]
pub struct Cuts {
    /// The tree and the cut pairs (indices into the mechanism).
    pub plan: Plan,
    /// Per cut (in `plan.cuts` order): its ranks.
    pub ranks: Vec<Ranks>,
    /// The report.
    pub report: CutReport,
}

/// The cuts of `m` (see the module documentation), without a budget.
pub fn analyze(m: &Mechanism, opts: &CutOptions) -> Result<CutReport, CutError> {
    analyze_within(m, opts, &Budget::UNLIMITED)
}

/// The cuts of `m` within `budget`.
pub fn analyze_within(
    m: &Mechanism,
    opts: &CutOptions,
    budget: &Budget,
) -> Result<CutReport, CutError> {
    cuts_within(m, opts, budget).map(|c| c.report)
}

/// The tree, the cuts and the report of `m` within `budget`.
pub fn cuts_within(m: &Mechanism, opts: &CutOptions, budget: &Budget) -> Result<Cuts, CutError> {
    let mut free = m.clone();
    for j in &mut free.joints {
        j.driven = 0;
    }
    // The whole Jacobian first (sparse, fast at any size): without a redundant constraint,
    // every closure is independent and no closure rank is taken.
    let gopts = crate::rigidity::geometric::GeometricOptions {
        geometry: opts.geometry,
        precision: opts.precision,
        check_finite: false,
    };
    let whole =
        crate::rigidity::geometric::analyze_within(&free, &gopts, budget).map_err(|e| match e {
            crate::rigidity::geometric::GeometricError::Motion(e) => CutError::Motion(e),
            crate::rigidity::geometric::GeometricError::Budget(e) => CutError::Budget(e),
        })?;
    let real = crate::geometry::realization(&free, opts.geometry, opts.precision)?;
    let threshold = rank::Threshold {
        file: crate::geometry::file_threshold(&free, &real.used),
    };
    let mut meter = budget.meter("the loop cuts");
    let ctx = choose::Ctx {
        m,
        models: &real.models,
        threshold,
        budget,
        independent: whole.redundant == 0,
    };
    let chosen = choose::choose(&ctx, &mut meter)?;
    let report = report(m, &real, &chosen);
    Ok(Cuts {
        plan: chosen.eval.plan,
        ranks: chosen.eval.ranks,
        report,
    })
}

/// The report of the chosen cuts.
fn report(m: &Mechanism, real: &crate::geometry::Realization, c: &choose::Chosen) -> CutReport {
    let e = &c.eval;
    let name = |b: usize| m.body_id(b).to_string();
    let tree: Vec<TreeJoint> = e
        .plan
        .order
        .iter()
        .filter_map(|&b| e.plan.links[b].map(|l| (b, l)))
        .map(|(b, l)| {
            let j = &m.joints[e.plan.pairs[l.pair].joint];
            TreeJoint {
                joint: j.id.clone(),
                kind: j.kind.code(),
                parent: name(l.parent),
                child: name(b),
                dof: real.models[e.plan.pairs[l.pair].joint].twists.ncols(),
            }
        })
        .collect();
    let cuts: Vec<Cut> = e
        .plan
        .cuts
        .iter()
        .enumerate()
        .map(|(k, &p)| {
            let pair = e.plan.pairs[p];
            let j = &m.joints[pair.joint];
            let r = e.ranks[k];
            let mut loop_joints: Vec<String> = e.loops[k]
                .iter()
                .map(|s| m.joints[e.plan.pairs[s.pair].joint].id.clone())
                .collect();
            loop_joints.push(j.id.clone());
            Cut {
                joint: j.id.clone(),
                kind: j.kind.code(),
                bodies: [name(pair.hub), name(pair.other)],
                why: c.why(m, p),
                loop_bodies: e.loop_bodies[k].iter().map(|&b| name(b)).collect(),
                loop_joints,
                rows: r.rows,
                rank: r.rank,
                redundant: r.redundant(),
                independent: r.redundant() == 0,
            }
        })
        .collect();
    let coordinates = e.coordinates(m, &real.models);
    let rows = cuts.iter().map(|c| c.rows).sum();
    let rank: usize = cuts.iter().map(|c| c.rank).sum();
    CutReport {
        name: m.name.clone(),
        space: m.space,
        b: m.b(),
        frame: name(m.frame),
        bodies: m.bodies.len(),
        joints: m.joints.len(),
        pairs: e.plan.pairs.len(),
        loops: cuts.len(),
        coordinates,
        rows,
        rank,
        redundant: rows - rank,
        mobility: coordinates.saturating_sub(rank),
        independent: cuts.iter().filter(|c| c.independent).count(),
        geometry_used: real.used.clone(),
        tree,
        floating: e.plan.roots.iter().skip(1).map(|&b| name(b)).collect(),
        cuts,
        note: c.note.clone(),
    }
}

#[cfg(test)]
mod tests;
