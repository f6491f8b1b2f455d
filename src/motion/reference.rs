//! The joint models as they were before their specialisation (runtime motion-space
//! dimension, `complement_of` recomputing its squared norms): the reference the tests compare
//! the current code with, bit for bit.

#![allow(clippy::needless_range_loop)]

use super::gram::{CANDIDATE_GAP, MAX_B, Vb, Vecs};
use super::model::{MIX_SALT, StackModel, mix_seed, random_unit};
use super::twists::{in_plane, need, unit, v3};
use super::{MotionError, is_contact, modelled};
use crate::joint::JointType;
use crate::mechanism::{Geometry, Space};
use crate::rng::SplitMix64;
use nalgebra::Vector3;

pub(crate) fn dot(a: &Vb, b: &Vb, n: usize) -> f64 {
    let mut r = 0.0;
    for k in 0..n {
        r += a[k] * b[k];
    }
    r
}

pub(crate) fn norm(a: &Vb, n: usize) -> f64 {
    dot(a, a, n).sqrt()
}

/// `v -= (q · v) q` twice over the basis (re-orthogonalization).
pub(crate) fn project_out(v: &mut Vb, basis: &[Vb], n: usize) {
    for _ in 0..2 {
        for q in basis {
            let d = dot(q, v, n);
            for k in 0..n {
                v[k] -= q[k] * d;
            }
        }
    }
}

pub(crate) fn normalized(v: &Vb, n: usize) -> Vb {
    let len = norm(v, n);
    let mut out = [0.0; MAX_B];
    for k in 0..n {
        out[k] = v[k] / len;
    }
    out
}

/// Orthonormal basis of the orthogonal complement of the span of `cols` (vectors of the
/// `b`-dimensional motion space, independent): greedy Gram-Schmidt on the unit vectors,
/// always taking the one with the largest residual, so no threshold is involved.
pub(crate) fn complement(cols: &[Vb], b: usize) -> Vecs {
    complement_of(orthonormal(cols, b), b)
}

/// [`complement`] of the span of `basis`, the output of [`orthonormal`] (a caller that has
/// it already need not compute it again).
fn complement_of(mut basis: Vecs, b: usize) -> Vecs {
    let first_new = basis.len();
    while basis.len() < b {
        // The residual of unit vector `e_i` has squared norm `1 − Σ_q q_i²` (the basis is
        // orthonormal to rounding, far below `CANDIDATE_GAP`): only the unit vectors within
        // the gap of the largest can have the largest computed residual, so only they are
        // projected, each exactly as [`project_out`] does. The vector taken is the one the
        // projection of every unit vector takes, bit for bit (the first largest).
        let mut sq = [0.0; MAX_B];
        for q in basis.as_slice() {
            for i in 0..b {
                sq[i] += q[i] * q[i];
            }
        }
        let mut top = f64::NEG_INFINITY;
        let mut finite = true;
        for s in sq.iter().take(b) {
            finite &= s.is_finite();
            top = top.max(1.0 - s);
        }
        let mut best: Option<(Vb, f64)> = None;
        for (i, s) in sq.iter().enumerate().take(b) {
            if finite && 1.0 - s < top - CANDIDATE_GAP {
                continue;
            }
            let mut v = [0.0; MAX_B];
            v[i] = 1.0;
            project_out(&mut v, basis.as_slice(), b);
            let n = norm(&v, b);
            if best.is_none_or(|(_, w)| n > w) {
                best = Some((v, n));
            }
        }
        let Some((v, _)) = best else {
            break;
        };
        basis.push(normalized(&v, b));
    }
    Vecs::of(&basis.as_slice()[first_new..])
}

/// Orthonormalize `cols` (modified Gram-Schmidt, twice); vectors that vanish are dropped.
pub(crate) fn orthonormal(cols: &[Vb], b: usize) -> Vecs {
    // The norm of all of them: the dot products summed in order.
    let mut sq = 0.0;
    for v in cols {
        sq += dot(v, v, b);
    }
    let scale = sq.sqrt().max(1e-300);
    let mut out = Vecs::EMPTY;
    for &c in cols {
        let mut v = c;
        project_out(&mut v, out.as_slice(), b);
        if norm(&v, b) > 1e-10 * scale {
            out.push(normalized(&v, b));
        }
    }
    out
}

/// The twists a joint without named DOF keeps once `driven` of its `all` allowed twists are
/// fixed: `all` itself when nothing is driven (bit for bit), else an orthonormal basis of
/// `k − driven` random combinations of them (`k = all.len()`), the coefficients uniform in
/// [−1, 1) from a generator seeded by `seed` (the geometry's bits, so the same geometry
/// always gives the same model). This is `all` mixed by a random invertible `k × k` matrix
/// with its first `driven` combinations dropped: a generic subspace of the allowed motions,
/// where dropping the first vectors of `all` (a basis built by pivoting on unit vectors)
/// left a subspace fixed by the construction, degenerate at a fixed fraction of draws.
pub(crate) fn kept_twists(all: &Vecs, driven: usize, seed: u64, b: usize) -> Vecs {
    let k = all.len();
    if driven == 0 {
        return *all;
    }
    if driven >= k {
        return Vecs::EMPTY;
    }
    let mut rng = SplitMix64::new(seed ^ MIX_SALT);
    // Random combinations are independent except on a set of measure zero; a few more draws
    // cover a rounding accident, and the fixed convention is the last resort.
    for _ in 0..4 {
        let mut mixed = Vecs::EMPTY;
        for _ in 0..k - driven {
            let mut v = [0.0; MAX_B];
            for t in all.as_slice() {
                let c = rng.next_signed();
                for (x, y) in v.iter_mut().zip(t).take(b) {
                    *x += c * y;
                }
            }
            mixed.push(v);
        }
        let kept = orthonormal(mixed.as_slice(), b);
        if kept.len() == k - driven && well_conditioned(mixed.as_slice(), b) {
            return kept;
        }
    }
    Vecs::of(&all.as_slice()[driven..])
}

/// Whether the vectors are far from dependent: each keeps a residual of at least 1e-3 of its
/// norm after projecting out the ones before it.
fn well_conditioned(vs: &[Vb], b: usize) -> bool {
    let mut basis = Vecs::EMPTY;
    for v in vs {
        let n = norm(v, b);
        let mut r = *v;
        project_out(&mut r, basis.as_slice(), b);
        let rn = norm(&r, b);
        if rn.partial_cmp(&(1e-3 * n)) != Some(std::cmp::Ordering::Greater) {
            return false;
        }
        basis.push(normalized(&r, b));
    }
    true
}

/// The generic contact model: `B − k` lines.
pub(crate) fn contact_rows(kind: JointType, g: &Geometry, space: Space) -> Vecs {
    let b = space.b() as usize;
    let k = (kind.grade() as usize).min(b);
    let mut rng = SplitMix64::new(mix_seed(g));
    let base = g.origin.map(v3).unwrap_or_else(Vector3::zeros);
    let mut rows = Vecs::EMPTY;
    for i in 0..b - k {
        let (q, mut d) = if i == 0 {
            (
                base,
                g.axis.map(v3).unwrap_or_else(|| random_unit(&mut rng)),
            )
        } else {
            (
                base + Vector3::new(rng.next_signed(), rng.next_signed(), rng.next_signed()),
                random_unit(&mut rng),
            )
        };
        if d.norm().partial_cmp(&1e-12) != Some(std::cmp::Ordering::Greater) {
            d = random_unit(&mut rng);
        }
        let row = match space {
            Space::Spatial => {
                let m = q.cross(&d);
                [m.x, m.y, m.z, d.x, d.y, d.z]
            }
            Space::Planar => {
                let d2 = if d.x.abs() + d.y.abs() < 1e-9 {
                    Vector3::new(1.0, 0.0, 0.0)
                } else {
                    d
                };
                v3b(q.x * d2.y - q.y * d2.x, d2.x, d2.y)
            }
            Space::Spherical => {
                let m = q.cross(&d);
                if m.norm() > 1e-9 {
                    v3b(m.x, m.y, m.z)
                } else {
                    let r = random_unit(&mut rng);
                    v3b(r.x, r.y, r.z)
                }
            }
        };
        rows.push(row);
    }
    // Orthonormal rows spanning the same lines; random lines are independent in practice, and
    // a dependent draw only yields fewer rows (never a panic).
    orthonormal(rows.as_slice(), b)
}

/// All allowed twists of `kind` in driven-DOF order (before removing driven ones).
pub(crate) fn full_twists(
    kind: JointType,
    g: &Geometry,
    space: Space,
) -> Result<Vecs, MotionError> {
    use JointType::*;
    let code = kind.code();
    let origin = |g: &Geometry| need(kind, "origin", g.origin).map(v3);
    let axis = |g: &Geometry| need(kind, "axis", g.axis).and_then(|a| unit(kind, "axis", a));
    let normal =
        |g: &Geometry| need(kind, "normal", g.normal).and_then(|a| unit(kind, "normal", a));
    match space {
        Space::Spatial => Ok(match kind {
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
                complement(&[[m.x, m.y, m.z, d.x, d.y, d.z]], 6)
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
        }),
        Space::Planar => Ok(match kind {
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
        }),
        Space::Spherical => Ok(match kind {
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
        }),
    }
}

/// `stack_model` as it was.
pub(crate) fn stack_model(
    kind: JointType,
    g: &Geometry,
    space: Space,
    driven: u32,
) -> Result<StackModel, MotionError> {
    let b = space.b() as usize;
    let grade = kind.grade() as u32;
    if grade as usize > b {
        return Err(MotionError::InvalidInSpace {
            kind: kind.code(),
            space: space.name(),
        });
    }
    if driven > grade {
        return Err(MotionError::DrivenAboveGrade {
            kind: kind.code(),
            driven,
            grade,
        });
    }
    if !modelled(kind, space) {
        let rows = contact_rows(kind, g, space);
        if rows.len() != b - grade as usize {
            return Err(MotionError::Degenerate {
                kind: kind.code(),
                reason: "the contact lines are dependent",
            });
        }
        let all = complement(rows.as_slice(), b);
        let twists = kept_twists(&all, driven as usize, mix_seed(g), b);
        let rows = complement(twists.as_slice(), b);
        return Ok(StackModel { b, rows, twists });
    }
    let full = full_twists(kind, g, space)?;
    let basis = orthonormal(full.as_slice(), b);
    if basis.len() != full.len() {
        return Err(MotionError::Degenerate {
            kind: kind.code(),
            reason: "its motion directions are dependent (parallel axes?)",
        });
    }
    let twists = if kind == JointType::SPSP {
        // Its twists are a basis of the annihilator of one line, ordered by pivoting: no DOF
        // of it is named (format.md), so a driven one is a generic direction.
        kept_twists(&full, driven as usize, mix_seed(g), b)
    } else {
        Vecs::of(full.as_slice().get(driven as usize..).unwrap_or(&[]))
    };
    // Nothing driven: the twists are `full`, whose orthonormal basis is at hand.
    let rows = if driven == 0 {
        complement_of(basis, b)
    } else {
        complement(twists.as_slice(), b)
    };
    Ok(StackModel { b, rows, twists })
}

/// A model that cannot fail: the generic contact model with the joint's grade (capped at B)
/// and driven DOF (capped at the grade). Used by [`realize`] for joints no model fits.
pub(crate) fn fallback_model(kind: JointType, space: Space, driven: u32, seed: u64) -> StackModel {
    let b = space.b() as usize;
    let k = (kind.grade() as usize).min(b);
    let mut rng = SplitMix64::new(seed);
    let mut rows = Vecs::EMPTY;
    for _ in 0..b - k {
        let mut r = [0.0; MAX_B];
        for x in r.iter_mut().take(b) {
            *x = rng.next_signed();
        }
        rows.push(r);
    }
    let rows = orthonormal(rows.as_slice(), b);
    let all = complement(rows.as_slice(), b);
    let twists = kept_twists(&all, driven as usize, seed, b);
    let rows = complement(twists.as_slice(), b);
    StackModel { b, rows, twists }
}

/// Two unit vectors perpendicular to unit `u` and to each other, chosen deterministically:
/// `e1 = normalize(u × a)` with `a` the world axis least aligned with `u`, `e2 = u × e1`.
pub(crate) fn perpendicular_pair(u: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
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
