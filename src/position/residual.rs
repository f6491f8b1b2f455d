//! Joint residuals at a configuration and their Jacobians with respect to the body twists.
//!
//! Each joint (each binary pair first → other of a multiple joint) becomes a few scalar
//! equations `e(pose_A, pose_B) = 0` (A = first listed body, B = the other) built from the
//! joint's features: points and directions attached to A or B at the reference configuration
//! (`docs/algorithms.md`, "Position level", lists them). Their number is `B − k`, and at the
//! reference configuration their Jacobian, a row per equation acting on `t_B − t_A`, spans the
//! same space as [`crate::motion::joint_model`]'s rows. The joint values (what a driven DOF
//! fixes) are listed in the driven-DOF order of the file format.
//!
//! Lengths are divided by the model size ([`PositionModel::scale`]) so that every residual is
//! of order one: a direction error of ε radians weighs like a position error of ε times the
//! model size.

use super::pose::{Pose, embed_columns};
use super::track::{TS, TV};
use crate::joint::JointType;
use crate::mechanism::{Geometry, Mechanism, Space};
use crate::motion::kinds::{self, Feature};
use crate::motion::perpendicular_pair;
use nalgebra::{DMatrix, Rotation3, Vector3};
use std::f64::consts::PI;

pub use crate::motion::ModelError;

/// The features of one joint, lengths scaled: those [`kinds::features`] lists for its kind
/// (the ones its twists are functions of), and a P's origin.
#[derive(Clone, Debug)]
struct Features {
    o: Vector3<f64>,
    o2: Vector3<f64>,
    u: Vector3<f64>,
    w: Vector3<f64>,
    n: Vector3<f64>,
    h: f64,
}

/// One binary pair of a joint: its equations and joint values.
#[derive(Clone, Debug)]
pub struct Pair {
    /// Index of the joint in `Mechanism::joints`.
    pub joint: usize,
    /// Index of the pair within the joint (0 for a binary joint).
    pub index: usize,
    /// First body (index into `Mechanism::bodies`).
    pub a: usize,
    /// Other body.
    pub b: usize,
    /// Kind.
    pub kind: JointType,
    /// Driven DOF on this pair.
    pub driven: usize,
    f: Features,
    /// Where the second body carries the joint at the reference configuration, as a move of
    /// the first body's features (identity when the file's configuration is closed there;
    /// from the joint's `second` geometry otherwise).
    pub offset: Pose,
}

/// The position model of a mechanism: every pair's equations, lengths scaled by `scale`.
#[derive(Clone, Debug)]
pub struct PositionModel {
    /// Motion space.
    pub space: Space,
    /// Model size: lengths are divided by it (the diagonal of the box of the joint points, or
    /// 1 when that is zero).
    pub scale: f64,
    /// Pairs in joint order.
    pub pairs: Vec<Pair>,
    /// Number of bodies.
    pub bodies: usize,
    /// The frame.
    pub frame: usize,
}

fn v3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

/// Wrap an angle difference to (−π, π].
pub(crate) fn wrap(x: f64) -> f64 {
    let y = x - 2.0 * PI * (x / (2.0 * PI)).round();
    if y <= -PI { y + 2.0 * PI } else { y }
}

/// Model size of a mechanism: the diagonal of the box of every joint point (1 if zero).
pub fn model_size(m: &Mechanism) -> f64 {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    let mut any = false;
    for j in &m.joints {
        if let Some(o) = j.geometry.origin {
            let o = v3(o);
            if o.iter().all(|x| x.is_finite()) {
                lo = lo.inf(&o);
                hi = hi.sup(&o);
                any = true;
            }
        }
    }
    let d = if any { (hi - lo).norm() } else { 0.0 };
    if d > 1e-9 && d.is_finite() { d } else { 1.0 }
}

impl PositionModel {
    /// Build the model of `m`. Errors name the joint.
    pub fn new(m: &Mechanism) -> Result<PositionModel, ModelError> {
        Self::of_joints(m, 0..m.joints.len())
    }

    /// The model of some joints of `m` only (pairs keep their joint's index in `m.joints`;
    /// lengths scaled by the model size of all of `m`).
    pub fn of_joints(
        m: &Mechanism,
        joints: impl IntoIterator<Item = usize>,
    ) -> Result<PositionModel, ModelError> {
        Self::of_joints_scaled(m, joints, model_size(m))
    }

    /// [`PositionModel::of_joints`] with lengths divided by `scale` (a model size computed
    /// once, for many small models of one mechanism).
    pub fn of_joints_scaled(
        m: &Mechanism,
        joints: impl IntoIterator<Item = usize>,
        scale: f64,
    ) -> Result<PositionModel, ModelError> {
        let mut pairs = Vec::new();
        for ji in joints {
            let j = &m.joints[ji];
            let f = features(m.space, j.kind, &j.geometry, scale, &j.id)?;
            let offset = match &j.geometry.second {
                Some(s) if j.bodies.len() == 2 => {
                    second_offset(m.space, j.kind, &f, s, scale, &j.id)?
                }
                _ => Pose::identity(),
            };
            let k = j.grade() as usize;
            let mut left = j.driven as usize;
            for (p, &b) in j.bodies.iter().skip(1).enumerate() {
                let d = left.min(k);
                left -= d;
                if d > 0 && j.kind == JointType::SPSP {
                    return Err(ModelError::NotDrivable {
                        joint: j.id.clone(),
                        kind: j.kind.code(),
                    });
                }
                pairs.push(Pair {
                    joint: ji,
                    index: p,
                    a: j.bodies[0],
                    b,
                    kind: j.kind,
                    driven: d,
                    f: f.clone(),
                    offset,
                });
            }
        }
        Ok(PositionModel {
            space: m.space,
            scale,
            pairs,
            bodies: m.bodies.len(),
            frame: m.frame,
        })
    }
}

fn features(
    space: Space,
    kind: JointType,
    g: &Geometry,
    scale: f64,
    joint: &str,
) -> Result<Features, ModelError> {
    use JointType::*;
    let missing = |field| ModelError::MissingField {
        joint: joint.to_string(),
        kind: kind.code(),
        field,
    };
    let bad = |field| ModelError::BadVector {
        joint: joint.to_string(),
        field,
    };
    let no_model = || ModelError::NoModel {
        joint: joint.to_string(),
        kind: kind.code(),
        space: space.name(),
    };
    let point = |v: Option<[f64; 3]>, field: &'static str, need: bool| match v {
        Some(a) => {
            let p = v3(a);
            if p.iter().all(|x| x.is_finite()) {
                Ok(p / scale)
            } else {
                Err(bad(field))
            }
        }
        None if need => Err(missing(field)),
        None => Ok(Vector3::zeros()),
    };
    let dir = |v: Option<[f64; 3]>, field: &'static str, default: Option<Vector3<f64>>| match v {
        Some(a) => {
            let d = v3(a);
            let n = d.norm();
            if n.is_finite() && n > 1e-300 {
                Ok(d / n)
            } else {
                Err(bad(field))
            }
        }
        None => default.ok_or_else(|| missing(field)),
    };
    let mut f = Features {
        o: Vector3::zeros(),
        o2: Vector3::zeros(),
        u: Vector3::z(),
        w: Vector3::x(),
        n: Vector3::z(),
        h: 0.0,
    };
    let list = kinds::features(kind, space).ok_or_else(no_model)?;
    if kind == P {
        // The equations keep a slide on its line, which needs a point of it (the twist does
        // not): the world origin when none is given.
        f.o = point(g.origin, "origin", false)?;
    }
    for &feature in list {
        let optional = kinds::optional(kind, feature);
        match feature {
            Feature::Origin => f.o = point(g.origin, "origin", !optional)?,
            Feature::Origin2 => f.o2 = point(g.origin2, "origin2", true)?,
            Feature::Axis if space == Space::Planar => {
                let a = g.axis.ok_or_else(|| missing("axis"))?;
                f.u = dir(Some([a[0], a[1], 0.0]), "axis", None)?;
            }
            Feature::Axis => f.u = dir(g.axis, "axis", None)?,
            Feature::Axis2 => f.w = dir(g.axis2, "axis2", None)?,
            Feature::Normal => f.n = dir(g.normal, "normal", optional.then(Vector3::z))?,
            Feature::Pitch => {
                let h = g.pitch.ok_or_else(|| missing("pitch"))?;
                if !h.is_finite() {
                    return Err(bad("pitch"));
                }
                f.h = h / scale;
            }
        }
    }
    match kind {
        U if f.u.cross(&f.w).norm() < 1e-9 => return Err(bad("axis2")),
        PC | CR if f.u.cross(&f.n).norm() < 1e-9 => return Err(bad("normal")),
        SPSP if (f.o2 - f.o).norm() < 1e-12 => return Err(bad("origin2")),
        FP if space != Space::Spatial => f.u = Vector3::x(),
        _ => {}
    }
    if space == Space::Planar {
        f.o.z = 0.0;
    }
    Ok(f)
}

/// The move that takes the first body's features of a joint to the ones its second body
/// carries (`second`): the least rotation taking the first axis (`axis`; `axis2` of a U;
/// `normal` of PL, FP) to the second's, about the joint point, then the translation taking the
/// (rotated) point to the second's `origin`. Fields left out stay as the first body's.
fn second_offset(
    space: Space,
    kind: JointType,
    f: &Features,
    s: &crate::mechanism::Second,
    scale: f64,
    joint: &str,
) -> Result<Pose, ModelError> {
    let bad = |field: &'static str| ModelError::BadVector {
        joint: joint.to_string(),
        field,
    };
    let (first, second, field) = match kind {
        JointType::U => (f.w, s.axis2, "second.axis2"),
        JointType::PL | JointType::FP => (f.n, s.normal, "second.normal"),
        _ => (f.u, s.axis, "second.axis"),
    };
    let mut q = Rotation3::identity();
    if let Some(a) = second {
        let mut d = v3(a);
        if space == Space::Planar {
            d.z = 0.0;
        }
        let n = d.norm();
        if !(n.is_finite() && n > 1e-300) {
            return Err(bad(field));
        }
        let d = d / n;
        let from = if space == Space::Planar {
            Vector3::new(first.x, first.y, 0.0).normalize()
        } else {
            first
        };
        q = Rotation3::rotation_between(&from, &d).unwrap_or_else(|| {
            // Opposite: a half turn about an axis perpendicular to it (z in the plane).
            let axis = if space == Space::Planar {
                Vector3::z()
            } else {
                perpendicular_pair(&from).0
            };
            Rotation3::new(axis * PI)
        });
    }
    let o_b = match s.origin {
        Some(a) => {
            let mut p = v3(a) / scale;
            if !p.iter().all(|x| x.is_finite()) {
                return Err(bad("second.origin"));
            }
            if space == Space::Planar {
                p.z = 0.0;
            }
            p
        }
        None => f.o,
    };
    Ok(Pose {
        rotation: q.into_inner(),
        translation: o_b - q * f.o,
    })
}

/// The move that takes joint `j`'s features on the first body to the ones its second body
/// carries (its `second` geometry), translation in file lengths; the identity without
/// `second`, `None` when the joint's geometry has no position model.
pub fn second_offset_of(m: &Mechanism, j: usize) -> Option<Pose> {
    let joint = &m.joints[j];
    let Some(s) = &joint.geometry.second else {
        return Some(Pose::identity());
    };
    let scale = model_size(m);
    let f = features(m.space, joint.kind, &joint.geometry, scale, &joint.id).ok()?;
    let p = second_offset(m.space, joint.kind, &f, s, scale, &joint.id).ok()?;
    Some(Pose {
        rotation: p.rotation,
        translation: p.translation * scale,
    })
}

/// The angle of B about `u` relative to A (right-hand rule), from a perpendicular pair.
fn angle_about(pa: &Pose, pb: &Pose, u: &Vector3<f64>) -> TS {
    let (e1, e2) = perpendicular_pair(u);
    let (a1, a2) = (TV::dir(pa.dir(&e1), 0), TV::dir(pa.dir(&e2), 0));
    let b1 = TV::dir(pb.dir(&e1), 1);
    a2.dot(&b1).atan2(&a1.dot(&b1))
}

/// The two angles of a universal joint: about `u` (on A), then about `w` (on B).
fn u_angles(pa: &Pose, pb: &Pose, u: &Vector3<f64>, w: &Vector3<f64>) -> [TS; 2] {
    let f1 = (w - u * u.dot(w)).normalize();
    let f2 = u.cross(&f1);
    let wb = TV::dir(pb.dir(w), 1);
    let phi1 = TV::dir(pa.dir(&f2), 0)
        .dot(&wb)
        .atan2(&TV::dir(pa.dir(&f1), 0).dot(&wb));
    let g1 = (u - w * w.dot(u)).normalize();
    let g2 = w.cross(&g1);
    let ua = TV::dir(pa.dir(u), 0);
    let phi2 = ua
        .dot(&TV::dir(pb.dir(&g2), 1))
        .scale(-1.0)
        .atan2(&ua.dot(&TV::dir(pb.dir(&g1), 1)));
    [phi1, phi2]
}

/// Component along reference direction `e` (of A) of the relative rotation vector of B; its
/// derivative is taken at coincident orientations (exact there, approximate elsewhere).
fn rotation_component(pa: &Pose, pb: &Pose, e: &Vector3<f64>) -> TS {
    let rel = pa.rotation.transpose() * pb.rotation;
    let rv = super::pose::log_rotation(&rel);
    let mut s = TS::constant(rv.dot(e));
    let we = pa.dir(e);
    for k in 0..3 {
        s.d[k] = -we[k];
        s.d[6 + k] = we[k];
    }
    s
}

fn comp(t: &TV, k: usize) -> TS {
    TS {
        v: t.v[k],
        d: t.d.row(k).into_owned(),
    }
}

impl Pair {
    /// The joint point in each body's reference coordinates (first body, other body), in
    /// model units.
    pub fn anchors(&self) -> (Vector3<f64>, Vector3<f64>) {
        (self.f.o, self.offset.point(&self.f.o))
    }

    /// The pose that carries the joint's features on the second body: `pb` followed by
    /// [`Pair::offset`] (`pb` itself when the joint has no `second` geometry).
    pub fn carried(&self, pb: &Pose) -> Pose {
        if self.offset == Pose::identity() {
            return *pb;
        }
        Pose {
            rotation: pb.rotation * self.offset.rotation,
            translation: pb.rotation * self.offset.translation + pb.translation,
        }
    }

    fn pa(&self, pa: &Pose, x: &Vector3<f64>) -> TV {
        TV::point(pa.point(x), 0)
    }
    fn pb(&self, pb: &Pose, x: &Vector3<f64>) -> TV {
        TV::point(pb.point(x), 1)
    }

    /// The constraint equations (without driven values), spatial derivative columns.
    fn constraints(&self, space: Space, pa: &Pose, pb: &Pose) -> Vec<TS> {
        use JointType::*;
        let f = &self.f;
        let da = |u: &Vector3<f64>| TV::dir(pa.dir(u), 0);
        let db = |u: &Vector3<f64>| TV::dir(pb.dir(u), 1);
        let delta = self.pb(pb, &f.o).sub(&self.pa(pa, &f.o));
        let parallel = |u: &Vector3<f64>| {
            let (e1, e2) = perpendicular_pair(u);
            let ub = db(u);
            [da(&e1).dot(&ub), da(&e2).dot(&ub)]
        };
        let on_line = |u: &Vector3<f64>| {
            let (e1, e2) = perpendicular_pair(u);
            [da(&e1).dot(&delta), da(&e2).dot(&delta)]
        };
        let coincide = || (0..3).map(|k| comp(&delta, k)).collect::<Vec<_>>();
        match space {
            Space::Spatial => match self.kind {
                R => {
                    let mut e = coincide();
                    e.extend(parallel(&f.u));
                    e
                }
                P => {
                    let (e1, e2) = perpendicular_pair(&f.u);
                    let mut e = parallel(&f.u).to_vec();
                    e.push(da(&e2).dot(&db(&e1)));
                    e.extend(on_line(&f.u));
                    e
                }
                H => {
                    let mut e = parallel(&f.u).to_vec();
                    e.extend(on_line(&f.u));
                    let s = da(&f.u).dot(&delta);
                    let phi = angle_about(pa, pb, &f.u);
                    e.push(s.sub(&phi.scale(f.h)));
                    e
                }
                C => {
                    let mut e = parallel(&f.u).to_vec();
                    e.extend(on_line(&f.u));
                    e
                }
                ER => {
                    let (e1, e2) = perpendicular_pair(&f.u);
                    let mut e = coincide();
                    e.push(da(&e2).dot(&db(&e1)));
                    e
                }
                U => {
                    let mut e = coincide();
                    e.push(da(&f.u).dot(&db(&f.w)).sub(&TS::constant(f.u.dot(&f.w))));
                    e
                }
                S => coincide(),
                PL | FP => {
                    let mut e = parallel(&f.n).to_vec();
                    e.push(da(&f.n).dot(&delta));
                    e
                }
                SP => vec![da(&f.n).dot(&delta)],
                SPSP => {
                    let d = self.pb(pb, &f.o2).sub(&self.pa(pa, &f.o));
                    vec![d.norm().sub(&TS::constant((f.o2 - f.o).norm()))]
                }
                SC => on_line(&f.u).to_vec(),
                PC => vec![
                    da(&f.n).dot(&delta),
                    da(&f.n).dot(&db(&f.u)).sub(&TS::constant(f.n.dot(&f.u))),
                ],
                CR => {
                    let mut e = parallel(&f.u).to_vec();
                    e.push(da(&f.n).dot(&delta));
                    e
                }
                _ => Vec::new(),
            },
            Space::Planar => match self.kind {
                R => vec![comp(&delta, 0), comp(&delta, 1)],
                P => {
                    let m = Vector3::z().cross(&f.u);
                    vec![
                        da(&Vector3::y()).dot(&db(&Vector3::x())),
                        da(&m).dot(&delta),
                    ]
                }
                _ => Vec::new(),
            },
            Space::Spherical => match self.kind {
                R => parallel(&f.u).to_vec(),
                _ => Vec::new(),
            },
        }
    }

    /// The joint values in driven-DOF order, with whether each is an angle.
    fn values(&self, space: Space, pa: &Pose, pb: &Pose) -> Vec<(TS, bool)> {
        use JointType::*;
        let f = &self.f;
        let da = |u: &Vector3<f64>| TV::dir(pa.dir(u), 0);
        let delta = self.pb(pb, &f.o).sub(&self.pa(pa, &f.o));
        let slide = |u: &Vector3<f64>| (da(u).dot(&delta), false);
        let turn = |u: &Vector3<f64>| (angle_about(pa, pb, u), true);
        let rv = |e: &Vector3<f64>| (rotation_component(pa, pb, e), true);
        let xyz = [Vector3::x(), Vector3::y(), Vector3::z()];
        match (space, self.kind) {
            (Space::Planar, R) => vec![turn(&Vector3::z())],
            (Space::Planar, P) => vec![slide(&f.u)],
            (Space::Planar, FP) => vec![
                slide(&Vector3::x()),
                slide(&Vector3::y()),
                turn(&Vector3::z()),
            ],
            (Space::Spherical, FP) => xyz.iter().map(rv).collect(),
            (_, R) | (_, H) => vec![turn(&f.u)],
            (_, P) => vec![slide(&f.u)],
            (_, C) => vec![slide(&f.u), turn(&f.u)],
            (_, U) => u_angles(pa, pb, &f.u, &f.w)
                .into_iter()
                .map(|a| (a, true))
                .collect(),
            (_, ER) => {
                let (e1, e2) = perpendicular_pair(&f.u);
                vec![rv(&e1), rv(&e2)]
            }
            (_, S) => xyz.iter().map(rv).collect(),
            (_, PL) | (_, FP) => {
                let (e1, e2) = perpendicular_pair(&f.n);
                vec![slide(&e1), slide(&e2), turn(&f.n)]
            }
            (_, F) => {
                let d0 = TV::point(pb.point(&Vector3::zeros()), 1)
                    .sub(&TV::point(pa.point(&Vector3::zeros()), 0));
                let mut v: Vec<(TS, bool)> = xyz.iter().map(|e| (da(e).dot(&d0), false)).collect();
                v.extend(xyz.iter().map(rv));
                v
            }
            (_, SP) => {
                let (e1, e2) = perpendicular_pair(&f.n);
                let mut v = vec![slide(&e1), slide(&e2)];
                v.extend(xyz.iter().map(rv));
                v
            }
            (_, SC) => {
                let mut v = vec![slide(&f.u)];
                v.extend(xyz.iter().map(rv));
                v
            }
            (_, PC) => {
                let (e1, e2) = perpendicular_pair(&f.n);
                let mut v = vec![slide(&e1), slide(&e2)];
                v.extend(u_angles(pa, pb, &f.n, &f.u).into_iter().map(|a| (a, true)));
                v
            }
            (_, CR) => vec![slide(&f.u), slide(&f.n.cross(&f.u)), turn(&f.u)],
            _ => Vec::new(),
        }
    }
}

/// The residual and Jacobian of one pair: `e` (rows) and `J` (rows × 2B: the first body's
/// twist columns, then the other's).
#[derive(Clone, Debug)]
pub struct PairEquations {
    /// Residual values.
    pub residual: Vec<f64>,
    /// Jacobian, `residual.len() × 2B`.
    pub jacobian: DMatrix<f64>,
    /// How many of the rows (the last ones) are driven values.
    pub driven_rows: usize,
}

impl PositionModel {
    /// Twist size B.
    pub fn b(&self) -> usize {
        self.space.b() as usize
    }

    /// Equations of pair `p` at poses `pa` (first body), `pb` (other): the constraints, then
    /// `value − target` for the first `targets.len()` joint values (angles wrapped to
    /// (−π, π]); targets are in model units (slides divided by [`PositionModel::scale`]).
    pub fn pair_equations(&self, p: usize, pa: &Pose, pb: &Pose, targets: &[f64]) -> PairEquations {
        let pair = &self.pairs[p];
        let pb = &pair.carried(pb);
        let mut rows = pair.constraints(self.space, pa, pb);
        let n_driven = if targets.is_empty() {
            0
        } else {
            let values = pair.values(self.space, pa, pb);
            let mut n = 0;
            for ((v, angle), t) in values.into_iter().zip(targets) {
                let mut r = v.sub(&TS::constant(*t));
                if angle {
                    r.v = wrap(r.v);
                }
                rows.push(r);
                n += 1;
            }
            n
        };
        let cols = embed_columns(self.space);
        let b = cols.len();
        let jacobian = DMatrix::from_fn(rows.len(), 2 * b, |i, j| {
            if j < b {
                rows[i].d[cols[j]]
            } else {
                rows[i].d[6 + cols[j - b]]
            }
        });
        PairEquations {
            residual: rows.iter().map(|r| r.v).collect(),
            jacobian,
            driven_rows: n_driven,
        }
    }

    /// The joint values of pair `p` (driven-DOF order; slides in model units, angles in
    /// radians in (−π, π]).
    pub fn pair_values(&self, p: usize, pa: &Pose, pb: &Pose) -> Vec<(f64, bool)> {
        let pair = &self.pairs[p];
        pair.values(self.space, pa, &pair.carried(pb))
            .into_iter()
            .map(|(v, a)| (v.v, a))
            .collect()
    }

    /// Number of constraint equations of pair `p` (without driven values).
    pub fn constraint_count(&self, p: usize) -> usize {
        self.pair_equations(p, &Pose::identity(), &Pose::identity(), &[])
            .residual
            .len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ball_joint_that_did_not_turn_reads_zero_not_nan() {
        // Its relative rotation rounded with a trace just above 3: the `acos` of
        // `Rotation3::scaled_axis` is NaN there, and `mbsa solve` wrote `NaN°`.
        // A spherical joint of Gepetto's two-legged Digit-like robot at `--set motor_knee=70`.
        let r = nalgebra::Matrix3::from_column_slice(&[
            1.0,
            1.567686990591483e-16,
            6.271025365656158e-16,
            -1.5676676676523737e-16,
            1.0,
            -5.862281146629122e-16,
            -6.2753621743461e-16,
            5.862416671900683e-16,
            1.0000000000000004,
        ]);
        let pa = Pose::identity();
        let pb = Pose {
            rotation: r,
            translation: Vector3::zeros(),
        };
        for e in [Vector3::x(), Vector3::y(), Vector3::z()] {
            let v = rotation_component(&pa, &pb, &e).v;
            assert!(v.is_finite() && v.abs() < 1e-15, "{v}");
        }
    }
    use crate::motion::kinds::Allowed;
    use crate::motion::{SplitMix64, random_geometry};

    /// The shared definition's features at the position model's (PC's axis and CR's normal
    /// are not made perpendicular here: the span of the twists does not depend on it).
    fn shared(f: &Features) -> kinds::Features<f64> {
        kinds::Features {
            origin: f.o.into(),
            origin2: f.o2.into(),
            axis: f.u.into(),
            axis2: f.w.into(),
            normal: f.n.into(),
            pitch: f.h,
            hint: [0.0; 3],
        }
    }

    /// The equations of one joint of `kind` with features `f`, at the reference
    /// configuration.
    fn equations(space: Space, kind: JointType, f: Features) -> PairEquations {
        let pair = Pair {
            joint: 0,
            index: 0,
            a: 0,
            b: 1,
            kind,
            driven: 0,
            f,
            offset: Pose::identity(),
        };
        let model = PositionModel {
            space,
            scale: 1.0,
            pairs: vec![pair],
            bodies: 2,
            frame: 0,
        };
        model.pair_equations(0, &Pose::identity(), &Pose::identity(), &[])
    }

    /// At random geometry, every kind with a position model: its residual vanishes at the
    /// reference configuration, its Jacobian acts on `t_B − t_A`, and its rows span exactly
    /// the annihilator of the twists [`kinds::allowed`] gives at the same features (B − k
    /// independent rows annihilating k independent twists; SPSP's one row along its line).
    #[test]
    fn jacobian_spans_the_annihilator_of_the_kinds_twists() {
        let mut checked = 0;
        for space in [Space::Spatial, Space::Planar, Space::Spherical] {
            let b = space.b() as usize;
            for kind in JointType::all() {
                if kinds::features(kind, space).is_none() {
                    continue;
                }
                let mut rng = SplitMix64::new(kind as u64 * 31 + space as u64);
                for trial in 0..20 {
                    let what = format!("{kind:?} {space:?} trial {trial}");
                    let mut g = random_geometry(kind, space, &mut rng);
                    if kind == JointType::CR {
                        // A slot's normal as written, across the axis: the residual keeps the
                        // slot's face along `normal` itself, where the twists use its part
                        // across the axis.
                        let (u, n) = (v3(g.axis.expect("drawn")), v3(g.normal.expect("drawn")));
                        g.normal = Some((n - u * u.dot(&n)).into());
                    }
                    let f = features(space, kind, &g, 1.0, "j").expect("a position model");
                    let e = equations(space, kind, f.clone());
                    assert!(e.residual.iter().all(|r| r.abs() < 1e-12), "{what}");
                    let (ja, jb) = (e.jacobian.columns(0, b), e.jacobian.columns(b, b));
                    assert!((ja + jb).norm() < 1e-12, "{what}");
                    let rank = |m: &DMatrix<f64>| if m.nrows() == 0 { 0 } else { m.rank(1e-9) };
                    let jb = jb.into_owned();
                    match kinds::allowed(kind, space, &shared(&f)).expect("a model") {
                        Allowed::Listed(list, k) => {
                            let t = DMatrix::from_fn(b, k, |i, c| list[c][i]);
                            assert_eq!(rank(&t.transpose()), k, "{what}: twists");
                            assert_eq!(jb.nrows(), b - k, "{what}: rows");
                            assert_eq!(rank(&jb), b - k, "{what}: independent rows");
                            assert!((&jb * &t).norm() < 1e-9, "{what}: rows · twists");
                        }
                        Allowed::AnnihilatorOf(line) => {
                            let both = jb.clone().insert_row(jb.nrows(), 0.0);
                            let both = DMatrix::from_fn(both.nrows(), b, |i, c| {
                                if i < jb.nrows() { jb[(i, c)] } else { line[c] }
                            });
                            assert_eq!((jb.nrows(), rank(&both)), (1, 1), "{what}");
                        }
                    }
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 20 * (15 + 3 + 2));
    }
}
