//! Rigid clusters: the union-find forest the bodies moving alike are joined in, and the
//! merging of clusters with isolated motions across the joints they share.

use super::jacobian::{Pair, Part};
use crate::budget::{BudgetExceeded, Meter};
use std::collections::BTreeMap;

/// The root of `x` in the union-find forest `uf`, compressing the path.
pub(super) fn find(uf: &mut [usize], x: usize) -> usize {
    let mut r = x;
    while uf[r] != r {
        r = uf[r];
    }
    let mut y = x;
    while uf[y] != r {
        let n = uf[y];
        uf[y] = r;
        y = n;
    }
    r
}

/// Join the sets of `x` and `y`, the smaller root staying the root (clusters are named by
/// their first body, so the output order does not depend on the merge order).
pub(super) fn union_min(uf: &mut [usize], x: usize, y: usize) {
    let (a, c) = (find(uf, x), find(uf, y));
    uf[a.max(c)] = a.min(c);
}

/// A part's clusters as they are joined: a union-find forest over the part's bodies, and for
/// each cluster the member it is compared through, one with the fewest isolated motions.
/// "Moves alike, modulo the isolated motions of both" is not transitive: a body spinning
/// between two coaxial pins agrees so with both neighbours, which turn relative to each other
/// (Gepetto's five-bar: `end_rod` and `rod_2` were one rigid part through the sphere between
/// them). A cluster compared through a member without isolated motions agrees exactly.
pub(super) struct Local {
    pub(super) uf: Vec<usize>,
    rep: Vec<usize>,
    iso: Vec<usize>,
}

impl Local {
    /// Every body alone; `iso[x]`: the number of isolated motions of body `x`.
    pub(super) fn new(iso: Vec<usize>) -> Local {
        Local {
            uf: (0..iso.len()).collect(),
            rep: (0..iso.len()).collect(),
            iso,
        }
    }

    /// The root of `x`'s cluster.
    pub(super) fn root(&mut self, x: usize) -> usize {
        find(&mut self.uf, x)
    }

    /// The member `x`'s cluster is compared through.
    pub(super) fn rep(&mut self, x: usize) -> usize {
        let r = self.root(x);
        self.rep[r]
    }

    /// Whether `x`'s cluster is compared through a member with isolated motions (every
    /// member has some).
    pub(super) fn has_iso(&mut self, x: usize) -> bool {
        let r = self.rep(x);
        self.iso[r] > 0
    }

    /// Join the clusters of `x` and `y` (the smaller root staying the root, so clusters are
    /// named by their first body whatever the merge order).
    pub(super) fn join(&mut self, x: usize, y: usize) {
        let (a, c) = (self.root(x), self.root(y));
        if a == c {
            return;
        }
        let (p, q) = (self.rep[a], self.rep[c]);
        let best = if (self.iso[q], q) < (self.iso[p], p) {
            q
        } else {
            p
        };
        let r = a.min(c);
        self.uf[a.max(c)] = r;
        self.rep[r] = best;
    }

    /// Join `x` and `y` when their clusters move alike by `same` (on their representatives).
    pub(super) fn join_if(&mut self, x: usize, y: usize, same: &impl Fn(usize, usize) -> bool) {
        if self.root(x) != self.root(y) && same(self.rep(x), self.rep(y)) {
            self.join(x, y);
        }
    }
}

/// Clusters with isolated motions compared with the clusters sharing a joint with them (the
/// bodies of each joint of the part: a multiple joint's bodies are not all pairs of each
/// other), merged when `same` says they move alike, until nothing changes (at most 4 rounds).
/// Shared by the exact and the sparse floating-point paths.
pub(super) fn merge_across_joints(
    part: &Part,
    pairs: &[Pair],
    lidx: &impl Fn(usize) -> usize,
    cl: &mut Local,
    same: impl Fn(usize, usize) -> bool,
    meter: &mut Meter,
) -> Result<(), BudgetExceeded> {
    let mut of_joint: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for &pi in &part.pairs {
        let p = pairs[pi];
        let v = of_joint.entry(p.joint).or_default();
        v.push(lidx(p.hub));
        v.push(lidx(p.other));
    }
    for _ in 0..4 {
        let mut changed = false;
        for members in of_joint.values() {
            let mut roots: Vec<usize> = members.iter().map(|&x| cl.root(x)).collect();
            roots.sort_unstable();
            roots.dedup();
            if !roots.iter().any(|&r| cl.has_iso(r)) {
                continue;
            }
            meter.charge((roots.len() as u64).saturating_mul(roots.len() as u64 * 64))?;
            for i in 0..roots.len() {
                for j in 0..i {
                    let (a, c) = (roots[j], roots[i]);
                    if cl.root(a) != cl.root(c)
                        && (cl.has_iso(a) || cl.has_iso(c))
                        && same(cl.rep(a), cl.rep(c))
                    {
                        cl.join(a, c);
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    Ok(())
}

/// The clusters of the forest `uf` (one per body), each named by its root with its bodies
/// ascending.
pub(super) fn clusters(uf: &mut [usize]) -> BTreeMap<usize, Vec<usize>> {
    let mut clusters: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for x in 0..uf.len() {
        let r = find(uf, x);
        clusters.entry(r).or_default().push(x);
    }
    clusters
}
