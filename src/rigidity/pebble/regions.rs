//! Overconstrained regions: the fundamental circuits that share bars, joined in a union-find
//! over the bars, as bodies and joints.

use super::Region;
use super::fast::FastSolution;
use super::game::solve;
use super::graph::Graph;
use crate::budget::{BudgetExceeded, Meter};
use crate::mechanism::Mechanism;

/// Union-find with path halving; the smaller root wins (order independence).
pub(super) struct Dsu(pub(super) Vec<u32>);

impl Dsu {
    pub(super) fn find(&mut self, mut i: u32) -> u32 {
        while self.0[i as usize] != i {
            let p = self.0[i as usize];
            self.0[i as usize] = self.0[p as usize];
            i = p;
        }
        i
    }
    pub(super) fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.0[hi as usize] = lo;
        }
    }
}

/// The overconstrained regions: the plain game (which finds every fundamental circuit) run
/// again on the bars of the rigid components that hold a redundant bar, only. Every circuit
/// lies inside one rigid component (its support is a tight set), so this gives the regions of
/// the whole game.
pub(super) fn regions_of_overconstrained(
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
pub(super) fn regions(m: &Mechanism, g: &Graph, accepted: &[bool], dsu: &mut Dsu) -> Vec<Region> {
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
