//! Maximum flow on compressed adjacency arrays (greedy start, then Dinic's phases: level
//! graph by breadth-first search, blocking flow by depth-first search with current-edge
//! pointers), iterative throughout so that graphs with millions of nodes neither recurse nor
//! allocate per node.

/// Capacity used for the uncapacitated middle edges (equation → body).
pub(crate) const INF: u32 = u32::MAX / 4;

/// An edge's head and residual capacity, side by side: the searches read both of every edge
/// they scan (two arrays were two cache misses an edge at 10^6 bodies).
#[derive(Clone, Copy, Default)]
struct Arc {
    to: u32,
    cap: u32,
}

#[cfg(test)]
thread_local! {
    /// Pushes along an edge on this thread (tests count the greedy start's edge updates).
    static PUSHES: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// A flow network in compressed sparse row form. Edge `e` and its reverse are paired through
/// `rev`; the residual capacity of an edge is `arc[e].cap`.
///
/// A network [`Network::three_layer`] builds keeps the source's edges implicit: node 0's edge
/// to left node `i` (node `2 + i`) and its reverse are edges `m + i` and `m + l + i` (`m`
/// explicit edges, `l` left nodes), their residual capacities side by side in one more entry
/// of `arc` each, past the explicit edges (8 bytes a left node instead of two 12-byte slots:
/// about 40 MB at 10^6 bodies; kept in `arc`, the network's arrays are allocated as before,
/// less: kept in an array of their own they changed where glibc placed the later arrays, and
/// the heap of the planar files grew by 8-19 MB). Node 0's
/// edges are those `l` edges in order, and each left node's reverse edge comes before its
/// explicit ones: the order the edge list gives, so every search visits the same edges in
/// the same order and finds the same flow.
#[cfg_attr(test, derive(Clone))]
pub(crate) struct Network {
    /// First explicit edge of each node (`u32`: a network of 10^6 bodies has about 2·10^7
    /// edges).
    start: Vec<u32>,
    /// The explicit edges, then (three-layer networks) for each left node `i` the residual
    /// capacities of the implicit edges node 0 → `i` (`to`) and back (`cap`: the flow on the
    /// first).
    arc: Vec<Arc>,
    rev: Vec<u32>,
    /// Number of left nodes with implicit edges to and from node 0 (0: none).
    nl: usize,
    /// Edges examined by the searches whose answer is a set of nodes (the maximum flow's last
    /// breadth-first search, [`Network::reachable_from`], [`Network::reaching`]): the work of
    /// the Dulmage–Mendelsohn split, for tests that bound it.
    scanned: std::cell::Cell<u64>,
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
        let mut arc = vec![Arc::default(); m];
        let mut rev = vec![0u32; m];
        edges(&mut |u, v, c| {
            let a = fill[u as usize];
            fill[u as usize] += 1;
            let b = fill[v as usize];
            fill[v as usize] += 1;
            let (a, b) = (a as usize, b as usize);
            arc[a] = Arc { to: v, cap: c };
            rev[a] = b as u32;
            arc[b] = Arc { to: u, cap: 0 };
            rev[b] = a as u32;
        });
        Network {
            start,
            arc,
            rev,
            nl: 0,
            scanned: std::cell::Cell::new(0),
        }
    }

    /// The three-layer network of the count (source 0, sink 1, left node `i` is node `2 + i`,
    /// right node `j` is node `2 + left.len() + j`): the one [`Network::new`] builds from the
    /// edge list s → left `i` (capacity `left[i]`), then left `i` → each right node of
    /// `ends(i)` (`u32::MAX`: none; capacity [`INF`]), for every `i` in order; then right `j` →
    /// t (capacity `right[j]`, `u32::MAX`: no edge) for every `j` in order. Same nodes, same
    /// edges in the same order at every node, so the same flow; built directly, without the
    /// edge list or a call per edge. `ends` is called twice per left node and must answer the
    /// same both times; a right node listed twice by one left node gets one edge. The edges
    /// s → left and their reverses are implicit (see [`Network`]).
    pub(crate) fn three_layer(
        left: &[u32],
        ends: impl Fn(usize) -> [u32; 2],
        right: &[u32],
    ) -> Network {
        Network::build_three_layer(left, ends, right, false).0
    }

    /// [`Network::three_layer`] with the greedy start of [`Network::max_flow_cut`] (from
    /// node 0 to node 1) pushed while it is built, and its value: the network in the state
    /// `three_layer` then the greedy start leave, every residual capacity equal. The greedy
    /// start visits the left nodes in order and each one's edges in order, the order the
    /// build writes them in, so each middle edge is written once with its flow (the greedy
    /// start read the edges again and wrote every middle edge's pair, at the body, a second
    /// time: a scattered write in the edge array each). Finish with
    /// [`Network::max_flow_after_greedy`].
    pub(crate) fn three_layer_greedy(
        left: &[u32],
        ends: impl Fn(usize) -> [u32; 2],
        right: &[u32],
    ) -> (Network, u64) {
        Network::build_three_layer(left, ends, right, true)
    }

    /// [`Network::three_layer`], and with `greedy` [`Network::three_layer_greedy`].
    fn build_three_layer(
        left: &[u32],
        ends: impl Fn(usize) -> [u32; 2],
        right: &[u32],
        greedy: bool,
    ) -> (Network, u64) {
        const NONE: u32 = u32::MAX;
        let (nl, nr) = (left.len(), right.len());
        let n = 2 + nl + nr;
        let rnode = |j: u32| 2 + nl + j as usize;
        let ends = |i: usize| {
            let [a, b] = ends(i);
            [a, if b == a { NONE } else { b }]
        };
        // Degrees of the explicit edges, then offsets (node 0's edges and the left nodes'
        // edges back to it are implicit).
        let mut start = vec![0u32; n + 1];
        start[2] = right.iter().filter(|&&c| c != NONE).count() as u32;
        for i in 0..nl {
            let mut d = 0;
            for j in ends(i) {
                if j != NONE {
                    d += 1;
                    start[rnode(j) + 1] += 1;
                }
            }
            start[2 + i + 1] = d;
        }
        for (j, &c) in right.iter().enumerate() {
            if c != NONE {
                start[rnode(j as u32) + 1] += 1;
            }
        }
        for x in 0..n {
            start[x + 1] += start[x];
        }
        let m = start[n] as usize;
        let mut arc = vec![Arc::default(); m + nl];
        let mut rev = vec![0u32; m];
        // Per right node: its next free slot (the left nodes' slots are written in order)
        // and, for the greedy start, the residual capacity of its edge to t (0: none), side
        // by side (one scattered read for both).
        let mut fill: Vec<[u32; 2]> = start[2 + nl..2 + nl + nr]
            .iter()
            .zip(right)
            .map(|(&f, &c)| [f, if greedy && c != NONE { c } else { 0 }])
            .collect();
        // An edge with residual `c` and its pair with residual `back`.
        let pair =
            |arc: &mut [Arc], rev: &mut [u32], a: u32, b: u32, to: u32, from: u32, c, back| {
                arc[a as usize] = Arc { to, cap: c };
                rev[a as usize] = b;
                arc[b as usize] = Arc {
                    to: from,
                    cap: back,
                };
                rev[b as usize] = a;
            };
        let mut total = 0u64;
        for (i, &c) in left.iter().enumerate() {
            let x = (2 + i) as u32;
            let mut a = start[2 + i];
            // The greedy start's pushes from this left node: as much as its source edge
            // still carries and the right node's edge to t takes, edge by edge.
            let mut rest = c;
            for j in ends(i) {
                if j != NONE {
                    let [b, room] = &mut fill[j as usize];
                    let d = rest.min(INF).min(*room);
                    *room -= d;
                    rest -= d;
                    pair(&mut arc, &mut rev, a, *b, rnode(j) as u32, x, INF - d, d);
                    *b += 1;
                    a += 1;
                }
            }
            total += u64::from(c - rest);
            // Node 0's edge to `x` and back: residual `rest`, flow `c - rest`.
            arc[m + i] = Arc {
                to: rest,
                cap: c - rest,
            };
        }
        let mut b = start[1];
        for (j, &c) in right.iter().enumerate() {
            if c != NONE {
                let [a, room] = fill[j];
                let room = if greedy { room } else { c };
                pair(
                    &mut arc,
                    &mut rev,
                    a,
                    b,
                    1,
                    rnode(j as u32) as u32,
                    room,
                    c - room,
                );
                b += 1;
            }
        }
        let net = Network {
            start,
            arc,
            rev,
            nl,
            scanned: std::cell::Cell::new(0),
        };
        (net, total)
    }

    /// Edges examined by the searches that answer a set of nodes so far.
    pub(crate) fn scanned(&self) -> u64 {
        self.scanned.get()
    }

    /// Count `n` more edges examined.
    fn scan(&self, n: usize) {
        self.scanned.set(self.scanned.get() + n as u64);
    }

    /// Number of nodes.
    pub(crate) fn nodes(&self) -> usize {
        self.start.len() - 1
    }

    /// Explicit edge indices leaving node `u` (forward and reverse edges alike): all of
    /// them unless the network was built by [`Network::three_layer`] (see
    /// [`Network::all_edges`]).
    pub(crate) fn edges(&self, u: usize) -> std::ops::Range<usize> {
        self.start[u] as usize..self.start[u + 1] as usize
    }

    /// The implicit edges leaving node `u`, which come before its explicit ones: the first
    /// index and how many.
    fn implicit(&self, u: usize) -> (usize, usize) {
        let (m, nl) = (self.arc.len() - self.nl, self.nl);
        if nl == 0 {
            (0, 0)
        } else if u == 0 {
            (m, nl)
        } else if (2..2 + nl).contains(&u) {
            (m + nl + (u - 2), 1)
        } else {
            (0, 0)
        }
    }

    /// Every edge index leaving node `u`, in order: the implicit ones, then [`Network::edges`].
    pub(crate) fn all_edges(&self, u: usize) -> impl Iterator<Item = usize> + use<> {
        let (first, k) = self.implicit(u);
        (first..first + k).chain(self.edges(u))
    }

    /// How many edges leave node `u`.
    fn degree(&self, u: usize) -> usize {
        self.implicit(u).1 + self.edges(u).len()
    }

    /// Head of edge `e`.
    pub(crate) fn head(&self, e: usize) -> usize {
        let m = self.arc.len() - self.nl;
        match e.checked_sub(m) {
            None => self.arc[e].to as usize,
            Some(i) if i < self.nl => 2 + i,
            Some(_) => 0,
        }
    }

    /// The edge paired with edge `e`.
    fn rev(&self, e: usize) -> usize {
        let (m, nl) = (self.arc.len() - self.nl, self.nl);
        match e.checked_sub(m) {
            None => self.rev[e] as usize,
            Some(i) if i < nl => e + nl,
            Some(_) => e - nl,
        }
    }

    /// Residual capacity of edge `e`.
    pub(crate) fn residual(&self, e: usize) -> u32 {
        let (m, nl) = (self.arc.len() - self.nl, self.nl);
        match e.checked_sub(m) {
            None => self.arc[e].cap,
            Some(i) if i < nl => self.arc[m + i].to,
            Some(i) => self.arc[m + i - nl].cap,
        }
    }

    /// The residual capacity of edge `e`, to change.
    fn residual_mut(&mut self, e: usize) -> &mut u32 {
        let (m, nl) = (self.arc.len() - self.nl, self.nl);
        match e.checked_sub(m) {
            None => &mut self.arc[e].cap,
            Some(i) if i < nl => &mut self.arc[m + i].to,
            Some(i) => &mut self.arc[m + i - nl].cap,
        }
    }

    /// Residual capacity of the edge paired with `e` (for a forward edge: the flow on it).
    pub(crate) fn reverse_residual(&self, e: usize) -> u32 {
        self.residual(self.rev(e))
    }

    /// Push `d` units along edge `e` (residual `d` or more).
    #[inline]
    fn push(&mut self, e: usize, d: u32) {
        #[cfg(test)]
        PUSHES.with(|p| p.set(p.get() + 1));
        *self.residual_mut(e) -= d;
        let r = self.rev(e);
        *self.residual_mut(r) += d;
    }

    /// Warm start for a three-layer network (s → left → right → t): push up to `d` units
    /// along s-u-v-t for each `(u, v, d)`, as capacity allows. A maximum flow from there is a
    /// maximum flow all the same (only the work to reach it changes).
    pub(crate) fn warm(&mut self, s: usize, t: usize, paths: &[(usize, usize, u32)]) {
        let n = self.nodes();
        let mut from_s = vec![usize::MAX; n];
        for e in self.all_edges(s) {
            from_s[self.head(e)] = e;
        }
        let mut to_t = vec![usize::MAX; n];
        for e in self.all_edges(t) {
            to_t[self.head(e)] = self.rev(e);
        }
        for &(u, v, d) in paths {
            let (e0, e2) = (from_s[u], to_t[v]);
            if e0 == usize::MAX || e2 == usize::MAX {
                continue;
            }
            // The forward edge u → v (only forward edges leave a left node towards the right).
            let Some(e1) = self.all_edges(u).find(|&e| self.head(e) == v) else {
                continue;
            };
            let d = d
                .min(self.residual(e0))
                .min(self.residual(e1))
                .min(self.residual(e2));
            if d == 0 {
                continue;
            }
            for e in [e0, e1, e2] {
                self.push(e, d);
            }
        }
    }

    /// Greedy start for a three-layer network (s → left → right → t): push along every
    /// s-u-v-t path while capacity remains. On mechanisms listed in build order this finds
    /// almost all the flow, leaving few and short augmenting paths.
    ///
    /// The residual capacity of each edge v → t is kept in a small array while it runs (and
    /// written to the edge and its pair in one pass at the end): read and pushed on the edges
    /// themselves, each push made three scattered reads and two scattered writes more at 10^6
    /// bodies. The same pushes in the same order, so the same flow: no other edge the greedy
    /// start reads or pushes is an edge v → t or its pair unless s and t are one node or
    /// joined by an edge, or t has an edge to itself; then the edges are used directly.
    ///
    /// In a network [`Network::three_layer`] built, from node 0 to node 1, the pair of each
    /// middle edge (left → right, at the right node) is written after the loop too: it is
    /// never read by the loop (no right node is a head of a source edge), and an edge and its
    /// pair hold [`INF`] together (it starts at `INF`, its pair at 0, and a push moves units
    /// from one to the other), so the pair of every middle edge that carries flow is `INF`
    /// less the edge's residual. Written in edge order: the edges are read front to back and
    /// their pairs are only stored to, where each path read and wrote its pair at the body (a
    /// scattered read and write in the 140 MB edge array at 10^6 bodies).
    ///
    /// Returns the units it pushed.
    pub(crate) fn greedy(&mut self, s: usize, t: usize) -> u64 {
        const NONE: u32 = u32::MAX;
        let deferred = s != t
            && self.all_edges(s).all(|e| self.head(e) != t)
            && self.all_edges(t).all(|e| self.head(e) != t);
        let middle_deferred = deferred && self.nl > 0 && s == 0 && t == 1;
        // Per node from the first with an edge to t (for a three-layer network the right
        // nodes, the last ones: 8 bytes a body, not a node): the edge v -> t, and its
        // residual capacity while deferred.
        let lo = self.all_edges(t).map(|e| self.head(e)).min().unwrap_or(0);
        let hi = self
            .all_edges(t)
            .map(|e| self.head(e) + 1)
            .max()
            .unwrap_or(0);
        let mut to_sink = vec![[NONE, 0]; hi.saturating_sub(lo)];
        for e in self.all_edges(t) {
            // e goes t -> v; its pair is the edge v -> t. (An implicit edge's index past
            // `u32` cannot occur: the network it was counted in had as many slots.)
            let e2 = self.rev(e);
            to_sink[self.head(e) - lo] = [u32::try_from(e2).unwrap_or(NONE), self.residual(e2)];
        }
        let mut total = 0u64;
        for e0 in self.all_edges(s) {
            let u = self.head(e0);
            for e1 in self.all_edges(u) {
                if self.residual(e0) == 0 {
                    break;
                }
                let (v, c1) = (self.head(e1), self.residual(e1));
                let Some(&[e2, room]) = v.checked_sub(lo).and_then(|i| to_sink.get(i)) else {
                    continue;
                };
                if v == s || e2 == NONE || c1 == 0 {
                    continue;
                }
                let e2 = e2 as usize;
                let room = if deferred { room } else { self.residual(e2) };
                let d = self.residual(e0).min(c1).min(room);
                if d == 0 {
                    continue;
                }
                self.push(e0, d);
                if middle_deferred {
                    // A middle edge is explicit; its pair is written after the loop.
                    *self.residual_mut(e1) -= d;
                } else {
                    self.push(e1, d);
                }
                if deferred {
                    to_sink[v - lo][1] -= d;
                } else {
                    self.push(e2, d);
                }
                total += d as u64;
            }
        }
        if middle_deferred {
            for x in 2..2 + self.nl {
                for e in self.edges(x) {
                    let c = self.arc[e].cap;
                    if c < INF {
                        let r = self.rev[e] as usize;
                        self.arc[r].cap = INF - c;
                    }
                }
            }
        }
        if deferred {
            // In node order: for a network `three_layer` built, the edges v -> t in order
            // and their pairs at t in order too.
            for [e2, room] in to_sink {
                if e2 != NONE {
                    let d = self.residual(e2 as usize) - room;
                    if d > 0 {
                        self.push(e2 as usize, d);
                    }
                }
            }
        }
        total
    }

    /// Push the maximum flow from `s` to `t`; returns its value.
    pub(crate) fn max_flow(&mut self, s: usize, t: usize) -> u64 {
        self.max_flow_cut(s, t).0
    }

    /// Push the maximum flow from `s` to `t`; returns its value and the nodes reachable from
    /// `s` in the residual network (what [`Network::reachable_from`] would give: the last
    /// breadth-first search, the one that finds no path to `t`, has just visited them).
    ///
    /// A greedy start, then Dinic's phases: a breadth-first search labels the nodes by their
    /// distance from `s` in the residual network, and a depth-first search with a current-edge
    /// pointer per node pushes a blocking flow along shortest paths, retiring every dead end
    /// for the rest of the phase. Each phase costs O(edges) and lengthens the shortest
    /// augmenting path, so a few phases finish the flow the greedy start leaves (the previous
    /// method ran one search per missing unit of flow).
    pub(crate) fn max_flow_cut(&mut self, s: usize, t: usize) -> (u64, Vec<bool>) {
        let total = self.greedy(s, t);
        self.max_flow_after_greedy(s, t, total)
    }

    /// [`Network::max_flow_cut`] after its greedy start has been pushed (by
    /// [`Network::greedy`], or while [`Network::three_layer_greedy`] built the
    /// network) and gave `total` units: Dinic's phases, and the nodes reachable from `s`.
    pub(crate) fn max_flow_after_greedy(
        &mut self,
        s: usize,
        t: usize,
        mut total: u64,
    ) -> (u64, Vec<bool>) {
        let n = self.nodes();
        if s == t {
            return (total, self.reachable_from(s));
        }
        let mut phase = DinicPhase::new(n);
        loop {
            let scanned = self.label_levels(s, t, &mut phase);
            if phase.level[t] == DinicPhase::UNSEEN {
                // This search ran to the end: it labelled exactly the nodes reachable from s
                // (the labels of earlier phases were cleared before it).
                self.scan(scanned);
                return (total, (0..n).map(|x| bit(&phase.seen, x)).collect());
            }
            total += self.blocking_flow(s, t, &mut phase);
        }
    }

    /// The levels of one Dinic phase: distance from `s` in the residual network, up to
    /// `t`'s, the labelled nodes in `phase.queue` by level (the previous phase's labels
    /// cleared first). Returns the edges scanned.
    fn label_levels(&self, s: usize, t: usize, phase: &mut DinicPhase) -> usize {
        const UNSEEN: u32 = DinicPhase::UNSEEN;
        let DinicPhase {
            level,
            seen,
            fresh,
            queue,
            ..
        } = phase;
        for &x in queue.iter() {
            level[x as usize] = UNSEEN;
            seen[x as usize / 64] = 0;
            fresh[x as usize / 64] = 0;
        }
        queue.clear();
        level[s] = 0;
        seen[s / 64] |= 1 << (s % 64);
        fresh[s / 64] |= 1 << (s % 64);
        queue.push(s as u32);
        let mut scanned = 0;
        // A level at a time: the level's nodes are `queue[lo..hi]`, scanned in ascending
        // order (their edges are then read front to back through the edge array, not in
        // the scattered order they were found in). The labels are the same: a node's
        // level is its distance from s, whatever order a level is scanned in.
        let (mut lx, mut lo) = (0u32, 0usize);
        while lo < queue.len() {
            if level[t] != UNSEEN && lx >= level[t] {
                break;
            }
            let hi = queue.len();
            ascending(&mut queue[lo..hi], fresh);
            let lx1 = lx + 1;
            for qi in lo..hi {
                let x = queue[qi] as usize;
                scanned += self.degree(x);
                // The implicit edges first (node 0's, or a left node's back to it), as the
                // edge list orders them. Whether the head is labelled is tested first: for
                // a left node's edge back to the source that spares a scattered read.
                let (first, k) = self.implicit(x);
                for e in first..first + k {
                    let v = self.head(e);
                    if !bit(seen, v) && self.residual(e) > 0 {
                        seen[v / 64] |= 1 << (v % 64);
                        fresh[v / 64] |= 1 << (v % 64);
                        level[v] = lx1;
                        queue.push(v as u32);
                    }
                }
                for a in &self.arc[self.edges(x)] {
                    let v = a.to as usize;
                    if a.cap > 0 && !bit(seen, v) {
                        seen[v / 64] |= 1 << (v % 64);
                        fresh[v / 64] |= 1 << (v % 64);
                        level[v] = lx1;
                        queue.push(v as u32);
                    }
                }
            }
            lo = hi;
            lx = lx1;
        }
        scanned
    }

    /// The blocking flow of one Dinic phase: advance along level-increasing edges, augment
    /// at `t`, retreat from dead ends (a retreated node is taken out of the phase). Returns
    /// the flow pushed.
    fn blocking_flow(&mut self, s: usize, t: usize, phase: &mut DinicPhase) -> u64 {
        const UNSEEN: u32 = DinicPhase::UNSEEN;
        let DinicPhase {
            level,
            next,
            queue,
            path,
            ..
        } = phase;
        // Each node's current edge, as a position in its list of edges (implicit ones
        // first).
        for &x in queue.iter() {
            next[x as usize] = 0;
        }
        path.clear();
        let mut pushed = 0u64;
        let mut u = s;
        loop {
            if u == t {
                let d = path.iter().map(|&e| self.residual(e)).min().unwrap_or(0);
                for &e in path.iter() {
                    self.push(e, d);
                }
                pushed += u64::from(d);
                let k = path
                    .iter()
                    .position(|&e| self.residual(e) == 0)
                    .unwrap_or(0);
                path.truncate(k);
                u = match path.last() {
                    Some(&e) => self.head(e),
                    None => s,
                };
                continue;
            }
            let (first, k) = self.implicit(u);
            let base = self.start[u] as usize;
            let end = (k + self.edges(u).len()) as u32;
            let mut advanced = false;
            while next[u] < end {
                let i = next[u] as usize;
                let (e, v, cap) = if i < k {
                    let e = first + i;
                    (e, self.head(e), self.residual(e))
                } else {
                    let e = base + (i - k);
                    let a = self.arc[e];
                    (e, a.to as usize, a.cap)
                };
                if cap > 0 && level[v] != UNSEEN && level[v] == level[u] + 1 {
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
                    u = self.head(self.rev(e));
                    next[u] += 1;
                }
                None => break,
            }
        }
        pushed
    }

    /// The flow's value from node 0 of a network [`Network::three_layer`] built: what its
    /// implicit source edges carry (0 for any other network).
    pub(crate) fn source_outflow(&self) -> u64 {
        let m = self.arc.len() - self.nl;
        self.arc[m..].iter().map(|a| u64::from(a.cap)).sum()
    }

    /// Nodes reachable from `s` through edges with residual capacity.
    pub(crate) fn reachable_from(&self, s: usize) -> Vec<bool> {
        let mut seen = vec![false; self.nodes()];
        let mut stack = vec![s];
        seen[s] = true;
        while let Some(u) = stack.pop() {
            self.scan(self.degree(u));
            let (first, k) = self.implicit(u);
            for e in first..first + k {
                let v = self.head(e);
                if self.residual(e) > 0 && !seen[v] {
                    seen[v] = true;
                    stack.push(v);
                }
            }
            for a in &self.arc[self.edges(u)] {
                let v = a.to as usize;
                if a.cap > 0 && !seen[v] {
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
        // In a network `three_layer` built, an edge between two left or right nodes (a
        // middle edge or its pair) and its pair hold [`INF`] together (see `greedy`): the
        // pair's residual is read off the edge itself, not where the pair lies in the edge
        // array (a scattered read an edge, at every body the search visits).
        let three_layer = self.nl > 0;
        while let Some(v) = stack.pop() {
            self.scan(self.degree(v));
            for e in self.all_edges(v) {
                // Edge e goes v -> u; its pair goes u -> v.
                let u = self.head(e);
                if seen[u] {
                    continue;
                }
                let back = if three_layer && v >= 2 && u >= 2 {
                    INF - self.residual(e)
                } else {
                    self.reverse_residual(e)
                };
                debug_assert_eq!(back, self.reverse_residual(e), "edge {e}");
                if back > 0 {
                    seen[u] = true;
                    stack.push(u);
                }
            }
        }
        seen
    }
}

/// Put the nodes of one breadth-first level in ascending order; `fresh` has exactly their
/// bits set, and has none set after. A level spread over few words is read back from the
/// bits in order; a sparse one is sorted.
fn ascending(nodes: &mut [u32], fresh: &mut [u64]) {
    let Some((lo, hi)) = nodes
        .iter()
        .fold(None, |r: Option<(u32, u32)>, &x| match r {
            None => Some((x, x)),
            Some((a, b)) => Some((a.min(x), b.max(x))),
        })
    else {
        return;
    };
    let words = lo as usize / 64..hi as usize / 64 + 1;
    if words.len() <= 8 * nodes.len() {
        let mut i = 0;
        for w in words {
            let mut bits = std::mem::take(&mut fresh[w]);
            while bits != 0 {
                if let Some(slot) = nodes.get_mut(i) {
                    *slot = (w * 64) as u32 + bits.trailing_zeros();
                }
                i += 1;
                bits &= bits - 1;
            }
        }
        debug_assert_eq!(i, nodes.len(), "one bit a node of the level");
    } else {
        nodes.sort_unstable();
        for &x in nodes.iter() {
            fresh[x as usize / 64] &= !(1u64 << (x % 64));
        }
    }
}

/// Whether node `x` is set in a bit set of one bit a node.
fn bit(seen: &[u64], x: usize) -> bool {
    seen[x / 64] >> (x % 64) & 1 != 0
}

/// The labels of a Dinic phase ([`Network::max_flow_after_greedy`]), kept from phase to
/// phase.
struct DinicPhase {
    /// Each node's level ([`DinicPhase::UNSEEN`]: not labelled).
    level: Vec<u32>,
    /// Whether a node is labelled in this search, one bit a node (445 KB at 10^6 bodies,
    /// where `level` is 14 MB): the test of every edge's head stays in cache.
    seen: Vec<u64>,
    /// The nodes labelled but not yet put in order, one bit a node (see [`ascending`]).
    fresh: Vec<u64>,
    /// Each node's current edge in the blocking flow.
    next: Vec<u32>,
    /// Nodes in order of their levels (a node's level is not read back from `level`: the
    /// search knows where each level ends in the queue). Four bytes a node: the queue holds
    /// most nodes while the network is at its largest. Reserved at once: grown by doubling,
    /// its earlier buffers were touched and freed too (12 MB more of the heap at 10^6
    /// bodies); untouched room costs no pages.
    queue: Vec<u32>,
    /// The edges of the path being advanced.
    path: Vec<usize>,
}

impl DinicPhase {
    const UNSEEN: u32 = u32::MAX;

    fn new(n: usize) -> DinicPhase {
        DinicPhase {
            level: vec![Self::UNSEEN; n],
            seen: vec![0u64; n.div_ceil(64)],
            fresh: vec![0u64; n.div_ceil(64)],
            next: vec![0u32; n],
            queue: Vec::with_capacity(n),
            path: Vec::new(),
        }
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
            let (got, side) = net.max_flow_cut(0, 1);
            assert_eq!(got, want, "round {round}: {edges:?}");
            // The residual network has no augmenting path left, and the source side the
            // flow returns is what a search of the residual network finds.
            assert!(!side[1]);
            assert_eq!(side, net.reachable_from(0), "round {round}: {edges:?}");
        }
    }

    /// The count's network built directly is the one built from its edge list: same edges
    /// at every node in the same order (so the same flow).
    #[test]
    fn three_layer_is_the_edge_list_network() {
        let mut rng = crate::rng::SplitMix64::new(11);
        for round in 0..300 {
            let (left, ends, right, want) = random_three_layer(&mut rng);
            let l = left.len();
            let got = Network::three_layer(&left, |i| ends[i], &right);
            assert_eq!(listing(&got), listing(&want), "round {round}");
            assert_eq!(got.nl, l, "round {round}: source edges implicit");
            assert_eq!(got.rev.len() + 2 * l, want.rev.len(), "round {round}");
        }
    }

    /// Every node's edges in order (implicit ones included), each as its head, its
    /// residual capacity and the place of its pair in this listing: two networks with the
    /// same listing are the same network, whatever edges they keep implicit.
    fn listing(n: &Network) -> Vec<(usize, usize, u32, usize)> {
        let order: Vec<usize> = (0..n.nodes()).flat_map(|u| n.all_edges(u)).collect();
        let mut place = std::collections::HashMap::new();
        for (i, &e) in order.iter().enumerate() {
            place.insert(e, i);
        }
        (0..n.nodes())
            .flat_map(|u| n.all_edges(u).map(move |e| (u, e)))
            .map(|(u, e)| (u, n.head(e), n.residual(e), place[&n.rev(e)]))
            .collect()
    }

    /// Fewer than `count` random warm-start paths `(left, right, units)` on nodes below `n`,
    /// each of fewer than `units` units (the draws in that order, so the tests' networks stay
    /// the ones they were written with).
    fn random_paths(
        rng: &mut crate::rng::SplitMix64,
        n: usize,
        count: u64,
        units: u64,
    ) -> Vec<(usize, usize, u32)> {
        (0..rng.below(count))
            .map(|_| {
                (
                    rng.below(n as u64) as usize,
                    rng.below(n as u64) as usize,
                    rng.below(units) as u32,
                )
            })
            .collect()
    }

    /// A random three-layer network as the count builds it: left capacities, each left
    /// node's two right ends (`u32::MAX`: none), right capacities (`u32::MAX`: no edge to
    /// t), and the same network from its edge list.
    fn random_three_layer(
        rng: &mut crate::rng::SplitMix64,
    ) -> (Vec<u32>, Vec<[u32; 2]>, Vec<u32>, Network) {
        let (l, r) = (rng.below(14) as usize, 1 + rng.below(12) as usize);
        let none = u32::MAX;
        let pick = |rng: &mut crate::rng::SplitMix64| match rng.below(5) {
            0 => none,
            _ => rng.below(r as u64) as u32,
        };
        let left: Vec<u32> = (0..l).map(|_| rng.below(7) as u32).collect();
        let ends: Vec<[u32; 2]> = (0..l).map(|_| [pick(rng), pick(rng)]).collect();
        let right: Vec<u32> = (0..r)
            .map(|_| match rng.below(6) {
                0 => none,
                c => c as u32,
            })
            .collect();
        let rnode = |j: u32| (2 + l) as u32 + j;
        let mut edges = Vec::new();
        for i in 0..l {
            let x = 2 + i as u32;
            edges.push((0, x, left[i]));
            let [a, b] = ends[i];
            if a != none {
                edges.push((x, rnode(a), INF));
            }
            if b != none && b != a {
                edges.push((x, rnode(b), INF));
            }
        }
        for (j, &c) in right.iter().enumerate() {
            if c != none {
                edges.push((rnode(j as u32), 1, c));
            }
        }
        let net = Network::new(2 + l + r, &edges);
        (left, ends, right, net)
    }

    /// With its source edges implicit, a three-layer network finds the flow of the same
    /// network with every edge explicit, edge for edge: value, both sides of the cut, every
    /// residual capacity and the edges the searches examined, warm-started or not (the
    /// count prints which pairs keep unsaturated equations).
    #[test]
    fn implicit_source_edges_give_the_same_flow() {
        let mut rng = crate::rng::SplitMix64::new(17);
        for round in 0..3000 {
            let (left, ends, right, mut want) = random_three_layer(&mut rng);
            let mut got = Network::three_layer(&left, |i| ends[i], &right);
            let n = want.nodes();
            if round % 3 == 0 {
                let paths = random_paths(&mut rng, n, 8, 5);
                got.warm(0, 1, &paths);
                want.warm(0, 1, &paths);
            }
            let (s, t) = match round % 11 {
                0 => (0, 0),
                1 => (1, 0),
                2 => (2 + left.len() / 2, 1),
                _ => (0, 1),
            };
            assert_eq!(
                got.max_flow_cut(s, t),
                want.max_flow_cut(s, t),
                "round {round}"
            );
            assert_eq!(listing(&got), listing(&want), "round {round}");
            for x in [0, 1, n - 1] {
                assert_eq!(got.reaching(x), want.reaching(x), "round {round}");
                assert_eq!(
                    got.reachable_from(x),
                    want.reachable_from(x),
                    "round {round}"
                );
            }
            assert_eq!(got.scanned(), want.scanned(), "round {round}");
        }
    }

    /// The maximum flow as it was before the greedy start kept the sink edges aside and the
    /// breadth-first search its labels in a bit set: the reference the flow must equal
    /// edge for edge (the diagnosis prints which pairs keep unsaturated equations).
    fn reference_flow_cut(net: &mut Network, s: usize, t: usize) -> (u64, Vec<bool>) {
        const NONE: u32 = u32::MAX;
        const UNSEEN: u32 = u32::MAX;
        let n = net.nodes();
        let mut to_sink = vec![NONE; n];
        for e in net.edges(t) {
            to_sink[net.head(e)] = net.rev[e];
        }
        let mut total = 0u64;
        for e0 in net.edges(s) {
            let u = net.head(e0);
            for e1 in net.edges(u) {
                if net.arc[e0].cap == 0 {
                    break;
                }
                let Arc { to: v, cap: c1 } = net.arc[e1];
                let e2 = to_sink[v as usize];
                if v as usize == s || e2 == NONE || c1 == 0 {
                    continue;
                }
                let e2 = e2 as usize;
                let d = net.arc[e0].cap.min(c1).min(net.arc[e2].cap);
                if d == 0 {
                    continue;
                }
                for e in [e0, e1, e2] {
                    net.push(e, d);
                }
                total += d as u64;
            }
        }
        if s == t {
            return (total, net.reachable_from(s));
        }
        let mut level = vec![UNSEEN; n];
        let mut next = vec![0u32; n];
        let mut queue: Vec<usize> = Vec::new();
        let mut path: Vec<usize> = Vec::new();
        loop {
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
                let lx = level[x] + 1;
                for a in &net.arc[net.edges(x)] {
                    let v = a.to as usize;
                    if a.cap > 0 && level[v] == UNSEEN {
                        level[v] = lx;
                        queue.push(v);
                    }
                }
            }
            if level[t] == UNSEEN {
                return (total, level.iter().map(|&l| l != UNSEEN).collect());
            }
            for &x in &queue {
                next[x] = net.start[x];
            }
            path.clear();
            let mut u = s;
            loop {
                if u == t {
                    let d = path.iter().map(|&e| net.arc[e].cap).min().unwrap_or(0);
                    for &e in &path {
                        net.push(e, d);
                    }
                    total += u64::from(d);
                    let k = path.iter().position(|&e| net.arc[e].cap == 0).unwrap_or(0);
                    path.truncate(k);
                    u = match path.last() {
                        Some(&e) => net.head(e),
                        None => s,
                    };
                    continue;
                }
                let end = net.start[u + 1];
                let mut advanced = false;
                while next[u] < end {
                    let e = next[u] as usize;
                    let Arc { to: v, cap } = net.arc[e];
                    let v = v as usize;
                    if cap > 0 && level[v] != UNSEEN && level[v] == level[u] + 1 {
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
                level[u] = UNSEEN;
                match path.pop() {
                    Some(e) => {
                        u = net.head(net.rev[e] as usize);
                        next[u] += 1;
                    }
                    None => break,
                }
            }
        }
    }

    fn arcs(n: &Network) -> Vec<(u32, u32)> {
        n.arc.iter().map(|a| (a.to, a.cap)).collect()
    }

    /// A random network: three layers as the count builds them, or (`wild`) with arbitrary
    /// extra edges, sometimes one from s to t.
    fn random_network(
        rng: &mut crate::rng::SplitMix64,
        wild: bool,
    ) -> (usize, Vec<(u32, u32, u32)>) {
        let (l, r) = (1 + rng.below(12) as u32, 1 + rng.below(12) as u32);
        let n = 2 + l + r;
        let mut edges = Vec::new();
        for a in 0..l {
            edges.push((0, 2 + a, rng.below(6) as u32));
            for b in 0..r {
                if rng.below(3) == 0 {
                    edges.push((2 + a, 2 + l + b, INF));
                }
            }
        }
        for b in 0..r {
            edges.push((2 + l + b, 1, rng.below(6) as u32));
        }
        if wild {
            for _ in 0..rng.below(8) {
                let (u, v) = (
                    rng.below(u64::from(n)) as u32,
                    rng.below(u64::from(n)) as u32,
                );
                // As in `phases_match_a_reference_on_random_networks` (the greedy start
                // pushes twice along an edge that is both a path's first and last one).
                if u != v && u != 1 && v != 0 {
                    edges.push((u, v, 1 + rng.below(4) as u32));
                }
            }
            if rng.below(2) == 0 {
                edges.push((0, 1, 1 + rng.below(4) as u32));
            }
        }
        (n as usize, edges)
    }

    /// The flow is the reference's edge for edge: every residual capacity, the value and the
    /// source side, on count networks and on networks where the greedy start cannot keep the
    /// sink edges aside (s joined to t, s = t), warm-started or not.
    #[test]
    fn flow_is_the_reference_edge_for_edge() {
        let mut rng = crate::rng::SplitMix64::new(13);
        for round in 0..2000 {
            let (n, edges) = random_network(&mut rng, round % 2 == 1);
            let mut net = Network::new(n, &edges);
            if round % 5 == 0 {
                let paths = random_paths(&mut rng, n, 6, 4);
                net.warm(0, 1, &paths);
            }
            let (s, t) = if round % 7 == 0 { (0, 0) } else { (0, 1) };
            let mut want = net.clone();
            let w = reference_flow_cut(&mut want, s, t);
            let g = net.max_flow_cut(s, t);
            assert_eq!(g, w, "round {round} s {s} t {t}: {edges:?}");
            assert_eq!(
                arcs(&net),
                arcs(&want),
                "round {round} s {s} t {t}: {edges:?}"
            );
        }
    }

    /// The breadth-first search scans each level in ascending node order: the same levels,
    /// so the same flow edge for edge as the reference's search in the order the nodes were
    /// found, on networks large enough for Dinic's phases to run after the greedy start and
    /// for a level's nodes to lie far apart (the sorted case of [`ascending`]).
    #[test]
    fn levels_in_node_order_give_the_reference_flow() {
        let mut rng = crate::rng::SplitMix64::new(23);
        let mut phases = 0;
        for round in 0..60 {
            let (l, r) = (50 + rng.below(3_000) as u32, 20 + rng.below(1_000) as u32);
            let n = 2 + l + r;
            let mut edges = Vec::new();
            for a in 0..l {
                edges.push((0, 2 + a, rng.below(7) as u32));
                for _ in 0..rng.below(4) {
                    edges.push((2 + a, 2 + l + rng.below(u64::from(r)) as u32, INF));
                }
            }
            for b in 0..r {
                edges.push((2 + l + b, 1, rng.below(9) as u32));
            }
            if round % 2 == 1 {
                // Back edges between the right and left layers: longer augmenting paths.
                for _ in 0..rng.below(200) {
                    let (u, v) = (
                        2 + l + rng.below(u64::from(r)) as u32,
                        2 + rng.below(u64::from(l)) as u32,
                    );
                    edges.push((u, v, 1 + rng.below(3) as u32));
                }
            }
            let mut net = Network::new(n as usize, &edges);
            if round % 3 == 0 {
                // A poor start: unit paths to the last right nodes first.
                let paths: Vec<(usize, usize, u32)> = (0..rng.below(500))
                    .map(|_| {
                        (
                            2 + rng.below(u64::from(l)) as usize,
                            (2 + l + r - 1 - rng.below(u64::from(r) / 4 + 1) as u32) as usize,
                            1,
                        )
                    })
                    .collect();
                net.warm(0, 1, &paths);
            }
            let mut want = net.clone();
            let w = reference_flow_cut(&mut want, 0, 1);
            let mut greedy = net.clone();
            if greedy.greedy(0, 1) < w.0 {
                phases += 1;
            }
            assert_eq!(net.max_flow_cut(0, 1), w, "round {round}");
            assert_eq!(arcs(&net), arcs(&want), "round {round}");
        }
        assert!(phases > 20, "only {phases} networks needed Dinic's phases");
    }

    /// [`ascending`] orders a level and clears its bits, from the bits (dense levels) or by
    /// sorting (sparse ones).
    #[test]
    fn ascending_orders_a_level_and_clears_its_bits() {
        let mut rng = crate::rng::SplitMix64::new(29);
        for round in 0..500 {
            let n = 1 + rng.below(20_000) as usize;
            let k = match round % 3 {
                0 => rng.below(8) as usize,
                1 => rng.below(n as u64 / 50 + 1) as usize,
                _ => rng.below(n as u64) as usize,
            };
            let mut fresh = vec![0u64; n.div_ceil(64)];
            let mut nodes = Vec::new();
            for _ in 0..k {
                let x = rng.below(n as u64) as usize;
                if fresh[x / 64] >> (x % 64) & 1 == 0 {
                    fresh[x / 64] |= 1 << (x % 64);
                    nodes.push(x as u32);
                }
            }
            let mut want = nodes.clone();
            want.sort_unstable();
            ascending(&mut nodes, &mut fresh);
            assert_eq!(nodes, want, "round {round}");
            assert!(fresh.iter().all(|&w| w == 0), "round {round}");
        }
    }

    /// A three-layer network of 3,000 left nodes (1-6 units, two random ends each) and 1,000
    /// right nodes of 6 units, several left nodes feeding each right one: (left units, ends,
    /// right units).
    fn dense_three_layer() -> (Vec<u32>, Vec<[u32; 2]>, Vec<u32>) {
        let mut rng = crate::rng::SplitMix64::new(19);
        let (l, r) = (3_000usize, 1_000usize);
        let left: Vec<u32> = (0..l).map(|_| 1 + rng.below(6) as u32).collect();
        let ends: Vec<[u32; 2]> = (0..l)
            .map(|_| [rng.below(r as u64) as u32, rng.below(r as u64) as u32])
            .collect();
        (left, ends, vec![6u32; r])
    }

    /// Work regression: the greedy start updates each edge to t once, not at every push
    /// through it, and the pairs of the middle edges after its loop (a three-layer network of
    /// 3,000 left and 1,000 right nodes, several left nodes feeding each right one, with and
    /// without a warm start): one push a path plus one per edge to t used, where each path
    /// pushed along its middle edge too (2 a path; formerly 3 with the edge to
    /// t); the flow is the three-edge pushes', edge for edge.
    #[test]
    fn greedy_updates_each_sink_edge_once() {
        let (left, ends, right) = dense_three_layer();
        let l = left.len();
        for warm in [false, true] {
            let mut net = Network::three_layer(&left, |i| ends[i], &right);
            if warm {
                // Some flow already on the middle edges (and on their pairs).
                let paths: Vec<(usize, usize, u32)> = (0..l / 3)
                    .map(|i| (2 + i, 2 + l + ends[i][0] as usize, 1))
                    .collect();
                net.warm(0, 1, &paths);
            }
            let mut want = net.clone();
            let before = PUSHES.with(|p| p.get());
            let total = net.greedy(0, 1);
            let pushes = PUSHES.with(|p| p.get()) - before;
            // Paths: middle edges given flow by the greedy start (each at most once).
            let paths = (2..2 + l)
                .flat_map(|x| net.edges(x))
                .filter(|&e| net.residual(e) < want.residual(e))
                .count() as u64;
            let used = net
                .edges(1)
                .filter(|&e| net.residual(e) > want.residual(e))
                .count() as u64;
            // Several paths through most edges to t (fewer after the warm start's).
            let shared = if warm { used } else { 2 * used };
            assert!(paths > shared, "{paths} paths through {used} edges to t");
            // One push a path (its source edge) and one a sink edge: the middle edges'
            // pairs are written after the loop, the sink edges' at its end.
            assert_eq!(pushes, paths + used, "{paths} paths, {used} edges to t");
            // The same flow as pushing along all three edges at once.
            let mut refer = 0;
            let mut to_sink = vec![u32::MAX; want.nodes()];
            for e in want.all_edges(1) {
                to_sink[want.head(e)] = want.rev(e) as u32;
            }
            for e0 in want.all_edges(0) {
                let u = want.head(e0);
                for e1 in want.all_edges(u) {
                    let v = want.head(e1);
                    let e2 = to_sink[v];
                    if v == 0 || e2 == u32::MAX {
                        continue;
                    }
                    let d = want
                        .residual(e0)
                        .min(want.residual(e1))
                        .min(want.residual(e2 as usize));
                    if d > 0 {
                        for e in [e0, e1, e2 as usize] {
                            want.push(e, d);
                        }
                        refer += u64::from(d);
                    }
                }
            }
            assert_eq!(total, refer, "warm {warm}");
            assert_eq!(listing(&net), listing(&want), "warm {warm}");
        }
    }

    /// The greedy start pushed while the network is built leaves the network `three_layer`
    /// then the greedy start leave, residual for residual, with the same value; the rest of
    /// the flow then finds the same flow, source side and searches (random three-layer
    /// networks, some needing Dinic's phases after the greedy start, and the 3,000-node one
    /// above, several left nodes to a right one).
    #[test]
    fn greedy_while_built_is_the_greedy_start() {
        let mut rng = crate::rng::SplitMix64::new(23);
        let mut phases = 0;
        for round in 0..3000 {
            let (left, ends, right, _) = random_three_layer(&mut rng);
            let (mut got, total) = Network::three_layer_greedy(&left, |i| ends[i], &right);
            let mut want = Network::three_layer(&left, |i| ends[i], &right);
            assert_eq!(total, want.greedy(0, 1), "round {round}");
            assert_eq!(listing(&got), listing(&want), "round {round}");
            assert_eq!(got.source_outflow(), total, "round {round}");
            let cut = got.max_flow_after_greedy(0, 1, total);
            assert_eq!(
                cut,
                want.max_flow_after_greedy(0, 1, total),
                "round {round}"
            );
            assert_eq!(listing(&got), listing(&want), "round {round}");
            assert_eq!(got.scanned(), want.scanned(), "round {round}");
            assert_eq!(got.source_outflow(), cut.0, "round {round}");
            phases += usize::from(cut.0 > total);
        }
        assert!(
            phases > 100,
            "{phases} networks needed more than the greedy start"
        );
        let (left, ends, right) = dense_three_layer();
        let (got, total) = Network::three_layer_greedy(&left, |i| ends[i], &right);
        let mut want = Network::three_layer(&left, |i| ends[i], &right);
        assert_eq!(total, want.greedy(0, 1));
        assert_eq!(listing(&got), listing(&want));
    }
}
