//! Repair: the fewest joint changes, from the catalogue and at the same geometry, that make a
//! model well posed for simulation (no redundant constraint, no isolated freedom) while its
//! motion stays the same.
//!
//! # Method
//! 1. The geometric analysis at the file's configuration (inputs released) gives the redundant
//!    constraints `N = rows − rank` and the isolated freedoms; the finite-mobility test the
//!    local dimension of the motion.
//! 2. Redundancy: the self-stresses (left null space of the constraint Jacobian, dense,
//!    [`stress`]) say which rows are implied by the others. A joint is *relaxed* (replaced by
//!    a catalogue kind allowing more twists, [`changes`]) only when the stresses reach every
//!    row it removes: the rank is unchanged, so the null space, every first-order motion, is
//!    the same (the old rows are a superset of the new and both null spaces have the same
//!    dimension). Greedy, most rows removed first ([`search`]), from several first steps:
//!    the candidates.
//! 3. Isolated freedoms: a ball whose centre lies on the axis of an isolated turn (the spin
//!    of a rod between two balls, of a rigid part across two balls) becomes a universal joint
//!    whose axes are perpendicular to that turn: one row that only that turn violates.
//! 4. Each candidate is applied and the model analysed again with the library's analyses:
//!    accepted only when it has the redundancy the search predicts, the same proper mobility,
//!    the isolated freedoms minus those stiffened, and the same finite mobility minus them.
//!
//! Driven joints are never changed (a new kind would change what the input drives), nor
//! multiple joints, nor joints without a geometric model. Spatial mechanisms only: planar and
//! spherical files have no kind between a hinge and the free pair.

mod changes;
mod search;
mod stress;

use crate::budget::{Budget, BudgetExceeded};
use crate::geometry::GeometrySource;
use crate::joint::JointType;
use crate::mechanism::{Geometry, Mechanism, Space};
use crate::motion::{self, MotionError};
use crate::rigidity::both::{self, Methods, RigidError, RigidOptions};
use crate::rigidity::geometric::GeometricReport;
use nalgebra::Vector3;
use serde::Serialize;

/// Options of [`repair`].
#[derive(Clone, Copy, Debug)]
pub struct RepairOptions {
    /// Most candidates searched (each a different first change).
    pub candidates: usize,
    /// Limits of every step.
    pub budget: Budget,
}

impl Default for RepairOptions {
    fn default() -> Self {
        RepairOptions {
            candidates: 4,
            budget: Budget::default(),
        }
    }
}

/// What the analyses say of a model: the constraints and motion with the inputs released,
/// the isolated freedoms with them driven.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct State {
    /// Redundant constraints.
    pub redundant: usize,
    /// True mobility (first order).
    pub mobility: usize,
    /// Isolated freedoms with the inputs driven: motions of a body or rigid part that no
    /// input and no joint controls (a rod's spin between two balls).
    pub isolated: usize,
    /// Finite mobility at the file's configuration (`None`: the test could not run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub finite: Option<usize>,
}

/// One joint changed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Change {
    /// Joint id.
    pub joint: String,
    /// The bodies it joins.
    pub bodies: Vec<String>,
    /// Its kind before (code).
    pub from: String,
    /// Its kind after (code).
    pub to: String,
    /// Its geometry after (the point kept; the axes the new kind reads).
    pub geometry: Geometry,
    /// Constraint rows removed (negative: added).
    pub rows_removed: i64,
    /// Why the motion is unchanged.
    pub why: String,
}

/// A set of changes, checked.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Candidate {
    /// Joints changed.
    pub joints_changed: usize,
    /// Joint freedoms added (rows removed minus rows added).
    pub freedoms_added: i64,
    /// The changes, in the file's joint order.
    pub changes: Vec<Change>,
    /// The analyses of the changed model.
    pub after: State,
    /// Nothing left to repair (no redundant constraint, no isolated freedom).
    pub complete: bool,
}

/// The result of [`repair`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RepairReport {
    /// Mechanism name.
    pub name: String,
    /// The analyses of the model as written.
    pub before: State,
    /// The checked candidates, best first (fewest joints changed, fewest freedoms added,
    /// most loaded joints, file order).
    pub candidates: Vec<Candidate>,
    /// What could not be repaired, and why; what the search skipped.
    pub notes: Vec<String>,
}

/// Why [`repair`] gave no report.
#[derive(Debug, thiserror::Error)]
pub enum RepairError {
    /// Some joints lack the geometry a repair needs.
    #[error("a repair needs every joint's geometry; these joints lack it: {}", .0.join(", "))]
    NoGeometry(Vec<String>),
    /// The file's configuration is not closed.
    #[error("the configuration written is not closed (joints with `second`: {}); close it first with `mbsa assemble`", .0.join(", "))]
    Open(Vec<String>),
    /// An analysis failed.
    #[error(transparent)]
    Rigid(#[from] RigidError),
    /// A joint model could not be built.
    #[error(transparent)]
    Motion(#[from] MotionError),
    /// The search would exceed the budget.
    #[error(transparent)]
    Budget(#[from] BudgetExceeded),
}

/// The repairs of `m` at its file's configuration.
pub fn repair(m: &Mechanism, opts: &RepairOptions) -> Result<RepairReport, RepairError> {
    let lacking = motion::lacking(m);
    if !lacking.is_empty() {
        return Err(RepairError::NoGeometry(
            lacking.iter().map(|l| l.describe()).collect(),
        ));
    }
    let open: Vec<String> = m
        .joints
        .iter()
        .filter(|j| j.geometry.second.is_some())
        .map(|j| j.id.clone())
        .collect();
    if !open.is_empty() {
        return Err(RepairError::Open(open));
    }
    let (before, geo) = analyses(m, &opts.budget)?;
    let mut report = RepairReport {
        name: m.name.clone(),
        before: before.clone(),
        candidates: Vec::new(),
        notes: Vec::new(),
    };
    if before.redundant == 0 && before.isolated == 0 {
        report
            .notes
            .push("no redundant constraint and no isolated freedom: nothing to repair".into());
        return Ok(report);
    }
    if m.space != Space::Spatial {
        report.notes.push(format!(
            "a {} file has no joint kind between a hinge and the free pair: write it in 3D \
             (space = \"spatial\") to repair it",
            m.space.name()
        ));
        return Ok(report);
    }
    if let Some(f) = before.finite.filter(|&f| f < before.mobility) {
        report.notes.push(format!(
            "the file's configuration is singular (finite mobility {f}, first order {}): a \
             relaxation that keeps the first-order motions may turn the singular ones into \
             finite motions, which the check rejects; repair the model at a regular \
             configuration",
            before.mobility
        ));
    }
    let stiff = stiffenings(m, &geo, &mut report.notes);
    let sets = relaxation_sets(m, &before, opts, &mut report.notes)?;
    let mut seen: Vec<Vec<(usize, String)>> = Vec::new();
    for (steps, left) in sets {
        let mut changes: Vec<(usize, Change)> = steps;
        changes.extend(stiff.iter().cloned());
        changes.sort_by_key(|(j, _)| *j);
        if changes.is_empty() {
            continue;
        }
        // Different first steps may end in the same set: check each set once.
        let key: Vec<(usize, String)> = changes
            .iter()
            .map(|(j, c)| (*j, format!("{} {:?}", c.to, c.geometry)))
            .collect();
        if seen.contains(&key) {
            continue;
        }
        seen.push(key);
        match check(m, &before, changes, left, stiff.len(), &opts.budget)? {
            Ok(candidate) => report.candidates.push(candidate),
            Err(note) => report.notes.push(note),
        }
    }
    report.notes.dedup();
    report
        .candidates
        .sort_by_key(|c| (!c.complete, c.joints_changed, c.freedoms_added));
    Ok(report)
}

/// The changed model analysed again: the candidate when it has the redundancy the search
/// left (`left`) and every motion of `before` but the `stiffened` isolated ones; else the note
/// that says why it was rejected.
fn check(
    m: &Mechanism,
    before: &State,
    changes: Vec<(usize, Change)>,
    left: usize,
    stiffened: usize,
    budget: &Budget,
) -> Result<Result<Candidate, String>, RepairError> {
    let (after, _) = analyses(&apply_changes(m, &changes), budget)?;
    let expected_finite = before.finite.map(|f| f.saturating_sub(stiffened));
    let same_motion = after.mobility + stiffened == before.mobility
        && after.isolated + stiffened == before.isolated
        && (expected_finite.is_none() || after.finite == expected_finite);
    if after.redundant != left || !same_motion {
        let joints: Vec<&str> = changes.iter().map(|(_, c)| c.joint.as_str()).collect();
        return Ok(Err(format!(
            "a candidate changing {} was rejected when checked: {} redundant, true mobility \
             {}, finite mobility {}",
            joints.join(", "),
            after.redundant,
            after.mobility,
            after.finite.map_or("unknown".into(), |f| f.to_string()),
        )));
    }
    Ok(Ok(Candidate {
        joints_changed: changes.len(),
        freedoms_added: changes.iter().map(|(_, c)| c.rows_removed).sum(),
        complete: after.redundant == 0 && after.isolated == 0,
        changes: changes.into_iter().map(|(_, c)| c).collect(),
        after,
    }))
}

/// The model with the candidate's changes: each changed joint gets its new kind and geometry.
pub fn apply(m: &Mechanism, c: &Candidate) -> Mechanism {
    let mut out = m.clone();
    for ch in &c.changes {
        if let Some(j) = out.joints.iter_mut().find(|j| j.id == ch.joint) {
            j.kind = JointType::parse(&ch.to).unwrap_or(j.kind);
            j.geometry = ch.geometry.clone().into();
        }
    }
    out
}

fn apply_changes(m: &Mechanism, changes: &[(usize, Change)]) -> Mechanism {
    let mut out = m.clone();
    for (j, ch) in changes {
        let joint = &mut out.joints[*j];
        joint.kind = JointType::parse(&ch.to).unwrap_or(joint.kind);
        joint.geometry = ch.geometry.clone().into();
    }
    out
}

/// The geometric analysis and the finite mobility of `m` with its inputs released, and the
/// isolated motions with them driven (the report they come from is returned).
fn analyses(m: &Mechanism, budget: &Budget) -> Result<(State, GeometricReport), RepairError> {
    let opts = RigidOptions {
        methods: Methods::Geometric,
        with_inputs: false,
        finite: true,
        geometry: GeometrySource::File,
        precision: None,
        budget: *budget,
    };
    let (geo, finite) = match both::analyze(m, &opts) {
        Ok(r) => (r.geometric, r.finite.map(|f| f.finite)),
        // Without a finite test (a configuration the test cannot start from) the first-order
        // analyses still decide; the report says the finite mobility is unknown.
        Err(RigidError::Finite(_)) => {
            let r = both::analyze(
                m,
                &RigidOptions {
                    finite: false,
                    ..opts
                },
            )?;
            (r.geometric, None)
        }
        Err(e) => return Err(e.into()),
    };
    let geo = geo.expect("the geometric analysis was asked for");
    let driven = if m.joints.iter().any(|j| j.driven > 0) {
        let with_inputs = RigidOptions {
            with_inputs: true,
            finite: false,
            ..opts
        };
        both::analyze(m, &with_inputs)?
            .geometric
            .expect("the geometric analysis was asked for")
    } else {
        geo.clone()
    };
    let state = State {
        redundant: geo.redundant,
        mobility: geo.mobility,
        isolated: driven.isolated,
        finite,
    };
    Ok((state, driven))
}

/// Changes by joint index, and the redundancy they leave.
type ChangeSet = (Vec<(usize, Change)>, usize);

/// The relaxation sets of the search.
fn relaxation_sets(
    m: &Mechanism,
    before: &State,
    opts: &RepairOptions,
    notes: &mut Vec<String>,
) -> Result<Vec<ChangeSet>, RepairError> {
    if before.redundant == 0 {
        return Ok(vec![(Vec::new(), 0)]);
    }
    let mut released = m.clone();
    for j in &mut released.joints {
        j.driven = 0;
    }
    let models = motion::configure(&released)?;
    let scale = motion::scale_of(m);
    let mut meter = opts.budget.meter("the repair search");
    let st = stress::stresses(&released, &models, before.redundant, &mut meter)?;
    let starts = search::first_steps(m, &st, &scale, opts.candidates.max(1), &mut meter)?;
    let mut out = Vec::new();
    for first in starts {
        let Some((steps, left)) = search::greedy(m, st.clone(), first, &scale, &mut meter)? else {
            continue;
        };
        if left > 0 && !notes.iter().any(|n| n.starts_with("no catalogue")) {
            notes.push(format!(
                "no catalogue joint at the same geometry frees the last {left} redundant \
                 constraint{} without adding motion: every change that removes one of their \
                 rows would also remove a row no self-stress carries",
                if left == 1 { "" } else { "s" }
            ));
        }
        let changes = steps
            .into_iter()
            .map(|s| {
                let joint = &m.joints[s.joint];
                let change = Change {
                    joint: joint.id.clone(),
                    bodies: joint
                        .bodies
                        .iter()
                        .map(|&b| m.body_id(b).to_string())
                        .collect(),
                    from: joint.kind.code().into(),
                    to: s.proposal.kind.code().into(),
                    geometry: s.proposal.geometry.clone(),
                    rows_removed: s.rows as i64,
                    why: format!(
                        "removes {} row{} the other joints' rows already imply (a self-stress \
                         carries {}): the rank, so every motion, stays the same",
                        s.rows,
                        if s.rows == 1 { "" } else { "s" },
                        if s.rows == 1 { "it" } else { "them" }
                    ),
                };
                (s.joint, change)
            })
            .collect();
        out.push((changes, left));
    }
    Ok(out)
}

/// The balls to stiffen: for each isolated turn with one axis, the first ball (file order,
/// not driven) whose centre is on the axis.
fn stiffenings(
    m: &Mechanism,
    geo: &GeometricReport,
    notes: &mut Vec<String>,
) -> Vec<(usize, Change)> {
    let scale = motion::scale_of(m);
    let mut out: Vec<(usize, Change)> = Vec::new();
    for motion in &geo.isolated_motions {
        let axis = motion
            .axis
            .as_ref()
            .filter(|a| a.kind == "rotation" && motion.dof == 1);
        let found =
            axis.and_then(|a| {
                let q = Vector3::from(a.point.unwrap_or([0.0; 3]));
                let d = Vector3::from(a.direction);
                motion.joints.iter().find_map(|id| {
                    let (ji, j) = m.joints.iter().enumerate().find(|(_, j)| &j.id == id)?;
                    if j.kind != JointType::S || j.driven > 0 || j.bodies.len() != 2 {
                        return None;
                    }
                    if out.iter().any(|(k, _)| *k == ji) {
                        return None;
                    }
                    let p = Vector3::from(j.geometry.origin?);
                    let off = (p - q) - d * (p - q).dot(&d);
                    (off.norm() <= 1e-6 * scale.length).then_some(())?;
                    let proposal = changes::stiffening(&j.geometry, d, &scale)?;
                    Some((ji, Change {
                    joint: j.id.clone(),
                    bodies: j.bodies.iter().map(|&b| m.body_id(b).to_string()).collect(),
                    from: "S".into(),
                    to: proposal.kind.code().into(),
                    geometry: proposal.geometry,
                    rows_removed: -1,
                    why: "blocks only the isolated turn of its rod or rigid part about the line \
                          through its balls: every other motion stays the same"
                        .into(),
                }))
                })
            });
        match found {
            Some(c) => out.push(c),
            None => notes.push(format!(
                "the isolated motion of {} ({} DOF) is left as it is: a repair stiffens a turn \
                 about the line through two balls (a rod's spin), and this motion is not one",
                motion.bodies.join(", "),
                motion.dof
            )),
        }
    }
    out
}
