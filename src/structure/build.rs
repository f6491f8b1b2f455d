//! The analysis assembled from a decomposition: each structural group's pair lists (from,
//! internal, to), type and inputs, the groups shown with their types, and the status.

use super::count::{Decomposition, Equations, Part, RawGroup};
use super::diagnose::diagnose;
use super::{
    Analysis, CountSummary, Diagnosis, Group, Isolated, Library, Missing, Near, Options,
    Redundancy, Status, TypeCount, UnderPart, UnderPiece, locked_planar, push_id, roman,
    spatiality,
};
use crate::joint::JointType;
use crate::mechanism::{BodyId, Mechanism};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// The analysis of `m` from its decomposition `dec` and groups `raw` (in canonical order).
#[allow(clippy::too_many_arguments)]
pub(super) fn build(
    m: &Mechanism,
    eqs: &Equations,
    dec: &Decomposition,
    raw: Vec<RawGroup>,
    unsolved: Vec<usize>,
    isolated: Vec<Isolated>,
    redundant: Vec<Redundancy>,
    opts: &Options,
    lib: &Library,
    twists: Option<&[nalgebra::DMatrix<f64>]>,
) -> Analysis {
    let ids = BodyIds::of(m);
    let key = solve_keys(m, dec, &raw, eqs.nodes);
    let (start, near) = near_lists(m, eqs);
    // Each group's pair lists, type and inputs on its own (in parallel: they read shared
    // data only); then the types are numbered in order of first appearance.
    let lists = GroupLists {
        m,
        eqs,
        key: &key,
        start: &start,
        near: &near,
        ids: &ids,
        twists,
    };
    let rendered: Vec<Rendered> = crate::par::map(raw.len(), |g| lists.render(g, &raw[g]));
    // The pair lists are written: their inputs (115 MB at 10^6 bodies) are freed before the
    // groups are made, not held with them.
    drop(near);
    drop(start);
    drop(key);
    let (groups, types) = shown_groups(eqs, &raw, rendered, lib, &ids);
    let mut diag = diagnose(m, eqs, dec, unsolved, &redundant, &isolated);
    let disconnected = disconnected(m, &ids);
    free_bodies(m, &disconnected, &mut diag);
    let status = status_of(m, &diag, &redundant);
    let mob = crate::mobility::mobility(m);
    let uncontrolled = diag.underdetermined.as_ref().map_or(0, |u| u.missing);
    // Notes for a determined mechanism: the redundant constraints set aside.
    let notes = if status == Status::Determined {
        std::mem::take(&mut diag.notes)
    } else {
        Vec::new()
    };
    Analysis {
        name: m.name.clone(),
        space: m.space.name(),
        b: m.b(),
        method: opts.method,
        count_only: opts.count_only,
        mobility: CountSummary {
            count: mob.mobility.count,
            inputs: mob.mobility.inputs,
        },
        status,
        geometry: None,
        uncontrolled,
        disconnected,
        levels: levels(eqs, &raw),
        groups,
        types,
        library: lib.name.clone(),
        isolated,
        spins: Vec::new(),
        redundant,
        unchecked: Vec::new(),
        diagnosis: (status != Status::Determined || !diag.unsolved.is_empty()).then_some(diag),
        generic: None,
        notes,
        set_aside: vec![0; m.joints.len()],
        finite: None,
    }
}

/// The highest level of a group of bodies (groups of element nodes only left out).
fn levels(eqs: &Equations, raw: &[RawGroup]) -> usize {
    raw.iter()
        .filter(|g| g.bodies.iter().any(|&x| !eqs.is_element(x)))
        .map(|g| g.level)
        .max()
        .unwrap_or(0)
}

/// Every body id written once, in body order; the group lists copy them from here (read from
/// the bodies, 48 bytes apart, each id was a cache miss at 10^6 bodies).
struct BodyIds {
    text: String,
    at: Vec<usize>,
    /// Integer ids that are their body's index plus one constant (every generated file) are
    /// written from the index: the group lists name bodies at random, and each read of the id
    /// table was two cache misses at 10^6 bodies.
    int_base: Option<i64>,
}

impl BodyIds {
    fn of(m: &Mechanism) -> BodyIds {
        let mut text = String::with_capacity(8 * m.bodies.len());
        let mut at = Vec::with_capacity(m.bodies.len() + 1);
        at.push(0);
        for body in &m.bodies {
            push_id(&mut text, &body.id);
            at.push(text.len());
        }
        let int_base = match m.bodies.first().map(|b| &b.id) {
            Some(BodyId::Int(first)) => {
                let follows = m.bodies.iter().enumerate().all(|(k, b)| {
                    matches!(b.id, BodyId::Int(i)
                        if i64::try_from(k).ok().and_then(|k| k.checked_add(*first)) == Some(i))
                });
                follows.then_some(*first)
            }
            _ => None,
        };
        BodyIds { text, at, int_base }
    }

    /// Body `b`'s id.
    fn get(&self, b: usize) -> &str {
        &self.text[self.at[b]..self.at[b + 1]]
    }

    /// Append body `b`'s id to `s`.
    fn put(&self, s: &mut String, b: usize) {
        match self.int_base {
            Some(c) => crate::format::push_int(s, b as i64 + c),
            None => s.push_str(self.get(b)),
        }
    }
}

/// The solve-order key of group `g`.
fn group_key(g: usize) -> u32 {
    u32::try_from(g + 2).unwrap_or(u32::MAX - 1)
}

/// Solve-order key of every node: frame (0) and over-determined part (1) are known first,
/// groups in canonical order (group g is g + 2), the under-determined part (or unsolved
/// bodies) last. Four bytes a node: the group lists read it at random.
fn solve_keys(m: &Mechanism, dec: &Decomposition, raw: &[RawGroup], nb: usize) -> Vec<u32> {
    let mut key = vec![u32::MAX; nb];
    for (b, k) in key.iter_mut().enumerate() {
        *k = match dec.body_part[b] {
            Part::Frame => 0,
            Part::Over => 1,
            _ => u32::MAX,
        };
    }
    for (g, grp) in raw.iter().enumerate() {
        for &b in &grp.bodies {
            key[b] = group_key(g);
        }
    }
    if let Some(k) = key.get_mut(m.frame) {
        *k = 0;
    }
    key
}

/// Pairs touching each node, compressed (`near[start[x]..start[x + 1]]`), in pair order, each
/// with what the group lists need of it: reading the pair's fields from `eqs` and the joint's
/// kind from the joint was five cache misses a pair at 10^6 bodies.
fn near_lists(m: &Mechanism, eqs: &Equations) -> (Vec<usize>, Vec<Near>) {
    let nb = eqs.nodes;
    let mut start = vec![0usize; nb + 1];
    for e in 0..eqs.len() {
        let [a, c] = eqs.bodies(e);
        start[a + 1] += 1;
        if c != a {
            start[c + 1] += 1;
        }
    }
    for i in 0..nb {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let blank = Near {
        y: 0,
        e: 0,
        driven: 0,
        joint: 0,
        kind: JointType::R,
        hub: false,
        input_only: false,
    };
    let mut near = vec![blank; start[nb]];
    for e in 0..eqs.len() {
        let [a, c] = eqs.bodies(e);
        let ji = eqs.joint[e];
        let p = Near {
            y: c as u32,
            e: e as u32,
            driven: eqs.driven[e],
            joint: ji as u32,
            kind: m.joints[ji].kind,
            hub: true,
            input_only: eqs.input_only[e],
        };
        near[fill[a]] = p;
        fill[a] += 1;
        if c != a {
            near[fill[c]] = Near {
                y: a as u32,
                hub: false,
                ..p
            };
            fill[c] += 1;
        }
    }
    (start, near)
}

/// A group's type, its pair lists (from, internal, to) and its inputs, as written.
type Rendered = (String, String, String, String, u32);

/// A pair in a group's lists: (first body, second body, pair, its joint's kind).
type Listed = (u32, u32, u32, JointType);

/// What the group lists read: the solve-order keys, the pairs near every node, the body ids
/// and the joints' twists at the file's configuration (spatial file geometry only).
struct GroupLists<'a> {
    m: &'a Mechanism,
    eqs: &'a Equations,
    key: &'a [u32],
    start: &'a [usize],
    near: &'a [Near],
    ids: &'a BodyIds,
    twists: Option<&'a [nalgebra::DMatrix<f64>]>,
}

/// One group's pairs as they are collected.
#[derive(Default)]
struct GroupPairs {
    from: Vec<Listed>,
    internal: Vec<Listed>,
    to: Vec<Listed>,
    /// Pairs per joint kind, in order of first appearance.
    kinds: Vec<(JointType, usize)>,
    inputs: u32,
    active_joints: Vec<usize>,
    /// (joint, its kind, pairs counted), to retype a joint that acts as a planar one.
    counted: Vec<(usize, JointType, usize)>,
}

impl GroupPairs {
    /// `n` pairs of joint `ji` (kind `jt`) count for the group.
    fn add_kind(&mut self, ji: usize, jt: JointType, n: usize) {
        if n == 0 {
            return;
        }
        self.active_joints.push(ji);
        self.counted.push((ji, jt, n));
        match self.kinds.iter_mut().find(|(k, _)| *k == jt) {
            Some((_, c)) => *c += n,
            None => self.kinds.push((jt, n)),
        }
    }
}

impl GroupLists<'_> {
    /// Group `g`'s type, pair lists and inputs.
    fn render(&self, g: usize, grp: &RawGroup) -> Rendered {
        let gk = group_key(g);
        let mut p = GroupPairs::default();
        let mut elements = self.body_pairs(grp, gk, &mut p);
        // A multiple joint as the binary pairs it stands for.
        elements.sort_unstable();
        elements.dedup();
        for v in elements {
            self.element_pairs(v, gk, &mut p);
        }
        let planar_here = self.planar_here(grp, &mut p);
        // Joint types in catalogue order, as the BTreeMap over `JointType` gave them.
        p.kinds.sort_unstable_by_key(|&(k, _)| k);
        let mut kind = String::new();
        for (k, n) in &p.kinds {
            let _ = write!(kind, "{n}{}", k.code());
        }
        kind.push_str(if planar_here {
            "2D"
        } else {
            self.m.space.suffix()
        });
        (
            kind,
            self.list(&mut p.from),
            self.list(&mut p.internal),
            self.list(&mut p.to),
            p.inputs,
        )
    }

    /// The pairs of the group's bodies (solve key `gk`) sorted into `p`; returns the element
    /// nodes of multiple joints met (rendered per joint by [`GroupLists::element_pairs`]).
    fn body_pairs(&self, grp: &RawGroup, gk: u32, p: &mut GroupPairs) -> Vec<usize> {
        let eqs = self.eqs;
        let mut elements: Vec<usize> = Vec::new();
        for &x in &grp.bodies {
            if eqs.is_element(x) {
                elements.push(x);
                continue;
            }
            let xi = x as u32;
            for n in &self.near[self.start[x]..self.start[x + 1]] {
                let y = n.y as usize;
                if eqs.is_element(y) {
                    elements.push(y);
                    continue;
                }
                let ky = self.key[y];
                if n.input_only {
                    // A multiple joint's inputs: counted, not listed (its pairs are below).
                    if ky < gk || (ky == gk && n.hub) {
                        p.inputs += n.driven;
                    }
                    continue;
                }
                let active = if ky == gk {
                    // Count an internal pair once, from its hub's side.
                    if !n.hub {
                        continue;
                    }
                    p.internal.push((xi.min(n.y), xi.max(n.y), n.e, n.kind));
                    true
                } else if ky < gk {
                    p.from.push((xi, n.y, n.e, n.kind));
                    true
                } else {
                    p.to.push((xi, n.y, n.e, n.kind));
                    false
                };
                if active {
                    p.add_kind(n.joint as usize, n.kind, 1);
                    p.inputs += n.driven;
                }
            }
        }
        elements
    }

    /// A multiple joint (element node `v`) as the binary pairs it stands for: with its element
    /// in the group, one body of the joint in the group is its hub; with the element solved
    /// before, each body of the group hangs on a body solved before that holds the element.
    fn element_pairs(&self, v: usize, gk: u32, p: &mut GroupPairs) {
        let jt = self.eqs.element_joint(v);
        let jk = self.m.joints[jt].kind;
        let mut inside: Vec<(u32, u32)> = Vec::new();
        let mut before: Vec<(u32, u32)> = Vec::new();
        let mut after: Vec<(u32, u32)> = Vec::new();
        for n in &self.near[self.start[v]..self.start[v + 1]] {
            match self.key[n.y as usize].cmp(&gk) {
                std::cmp::Ordering::Equal => inside.push((n.y, n.e)),
                std::cmp::Ordering::Less => before.push((n.y, n.e)),
                std::cmp::Ordering::Greater => after.push((n.y, n.e)),
            }
        }
        if self.key[v] == gk {
            let Some(&(hub, _)) = inside.first() else {
                return;
            };
            for &(y, e) in &inside[1..] {
                p.internal.push((hub, y, e, jk));
            }
            for &(y, e) in &before {
                p.from.push((hub, y, e, jk));
            }
            for &(y, e) in &after {
                p.to.push((hub, y, e, jk));
            }
            p.add_kind(jt, jk, inside.len() - 1 + before.len());
        } else if self.key[v] < gk {
            let holder = before.first().map_or(self.m.frame as u32, |&(y, _)| y);
            for &(x, e) in &inside {
                p.from.push((x, holder, e, jk));
            }
            p.add_kind(jt, jk, inside.len());
        } else if let Some(&(holder, _)) = after.first() {
            for &(x, e) in &inside {
                p.to.push((x, holder, e, jk));
            }
        }
    }

    /// A spatial group that closes a loop whose joints move in a space of 3 dimensions at the
    /// file's configuration (a planar or spherical loop written in space) is typed by the
    /// spatiality it really has: whether it is typed planar (its kinds retyped where a joint
    /// acts as a planar one).
    fn planar_here(&self, grp: &RawGroup, p: &mut GroupPairs) -> bool {
        let pairs: usize = p.kinds.iter().map(|&(_, n)| n).sum();
        let real = grp
            .bodies
            .iter()
            .filter(|&&x| !self.eqs.is_element(x))
            .count();
        let mut planar_here = false;
        if let Some(tw) = self.twists
            && pairs > real
        {
            p.active_joints.sort_unstable();
            p.active_joints.dedup();
            planar_here = spatiality(p.active_joints.iter().map(|&j| &tw[j])) <= 3;
            // The freedoms of a ball (or another joint of several) that the group's
            // single-freedom joints keep out of their plane are locked: the joint acts as
            // the planar joint it is inside the plane (the S of a planar loop as its pin).
            if !planar_here && let Some(acts) = locked_planar(tw, &p.active_joints) {
                planar_here = true;
                p.kinds.clear();
                for &(ji, jt, n) in &p.counted {
                    let k = acts.iter().find(|&&(j, _)| j == ji).map_or(jt, |&(_, k)| k);
                    match p.kinds.iter_mut().find(|(x, _)| *x == k) {
                        Some((_, c)) => *c += n,
                        None => p.kinds.push((k, n)),
                    }
                }
            }
        }
        planar_here
    }

    /// A pair list as written: sorted, `a&b` and the joint's code per pair, each ended by `.`.
    fn list(&self, list: &mut [Listed]) -> String {
        list.sort_unstable();
        let mut s = String::with_capacity(list.len() * 8);
        for &(i, j, _, k) in list.iter() {
            self.ids.put(&mut s, i as usize);
            s.push('&');
            self.ids.put(&mut s, j as usize);
            s.push_str(k.code());
            s.push('.');
        }
        s
    }
}

/// The groups as shown, with the types in order of first appearance (their counts and library
/// membership).
fn shown_groups(
    eqs: &Equations,
    raw: &[RawGroup],
    rendered: Vec<Rendered>,
    lib: &Library,
    ids: &BodyIds,
) -> (Vec<Group>, Vec<TypeCount>) {
    let mut groups = Vec::with_capacity(raw.len());
    let mut type_order: Vec<(String, usize, bool)> = Vec::new();
    let mut type_index: BTreeMap<String, usize> = BTreeMap::new();
    let (shown, mut deps_shown) = shown_numbers(eqs, raw);
    for (g, (grp, (kind, from, internal, to, inputs))) in raw.iter().zip(rendered).enumerate() {
        if shown[g] == usize::MAX {
            continue;
        }
        let t = match type_index.get(&kind) {
            Some(&t) => t,
            None => {
                let t = type_order.len();
                type_order.push((kind.clone(), 0, lib.contains(&kind)));
                type_index.insert(kind.clone(), t);
                t
            }
        };
        type_order[t].1 += 1;
        let bodies: Vec<String> = grp
            .bodies
            .iter()
            .filter(|&&x| !eqs.is_element(x))
            .map(|&b| ids.get(b).to_string())
            .collect();
        groups.push(Group {
            name: format!("SG-{}", roman(shown[g] + 1)),
            nm: bodies.len(),
            bodies,
            level: grp.level,
            inputs,
            in_library: type_order[t].2,
            kind,
            depends_on: std::mem::take(&mut deps_shown[g]),
            from,
            internal,
            to,
        });
    }
    let types = type_order
        .into_iter()
        .map(|(kind, count, in_library)| TypeCount {
            kind,
            count,
            in_library,
        })
        .collect();
    (groups, types)
}

/// Each group's number as shown (`usize::MAX`: hidden) and the shown groups it depends on.
/// Groups of element nodes only (a shared pin fixed by one solved body) are not shown: shown
/// groups are numbered in order, and a dependency on a hidden group is one on what that group
/// depends on.
fn shown_numbers(eqs: &Equations, raw: &[RawGroup]) -> (Vec<usize>, Vec<Vec<usize>>) {
    let real = |g: usize| raw[g].bodies.iter().any(|&x| !eqs.is_element(x));
    let mut shown = vec![usize::MAX; raw.len()];
    let mut n_shown = 0;
    for (g, slot) in shown.iter_mut().enumerate() {
        if real(g) {
            *slot = n_shown;
            n_shown += 1;
        }
    }
    let mut deps_shown: Vec<Vec<usize>> = Vec::with_capacity(raw.len());
    for grp in raw {
        let mut d: Vec<usize> = Vec::new();
        for &x in &grp.deps {
            if shown[x] != usize::MAX {
                d.push(shown[x]);
            } else {
                d.extend(deps_shown[x].iter().copied());
            }
        }
        d.sort_unstable();
        d.dedup();
        deps_shown.push(d);
    }
    (shown, deps_shown)
}

/// The status from the diagnosis. Mixed whenever equations that can fight (too many by count,
/// or a group's deficit the rank check found, whose right-hand side the inputs move) and
/// uncontrolled DOF coexist. Constraints dependent at the file's configuration are consistent
/// there and set aside before the decomposition, and with no input driven every right-hand
/// side is zero: such redundancy fights nothing, so it makes a mechanism neither
/// over-determined nor mixed (as it leaves a determined one determined); the notes list it.
fn status_of(m: &Mechanism, diag: &Diagnosis, redundant: &[Redundancy]) -> Status {
    let over = diag.overdetermined.is_some();
    let under = diag.underdetermined.is_some();
    let driven = m.joints.iter().any(|j| j.driven > 0);
    let redundant_eqs = over || (driven && redundant.iter().any(|r| !r.configuration));
    if under && redundant_eqs {
        Status::Mixed
    } else if under {
        Status::Underdetermined
    } else if over {
        Status::Overdetermined
    } else {
        Status::Determined
    }
}

/// A declared body that no joint names moves freely: its B DOF are uncontrolled, as the
/// mobility count and `rigid` have them, so the status says under-determined and a note names
/// the bodies.
fn free_bodies(m: &Mechanism, disconnected: &[String], diag: &mut Diagnosis) {
    if disconnected.is_empty() {
        return;
    }
    let b = m.b();
    let part = diag.underdetermined.get_or_insert_with(|| UnderPart {
        missing: 0,
        short: Vec::new(),
        bodies: Vec::new(),
        input_candidates: Vec::new(),
        pieces: Vec::new(),
    });
    // Each free body is a piece of its own beside what the part held.
    if part.pieces.is_empty() && !part.bodies.is_empty() {
        part.pieces.push(UnderPiece {
            missing: part.missing,
            bodies: part.bodies.clone(),
            input_candidates: part.input_candidates.clone(),
        });
    }
    let pieces = !part.pieces.is_empty() || disconnected.len() > 1;
    for body in disconnected {
        if pieces {
            part.pieces.push(UnderPiece {
                missing: u64::from(b),
                bodies: vec![body.clone()],
                input_candidates: Vec::new(),
            });
        }
        part.missing += u64::from(b);
        part.short.push(Missing {
            body: body.clone(),
            missing: b,
        });
        part.bodies.push(body.clone());
    }
    diag.notes.push(format!(
        "bodies {{{}}} are named by no joint: each moves freely ({b} DOF that no input \
         controls); join them to the mechanism or remove them",
        super::capped(disconnected)
    ));
}

/// The bodies no joint names (the frame left out).
fn disconnected(m: &Mechanism, ids: &BodyIds) -> Vec<String> {
    let mut touched = vec![false; m.bodies.len()];
    for j in &m.joints {
        for &x in &j.bodies {
            touched[x] = true;
        }
    }
    (0..m.bodies.len())
        .filter(|&x| !touched[x] && x != m.frame)
        .map(|b| ids.get(b).to_string())
        .collect()
}
