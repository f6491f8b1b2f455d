//! Closure check (do the poses satisfy every joint?), assembly (project a configuration onto
//! the constraints) and writing a mechanism at a configuration.

use super::newton::{NewtonOptions, NewtonOutcome, System, Targets};
use super::pose::{Configuration, Pose};
use super::residual::{ModelError, PositionModel};
use super::solve::SolveError;
use crate::joint::JointType;
use crate::mechanism::{Mechanism, Space};
use serde::Serialize;

/// One joint's closure residual.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JointResidual {
    /// Joint id.
    pub joint: String,
    /// Norm of its constraint residual in file units (a direction error of ε radians counts
    /// as ε times the model size).
    pub residual: f64,
}

/// Verdict of the closure check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ClosureStatus {
    /// Every residual within the tolerance.
    Closed,
    /// Some residual above the tolerance but below the gross limit: a warning.
    Open,
    /// Some residual above the gross limit (1e-3 × model size): an error.
    Broken,
}

/// The closure section of a report.
#[derive(Clone, Debug, PartialEq, Serialize)]
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

impl Closure {
    /// A one-line message for a warning or error, or `None` when closed.
    pub fn message(&self) -> Option<String> {
        let list = self
            .joints
            .iter()
            .map(|j| format!("{} ({:.3e})", j.joint, j.residual))
            .collect::<Vec<_>>()
            .join(", ");
        match self.status {
            ClosureStatus::Closed => None,
            ClosureStatus::Open => Some(format!(
                "the configuration misses closure by {:.3e} (tolerance {:.1e}) at joint(s) {list}",
                self.max_residual, self.tolerance
            )),
            ClosureStatus::Broken => Some(format!(
                "the configuration is not assembled: joint(s) {list} open by up to {:.3e}, more than {:.1e} (1e-3 x model size); `--assemble` projects it onto the constraints",
                self.max_residual, self.gross_limit
            )),
        }
    }
}

/// Default closure tolerance: `1e-9 ×` model size.
pub const DEFAULT_TOLERANCE: f64 = 1e-9;

/// Check every joint at `config` (driven values not counted). `tolerance` in file units
/// (default `1e-9 ×` model size).
pub fn check_closure(
    m: &Mechanism,
    config: &Configuration,
    tolerance: Option<f64>,
) -> Result<Closure, ModelError> {
    let model = PositionModel::new(&undriven(m))?;
    Ok(closure_of(m, &model, config, tolerance))
}

/// [`check_closure`] with a model already built.
pub fn closure_of(
    m: &Mechanism,
    model: &PositionModel,
    config: &Configuration,
    tolerance: Option<f64>,
) -> Closure {
    let s = model.scale;
    let tol = tolerance.unwrap_or(DEFAULT_TOLERANCE * s);
    let gross = 1e-3 * s;
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
        model_size: s,
        tolerance: tol,
        gross_limit: gross,
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
    let out = sys.solve(&model, &targets, &mut config, opts);
    if !out.converged {
        let mut ids: Vec<&str> = Vec::new();
        for (i, &p) in sys.pairs.iter().enumerate() {
            let id = m.joints[model.pairs[p].joint].id.as_str();
            if out.pair_residuals[i] > opts.tolerance && !ids.contains(&id) {
                ids.push(id);
            }
        }
        return Err(SolveError::Unreachable {
            group: "assembly".into(),
            bodies: "(all)".into(),
            joints: ids.join(", "),
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
/// the first).
pub fn moved_mechanism(m: &Mechanism, config: &Configuration) -> Mechanism {
    let mut out = m.clone();
    let planar = m.space == Space::Planar;
    // Pose translations are in model units.
    let scale = super::residual::model_size(m);
    let file_units = |p: Pose| Pose {
        rotation: p.rotation,
        translation: p.translation * scale,
    };
    for j in &mut out.joints {
        let a = file_units(config.poses[j.bodies[0]]);
        let b = j
            .bodies
            .get(1)
            .map(|&i| file_units(config.poses[i]))
            .unwrap_or_else(Pose::identity);
        let on_second = matches!(j.kind, JointType::SP | JointType::SC | JointType::PC);
        let owner = if on_second { b } else { a };
        let g = &mut j.geometry;
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
