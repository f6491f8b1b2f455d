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

fn solve(g: &Graph, l: u8, regions: bool) -> Solution {
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
            }
        }
    }
    let components = components(g, &mut game, &accepted);
    Solution {
        accepted,
        circuits,
        components,
    }
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

/// Analyse the generic rigidity of `m`.
pub fn analyze(m: &Mechanism, opts: &PebbleOptions) -> PebbleReport {
    let b = m.b();
    let l = b as u8;
    let g = Graph::build(m, opts, None);
    let mut sol = solve(&g, l, true);
    let rank = sol.accepted.iter().filter(|&&a| a).count() as i64;
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
    let mut comps: Vec<Vec<usize>> = sol
        .components
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

    let mut overconstrained = Vec::new();
    if let Some(dsu) = &mut sol.circuits {
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
            if !sol.accepted[i] {
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
        overconstrained = regions
            .into_iter()
            .map(|(bs, js, r)| Region {
                bodies: bs.into_iter().map(id).collect(),
                joints: js.into_iter().map(|j| m.joints[j].id.clone()).collect(),
                redundant: r,
            })
            .collect();
    }

    let n = m.bodies.len();
    let degenerate = if sol.components.iter().any(|c| c.len() >= 2 && c.len() < n) {
        true
    } else if n > 2 && sol.components.iter().any(|c| c.len() == n) {
        // The whole chain is rigid: a proper rigid sub-chain avoids some body.
        (0..n).any(|w| {
            let g = Graph::build(m, opts, Some(w));
            solve(&g, l, false)
                .components
                .iter()
                .any(|c| c.iter().filter(|&&x| x != w).count() >= 2)
        })
    } else {
        false
    };

    PebbleReport {
        name: m.name.clone(),
        space: m.space.name(),
        b,
        bodies: n,
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
