//! The spanning tree of the joint graph and its cut pairs (Kruskal over the binary pairs in
//! the order of the rule, [`super`]), oriented from the frame, and the loop each cut closes.

use crate::budget::{BudgetExceeded, Meter};
use crate::joint::JointType;
use crate::mechanism::Mechanism;
use std::collections::BTreeSet;

/// A binary pair of a joint (a multiple joint of n bodies is n − 1 pairs hub→other).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pair {
    /// Index of the joint in [`Mechanism::joints`].
    pub joint: usize,
    /// The joint's first body (the hub of a multiple joint).
    pub hub: usize,
    /// The other body of this pair.
    pub other: usize,
}

/// A body's link to its parent in the tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Link {
    /// The tree pair.
    pub pair: usize,
    /// The parent body.
    pub parent: usize,
}

/// The tree and the cuts: which pair joins each body to its parent, the bodies in depth-first
/// order from each root, and the pairs left out of the tree.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// Every binary pair, in joint order.
    pub pairs: Vec<Pair>,
    /// Per body: the link to its parent (`None` for a root).
    pub links: Vec<Option<Link>>,
    /// Per body: its depth below its root.
    pub depth: Vec<usize>,
    /// The roots: the frame first, then the first body (in body order) of each part not
    /// joined to the frame.
    pub roots: Vec<usize>,
    /// Every body, each root followed by its subtree depth first (children in pair order).
    pub order: Vec<usize>,
    /// The cut pairs, in pair order.
    pub cuts: Vec<usize>,
}

/// Preferences that override the rule's classes in the exchange step: pairs kept in the tree
/// when they can be, pairs cut when they can be.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Force {
    /// Pairs put first (kept in the tree).
    pub keep: BTreeSet<usize>,
    /// Pairs put last (cut where they close a loop).
    pub cut: BTreeSet<usize>,
}

/// The binary pairs of `m`, in joint order.
pub fn pairs_of(m: &Mechanism) -> Vec<Pair> {
    let mut out = Vec::new();
    for (ji, j) in m.joints.iter().enumerate() {
        if let Some((&hub, rest)) = j.bodies.split_first() {
            out.extend(rest.iter().map(|&other| Pair {
                joint: ji,
                hub,
                other,
            }));
        }
    }
    out
}

/// The rule's class of a joint, lower kept in the tree first: driven joints (an actuator acts
/// on a tree joint), then the others, then spherical joints (cut first: a ball closure is a
/// point constraint every simulator has).
pub fn class(m: &Mechanism, joint: usize) -> u8 {
    let j = &m.joints[joint];
    if j.driven > 0 {
        0
    } else if j.kind == JointType::S {
        2
    } else {
        1
    }
}

fn find(uf: &mut [usize], mut x: usize) -> usize {
    while uf[x] != x {
        uf[x] = uf[uf[x]];
        x = uf[x];
    }
    x
}

/// The tree by the rule's order (with `force`), oriented from the frame.
pub fn plan(m: &Mechanism, force: &Force, meter: &mut Meter) -> Result<Plan, BudgetExceeded> {
    let pairs = pairs_of(m);
    meter.charge(pairs.len() as u64 * 4 + m.bodies.len() as u64)?;
    let rank = |p: usize| -> u8 {
        if force.keep.contains(&p) {
            0
        } else if force.cut.contains(&p) {
            4
        } else {
            1 + class(m, pairs[p].joint)
        }
    };
    let mut sorted: Vec<usize> = (0..pairs.len()).collect();
    // Stable: within a class, the pair order (joint order, then the pairs of a joint).
    sorted.sort_by_key(|&p| rank(p));
    let mut uf: Vec<usize> = (0..m.bodies.len()).collect();
    let mut in_tree = vec![false; pairs.len()];
    for p in sorted {
        let (a, b) = (find(&mut uf, pairs[p].hub), find(&mut uf, pairs[p].other));
        if a != b {
            uf[a] = b;
            in_tree[p] = true;
        }
    }
    let cuts = (0..pairs.len()).filter(|&p| !in_tree[p]).collect();
    let (links, depth, roots, order) = orient(m, &pairs, &in_tree);
    Ok(Plan {
        pairs,
        links,
        depth,
        roots,
        order,
        cuts,
    })
}

type Oriented = (Vec<Option<Link>>, Vec<usize>, Vec<usize>, Vec<usize>);

/// The tree pairs oriented from the frame (then from the first body of each other part):
/// each body's link to its parent, its depth, the roots and the depth-first order.
fn orient(m: &Mechanism, pairs: &[Pair], in_tree: &[bool]) -> Oriented {
    let nb = m.bodies.len();
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); nb];
    for (p, pair) in pairs.iter().enumerate().filter(|(p, _)| in_tree[*p]) {
        adj[pair.hub].push(p);
        adj[pair.other].push(p);
    }
    let mut links: Vec<Option<Link>> = vec![None; nb];
    let mut depth = vec![0usize; nb];
    let mut seen = vec![false; nb];
    let mut roots = Vec::new();
    let mut order = Vec::with_capacity(nb);
    let starts = std::iter::once(m.frame).chain((0..nb).filter(|&b| b != m.frame));
    for root in starts {
        if seen[root] {
            continue;
        }
        roots.push(root);
        seen[root] = true;
        // Depth first, children in pair order (pushed reversed).
        let mut stack = vec![root];
        while let Some(x) = stack.pop() {
            order.push(x);
            for &p in adj[x].iter().rev() {
                let y = if pairs[p].hub == x {
                    pairs[p].other
                } else {
                    pairs[p].hub
                };
                if !seen[y] {
                    seen[y] = true;
                    links[y] = Some(Link { pair: p, parent: x });
                    depth[y] = depth[x] + 1;
                    stack.push(y);
                }
            }
        }
    }
    (links, depth, roots, order)
}

/// One step of a loop: a tree pair and the sign of its relative twist in the closure
/// (`t_other − t_hub` of the cut is the sum of `sign · twist` of the steps).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// The tree pair.
    pub pair: usize,
    /// +1 or −1.
    pub sign: f64,
}

/// The loop cut pair `c` closes: its bodies from the cut's hub through the tree to its other
/// body, and the tree steps whose twists make `t_other − t_hub`.
pub fn closed_loop(
    plan: &Plan,
    c: usize,
    meter: &mut Meter,
) -> Result<(Vec<usize>, Vec<Step>), BudgetExceeded> {
    let Pair { hub, other, .. } = plan.pairs[c];
    // Up from both ends to the common ancestor.
    let (mut a, mut b) = (hub, other);
    let (mut up_a, mut up_b) = (vec![hub], vec![other]);
    let (mut steps_a, mut steps_b) = (Vec::new(), Vec::new());
    // t_child = t_parent + s · twist, s = +1 when the parent is the pair's hub.
    let sign = |link: &Link| {
        if plan.pairs[link.pair].hub == link.parent {
            1.0
        } else {
            -1.0
        }
    };
    while a != b {
        meter.charge(1)?;
        let up_from_a = plan.depth[a] >= plan.depth[b];
        let x = if up_from_a { a } else { b };
        let Some(link) = plan.links[x] else {
            // Different parts: a cut never joins two of them (it would be a tree pair).
            break;
        };
        let s = sign(&link);
        if up_from_a {
            steps_a.push(Step {
                pair: link.pair,
                sign: -s,
            });
            a = link.parent;
            up_a.push(a);
        } else {
            steps_b.push(Step {
                pair: link.pair,
                sign: s,
            });
            b = link.parent;
            up_b.push(b);
        }
    }
    up_b.pop();
    let mut bodies = up_a;
    bodies.extend(up_b.into_iter().rev());
    steps_a.extend(steps_b.into_iter().rev());
    Ok((bodies, steps_a))
}
