//! The search of the count-valid placements: the bases of the placement matroid, depth
//! first, by exchanges along alternating paths, with a trail to undo them.

use super::problem::{NONE, Problem, Scratch, State};
use super::prune::LazyPruner;
use crate::budget::{BudgetExceeded, Meter};

/// The search's callback: a placement (units per pair) and its flow (units of each pair into
/// its two bodies); `false` stops the search.
type LeafFn<'a> = &'a mut dyn FnMut(&[u32], &[[u32; 2]]) -> bool;

impl Problem {
    /// Visit every count-valid placement (sparse `(pair, driven)`, pair order) in
    /// lexicographic order of its units' candidate positions (the most units on the earliest
    /// candidate first), calling `leaf` on each; `leaf` returns `false` to stop. Charges
    /// `meter` one unit per search step and per body an exchange visits.
    ///
    /// The search is a binary partition of the bases of the placement matroid: a node holds
    /// one complete placement (a perfect matching of equations and inputs to unknowns) and
    /// bounds `lo ≤ w ≤ hi` per pair; it decides the first candidate still open, first "one
    /// more unit here" (same placement, or one exchange), then "no more units here" (each
    /// unit removed is refilled by an augmenting path). A branch whose bounds admit no
    /// placement is cut at once by a failed exchange, so there are no dead ends: the first
    /// placement comes after one greedy pass, and each further one after at most one
    /// exchange per candidate. Changes are undone from a trail, so memory stays linear. A
    /// failed exchange marks the bodies it reached (no free unit from there) until units move
    /// back, so a run of candidates that take no unit costs one pass over the bodies, not one
    /// each (with `--limit`, the work grows with the placements found, not with candidates ×
    /// bodies).
    ///
    /// With `prune` (where the count does not see every motion), once it is made, "one more
    /// unit here" is taken only while the units fixed so far stay independent on the motions
    /// and move no isolated freedom ([`super::prune::Pruner`]): every placement reached from
    /// then on passes that test.
    pub(super) fn search(
        &self,
        meter: &mut Meter,
        leaf: LeafFn<'_>,
        mut prune: Option<&mut LazyPruner<'_>>,
    ) -> Result<(), BudgetExceeded> {
        let Some(root) = &self.root else {
            return Ok(());
        };
        let mut t = Search {
            s: root.clone(),
            w: self.lo.clone(),
            lo: self.lo.clone(),
            hi: self.hi.clone(),
            trail: Vec::new(),
            sc: self.scratch(),
            dead: vec![0; self.u.len()],
            version: 1,
            free: 0,
        };
        if !self.greedy(&mut t, meter)? {
            return Ok(());
        }
        self.fix_coloops(&mut t, meter)?;
        t.trail.clear();
        t.free = (0..t.w.len()).map(|q| t.free_of(q)).sum();
        // Choice points: (trail mark, candidate position) whose "no more units" branch is
        // still to be explored.
        let mut choices: Vec<(usize, usize)> = Vec::new();
        let mut cur = 0usize;
        // The order the pruner reads the fixed units in: pairs that are no candidate (kept
        // inputs), then the candidates in the search's order.
        let order: Vec<usize> = match prune {
            Some(_) => {
                let mut is_cand = vec![false; t.w.len()];
                self.cand.iter().for_each(|&q| is_cand[q] = true);
                (0..t.w.len())
                    .filter(|&q| !is_cand[q])
                    .chain(self.cand.iter().copied())
                    .collect()
            }
            None => Vec::new(),
        };
        let mut units: Vec<(usize, u32)> = Vec::new();
        loop {
            meter.charge(1)?;
            if prune.as_ref().is_some_and(|p| p.exhausted()) {
                return Ok(());
            }
            while cur < self.cand.len() && t.lo[self.cand[cur]] >= t.hi[self.cand[cur]] {
                cur += 1;
            }
            let mut go_back = false;
            if cur == self.cand.len() {
                let ok = self
                    .kept_groups
                    .iter()
                    .all(|(qs, min)| qs.iter().map(|&q| t.w[q]).sum::<u32>() >= *min);
                if ok && !leaf(&t.w, &t.s.flow) {
                    return Ok(());
                }
                go_back = true;
            } else {
                let q = self.cand[cur];
                let mark = t.trail.len();
                let admits = match prune.as_mut().and_then(|lp| {
                    let m = lp.mechanism();
                    lp.get().map(|p| (m, p))
                }) {
                    Some((m, p)) => {
                        units.clear();
                        units.extend(order.iter().filter_map(|&r| {
                            let n = t.lo[r] + u32::from(r == q);
                            (n > 0).then_some((r, n))
                        }));
                        meter.charge(units.len() as u64 + 1)?;
                        p.independent(m, &units)
                    }
                    None => true,
                };
                if admits && (t.w[q] > t.lo[q] || self.exchange_in(&mut t, q, meter)?) {
                    choices.push((mark, cur));
                    t.set_lo(q, t.lo[q] + 1);
                } else if !self.cap(&mut t, q, meter)? {
                    go_back = true;
                }
            }
            if go_back {
                // The "no more units" branch of the latest choice point that admits one.
                loop {
                    let Some((mark, c)) = choices.pop() else {
                        return Ok(());
                    };
                    t.undo(mark);
                    cur = c;
                    if self.cap(&mut t, self.cand[c], meter)? {
                        break;
                    }
                }
            }
        }
    }

    /// The greedy first placement: as many units as fit on each candidate in order.
    /// `false` when it falls short (there is no placement).
    fn greedy(&self, t: &mut Search, meter: &mut Meter) -> Result<bool, BudgetExceeded> {
        let mut placed = 0usize;
        let mut full = vec![false; self.u.len()];
        for &q in &self.cand {
            while placed < self.need && t.w[q] < t.hi[q] {
                // Bodies whose spare unknowns no unit reaches are marked `full` once, so a
                // run of candidates that take no unit costs one pass (charged: bodies seen).
                let r = self.augment_marked(&mut t.s, &[q], &mut t.sc, Some(&mut full));
                meter.charge(t.sc.queue.len() as u64 + 1)?;
                if r.is_none() {
                    break;
                }
                t.w[q] += 1;
                placed += 1;
            }
        }
        Ok(placed >= self.need)
    }

    /// Fix the units every placement needs (matroid coloops): a unit is needed
    /// unless some slot outside the placement reaches it by an alternating path (one BFS
    /// from all such slots). A tree (star, serial chain) is then decided in linear time.
    fn fix_coloops(&self, t: &mut Search, meter: &mut Meter) -> Result<(), BudgetExceeded> {
        let Search { s, w, hi, sc, .. } = t;
        sc.next_stamp();
        for &q in &self.cand {
            if w[q] < hi[q] {
                for x in [self.a[q], self.c[q]] {
                    if x != self.frame && sc.seen[x] != sc.stamp {
                        sc.seen[x] = sc.stamp;
                        sc.queue.push(x);
                    }
                }
            }
        }
        let mut reached = vec![false; self.a.len()];
        let mut qi = 0;
        while qi < sc.queue.len() {
            let x = sc.queue[qi];
            qi += 1;
            meter.charge(1 + self.touching[x].len() as u64)?;
            for &r in &self.touching[x] {
                if s.flow[r][self.side(r, x)] == 0 {
                    continue;
                }
                reached[r] = true;
                let y = self.other(r, x);
                if y != self.frame && y != x && sc.seen[y] != sc.stamp {
                    sc.seen[y] = sc.stamp;
                    sc.queue.push(y);
                }
            }
        }
        for &q in &self.cand {
            if !reached[q] {
                t.lo[q] = t.lo[q].max(t.w[q]);
            }
        }
        Ok(())
    }

    /// "One more unit on `q`" when the placement has none spare there: add a unit of `q` and
    /// drop a free unit (above its lower bound) of another pair, along an alternating path.
    /// (Over 80 lines: one breadth-first search for the free unit, then the walk back along its
    /// path.)
    fn exchange_in(
        &self,
        t: &mut Search,
        q: usize,
        meter: &mut Meter,
    ) -> Result<bool, BudgetExceeded> {
        // No unit above its lower bound on another pair: nothing to drop (the search below
        // would visit every body it reaches to find none, once a placement: the place of the
        // only input of an Assur linkage is then fixed).
        if t.free == t.free_of(q) {
            return Ok(false);
        }
        let found = {
            let Search {
                s,
                w,
                lo,
                sc,
                dead,
                version,
                ..
            } = &mut *t;
            sc.next_stamp();
            for x in [self.a[q], self.c[q]] {
                if x != self.frame && sc.seen[x] != sc.stamp && dead[x] != *version {
                    sc.seen[x] = sc.stamp;
                    sc.prev[x] = (q as u32, NONE);
                    sc.queue.push(x);
                }
            }
            let mut found = None;
            let mut qi = 0;
            'bfs: while qi < sc.queue.len() {
                let x = sc.queue[qi];
                qi += 1;
                meter.charge(1 + self.touching[x].len() as u64)?;
                for &r in &self.touching[x] {
                    if s.flow[r][self.side(r, x)] == 0 {
                        continue;
                    }
                    if r != q && w[r] > lo[r] {
                        found = Some((x, r));
                        break 'bfs;
                    }
                    let y = self.other(r, x);
                    if y != self.frame && y != x && sc.seen[y] != sc.stamp && dead[y] != *version {
                        sc.seen[y] = sc.stamp;
                        sc.prev[y] = (r as u32, x as u32);
                        sc.queue.push(y);
                    }
                }
            }
            if found.is_none() {
                // No free unit is reachable from any body this search reached: while the
                // placement (flows, units, lower bounds) stays as it is, later exchanges skip
                // them (a run of failed exchanges costs one pass over the bodies, not one each).
                for &x in &sc.queue {
                    dead[x] = *version;
                }
            }
            found
        };
        let Some((x, r)) = found else {
            return Ok(false);
        };
        // Drop a unit of r at x, then push the new unit of q along the path into x.
        t.flow_add(r, self.side(r, x), -1);
        t.w_add(r, -1);
        let mut y = x;
        loop {
            let (pq, from) = t.sc.prev[y];
            let pq = pq as usize;
            t.flow_add(pq, self.side(pq, y), 1);
            if from == NONE {
                t.w_add(pq, 1);
                return Ok(true);
            }
            let from = from as usize;
            t.flow_add(pq, self.side(pq, from), -1);
            y = from;
        }
    }

    /// "No more units on `q`": its upper bound drops to its lower one; each unit above is
    /// removed and the body it held refilled from a pair with spare capacity, along an
    /// alternating path. `false` when some unit cannot be refilled (the branch is empty).
    fn cap(&self, t: &mut Search, q: usize, meter: &mut Meter) -> Result<bool, BudgetExceeded> {
        t.set_hi(q, t.lo[q]);
        while t.w[q] > t.hi[q] {
            // Units move back to pairs below their upper bound: free units may appear.
            t.version += 1;
            let side = usize::from(t.s.flow[q][0] == 0);
            let x = if side == 0 { self.a[q] } else { self.c[q] };
            t.flow_add(q, side, -1);
            t.w_add(q, -1);
            if !self.refill(t, x, meter)? {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Give body `x`, one unit short, a unit from a pair below its upper bound, moving units
    /// between the two bodies of pairs along the way.
    fn refill(&self, t: &mut Search, x: usize, meter: &mut Meter) -> Result<bool, BudgetExceeded> {
        let found = {
            let Search { s, w, hi, sc, .. } = &mut *t;
            sc.next_stamp();
            sc.seen[x] = sc.stamp;
            sc.prev[x] = (NONE, NONE);
            sc.queue.push(x);
            let mut found = None;
            let mut qi = 0;
            'bfs: while qi < sc.queue.len() {
                let z = sc.queue[qi];
                qi += 1;
                meter.charge(1 + self.touching[z].len() as u64)?;
                for &r in &self.touching[z] {
                    if w[r] < hi[r] {
                        found = Some((z, r));
                        break 'bfs;
                    }
                    let y = self.other(r, z);
                    if y == self.frame || y == z || sc.seen[y] == sc.stamp {
                        continue;
                    }
                    if s.flow[r][self.side(r, y)] > 0 {
                        sc.seen[y] = sc.stamp;
                        sc.prev[y] = (r as u32, z as u32);
                        sc.queue.push(y);
                    }
                }
            }
            found
        };
        let Some((z, r)) = found else {
            return Ok(false);
        };
        t.flow_add(r, self.side(r, z), 1);
        t.w_add(r, 1);
        let mut y = z;
        while y != x {
            let (pq, to) = t.sc.prev[y];
            let (pq, to) = (pq as usize, to as usize);
            t.flow_add(pq, self.side(pq, y), -1);
            t.flow_add(pq, self.side(pq, to), 1);
            y = to;
        }
        Ok(true)
    }
}

/// The mutable state of [`Problem::search`], with a trail of old values to undo.
pub(super) struct Search {
    s: State,
    w: Vec<u32>,
    lo: Vec<u32>,
    hi: Vec<u32>,
    trail: Vec<(u8, u32, u32)>,
    sc: Scratch,
    /// Bodies from which [`Problem::exchange_in`] found no free unit, valid while `dead[x] ==
    /// version`. A successful exchange keeps them valid (it is an augmenting path towards a
    /// free unit: it changes flows only between bodies that all reach one, so a body that
    /// reached none still reaches none), and so does raising a lower bound (fewer free units);
    /// removing units ([`Problem::cap`]) and undoing bump `version`.
    dead: Vec<u64>,
    version: u64,
    /// Units above their lower bound, summed over the pairs (`Σ w − lo` where positive):
    /// with none but on the pair itself, an exchange has none to drop and fails at once.
    free: u64,
}

impl Search {
    /// Units of `q` above its lower bound.
    fn free_of(&self, q: usize) -> u64 {
        u64::from(self.w[q].saturating_sub(self.lo[q]))
    }
    fn flow_add(&mut self, q: usize, side: usize, d: i32) {
        let old = self.s.flow[q][side];
        self.trail.push((side as u8, q as u32, old));
        self.s.flow[q][side] = old.wrapping_add_signed(d);
    }
    fn w_add(&mut self, q: usize, d: i32) {
        let old = self.w[q];
        self.trail.push((2, q as u32, old));
        self.free -= self.free_of(q);
        self.w[q] = old.wrapping_add_signed(d);
        self.free += self.free_of(q);
    }
    fn set_lo(&mut self, q: usize, v: u32) {
        self.trail.push((3, q as u32, self.lo[q]));
        self.free -= self.free_of(q);
        self.lo[q] = v;
        self.free += self.free_of(q);
    }
    fn set_hi(&mut self, q: usize, v: u32) {
        self.trail.push((4, q as u32, self.hi[q]));
        self.hi[q] = v;
    }
    fn undo(&mut self, mark: usize) {
        while self.trail.len() > mark {
            let Some((k, q, old)) = self.trail.pop() else {
                break;
            };
            let q = q as usize;
            if k < 4 {
                self.version += 1;
            }
            match k {
                0 | 1 => self.s.flow[q][k as usize] = old,
                2 | 3 => {
                    self.free -= self.free_of(q);
                    if k == 2 {
                        self.w[q] = old;
                    } else {
                        self.lo[q] = old;
                    }
                    self.free += self.free_of(q);
                }
                _ => self.hi[q] = old,
            }
        }
    }
}
