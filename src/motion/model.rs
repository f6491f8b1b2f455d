//! One joint's model: its constraint rows and the twists it keeps once its driven DOF are
//! fixed, on the stack ([`StackModel`]) or as matrices ([`JointModel`]).

use super::gram::{
    MAX_B, Vecs, as_rows, columns, complement, complement_of, orthonormal,
    orthonormal_if_well_conditioned,
};
use super::kinds::{line, short};
use super::twists::{full_twists, v3};
use super::{JointModel, MotionError, modelled};
use crate::joint::JointType;
use crate::mechanism::{Geometry, Space};
use crate::rng::SplitMix64;
use nalgebra::{DMatrix, Vector3};

pub(super) fn mix_seed(g: &Geometry) -> u64 {
    let mut h: u64 = 0x5EED_C0A7_AC70_0001;
    let mut eat = |x: f64| {
        h = (h ^ x.to_bits())
            .wrapping_mul(0x100_0000_01B3)
            .rotate_left(17);
    };
    for a in [g.origin, g.axis, g.axis2, g.normal].into_iter().flatten() {
        a.iter().for_each(|&x| eat(x));
    }
    if let Some(p) = g.pitch {
        eat(p);
    }
    h
}

pub(super) fn random_unit(rng: &mut SplitMix64) -> Vector3<f64> {
    loop {
        let v = Vector3::new(rng.next_signed(), rng.next_signed(), rng.next_signed());
        let n = v.norm();
        if n > 0.1 && n <= 1.0 {
            return v / n;
        }
    }
}

/// Salt of the generator that mixes a joint's twists ([`kept_twists`]), so that its stream is
/// not the one that drew the contact lines from the same seed.
pub(super) const MIX_SALT: u64 = 0x6D1C_7E0F_D81E_5A17;

/// The twists a joint without named DOF keeps once `driven` of its `all` allowed twists are
/// fixed: `all` itself when nothing is driven (bit for bit), else an orthonormal basis of
/// `k − driven` random combinations of them (`k = all.len()`), the coefficients uniform in
/// [−1, 1) from a generator seeded by `seed` (the geometry's bits, so the same geometry
/// always gives the same model). This is `all` mixed by a random invertible `k × k` matrix
/// with its first `driven` combinations dropped: a generic subspace of the allowed motions,
/// where dropping the first vectors of `all` (a basis built by pivoting on unit vectors)
/// left a subspace fixed by the construction, degenerate at a fixed fraction of draws.
pub(super) fn kept_twists<const N: usize>(all: &Vecs, driven: usize, seed: u64) -> Vecs {
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
                for (x, y) in v.iter_mut().zip(t).take(N) {
                    *x += c * y;
                }
            }
            mixed.push(v);
        }
        if let Some(kept) = orthonormal_if_well_conditioned::<N>(mixed.as_slice()) {
            return kept;
        }
    }
    Vecs::of(&all.as_slice()[driven..])
}

/// The generic contact model: `B − k` lines.
pub(super) fn contact_rows<const N: usize>(kind: JointType, g: &Geometry, space: Space) -> Vecs {
    let b = N;
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
            Space::Spatial => line(&q.into(), &d.into()),
            Space::Planar => {
                let d2 = if d.x.abs() + d.y.abs() < 1e-9 {
                    Vector3::new(1.0, 0.0, 0.0)
                } else {
                    d
                };
                short(q.x * d2.y - q.y * d2.x, d2.x, d2.y)
            }
            Space::Spherical => {
                let m = q.cross(&d);
                if m.norm() > 1e-9 {
                    short(m.x, m.y, m.z)
                } else {
                    let r = random_unit(&mut rng);
                    short(r.x, r.y, r.z)
                }
            }
        };
        rows.push(row);
    }
    // Orthonormal rows spanning the same lines; random lines are independent in practice, and
    // a dependent draw only yields fewer rows (never a panic).
    orthonormal::<N>(rows.as_slice())
}

/// The motion model of a joint of `kind` at geometry `g` with `driven` DOF fixed.
pub fn joint_model(
    kind: JointType,
    g: &Geometry,
    space: Space,
    driven: u32,
) -> Result<JointModel, MotionError> {
    stack_model(kind, g, space, driven).map(|s| s.matrices())
}

/// A joint model on the stack ([`JointModel`] without the heap): the constraint rows and the
/// allowed twists as vectors of the motion space. Analyses that build a model for each of
/// 10^6 joints use it directly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StackModel {
    /// Dimension of the motion space.
    pub b: usize,
    /// Constraint rows.
    pub rows: Vecs,
    /// Allowed twists (driven DOF removed), in driven-DOF order.
    pub twists: Vecs,
}

impl StackModel {
    pub(super) fn matrices(&self) -> JointModel {
        JointModel {
            rows: as_rows(self.b, self.rows.as_slice()),
            twists: columns(self.b, self.twists.as_slice()),
        }
    }
}

/// [`joint_model`] on the stack.
pub(crate) fn stack_model(
    kind: JointType,
    g: &Geometry,
    space: Space,
    driven: u32,
) -> Result<StackModel, MotionError> {
    match space {
        Space::Spatial => stack_model_in::<6>(kind, g, space, driven),
        Space::Planar | Space::Spherical => stack_model_in::<3>(kind, g, space, driven),
    }
}

/// [`stack_model`] in a motion space of dimension `N` (`space.b()`).
pub(super) fn stack_model_in<const N: usize>(
    kind: JointType,
    g: &Geometry,
    space: Space,
    driven: u32,
) -> Result<StackModel, MotionError> {
    let b = N;
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
        let rows = contact_rows::<N>(kind, g, space);
        if rows.len() != b - grade as usize {
            return Err(MotionError::Degenerate {
                kind: kind.code(),
                reason: "the contact lines are dependent",
            });
        }
        let all = complement::<N>(rows.as_slice());
        let twists = kept_twists::<N>(&all, driven as usize, mix_seed(g));
        let rows = complement::<N>(twists.as_slice());
        return Ok(StackModel { b, rows, twists });
    }
    let full = full_twists(kind, g, space)?;
    let basis = orthonormal::<N>(full.as_slice());
    if basis.len() != full.len() {
        return Err(MotionError::Degenerate {
            kind: kind.code(),
            reason: "its motion directions are dependent (parallel axes?)",
        });
    }
    let twists = if kind == JointType::SPSP {
        // Its twists are a basis of the annihilator of one line, ordered by pivoting: no DOF
        // of it is named (format.md), so a driven one is a generic direction.
        kept_twists::<N>(&full, driven as usize, mix_seed(g))
    } else {
        Vecs::of(full.as_slice().get(driven as usize..).unwrap_or(&[]))
    };
    // Nothing driven: the twists are `full`, whose orthonormal basis is at hand.
    let rows = if driven == 0 {
        complement_of::<N>(basis)
    } else {
        complement::<N>(twists.as_slice())
    };
    Ok(StackModel { b, rows, twists })
}

/// `M(c)`: a twist about point `c` to the same twist about the world origin (`None` in a
/// spherical mechanism, whose twists have no point). The body-local twists of the geometric
/// analysis's sparse path and of the rank check at the file's geometry.
pub(crate) fn twist_shift(space: Space, c: [f64; 3]) -> Option<DMatrix<f64>> {
    match space {
        Space::Spherical => None,
        Space::Planar => {
            // v_O = v_c − ω ẑ × c = (v_cx + ω c_y, v_cy − ω c_x).
            let mut m = DMatrix::identity(3, 3);
            m[(1, 0)] = c[1];
            m[(2, 0)] = -c[0];
            Some(m)
        }
        Space::Spatial => {
            // v_O = v_c + c × ω.
            let mut m = DMatrix::identity(6, 6);
            let [x, y, z] = c;
            m[(3, 1)] = -z;
            m[(3, 2)] = y;
            m[(4, 0)] = z;
            m[(4, 2)] = -x;
            m[(5, 0)] = -y;
            m[(5, 1)] = x;
            Some(m)
        }
    }
}

/// A model that cannot fail: the generic contact model with the joint's grade (capped at B)
/// and driven DOF (capped at the grade). Used by [`realize`] for joints no model fits.
pub(super) fn fallback_model(kind: JointType, space: Space, driven: u32, seed: u64) -> StackModel {
    match space {
        Space::Spatial => fallback_model_in::<6>(kind, driven, seed),
        Space::Planar | Space::Spherical => fallback_model_in::<3>(kind, driven, seed),
    }
}

/// [`fallback_model`] in a motion space of dimension `N`.
pub(super) fn fallback_model_in<const N: usize>(
    kind: JointType,
    driven: u32,
    seed: u64,
) -> StackModel {
    let b = N;
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
    let rows = orthonormal::<N>(rows.as_slice());
    let all = complement::<N>(rows.as_slice());
    let twists = kept_twists::<N>(&all, driven as usize, seed);
    let rows = complement::<N>(twists.as_slice());
    StackModel { b, rows, twists }
}
