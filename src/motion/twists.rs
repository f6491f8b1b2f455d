//! A joint's allowed twists at the file's (or a random) geometry: the geometry's fields read
//! and checked for each kind, then the kind's twists.

use super::MotionError;
use super::gram::{Vb, Vecs, complement};
use super::is_contact;
use super::kinds::{self, Allowed, Features};
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

/// Two unit vectors perpendicular to unit `u` and to each other, chosen deterministically:
/// `e1 = normalize(u × a)` with `a` the world axis least aligned with `u`, `e2 = u × e1`
/// ([`kinds::perpendicular_pair`] in floating point).
pub fn perpendicular_pair(u: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let (e1, e2) = kinds::perpendicular_pair(&(*u).into(), &[0.0; 3]);
    (e1.into(), e2.into())
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
/// annihilator of one line (SPSP, spatial only), which [`super::batch`] builds in lanes.
#[allow(clippy::large_enum_variant)] // On the stack, returned once per joint: no box.
pub(super) enum TwistSpec {
    /// The twists themselves.
    Listed(Vecs),
    /// The twists are [`complement`] of this one line.
    AnnihilatorOf(Vb),
}

/// [`full_twists`] up to the Gram-Schmidt it may need: [`kinds::allowed`] at the features
/// [`file_features`] reads from `g` (no twist for a count-only kind).
#[inline]
pub(super) fn twist_spec(
    kind: JointType,
    g: &Geometry,
    space: Space,
) -> Result<TwistSpec, MotionError> {
    let spec = file_features(kind, g, space)?.and_then(|f| kinds::allowed(kind, space, &f));
    Ok(match spec {
        Some(Allowed::Listed(list, n)) => TwistSpec::Listed(Vecs::from_parts(list, n)),
        Some(Allowed::AnnihilatorOf(line)) => TwistSpec::AnnihilatorOf(line),
        None => TwistSpec::Listed(Vecs::EMPTY),
    })
}

/// The features of a joint of `kind` read from the file's geometry `g`, in the order its
/// fields are checked (the first missing or degenerate one is the error): directions made
/// unit, PC's axis and CR's normal made perpendicular to the other direction, optional
/// fields defaulted ([`kinds::features`]). `None` for a count-only kind; an error for a kind
/// invalid in `space`.
fn file_features(
    kind: JointType,
    g: &Geometry,
    space: Space,
) -> Result<Option<Features<f64>>, MotionError> {
    use JointType::*;
    let origin = || need(kind, "origin", g.origin).map(v3);
    let axis = || need(kind, "axis", g.axis).and_then(|a| unit(kind, "axis", a));
    let normal = || need(kind, "normal", g.normal).and_then(|a| unit(kind, "normal", a));
    let or_zero = |p: Option<[f64; 3]>| p.map(v3).unwrap_or_else(Vector3::zeros);
    let z = Vector3::zeros();
    let mut f = Features::zeros();
    let mut set = |p: Vector3<f64>, u: Vector3<f64>, n: Vector3<f64>| {
        (f.origin, f.axis, f.normal) = (p.into(), u.into(), n.into());
    };
    match (space, kind) {
        (Space::Spatial, R | C | ER) => {
            let u = axis()?;
            set(origin()?, u, z);
        }
        (Space::Spatial, P) | (Space::Spherical, R) => set(z, axis()?, z),
        (Space::Spatial, H) => {
            let (u, p) = (axis()?, origin()?);
            f.pitch = pitch(kind, g)?;
            set(p, u, z);
        }
        (Space::Spatial, U) => {
            let (u, p) = (axis()?, origin()?);
            let u2 = unit(kind, "axis2", need(kind, "axis2", g.axis2)?)?;
            set(p, u, z);
            f.axis2 = u2.into();
        }
        (Space::Spatial, S) => set(origin()?, z, z),
        (Space::Spatial, PL | FP) => {
            let n = match (kind, g.normal) {
                (_, Some(n)) => unit(kind, "normal", n)?,
                (FP, None) => Vector3::z(),
                _ => need(kind, "normal", g.normal).map(v3)?,
            };
            set(or_zero(g.origin), z, n);
        }
        (Space::Spatial, SP) => {
            let p = origin()?;
            set(p, z, normal()?);
        }
        (Space::Spatial, SC) => {
            let p = origin()?;
            set(p, axis()?, z);
        }
        (Space::Spatial, PC | CR) => {
            let (p, u, n) = (origin()?, axis()?, normal()?);
            if kind == PC {
                let u = in_plane(kind, &u, &n, "`axis` must not be parallel to `normal`")?;
                set(p, u, n);
            } else {
                let n = in_plane(kind, &n, &u, "`normal` must not be parallel to `axis`")?;
                set(p, u, n);
            }
        }
        (Space::Spatial, SPSP) => {
            let c1 = origin()?;
            let c2 = second_centre(kind, g, &c1)?;
            set(c1, z, z);
            f.origin2 = c2.into();
        }
        (Space::Spatial, F) | (Space::Spherical, FP) => {}
        (Space::Spatial, _) => return Ok(None),
        (Space::Planar, R) => set(origin()?, z, z),
        (Space::Planar, P) => {
            let a = need(kind, "axis", g.axis)?;
            set(z, unit(kind, "axis", [a[0], a[1], 0.0])?, z);
        }
        (Space::Planar, FP) => set(or_zero(g.origin), z, z),
        (_, k) if is_contact(k) => return Ok(None),
        _ => {
            return Err(MotionError::InvalidInSpace {
                kind: kind.code(),
                space: space.name(),
            });
        }
    }
    Ok(Some(f))
}

/// The pitch of an H, finite.
fn pitch(kind: JointType, g: &Geometry) -> Result<f64, MotionError> {
    let h = need(kind, "pitch", g.pitch)?;
    if !h.is_finite() {
        return Err(MotionError::ZeroVector {
            kind: kind.code(),
            field: "pitch",
        });
    }
    Ok(h)
}

/// The second centre of an SPSP, apart from the first `c1`.
fn second_centre(
    kind: JointType,
    g: &Geometry,
    c1: &Vector3<f64>,
) -> Result<Vector3<f64>, MotionError> {
    let c2 = v3(need(kind, "origin2", g.origin2)?);
    let d = c2 - c1;
    if d.norm().is_nan() || d.norm() <= 1e-12 {
        return Err(MotionError::Degenerate {
            kind: kind.code(),
            reason: "`origin` and `origin2` (the two centres) coincide",
        });
    }
    Ok(c2)
}
