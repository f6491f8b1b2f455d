//! Poses and vectors: rigid transforms from positions and rotations, unit axes, and the geometry
//! of a point closure.

use super::toml_text::num;
use crate::mechanism::Geometry;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

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

/// A unit vector from three numbers, `None` if it is zero.
pub(crate) fn unit(v: &[f64]) -> Option<Vector3<f64>> {
    let v = Vector3::new(v[0], v[1], v[2]);
    let n = v.norm();
    (n > 1e-12 && n.is_finite()).then(|| v / n)
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
