//! The component pebble game: the game with its rigid components kept as it goes (contracted
//! into one vertex each), so that large rigid frameworks cost about linear work.

use super::graph::Graph;
use crate::budget::{BudgetExceeded, Meter};

/// The component pebble game with contraction: the game of [`Game`], but
/// every rigid component found is contracted into one vertex of weight B (a *super-body*, kept
/// under the id of one of its bodies) and each joint node inside it is re-pinned to that
/// vertex by B − k bars. A tight set behaves, for every bar outside it, like one body with its
/// nodes pinned on it (the count matroid of the contracted graph is the contraction of the
/// original's by the component's bars), so:
/// - a bar with both ends in one component is redundant without any search (same super-body,
///   or a node already pinned to it by B − k bars);
/// - searches cross a component in one step: a super-body has at most B out-edges;
/// - after an independent bar uv is inserted, a failed gather of B + 1 pebbles on u, v gives
///   the minimal tight set, the reverse search grows it to the maximal one (Lee and Streinu),
///   and the parts are merged into the part with the most in-edges (the others' edges are
///   relabelled: smaller into larger);
/// - a bar with an end of fewer bars than its weight is inserted without a search (that end
///   pays for it), and the tightness check after it is skipped when degrees rule a tight set
///   out;
/// - a bar that needs a search keeps one pebble (an end's own, or the one from the latest
///   vertex) and gives the B borrowed ones back along the paths they came by, after the
///   tightness check: on a flexible linkage the free pebbles stay at the frame and in the
///   slack of the group being built, instead of wandering away with every search (an
///   earlier game grew with exponent 1.76 on Assur linkages).
///
/// The answers (which bars are independent, the rigid components) are those of the plain game;
/// `tests/it/pebble_props.rs` compares them on random graphs.
pub(super) struct Fast {
    pub(super) l: u8,
    pub(super) n_bodies: usize,
    /// The vertices, one cache line each: pebbles, out-bars and the search's marks.
    pub(super) v: Vec<Vtx>,
    /// Every bar at each vertex, in and out (bar ids into `ends`). A flip leaves these lists
    /// as they are; only inserting a bar and contracting a component change them.
    pub(super) inc: Vec<Vec<u32>>,
    /// The two ends of each bar, in no particular order (the direction is in the out-bars).
    pub(super) ends: Vec<[u32; 2]>,
    /// Position of each bar in the `inc` list of `ends[bar][0]` and of `ends[bar][1]`.
    pub(super) pos: Vec<[u32; 2]>,
    /// Union-find over bodies: the root is the super-body's id.
    pub(super) parent: Vec<u32>,
    /// Bodies of each super-body (at its root).
    pub(super) members: Vec<Vec<u32>>,
    pub(super) epoch: u32,
    pub(super) stack: Vec<u32>,
    pub(super) visited: Vec<u32>,
    /// Reverse search: in the growing tight set (`qmark == qepoch`), known to reach a free
    /// pebble (`fmark == qepoch`).
    pub(super) qmark: Vec<u32>,
    pub(super) fmark: Vec<u32>,
    pub(super) qepoch: u32,
    /// When not u32::MAX, searches take a pebble from this vertex only.
    pub(super) only: u32,
    /// Position of each vertex in the insertion order (first bar that names it): a closing
    /// bar keeps the borrowed pebble of the latest vertex.
    pub(super) rank: Vec<u32>,
    /// Pebble moves kept for undoing, while `recording`: (source, target, start in `log`), and
    /// the bars each move turned round, as (tail, head, bar) after the turn.
    pub(super) moves: Vec<(u32, u32, u32)>,
    pub(super) log: Vec<[u32; 3]>,
    pub(super) recording: bool,
    /// Whether some contraction made a rigid set of at least two bodies but not all of them
    /// (it stays rigid as bars are added: a proper rigid sub-chain).
    pub(super) proper: bool,
    /// Work units not yet charged to the meter.
    pub(super) work: u64,
}

/// Most out-bars of a vertex: pebbles + out-bars = weight ≤ B ≤ 6 at every moment.
pub(super) const MAX_OUT: usize = 6;

/// One vertex of the contracted game in one cache line: a search step reads the vertex's
/// out-bars (heads inline) and each head's mark and pebbles, one line each; turning a path
/// round touches the same lines. An earlier version kept these in eight arrays and two heap lists per
/// vertex (about ten cache misses per step at 10^6 vertices).
#[derive(Clone, Copy, Default)]
#[repr(C, align(64))]
pub(super) struct Vtx {
    /// Heads and bar ids of the out-bars, `nout` of them.
    pub(super) head: [u32; MAX_OUT],
    pub(super) bar: [u32; MAX_OUT],
    /// Search epoch that reached the vertex.
    pub(super) mark: u32,
    /// The vertex the search came from, and the slot of its out-bar to this one.
    pub(super) from: u32,
    pub(super) peb: u8,
    pub(super) weight: u8,
    pub(super) nout: u8,
    pub(super) slot: u8,
}

impl Vtx {
    pub(super) fn push_out(&mut self, h: u32, bar: u32) {
        let n = self.nout as usize;
        self.head[n] = h;
        self.bar[n] = bar;
        self.nout += 1;
    }

    /// Remove the out-bar in `slot`; the last one takes its place (as `Vec::swap_remove`).
    pub(super) fn remove_out(&mut self, slot: usize) -> u32 {
        let last = self.nout as usize - 1;
        let bar = self.bar[slot];
        self.head[slot] = self.head[last];
        self.bar[slot] = self.bar[last];
        self.nout -= 1;
        bar
    }

    pub(super) fn outs(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        let n = self.nout as usize;
        self.head[..n]
            .iter()
            .copied()
            .zip(self.bar[..n].iter().copied())
    }
}

impl Fast {
    pub(super) fn new(weight: Vec<u8>, n_bodies: usize, l: u8, bars: usize) -> Fast {
        let n = weight.len();
        Fast {
            l,
            n_bodies,
            v: weight
                .iter()
                .map(|&w| Vtx {
                    peb: w,
                    weight: w,
                    ..Vtx::default()
                })
                .collect(),
            inc: vec![Vec::new(); n],
            ends: Vec::with_capacity(bars),
            pos: Vec::with_capacity(bars),
            parent: (0..n_bodies as u32).collect(),
            members: (0..n_bodies as u32).map(|b| vec![b]).collect(),
            epoch: 0,
            stack: Vec::new(),
            visited: Vec::new(),
            qmark: vec![0; n],
            fmark: vec![0; n],
            qepoch: 0,
            rank: vec![u32::MAX; n],
            only: u32::MAX,
            moves: Vec::new(),
            log: Vec::new(),
            recording: false,
            proper: false,
            work: 0,
        }
    }

    pub(super) fn peb(&self, x: u32) -> u8 {
        self.v[x as usize].peb
    }

    pub(super) fn weight(&self, x: u32) -> u8 {
        self.v[x as usize].weight
    }

    /// Whether a tight set of two or more vertices may hold both `x` and `y`, by degrees alone.
    /// In a tight set T every vertex z has at least its weight of bars inside T (removing
    /// z leaves at most w(T − z) − B bars if T − z spans one, and if not, z carries all
    /// w(T) − B ≥ w(z) of them), and a body with fewer than B bars in T has only nodes beside
    /// it (else the same count gives B).
    pub(super) fn may_be_tight(&self, x: u32, y: u32) -> bool {
        let short = |z: u32| self.degree(z) < self.weight(z) as usize;
        let thin_body = |z: u32| self.is_body(z) && self.degree(z) < self.l as usize;
        let full_body = |z: u32| {
            self.is_body(z) && self.degree(z) == self.l as usize && self.beside_two_bodies(z)
        };
        !(short(x)
            || short(y)
            || (thin_body(x) && self.is_body(y))
            || (thin_body(y) && self.is_body(x))
            || full_body(x)
            || full_body(y))
    }

    /// An end of the bar x–y that can take it without a search: a vertex `t` with fewer bars
    /// than its weight makes the bar independent whatever the rest of the graph (any bar set
    /// E′ through the new bar either has bars away from t, at most w(V′ − t) − B of them,
    /// plus at most w(t) at t, or is a star at t, whose bars to each neighbour stay within
    /// that neighbour's weight), and t has a free pebble to spend on it. Returns (tail, head):
    /// the end with more spare bars (usually the newer body; x on a tie, so that the frame
    /// spends its pebbles on its first neighbour and the free ones sit on both, each
    /// reachable from the other).
    pub(super) fn fresh_end(&self, x: u32, y: u32) -> Option<(u32, u32)> {
        let spare = |t: u32| (self.weight(t) as usize).saturating_sub(self.degree(t));
        let fits = |t: u32, h: u32| {
            spare(t) > 0
                && (!self.is_body(t)
                    || self.is_body(h)
                    || self.bars_between(h, t) < self.weight(h) as usize)
        };
        let (a, b) = if spare(x) >= spare(y) { (x, y) } else { (y, x) };
        if fits(a, b) {
            Some((a, b))
        } else if fits(b, a) {
            Some((b, a))
        } else {
            None
        }
    }

    /// The other end of `bar` at `x`.
    pub(super) fn other(&self, bar: u32, x: u32) -> u32 {
        let [a, b] = self.ends[bar as usize];
        if a == x { b } else { a }
    }

    /// Whether body `z`, with at most B bars, has two different (super-)bodies beside it. Then
    /// no tight set holds z with another vertex: it would hold all of z's bars (a vertex
    /// carries at least its weight of bars inside a tight set), so the rest would be a
    /// tight set with two super-bodies before this bar (the game contracts every such set as
    /// it forms), or a bar-free set of weight B.
    pub(super) fn beside_two_bodies(&self, z: u32) -> bool {
        let mut first: Option<u32> = None;
        for &bar in &self.inc[z as usize] {
            let y = self.other(bar, z);
            if self.is_body(y) {
                match first {
                    None => first = Some(y),
                    Some(f) if f != y => return true,
                    Some(_) => {}
                }
            }
        }
        false
    }

    /// Bars at vertex `x` in the contracted graph.
    pub(super) fn degree(&self, x: u32) -> usize {
        self.inc[x as usize].len()
    }

    pub(super) fn is_body(&self, x: u32) -> bool {
        (x as usize) < self.n_bodies
    }

    /// The current vertex of original vertex `x`: its super-body, or the node itself.
    pub(super) fn rep(&mut self, mut x: u32) -> u32 {
        if !self.is_body(x) {
            return x;
        }
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = p;
            self.work += 1;
        }
        x
    }

    pub(super) fn next_epoch(&mut self) -> u32 {
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.v.iter_mut().for_each(|r| r.mark = 0);
            self.epoch = 1;
        }
        self.epoch
    }

    /// Add a bar oriented `t` → `h` (the caller accounts for the pebble).
    pub(super) fn link(&mut self, t: u32, h: u32) -> u32 {
        let bar = self.ends.len() as u32;
        self.ends.push([t, h]);
        self.pos.push([
            self.inc[t as usize].len() as u32,
            self.inc[h as usize].len() as u32,
        ]);
        self.inc[t as usize].push(bar);
        self.inc[h as usize].push(bar);
        self.v[t as usize].push_out(h, bar);
        bar
    }

    /// Remove `bar` from the lists of both its ends (not from the out-bars).
    pub(super) fn unlink(&mut self, bar: u32) {
        for side in 0..2 {
            let x = self.ends[bar as usize][side];
            let p = self.pos[bar as usize][side] as usize;
            let list = &mut self.inc[x as usize];
            list.swap_remove(p);
            if let Some(&moved) = list.get(p) {
                let s = usize::from(self.ends[moved as usize][0] != x);
                self.pos[moved as usize][s] = p as u32;
            }
        }
    }

    /// Turn round the out-bar in `slot` of `p` (to `z`): it becomes an out-bar of `z`.
    pub(super) fn flip_slot(&mut self, p: u32, slot: usize, z: u32) -> u32 {
        let bar = self.v[p as usize].remove_out(slot);
        self.v[z as usize].push_out(p, bar);
        bar
    }

    /// Position of `bar` among the out-bars of `t`.
    pub(super) fn slot_of(&self, t: u32, bar: u32) -> usize {
        let r = &self.v[t as usize];
        r.bar[..r.nout as usize]
            .iter()
            .position(|&b| b == bar)
            .unwrap_or(0)
    }

    /// Bars between node `n` and vertex `s`, in either direction (both out-lists are short).
    pub(super) fn bars_between(&self, n: u32, s: u32) -> usize {
        let a = self.v[n as usize].outs().filter(|&(h, _)| h == s).count();
        let b = self.v[s as usize].outs().filter(|&(h, _)| h == n).count();
        a + b
    }

    /// Move one free pebble reachable from `s` onto `s`, never taking one from `a` or `b`.
    pub(super) fn find_pebble(&mut self, s: u32, a: u32, b: u32) -> bool {
        let e = self.next_epoch();
        self.v[s as usize].mark = e;
        self.stack.clear();
        self.stack.push(s);
        while let Some(x) = self.stack.pop() {
            let rx = self.v[x as usize];
            for i in 0..rx.nout as usize {
                let y = rx.head[i];
                self.work += 1;
                let ry = &mut self.v[y as usize];
                if ry.mark == e {
                    continue;
                }
                ry.mark = e;
                ry.from = x;
                ry.slot = i as u8;
                self.visited.push(y);
                if y != a && y != b && ry.peb > 0 && (self.only == u32::MAX || self.only == y) {
                    ry.peb -= 1;
                    if self.recording {
                        self.moves.push((y, s, self.log.len() as u32));
                    }
                    let mut z = y;
                    while z != s {
                        let (p, slot) = (self.v[z as usize].from, self.v[z as usize].slot);
                        let bar = self.flip_slot(p, slot as usize, z);
                        if self.recording {
                            self.log.push([z, p, bar]);
                        }
                        z = p;
                        self.work += 1;
                    }
                    self.v[s as usize].peb += 1;
                    return true;
                }
                self.stack.push(y);
            }
        }
        false
    }

    /// Insert the independent bar between the representatives `x` and `y`, paid by a pebble
    /// of `t` and directed from `t` to `h`; then, when the pair may be tight (no `l + 1`
    /// pebbles can be gathered on it), contract the new rigid component.
    pub(super) fn insert_bar(&mut self, t: u32, h: u32, x: u32, y: u32) {
        self.v[t as usize].peb -= 1;
        self.link(t, h);
        if self.may_be_tight(x, y) {
            self.recording = true;
            let ok = self.gather(x, y, self.l + 1);
            self.recording = false;
            if ok {
                self.undo_to(0);
            } else {
                self.keep_moves(0);
                self.contract(x, y);
            }
        }
    }

    /// Gather `target` free pebbles on {u, v}; on failure `visited` holds the rest of the
    /// minimal tight set containing u and v (closed: no out-edge leaves it).
    pub(super) fn gather(&mut self, u: u32, v: u32, target: u8) -> bool {
        // Fill first the end that holds more pebbles (fewer bars on a tie): usually the newer
        // body, whose missing pebbles are near.
        let key = |x: u32| (self.peb(x), usize::MAX - self.degree(x));
        let (u, v) = if key(v) > key(u) { (v, u) } else { (u, v) };
        while self.peb(u) + self.peb(v) < target {
            self.visited.clear();
            if self.peb(u) < self.weight(u) && self.find_pebble(u, u, v) {
                continue;
            }
            if self.peb(v) < self.weight(v) && self.find_pebble(v, u, v) {
                continue;
            }
            return false;
        }
        true
    }

    /// Undo the recorded pebble moves after the first `mark`, last first: every pebble goes
    /// back where it came from, every bar turns back.
    pub(super) fn undo_to(&mut self, mark: usize) {
        while self.moves.len() > mark {
            let Some((z, s, start)) = self.moves.pop() else {
                break;
            };
            // The bars turn back in the order they turned, each pushed onto its old tail, from
            // which the next is removed: the push and the removal are one replacement in
            // place (push, then `swap_remove` moves the pushed bar into the freed slot), so a
            // vertex never holds more than its weight of out-bars.
            let mut pending: Option<(u32, u32, u32)> = None;
            for k in start as usize..self.log.len() {
                let [t, h, bar] = self.log[k];
                let j = self.slot_of(t, bar);
                match pending {
                    Some((x, head, b)) if x == t => {
                        let r = &mut self.v[t as usize];
                        r.head[j] = head;
                        r.bar[j] = b;
                    }
                    other => {
                        if let Some((x, head, b)) = other {
                            self.v[x as usize].push_out(head, b);
                        }
                        self.v[t as usize].remove_out(j);
                    }
                }
                pending = Some((h, t, bar));
                self.work += 1;
            }
            if let Some((x, head, b)) = pending {
                self.v[x as usize].push_out(head, b);
            }
            self.log.truncate(start as usize);
            self.v[s as usize].peb -= 1;
            self.v[z as usize].peb += 1;
        }
    }

    /// Forget the recorded moves after `mark` (they stay made).
    pub(super) fn keep_moves(&mut self, mark: usize) {
        if let Some(&(_, _, start)) = self.moves.get(mark) {
            self.log.truncate(start as usize);
        }
        self.moves.truncate(mark);
    }
}

/// The outcome of the contracted game.
pub(super) struct FastSolution {
    pub(super) accepted: Vec<bool>,
    /// Rigid components as sorted body lists (every body in exactly one, singletons included).
    pub(super) components: Vec<Vec<usize>>,
    /// For each vertex, its final super-body (bodies) or itself (nodes).
    pub(super) rep: Vec<u32>,
    /// The final state (which nodes are pinned to which super-body).
    pub(super) game: Fast,
}

pub(super) fn solve_fast(
    g: &Graph,
    l: u8,
    meter: &mut Meter,
) -> Result<FastSolution, BudgetExceeded> {
    let mut game = Fast::new(g.weight.clone(), g.n_bodies, l, g.bars.len());
    let mut accepted = vec![false; g.bars.len()];
    let order = 0..g.bars.len() as u32;
    meter.charge(g.bars.len() as u64 + g.weight.len() as u64)?;
    let mut next = 0;
    for &(u, v) in &g.bars {
        for z in [u, v] {
            if game.rank[z as usize] == u32::MAX {
                game.rank[z as usize] = next;
                next += 1;
            }
        }
    }
    for i in order {
        let i = i as usize;
        let (u, v) = g.bars[i];
        let (x, y) = (game.rep(u), game.rep(v));
        game.work += 1;
        if x == y {
            // A bar from a body to itself, or inside one rigid component: redundant.
        } else if !game.is_body(y) && game.bars_between(y, x) >= game.weight(y) as usize {
            // The node is pinned to the component: redundant.
        } else if let Some((t, h)) = game.fresh_end(x, y) {
            // Independent without a search: the pebble comes from the end with room.
            game.insert_bar(t, h, x, y);
            accepted[i] = true;
        } else {
            accepted[i] = game.place_by_search(x, y);
        }
        meter.charge(std::mem::take(&mut game.work))?;
    }
    let mut components = Vec::new();
    let mut rep = Vec::with_capacity(g.weight.len());
    for x in 0..g.weight.len() as u32 {
        rep.push(game.rep(x));
    }
    for (b, &r) in rep.iter().enumerate().take(g.n_bodies) {
        if r == b as u32 {
            let mut c: Vec<usize> = game.members[b].iter().map(|&x| x as usize).collect();
            c.sort_unstable();
            components.push(c);
        }
    }
    components.sort_unstable();
    meter.charge(std::mem::take(&mut game.work) + g.weight.len() as u64)?;
    Ok(FastSolution {
        accepted,
        components,
        rep,
        game,
    })
}

impl Fast {
    /// A bar between super-bodies or nodes `x` and `y` that needs a search: whether it is
    /// independent (then inserted, the tight set it closes contracted).
    ///
    /// One pebble for the bar itself, kept; the other B, only borrowed to show the bar
    /// independent (and then the pair not tight), go back where they came from. The kept one
    /// is the own pebble of an end, or else the one from the latest vertex in the insertion
    /// order (the local slack, not the pebbles of the old, settled part). One gather answers
    /// both questions: B + 2 pebbles on the pair before the bar are B + 1 after it (every set
    /// holding both ends gains exactly this bar), so the bar is independent and leaves the
    /// pair in no tight set; exactly B + 1 means independent and tight, and the failed search
    /// for the last one visited the minimal tight set, as a failed gather after the insertion
    /// would.
    fn place_by_search(&mut self, x: u32, y: u32) -> bool {
        let l = self.l;
        let (ox, oy) = (self.peb(x), self.peb(y));
        let wide = self.weight(x) + self.weight(y) > l + 1;
        self.recording = true;
        let ok = self.gather(x, y, l + 1);
        let loose = ok && wide && self.gather(x, y, l + 2);
        self.recording = false;
        if ok && wide && !loose {
            // Tight once the bar is in: keep the moves (the contraction reads the state),
            // pay with a pebble of the pair and contract the set the search found.
            self.keep_moves(0);
            let (t, h) = if self.peb(x) > 0 { (x, y) } else { (y, x) };
            self.v[t as usize].peb -= 1;
            self.link(t, h);
            self.contract(x, y);
            true
        } else if ok {
            let (t, h) = if ox > 0 {
                (x, y)
            } else if oy > 0 {
                (y, x)
            } else {
                self.latest_pebble(x, y)
            };
            self.undo_to(0);
            if loose {
                // Not tight after the bar (B + 2 pebbles were there): no check.
                self.v[t as usize].peb -= 1;
                self.link(t, h);
            } else {
                self.insert_bar(t, h, x, y);
            }
            true
        } else {
            self.undo_to(0);
            false
        }
    }

    /// The bar's (tail, head) when neither end had a pebble of its own: the pebble drawn
    /// from the latest vertex in the insertion order the gather moved one from, fetched
    /// again alone.
    fn latest_pebble(&mut self, x: u32, y: u32) -> (u32, u32) {
        let (z, s) = self
            .moves
            .iter()
            .map(|m| (m.0, m.1))
            .max_by_key(|&(z, _)| self.rank[z as usize])
            .unwrap_or((u32::MAX, x));
        let (p, q) = if s == x { (x, y) } else { (y, x) };
        self.undo_to(0);
        self.visited.clear();
        self.only = z;
        let got = if self.find_pebble(p, x, y) {
            Some((p, q))
        } else if self.find_pebble(q, x, y) {
            Some((q, p))
        } else {
            None
        };
        self.only = u32::MAX;
        match got {
            Some(p) => p,
            None => {
                let _ = self.find_pebble(x, x, y) || self.find_pebble(y, x, y);
                if self.peb(x) > 0 { (x, y) } else { (y, x) }
            }
        }
    }
}
