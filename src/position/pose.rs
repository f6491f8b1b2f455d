//! Body poses and configurations, and the retraction that moves a pose by a twist.
//!
//! A pose maps the body's points from the reference configuration (the file's geometry, every
//! body at the identity) to the world: `y = R x + p`. So `p` is where the body point that was
//! at the world origin now is, and a twist `(ω; v_O)` of the body moves a world point `y` at
//! velocity `v_O + ω × y`, as in [`crate::motion`]. Planar poses rotate about z and translate
//! in the plane; spherical poses only rotate.

use crate::mechanism::Space;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use serde::Serialize;

/// The pose of one body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Rotation from the reference to the current configuration.
    pub rotation: Matrix3<f64>,
    /// Current position of the body point that was at the world origin.
    pub translation: Vector3<f64>,
}

impl Default for Pose {
    fn default() -> Pose {
        Pose::identity()
    }
}

impl Pose {
    /// The reference pose.
    pub fn identity() -> Pose {
        Pose {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// Where the body point at reference position `x` is now.
    pub fn point(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * x + self.translation
    }

    /// Where the body direction at reference `u` points now.
    pub fn dir(&self, u: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * u
    }

    /// Move by the spatial twist `(ω; v)` taken as a finite step: the exponential of the
    /// twist (a screw motion), `y ↦ exp(ω) y + V v` with `V = I + (1 − cos θ)/θ² [ω] +
    /// (θ − sin θ)/θ³ [ω]²`, `θ = |ω|`. A rotation about an axis far from the origin is then
    /// exact, so Newton's steps do not degrade with the distance of a body from the origin.
    pub fn moved(&self, w: &Vector3<f64>, v: &Vector3<f64>) -> Pose {
        let r = Rotation3::new(*w).into_inner();
        let th = w.norm();
        let k = Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0);
        let (a, b) = if th < 1e-6 {
            (0.5 - th * th / 24.0, 1.0 / 6.0 - th * th / 120.0)
        } else {
            (
                (1.0 - th.cos()) / (th * th),
                (th - th.sin()) / (th * th * th),
            )
        };
        let vv = Matrix3::identity() + k * a + k * k * b;
        let rotation = orthonormalized(&(r * self.rotation));
        Pose {
            rotation,
            translation: r * self.translation + vv * v,
        }
    }

    /// Move by a twist of the motion space (`B` numbers, see [`embed`]).
    pub fn moved_by(&self, space: Space, t: &[f64]) -> Pose {
        let (w, v) = embed(space, t);
        self.moved(&w, &v)
    }

    /// Rotation vector (axis times angle, radians).
    pub fn rotation_vector(&self) -> Vector3<f64> {
        Rotation3::from_matrix_unchecked(self.rotation).scaled_axis()
    }
}

/// The rotation nearest to an almost orthonormal `m` (Gram–Schmidt on its columns), so that
/// rounding does not build up over long sweeps.
fn orthonormalized(m: &Matrix3<f64>) -> Matrix3<f64> {
    let c0 = m.column(0).normalize();
    let c1 = m.column(1) - c0 * c0.dot(&m.column(1));
    let c1 = c1.normalize();
    let c2 = c0.cross(&c1);
    Matrix3::from_columns(&[c0, c1, c2])
}

/// A spatial twist `(ω, v)` from the `B` numbers of a motion-space twist: planar
/// `(ω_z; v_x, v_y)`, spherical `ω`.
pub fn embed(space: Space, t: &[f64]) -> (Vector3<f64>, Vector3<f64>) {
    match space {
        Space::Spatial => (
            Vector3::new(t[0], t[1], t[2]),
            Vector3::new(t[3], t[4], t[5]),
        ),
        Space::Planar => (Vector3::new(0.0, 0.0, t[0]), Vector3::new(t[1], t[2], 0.0)),
        Space::Spherical => (Vector3::new(t[0], t[1], t[2]), Vector3::zeros()),
    }
}

/// Which of the 6 spatial twist components `(ω; v)` a motion space's twist holds, in order.
pub fn embed_columns(space: Space) -> &'static [usize] {
    match space {
        Space::Spatial => &[0, 1, 2, 3, 4, 5],
        Space::Planar => &[2, 3, 4],
        Space::Spherical => &[0, 1, 2],
    }
}

/// A configuration: one pose per body of the mechanism (indexed like `Mechanism::bodies`).
#[derive(Clone, Debug, PartialEq)]
pub struct Configuration {
    /// The poses.
    pub poses: Vec<Pose>,
}

impl Configuration {
    /// The file's configuration: every body at the identity.
    pub fn reference(bodies: usize) -> Configuration {
        Configuration {
            poses: vec![Pose::identity(); bodies],
        }
    }
}

/// A pose as reported (file units, degrees).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseReport {
    /// Body id.
    pub body: String,
    /// Position of the body point that was at the world origin.
    pub translation: [f64; 3],
    /// Rotation as a unit quaternion `[w, x, y, z]`.
    pub quaternion: [f64; 4],
    /// Rotation angle in degrees (about `axis`; about z in a planar mechanism, signed).
    pub angle_deg: f64,
    /// Rotation axis (unit; `[0, 0, 1]` when the angle is zero).
    pub axis: [f64; 3],
}

/// Rotation vector (axis times angle) of an almost orthonormal matrix. Robust near the
/// identity, where `Rotation3::angle` (an `acos` of the trace) gives NaN once rounding puts
/// the trace above 3: that NaN silently disabled the curve test and the slices, and wrote
/// `NaN°` for a ball joint that did not turn. Near a half turn, where the skew part vanishes,
/// nalgebra's own logarithm takes over.
pub(crate) fn log_rotation(r: &Matrix3<f64>) -> Vector3<f64> {
    let w = Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    ) * 0.5;
    let s = w.norm();
    let c = ((r.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
    if c < -0.9 {
        let v = Rotation3::from_matrix_unchecked(*r).scaled_axis();
        if v.iter().all(|x| x.is_finite()) {
            return v;
        }
    }
    if s < 1e-300 {
        return Vector3::zeros();
    }
    w * (s.atan2(c) / s)
}

/// Round tiny noise to zero and keep 12 significant digits so reports are stable.
pub(crate) fn tidy(x: f64) -> f64 {
    if x.abs() < 1e-12 {
        return 0.0;
    }
    let s = format!("{x:.11e}");
    s.parse().unwrap_or(x)
}

impl PoseReport {
    /// Report `pose` of body `body` in a `space` mechanism; `scale` converts lengths back to
    /// file units.
    pub fn new(body: String, pose: &Pose, space: Space, scale: f64) -> PoseReport {
        let q =
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(pose.rotation));
        let (mut axis, mut angle) = q
            .axis_angle()
            .map(|(a, t)| (a.into_inner(), t))
            .unwrap_or((Vector3::z(), 0.0));
        if space == Space::Planar && axis.z < 0.0 {
            axis = -axis;
            angle = -angle;
        }
        let t = pose.translation * scale;
        let angle_deg = tidy(angle.to_degrees());
        // A rotation of 10^-13 degrees still has an axis, made of rounding noise: the angle
        // reported as zero gets the zero rotation's axis, as documented.
        if angle_deg == 0.0 {
            axis = Vector3::z();
        }
        PoseReport {
            body,
            translation: [tidy(t.x), tidy(t.y), tidy(t.z)],
            quaternion: [tidy(q.w), tidy(q.i), tidy(q.j), tidy(q.k)],
            angle_deg,
            axis: [tidy(axis.x), tidy(axis.y), tidy(axis.z)],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rotation_vector_is_read_back_near_a_half_turn_and_elsewhere() {
        // Near the identity: `position::residual`'s test of a ball joint that did not turn.
        // A half turn about z, and a quarter turn about x, are read back.
        let half = Rotation3::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI);
        let v = log_rotation(half.matrix());
        assert!(
            (v.norm() - std::f64::consts::PI).abs() < 1e-12 && v.z.abs() > 3.0,
            "{v}"
        );
        let quarter = Rotation3::from_axis_angle(&Vector3::x_axis(), 0.5 * std::f64::consts::PI);
        let v = log_rotation(quarter.matrix());
        assert!(
            (v - Vector3::new(0.5 * std::f64::consts::PI, 0.0, 0.0)).norm() < 1e-12,
            "{v}"
        );
    }

    #[test]
    fn a_rotation_reported_as_zero_has_the_zero_rotations_axis() {
        // 10^-15 rad about a tilted axis: the angle is reported as 0 degrees, so the axis must
        // be the documented [0, 0, 1], not the tilted axis the noise happens to have.
        let tiny = Pose {
            rotation: Rotation3::new(Vector3::new(0.6e-15, -0.8e-15, 0.0)).into_inner(),
            translation: Vector3::zeros(),
        };
        let r = PoseReport::new("b".into(), &tiny, Space::Spatial, 1.0);
        assert_eq!(r.angle_deg, 0.0);
        assert_eq!(r.axis, [0.0, 0.0, 1.0]);
        // A real rotation keeps its axis.
        let turn = Pose {
            rotation: Rotation3::new(Vector3::new(0.3, -0.4, 0.0)).into_inner(),
            translation: Vector3::zeros(),
        };
        let r = PoseReport::new("b".into(), &turn, Space::Spatial, 1.0);
        assert!((r.angle_deg - 0.5f64.to_degrees()).abs() < 1e-9);
        assert_eq!(r.axis, [0.6, -0.8, 0.0]);
    }
}
