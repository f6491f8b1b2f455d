//! Maximum flow on compressed adjacency arrays (greedy start, then Dinic's phases: level
//! graph by breadth-first search, blocking flow by depth-first search with current-edge
//! pointers), iterative throughout so that graphs with millions of nodes neither recurse nor
//! allocate per node.

/// Capacity used for the uncapacitated middle edges (equation → body).
pub(crate) const INF: u32 = u32::MAX / 4;

/// A flow network in compressed sparse row form. Edge `e` and its reverse are paired through
/// `rev`; the residual capacity of an edge is `cap[e]`.
pub(crate) struct Network {
    /// First edge of each node (`u32`: a network of 10^6 bodies has about 2·10^7 edges).
    start: Vec<u32>,
    to: Vec<u32>,
    cap: Vec<u32>,
    rev: Vec<u32>,
}

impl Network {
    /// Build from directed edges `(from, to, capacity)` over `n` nodes.
    pub(crate) fn new(n: usize, edges: &[(u32, u32, u32)]) -> Network {
        Network::from_edges(n, |put| {
            for &(u, v, c) in edges {
                put(u, v, c);
            }
        })
    }

    /// Build from directed edges `(from, to, capacity)` over `n` nodes, listed by `edges`
    /// (called twice, and it must list the same edges in the same order both times): the
    /// network is the one [`Network::new`] builds from that list, without holding the list
    /// (12 bytes an edge, 100 MB at 10^6 bodies) next to it.
    pub(crate) fn from_edges(n: usize, edges: impl Fn(&mut dyn FnMut(u32, u32, u32))) -> Network {
        let mut start = vec![0u32; n + 1];
        edges(&mut |u, v, _| {
            start[u as usize + 1] += 1;
            start[v as usize + 1] += 1;
        });
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let m = start[n] as usize;
        let mut fill = start.clone();
        let mut to = vec![0u32; m];
        let mut cap = vec![0u32; m];
        let mut rev = vec![0u32; m];
        edges(&mut |u, v, c| {
            let a = fill[u as usize];
            fill[u as usize] += 1;
            let b = fill[v as usize];
            fill[v as usize] += 1;
            let (a, b) = (a as usize, b as usize);
            to[a] = v;
            cap[a] = c;
            rev[a] = b as u32;
            to[b] = u;
            cap[b] = 0;
            rev[b] = a as u32;
        });
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
        self.start[u] as usize..self.start[u + 1] as usize
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

    /// Warm start for a three-layer network (s → left → right → t): push up to `d` units
    /// along s-u-v-t for each `(u, v, d)`, as capacity allows. A maximum flow from there is a
    /// maximum flow all the same (only the work to reach it changes).
    pub(crate) fn warm(&mut self, s: usize, t: usize, paths: &[(usize, usize, u32)]) {
        let n = self.nodes();
        let mut from_s = vec![usize::MAX; n];
        for e in self.edges(s) {
            from_s[self.to[e] as usize] = e;
        }
        let mut to_t = vec![usize::MAX; n];
        for e in self.edges(t) {
            to_t[self.to[e] as usize] = self.rev[e] as usize;
        }
        for &(u, v, d) in paths {
            let (e0, e2) = (from_s[u], to_t[v]);
            if e0 == usize::MAX || e2 == usize::MAX {
                continue;
            }
            // The forward edge u → v (only forward edges leave a left node towards the right).
            let Some(e1) = self.edges(u).find(|&e| self.to[e] as usize == v) else {
                continue;
            };
            let d = d.min(self.cap[e0]).min(self.cap[e1]).min(self.cap[e2]);
            if d == 0 {
                continue;
            }
            for e in [e0, e1, e2] {
                self.cap[e] -= d;
                self.cap[self.rev[e] as usize] += d;
            }
        }
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
    /// A greedy start, then Dinic's phases: a breadth-first search labels the nodes by their
    /// distance from `s` in the residual network, and a depth-first search with a current-edge
    /// pointer per node pushes a blocking flow along shortest paths, retiring every dead end
    /// for the rest of the phase. Each phase costs O(edges) and lengthens the shortest
    /// augmenting path, so a few phases finish the flow the greedy start leaves (the previous
    /// method ran one search per missing unit of flow).
    pub(crate) fn max_flow(&mut self, s: usize, t: usize) -> u64 {
        const UNSEEN: u32 = u32::MAX;
        let n = self.nodes();
        let mut total = self.greedy(s, t);
        if s == t {
            return total;
        }
        let mut level = vec![UNSEEN; n];
        let mut next = vec![0u32; n];
        let mut queue: Vec<usize> = Vec::new();
        let mut path: Vec<usize> = Vec::new();
        loop {
            // Levels: distance from s in the residual network, up to t's.
            for &x in &queue {
                level[x] = UNSEEN;
            }
            queue.clear();
            level[s] = 0;
            queue.push(s);
            let mut qi = 0;
            while qi < queue.len() {
                let x = queue[qi];
                qi += 1;
                if level[t] != UNSEEN && level[x] >= level[t] {
                    break;
                }
                for e in self.edges(x) {
                    let v = self.to[e] as usize;
                    if self.cap[e] > 0 && level[v] == UNSEEN {
                        level[v] = level[x] + 1;
                        queue.push(v);
                    }
                }
            }
            if level[t] == UNSEEN {
                level[s] = UNSEEN;
                for &x in &queue {
                    level[x] = UNSEEN;
                }
                break;
            }
            for &x in &queue {
                next[x] = self.start[x];
            }
            // Blocking flow: advance along level-increasing edges, augment at t, retreat
            // from dead ends (a retreated node is taken out of the phase).
            path.clear();
            let mut u = s;
            loop {
                if u == t {
                    let d = path.iter().map(|&e| self.cap[e]).min().unwrap_or(0);
                    for &e in &path {
                        self.cap[e] -= d;
                        self.cap[self.rev[e] as usize] += d;
                    }
                    total += u64::from(d);
                    let k = path.iter().position(|&e| self.cap[e] == 0).unwrap_or(0);
                    path.truncate(k);
                    u = match path.last() {
                        Some(&e) => self.to[e] as usize,
                        None => s,
                    };
                    continue;
                }
                let end = self.start[u + 1];
                let mut advanced = false;
                while next[u] < end {
                    let e = next[u] as usize;
                    let v = self.to[e] as usize;
                    if self.cap[e] > 0 && level[v] != UNSEEN && level[v] == level[u] + 1 {
                        path.push(e);
                        u = v;
                        advanced = true;
                        break;
                    }
                    next[u] += 1;
                }
                if advanced {
                    continue;
                }
                if u == s {
                    break;
                }
                // Dead end: out of this phase; the edge into it is useless too.
                level[u] = UNSEEN;
                match path.pop() {
                    Some(e) => {
                        u = self.to[self.rev[e] as usize] as usize;
                        next[u] += 1;
                    }
                    None => break,
                }
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

    /// Edmonds-Karp on a capacity matrix: the reference for small random networks.
    fn reference(n: usize, edges: &[(u32, u32, u32)], s: usize, t: usize) -> u64 {
        let mut c = vec![vec![0u64; n]; n];
        for &(u, v, w) in edges {
            c[u as usize][v as usize] += u64::from(w);
        }
        let mut total = 0;
        loop {
            let mut parent = vec![usize::MAX; n];
            parent[s] = s;
            let mut q = std::collections::VecDeque::from([s]);
            while let Some(x) = q.pop_front() {
                for y in 0..n {
                    if c[x][y] > 0 && parent[y] == usize::MAX {
                        parent[y] = x;
                        q.push_back(y);
                    }
                }
            }
            if parent[t] == usize::MAX {
                return total;
            }
            let mut d = u64::MAX;
            let mut y = t;
            while y != s {
                d = d.min(c[parent[y]][y]);
                y = parent[y];
            }
            let mut y = t;
            while y != s {
                c[parent[y]][y] -= d;
                c[y][parent[y]] += d;
                y = parent[y];
            }
            total += d;
        }
    }

    #[test]
    fn phases_match_a_reference_on_random_networks() {
        let mut rng = crate::rng::SplitMix64::new(7);
        for round in 0..300 {
            // Three layers as in the structural analysis (s, equations, bodies, t), plus a
            // few arbitrary edges now and then.
            let (l, r) = (1 + rng.below(12) as u32, 1 + rng.below(12) as u32);
            let n = 2 + l + r;
            let mut edges = Vec::new();
            for a in 0..l {
                edges.push((0, 2 + a, 1 + rng.below(6) as u32));
                for b in 0..r {
                    if rng.below(3) == 0 {
                        edges.push((2 + a, 2 + l + b, INF));
                    }
                }
            }
            for b in 0..r {
                edges.push((2 + l + b, 1, 1 + rng.below(6) as u32));
            }
            if round % 3 == 0 {
                for _ in 0..rng.below(6) {
                    let (u, v) = (
                        rng.below(u64::from(n)) as u32,
                        rng.below(u64::from(n)) as u32,
                    );
                    if u != v && u != 1 && v != 0 {
                        edges.push((u, v, 1 + rng.below(4) as u32));
                    }
                }
            }
            let want = reference(n as usize, &edges, 0, 1);
            let mut net = Network::new(n as usize, &edges);
            assert_eq!(net.max_flow(0, 1), want, "round {round}: {edges:?}");
            // The residual network has no augmenting path left.
            assert!(!net.reachable_from(0)[1]);
        }
    }
}
