//! The solve order in which the constraint rows set aside at the file's configuration are
//! chosen: the count decomposition of a first choice, each of its groups split into the
//! groups that all its own equations (the rows set aside included) determine in turn, and
//! the groups it left in the under-determined part found.
//!
//! Why: a row is set aside when it depends on the rows kept before it, so the order decides
//! which group pays for a dependency. A group whose own rows were spent on a later group's
//! dependency merges with that group; its own equations, all of them, still determine it
//! first. The split below is read off the motions of the group with one body removed, which
//! depend on the equations only, not on which of them a greedy choice kept.

use super::float::{MAX_DENSE_UNKNOWNS, Tol};
use super::rows::{PairRows, RowsView};
use super::unknowns::LocalFrames;
use crate::mechanism::Mechanism;
use crate::structure::count::{Equations, Part, decompose};
use nalgebra::DMatrix;

/// A node's place in the solve order: its group's level and number, then its part within
/// the group (the frame and an over-determined part first, an under-determined part last).
pub(super) type SolveKeys = Vec<(usize, usize, usize)>;

/// Pair `e`'s row `r` (`i`-th) on node `x`'s columns: its twist about its own reference
/// point when `local` has one, signed.
pub(super) fn on_node(
    local: Option<&LocalFrames>,
    r: &RowsView<'_>,
    i: usize,
    x: usize,
    sign: f64,
) -> Vec<f64> {
    let b = r.ncols();
    match local.and_then(|lf| lf.frame[x].as_ref()) {
        Some(s) => (0..b)
            .map(|k| sign * (0..b).map(|l| r[(i, l)] * s[(l, k)]).sum::<f64>())
            .collect(),
        None => (0..b).map(|k| sign * r[(i, k)]).collect(),
    }
}

/// What the split reads: the pairs' rows with their inputs, the threshold and the bodies'
/// local frames.
pub(super) struct Split<'a> {
    pub m: &'a Mechanism,
    pub eqs: &'a Equations,
    pub rows: &'a PairRows,
    pub tol: &'a Tol,
    pub local: Option<&'a LocalFrames>,
}

impl Split<'_> {
    /// The solve order of the count decomposition with `kept` rows per pair (inputs
    /// included), each group with rows set aside among its own pairs split by
    /// [`Split::parts`]; `None` when no group splits (the first choice stands).
    pub(super) fn solve_order(&self, kept: &[u32]) -> Option<SolveKeys> {
        let (m, eqs) = (self.m, self.eqs);
        let mut counted = eqs.clone();
        counted.cap = kept.to_vec();
        let d = decompose(m, &counted, &eqs.unknowns(m));
        let level = |x: usize| match d.body_part.get(x) {
            Some(Part::Group(g)) => d.groups[*g].level,
            Some(Part::Under) => usize::MAX,
            _ => 0,
        };
        let mut keys: SolveKeys = (0..eqs.nodes)
            .map(|x| match d.body_part[x] {
                Part::Group(g) => (d.groups[g].level, g, 0),
                Part::Under => (usize::MAX, 0, 0),
                _ => (0, 0, 0),
            })
            .collect();
        let touching = touching(eqs);
        let b = m.b() as usize;
        let mut split = false;
        for (g, grp) in d.groups.iter().enumerate() {
            if b * grp.bodies.len() > MAX_DENSE_UNKNOWNS || grp.bodies.len() < 2 {
                continue;
            }
            // Its own pairs: into the group from the group, the frame or a lower level (a
            // pair to a lower level that is not a dependency lost all its rows; those bodies
            // are solved before the group all the same).
            let own = own_pairs(eqs, &touching, &grp.bodies, |y| {
                d.body_part[y] == Part::Group(g) || level(y) < grp.level
            });
            if own.iter().all(|&e| kept[e] as usize >= self.rows.nrows(e)) {
                // Every own row kept: no proper part has more rows than the count gave it.
                continue;
            }
            if let Some(parts) = self.parts(&grp.bodies, &own) {
                for (&x, p) in grp.bodies.iter().zip(parts) {
                    split |= p > 0;
                    keys[x].2 = p;
                }
            }
        }
        // Groups a choice left in the under-determined part, after every group.
        let under: Vec<usize> = (0..eqs.nodes)
            .filter(|&x| d.body_part[x] == Part::Under)
            .collect();
        if let Some((bodies, parts)) = self.determined_in(under, &touching, kept) {
            split = true;
            for (&x, p) in bodies.iter().zip(parts) {
                keys[x] = (usize::MAX - 1, 0, p);
            }
        }
        split.then_some(keys)
    }

    /// The largest subset of the under-determined part `under` that its own rows determine,
    /// every group solved, and its parts by [`Split::parts`]; `None` when it is empty, when
    /// no own row was set aside (the count's under-determined part is then the rank's), or
    /// past [`MAX_DENSE_UNKNOWNS`]. A body that moves in some motion of the part (its own
    /// rows, the groups fixed) is in no determined subset; without the bodies that move, the
    /// motions are found again, until none moves.
    fn determined_in(
        &self,
        mut under: Vec<usize>,
        touching: &[Vec<usize>],
        kept: &[u32],
    ) -> Option<(Vec<usize>, Vec<usize>)> {
        let b = self.m.b() as usize;
        let solved: Vec<bool> = {
            let mut s = vec![true; self.eqs.nodes];
            for &x in &under {
                s[x] = false;
            }
            s
        };
        if under.is_empty() || b * under.len() > MAX_DENSE_UNKNOWNS {
            return None;
        }
        let mut first = true;
        loop {
            let own = own_pairs(self.eqs, touching, &under, |y| {
                solved[y] || under.binary_search(&y).is_ok()
            });
            if first && own.iter().all(|&e| kept[e] as usize >= self.rows.nrows(e)) {
                return None;
            }
            first = false;
            let (j, _) = self.group_rows(&under, &own);
            let moving = moving_bodies(j, b, self.tol);
            if !moving.contains(&true) {
                let parts = self.parts(&under, &own)?;
                return Some((under, parts));
            }
            let mut k = 0;
            under.retain(|_| {
                k += 1;
                !moving[k - 1]
            });
            if under.is_empty() {
                return None;
            }
        }
    }

    /// The parts of a group `bodies` (ascending) given the bodies its `own` pairs reach
    /// outside it, in a solve order: for each body `z`, the bodies that stay fixed in every
    /// motion of the group once `z` and its pairs are removed (`F_z`, the largest subset
    /// determined without `z`); bodies with the same `F_z` form one part, and a part whose
    /// set is smaller comes first (a part solved after another keeps it fixed, so its set
    /// holds the other's and more). Each body's part number, or `None` when the group's
    /// rows do not have full rank on its columns (left as it is).
    ///
    /// Motions of the group less `z`: the group's rows `J = QR` have full column rank, so a
    /// twist `x` satisfies every row off `z`'s pairs exactly when `J x = Q t` (`t = R x`)
    /// vanishes off those pairs' rows, that is when `t` is a right singular vector of the
    /// rows of `Q` on `z`'s pairs with singular value 1. One factorization serves every `z`.
    fn parts(&self, bodies: &[usize], own: &[usize]) -> Option<Vec<usize>> {
        let b = self.m.b() as usize;
        let n = b * bodies.len();
        let (j, pair_of) = self.group_rows(bodies, own);
        if j.nrows() < n {
            return None;
        }
        let nrows = j.nrows();
        let cut = self.tol.cut(1.0, nrows);
        let qr = j.qr();
        let (q, r) = (qr.q(), qr.r());
        let diagonal: Vec<f64> = (0..n).map(|i| r[(i, i)]).collect();
        self.tol.note_all(&diagonal, cut);
        if diagonal.iter().any(|d| d.abs() <= cut) {
            return None;
        }
        let fixed: Vec<Vec<bool>> = bodies
            .iter()
            .enumerate()
            .map(|(kz, &z)| {
                let on_z: Vec<usize> = (0..nrows)
                    .filter(|&i| self.eqs.bodies(pair_of[i]).contains(&z))
                    .collect();
                let moved = motions_without(&q, &r, &on_z, cut);
                (0..bodies.len())
                    .map(|k| {
                        k != kz
                            && (k * b..(k + 1) * b)
                                .all(|c| moved.row(c).iter().all(|v| v.abs() <= cut))
                    })
                    .collect()
            })
            .collect();
        let size = |f: &Vec<bool>| f.iter().filter(|&&x| x).count();
        let mut sets: Vec<&Vec<bool>> = fixed.iter().collect();
        sets.sort_by(|a, c| (size(a), *a).cmp(&(size(c), *c)));
        sets.dedup();
        Some(
            fixed
                .iter()
                .map(|f| sets.iter().position(|s| *s == f).unwrap_or(0))
                .collect(),
        )
    }

    /// The group's rows (every row of its own pairs, inputs included) on its bodies'
    /// columns, each scaled to unit norm there, and the pair of each row.
    fn group_rows(&self, bodies: &[usize], own: &[usize]) -> (DMatrix<f64>, Vec<usize>) {
        let b = self.m.b() as usize;
        let n = b * bodies.len();
        let col = |x: usize| bodies.binary_search(&x).ok().map(|k| k * b);
        let mut data: Vec<f64> = Vec::new();
        let mut pair_of = Vec::new();
        for &e in own {
            let r = self.rows.get(e);
            let [h, o] = self.eqs.bodies(e);
            for i in 0..r.nrows() {
                let mut v = vec![0.0; n];
                for (x, sign) in [(h, -1.0), (o, 1.0)] {
                    let Some(c) = col(x) else {
                        continue;
                    };
                    for (k, t) in on_node(self.local, &r, i, x, sign).into_iter().enumerate() {
                        v[c + k] += t;
                    }
                }
                let norm = v.iter().map(|t| t * t).sum::<f64>().sqrt();
                if norm > 0.0 {
                    data.extend(v.iter().map(|t| t / norm));
                    pair_of.push(e);
                }
            }
        }
        let rows = pair_of.len();
        (DMatrix::from_row_slice(rows, n, &data), pair_of)
    }
}

/// An orthonormal basis (columns) of the twists `x` with `J x` zero off the rows `on_z`,
/// `J = QR` of full column rank; entries of a body that none of them moves are at most
/// about `cut`.
fn motions_without(q: &DMatrix<f64>, r: &DMatrix<f64>, on_z: &[usize], cut: f64) -> DMatrix<f64> {
    let n = r.ncols();
    let qp = DMatrix::from_fn(on_z.len(), n, |i, k| q[(on_z[i], k)]);
    let svd = qp.svd(false, true);
    let Some(vt) = svd.v_t else {
        return DMatrix::zeros(n, 0);
    };
    let ts: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| {
            let s = svd.singular_values[i].min(1.0);
            ((1.0 - s) * (1.0 + s)).sqrt() <= cut
        })
        .collect();
    if ts.is_empty() {
        return DMatrix::zeros(n, 0);
    }
    let t = DMatrix::from_fn(n, ts.len(), |k, c| vt[(ts[c], k)]);
    let Some(x) = r.solve_upper_triangular(&t) else {
        return DMatrix::zeros(n, 0);
    };
    x.qr().q()
}

/// The pairs touching `bodies` whose other node is one of them or `known`, ascending.
fn own_pairs(
    eqs: &Equations,
    touching: &[Vec<usize>],
    bodies: &[usize],
    known: impl Fn(usize) -> bool,
) -> Vec<usize> {
    let mut own: Vec<usize> = bodies
        .iter()
        .flat_map(|&x| touching[x].iter().copied())
        .filter(|&e| eqs.bodies(e).iter().all(|&y| known(y)))
        .collect();
    own.sort_unstable();
    own.dedup();
    own
}

/// Per body (`b` columns each) of `j`'s columns, whether some twist of `j`'s null space
/// moves it (entries of a fixed body are at most about the threshold).
fn moving_bodies(j: DMatrix<f64>, b: usize, tol: &Tol) -> Vec<bool> {
    let n = j.ncols();
    // A square matrix with `j`'s null space: its `R` when it has at least as many rows.
    let square = if j.nrows() >= n {
        j.qr().r()
    } else {
        let mut p = DMatrix::<f64>::zeros(n, n);
        p.view_mut((0, 0), (j.nrows(), n)).copy_from(&j);
        p
    };
    let svd = square.svd(false, true);
    let Some(vt) = svd.v_t else {
        return vec![true; n / b.max(1)];
    };
    let smax = svd.singular_values.iter().copied().fold(0.0, f64::max);
    let cut = tol.cut(smax, n);
    tol.note_all(svd.singular_values.as_slice(), cut);
    let null: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] <= cut)
        .collect();
    (0..n / b.max(1))
        .map(|k| {
            null.iter()
                .any(|&i| (k * b..(k + 1) * b).any(|c| vt[(i, c)].abs() > cut.max(1e-9)))
        })
        .collect()
}

/// The pairs touching each node (a pair of a node with itself left out).
fn touching(eqs: &Equations) -> Vec<Vec<usize>> {
    let mut t: Vec<Vec<usize>> = vec![Vec::new(); eqs.nodes];
    for e in 0..eqs.len() {
        let [h, o] = eqs.bodies(e);
        if h != o {
            t[h].push(e);
            t[o].push(e);
        }
    }
    t
}
