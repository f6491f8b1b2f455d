//! The contraction of rigid components in the component pebble game: after a failed gather,
//! the minimal tight set grown to the maximal one (Lee and Streinu's reverse search) and
//! contracted into one super-body.

use super::fast::Fast;

impl Fast {
    /// Whether node `n` is pinned to super-body `k` (B − k bars between them).
    pub(super) fn pinned_to(&self, n: u32, k: u32) -> bool {
        !self.is_body(n) && self.bars_between(n, k) >= self.weight(n) as usize
    }

    /// Whether node `n` has all its pebbles on bars to one super-body of the set.
    pub(super) fn pinned_in_set(&self, n: u32, q_e: u32) -> bool {
        let r = &self.v[n as usize];
        if self.is_body(n) || r.nout < r.weight {
            return false;
        }
        let mut heads = r.outs().map(|(h, _)| h);
        let first = heads.next();
        first.is_some_and(|h| self.qmark[h as usize] == q_e && heads.all(|y| y == h))
    }

    /// Reverse-search step: every vertex with a bar into `x` that reaches no free pebble
    /// outside the set joins it, with every vertex its search visited.
    pub(super) fn scan_in(&mut self, x: u32, q_e: u32, q: &mut Vec<u32>, seen: &mut Vec<u32>) {
        let own = self.v[x as usize];
        let own = &own.bar[..own.nout as usize];
        let mut k = 0;
        while k < self.inc[x as usize].len() {
            let bar = self.inc[x as usize][k];
            k += 1;
            if own.contains(&bar) {
                continue; // An out-bar of x.
            }
            let p = self.other(bar, x);
            self.work += 1;
            if self.qmark[p as usize] == q_e || self.fmark[p as usize] == q_e {
                continue;
            }
            let e = self.next_epoch();
            self.v[p as usize].mark = e;
            let mut found = self.peb(p) > 0;
            seen.clear();
            seen.push(p);
            let mut si = 0;
            while si < seen.len() && !found {
                let y = seen[si];
                si += 1;
                let ry = self.v[y as usize];
                for (z, _) in ry.outs() {
                    let z = z as usize;
                    self.work += 1;
                    if self.qmark[z] == q_e || self.v[z].mark == e {
                        continue;
                    }
                    if self.fmark[z] == q_e || self.v[z].peb > 0 {
                        found = true;
                        break;
                    }
                    self.v[z].mark = e;
                    seen.push(z as u32);
                }
            }
            if found {
                self.fmark[p as usize] = q_e;
            } else {
                for &y in seen.iter() {
                    self.qmark[y as usize] = q_e;
                    q.push(y);
                }
            }
        }
    }

    /// In-bars of `x` (bars at it that are not its out-bars).
    pub(super) fn in_degree(&self, x: u32) -> usize {
        self.degree(x) - self.v[x as usize].nout as usize
    }

    /// After a failed gather on {u, v}: grow the minimal tight set to the maximal one and
    /// contract it.
    pub(super) fn contract(&mut self, u: u32, v: u32) {
        let (q, keep) = self.tight_set(u, v);
        // The set is closed: every out-bar of a member is inside it. Drop them all.
        for &x in &q {
            let r = self.v[x as usize];
            for (_, bar) in r.outs() {
                self.unlink(bar);
                self.work += 1;
            }
            self.v[x as usize].nout = 0;
        }
        for &x in &q {
            if x == keep {
                continue;
            }
            if self.is_body(x) {
                self.merge_body(x, keep);
            } else {
                // A node of the component: pinned to the super-body by its B − k bars.
                for _ in 0..self.weight(x) {
                    self.link(x, keep);
                }
                self.v[x as usize].peb = 0;
            }
        }
        self.v[keep as usize].peb = self.l;
        let size = self.members[keep as usize].len();
        if size >= 2 && size < self.n_bodies {
            self.proper = true;
        }
    }

    /// The maximal tight set holding the new bar's ends `u` and `v` (its members, in the
    /// order found, from the closed set the failed search visited) and the super-body kept
    /// for it.
    fn tight_set(&mut self, u: u32, v: u32) -> (Vec<u32>, u32) {
        self.qepoch = self.qepoch.wrapping_add(1);
        if self.qepoch == 0 {
            self.qmark.iter_mut().for_each(|m| *m = 0);
            self.fmark.iter_mut().for_each(|m| *m = 0);
            self.qepoch = 1;
        }
        let q_e = self.qepoch;
        let mut q: Vec<u32> = Vec::with_capacity(self.visited.len() + 2);
        for x in [u, v].into_iter().chain(std::mem::take(&mut self.visited)) {
            if self.qmark[x as usize] != q_e {
                self.qmark[x as usize] = q_e;
                q.push(x);
            }
        }
        // A body with fewer than B bars is in no tight set with another body (removing it
        // would leave more bars than the count allows, or it alone would carry all w(T) - B
        // bars, so the rest is nodes), so the maximal tight set is the closed set the search
        // found: the body and nodes pinned to it (the others were pinned to it before). No
        // reverse search, which would scan every bar into a shared joint's node.
        let lone = [u, v]
            .into_iter()
            .find(|&x| self.is_body(x) && self.degree(x) < self.l as usize);
        let big = if lone.is_none() {
            self.reverse_search(u, v, q_e, &mut q)
        } else {
            None
        };
        (q, lone.or(big).unwrap_or(u))
    }

    /// The reverse search growing the closed set `q` (marked `q_e`) of the new bar's ends `u`
    /// and `v` to the maximal tight set; the super-body to keep.
    fn reverse_search(&mut self, u: u32, v: u32, q_e: u32, q: &mut Vec<u32>) -> Option<u32> {
        // Reverse search (Lee and Streinu): a vertex with a bar into the set joins it when it
        // reaches no free pebble outside the set. One super-body of the set, `keep` (the one
        // with the most in-bars, usually the big component drawn in by the search), and the
        // nodes pinned to it are never scanned: a vertex whose bars all go into them and that
        // holds no free pebble would already have been tight with `keep` (contracted into it
        // or pinned to it), so every other joiner has a bar into another member (or into
        // the new bar's node, which the new bar may have just pinned: always scanned). Until the
        // set stops growing, `big` is the candidate (a larger one replaces it, and the old one
        // is scanned then) and pinned nodes wait.
        let mut big: Option<u32> = None;
        let mut fixed = false;
        let mut waiting: Vec<u32> = Vec::new();
        let mut seen: Vec<u32> = Vec::new();
        let mut qi = 0;
        loop {
            while qi < q.len() {
                let x = q[qi];
                qi += 1;
                if self.is_body(x) {
                    match big {
                        None => big = Some(x),
                        Some(b) if !fixed && self.in_degree(x) > self.in_degree(b) => {
                            big = Some(x);
                            self.scan_in(b, q_e, q, &mut seen);
                        }
                        Some(b) if b == x => {}
                        Some(_) => self.scan_in(x, q_e, q, &mut seen),
                    }
                } else if x != u
                    && x != v
                    && (big.is_some_and(|b| self.pinned_to(x, b))
                        || (!fixed && self.pinned_in_set(x, q_e)))
                {
                    if !fixed {
                        waiting.push(x);
                    }
                } else {
                    self.scan_in(x, q_e, q, &mut seen);
                }
            }
            if fixed {
                break;
            }
            fixed = true;
            let k = big.unwrap_or(u);
            big = Some(k);
            for x in std::mem::take(&mut waiting) {
                if !self.pinned_to(x, k) {
                    self.scan_in(x, q_e, q, &mut seen);
                }
            }
        }
        big
    }

    /// Contract body `x` of a tight set into the kept super-body `keep`: its in-bars (all
    /// from outside now) relabelled to `keep`, its members moved.
    fn merge_body(&mut self, x: u32, keep: u32) {
        // Relabel the in-bars (all from outside now) to the kept super-body.
        let inn = std::mem::take(&mut self.inc[x as usize]);
        for bar in inn {
            let side = usize::from(self.ends[bar as usize][0] != x);
            let t = self.ends[bar as usize][1 - side];
            self.ends[bar as usize][side] = keep;
            self.pos[bar as usize][side] = self.inc[keep as usize].len() as u32;
            self.inc[keep as usize].push(bar);
            let rt = &mut self.v[t as usize];
            for i in 0..rt.nout as usize {
                if rt.bar[i] == bar {
                    rt.head[i] = keep;
                }
            }
            self.work += 1;
        }
        self.parent[x as usize] = keep;
        let mut mine = std::mem::take(&mut self.members[x as usize]);
        if mine.len() > self.members[keep as usize].len() {
            std::mem::swap(&mut mine, &mut self.members[keep as usize]);
        }
        self.work += mine.len() as u64;
        self.members[keep as usize].extend(mine);
        self.v[x as usize].peb = 0;
    }
}
