//! Loops: a minimum cycle basis of the body graph (Horton's algorithm) and each loop's
//! spatiality and overconstraint.

use super::clusters::find;
use super::dense::small_rank;
use super::report::LoopInfo;
use crate::mechanism::Mechanism;
use nalgebra::{DMatrix, DVector};

/// Minimum cycle basis by Horton's algorithm on an undirected multigraph (`edges` as node
/// pairs). Returns each cycle as a sorted list of edge indices. `None` when the candidate set
/// would be too large.
pub(super) fn min_cycle_basis(nodes: usize, edges: &[(usize, usize)]) -> Option<Vec<Vec<usize>>> {
    // Cycle space dimension per connected component.
    let mut uf: Vec<usize> = (0..nodes).collect();
    let mut comps = nodes;
    for &(a, b) in edges {
        let (ra, rb) = (find(&mut uf, a), find(&mut uf, b));
        if ra != rb {
            uf[ra] = rb;
            comps -= 1;
        }
    }
    let dim = edges.len() + comps - nodes;
    if dim == 0 {
        return Some(Vec::new());
    }
    if dim > 400 || nodes.saturating_mul(edges.len()) > 400_000 {
        return None;
    }
    let cands = candidates(nodes, edges);
    Some(independent(cands, edges.len(), dim))
}

/// Horton's candidate cycles, shortest first: for every node v and edge (a, b) off v's BFS
/// tree whose tree paths to v meet only at v, the cycle of the edge and both paths (as bits
/// over the edges).
fn candidates(nodes: usize, edges: &[(usize, usize)]) -> Vec<(usize, Vec<u64>)> {
    let mut adj: Vec<Vec<(usize, usize)>> = vec![Vec::new(); nodes];
    for (ei, &(a, b)) in edges.iter().enumerate() {
        adj[a].push((b, ei));
        adj[b].push((a, ei));
    }
    let words = edges.len().div_ceil(64);
    let mut cands: Vec<(usize, Vec<u64>)> = Vec::new();
    for v in 0..nodes {
        // BFS tree from v.
        let mut parent: Vec<Option<(usize, usize)>> = vec![None; nodes];
        let mut depth = vec![usize::MAX; nodes];
        let mut first = vec![usize::MAX; nodes];
        depth[v] = 0;
        let mut queue = std::collections::VecDeque::from([v]);
        while let Some(x) = queue.pop_front() {
            for &(y, e) in &adj[x] {
                if depth[y] == usize::MAX {
                    depth[y] = depth[x] + 1;
                    parent[y] = Some((x, e));
                    first[y] = if x == v { y } else { first[x] };
                    queue.push_back(y);
                }
            }
        }
        for (ei, &(a, b)) in edges.iter().enumerate() {
            if depth[a] == usize::MAX || depth[b] == usize::MAX {
                continue;
            }
            if parent[a].is_some_and(|p| p.1 == ei) || parent[b].is_some_and(|p| p.1 == ei) {
                continue;
            }
            // The two tree paths must meet only at v.
            if a != v && b != v && first[a] == first[b] {
                continue;
            }
            let mut bits = vec![0u64; words];
            bits[ei / 64] ^= 1 << (ei % 64);
            for start in [a, b] {
                let mut x = start;
                while let Some((p, e)) = parent[x] {
                    bits[e / 64] ^= 1 << (e % 64);
                    x = p;
                }
            }
            let len = depth[a] + depth[b] + 1;
            cands.push((len, bits));
        }
    }
    cands.sort();
    cands.dedup();
    cands
}

/// The first `dim` candidates independent over GF(2) (greedy, in order), each as a sorted
/// list of edge indices (out of `ne` edges).
fn independent(cands: Vec<(usize, Vec<u64>)>, ne: usize, dim: usize) -> Vec<Vec<usize>> {
    let mut basis: Vec<(usize, Vec<u64>)> = Vec::new(); // (pivot bit, reduced vector)
    let mut out = Vec::new();
    for (_, bits) in cands {
        let mut r = bits.clone();
        for (p, bv) in &basis {
            if r[p / 64] >> (p % 64) & 1 == 1 {
                for (x, y) in r.iter_mut().zip(bv) {
                    *x ^= y;
                }
            }
        }
        let pivot = (0..ne).find(|&i| r[i / 64] >> (i % 64) & 1 == 1);
        if let Some(p) = pivot {
            // Keep the basis reduced on earlier pivots as well.
            for (_, bv) in basis.iter_mut() {
                if bv[p / 64] >> (p % 64) & 1 == 1 {
                    for (x, y) in bv.iter_mut().zip(&r) {
                        *x ^= y;
                    }
                }
            }
            basis.push((p, r));
            out.push(
                (0..ne)
                    .filter(|&i| bits[i / 64] >> (i % 64) & 1 == 1)
                    .collect(),
            );
            if out.len() == dim {
                break;
            }
        }
    }
    out
}

/// Order a cycle's edges into a walk; returns the node sequence.
pub(super) fn walk(cycle: &[usize], edges: &[(usize, usize)]) -> Vec<usize> {
    let mut left: Vec<usize> = cycle.to_vec();
    let Some(e0) = left.first().copied() else {
        return Vec::new();
    };
    left.remove(0);
    let (start, mut cur) = edges[e0];
    let mut nodes = vec![start];
    while cur != start || nodes.len() == 1 {
        nodes.push(cur);
        let Some(pos) = left
            .iter()
            .position(|&e| edges[e].0 == cur || edges[e].1 == cur)
        else {
            break;
        };
        let e = left.remove(pos);
        cur = if edges[e].0 == cur {
            edges[e].1
        } else {
            edges[e].0
        };
        if left.is_empty() {
            break;
        }
    }
    nodes
}

/// The body graph of `m` in which a multiple joint is a node (after the bodies): the number
/// of nodes, the edges and each edge's joint.
fn body_graph(m: &Mechanism) -> (usize, Vec<(usize, usize)>, Vec<usize>) {
    let mut gnodes = m.bodies.len();
    let mut gedges: Vec<(usize, usize)> = Vec::new();
    let mut edge_joint: Vec<usize> = Vec::new();
    for (ji, j) in m.joints.iter().enumerate() {
        if j.bodies.len() == 2 {
            gedges.push((j.bodies[0], j.bodies[1]));
            edge_joint.push(ji);
        } else if j.bodies.len() > 2 {
            let node = gnodes;
            gnodes += 1;
            for &x in &j.bodies {
                gedges.push((x, node));
                edge_joint.push(ji);
            }
        }
    }
    (gnodes, gedges, edge_joint)
}

/// The loops of `m`: a minimum cycle basis of the body graph in which a multiple joint is a
/// node, each loop with its spatiality (the rank of its joints' full twists, driven DOF
/// included, from `full_twists`); or why they are not listed.
pub(super) fn loops(
    m: &Mechanism,
    full_twists: &dyn Fn() -> Vec<DMatrix<f64>>,
) -> (Vec<LoopInfo>, Option<String>) {
    let (gnodes, gedges, edge_joint) = body_graph(m);
    match min_cycle_basis(gnodes, &gedges) {
        None => (
            Vec::new(),
            Some(format!(
                "loop basis not listed: {} independent loops, too many to enumerate",
                gedges.len() + 1 - gnodes.min(gedges.len() + 1)
            )),
        ),
        Some(cycles) => {
            let full_twists = full_twists();
            let out = cycles
                .iter()
                .map(|cyc| loop_info(m, cyc, &gedges, &edge_joint, &full_twists))
                .collect();
            (out, None)
        }
    }
}

/// One loop of the basis: its joints along the walk, its bodies, its spatiality and its
/// overconstraint.
fn loop_info(
    m: &Mechanism,
    cyc: &[usize],
    gedges: &[(usize, usize)],
    edge_joint: &[usize],
    full_twists: &[DMatrix<f64>],
) -> LoopInfo {
    let nb = m.bodies.len();
    let b = m.b() as usize;
    let seq = walk(cyc, gedges);
    let mut joints: Vec<usize> = Vec::new();
    for &e in cyc {
        if !joints.contains(&edge_joint[e]) {
            joints.push(edge_joint[e]);
        }
    }
    // Order joints along the walk.
    let mut ordered: Vec<usize> = Vec::new();
    for w in seq.windows(2).chain(std::iter::once(
        &[*seq.last().unwrap_or(&0), *seq.first().unwrap_or(&0)][..],
    )) {
        if let Some(&e) = cyc.iter().find(|&&e| {
            (gedges[e].0 == w[0] && gedges[e].1 == w[1])
                || (gedges[e].1 == w[0] && gedges[e].0 == w[1])
        }) && !ordered.contains(&edge_joint[e])
        {
            ordered.push(edge_joint[e]);
        }
    }
    for j in joints {
        if !ordered.contains(&j) {
            ordered.push(j);
        }
    }
    let cols: Vec<DVector<f64>> = ordered
        .iter()
        .flat_map(|&j| {
            full_twists
                .get(j)
                .map(|t| t.column_iter().map(|c| c.into_owned()).collect::<Vec<_>>())
                .unwrap_or_default()
        })
        .collect();
    let spatiality = if cols.is_empty() {
        0
    } else {
        let mut a = DMatrix::from_columns(&cols);
        for mut c in a.column_iter_mut() {
            let n = c.norm();
            if n > 0.0 {
                c /= n;
            }
        }
        small_rank(&a, 1e-8 * cols.len() as f64)
    };
    LoopInfo {
        joints: ordered.iter().map(|&j| m.joints[j].id.clone()).collect(),
        bodies: seq
            .iter()
            .filter(|&&x| x < nb)
            .map(|&x| m.body_id(x).to_string())
            .collect(),
        spatiality,
        overconstraint: b.saturating_sub(spatiality),
    }
}
