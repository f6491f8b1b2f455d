//! Block-sparse rank-revealing elimination (multifrontal QR) over groups of unknowns, shared
//! by the geometric rigidity analysis and the structural rank check: the rows touching one
//! group are merged into a front, a Householder QR with column pivoting on that group's
//! columns decides its rank, and the remaining rows become a new block on its neighbours.

use crate::budget::{BudgetExceeded, Meter};
use crate::rng::SplitMix64;
use nalgebra::{DMatrix, DVector};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A row block over some groups of unknowns: `mat` has the groups' columns side by side, in
/// the order of `groups`.
#[derive(Clone, Debug)]
pub(crate) struct Block {
    pub groups: Vec<usize>,
    pub mat: DMatrix<f64>,
}

#[derive(Clone, Debug)]
pub(crate) struct Record {
    pub(crate) group: usize,
    /// Local column of the group for each pivot (then the free columns), in R's order.
    perm: Vec<usize>,
    pub(crate) rank: usize,
    others: Vec<usize>,
    r: DMatrix<f64>,
}

/// Why a bounded elimination stopped before its end.
#[derive(Debug)]
pub(crate) enum Stop {
    /// The next front would have passed the byte cap: the bytes that step needed.
    Memory(u64),
    /// The meter's work limit was passed.
    Work(BudgetExceeded),
}

impl Stop {
    /// The bytes needed, for the callers without a meter (their only way to stop).
    fn bytes(self) -> u64 {
        match self {
            Stop::Memory(n) => n,
            Stop::Work(_) => u64::MAX,
        }
    }
}

pub(crate) struct Elimination {
    pub offsets: Vec<usize>,
    pub sizes: Vec<usize>,
    pub records: Vec<Record>,
    pub rank: usize,
    pub kept_min: f64,
    pub dropped_max: f64,
    /// The norm of the best column of every front whose pivoting stopped on the threshold
    /// (one per such front), for [`Elimination::steered_threshold`].
    pub dropped: Vec<f64>,
}

impl Elimination {
    /// Rank-revealing elimination of the blocks over groups of the given sizes.
    pub(crate) fn run(sizes: &[usize], blocks: Vec<Block>, abs_tol: f64) -> Elimination {
        match Self::run_within(sizes, blocks, abs_tol, u64::MAX) {
            Ok(e) => e,
            Err(_) => unreachable!("no memory cap"),
        }
    }

    /// [`Elimination::run`] that stops, before allocating a front, once the fronts' factors
    /// kept plus the blocks waiting plus the next front would pass `max_bytes` (fill-in on a
    /// large, densely coupled block grows without a bound the caller can foresee). The error
    /// is the number of bytes that step needed.
    pub(crate) fn run_within(
        sizes: &[usize],
        blocks: Vec<Block>,
        abs_tol: f64,
        max_bytes: u64,
    ) -> Result<Elimination, u64> {
        Self::run_ordered(sizes, blocks, abs_tol, max_bytes, None, None).map_err(Stop::bytes)
    }

    /// [`Elimination::run_within`] that also charges `meter`, front by front and before doing
    /// it, the work it really does: building each front and copying out the rows it leaves
    /// over (rows × columns, three times), its Householder steps (rows × columns, twice per
    /// pivot tried) and the compression of the rows left over (2 · rows × columns² of that
    /// block). On an over-determined, filling elimination (the
    /// transpose of a self-stress support) this is many times the triangular factors
    /// ([`Elimination::work`]), so the work limit stops it where that count would not.
    pub(crate) fn run_metered(
        sizes: &[usize],
        blocks: Vec<Block>,
        abs_tol: f64,
        max_bytes: u64,
        meter: &mut Meter,
    ) -> Result<Elimination, Stop> {
        Self::run_ordered(sizes, blocks, abs_tol, max_bytes, None, Some(meter))
    }

    /// [`Elimination::run_within`] with the groups eliminated in the given `order` (every group
    /// once) instead of smallest front first. With groups of one unknown each this is a
    /// Gram-Schmidt of the columns in that order: a column is a pivot exactly when its residual
    /// against the pivots before it exceeds `abs_tol` (a greedy choice of independent columns).
    pub(crate) fn run_in_order(
        sizes: &[usize],
        blocks: Vec<Block>,
        abs_tol: f64,
        max_bytes: u64,
        order: &[usize],
    ) -> Result<Elimination, u64> {
        Self::run_ordered(sizes, blocks, abs_tol, max_bytes, Some(order), None).map_err(Stop::bytes)
    }

    /// [`Elimination::run_in_order`] that also charges `meter` (as [`Elimination::run_metered`]).
    /// Groups missing from `order` are never eliminated: their columns stay in the rows the
    /// factors keep, as a right-hand side does.
    pub(crate) fn run_in_order_metered(
        sizes: &[usize],
        blocks: Vec<Block>,
        abs_tol: f64,
        max_bytes: u64,
        order: &[usize],
        meter: &mut Meter,
    ) -> Result<Elimination, Stop> {
        Self::run_ordered(sizes, blocks, abs_tol, max_bytes, Some(order), Some(meter))
    }

    fn run_ordered(
        sizes: &[usize],
        blocks: Vec<Block>,
        abs_tol: f64,
        max_bytes: u64,
        order: Option<&[usize]>,
        mut meter: Option<&mut Meter>,
    ) -> Result<Elimination, Stop> {
        let n = sizes.len();
        let mut f = Frontal::new(sizes, blocks, abs_tol, order.is_none());
        // A given order: the groups in turn, no scores.
        let mut next_in_order = order.map(|o| o.iter());
        loop {
            let g = match next_in_order.as_mut() {
                Some(it) => match it.next() {
                    Some(&g) => g,
                    None => break,
                },
                None => match f.heap.pop() {
                    Some(Reverse((_, g, ver))) => {
                        if f.done[g] || ver != f.version[g] {
                            continue;
                        }
                        g
                    }
                    None => break,
                },
            };
            if g >= n || f.done[g] {
                continue;
            }
            f.eliminate(g, max_bytes, meter.as_deref_mut())?;
        }
        Ok(f.finish())
    }

    /// A threshold under which a new run should reach rank `target`, chosen from this run's
    /// decisions: with `d` pivots too many, the geometric mean of the `d`-th and `d+1`-th
    /// smallest pivot norms kept (so the `d` smallest fall under it); with `d` too few, that of
    /// the `d`-th and `d+1`-th largest norms dropped (one per front that stopped pivoting, the
    /// only ones recorded). The middle of the gap in magnitude, not its edge: the next run's
    /// pivots near the threshold differ by rounding once an earlier decision changes. `None`
    /// when the rank is already `target` or this run has too few decisions to choose from.
    pub(crate) fn steered_threshold(&self, target: usize) -> Option<f64> {
        let between = |lo: f64, hi: Option<f64>| match hi {
            Some(hi) if hi > lo && lo > 0.0 => Some((lo * hi).sqrt()),
            _ => None,
        };
        if self.rank > target {
            let d = self.rank - target;
            let mut kept: Vec<f64> = self
                .records
                .iter()
                .flat_map(|rec| (0..rec.rank).map(move |i| rec.r[(i, i)].abs()))
                .collect();
            if kept.len() < d {
                return None;
            }
            kept.sort_unstable_by(f64::total_cmp);
            // No larger pivot left: just above the largest.
            between(kept[d - 1], kept.get(d).copied()).or(Some(kept[d - 1] * (1.0 + 1e-9)))
        } else if self.rank < target {
            let d = target - self.rank;
            let mut dropped = self.dropped.clone();
            if dropped.len() < d {
                return None;
            }
            dropped.sort_unstable_by(|a, b| b.total_cmp(a));
            match dropped.get(d) {
                Some(&lo) => between(lo, Some(dropped[d - 1])),
                None => Some(dropped[d - 1] * (1.0 - 1e-9)),
            }
        } else {
            None
        }
    }

    /// Work units of the elimination done (entries of the fronts' triangular factors times
    /// their group's size), for budget meters.
    pub(crate) fn work(&self) -> u64 {
        self.records
            .iter()
            .map(|r| (r.r.nrows().max(1) * r.r.ncols().max(1) * r.perm.len().max(1)) as u64)
            .sum()
    }

    /// The largest front's number of columns (its group's and its neighbours').
    pub(crate) fn max_front(&self) -> usize {
        self.records.iter().map(|r| r.r.ncols()).max().unwrap_or(0)
    }

    /// Entries of the fronts' triangular factors (the cost of one back substitution).
    pub(crate) fn factor_entries(&self) -> u64 {
        self.records.iter().map(|r| r.r.len() as u64).sum()
    }

    /// `k` random vectors of the null space (columns of a `total × k` matrix), in one back
    /// substitution: every free column gets a random value in [−1, 1] (seeded), the pivots
    /// follow. Each is a random combination of the [`Elimination::null_space`] basis, so `k`
    /// of them span the image of any linear map of rank ≤ `k` on the null space (almost
    /// surely). Cost: `k` times the factor's entries.
    pub(crate) fn random_null_vectors(&self, k: usize, seed: u64) -> DMatrix<f64> {
        let total: usize = self.sizes.iter().sum();
        let mut x = DMatrix::zeros(total, k);
        let mut rng = SplitMix64::new(seed);
        for rec in &self.records {
            let o = self.offsets[rec.group];
            for &c in &rec.perm[rec.rank..] {
                for j in 0..k {
                    x[(o + c, j)] = rng.next_signed();
                }
            }
        }
        for h in self.records.iter().rev() {
            if h.rank == 0 {
                continue;
            }
            let sg = self.sizes[h.group];
            let o = self.offsets[h.group];
            // rhs = −R_free · x_free − R_others · x_others
            let mut rhs = DMatrix::zeros(h.rank, k);
            for q in h.rank..sg {
                let row = x.row(o + h.perm[q]).into_owned();
                rhs.ger(-1.0, &h.r.column(q), &row.transpose(), 1.0);
            }
            let mut c = sg;
            for &g in &h.others {
                let s = self.sizes[g];
                let xo = x.rows(self.offsets[g], s);
                rhs.gemm(-1.0, &h.r.view((0, c), (h.rank, s)), &xo, 1.0);
                c += s;
            }
            for i in (0..h.rank).rev() {
                for j in 0..k {
                    let mut s = rhs[(i, j)];
                    for l in i + 1..h.rank {
                        s -= h.r[(i, l)] * x[(o + h.perm[l], j)];
                    }
                    x[(o + h.perm[i], j)] = s / h.r[(i, i)];
                }
            }
        }
        x
    }

    /// Back substitution through every factor, last first: `x` holds the values of the
    /// groups not eliminated; each eliminated group's pivot unknowns are solved from its
    /// rows and its free unknowns set to 0. With a right-hand side `e` as a group of one
    /// column left out of the order and set to 1, the eliminated unknowns become the basic
    /// least-squares solution of `J x = −e`.
    pub(crate) fn back_substitute(&self, x: &mut DVector<f64>) {
        for h in self.records.iter().rev() {
            let sg = self.sizes[h.group];
            let at = self.offsets[h.group];
            for q in h.rank..sg {
                x[at + h.perm[q]] = 0.0;
            }
            if h.rank == 0 {
                continue;
            }
            let mut rhs = DVector::zeros(h.rank);
            let mut c = sg;
            for &o in &h.others {
                let s = self.sizes[o];
                rhs -= h.r.view((0, c), (h.rank, s)) * x.rows(self.offsets[o], s);
                c += s;
            }
            for i in (0..h.rank).rev() {
                let mut s = rhs[i];
                for k in i + 1..h.rank {
                    s -= h.r[(i, k)] * x[at + h.perm[k]];
                }
                x[at + h.perm[i]] = s / h.r[(i, i)];
            }
        }
    }

    /// A basis of the null space (dense vectors over all unknowns), one per free column.
    pub(crate) fn null_space(&self) -> Vec<DVector<f64>> {
        let total: usize = self.sizes.iter().sum();
        let mut out = Vec::new();
        for (ri, rec) in self.records.iter().enumerate() {
            for fpos in rec.rank..rec.perm.len() {
                let mut x = DVector::zeros(total);
                x[self.offsets[rec.group] + rec.perm[fpos]] = 1.0;
                for hi in (0..=ri).rev() {
                    let h = &self.records[hi];
                    if h.rank == 0 {
                        continue;
                    }
                    let sg = self.sizes[h.group];
                    // rhs = −R_others · x_others − R_free · x_free
                    let mut rhs = DVector::zeros(h.rank);
                    let mut any = false;
                    let mut c = sg;
                    for &o in &h.others {
                        let s = self.sizes[o];
                        let xo = x.rows(self.offsets[o], s);
                        if xo.iter().any(|v| *v != 0.0) {
                            any = true;
                            rhs -= h.r.view((0, c), (h.rank, s)) * xo;
                        }
                        c += s;
                    }
                    if hi == ri {
                        any = true;
                        for q in h.rank..sg {
                            let v = x[self.offsets[h.group] + h.perm[q]];
                            if v != 0.0 {
                                rhs -= h.r.column(q) * v;
                            }
                        }
                    }
                    if !any {
                        continue;
                    }
                    // Back substitution on the upper-triangular pivot part.
                    let mut y = DVector::zeros(h.rank);
                    for i in (0..h.rank).rev() {
                        let mut s = rhs[i];
                        for k in i + 1..h.rank {
                            s -= h.r[(i, k)] * y[k];
                        }
                        y[i] = s / h.r[(i, i)];
                    }
                    for i in 0..h.rank {
                        x[self.offsets[h.group] + h.perm[i]] = y[i];
                    }
                }
                out.push(x);
            }
        }
        out
    }
}

/// The size in bytes of a block's matrix.
fn bytes(m: &DMatrix<f64>) -> u64 {
    (m.len() as u64).saturating_mul(8)
}

/// A multifrontal elimination under way ([`Elimination::run_ordered`]): the row blocks
/// waiting, by group, the greedy order's scores, and what the fronts decided so far.
struct Frontal<'s> {
    sizes: &'s [usize],
    abs_tol: f64,
    /// Smallest front first (else a given order: no scores).
    greedy: bool,
    /// Bytes of the blocks waiting and the factors kept.
    held: u64,
    store: Vec<Option<Block>>,
    /// Block ids per group, ascending (ids only grow); ids of blocks taken since are
    /// skipped and pruned lazily. Same order as a set of live ids, without its cost.
    of_group: Vec<Vec<usize>>,
    /// Scratch for unions of groups: a stamp per group (the union's members carry the
    /// current clock).
    stamp: Vec<usize>,
    clock: usize,
    heap: BinaryHeap<Reverse<(usize, usize, usize)>>,
    version: Vec<usize>,
    done: Vec<bool>,
    /// Column offset of each group in the current front.
    col_of: Vec<usize>,
    records: Vec<Record>,
    rank: usize,
    kept_min: f64,
    dropped_max: f64,
    dropped: Vec<f64>,
    /// Tests keep the former bookkeeping (a set of live block ids per group, unions as
    /// sets) beside it and check that every score and every front's members agree.
    #[cfg(test)]
    shadow: shadow::Shadow,
}

impl<'s> Frontal<'s> {
    /// The blocks waiting (empty ones dropped) and, in the greedy order, every group scored.
    fn new(sizes: &'s [usize], blocks: Vec<Block>, abs_tol: f64, greedy: bool) -> Self {
        let held: u64 = blocks.iter().map(|b| bytes(&b.mat)).sum();
        let n = sizes.len();
        let mut f = Frontal {
            sizes,
            abs_tol,
            greedy,
            held,
            store: Vec::new(),
            of_group: vec![Vec::new(); n],
            stamp: vec![0usize; n],
            clock: 0usize,
            heap: BinaryHeap::new(),
            version: vec![0usize; n],
            done: vec![false; n],
            col_of: vec![0usize; n],
            records: Vec::new(),
            rank: 0,
            kept_min: f64::INFINITY,
            dropped_max: 0.0,
            dropped: Vec::new(),
            #[cfg(test)]
            shadow: shadow::Shadow::new(n, &[]),
        };
        for b in blocks {
            if !b.groups.is_empty() && b.mat.nrows() > 0 {
                f.add(b);
            }
        }
        #[cfg(test)]
        {
            f.shadow = shadow::Shadow::new(n, &f.store);
        }
        for g in (0..n).filter(|_| greedy) {
            let s = f.score(g);
            #[cfg(test)]
            assert_eq!(s, f.shadow.score(g, &f.store, sizes), "score of group {g}");
            f.heap.push(Reverse((s, g, 0usize)));
        }
        f
    }

    /// A new block waiting on its groups.
    fn add(&mut self, b: Block) {
        let id = self.store.len();
        for &g in &b.groups {
            self.of_group[g].push(id);
        }
        self.store.push(Some(b));
    }

    /// The front width of `g` now: the sizes of the union of the groups of its live blocks.
    fn score(&mut self, g: usize) -> usize {
        let store = &self.store;
        self.of_group[g].retain(|&bi| store[bi].is_some());
        self.clock += 1;
        let mut width = 0;
        for &bi in &self.of_group[g] {
            if let Some(b) = &store[bi] {
                for &h in &b.groups {
                    if self.stamp[h] != self.clock {
                        self.stamp[h] = self.clock;
                        width += self.sizes[h];
                    }
                }
            }
        }
        width
    }

    /// Group `g`'s front: its rows merged, its columns pivoted, the rows left passed on to
    /// its neighbours, its factor recorded.
    fn eliminate(
        &mut self,
        g: usize,
        max_bytes: u64,
        mut meter: Option<&mut Meter>,
    ) -> Result<(), Stop> {
        self.done[g] = true;
        let (members, others) = self.take_members(g);
        let sg = self.sizes[g];
        let mut front = self.assemble(g, &members, &others, max_bytes, meter.as_deref_mut())?;
        drop(members);
        let nrows = front.nrows();
        let (perm, r) = self.pivot(&mut front, sg);
        self.rank += r;
        let rmat = front.rows(0, r).into_owned();
        if nrows > r && !others.is_empty() {
            self.pass_on(&front, sg, r, &others, meter)?;
        } else if nrows > r {
            // Rows left with no unknowns: their residual norm is a dropped decision.
            let rest = front.view((r, 0), (nrows - r, front.ncols())).norm();
            self.dropped_max = self.dropped_max.max(rest.min(self.abs_tol));
        }
        let greedy = self.greedy;
        for &h in others.iter().filter(|_| greedy) {
            if !self.done[h] {
                self.version[h] += 1;
                let s = self.score(h);
                #[cfg(test)]
                assert_eq!(
                    s,
                    self.shadow.score(h, &self.store, self.sizes),
                    "score of group {h}"
                );
                self.heap.push(Reverse((s, h, self.version[h])));
            }
        }
        self.held = self.held.saturating_add(bytes(&rmat));
        self.records.push(Record {
            group: g,
            perm,
            rank: r,
            others,
            r: rmat,
        });
        Ok(())
    }

    /// The live blocks on `g`, taken out of waiting, and the other groups they touch
    /// (ascending).
    fn take_members(&mut self, g: usize) -> (Vec<Block>, Vec<usize>) {
        let ids = std::mem::take(&mut self.of_group[g]);
        #[cfg(test)]
        let live = self.shadow.take(g, &self.store);
        let mut members: Vec<Block> = Vec::new();
        #[cfg(test)]
        let mut taken = Vec::new();
        for id in ids {
            #[cfg(test)]
            if self.store[id].is_some() {
                taken.push(id);
            }
            if let Some(b) = self.store[id].take() {
                self.held = self.held.saturating_sub(bytes(&b.mat));
                members.push(b);
            }
        }
        #[cfg(test)]
        assert_eq!(taken, live, "members of the front of group {g}");
        self.clock += 1;
        self.stamp[g] = self.clock;
        let mut others: Vec<usize> = Vec::new();
        for b in &members {
            for &h in &b.groups {
                if self.stamp[h] != self.clock {
                    self.stamp[h] = self.clock;
                    others.push(h);
                }
            }
        }
        others.sort_unstable();
        (members, others)
    }

    /// The front of `g`: the members' rows over `g`'s columns first, then the others'; or
    /// the bytes it would pass `max_bytes` with, or the meter's limit.
    fn assemble(
        &mut self,
        g: usize,
        members: &[Block],
        others: &[usize],
        max_bytes: u64,
        meter: Option<&mut Meter>,
    ) -> Result<DMatrix<f64>, Stop> {
        let sizes = self.sizes;
        let sg = sizes[g];
        // Column offsets in the front: g first, then the others.
        self.col_of[g] = 0;
        let mut width = sg;
        for &h in others {
            self.col_of[h] = width;
            width += sizes[h];
        }
        let nrows: usize = members.iter().map(|b| b.mat.nrows()).sum();
        let front_bytes = (nrows as u64)
            .saturating_mul(width as u64)
            .saturating_mul(8);
        let members_bytes: u64 = members.iter().map(|b| bytes(&b.mat)).sum();
        let need = self
            .held
            .saturating_add(members_bytes)
            .saturating_add(front_bytes.saturating_mul(2));
        if need > max_bytes {
            return Err(Stop::Memory(need));
        }
        if let Some(m) = meter {
            // Per cell of the front: zeroing and filling it, copying the rows left over
            // out, and two passes (vᵀ·front, then the rank-one update) per pivot tried
            // (at most min(group size, rows) of them). Large fronts run at memory speed,
            // so each pass is charged, not each pivot once.
            let steps = sg.min(nrows) as u64;
            let cells = (nrows as u64).saturating_mul(width as u64);
            m.charge(cells.saturating_mul(steps.saturating_mul(2).saturating_add(3)))
                .map_err(Stop::Work)?;
        }
        let mut front = DMatrix::zeros(nrows, width);
        let mut r0 = 0;
        for b in members {
            let mut c0 = 0;
            for &h in &b.groups {
                let s = sizes[h];
                let dst = self.col_of[h];
                front
                    .view_mut((r0, dst), (b.mat.nrows(), s))
                    .copy_from(&b.mat.view((0, c0), (b.mat.nrows(), s)));
                c0 += s;
            }
            r0 += b.mat.nrows();
        }
        Ok(front)
    }

    /// Householder QR with column pivoting on the group's `sg` columns of the front, while a
    /// column's norm exceeds the threshold: the permutation and the rank.
    fn pivot(&mut self, front: &mut DMatrix<f64>, sg: usize) -> (Vec<usize>, usize) {
        let nrows = front.nrows();
        let mut perm: Vec<usize> = (0..sg).collect();
        let mut r = 0;
        while r < sg && r < nrows {
            // Column pivoting among the group's remaining columns.
            let (best, bn) = (r..sg)
                .map(|j| (j, front.view((r, j), (nrows - r, 1)).norm()))
                .fold((r, -1.0), |acc, x| if x.1 > acc.1 { x } else { acc });
            if bn <= self.abs_tol {
                self.dropped_max = self.dropped_max.max(bn);
                self.dropped.push(bn);
                break;
            }
            self.kept_min = self.kept_min.min(bn);
            if best != r {
                front.swap_columns(best, r);
                perm.swap(best, r);
            }
            householder(front, r, r);
            r += 1;
        }
        (perm, r)
    }

    /// The front's rows below the `r` pivots, on the other groups' columns, become a new
    /// block on those groups (compressed to as many rows as columns).
    fn pass_on(
        &mut self,
        front: &DMatrix<f64>,
        sg: usize,
        r: usize,
        others: &[usize],
        meter: Option<&mut Meter>,
    ) -> Result<(), Stop> {
        let (nrows, width) = front.shape();
        let mut rest = front.view((r, sg), (nrows - r, width - sg)).into_owned();
        if rest.nrows() > rest.ncols() {
            // Compress: an orthogonal transformation keeps the row space.
            let k = rest.ncols();
            if let Some(m) = meter {
                // Two passes over at most all of it per column.
                let cells = (rest.nrows() as u64).saturating_mul(k as u64);
                m.charge(cells.saturating_mul(k as u64).saturating_mul(2))
                    .map_err(Stop::Work)?;
            }
            for c in 0..k {
                householder(&mut rest, c, c);
            }
            rest = rest.rows(0, k).into_owned();
        }
        self.held = self.held.saturating_add(bytes(&rest));
        #[cfg(test)]
        self.shadow.add(self.store.len(), others);
        self.add(Block {
            groups: others.to_vec(),
            mat: rest,
        });
        Ok(())
    }

    /// The factorization.
    fn finish(self) -> Elimination {
        let mut offsets = Vec::with_capacity(self.sizes.len());
        let mut acc = 0;
        for &s in self.sizes {
            offsets.push(acc);
            acc += s;
        }
        Elimination {
            offsets,
            sizes: self.sizes.to_vec(),
            records: self.records,
            rank: self.rank,
            kept_min: self.kept_min,
            dropped_max: self.dropped_max,
            dropped: self.dropped,
        }
    }
}

/// Apply the Householder reflection that zeroes column `c` below row `r` to rows r.. of `m`.
fn householder(m: &mut DMatrix<f64>, r: usize, c: usize) {
    let nr = m.nrows();
    if r >= nr {
        return;
    }
    let mut v: DVector<f64> = m.view((r, c), (nr - r, 1)).column(0).into_owned();
    let alpha = v.norm();
    if alpha == 0.0 {
        return;
    }
    let a = if v[0] > 0.0 { -alpha } else { alpha };
    v[0] -= a;
    let vn2 = v.norm_squared();
    if vn2 == 0.0 {
        return;
    }
    let nc = m.ncols();
    let mut sub = m.view_mut((r, c), (nr - r, nc - c));
    // sub -= 2 v (vᵀ sub) / (vᵀ v)
    let w = sub.tr_mul(&v) * (2.0 / vn2);
    sub.ger(-1.0, &v, &w, 1.0);
    m[(r, c)] = a;
    for i in r + 1..nr {
        m[(i, c)] = 0.0;
    }
}

/// `back = Aᵀ (A g)` for one block `A` (`r × w`, column-major in `av`) into the first `r` / `w` entries
/// of the scratch slices. Small blocks (fewer than 8 rows: every joint's) take a plain loop in
/// the very order of nalgebra's `gemv` (column by column, `y = a·x + y`) and `dot` (row by row
/// from zero, its 8-way unrolling idle below 8 rows), so the result is bit-identical to
/// `&a * g` and `a.tr_mul(..)` without their per-call views and checks; larger ones call them.
fn block_normal_product(
    av: &[f64],
    r: usize,
    w: usize,
    g: &[f64],
    jb: &mut [f64],
    back: &mut [f64],
) {
    if r >= 8 {
        let a = nalgebra::DMatrixView::from_slice(av, r, w);
        let gv = DVector::from_column_slice(&g[..w]);
        let j = a * gv;
        let t = a.tr_mul(&j);
        back[..w].copy_from_slice(t.as_slice());
        return;
    }
    if w == 0 {
        return;
    }
    for i in 0..r {
        jb[i] = av[i] * g[0];
    }
    for j in 1..w {
        let gj = g[j];
        let col = &av[j * r..j * r + r];
        for i in 0..r {
            jb[i] += col[i] * gj;
        }
    }
    for j in 0..w {
        let col = &av[j * r..j * r + r];
        let mut s = 0.0;
        for i in 0..r {
            s += col[i] * jb[i];
        }
        back[j] = s;
    }
}

/// σ_max of the block matrix by power iteration on JᵀJ.
///
/// The same operations in the same order as the plain loop (kept as [`sigma_max_reference`],
/// which the tests compare bit for bit): 40 sweeps at most, each `x /= ‖x‖`, then every
/// block's `Aᵀ(A x)` added into `y` in the order of the blocks' first columns, then `‖y‖`.
/// What changed is the cost of a sweep, which grew faster than the blocks (0.39 s on the
/// planar Assur 10^5 file, 9.1 s at 10^6, where the blocks and vectors leave the cache and
/// each block's loops over its groups and rows, of lengths read from memory, kept few cache
/// misses in flight):
/// - blocks of the usual shapes (a joint's rows on one or two bodies of 3 or 6 unknowns) go
///   through loops of fixed length ([`fixed_block`]), the others through the general ones,
/// - the shapes and groups are packed as `u32`,
/// - `‖x‖` is the previous sweep's `‖y‖` (the same vector), not computed twice.
pub(crate) fn sigma_max(sizes: &[usize], offsets: &[usize], blocks: &[Block]) -> f64 {
    let total: usize = sizes.iter().sum();
    if total == 0 || blocks.is_empty() {
        return 0.0;
    }
    let fits = |v: usize| u32::try_from(v).is_ok();
    if !fits(total.saturating_add(1))
        || blocks
            .iter()
            .any(|b| !fits(b.mat.len()) || !fits(b.groups.len()))
    {
        return sigma_max_reference(sizes, offsets, blocks);
    }
    let mut rng = SplitMix64::new(0x51_67_4D_41);
    let mut x = DVector::from_fn(total, |_, _| rng.next_signed() + 1.5);
    // Packed in the order of their first column (as the reference): the gathers and the sums
    // sweep the vectors nearly in order, and the order of the sums into `y` is the reference's.
    let first = |b: &Block| b.groups.iter().map(|&g| offsets[g]).min().unwrap_or(0);
    let mut order: Vec<usize> = (0..blocks.len()).collect();
    order.sort_by_key(|&i| first(&blocks[i]));
    let mut vals: Vec<f64> = Vec::with_capacity(blocks.iter().map(|b| b.mat.len()).sum());
    let mut segs: Vec<(u32, u32)> = Vec::with_capacity(blocks.iter().map(|b| b.groups.len()).sum());
    // (rows, columns, groups, shape) of each block; shape: see `fixed_shape`.
    let mut shapes: Vec<(u32, u32, u32, u8)> = Vec::with_capacity(blocks.len());
    for b in order.iter().map(|&i| &blocks[i]) {
        vals.extend_from_slice(b.mat.as_slice());
        segs.extend(
            b.groups
                .iter()
                .map(|&g| (offsets[g] as u32, sizes[g] as u32)),
        );
        let (r, w) = b.mat.shape();
        let zs: Vec<usize> = b.groups.iter().map(|&g| sizes[g]).collect();
        shapes.push((
            r as u32,
            w as u32,
            b.groups.len() as u32,
            fixed_shape(r, w, &zs),
        ));
    }
    drop(order);
    let wmax = shapes.iter().map(|s| s.1 as usize).max().unwrap_or(0);
    let rmax = shapes.iter().map(|s| s.0 as usize).max().unwrap_or(0);
    let mut gs = vec![0.0; wmax];
    let mut js = vec![0.0; rmax];
    let mut bs = vec![0.0; wmax];
    let mut y = DVector::zeros(total);
    let mut est = 0.0;
    let mut n = x.norm();
    for _ in 0..40 {
        if n == 0.0 {
            return 0.0;
        }
        x /= n;
        y.fill(0.0);
        let (xs, ys) = (x.as_slice(), y.as_mut_slice());
        let (mut at, mut sg) = (0, 0);
        for &(r, w, ng, shape) in &shapes {
            let (r, w, ng) = (r as usize, w as usize, ng as usize);
            let av = &vals[at..at + r * w];
            at += r * w;
            let bsegs = &segs[sg..sg + ng];
            sg += ng;
            macro_rules! fixed {
                ($($k:literal => ($r:literal, $z:literal, $w:literal)),* $(,)?) => {
                    match shape {
                        $($k => {
                            fixed_block::<$r, $z, $w>(av, bsegs, xs, ys);
                            continue;
                        })*
                        _ => {}
                    }
                };
            }
            fixed!(
                1 => (1, 3, 3), 2 => (2, 3, 3), 3 => (3, 3, 3),
                4 => (1, 3, 6), 5 => (2, 3, 6), 6 => (3, 3, 6),
                7 => (1, 6, 6), 8 => (2, 6, 6), 9 => (3, 6, 6),
                10 => (4, 6, 6), 11 => (5, 6, 6),
                12 => (1, 6, 12), 13 => (2, 6, 12), 14 => (3, 6, 12),
                15 => (4, 6, 12), 16 => (5, 6, 12),
            );
            // The general block, as the reference.
            let mut c = 0;
            for &(o, z) in bsegs {
                let (o, z) = (o as usize, z as usize);
                for (d, s) in gs[c..c + z].iter_mut().zip(&xs[o..o + z]) {
                    *d = *s;
                }
                c += z;
            }
            for d in &mut gs[c.min(w)..w] {
                *d = 0.0;
            }
            block_normal_product(av, r, w, &gs, &mut js, &mut bs);
            let mut c = 0;
            for &(o, z) in bsegs {
                let (o, z) = (o as usize, z as usize);
                for (d, s) in ys[o..o + z].iter_mut().zip(&bs[c..c + z]) {
                    *d += *s;
                }
                c += z;
            }
        }
        let ny = y.norm();
        let e = ny.sqrt();
        std::mem::swap(&mut x, &mut y);
        // The next sweep's ‖x‖: the same vector, the same function.
        n = ny;
        if (e - est).abs() <= 1e-6 * e {
            est = e;
            break;
        }
        est = e;
    }
    est * 1.0
}

/// The fixed shape of a block for [`sigma_max`] (0: general): `r` rows (1 to 5) on one or two
/// groups of 3 or 6 unknowns that fill its `w` columns.
fn fixed_shape(r: usize, w: usize, zs: &[usize]) -> u8 {
    let z = zs.first().copied().unwrap_or(0);
    if zs.is_empty() || zs.len() > 2 || zs.iter().any(|&v| v != z) || zs.len() * z != w {
        return 0;
    }
    match (z, zs.len(), r) {
        (3, 1, 1..=3) => r as u8,
        (3, 2, 1..=3) => 3 + r as u8,
        (6, 1, 1..=5) => 6 + r as u8,
        (6, 2, 1..=5) => 11 + r as u8,
        _ => 0,
    }
}

/// `y += Aᵀ(A x)` over the block's groups for a block of `R` rows on `W / Z` groups of `Z`
/// unknowns each (`W` columns), in the order of [`block_normal_product`]'s plain loop
/// (nalgebra's `gemv`, then `dot` from zero) and of the reference's sums into `y`.
fn fixed_block<const R: usize, const Z: usize, const W: usize>(
    av: &[f64],
    segs: &[(u32, u32)],
    xs: &[f64],
    ys: &mut [f64],
) {
    let av = &av[..R * W];
    let mut g = [0.0; W];
    for k in 0..W / Z {
        let o = segs[k].0 as usize;
        let src = &xs[o..o + Z];
        for i in 0..Z {
            g[k * Z + i] = src[i];
        }
    }
    let mut jb = [0.0; R];
    for i in 0..R {
        jb[i] = av[i] * g[0];
    }
    for j in 1..W {
        let gj = g[j];
        for i in 0..R {
            jb[i] += av[j * R + i] * gj;
        }
    }
    let mut back = [0.0; W];
    for j in 0..W {
        let mut s = 0.0;
        for i in 0..R {
            s += av[j * R + i] * jb[i];
        }
        back[j] = s;
    }
    for k in 0..W / Z {
        let o = segs[k].0 as usize;
        let dst = &mut ys[o..o + Z];
        for i in 0..Z {
            dst[i] += back[k * Z + i];
        }
    }
}

/// The former [`sigma_max`] (one loop over the blocks with their shapes read from memory),
/// kept to check the new one bit for bit and for systems too large for `u32` indices.
pub(crate) fn sigma_max_reference(sizes: &[usize], offsets: &[usize], blocks: &[Block]) -> f64 {
    let total: usize = sizes.iter().sum();
    if total == 0 || blocks.is_empty() {
        return 0.0;
    }
    let mut rng = SplitMix64::new(0x51_67_4D_41);
    let mut x = DVector::from_fn(total, |_, _| rng.next_signed() + 1.5);
    let mut est = 0.0;
    // The blocks packed once into two flat arrays (each block's matrix, column-major, and the
    // (offset, size) of its groups), and scratch vectors sized for the widest block reused by
    // every block and iteration. Forty sweeps over a `Vec<Block>` of small heap matrices and
    // group lists, with three fresh vectors and nalgebra's views per block, were a third of
    // `rigid --method geometric` on the planar Assur 10^5 file: the products are tiny, the
    // pointer chasing and allocation were not.
    let mut vals: Vec<f64> = Vec::with_capacity(blocks.iter().map(|b| b.mat.len()).sum());
    let mut segs: Vec<(usize, usize)> =
        Vec::with_capacity(blocks.iter().map(|b| b.groups.len()).sum());
    let mut shapes: Vec<(usize, usize, usize)> = Vec::with_capacity(blocks.len());
    // Packed in the order of their first column: the gathers from `x` and the sums into `y`
    // then sweep the vectors nearly in order instead of jumping across them (at 10^6 bodies
    // the two vectors are 24 MB each and the random order missed the cache on every block).
    // This changes only the order of the sums into `y`, by rounding.
    let first = |b: &Block| b.groups.iter().map(|&g| offsets[g]).min().unwrap_or(0);
    let mut order: Vec<usize> = (0..blocks.len()).collect();
    order.sort_by_key(|&i| first(&blocks[i]));
    for b in order.iter().map(|&i| &blocks[i]) {
        vals.extend_from_slice(b.mat.as_slice());
        segs.extend(b.groups.iter().map(|&g| (offsets[g], sizes[g])));
        shapes.push((b.mat.nrows(), b.mat.ncols(), b.groups.len()));
    }
    let wmax = shapes.iter().map(|s| s.1).max().unwrap_or(0);
    let rmax = shapes.iter().map(|s| s.0).max().unwrap_or(0);
    let mut gs = vec![0.0; wmax];
    let mut js = vec![0.0; rmax];
    let mut bs = vec![0.0; wmax];
    let mut y = DVector::zeros(total);
    for _ in 0..40 {
        let n = x.norm();
        if n == 0.0 {
            return 0.0;
        }
        x /= n;
        y.fill(0.0);
        let (xs, ys) = (x.as_slice(), y.as_mut_slice());
        let (mut at, mut sg) = (0, 0);
        for &(r, w, ng) in &shapes {
            let av = &vals[at..at + r * w];
            at += r * w;
            let bsegs = &segs[sg..sg + ng];
            sg += ng;
            let mut c = 0;
            for &(o, z) in bsegs {
                // An element loop: a group is a handful of entries, and `copy_from_slice`
                // would call `memmove` for each.
                for (d, s) in gs[c..c + z].iter_mut().zip(&xs[o..o + z]) {
                    *d = *s;
                }
                c += z;
            }
            // Columns no group claims stay zero, as in a fresh vector.
            for d in &mut gs[c.min(w)..w] {
                *d = 0.0;
            }
            block_normal_product(av, r, w, &gs, &mut js, &mut bs);
            let mut c = 0;
            for &(o, z) in bsegs {
                for (d, s) in ys[o..o + z].iter_mut().zip(&bs[c..c + z]) {
                    *d += *s;
                }
                c += z;
            }
        }
        let e = y.norm().sqrt();
        std::mem::swap(&mut x, &mut y);
        if (e - est).abs() <= 1e-6 * e {
            est = e;
            break;
        }
        est = e;
    }
    // Power iteration converges from below; a small margin keeps the threshold conservative.
    est * 1.0
}
/// The biconnected blocks of a graph given by adjacency lists of `(neighbour, edge)` (Hopcroft–
/// Tarjan, iterative, from `root` first, then from each further component's first vertex):
/// each block's root (the vertex through which the search entered it) and its edges ascending,
/// in the order the search closes them. Shared by the structural rank check and the geometric
/// rigidity analysis, which both work block by block.
pub(crate) fn biconnected_blocks(
    adj: &[Vec<(usize, usize)>],
    root: usize,
) -> Vec<(usize, Vec<usize>)> {
    let nb = adj.len();
    let mut disc = vec![usize::MAX; nb];
    let mut low = vec![0usize; nb];
    let mut time = 0;
    let mut estack: Vec<usize> = Vec::new();
    let mut blocks: Vec<(usize, Vec<usize>)> = Vec::new();
    for s in std::iter::once(root).chain(0..nb) {
        if disc[s] != usize::MAX {
            continue;
        }
        disc[s] = time;
        low[s] = time;
        time += 1;
        // (node, edge it was entered by, next neighbour index)
        let mut stack: Vec<(usize, usize, usize)> = vec![(s, usize::MAX, 0)];
        while let Some(&mut (v, via, ref mut next)) = stack.last_mut() {
            if *next < adj[v].len() {
                let (w, e) = adj[v][*next];
                *next += 1;
                if e == via {
                    continue;
                }
                if disc[w] == usize::MAX {
                    estack.push(e);
                    disc[w] = time;
                    low[w] = time;
                    time += 1;
                    stack.push((w, e, 0));
                } else if disc[w] < disc[v] {
                    estack.push(e);
                    low[v] = low[v].min(disc[w]);
                }
            } else {
                stack.pop();
                if let Some(&(p, _, _)) = stack.last() {
                    low[p] = low[p].min(low[v]);
                    if low[v] >= disc[p] {
                        let mut block = Vec::new();
                        while let Some(e) = estack.pop() {
                            block.push(e);
                            if e == via {
                                break;
                            }
                        }
                        block.sort_unstable();
                        blocks.push((p, block));
                    }
                }
            }
        }
    }
    blocks
}

/// The elimination's former bookkeeping, kept for tests: a set of live block ids per group
/// and the front widths as set unions ([`Elimination::run_within`] must agree with it).
#[cfg(test)]
mod shadow {
    use super::Block;
    use std::collections::BTreeSet;

    pub(super) struct Shadow {
        of_group: Vec<BTreeSet<usize>>,
    }

    impl Shadow {
        pub(super) fn new(n: usize, store: &[Option<Block>]) -> Shadow {
            let mut of_group = vec![BTreeSet::new(); n];
            for (id, b) in store.iter().enumerate() {
                for &g in &b.as_ref().expect("all live at the start").groups {
                    of_group[g].insert(id);
                }
            }
            Shadow { of_group }
        }

        pub(super) fn add(&mut self, id: usize, groups: &[usize]) {
            for &g in groups {
                self.of_group[g].insert(id);
            }
        }

        /// The live blocks on `g`, removed from every group (ascending ids).
        pub(super) fn take(&mut self, g: usize, store: &[Option<Block>]) -> Vec<usize> {
            let ids: Vec<usize> = self.of_group[g].iter().copied().collect();
            for &id in &ids {
                if let Some(b) = &store[id] {
                    for &h in &b.groups {
                        self.of_group[h].remove(&id);
                    }
                }
            }
            ids
        }

        pub(super) fn score(&self, g: usize, store: &[Option<Block>], sizes: &[usize]) -> usize {
            let mut u = BTreeSet::new();
            for &bi in &self.of_group[g] {
                if let Some(b) = &store[bi] {
                    u.extend(b.groups.iter().copied());
                }
            }
            u.iter().map(|&h| sizes[h]).sum::<usize>()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The packed σ_max (fixed-shape blocks, `u32` indices, the norm carried over) gives the
    /// plain loop's bits: blocks on one to three groups of 3, 6 or other sizes, 0 to 9 rows
    /// (the fixed shapes, the general small blocks and nalgebra's products from 8 rows), now
    /// and then a column no group claims.
    #[test]
    fn sigma_max_gives_the_plain_loops_bits() {
        let mut rng = SplitMix64::new(0x5167_4d41);
        for case in 0..80 {
            let n = 2 + rng.below(40) as usize;
            let main = if case % 2 == 0 { 3 } else { 6 };
            let sizes: Vec<usize> = (0..n)
                .map(|_| match rng.below(4) {
                    0 => 1 + rng.below(6) as usize,
                    1 => 3,
                    _ => main,
                })
                .collect();
            let mut offsets = Vec::new();
            let mut total = 0;
            for &s in &sizes {
                offsets.push(total);
                total += s;
            }
            let nblocks = 1 + rng.below(3 * n as u64) as usize;
            let blocks: Vec<Block> = (0..nblocks)
                .map(|_| {
                    let k = 1 + rng.below(3) as usize;
                    let mut groups: Vec<usize> =
                        (0..k).map(|_| rng.below(n as u64) as usize).collect();
                    groups.sort_unstable();
                    groups.dedup();
                    let extra = usize::from(rng.below(10) == 0);
                    let width: usize = groups.iter().map(|&g| sizes[g]).sum::<usize>() + extra;
                    let rows = rng.below(10) as usize;
                    let mat = DMatrix::from_fn(rows, width, |_, _| rng.next_signed());
                    Block { groups, mat }
                })
                .collect();
            let new = sigma_max(&sizes, &offsets, &blocks);
            let old = sigma_max_reference(&sizes, &offsets, &blocks);
            assert_eq!(new.to_bits(), old.to_bits(), "case {case}: {new} vs {old}");
        }
    }

    /// Random block systems, over- and under-determined, with blocks on up to five groups
    /// (rows left over fill in, blocks are taken and rescored many times): the vector
    /// bookkeeping of [`Elimination::run_within`] gives the set-based one's scores and fronts
    /// (asserted inside, [`shadow`]), and the rank is the dense SVD's (generic entries).
    #[test]
    fn pivot_order_bookkeeping_matches_the_set_based_one() {
        let mut rng = SplitMix64::new(0x0fa5_7e11);
        for case in 0..40 {
            let n = 5 + rng.below(40) as usize;
            let sizes: Vec<usize> = (0..n).map(|_| 1 + rng.below(6) as usize).collect();
            let mut offsets = Vec::new();
            let mut total = 0;
            for &s in &sizes {
                offsets.push(total);
                total += s;
            }
            let nblocks = n / 2 + rng.below(3 * n as u64) as usize;
            let mut blocks = Vec::new();
            let mut dense_rows: Vec<Vec<f64>> = Vec::new();
            for _ in 0..nblocks {
                let k = 1 + rng.below(5) as usize;
                let mut groups: Vec<usize> = (0..k).map(|_| rng.below(n as u64) as usize).collect();
                groups.sort_unstable();
                groups.dedup();
                let width: usize = groups.iter().map(|&g| sizes[g]).sum();
                let rows = 1 + rng.below(6) as usize;
                let mat = DMatrix::from_fn(rows, width, |_, _| rng.next_signed());
                for i in 0..rows {
                    let mut row = vec![0.0; total];
                    let mut c = 0;
                    for &g in &groups {
                        for j in 0..sizes[g] {
                            row[offsets[g] + j] = mat[(i, c + j)];
                        }
                        c += sizes[g];
                    }
                    dense_rows.push(row);
                }
                blocks.push(Block { groups, mat });
            }
            let e = Elimination::run(&sizes, blocks, 1e-9);
            let dense = DMatrix::from_fn(dense_rows.len(), total, |i, j| dense_rows[i][j]);
            let sv = dense.singular_values();
            let expected = sv.iter().filter(|&&s| s > 1e-9 * sv.max().max(1.0)).count();
            assert_eq!(e.rank, expected, "case {case}");
        }
    }

    /// The steered threshold moves a run's rank to the target in one more run: with pivots
    /// too many it falls in the gap above the `d` smallest kept pivot norms, with too few in
    /// the gap below the `d` largest dropped ones (one group per unknown, so every column's
    /// decision is recorded); with fewer decisions than asked, or at the target, none.
    #[test]
    fn steered_threshold_reaches_the_target_rank() {
        let norms = [1.0, 0.1, 1e-6, 1e-7, 3e-9];
        let sizes = vec![1usize; norms.len()];
        let blocks: Vec<Block> = norms
            .iter()
            .enumerate()
            .map(|(g, &v)| Block {
                groups: vec![g],
                mat: DMatrix::from_element(1, 1, v),
            })
            .collect();
        let at = |t: f64| Elimination::run(&sizes, blocks.clone(), t);
        let low = at(1e-12);
        assert_eq!(low.rank, 5);
        for target in 1..5 {
            let t = low.steered_threshold(target).expect("steers down");
            assert_eq!(at(t).rank, target, "down to {target}: {t:e}");
        }
        assert!(low.steered_threshold(5).is_none());
        let high = at(2.0);
        assert_eq!(high.rank, 0);
        assert_eq!(high.dropped.len(), 5);
        for target in 1..=5 {
            let t = high.steered_threshold(target).expect("steers up");
            assert_eq!(at(t).rank, target, "up to {target}: {t:e}");
        }
        assert!(high.steered_threshold(6).is_none());
        // Down by one from rank 4: between 1e-7 and 1e-6, not at the edge of either.
        let t = at(1e-8).steered_threshold(3).expect("steers");
        assert!(t > 2e-7 && t < 5e-7, "{t:e}");
    }

    /// The metered elimination charges its fronts' real work, which on an over-determined
    /// system with fill (the shape of a self-stress support's transpose: more rows than
    /// columns per group, rows left over on the union of their neighbours) is far more than
    /// the triangular factors [`Elimination::work`] counts; it gives the same elimination as
    /// the unmetered one, and a work limit below its charge stops it with the meter's error.
    #[test]
    fn metered_elimination_charges_fronts_and_compressions() {
        let mut rng = SplitMix64::new(0x5e1f_5743);
        let n = 60;
        let sizes = vec![6usize; n];
        let make = |rng: &mut SplitMix64| -> Vec<Block> {
            (0..n)
                .map(|g| {
                    // Each group's six equations on itself and two random other groups.
                    let mut groups = vec![
                        g,
                        rng.below(n as u64) as usize,
                        rng.below(n as u64) as usize,
                    ];
                    groups.sort_unstable();
                    groups.dedup();
                    let width = 6 * groups.len();
                    let mat = DMatrix::from_fn(8, width, |_, _| rng.next_signed());
                    Block { groups, mat }
                })
                .collect()
        };
        let blocks = make(&mut rng);
        let plain = Elimination::run(&sizes, blocks.clone(), 1e-9);
        let mut meter = crate::budget::Budget::UNLIMITED.meter("test");
        let metered = Elimination::run_metered(&sizes, blocks.clone(), 1e-9, u64::MAX, &mut meter)
            .expect("no limit");
        assert_eq!(metered.rank, plain.rank);
        assert_eq!(metered.records.len(), plain.records.len());
        for (a, b) in metered.records.iter().zip(&plain.records) {
            assert_eq!(a.group, b.group);
            assert_eq!(a.r, b.r);
        }
        let used = meter.used();
        // Every front's rows × columns at least once per pivot: here well over the factors.
        assert!(
            used > 4 * plain.work(),
            "charged {used}, factors {}",
            plain.work()
        );
        // The same charge again (deterministic), and a limit one unit short stops it.
        let budget = crate::budget::Budget {
            max_work: used,
            ..crate::budget::Budget::UNLIMITED
        };
        let mut exact = budget.meter("test");
        assert!(
            Elimination::run_metered(&sizes, blocks.clone(), 1e-9, u64::MAX, &mut exact).is_ok()
        );
        assert_eq!(exact.used(), used);
        let short = crate::budget::Budget {
            max_work: used - 1,
            ..crate::budget::Budget::UNLIMITED
        };
        let mut meter = short.meter("the test elimination");
        match Elimination::run_metered(&sizes, blocks, 1e-9, u64::MAX, &mut meter) {
            Err(Stop::Work(e)) => assert_eq!(e.limit, crate::budget::Limit::Work),
            Err(Stop::Memory(n)) => panic!("memory {n}"),
            Ok(_) => panic!("answered within {} units", used - 1),
        }
    }
}
