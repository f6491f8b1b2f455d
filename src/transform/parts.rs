//! Independent parts: the pieces a mechanism falls into once the frame is removed, each
//! placed on its own, and the parts of one expansion of a multiple joint.

use super::combine::join_parts;
use super::expansion::{Expansions, Skeleton};
use super::place::place;
use super::rules::Rules;
use super::{Placed, Placement, TransformError, TransformOptions};
use crate::budget::Meter;
use crate::joint::JointType;
use crate::mechanism::{Joint, Mechanism};
use crate::structure::{self, Library};
use std::collections::HashMap;
use std::sync::Arc;

/// What one expansion placed part by part ([`ExpansionParts::place`]).
pub(super) struct ByParts {
    pub(super) isolated: u32,
    pub(super) set_aside: u32,
    pub(super) f: i64,
    pub(super) drivable: usize,
    /// `None`: no count-valid placement; else the expansion's one count-valid placement,
    /// with its analysis when it is determined.
    pub(super) placement: Option<Option<Placement>>,
}

/// The placements of one part of an expansion, as placed alone (in the part's own indices),
/// kept for every part of any expansion with the same structure.
struct PartResult {
    placed: Placed,
    /// The first determined placement (there is at most one when `placed.cut` is false).
    placement: Option<Placement>,
}

/// An expansion of a multiple joint placed part by part, with each part's placements kept
/// across expansions ("parts" as [`split`] makes them: joined only through the frame).
///
/// The expansions of a shared joint differ in a few pairs only (the first 64 trees of a joint
/// of n bodies differ from the star in where one body hangs), and most of their parts are
/// the same up to renaming (one body on one pair to the frame). The whole expansion was
/// analysed twice per expansion (without inputs, then its placement): 128 analyses of every
/// pair of a 10^5-body shared S joint, over 50 s. A part is now placed once per structure
/// (its bodies in order, frame position, each joint's type, bodies and rules: the random
/// realization is drawn by joint index, and a part's joints are numbered alike), and an
/// expansion whose parts have one placement each is that placement, joined as
/// [`combine_parts`] joins the placements of the file's independent parts (the same groups, levels,
/// types and canonical order). An expansion with a part of several placements, or a note, is
/// placed whole, as before.
#[derive(Default)]
pub(super) struct ExpansionParts {
    index: HashMap<Vec<u32>, usize>,
    results: Vec<PartResult>,
}

impl ExpansionParts {
    /// Whether the expansions of `m` may be placed part by part under `rules`: random
    /// geometry (or none), and no kept input on a multiple joint (a minimum over all its
    /// pairs, which span the parts).
    pub(super) fn applies(exps: &Expansions<'_>, rules: &Rules, opts: &TransformOptions) -> bool {
        opts.split
            && rules.random
            && !exps.multi.is_empty()
            && exps.multi.iter().all(|&j| rules.keep[j] == 0)
    }

    /// Place expansion `e` (number `x`) part by part; `None` when it is in one piece or a
    /// part has several placements or a note (then the whole expansion is placed).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn place(
        &mut self,
        e: &Skeleton<'_>,
        x: usize,
        rules: &Rules,
        opts: &TransformOptions,
        lib: &Library,
        ids: &Arc<Vec<String>>,
        meter: &mut Meter,
    ) -> Result<Option<ByParts>, TransformError> {
        let m = e.m;
        let sets = part_sets_of(m.bodies.len(), m.frame, e.ends.len(), |q| &e.ends[q][..]);
        if sets.len() < 2 {
            return Ok(None);
        }
        meter.charge((m.bodies.len() + e.ends.len()) as u64 / 8 + 1)?;
        let of_part = self.results_of(e, &sets, rules, opts, lib, meter)?;
        let results = &self.results;
        let placed = |i: usize| &results[of_part[i]].placed;
        if (0..sets.len()).any(|i| !placed(i).notes.is_empty()) {
            return Ok(None);
        }
        let mut by = ByParts {
            isolated: 0,
            set_aside: 0,
            f: 0,
            drivable: 0,
            placement: None,
        };
        for i in 0..sets.len() {
            let r = placed(i);
            by.isolated += r.isolated;
            by.set_aside += r.set_aside;
            by.f += r.f;
            by.drivable += r.drivable;
        }
        // A part without placements: none for the expansion (the count is block diagonal).
        if (0..sets.len()).any(|i| placed(i).count_valid == 0) {
            return Ok(Some(by));
        }
        if (0..sets.len()).any(|i| placed(i).cut || placed(i).count_valid != 1) {
            return Ok(None);
        }
        // Determined when every part is (the rank check is block diagonal too).
        let members: Option<Vec<&Placement>> = (0..sets.len())
            .map(|i| results[of_part[i]].placement.as_ref())
            .collect();
        let Some(members) = members else {
            by.placement = Some(None);
            return Ok(Some(by));
        };
        let rebuild = vec![true; members.len()];
        let joined = join_parts(
            &|q| Some(e.names(q)),
            Some(&e.origin),
            &sets,
            &members,
            &rebuild,
            ids,
            e.expansion_label(),
            x,
        );
        let Some(p) = joined else {
            return Ok(None);
        };
        by.placement = Some(Some(p));
        Ok(Some(by))
    }

    /// The entry of `results` of each part of expansion `e` (`sets`), each structure placed
    /// once.
    fn results_of(
        &mut self,
        e: &Skeleton<'_>,
        sets: &[(Vec<usize>, Vec<usize>)],
        rules: &Rules,
        opts: &TransformOptions,
        lib: &Library,
        meter: &mut Meter,
    ) -> Result<Vec<usize>, TransformError> {
        let m = e.m;
        // One placement per part is enough to know whether there are several; the parts are
        // analysed at the whole's random realization even where a part alone has the file's
        // geometry.
        let popts = TransformOptions {
            limit: Some(1),
            analysis: structure::Options {
                geometry: random_source(opts.analysis.geometry),
                ..opts.analysis
            },
            ..opts.clone()
        };
        let mut local = vec![usize::MAX; m.bodies.len()];
        let mut of_part: Vec<usize> = Vec::with_capacity(sets.len());
        let mut key: Vec<u32> = Vec::new();
        for (joints, bodies) in sets {
            let joint = |q: usize| (m.joints[e.origin[q]].kind, &e.ends[q][..], e.origin[q]);
            part_key(m, joints, bodies, joint, rules, &mut local, &mut key);
            let at = match self.index.get(&key) {
                Some(&at) => at,
                None => {
                    let mech = part_mechanism_of(m, joints, bodies, &mut local, |q| e.joint(q));
                    let origins: Vec<usize> = joints.iter().map(|&q| e.origin[q]).collect();
                    let prules = rules.restrict(&origins);
                    let mut first: Option<Placement> = None;
                    let placed = place(
                        &mech,
                        &prules,
                        &popts,
                        lib,
                        meter,
                        None,
                        &mut |p| {
                            first.get_or_insert(p);
                            true
                        },
                        None,
                    )?;
                    self.results.push(PartResult {
                        placed,
                        placement: first,
                    });
                    self.index.insert(key.clone(), self.results.len() - 1);
                    self.results.len() - 1
                }
            };
            of_part.push(at);
        }
        Ok(of_part)
    }
}

/// The random realization a geometry source falls back to (the file's geometry is never
/// used where this is asked: the whole is analysed at a random realization).
fn random_source(g: crate::geometry::GeometrySource) -> crate::geometry::GeometrySource {
    use crate::geometry::GeometrySource;
    match g {
        GeometrySource::Auto { seed } => GeometrySource::Random { seed },
        other => other,
    }
}

/// The independent parts of `m`, as index sets: each part is the frame with one connected
/// component of the other bodies (joined by joints that do not pass through the frame) and
/// the joints touching it, in order of their first joint; a mechanism in one piece gives none.
/// Every joint belongs to exactly one part: the frame's equations only ever fix the frame, so
/// the constraint Jacobian (frame fixed) is block diagonal over the parts, and so are the
/// matching, the groups and the rank check. Each part's joints (ascending) and bodies
/// (ascending, the frame included); [`part_mechanism`] builds one part's mechanism.
pub(super) fn part_sets(m: &Mechanism) -> Vec<(Vec<usize>, Vec<usize>)> {
    part_sets_of(m.bodies.len(), m.frame, m.joints.len(), |q| {
        &m.joints[q].bodies[..]
    })
}

/// [`part_sets`] of `nb` bodies, the frame `frame`, and `nj` joints whose bodies are
/// `bodies_of(q)`.
fn part_sets_of<'a>(
    nb: usize,
    frame: usize,
    nj: usize,
    bodies_of: impl Fn(usize) -> &'a [usize],
) -> Vec<(Vec<usize>, Vec<usize>)> {
    let mut parent = linked_bodies(nb, frame, nj, &bodies_of);
    // Part of each root, numbered by first joint, then bodies without joints by index.
    let mut part_of: Vec<Option<usize>> = vec![None; nb];
    let mut joints_of: Vec<Vec<usize>> = Vec::new();
    let mut joint_part: Vec<Option<usize>> = vec![None; nj];
    for (ji, jp) in joint_part.iter_mut().enumerate() {
        let Some(&b) = bodies_of(ji).iter().find(|&&b| b != frame && b < nb) else {
            continue;
        };
        let r = root(&mut parent, b);
        let p = *part_of[r].get_or_insert_with(|| {
            joints_of.push(Vec::new());
            joints_of.len() - 1
        });
        joints_of[p].push(ji);
        *jp = Some(p);
    }
    for b in 0..nb {
        if b != frame {
            let r = root(&mut parent, b);
            if part_of[r].is_none() {
                joints_of.push(Vec::new());
                part_of[r] = Some(joints_of.len() - 1);
            }
        }
    }
    let mut bodies_of: Vec<Vec<usize>> = vec![Vec::new(); joints_of.len()];
    for b in 0..nb {
        if b == frame {
            continue;
        }
        let r = root(&mut parent, b);
        if let Some(p) = part_of[r] {
            bodies_of[p].push(b);
        }
    }
    // Joints only on the frame (none should exist) join the first part.
    if !joints_of.is_empty() {
        for (ji, jp) in joint_part.iter().enumerate() {
            if jp.is_none() {
                joints_of[0].push(ji);
            }
        }
        joints_of[0].sort_unstable();
    }
    if joints_of.len() <= 1 {
        return Vec::new();
    }
    for bodies in &mut bodies_of {
        // The frame's place among the sorted bodies: a binary search, not a sort per part.
        let at = bodies.partition_point(|&b| b < frame);
        bodies.insert(at, frame);
    }
    joints_of.into_iter().zip(bodies_of).collect()
}

/// Union-find of the bodies other than the frame, joined by the joints (`bodies_of(q)`):
/// each body's parent, the smallest body of its set at the root.
fn linked_bodies<'a>(
    nb: usize,
    frame: usize,
    nj: usize,
    bodies_of: &impl Fn(usize) -> &'a [usize],
) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..nb).collect();
    for q in 0..nj {
        let mut first: Option<usize> = None;
        for &b in bodies_of(q) {
            if b == frame || b >= nb {
                continue;
            }
            match first {
                None => first = Some(b),
                Some(f) => {
                    let (ra, rb) = (root(&mut parent, f), root(&mut parent, b));
                    if ra != rb {
                        parent[ra.max(rb)] = ra.min(rb);
                    }
                }
            }
        }
    }
    parent
}

/// The root of `x` in the union-find `p`, halving the path.
fn root(p: &mut [usize], mut x: usize) -> usize {
    while p[x] != x {
        p[x] = p[p[x]];
        x = p[x];
    }
    x
}

/// The mechanism of one part of `m` (its `joints` and sorted `bodies`, the frame among them).
/// `local` is a table of every body of `m`, all `usize::MAX`, used and cleared here (one
/// table for every part: a table per part was quadratic, 10^5 parts of a 10^5-body star
/// cleared 80 GB).
pub(super) fn part_mechanism(
    m: &Mechanism,
    joints: &[usize],
    bodies: &[usize],
    local: &mut [usize],
) -> Mechanism {
    part_mechanism_of(m, joints, bodies, local, |q| m.joints[q].clone())
}

/// [`part_mechanism`] with joint `q` given by `joint(q)` (the pairs of an expansion not built
/// as a whole, [`Skeleton`]); the bodies, frame and space are `m`'s.
fn part_mechanism_of(
    m: &Mechanism,
    joints: &[usize],
    bodies: &[usize],
    local: &mut [usize],
    joint: impl Fn(usize) -> Joint,
) -> Mechanism {
    for (i, &b) in bodies.iter().enumerate() {
        local[b] = i;
    }
    let mech = Mechanism {
        name: m.name.clone(),
        description: None,
        space: m.space,
        frame: local[m.frame],
        bodies: bodies.iter().map(|&b| m.bodies[b].clone()).collect(),
        joints: joints
            .iter()
            .map(|&ji| {
                let mut j = joint(ji);
                j.bodies = j.bodies.iter().map(|&b| local[b]).collect();
                j
            })
            .collect(),
        expect: Default::default(),
        // A part's numbers are the file's: known as precisely.
        precision: m.precision,
    };
    for &b in bodies {
        local[b] = usize::MAX;
    }
    mech
}

/// The structure of one part (its `joints` and sorted `bodies` in `m`) as a key: bodies, the
/// frame's place, and each joint's type, rules (of its original joint) and bodies in the
/// part's own indices (`joint(q)`: type, bodies and original joint of joint `q`). Two parts with the same key are placed alike up to renaming when
/// the realization is random (drawn by joint index) or there is none. `local` is a table of
/// every body of `m`, all `usize::MAX`, used and cleared here.
pub(super) fn part_key<'a>(
    m: &Mechanism,
    joints: &[usize],
    bodies: &[usize],
    joint: impl Fn(usize) -> (JointType, &'a [usize], usize),
    rules: &Rules,
    local: &mut [usize],
    key: &mut Vec<u32>,
) {
    for (i, &b) in bodies.iter().enumerate() {
        local[b] = i;
    }
    key.clear();
    key.extend([
        bodies.len() as u32,
        local[m.frame] as u32,
        joints.len() as u32,
    ]);
    for &q in joints {
        let (kind, ends, o) = joint(q);
        key.extend([
            kind as u32,
            u32::from(rules.allowed[o]),
            rules.keep[o],
            ends.len() as u32,
        ]);
        key.extend(ends.iter().map(|&b| local[b] as u32));
    }
    for &b in bodies {
        local[b] = usize::MAX;
    }
}

/// `bodies 2-5` style label of a part (its `bodies`) for notes: its movable bodies' ids,
/// shortened.
pub(super) fn part_label(m: &Mechanism, bodies: &[usize]) -> String {
    let ids: Vec<String> = bodies
        .iter()
        .filter(|&&b| b != m.frame)
        .map(|&b| m.body_id(b).to_string())
        .collect();
    match ids.len() {
        0 => "no bodies".into(),
        1..=4 => format!("bodies {}", ids.join(", ")),
        k => format!("bodies {}, {} and {} more", ids[0], ids[1], k - 2),
    }
}
