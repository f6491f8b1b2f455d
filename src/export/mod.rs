//! Writing a mechanism for a simulator: MJCF (MuJoCo) and SDFormat (Gazebo).
//!
//! The tree and the cuts are those of [`crate::cut`]. Each joint becomes the elementary
//! joints of the target composed in its driven-DOF order ([`elements`]); a kind no target
//! joint composes is refused with its joint named. Every body frame is the world frame at the
//! file's configuration (a mechanism file gives joints in one world frame, bodies have no
//! frame of their own), so the joint positions and axes written are the file's numbers, digit
//! for digit, and the reference pose is every joint at 0.
//!
//! - MJCF: the tree as nested bodies; a spherical cut as `<equality><connect>`; any other
//!   cut of kind K between bodies A and B as a light body V, child of A, with the joints of K,
//!   and `<equality><weld body1="V" body2="B">`: V's freedoms and the weld's six rows leave
//!   exactly K's constraint between A and B (the mbsa importer merges welded bodies, so the
//!   model read back has K between A and B again). Driven inputs are actuators, the
//!   configuration a keyframe.
//! - SDFormat: every joint directly (SDFormat allows a joint graph with loops), a kind that
//!   is not one SDFormat joint as a chain through light links. SDFormat has no actuator
//!   element: the driven joints are listed in a comment.
//!
//! A planar or spherical mechanism is written in space (planar in z = 0, spherical about the
//! origin); each cut's closure also frees the motions out of its space, which the tree
//! already blocks, so that no closure row is redundant for being written in space
//! ([`elements::out_of_space`]).

mod elements;
mod mjcf;
mod sdf;
mod xml;

pub use elements::{Elem, elements, out_of_space};

use crate::budget::{Budget, BudgetExceeded};
use crate::cut::{CutOptions, CutReport, Plan};
use crate::geometry::GeometrySource;
use crate::joint::JointType;
use crate::mechanism::{Geometry, Mechanism};
use crate::motion::{Lacking, MotionError};

/// A simulator format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// MuJoCo MJCF.
    Mjcf,
    /// SDFormat 1.7.
    Sdf,
}

impl Target {
    /// Display name.
    pub fn name(self) -> &'static str {
        match self {
            Target::Mjcf => "MJCF",
            Target::Sdf => "SDFormat",
        }
    }
}

/// Options of [`export_within`].
#[derive(Clone, Debug, PartialEq)]
pub struct ExportOptions {
    /// The format.
    pub target: Target,
    /// The geometry written: the file's (default) or a random realization of the joint types.
    pub geometry: GeometrySource,
    /// File geometry: how precisely its numbers are known (for the cuts' rank decisions).
    pub precision: Option<f64>,
    /// The source's name, for the comments of the file written.
    pub source: String,
}

/// Why [`export_within`] wrote nothing.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExportError {
    /// Joints of kinds the target has no joint for.
    #[error("{target} has no joint for {}", describe_kinds(.joints))]
    Unsupported {
        /// The target's name.
        target: &'static str,
        /// (joint id, kind code).
        joints: Vec<(String, &'static str)>,
    },
    /// Joints without the geometry an export writes.
    #[error("{} joint(s) lack the geometry an export writes: {}", .0.len(), describe_lacking(.0))]
    Lacking(Vec<Lacking>),
    /// The joint geometry cannot be modelled.
    #[error(transparent)]
    Motion(#[from] MotionError),
    /// The work would exceed the budget.
    #[error(transparent)]
    Budget(#[from] BudgetExceeded),
}

impl ExportError {
    /// What to do about it.
    pub fn help(&self) -> Option<String> {
        match self {
            ExportError::Unsupported { .. } => Some(
                "gears, cams, rolling and point contacts have no simulator joint (and MJCF no \
                 screw): replace them by the lower pairs they stand for, or export the rest"
                    .into(),
            ),
            ExportError::Lacking(_) => Some(
                "write their origin/axis fields (docs/format.md), or export a random \
                 realization of the joint types with `--geometry random [--seed N]`"
                    .into(),
            ),
            _ => None,
        }
    }
}

fn describe_kinds(joints: &[(String, &'static str)]) -> String {
    let listed: Vec<String> = joints
        .iter()
        .take(5)
        .map(|(j, k)| format!("`{j}` ({k})"))
        .collect();
    let more = joints.len().saturating_sub(5);
    let tail = if more > 0 {
        format!(" and {more} more")
    } else {
        String::new()
    };
    format!("joint(s) {}{tail}", listed.join(", "))
}

fn describe_lacking(l: &[Lacking]) -> String {
    let mut s: Vec<String> = l.iter().take(5).map(Lacking::describe).collect();
    if l.len() > 5 {
        s.push(format!("{} more", l.len() - 5));
    }
    s.join(", ")
}

/// An export.
#[derive(Clone, Debug)]
pub struct Export {
    /// The file's text.
    pub text: String,
    /// What a user should know (also written as comments in the file).
    pub warnings: Vec<String>,
    /// The tree and cuts written.
    pub cuts: CutReport,
}

/// One binary pair as written: its elementary joints (driven-DOF order), their names, the
/// driven DOF of the pair, and whether it is a cut.
#[derive(Clone, Debug)]
pub(crate) struct PairOut {
    /// The pair's name: the joint's id (with the other body for a multiple joint).
    pub(crate) label: String,
    pub(crate) elems: Vec<Elem>,
    pub(crate) names: Vec<String>,
    pub(crate) driven: u32,
    pub(crate) cut: bool,
    /// The kind written, for comments.
    pub(crate) kind: JointType,
}

/// What the writers share.
pub(crate) struct Model<'a> {
    pub(crate) m: &'a Mechanism,
    pub(crate) plan: &'a Plan,
    pub(crate) pairs: Vec<PairOut>,
    pub(crate) cuts: &'a CutReport,
    pub(crate) geoms: Vec<Geometry>,
    pub(crate) body_names: Vec<String>,
    /// Names given to bodies so far (the mechanism's, then light bodies).
    pub(crate) bodies: xml::Names,
    pub(crate) source: &'a str,
    pub(crate) warnings: &'a [String],
    /// The mechanism's `precision` key, written where the target has room for it (no
    /// number's digits carry it): file geometry only.
    pub(crate) precision: Option<f64>,
}

/// Write `m` for `opts.target`, within `budget`.
pub fn export_within(
    m: &Mechanism,
    opts: &ExportOptions,
    budget: &Budget,
) -> Result<Export, ExportError> {
    unsupported(m, opts.target)?;
    if let GeometrySource::File = opts.geometry {
        let lack = crate::motion::lacking(m);
        if !lack.is_empty() {
            return Err(ExportError::Lacking(lack));
        }
    }
    let (random, used) = crate::geometry::geometries(m, opts.geometry, opts.precision)?;
    // The file's own numbers (`geometries` gives them made dimensionless), or the random ones.
    let geoms: Vec<Geometry> = match used.seed {
        Some(_) => random,
        None => m.joints.iter().map(|j| j.geometry.to_geometry()).collect(),
    };
    let copts = CutOptions {
        geometry: opts.geometry,
        precision: opts.precision,
    };
    let cuts = crate::cut::cuts_within(m, &copts, budget).map_err(|e| match e {
        crate::cut::CutError::Motion(e) => ExportError::Motion(e),
        crate::cut::CutError::Budget(e) => ExportError::Budget(e),
    })?;
    let mut warnings = Vec::new();
    if let Some(msg) = used.closure.as_ref().and_then(|c| c.message()) {
        warnings.push(format!(
            "{msg}; the export uses each joint's first-body geometry (`mbsa assemble` closes it)"
        ));
    }
    if cuts.report.redundant > 0 {
        warnings.push(redundant_warning(&cuts.report, opts.target));
    }
    let bytes = (m.joints.len() as u64 + m.bodies.len() as u64).saturating_mul(1024);
    budget.check_memory(bytes, || "the exported file".into())?;
    let mut model = build(m, &cuts.plan, &cuts.report, geoms, &opts.source, &warnings);
    model.precision = m.precision.filter(|p| *p > 0.0 && used.seed.is_none());
    let text = match opts.target {
        Target::Mjcf => mjcf::write(&mut model),
        Target::Sdf => sdf::write(&mut model),
    };
    Ok(Export {
        text,
        warnings,
        cuts: cuts.report,
    })
}

/// The joints whose kind `target` cannot write, refused together.
fn unsupported(m: &Mechanism, target: Target) -> Result<(), ExportError> {
    let probe = Geometry {
        origin: Some([0.0; 3]),
        origin2: Some([1.0, 0.0, 0.0]),
        axis: Some([0.0, 0.0, 1.0]),
        axis2: Some([1.0, 0.0, 0.0]),
        normal: Some([0.0, 0.0, 1.0]),
        pitch: Some(0.0),
        second: None,
    };
    let joints: Vec<(String, &'static str)> = m
        .joints
        .iter()
        .filter(|j| {
            (target == Target::Mjcf && j.kind == JointType::H)
                || elements(j.kind, m.space, &probe).is_none()
        })
        .map(|j| (j.id.clone(), j.kind.code()))
        .collect();
    if joints.is_empty() {
        Ok(())
    } else {
        Err(ExportError::Unsupported {
            target: target.name(),
            joints,
        })
    }
}

/// The warning of an export that carries redundant closure rows.
fn redundant_warning(r: &CutReport, target: Target) -> String {
    let carriers: Vec<String> = r
        .cuts
        .iter()
        .filter(|c| c.redundant > 0)
        .take(5)
        .map(|c| format!("`{}` ({})", c.joint, c.redundant))
        .collect();
    format!(
        "the {} export carries {} redundant constraint row(s), in the closure(s) of {}: the \
         mechanism is overconstrained at this configuration (`mbsa rigid` counts the same), \
         and no choice of cuts removes them; a simulator sees a singular constraint Jacobian \
         until a joint of those loops is relaxed (`mbsa repair` says which, and into what)",
        target.name(),
        r.redundant,
        carriers.join(", ")
    )
}

/// The pairs as written: elements, names, driven shares.
fn build<'a>(
    m: &'a Mechanism,
    plan: &'a Plan,
    cuts: &'a CutReport,
    geoms: Vec<Geometry>,
    source: &'a str,
    warnings: &'a [String],
) -> Model<'a> {
    // One namespace for bodies and joints: SDFormat 1.7 wants them apart from each other.
    let mut bodies = xml::Names::default();
    let body_names: Vec<String> = (0..m.bodies.len())
        .map(|b| bodies.take(&m.body_id(b).to_string()))
        .collect();
    let is_cut = {
        let mut v = vec![false; plan.pairs.len()];
        for &c in &plan.cuts {
            v[c] = true;
        }
        v
    };
    let mut left: Vec<u32> = m.joints.iter().map(|j| j.driven).collect();
    let mut pairs = Vec::with_capacity(plan.pairs.len());
    for (p, pair) in plan.pairs.iter().enumerate() {
        let j = &m.joints[pair.joint];
        let g = &geoms[pair.joint];
        let mut elems = elements(j.kind, m.space, g).unwrap_or_default();
        if is_cut[p] {
            elems.extend(out_of_space(m.space, g));
        }
        let label = if j.bodies.len() > 2 {
            format!("{}[{}]", j.id, m.body_id(pair.other))
        } else {
            j.id.clone()
        };
        let elem_names = elem_names(&mut bodies, &label, elems.len());
        let driven = left[pair.joint].min(j.grade());
        left[pair.joint] -= driven;
        pairs.push(PairOut {
            label,
            elems,
            names: elem_names,
            driven,
            cut: is_cut[p],
            kind: j.kind,
        });
    }
    Model {
        m,
        plan,
        pairs,
        cuts,
        geoms,
        body_names,
        bodies,
        source,
        warnings,
        precision: None,
    }
}

/// The names of a pair's elementary joints: its label alone, or `label:1`, `label:2`, ...
fn elem_names(names: &mut xml::Names, label: &str, n: usize) -> Vec<String> {
    if n == 1 {
        vec![names.take(label)]
    } else {
        (1..=n)
            .map(|k| names.take(&format!("{label}:{k}")))
            .collect()
    }
}

#[cfg(test)]
mod tests;
