//! Rows a square tier leaves over, set aside as sparse rows and reduced by each later group's
//! pivot rows once that group is eliminated.

use super::super::field::{Fp, axpy_sub};
use super::matrix::SparseRow;
use super::trace::{DEPENDENT, Trace};

/// A row a square tier left over (its diagonal block is singular at this matrix), set aside
/// instead of joining the fronts of every later group it reaches (which made those fronts as
/// wide as the union of the pivot rows it met). It is reduced by each later group's pivot rows
/// once that group is eliminated (adding their other columns to it) until it either becomes
/// zero (a dependent row) or meets a free column of that group, whose pivot it becomes (an
/// extra row of the group's [`Record`]). The result is the same row space as carrying it in
/// the fronts, with work proportional to the records it meets, not to the front widths.
pub(super) struct Carried {
    /// Its entries by group (each the group's columns), groups not yet eliminated.
    pub(super) parts: std::collections::BTreeMap<usize, Vec<Fp>>,
    /// When tracking: its combination of working rows (ids ascending): its own working id
    /// and the rows of the group being met (a new working id after each group).
    pub(super) combo: std::collections::BTreeMap<u32, Fp>,
    /// Entries of `parts`.
    pub(super) len: usize,
}

impl Carried {
    pub(super) fn entries(&self) -> usize {
        self.len + self.combo.len()
    }
}

/// A group's pivot rows just eliminated, for the rows set aside that reach it.
pub(super) struct PivotRows<'a> {
    pub(super) g: usize,
    /// Local pivot columns, one per row.
    pub(super) pivots: &'a [usize],
    /// Local non-pivot columns.
    pub(super) free: &'a [usize],
    /// The other groups of the rows, in column order after the group's own.
    pub(super) others: &'a [usize],
    /// Row-major, `width` per row (the record's layout).
    pub(super) rows: &'a [Fp],
    pub(super) width: usize,
    /// When tracking: each pivot row's coefficients on the chosen rows (`sg` per row, the
    /// front's first rows), the chosen rows' front positions and the front's working ids.
    pub(super) tr: Option<(&'a [Fp], &'a [u32], &'a [u32])>,
}

/// The rows set aside during a factorization ([`Carried`]).
pub(super) struct CarriedSet<'a> {
    pub(super) carried: &'a mut Vec<Option<Carried>>,
    pub(super) carried_on: &'a mut Vec<Vec<u32>>,
    pub(super) carried_len: &'a mut usize,
    pub(super) sizes: &'a [usize],
    pub(super) offsets: &'a [usize],
}

impl CarriedSet<'_> {
    /// `w -= f · (row over the groups of `others` from column `c0`)`, registering the
    /// groups it newly touches.
    fn sub_parts(&mut self, c: u32, f: Fp, others: &[usize], row: &[Fp]) {
        let Some(w) = self.carried[c as usize].as_mut() else {
            return;
        };
        let mut c0 = 0;
        for &h in others {
            let s = self.sizes[h];
            let src = &row[c0..c0 + s];
            c0 += s;
            if src.iter().all(|x| x.is_zero()) {
                continue;
            }
            let part = w.parts.entry(h).or_insert_with(|| {
                self.carried_on[h].push(c);
                w.len += s;
                vec![Fp::ZERO; s]
            });
            axpy_sub(part, f, src);
        }
    }

    /// The rows set aside that touch group `p.g` (ids `touching`), reduced by its pivot
    /// rows; then, free column by free column, one of those nonzero there (the shortest)
    /// becomes its pivot and is eliminated from the others. Returns the extra rows of the
    /// group's record (its pivots), how many rows became zero (dependent; emitted to the
    /// trace) and the work done.
    pub(super) fn meet(
        &mut self,
        touching: &[u32],
        p: &PivotRows<'_>,
        trace: Option<&mut Trace>,
    ) -> (Vec<(usize, SparseRow)>, usize, u64) {
        let mut work = 0u64;
        let before: usize = touching
            .iter()
            .filter_map(|&c| self.carried[c as usize].as_ref())
            .map(Carried::entries)
            .sum();
        let mut res = self.reduce_by_pivots(touching, p, &mut work);
        // The groups whose entries changed: the pivot rows' and the absorbed rows'.
        let mut changed: Vec<usize> = p.others.to_vec();
        let mut extra = Vec::new();
        for &q in p.free {
            if let Some(e) = self.pivot_on_free(q, p.g, &mut res, &mut changed, &mut work) {
                extra.push(e);
            }
        }
        let dependent = self.settle(res, changed, trace, &mut work);
        let after: usize = touching
            .iter()
            .filter_map(|&c| self.carried[c as usize].as_ref())
            .map(Carried::entries)
            .sum();
        *self.carried_len = self.carried_len.saturating_sub(before) + after;
        (extra, dependent, work + touching.len() as u64)
    }

    /// Each row of `touching` still on group `p.g`, reduced by the pivot rows: its entries
    /// on the group after the reduction (zero on the pivot columns), taken out of its parts.
    fn reduce_by_pivots(
        &mut self,
        touching: &[u32],
        p: &PivotRows<'_>,
        work: &mut u64,
    ) -> Vec<(u32, Vec<Fp>)> {
        let g = p.g;
        let sg = self.sizes[g];
        let mut res: Vec<(u32, Vec<Fp>)> = Vec::with_capacity(touching.len());
        for &c in touching {
            let Some(mut vals) = self.carried[c as usize].as_mut().and_then(|w| {
                let v = w.parts.remove(&g)?;
                w.len -= v.len();
                Some(v)
            }) else {
                continue;
            };
            for (k, &pc) in p.pivots.iter().enumerate() {
                let f = vals[pc];
                if f.is_zero() {
                    continue;
                }
                let row = &p.rows[k * p.width..(k + 1) * p.width];
                axpy_sub(&mut vals, f, &row[..sg]);
                self.sub_parts(c, f, p.others, &row[sg..]);
                *work += p.width as u64;
                if let (Some((tr, chosen, in_ids)), Some(w)) =
                    (p.tr, self.carried[c as usize].as_mut())
                {
                    for (m, &at) in chosen.iter().enumerate() {
                        let v = tr[k * sg + m];
                        if !v.is_zero() {
                            *w.combo.entry(in_ids[at as usize]).or_insert(Fp::ZERO) -= f * v;
                        }
                    }
                    *work += chosen.len() as u64;
                }
            }
            res.push((c, vals));
        }
        res
    }

    /// Free column `q` of group `g`: the shortest of the reduced rows `res` nonzero there
    /// becomes its pivot, is eliminated from the others and leaves `res`; returns its
    /// equation for the record, `x[q] = −Σ row · x`.
    fn pivot_on_free(
        &mut self,
        q: usize,
        g: usize,
        res: &mut Vec<(u32, Vec<Fp>)>,
        changed: &mut Vec<usize>,
        work: &mut u64,
    ) -> Option<(usize, SparseRow)> {
        let sg = self.sizes[g];
        let b = res
            .iter()
            .enumerate()
            .filter(|(_, (_, v))| !v[q].is_zero())
            .min_by_key(|(i, (c, _))| {
                let len = self.carried[*c as usize]
                    .as_ref()
                    .map_or(0, Carried::entries);
                (len, *i)
            })
            .map(|(i, _)| i)?;
        let (cb, vb) = res.remove(b);
        let wb = self.carried[cb as usize].take()?;
        let inv = vb[q].inv();
        // Flatten its other groups once, for the eliminations below.
        let mut hs: Vec<usize> = Vec::with_capacity(wb.parts.len());
        let mut flat: Vec<Fp> = Vec::new();
        for (&h, part) in &wb.parts {
            hs.push(h);
            flat.extend_from_slice(part);
        }
        changed.extend_from_slice(&hs);
        for (ci, vi) in res.iter_mut() {
            let f = vi[q];
            if f.is_zero() {
                continue;
            }
            let f = f * inv;
            axpy_sub(vi, f, &vb);
            self.sub_parts(*ci, f, &hs, &flat);
            *work += (sg + flat.len() + wb.combo.len()) as u64;
            if let Some(wi) = self.carried[*ci as usize].as_mut() {
                for (&id, &v) in &wb.combo {
                    *wi.combo.entry(id).or_insert(Fp::ZERO) -= f * v;
                }
            }
        }
        // Its equation, normalized: x[q] = −Σ row · x.
        let mut row: SparseRow = vb
            .iter()
            .enumerate()
            .filter(|&(k, v)| k != q && !v.is_zero())
            .map(|(k, &v)| ((self.offsets[g] + k) as u32, v * inv))
            .collect();
        let mut c0 = 0;
        for &h in &hs {
            for k in 0..self.sizes[h] {
                let v = flat[c0 + k];
                if !v.is_zero() {
                    row.push(((self.offsets[h] + k) as u32, v * inv));
                }
            }
            c0 += self.sizes[h];
        }
        row.sort_unstable_by_key(|e| e.0);
        *work += row.len() as u64;
        Some((q, row))
    }

    /// The reduced rows left in `res`, zero on the group: their parts on the `changed`
    /// groups that cancelled dropped; zero everywhere means dependent (emitted to the
    /// trace), else still carried. Returns how many were dependent.
    fn settle(
        &mut self,
        res: Vec<(u32, Vec<Fp>)>,
        mut changed: Vec<usize>,
        mut trace: Option<&mut Trace>,
        work: &mut u64,
    ) -> usize {
        changed.sort_unstable();
        changed.dedup();
        *work += (res.len() * (changed.len() + 1)) as u64;
        let mut dependent = 0;
        for (c, _) in res {
            let Some(w) = self.carried[c as usize].as_mut() else {
                continue;
            };
            // Groups whose entries cancelled (only those changed here can have).
            for h in &changed {
                if w.parts
                    .get(h)
                    .is_some_and(|v| v.iter().all(|x| x.is_zero()))
                {
                    w.len -= self.sizes[*h];
                    w.parts.remove(h);
                }
            }
            if !w.parts.is_empty() {
                // Still carried: its combination becomes a working row of its own, so that
                // it stays as short as this front's (the trace chains, as for the fronts).
                if let Some(t) = trace.as_deref_mut()
                    && !(w.combo.len() == 1 && w.combo.values().all(|&v| v == Fp::ONE))
                {
                    t.outputs.push((t.nids, t.terms.len() as u32));
                    let combo = std::mem::take(&mut w.combo);
                    t.terms.extend(combo.into_iter().filter(|e| !e.1.is_zero()));
                    w.combo.insert(t.nids, Fp::ONE);
                    t.nids += 1;
                }
            } else {
                dependent += 1;
                if let (Some(t), Some(w)) = (trace.as_deref_mut(), self.carried[c as usize].take())
                {
                    t.outputs.push((DEPENDENT, t.terms.len() as u32));
                    t.terms
                        .extend(w.combo.into_iter().filter(|e| !e.1.is_zero()));
                } else {
                    self.carried[c as usize] = None;
                }
            }
        }
        dependent
    }
}

#[cfg(test)]
thread_local! {
    /// Tests compare with the former carrying of the rows a square tier leaves over.
    pub(super) static SET_ASIDE: std::cell::Cell<bool> = const { std::cell::Cell::new(true) };
}

#[cfg(test)]
pub(super) fn set_aside_enabled() -> bool {
    SET_ASIDE.with(|c| c.get())
}

#[cfg(not(test))]
pub(super) fn set_aside_enabled() -> bool {
    true
}
