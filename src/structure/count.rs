//! The count decomposition: maximum flow from joint equations to body unknowns, the
//! Dulmage–Mendelsohn split of the residual graph, and the strongly connected components of
//! the well-determined part (the structural groups) with their levels.

use crate::graph::flow::{INF, Network};
use crate::graph::scc::tarjan_flat;
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
        // Every list sized once, to the pairs pushed below (a binary joint is one pair; a
        // multiple joint of n bodies n pairs and its input pairs): grown by doubling, the six
        // lists of 2.6·10^6 pairs were copied about once more each.
        let pairs: usize = m
            .joints
            .iter()
            .map(|j| match j.bodies.len() {
                0 => 0,
                2 => 1,
                n => {
                    let k = j.grade().max(1);
                    n + (n - 1).min(j.driven.div_ceil(k) as usize)
                }
            })
            .sum();
        let mut e = Equations {
            joint: Vec::with_capacity(pairs),
            hub: Vec::with_capacity(pairs),
            other: Vec::with_capacity(pairs),
            cap: Vec::with_capacity(pairs),
            driven: Vec::with_capacity(pairs),
            input_only: Vec::with_capacity(pairs),
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
#[derive(Clone, Debug, Default)]
#[cfg_attr(test, derive(PartialEq))]
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
    decompose_counted(m, eqs, u, None).0
}

/// What a decomposition leaves for the next one of the same mechanism after some pairs'
/// equation counts were lowered (the rank check's rounds): the maximum flow's value and its
/// source side (the nodes reachable from the source in the residual network: the same for
/// every maximum flow).
pub(crate) struct FlowRound {
    /// The maximum flow's value.
    value: u64,
    /// The source side, one bit a node of the network.
    over: Vec<u64>,
    /// The network's nodes.
    nodes: usize,
    /// The counts decomposed (debug builds check the caller's list of lowerings with them).
    #[cfg(debug_assertions)]
    counts: (Vec<u32>, Vec<u32>),
}

/// A previous decomposition's [`FlowRound`] and the pairs lowered since, each with its count
/// then.
pub(crate) type Prior<'a> = (&'a FlowRound, &'a [(usize, u32)]);

/// [`decompose`] in a sequence of decompositions of one mechanism: `prior` is the previous
/// decomposition's [`FlowRound`] and the pairs lowered since, each with its count then (`eqs`
/// and `u` otherwise as they were). Returns the same decomposition as [`decompose`], and
/// the round to pass to the next (always there).
///
/// When every pair lowered since lies outside the previous source side and the greedy
/// start's flow is already worth the previous maximum less the units lowered, that flow is
/// maximum and its source side is the previous one (see [`same_source_side`]): the
/// breadth-first search that would find no augmenting path and label that side again
/// (3.4·10^6 nodes at 10^6 random spatial bodies) is not run. That search changes no
/// residual capacity, so the network, and every output read from it, is the one it would
/// have left.
pub(crate) fn decompose_next(
    m: &Mechanism,
    eqs: &Equations,
    u: &[u32],
    prior: Option<Prior>,
) -> (Decomposition, Option<FlowRound>) {
    let (dec, _, round) = decompose_counted(m, eqs, u, Some(prior));
    (dec, round)
}

/// Whether the flow network of this decomposition, with a flow of `value` pushed, has the
/// previous round's source side as its own (then the flow is maximum, and a search of its
/// residual network would find no path to the sink and label that side). The network is
/// the previous one but for the lowered pairs' source edges, whose capacities fell.
///
/// Why: let `f1` be the previous maximum flow and `S` its source side (the nodes reachable
/// from the source in its residual network). Every edge leaving `S` is saturated by `f1`
/// and every edge entering `S` carries nothing (else the far end would be reachable). A
/// lowered pair `e` outside `S` had its source edge leaving `S`, so saturated: take the
/// `δ` units it lost off `f1` along its edges to its bodies and on to the sink, all outside
/// `S` (an edge from `e` into `S` carries nothing). The flow `f'` so made is feasible now,
/// worth `value(f1) − Σδ`, and still saturates every edge leaving `S` (at the lowered
/// capacities) with nothing entering `S`: it equals the capacity of the cut `S`, so it is
/// maximum, and the maximum is `value(f1) − Σδ`. Inside `S` neither capacities nor flow
/// changed, and no residual edge leaves `S`: `f'`'s source side is `S`. The source side is
/// the same for every maximum flow (the smallest minimum cut), so a flow worth `value(f1) −
/// Σδ` is maximum and has source side `S`.
fn same_source_side(
    eqs: &Equations,
    u: &[u32],
    nodes: usize,
    value: u64,
    (round, lowered): Prior,
) -> bool {
    #[cfg(debug_assertions)]
    {
        let mut before = eqs.cap.clone();
        for &(e, c) in lowered.iter().rev() {
            before[e] = c;
        }
        debug_assert!(
            before == round.counts.0 && u == round.counts.1,
            "only the listed pairs were lowered since the previous round"
        );
    }
    #[cfg(not(debug_assertions))]
    let _ = u;
    if round.nodes != nodes {
        return false;
    }
    // Each pair's count at the previous round: its first listed one (a count only falls).
    let mut first: Vec<(usize, u32)> = lowered.to_vec();
    first.sort_by_key(|&(e, c)| (e, std::cmp::Reverse(c)));
    first.dedup_by_key(|&mut (e, _)| e);
    let mut units = 0u64;
    for (e, before) in first {
        let node = 2 + e;
        let Some(&now) = eqs.cap.get(e) else {
            return false;
        };
        if now > before
            || round
                .over
                .get(node / 64)
                .is_none_or(|w| w >> (node % 64) & 1 != 0)
        {
            return false;
        }
        units += u64::from(before - now);
    }
    round.value.checked_sub(units) == Some(value)
}

/// [`decompose`], the edges its searches of the flow network examined (the maximum flow's
/// and the Dulmage–Mendelsohn split's), and with `next` the [`FlowRound`] of
/// [`decompose_next`].
fn decompose_counted(
    m: &Mechanism,
    eqs: &Equations,
    u: &[u32],
    next: Option<Option<Prior>>,
) -> (Decomposition, u64, Option<FlowRound>) {
    let (mut net, total) = greedy_flow(m, eqs, u);
    let (from_src, round) = source_side(eqs, u, &mut net, total, next);
    let (flow, eq_excess) = read_flow(m, eqs, &net);
    let mut touched = vec![false; eqs.nodes];
    for e in 0..eqs.len() {
        for x in eqs.bodies(e) {
            touched[x] = true;
        }
    }
    let body_missing = missing_dof(m, eqs, &net, &touched);
    let (mut body_part, mut eq_part, scanned) = split_parts(m, eqs, net, from_src, &touched);
    let (deg, adj) = dependencies(eqs, &flow, &body_part, &eq_part);
    let groups = ordered_groups(eqs, &body_part, deg, adj);
    assign_groups(eqs, &flow, &groups, &mut body_part, &mut eq_part);
    (
        Decomposition {
            body_part,
            eq_part,
            groups,
            eq_excess,
            body_missing,
        },
        scanned,
        round,
    )
}

/// The network's node of pair `e` (after the source and the sink).
fn eq_node(e: usize) -> usize {
    2 + e
}

/// The network's node of body `b` (after the pairs).
fn body_node(eqs: &Equations, b: usize) -> usize {
    2 + eqs.len() + b
}

/// The flow network source → pairs → bodies → sink with its greedy start pushed, and that
/// start's value. Built directly in the order the edge list s → pairs, pair → bodies,
/// bodies → t gives (the maximum flow found depends on that order).
fn greedy_flow(m: &Mechanism, eqs: &Equations, u: &[u32]) -> (Network, u64) {
    let (src, sink) = (0usize, 1usize);
    const NONE: u32 = u32::MAX;
    let sink_caps: Vec<u32> = (0..eqs.nodes)
        .map(|b| match u.get(b) {
            Some(&ub) if b != m.frame => ub,
            _ => NONE,
        })
        .collect();
    let frame = m.frame;
    let ends = |e: usize| {
        eqs.bodies(e)
            .map(|x| if x == frame { NONE } else { x as u32 })
    };
    if eqs.hint.len() == eqs.len() {
        let mut net = Network::three_layer(&eqs.cap, ends, &sink_caps);
        let mut start = Vec::new();
        for (e, h) in eqs.hint.iter().enumerate() {
            for (x, &d) in eqs.bodies(e).into_iter().zip(h) {
                if x != m.frame && d > 0 {
                    start.push((eq_node(e), body_node(eqs, x), d));
                }
            }
        }
        net.warm(src, sink, &start);
        let total = net.greedy(src, sink);
        (net, total)
    } else {
        // The greedy start pushed as the network is built: the same pushes (see
        // `Network::three_layer_greedy`).
        Network::three_layer_greedy(&eqs.cap, ends, &sink_caps)
    }
}

/// The maximum flow from the greedy start worth `total`, and the nodes reachable from the
/// source: they come with the flow (its last search), or are the previous round's (see
/// [`same_source_side`]). With `next`, the [`FlowRound`] for the next decomposition.
fn source_side(
    eqs: &Equations,
    u: &[u32],
    net: &mut Network,
    total: u64,
    next: Option<Option<Prior>>,
) -> (Vec<bool>, Option<FlowRound>) {
    let (src, sink) = (0usize, 1usize);
    let prior = next.flatten();
    let known =
        prior.is_some_and(|p| same_source_side(eqs, u, net.nodes(), net.source_outflow(), p));
    let from_src: Vec<bool> = match prior {
        Some((round, _)) if known => (0..net.nodes())
            .map(|x| round.over[x / 64] >> (x % 64) & 1 != 0)
            .collect(),
        _ => net.max_flow_after_greedy(src, sink, total).1,
    };
    let round = next.map(|_| {
        let over = from_src
            .chunks(64)
            .map(|c| {
                c.iter()
                    .enumerate()
                    .fold(0u64, |w, (i, &r)| w | u64::from(r) << i)
            })
            .collect();
        FlowRound {
            value: net.source_outflow(),
            over,
            nodes: net.nodes(),
            #[cfg(debug_assertions)]
            counts: (eqs.cap.clone(), u.to_vec()),
        }
    });
    (from_src, round)
}

/// Read the flow back: whether each side of each pair carries flow (all that is read of it
/// later; two bytes a pair rather than eight, held with the network), and each pair's
/// unsaturated equations.
fn read_flow(m: &Mechanism, eqs: &Equations, net: &Network) -> (Vec<[bool; 2]>, Vec<u32>) {
    let src = 0usize;
    let ne = eqs.len();
    let mut flow = vec![[false; 2]; ne];
    let mut eq_excess = vec![0u32; ne];
    for (e, f) in flow.iter_mut().enumerate() {
        let [h, o] = eqs.bodies(e);
        for a in net.all_edges(eq_node(e)) {
            let v = net.head(a);
            if v == src {
                // Reverse of source edge: its residual is the flow in.
                eq_excess[e] = eqs.cap[e] - net.residual(a).min(eqs.cap[e]);
            } else if v == body_node(eqs, h) && h != m.frame {
                // A forward edge of capacity INF: what it lost is its flow (read here rather
                // than on its reverse, which sits at the body, far away).
                f[0] = net.residual(a) < INF;
            } else if v == body_node(eqs, o) {
                f[1] = net.residual(a) < INF;
            }
        }
    }
    (flow, eq_excess)
}

/// Missing DOF per body (`u_b − flow`; none for the frame and bodies no pair `touched`).
fn missing_dof(m: &Mechanism, eqs: &Equations, net: &Network, touched: &[bool]) -> Vec<u32> {
    let sink = 1usize;
    let mut body_missing = vec![0u32; eqs.nodes];
    for (b, miss) in body_missing.iter_mut().enumerate() {
        if b == m.frame || !touched[b] {
            continue;
        }
        for a in net.edges(body_node(eqs, b)) {
            if net.head(a) == sink {
                *miss = net.residual(a);
            }
        }
    }
    body_missing
}

/// Dulmage–Mendelsohn: reachable from the source = over-determined, reaching the sink =
/// under-determined, the rest is perfectly matched within itself (`Group(usize::MAX)` until
/// the groups are known). The parts of the bodies and of the pairs, and the edges the
/// network's searches examined. The network is read no more: its pages take the parts' lists.
#[allow(clippy::type_complexity)]
fn split_parts(
    m: &Mechanism,
    eqs: &Equations,
    net: Network,
    from_src: Vec<bool>,
    touched: &[bool],
) -> (Vec<Part>, Vec<Part>, u64) {
    let nb = eqs.nodes;
    let to_sink = net.reaching(1);
    let scanned = net.scanned();
    drop(net);
    let classify = |node: usize| {
        if from_src[node] {
            Part::Over
        } else if to_sink[node] {
            Part::Under
        } else {
            Part::Group(usize::MAX)
        }
    };
    let mut body_part: Vec<Part> = (0..nb).map(|b| classify(body_node(eqs, b))).collect();
    body_part[m.frame] = Part::Frame;
    // Bodies no joint names are not part of the mechanism: no group, no missing DOF.
    for b in 0..nb {
        if !touched[b] {
            body_part[b] = Part::Frame;
        }
    }
    let eq_part: Vec<Part> = (0..eqs.len()).map(|e| classify(eq_node(e))).collect();
    (body_part, eq_part, scanned)
}

/// Dependency graph among well-determined bodies, compressed (`adj[deg[x]..deg[x + 1]]`):
/// b depends on a when an equation that flows into b also touches a.
fn dependencies(
    eqs: &Equations,
    flow: &[[bool; 2]],
    body_part: &[Part],
    eq_part: &[Part],
) -> (Vec<usize>, Vec<u32>) {
    let nb = eqs.nodes;
    let ne = eqs.len();
    let well = |b: usize| matches!(body_part[b], Part::Group(_));
    // The dependency `x -> y` of side `i` of pair `e`, if any (counted, then placed: no list
    // of edges next to the arrays).
    let dep = |e: usize, i: usize| -> Option<(usize, usize)> {
        if !matches!(eq_part[e], Part::Group(_)) || !flow[e][i] {
            return None;
        }
        let bs = eqs.bodies(e);
        let (x, y) = (bs[i], bs[1 - i]);
        (well(x) && y != x && well(y)).then_some((x, y))
    };
    let mut deg = vec![0usize; nb + 1];
    for e in 0..ne {
        for i in 0..2 {
            if let Some((x, _)) = dep(e, i) {
                deg[x + 1] += 1;
            }
        }
    }
    for i in 0..nb {
        deg[i + 1] += deg[i];
    }
    let mut fill = deg.clone();
    let mut adj = vec![0u32; deg[nb]];
    for e in 0..ne {
        for i in 0..2 {
            if let Some((x, y)) = dep(e, i) {
                adj[fill[x]] = y as u32;
                fill[x] += 1;
            }
        }
    }
    (deg, adj)
}

/// The groups: the strongly connected components of the dependency graph (`deg`, `adj`)
/// among well-determined bodies, with their levels, in canonical order.
fn ordered_groups(
    eqs: &Equations,
    body_part: &[Part],
    deg: Vec<usize>,
    adj: Vec<u32>,
) -> Vec<RawGroup> {
    let nb = eqs.nodes;
    let active: Vec<bool> = (0..nb)
        .map(|b| matches!(body_part[b], Part::Group(_)))
        .collect();
    let (mut members, bounds) = tarjan_flat(&deg, &adj, &active);
    drop(active);
    let nc = bounds.len() - 1;

    // Tarjan emits dependencies first, so levels can be assigned in emission order.
    let mut comp = vec![u32::MAX; nb];
    for c in 0..nc {
        for &b in &members[bounds[c]..bounds[c + 1]] {
            comp[b as usize] = c as u32;
        }
    }
    // A component of element nodes only (a shared pin fixed by one solved body) is no group
    // of bodies: it adds no level (its level is its dependencies').
    let mut level = vec![1usize; nc];
    let mut dstart = vec![0usize; nc + 1];
    let mut dlist: Vec<u32> = Vec::new();
    for c in 0..nc {
        let s = &members[bounds[c]..bounds[c + 1]];
        let base = usize::from(s.iter().any(|&x| !eqs.is_element(x as usize)));
        let mut lv = 0;
        for &b in s {
            let b = b as usize;
            for &y in &adj[deg[b]..deg[b + 1]] {
                let d = comp[y as usize];
                if d != c as u32 {
                    lv = lv.max(level[d as usize]);
                    dlist.push(d);
                }
            }
        }
        level[c] = base + lv;
        dstart[c + 1] = dlist.len();
    }
    drop(comp);
    drop(adj);
    canonical_flat(&mut members, &bounds, level, &dstart, &dlist)
}

/// Each group's bodies and pairs take its number: a pair goes to the group its flow goes
/// into.
fn assign_groups(
    eqs: &Equations,
    flow: &[[bool; 2]],
    groups: &[RawGroup],
    body_part: &mut [Part],
    eq_part: &mut [Part],
) {
    for (g, grp) in groups.iter().enumerate() {
        for &b in &grp.bodies {
            body_part[b] = Part::Group(g);
        }
    }
    for e in 0..eqs.len() {
        if matches!(eq_part[e], Part::Group(_)) {
            let bs = eqs.bodies(e);
            let receiving = if flow[e][0] {
                Some(bs[0])
            } else if flow[e][1] {
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

/// [`canonical`] of the components `members[bounds[c]..bounds[c + 1]]` (sorted in place)
/// with dependencies `deps[dstart[c]..dstart[c + 1]]`: the same groups, without a vector per
/// component on the way.
fn canonical_flat(
    members: &mut [u32],
    bounds: &[usize],
    level: Vec<usize>,
    dstart: &[usize],
    deps: &[u32],
) -> Vec<RawGroup> {
    let nc = bounds.len() - 1;
    for c in 0..nc {
        members[bounds[c]..bounds[c + 1]].sort_unstable();
    }
    let members = &*members;
    let comp = |c: usize| &members[bounds[c]..bounds[c + 1]];
    let mut order: Vec<usize> = (0..nc).collect();
    order.sort_by_key(|&c| {
        (
            level[c],
            comp(c).len(),
            comp(c).first().map(|&x| x as usize),
        )
    });
    let mut rank = vec![0u32; nc];
    for (r, &c) in order.iter().enumerate() {
        rank[c] = r as u32;
    }
    order
        .iter()
        .map(|&c| {
            let mut d: Vec<usize> = deps[dstart[c]..dstart[c + 1]]
                .iter()
                .map(|&x| rank[x as usize] as usize)
                .collect();
            d.sort_unstable();
            d.dedup();
            RawGroup {
                bodies: comp(c).iter().map(|&x| x as usize).collect(),
                level: level[c],
                deps: d,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pair lists are allocated once, at their final length: binary joints, multiple
    /// joints with and without inputs (input pairs), the bundled examples.
    #[test]
    fn equation_lists_are_sized_once() {
        use crate::joint::JointType;
        let mut cases = vec![
            crate::generate::random(2000, false, 1).expect("valid").0,
            crate::generate::star(300, JointType::S, false, true, true).expect("valid"),
            crate::generate::star(300, JointType::R, false, true, false).expect("valid"),
        ];
        for name in crate::examples::names() {
            let (_, text) = crate::examples::find(name).expect("bundled");
            cases
                .push(crate::format::load(name, text, crate::format::Format::Toml).expect("reads"));
        }
        for m in &cases {
            let e = Equations::of(m);
            let n = e.len();
            assert!(n > 0, "{}", m.name);
            let caps = [
                e.joint.capacity(),
                e.hub.capacity(),
                e.other.capacity(),
                e.cap.capacity(),
                e.driven.capacity(),
                e.input_only.capacity(),
            ];
            assert_eq!(caps, [n; 6], "{}", m.name);
        }
    }

    /// Work regression: the searches of one decomposition examine each edge of the flow
    /// network at most once when the greedy start finds the whole flow (random mechanisms:
    /// one breadth-first search that finds no path to the sink gives the over-determined
    /// part, one search from the sink the under-determined part; the two are disjoint). The
    /// over-determined part was searched twice before (the flow's last search, then again),
    /// 1.6 times the network's edges on this family at 3,000 bodies.
    #[test]
    fn decomposition_searches_each_edge_once() {
        for seed in [1, 2] {
            let (m, _) = crate::generate::random(3_000, false, seed).expect("valid parameters");
            // The counts `analyze` decomposes: rows and unknowns after the rank check.
            let mut eqs = Equations::of(&m);
            let mut u = eqs.unknowns(&m);
            let (geoms, used) = crate::geometry::geometries(
                &m,
                crate::geometry::GeometrySource::Random { seed: 0 },
                None,
            )
            .expect("random geometry");
            let shortcut = super::super::rank::Shortcut::None;
            super::super::rank::check(&m, &geoms, &used, &mut eqs, &mut u, None, shortcut);
            let (dec, scanned, _) = decompose_counted(&m, &eqs, &u, None);
            // Edge slots of the network (each edge and its reverse).
            let mut edges = eqs.len() as u64;
            for e in 0..eqs.len() {
                let [h, o] = eqs.bodies(e);
                edges += u64::from(h != m.frame) + u64::from(o != m.frame && o != h);
            }
            edges += (0..eqs.nodes).filter(|&b| b != m.frame).count() as u64;
            let over = dec.body_part.iter().filter(|&&p| p == Part::Over).count();
            assert!(
                over > 100,
                "{over} over-determined bodies: the case this is about"
            );
            assert!(
                scanned <= 2 * edges,
                "{scanned} edges examined, the network has {}",
                2 * edges
            );
        }
    }

    /// A later round's decomposition from the previous round's flow is the decomposition
    /// made from scratch (parts, groups, and the flow's unsaturated pairs and missing DOF),
    /// whichever pairs were lowered: pairs of groups and of the under-determined part (the
    /// search for the source side is skipped: fewer edges examined), pairs of the
    /// over-determined part (it is not), some lowered twice, some to nothing; and again a
    /// round later from that round.
    #[test]
    fn later_rounds_are_the_cold_decomposition() {
        let mut skipped = 0;
        for (seed, planar) in [(1, false), (2, false), (3, true)] {
            let (m, _) = crate::generate::random(3_000, planar, seed).expect("valid parameters");
            let mut eqs = Equations::of(&m);
            let u = eqs.unknowns(&m);
            let (dec, _, round) = decompose_counted(&m, &eqs, &u, Some(None));
            let mut round = round.expect("asked for");
            for step in 0..4 {
                let dec_before = if step == 0 {
                    dec.clone()
                } else {
                    decompose(&m, &eqs, &u)
                };
                // Which pairs to lower: of groups (step 0, 2), of the under-determined part
                // (step 1), of the over-determined part (step 3).
                let pick = |e: usize| match (step, dec_before.eq_part[e]) {
                    (0 | 2, Part::Group(_)) => e % 7 == step,
                    (1, Part::Under) => e.is_multiple_of(5),
                    (3, Part::Over) => e.is_multiple_of(11),
                    _ => false,
                };
                let mut lowerings = Vec::new();
                for e in 0..eqs.len() {
                    if eqs.cap[e] > 0 && pick(e) {
                        lowerings.push((e, eqs.cap[e]));
                        eqs.cap[e] -= 1;
                        if e.is_multiple_of(3) {
                            lowerings.push((e, eqs.cap[e]));
                            eqs.cap[e] = 0;
                        }
                    }
                }
                if lowerings.is_empty() {
                    // No such pair left (its groups are under-determined now).
                    assert!(step > 0, "seed {seed}: groups to lower");
                    continue;
                }
                let (got, scanned, next) =
                    decompose_counted(&m, &eqs, &u, Some(Some((&round, &lowerings))));
                let (want, cold_scanned, cold) = decompose_counted(&m, &eqs, &u, Some(None));
                assert_eq!(got, want, "seed {seed} step {step}");
                let (next, cold) = (next.expect("asked for"), cold.expect("asked for"));
                assert_eq!(
                    (next.value, &next.over, next.nodes),
                    (cold.value, &cold.over, cold.nodes),
                    "seed {seed} step {step}"
                );
                if scanned < cold_scanned {
                    skipped += 1;
                } else {
                    assert_eq!(scanned, cold_scanned, "seed {seed} step {step}");
                }
                round = next;
            }
        }
        assert!(skipped >= 3, "the search was skipped {skipped} times");
    }
}
