//! The count decomposition: maximum flow from joint equations to body unknowns, the
//! Dulmage–Mendelsohn split of the residual graph, and the strongly connected components of
//! the well-determined part (the structural groups) with their levels.

use super::flow::{INF, Network};
use crate::mechanism::Mechanism;

/// The equation nodes. A binary joint is one pair carrying `B − k` constraint equations plus
/// its driven DOF. A multiple joint of n ≥ 3 bodies is modelled symmetrically, so that nothing
/// depends on the order in which it lists its bodies: an *element node* (index `nb + i`, the
/// shared pin, axis or centre; `B − k` unknowns, its pose less the joint's own motion) and n
/// pairs element→body of `B − k` equations each; its driven DOF are *input pairs* between its
/// first listed body and the others in order (at most k each), carrying only the inputs.
#[derive(Clone, Debug)]
pub(crate) struct Equations {
    /// Joint index of each pair.
    pub joint: Vec<usize>,
    /// First node (a body, or the element node of a multiple joint).
    pub hub: Vec<usize>,
    /// Other body index.
    pub other: Vec<usize>,
    /// Number of equations (after any lowering by the rank check).
    pub cap: Vec<u32>,
    /// Driven DOF carried by this pair.
    pub driven: Vec<u32>,
    /// Whether the pair carries only a multiple joint's inputs (no constraint equations).
    pub input_only: Vec<bool>,
    /// Body nodes and element nodes: `bodies + elements.len()`.
    pub nodes: usize,
    /// The joint of each element node (node `bodies + i` is the element of `elements[i]`).
    pub elements: Vec<usize>,
    /// Number of bodies (element nodes come after them).
    pub bodies: usize,
    /// A flow to start the maximum flow from (units of each pair into its hub and its other
    /// node), or empty. Only a warm start: the decomposition is the same without it.
    pub hint: Vec<[u32; 2]>,
}

impl Equations {
    /// The pairs of `m`.
    pub fn of(m: &Mechanism) -> Equations {
        let b = m.b();
        let nb = m.bodies.len();
        let mut e = Equations {
            joint: Vec::new(),
            hub: Vec::new(),
            other: Vec::new(),
            cap: Vec::new(),
            driven: Vec::new(),
            input_only: Vec::new(),
            nodes: nb,
            elements: Vec::new(),
            bodies: nb,
            hint: Vec::new(),
        };
        for (ji, j) in m.joints.iter().enumerate() {
            let k = j.grade();
            let Some((&first, others)) = j.bodies.split_first() else {
                continue;
            };
            if others.len() == 1 {
                e.push(
                    ji,
                    first,
                    others[0],
                    b.saturating_sub(k) + j.driven,
                    j.driven,
                    false,
                );
                continue;
            }
            let node = e.nodes;
            e.nodes += 1;
            e.elements.push(ji);
            // Pairs in body order, not listing order: nothing downstream (flow, rank check
            // numerics, tie-breaks) may see the order in which the file lists the bodies.
            let mut sorted = j.bodies.clone();
            sorted.sort_unstable();
            for x in sorted {
                e.push(ji, node, x, b.saturating_sub(k), 0, false);
            }
            // Inputs between the first listed body and the others in order; the last pair
            // takes whatever is left so no driven DOF is lost.
            let mut left = j.driven;
            let n = others.len();
            for (p, &o) in others.iter().enumerate() {
                if left == 0 {
                    break;
                }
                let share = if p + 1 == n { left } else { left.min(k) };
                left -= share;
                e.push(ji, first, o, share, share, true);
            }
        }
        e
    }

    fn push(&mut self, joint: usize, hub: usize, other: usize, cap: u32, driven: u32, input: bool) {
        self.joint.push(joint);
        self.hub.push(hub);
        self.other.push(other);
        self.cap.push(cap);
        self.driven.push(driven);
        self.input_only.push(input);
    }

    /// Unknowns of every node before the rank check: B per movable body, 0 for the frame,
    /// `B − k` per element node.
    pub fn unknowns(&self, m: &Mechanism) -> Vec<u32> {
        let b = m.b();
        let mut u = vec![b; self.nodes];
        if let Some(f) = u.get_mut(m.frame) {
            *f = 0;
        }
        for (i, &ji) in self.elements.iter().enumerate() {
            u[self.bodies + i] = b.saturating_sub(m.joints[ji].grade());
        }
        u
    }

    /// Whether node `x` is an element node (not a body).
    pub fn is_element(&self, x: usize) -> bool {
        x >= self.bodies
    }

    /// The joint whose element node `x` is.
    pub fn element_joint(&self, x: usize) -> usize {
        self.elements[x - self.bodies]
    }

    /// A node's name: the body id, or `<J>` for the element of joint J.
    pub fn node_name(&self, m: &Mechanism, x: usize) -> String {
        if self.is_element(x) {
            format!("<{}>", m.joints[self.element_joint(x)].id)
        } else {
            m.body_id(x).to_string()
        }
    }

    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.joint.len()
    }

    /// The two bodies of pair `e`.
    pub fn bodies(&self, e: usize) -> [usize; 2] {
        [self.hub[e], self.other[e]]
    }
}

/// Where a body or equation ended up.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Part {
    /// The fixed frame (bodies only).
    Frame,
    /// The over-determined part.
    Over,
    /// A well-determined structural group (index in canonical order).
    Group(usize),
    /// The under-determined part.
    Under,
}

/// A structural group before rendering.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct RawGroup {
    /// Body indices, ascending.
    pub bodies: Vec<usize>,
    /// Solve level (1 = depends on the frame only).
    pub level: usize,
    /// Groups it depends on (canonical indices, ascending).
    pub deps: Vec<usize>,
}

/// The result of the count decomposition.
#[derive(Clone, Debug)]
pub(crate) struct Decomposition {
    /// Part of each body.
    pub body_part: Vec<Part>,
    /// Part of each equation node.
    pub eq_part: Vec<Part>,
    /// Groups in canonical order.
    pub groups: Vec<RawGroup>,
    /// Unsaturated equations per node (`cap − flow`).
    pub eq_excess: Vec<u32>,
    /// Missing DOF per body (`u_b − flow`).
    pub body_missing: Vec<u32>,
}

/// Decompose `m` with equation counts `eqs.cap` and body unknown counts `u` (per body index).
pub(crate) fn decompose(m: &Mechanism, eqs: &Equations, u: &[u32]) -> Decomposition {
    let ne = eqs.len();
    let nb = eqs.nodes;
    let (src, sink) = (0usize, 1usize);
    let eq_node = |e: usize| 2 + e;
    let body_node = |b: usize| 2 + ne + b;
    // The edges are listed twice (counted, then placed) rather than held in a list.
    let mut net = Network::from_edges(2 + ne + nb, |put| {
        for e in 0..ne {
            put(src as u32, eq_node(e) as u32, eqs.cap[e]);
            let [h, o] = eqs.bodies(e);
            if h != m.frame {
                put(eq_node(e) as u32, body_node(h) as u32, INF);
            }
            if o != m.frame && o != h {
                put(eq_node(e) as u32, body_node(o) as u32, INF);
            }
        }
        for (b, &ub) in u.iter().enumerate().take(nb) {
            if b != m.frame {
                put(body_node(b) as u32, sink as u32, ub);
            }
        }
    });
    if eqs.hint.len() == ne {
        let mut start = Vec::new();
        for (e, h) in eqs.hint.iter().enumerate() {
            for (x, &d) in eqs.bodies(e).into_iter().zip(h) {
                if x != m.frame && d > 0 {
                    start.push((eq_node(e), body_node(x), d));
                }
            }
        }
        net.warm(src, sink, &start);
    }
    net.max_flow(src, sink);

    // Read the flow back.
    let mut flow = vec![[0u32; 2]; ne];
    let mut eq_excess = vec![0u32; ne];
    for (e, f) in flow.iter_mut().enumerate() {
        let [h, o] = eqs.bodies(e);
        for a in net.edges(eq_node(e)) {
            let v = net.head(a);
            if v == src {
                // Reverse of source edge: its residual is the flow in.
                eq_excess[e] = eqs.cap[e] - net.residual(a).min(eqs.cap[e]);
            } else if v == body_node(h) && h != m.frame {
                f[0] = net.reverse_residual(a);
            } else if v == body_node(o) {
                f[1] = net.reverse_residual(a);
            }
        }
    }
    let mut body_missing = vec![0u32; nb];
    let mut touched = vec![false; nb];
    for e in 0..ne {
        for x in eqs.bodies(e) {
            touched[x] = true;
        }
    }
    for (b, miss) in body_missing.iter_mut().enumerate() {
        if b == m.frame || !touched[b] {
            continue;
        }
        for a in net.edges(body_node(b)) {
            if net.head(a) == sink {
                *miss = net.residual(a);
            }
        }
    }

    // Dulmage–Mendelsohn: reachable from the source = over-determined, reaching the sink =
    // under-determined, the rest is perfectly matched within itself.
    let from_src = net.reachable_from(src);
    let to_sink = net.reaching(sink);
    let classify = |node: usize| {
        if from_src[node] {
            Part::Over
        } else if to_sink[node] {
            Part::Under
        } else {
            Part::Group(usize::MAX)
        }
    };
    let mut body_part: Vec<Part> = (0..nb).map(|b| classify(body_node(b))).collect();
    body_part[m.frame] = Part::Frame;
    // Bodies no joint names are not part of the mechanism: no group, no missing DOF.
    for b in 0..nb {
        if !touched[b] {
            body_part[b] = Part::Frame;
        }
    }
    let mut eq_part: Vec<Part> = (0..ne).map(|e| classify(eq_node(e))).collect();
    drop(net);

    // Dependency graph among well-determined bodies: b depends on a when an equation that
    // flows into b also touches a.
    let well = |b: usize, parts: &[Part]| matches!(parts[b], Part::Group(_));
    let mut deg = vec![0usize; nb + 1];
    let mut dep_edges: Vec<(usize, usize)> = Vec::new();
    for e in 0..ne {
        if !matches!(eq_part[e], Part::Group(_)) {
            continue;
        }
        let bs = eqs.bodies(e);
        for (i, &x) in bs.iter().enumerate() {
            if flow[e][i] == 0 || !well(x, &body_part) {
                continue;
            }
            let y = bs[1 - i];
            if y != x && well(y, &body_part) {
                dep_edges.push((x, y));
                deg[x + 1] += 1;
            }
        }
    }
    for i in 0..nb {
        deg[i + 1] += deg[i];
    }
    let mut fill = deg.clone();
    let mut adj = vec![0u32; dep_edges.len()];
    for &(x, y) in &dep_edges {
        adj[fill[x]] = y as u32;
        fill[x] += 1;
    }
    let active: Vec<bool> = (0..nb).map(|b| well(b, &body_part)).collect();
    let sccs = tarjan(&deg, &adj, &active);

    // Tarjan emits dependencies first, so levels can be assigned in emission order.
    let mut comp = vec![usize::MAX; nb];
    for (c, s) in sccs.iter().enumerate() {
        for &b in s {
            comp[b] = c;
        }
    }
    // A component of element nodes only (a shared pin fixed by one solved body) is no group
    // of bodies: it adds no level (its level is its dependencies').
    let mut level = vec![1usize; sccs.len()];
    let mut cdeps: Vec<Vec<usize>> = vec![Vec::new(); sccs.len()];
    for (c, s) in sccs.iter().enumerate() {
        let base = usize::from(s.iter().any(|&x| !eqs.is_element(x)));
        let mut lv = 0;
        for &b in s {
            for &y in &adj[deg[b]..deg[b + 1]] {
                let d = comp[y as usize];
                if d != c {
                    lv = lv.max(level[d]);
                    cdeps[c].push(d);
                }
            }
        }
        level[c] = base + lv;
    }
    let groups = canonical(sccs, level, cdeps);
    for (g, grp) in groups.iter().enumerate() {
        for &b in &grp.bodies {
            body_part[b] = Part::Group(g);
        }
    }
    for e in 0..ne {
        if matches!(eq_part[e], Part::Group(_)) {
            let bs = eqs.bodies(e);
            let receiving = if flow[e][0] > 0 {
                Some(bs[0])
            } else if flow[e][1] > 0 {
                Some(bs[1])
            } else {
                None
            };
            eq_part[e] = match receiving.map(|b| body_part[b]) {
                Some(Part::Group(g)) => Part::Group(g),
                // No flow (a pair with zero equations): it belongs to the later of its groups.
                _ => {
                    let g = bs
                        .iter()
                        .filter_map(|&b| match body_part[b] {
                            Part::Group(g) => Some(g),
                            _ => None,
                        })
                        .max();
                    match g {
                        Some(g) => Part::Group(g),
                        None if bs.iter().any(|&b| body_part[b] == Part::Over) => Part::Over,
                        None => Part::Frame,
                    }
                }
            };
        }
    }
    Decomposition {
        body_part,
        eq_part,
        groups,
        eq_excess,
        body_missing,
    }
}

/// Sort components into canonical order (level, size, smallest body) and renumber dependencies.
pub(crate) fn canonical(
    comps: Vec<Vec<usize>>,
    level: Vec<usize>,
    deps: Vec<Vec<usize>>,
) -> Vec<RawGroup> {
    let mut order: Vec<usize> = (0..comps.len()).collect();
    let mut comps: Vec<Vec<usize>> = comps
        .into_iter()
        .map(|mut c| {
            c.sort_unstable();
            c
        })
        .collect();
    order.sort_by_key(|&c| (level[c], comps[c].len(), comps[c].first().copied()));
    let mut rank = vec![0usize; comps.len()];
    for (r, &c) in order.iter().enumerate() {
        rank[c] = r;
    }
    order
        .iter()
        .map(|&c| {
            let mut d: Vec<usize> = deps[c].iter().map(|&x| rank[x]).collect();
            d.sort_unstable();
            d.dedup();
            RawGroup {
                bodies: std::mem::take(&mut comps[c]),
                level: level[c],
                deps: d,
            }
        })
        .collect()
}

/// Iterative Tarjan SCC over the nodes with `active` set, CSR adjacency `adj[start[v]..start[v+1]]`.
/// Components come out in reverse topological order (a component after everything it reaches).
pub(crate) fn tarjan(start: &[usize], adj: &[u32], active: &[bool]) -> Vec<Vec<usize>> {
    let n = active.len();
    const UNSEEN: usize = usize::MAX;
    let mut index = vec![UNSEEN; n];
    let mut low = vec![0usize; n];
    let mut on_stack = vec![false; n];
    let mut stack: Vec<usize> = Vec::new();
    let mut call: Vec<(usize, usize)> = Vec::new();
    let mut next = 0usize;
    let mut out = Vec::new();
    for root in 0..n {
        if !active[root] || index[root] != UNSEEN {
            continue;
        }
        index[root] = next;
        low[root] = next;
        next += 1;
        stack.push(root);
        on_stack[root] = true;
        call.push((root, start[root]));
        while let Some(top) = call.last_mut() {
            let v = top.0;
            if top.1 < start[v + 1] {
                let w = adj[top.1] as usize;
                top.1 += 1;
                if !active[w] {
                    continue;
                }
                if index[w] == UNSEEN {
                    index[w] = next;
                    low[w] = next;
                    next += 1;
                    stack.push(w);
                    on_stack[w] = true;
                    call.push((w, start[w]));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
            } else {
                call.pop();
                if let Some(&(p, _)) = call.last() {
                    low[p] = low[p].min(low[v]);
                }
                if low[v] == index[v] {
                    let mut comp = Vec::new();
                    loop {
                        let w = stack.pop().expect("v is still on the stack");
                        on_stack[w] = false;
                        comp.push(w);
                        if w == v {
                            break;
                        }
                    }
                    out.push(comp);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tarjan_finds_cycles_dependencies_first() {
        // 0 -> 1 -> 2 -> 1, 3 isolated.
        let start = [0, 1, 2, 3, 3];
        let adj = [1u32, 2, 1];
        let sccs = tarjan(&start, &adj, &[true; 4]);
        let mut sorted: Vec<Vec<usize>> = sccs
            .iter()
            .map(|c| {
                let mut c = c.clone();
                c.sort();
                c
            })
            .collect();
        assert_eq!(sorted[0], vec![1, 2]);
        assert_eq!(sorted[1], vec![0]);
        sorted.sort();
        assert_eq!(sorted, vec![vec![0], vec![1, 2], vec![3]]);
    }
}
