//! The paper's reference method (MBSSA3D Algorithms 1-3): repeatedly search the connected
//! chains of 1, 2, 3, ... unsolved bodies for the smallest one whose active joints carry exactly
//! as many equations as its bodies have unknowns, mark it solved and start again.
//!
//! The search is exponential in the number of bodies (the paper's Table 16 reports 70,940 s for
//! a 26-body case); it is kept as an independent check of the flow method
//! ([`super::Method::Exhaustive`]) and is only practical for small mechanisms (say ≤ 20 bodies).
//! Every candidate set and every neighbour scanned is charged to a work [`Meter`], so a larger
//! mechanism stops with the budget's error instead of running for hours.

use super::count::{Equations, RawGroup, canonical};
use crate::budget::{BudgetExceeded, Meter};
use crate::mechanism::Mechanism;

/// Groups found by the search, in canonical order, and the bodies it could not place.
pub(crate) struct Search {
    /// The structural groups.
    pub groups: Vec<RawGroup>,
    /// Movable bodies left unsolved (ascending).
    pub unsolved: Vec<usize>,
}

/// Run the smallest-first search with equation counts `eqs.cap` and body unknowns `u`,
/// charging `meter` a unit per candidate set, per body and pair it reads and per neighbour it
/// scans; the budget's error once the meter runs out.
pub(crate) fn search(
    m: &Mechanism,
    eqs: &Equations,
    u: &[u32],
    meter: &mut Meter,
) -> Result<Search, BudgetExceeded> {
    let nb = eqs.nodes;
    let mut nbrs: Vec<Vec<usize>> = vec![Vec::new(); nb];
    for e in 0..eqs.len() {
        let [a, b] = eqs.bodies(e);
        if a != b && a != m.frame && b != m.frame {
            nbrs[a].push(b);
            nbrs[b].push(a);
        }
    }
    for n in &mut nbrs {
        n.sort_unstable();
        n.dedup();
    }
    // Pairs touching each body, to count active equations quickly.
    let mut touching: Vec<Vec<usize>> = vec![Vec::new(); nb];
    for e in 0..eqs.len() {
        let [a, b] = eqs.bodies(e);
        touching[a].push(e);
        if b != a {
            touching[b].push(e);
        }
    }

    let mut solved = vec![false; nb];
    solved[m.frame] = true;
    // Bodies no joint names are not part of the mechanism (reported as disconnected).
    for (b, t) in touching.iter().enumerate() {
        if t.is_empty() {
            solved[b] = true;
        }
    }
    let mut found: Vec<Vec<usize>> = Vec::new();
    let mut group_of = vec![usize::MAX; nb];
    loop {
        let unsolved: Vec<usize> = (0..nb).filter(|&b| !solved[b]).collect();
        if unsolved.is_empty() {
            break;
        }
        meter.charge(nb as u64)?;
        let mut hit: Option<Vec<usize>> = None;
        for size in 1..=unsolved.len() {
            let mut check = |set: &[usize], meter: &mut Meter| {
                let reads: usize = set.iter().map(|&b| touching[b].len()).sum();
                meter.charge((set.len() + reads) as u64)?;
                if satisfies(set, eqs, u, &solved, &touching) {
                    hit = Some(set.to_vec());
                    Ok(true)
                } else {
                    Ok(false)
                }
            };
            if connected_sets(&unsolved, &nbrs, &solved, size, meter, &mut check)? {
                break;
            }
        }
        let Some(mut set) = hit else { break };
        set.sort_unstable();
        for &b in &set {
            solved[b] = true;
            group_of[b] = found.len();
        }
        found.push(set);
    }

    // Dependencies: a pair with equations between two groups is active for the later one.
    let mut deps: Vec<Vec<usize>> = vec![Vec::new(); found.len()];
    for e in 0..eqs.len() {
        if eqs.cap[e] == 0 {
            continue;
        }
        let [a, b] = eqs.bodies(e);
        let (ga, gb) = (group_of[a], group_of[b]);
        if ga == usize::MAX || gb == usize::MAX || ga == gb {
            continue;
        }
        deps[ga.max(gb)].push(ga.min(gb));
    }
    // As the flow method: a group of element nodes only adds no level.
    let mut level = vec![1usize; found.len()];
    for g in 0..found.len() {
        let base = usize::from(found[g].iter().any(|&x| !eqs.is_element(x)));
        level[g] = base + deps[g].iter().map(|&d| level[d]).max().unwrap_or(0);
    }
    Ok(Search {
        groups: canonical(found, level, deps),
        unsolved: (0..nb).filter(|&b| !solved[b]).collect(),
    })
}

/// What [`connected_sets`] calls on each set: `Ok(true)` stops the enumeration.
type Visit<'a> = dyn FnMut(&[usize], &mut Meter) -> Result<bool, BudgetExceeded> + 'a;

/// Whether the active pairs of `set` carry exactly as many equations as it has unknowns.
fn satisfies(
    set: &[usize],
    eqs: &Equations,
    u: &[u32],
    solved: &[bool],
    touching: &[Vec<usize>],
) -> bool {
    let inside = |b: usize| solved[b] || set.contains(&b);
    let mut total: u64 = 0;
    let mut seen: Vec<usize> = Vec::new();
    for &b in set {
        for &e in &touching[b] {
            let [x, y] = eqs.bodies(e);
            if inside(x) && inside(y) && !seen.contains(&e) {
                seen.push(e);
                total += eqs.cap[e] as u64;
            }
        }
    }
    total == set.iter().map(|&b| u[b] as u64).sum::<u64>()
}

/// Visit every connected set of `size` unsolved bodies (Wernicke's ESU enumeration, each set
/// once); stop and return true as soon as `visit` does.
fn connected_sets(
    unsolved: &[usize],
    nbrs: &[Vec<usize>],
    solved: &[bool],
    size: usize,
    meter: &mut Meter,
    visit: &mut Visit<'_>,
) -> Result<bool, BudgetExceeded> {
    for &v in unsolved {
        meter.charge(1 + nbrs[v].len() as u64)?;
        let ext: Vec<usize> = nbrs[v]
            .iter()
            .copied()
            .filter(|&w| w > v && !solved[w])
            .collect();
        let mut sub = vec![v];
        let mut walk = Walk {
            v,
            size,
            nbrs,
            solved,
            meter: &mut *meter,
        };
        if walk.extend(&mut sub, ext, visit)? {
            return Ok(true);
        }
    }
    Ok(false)
}

/// One root's enumeration in [`connected_sets`]: the sets whose smallest body is `v`.
struct Walk<'a> {
    v: usize,
    size: usize,
    nbrs: &'a [Vec<usize>],
    solved: &'a [bool],
    meter: &'a mut Meter,
}

impl Walk<'_> {
    fn extend(
        &mut self,
        sub: &mut Vec<usize>,
        mut ext: Vec<usize>,
        visit: &mut Visit<'_>,
    ) -> Result<bool, BudgetExceeded> {
        let (v, nbrs, solved) = (self.v, self.nbrs, self.solved);
        if sub.len() == self.size {
            return visit(sub, self.meter);
        }
        while let Some(w) = ext.pop() {
            // The scan below reads each neighbour of w against sub and the extension.
            self.meter
                .charge(1 + (nbrs[w].len() * (sub.len() + ext.len() + 1)) as u64)?;
            // Exclusive neighbours of w: not in sub and not adjacent to sub.
            let mut next = ext.clone();
            for &x in &nbrs[w] {
                if x > v
                    && !solved[x]
                    && !sub.contains(&x)
                    && !next.contains(&x)
                    && x != w
                    && !sub.iter().any(|&s| nbrs[s].binary_search(&x).is_ok())
                {
                    next.push(x);
                }
            }
            sub.push(w);
            let stop = self.extend(sub, next, visit);
            sub.pop();
            if stop? {
                return Ok(true);
            }
        }
        Ok(false)
    }
}
