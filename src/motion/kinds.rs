//! The kinematics of every joint kind, written once: the relative twists a joint allows as
//! functions of its features (points, directions, pitch), over any scalar with the ring
//! operations ([`Scalar`]). The floating-point models ([`super::twists`]) evaluate them at
//! the file's checked and normalized geometry, the exact models ([`super::exact`]) at random
//! elements of GF(p), and the position level ([`crate::position`]) builds its residuals from
//! the same features ([`features`]).
//!
//! Twists follow the conventions of [`crate::motion`]: spatial `(ω; v_O)`, planar
//! `(ω_z; v_x, v_y)` and spherical `ω`, stored in the first B of six coordinates.

use crate::exact::field::Fp;
use crate::joint::JointType;
use crate::mechanism::Space;
use nalgebra::Vector3;
use std::ops::{Add, Mul, Neg, Sub};

/// The scalars a joint's twists are written over: the ring operations, and the two steps
/// where measuring lengths matters (a floating-point direction is kept at unit length and its
/// perpendicular pair is chosen from the world axes; over a field, twist spaces are spans and
/// the pair is built from a random direction).
pub trait Scalar:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// A direction not parallel to `d`, the start of its perpendicular pair: the world axis
    /// least aligned with `d` (floating point), or `hint` (a random direction, over a field).
    fn across(d: &V3<Self>, hint: &V3<Self>) -> V3<Self>;
    /// `v` at unit length (floating point); unchanged over a field.
    fn normalize(v: V3<Self>) -> V3<Self>;
}

impl Scalar for f64 {
    const ZERO: f64 = 0.0;
    const ONE: f64 = 1.0;
    fn across(u: &V3<f64>, _: &V3<f64>) -> V3<f64> {
        let [x, y, z] = u.map(f64::abs);
        let i = if x <= y && x <= z {
            0
        } else if y <= z {
            1
        } else {
            2
        };
        unit(i)
    }
    fn normalize(v: V3<f64>) -> V3<f64> {
        // nalgebra's normalization, bit for bit what the models have always used.
        Vector3::from(v).normalize().into()
    }
}

impl Scalar for Fp {
    const ZERO: Fp = Fp::ZERO;
    const ONE: Fp = Fp::ONE;
    fn across(_: &V3<Fp>, hint: &V3<Fp>) -> V3<Fp> {
        *hint
    }
    fn normalize(v: V3<Fp>) -> V3<Fp> {
        v
    }
}

/// A 3-vector.
pub type V3<T> = [T; 3];

/// A vector of a motion space (B ≤ 6 coordinates used, the rest zero).
pub type Twist<T> = [T; 6];

/// The features of one joint: what its twists are functions of. A kind reads only some of
/// them ([`features`]); the others may hold anything.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Features<T> {
    /// The joint point `p` (the centre of S, SP, SC; the first centre of SPSP).
    pub origin: V3<T>,
    /// The second centre of SPSP.
    pub origin2: V3<T>,
    /// The axis `u` (R, P, H, C, ER, U, SC, CR; PC: the cylinder axis, perpendicular to
    /// `normal`).
    pub axis: V3<T>,
    /// The second axis of U.
    pub axis2: V3<T>,
    /// The plane normal `n` (PL, FP, SP, PC; CR: the slot's normal, only its component
    /// perpendicular to `axis` counts).
    pub normal: V3<T>,
    /// The pitch of H (length per radian).
    pub pitch: T,
    /// The direction a perpendicular pair starts from over a field ([`Scalar::across`]).
    pub hint: V3<T>,
}

impl<T: Scalar> Features<T> {
    /// Every feature zero.
    pub fn zeros() -> Features<T> {
        let z = [T::ZERO; 3];
        Features {
            origin: z,
            origin2: z,
            axis: z,
            axis2: z,
            normal: z,
            pitch: T::ZERO,
            hint: z,
        }
    }
}

/// One feature of a joint, named as its geometry field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    /// `origin`.
    Origin,
    /// `origin2`.
    Origin2,
    /// `axis`.
    Axis,
    /// `axis2`.
    Axis2,
    /// `normal`.
    Normal,
    /// `pitch`.
    Pitch,
}

/// The features the twists of `kind` read in `space` (`None`: the kind has no model there,
/// count-only kinds and kinds invalid in the space). An optional feature (FP's `origin` and
/// `normal`, PL's `origin`) has a default: the world origin, the z axis.
pub fn features(kind: JointType, space: Space) -> Option<&'static [Feature]> {
    use Feature::*;
    use JointType::*;
    Some(match (space, kind) {
        (Space::Spatial, R | C | ER | SC) => &[Origin, Axis],
        (Space::Spatial, P) | (Space::Spherical, R) | (Space::Planar, P) => &[Axis],
        (Space::Spatial, H) => &[Origin, Axis, Pitch],
        (Space::Spatial, U) => &[Origin, Axis, Axis2],
        (Space::Spatial, S) | (Space::Planar, R | FP) => &[Origin],
        (Space::Spatial, PL | FP | SP) => &[Origin, Normal],
        (Space::Spatial, PC | CR) => &[Origin, Axis, Normal],
        (Space::Spatial, SPSP) => &[Origin, Origin2],
        (Space::Spatial, F) | (Space::Spherical, FP) => &[],
        _ => return None,
    })
}

/// Whether `feature` of `kind` may be left out: PL's and FP's `origin` (the world origin) and
/// FP's `normal` (the z axis).
pub fn optional(kind: JointType, feature: Feature) -> bool {
    matches!(
        (kind, feature),
        (JointType::PL | JointType::FP, Feature::Origin) | (JointType::FP, Feature::Normal)
    )
}

/// A joint's allowed twists: listed, or the annihilator of one line (SPSP, whose one
/// constraint is a force along the line of centres; each scalar takes the annihilator its
/// own way).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Allowed<T> {
    /// The twists, `len` of them, in driven-DOF order.
    Listed([Twist<T>; 6], usize),
    /// The twists are the annihilator of this line (moment about the origin first).
    AnnihilatorOf(Twist<T>),
}

impl<T: Scalar> Allowed<T> {
    fn of(list: &[Twist<T>]) -> Allowed<T> {
        let mut out = [[T::ZERO; 6]; 6];
        out[..list.len()].copy_from_slice(list);
        Allowed::Listed(out, list.len())
    }
}

/// `a × b`, in nalgebra's order of operations.
pub fn cross<T: Scalar>(a: &V3<T>, b: &V3<T>) -> V3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// World axis `i`.
pub fn unit<T: Scalar>(i: usize) -> V3<T> {
    let mut v = [T::ZERO; 3];
    v[i] = T::ONE;
    v
}

/// The rotation about `u` through `p`: `(u; p × u)`.
pub fn turn<T: Scalar>(u: &V3<T>, p: &V3<T>) -> Twist<T> {
    let m = cross(p, u);
    [u[0], u[1], u[2], m[0], m[1], m[2]]
}

/// The translation along `u`: `(0; u)`.
pub fn slide<T: Scalar>(u: &V3<T>) -> Twist<T> {
    let z = T::ZERO;
    [z, z, z, u[0], u[1], u[2]]
}

/// The line through `q` along `d` as a wrench `(q × d; d)` (a pure force).
pub fn line<T: Scalar>(q: &V3<T>, d: &V3<T>) -> Twist<T> {
    let m = cross(q, d);
    [m[0], m[1], m[2], d[0], d[1], d[2]]
}

/// A vector of a 3-dimensional motion space.
pub fn short<T: Scalar>(a: T, b: T, c: T) -> Twist<T> {
    let z = T::ZERO;
    [a, b, c, z, z, z]
}

/// Two directions perpendicular to `d` and to each other: `e1 = normalize(d × a)` with `a`
/// [`Scalar::across`] `d`, `e2 = d × e1` (unit when `d` is).
pub fn perpendicular_pair<T: Scalar>(d: &V3<T>, hint: &V3<T>) -> (V3<T>, V3<T>) {
    let e1 = T::normalize(cross(d, &T::across(d, hint)));
    let e2 = cross(d, &e1);
    (e1, e2)
}

/// The rotations about the world x, y, z axes through `c` (the turns of a ball).
fn world_turns<T: Scalar>(c: &V3<T>) -> [Twist<T>; 3] {
    [0, 1, 2].map(|i| turn(&unit(i), c))
}

/// The allowed twists of `kind` in `space` at features `f`, in the driven-DOF order of
/// `format.md` (translations before rotations; C slide then turn; PL the two in-plane slides
/// then the turn; U `axis` then `axis2`; S turns about world x, y, z through the centre; F/FP
/// translations then rotations). `None` when the kind has no model there ([`features`]).
pub fn allowed<T: Scalar>(kind: JointType, space: Space, f: &Features<T>) -> Option<Allowed<T>> {
    use JointType::*;
    let (p, u) = (&f.origin, &f.axis);
    Some(match space {
        Space::Spatial => return spatial(kind, f),
        Space::Planar => {
            let (o, z) = (T::ONE, T::ZERO);
            match kind {
                R => Allowed::of(&[short(o, p[1], -p[0])]),
                P => Allowed::of(&[short(z, u[0], u[1])]),
                FP => Allowed::of(&[short(z, o, z), short(z, z, o), short(o, p[1], -p[0])]),
                _ => return None,
            }
        }
        Space::Spherical => match kind {
            R => Allowed::of(&[short(u[0], u[1], u[2])]),
            FP => Allowed::of(&[0, 1, 2].map(|i| {
                let e = unit::<T>(i);
                short(e[0], e[1], e[2])
            })),
            _ => return None,
        },
    })
}

/// [`allowed`] in a spatial mechanism.
fn spatial<T: Scalar>(kind: JointType, f: &Features<T>) -> Option<Allowed<T>> {
    use JointType::*;
    let (p, u, n) = (&f.origin, &f.axis, &f.normal);
    let pair = |d: &V3<T>| perpendicular_pair(d, &f.hint);
    Some(match kind {
        R => Allowed::of(&[turn(u, p)]),
        P => Allowed::of(&[slide(u)]),
        H => {
            let m = cross(p, u);
            let h = f.pitch;
            let t = [
                u[0],
                u[1],
                u[2],
                m[0] + u[0] * h,
                m[1] + u[1] * h,
                m[2] + u[2] * h,
            ];
            Allowed::of(&[t])
        }
        C => Allowed::of(&[slide(u), turn(u, p)]),
        ER => {
            // A ball whose turn about `axis` is blocked.
            let (e1, e2) = pair(u);
            Allowed::of(&[turn(&e1, p), turn(&e2, p)])
        }
        U => Allowed::of(&[turn(u, p), turn(&f.axis2, p)]),
        S => Allowed::of(&world_turns(p)),
        PL | FP => {
            let (e1, e2) = pair(n);
            Allowed::of(&[slide(&e1), slide(&e2), turn(n, p)])
        }
        SP => {
            // Sphere (second body) on a plane (first body): slides in the plane, then the
            // three turns about the centre.
            let (e1, e2) = pair(n);
            let [t1, t2, t3] = world_turns(p);
            Allowed::of(&[slide(&e1), slide(&e2), t1, t2, t3])
        }
        SC => {
            // Sphere centre kept on the cylinder axis: the slide, then the three turns.
            let [t1, t2, t3] = world_turns(p);
            Allowed::of(&[slide(u), t1, t2, t3])
        }
        PC => {
            // Cylinder on a plane: two slides in the plane, turn about the normal, turn
            // about the cylinder axis (in the plane).
            let (e1, e2) = pair(n);
            Allowed::of(&[slide(&e1), slide(&e2), turn(n, p), turn(u, p)])
        }
        CR => {
            // Cylinder in a slot: slide along the axis, slide across the slot, turn about
            // the axis.
            Allowed::of(&[slide(u), slide(&cross(n, u)), turn(u, p)])
        }
        SPSP => {
            let q = &f.origin2;
            let d = T::normalize([q[0] - p[0], q[1] - p[1], q[2] - p[2]]);
            Allowed::AnnihilatorOf(line(p, &d))
        }
        F => {
            let [s1, s2, s3] = [0, 1, 2].map(|i| slide(&unit(i)));
            let [t1, t2, t3] = world_turns(&[T::ZERO; 3]);
            Allowed::of(&[s1, s2, s3, t1, t2, t3])
        }
        _ => return None,
    })
}
