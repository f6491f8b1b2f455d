//! Which joints take part in the motions [`super::finite_mobility`] finds: those moved only
//! by the instantaneous freedoms, the toggles (stationary here, moving nearby) and the locked
//! freedoms of each joint, here and at the nearby configurations.

use super::super::newton::System;
use super::super::residual::PositionModel;
use crate::mechanism::Mechanism;
use nalgebra::DMatrix;

/// The relative motion of a pair over the columns of a basis of motions.
pub(super) struct PairMotion<'a> {
    pub(super) model: &'a PositionModel,
    pub(super) sys: &'a System,
}

impl PairMotion<'_> {
    /// The relative twists of pair `p` (`b` rows) over the columns of `basis`.
    fn relative(&self, basis: &DMatrix<f64>, p: usize) -> DMatrix<f64> {
        let b = self.model.b();
        let pair = &self.model.pairs[p];
        let col = |body: usize| self.sys.bodies.iter().position(|&x| x == body);
        let (cb, ca) = (col(pair.b), col(pair.a));
        DMatrix::from_fn(b, basis.ncols(), |k, c| {
            let tb = cb.map_or(0.0, |i| basis[(i * b + k, c)]);
            let ta = ca.map_or(0.0, |i| basis[(i * b + k, c)]);
            tb - ta
        })
    }

    /// The largest relative motion of pair `p` over the columns of `basis`.
    fn of(&self, basis: &DMatrix<f64>, p: usize) -> f64 {
        self.relative(basis, p)
            .column_iter()
            .map(|c| c.norm())
            .fold(0.0, f64::max)
    }

    /// The least motion at the nearby configurations `step` away that counts as moving. At
    /// a sample `step` away a toggle's joint moves about `step` times its second-order rate:
    /// a piston at a crank's dead centre 1e-3 rad away slides at 1e-4 of the crank's rate
    /// (Modelica's EngineV6 has two). So the floor scales with the step and with the fastest
    /// joint; a joint locked for good stays at rounding (1e-10), far below it.
    fn floor(&self, near: &DMatrix<f64>, step: f64) -> f64 {
        let scale = (0..self.model.pairs.len())
            .map(|p| self.of(near, p))
            .fold(0.0, f64::max);
        1e-3 * step * scale
    }

    /// The rank of pair `p`'s relative twists over the columns of `basis`: singular values
    /// above `abs`.
    fn rank(&self, basis: &DMatrix<f64>, p: usize, abs: f64) -> usize {
        if basis.ncols() == 0 {
            return 0;
        }
        let rel = self.relative(basis, p);
        rel.singular_values().iter().filter(|s| **s > abs).count()
    }
}

/// The joints moved by the part of the first-order motions `n0` far from the nearby
/// tangent space `near` (the instantaneous-only freedoms).
pub(super) fn instantaneous_joints(
    m: &Mechanism,
    motion: &PairMotion<'_>,
    n0: &DMatrix<f64>,
    near: &DMatrix<f64>,
) -> Vec<String> {
    let model = motion.model;
    let mut singular_joints = Vec::new();
    let proj = n0 - near * (near.transpose() * n0);
    let svd = nalgebra::SVD::try_new(proj, true, false, f64::EPSILON, 10_000);
    if let Some((Some(u), values)) = svd.map(|d| (d.u, d.singular_values)) {
        let svd_values = values;
        let keep: Vec<usize> = (0..svd_values.len())
            .filter(|&i| svd_values[i] > 0.1)
            .collect();
        let extra = DMatrix::from_fn(u.nrows(), keep.len(), |r, c| u[(r, keep[c])]);
        for p in 0..model.pairs.len() {
            let id = &m.joints[model.pairs[p].joint].id;
            if motion.of(&extra, p) > 1e-6 && !singular_joints.contains(id) {
                singular_joints.push(id.clone());
            }
        }
    }
    singular_joints
}

/// The joints stationary in every first-order motion `n0` that move in the nearby tangent
/// space `near` (toggles).
pub(super) fn toggle_joints(
    m: &Mechanism,
    motion: &PairMotion<'_>,
    n0: &DMatrix<f64>,
    near: &DMatrix<f64>,
    step: f64,
) -> Vec<String> {
    let model = motion.model;
    let floor = motion.floor(near, step);
    let mut locked_at_toggle = Vec::new();
    for p in 0..model.pairs.len() {
        let id = &m.joints[model.pairs[p].joint].id;
        if motion.of(n0, p) < 1e-7 && motion.of(near, p) > floor && !locked_at_toggle.contains(id) {
            locked_at_toggle.push(id.clone());
        }
    }
    locked_at_toggle
}

/// The freedoms of one joint with no first-order motion here, and how many of them move at
/// the nearby configurations.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct LockedJoint {
    pub joint: String,
    pub here: usize,
    pub moving_nearby: usize,
}

/// Per joint, its freedoms unused by every first-order motion `n0` (its grade minus the rank
/// of its relative twists over `n0`, as the geometric report counts them), and how many of
/// them the nearby tangent space `near` uses. Joints with no locked freedom are left out.
pub(super) fn locked_freedoms(
    m: &Mechanism,
    motion: &PairMotion<'_>,
    n0: &DMatrix<f64>,
    near: &DMatrix<f64>,
    step: f64,
) -> Vec<LockedJoint> {
    let model = motion.model;
    let floor = motion.floor(near, step);
    let mut out: Vec<LockedJoint> = Vec::new();
    for p in 0..model.pairs.len() {
        let j = model.pairs[p].joint;
        let grade = usize::from(m.joints[j].kind.grade());
        let here = grade.saturating_sub(motion.rank(n0, p, 1e-7));
        if here == 0 {
            continue;
        }
        let moving = motion.rank(near, p, floor).min(grade);
        let moving_nearby = moving.saturating_sub(grade - here);
        let id = &m.joints[j].id;
        match out.iter_mut().find(|l| &l.joint == id) {
            Some(l) => {
                l.here += here;
                l.moving_nearby += moving_nearby;
            }
            None => out.push(LockedJoint {
                joint: id.clone(),
                here,
                moving_nearby,
            }),
        }
    }
    out
}

/// The note that accounts for every locked freedom: those that move nearby and those that
/// stay locked there. `None` when no freedom is locked.
pub(super) fn locked_note(locked: &[LockedJoint]) -> Option<String> {
    let total: usize = locked.iter().map(|l| l.here).sum();
    if total == 0 {
        return None;
    }
    let moving: Vec<String> = locked
        .iter()
        .filter(|l| l.moving_nearby > 0)
        .map(|l| format!("{} {}", l.joint, l.moving_nearby))
        .collect();
    let staying: Vec<String> = locked
        .iter()
        .filter(|l| l.here > l.moving_nearby)
        .map(|l| format!("{} {}", l.joint, l.here - l.moving_nearby))
        .collect();
    let n_moving: usize = locked.iter().map(|l| l.moving_nearby).sum();
    let mut parts = Vec::new();
    if n_moving > 0 {
        parts.push(format!(
            "{n_moving} move at the nearby configurations ({})",
            crate::words::capped(&moving)
        ));
    }
    if total > n_moving {
        parts.push(format!(
            "{} stay locked there ({})",
            total - n_moving,
            crate::words::capped(&staying)
        ));
    }
    Some(format!(
        "locked DOF: {total} joint freedom(s) have no first-order motion here; {}",
        parts.join(", ")
    ))
}
