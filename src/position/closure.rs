//! Closure check (do the poses satisfy every joint?), assembly (project a configuration onto
//! the constraints) and writing a mechanism at a configuration.

use super::newton::{NewtonOptions, NewtonOutcome, System, Targets};
use super::pose::{Configuration, Pose};
use super::residual::{ModelError, PositionModel};
use super::solve::{SolveError, joints_of};
use crate::joint::JointType;
use crate::mechanism::{Mechanism, Space};
use serde::Serialize;

/// One joint's closure residual.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct JointResidual {
    /// Joint id.
    pub joint: String,
    /// Norm of its constraint residual in file units (a direction error of ε radians counts
    /// as ε times the model size).
    pub residual: f64,
}

/// Verdict of the closure check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ClosureStatus {
    /// Every residual within the tolerance.
    Closed,
    /// Some residual above the tolerance but below the gross limit: a warning.
    Open,
    /// Some residual above the gross limit ([`GROSS`] × model size): an error.
    Broken,
}

/// The closure section of a report.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Closure {
    /// Model size (diagonal of the box of the joint points).
    pub model_size: f64,
    /// Tolerance (file units).
    pub tolerance: f64,
    /// Gross limit (file units).
    pub gross_limit: f64,
    /// Largest joint residual.
    pub max_residual: f64,
    /// Verdict.
    pub status: ClosureStatus,
    /// Joints above the tolerance, in joint order.
    pub joints: Vec<JointResidual>,
}

/// How many open joints one-line messages and table reports list (the worst first).
pub const LISTED: usize = 5;

impl Closure {
    /// The joints above the tolerance, worst first (ties in joint order), at most `n`.
    pub fn worst(&self, n: usize) -> Vec<&JointResidual> {
        let mut v: Vec<&JointResidual> = self.joints.iter().collect();
        v.sort_by(|a, b| b.residual.total_cmp(&a.residual));
        v.truncate(n);
        v
    }

    fn list(&self) -> String {
        let mut s = self
            .worst(LISTED)
            .iter()
            .map(|j| format!("{} ({:.3e})", j.joint, j.residual))
            .collect::<Vec<_>>()
            .join(", ");
        if self.joints.len() > LISTED {
            s.push_str(&format!(" and {} more", self.joints.len() - LISTED));
        }
        s
    }

    /// A one-line message for a warning or error, or `None` when closed.
    pub fn message(&self) -> Option<String> {
        let list = self.list();
        match self.status {
            ClosureStatus::Closed => None,
            ClosureStatus::Open => Some(format!(
                "the configuration misses closure by {:.3e} (tolerance {:.1e}) at joint(s) {list}",
                self.max_residual, self.tolerance
            )),
            ClosureStatus::Broken => Some(format!(
                "the configuration is not assembled: joint(s) {list} open by up to {:.3e}, more than {:.1e} ({GROSS:.0e} x model size); `mbsa assemble` (or `solve --assemble`) projects it onto the constraints",
                self.max_residual, self.gross_limit
            )),
        }
    }
}

/// The default closure tolerance factor: `1e-9 ×` model size (exact numbers).
pub const DEFAULT_TOLERANCE: f64 = 1e-9;

/// Gross limit: a joint open by more than this times the model size is an error (the
/// configuration is not assembled); between the tolerance and this, a warning.
pub const GROSS: f64 = 1e-2;

/// The closure tolerance (file lengths) of a model of size `scale` whose numbers are known to
/// ±`precision` (`crate::motion::written_precision`): `1e-9 × scale`, or what two rounded
/// copies of a point (3 coordinates each, `2√3 δ`) or of a unit axis (an angle of `2√3 δ`
/// times the model size) can differ by: `4 δ max(1, scale)`, whichever is larger.
pub fn tolerance_for(scale: f64, precision: f64) -> f64 {
    (DEFAULT_TOLERANCE * scale).max(4.0 * precision * scale.max(1.0))
}

/// Check every joint at `config` (driven values not counted). `tolerance` in file units
/// (default [`tolerance_for`] the written precision of `m`).
pub fn check_closure(
    m: &Mechanism,
    config: &Configuration,
    tolerance: Option<f64>,
) -> Result<Closure, ModelError> {
    let model = PositionModel::new(&undriven(m))?;
    Ok(closure_of(m, &model, config, tolerance))
}

/// The closure of the file's own configuration, which only a joint with `second` geometry
/// (the joint as carried by its second body) can miss: every other joint is closed by
/// construction (residual 0), so only those are evaluated (cheap at any size, and joints
/// without a position model do not matter). `tolerance` as in [`check_closure`].
pub fn file_closure(m: &Mechanism, tolerance: Option<f64>) -> Result<Closure, ModelError> {
    let open: Vec<usize> = (0..m.joints.len())
        .filter(|&j| m.joints[j].geometry.second.is_some() && m.joints[j].bodies.len() == 2)
        .collect();
    if open.is_empty() {
        // Closed by construction: no copy of the mechanism, no configuration (large files).
        let s = super::residual::model_size(m);
        return Ok(Closure {
            model_size: super::pose::tidy(s),
            tolerance: super::pose::tidy(
                tolerance.unwrap_or_else(|| tolerance_for(s, crate::motion::written_precision(m))),
            ),
            gross_limit: super::pose::tidy(GROSS * s),
            max_residual: 0.0,
            status: ClosureStatus::Closed,
            joints: Vec::new(),
        });
    }
    let model = PositionModel::of_joints(&undriven(m), open)?;
    Ok(closure_of(
        m,
        &model,
        &Configuration::reference(m.bodies.len()),
        tolerance,
    ))
}

/// [`check_closure`] with a model already built (only its pairs are evaluated).
pub fn closure_of(
    m: &Mechanism,
    model: &PositionModel,
    config: &Configuration,
    tolerance: Option<f64>,
) -> Closure {
    let s = model.scale;
    let tol = tolerance.unwrap_or_else(|| tolerance_for(s, crate::motion::written_precision(m)));
    let gross = GROSS * s;
    let mut per_joint = vec![0.0f64; m.joints.len()];
    for (p, pair) in model.pairs.iter().enumerate() {
        let e = model.pair_equations(p, &config.poses[pair.a], &config.poses[pair.b], &[]);
        let n = e.residual.iter().map(|x| x * x).sum::<f64>().sqrt() * s;
        per_joint[pair.joint] = per_joint[pair.joint].max(n);
    }
    let max_residual = per_joint.iter().copied().fold(0.0, f64::max);
    let joints = per_joint
        .iter()
        .enumerate()
        .filter(|(_, r)| **r > tol)
        .map(|(j, r)| JointResidual {
            joint: m.joints[j].id.clone(),
            residual: super::pose::tidy(*r),
        })
        .collect();
    let status = if max_residual > gross {
        ClosureStatus::Broken
    } else if max_residual > tol {
        ClosureStatus::Open
    } else {
        ClosureStatus::Closed
    };
    Closure {
        model_size: super::pose::tidy(s),
        tolerance: super::pose::tidy(tol),
        gross_limit: super::pose::tidy(gross),
        max_residual: super::pose::tidy(max_residual),
        status,
        joints,
    }
}

/// A copy of `m` with no driven DOF.
pub fn undriven(m: &Mechanism) -> Mechanism {
    let mut u = m.clone();
    for j in &mut u.joints {
        j.driven = 0;
    }
    u
}

/// Project `start` onto the constraints (driven DOF free): Gauss–Newton with minimum-norm
/// steps, so the configuration changes least. Errors name the joints left open.
pub fn assemble(
    m: &Mechanism,
    start: &Configuration,
    opts: &NewtonOptions,
) -> Result<(Configuration, NewtonOutcome), SolveError> {
    let free = undriven(m);
    let model = PositionModel::new(&free)?;
    let sys = System {
        pairs: (0..model.pairs.len()).collect(),
        bodies: (0..m.bodies.len()).filter(|&b| b != m.frame).collect(),
    };
    let targets: Targets = vec![Vec::new(); model.pairs.len()];
    let mut config = start.clone();
    let mut out = sys.solve(&model, &targets, &mut config, opts);
    // A loop that is redundant at the configuration (a planar loop written in space with its
    // axes rounded) leaves a residual floor near the rounding of its numbers, which Newton's
    // tolerance may not reach; within the closure tolerance for exact numbers it is closed.
    if !out.converged && out.residual <= DEFAULT_TOLERANCE {
        out.converged = true;
    }
    if !out.converged {
        return Err(SolveError::Unreachable {
            group: "assembly".into(),
            bodies: "(all)".into(),
            joints: joints_of(m, &model, &sys.pairs, &out.pair_residuals, opts.tolerance),
            residual: out.residual * model.scale,
        });
    }
    Ok((config, out))
}

fn arr(v: nalgebra::Vector3<f64>, planar: bool) -> [f64; 3] {
    let t = super::pose::tidy;
    [t(v.x), t(v.y), if planar { 0.0 } else { t(v.z) }]
}

/// `m` with its joint geometry moved to `config` (which becomes the new reference): each
/// feature moves with the body it is attached to (the sphere centre of SP and SC and the
/// cylinder of PC, `axis2` of U and `origin2` of SPSP with the second body, the rest with
/// the first). A joint's `second` geometry is dropped: the second body's features are
/// carried by its pose followed by the `second` offset, which at a closed configuration puts
/// them where the first body's are.
pub fn moved_mechanism(m: &Mechanism, config: &Configuration) -> Mechanism {
    let mut out = m.clone();
    let planar = m.space == Space::Planar;
    // Pose translations are in model units.
    let scale = super::residual::model_size(m);
    let file_units = |p: Pose| Pose {
        rotation: p.rotation,
        translation: p.translation * scale,
    };
    for (ji, j) in out.joints.iter_mut().enumerate() {
        let a = file_units(config.poses[j.bodies[0]]);
        let mut b = j
            .bodies
            .get(1)
            .map(|&i| file_units(config.poses[i]))
            .unwrap_or_else(Pose::identity);
        if j.geometry.second.is_some() {
            let t = super::residual::second_offset_of(m, ji).unwrap_or_else(Pose::identity);
            b = Pose {
                rotation: b.rotation * t.rotation,
                translation: b.rotation * t.translation + b.translation,
            };
        }
        let on_second = matches!(j.kind, JointType::SP | JointType::SC | JointType::PC);
        let owner = if on_second { b } else { a };
        let g = &mut j.geometry;
        g.second = None;
        let v = |x: [f64; 3]| nalgebra::Vector3::new(x[0], x[1], x[2]);
        if let Some(o) = g.origin {
            g.origin = Some(arr(owner.point(&v(o)), planar));
        }
        if let Some(u) = g.axis {
            let p = if j.kind == JointType::PC { b } else { a };
            g.axis = Some(arr(p.dir(&v(u)), planar && j.kind != JointType::R));
        }
        if let Some(o) = g.origin2 {
            g.origin2 = Some(arr(b.point(&v(o)), planar));
        }
        if let Some(u) = g.axis2 {
            g.axis2 = Some(arr(b.dir(&v(u)), false));
        }
        if let Some(n) = g.normal {
            g.normal = Some(arr(a.dir(&v(n)), false));
        }
    }
    out
}
