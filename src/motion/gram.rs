//! Gram-Schmidt on stack vectors of the motion space: orthonormal bases and complements, bit
//! for bit reproducible (every sum in index order from 0).

use nalgebra::DMatrix;

pub(super) fn columns(b: usize, cols: &[Vb]) -> DMatrix<f64> {
    DMatrix::from_fn(b, cols.len(), |i, j| cols[j][i])
}

/// The vectors as the rows of a matrix.
pub(super) fn as_rows(b: usize, rows: &[Vb]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), b, |i, j| rows[i][j])
}

// The Gram-Schmidt helpers run on stack vectors of the motion space (B <= 6): they are called
// for every joint of every realization. Their arithmetic is nalgebra's for vectors shorter
// than 8 (dot products summed in order from 0, `normalize` as division by the norm), so the
// results are bit for bit those of the DVector code they replaced.

/// Largest motion-space dimension.
pub(super) const MAX_B: usize = 6;

pub(super) type Vb = [f64; MAX_B];

/// Up to [`MAX_B`] vectors of the motion space, on the stack (a joint's twists or rows).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Vecs {
    v: [Vb; MAX_B],
    n: usize,
}

impl Vecs {
    pub(super) const EMPTY: Vecs = Vecs {
        v: [[0.0; MAX_B]; MAX_B],
        n: 0,
    };

    pub(super) fn of(list: &[Vb]) -> Vecs {
        let mut out = Vecs::EMPTY;
        list.iter().for_each(|&x| out.push(x));
        out
    }

    /// Append `x` (never more than [`MAX_B`] vectors: motion spaces have no more).
    pub(super) fn push(&mut self, x: Vb) {
        if let Some(slot) = self.v.get_mut(self.n) {
            *slot = x;
            self.n += 1;
        }
    }

    /// The first `n` of `v`.
    pub(super) fn from_parts(v: [Vb; MAX_B], n: usize) -> Vecs {
        Vecs { v, n: n.min(MAX_B) }
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
// they replaced.

pub(super) fn dot<const N: usize>(a: &Vb, b: &Vb) -> f64 {
    let mut r = 0.0;
    for (x, y) in a.iter().zip(b).take(N) {
        r += x * y;
    }
    r
}

pub(super) fn norm<const N: usize>(a: &Vb) -> f64 {
    dot::<N>(a, a).sqrt()
}

/// `v -= (q · v) q` twice over the basis (re-orthogonalization).
pub(super) fn project_out<const N: usize>(v: &mut Vb, basis: &[Vb]) {
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
pub(super) fn normalized<const N: usize>(v: &Vb, len: f64) -> Vb {
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
pub(super) fn project_unit<const N: usize>(i: usize, basis: &[Vb]) -> Vb {
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
pub(super) fn complement<const N: usize>(cols: &[Vb]) -> Vecs {
    complement_of::<N>(orthonormal::<N>(cols))
}

/// [`complement`] of the span of `basis`, the output of [`orthonormal`] (a caller that has
/// it already need not compute it again).
pub(super) fn complement_of<const N: usize>(mut basis: Vecs) -> Vecs {
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
    pub(super) static PROJECTED: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// How far below the largest estimated squared residual a unit vector in [`complement`] is
/// still projected. The estimate and the projection differ by rounding (about `1e-15`, and
/// at most the basis' loss of orthogonality); the largest squared residual is at least
/// `1 / B`, so a unit vector this far below cannot have the largest.
pub(super) const CANDIDATE_GAP: f64 = 1e-4;

/// Orthonormalize `cols` (modified Gram-Schmidt, twice); vectors that vanish are dropped.
pub(super) fn orthonormal<const N: usize>(cols: &[Vb]) -> Vecs {
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

/// [`orthonormal`] of `vs` when it drops none of them and they are far from dependent (each
/// keeps a residual of at least 1e-3 of its norm after projecting out the ones before it).
/// One Gram-Schmidt pass serves both tests: while no vector is dropped, the basis built by
/// [`orthonormal`] and the one the residuals are measured against are the same vectors.
pub(super) fn orthonormal_if_well_conditioned<const N: usize>(vs: &[Vb]) -> Option<Vecs> {
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
