//! The block triangular order of the column groups: a b-matching of the rows to the groups
//! (by maximum flow) and the strongly connected components of what the matched rows touch.

use super::blocks::{Blk, blocks_of};
use super::matrix::SparseMatrix;

/// The elimination tier of each column group of `a` that [`Factor::new`] uses (lower
/// first): its block triangular order (module docs).
pub fn elimination_tiers(a: &SparseMatrix) -> Vec<u32> {
    let (blocks, _) = blocks_of(a);
    tiers(&a.groups(), &blocks).0
}

/// The elimination tier of every group (lower first) and the work spent finding it: the
/// block triangular order. A maximum b-matching of the blocks' rows to the groups (a group
/// takes at most as many rows as it has columns; [`crate::structure::flow`]) gives each
/// group its own rows; group `k` must go before group `h` when rows matched to `k` touch
/// `h` (otherwise they would still be live when `h` is eliminated, join its front and be
/// left over onto its neighbours). The strongly connected components of that relation, in
/// topological order, are the tiers: for a square generic matrix the blocks of its block
/// triangular form, within which the greedy minimum-front order decides.
pub(super) fn tiers(sizes: &[usize], blocks: &[Blk]) -> (Vec<u32>, u64) {
    use crate::graph::flow::{INF, Network};
    let n = sizes.len();
    let nb = blocks.len();
    if n == 0 || nb == 0 {
        return (vec![0; n], 0);
    }
    let (s, t) = (0usize, nb + n + 1);
    let group_node = |g: usize| (nb + 1 + g) as u32;
    let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(nb + n + 2 * nb);
    for (i, b) in blocks.iter().enumerate() {
        let u = (i + 1) as u32;
        edges.push((s as u32, u, b.nrows.min(INF as usize) as u32));
        // The last group first: a block of rows on a body and earlier bodies is then
        // matched to its body by the greedy start.
        for &g in b.groups.iter().rev() {
            edges.push((u, group_node(g), INF));
        }
    }
    for (g, &sz) in sizes.iter().enumerate() {
        edges.push((group_node(g), t as u32, sz.min(INF as usize) as u32));
    }
    let mut net = Network::new(t + 1, &edges);
    net.max_flow(s, t);
    let mut work = edges.len() as u64 * 4;
    // k -> h: rows matched to k touch h.
    let mut adj_start = vec![0usize; n + 1];
    let mut owners_of: Vec<Vec<usize>> = Vec::with_capacity(nb);
    for (i, b) in blocks.iter().enumerate() {
        let mut owners = Vec::new();
        for e in net.edges(i + 1) {
            let v = net.head(e);
            if v > nb && v <= nb + n && net.reverse_residual(e) > 0 {
                owners.push(v - nb - 1);
            }
        }
        for &k in &owners {
            adj_start[k + 1] += b.groups.len().saturating_sub(1);
        }
        owners_of.push(owners);
    }
    for g in 0..n {
        adj_start[g + 1] += adj_start[g];
    }
    let mut adj = vec![0u32; adj_start[n]];
    let mut fill = adj_start.clone();
    for (b, owners) in blocks.iter().zip(&owners_of) {
        for &k in owners {
            for &h in &b.groups {
                if h != k {
                    adj[fill[k]] = h as u32;
                    fill[k] += 1;
                }
            }
        }
    }
    work += adj.len() as u64 * 4;
    drop(owners_of);
    let (mut comp, ncomp) = components(&adj_start, &adj);
    // The over-determined part: groups reachable from rows the matching left over (in the
    // residual network: a row to any group it touches, a group to the rows matched to it).
    // Left-over rows join every front they touch whatever the order, so there the order
    // within is left to the greedy: one last tier.
    let over = net.reachable_from(s);
    for (g, c) in comp.iter_mut().enumerate() {
        *c = if over[nb + 1 + g] {
            ncomp
        } else {
            ncomp - 1 - *c
        };
    }
    (comp, work)
}

/// The strongly connected component of each of the `adj_start.len() - 1` groups, and
/// their number: Tarjan's, a component completed only after every component it reaches,
/// so completion order is reverse topological.
fn components(adj_start: &[usize], adj: &[u32]) -> (Vec<u32>, u32) {
    let n = adj_start.len() - 1;
    let (members, bounds) = crate::graph::scc::tarjan_flat(adj_start, adj, &vec![true; n]);
    let ncomp = (bounds.len() - 1) as u32;
    let mut comp = vec![0u32; n];
    for (c, span) in bounds.windows(2).enumerate() {
        for &w in &members[span[0]..span[1]] {
            comp[w as usize] = c as u32;
        }
    }
    (comp, ncomp)
}
