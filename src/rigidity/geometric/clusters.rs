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

/// Clusters with isolated motions compared with the clusters sharing a joint with them (the
/// bodies of each joint of the part: a multiple joint's bodies are not all pairs of each
/// other), merged when `same` says they move alike, until nothing changes (at most 4 rounds).
/// Shared by the exact and the sparse floating-point paths.
pub(super) fn merge_across_joints(
    part: &Part,
    pairs: &[Pair],
    lidx: &impl Fn(usize) -> usize,
    luf: &mut [usize],
    has_iso: impl Fn(usize) -> bool,
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
            let mut roots: Vec<usize> = members.iter().map(|&x| find(luf, x)).collect();
            roots.sort_unstable();
            roots.dedup();
            if !roots.iter().any(|&r| has_iso(r)) {
                continue;
            }
            meter.charge((roots.len() as u64).saturating_mul(roots.len() as u64 * 64))?;
            for i in 0..roots.len() {
                for j in 0..i {
                    let (a, c) = (roots[j], roots[i]);
                    if find(luf, a) == a
                        && find(luf, c) == c
                        && (has_iso(a) || has_iso(c))
                        && same(a, c)
                    {
                        luf[c] = a;
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
