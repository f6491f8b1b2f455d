//! The null space from a factor: the column order, the free columns, random null vectors and
//! a sparse basis, by back substitution through the records.

use super::super::field::Fp;
use super::factor::Factor;
use super::matrix::SparseRow;
use super::record::{Record, solve_extra};
use crate::rng::SplitMix64;
use std::collections::BinaryHeap;

impl Factor {
    /// The columns in elimination order (group by group, each group's columns in order):
    /// a fill-reducing order for [`RowBasis::with_column_order`].
    pub fn column_order(&self) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.ncols());
        let mut seen = vec![false; self.sizes.len()];
        for rec in &self.records {
            seen[rec.group()] = true;
            let off = self.offsets[rec.group()];
            out.extend((off..off + self.sizes[rec.group()]).map(|c| c as u32));
        }
        for (g, &s) in self.sizes.iter().enumerate() {
            if !seen[g] {
                let off = self.offsets[g];
                out.extend((off..off + s).map(|c| c as u32));
            }
        }
        out
    }

    /// The free columns (global indices), one per null-space vector, in the order of
    /// [`Factor::null_space`]: vector k is 1 on free column k and 0 on the other free
    /// columns.
    pub fn free_columns(&self) -> Vec<u32> {
        self.records
            .iter()
            .flat_map(|rec| rec.open().map(|f| (self.offsets[rec.group()] + f) as u32))
            .collect()
    }

    /// `k` random vectors of the null space {x : A x = 0}, dense: each free column gets a
    /// random field element and the pivots follow by back substitution, record by record in
    /// reverse elimination order (a record's rows involve its own group and groups
    /// eliminated after it). The cost is `k` passes over the factor, whatever the nullity;
    /// a linear map on the null space has the rank of its values on `k` such vectors (for
    /// `k` at least that rank) except with probability at most `k / p`.
    pub fn random_null_vectors(&self, k: usize, rng: &mut SplitMix64) -> Vec<Vec<Fp>> {
        let total = self.ncols();
        let mut out = Vec::with_capacity(k);
        for _ in 0..k {
            let mut x = vec![Fp::ZERO; total];
            for rec in self.records.iter().rev() {
                let off = self.offsets[rec.group()];
                for q in rec.open() {
                    x[off + q] = Fp::random(rng);
                }
                solve_extra(rec, off, &mut x);
                for (i, &pc) in rec.pivots().iter().enumerate() {
                    let row = &rec.rows[i * rec.width()..(i + 1) * rec.width()];
                    let mut s = Fp::ZERO;
                    for (j, &q) in rec.free().iter().enumerate() {
                        s += row[j] * x[off + q as usize];
                    }
                    let mut c = rec.free().len();
                    for &o in rec.others() {
                        let o = o as usize;
                        let so = self.sizes[o];
                        let oo = self.offsets[o];
                        for kk in 0..so {
                            s += row[c + kk] * x[oo + kk];
                        }
                        c += so;
                    }
                    x[off + pc as usize] = -s;
                }
            }
            out.push(x);
        }
        out
    }

    /// A basis of the null space {x : A x = 0}: `nullity()` sparse vectors, by back
    /// substitution from each free column through the groups it reaches. The vectors are
    /// as dense as the motions they describe (a serial chain's are long), so the cost is
    /// that of the output.
    pub fn null_space(&self) -> Vec<SparseRow> {
        let n = self.sizes.len();
        let total = self.ncols();
        let users = self.record_users();
        let mut x = vec![Fp::ZERO; total];
        let mut touched_groups: Vec<usize> = Vec::new();
        let mut group_seen = vec![false; n];
        let mut queued = vec![false; self.records.len()];
        let mut out = Vec::with_capacity(self.nullity());
        for (ri, rec) in self.records.iter().enumerate() {
            for f in rec.open() {
                let col = self.offsets[rec.group()] + f;
                x[col] = Fp::ONE;
                let mut heap: BinaryHeap<usize> = BinaryHeap::new();
                heap.push(ri);
                queued[ri] = true;
                let mut queued_list = vec![ri];
                let mark = |g: usize, seen: &mut Vec<bool>, list: &mut Vec<usize>| {
                    if !seen[g] {
                        seen[g] = true;
                        list.push(g);
                    }
                };
                mark(rec.group(), &mut group_seen, &mut touched_groups);
                while let Some(hi) = heap.pop() {
                    let h = &self.records[hi];
                    let any = self.solve_sparse(h, &mut x);
                    if any {
                        mark(h.group(), &mut group_seen, &mut touched_groups);
                    }
                    if any || hi == ri {
                        for &u in &users[h.group()] {
                            if !queued[u] {
                                queued[u] = true;
                                queued_list.push(u);
                                heap.push(u);
                            }
                        }
                    }
                }
                touched_groups.sort_unstable();
                let mut v: SparseRow = Vec::new();
                for &g in &touched_groups {
                    let off = self.offsets[g];
                    for (k, e) in x[off..off + self.sizes[g]].iter_mut().enumerate() {
                        if !e.is_zero() {
                            v.push(((off + k) as u32, *e));
                            *e = Fp::ZERO;
                        }
                    }
                    group_seen[g] = false;
                }
                touched_groups.clear();
                for q in queued_list {
                    queued[q] = false;
                }
                out.push(v);
            }
        }
        out
    }

    /// Per group `h`, the records whose front used it as a neighbour (those are solved
    /// after `h`), or whose set-aside rows reach it outside their front.
    fn record_users(&self) -> Vec<Vec<usize>> {
        let n = self.sizes.len();
        let mut users: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut rec_of = vec![usize::MAX; n];
        for (ri, rec) in self.records.iter().enumerate() {
            rec_of[rec.group()] = ri;
            for &h in rec.others() {
                users[h as usize].push(ri);
            }
            // A set-aside row's columns on groups outside the record's front.
            let mut hs: Vec<usize> = rec
                .extra
                .iter()
                .flat_map(|e| e.1.iter())
                .map(|&(col, _)| self.offsets.partition_point(|&o| o <= col as usize) - 1)
                .filter(|&h| h != rec.group() && !rec.others().contains(&(h as u32)))
                .collect();
            hs.sort_unstable();
            hs.dedup();
            for h in hs {
                users[h].push(ri);
            }
        }
        users
    }

    /// The pivots of record `h` by back substitution in `x`, skipping zero entries (a
    /// null vector of [`Factor::null_space`] is zero on most groups). Whether any pivot or
    /// set-aside column came out nonzero.
    fn solve_sparse(&self, h: &Record, x: &mut [Fp]) -> bool {
        let off = self.offsets[h.group()];
        let mut any = solve_extra(h, off, x);
        for (i, &pc) in h.pivots().iter().enumerate() {
            let row = &h.rows[i * h.width()..(i + 1) * h.width()];
            let mut s = Fp::ZERO;
            for (j, &q) in h.free().iter().enumerate() {
                let v = x[off + q as usize];
                if !v.is_zero() {
                    s += row[j] * v;
                }
            }
            let mut c = h.free().len();
            for &o in h.others() {
                let o = o as usize;
                let so = self.sizes[o];
                let xo = &x[self.offsets[o]..self.offsets[o] + so];
                for (k, &v) in xo.iter().enumerate() {
                    if !v.is_zero() {
                        s += row[c + k] * v;
                    }
                }
                c += so;
            }
            let val = -s;
            x[off + pc as usize] = val;
            any |= !val.is_zero();
        }
        any
    }
}
