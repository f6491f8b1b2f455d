//! The joint-motion model: the relative twists each joint allows and the constraint rows it
//! imposes, at given (file) or random (generic) geometry.
//!
//! # Conventions
//! - Spatial (B = 6): a twist is `t = (ω; v_O)`, with `v_O` the velocity of the body point that
//!   is at the world origin. A revolute about unit `u` through `p` allows `(u; p × u)`, a slide
//!   along `u` allows `(0; u)`, a helix of pitch `h` allows `(u; p × u + h u)`.
//! - Planar (B = 3): `t = (ω_z; v_x, v_y)`, `v` again the velocity of the point at the origin;
//!   a revolute at `p` allows `(1; p_y, −p_x)`.
//! - Spherical (B = 3): `t = ω` (every axis passes through the fixed centre, the origin).
//! - A constraint row `r` acts on a twist by the plain dot product `r · t`. Rows are wrenches
//!   written `(m_O; f)` (moment about the origin first) so that the plain dot product with
//!   `(ω; v_O)` is the reciprocal (virtual power) product. `rows · twists = 0` always, and the
//!   rows are an orthonormal basis of the annihilator of `twists`.
//!
//! # Driven DOF
//! The allowed twists are listed in the driven-DOF order of `format.md` (translations before
//! rotations; C slide then turn; PL the two in-plane slides then the turn; U `axis` then
//! `axis2`; S turns about world x, y, z through the centre; F/FP translations then
//! rotations) and the first `driven` of them are removed: a driven DOF is fixed. Kinds whose
//! DOF have no name (the count-only kinds below, SPSP, and the fallback model of a joint no
//! model fits) keep a generic subspace instead: `k − driven` random combinations of their `k`
//! allowed twists, drawn from the geometry's bits (`kept_twists`). Dropping the first twists
//! of their basis, built by pivoting on unit vectors, kept a subspace fixed by the
//! construction: a random realization was degenerate with a fixed probability.
//!
//! # Joints without a standard geometry
//! - ER (slotted spherical) is defined here as a ball at `origin` whose rotation about `axis`
//!   is blocked: it allows the two rotations through `origin` about the axes perpendicular to
//!   `axis` (in the order of [`perpendicular_pair`]), and no translation.
//! - Count-only kinds (CPEP, L, EO, EPI, CTEP, RP, RD, CR, CTRP, SC, PC, CBIP, SP, SPSP) get the
//!   generic realization of a contact joint: `B − k` pure forces (lines). The first line passes
//!   through `origin` along `axis` when they are given; the other points and directions are
//!   pseudo-random, drawn from a generator seeded by the geometry's bits, so the same geometry
//!   always gives the same model. Such a joint has the right number of constraints in general
//!   position: enough for rank and mobility questions, not a model of a particular contact.
//! - FP in a spatial mechanism is treated like PL (normal `normal`, default z).
//!
//! # Multiple joints
//! A joint joining n > 2 bodies is n − 1 binary pairs hub→other (hub = first listed body), each
//! with the same model; pair equation `rows · (t_other − t_hub) = 0`; the frame's twist is 0.

use crate::joint::JointType;
use crate::mechanism::{Geometry, Mechanism, Space};
use nalgebra::{DMatrix, Vector3};

use crate::numbers::rounding_of;
pub use crate::rng::SplitMix64;
use crate::rng::indexed_seed;

mod batch;
pub(crate) use batch::{Scratch, pair_rows_many};
#[cfg(test)]
mod reference;

/// The motion model of one joint (of one binary pair of it).
#[derive(Clone, Debug, PartialEq)]
pub struct JointModel {
    /// Constraint rows, `(B − k + driven) × B`: an orthonormal basis of the annihilator of
    /// `twists` (see the module conventions).
    pub rows: DMatrix<f64>,
    /// Allowed relative twists once the driven DOF are fixed, `B × (k − driven)`, columns in
    /// driven-DOF order (the driven ones removed).
    pub twists: DMatrix<f64>,
}

/// Why a joint model cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MotionError {
    /// A geometry field this joint kind needs is missing.
    #[error("a {kind} joint needs `{field}` for geometric analysis")]
    MissingField {
        /// Joint kind code.
        kind: &'static str,
        /// The missing field.
        field: &'static str,
    },
    /// A direction is zero (or not finite).
    #[error("`{field}` of a {kind} joint is zero or not finite")]
    ZeroVector {
        /// Joint kind code.
        kind: &'static str,
        /// The field.
        field: &'static str,
    },
    /// The geometry makes the joint's twists dependent (e.g. a U with parallel axes).
    #[error("a {kind} joint has degenerate geometry: {reason}")]
    Degenerate {
        /// Joint kind code.
        kind: &'static str,
        /// Why.
        reason: &'static str,
    },
    /// The kind cannot be modelled in this motion space.
    #[error("a {kind} joint cannot be modelled in a {space} mechanism")]
    InvalidInSpace {
        /// Joint kind code.
        kind: &'static str,
        /// The space name.
        space: &'static str,
    },
    /// More driven DOF than the joint's grade.
    #[error("a {kind} joint has {driven} driven DOF but grade {grade}")]
    DrivenAboveGrade {
        /// Joint kind code.
        kind: &'static str,
        /// Driven DOF.
        driven: u32,
        /// Grade.
        grade: u32,
    },
    /// The file's configuration misses closure grossly (more than
    /// [`crate::position::closure::GROSS`] × the model size): it is not assembled.
    #[error(
        "the configuration written is not assembled: joint `{joint}` is open by {residual:.3e}, more than {limit:.1e} (1e-2 x model size){others}; `mbsa assemble FILE > closed.toml` projects it onto the constraints (least change)"
    )]
    NotClosed {
        /// The worst joint.
        joint: String,
        /// Its residual (file lengths).
        residual: f64,
        /// The gross limit.
        limit: f64,
        /// The other joints over the limit, in words (empty when none).
        others: String,
    },
    /// The closure of a joint with `second` geometry cannot be evaluated.
    #[error("closure check: {0}")]
    Closure(ModelError),
    /// An error located at a joint of a mechanism.
    #[error("joint `{joint}`: {source}")]
    InJoint {
        /// Joint id.
        joint: String,
        /// The error.
        #[source]
        source: Box<MotionError>,
    },
}

/// Why a mechanism has no position model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A geometry field the joint needs is missing.
    #[error("joint `{joint}`: a {kind} joint needs `{field}` for the position level")]
    MissingField {
        /// Joint id.
        joint: String,
        /// Kind code.
        kind: &'static str,
        /// Field.
        field: &'static str,
    },
    /// A direction is zero or not finite, or a number is not finite.
    #[error("joint `{joint}`: `{field}` is zero or not finite")]
    BadVector {
        /// Joint id.
        joint: String,
        /// Field.
        field: &'static str,
    },
    /// The kind has no position model (generic contact kinds, or not in this space).
    #[error("joint `{joint}`: a {kind} joint has no position model in a {space} mechanism")]
    NoModel {
        /// Joint id.
        joint: String,
        /// Kind code.
        kind: &'static str,
        /// Space.
        space: &'static str,
    },
    /// The mechanism is too large for a dense analysis.
    #[error("{bodies} bodies: the dense position analysis handles at most {limit}")]
    TooLarge {
        /// Bodies.
        bodies: usize,
        /// Limit.
        limit: usize,
    },
    /// Driving this kind is not supported.
    #[error("joint `{joint}`: driving a {kind} joint is not supported by the position level")]
    NotDrivable {
        /// Joint id.
        joint: String,
        /// Kind code.
        kind: &'static str,
    },
}

/// Whether a kind has no geometric model of its own (count only) and gets the generic contact
/// realization.
pub fn is_contact(kind: JointType) -> bool {
    use JointType::*;
    matches!(kind, CPEP | L | EO | EPI | CTEP | RP | RD | CTRP | CBIP)
}

/// Whether a kind has a geometric model in this motion space: contact kinds with geometry
/// (SP, SPSP, SC, PC, CR) have one in space only; the count-only kinds ([`is_contact`]) never.
fn modelled(kind: JointType, space: Space) -> bool {
    use JointType::*;
    match kind {
        SP | SPSP | SC | PC | CR => space == Space::Spatial,
        k => !is_contact(k),
    }
}

fn v3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

fn unit(kind: JointType, field: &'static str, a: [f64; 3]) -> Result<Vector3<f64>, MotionError> {
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

fn need<T: Copy>(kind: JointType, field: &'static str, value: Option<T>) -> Result<T, MotionError> {
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

fn spatial_rot(u: &Vector3<f64>, p: &Vector3<f64>) -> Vb {
    let m = p.cross(u);
    [u.x, u.y, u.z, m.x, m.y, m.z]
}

fn spatial_trans(u: &Vector3<f64>) -> Vb {
    [0.0, 0.0, 0.0, u.x, u.y, u.z]
}

/// A vector of a 3-dimensional motion space (the rest zero).
fn v3b(a: f64, b: f64, c: f64) -> Vb {
    [a, b, c, 0.0, 0.0, 0.0]
}

/// The rotations about the world x, y, z axes through `c` (the turns of a ball).
fn world_turns(c: &Vector3<f64>) -> [Vb; 3] {
    [Vector3::x(), Vector3::y(), Vector3::z()].map(|e| spatial_rot(&e, c))
}

/// The unit component of `v` perpendicular to unit `n` (geometry written to a few decimals is
/// not exactly perpendicular); an error when `v` is (nearly) parallel to `n`.
fn in_plane(
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

fn columns(b: usize, cols: &[Vb]) -> DMatrix<f64> {
    DMatrix::from_fn(b, cols.len(), |i, j| cols[j][i])
}

/// The vectors as the rows of a matrix.
fn as_rows(b: usize, rows: &[Vb]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), b, |i, j| rows[i][j])
}

// The Gram-Schmidt helpers run on stack vectors of the motion space (B <= 6): they are called
// for every joint of every realization. Their arithmetic is nalgebra's for vectors shorter
// than 8 (dot products summed in order from 0, `normalize` as division by the norm), so the
// results are bit for bit those of the DVector code they replaced.

/// Largest motion-space dimension.
const MAX_B: usize = 6;

type Vb = [f64; MAX_B];

/// Up to [`MAX_B`] vectors of the motion space, on the stack (a joint's twists or rows).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Vecs {
    v: [Vb; MAX_B],
    n: usize,
}

impl Vecs {
    const EMPTY: Vecs = Vecs {
        v: [[0.0; MAX_B]; MAX_B],
        n: 0,
    };

    fn of(list: &[Vb]) -> Vecs {
        let mut out = Vecs::EMPTY;
        list.iter().for_each(|&x| out.push(x));
        out
    }

    /// Append `x` (never more than [`MAX_B`] vectors: motion spaces have no more).
    fn push(&mut self, x: Vb) {
        if let Some(slot) = self.v.get_mut(self.n) {
            *slot = x;
            self.n += 1;
        }
    }

    /// The vectors.
    pub(crate) fn as_slice(&self) -> &[Vb] {
        &self.v[..self.n]
    }

    /// Number of vectors.
    pub(crate) fn len(&self) -> usize {
        self.n
    }
}

// The helpers below take the dimension as a constant `N` (3 or 6, [`Space::b`]; the entry
// points dispatch once per joint): their loops unroll. Every sum is still taken in index
// order from 0, so the results are bit for bit those of the loops up to a runtime dimension
// they replaced (`reference.rs`, compared in the tests).

fn dot<const N: usize>(a: &Vb, b: &Vb) -> f64 {
    let mut r = 0.0;
    for (x, y) in a.iter().zip(b).take(N) {
        r += x * y;
    }
    r
}

fn norm<const N: usize>(a: &Vb) -> f64 {
    dot::<N>(a, a).sqrt()
}

/// `v -= (q · v) q` twice over the basis (re-orthogonalization).
fn project_out<const N: usize>(v: &mut Vb, basis: &[Vb]) {
    for _ in 0..2 {
        for q in basis {
            let d = dot::<N>(q, v);
            for (x, y) in v.iter_mut().zip(q).take(N) {
                *x -= y * d;
            }
        }
    }
}

/// `v / len` with `len` its norm ([`norm`], which the caller has computed already).
fn normalized<const N: usize>(v: &Vb, len: f64) -> Vb {
    let mut out = [0.0; MAX_B];
    for (o, x) in out.iter_mut().zip(v).take(N) {
        *o = x / len;
    }
    out
}

/// Unit vector `e_i` through [`project_out`]. Its first product `q · e_i` with the first
/// basis vector `q` is `q_i + 0.0` when `q` is finite: the sum of `q_k · 0 = ±0` for `k ≠ i`
/// and of `q_i · 1` from `+0.0` (a sum of zeros from `+0.0` is `+0.0`, adding `±0` to a
/// nonzero sum leaves it, and `+0.0 + q_i` is `q_i + 0.0`). The rest is [`project_out`].
fn project_unit<const N: usize>(i: usize, basis: &[Vb]) -> Vb {
    let mut v = [0.0; MAX_B];
    v[i] = 1.0;
    match basis.split_first() {
        Some((q, rest)) if q.iter().take(N).all(|x| x.is_finite()) => {
            let d = q[i] + 0.0;
            for (x, y) in v.iter_mut().zip(q).take(N) {
                *x -= y * d;
            }
            for q in rest {
                let d = dot::<N>(q, &v);
                for (x, y) in v.iter_mut().zip(q).take(N) {
                    *x -= y * d;
                }
            }
            for q in basis {
                let d = dot::<N>(q, &v);
                for (x, y) in v.iter_mut().zip(q).take(N) {
                    *x -= y * d;
                }
            }
        }
        _ => project_out::<N>(&mut v, basis),
    }
    v
}

/// Orthonormal basis of the orthogonal complement of the span of `cols` (vectors of the
/// `N`-dimensional motion space, independent): greedy Gram-Schmidt on the unit vectors,
/// always taking the one with the largest residual, so no threshold is involved.
fn complement<const N: usize>(cols: &[Vb]) -> Vecs {
    complement_of::<N>(orthonormal::<N>(cols))
}

/// [`complement`] of the span of `basis`, the output of [`orthonormal`] (a caller that has
/// it already need not compute it again).
fn complement_of<const N: usize>(mut basis: Vecs) -> Vecs {
    // The residual of unit vector `e_i` has squared norm `1 − Σ_q q_i²` (the basis is
    // orthonormal to rounding, far below `CANDIDATE_GAP`): only the unit vectors within the
    // gap of the largest can have the largest computed residual, so only they are projected,
    // each exactly as [`project_out`] does. The vector taken is the one the projection of
    // every unit vector takes, bit for bit (the first largest). The sums `Σ_q q_i²` grow by
    // one term per vector taken, added last: the same sums, in the same order, as summing
    // over the whole basis again.
    let mut sq = [0.0; MAX_B];
    for q in basis.as_slice() {
        for (s, x) in sq.iter_mut().zip(q).take(N) {
            *s += x * x;
        }
    }
    let mut out = Vecs::EMPTY;
    while basis.len() < N {
        let mut top = f64::NEG_INFINITY;
        let mut finite = true;
        for s in sq.iter().take(N) {
            finite &= s.is_finite();
            top = top.max(1.0 - s);
        }
        let mut best: Option<(Vb, f64)> = None;
        for (i, s) in sq.iter().enumerate().take(N) {
            if finite && 1.0 - s < top - CANDIDATE_GAP {
                continue;
            }
            #[cfg(test)]
            PROJECTED.with(|c| c.set(c.get() + 1));
            let v = project_unit::<N>(i, basis.as_slice());
            let n = norm::<N>(&v);
            if best.is_none_or(|(_, w)| n > w) {
                best = Some((v, n));
            }
        }
        let Some((v, n)) = best else {
            break;
        };
        let q = normalized::<N>(&v, n);
        for (s, x) in sq.iter_mut().zip(&q).take(N) {
            *s += x * x;
        }
        basis.push(q);
        out.push(q);
    }
    out
}

#[cfg(test)]
thread_local! {
    /// Unit vectors [`complement`] projected on this thread (its work measure in tests).
    static PROJECTED: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// How far below the largest estimated squared residual a unit vector in [`complement`] is
/// still projected. The estimate and the projection differ by rounding (about `1e-15`, and
/// at most the basis' loss of orthogonality); the largest squared residual is at least
/// `1 / B`, so a unit vector this far below cannot have the largest.
const CANDIDATE_GAP: f64 = 1e-4;

/// Orthonormalize `cols` (modified Gram-Schmidt, twice); vectors that vanish are dropped.
fn orthonormal<const N: usize>(cols: &[Vb]) -> Vecs {
    // The norm of all of them: the dot products summed in order.
    let mut sq = 0.0;
    for v in cols {
        sq += dot::<N>(v, v);
    }
    let scale = sq.sqrt().max(1e-300);
    let mut out = Vecs::EMPTY;
    for &c in cols {
        let mut v = c;
        project_out::<N>(&mut v, out.as_slice());
        let n = norm::<N>(&v);
        if n > 1e-10 * scale {
            out.push(normalized::<N>(&v, n));
        }
    }
    out
}

fn mix_seed(g: &Geometry) -> u64 {
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

fn random_unit(rng: &mut SplitMix64) -> Vector3<f64> {
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
const MIX_SALT: u64 = 0x6D1C_7E0F_D81E_5A17;

/// The twists a joint without named DOF keeps once `driven` of its `all` allowed twists are
/// fixed: `all` itself when nothing is driven (bit for bit), else an orthonormal basis of
/// `k − driven` random combinations of them (`k = all.len()`), the coefficients uniform in
/// [−1, 1) from a generator seeded by `seed` (the geometry's bits, so the same geometry
/// always gives the same model). This is `all` mixed by a random invertible `k × k` matrix
/// with its first `driven` combinations dropped: a generic subspace of the allowed motions,
/// where dropping the first vectors of `all` (a basis built by pivoting on unit vectors)
/// left a subspace fixed by the construction, degenerate at a fixed fraction of draws.
fn kept_twists<const N: usize>(all: &Vecs, driven: usize, seed: u64) -> Vecs {
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

/// [`orthonormal`] of `vs` when it drops none of them and they are far from dependent (each
/// keeps a residual of at least 1e-3 of its norm after projecting out the ones before it).
/// One Gram-Schmidt pass serves both tests: while no vector is dropped, the basis built by
/// [`orthonormal`] and the one the residuals are measured against are the same vectors.
fn orthonormal_if_well_conditioned<const N: usize>(vs: &[Vb]) -> Option<Vecs> {
    let mut sq = 0.0;
    for v in vs {
        sq += dot::<N>(v, v);
    }
    let scale = sq.sqrt().max(1e-300);
    let mut basis = Vecs::EMPTY;
    for v in vs {
        let n = norm::<N>(v);
        let mut r = *v;
        project_out::<N>(&mut r, basis.as_slice());
        let rn = norm::<N>(&r);
        let kept = rn > 1e-10 * scale;
        if !kept || rn.partial_cmp(&(1e-3 * n)) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        basis.push(normalized::<N>(&r, rn));
    }
    Some(basis)
}

/// The generic contact model: `B − k` lines.
fn contact_rows<const N: usize>(kind: JointType, g: &Geometry, space: Space) -> Vecs {
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
    orthonormal::<N>(rows.as_slice())
}

/// All allowed twists of `kind` in driven-DOF order (before removing driven ones).
#[inline]
fn full_twists(kind: JointType, g: &Geometry, space: Space) -> Result<Vecs, MotionError> {
    Ok(match twist_spec(kind, g, space)? {
        TwistSpec::Listed(full) => full,
        TwistSpec::AnnihilatorOf(line) => complement::<6>(&[line]),
    })
}

/// A joint's allowed twists ([`full_twists`]) before any Gram-Schmidt: listed, or the
/// annihilator of one line (SPSP, spatial only), which [`batch`] builds in lanes.
#[allow(clippy::large_enum_variant)] // On the stack, returned once per joint: no box.
enum TwistSpec {
    /// The twists themselves.
    Listed(Vecs),
    /// The twists are [`complement`] of this one line.
    AnnihilatorOf(Vb),
}

/// [`full_twists`] up to the Gram-Schmidt it may need.
#[inline]
fn twist_spec(kind: JointType, g: &Geometry, space: Space) -> Result<TwistSpec, MotionError> {
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
    fn matrices(&self) -> JointModel {
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
fn stack_model_in<const N: usize>(
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

/// Random generic geometry for a joint of `kind`: every field set (origin, unit axis, unit
/// axis2, unit normal, pitch), coordinates uniform in [−1, 1). Planar: z = 0 and axes in the
/// plane (an R axis is z). Spherical: the origin is the centre (0, 0, 0).
pub fn random_geometry(kind: JointType, space: Space, rng: &mut SplitMix64) -> Geometry {
    random_geometry_to(kind, space, rng, Drawn::All)
}

/// How far into [`random_geometry`]'s draws (origin, axis, axis2, normal, pitch, origin2, in
/// this order) a kind's model reads ([`full_twists`]): the fields after it need not be drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Drawn {
    Origin,
    Axis,
    Axis2,
    Normal,
    All,
}

/// The last field of [`random_geometry`] the model of `kind` in `space` reads. H reads the
/// pitch; SPSP, the contact models and the fallback model hash every field ([`mix_seed`]).
fn model_reads(kind: JointType, space: Space) -> Drawn {
    use JointType::*;
    match (space, kind) {
        (Space::Spatial, S) => Drawn::Origin,
        (Space::Spatial, R | P | C | ER | SC) => Drawn::Axis,
        (Space::Spatial, U) => Drawn::Axis2,
        (Space::Spatial, PL | FP | SP | PC | CR) => Drawn::Normal,
        (Space::Planar, R | FP) | (Space::Spherical, FP) => Drawn::Origin,
        (Space::Planar, P) | (Space::Spherical, R) => Drawn::Axis,
        _ => Drawn::All,
    }
}

/// [`random_geometry`] drawn up to field `last` (the later fields `None`): the same stream,
/// so the fields drawn are bit for bit those of the whole geometry.
fn random_geometry_to(
    kind: JointType,
    space: Space,
    rng: &mut SplitMix64,
    last: Drawn,
) -> Geometry {
    let mut origin = [rng.next_signed(), rng.next_signed(), rng.next_signed()];
    let draw = |rng: &mut SplitMix64, field: Drawn| -> Option<[f64; 3]> {
        (last >= field).then(|| random_unit(rng).into())
    };
    let mut axis = draw(rng, Drawn::Axis);
    let axis2 = draw(rng, Drawn::Axis2);
    let normal = draw(rng, Drawn::Normal);
    let (pitch, origin2) = if last == Drawn::All {
        let pitch = rng.next_signed();
        let origin2 = [rng.next_signed(), rng.next_signed(), rng.next_signed()];
        (Some(pitch), Some(origin2))
    } else {
        (None, None)
    };
    match space {
        Space::Spatial => {}
        Space::Planar => {
            origin[2] = 0.0;
            axis = axis.map(|axis| {
                if kind == JointType::R {
                    [0.0, 0.0, 1.0]
                } else {
                    let n = (axis[0] * axis[0] + axis[1] * axis[1]).sqrt().max(1e-12);
                    let axis = [axis[0] / n, axis[1] / n, 0.0];
                    if axis == [0.0, 0.0, 0.0] {
                        [1.0, 0.0, 0.0]
                    } else {
                        axis
                    }
                }
            });
        }
        Space::Spherical => origin = [0.0, 0.0, 0.0],
    }
    Geometry {
        origin: Some(origin),
        axis,
        axis2,
        origin2,
        normal,
        pitch,
        second: None,
    }
}

/// A model that cannot fail: the generic contact model with the joint's grade (capped at B)
/// and driven DOF (capped at the grade). Used by [`realize`] for joints no model fits.
fn fallback_model(kind: JointType, space: Space, driven: u32, seed: u64) -> StackModel {
    match space {
        Space::Spatial => fallback_model_in::<6>(kind, driven, seed),
        Space::Planar | Space::Spherical => fallback_model_in::<3>(kind, driven, seed),
    }
}

/// [`fallback_model`] in a motion space of dimension `N`.
fn fallback_model_in<const N: usize>(kind: JointType, driven: u32, seed: u64) -> StackModel {
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

/// One model per joint at random generic geometry (the file geometry is ignored), seeded per
/// (seed, joint index). A joint no model fits (a kind invalid in the space, driven above the
/// grade: the reader rejects both) gets a generic model of its grade.
pub fn realize(m: &Mechanism, seed: u64) -> Vec<JointModel> {
    crate::par::map(m.joints.len(), |i| {
        let j = &m.joints[i];
        let s = indexed_seed(seed, i);
        let mut rng = SplitMix64::new(s);
        let g = random_geometry(j.kind, m.space, &mut rng);
        stack_model(j.kind, &g, m.space, j.driven)
            .unwrap_or_else(|_| fallback_model(j.kind, m.space, j.driven, s))
            .matrices()
    })
}

/// How many bodies (the first, in body order) [`scale_of`] measures for the characteristic
/// length: a median over 65,536 bodies is as good as over all, and the scratch memory stays
/// bounded (2.6 MB) on a 10^6-body file.
const SIZED_BODIES: usize = 1 << 16;

/// The change of origin and length unit that makes the file's geometry dimensionless before
/// any rank decision: a point `p` becomes `(p − centre) / length`, a pitch `h` becomes
/// `h / length`, directions are unchanged. Twists and rows built at the scaled geometry are
/// those of the same model written in any length unit and placed anywhere; the rounding
/// threshold is scaled to match ([`file_threshold`]). Reports give points in file units
/// ([`Scale::world_twist`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    /// The centre of the bounding box of the joint points (file units).
    pub centre: [f64; 3],
    /// The characteristic length (file units, > 0).
    pub length: f64,
}

impl Scale {
    /// No change (random realizations, spherical mechanisms, files without points).
    pub const IDENTITY: Scale = Scale {
        centre: [0.0; 3],
        length: 1.0,
    };

    /// A point in characteristic lengths about the centre.
    pub fn point(&self, p: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|i| (p[i] - self.centre[i]) / self.length)
    }

    /// A joint's geometry made dimensionless (points and the pitch; directions unchanged).
    pub fn geometry(&self, g: &Geometry) -> Geometry {
        let mut out = g.clone();
        if *self == Scale::IDENTITY {
            return out;
        }
        out.origin = g.origin.map(|p| self.point(p));
        out.origin2 = g.origin2.map(|p| self.point(p));
        out.pitch = g.pitch.map(|h| h / self.length);
        if let Some(second) = out.second.as_mut() {
            second.origin = second.origin.map(|p| self.point(p));
        }
        out
    }

    /// A twist of the dimensionless geometry (about the centre, lengths in characteristic
    /// lengths) as the twist of the file's geometry about the world origin in file units:
    /// `v_O = Lc · v_c + c × ω` (spatial), `(Lc · v_c,x + ω c_y, Lc · v_c,y − ω c_x)`
    /// (planar); a spherical twist is unchanged.
    pub fn world_twist(&self, space: Space, t: &[f64]) -> Vec<f64> {
        let (c, l) = (self.centre, self.length);
        match (space, t) {
            (Space::Spatial, &[wx, wy, wz, vx, vy, vz]) => vec![
                wx,
                wy,
                wz,
                l * vx + c[1] * wz - c[2] * wy,
                l * vy + c[2] * wx - c[0] * wz,
                l * vz + c[0] * wy - c[1] * wx,
            ],
            (Space::Planar, &[w, vx, vy]) => vec![w, l * vx + w * c[1], l * vy - w * c[0]],
            _ => t.to_vec(),
        }
    }
}

/// The dimensionless geometry of `m`'s file geometry ([`Scale`]). The centre is the centre
/// of the bounding box of the joint points (`origin`, `origin2`). The characteristic length
/// is the median body size, a body's size being the largest distance from its first joint's
/// origin to its other joints' origins (bodies whose joints' origins coincide left out): the
/// length of a typical link, which does not grow with the number of links. (A length that
/// grew with the model's extent, such as the RMS distance of the points from the centre,
/// would shrink a long row's bars to 1/N and its smallest singular values with them, below
/// the relative threshold.) Without such a body, half the bounding box's diagonal; without
/// points (or in a spherical mechanism, whose points are the fixed centre), no change.
pub fn scale_of(m: &Mechanism) -> Scale {
    if m.space == Space::Spherical {
        return Scale::IDENTITY;
    }
    let finite = |p: &[f64; 3]| p.iter().all(|x| x.is_finite());
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in m
        .joints
        .iter()
        .flat_map(|j| [j.geometry.origin, j.geometry.origin2])
        .flatten()
        .filter(finite)
    {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    if lo[0] > hi[0] {
        return Scale::IDENTITY;
    }
    let centre = [0, 1, 2].map(|i| lo[i] + (hi[i] - lo[i]) / 2.0);
    let nb = m.bodies.len().min(SIZED_BODIES);
    let mut anchor: Vec<Option<[f64; 3]>> = vec![None; nb];
    let mut size = vec![0.0f64; nb];
    for j in &m.joints {
        let Some(o) = j.geometry.origin.filter(finite) else {
            continue;
        };
        for &b in j.bodies.iter().filter(|&&b| b < nb) {
            match anchor[b] {
                None => anchor[b] = Some(o),
                Some(a) => {
                    let d = (0..3).map(|i| (o[i] - a[i]).powi(2)).sum::<f64>().sqrt();
                    size[b] = size[b].max(d);
                }
            }
        }
    }
    let mut sizes: Vec<f64> = size
        .into_iter()
        .filter(|s| s.is_finite() && *s > 0.0)
        .collect();
    let length = if sizes.is_empty() {
        (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt() / 2.0
    } else {
        let mid = sizes.len() / 2;
        *sizes.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    if !(length.is_finite() && length > 0.0 && finite(&centre)) {
        return Scale::IDENTITY;
    }
    Scale { centre, length }
}

/// Build every joint model at the file's geometry (in parallel), keeping only the first error
/// in joint order.
pub(crate) fn check_file_geometry(m: &Mechanism) -> Result<(), MotionError> {
    let errors: Vec<Option<MotionError>> = crate::par::map(m.joints.len(), |i| {
        let j = &m.joints[i];
        if !modelled(j.kind, m.space) && j.geometry.is_empty() {
            return None;
        }
        joint_model(j.kind, &j.geometry, m.space, j.driven)
            .err()
            .map(|e| MotionError::InJoint {
                joint: j.id.clone(),
                source: Box::new(e),
            })
    });
    match errors.into_iter().flatten().next() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Joint `i`'s geometry in the random realization `seed` ([`geometries`]' choice, one joint at
/// a time: 10^6 joints need not hold them all).
pub(crate) fn random_joint_geometry(m: &Mechanism, seed: u64, i: usize) -> Geometry {
    random_geometry(
        m.joints[i].kind,
        m.space,
        &mut SplitMix64::new(indexed_seed(seed, i)),
    )
}

/// Joint `i`'s geometry in the random realization `seed` as its pair model reads it: the
/// fields of [`random_joint_geometry`] its model reads, the later ones not drawn.
pub(crate) fn random_pair_geometry(m: &Mechanism, seed: u64, i: usize) -> Geometry {
    let kind = m.joints[i].kind;
    let mut rng = SplitMix64::new(indexed_seed(seed, i));
    random_geometry_to(kind, m.space, &mut rng, model_reads(kind, m.space))
}

/// Every joint's geometry when the file's is used ([`geometries`]), made dimensionless
/// ([`scale_of`], the same as [`GeometryUsed::scale`]): the rank decisions made on it do not
/// depend on the length unit or on where the model sits.
pub(crate) fn file_geometries(m: &Mechanism) -> Vec<Geometry> {
    let scale = scale_of(m);
    m.joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            if !modelled(j.kind, m.space) && j.geometry.is_empty() {
                random_geometry(j.kind, m.space, &mut SplitMix64::new(indexed_seed(0, i)))
            } else {
                scale.geometry(&j.geometry)
            }
        })
        .collect()
}

/// The model of one binary pair of joint `index` of `m` at geometry `g` with `driven` of its
/// DOF fixed; a joint no model fits (the reader rejects such files) gets a generic model of
/// its grade, so analyses of mechanisms built in code never fail here.
pub fn pair_model(m: &Mechanism, index: usize, g: &Geometry, driven: u32) -> JointModel {
    pair_stack_model(m, index, g, driven).matrices()
}

/// [`pair_model`] on the stack.
pub(crate) fn pair_stack_model(
    m: &Mechanism,
    index: usize,
    g: &Geometry,
    driven: u32,
) -> StackModel {
    let j = &m.joints[index];
    stack_model(j.kind, g, m.space, driven)
        .unwrap_or_else(|_| fallback_model(j.kind, m.space, driven, indexed_seed(0, index)))
}

/// One model per joint at the file geometry made dimensionless ([`scale_of`]: every point
/// taken about the model's centre and every length divided by its characteristic length, so
/// the twists and rows are those of the same model in any length unit and at any place).
/// Kinds without a geometric model get the generic contact model seeded by the joint index.
/// Errors name the joint.
pub fn configure(m: &Mechanism) -> Result<Vec<JointModel>, MotionError> {
    let scale = scale_of(m);
    m.joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let g = if !modelled(j.kind, m.space) && j.geometry.is_empty() {
                random_geometry(j.kind, m.space, &mut SplitMix64::new(indexed_seed(0, i)))
            } else {
                scale.geometry(&j.geometry)
            };
            joint_model(j.kind, &g, m.space, j.driven).map_err(|e| MotionError::InJoint {
                joint: j.id.clone(),
                source: Box::new(e),
            })
        })
        .collect()
}

/// A joint without the geometry its kind needs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Lacking {
    /// Joint id.
    pub joint: String,
    /// Its kind's code.
    pub kind: &'static str,
    /// The missing fields (empty when the kind has no geometric model at all).
    pub fields: Vec<&'static str>,
    /// The kind has no geometric model in this space (cams, gears, rolling, point contacts).
    pub no_model: bool,
}

impl Lacking {
    /// `A (S: origin)` or `G (EO: no geometric model)`.
    pub fn describe(&self) -> String {
        if self.no_model {
            format!("{} ({}: no geometric model)", self.joint, self.kind)
        } else {
            format!("{} ({}: {})", self.joint, self.kind, self.fields.join(", "))
        }
    }
}

/// The joints that lack geometry fields their kind needs, and those whose kind has no
/// geometric model: a mechanism has its geometry only when this is empty.
pub fn lacking(m: &Mechanism) -> Vec<Lacking> {
    m.joints.iter().filter_map(|j| lacking_of(m, j)).collect()
}

/// Whether joint `j` of `m` lacks the geometry field `f` (a name from its kind's list).
fn field_missing(m: &Mechanism, j: &crate::mechanism::Joint, f: &str) -> bool {
    let g = &j.geometry;
    match f {
        "origin" => g.origin.is_none() && m.space != Space::Spherical,
        "origin2" => g.origin2.is_none(),
        "axis" => g.axis.is_none() && !(m.space == Space::Planar && j.kind == JointType::R),
        "axis2" => g.axis2.is_none(),
        "normal" => g.normal.is_none(),
        "pitch" => g.pitch.is_none(),
        _ => false,
    }
}

/// Whether joint `j` would be listed by [`lacking`] (without building its entry).
pub(crate) fn lacks(m: &Mechanism, j: &crate::mechanism::Joint) -> bool {
    (!modelled(j.kind, m.space) && j.kind != JointType::FP)
        || j.kind
            .info()
            .geometry
            .iter()
            .any(|f| field_missing(m, j, f))
}

/// Joint `j`'s entry of [`lacking`], if it has one.
pub(crate) fn lacking_of(m: &Mechanism, j: &crate::mechanism::Joint) -> Option<Lacking> {
    let fields: Vec<&'static str> = j
        .kind
        .info()
        .geometry
        .iter()
        .copied()
        .filter(|f| field_missing(m, j, f))
        .collect();
    let no_model = !modelled(j.kind, m.space) && j.kind != JointType::FP;
    (no_model || !fields.is_empty()).then(|| Lacking {
        joint: j.id.clone(),
        kind: j.kind.code(),
        fields,
        no_model,
    })
}

/// Whether every joint has the geometry fields its kind needs ([`lacking`] is empty).
pub fn has_geometry(m: &Mechanism) -> bool {
    // No list built: a mechanism without geometry lacks it at every joint.
    !m.joints.iter().any(|j| lacks(m, j))
}

/// How precisely the file's geometry numbers are known: its `precision` key
/// ([`Mechanism::precision`]) when it has one, else the largest rounding uncertainty of a
/// written number. A number shown with 4 or more significant digits and d decimals is known
/// to ±0.5·10^−d (CAD exports round so); a shorter one (`2.5`, `0`, `1`) is taken as exact.
/// Numbers are judged by their shortest round-trip decimal form ([`rounding_of`]).
pub fn written_precision(m: &Mechanism) -> f64 {
    m.precision.unwrap_or_else(|| written(m, false))
}

/// [`written_precision`] of the direction numbers alone (axes, normals): a rounded direction
/// moves a joint's constraint rows by its error times the lever arm, a rounded point only by
/// its error, so the threshold weighs the two apart ([`file_threshold`]). The `precision`
/// key, like `--tolerance`, sets both.
pub fn written_direction_precision(m: &Mechanism) -> f64 {
    m.precision.unwrap_or_else(|| written(m, true))
}

fn written(m: &Mechanism, directions_only: bool) -> f64 {
    let mut worst: f64 = 0.0;
    for j in &m.joints {
        let g = &j.geometry;
        let points = [g.origin, g.origin2];
        let directions = [g.axis, g.axis2, g.normal];
        let second = g.second.as_ref().map(|s| {
            s.vectors()
                .into_iter()
                .filter(|(name, _)| !directions_only || *name != "origin")
                .map(|(_, v)| v)
        });
        let vectors = directions
            .iter()
            .chain(points.iter().filter(|_| !directions_only))
            .copied()
            .chain(second.into_iter().flatten());
        let numbers = vectors
            .flatten()
            .flat_map(|v| v.into_iter())
            .chain(g.pitch.filter(|_| !directions_only));
        for x in numbers {
            worst = worst.max(rounding_of(x));
        }
    }
    worst
}

/// The lever arm of the constraint rows at the dimensionless geometry `scale` gives: the
/// largest coordinate of a joint point about the centre, in characteristic lengths (the rows'
/// moments are taken about the centre).
pub(crate) fn lever(m: &Mechanism, scale: &Scale) -> f64 {
    m.joints
        .iter()
        .flat_map(|j| [j.geometry.origin, j.geometry.origin2])
        .flatten()
        .flat_map(|p| scale.point(p).into_iter())
        .filter(|x| x.is_finite())
        .fold(0.0f64, |a, x| a.max(x.abs()))
}

/// Factor of the precision-derived threshold: rounding a point by δ moves a joint's unit rows
/// by about δ, rounding a direction by δ_d with lever arms up to L by about δ_d·(1 + L), and an
/// exact zero singular value by about as much (the Bennett linkage rounded to 4 decimals:
/// 1.3e-5 for δ = 5e-5); twice that is the threshold, and a decision within a factor 100 of it
/// is flagged.
pub const FILE_TOL_FACTOR: f64 = 2.0;

#[cfg(test)]
mod tests {
    use super::reference as old;
    use super::*;
    use crate::mechanism::{BodyId, JointSpec};
    use nalgebra::DVector;

    /// The file's `precision` key is what the precision functions use, whatever the digits say.
    #[test]
    fn written_precision_takes_the_files_key() {
        use crate::format::{Format, load};
        let digits =
            "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\norigin = [0.1234, 0, 0]\n";
        let m = load("p.toml", digits, Format::Toml).unwrap();
        assert_eq!(written_precision(&m), 5e-5);
        let keyed = digits.replace("frame = 1\n", "frame = 1\nprecision = 1e-9\n");
        let m = load("p.toml", &keyed, Format::Toml).unwrap();
        assert_eq!(written_precision(&m), 1e-9);
        assert_eq!(written_direction_precision(&m), 1e-9);
    }

    /// [`complement`] in a motion space of runtime dimension `b` (3 or 6).
    fn complement_in(cols: &[Vb], b: usize) -> Vecs {
        match b {
            6 => complement::<6>(cols),
            3 => complement::<3>(cols),
            _ => panic!("no motion space has dimension {b}"),
        }
    }

    /// [`contact_rows`] in `space`.
    fn contact_rows_in(kind: JointType, g: &Geometry, space: Space) -> Vecs {
        match space {
            Space::Spatial => contact_rows::<6>(kind, g, space),
            _ => contact_rows::<3>(kind, g, space),
        }
    }

    fn check(m: &JointModel, b: usize, dim: usize) {
        assert_eq!(m.twists.nrows(), b);
        assert_eq!(m.rows.ncols(), b);
        assert_eq!(m.twists.ncols(), dim);
        assert_eq!(m.rows.nrows(), b - dim);
        let p = &m.rows * &m.twists;
        assert!(p.norm() < 1e-12, "rows · twists = {p}");
        let full = m.twists.clone().insert_columns(dim, 0, 0.0);
        let stacked = DMatrix::from_fn(b, b, |i, j| {
            if j < dim {
                full[(i, j)]
            } else {
                m.rows[(j - dim, i)]
            }
        });
        assert_eq!(stacked.rank(1e-9), b);
    }

    /// [`complement`] projects only the unit vectors that can have the largest residual; bit
    /// for bit the same as projecting every one through [`project_out`] (the code it
    /// replaced), so rank decisions and every output are unchanged. Random columns, columns
    /// with exact zeros and coordinate directions (ties between unit vectors), nearly
    /// dependent columns, and the twists of every joint kind at random and axis-aligned
    /// geometry.
    #[test]
    fn complement_equals_one_vector_at_a_time() {
        let mut rng = SplitMix64::new(7);
        for trial in 0..3000 {
            let b = [3, 6][trial % 2];
            let d = trial % b;
            let cols: Vec<Vb> = (0..d)
                .map(|_| {
                    let mut v = [0.0; MAX_B];
                    for x in v.iter_mut().take(b) {
                        // Some exact zeros, as joint twists have.
                        let r = rng.next_signed();
                        *x = if r.abs() < 0.2 { 0.0 } else { r };
                    }
                    v
                })
                .collect();
            check_complement(&cols, b, trial);
        }
        // Structured columns: small integers (many exact ties), nearly dependent pairs.
        for trial in 0..3000 {
            let b = [3, 6][trial % 2];
            let d = trial % b;
            let mut cols: Vec<Vb> = (0..d)
                .map(|_| {
                    let mut v = [0.0; MAX_B];
                    for x in v.iter_mut().take(b) {
                        *x = (rng.below(5) as f64 - 2.0) * [1.0, 0.5][rng.below(2) as usize];
                    }
                    v
                })
                .collect();
            if d >= 2 && trial % 3 == 0 {
                let k = rng.below(b as u64) as usize;
                cols[1] = cols[0];
                cols[1][k] += [1e-9, 1e-7, 1e-12][trial / 3 % 3];
            }
            check_complement(&cols, b, trial);
        }
        // The twists of every joint kind, random and axis-aligned geometry.
        for space in [Space::Spatial, Space::Planar, Space::Spherical] {
            let b = space.b() as usize;
            for kind in JointType::all() {
                for trial in 0..40 {
                    let mut g = random_geometry(kind, space, &mut rng);
                    if trial % 2 == 0 {
                        let axis = |r: u64| {
                            let mut a = [0.0; 3];
                            a[r as usize % 3] = 1.0;
                            a
                        };
                        g.axis = g.axis.map(|_| axis(rng.below(3)));
                        g.axis2 = g.axis2.map(|_| axis(rng.below(3)));
                        g.normal = g.normal.map(|_| axis(rng.below(3)));
                        g.origin = g.origin.map(|o| o.map(|x| (x * 2.0).round()));
                    }
                    if kind.grade() as usize <= b {
                        check_complement(contact_rows_in(kind, &g, space).as_slice(), b, trial);
                    }
                    if let Ok(full) = full_twists(kind, &g, space) {
                        for driven in 0..=full.len() {
                            check_complement(&full.as_slice()[driven..], b, trial);
                        }
                    }
                }
            }
        }
    }

    /// The models bit for bit those of the code before the specialisation (`reference.rs`: runtime
    /// dimension, squared norms summed again for every new vector): every kind in every
    /// space, every number of driven DOF, at random geometry, at axis-aligned geometry with
    /// small integer points (exact zeros and ties), at degenerate geometry (parallel axes,
    /// coincident centres, zero or non-finite fields, huge and tiny coordinates: errors and
    /// the fallback model), and the fallback model itself.
    #[test]
    fn models_equal_the_reference_bit_for_bit() {
        let bits = |v: &Vecs| -> Vec<[u64; MAX_B]> {
            v.as_slice().iter().map(|x| x.map(f64::to_bits)).collect()
        };
        let same = |a: &StackModel, b: &StackModel, what: &str| {
            assert_eq!(a.b, b.b, "{what}");
            assert_eq!(bits(&a.rows), bits(&b.rows), "{what}: rows");
            assert_eq!(bits(&a.twists), bits(&b.twists), "{what}: twists");
        };
        let mut rng = SplitMix64::new(1611);
        let mut compared = 0;
        #[allow(clippy::type_complexity)]
        let mut many: [Vec<(JointType, Geometry, u32, u64, Vecs, String)>; 3] = Default::default();
        for space in [Space::Spatial, Space::Planar, Space::Spherical] {
            for kind in JointType::all() {
                for trial in 0..300 {
                    let mut g = random_geometry(kind, space, &mut rng);
                    let axis = |r: u64| {
                        let mut a = [0.0; 3];
                        a[r as usize % 3] = [1.0, -1.0][r as usize / 3 % 2];
                        a
                    };
                    match trial % 6 {
                        0 | 1 => {}
                        2 => {
                            g.axis = Some(axis(rng.below(6)));
                            g.axis2 = Some(axis(rng.below(6)));
                            g.normal = Some(axis(rng.below(6)));
                            g.origin = g.origin.map(|o| o.map(|x| (x * 2.0).round()));
                            g.origin2 = g.origin2.map(|o| o.map(|x| (x * 2.0).round()));
                        }
                        3 => {
                            // Parallel or nearly parallel directions, coincident centres.
                            let eps = [0.0, 1e-12, 1e-9, 1e-4][rng.below(4) as usize];
                            let a = g.axis.unwrap_or([0.0, 0.0, 1.0]);
                            g.axis2 = Some([a[0] + eps, a[1], a[2]]);
                            g.normal = Some([a[0], a[1] - eps, a[2]]);
                            g.origin2 = g.origin.map(|o| [o[0] + eps, o[1], o[2]]);
                        }
                        4 => {
                            // Extreme magnitudes and non-finite fields.
                            let x = [1e200, 1e-200, f64::INFINITY, f64::NAN, 0.0, -0.0]
                                [rng.below(6) as usize];
                            match rng.below(5) {
                                0 => g.origin = g.origin.map(|o| [x, o[1], o[2]]),
                                1 => g.axis = Some([x, 0.0, 0.0]),
                                2 => g.normal = Some([0.0, x, 0.0]),
                                3 => g.pitch = Some(x),
                                _ => g.origin2 = g.origin2.map(|o| [o[0], o[1], x]),
                            }
                        }
                        _ => {
                            // A field missing.
                            match rng.below(5) {
                                0 => g.origin = None,
                                1 => g.axis = None,
                                2 => g.axis2 = None,
                                3 => g.normal = None,
                                _ => g.origin2 = None,
                            }
                        }
                    }
                    for driven in 0..=kind.grade() as u32 + 1 {
                        let what = format!("{kind:?} {space:?} driven {driven} trial {trial}");
                        let seed = rng.next_u64();
                        let want = match (
                            stack_model(kind, &g, space, driven),
                            old::stack_model(kind, &g, space, driven),
                        ) {
                            (Ok(a), Ok(b)) => {
                                same(&a, &b, &what);
                                b.rows
                            }
                            (Err(a), Err(b)) => {
                                assert_eq!(a.to_string(), b.to_string(), "{what}");
                                old::fallback_model(kind, space, driven, seed).rows
                            }
                            (a, b) => panic!("{what}: {a:?} against {b:?}"),
                        };
                        // The rows of many models at once ([`batch`]), in a random order.
                        many[space as usize].push((
                            kind,
                            g.clone(),
                            driven,
                            seed,
                            want,
                            what.clone(),
                        ));
                        same(
                            &fallback_model(kind, space, driven, seed),
                            &old::fallback_model(kind, space, driven, seed),
                            &what,
                        );
                        compared += 1;
                    }
                }
            }
        }
        assert!(compared > 30_000, "{compared}");
        batch::RUNS.with(|c| c.set([0; 2]));
        for space in [Space::Spatial, Space::Planar, Space::Spherical] {
            let cases = &mut many[space as usize];
            // Kinds and driven DOF mixed in the lanes.
            for i in (1..cases.len()).rev() {
                cases.swap(i, rng.below(i as u64 + 1) as usize);
            }
            let requests = |i: usize| {
                let (k, g, d, s, _, _) = &cases[i];
                (*k, g, *d, *s)
            };
            let mut scratch = batch::Scratch::default();
            let rows = match space {
                Space::Spatial => {
                    batch::rows_many::<6, _>(space, cases.len(), requests, &mut scratch)
                }
                _ => batch::rows_many::<3, _>(space, cases.len(), requests, &mut scratch),
            };
            for (j, (_, _, _, _, want, what)) in cases.iter().enumerate() {
                let got = Vecs::of(rows.get(j));
                assert_eq!(bits(&got), bits(want), "{what}: rows of many");
            }
        }
        // Lanes as well as one at a time (errors, count-only kinds, a length's last few).
        let [lanes, single] = batch::RUNS.with(|c| c.get());
        assert!(
            lanes > 10_000 && single > 1_000,
            "{lanes} in lanes, {single} alone"
        );
    }

    /// [`random_pair_geometry`] draws only the fields a model reads: its models are bit
    /// for bit those at the whole [`random_geometry`] (a field the model reads but not drawn
    /// would be an error, then the fallback model), and the fields drawn are the same.
    #[test]
    fn partial_random_geometry_gives_the_same_models() {
        let bits = |v: &Vecs| -> Vec<[u64; MAX_B]> {
            v.as_slice().iter().map(|x| x.map(f64::to_bits)).collect()
        };
        let mut partial = 0;
        for space in [Space::Spatial, Space::Planar, Space::Spherical] {
            for kind in JointType::all() {
                let reads = model_reads(kind, space);
                partial += usize::from(reads != Drawn::All);
                for seed in 0..200u64 {
                    let whole = random_geometry(kind, space, &mut SplitMix64::new(seed));
                    let g = random_geometry_to(kind, space, &mut SplitMix64::new(seed), reads);
                    let fields = |g: &Geometry| {
                        [g.origin, g.axis, g.axis2, g.normal, g.origin2]
                            .map(|f| f.map(|a| a.map(f64::to_bits)))
                    };
                    for (a, b) in fields(&g).iter().zip(fields(&whole)) {
                        assert!(a.is_none() || *a == b, "{kind:?} {space:?}");
                    }
                    assert!(g.pitch.is_none() || g.pitch == whole.pitch);
                    for driven in 0..=kind.grade() as u32 {
                        let what = format!("{kind:?} {space:?} driven {driven} seed {seed}");
                        match (
                            stack_model(kind, &g, space, driven),
                            stack_model(kind, &whole, space, driven),
                        ) {
                            (Ok(a), Ok(b)) => {
                                assert_eq!(bits(&a.rows), bits(&b.rows), "{what}");
                                assert_eq!(bits(&a.twists), bits(&b.twists), "{what}");
                            }
                            (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string(), "{what}"),
                            (a, b) => panic!("{what}: {a:?} against {b:?}"),
                        }
                    }
                }
            }
        }
        assert!(partial >= 15, "{partial}");
    }

    /// Work regression: [`complement`] projected every unit vector for every new vector
    /// (`B` per row of the model, 30 for a spatial revolute joint); at random geometry only
    /// the one with the largest residual is projected.
    #[test]
    fn complement_projects_one_unit_vector_per_new_vector() {
        let mut rng = SplitMix64::new(3);
        for kind in [JointType::R, JointType::U, JointType::H] {
            let g = random_geometry(kind, Space::Spatial, &mut rng);
            let twists = full_twists(kind, &g, Space::Spatial).expect("modelled");
            PROJECTED.with(|c| c.set(0));
            let rows = complement::<6>(twists.as_slice());
            assert_eq!(rows.len(), 6 - twists.len());
            assert_eq!(PROJECTED.with(|c| c.get()), rows.len(), "{kind:?}");
        }
    }

    /// [`complement`] as it was: every unit vector projected for every new vector.
    fn reference(cols: &[Vb], b: usize) -> Vec<Vb> {
        let mut basis: Vec<Vb> = old::orthonormal(cols, b).as_slice().to_vec();
        let first_new = basis.len();
        while basis.len() < b {
            let mut best: Option<(Vb, f64)> = None;
            for i in 0..b {
                let mut v = [0.0; MAX_B];
                v[i] = 1.0;
                old::project_out(&mut v, &basis, b);
                let n = old::norm(&v, b);
                if best.is_none_or(|(_, w)| n > w) {
                    best = Some((v, n));
                }
            }
            let (v, _) = best.expect("b > 0");
            basis.push(old::normalized(&v, b));
        }
        basis[first_new..].to_vec()
    }

    fn check_complement(cols: &[Vb], b: usize, trial: usize) {
        let got = complement_in(cols, b);
        let want = reference(cols, b);
        assert_eq!(got.len(), want.len(), "trial {trial}: {cols:?}");
        for (g, w) in got.as_slice().iter().zip(&want) {
            let bits = |v: &Vb| v.map(f64::to_bits);
            assert_eq!(bits(g), bits(w), "trial {trial}: {cols:?}");
        }
    }

    #[test]
    fn splitmix_vector() {
        let mut r = SplitMix64::new(0);
        assert_eq!(r.next_u64(), 0xe220a8397b1dcdaf);
        assert_eq!(r.next_u64(), 0x6e789e6aa1b965f4);
    }

    #[test]
    fn every_kind_has_consistent_rows_and_twists() {
        for space in [Space::Spatial, Space::Planar, Space::Spherical] {
            let b = space.b() as usize;
            for kind in JointType::all() {
                let mut rng = SplitMix64::new(kind as u64 + 11);
                let g = random_geometry(kind, space, &mut rng);
                for driven in 0..=kind.grade() as u32 {
                    match joint_model(kind, &g, space, driven) {
                        Ok(m) => check(&m, b, kind.grade() as usize - driven as usize),
                        Err(MotionError::InvalidInSpace { .. }) => {
                            assert!(space != Space::Spatial, "{kind:?} spatial");
                        }
                        Err(e) => panic!("{kind:?} {space:?}: {e}"),
                    }
                }
            }
        }
    }

    /// A driven DOF of a kind without named DOF keeps a generic direction. Formerly
    /// a planar contact joint (one line, two allowed twists) dropped the first twist of its
    /// pivoted basis, and whenever the pivot was the rotation the twist kept was `r × e_ω`, a
    /// pure translation: a fixed fraction of draws gave an input that cannot turn the body.
    /// Nothing driven gives the twists as before, and the same geometry the same model.
    #[test]
    fn driven_dof_without_a_name_is_generic() {
        let mut rng = SplitMix64::new(16);
        for (kind, space) in [
            (JointType::EO, Space::Planar),
            (JointType::RP, Space::Planar),
            (JointType::L, Space::Spherical),
            (JointType::SPSP, Space::Spatial),
            (JointType::CTEP, Space::Spatial),
        ] {
            let b = space.b() as usize;
            let k = kind.grade() as usize;
            for _ in 0..200 {
                let g = random_geometry(kind, space, &mut rng);
                let all = if modelled(kind, space) {
                    full_twists(kind, &g, space).expect("a model")
                } else {
                    complement_in(contact_rows_in(kind, &g, space).as_slice(), b)
                };
                let undriven = stack_model(kind, &g, space, 0).expect("a model");
                assert_eq!(undriven.twists, all, "{kind:?}: nothing driven, as before");
                for driven in 1..=k as u32 {
                    let m = stack_model(kind, &g, space, driven).expect("a model");
                    check(&m.matrices(), b, k - driven as usize);
                    assert_eq!(m, stack_model(kind, &g, space, driven).expect("a model"));
                    // Inside the allowed motions: annihilated by the undriven rows.
                    for t in m.twists.as_slice() {
                        for r in undriven.rows.as_slice() {
                            assert!(old::dot(r, t, b).abs() < 1e-12, "{kind:?}");
                        }
                    }
                }
                if space == Space::Planar {
                    // One twist kept: it turns the body (ω ≠ 0) and moves the origin.
                    let t = stack_model(kind, &g, space, 1).expect("a model").twists;
                    assert!(
                        t.as_slice()[0][0].abs() > 1e-6,
                        "{kind:?}: a pure translation"
                    );
                }
            }
        }
        // The fallback model too: nothing driven as before, driven generic.
        for seed in 0..50 {
            let m = fallback_model(JointType::EO, Space::Planar, 1, seed);
            check(&m.matrices(), 3, 1);
            assert!(m.twists.as_slice()[0][0].abs() > 1e-6, "a pure translation");
        }
    }

    #[test]
    fn planar_revolute_twist() {
        let g = Geometry {
            origin: Some([2.0, 3.0, 0.0]),
            ..Geometry::default()
        };
        let m = joint_model(JointType::R, &g, Space::Planar, 0).unwrap();
        assert_eq!(m.twists.column(0).as_slice(), &[1.0, 3.0, -2.0]);
        // The velocity of the pin point itself is zero: v_p = v_O + ω ẑ × p.
        let (w, vx, vy) = (1.0, 3.0, -2.0);
        assert_eq!((vx - w * 3.0, vy + w * 2.0), (0.0, 0.0));
    }

    #[test]
    fn spatial_revolute_and_driven_order() {
        let g = Geometry {
            origin: Some([1.0, 0.0, 0.0]),
            axis: Some([0.0, 0.0, 2.0]),
            ..Geometry::default()
        };
        let r = joint_model(JointType::R, &g, Space::Spatial, 0).unwrap();
        assert_eq!(
            r.twists.column(0).as_slice(),
            &[0.0, 0.0, 1.0, 0.0, -1.0, 0.0]
        );
        // C with the slide driven keeps only the turn.
        let c = joint_model(JointType::C, &g, Space::Spatial, 1).unwrap();
        assert_eq!(c.twists.column(0).as_slice(), r.twists.column(0).as_slice());
        check(&c, 6, 1);
    }

    #[test]
    fn missing_fields_are_named() {
        let e = joint_model(JointType::U, &Geometry::default(), Space::Spatial, 0).unwrap_err();
        assert!(matches!(e, MotionError::MissingField { field: "axis", .. }));
        let g = Geometry {
            origin: Some([0.0; 3]),
            axis: Some([1.0, 0.0, 0.0]),
            ..Geometry::default()
        };
        let e = joint_model(JointType::U, &g, Space::Spatial, 0).unwrap_err();
        assert!(matches!(
            e,
            MotionError::MissingField { field: "axis2", .. }
        ));
        let m = Mechanism::from_parts(
            "t",
            Space::Spatial,
            BodyId::Int(1),
            vec![],
            vec![JointSpec::new(JointType::S, 1, 2, 0)],
        );
        let e = configure(&m).unwrap_err();
        assert_eq!(
            e.to_string(),
            "joint `1-2`: a S joint needs `origin` for geometric analysis"
        );
    }

    #[test]
    fn ss_bar_has_one_isolated_spin() {
        let s = |p: [f64; 3]| {
            let g = Geometry {
                origin: Some(p),
                ..Geometry::default()
            };
            joint_model(JointType::S, &g, Space::Spatial, 0).unwrap()
        };
        let (a, b) = (s([0.1, 0.2, 0.3]), s([1.0, -0.5, 0.7]));
        let stacked = DMatrix::from_fn(6, 6, |i, j| {
            if i < 3 {
                a.rows[(i, j)]
            } else {
                b.rows[(i - 3, j)]
            }
        });
        let nullity = 6 - stacked.rank(1e-9);
        assert_eq!(nullity, 1);
        // The spin: rotation about the line through both centres.
        let u = Vector3::new(0.9, -0.7, 0.4).normalize();
        let t = DVector::from_vec(spatial_rot(&u, &Vector3::new(0.1, 0.2, 0.3)).to_vec());
        assert!((&stacked * t).norm() < 1e-12);
    }

    #[test]
    fn realize_is_per_joint() {
        let j = |a, b| JointSpec::new(JointType::R, a, b, 0);
        let m1 = Mechanism::from_parts(
            "a",
            Space::Spatial,
            BodyId::Int(1),
            vec![],
            vec![j(1, 2), j(2, 3)],
        );
        let m2 = Mechanism::from_parts(
            "b",
            Space::Spatial,
            BodyId::Int(1),
            vec![],
            vec![j(1, 2), j(2, 3), j(3, 1)],
        );
        let (r1, r2) = (realize(&m1, 5), realize(&m2, 5));
        assert_eq!(r1[..], r2[..2]);
        assert_ne!(r1[0], r1[1]);
    }
}
