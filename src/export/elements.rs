//! Each joint kind as the elementary joints of a simulator (hinge, slide, ball, and the SDF
//! screw), composed in the driven-DOF order of the kind's twists (`motion::kinds`): the chain
//! allows exactly the joint's twists at the configuration written.

use crate::joint::JointType;
use crate::mechanism::{Geometry, Space};
use nalgebra::Vector3;

/// An elementary joint: its kind, a point and a direction in the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Elem {
    /// A turn about `axis` through `pos`.
    Hinge {
        /// A point of the axis.
        pos: [f64; 3],
        /// The direction (as written: not normalized).
        axis: [f64; 3],
    },
    /// A slide along `axis` (`pos` places the joint, it does not change the motion).
    Slide {
        /// Where the joint is drawn.
        pos: [f64; 3],
        /// The direction.
        axis: [f64; 3],
    },
    /// The three turns about `pos`.
    Ball {
        /// The centre.
        pos: [f64; 3],
    },
    /// A screw (SDFormat only): turn about `axis` through `pos` with `pitch` length per radian.
    Screw {
        /// A point of the axis.
        pos: [f64; 3],
        /// The direction.
        axis: [f64; 3],
        /// Length per radian.
        pitch: f64,
    },
}

impl Elem {
    /// The freedoms it allows.
    pub fn dof(&self) -> u32 {
        match self {
            Elem::Ball { .. } => 3,
            _ => 1,
        }
    }

    /// Its point.
    pub fn pos(&self) -> [f64; 3] {
        match *self {
            Elem::Hinge { pos, .. }
            | Elem::Slide { pos, .. }
            | Elem::Ball { pos }
            | Elem::Screw { pos, .. } => pos,
        }
    }
}

const ZERO: [f64; 3] = [0.0; 3];
const X: [f64; 3] = [1.0, 0.0, 0.0];
const Y: [f64; 3] = [0.0, 1.0, 0.0];
const Z: [f64; 3] = [0.0, 0.0, 1.0];

fn unit(v: [f64; 3]) -> Vector3<f64> {
    Vector3::from(v).normalize()
}

/// The two directions perpendicular to `d`, as the kinds take them.
fn pair(d: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let (e1, e2) = crate::motion::perpendicular_pair(&unit(d));
    (e1.into(), e2.into())
}

/// The elementary joints of a joint of `kind` in `space` with geometry `g` (checked: the
/// fields its model needs are there), in driven-DOF order; `None` for a kind no simulator
/// joint composes (gears, cams, rolling and point contacts).
pub fn elements(kind: JointType, space: Space, g: &Geometry) -> Option<Vec<Elem>> {
    match space {
        Space::Spatial => spatial(kind, g),
        Space::Planar => planar(kind, g),
        Space::Spherical => spherical(kind, g),
    }
}

fn spatial(kind: JointType, g: &Geometry) -> Option<Vec<Elem>> {
    use Elem::*;
    use JointType::*;
    let o = g.origin.unwrap_or(ZERO);
    let hinge = |axis: [f64; 3]| Hinge { pos: o, axis };
    let slide = |axis: [f64; 3]| Slide { pos: o, axis };
    let u = g.axis.unwrap_or(Z);
    let n = g.normal.unwrap_or(Z);
    Some(match kind {
        R => vec![hinge(u)],
        P => vec![slide(u)],
        H => vec![Screw {
            pos: o,
            axis: u,
            pitch: g.pitch.unwrap_or(0.0),
        }],
        C => vec![slide(u), hinge(u)],
        ER => {
            let (e1, e2) = pair(u);
            vec![hinge(e1), hinge(e2)]
        }
        U => vec![hinge(u), hinge(g.axis2.unwrap_or(X))],
        S => vec![Ball { pos: o }],
        PL | FP => {
            let (e1, e2) = pair(n);
            vec![slide(e1), slide(e2), hinge(n)]
        }
        SP => {
            let (e1, e2) = pair(n);
            vec![slide(e1), slide(e2), Ball { pos: o }]
        }
        SC => vec![slide(u), Ball { pos: o }],
        PC => {
            let (e1, e2) = pair(n);
            vec![slide(e1), slide(e2), hinge(n), hinge(u)]
        }
        CR => {
            let across: [f64; 3] = unit(n).cross(&unit(u)).normalize().into();
            vec![slide(u), slide(across), hinge(u)]
        }
        SPSP => {
            let q = g.origin2.unwrap_or(ZERO);
            let (e1, e2) = pair([q[0] - o[0], q[1] - o[1], q[2] - o[2]]);
            vec![hinge(e1), hinge(e2), Ball { pos: q }]
        }
        F => vec![
            Slide { pos: ZERO, axis: X },
            Slide { pos: ZERO, axis: Y },
            Slide { pos: ZERO, axis: Z },
            Ball { pos: ZERO },
        ],
        _ => return None,
    })
}

/// A planar joint in the plane z = 0.
fn planar(kind: JointType, g: &Geometry) -> Option<Vec<Elem>> {
    use Elem::*;
    let o = g.origin.map(|p| [p[0], p[1], 0.0]).unwrap_or(ZERO);
    Some(match kind {
        JointType::R => vec![Hinge { pos: o, axis: Z }],
        JointType::P => {
            let u = g.axis.unwrap_or(X);
            vec![Slide {
                pos: o,
                axis: [u[0], u[1], 0.0],
            }]
        }
        JointType::FP => vec![
            Slide { pos: o, axis: X },
            Slide { pos: o, axis: Y },
            Hinge { pos: o, axis: Z },
        ],
        _ => return None,
    })
}

/// A spherical joint about the world origin (the fixed centre).
fn spherical(kind: JointType, g: &Geometry) -> Option<Vec<Elem>> {
    Some(match kind {
        JointType::R => vec![Elem::Hinge {
            pos: ZERO,
            axis: g.axis.unwrap_or(Z),
        }],
        JointType::FP => vec![Elem::Ball { pos: ZERO }],
        _ => return None,
    })
}

/// The motions out of a planar or spherical mechanism's own space, which its tree joints
/// already block: a cut's closure also frees them, so that it holds the rows of the joint in
/// its own space only (none of them redundant by being written in space). Planar: the slide
/// along z and the turns about x and y through the joint's point; spherical: the three slides.
pub fn out_of_space(space: Space, g: &Geometry) -> Vec<Elem> {
    match space {
        Space::Spatial => Vec::new(),
        Space::Planar => {
            let o = g.origin.map(|p| [p[0], p[1], 0.0]).unwrap_or(ZERO);
            vec![
                Elem::Slide { pos: o, axis: Z },
                Elem::Hinge { pos: o, axis: X },
                Elem::Hinge { pos: o, axis: Y },
            ]
        }
        Space::Spherical => [X, Y, Z]
            .map(|axis| Elem::Slide { pos: ZERO, axis })
            .to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::joint_model;
    use nalgebra::DMatrix;

    /// The twist of an elementary joint, `(ω; v_O)`.
    fn twists(e: &Elem) -> Vec<[f64; 6]> {
        let turn = |p: [f64; 3], u: [f64; 3]| {
            let u = unit(u);
            let m = Vector3::from(p).cross(&u);
            [u[0], u[1], u[2], m[0], m[1], m[2]]
        };
        match *e {
            Elem::Hinge { pos, axis } => vec![turn(pos, axis)],
            Elem::Slide { axis, .. } => {
                let u = unit(axis);
                vec![[0.0, 0.0, 0.0, u[0], u[1], u[2]]]
            }
            Elem::Ball { pos } => vec![turn(pos, X), turn(pos, Y), turn(pos, Z)],
            Elem::Screw { pos, axis, pitch } => {
                let mut t = turn(pos, axis);
                let u = unit(axis);
                for i in 0..3 {
                    t[3 + i] += pitch * u[i];
                }
                vec![t]
            }
        }
    }

    fn geometry() -> Geometry {
        Geometry {
            origin: Some([0.3, -1.2, 0.7]),
            origin2: Some([1.1, 0.4, -0.2]),
            axis: Some([0.2, 0.9, -0.4]),
            axis2: Some([0.9, -0.2, 0.0]),
            normal: Some([0.1, 0.2, 0.95]),
            pitch: Some(0.3),
            second: None,
        }
    }

    #[test]
    fn every_composed_kind_allows_exactly_its_twists() {
        let mut g = geometry();
        for kind in JointType::all() {
            if kind == JointType::CR {
                // The slot's normal perpendicular to the axis (only that component counts).
                g.normal = Some([0.9, -0.2, 0.0]);
            }
            let Some(elems) = elements(kind, Space::Spatial, &g) else {
                continue;
            };
            let ts: Vec<[f64; 6]> = elems.iter().flat_map(twists).collect();
            let t = DMatrix::from_fn(6, ts.len(), |r, c| ts[c][r]);
            let model = joint_model(kind, &g, Space::Spatial, 0).expect("a model");
            assert_eq!(ts.len(), model.twists.ncols(), "{kind:?}: freedoms");
            let residual = (&model.rows * &t).abs().max();
            assert!(residual < 1e-12, "{kind:?}: rows · twists = {residual}");
            assert_eq!(t.rank(1e-9), ts.len(), "{kind:?}: independent");
            g = geometry();
        }
    }
}
