//! The constraint rows `J` of an expansion over GF(p) and a basis of their null space, by
//! back-substitution along the blocks of a routing of the rows into the bodies' unknowns.

use super::oracle::ORACLE_NULLITY;
use crate::exact::Fp;
use crate::mechanism::Mechanism;
use std::cmp::Ordering;

/// Unknowns of one block at most in [`block_null_vectors`] (a dense solve of about `d³`
/// steps); a larger block falls back to the whole factorization.
const BLOCK_MAX: usize = 384;

/// A basis of the null space of `J` (the constraint rows of `m` at realization `seed`,
/// exactly as [`jacobian`] builds them) without factorizing `J`, and each body's first
/// column as [`jacobian`] gives it. The rows of `J` are routed into the bodies' unknowns (a
/// matching of row units to body units, `b` a body, by augmenting paths); `J` is completed
/// to a square system `M = [J; E]` by one random row `E` on the unknowns of a body for each
/// unit the routing leaves free there. `M` is block triangular along the strongly connected
/// components of the routing (a row routed to body `z` touches `z` and one other body), so
/// `M x = [0; e_l]`, for each unit vector `e_l`, is solved component by component with small
/// dense exact solves: linear in the size of `m`. When every block is nonsingular, so is `M`:
/// `J` has full row rank and the `x` are a basis of its null space (its nullity is the
/// number of free units).
///
/// `None` (the caller factorizes `J`, the same decision) when a joint is not binary or joins
/// a body to itself, a joint's rows are not `b − grade`, a row finds no unit, the routing's
/// search exceeds its linear cap, the nullity exceeds [`ORACLE_NULLITY`], or a block is
/// singular (at this `E` or because `J` has dependent rows) or larger than [`BLOCK_MAX`].
pub(super) fn block_null_vectors(m: &Mechanism, seed: u64) -> Option<(Vec<usize>, Vec<Vec<Fp>>)> {
    let pairs = Pairs::of(m)?;
    let dist = pairs.distances();
    let (flow, used) = pairs.route(&dist)?;
    drop(dist);
    let nrows: usize = pairs.rows_of.iter().map(|&r| r as usize).sum();
    let n = pairs.ncols.checked_sub(nrows)?;
    if n > ORACLE_NULLITY {
        return None;
    }
    let (members, bounds) = pairs.components(&flow, nrows);
    let mut solve = Blocks {
        m,
        seed,
        pairs: &pairs,
        flow: &flow,
        used: &used,
        n,
        v: vec![vec![Fp::ZERO; pairs.ncols]; n],
        rng: crate::rng::SplitMix64::new(seed ^ 0xB10C_5B57_0000_0001),
        done: vec![false; pairs.ends.len()],
        loc: vec![NIL; pairs.col.len()],
        unit: 0,
        a: Vec::new(),
    };
    let mut comp: Vec<usize> = Vec::new();
    for span in bounds.windows(2) {
        // `tarjan_flat` lists a component from the top of its stack down; the block takes it
        // bottom up (its root first), the order of its unknowns, rows and random rows.
        comp.clear();
        comp.extend(members[span[0]..span[1]].iter().rev().map(|&x| x as usize));
        solve.block(&comp)?;
    }
    let (unit, v) = (solve.unit, solve.v);
    (unit == n).then_some((pairs.col, v))
}

/// No body, no pair, no path step in [`block_null_vectors`].
const NIL: u32 = u32::MAX;

/// The pairs of a mechanism with binary joints as [`block_null_vectors`] routes them.
struct Pairs {
    /// Unknowns of a body.
    b: usize,
    frame: usize,
    /// Column of each body's first unknown (`usize::MAX`: the frame), and the columns in all.
    col: Vec<usize>,
    ncols: usize,
    /// Each pair's two bodies and its rows.
    ends: Vec<[u32; 2]>,
    rows_of: Vec<u8>,
    /// The pairs at each body (frame excluded), compressed:
    /// `touching[start[z]..start[z + 1]]`.
    start: Vec<u32>,
    touching: Vec<u32>,
}

impl Pairs {
    /// The pairs of `m`; `None` when a joint is not binary or joins a body to itself.
    fn of(m: &Mechanism) -> Option<Pairs> {
        let b = m.b() as usize;
        let nb = m.bodies.len();
        let nq = m.joints.len();
        let frame = m.frame;
        if b == 0 || nb == 0 {
            return None;
        }
        let mut col = vec![usize::MAX; nb];
        let mut c = 0;
        for (x, slot) in col.iter_mut().enumerate() {
            if x != frame {
                *slot = c;
                c += b;
            }
        }
        let ncols = c;
        let mut ends: Vec<[u32; 2]> = Vec::with_capacity(nq);
        let mut rows_of: Vec<u8> = Vec::with_capacity(nq);
        let mut deg = vec![0u32; nb + 1];
        for j in &m.joints {
            let [x, y] = j.bodies[..] else {
                return None;
            };
            if x == y || x >= nb || y >= nb {
                return None;
            }
            ends.push([x as u32, y as u32]);
            rows_of.push((b - (j.grade() as usize).min(b)) as u8);
            for z in [x, y] {
                if z != frame {
                    deg[z + 1] += 1;
                }
            }
        }
        for z in 0..nb {
            deg[z + 1] += deg[z];
        }
        let start = deg;
        let mut fill: Vec<u32> = start[..nb].to_vec();
        let mut touching = vec![0u32; start[nb] as usize];
        for (q, e) in ends.iter().enumerate() {
            for &z in e {
                let z = z as usize;
                if z != frame {
                    touching[fill[z] as usize] = q as u32;
                    fill[z] += 1;
                }
            }
        }
        Some(Pairs {
            b,
            frame,
            col,
            ncols,
            ends,
            rows_of,
            start,
            touching,
        })
    }

    /// Pairs at body `z`.
    fn at(&self, z: usize) -> &[u32] {
        &self.touching[self.start[z] as usize..self.start[z + 1] as usize]
    }

    /// Which end of pair `q` body `z` is.
    fn side(&self, q: usize, z: usize) -> usize {
        usize::from(self.ends[q][0] as usize != z)
    }

    /// Each body's distance from the frame along the pairs (`NIL`: unreached). A row goes to
    /// the farther of its two bodies when both have room, so the free units (the random rows)
    /// stay near the frame, where the inputs of a linkage built outwards from its cranks sit
    /// and the blocks are small; a free unit far out would tie every group between it and
    /// the frame into one block.
    fn distances(&self) -> Vec<u32> {
        let frame = self.frame;
        let mut dist = vec![NIL; self.col.len()];
        let mut queue: Vec<u32> = Vec::new();
        dist[frame] = 0;
        for e in &self.ends {
            for s in 0..2 {
                let (z, w) = (e[s] as usize, e[1 - s] as usize);
                if z == frame && dist[w] == NIL {
                    dist[w] = 1;
                    queue.push(w as u32);
                }
            }
        }
        let mut head = 0;
        while head < queue.len() {
            let z = queue[head] as usize;
            head += 1;
            for &q in self.at(z) {
                let w = self.ends[q as usize][1 - self.side(q as usize, z)] as usize;
                if dist[w] == NIL {
                    dist[w] = dist[z] + 1;
                    queue.push(w as u32);
                }
            }
        }
        dist
    }

    /// The routing: `flow[q][s]` rows of pair `q` on its body `ends[q][s]`, and the rows each
    /// body holds. `None` when a row finds no unit or the search passes its linear cap.
    fn route(&self, dist: &[u32]) -> Option<(Vec<[u8; 2]>, Vec<u8>)> {
        let (b, frame) = (self.b, self.frame);
        let nb = self.col.len();
        let nq = self.ends.len();
        let mut flow = vec![[0u8; 2]; nq];
        let mut used = vec![0u8; nb];
        let mut seen = vec![0u32; nb];
        let mut prev: Vec<(u32, u32)> = vec![(NIL, NIL); nb];
        let mut queue: Vec<u32> = Vec::new();
        let mut stamp = 0u32;
        let mut work: u64 = 0;
        let cap_work = 64 * (nb + nq) as u64 + 100_000;
        for q in 0..nq {
            for _ in 0..self.rows_of[q] {
                stamp = stamp.checked_add(1)?;
                queue.clear();
                let [x, y] = self.ends[q];
                // Unreached bodies (`NIL`) count as farthest.
                let order = if dist[y as usize] > dist[x as usize] {
                    [y, x]
                } else {
                    [x, y]
                };
                for z in order {
                    let z = z as usize;
                    if z != frame && seen[z] != stamp {
                        seen[z] = stamp;
                        prev[z] = (NIL, q as u32);
                        queue.push(z as u32);
                    }
                }
                let mut head = 0;
                let mut found = None;
                while head < queue.len() {
                    let z = queue[head] as usize;
                    head += 1;
                    if (used[z] as usize) < b {
                        found = Some(z);
                        break;
                    }
                    for &q2 in self.at(z) {
                        let q2 = q2 as usize;
                        work += 1;
                        if flow[q2][self.side(q2, z)] == 0 {
                            continue;
                        }
                        let w = self.ends[q2][1 - self.side(q2, z)] as usize;
                        if w == frame || seen[w] == stamp {
                            continue;
                        }
                        seen[w] = stamp;
                        prev[w] = (z as u32, q2 as u32);
                        queue.push(w as u32);
                    }
                }
                work += head as u64;
                if work > cap_work {
                    return None;
                }
                // One more row on the free body; each pair on the path moves one of its rows
                // from the body before it to the body after it.
                let mut w = found?;
                used[w] += 1;
                loop {
                    let (z, q2) = prev[w];
                    let q2 = q2 as usize;
                    flow[q2][self.side(q2, w)] += 1;
                    if z == NIL {
                        break;
                    }
                    let z = z as usize;
                    flow[q2][self.side(q2, z)] -= 1;
                    w = z;
                }
            }
        }
        Some((flow, used))
    }

    /// Tarjan's components of "a row routed to `z` touches `w`" (frame excluded), emitted
    /// sinks first: each block's rows touch only its own unknowns and those of blocks
    /// already solved. The arcs of each body in `touching` order, so the components come out
    /// as a walk of `touching` itself would find them.
    fn components(&self, flow: &[[u8; 2]], nrows: usize) -> (Vec<u32>, Vec<usize>) {
        let nb = self.col.len();
        let mut arc_start = vec![0usize; nb + 1];
        let mut arcs: Vec<u32> = Vec::with_capacity(nrows);
        for z in 0..nb {
            for &q in self.at(z) {
                let q = q as usize;
                if flow[q][self.side(q, z)] != 0 {
                    arcs.push(self.ends[q][1 - self.side(q, z)]);
                }
            }
            arc_start[z + 1] = arcs.len();
        }
        let mut active = vec![true; nb];
        active[self.frame] = false;
        crate::graph::scc::tarjan_flat(&arc_start, &arcs, &active)
    }
}

/// The back-substitution of [`block_null_vectors`], block by block: the null vectors so far
/// and what the blocks share.
struct Blocks<'a> {
    m: &'a Mechanism,
    seed: u64,
    pairs: &'a Pairs,
    flow: &'a [[u8; 2]],
    used: &'a [u8],
    /// The nullity: free units, null vectors, right-hand sides.
    n: usize,
    /// The null vectors, solved block by block.
    v: Vec<Vec<Fp>>,
    rng: crate::rng::SplitMix64,
    /// Pairs whose rows a block has taken.
    done: Vec<bool>,
    /// Each body's place in the current block (`NIL`: not in it).
    loc: Vec<u32>,
    /// Free units (random rows) placed so far.
    unit: usize,
    /// The current block's `[A | R]`, row-major.
    a: Vec<Fp>,
}

impl Blocks<'_> {
    /// Solve the block of bodies `comp` (root first) for every null vector; `None` when it
    /// is singular, too large, or its rows do not fill it.
    fn block(&mut self, comp: &[usize]) -> Option<()> {
        let b = self.pairs.b;
        let d = b * comp.len();
        if d > BLOCK_MAX {
            return None;
        }
        for (i, &x) in comp.iter().enumerate() {
            self.loc[x] = i as u32;
        }
        // [A | R] row-major: the block's rows on its unknowns, the right-hand sides.
        let w_all = d + self.n;
        self.a.clear();
        self.a.resize(d * w_all, Fp::ZERO);
        let r = self.constraint_rows(comp, d, w_all)?;
        let r = self.random_rows(comp, d, w_all, r)?;
        if r != d {
            return None;
        }
        gauss_jordan(&mut self.a, d, w_all)?;
        let col = &self.pairs.col;
        for &x in comp {
            let i0 = self.loc[x] as usize * b;
            for k in 0..b {
                for (l, vl) in self.v.iter_mut().enumerate() {
                    vl[col[x] + k] = self.a[(i0 + k) * w_all + d + l];
                }
            }
            self.loc[x] = NIL;
        }
        Some(())
    }

    /// The rows routed into the block's bodies: their entries on its unknowns, and those on
    /// the bodies of blocks solved before moved to the right-hand sides. The rows filled.
    fn constraint_rows(&mut self, comp: &[usize], d: usize, w_all: usize) -> Option<usize> {
        use crate::motion::exact as models;
        let (pairs, b) = (self.pairs, self.pairs.b);
        let mut r = 0usize;
        for &x in comp {
            for &q in pairs.at(x) {
                let q = q as usize;
                if self.done[q] || self.flow[q][pairs.side(q, x)] == 0 {
                    continue;
                }
                self.done[q] = true;
                let rows = models::joint_rows(self.m, q, self.seed, 0);
                if rows.nrows() != pairs.rows_of[q] as usize || rows.ncols() != b {
                    return None;
                }
                for i in 0..rows.nrows() {
                    if r >= d {
                        return None;
                    }
                    let line = &mut self.a[r * w_all..(r + 1) * w_all];
                    for (s, &u) in pairs.ends[q].iter().enumerate() {
                        let u = u as usize;
                        if u == pairs.frame {
                            continue;
                        }
                        for k in 0..b {
                            let e = if s == 0 { -rows[(i, k)] } else { rows[(i, k)] };
                            if self.loc[u] != NIL {
                                line[self.loc[u] as usize * b + k] += e;
                            } else {
                                // A body of a block solved before.
                                for (l, vl) in self.v.iter().enumerate() {
                                    line[d + l] -= e * vl[pairs.col[u] + k];
                                }
                            }
                        }
                    }
                    r += 1;
                }
            }
        }
        Some(r)
    }

    /// One random row on a body's unknowns for each unit the routing leaves free there, with
    /// its own unit right-hand side, after row `r`. The rows filled.
    fn random_rows(&mut self, comp: &[usize], d: usize, w_all: usize, r: usize) -> Option<usize> {
        let b = self.pairs.b;
        let mut r = r;
        for &x in comp {
            for _ in self.used[x] as usize..b {
                if r >= d || self.unit >= self.n {
                    return None;
                }
                let line = &mut self.a[r * w_all..(r + 1) * w_all];
                for k in 0..b {
                    line[self.loc[x] as usize * b + k] = Fp::random_nonzero(&mut self.rng);
                }
                line[d + self.unit] = Fp::ONE;
                self.unit += 1;
                r += 1;
            }
        }
        Some(r)
    }
}

/// Gauss-Jordan on the `d × w_all` row-major `[A | R]`: `A` becomes the identity and `R` the
/// solutions. `None` when `A` is singular.
fn gauss_jordan(a: &mut [Fp], d: usize, w_all: usize) -> Option<()> {
    use crate::exact::field::axpy_sub;
    for cc in 0..d {
        let p = (cc..d).find(|&i| !a[i * w_all + cc].is_zero())?;
        if p != cc {
            for t in 0..w_all {
                a.swap(p * w_all + t, cc * w_all + t);
            }
        }
        let inv = a[cc * w_all + cc].inv();
        for t in cc..w_all {
            a[cc * w_all + t] *= inv;
        }
        for i in 0..d {
            if i == cc {
                continue;
            }
            let f = a[i * w_all + cc];
            if f.is_zero() {
                continue;
            }
            let (lo, hi) = a.split_at_mut(i.max(cc) * w_all);
            let (dst, src) = if i < cc {
                (&mut lo[i * w_all..(i + 1) * w_all], &hi[..w_all])
            } else {
                (&mut hi[..w_all], &lo[cc * w_all..(cc + 1) * w_all])
            };
            axpy_sub(&mut dst[cc..], f, &src[cc..]);
        }
    }
    Some(())
}

/// Each body's first column in a Jacobian of `B` columns per movable body (`usize::MAX`:
/// the frame), and the number of columns.
pub(super) fn body_columns(m: &Mechanism) -> (Vec<usize>, usize) {
    let b = m.b() as usize;
    let mut col = vec![usize::MAX; m.bodies.len()];
    let mut c = 0;
    for (x, slot) in col.iter_mut().enumerate() {
        if x != m.frame {
            *slot = c;
            c += b;
        }
    }
    (col, c)
}

/// The constraint rows `J` of `m` (binary joints, no inputs) over GF(p) at the random
/// realization `seed`, one column group per movable body, and each body's first column
/// (`usize::MAX`: the frame).
pub(super) fn jacobian(m: &Mechanism, seed: u64) -> (crate::exact::SparseMatrix, Vec<usize>) {
    use crate::exact::{Fp, SparseMatrix};
    use crate::motion::exact as models;
    let b = m.b() as usize;
    let (col, _) = body_columns(m);
    let mut j = SparseMatrix::with_groups(vec![b; m.bodies.len().saturating_sub(1)]);
    for q in 0..m.joints.len() {
        let [x, y] = m.joints[q].bodies[..] else {
            continue;
        };
        let rows = models::joint_rows(m, q, seed, 0);
        for r in 0..rows.nrows() {
            let mut entries: Vec<(u32, Fp)> = Vec::with_capacity(2 * b);
            for (z, negate) in [(x, true), (y, false)] {
                if x == y || col[z] == usize::MAX {
                    continue;
                }
                for k in 0..b {
                    let v = rows[(r, k)];
                    entries.push(((col[z] + k) as u32, if negate { -v } else { v }));
                }
            }
            j.push_row(entries);
        }
    }
    (j, col)
}

/// The rows of [`jacobian`] made one at a time when the exact factorization reads them:
/// each row's B values and its joint (8 bytes a value, 4 a row, 8 a joint) instead of a
/// vector a row (about 230 bytes a spatial row, with its allocation), which were the peak
/// of `transform` on the random families (rs5: 132 MB of 378).
pub(super) struct JacobianRows {
    b: usize,
    ngroups: usize,
    /// Row `i`'s values in `vals[i * b..(i + 1) * b]`: its joint's row as
    /// `models::joint_rows` gives it.
    vals: Vec<crate::exact::Fp>,
    /// The joint (index into `sides`) of each row.
    owner: Vec<u32>,
    /// Per binary joint: the column groups of its two bodies (the first one's entries
    /// negated), [`NO_GROUP`] for the frame; both [`NO_GROUP`] for a joint on one body
    /// twice, whose rows are empty in [`jacobian`].
    sides: Vec<[u32; 2]>,
}

/// A body without columns (the frame) in [`JacobianRows`].
const NO_GROUP: u32 = u32::MAX;

impl JacobianRows {
    /// [`jacobian`]'s rows of `m` at `seed`; `None` where its indices (columns, rows,
    /// joints) do not fit in `u32`, or a joint's rows are narrower than B.
    pub(super) fn of(m: &Mechanism, seed: u64) -> Option<JacobianRows> {
        use crate::motion::exact as models;
        let b = m.b() as usize;
        let ngroups = m.bodies.len().saturating_sub(1);
        let small = |x: usize| u32::try_from(x).ok().filter(|&x| x != NO_GROUP);
        small(ngroups.checked_mul(b)?)?;
        // Body `z`'s group: its columns are `col[z]..col[z] + b` in `jacobian`.
        let group = |z: usize| match z.cmp(&m.frame) {
            Ordering::Less => small(z),
            Ordering::Equal => Some(NO_GROUP),
            Ordering::Greater => small(z - 1),
        };
        // Reserved at the count's rows (B − k a binary joint, what `joint_rows` gives), so
        // that the largest array is not grown by doubling.
        let binary = m.joints.iter().filter(|j| j.bodies.len() == 2);
        let nrows: usize = binary
            .clone()
            .map(|j| b.saturating_sub(j.grade() as usize))
            .sum();
        let mut vals = Vec::with_capacity(nrows.saturating_mul(b));
        let mut owner = Vec::with_capacity(nrows);
        let mut sides = Vec::with_capacity(binary.count());
        for q in 0..m.joints.len() {
            let [x, y] = m.joints[q].bodies[..] else {
                continue;
            };
            let rows = models::joint_rows(m, q, seed, 0);
            if rows.nrows() > 0 && rows.ncols() < b {
                return None;
            }
            let k = small(sides.len())?;
            sides.push(if x == y {
                [NO_GROUP, NO_GROUP]
            } else {
                [group(x)?, group(y)?]
            });
            for r in 0..rows.nrows() {
                owner.push(k);
                vals.extend((0..b).map(|c| rows[(r, c)]));
            }
        }
        small(owner.len())?;
        Some(JacobianRows {
            b,
            ngroups,
            vals,
            owner,
            sides,
        })
    }
}

impl crate::exact::sparse::Rows for JacobianRows {
    fn ncols(&self) -> usize {
        self.ngroups * self.b
    }
    fn nrows(&self) -> usize {
        self.owner.len()
    }
    fn group_sizes(&self) -> Vec<usize> {
        vec![self.b; self.ngroups]
    }
    /// As `push_row` leaves the row [`jacobian`] pushes: the first body's entries negated,
    /// the two groups' columns in increasing order (the bodies' groups differ), zeros
    /// dropped; empty for a joint on one body twice.
    fn row<'a>(
        &'a self,
        i: usize,
        buf: &'a mut crate::exact::sparse::SparseRow,
    ) -> &'a [(u32, crate::exact::Fp)] {
        buf.clear();
        let [gx, gy] = self.sides[self.owner[i] as usize];
        if gx == gy {
            return buf;
        }
        let vals = &self.vals[i * self.b..(i + 1) * self.b];
        let mut sides = [(gx, true), (gy, false)];
        if gy < gx {
            sides.swap(0, 1);
        }
        for (g, negate) in sides {
            if g == NO_GROUP {
                continue;
            }
            for (k, &v) in vals.iter().enumerate() {
                let v = if negate { -v } else { v };
                if !v.is_zero() {
                    buf.push((g * self.b as u32 + k as u32, v));
                }
            }
        }
        buf
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `J v` for the null vectors `v` of [`block_null_vectors`], through [`jacobian`]'s rows.
    fn j_times(m: &Mechanism, seed: u64, v: &[crate::exact::Fp]) -> Vec<crate::exact::Fp> {
        use crate::exact::Fp;
        use crate::motion::exact as models;
        let (_, col) = jacobian(m, seed);
        let b = m.b() as usize;
        let mut out = Vec::new();
        for q in 0..m.joints.len() {
            let [x, y] = m.joints[q].bodies[..] else {
                continue;
            };
            let rows = models::joint_rows(m, q, seed, 0);
            for i in 0..rows.nrows() {
                let mut s = Fp::ZERO;
                for k in 0..b {
                    if col[y] != usize::MAX {
                        s += rows[(i, k)] * v[col[y] + k];
                    }
                    if col[x] != usize::MAX {
                        s -= rows[(i, k)] * v[col[x] + k];
                    }
                }
                out.push(s);
            }
        }
        out
    }

    /// [`JacobianRows`] makes [`jacobian`]'s rows, row for row (entries, order, empty
    /// rows), with its columns and groups: bundled mechanisms with binary joints, random
    /// linkages planar and spatial, and a file whose frame is not its first body and with
    /// a joint on one body twice and joints to the frame on either side.
    #[test]
    fn jacobian_rows_made_one_at_a_time_are_the_jacobian() {
        use crate::exact::sparse::Rows;
        use crate::generate::random;
        let mut mechs: Vec<Mechanism> = Vec::new();
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/mechanisms");
        for f in std::fs::read_dir(dir).expect("mechanisms") {
            let f = f.expect("entry").path();
            let text = std::fs::read_to_string(&f).expect("reads");
            if let Ok(m) = crate::format::load("m", &text, crate::format::Format::Toml) {
                mechs.push(m);
            }
        }
        for seed in 0..4 {
            for planar in [true, false] {
                mechs.push(random(15, planar, seed).expect("random").0);
            }
        }
        let text = "space = \"spatial\"\nframe = 2\n\n[[joint]]\ntype = \"S\"\nbodies = [1, 2]\n\n\
                    [[joint]]\ntype = \"R\"\nbodies = [1, 3]\n\n[[joint]]\ntype = \"U\"\n\
                    bodies = [2, 3]\n\n[[joint]]\ntype = \"P\"\nbodies = [3, 1]\n\n\
                    [[joint]]\ntype = \"S\"\nbodies = [1, 2, 3]\n";
        let mut m = crate::format::load("t", text, crate::format::Format::Toml).expect("loads");
        // A joint on one body twice (the reader refuses one; `jacobian` gives it empty rows).
        let x = m.joints[1].bodies[1];
        m.joints[1].bodies = vec![x, x].into();
        mechs.push(m);
        let (mut rows_seen, mut empty) = (0, 0);
        for m in &mechs {
            for seed in [1u64, 0x5EED_0000_1234] {
                let (j, _) = jacobian(m, seed);
                let r = JacobianRows::of(m, seed).expect("fits");
                assert_eq!(r.ncols(), j.ncols);
                assert_eq!(r.group_sizes(), j.groups());
                assert_eq!(Rows::nrows(&r), j.nrows());
                let mut buf = Vec::new();
                for (i, want) in j.rows.iter().enumerate() {
                    assert_eq!(r.row(i, &mut buf), &want[..], "row {i}");
                    empty += usize::from(want.is_empty());
                }
                rows_seen += j.nrows();
            }
        }
        assert!(
            rows_seen > 1000 && empty > 0,
            "{rows_seen} rows, {empty} empty"
        );
    }

    /// The back-substituted null vectors are null vectors of `J`, as many as its nullity,
    /// and span the factorization's null space (bundled mechanisms with binary joints, Assur
    /// linkages planar and spatial of every class, random linkages); where `J` has dependent
    /// rows there is none (the caller factorizes).
    #[test]
    fn block_null_vectors_span_the_null_space() {
        use crate::exact::{Factor, dense};
        use crate::generate::{Variant, assur, assur_spatial, random};
        let mut mechs: Vec<(String, Mechanism)> = Vec::new();
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/mechanisms");
        let mut files: Vec<_> = std::fs::read_dir(dir)
            .expect("mechanisms")
            .map(|e| e.expect("entry").path())
            .collect();
        files.sort();
        for f in files {
            let text = std::fs::read_to_string(&f).expect("reads");
            let name = f.display().to_string();
            if let Ok(m) = crate::format::load(&name, &text, crate::format::Format::Toml) {
                mechs.push((name, m));
            }
        }
        for class in 1..=3 {
            for seed in 0..3 {
                for variant in [Variant::A, Variant::B] {
                    let m = assur(class, 6, seed, variant).expect("assur");
                    mechs.push((format!("assur {class} {seed}"), m));
                    let m = assur_spatial(class, 6, seed, variant).expect("assur");
                    mechs.push((format!("spatial assur {class} {seed}"), m));
                }
            }
        }
        for seed in 0..6 {
            for planar in [true, false] {
                let (m, _) = random(12, planar, seed).expect("random");
                mechs.push((format!("random {planar} {seed}"), m));
            }
        }
        let (mut solved, mut dependent) = (0, 0);
        for (name, m) in &mechs {
            if m.joints.iter().any(|j| j.bodies.len() != 2) {
                continue;
            }
            for seed in [1u64, 0x5EED_0000_1234] {
                let (j, col) = jacobian(m, seed);
                let f = Factor::new(&j);
                let got = block_null_vectors(m, seed);
                if f.rank() < j.nrows() {
                    assert!(got.is_none(), "{name}: J is dependent");
                    dependent += 1;
                    continue;
                }
                let Some((col2, v)) = got else {
                    continue;
                };
                assert_eq!(col, col2, "{name}");
                let n = f.nullity();
                assert_eq!(v.len(), n, "{name}");
                for vl in &v {
                    assert!(j_times(m, seed, vl).iter().all(|x| x.is_zero()), "{name}");
                }
                let w = f.random_null_vectors(n, &mut crate::rng::SplitMix64::new(seed));
                let ncols = (m.bodies.len() - 1) * m.b() as usize;
                let ours = nalgebra::DMatrix::from_fn(ncols, n, |i, l| v[l][i]);
                let both = nalgebra::DMatrix::from_fn(ncols, 2 * n, |i, l| {
                    if l < n { v[l][i] } else { w[l - n][i] }
                });
                assert_eq!(dense::rank(&ours), n, "{name}: independent");
                assert_eq!(dense::rank(&both), n, "{name}: the same space");
                solved += 1;
            }
        }
        assert!(solved >= 40, "{solved} solved");
        assert!(dependent >= 1, "{dependent} dependent");
    }

    /// A singular block gives up (the caller factorizes): a body held to the frame by two
    /// spherical joints has six rows of rank five on its six unknowns.
    #[test]
    fn block_null_vectors_give_up_on_a_singular_block() {
        let text = "name = \"two S\"\nspace = \"spatial\"\nframe = 1\n\n[[joint]]\nid = \"a\"\n\
                    type = \"S\"\nbodies = [1, 2]\n\n[[joint]]\nid = \"b\"\ntype = \"S\"\n\
                    bodies = [1, 2]\n";
        let m = crate::format::load("two-s", text, crate::format::Format::Toml).expect("loads");
        let (j, _) = jacobian(&m, 3);
        assert!(crate::exact::Factor::new(&j).rank() < j.nrows());
        assert!(block_null_vectors(&m, 3).is_none());
        // One S: three rows, nullity three, one block of six unknowns with three random rows.
        let one = "name = \"one S\"\nspace = \"spatial\"\nframe = 1\n\n[[joint]]\nid = \"a\"\n\
                   type = \"S\"\nbodies = [1, 2]\n";
        let m = crate::format::load("one-s", one, crate::format::Format::Toml).expect("loads");
        let (_, v) = block_null_vectors(&m, 3).expect("solved");
        assert_eq!(v.len(), 3);
    }
}
