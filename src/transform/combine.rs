//! The placements of a whole from those of its independent parts: the counts as products,
//! the scores as combined keys, and the best placements of the whole, joined part by part.

use super::partition::{Partition, Repr};
use super::parts::{part_key, part_label, part_mechanism};
use super::place::place;
use super::ranked::compare_scores;
use super::rules::Rules;
use super::{
    Criterion, Input, Placed, Placement, Progress, ProgressFn, Scores, Summary, TransformError,
    TransformOptions, list_cap,
};
use crate::budget::{BudgetExceeded, Meter};
use crate::mechanism::Mechanism;
use crate::structure::{Library, TypeCount};
use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

/// The placement of a whole from one placement per part, each in its part's own indices
/// (`sets[i]`: the part's joints and bodies in the whole's indices), as the analysis of the
/// whole gives it: inputs in the order of the whole's joints (`origin`: the original joint
/// of each joint of an expansion, then the pair), groups in canonical order (level, size,
/// smallest body), types in order of first appearance. A member with `rebuild[i]` was placed
/// on another part of the same structure: its inputs are named by `names` (joint `q`'s id and
/// bodies' label; the part's joints are binary); `expansion`: the label and the brief label
/// ([`Placement::expansion_brief`]). `None` if a member names a joint or body the part lacks (never
/// expected).
#[allow(clippy::too_many_arguments)]
pub(super) fn join_parts(
    names: &dyn Fn(usize) -> Option<(String, String)>,
    origin: Option<&[usize]>,
    sets: &[(Vec<usize>, Vec<usize>)],
    members: &[&Placement],
    rebuild: &[bool],
    ids: &Arc<Vec<String>>,
    (expansion, brief): (Option<String>, Option<String>),
    exp: usize,
) -> Option<Placement> {
    // (original joint, joint, order within the part, input)
    let mut inputs: Vec<(usize, usize, usize, Input)> = Vec::new();
    let mut key: Option<Key> = None;
    // (level, size, smallest body, part, group)
    let mut groups: Vec<(usize, usize, usize, usize, usize)> = Vec::new();
    for (pi, (p, (joints, bodies))) in members.iter().zip(sets).enumerate() {
        for (k, (l, i)) in p.inputs_at.iter().zip(&p.inputs).enumerate() {
            let q = *joints.get(*l)?;
            let o = origin.map_or(Some(q), |o| o.get(q).copied())?;
            let input = if rebuild[pi] {
                let (joint, pair) = names(q)?;
                Input {
                    joint,
                    pair,
                    driven: i.driven,
                }
            } else {
                i.clone()
            };
            inputs.push((o, q, k, input));
        }
        let k = Key::of(&p.scores);
        key = Some(key.map_or(k, |a| a.join(k)));
        for (gi, g) in p.groups_at.iter().enumerate() {
            groups.push((g.0, p.partition.group_len(gi), *bodies.get(g.1)?, pi, gi));
        }
    }
    inputs.sort_unstable_by_key(|i| (i.0, i.1, i.2));
    groups.sort_unstable();
    let (types, kinds, in_lib) = joined_types(members, &groups);
    let partition = joined_partition(members, sets, &groups, ids);
    Some(Placement {
        rank: None,
        family: None,
        scores: key?.scores(),
        inputs_at: inputs.iter().map(|i| i.0).collect(),
        inputs: inputs.into_iter().map(|i| i.3).collect(),
        expansion,
        brief,
        types,
        partition,
        seq: 0,
        exp,
        groups_at: groups.iter().map(|g| (g.0, g.2)).collect(),
        kinds,
        in_lib,
        lean: None,
    })
}

/// The group types of a joined placement in order of first appearance, and each group's
/// type and coverage (`groups`: level, size, smallest body, part, group; canonical order).
fn joined_types(
    members: &[&Placement],
    groups: &[(usize, usize, usize, usize, usize)],
) -> (Vec<TypeCount>, Vec<u32>, Vec<bool>) {
    let mut types: Vec<TypeCount> = Vec::new();
    let mut kinds = Vec::with_capacity(groups.len());
    let mut in_lib = Vec::with_capacity(groups.len());
    for &(_, _, _, pi, gi) in groups {
        let p = members[pi];
        let kind = p
            .kinds
            .get(gi)
            .and_then(|&t| p.types.get(t as usize))
            .map_or("", |t| t.kind.as_str());
        let t = match types.iter().position(|t| t.kind == kind) {
            Some(t) => {
                types[t].count += 1;
                t
            }
            None => {
                types.push(TypeCount {
                    kind: kind.to_string(),
                    count: 1,
                    in_library: p.in_lib[gi],
                });
                types.len() - 1
            }
        };
        kinds.push(t as u32);
        in_lib.push(p.in_lib[gi]);
    }
    (types, kinds, in_lib)
}

/// The partition of a joined placement: its `groups` (level, size, smallest body, part,
/// group; canonical order) with their bodies in the whole's indices.
fn joined_partition(
    members: &[&Placement],
    sets: &[(Vec<usize>, Vec<usize>)],
    groups: &[(usize, usize, usize, usize, usize)],
    ids: &Arc<Vec<String>>,
) -> Partition {
    // A group's bodies in the whole's indices (`None`: a part named a body its id table
    // lacks, never expected; the partition is then kept as text).
    let whole = |pi: usize, gi: usize| -> Option<Vec<u32>> {
        let bodies = &sets[pi].1;
        match &members[pi].partition.0 {
            Repr::Indexed {
                bodies: local,
                ends,
                ..
            } => Some(
                local[Partition::range(ends, gi)]
                    .iter()
                    .map(|&b| bodies.get(b as usize).map_or(u32::MAX, |&g| g as u32))
                    .collect(),
            ),
            Repr::Text(_) => None,
        }
    };
    let indexed = members
        .iter()
        .all(|p| matches!(p.partition.0, Repr::Indexed { .. }));
    if indexed {
        Partition::indexed(
            ids,
            groups
                .iter()
                .map(|&(_, _, _, pi, gi)| whole(pi, gi).unwrap_or_default()),
        )
    } else {
        Partition(Repr::Text(
            groups
                .iter()
                .map(|&(_, _, _, pi, gi)| match whole(pi, gi) {
                    Some(v) => v
                        .iter()
                        .map(|&b| ids.get(b as usize).cloned().unwrap_or_default())
                        .collect(),
                    None => members[pi]
                        .partition
                        .group(gi)
                        .into_iter()
                        .map(str::to_string)
                        .collect(),
                })
                .collect(),
        ))
    }
}

/// The scores of a placement as a combinable key: groups and covered groups add up over the
/// parts, "every group covered" is the conjunction, the largest group and the levels are the
/// maxima. So the whole's scores are a function of the parts' keys, and ranking the whole
/// by any `--rank` order only needs each part's placements grouped by key.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Key {
    groups: usize,
    covered: usize,
    all_covered: bool,
    largest: usize,
    levels: usize,
}

impl Key {
    fn of(s: &Scores) -> Key {
        Key {
            groups: s.groups,
            covered: s.covered,
            all_covered: s.all_covered,
            largest: s.largest,
            levels: s.levels,
        }
    }
    fn join(self, o: Key) -> Key {
        Key {
            groups: self.groups + o.groups,
            covered: self.covered + o.covered,
            all_covered: self.all_covered && o.all_covered,
            largest: self.largest.max(o.largest),
            levels: self.levels.max(o.levels),
        }
    }
    fn scores(self) -> Scores {
        Scores {
            groups: self.groups,
            largest: self.largest,
            levels: self.levels,
            covered: self.covered,
            all_covered: self.all_covered,
        }
    }
}

/// One part's placements by key: how many, and the first `cap` of each (enumeration order,
/// in the part's own indices), with what placing it found. Kept once for every part of the
/// same structure ([`combine_parts`]).
struct PartKeys {
    placed: Placed,
    keys: Vec<(Key, u128, Vec<Placement>)>,
    /// Placed on a part of the same structure that may be another (binary joints, random
    /// geometry): its inputs are named from the whole's joints.
    shared: bool,
}

/// Place every part, count the whole as the product of the parts' counts, and stream the best
/// placements of the whole (best first, at most [`list_cap`]).
///
/// Parts of the same structure (bodies in order, the frame's position, each joint's type,
/// bodies and rules) with binary joints and a random realization (drawn by joint index, and
/// a part's joints are numbered alike) or none are placed once: a star of 10^6 bodies on the
/// frame is one analysis of a one-body part, not 10^6 of them, and no part's mechanism is
/// held past its placing (a `Mechanism` per part held at once was 3.3 GB at 10^6).
#[allow(clippy::too_many_arguments)]
pub(super) fn combine_parts(
    m: &Mechanism,
    sets: &[(Vec<usize>, Vec<usize>)],
    rules: &Rules,
    opts: &TransformOptions,
    lib: &Library,
    meter: &mut Meter,
    progress: Option<ProgressFn<'_>>,
    summary: &mut Summary,
    sink: &mut dyn FnMut(Placement),
) -> Result<(), TransformError> {
    let cap = list_cap(m, opts.limit);
    let (memo, per) = place_parts(m, sets, rules, opts, lib, meter, progress, summary, cap)?;
    if summary.determined == 0 {
        return Ok(());
    }
    let layers = key_layers(&memo, &per, meter)?;
    let criteria = if opts.rank.is_empty() {
        Criterion::DEFAULT.to_vec()
    } else {
        opts.rank.clone()
    };
    let Some(last) = layers.last() else {
        return Ok(());
    };
    let mut whole: Vec<Key> = last.iter().map(|(k, _)| *k).collect();
    whole.sort_by(|a, b| compare_scores(&a.scores(), &b.scores(), &criteria).then(a.cmp(b)));
    let parts = Whole {
        m,
        sets,
        memo: &memo,
        per: &per,
        layers: &layers,
        ids: Arc::new(m.bodies.iter().map(|b| b.id.to_string()).collect()),
        rebuild: per.iter().map(|&at| memo[at].shared).collect(),
        cap,
    };
    let mut listed = 0usize;
    for target in whole {
        if !parts.stream_key(target, &mut listed, meter, sink)? {
            break;
        }
    }
    summary.listed = listed;
    Ok(())
}

/// Place every part of `m` (`sets`), once per structure where parts may share it, and count
/// the whole in `summary` (counts, truncation, notes). Each part's placements by key
/// (`memo`), and the entry of `memo` of each part.
#[allow(clippy::too_many_arguments)]
fn place_parts(
    m: &Mechanism,
    sets: &[(Vec<usize>, Vec<usize>)],
    rules: &Rules,
    opts: &TransformOptions,
    lib: &Library,
    meter: &mut Meter,
    progress: Option<ProgressFn<'_>>,
    summary: &mut Summary,
    cap: usize,
) -> Result<(Vec<PartKeys>, Vec<usize>), TransformError> {
    let mut memo: Vec<PartKeys> = Vec::new();
    let mut index: HashMap<Vec<u32>, usize> = HashMap::new();
    let mut per: Vec<usize> = Vec::with_capacity(sets.len());
    let (mut count_valid, mut determined) = (1u128, 1u128);
    summary.expansions = 1;
    summary.expansions_total = 1;
    let mut examined = 0usize;
    let mut local = vec![usize::MAX; m.bodies.len()];
    let mut key: Vec<u32> = Vec::new();
    for (pi, (joints, bodies)) in sets.iter().enumerate() {
        let shared = shareable(m, joints, rules, opts);
        let seen = if shared {
            let joint = |q: usize| (m.joints[q].kind, &m.joints[q].bodies[..], q);
            part_key(m, joints, bodies, joint, rules, &mut local, &mut key);
            index.get(&key).copied()
        } else {
            None
        };
        let at = match seen {
            Some(at) => at,
            None => {
                let mech = part_mechanism(m, joints, bodies, &mut local);
                let prules = rules.restrict(joints);
                let keys = part_keys(&mech, &prules, opts, lib, meter, cap, shared)?;
                memo.push(keys);
                if shared {
                    index.insert(key.clone(), memo.len() - 1);
                }
                memo.len() - 1
            }
        };
        per.push(at);
        let r = &memo[at].placed;
        summary.absorb(r);
        summary.truncated |= r.cut;
        examined += r.count_valid;
        count_valid = count_valid.saturating_mul(r.count_valid as u128);
        determined = determined.saturating_mul(r.determined as u128);
        for n in &r.notes {
            let n = format!("part {} ({}): {n}", pi + 1, part_label(m, bodies));
            summary.notes.push(n);
        }
        if let Some(cb) = progress {
            cb(Progress {
                examined,
                total: examined,
                determined: 0,
            });
        }
    }
    summary.count_valid = count_valid;
    summary.determined = determined;
    summary.excluded_by_rank = count_valid.saturating_sub(determined);
    if count_valid == u128::MAX {
        summary.excluded_by_rank = 0;
    }
    summary.notes.push(format!(
        "{} independent parts (joined only through the frame), placed one by one: the counts \
         are the products of the parts' counts",
        sets.len()
    ));
    Ok((memo, per))
}

/// Whether the part of `m` with `joints` may be placed once for every part of its
/// structure: binary joints and a random realization or none. A part alone takes the file's
/// geometry (when the whole lacks some) if all its joints have theirs: placed alone then,
/// as before.
fn shareable(m: &Mechanism, joints: &[usize], rules: &Rules, opts: &TransformOptions) -> bool {
    rules.random
        && joints.iter().all(|&j| m.joints[j].bodies.len() == 2)
        && (opts.analysis.count_only
            || matches!(
                opts.analysis.geometry,
                crate::geometry::GeometrySource::Random { .. }
            )
            || joints.iter().all(|&j| m.joints[j].geometry.is_empty()))
}

/// Place one part's mechanism and keep its placements by key (the first `cap` of each).
fn part_keys(
    mech: &Mechanism,
    prules: &Rules,
    opts: &TransformOptions,
    lib: &Library,
    meter: &mut Meter,
    cap: usize,
    shared: bool,
) -> Result<PartKeys, TransformError> {
    let mut by: BTreeMap<Key, (u128, Vec<Placement>)> = BTreeMap::new();
    let placed = place(
        mech,
        prules,
        opts,
        lib,
        meter,
        None,
        &mut |p| {
            let e = by.entry(Key::of(&p.scores)).or_default();
            e.0 += 1;
            if e.1.len() < cap {
                e.1.push(p);
            }
            true
        },
        None,
    )?;
    Ok(PartKeys {
        placed,
        keys: by.into_iter().map(|(k, (n, v))| (k, n, v)).collect(),
        shared,
    })
}

/// The keys of the whole, part by part: layer i holds the keys of parts 0..=i combined, with
/// how many placements give each.
fn key_layers(
    memo: &[PartKeys],
    per: &[usize],
    meter: &mut Meter,
) -> Result<Vec<Vec<(Key, u128)>>, BudgetExceeded> {
    let mut layers: Vec<Vec<(Key, u128)>> = Vec::with_capacity(per.len());
    for (i, &at) in per.iter().enumerate() {
        let pk = &memo[at];
        let mut next: BTreeMap<Key, u128> = BTreeMap::new();
        if i == 0 {
            for (k, n, _) in &pk.keys {
                next.insert(*k, *n);
            }
        } else {
            let prev = &layers[i - 1];
            meter.charge((prev.len() * pk.keys.len()) as u64 + 1)?;
            for (a, na) in prev {
                for (b, nb, _) in &pk.keys {
                    let (a, na) = (*a, *na);
                    let e = next.entry(a.join(*b)).or_insert(0);
                    *e = e.saturating_add(na.saturating_mul(*nb));
                }
            }
        }
        layers.push(next.into_iter().collect());
    }
    Ok(layers)
}

/// The placed parts of a whole, from which its best placements are joined.
struct Whole<'a> {
    m: &'a Mechanism,
    sets: &'a [(Vec<usize>, Vec<usize>)],
    memo: &'a [PartKeys],
    per: &'a [usize],
    layers: &'a [Vec<(Key, u128)>],
    /// The whole's body ids.
    ids: Arc<Vec<String>>,
    /// Whether each part's inputs are named from the whole's joints.
    rebuild: Vec<bool>,
    /// The most placements listed.
    cap: usize,
}

impl Whole<'_> {
    /// Stream the placements of key `target`: every choice of one key per part that joins to
    /// `target`, the last part first. `false` once the listing stops.
    fn stream_key(
        &self,
        target: Key,
        listed: &mut usize,
        meter: &mut Meter,
        sink: &mut dyn FnMut(Placement),
    ) -> Result<bool, BudgetExceeded> {
        let (memo, per, layers) = (self.memo, self.per, self.layers);
        let n = per.len();
        let mut tgt = vec![target; n];
        let mut cursor = vec![0usize; n];
        let mut chosen = vec![0usize; n];
        let mut i = n - 1;
        loop {
            let np = if i == 0 { 1 } else { layers[i - 1].len() };
            let total = memo[per[i]].keys.len() * np;
            let mut hit = false;
            while cursor[i] < total {
                let c = cursor[i];
                cursor[i] += 1;
                meter.charge(1)?;
                let (si, pj) = (c / np, c % np);
                let k = memo[per[i]].keys[si].0;
                if i == 0 {
                    if k == tgt[0] {
                        chosen[0] = si;
                        hit = true;
                        break;
                    }
                } else if let Some(&(prev, _)) = layers[i - 1].get(pj)
                    && prev.join(k) == tgt[i]
                {
                    chosen[i] = si;
                    tgt[i - 1] = prev;
                    hit = true;
                    break;
                }
            }
            if !hit {
                if i == n - 1 {
                    return Ok(true);
                }
                i += 1;
                continue;
            }
            if i > 0 {
                i -= 1;
                cursor[i] = 0;
                continue;
            }
            if !self.stream_product(&chosen, listed, meter, sink)? {
                return Ok(false);
            }
        }
    }

    /// A full choice (`chosen`: a key of each part): the product of the parts' listed
    /// placements, the last part varying fastest. `false` once the listing stops.
    fn stream_product(
        &self,
        chosen: &[usize],
        listed: &mut usize,
        meter: &mut Meter,
        sink: &mut dyn FnMut(Placement),
    ) -> Result<bool, BudgetExceeded> {
        let m = self.m;
        let n = self.per.len();
        let lists: Vec<&Vec<Placement>> = (0..n)
            .map(|p| &self.memo[self.per[p]].keys[chosen[p]].2)
            .collect();
        let mut digit = vec![0usize; n];
        'prod: loop {
            meter.charge(n as u64)?;
            let members: Vec<&Placement> = (0..n).map(|p| &lists[p][digit[p]]).collect();
            let labels: Vec<String> = members.iter().filter_map(|p| p.expansion.clone()).collect();
            let briefs: Vec<&str> = members.iter().filter_map(|p| p.expansion_brief()).collect();
            let cut = members.iter().any(|p| p.brief.is_some());
            let names = |q: usize| {
                let j = m.joints.get(q)?;
                Some((j.id.clone(), m.joint_bodies_label(j)))
            };
            let Some(mut p) = join_parts(
                &names,
                None,
                self.sets,
                &members,
                &self.rebuild,
                &self.ids,
                (
                    (!labels.is_empty()).then(|| labels.join("; ")),
                    cut.then(|| briefs.join("; ")),
                ),
                members.iter().map(|p| p.exp).max().unwrap_or(0),
            ) else {
                return Ok(false);
            };
            p.seq = *listed;
            sink(p);
            *listed += 1;
            if *listed >= self.cap {
                return Ok(false);
            }
            let mut d = n;
            loop {
                if d == 0 {
                    break 'prod;
                }
                d -= 1;
                digit[d] += 1;
                if digit[d] < lists[d].len() {
                    continue 'prod;
                }
                digit[d] = 0;
            }
        }
        Ok(true)
    }
}
