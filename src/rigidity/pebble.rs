//! Generic rigidity by counting: the pebble game on the body-bar multigraph.
//!
//! Every body is a vertex carrying B pebbles (B = 6 spatial, 3 planar or spherical). A binary
//! joint of grade k is B − k parallel bars between its two bodies (Tay's body-bar count). A
//! multiple joint of n ≥ 3 bodies becomes a *joint node* carrying B − k pebbles, with B − k bars
//! from each of its bodies to the node: the shared element (the common pin of a planar multiple
//! revolute, the common centre of a multiple spherical joint). Its count is exactly the hub
//! expansion's (n − 1 pairs of B − k bars), but, unlike that expansion, it knows that all the
//! bodies share one element, so two triangles pinned at a common point are two rigid
//! components, as in the bar-joint framework.
//!
//! A bar set is independent when every vertex set V′ spanning bars holds at most
//! w(V′) − B of them (w = pebbles: B per body, B − k per node); for bodies alone this is the
//! (B, B) count of Tay's theorem (generically rigid iff B edge-disjoint spanning trees). The
//! pebble game decides independence bar by bar; a rejected bar is redundant and the minimal
//! tight set the failed search visits is the support of its fundamental circuit. Rigid
//! components are maximal tight sets (w(V′) − B independent bars), found after the game with
//! Lee and Streinu's reverse search. Searches are local in practice; the worst case is
//! O(bars · (bodies + bars)).

use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::mechanism::Mechanism;
use serde::Serialize;

/// What the analysis counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PebbleOptions {
    /// Count each driven DOF as one more bar on its joint (default: inputs are ignored).
    pub with_inputs: bool,
}

/// An overconstrained region: a connected part of the redundancy (the union of fundamental
/// circuits that share bars, i.e. a connected component of the count matroid).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Region {
    /// Bodies touched by the region's bars, in model order.
    pub bodies: Vec<String>,
    /// Joints whose bars take part, in file order.
    pub joints: Vec<String>,
    /// Redundant bars (constraints) in the region.
    pub redundant: u64,
}

/// The limits of counting, stated in every report.
pub const LIMITS: &str = "Counting is exact for generic body-bar and body-hinge frameworks (and for \
planar bar-joint frameworks written as bars pinned at shared points). Special geometry (parallel \
or concurrent axes, spherical joints, S-S bars, planar or spherical loops written in space) can \
make it wrong in either direction; the geometric analysis is the remedy.";

/// Generic rigidity of a mechanism from its topology alone.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct PebbleReport {
    /// Mechanism name.
    pub name: String,
    /// Motion space name.
    pub space: &'static str,
    /// DOF of a free body (6 or 3).
    pub b: u32,
    /// Number of bodies, the frame included.
    pub bodies: usize,
    /// Number of bars of the body-bar graph: B − k per binary joint, n·(B − k) from the n
    /// bodies of a multiple joint to its node, plus one per driven DOF when counted.
    pub bars: u64,
    /// Whether driven inputs were counted as bars.
    pub with_inputs: bool,
    /// Chebyshev-Gruebler-Kutzbach count B·Nm − Σ pairs·(B − k) (inputs never subtracted).
    pub count: i64,
    /// Generic DOF with the frame fixed: `count + redundant` (minus the inputs when counted).
    pub dof: i64,
    /// Generic DOF of the free chain, the B motions of the whole included (`dof + B`).
    pub dof_free: i64,
    /// Redundant bars: constraints that generic geometry already implies.
    pub redundant: u64,
    /// Maximal rigid components (body ids): every component of at least two bodies, plus the
    /// frame's component even if the frame is alone in it. Bodies not listed are rigid
    /// components on their own. Sorted by first body in model order.
    pub rigid: Vec<Vec<String>>,
    /// Bodies rigidly attached to the frame (they cannot move).
    pub immobile: Vec<String>,
    /// Overconstrained regions, sorted by first body.
    pub overconstrained: Vec<Region>,
    /// True when a proper sub-chain of at least two bodies is rigid on its own (it could be
    /// replaced by one body; structural synthesis calls such a chain degenerate). When the
    /// whole chain is rigid this is checked by deleting each body in turn.
    pub degenerate: bool,
    /// What counting can and cannot tell.
    pub limits: &'static str,
}

/// The body-bar multigraph: vertices `0..n_bodies` are bodies, the rest joint nodes.
struct Graph {
    weight: Vec<u8>,
    n_bodies: usize,
    /// Bars as (vertex, vertex).
    bars: Vec<(u32, u32)>,
    /// Joint index of each bar.
    joint: Vec<u32>,
}

impl Graph {
    /// Build the multigraph, leaving out body `skip` (and every bar touching it).
    fn build(m: &Mechanism, opts: &PebbleOptions, skip: Option<usize>) -> Graph {
        let b = m.b();
        let n_bodies = m.bodies.len();
        let mut g = Graph {
            weight: vec![b as u8; n_bodies],
            n_bodies,
            bars: Vec::new(),
            joint: Vec::new(),
        };
        for (ji, j) in m.joints.iter().enumerate() {
            // The reader validates indices; skipping bad ones keeps this panic-free anyway.
            let bodies: Vec<usize> = j
                .bodies
                .iter()
                .copied()
                .filter(|&x| x < n_bodies && Some(x) != skip)
                .collect();
            if bodies.len() < 2 {
                continue;
            }
            let c = b.saturating_sub(j.grade());
            let add = |g: &mut Graph, x: usize, y: usize, times: u32| {
                for _ in 0..times {
                    g.bars.push((x as u32, y as u32));
                    g.joint.push(ji as u32);
                }
            };
            if c > 0 {
                if bodies.len() == 2 {
                    add(&mut g, bodies[0], bodies[1], c);
                } else {
                    let node = g.weight.len();
                    g.weight.push(c as u8);
                    for &x in &bodies {
                        add(&mut g, x, node, c);
                    }
                }
            }
            if opts.with_inputs && j.driven > 0 {
                // Driven DOF lock pairs hub→other in order, at most the grade on each.
                let mut left = j.driven;
                for &x in &bodies[1..] {
                    let here = left.min(j.grade());
                    add(&mut g, bodies[0], x, here);
                    left -= here;
                }
            }
        }
        g
    }
}

/// The pebble game state.
struct Game {
    l: u8,
    weight: Vec<u8>,
    peb: Vec<u8>,
    /// Out-edges (head, bar) of each vertex; at most its weight of them.
    out: Vec<Vec<(u32, u32)>>,
    /// In-edge tails, kept only for the component search.
    inn: Option<Vec<Vec<u32>>>,
    mark: Vec<u32>,
    epoch: u32,
    parent: Vec<(u32, u32)>,
    stack: Vec<u32>,
    visited: Vec<u32>,
    /// Work units not yet charged to the meter.
    work: u64,
}

impl Game {
    fn new(weight: Vec<u8>, l: u8) -> Game {
        let n = weight.len();
        Game {
            l,
            peb: weight.clone(),
            weight,
            out: vec![Vec::new(); n],
            inn: None,
            mark: vec![0; n],
            epoch: 0,
            parent: vec![(0, 0); n],
            stack: Vec::new(),
            visited: Vec::new(),
            work: 0,
        }
    }

    fn next_epoch(&mut self) -> u32 {
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.mark.iter_mut().for_each(|m| *m = 0);
            self.epoch = 1;
        }
        self.epoch
    }

    /// Move one free pebble reachable from `s` onto `s`, never taking one from `a` or `b`.
    /// Visited vertices are appended to `self.visited`.
    fn find_pebble(&mut self, s: u32, a: u32, b: u32) -> bool {
        let e = self.next_epoch();
        self.mark[s as usize] = e;
        self.stack.clear();
        self.stack.push(s);
        while let Some(x) = self.stack.pop() {
            for i in 0..self.out[x as usize].len() {
                let (y, bar) = self.out[x as usize][i];
                self.work += 1;
                if self.mark[y as usize] == e {
                    continue;
                }
                self.mark[y as usize] = e;
                self.parent[y as usize] = (x, bar);
                self.visited.push(y);
                if y != a && y != b && self.peb[y as usize] > 0 {
                    self.reverse(s, y);
                    return true;
                }
                self.stack.push(y);
            }
        }
        false
    }

    /// Reverse the search path from `s` to `y`, moving a pebble from `y` to `s`.
    fn reverse(&mut self, s: u32, y: u32) {
        self.peb[y as usize] -= 1;
        let mut x = y;
        while x != s {
            let (p, bar) = self.parent[x as usize];
            let out = &mut self.out[p as usize];
            let pos = out
                .iter()
                .position(|&(_, b)| b == bar)
                .expect("the search reached x through this out-edge of p");
            out.swap_remove(pos);
            self.out[x as usize].push((p, bar));
            if let Some(inn) = &mut self.inn {
                let list = &mut inn[x as usize];
                let pos = list
                    .iter()
                    .position(|&t| t == p)
                    .expect("in-lists mirror out-lists");
                list.swap_remove(pos);
                inn[p as usize].push(x);
            }
            x = p;
        }
        self.peb[s as usize] += 1;
    }

    /// Gather `target` free pebbles on {u, v}. On failure `self.visited` holds the rest of
    /// the minimal tight set containing u and v.
    fn gather(&mut self, u: u32, v: u32, target: u8) -> bool {
        while self.peb[u as usize] + self.peb[v as usize] < target {
            self.visited.clear();
            if self.peb[u as usize] < self.weight[u as usize] && self.find_pebble(u, u, v) {
                continue;
            }
            if self.peb[v as usize] < self.weight[v as usize] && self.find_pebble(v, u, v) {
                continue;
            }
            return false;
        }
        true
    }

    fn insert(&mut self, u: u32, v: u32, bar: u32) {
        let (t, h) = if self.peb[u as usize] > 0 {
            (u, v)
        } else {
            (v, u)
        };
        self.peb[t as usize] -= 1;
        self.out[t as usize].push((h, bar));
        if let Some(inn) = &mut self.inn {
            inn[h as usize].push(t);
        }
    }
}

/// The component pebble game with contraction (issue 16 item 3): the game of [`Game`], but
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
///   slack of the group being built, instead of wandering away with every search (session
///   5's game: 1.76 growth exponent on Assur linkages).
///
/// The answers (which bars are independent, the rigid components) are those of the plain game;
/// `tests/pebble_props.rs` compares them on random graphs.
struct Fast {
    l: u8,
    n_bodies: usize,
    /// The vertices, one cache line each: pebbles, out-bars and the search's marks.
    v: Vec<Vtx>,
    /// Every bar at each vertex, in and out (bar ids into `ends`). A flip leaves these lists
    /// as they are; only inserting a bar and contracting a component change them.
    inc: Vec<Vec<u32>>,
    /// The two ends of each bar, in no particular order (the direction is in the out-bars).
    ends: Vec<[u32; 2]>,
    /// Position of each bar in the `inc` list of `ends[bar][0]` and of `ends[bar][1]`.
    pos: Vec<[u32; 2]>,
    /// Union-find over bodies: the root is the super-body's id.
    parent: Vec<u32>,
    /// Bodies of each super-body (at its root).
    members: Vec<Vec<u32>>,
    epoch: u32,
    stack: Vec<u32>,
    visited: Vec<u32>,
    /// Reverse search: in the growing tight set (`qmark == qepoch`), known to reach a free
    /// pebble (`fmark == qepoch`).
    qmark: Vec<u32>,
    fmark: Vec<u32>,
    qepoch: u32,
    /// When not u32::MAX, searches take a pebble from this vertex only.
    only: u32,
    /// Position of each vertex in the insertion order (first bar that names it): a closing
    /// bar keeps the borrowed pebble of the latest vertex.
    rank: Vec<u32>,
    /// Pebble moves kept for undoing, while `recording`: (source, target, start in `log`), and
    /// the bars each move turned round, as (tail, head, bar) after the turn.
    moves: Vec<(u32, u32, u32)>,
    log: Vec<[u32; 3]>,
    recording: bool,
    /// Whether some contraction made a rigid set of at least two bodies but not all of them
    /// (it stays rigid as bars are added: a proper rigid sub-chain).
    proper: bool,
    /// Work units not yet charged to the meter.
    work: u64,
}

/// Most out-bars of a vertex: pebbles + out-bars = weight ≤ B ≤ 6 at every moment.
const MAX_OUT: usize = 6;

/// One vertex of the contracted game in one cache line: a search step reads the vertex's
/// out-bars (heads inline) and each head's mark and pebbles, one line each; turning a path
/// round touches the same lines. Session 7 kept these in eight arrays and two heap lists per
/// vertex (about ten cache misses per step at 10^6 vertices).
#[derive(Clone, Copy, Default)]
#[repr(C, align(64))]
struct Vtx {
    /// Heads and bar ids of the out-bars, `nout` of them.
    head: [u32; MAX_OUT],
    bar: [u32; MAX_OUT],
    /// Search epoch that reached the vertex.
    mark: u32,
    /// The vertex the search came from, and the slot of its out-bar to this one.
    from: u32,
    peb: u8,
    weight: u8,
    nout: u8,
    slot: u8,
}

impl Vtx {
    fn push_out(&mut self, h: u32, bar: u32) {
        let n = self.nout as usize;
        self.head[n] = h;
        self.bar[n] = bar;
        self.nout += 1;
    }

    /// Remove the out-bar in `slot`; the last one takes its place (as `Vec::swap_remove`).
    fn remove_out(&mut self, slot: usize) -> u32 {
        let last = self.nout as usize - 1;
        let bar = self.bar[slot];
        self.head[slot] = self.head[last];
        self.bar[slot] = self.bar[last];
        self.nout -= 1;
        bar
    }

    fn outs(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        let n = self.nout as usize;
        self.head[..n]
            .iter()
            .copied()
            .zip(self.bar[..n].iter().copied())
    }
}

impl Fast {
    fn new(weight: Vec<u8>, n_bodies: usize, l: u8, bars: usize) -> Fast {
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

    fn peb(&self, x: u32) -> u8 {
        self.v[x as usize].peb
    }

    fn weight(&self, x: u32) -> u8 {
        self.v[x as usize].weight
    }

    /// Whether a tight set of two or more vertices may hold both `x` and `y`, by degrees alone.
    /// In a tight set T every vertex z has at least its weight of bars inside T (removing
    /// z leaves at most w(T − z) − B bars if T − z spans one, and if not, z carries all
    /// w(T) − B ≥ w(z) of them), and a body with fewer than B bars in T has only nodes beside
    /// it (else the same count gives B).
    fn may_be_tight(&self, x: u32, y: u32) -> bool {
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
    fn fresh_end(&self, x: u32, y: u32) -> Option<(u32, u32)> {
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
    fn other(&self, bar: u32, x: u32) -> u32 {
        let [a, b] = self.ends[bar as usize];
        if a == x { b } else { a }
    }

    /// Whether body `z`, with at most B bars, has two different (super-)bodies beside it. Then
    /// no tight set holds z with another vertex: it would hold all of z's bars (a vertex
    /// carries at least its weight of bars inside a tight set), so the rest would be a
    /// tight set with two super-bodies before this bar (the game contracts every such set as
    /// it forms), or a bar-free set of weight B.
    fn beside_two_bodies(&self, z: u32) -> bool {
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
    fn degree(&self, x: u32) -> usize {
        self.inc[x as usize].len()
    }

    fn is_body(&self, x: u32) -> bool {
        (x as usize) < self.n_bodies
    }

    /// The current vertex of original vertex `x`: its super-body, or the node itself.
    fn rep(&mut self, mut x: u32) -> u32 {
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

    fn next_epoch(&mut self) -> u32 {
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.v.iter_mut().for_each(|r| r.mark = 0);
            self.epoch = 1;
        }
        self.epoch
    }

    /// Add a bar oriented `t` → `h` (the caller accounts for the pebble).
    fn link(&mut self, t: u32, h: u32) -> u32 {
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
    fn unlink(&mut self, bar: u32) {
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
    fn flip_slot(&mut self, p: u32, slot: usize, z: u32) -> u32 {
        let bar = self.v[p as usize].remove_out(slot);
        self.v[z as usize].push_out(p, bar);
        bar
    }

    /// Position of `bar` among the out-bars of `t`.
    fn slot_of(&self, t: u32, bar: u32) -> usize {
        let r = &self.v[t as usize];
        r.bar[..r.nout as usize]
            .iter()
            .position(|&b| b == bar)
            .unwrap_or(0)
    }

    /// Bars between node `n` and vertex `s`, in either direction (both out-lists are short).
    fn bars_between(&self, n: u32, s: u32) -> usize {
        let a = self.v[n as usize].outs().filter(|&(h, _)| h == s).count();
        let b = self.v[s as usize].outs().filter(|&(h, _)| h == n).count();
        a + b
    }

    /// Move one free pebble reachable from `s` onto `s`, never taking one from `a` or `b`.
    fn find_pebble(&mut self, s: u32, a: u32, b: u32) -> bool {
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
    fn insert_bar(&mut self, t: u32, h: u32, x: u32, y: u32) {
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
    fn gather(&mut self, u: u32, v: u32, target: u8) -> bool {
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
    fn undo_to(&mut self, mark: usize) {
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
    fn keep_moves(&mut self, mark: usize) {
        if let Some(&(_, _, start)) = self.moves.get(mark) {
            self.log.truncate(start as usize);
        }
        self.moves.truncate(mark);
    }

    /// Whether node `n` is pinned to super-body `k` (B − k bars between them).
    fn pinned_to(&self, n: u32, k: u32) -> bool {
        !self.is_body(n) && self.bars_between(n, k) >= self.weight(n) as usize
    }

    /// Whether node `n` has all its pebbles on bars to one super-body of the set.
    fn pinned_in_set(&self, n: u32, q_e: u32) -> bool {
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
    fn scan_in(&mut self, x: u32, q_e: u32, q: &mut Vec<u32>, seen: &mut Vec<u32>) {
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
    fn in_degree(&self, x: u32) -> usize {
        self.degree(x) - self.v[x as usize].nout as usize
    }

    /// After a failed gather on {u, v}: grow the minimal tight set to the maximal one and
    /// contract it.
    fn contract(&mut self, u: u32, v: u32) {
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
        // A body with fewer than B bars is in no tight set with another body (removing it
        // would leave more bars than the count allows, or it alone would carry all w(T) - B
        // bars, so the rest is nodes), so the maximal tight set is the closed set the search
        // found: the body and nodes pinned to it (the others were pinned to it before). No
        // reverse search, which would scan every bar into a shared joint's node.
        let lone = [u, v]
            .into_iter()
            .find(|&x| self.is_body(x) && self.degree(x) < self.l as usize);
        let mut qi = 0;
        if lone.is_none() {
            loop {
                while qi < q.len() {
                    let x = q[qi];
                    qi += 1;
                    if self.is_body(x) {
                        match big {
                            None => big = Some(x),
                            Some(b) if !fixed && self.in_degree(x) > self.in_degree(b) => {
                                big = Some(x);
                                self.scan_in(b, q_e, &mut q, &mut seen);
                            }
                            Some(b) if b == x => {}
                            Some(_) => self.scan_in(x, q_e, &mut q, &mut seen),
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
                        self.scan_in(x, q_e, &mut q, &mut seen);
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
                        self.scan_in(x, q_e, &mut q, &mut seen);
                    }
                }
            }
        }
        let keep = lone.or(big).unwrap_or(u);
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
}

/// The outcome of the contracted game.
struct FastSolution {
    accepted: Vec<bool>,
    /// Rigid components as sorted body lists (every body in exactly one, singletons included).
    components: Vec<Vec<usize>>,
    /// For each vertex, its final super-body (bodies) or itself (nodes).
    rep: Vec<u32>,
    /// The final state (which nodes are pinned to which super-body).
    game: Fast,
}

fn solve_fast(g: &Graph, l: u8, meter: &mut Meter) -> Result<FastSolution, BudgetExceeded> {
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
            // One pebble for the bar itself, kept; the other B, only borrowed to show the bar
            // independent (and then the pair not tight), go back where they came from. The
            // kept one is the own pebble of an end, or else the one from the latest vertex in
            // the insertion order (the local slack, not the pebbles of the old, settled part).
            // One gather answers both questions: B + 2 pebbles on the pair before the bar are
            // B + 1 after it (every set holding both ends gains exactly this bar), so the bar
            // is independent and leaves the pair in no tight set; exactly B + 1 means
            // independent and tight, and the failed search for the last one visited the
            // minimal tight set, as a failed gather after the insertion would.
            let (ox, oy) = (game.peb(x), game.peb(y));
            let wide = game.weight(x) + game.weight(y) > l + 1;
            game.recording = true;
            let ok = game.gather(x, y, l + 1);
            let loose = ok && wide && game.gather(x, y, l + 2);
            game.recording = false;
            if ok && wide && !loose {
                // Tight once the bar is in: keep the moves (the contraction reads the state),
                // pay with a pebble of the pair and contract the set the search found.
                game.keep_moves(0);
                let (t, h) = if game.peb(x) > 0 { (x, y) } else { (y, x) };
                game.v[t as usize].peb -= 1;
                game.link(t, h);
                game.contract(x, y);
                accepted[i] = true;
            } else if ok {
                let (t, h) = if ox > 0 {
                    (x, y)
                } else if oy > 0 {
                    (y, x)
                } else {
                    let (z, s) = game
                        .moves
                        .iter()
                        .map(|m| (m.0, m.1))
                        .max_by_key(|&(z, _)| game.rank[z as usize])
                        .unwrap_or((u32::MAX, x));
                    let (p, q) = if s == x { (x, y) } else { (y, x) };
                    game.undo_to(0);
                    game.visited.clear();
                    game.only = z;
                    let got = if game.find_pebble(p, x, y) {
                        Some((p, q))
                    } else if game.find_pebble(q, x, y) {
                        Some((q, p))
                    } else {
                        None
                    };
                    game.only = u32::MAX;
                    match got {
                        Some(p) => p,
                        None => {
                            let _ = game.find_pebble(x, x, y) || game.find_pebble(y, x, y);
                            if game.peb(x) > 0 { (x, y) } else { (y, x) }
                        }
                    }
                };
                game.undo_to(0);
                if loose {
                    // Not tight after the bar (B + 2 pebbles were there): no check.
                    game.v[t as usize].peb -= 1;
                    game.link(t, h);
                } else {
                    game.insert_bar(t, h, x, y);
                }
                accepted[i] = true;
            } else {
                game.undo_to(0);
            }
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

/// Union-find with path halving; the smaller root wins (order independence).
struct Dsu(Vec<u32>);

impl Dsu {
    fn find(&mut self, mut i: u32) -> u32 {
        while self.0[i as usize] != i {
            let p = self.0[i as usize];
            self.0[i as usize] = self.0[p as usize];
            i = p;
        }
        i
    }
    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.0[hi as usize] = lo;
        }
    }
}

/// The outcome of the game on one graph.
struct Solution {
    accepted: Vec<bool>,
    /// Bar union-find joining each redundant bar with its fundamental circuit.
    circuits: Option<Dsu>,
    /// Rigid components as sorted body lists (every maximal tight set with a body).
    components: Vec<Vec<usize>>,
}

fn solve(g: &Graph, l: u8, regions: bool, meter: &mut Meter) -> Result<Solution, BudgetExceeded> {
    let mut game = Game::new(g.weight.clone(), l);
    let mut accepted = vec![false; g.bars.len()];
    let mut circuits = regions.then(|| Dsu((0..g.bars.len() as u32).collect()));
    let mut seen = vec![0u32; g.weight.len()];
    let mut seen_epoch = 0u32;
    for (i, &(u, v)) in g.bars.iter().enumerate() {
        if u == v {
            continue; // A bar from a body to itself constrains nothing: redundant.
        }
        if game.gather(u, v, l + 1) {
            game.insert(u, v, i as u32);
            accepted[i] = true;
        } else if let Some(dsu) = &mut circuits {
            // The circuit is this bar plus every accepted bar inside the tight set, which is
            // closed: its vertices' out-edges stay inside it.
            seen_epoch += 1;
            let mut tight: Vec<u32> = vec![u, v];
            tight.extend(game.visited.iter().copied());
            for x in tight {
                if seen[x as usize] == seen_epoch {
                    continue;
                }
                seen[x as usize] = seen_epoch;
                for &(_, bar) in &game.out[x as usize] {
                    dsu.union(i as u32, bar);
                }
                game.work += game.out[x as usize].len() as u64;
            }
        }
        meter.charge(std::mem::take(&mut game.work))?;
    }
    let components = components(g, &mut game, &accepted);
    meter.charge(std::mem::take(&mut game.work))?;
    Ok(Solution {
        accepted,
        circuits,
        components,
    })
}

/// Maximal tight sets containing a body, from the final pebble state (Lee and Streinu's
/// component detection, run once per accepted bar not yet inside a found component).
fn components(g: &Graph, game: &mut Game, accepted: &[bool]) -> Vec<Vec<usize>> {
    let n = g.weight.len();
    let mut inn = vec![Vec::new(); n];
    for (t, outs) in game.out.iter().enumerate() {
        for &(h, _) in outs {
            inn[h as usize].push(t as u32);
        }
    }
    game.inn = Some(inn);
    let nb = g.n_bodies;
    let mut comp_of: Vec<Option<usize>> = vec![None; nb];
    let mut node_comps: Vec<Vec<usize>> = vec![Vec::new(); n - nb];
    let mut comps: Vec<Vec<usize>> = Vec::new();
    // Per component search: 1 = in Q, 2 = known to reach a free pebble.
    let mut state = vec![0u8; n];
    let mut touched: Vec<u32> = Vec::new();
    let l = game.l;
    let inside = |x: u32, c: usize, comp_of: &[Option<usize>], node_comps: &[Vec<usize>]| {
        let x = x as usize;
        if x < nb {
            comp_of[x] == Some(c)
        } else {
            node_comps[x - nb].contains(&c)
        }
    };
    let mut last: Option<(u32, u32)> = None;
    for (i, &(u, v)) in g.bars.iter().enumerate() {
        // A parallel bar right after its twin gives the same answer.
        if !accepted[i] || last.replace((u, v)) == Some((u, v)) {
            continue;
        }
        let covered = [u, v].iter().any(|&x| {
            (x as usize) < nb
                && comp_of[x as usize].is_some_and(|c| {
                    inside(u, c, &comp_of, &node_comps) && inside(v, c, &comp_of, &node_comps)
                })
        });
        if covered {
            continue;
        }
        if game.gather(u, v, l + 1) {
            continue; // Room for one more bar: no tight set holds both ends.
        }
        // The failed search visited the minimal tight set containing u and v.
        let e = game.next_epoch();
        let mut reach = vec![u, v];
        game.mark[u as usize] = e;
        game.mark[v as usize] = e;
        for k in 0..game.visited.len() {
            let x = game.visited[k];
            if game.mark[x as usize] != e {
                game.mark[x as usize] = e;
                reach.push(x);
            }
        }
        for &x in &reach {
            state[x as usize] = 1;
            touched.push(x);
        }
        let mut q = reach.clone();
        let mut qi = 0;
        let inn_lists = game.inn.take().expect("set above");
        while qi < q.len() {
            let x = q[qi];
            qi += 1;
            for &p in &inn_lists[x as usize] {
                game.work += 1;
                if state[p as usize] != 0 {
                    continue;
                }
                // Does p reach a free pebble (outside u, v) without entering Q?
                let e = game.next_epoch();
                game.mark[p as usize] = e;
                let mut found = game.peb[p as usize] > 0;
                let mut seen = vec![p];
                let mut si = 0;
                while si < seen.len() && !found {
                    let y = seen[si];
                    si += 1;
                    for &(z, _) in &game.out[y as usize] {
                        game.work += 1;
                        let zs = state[z as usize];
                        if zs == 1 || game.mark[z as usize] == e {
                            continue;
                        }
                        if zs == 2 || game.peb[z as usize] > 0 {
                            found = true;
                            break;
                        }
                        game.mark[z as usize] = e;
                        seen.push(z);
                    }
                }
                if found {
                    state[p as usize] = 2;
                    touched.push(p);
                } else {
                    for &y in &seen {
                        state[y as usize] = 1;
                        touched.push(y);
                        q.push(y);
                    }
                }
            }
        }
        game.inn = Some(inn_lists);
        let c = comps.len();
        let mut bodies: Vec<usize> = Vec::new();
        for &x in &q {
            let x = x as usize;
            if x < nb {
                comp_of[x] = Some(c);
                bodies.push(x);
            } else {
                node_comps[x - nb].push(c);
            }
        }
        bodies.sort_unstable();
        comps.push(bodies);
        for &x in &touched {
            state[x as usize] = 0;
        }
        touched.clear();
    }
    comps
}

/// Analyse the generic rigidity of `m` (no work limit).
pub fn analyze(m: &Mechanism, opts: &PebbleOptions) -> PebbleReport {
    // An unlimited meter never runs out; the reference is only a panic-free fallback.
    analyze_within(m, opts, &Budget::UNLIMITED).unwrap_or_else(|_| analyze_reference(m, opts))
}

/// Analyse the generic rigidity of `m` within `budget`: the component pebble game, whose
/// loops charge a work meter (about one unit per bar looked at); past
/// [`Budget::max_work`], the typed error.
pub fn analyze_within(
    m: &Mechanism,
    opts: &PebbleOptions,
    budget: &Budget,
) -> Result<PebbleReport, BudgetExceeded> {
    let mut meter = budget.meter("the pebble game");
    analyze_metered(m, opts, &mut meter)
}

/// The analysis and the work units it charged (no limit): for the scale tests and the
/// benchmarks, which compare work (deterministic) rather than time.
#[doc(hidden)]
pub fn analyze_counting_work(m: &Mechanism, opts: &PebbleOptions) -> (PebbleReport, u64) {
    let mut meter = Budget::UNLIMITED.meter("the pebble game");
    match analyze_metered(m, opts, &mut meter) {
        Ok(r) => (r, meter.used()),
        Err(_) => (analyze_reference(m, opts), meter.used()),
    }
}

fn analyze_metered(
    m: &Mechanism,
    opts: &PebbleOptions,
    meter: &mut Meter,
) -> Result<PebbleReport, BudgetExceeded> {
    let l = m.b() as u8;
    let g = Graph::build(m, opts, None);
    meter.charge(g.bars.len() as u64 + g.weight.len() as u64)?;
    let sol = solve_fast(&g, l, meter)?;
    let overconstrained = if sol.accepted.iter().all(|&a| a) {
        Vec::new()
    } else {
        regions_of_overconstrained(m, &g, &sol, l, meter)?
    };
    let n = m.bodies.len();
    let degenerate = if sol.components.iter().any(|c| c.len() >= 2 && c.len() < n) {
        true
    } else if n > 2 && sol.components.iter().any(|c| c.len() == n) {
        // The whole chain is rigid: a proper rigid sub-chain avoids some body. One that the
        // game contracted on its way (a tight set stays tight as bars are added) settles it;
        // otherwise the game runs again without each body in turn.
        let mut found = sol.game.proper;
        for w in 0..n {
            if found {
                break;
            }
            let g = Graph::build(m, opts, Some(w));
            meter.charge(g.bars.len() as u64 + g.weight.len() as u64)?;
            if solve_fast(&g, l, meter)?
                .components
                .iter()
                .any(|c| c.iter().filter(|&&x| x != w).count() >= 2)
            {
                found = true;
                break;
            }
        }
        found
    } else {
        false
    };
    Ok(report(
        m,
        opts,
        &g,
        &sol.accepted,
        &sol.components,
        overconstrained,
        degenerate,
    ))
}

/// The same analysis by the plain pebble game (no component bookkeeping, components found
/// after the game, a search per bar): quadratic on large rigid frameworks. Kept as the test
/// oracle of [`analyze`] (`tests/pebble_props.rs`).
#[doc(hidden)]
pub fn analyze_reference(m: &Mechanism, opts: &PebbleOptions) -> PebbleReport {
    let l = m.b() as u8;
    let g = Graph::build(m, opts, None);
    let mut meter = Budget::UNLIMITED.meter("the pebble game");
    let Ok(mut sol) = solve(&g, l, true, &mut meter) else {
        unreachable!("an unlimited meter never runs out")
    };
    let overconstrained = match &mut sol.circuits {
        Some(dsu) => regions(m, &g, &sol.accepted, dsu),
        None => Vec::new(),
    };
    let n = m.bodies.len();
    let degenerate = if sol.components.iter().any(|c| c.len() >= 2 && c.len() < n) {
        true
    } else if n > 2 && sol.components.iter().any(|c| c.len() == n) {
        (0..n).any(|w| {
            let g = Graph::build(m, opts, Some(w));
            solve(&g, l, false, &mut meter).is_ok_and(|s| {
                s.components
                    .iter()
                    .any(|c| c.iter().filter(|&&x| x != w).count() >= 2)
            })
        })
    } else {
        false
    };
    report(
        m,
        opts,
        &g,
        &sol.accepted,
        &sol.components,
        overconstrained,
        degenerate,
    )
}

/// The overconstrained regions: the plain game (which finds every fundamental circuit) run
/// again on the bars of the rigid components that hold a redundant bar, only. Every circuit
/// lies inside one rigid component (its support is a tight set), so this gives the regions of
/// the whole game.
fn regions_of_overconstrained(
    m: &Mechanism,
    g: &Graph,
    sol: &FastSolution,
    l: u8,
    meter: &mut Meter,
) -> Result<Vec<Region>, BudgetExceeded> {
    let nb = g.n_bodies;
    let mut heavy = vec![false; nb];
    for (i, &(u, _)) in g.bars.iter().enumerate() {
        if !sol.accepted[i] {
            heavy[sol.rep[u as usize] as usize] = true;
        }
    }
    let mut sub = Graph {
        weight: g.weight.clone(),
        n_bodies: nb,
        bars: Vec::new(),
        joint: Vec::new(),
    };
    for (i, &(u, v)) in g.bars.iter().enumerate() {
        let s = sol.rep[u as usize];
        if !heavy[s as usize] {
            continue;
        }
        let inside = if (v as usize) < nb {
            sol.rep[v as usize] == s
        } else {
            sol.game.bars_between(v, s) >= g.weight[v as usize] as usize
        };
        if inside {
            sub.bars.push((u, v));
            sub.joint.push(g.joint[i]);
        }
    }
    meter.charge(g.bars.len() as u64)?;
    let mut sub_sol = solve(&sub, l, true, meter)?;
    Ok(match &mut sub_sol.circuits {
        Some(dsu) => regions(m, &sub, &sub_sol.accepted, dsu),
        None => Vec::new(),
    })
}

/// Group the bars by circuit union-find root; the groups with a redundant bar are regions.
fn regions(m: &Mechanism, g: &Graph, accepted: &[bool], dsu: &mut Dsu) -> Vec<Region> {
    let id = |i: usize| m.body_id(i).to_string();
    let mut groups: std::collections::BTreeMap<u32, (Vec<usize>, Vec<usize>, u64)> =
        std::collections::BTreeMap::new();
    for (i, &(u, v)) in g.bars.iter().enumerate() {
        let root = dsu.find(i as u32);
        let entry = groups.entry(root).or_default();
        for x in [u as usize, v as usize] {
            if x < g.n_bodies {
                entry.0.push(x);
            }
        }
        entry.1.push(g.joint[i] as usize);
        if !accepted[i] {
            entry.2 += 1;
        }
    }
    let mut regions: Vec<(Vec<usize>, Vec<usize>, u64)> = groups
        .into_values()
        .filter(|r| r.2 > 0)
        .map(|(mut bs, mut js, r)| {
            bs.sort_unstable();
            bs.dedup();
            js.sort_unstable();
            js.dedup();
            (bs, js, r)
        })
        .collect();
    regions.sort();
    regions
        .into_iter()
        .map(|(bs, js, r)| Region {
            bodies: bs.into_iter().map(id).collect(),
            joints: js.into_iter().map(|j| m.joints[j].id.clone()).collect(),
            redundant: r,
        })
        .collect()
}

/// Assemble the report from the game's outcome.
fn report(
    m: &Mechanism,
    opts: &PebbleOptions,
    g: &Graph,
    accepted: &[bool],
    components: &[Vec<usize>],
    overconstrained: Vec<Region>,
    degenerate: bool,
) -> PebbleReport {
    let b = m.b();
    let rank = accepted.iter().filter(|&&a| a).count() as i64;
    let redundant = g.bars.len() as u64 - rank as u64;
    let total_weight: i64 = g.weight.iter().map(|&w| w as i64).sum();
    let dof_free = total_weight - rank;
    let constraints: i64 = m
        .joints
        .iter()
        .map(|j| j.pairs() as i64 * b.saturating_sub(j.grade()) as i64)
        .sum();
    let count = b as i64 * m.movable() as i64 - constraints;
    let id = |i: usize| m.body_id(i).to_string();

    let frame = m.frame;
    let mut comps: Vec<Vec<usize>> = components
        .iter()
        .filter(|c| c.len() >= 2 || c.contains(&frame))
        .cloned()
        .collect();
    if frame < m.bodies.len() && !comps.iter().any(|c| c.contains(&frame)) {
        comps.push(vec![frame]);
    }
    comps.sort();
    let immobile = comps
        .iter()
        .find(|c| c.contains(&frame))
        .map(|c| c.iter().filter(|&&x| x != frame).map(|&x| id(x)).collect())
        .unwrap_or_default();

    PebbleReport {
        name: m.name.clone(),
        space: m.space.name(),
        b,
        bodies: m.bodies.len(),
        bars: g.bars.len() as u64,
        with_inputs: opts.with_inputs,
        count,
        dof: dof_free - b as i64,
        dof_free,
        redundant,
        rigid: comps
            .into_iter()
            .map(|c| c.into_iter().map(id).collect())
            .collect(),
        immobile,
        overconstrained,
        degenerate,
        limits: LIMITS,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::joint::JointType::{self, *};
    use crate::mechanism::{BodyId, JointSpec, Space};

    fn j(kind: JointType, bodies: &[i64]) -> JointSpec {
        let mut s = JointSpec::new(kind, bodies[0], bodies[1], 0);
        s.bodies = bodies.iter().map(|&b| BodyId::Int(b)).collect();
        s
    }

    fn run(space: Space, joints: Vec<JointSpec>) -> PebbleReport {
        let m = Mechanism::from_parts("t", space, BodyId::Int(1), vec![], joints);
        analyze(&m, &PebbleOptions::default())
    }

    fn ids(r: &PebbleReport) -> Vec<Vec<&str>> {
        r.rigid
            .iter()
            .map(|c| c.iter().map(String::as_str).collect())
            .collect()
    }

    /// Planar four-bar 1-2-3-4 with revolutes at the points A (1,2), B (2,3), C (3,4),
    /// D (4,1); `diagonals` adds bar 5 (A-C) and then bar 6 (B-D), pinned at those points.
    fn four_bar(diagonals: usize) -> Vec<JointSpec> {
        let mut a = vec![1, 2];
        let mut b = vec![2, 3];
        let mut c = vec![3, 4];
        let mut d = vec![4, 1];
        if diagonals >= 1 {
            a.push(5);
            c.push(5);
        }
        if diagonals >= 2 {
            b.push(6);
            d.push(6);
        }
        [a, b, c, d].iter().map(|p| j(R, p)).collect()
    }

    #[test]
    fn triangle_is_rigid() {
        let r = run(
            Space::Planar,
            vec![j(R, &[1, 2]), j(R, &[2, 3]), j(R, &[3, 1])],
        );
        assert_eq!((r.count, r.dof, r.dof_free, r.redundant), (0, 0, 3, 0));
        assert_eq!(ids(&r), [["1", "2", "3"]]);
        assert_eq!(r.immobile, ["2", "3"]);
        assert!(r.overconstrained.is_empty());
        assert!(!r.degenerate, "no proper sub-chain of a triangle is rigid");
    }

    #[test]
    fn four_bar_has_one_dof() {
        let r = run(Space::Planar, four_bar(0));
        assert_eq!((r.count, r.dof, r.redundant), (1, 1, 0));
        assert_eq!(ids(&r), [["1"]]);
        assert!(!r.degenerate);
    }

    #[test]
    fn one_diagonal_makes_it_rigid() {
        let r = run(Space::Planar, four_bar(1));
        assert_eq!((r.count, r.dof, r.redundant), (0, 0, 0));
        assert_eq!(ids(&r), [["1", "2", "3", "4", "5"]]);
        // The triangle 1-4-5 (points A, D, C) is a proper rigid sub-chain.
        assert!(r.degenerate);
    }

    #[test]
    fn both_diagonals_are_one_redundant_bar() {
        let r = run(Space::Planar, four_bar(2));
        assert_eq!((r.count, r.dof, r.redundant), (-1, 0, 1));
        assert_eq!(ids(&r), [["1", "2", "3", "4", "5", "6"]]);
        assert_eq!(r.overconstrained.len(), 1);
        let region = &r.overconstrained[0];
        assert_eq!(region.redundant, 1);
        assert_eq!(region.bodies.len(), 6);
        assert_eq!(region.joints, ["1-2-5", "2-3-6", "3-4-5", "4-1-6"]);
        assert!(r.degenerate);
    }

    #[test]
    fn two_triangles_sharing_a_vertex() {
        // Bars 1-3 and 4-6 form two triangles pinned together at one point P.
        let r = run(
            Space::Planar,
            vec![
                j(R, &[1, 2, 4, 5]),
                j(R, &[2, 3]),
                j(R, &[3, 1]),
                j(R, &[5, 6]),
                j(R, &[6, 4]),
            ],
        );
        assert_eq!(ids(&r), [vec!["1", "2", "3"], vec!["4", "5", "6"]]);
        assert_eq!((r.dof, r.redundant), (1, 0));
        assert!(r.degenerate);
    }

    #[test]
    fn stacked_four_bars() {
        // Lower four-bar on points p1..p4 with both diagonals (bars 1..6, frame 1 = p1p2),
        // upper four-bar p3-p6-p5-p4 on the lower top bar 3 (bars 7, 8, 9).
        let r = run(
            Space::Planar,
            vec![
                j(R, &[1, 4, 5]),
                j(R, &[1, 2, 6]),
                j(R, &[2, 3, 5, 7]),
                j(R, &[3, 4, 6, 9]),
                j(R, &[8, 9]),
                j(R, &[7, 8]),
            ],
        );
        assert_eq!((r.dof, r.redundant), (1, 1));
        assert_eq!(ids(&r), [["1", "2", "3", "4", "5", "6"]]);
        assert_eq!(r.overconstrained.len(), 1);
        assert_eq!(r.overconstrained[0].bodies, ["1", "2", "3", "4", "5", "6"]);
        assert_eq!(r.overconstrained[0].redundant, 1);
        assert!(r.degenerate);
    }

    #[test]
    fn spatial_rssr_counts_the_bar_spin() {
        // Body-bar counting sees the spin of the S-S bar as a DOF: generic DOF 2.
        let r = run(
            Space::Spatial,
            vec![j(R, &[1, 2]), j(S, &[2, 3]), j(S, &[3, 4]), j(R, &[4, 1])],
        );
        assert_eq!((r.count, r.dof, r.redundant), (2, 2, 0));
        assert_eq!(ids(&r), [["1"]]);
    }

    #[test]
    fn two_spherical_joints_look_rigid_to_counting() {
        // Two S joints between the same bodies: 6 bars, a rigid pair by counting, although
        // the bodies can turn about the line through the centres (a limit of counting).
        let r = run(Space::Spatial, vec![j(S, &[1, 2]), j(S, &[1, 2])]);
        assert_eq!((r.dof, r.redundant), (0, 0));
        assert_eq!(ids(&r), [["1", "2"]]);
    }

    #[test]
    fn tetrahedron_of_ss_bars() {
        // Six bars (bodies 1..6) on four points, three bars at each point: spins counted.
        let r = run(
            Space::Spatial,
            vec![
                j(S, &[1, 2, 3]),
                j(S, &[1, 4, 5]),
                j(S, &[2, 4, 6]),
                j(S, &[3, 5, 6]),
            ],
        );
        assert_eq!((r.count, r.dof, r.redundant), (6, 6, 0));
    }

    #[test]
    fn multiple_joint_with_redundancy() {
        // Crank 2 and links 3, 4 from the ground share one pin: 4 repeats the dyad 2-3.
        let r = run(
            Space::Planar,
            vec![
                j(R, &[1, 2]),
                j(R, &[2, 3, 4]),
                j(R, &[3, 1]),
                j(R, &[4, 1]),
            ],
        );
        assert_eq!((r.count, r.dof, r.redundant), (-1, 0, 1));
        assert_eq!(ids(&r), [["1", "2", "3", "4"]]);
    }

    #[test]
    fn inputs_count_as_bars_on_request() {
        let mut joints = four_bar(0);
        joints[0].driven = 1;
        let m = Mechanism::from_parts("t", Space::Planar, BodyId::Int(1), vec![], joints);
        let off = analyze(&m, &PebbleOptions::default());
        let on = analyze(&m, &PebbleOptions { with_inputs: true });
        assert_eq!((off.dof, on.dof), (1, 0));
        assert_eq!(on.rigid, [["1", "2", "3", "4"]]);
        assert_eq!(on.count, off.count);
    }

    #[test]
    fn disconnected_and_bad_input_do_not_panic() {
        let r = run(Space::Planar, vec![j(R, &[1, 1]), j(R, &[2, 3])]);
        assert_eq!(r.redundant, 2);
        assert_eq!(r.dof, 3 * 2 - 2);
    }
}
