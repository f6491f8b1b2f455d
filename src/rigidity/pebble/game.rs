//! The plain pebble game (a search per bar), its fundamental circuits and the rigid
//! components found after it (Lee and Streinu's reverse search): the reference the component
//! game is checked against, and the game the overconstrained regions are found with.

use super::graph::Graph;
use super::regions::Dsu;
use crate::budget::{BudgetExceeded, Meter};

/// The pebble game state.
pub(super) struct Game {
    pub(super) l: u8,
    pub(super) weight: Vec<u8>,
    pub(super) peb: Vec<u8>,
    /// Out-edges (head, bar) of each vertex; at most its weight of them.
    pub(super) out: Vec<Vec<(u32, u32)>>,
    /// In-edge tails, kept only for the component search.
    pub(super) inn: Option<Vec<Vec<u32>>>,
    pub(super) mark: Vec<u32>,
    pub(super) epoch: u32,
    pub(super) parent: Vec<(u32, u32)>,
    pub(super) stack: Vec<u32>,
    pub(super) visited: Vec<u32>,
    /// Work units not yet charged to the meter.
    pub(super) work: u64,
}

impl Game {
    pub(super) fn new(weight: Vec<u8>, l: u8) -> Game {
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

    pub(super) fn next_epoch(&mut self) -> u32 {
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.mark.iter_mut().for_each(|m| *m = 0);
            self.epoch = 1;
        }
        self.epoch
    }

    /// Move one free pebble reachable from `s` onto `s`, never taking one from `a` or `b`.
    /// Visited vertices are appended to `self.visited`.
    pub(super) fn find_pebble(&mut self, s: u32, a: u32, b: u32) -> bool {
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
    pub(super) fn reverse(&mut self, s: u32, y: u32) {
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
    pub(super) fn gather(&mut self, u: u32, v: u32, target: u8) -> bool {
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

    pub(super) fn insert(&mut self, u: u32, v: u32, bar: u32) {
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

/// The outcome of the game on one graph.
pub(super) struct Solution {
    pub(super) accepted: Vec<bool>,
    /// Bar union-find joining each redundant bar with its fundamental circuit.
    pub(super) circuits: Option<Dsu>,
    /// Rigid components as sorted body lists (every maximal tight set with a body).
    pub(super) components: Vec<Vec<usize>>,
}

pub(super) fn solve(
    g: &Graph,
    l: u8,
    regions: bool,
    meter: &mut Meter,
) -> Result<Solution, BudgetExceeded> {
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
pub(super) fn components(g: &Graph, game: &mut Game, accepted: &[bool]) -> Vec<Vec<usize>> {
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
        let q = tight_set(game, u, v, &mut state, &mut touched);
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

/// The maximal tight set holding `u` and `v` after a failed gather, grown from the minimal
/// one the search visited (Lee and Streinu's reverse search); `state` marks its members (1)
/// and the vertices known to reach a free pebble (2), all listed in `touched`.
fn tight_set(
    game: &mut Game,
    u: u32,
    v: u32,
    state: &mut [u8],
    touched: &mut Vec<u32>,
) -> Vec<u32> {
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
            let (found, seen) = reaches_free(game, p, state);
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
    q
}

/// Does `p` reach a free pebble (outside u, v) without entering the set (`state` 1)? And the
/// vertices the search saw.
fn reaches_free(game: &mut Game, p: u32, state: &[u8]) -> (bool, Vec<u32>) {
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
    (found, seen)
}
