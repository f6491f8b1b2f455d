//! Maximum flow on compressed adjacency arrays (greedy start, then BFS augmenting paths with
//! dead-node pruning), iterative throughout so that graphs with millions of nodes neither
//! recurse nor allocate per node.

/// Capacity used for the uncapacitated middle edges (equation → body).
pub(crate) const INF: u32 = u32::MAX / 4;

/// A flow network in compressed sparse row form. Edge `e` and its reverse are paired through
/// `rev`; the residual capacity of an edge is `cap[e]`.
pub(crate) struct Network {
    start: Vec<usize>,
    to: Vec<u32>,
    cap: Vec<u32>,
    rev: Vec<u32>,
}

impl Network {
    /// Build from directed edges `(from, to, capacity)` over `n` nodes.
    pub(crate) fn new(n: usize, edges: &[(u32, u32, u32)]) -> Network {
        let mut start = vec![0usize; n + 1];
        for &(u, v, _) in edges {
            start[u as usize + 1] += 1;
            start[v as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let m = start[n];
        let mut fill = start.clone();
        let mut to = vec![0u32; m];
        let mut cap = vec![0u32; m];
        let mut rev = vec![0u32; m];
        for &(u, v, c) in edges {
            let a = fill[u as usize];
            fill[u as usize] += 1;
            let b = fill[v as usize];
            fill[v as usize] += 1;
            to[a] = v;
            cap[a] = c;
            rev[a] = b as u32;
            to[b] = u;
            cap[b] = 0;
            rev[b] = a as u32;
        }
        Network {
            start,
            to,
            cap,
            rev,
        }
    }

    /// Number of nodes.
    pub(crate) fn nodes(&self) -> usize {
        self.start.len() - 1
    }

    /// Edge indices leaving node `u` (forward and reverse edges alike).
    pub(crate) fn edges(&self, u: usize) -> std::ops::Range<usize> {
        self.start[u]..self.start[u + 1]
    }

    /// Head of edge `e`.
    pub(crate) fn head(&self, e: usize) -> usize {
        self.to[e] as usize
    }

    /// Residual capacity of edge `e`.
    pub(crate) fn residual(&self, e: usize) -> u32 {
        self.cap[e]
    }

    /// Residual capacity of the edge paired with `e` (for a forward edge: the flow on it).
    pub(crate) fn reverse_residual(&self, e: usize) -> u32 {
        self.cap[self.rev[e] as usize]
    }

    /// Greedy start for a three-layer network (s → left → right → t): push along every
    /// s-u-v-t path while capacity remains. On mechanisms listed in build order this finds
    /// almost all the flow, leaving few and short augmenting paths.
    fn greedy(&mut self, s: usize, t: usize) -> u64 {
        let n = self.nodes();
        let mut to_sink = vec![usize::MAX; n];
        for e in self.edges(t) {
            // e goes t -> v; its pair is the edge v -> t.
            to_sink[self.to[e] as usize] = self.rev[e] as usize;
        }
        let mut total = 0u64;
        for e0 in self.edges(s) {
            let u = self.to[e0] as usize;
            for e1 in self.edges(u) {
                if self.cap[e0] == 0 {
                    break;
                }
                let v = self.to[e1] as usize;
                let e2 = to_sink[v];
                if v == s || e2 == usize::MAX || self.cap[e1] == 0 {
                    continue;
                }
                let d = self.cap[e0].min(self.cap[e1]).min(self.cap[e2]);
                if d == 0 {
                    continue;
                }
                for e in [e0, e1, e2] {
                    self.cap[e] -= d;
                    self.cap[self.rev[e] as usize] += d;
                }
                total += d as u64;
            }
        }
        total
    }

    /// Push the maximum flow from `s` to `t`; returns its value.
    ///
    /// A greedy start, then for every source edge with capacity left, shortest augmenting
    /// paths found by BFS. A search that fails marks every node it saw as dead: such a node
    /// cannot reach `t`, and later augmentations (along paths of live nodes) add edges only
    /// between live nodes, so it never will. Each unit of flow costs one local search and
    /// each failure retires its region, which keeps the whole near-linear on mechanisms.
    pub(crate) fn max_flow(&mut self, s: usize, t: usize) -> u64 {
        let n = self.nodes();
        let mut total = self.greedy(s, t);
        let mut dead = vec![false; n];
        let mut stamp = vec![0u32; n];
        let mut parent = vec![usize::MAX; n];
        let mut queue: Vec<usize> = Vec::new();
        let mut round = 0u32;
        for e0 in self.edges(s) {
            let u = self.to[e0] as usize;
            while self.cap[e0] > 0 && !dead[u] {
                round = round.wrapping_add(1);
                if round == 0 {
                    // Stamps wrapped: clear them once.
                    stamp.iter_mut().for_each(|x| *x = 0);
                    round = 1;
                }
                queue.clear();
                queue.push(u);
                stamp[u] = round;
                let mut found = false;
                let mut qi = 0;
                'bfs: while qi < queue.len() {
                    let x = queue[qi];
                    qi += 1;
                    for e in self.edges(x) {
                        let v = self.to[e] as usize;
                        if self.cap[e] == 0 || v == s || dead[v] || stamp[v] == round {
                            continue;
                        }
                        stamp[v] = round;
                        parent[v] = e;
                        if v == t {
                            found = true;
                            break 'bfs;
                        }
                        queue.push(v);
                    }
                }
                if !found {
                    for &x in &queue {
                        dead[x] = true;
                    }
                    break;
                }
                let mut bottleneck = self.cap[e0];
                let mut v = t;
                while v != u {
                    let e = parent[v];
                    bottleneck = bottleneck.min(self.cap[e]);
                    v = self.to[self.rev[e] as usize] as usize;
                }
                let mut v = t;
                while v != u {
                    let e = parent[v];
                    self.cap[e] -= bottleneck;
                    self.cap[self.rev[e] as usize] += bottleneck;
                    v = self.to[self.rev[e] as usize] as usize;
                }
                self.cap[e0] -= bottleneck;
                self.cap[self.rev[e0] as usize] += bottleneck;
                total += bottleneck as u64;
            }
        }
        total
    }

    /// Nodes reachable from `s` through edges with residual capacity.
    pub(crate) fn reachable_from(&self, s: usize) -> Vec<bool> {
        let mut seen = vec![false; self.nodes()];
        let mut stack = vec![s];
        seen[s] = true;
        while let Some(u) = stack.pop() {
            for e in self.edges(u) {
                let v = self.to[e] as usize;
                if self.cap[e] > 0 && !seen[v] {
                    seen[v] = true;
                    stack.push(v);
                }
            }
        }
        seen
    }

    /// Nodes from which `t` is reachable through edges with residual capacity.
    pub(crate) fn reaching(&self, t: usize) -> Vec<bool> {
        let mut seen = vec![false; self.nodes()];
        let mut stack = vec![t];
        seen[t] = true;
        while let Some(v) = stack.pop() {
            for e in self.edges(v) {
                // Edge e goes v -> u; its pair goes u -> v.
                let u = self.to[e] as usize;
                if self.cap[self.rev[e] as usize] > 0 && !seen[u] {
                    seen[u] = true;
                    stack.push(u);
                }
            }
        }
        seen
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_bipartite_flow() {
        // s=0, t=1, left 2,3 (cap 2, 1), right 4,5 (cap 1, 2).
        let edges = [
            (0, 2, 2),
            (0, 3, 1),
            (2, 4, INF),
            (2, 5, INF),
            (3, 4, INF),
            (4, 1, 1),
            (5, 1, 2),
        ];
        let mut n = Network::new(6, &edges);
        assert_eq!(n.max_flow(0, 1), 3);
        // Without the sink edge of 5 only one unit gets through (via 4).
        let mut n = Network::new(6, &edges[..6]);
        assert_eq!(n.max_flow(0, 1), 1);
        let src = n.reachable_from(0);
        assert!(src[2] && src[3] && src[4] && src[5] && !src[1]);
        let sink = n.reaching(1);
        assert!(!sink[0] && !sink[4]);
    }
}
