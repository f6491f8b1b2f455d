//! `--merge-balls`: a ball joint written as three revolute joints whose axes meet at one
//! point, through two intermediate bodies that nothing else holds (as CAD exporters write
//! it), merged into one spherical joint between the outer bodies. A loop cut open at the
//! file's configuration may leave the pin to an outer body carried apart on that body's side
//! (`second`): the ball keeps that side's centre.

use super::JointRec;
use super::pins::retain_alive;
use super::pose::unit;
use crate::joint::JointType;
use crate::mechanism::{Geometry, Second};
use nalgebra::{Matrix3, Vector3};

/// Merge every chain `A -R- m1 -R- m2 -R- B` whose three revolute joints are undriven, with
/// axes meeting at one point and independent there, and whose `m1`, `m2` (not the frame) have
/// no other joint, into one S joint between `A` and `B` at that point. Returns the bodies
/// dropped (two a ball), in the order merged.
pub(super) fn merge_balls(joints: &mut Vec<JointRec>, frame: usize) -> Vec<usize> {
    let n = joints
        .iter()
        .flat_map(|j| j.bodies.iter().copied())
        .max()
        .map_or(0, |b| b + 1);
    let mut on: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (k, j) in joints.iter().enumerate() {
        for &b in &j.bodies {
            on[b].push(k);
        }
    }
    let mut alive = vec![true; joints.len()];
    let mut dropped = Vec::new();
    for m1 in 0..n {
        if m1 == frame || on[m1].len() != 2 {
            continue;
        }
        let (j0, j1) = (on[m1][0], on[m1][1]);
        for (ja, jb) in [(j0, j1), (j1, j0)] {
            let Some(chain) = ball_chain(joints, &on, &alive, frame, m1, ja, jb) else {
                continue;
            };
            let Chain {
                a,
                m2,
                jc,
                b,
                at,
                second,
            } = chain;
            let id = format!("{}+{}+{}", joints[ja].id, joints[jb].id, joints[jc].id);
            let mut comments = std::mem::take(&mut joints[ja].comments);
            comments.extend(joints[jb].comments.iter().cloned());
            comments.extend(joints[jc].comments.iter().cloned());
            joints[ja] = JointRec {
                id,
                kind: JointType::S,
                bodies: vec![a, b],
                driven: 0,
                geometry: Geometry {
                    origin: Some(at),
                    second,
                    ..Geometry::default()
                },
                comments,
            };
            alive[jb] = false;
            alive[jc] = false;
            on[m1].clear();
            on[m2].clear();
            for k in &mut on[b] {
                if *k == jc {
                    *k = ja;
                }
            }
            dropped.extend([m1, m2]);
            break;
        }
    }
    retain_alive(joints, &alive);
    dropped
}

/// A chain found from its first intermediate body: the ball joins `a` to `b` at `at`, and
/// `b` carries it at `second` when the file leaves it open there.
struct Chain {
    a: usize,
    m2: usize,
    jc: usize,
    b: usize,
    at: [f64; 3],
    second: Option<Box<Second>>,
}

/// The chain `a -ja- m1 -jb- m2 -jc- b`, when it is a ball written as three revolute joints.
fn ball_chain(
    joints: &[JointRec],
    on: &[Vec<usize>],
    alive: &[bool],
    frame: usize,
    m1: usize,
    ja: usize,
    jb: usize,
) -> Option<Chain> {
    let plain_pin = |k: usize| alive[k] && joints[k].kind == JointType::R && joints[k].driven == 0;
    let other = |k: usize, x: usize| -> Option<usize> {
        match joints[k].bodies[..] {
            [p, q] if p == x && q != x => Some(q),
            [p, q] if q == x && p != x => Some(p),
            _ => None,
        }
    };
    if !plain_pin(ja) || !plain_pin(jb) {
        return None;
    }
    let a = other(ja, m1)?;
    let m2 = other(jb, m1)?;
    if m2 == frame || m2 == a || on[m2].len() != 2 {
        return None;
    }
    let jc = on[m2].iter().copied().find(|&k| k != jb)?;
    if !plain_pin(jc) {
        return None;
    }
    let b = other(jc, m2)?;
    if b == a || b == m1 {
        return None;
    }
    let (ga, gb, gc) = (
        &joints[ja].geometry,
        &joints[jb].geometry,
        &joints[jc].geometry,
    );
    let at = meeting_point(&[ga, gb, gc])?;
    // Open only where the last pin meets `b`, as `b` carries it: the centre there.
    if ga.second.is_some() || gb.second.is_some() {
        return None;
    }
    let second = match &gc.second {
        None => None,
        Some(s) if joints[jc].bodies[1] == b => Some(Box::new(Second {
            origin: Some(carried(gc, s, at)?),
            ..Second::default()
        })),
        Some(_) => return None,
    };
    Some(Chain {
        a,
        m2,
        jc,
        b,
        at,
        second,
    })
}

/// The point `at` of the pin `g`'s axis as its second body carries it (`s`): as far along
/// that body's axis from its origin as `at` is along the pin's own.
fn carried(g: &Geometry, s: &Second, at: [f64; 3]) -> Option<[f64; 3]> {
    let (o, d) = (Vector3::from(g.origin?), unit(&g.axis?)?);
    let o2 = Vector3::from(s.origin.or(g.origin)?);
    let d2 = unit(&s.axis.or(g.axis)?)?;
    let p = o2 + d2 * (Vector3::from(at) - o).dot(&d);
    p.iter().all(|v| v.is_finite()).then(|| [p.x, p.y, p.z])
}

/// The point where three joint axes meet, when they do (each within 1e-6 of the model's size
/// of it) and are independent there (no two parallel, not in one plane).
fn meeting_point(g: &[&Geometry; 3]) -> Option<[f64; 3]> {
    let mut lines = Vec::with_capacity(3);
    for x in g {
        let o = Vector3::from(x.origin?);
        let d = unit(&x.axis?)?;
        lines.push((o, d));
    }
    let dirs = Matrix3::from_columns(&[lines[0].1, lines[1].1, lines[2].1]);
    if dirs.determinant().abs() < 1e-6 {
        return None;
    }
    // The least-squares meeting point: sum over the lines of (I - d d^T)(p - o) = 0.
    let mut lhs = Matrix3::zeros();
    let mut rhs = Vector3::zeros();
    for (o, d) in &lines {
        let proj = Matrix3::identity() - d * d.transpose();
        lhs += proj;
        rhs += proj * o;
    }
    let p = lhs.lu().solve(&rhs)?;
    let scale = 1.0 + lines.iter().map(|(o, _)| o.norm()).fold(p.norm(), f64::max);
    let off = |(o, d): &(Vector3<f64>, Vector3<f64>)| (p - o).cross(d).norm();
    (p.iter().all(|v| v.is_finite()) && lines.iter().all(|l| off(l) < 1e-6 * scale))
        .then(|| [p.x, p.y, p.z])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pin(id: &str, a: usize, b: usize, origin: [f64; 3], axis: [f64; 3]) -> JointRec {
        JointRec {
            id: id.into(),
            kind: JointType::R,
            bodies: vec![a, b],
            driven: 0,
            geometry: Geometry {
                origin: Some(origin),
                axis: Some(axis),
                ..Geometry::default()
            },
            comments: Vec::new(),
        }
    }

    /// Frame 0, rod 1 on a hinge; bodies 2 and 3 the ball's intermediate links; 4 beyond.
    fn rod_and_ball(third_axis: [f64; 3], third_origin: [f64; 3]) -> Vec<JointRec> {
        let c = [1.0, 0.0, 0.0];
        vec![
            pin("hinge", 0, 1, [0.0; 3], [0.0, 0.0, 1.0]),
            pin("bx", 1, 2, c, [1.0, 0.0, 0.0]),
            pin("by", 2, 3, [1.0, 2.0, 0.0], [0.0, 1.0, 0.0]),
            pin("bz", 3, 4, third_origin, third_axis),
        ]
    }

    #[test]
    fn three_pins_meeting_at_a_point_become_one_ball() {
        // The second axis passes through the centre from another origin on it.
        let mut js = rod_and_ball([0.0, 0.0, 1.0], [1.0, 0.0, 2.0]);
        js[2].geometry.origin = Some([1.0, 3.0, 0.0]);
        let dropped = merge_balls(&mut js, 0);
        assert_eq!(dropped, [2, 3]);
        assert_eq!(js.len(), 2);
        assert_eq!(js[1].kind, JointType::S);
        assert_eq!(js[1].bodies, [1, 4]);
        assert_eq!(js[1].id, "bx+by+bz");
        let o = js[1].geometry.origin.expect("a centre");
        assert!((o[0] - 1.0).abs() < 1e-12 && o[1].abs() < 1e-12 && o[2].abs() < 1e-12);
    }

    #[test]
    fn a_ball_left_open_at_its_last_pin_keeps_the_outer_body_s_centre() {
        let mut js = rod_and_ball([0.0, 0.0, 1.0], [1.0, 0.0, 2.0]);
        // Body 4 carries the last pin 3 units off along x, turned to carry it along y.
        js[3].geometry.second = Some(Box::new(Second {
            origin: Some([4.0, 0.0, 2.0]),
            axis: Some([0.0, 1.0, 0.0]),
            ..Second::default()
        }));
        assert_eq!(merge_balls(&mut js, 0), [2, 3]);
        let s = js[1].geometry.second.as_ref().expect("open");
        // The centre is 2 units back along the pin from its origin: 2 units back along y.
        let o = s.origin.expect("a centre");
        assert!(
            (o[0] - 4.0).abs() < 1e-12 && (o[1] + 2.0).abs() < 1e-12 && (o[2] - 2.0).abs() < 1e-12,
            "{o:?}"
        );
        // Open at the first pin instead: left as written.
        let mut js = rod_and_ball([0.0, 0.0, 1.0], [1.0, 0.0, 2.0]);
        js[1].geometry.second = Some(Box::new(Second::default()));
        assert!(merge_balls(&mut js, 0).is_empty());
    }

    #[test]
    fn pins_that_miss_the_point_or_lie_in_one_plane_stay() {
        // The third axis passes 0.1 away from the centre.
        let mut js = rod_and_ball([0.0, 0.0, 1.0], [1.0, 0.1, 0.0]);
        assert!(merge_balls(&mut js, 0).is_empty());
        assert_eq!(js.len(), 4);
        // Three axes in one plane (a planar chain of pins at one point is no ball).
        let mut js = rod_and_ball([1.0, 1.0, 0.0], [1.0, 0.0, 0.0]);
        assert!(merge_balls(&mut js, 0).is_empty());
    }

    #[test]
    fn a_driven_pin_or_a_held_intermediate_body_stays() {
        let mut js = rod_and_ball([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
        js[2].driven = 1;
        assert!(merge_balls(&mut js, 0).is_empty());
        // Body 3 also held by a spring link to the frame.
        let mut js = rod_and_ball([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
        js.push(pin("extra", 3, 0, [5.0, 0.0, 0.0], [0.0, 0.0, 1.0]));
        assert!(merge_balls(&mut js, 0).is_empty());
    }
}
