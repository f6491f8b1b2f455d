//! One side of a joint moved rigidly: where a loop cut welds two links that the file places
//! apart, one link (with everything welded to it) is moved to where the cut puts it, and each
//! joint between the moved links and the rest carries the moved side's features in `second`,
//! as a cut joint that the file leaves open does (`mbsa assemble` closes them all).

use super::Pose;
use super::toml_text::num;
use crate::joint::JointType;
use crate::mechanism::{Geometry, Second, Space};
use nalgebra::{Point3, Vector3};

/// Whether a joint of `kind` can carry one side moved by any rigid move: its `second`
/// geometry stands for the move up to the joint's own freedom. That holds where the joint
/// turns freely about the feature `second` aligns (R, C, U about their axes; S about any
/// axis), and for the kinds with no geometry (counted only).
pub(crate) fn can_move_side(kind: JointType) -> bool {
    use JointType::*;
    matches!(kind, R | C | U | S) || kind.info().geometry.is_empty()
}

/// Move side `side` (0: the first body, 1: the second) of a joint of `kind` by `d`: the
/// moved side's features are those `d` carries them to; the other side keeps its own (in
/// `second` when the first side moves). Only for kinds [`can_move_side`] accepts.
pub(crate) fn move_side(kind: JointType, g: &mut Geometry, side: usize, d: &Pose) {
    if kind.info().geometry.is_empty() {
        return;
    }
    let fields = Second::fields(kind, Space::Spatial);
    let mut s = g.second.take().map(|b| *b).unwrap_or_default();
    for &f in fields {
        let first = first_field(g, f);
        let slot = second_field(&mut s, f);
        if side == 1 {
            *slot = slot.or(first).map(|v| apply(d, f, v));
        } else {
            *slot = slot.or(first);
        }
    }
    if side == 0 {
        for f in ["origin", "axis", "axis2", "normal"] {
            if let Some(v) = first_field_mut(g, f) {
                *v = apply(d, f, *v);
            }
        }
    }
    let differs = fields.iter().any(|&f| {
        let (a, b) = (first_field(g, f), *second_field(&mut s, f));
        match (a, b) {
            (Some(a), Some(b)) => a.iter().zip(b).any(|(x, y)| num(*x) != num(y)),
            (None, None) => false,
            _ => true,
        }
    });
    if differs {
        g.second = Some(Box::new(s));
    }
}

/// Move every feature of a joint both of whose sides move by `d`.
pub(crate) fn move_joint(g: &mut Geometry, d: &Pose) {
    for f in ["origin", "origin2", "axis", "axis2", "normal"] {
        if let Some(v) = first_field_mut(g, f) {
            *v = apply(d, f, *v);
        }
    }
    if let Some(s) = g.second.as_deref_mut() {
        for f in ["origin", "axis", "axis2", "normal"] {
            let slot = second_field(s, f);
            *slot = slot.map(|v| apply(d, f, v));
        }
    }
}

/// A point moved by `d`, or a direction turned by its rotation.
fn apply(d: &Pose, field: &str, v: [f64; 3]) -> [f64; 3] {
    let out = if field.starts_with("origin") {
        (d * Point3::from(v)).coords
    } else {
        d.rotation * Vector3::from(v)
    };
    [out.x, out.y, out.z]
}

fn first_field(g: &Geometry, f: &str) -> Option<[f64; 3]> {
    match f {
        "origin" => g.origin,
        "origin2" => g.origin2,
        "axis" => g.axis,
        "axis2" => g.axis2,
        _ => g.normal,
    }
}

fn first_field_mut<'a>(g: &'a mut Geometry, f: &str) -> Option<&'a mut [f64; 3]> {
    match f {
        "origin" => g.origin.as_mut(),
        "origin2" => g.origin2.as_mut(),
        "axis" => g.axis.as_mut(),
        "axis2" => g.axis2.as_mut(),
        _ => g.normal.as_mut(),
    }
}

fn second_field<'a>(s: &'a mut Second, f: &str) -> &'a mut Option<[f64; 3]> {
    match f {
        "origin" => &mut s.origin,
        "axis" => &mut s.axis,
        "axis2" => &mut s.axis2,
        _ => &mut s.normal,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
    }

    #[test]
    fn a_moved_second_side_is_carried_in_second() {
        let d = Pose::from_parts(
            Translation3::new(1.0, 0.0, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        );
        let mut g = Geometry {
            origin: Some([0.0, 1.0, 0.0]),
            axis: Some([1.0, 0.0, 0.0]),
            ..Geometry::default()
        };
        move_side(JointType::R, &mut g, 1, &d);
        let s = g.second.as_deref().expect("second");
        assert_eq!(g.origin, Some([0.0, 1.0, 0.0]));
        assert!(close(s.origin.expect("origin"), [0.0, 0.0, 0.0]));
        assert!(close(s.axis.expect("axis"), [0.0, 1.0, 0.0]));
    }

    #[test]
    fn a_moved_first_side_keeps_the_second_where_it_was() {
        let d = Pose::from_parts(Translation3::new(0.0, 0.0, 2.0), UnitQuaternion::identity());
        let mut g = Geometry {
            origin: Some([1.0, 0.0, 0.0]),
            ..Geometry::default()
        };
        move_side(JointType::S, &mut g, 0, &d);
        assert_eq!(g.origin, Some([1.0, 0.0, 2.0]));
        let s = g.second.as_deref().expect("second");
        assert_eq!(s.origin, Some([1.0, 0.0, 0.0]));
    }

    #[test]
    fn moving_a_side_back_to_the_other_drops_second() {
        let d = Pose::from_parts(Translation3::new(0.0, 3.0, 0.0), UnitQuaternion::identity());
        let mut g = Geometry {
            origin: Some([0.0, 0.0, 0.0]),
            axis: Some([0.0, 0.0, 1.0]),
            ..Geometry::default()
        };
        move_side(JointType::R, &mut g, 1, &d);
        assert!(g.second.is_some());
        move_side(JointType::R, &mut g, 1, &d.inverse());
        assert!(g.second.is_none());
    }

    #[test]
    fn only_kinds_that_turn_about_the_aligned_feature_can_move_a_side() {
        assert!(can_move_side(JointType::R));
        assert!(can_move_side(JointType::F));
        assert!(!can_move_side(JointType::P));
        assert!(!can_move_side(JointType::H));
    }
}
