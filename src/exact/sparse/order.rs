//! The greedy minimum-front order within a tier: the live blocks by group with each group's
//! estimated fill, and the queue of groups waiting to be eliminated.

use super::blocks::Blk;

/// The groups waiting to be eliminated, least key first: `(tier, estimated fill, front
/// width)`, ties by group. An indexed 4-ary heap holding one entry per group, its key changed
/// in place when the group is rescored. It pops the groups in the very order of the former
/// `BinaryHeap` of `Reverse((tier, score, group, version))` that took a new entry at every
/// rescore and skipped the stale ones (the keys are distinct, so the order is the keys' order
/// whatever the heap), without the stale entries: at 10^6 bodies they were tens of megabytes
/// and every pop walked down a heap several times the size of the live one.
pub(super) struct GroupQueue {
    /// `(tier, fill, width, group)`, a 4-ary min-heap.
    pub(super) heap: Vec<(u32, usize, usize, usize)>,
    /// Each group's place in `heap` ([`GroupQueue::NONE`]: not in it).
    pub(super) pos: Vec<usize>,
}

impl GroupQueue {
    const NONE: usize = usize::MAX;

    pub(super) fn new(n: usize) -> GroupQueue {
        GroupQueue {
            heap: Vec::with_capacity(n),
            pos: vec![Self::NONE; n],
        }
    }

    /// Put `g` in the queue with `key`, or change its key.
    pub(super) fn set(&mut self, g: usize, key: (u32, usize, usize)) {
        let e = (key.0, key.1, key.2, g);
        let i = self.pos[g];
        if i == Self::NONE {
            self.heap.push(e);
            let i = self.heap.len() - 1;
            self.pos[g] = i;
            self.up(i);
        } else {
            let old = self.heap[i];
            self.heap[i] = e;
            if e < old {
                self.up(i);
            } else {
                self.down(i);
            }
        }
    }

    /// The group of least key, taken out of the queue.
    pub(super) fn pop(&mut self) -> Option<usize> {
        let top = *self.heap.first()?;
        let last = self.heap.pop()?;
        self.pos[top.3] = Self::NONE;
        if !self.heap.is_empty() {
            self.heap[0] = last;
            self.pos[last.3] = 0;
            self.down(0);
        }
        Some(top.3)
    }

    fn up(&mut self, mut i: usize) {
        let e = self.heap[i];
        while i > 0 {
            let p = (i - 1) / 4;
            if self.heap[p] <= e {
                break;
            }
            self.heap[i] = self.heap[p];
            self.pos[self.heap[i].3] = i;
            i = p;
        }
        self.heap[i] = e;
        self.pos[e.3] = i;
    }

    fn down(&mut self, mut i: usize) {
        let e = self.heap[i];
        let n = self.heap.len();
        loop {
            let c0 = 4 * i + 1;
            if c0 >= n {
                break;
            }
            let mut m = c0;
            for c in c0 + 1..(c0 + 4).min(n) {
                if self.heap[c] < self.heap[m] {
                    m = c;
                }
            }
            if self.heap[m] >= e {
                break;
            }
            self.heap[i] = self.heap[m];
            self.pos[self.heap[i].3] = i;
            i = m;
        }
        self.heap[i] = e;
        self.pos[e.3] = i;
    }
}

/// The live blocks of an elimination, indexed by group, with per-group row and width sums
/// kept up to date for the pivot order.
pub(super) struct Pool<'a> {
    pub(super) sizes: &'a [usize],
    store: Vec<Option<Blk>>,
    /// Block ids per group (dead ids pruned lazily).
    of_group: Vec<Vec<usize>>,
    /// Live blocks, their rows and the sum of their widths, per group.
    nblk: Vec<usize>,
    rsum: Vec<usize>,
    wsum: Vec<usize>,
    /// Bytes held by the live blocks.
    pub(super) bytes: u64,
    /// Scratch of [`Pool::score`]: the group's blocks and the groups of `U`.
    sc_blocks: Vec<(usize, usize, usize)>,
    sc_u: Vec<usize>,
}

/// Blocks on more groups than this are "wide" (a carried row): the pivot order treats them
/// approximately.
pub(super) const WIDE_BLOCK: usize = 64;

/// Groups with more live blocks than this get the width bound instead of the exact union.
const EXACT_SCORE_BLOCKS: usize = 32;

impl<'a> Pool<'a> {
    pub(super) fn new(sizes: &'a [usize], cap: usize) -> Pool<'a> {
        let n = sizes.len();
        Pool {
            sizes,
            store: Vec::with_capacity(cap),
            of_group: vec![Vec::new(); n],
            nblk: vec![0; n],
            rsum: vec![0; n],
            wsum: vec![0; n],
            bytes: 0,
            sc_blocks: Vec::new(),
            sc_u: Vec::new(),
        }
    }

    pub(super) fn width(&self, b: &Blk) -> usize {
        b.width()
    }

    pub(super) fn add(&mut self, b: Blk) {
        let id = self.store.len();
        let w = self.width(&b);
        self.bytes = self.bytes.saturating_add(b.bytes());
        for &g in &b.groups {
            self.of_group[g].push(id);
            self.nblk[g] += 1;
            self.rsum[g] += b.nrows;
            self.wsum[g] += w;
        }
        self.store.push(Some(b));
    }

    /// Remove and return the live blocks on group `g`.
    pub(super) fn take(&mut self, g: usize) -> Vec<Blk> {
        let ids = std::mem::take(&mut self.of_group[g]);
        let mut out = Vec::with_capacity(ids.len());
        for id in ids {
            if let Some(b) = self.store[id].take() {
                let w = self.width(&b);
                self.bytes = self.bytes.saturating_sub(b.bytes());
                for &h in &b.groups {
                    self.nblk[h] -= 1;
                    self.rsum[h] -= b.nrows;
                    self.wsum[h] -= w;
                }
                out.push(b);
            }
        }
        out
    }

    /// The cost of eliminating `g` now, as (estimated new entries, front width). The
    /// estimate takes the pivots from the narrowest blocks (as the elimination does), lets
    /// `U` be the columns those pivot rows span, and counts the pivot rows (`|U|` each) and,
    /// for every row left over, the columns of `U` its block lacks (its fill). A group whose
    /// front has no more rows than columns leaves nothing behind (a tip of a chain, a leaf
    /// of a star, the last body of a determined group); a row crossing many groups that is
    /// only carried along adds little. Groups on more than [`EXACT_SCORE_BLOCKS`] blocks
    /// get a bound instead (they go late).
    /// Over 80 lines: one estimate in two passes over the same blocks, sharing their marks.
    pub(super) fn score(
        &mut self,
        g: usize,
        stamp: &mut [usize],
        clock: &mut usize,
    ) -> (usize, usize) {
        let sg = self.sizes[g];
        let ids = &mut self.of_group[g];
        if ids.len() > 2 * self.nblk[g] + 8 {
            let store = &self.store;
            ids.retain(|&id| store[id].is_some());
        }
        if self.nblk[g] > EXACT_SCORE_BLOCKS {
            let width = (self.wsum[g] + sg).saturating_sub(self.nblk[g] * sg);
            return (self.rsum[g].saturating_mul(width), width);
        }
        let mut blocks = std::mem::take(&mut self.sc_blocks);
        blocks.clear();
        blocks.extend(self.of_group[g].iter().filter_map(|&id| {
            let b = self.store[id].as_ref()?;
            Some((self.width(b), b.nrows, id))
        }));
        blocks.sort_unstable();
        // U: the union of the narrowest blocks supplying sg rows.
        *clock += 1;
        let mark = *clock;
        stamp[g] = mark;
        let mut u_groups = std::mem::take(&mut self.sc_u);
        u_groups.clear();
        let mut uw = sg;
        let mut need = sg;
        for &(_, nr, id) in &blocks {
            if need == 0 {
                break;
            }
            if let Some(b) = &self.store[id] {
                for &h in &b.groups {
                    if stamp[h] != mark {
                        stamp[h] = mark;
                        uw += self.sizes[h];
                        u_groups.push(h);
                    }
                }
            }
            need = need.saturating_sub(nr);
        }
        let pivots = sg - need;
        let mut fill = pivots * uw;
        // Rows left over gain the columns of U their block lacks; the width counts the
        // narrow blocks' groups exactly and the wide ones' by their width.
        let mut left = pivots;
        *clock += 1;
        let wmark = *clock;
        stamp[g] = wmark;
        let mut width = uw;
        for &(bw, nr, id) in &blocks {
            let used = left.min(nr);
            left -= used;
            let rest = nr - used;
            let Some(b) = &self.store[id] else { continue };
            let mut inside = sg;
            if b.groups.len() <= WIDE_BLOCK {
                for &h in &b.groups {
                    if stamp[h] == mark {
                        inside += self.sizes[h];
                    } else if stamp[h] != wmark {
                        stamp[h] = wmark;
                        width += self.sizes[h];
                    }
                }
            } else {
                for &h in &u_groups {
                    if b.groups.binary_search(&h).is_ok() {
                        inside += self.sizes[h];
                    }
                }
                width += bw - inside;
            }
            fill += rest * uw.saturating_sub(inside);
        }
        (self.sc_blocks, self.sc_u) = (blocks, u_groups);
        (fill, width)
    }
}
