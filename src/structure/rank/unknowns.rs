//! Each body's reduced unknowns: the complement of the null space of its pairs' stacked rows
//! (its isolated freedoms), screened for full column rank on the stack, and written about the
//! body's own reference point at the file's geometry.

use super::Bases;
use super::attempt::{Attempt, Touching};
use super::cache::Digest;
use super::float::{Tol, svd_parts};
use super::rows::{PairRows, RowsView};
use crate::geometry::GeometryUsed;
use crate::mechanism::{Geometry, Mechanism, Space};
use crate::motion;
use crate::structure::count::Equations;
use nalgebra::DMatrix;

impl Attempt<'_> {
    /// Every node's reduced unknowns (each body on its own, in parallel): the frame none, an
    /// element node the row space of its joint's rows, a body [`reduced_basis`] (or
    /// [`local_basis`] at the file's geometry) of the pairs touching it. `prev`: the last
    /// attempt's bases and which pairs were built again since.
    pub(super) fn reduced_unknowns(
        &self,
        eqs: &Equations,
        free: &PairRows,
        touching: &Touching,
        prev: Option<(Bases, Vec<bool>)>,
    ) -> Bases {
        let b = self.b;
        // The first pin pair of every element node.
        let mut pin_pair = vec![usize::MAX; eqs.elements.len()];
        for e in (0..eqs.len()).rev() {
            if eqs.is_element(eqs.hub[e]) && !eqs.input_only[e] {
                pin_pair[eqs.hub[e] - eqs.bodies] = e;
            }
        }
        crate::par::map(eqs.nodes, |body| {
            if body == self.m.frame {
                return Some(DMatrix::zeros(b, 0));
            }
            if eqs.is_element(body) {
                // The shared element moves only across its joint's constraint directions: its
                // unknowns are the row space of the joint's rows (orthonormal, so their
                // transpose). (At the file's configuration `rows` may already have lost
                // dependent equations: the joint's full rows are in `free` then.)
                let e = pin_pair[body - eqs.bodies];
                return Some(
                    free.try_get(e)
                        .or(self.rows.try_get(e))
                        .map_or_else(|| DMatrix::zeros(b, 0), |r| r.transpose()),
                );
            }
            let mine = touching.pairs(body);
            if let Some((bases, changed)) = &prev
                && !mine.iter().any(|&e| changed[e as usize])
            {
                // Same rows, same tolerance: the last attempt's basis.
                return bases[body].clone();
            }
            self.body_basis(body, mine, eqs)
        })
    }

    /// A body's reduced unknowns from the pairs `mine` touching it, through the cache when
    /// there is one.
    ///
    /// Isolated means undrivable: a motion across a cut of two or more constraining joints.
    /// A body on one joint moves by that joint's own DOF, which an input drives; a body on a
    /// free joint (F: no constraint at all) moves by its DOF too, every motion of the body, as
    /// a car's chassis pitching about its wheels' axle; a body others reach the frame through
    /// is dragged by the inputs beyond it, as the inner links of a chain of ball joints (found
    /// only when a body has an isolated freedom, which few have).
    fn body_basis(&self, body: usize, mine: &[u32], eqs: &Equations) -> Option<DMatrix<f64>> {
        let v = self.pairs_basis(body, mine, eqs);
        if v.as_ref().is_some_and(|v| v.ncols() < self.b)
            && self
                .separating
                .get_or_init(|| crate::mobility::separating_bodies(self.m))
                .get(body)
                .copied()
                .unwrap_or(false)
        {
            return self
                .local
                .as_ref()
                .and_then(|lf| lf.frame[body].as_ref())
                .cloned();
        }
        v
    }

    /// [`Self::body_basis`] before the bodies others reach the frame through are set apart.
    fn pairs_basis(&self, body: usize, mine: &[u32], eqs: &Equations) -> Option<DMatrix<f64>> {
        let b = self.b;
        let frame = self.local.as_ref().and_then(|lf| lf.frame[body].as_ref());
        if mine
            .iter()
            .any(|&e| self.m.joints[eqs.joint[e as usize]].grade() as usize >= b)
        {
            return frame.cloned();
        }
        let mut joints = mine
            .iter()
            .map(|&e| e as usize)
            .filter(|&e| self.rows.nrows(e) > 0)
            .map(|e| eqs.joint[e]);
        let first = joints.next();
        if !joints.any(|j| Some(j) != first) {
            return frame.cloned();
        }
        let basis = |rows: &PairRows| match frame {
            Some(s) => Some(local_basis(
                b,
                mine.iter().map(|&e| rows.get(e as usize)),
                s,
                &self.tol,
            )),
            None => reduced_basis(b, mine.iter().map(|&e| rows.get(e as usize)), &self.tol),
        };
        let Some(c) = self.cache else {
            return basis(&self.rows);
        };
        let mut d = Digest::new(2);
        self.tol_words.iter().for_each(|&w| d.word(w));
        mine.iter().for_each(|&e| d.wide(self.rd[e as usize]));
        if let Some(s) = frame {
            d.matrix(s);
        }
        let k = d.finish();
        if let Some(hit) = c.get_basis(k) {
            return hit;
        }
        let v = basis(&self.rows);
        c.put_basis(k, &v);
        v
    }
}

/// Stacks of more rows than this are reduced by a QR before the SVD in [`reduced_basis`].
const TALL_STACK_ROWS: usize = 96;

/// The reduced unknowns of a body whose pairs have the constraint rows `rows` (its neighbours
/// held fixed): `None` when the stacked rows have full column rank (no isolated freedom: the
/// body keeps all `b` unknowns, basis the identity), else an orthonormal basis of the
/// complement of their null space.
///
/// Full column rank is first screened by [`surely_full_rank`]: a singular value ratio above 1e-6 is
/// far from the SVD threshold of [`REL_TOL`](super::float::REL_TOL), so the SVD would keep every
/// direction too. Anything else goes to the padded SVD.
pub(super) fn reduced_basis<'a>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>> + Clone,
    t: &Tol,
) -> Option<DMatrix<f64>> {
    // The pairs' rows are loaded into the cache together (see [`warm`](super::proof::warm)) as they
    // are counted.
    let mut touched = 0.0;
    let total: usize = rows
        .clone()
        .map(|r| {
            if r.ncols() > 0 {
                touched += (0..r.nrows())
                    .map(|i| r[(i, 0)] + r[(i, r.ncols() - 1)])
                    .sum::<f64>();
            }
            r.nrows()
        })
        .sum();
    std::hint::black_box(touched);
    if total == 0 {
        return Some(DMatrix::zeros(b, 0));
    }
    if total >= b && t.abs == 0.0 && surely_full_rank(b, total, rows.clone()) {
        return None;
    }
    let mut s = DMatrix::<f64>::zeros(total, b);
    let mut r0 = 0;
    for r in rows {
        s.view_mut((r0, 0), (r.nrows(), b)).copy_from(&r);
        r0 += r.nrows();
    }
    Some(row_space(b, s, t))
}

/// An orthonormal basis (`b × rank`) of the row space of the stacked rows `s` (`total × b`),
/// the right singular vectors above the threshold.
fn row_space(b: usize, s: DMatrix<f64>, t: &Tol) -> DMatrix<f64> {
    let total = s.nrows();
    // Only V is needed: skipping U leaves V and the singular values unchanged. A body held
    // by many pairs (the hub of a star: 10^5 pairs) first has its tall stack reduced to the
    // b × b triangle of its QR (same singular values and right singular vectors), instead of
    // an SVD padded to total × total; the threshold keeps the stack's size.
    let (sv, tol, v_t) = if total > TALL_STACK_ROWS {
        let r = s.qr().r();
        let (sv, _, _, v_t) = svd_parts(&r, false, true, t);
        let max = sv.iter().copied().fold(0.0, f64::max);
        (sv, t.cut(max, total), v_t)
    } else {
        let (sv, tol, _, v_t) = svd_parts(&s, false, true, t);
        (sv, tol, v_t)
    };
    let v_t = v_t.expect("requested V^T");
    t.note_all(&sv, tol);
    let keep: Vec<usize> = (0..sv.len()).filter(|&i| sv[i] > tol).collect();
    let mut qb = DMatrix::<f64>::zeros(b, keep.len());
    for (c, &i) in keep.iter().enumerate() {
        for k in 0..b {
            qb[(k, c)] = v_t[(i, k)];
        }
    }
    qb
}

/// Body-local twists at the file's geometry. Each body's unknowns are written about its own
/// reference point (the mean of the origins of its pairs' joints, at the dimensionless
/// geometry), `t_centre = S_x · t_local`: an invertible change of columns per body, so ranks
/// and left null spaces (the redundancies and their weights) are unchanged, but the rows a body
/// sees carry lever arms of its own size instead of its distance from the centre. A bar of a
/// row of 1,000 windows sits 500 link lengths from the centre: its rotation about its two pins
/// then changes its rows by about 1/500 of their size, which the precision-derived threshold
/// (lever 500) took for an isolated freedom. The same change of coordinates as the sparse path
/// of the geometric analysis (`rigidity::geometric::sparse_float`).
pub(crate) struct LocalFrames {
    /// `S_x` per node (`None`: the frame, element nodes, bodies without a joint point).
    pub(super) frame: Vec<Option<DMatrix<f64>>>,
    /// The largest lever arm of a joint point about its body's reference point (in
    /// characteristic lengths).
    lever: f64,
}

impl LocalFrames {
    /// The frames of `m`'s bodies at the (dimensionless) file geometry `geoms`; `None` for a
    /// spherical mechanism (no translations to move).
    pub(super) fn new(m: &Mechanism, geoms: &[Geometry], eqs: &Equations) -> Option<LocalFrames> {
        if m.space == Space::Spherical || geoms.len() != m.joints.len() {
            return None;
        }
        let nb = eqs.nodes;
        let mut sum = vec![[0.0f64; 3]; nb];
        let mut count = vec![0usize; nb];
        let body = |x: usize| x != m.frame && !eqs.is_element(x);
        for e in 0..eqs.len() {
            let [h, o] = eqs.bodies(e);
            let Some(p) = geoms[eqs.joint[e]].origin else {
                continue;
            };
            if h == o || !p.iter().all(|v| v.is_finite()) {
                continue;
            }
            for x in [h, o] {
                if body(x) {
                    (0..3).for_each(|i| sum[x][i] += p[i]);
                    count[x] += 1;
                }
            }
        }
        let centre: Vec<Option<[f64; 3]>> = (0..nb)
            .map(|x| (count[x] > 0).then(|| sum[x].map(|v| v / count[x] as f64)))
            .collect();
        let mut lever = 0.0f64;
        for e in 0..eqs.len() {
            let [h, o] = eqs.bodies(e);
            let g = &geoms[eqs.joint[e]];
            for x in [h, o] {
                let Some(c) = centre[x] else {
                    continue;
                };
                for p in [g.origin, g.origin2].into_iter().flatten() {
                    for i in 0..3 {
                        let d = (p[i] - c[i]).abs();
                        if d.is_finite() {
                            lever = lever.max(d);
                        }
                    }
                }
            }
        }
        let frame = centre
            .into_iter()
            .map(|c| c.and_then(|c| motion::twist_shift(m.space, c)))
            .collect();
        Some(LocalFrames { frame, lever })
    }

    /// [`crate::geometry::file_threshold`] with the body-local lever arm: a direction rounded by
    /// `δ_d` moves a row written about its body's reference point by `δ_d` times its distance
    /// from that point.
    /// Every pair's rows made orthonormal on the local twists of one of its bodies (the
    /// other one, that body being the frame): row operations within the pair, which change no
    /// rank and keep the pair's row space. The rows are built orthonormal about the centre;
    /// moved to a body's own reference point `d` link lengths away, they shrink to about `1/d`
    /// and lean on each other (the change of coordinates has a condition number of about
    /// `d²`), and every rank decision against the precision-derived threshold (made for
    /// orthonormal rows) took them for dependent ones: a row of 200 windows written to one
    /// decimal had 525 of its 1,196 equations set aside where `mbsa rigid` found none. The two
    /// bodies of a pair are neighbours, so the rows stay well scaled on the other body too.
    pub(super) fn orthonormalize_rows(&self, m: &Mechanism, eqs: &Equations, rows: &mut PairRows) {
        for e in 0..rows.len() {
            let [h, o] = eqs.bodies(e);
            let x = if o != m.frame { o } else { h };
            let Some(s) = self.frame.get(x).and_then(Option::as_ref) else {
                continue;
            };
            if h == o || rows.nrows(e) == 0 {
                continue;
            }
            if let Some(out) = orthonormal_on(&rows.get(e).into_owned(), s) {
                rows.set(e, &out);
            }
        }
    }

    pub(super) fn threshold(&self, used: &GeometryUsed) -> f64 {
        let Some(delta) = used.precision.filter(|&d| d > 0.0) else {
            return 0.0;
        };
        let directions = used.direction_precision.unwrap_or(delta);
        let length = used.scale.map_or(1.0, |s| s.length);
        crate::motion::FILE_TOL_FACTOR * (delta / length + directions * self.lever)
    }
}

/// The rows `r` made orthonormal on the twists `r · s` by Gram-Schmidt (twice), the same row
/// operations on `r`; `None` when a row is dependent there (`s` is invertible: rounding only).
fn orthonormal_on(r: &DMatrix<f64>, s: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let local = r * s;
    let mut done: Vec<(Vec<f64>, Vec<f64>)> = Vec::with_capacity(r.nrows());
    for i in 0..r.nrows() {
        let mut v: Vec<f64> = local.row(i).iter().copied().collect();
        let mut w: Vec<f64> = r.row(i).iter().copied().collect();
        for _ in 0..2 {
            for (qv, qw) in &done {
                let d: f64 = qv.iter().zip(&v).map(|(a, c)| a * c).sum();
                v.iter_mut().zip(qv).for_each(|(t, q)| *t -= d * q);
                w.iter_mut().zip(qw).for_each(|(t, q)| *t -= d * q);
            }
        }
        let n = v.iter().map(|t| t * t).sum::<f64>().sqrt();
        if !(n > 1e-12 && n.is_finite()) {
            return None;
        }
        v.iter_mut().for_each(|t| *t /= n);
        w.iter_mut().for_each(|t| *t /= n);
        done.push((v, w));
    }
    Some(DMatrix::from_fn(r.nrows(), r.ncols(), |i, k| done[i].1[k]))
}

/// [`reduced_basis`] about the body's reference point: the stacked rows times `s` (its
/// [`LocalFrames`] change of coordinates), each scaled to unit norm, their null space by the
/// SVD at `t`; the unknowns kept are `s` times the complement (all of `s` when nothing is
/// isolated), so the blocks see the body's local twists.
pub(super) fn local_basis<'a>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>> + Clone,
    s: &DMatrix<f64>,
    t: &Tol,
) -> DMatrix<f64> {
    let total: usize = rows.clone().map(|r| r.nrows()).sum();
    if total == 0 {
        return DMatrix::zeros(b, 0);
    }
    let mut a = DMatrix::<f64>::zeros(total, b);
    let mut r0 = 0;
    for r in rows {
        a.view_mut((r0, 0), (r.nrows(), b))
            .copy_from(&(r.into_owned() * s));
        r0 += r.nrows();
    }
    for mut row in a.row_iter_mut() {
        let n = row.norm();
        if n > 0.0 {
            row.unscale_mut(n);
        }
    }
    let ql = row_space(b, a, t);
    if ql.ncols() >= b {
        return s.clone();
    }
    s * ql
}

/// Whether the stacked `rows` (`b` columns) surely have full column rank, far from the SVD
/// threshold. Gaussian elimination with partial pivoting picks `b` rows, a square submatrix `T`
/// with `|det T|` the product of the pivots and `σ_min(T) ≥ |det T| / ‖T‖_F^(b−1)`; removing rows
/// never raises `σ_min`, and `σ_max ≤ F`, the Frobenius norm of all rows. So `|det T| > 1e-6 · F ·
/// ‖T‖_F^(b−1)` means `σ_min > 1e-6 · σ_max`, far above the SVD threshold (`n ·`
/// [`REL_TOL`](super::float::REL_TOL) with n ≤ 48 rows here). Runs for every body, on the stack.
fn surely_full_rank<'a>(b: usize, total: usize, rows: impl Iterator<Item = RowsView<'a>>) -> bool {
    // The arrays sized to the stack of rows (zeroing 48 rows for a body held by two pairs
    // cost as much as the elimination).
    match total {
        0..=8 => full_rank_within::<8>(b, rows),
        9..=16 => full_rank_within::<16>(b, rows),
        17..=24 => full_rank_within::<24>(b, rows),
        25..=32 => full_rank_within::<32>(b, rows),
        _ => full_rank_within::<48>(b, rows),
    }
}

/// [`surely_full_rank`] with arrays of `MAX_ROWS` rows (fewer rows than that in `rows`, or
/// the answer is `false`).
fn full_rank_within<'a, const MAX_ROWS: usize>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>>,
) -> bool {
    elimination::<MAX_ROWS>(b, rows).is_some_and(|e| e.proves(b))
}

/// What [`full_rank_within`] decides on: `|det T|` (the product of the pivots' magnitudes),
/// `F²` (all rows) and `‖T‖_F²` (the pivot rows).
#[derive(Clone, Copy, Debug)]
struct Eliminated {
    det: f64,
    frob2: f64,
    sub2: f64,
}

impl Eliminated {
    /// `|det T| > 1e-6 · F · ‖T‖_F^(b−1)`.
    fn proves(&self, b: usize) -> bool {
        self.det > 1e-6 * self.frob2.sqrt() * self.sub2.sqrt().powi(b as i32 - 1)
    }
}

/// The elimination of [`full_rank_within`]; `None` where it answers `false` before the test
/// (more than `MAX_ROWS` rows, fewer than `b`, all zero, a zero pivot).
///
/// The stack is held column by column (`a[k][row]`): a step's multipliers `row[c] / pivot`
/// and its updates `row[k] −= f · top[k]` run over consecutive rows, two to an instruction,
/// and only on the columns still to be read (`c + 1 .. b`). Every entry that is read gets
/// the operations of the row-major elimination it replaced (kept as the tests' reference,
/// `elimination_reference`) in the same order, and each pivot is the same row (the last of
/// the largest magnitudes, as `max_by` of `total_cmp` chose it), so the three numbers are
/// bit for bit the same. The row-major elimination divided one row at a time and updated
/// the dead columns too.
#[allow(clippy::needless_range_loop)]
fn elimination<'a, const MAX_ROWS: usize>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>>,
) -> Option<Eliminated> {
    if b > 6 {
        return None;
    }
    let mut a = [[0.0f64; MAX_ROWS]; 6];
    let mut norm2 = [0.0f64; MAX_ROWS];
    let mut n = 0;
    for r in rows {
        for i in 0..r.nrows() {
            if n == MAX_ROWS {
                return None;
            }
            let mut s = 0.0;
            for k in 0..b {
                let v = r[(i, k)];
                a[k][n] = v;
                s += v * v;
            }
            norm2[n] = s;
            n += 1;
        }
    }
    let frob2: f64 = norm2[..n].iter().sum();
    if n < b || frob2 == 0.0 {
        return None;
    }
    let mut det = 1.0f64;
    let mut sub2 = 0.0;
    let mut f = [0.0f64; MAX_ROWS];
    for c in 0..b {
        // Magnitudes have no sign bit: `total_cmp` orders them as their bits do. `>=` keeps
        // the last of equal ones, as `max_by` did.
        let mut p = c;
        let mut best = 0u64;
        for (i, v) in a[c][..n].iter().enumerate().skip(c) {
            let key = v.to_bits() & !(1u64 << 63);
            if key >= best {
                best = key;
                p = i;
            }
        }
        let pivot = a[c][p];
        if pivot == 0.0 {
            return None;
        }
        // Columns before `c` are never read again: only the live ones swap.
        for col in a[c..b].iter_mut() {
            col.swap(c, p);
        }
        norm2.swap(c, p);
        det *= pivot.abs();
        sub2 += norm2[c];
        for (fi, &x) in f[c + 1..n].iter_mut().zip(&a[c][c + 1..n]) {
            *fi = x / pivot;
        }
        for k in c + 1..b {
            let t = a[k][c];
            for (x, &fi) in a[k][c + 1..n].iter_mut().zip(&f[c + 1..n]) {
                *x -= fi * t;
            }
        }
    }
    Some(Eliminated { det, frob2, sub2 })
}

/// [`elimination`] as it was (row by row, the row updates over columns `c..b`): the tests'
/// reference.
#[cfg(test)]
fn elimination_reference<'a, const MAX_ROWS: usize>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>>,
) -> Option<Eliminated> {
    let mut a = [[0.0f64; 6]; MAX_ROWS];
    let mut norm2 = [0.0f64; MAX_ROWS];
    let mut n = 0;
    if b > 6 {
        return None;
    }
    for r in rows {
        for i in 0..r.nrows() {
            if n == MAX_ROWS {
                return None;
            }
            for k in 0..b {
                a[n][k] = r[(i, k)];
                norm2[n] += a[n][k] * a[n][k];
            }
            n += 1;
        }
    }
    let frob2: f64 = norm2[..n].iter().sum();
    if n < b || frob2 == 0.0 {
        return None;
    }
    let mut det = 1.0f64;
    let mut sub2 = 0.0;
    for c in 0..b {
        let p = (c..n)
            .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
            .unwrap_or(c);
        let pivot = a[p][c];
        if pivot == 0.0 {
            return None;
        }
        a.swap(c, p);
        norm2.swap(c, p);
        det *= pivot.abs();
        sub2 += norm2[c];
        let top = a[c];
        for row in a.iter_mut().take(n).skip(c + 1) {
            let f = row[c] / pivot;
            for k in c..b {
                row[k] -= f * top[k];
            }
        }
    }
    Some(Eliminated { det, frob2, sub2 })
}

/// [`full_rank_within`] as it was: the tests' reference.
#[cfg(test)]
fn full_rank_within_reference<'a, const MAX_ROWS: usize>(
    b: usize,
    rows: impl Iterator<Item = RowsView<'a>>,
) -> bool {
    elimination_reference::<MAX_ROWS>(b, rows).is_some_and(|e| e.proves(b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::rank::rows::view;

    /// The body screen's elimination over fixed-width rows decides as the reference (updates
    /// over the live columns only): random stacks of 3 or 6 columns and 1 to 48 rows, of full
    /// rank, rank deficient (repeated or combined rows), scaled and near the screen's bound.
    #[test]
    fn body_screen_is_the_reference() {
        fn stack<const M: usize>(rows: &DMatrix<f64>, b: usize) -> (bool, bool) {
            let view = view(rows);
            let new = full_rank_within::<M>(b, std::iter::once(view));
            let old = full_rank_within_reference::<M>(b, std::iter::once(view));
            (new, old)
        }
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut seen = [0usize; 2];
        for i in 0..6000 {
            let b = if i % 2 == 0 { 6 } else { 3 };
            let n = 1 + rng.below(48) as usize;
            let mut a = DMatrix::<f64>::from_fn(n, b, |_, _| rng.next_signed());
            match rng.below(5) {
                0 if n > 1 => {
                    let (x, y) = (rng.below(n as u64) as usize, rng.below(n as u64) as usize);
                    let row = a.row(x).clone_owned();
                    a.row_mut(y).copy_from(&row);
                }
                1 => {
                    // A column nearly dependent on another: near the 1e-6 bound.
                    let (c, d) = (rng.below(b as u64) as usize, rng.below(b as u64) as usize);
                    let f = 10f64.powi(-(rng.below(10) as i32));
                    for r in 0..n {
                        let v = a[(r, d)] + f * rng.next_signed();
                        a[(r, c)] = v;
                    }
                }
                2 => {
                    let c = rng.below(b as u64) as usize;
                    let f = 10f64.powi(-(rng.below(9) as i32));
                    a.column_mut(c).scale_mut(f);
                }
                _ => {}
            }
            let (new, old) = match n {
                0..=8 => stack::<8>(&a, b),
                9..=16 => stack::<16>(&a, b),
                _ => stack::<48>(&a, b),
            };
            assert_eq!(new, old, "case {i}");
            seen[usize::from(new)] += 1;
        }
        assert!(seen.iter().all(|&c| c > 500), "{seen:?}");
    }

    /// The column-major elimination gives the numbers of the row-major one bit for bit
    /// (`|det T|`, `F²`, `‖T‖_F²`, or the same early stop), on stacks of 3 or 6 columns and 1
    /// to 50 rows: random, small integers (ties between pivot candidates of either sign),
    /// exact zeros (zero pivots), repeated rows, tiny, huge, infinite and NaN entries.
    #[test]
    fn column_major_elimination_is_the_reference() {
        fn numbers<const M: usize>(a: &DMatrix<f64>, b: usize) -> [Option<[u64; 3]>; 2] {
            let bits = |e: Option<Eliminated>| {
                e.map(|e| [e.det.to_bits(), e.frob2.to_bits(), e.sub2.to_bits()])
            };
            // Split into pairs of one to three rows, as the bodies' stacks come.
            let split = |a: &DMatrix<f64>| -> Vec<DMatrix<f64>> {
                let mut out = Vec::new();
                let mut r = 0;
                while r < a.nrows() {
                    let k = (1 + r % 3).min(a.nrows() - r);
                    out.push(a.rows(r, k).into_owned());
                    r += k;
                }
                out
            };
            let parts = split(a);
            [
                bits(elimination::<M>(b, parts.iter().map(view))),
                bits(elimination_reference::<M>(b, parts.iter().map(view))),
            ]
        }
        let mut rng = crate::rng::SplitMix64::new(11);
        let mut seen = [0usize; 3];
        for i in 0..30_000 {
            let b = if i % 2 == 0 { 6 } else { 3 };
            let n = 1 + rng.below(50) as usize;
            let style = rng.below(8);
            let a = DMatrix::<f64>::from_fn(n, b, |_, _| {
                let r = rng.next_signed();
                match (style, rng.below(16)) {
                    (0, _) => (r * 3.0).round(),
                    (1, 0..=7) => 0.0,
                    (2, 0) => [f64::NAN, f64::INFINITY, -f64::INFINITY][rng.below(3) as usize],
                    (3, _) => r * 1e-160,
                    (4, _) => r * 1e160,
                    (5, 0..=3) => -0.0,
                    _ => r,
                }
            });
            let a = if style == 6 && n > 1 {
                // Repeated rows (a deficient stack).
                DMatrix::from_fn(n, b, |r, c| a[(r / 2, c)])
            } else {
                a
            };
            let [new, old] = match n {
                0..=8 => numbers::<8>(&a, b),
                9..=16 => numbers::<16>(&a, b),
                17..=24 => numbers::<24>(&a, b),
                25..=32 => numbers::<32>(&a, b),
                _ => numbers::<48>(&a, b),
            };
            assert_eq!(new, old, "case {i}");
            let k = match new {
                None => 0,
                Some(e) if f64::from_bits(e[0]).is_finite() => 1,
                Some(_) => 2,
            };
            seen[k] += 1;
        }
        assert!(seen.iter().all(|&c| c > 200), "{seen:?}");
    }
}
