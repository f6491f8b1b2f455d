//! The structure one determined placement gives: its full analysis, or its groups read from
//! the search's own flow ([`Lean`]), as a [`Placement`].

use super::expansion::{Expansion, inputs_of};
use super::partition::{BodyNames, Partition, Repr};
use super::ranked::scores;
use super::{Placement, Scores};
use crate::joint::JointType;
use crate::mechanism::Mechanism;
use crate::structure::{self, Analysis, Library, Status, TypeCount};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Analyse `mech` with the placement `w`; the analysis if it is determined, and the work
/// units of the rank decisions it made.
pub(super) fn evaluate(
    mech: &mut Mechanism,
    w: &[(usize, u32)],
    flow: &[[u8; 2]],
    opts: &structure::Options,
    lib: &Library,
    cache: &structure::AnalysisCache,
    certified: bool,
) -> (Option<Analysis>, u64) {
    for j in &mut mech.joints {
        j.driven = 0;
    }
    for &(q, n) in w {
        mech.joints[q].driven = n;
    }
    // The geometry was checked before the enumeration: this analysis cannot fail.
    match structure::analyze_placement(mech, opts, lib, Some(cache), Some(flow), certified) {
        Ok((a, work)) => (a.filter(|a| a.status == Status::Determined), work),
        Err(_) => (None, 0),
    }
}

pub(super) fn placement(
    mech: &Mechanism,
    e: &Expansion,
    x: usize,
    a: &Analysis,
    w: &[(usize, u32)],
    names: &BodyNames,
) -> Placement {
    let smallest = |g: &structure::Group| {
        g.bodies
            .iter()
            .filter_map(|b| mech.body_index(&crate::mechanism::BodyId::from_text(b)))
            .min()
            .unwrap_or(usize::MAX)
    };
    placement_of(
        mech,
        e,
        x,
        w,
        Groups {
            scores: scores(a),
            types: a.types.clone(),
            partition: names.partition(
                &a.groups
                    .iter()
                    .map(|g| g.bodies.as_slice())
                    .collect::<Vec<_>>(),
            ),
            groups_at: a.groups.iter().map(|g| (g.level, smallest(g))).collect(),
            kinds: a
                .groups
                .iter()
                .map(|g| {
                    a.types
                        .iter()
                        .position(|t| t.kind == g.kind)
                        .unwrap_or(usize::MAX) as u32
                })
                .collect(),
            in_lib: a.groups.iter().map(|g| g.in_library).collect(),
        },
    )
}

/// The groups of a determined placement, as a [`Placement`] keeps them.
pub(super) struct Groups {
    scores: Scores,
    types: Vec<TypeCount>,
    partition: Partition,
    groups_at: Vec<(usize, usize)>,
    kinds: Vec<u32>,
    in_lib: Vec<bool>,
}

pub(super) fn placement_of(
    mech: &Mechanism,
    e: &Expansion,
    x: usize,
    w: &[(usize, u32)],
    g: Groups,
) -> Placement {
    let mut sorted: Vec<(usize, u32)> = w.iter().copied().filter(|&(_, n)| n > 0).collect();
    sorted.sort_by_key(|&(q, _)| (e.origin[q], q));
    Placement {
        rank: None,
        family: None,
        inputs: inputs_of(mech, e, w),
        expansion: e.label.clone(),
        brief: e.brief.clone(),
        scores: g.scores,
        types: g.types,
        partition: g.partition,
        seq: 0,
        exp: x,
        inputs_at: sorted.iter().map(|&(q, _)| e.origin[q]).collect(),
        groups_at: g.groups_at,
        kinds: g.kinds,
        in_lib: g.in_lib,
        lean: None,
    }
}

/// The analysis of a placement the exact rank certifies, from the search's own flow (one pass
/// over arrays, no rank check, no maximum flow, no rendering of the pair lists), with what it
/// reuses across the placements of one expansion: each body's pairs and id.
///
/// Why it is the analysis's answer: the oracle proved the placement's whole system of full
/// row rank, so the certified rank check factorizes nothing and returns the count
/// decomposition (`structure::analyze_placement`); with no isolated freedom in the input-free
/// analysis there is none with inputs either (more rows, smaller null spaces), so every body
/// keeps all its unknowns and every pair its `B − k` equations plus its inputs. The search's
/// flow routes all of them (the placement is determined by count), and the groups of a
/// determined count are the strongly connected components of "an equation flowing into `x`
/// touches `y`" under any perfect flow (the Dulmage–Mendelsohn fine decomposition does not
/// depend on the flow): the same components, levels, canonical order and types.
/// `TransformOptions::full_analyses` runs the full analysis instead; a test compares both.
pub(super) struct Lean {
    /// Pairs touching each body (`touch[start[x]..start[x + 1]]`), a pair of a body with
    /// itself once, in pair order (as `structure::build` lists them).
    start: Vec<usize>,
    touch: Vec<u32>,
    /// Body ids as the analysis writes them (shared with the placements' partitions).
    pub(super) ids: Arc<Vec<String>>,
    /// Each pair's two bodies and joint type (read from the joints, hundreds of bytes apart,
    /// each was a cache miss).
    ends: Vec<[u32; 2]>,
    kind: Vec<JointType>,
    /// The frame's index.
    frame: usize,
    /// Work units of one lean analysis: a few passes over the bodies and pairs.
    pub(super) work: u64,
}

impl Lean {
    pub(super) fn of(m: &Mechanism, ids: &Arc<Vec<String>>) -> Lean {
        let nb = m.bodies.len();
        let mut start = vec![0usize; nb + 1];
        for j in &m.joints {
            if let [a, c] = j.bodies[..] {
                start[a + 1] += 1;
                if c != a {
                    start[c + 1] += 1;
                }
            }
        }
        for i in 0..nb {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut touch = vec![0u32; start[nb]];
        for (q, j) in m.joints.iter().enumerate() {
            if let [a, c] = j.bodies[..] {
                touch[fill[a]] = q as u32;
                fill[a] += 1;
                if c != a {
                    touch[fill[c]] = q as u32;
                    fill[c] += 1;
                }
            }
        }
        let ends = m
            .joints
            .iter()
            .map(|j| match j.bodies[..] {
                [a, c] => [a as u32, c as u32],
                _ => [m.frame as u32; 2],
            })
            .collect();
        Lean {
            start,
            touch,
            ids: Arc::clone(ids),
            ends,
            kind: m.joints.iter().map(|j| j.kind).collect(),
            frame: m.frame,
            work: 8 * (m.bodies.len() + m.joints.len()) as u64 + 100,
        }
    }

    /// The groups (level and bodies, canonical order) of the placement whose search flow (any flow routing all
    /// its equations and inputs: the components do not depend on which) is `flow`.
    pub(super) fn raw(&self, flow: &[[u8; 2]]) -> Vec<(usize, Vec<usize>)> {
        let nb = self.start.len() - 1;
        let frame = self.frame;
        let ends = |q: usize| {
            let [a, c] = self.ends[q];
            (a as usize, c as usize)
        };
        // x -> y: an equation flowing into x touches y (bodies other than the frame).
        let mut deg = vec![0usize; nb + 1];
        let edge = |q: usize, i: usize| -> Option<(usize, usize)> {
            let (a, c) = ends(q);
            let (x, y) = if i == 0 { (a, c) } else { (c, a) };
            (flow.get(q).is_some_and(|f| f[i] > 0) && x != frame && y != frame && x != y)
                .then_some((x, y))
        };
        for q in 0..self.ends.len() {
            for i in 0..2 {
                if let Some((x, _)) = edge(q, i) {
                    deg[x + 1] += 1;
                }
            }
        }
        for i in 0..nb {
            deg[i + 1] += deg[i];
        }
        let mut fill = deg.clone();
        let mut adj = vec![0u32; deg[nb]];
        for q in 0..self.ends.len() {
            for i in 0..2 {
                if let Some((x, y)) = edge(q, i) {
                    adj[fill[x]] = y as u32;
                    fill[x] += 1;
                }
            }
        }
        drop(fill);
        let active: Vec<bool> = (0..nb)
            .map(|x| x != frame && self.start[x + 1] > self.start[x])
            .collect();
        let sccs = structure::tarjan(&deg, &adj, &active);
        // Dependencies first: levels in emission order.
        let mut comp = vec![usize::MAX; nb];
        for (c, s) in sccs.iter().enumerate() {
            for &x in s {
                comp[x] = c;
            }
        }
        let mut level = vec![1usize; sccs.len()];
        for (c, s) in sccs.iter().enumerate() {
            let mut lv = 0;
            for &x in s {
                for &y in &adj[deg[x]..deg[x + 1]] {
                    let d = comp[y as usize];
                    if d != c {
                        lv = lv.max(level[d]);
                    }
                }
            }
            level[c] = 1 + lv;
        }
        let n = sccs.len();
        structure::canonical(sccs, level, vec![Vec::new(); n])
            .into_iter()
            .map(|g| (g.level, g.bodies))
            .collect()
    }

    /// The groups of placement `w` (pairs of `m`, all binary) whose search flow is `flow`.
    pub(super) fn groups(&self, m: &Mechanism, flow: &[[u8; 2]], lib: &Library) -> Groups {
        let nb = m.bodies.len();
        let raw = self.raw(flow);
        // Solve-order key: the frame (and bodies no joint names) first, then the groups.
        let mut key = vec![-2i64; nb];
        for (g, grp) in raw.iter().enumerate() {
            for &x in &grp.1 {
                key[x] = g as i64;
            }
        }
        let mut types: Vec<TypeCount> = Vec::new();
        let mut type_index: BTreeMap<String, usize> = BTreeMap::new();
        let mut out = Groups {
            scores: Scores {
                groups: raw.len(),
                largest: 0,
                levels: 0,
                covered: 0,
                all_covered: true,
            },
            types: Vec::new(),
            partition: Partition(Repr::Text(Vec::new())),
            groups_at: Vec::with_capacity(raw.len()),
            kinds: Vec::with_capacity(raw.len()),
            in_lib: Vec::with_capacity(raw.len()),
        };
        let mut kinds: Vec<(JointType, usize)> = Vec::new();
        for (g, grp) in raw.iter().enumerate() {
            let gk = g as i64;
            let mut kind = self.kind_of(&grp.1, gk, &key, &mut kinds);
            kind.push_str(m.space.suffix());
            let t = match type_index.get(&kind) {
                Some(&t) => t,
                None => {
                    let t = types.len();
                    types.push(TypeCount {
                        kind: kind.clone(),
                        count: 0,
                        in_library: lib.contains(&kind),
                    });
                    type_index.insert(kind.clone(), t);
                    t
                }
            };
            types[t].count += 1;
            let covered = types[t].in_library;
            out.scores.largest = out.scores.largest.max(grp.1.len());
            out.scores.levels = out.scores.levels.max(grp.0);
            out.scores.covered += usize::from(covered);
            out.groups_at
                .push((grp.0, grp.1.first().copied().unwrap_or(usize::MAX)));
            out.kinds.push(t as u32);
            out.in_lib.push(covered);
        }
        out.scores.all_covered = out.scores.covered == raw.len();
        out.types = types;
        out.partition = Partition::indexed(
            &self.ids,
            raw.iter()
                .map(|grp| grp.1.iter().map(|&x| x as u32).collect()),
        );
        out
    }

    /// The SG type of the group of `bodies` (number `gk` in solve order, `key` each body's
    /// group) without its space suffix: its active pairs counted by joint type. `kinds` is a
    /// buffer.
    fn kind_of(
        &self,
        bodies: &[usize],
        gk: i64,
        key: &[i64],
        kinds: &mut Vec<(JointType, usize)>,
    ) -> String {
        let ends = |q: usize| {
            let [a, c] = self.ends[q];
            (a as usize, c as usize)
        };
        kinds.clear();
        for &x in bodies {
            for &q in &self.touch[self.start[x]..self.start[x + 1]] {
                let q = q as usize;
                let (a, c) = ends(q);
                let y = if a == x { c } else { a };
                // Active: internal (counted once, from its first body) or to a body
                // solved before.
                if (key[y] == gk && x != a) || key[y] > gk {
                    continue;
                }
                let jt = self.kind[q];
                match kinds.iter_mut().find(|(k, _)| *k == jt) {
                    Some((_, c)) => *c += 1,
                    None => kinds.push((jt, 1)),
                }
            }
        }
        kinds.sort_unstable_by_key(|&(k, _)| k);
        let mut kind = String::new();
        for (k, n) in kinds.iter() {
            let _ = std::fmt::Write::write_fmt(&mut kind, format_args!("{n}{}", k.code()));
        }
        kind
    }
}
