//! Poses and vectors: rigid transforms from positions and rotations, unit axes, and the geometry
//! of a point closure.

use super::toml_text::num;
use crate::mechanism::Geometry;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

/// A pose: rotation then translation (maps body coordinates to world coordinates).
pub(crate) type Pose = Isometry3<f64>;

/// A pose from a position and a rotation.
pub(crate) fn pose(p: [f64; 3], q: UnitQuaternion<f64>) -> Pose {
    Isometry3::from_parts(Translation3::new(p[0], p[1], p[2]), q)
}

/// Roll-pitch-yaw (fixed axes x, y, z: R = Rz(yaw) Ry(pitch) Rx(roll)), as URDF and SDFormat.
pub(crate) fn rpy(r: f64, p: f64, y: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(r, p, y)
}

/// A unit vector from three numbers, `None` if it is zero (or not finite).
pub(crate) fn unit(v: &[f64]) -> Option<Vector3<f64>> {
    let v = tame(Vector3::new(v[0], v[1], v[2]));
    let n = v.norm();
    (n > 1e-12 && n.is_finite()).then(|| v / n)
}

/// `v` as it is when its norm is finite, else divided by its largest component first (a
/// vector of 1e200s overflows the sum of squares; scaled it keeps its direction).
pub(crate) fn tame(v: Vector3<f64>) -> Vector3<f64> {
    if v.norm().is_finite() {
        return v;
    }
    let m = v.amax();
    if m.is_finite() && m > 0.0 { v / m } else { v }
}

/// The rotation of a quaternion `w x y z`, `None` if it is zero (norm below 1e-12) or not
/// finite; one whose norm overflows is scaled by its largest component first.
pub(crate) fn unit_quat(w: f64, x: f64, y: f64, z: f64) -> Option<UnitQuaternion<f64>> {
    let mut q = Quaternion::new(w, x, y, z);
    if !q.norm().is_finite() {
        let m = q.coords.amax();
        if !m.is_finite() {
            return None;
        }
        q /= m;
    }
    (q.norm() >= 1e-12).then(|| UnitQuaternion::from_quaternion(q))
}

pub(crate) fn arr(v: Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// The geometry of a point joint (S) of a loop closure whose point is `p1` on the first body
/// and `p2` on the second at the configuration: `origin` = `p1`, and `second.origin` = `p2`
/// when the two differ as written (the loop is open there; `mbsa assemble` closes it).
pub(crate) fn point_closure(p1: Vector3<f64>, p2: Vector3<f64>) -> Geometry {
    let (a, b) = (arr(p1), arr(p2));
    let differ = a.iter().zip(&b).any(|(x, y)| num(*x) != num(*y));
    Geometry {
        origin: Some(a),
        second: differ.then(|| {
            Box::new(crate::mechanism::Second {
                origin: Some(b),
                ..Default::default()
            })
        }),
        ..Geometry::default()
    }
}
