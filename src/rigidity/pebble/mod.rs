//! Generic rigidity by counting: the pebble game on the body-bar multigraph.
//!
//! Every body is a vertex carrying B pebbles (B = 6 spatial, 3 planar or spherical). A binary
//! joint of grade k is B − k parallel bars between its two bodies (Tay's body-bar count). A
//! multiple joint of n ≥ 3 bodies becomes a *joint node* carrying B − k pebbles, with B − k bars
//! from each of its bodies to the node: the shared element (the common pin of a planar multiple
//! revolute, the common centre of a multiple spherical joint). Its count is exactly the hub
//! expansion's (n − 1 pairs of B − k bars), but, unlike that expansion, it knows that all the
//! bodies share one element, so two triangles pinned at a common point are two rigid
//! components, as in the bar-joint framework.
//!
//! A bar set is independent when every vertex set V′ spanning bars holds at most
//! w(V′) − B of them (w = pebbles: B per body, B − k per node); for bodies alone this is the
//! (B, B) count of Tay's theorem (generically rigid iff B edge-disjoint spanning trees). The
//! pebble game decides independence bar by bar; a rejected bar is redundant and the minimal
//! tight set the failed search visits is the support of its fundamental circuit. Rigid
//! components are maximal tight sets (w(V′) − B independent bars), found after the game with
//! Lee and Streinu's reverse search. Searches are local in practice; the worst case is
//! O(bars · (bodies + bars)).

use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::mechanism::Mechanism;
use serde::Serialize;

mod contract;
mod fast;
mod game;
mod graph;
mod regions;
#[cfg(test)]
mod tests;

use fast::solve_fast;
use game::solve;
use graph::Graph;
use regions::{regions, regions_of_overconstrained};

/// What the analysis counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PebbleOptions {
    /// Count each driven DOF as one more bar on its joint (default: inputs are ignored).
    pub with_inputs: bool,
}

/// An overconstrained region: a connected part of the redundancy (the union of fundamental
/// circuits that share bars, i.e. a connected component of the count matroid).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Region {
    /// Bodies touched by the region's bars, in model order.
    pub bodies: Vec<String>,
    /// Joints whose bars take part, in file order.
    pub joints: Vec<String>,
    /// Redundant bars (constraints) in the region.
    pub redundant: u64,
}

/// The limits of counting, stated in every report.
pub const LIMITS: &str = "Counting is exact for generic body-bar and body-hinge frameworks (and for \
planar bar-joint frameworks written as bars pinned at shared points). Special geometry (parallel \
or concurrent axes, spherical joints, S-S bars, planar or spherical loops written in space) can \
make it wrong in either direction; the geometric analysis is the remedy.";

/// Generic rigidity of a mechanism from its topology alone.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct PebbleReport {
    /// Mechanism name.
    pub name: String,
    /// Motion space name.
    pub space: &'static str,
    /// DOF of a free body (6 or 3).
    pub b: u32,
    /// Number of bodies, the frame included.
    pub bodies: usize,
    /// Number of bars of the body-bar graph: B − k per binary joint, n·(B − k) from the n
    /// bodies of a multiple joint to its node, plus one per driven DOF when counted.
    pub bars: u64,
    /// Whether driven inputs were counted as bars.
    pub with_inputs: bool,
    /// Chebyshev-Gruebler-Kutzbach count B·Nm − Σ pairs·(B − k) (inputs never subtracted).
    pub count: i64,
    /// Generic DOF with the frame fixed: `count + redundant` (minus the inputs when counted).
    pub dof: i64,
    /// Generic DOF of the free chain, the B motions of the whole included (`dof + B`).
    pub dof_free: i64,
    /// Redundant bars: constraints that generic geometry already implies.
    pub redundant: u64,
    /// Maximal rigid components (body ids): every component of at least two bodies, plus the
    /// frame's component even if the frame is alone in it. Bodies not listed are rigid
    /// components on their own. Sorted by first body in model order.
    pub rigid: Vec<Vec<String>>,
    /// Bodies rigidly attached to the frame (they cannot move).
    pub immobile: Vec<String>,
    /// Overconstrained regions, sorted by first body.
    pub overconstrained: Vec<Region>,
    /// True when a proper sub-chain of at least two bodies is rigid on its own (it could be
    /// replaced by one body; structural synthesis calls such a chain degenerate). When the
    /// whole chain is rigid this is checked by deleting each body in turn.
    pub degenerate: bool,
    /// What counting can and cannot tell.
    pub limits: &'static str,
}

/// Analyse the generic rigidity of `m` (no work limit).
pub fn analyze(m: &Mechanism, opts: &PebbleOptions) -> PebbleReport {
    // An unlimited meter never runs out; the reference is only a panic-free fallback.
    analyze_within(m, opts, &Budget::UNLIMITED).unwrap_or_else(|_| analyze_reference(m, opts))
}

/// Analyse the generic rigidity of `m` within `budget`: the component pebble game, whose
/// loops charge a work meter (about one unit per bar looked at); past
/// [`Budget::max_work`], the typed error.
pub fn analyze_within(
    m: &Mechanism,
    opts: &PebbleOptions,
    budget: &Budget,
) -> Result<PebbleReport, BudgetExceeded> {
    let mut meter = budget.meter("the pebble game");
    analyze_metered(m, opts, &mut meter)
}

/// The analysis and the work units it charged (no limit): for the scale tests and the
/// benchmarks, which compare work (deterministic) rather than time.
#[doc(hidden)]
pub fn analyze_counting_work(m: &Mechanism, opts: &PebbleOptions) -> (PebbleReport, u64) {
    let mut meter = Budget::UNLIMITED.meter("the pebble game");
    match analyze_metered(m, opts, &mut meter) {
        Ok(r) => (r, meter.used()),
        Err(_) => (analyze_reference(m, opts), meter.used()),
    }
}

fn analyze_metered(
    m: &Mechanism,
    opts: &PebbleOptions,
    meter: &mut Meter,
) -> Result<PebbleReport, BudgetExceeded> {
    let l = m.b() as u8;
    let g = Graph::build(m, opts, None);
    meter.charge(g.bars.len() as u64 + g.weight.len() as u64)?;
    let sol = solve_fast(&g, l, meter)?;
    let overconstrained = if sol.accepted.iter().all(|&a| a) {
        Vec::new()
    } else {
        regions_of_overconstrained(m, &g, &sol, l, meter)?
    };
    let n = m.bodies.len();
    let degenerate = if sol.components.iter().any(|c| c.len() >= 2 && c.len() < n) {
        true
    } else if n > 2 && sol.components.iter().any(|c| c.len() == n) {
        // The whole chain is rigid: a proper rigid sub-chain avoids some body. One that the
        // game contracted on its way (a tight set stays tight as bars are added) settles it;
        // otherwise the game runs again without each body in turn.
        let mut found = sol.game.proper;
        for w in 0..n {
            if found {
                break;
            }
            let g = Graph::build(m, opts, Some(w));
            meter.charge(g.bars.len() as u64 + g.weight.len() as u64)?;
            if solve_fast(&g, l, meter)?
                .components
                .iter()
                .any(|c| c.iter().filter(|&&x| x != w).count() >= 2)
            {
                found = true;
                break;
            }
        }
        found
    } else {
        false
    };
    Ok(report(
        m,
        opts,
        &g,
        &sol.accepted,
        &sol.components,
        overconstrained,
        degenerate,
    ))
}

/// The same analysis by the plain pebble game (no component bookkeeping, components found
/// after the game, a search per bar): quadratic on large rigid frameworks. Kept as the test
/// oracle of [`analyze`] (`tests/it/pebble_props.rs`).
#[doc(hidden)]
pub fn analyze_reference(m: &Mechanism, opts: &PebbleOptions) -> PebbleReport {
    let l = m.b() as u8;
    let g = Graph::build(m, opts, None);
    let mut meter = Budget::UNLIMITED.meter("the pebble game");
    let Ok(mut sol) = solve(&g, l, true, &mut meter) else {
        unreachable!("an unlimited meter never runs out")
    };
    let overconstrained = match &mut sol.circuits {
        Some(dsu) => regions(m, &g, &sol.accepted, dsu),
        None => Vec::new(),
    };
    let n = m.bodies.len();
    let degenerate = if sol.components.iter().any(|c| c.len() >= 2 && c.len() < n) {
        true
    } else if n > 2 && sol.components.iter().any(|c| c.len() == n) {
        (0..n).any(|w| {
            let g = Graph::build(m, opts, Some(w));
            solve(&g, l, false, &mut meter).is_ok_and(|s| {
                s.components
                    .iter()
                    .any(|c| c.iter().filter(|&&x| x != w).count() >= 2)
            })
        })
    } else {
        false
    };
    report(
        m,
        opts,
        &g,
        &sol.accepted,
        &sol.components,
        overconstrained,
        degenerate,
    )
}

/// Assemble the report from the game's outcome.
fn report(
    m: &Mechanism,
    opts: &PebbleOptions,
    g: &Graph,
    accepted: &[bool],
    components: &[Vec<usize>],
    overconstrained: Vec<Region>,
    degenerate: bool,
) -> PebbleReport {
    let b = m.b();
    let rank = accepted.iter().filter(|&&a| a).count() as i64;
    let redundant = g.bars.len() as u64 - rank as u64;
    let total_weight: i64 = g.weight.iter().map(|&w| w as i64).sum();
    let dof_free = total_weight - rank;
    let constraints: i64 = m
        .joints
        .iter()
        .map(|j| j.pairs() as i64 * b.saturating_sub(j.grade()) as i64)
        .sum();
    let count = b as i64 * m.movable() as i64 - constraints;
    let id = |i: usize| m.body_id(i).to_string();

    let frame = m.frame;
    let mut comps: Vec<Vec<usize>> = components
        .iter()
        .filter(|c| c.len() >= 2 || c.contains(&frame))
        .cloned()
        .collect();
    if frame < m.bodies.len() && !comps.iter().any(|c| c.contains(&frame)) {
        comps.push(vec![frame]);
    }
    comps.sort();
    let immobile = comps
        .iter()
        .find(|c| c.contains(&frame))
        .map(|c| c.iter().filter(|&&x| x != frame).map(|&x| id(x)).collect())
        .unwrap_or_default();

    PebbleReport {
        name: m.name.clone(),
        space: m.space.name(),
        b,
        bodies: m.bodies.len(),
        bars: g.bars.len() as u64,
        with_inputs: opts.with_inputs,
        count,
        dof: dof_free - b as i64,
        dof_free,
        redundant,
        rigid: comps
            .into_iter()
            .map(|c| c.into_iter().map(id).collect())
            .collect(),
        immobile,
        overconstrained,
        degenerate,
        limits: LIMITS,
    }
}
