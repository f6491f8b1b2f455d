//! A joint's allowed twists at the file's (or a random) geometry: the geometry's fields read
//! and checked for each kind, then the kind's twists.

use super::MotionError;
use super::gram::{Vb, Vecs, complement};
use super::is_contact;
use crate::joint::JointType;
use crate::mechanism::{Geometry, Space};
use nalgebra::Vector3;

pub(super) fn v3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

pub(super) fn unit(
    kind: JointType,
    field: &'static str,
    a: [f64; 3],
) -> Result<Vector3<f64>, MotionError> {
    let v = v3(a);
    let n = v.norm();
    if !n.is_finite() || n <= 1e-300 {
        return Err(MotionError::ZeroVector {
            kind: kind.code(),
            field,
        });
    }
    Ok(v / n)
}

pub(super) fn need<T: Copy>(
    kind: JointType,
    field: &'static str,
    value: Option<T>,
) -> Result<T, MotionError> {
    value.ok_or(MotionError::MissingField {
        kind: kind.code(),
        field,
    })
}

/// Two unit vectors perpendicular to unit `u` and to each other, chosen deterministically:
/// `e1 = normalize(u × a)` with `a` the world axis least aligned with `u`, `e2 = u × e1`.
pub fn perpendicular_pair(u: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let a = if u.x.abs() <= u.y.abs() && u.x.abs() <= u.z.abs() {
        Vector3::x()
    } else if u.y.abs() <= u.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let e1 = u.cross(&a).normalize();
    let e2 = u.cross(&e1);
    (e1, e2)
}

pub(super) fn spatial_rot(u: &Vector3<f64>, p: &Vector3<f64>) -> Vb {
    let m = p.cross(u);
    [u.x, u.y, u.z, m.x, m.y, m.z]
}

pub(super) fn spatial_trans(u: &Vector3<f64>) -> Vb {
    [0.0, 0.0, 0.0, u.x, u.y, u.z]
}

/// A vector of a 3-dimensional motion space (the rest zero).
pub(super) fn v3b(a: f64, b: f64, c: f64) -> Vb {
    [a, b, c, 0.0, 0.0, 0.0]
}

/// The rotations about the world x, y, z axes through `c` (the turns of a ball).
pub(super) fn world_turns(c: &Vector3<f64>) -> [Vb; 3] {
    [Vector3::x(), Vector3::y(), Vector3::z()].map(|e| spatial_rot(&e, c))
}

/// The unit component of `v` perpendicular to unit `n` (geometry written to a few decimals is
/// not exactly perpendicular); an error when `v` is (nearly) parallel to `n`.
pub(super) fn in_plane(
    kind: JointType,
    v: &Vector3<f64>,
    n: &Vector3<f64>,
    reason: &'static str,
) -> Result<Vector3<f64>, MotionError> {
    let w = v - n * n.dot(v);
    if w.norm() < 1e-3 {
        return Err(MotionError::Degenerate {
            kind: kind.code(),
            reason,
        });
    }
    Ok(w / w.norm())
}

/// All allowed twists of `kind` in driven-DOF order (before removing driven ones).
#[inline]
pub(super) fn full_twists(
    kind: JointType,
    g: &Geometry,
    space: Space,
) -> Result<Vecs, MotionError> {
    Ok(match twist_spec(kind, g, space)? {
        TwistSpec::Listed(full) => full,
        TwistSpec::AnnihilatorOf(line) => complement::<6>(&[line]),
    })
}

/// A joint's allowed twists ([`full_twists`]) before any Gram-Schmidt: listed, or the
/// annihilator of one line (SPSP, spatial only), which [`batch`] builds in lanes.
#[allow(clippy::large_enum_variant)] // On the stack, returned once per joint: no box.
pub(super) enum TwistSpec {
    /// The twists themselves.
    Listed(Vecs),
    /// The twists are [`complement`] of this one line.
    AnnihilatorOf(Vb),
}

/// [`full_twists`] up to the Gram-Schmidt it may need.
#[inline]
pub(super) fn twist_spec(
    kind: JointType,
    g: &Geometry,
    space: Space,
) -> Result<TwistSpec, MotionError> {
    use JointType::*;
    let code = kind.code();
    let origin = |g: &Geometry| need(kind, "origin", g.origin).map(v3);
    let axis = |g: &Geometry| need(kind, "axis", g.axis).and_then(|a| unit(kind, "axis", a));
    let normal =
        |g: &Geometry| need(kind, "normal", g.normal).and_then(|a| unit(kind, "normal", a));
    match space {
        Space::Spatial => Ok(TwistSpec::Listed(match kind {
            R => Vecs::of(&[spatial_rot(&axis(g)?, &origin(g)?)]),
            P => Vecs::of(&[spatial_trans(&axis(g)?)]),
            H => {
                let (u, p) = (axis(g)?, origin(g)?);
                let h = need(kind, "pitch", g.pitch)?;
                if !h.is_finite() {
                    return Err(MotionError::ZeroVector {
                        kind: code,
                        field: "pitch",
                    });
                }
                let m = p.cross(&u) + u * h;
                Vecs::of(&[[u.x, u.y, u.z, m.x, m.y, m.z]])
            }
            C => {
                let (u, p) = (axis(g)?, origin(g)?);
                Vecs::of(&[spatial_trans(&u), spatial_rot(&u, &p)])
            }
            ER => {
                let (u, p) = (axis(g)?, origin(g)?);
                let (e1, e2) = perpendicular_pair(&u);
                Vecs::of(&[spatial_rot(&e1, &p), spatial_rot(&e2, &p)])
            }
            U => {
                let (u, p) = (axis(g)?, origin(g)?);
                let u2 = unit(kind, "axis2", need(kind, "axis2", g.axis2)?)?;
                Vecs::of(&[spatial_rot(&u, &p), spatial_rot(&u2, &p)])
            }
            S => Vecs::of(&world_turns(&origin(g)?)),
            PL | FP => {
                let n = match (kind, g.normal) {
                    (_, Some(n)) => unit(kind, "normal", n)?,
                    (FP, None) => Vector3::z(),
                    _ => need(kind, "normal", g.normal).map(v3)?,
                };
                let p = g.origin.map(v3).unwrap_or_else(Vector3::zeros);
                let (e1, e2) = perpendicular_pair(&n);
                Vecs::of(&[spatial_trans(&e1), spatial_trans(&e2), spatial_rot(&n, &p)])
            }
            SP => {
                // Sphere (second body) on a plane (first body): slides in the plane, then the
                // three turns about the centre.
                let (c, n) = (origin(g)?, normal(g)?);
                let (e1, e2) = perpendicular_pair(&n);
                let mut out = Vecs::of(&[spatial_trans(&e1), spatial_trans(&e2)]);
                world_turns(&c).into_iter().for_each(|t| out.push(t));
                out
            }
            SC => {
                // Sphere centre kept on the cylinder axis: the slide, then the three turns.
                let (c, u) = (origin(g)?, axis(g)?);
                let mut out = Vecs::of(&[spatial_trans(&u)]);
                world_turns(&c).into_iter().for_each(|t| out.push(t));
                out
            }
            PC => {
                // Cylinder on a plane: two slides in the plane, turn about the normal, turn
                // about the cylinder axis (its component in the plane).
                let (p, u, n) = (origin(g)?, axis(g)?, normal(g)?);
                let u = in_plane(kind, &u, &n, "`axis` must not be parallel to `normal`")?;
                let (e1, e2) = perpendicular_pair(&n);
                Vecs::of(&[
                    spatial_trans(&e1),
                    spatial_trans(&e2),
                    spatial_rot(&n, &p),
                    spatial_rot(&u, &p),
                ])
            }
            CR => {
                // Cylinder in a slot: slide along the axis, slide across the slot, turn about
                // the axis.
                let (p, u, n) = (origin(g)?, axis(g)?, normal(g)?);
                let n = in_plane(kind, &n, &u, "`normal` must not be parallel to `axis`")?;
                Vecs::of(&[
                    spatial_trans(&u),
                    spatial_trans(&n.cross(&u)),
                    spatial_rot(&u, &p),
                ])
            }
            SPSP => {
                // One force along the line of centres; the allowed motions are its annihilator.
                let c1 = origin(g)?;
                let c2 = v3(need(kind, "origin2", g.origin2)?);
                let d = c2 - c1;
                if d.norm().is_nan() || d.norm() <= 1e-12 {
                    return Err(MotionError::Degenerate {
                        kind: code,
                        reason: "`origin` and `origin2` (the two centres) coincide",
                    });
                }
                let d = d / d.norm();
                let m = c1.cross(&d);
                return Ok(TwistSpec::AnnihilatorOf([m.x, m.y, m.z, d.x, d.y, d.z]));
            }
            F => {
                let mut out = Vecs::EMPTY;
                for e in [Vector3::x(), Vector3::y(), Vector3::z()] {
                    out.push(spatial_trans(&e));
                }
                for e in [Vector3::x(), Vector3::y(), Vector3::z()] {
                    out.push(spatial_rot(&e, &Vector3::zeros()));
                }
                out
            }
            _ => Vecs::EMPTY,
        })),
        Space::Planar => Ok(TwistSpec::Listed(match kind {
            R => {
                let p = origin(g)?;
                Vecs::of(&[v3b(1.0, p.y, -p.x)])
            }
            P => {
                let a = need(kind, "axis", g.axis)?;
                let u = unit(kind, "axis", [a[0], a[1], 0.0])?;
                Vecs::of(&[v3b(0.0, u.x, u.y)])
            }
            FP => {
                let p = g.origin.map(v3).unwrap_or_else(Vector3::zeros);
                Vecs::of(&[v3b(0.0, 1.0, 0.0), v3b(0.0, 0.0, 1.0), v3b(1.0, p.y, -p.x)])
            }
            k if is_contact(k) => Vecs::EMPTY,
            _ => {
                return Err(MotionError::InvalidInSpace {
                    kind: code,
                    space: "planar",
                });
            }
        })),
        Space::Spherical => Ok(TwistSpec::Listed(match kind {
            R => {
                let u = axis(g)?;
                Vecs::of(&[v3b(u.x, u.y, u.z)])
            }
            FP => Vecs::of(&[v3b(1.0, 0.0, 0.0), v3b(0.0, 1.0, 0.0), v3b(0.0, 0.0, 1.0)]),
            k if is_contact(k) => Vecs::EMPTY,
            _ => {
                return Err(MotionError::InvalidInSpace {
                    kind: code,
                    space: "spherical",
                });
            }
        })),
    }
}
