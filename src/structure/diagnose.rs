//! The diagnosis of an analysis: the over- and under-determined parts in words and lists, the
//! joints that could take one more input, and the redundancies found by the rank check.

use super::count::{Decomposition, Equations, Part};
use super::{
    Diagnosis, Excess, Isolated, Missing, NOTE_JOINTS, OverPart, Redundancy, UnderPart, UnderPiece,
    capped,
};
use crate::mechanism::Mechanism;
use serde::Serialize;

/// The over- and under-determined parts in words and lists.
pub(super) fn diagnose(
    m: &Mechanism,
    eqs: &Equations,
    dec: &Decomposition,
    unsolved: Vec<usize>,
    redundant: &[Redundancy],
    isolated: &[Isolated],
) -> Diagnosis {
    let mut d = Diagnosis {
        unsolved: unsolved.iter().map(|&b| eqs.node_name(m, b)).collect(),
        ..Diagnosis::default()
    };
    if let Some((part, note)) = over_part(m, eqs, dec) {
        d.notes.push(note);
        d.overdetermined = Some(part);
    }
    let bases = floating_bases(m, dec);
    if let Some((part, note)) = under_part(m, eqs, dec, isolated, &bases) {
        d.notes.push(note);
        d.notes.extend(floating_base_note(m, &bases, part.missing));
        d.underdetermined = Some(part);
    }
    d.notes.extend(redundant.iter().map(redundancy_note));
    d
}

/// The ids of the joints `js`, sorted by joint and without repeats.
fn joint_ids(m: &Mechanism, mut js: Vec<usize>) -> Vec<String> {
    js.sort_unstable();
    js.dedup();
    js.into_iter()
        .map(|j| m.joints[j].id.clone())
        .collect::<Vec<_>>()
}

/// The over-determined part and its note: the equations the bodies cannot satisfy.
fn over_part(m: &Mechanism, eqs: &Equations, dec: &Decomposition) -> Option<(OverPart, String)> {
    let over_eqs: Vec<usize> = (0..eqs.len()).filter(|&e| dec.eq_excess[e] > 0).collect();
    if over_eqs.is_empty() {
        return None;
    }
    let pair_label = |e: usize| {
        let [a, c] = eqs.bodies(e);
        format!("{}-{}", eqs.node_name(m, a), eqs.node_name(m, c))
    };
    let excess: u64 = over_eqs.iter().map(|&e| dec.eq_excess[e] as u64).sum();
    let part_eqs: Vec<usize> = (0..eqs.len())
        .filter(|&e| dec.eq_part[e] == Part::Over)
        .collect();
    let bodies: Vec<String> = (0..m.bodies.len())
        .filter(|&b| dec.body_part[b] == Part::Over)
        .map(|b| m.body_id(b).to_string())
        .collect();
    let unsaturated: Vec<Excess> = over_eqs
        .iter()
        .map(|&e| Excess {
            joint: m.joints[eqs.joint[e]].id.clone(),
            pair: pair_label(e),
            excess: dec.eq_excess[e],
        })
        .collect();
    let with_inputs =
        over_eqs.iter().any(|&e| eqs.driven[e] > 0) || part_eqs.iter().any(|&e| eqs.driven[e] > 0);
    let remedy = if with_inputs {
        "remove an input there or free a joint"
    } else {
        "the joints over-constrain these bodies for generic dimensions: free a joint"
    };
    let note = format!(
        "{excess} equation(s) too many: {} {} more than the bodies {{{}}} can satisfy; \
         {remedy}",
        if unsaturated.len() == 1 {
            "joint"
        } else {
            "joints"
        },
        capped(
            &unsaturated
                .iter()
                .map(|x| format!("{} (+{})", x.joint, x.excess))
                .collect::<Vec<_>>()
        ),
        capped(&bodies)
    );
    let part = OverPart {
        excess,
        unsaturated,
        joints: joint_ids(m, part_eqs.iter().map(|&e| eqs.joint[e]).collect()),
        bodies,
    };
    Some((part, note))
}

/// The under-determined part and its note: the DOF no input fixes and the joints that could
/// take one more input.
fn under_part(
    m: &Mechanism,
    eqs: &Equations,
    dec: &Decomposition,
    isolated: &[Isolated],
    bases: &[(usize, usize, u32)],
) -> Option<(UnderPart, String)> {
    // Element nodes (`<J>`: the shared pin of multiple joint J) can miss DOF too.
    let short: Vec<Missing> = (0..eqs.nodes)
        .filter(|&b| b != m.frame && dec.body_missing[b] > 0)
        .map(|b| Missing {
            body: eqs.node_name(m, b),
            missing: dec.body_missing[b],
        })
        .collect();
    if short.is_empty() {
        return None;
    }
    let missing: u64 = short.iter().map(|s| s.missing as u64).sum();
    let in_part: Vec<bool> = (0..eqs.nodes)
        .map(|b| dec.body_part[b] == Part::Under)
        .collect();
    let bodies: Vec<String> = (0..m.bodies.len())
        .filter(|&b| in_part[b])
        .map(|b| m.body_id(b).to_string())
        .collect();
    let cands = input_candidates(m, eqs, &in_part);
    let caveat = isolated_caveat(m, &cands, isolated);
    let input_candidates = joint_ids(m, cands);
    let pieces = under_pieces(m, eqs, dec, &in_part, &[]);
    let base_dof: u64 = bases.iter().map(|&(_, _, f)| u64::from(f)).sum();
    let beyond: Vec<UnderPiece> = if pieces.len() < 2 && missing > base_dof && !bases.is_empty() {
        let mut posed = vec![false; eqs.nodes];
        bases.iter().for_each(|&(_, body, _)| posed[body] = true);
        // Parts where every joint is driven already move only with the base (a humanoid
        // whose every hinge is driven): no input there fixes anything.
        under_pieces(m, eqs, dec, &in_part, &posed)
            .into_iter()
            .filter(|p| !p.input_candidates.is_empty())
            .collect()
    } else {
        Vec::new()
    };
    let note = if beyond.len() >= 2 {
        // A robot whose legs meet only at its free base (the Cassie): each leg on its own,
        // without a count (the flow's split of the base's DOF among the legs is arbitrary).
        let mut each: Vec<String> = beyond
            .iter()
            .take(NOTE_PIECES)
            .map(|p| {
                format!(
                    "\n  - bodies {{{}}}: one more input on one of the joints {} would fix one",
                    capped(&p.bodies),
                    capped(&p.input_candidates)
                )
            })
            .collect();
        if beyond.len() > NOTE_PIECES {
            each.push(format!("\n  - {}", more_parts(beyond.len() - NOTE_PIECES)));
        }
        let caveat = caveat.trim_start();
        format!(
            "{missing} DOF not fixed by any input: {base_dof} of the floating base (below), the \
             rest in {} parts that meet only at the base:{}{}{caveat}",
            beyond.len(),
            each.concat(),
            if caveat.is_empty() { "" } else { "\n  " },
        )
    } else if pieces.len() < 2 {
        format!(
            "{missing} DOF not fixed by any input: bodies {{{}}} can move; one more input on \
             one of the joints {} would fix one DOF{caveat}",
            capped(&bodies),
            capped(&input_candidates)
        )
    } else {
        let mut each: Vec<String> = pieces
            .iter()
            .take(NOTE_PIECES)
            .map(|p| {
                format!(
                    "{} DOF of bodies {{{}}} (one more input on one of the joints {} would fix \
                     one)",
                    p.missing,
                    capped(&p.bodies),
                    capped(&p.input_candidates)
                )
            })
            .collect();
        if pieces.len() > NOTE_PIECES {
            let rest = &pieces[NOTE_PIECES..];
            let dof: u64 = rest.iter().map(|p| p.missing).sum();
            each.push(format!("{} of {dof} DOF", more_parts(rest.len())));
        }
        format!(
            "{missing} DOF not fixed by any input, in {} independent parts: {}{caveat}",
            pieces.len(),
            each.join("; ")
        )
    };
    let part = UnderPart {
        missing,
        short,
        bodies,
        input_candidates,
        pieces,
    };
    Some((part, note))
}

/// "1 more part", "3 more parts".
fn more_parts(n: usize) -> String {
    if n == 1 {
        "1 more part".into()
    } else {
        format!("{n} more parts")
    }
}

/// Independent pieces of the under-determined part a note describes one by one.
const NOTE_PIECES: usize = 6;

/// The under-determined part's independent pieces (connected by no equation between two of
/// their nodes), in the order of their first body; empty when there is one. The nodes
/// `posed` (floating bases, or none) are taken as held: they join nothing and are in no piece.
fn under_pieces(
    m: &Mechanism,
    eqs: &Equations,
    dec: &Decomposition,
    in_part: &[bool],
    posed: &[bool],
) -> Vec<UnderPiece> {
    let posed = |x: usize| posed.get(x).copied().unwrap_or(false);
    let in_part = |x: usize| in_part[x] && !posed(x);
    let mut uf: Vec<usize> = (0..eqs.nodes).collect();
    fn root(uf: &mut [usize], mut x: usize) -> usize {
        while uf[x] != x {
            uf[x] = uf[uf[x]];
            x = uf[x];
        }
        x
    }
    let mut join = |a: usize, b: usize| {
        let (ra, rb) = (root(&mut uf, a), root(&mut uf, b));
        uf[ra.max(rb)] = ra.min(rb);
    };
    for e in 0..eqs.len() {
        let [a, b] = eqs.bodies(e);
        if in_part(a) && in_part(b) {
            join(a, b);
        }
    }
    // The bodies of one multiple joint are one piece, its pin known or not: so every joint
    // touches at most one piece, and the pieces' candidate lists stay as long as the joints.
    for j in &m.joints {
        let mut inside = j.bodies.iter().copied().filter(|&x| in_part(x));
        if let Some(first) = inside.next() {
            inside.for_each(|x| join(first, x));
        }
    }
    // Each node's piece, numbered in the order of the pieces' first nodes.
    let mut piece = vec![usize::MAX; eqs.nodes];
    let mut of_root = vec![usize::MAX; eqs.nodes];
    let mut pieces: Vec<UnderPiece> = Vec::new();
    for x in (0..eqs.nodes).filter(|&x| in_part(x) && x != m.frame) {
        let r = root(&mut uf, x);
        if of_root[r] == usize::MAX {
            of_root[r] = pieces.len();
            pieces.push(UnderPiece {
                missing: 0,
                bodies: Vec::new(),
                input_candidates: Vec::new(),
            });
        }
        let p = &mut pieces[of_root[r]];
        piece[x] = of_root[r];
        p.missing += u64::from(dec.body_missing[x]);
        if x < m.bodies.len() {
            p.bodies.push(m.body_id(x).to_string());
        }
    }
    if pieces.len() < 2 {
        return Vec::new();
    }
    // Each piece's candidates: as `input_candidates`, in one pass over the joints (a pass per
    // piece was quadratic: 10^5 bodies on one shared joint are 10^5 pieces).
    let mut element_of = vec![usize::MAX; m.joints.len()];
    for (i, &ji) in eqs.elements.iter().enumerate().rev() {
        element_of[ji] = i;
    }
    let mut cands: Vec<Vec<usize>> = vec![Vec::new(); pieces.len()];
    for (ji, j) in m.joints.iter().enumerate() {
        if j.driven >= j.grade() * j.pairs() {
            continue;
        }
        let element = (element_of[ji] != usize::MAX).then(|| eqs.bodies + element_of[ji]);
        let mut touched: Vec<usize> = element
            .into_iter()
            .chain(j.bodies.iter().copied())
            .filter_map(|x| piece.get(x).copied().filter(|&p| p != usize::MAX))
            .collect();
        touched.sort_unstable();
        touched.dedup();
        for p in touched {
            cands[p].push(ji);
        }
    }
    for (p, c) in pieces.iter_mut().zip(cands) {
        p.input_candidates = joint_ids(m, c);
    }
    pieces
}

/// The floating bases among the `missing` DOF no input fixes, on a line of their own: the free
/// joints between the frame and a body of the under-determined part that are not driven in
/// full (a robot imported with its base free: the Cassie's 12 DOF are its base's 6 and 6 of
/// its legs).
fn floating_base_note(
    m: &Mechanism,
    bases: &[(usize, usize, u32)],
    missing: u64,
) -> Option<String> {
    let bases: Vec<(String, u32)> = bases
        .iter()
        .map(|&(j, body, free)| {
            let id = &m.joints[j].id;
            (
                format!("{id} ({} to {})", m.body_id(m.frame), m.body_id(body)),
                free,
            )
        })
        .collect();
    if bases.is_empty() {
        return None;
    }
    let dof: u64 = bases.iter().map(|b| u64::from(b.1)).sum();
    let names: Vec<String> = bases.into_iter().map(|b| b.0).collect();
    Some(format!(
        "floating base: {dof} of these {missing} DOF are the free joint(s) {}; give the base's \
         pose (drive the joint in full) or fix it to the frame (`mbsa transform` takes it as \
         driven in full by default)",
        capped(&names)
    ))
}

/// The bodies of the under-determined part on a free joint to the frame not driven in full,
/// with the joint and its freedoms left (one entry a joint, in joint order). A body that
/// reaches the frame by joints other than free joints to it (a MuJoCo `connect` to the world)
/// is no floating base: they fix some of its DOF. One pass over the joints whatever the
/// number of free bodies.
fn floating_bases(m: &Mechanism, dec: &Decomposition) -> Vec<(usize, usize, u32)> {
    let free: Vec<usize> = (0..m.joints.len())
        .filter(|&j| m.free_to_frame(j))
        .collect();
    if free.is_empty() {
        return Vec::new();
    }
    let held = crate::mobility::Components::of_joints(
        m,
        (0..m.joints.len()).filter(|&j| !m.free_to_frame(j)),
    );
    let frame = held.root(m.frame);
    free.into_iter()
        .filter_map(|j| {
            let joint = &m.joints[j];
            let body = *joint.bodies.iter().find(|&&x| x != m.frame)?;
            let left = joint.grade() - joint.driven.min(joint.grade());
            (left > 0 && dec.body_part.get(body) == Some(&Part::Under) && held.root(body) != frame)
                .then_some((j, body, left))
        })
        .collect()
}

/// The joints with a spare freedom that touch the under-determined part (`in_part` per node),
/// in joint order.
fn input_candidates(m: &Mechanism, eqs: &Equations, in_part: &[bool]) -> Vec<usize> {
    let mut cands: Vec<usize> = Vec::new();
    // The element node of each multiple joint (a search per joint was quadratic).
    let mut element_of = vec![usize::MAX; m.joints.len()];
    for (i, &ji) in eqs.elements.iter().enumerate().rev() {
        element_of[ji] = i;
    }
    for (ji, j) in m.joints.iter().enumerate() {
        let spare = j.driven < j.grade() * j.pairs();
        let element_in = (element_of[ji] != usize::MAX)
            .then_some(element_of[ji])
            .is_some_and(|i| in_part[eqs.bodies + i]);
        if spare && (element_in || j.bodies.iter().any(|&b| in_part[b])) {
            cands.push(ji);
        }
    }
    cands
}

/// The candidates are found by count. A body with an isolated freedom (a bar spinning between
/// two balls) can take an input that only turns that freedom and fixes nothing else (a Delta
/// robot's rods): such candidates are named, with how to test one (empty when there are none).
fn isolated_caveat(m: &Mechanism, cands: &[usize], isolated: &[Isolated]) -> String {
    let spinning: std::collections::HashSet<&str> =
        isolated.iter().map(|i| i.body.as_str()).collect();
    let doubtful: Vec<String> = if spinning.is_empty() {
        Vec::new()
    } else {
        joint_ids(
            m,
            cands
                .iter()
                .copied()
                .filter(|&ji| {
                    m.joints[ji]
                        .bodies
                        .iter()
                        .any(|&b| spinning.contains(m.body_id(b).to_string().as_str()))
                })
                .collect(),
        )
    };
    match doubtful.len() {
        0 => String::new(),
        n => format!(
            " (counted; an input on {} holds a body with an isolated freedom and may only \
             turn it, fixing none: `--inputs` tests one)",
            if n <= NOTE_JOINTS {
                doubtful.join(", ")
            } else {
                format!(
                    "{} and {} more",
                    doubtful[..NOTE_JOINTS].join(", "),
                    n - NOTE_JOINTS
                )
            }
        ),
    }
}

/// A redundancy's note: set aside at the file's configuration, or found by the rank check.
fn redundancy_note(r: &Redundancy) -> String {
    if r.configuration {
        format!(
            "bodies {{{}}}: {} redundant constraint(s) set aside (lowered on {}); {}",
            capped(&r.bodies),
            r.count,
            capped(&r.lowered.split(", ").collect::<Vec<_>>()),
            r.freedom
        )
    } else {
        format!(
            "group {{{}}}: joints {} carry {} redundant equation(s); {}",
            capped(&r.bodies),
            capped(&r.joints),
            r.count,
            r.freedom
        )
    }
}

/// A rigid part's own spin: its bodies turning together as one body, moving no other, across
/// a cut of two or more joints that allow it (a part held by two S joints about the line
/// through their centres). No input turns it: set aside like a single body's isolated freedom.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Spin {
    /// The part's bodies.
    pub bodies: Vec<String>,
    /// The joints across the cut.
    pub joints: Vec<String>,
    /// The DOF set aside.
    pub dimension: u32,
}

/// The spins [`set_aside_spins`] set aside, and the notes of those no group deficit names.
#[derive(Default)]
pub(super) struct Spins {
    parts: Vec<Spin>,
    notes: Vec<String>,
}

/// The DOF left missing that are isolated freedoms of a rigid part, set aside as `mbsa rigid
/// --with-inputs` sets them aside (one rule for both: the structurally isolated motions of
/// [`crate::rigidity::geometric`], a rigid cluster turning as one body across a cut of two or
/// more joints that allow it, the rest fixed; a part held by two S joints spins about the line
/// through their centres). Such a spin moves no other body and no input turns it, so it is not
/// a freedom the inputs leave uncontrolled: each spin's DOF come off the unknowns `u` of the
/// part's bodies that miss DOF in `dec` (as a single body's isolated freedom does; an unknown
/// no equation reaches can go without changing the maximum flow), and `dec` is decomposed
/// again. A group deficit on the part says so in its words; the other spins are returned as
/// notes. Runs only where DOF are missing and a spin may be why: the rank check found
/// dependent equations (a spin makes the rows of its part dependent), or a part of several
/// bodies is held by balls alone on one line
/// ([`ball_held_part`](super::ball_parts::ball_held_part)); at the geometry of the
/// analysis, for at most [`SPIN_CHECK_BODIES`] bodies and within [`SPIN_CHECK_WORK`] work
/// units and [`SPIN_CHECK_MEMORY`] bytes of the geometric analysis: past any (a large
/// mechanism: its geometric analysis takes seconds where the count's analysis takes a fraction
/// of one) the count's answer stays, as `mbsa rigid` gives the spins at any size.
pub(super) fn set_aside_spins(
    m: &Mechanism,
    opts: &super::Options,
    eqs: &Equations,
    dec: &mut Decomposition,
    u: &mut [u32],
    redundant: &mut [Redundancy],
) -> Spins {
    use crate::rigidity::geometric::{GeometricOptions, analyze_within};
    let missing = (0..m.bodies.len()).any(|b| b != m.frame && dec.body_missing[b] > 0);
    // A spin shows as dependent equations of its part, or, for a part of several bodies held
    // by balls alone, as DOF the count leaves missing with every equation independent (the
    // two-body struts of an SPS Stewart platform, cylinder and rod: six DOF "not fixed", where
    // the inputs fix the platform and the struts spin).
    if !missing
        || (redundant.is_empty() && !super::ball_parts::ball_held_part(m))
        || m.bodies.len() > SPIN_CHECK_BODIES
    {
        return Spins::default();
    }
    let gopts = GeometricOptions {
        geometry: opts.geometry,
        precision: opts.precision,
        check_finite: false,
    };
    let budget = crate::budget::Budget {
        max_work: SPIN_CHECK_WORK,
        max_memory_bytes: SPIN_CHECK_MEMORY,
        ..crate::budget::Budget::DEFAULT
    };
    let Ok(report) = analyze_within(m, &gopts, &budget) else {
        return Spins::default();
    };
    let index: std::collections::HashMap<String, usize> = (0..m.bodies.len())
        .map(|b| (m.body_id(b).to_string(), b))
        .collect();
    // The smallest parts first: a part inside another (a bipyramid turning inside a banana
    // that turns as a whole) takes its own missing DOF before the larger part takes any.
    let mut spins: Vec<_> = report
        .isolated_motions
        .iter()
        .filter(|x| x.kind == "structurally")
        .collect();
    spins.sort_by_key(|x| x.bodies.len());
    let mut out = Spins::default();
    let mut named: Vec<usize> = Vec::new();
    let mut units = 0;
    for motion in spins {
        let part: Vec<usize> = motion
            .bodies
            .iter()
            .filter_map(|b| index.get(b))
            .copied()
            .collect();
        let mut taken = 0u32;
        while (taken as usize) < motion.dof && units < MAX_SPIN_UNITS {
            units += 1;
            if !take_one(m, eqs, dec, u, &part) {
                break;
            }
            taken += 1;
        }
        if taken == 0 {
            continue;
        }
        out.parts.push(Spin {
            bodies: motion.bodies.clone(),
            joints: motion.joints.clone(),
            dimension: taken,
        });
        let words = spin_words(&motion.bodies, &motion.joints, taken);
        if let Some(note) = name_deficit(redundant, &mut named, &motion.bodies, taken, words) {
            out.notes.push(note);
        }
    }
    out
}

/// The first group deficit on the part `bodies` not yet `named` says its `taken` DOF are the
/// part's spin (`words`); without one, `words` are a note of their own.
fn name_deficit(
    redundant: &mut [Redundancy],
    named: &mut Vec<usize>,
    bodies: &[String],
    taken: u32,
    words: String,
) -> Option<String> {
    let found = redundant.iter_mut().enumerate().find(|(i, r)| {
        !r.configuration && !named.contains(i) && r.bodies.iter().any(|b| bodies.contains(b))
    });
    let Some((i, r)) = found else {
        return Some(words);
    };
    named.push(i);
    r.freedom = if r.count <= taken {
        words
    } else {
        format!(
            "{words}; {} more freedom(s) that no input controls",
            r.count - taken
        )
    };
    None
}

/// Work cap of the geometric analysis [`set_aside_spins`] runs (units of
/// [`crate::budget::Budget::max_work`]): it keeps `analyze` within a small multiple of its own
/// time where the count has the answer.
pub const SPIN_CHECK_WORK: u64 = 30_000_000;

/// Largest mechanism (bodies) whose spins [`set_aside_spins`] looks for: the geometric
/// analysis costs about 40 ms at 10^3 bodies and 0.4 s at 10^4 (docs/benchmarks.md).
pub const SPIN_CHECK_BODIES: usize = 2_000;

/// Memory cap of the geometric analysis [`set_aside_spins`] runs, in bytes.
pub const SPIN_CHECK_MEMORY: u64 = 256 * 1024 * 1024;

/// Spin DOF [`set_aside_spins`] sets aside at most (each one decomposition).
const MAX_SPIN_UNITS: usize = 64;

/// One unknown off a body of `part` that can miss a DOF (one the decomposition `dec` leaves
/// short, else one of its under-determined part: a maximum flow leaves it short), and `dec`
/// decomposed again; kept only when one DOF fewer is missing and no equation is left over.
fn take_one(
    m: &Mechanism,
    eqs: &Equations,
    dec: &mut Decomposition,
    u: &mut [u32],
    part: &[usize],
) -> bool {
    let missing = |d: &Decomposition| d.body_missing.iter().map(|&x| u64::from(x)).sum::<u64>();
    let excess = |d: &Decomposition| d.eq_excess.iter().map(|&x| u64::from(x)).sum::<u64>();
    let short = part.iter().copied().find(|&b| dec.body_missing[b] > 0);
    let under = || {
        part.iter()
            .copied()
            .find(|&b| dec.body_part[b] == Part::Under && u[b] > 0)
    };
    let Some(b) = short.or_else(under) else {
        return false;
    };
    u[b] -= 1;
    let next = super::count::decompose(m, eqs, u);
    if missing(&next) + 1 == missing(dec) && excess(&next) == excess(dec) {
        *dec = next;
        true
    } else {
        u[b] += 1;
        false
    }
}

/// The words for the spin (`isolated` DOF) of the rigid part `bodies` that its boundary
/// `joints` allow.
fn spin_words(bodies: &[String], joints: &[String], isolated: u32) -> String {
    format!(
        "bodies {{{}}} turn together as one rigid part, moving no other body, by {isolated} \
         freedom(s) the joints {} allow (an isolated freedom, as `mbsa rigid --with-inputs` \
         sets it aside): no input is needed for it",
        capped(bodies),
        capped(joints),
    )
}

/// The spins of [`set_aside_spins`] in analysis `a`, their notes with the diagnosis's notes or
/// the notes of a determined mechanism.
pub(super) fn spin_notes(a: &mut super::Analysis, spins: Spins) {
    a.spins = spins.parts;
    match a.diagnosis.as_mut() {
        Some(d) => d.notes.extend(spins.notes),
        None => a.notes.extend(spins.notes),
    }
}

/// Whether analysis `a` of `m` may stand at a toggle of a driven joint: at the file's
/// geometry, not determined because a group lost rank (not by count), with an input. Then
/// [`super::check_finite`] runs the finite-mobility test to find the toggle ([`name_toggle`]).
pub(super) fn toggle_suspect(m: &Mechanism, a: &super::Analysis) -> bool {
    a.geometry.as_ref().is_some_and(|g| g.is_file())
        && a.status != super::Status::Determined
        && a.redundant.iter().any(|r| !r.configuration)
        && m.joints.iter().any(|j| j.driven > 0)
}

/// A driven joint that the finite-mobility test `f` finds locked at a toggle (stationary in
/// every first-order motion here, moving nearby) is an input that cannot move at this
/// configuration: its equation is the over-determined part (it fixes nothing the joints do
/// not already fix), the freedom it drives elsewhere is the under-determined part, and the
/// remedy is to move the input or leave the pose, not to add one. The diagnosis of `a` says
/// so, as `mbsa rigid --finite` does; nothing changes when no driven joint is at a toggle.
pub(super) fn name_toggle(
    m: &Mechanism,
    a: &mut super::Analysis,
    f: &crate::position::finite::FiniteMobility,
) {
    let toggles: Vec<usize> = (0..m.joints.len())
        .filter(|&j| m.joints[j].driven > 0 && f.locked_at_toggle.contains(&m.joints[j].id))
        .collect();
    let Some(d) = a.diagnosis.as_mut() else {
        return;
    };
    if toggles.is_empty() || f.assembled || d.overdetermined.is_some() {
        return;
    }
    let pair = |j: usize| {
        let bs = &m.joints[j].bodies;
        let names: Vec<String> = bs.iter().map(|&b| m.body_id(b).to_string()).collect();
        names.join("-")
    };
    let ids = joint_ids(m, toggles.clone());
    let mut bodies: Vec<usize> = toggles
        .iter()
        .flat_map(|&j| m.joints[j].bodies.iter().copied())
        .filter(|&b| b != m.frame)
        .collect();
    bodies.sort_unstable();
    bodies.dedup();
    let bodies: Vec<String> = bodies.iter().map(|&b| m.body_id(b).to_string()).collect();
    let excess: u64 = toggles.iter().map(|&j| u64::from(m.joints[j].driven)).sum();
    d.overdetermined = Some(OverPart {
        excess,
        unsaturated: toggles
            .iter()
            .map(|&j| Excess {
                joint: m.joints[j].id.clone(),
                pair: pair(j),
                excess: m.joints[j].driven,
            })
            .collect(),
        joints: ids.clone(),
        bodies: bodies.clone(),
    });
    let toggle_note = format!(
        "toggle: the input on {} cannot move at this configuration: the joint is stationary in \
         every first-order motion here but moves at nearby configurations (a dead centre), so \
         its {excess} input(s) fix nothing the joints do not already fix and the bodies {{{}}} \
         it places are held by the toggle, not by the input; move the input to another joint \
         or analyse a configuration away from the toggle; `mbsa rigid --finite` gives the \
         details",
        capped(&ids),
        capped(&bodies)
    );
    if let Some(u) = d.underdetermined.as_mut() {
        u.input_candidates.clear();
        for p in &mut u.pieces {
            p.input_candidates.clear();
        }
        let prefix = format!("{} DOF not fixed by any input", u.missing);
        let under_note = format!(
            "{prefix}: bodies {{{}}} can move, left free by the input at the toggle on {}; \
             moving that input, not adding one, fixes them",
            capped(&u.bodies),
            capped(&ids)
        );
        match d.notes.iter().position(|n| n.starts_with(&prefix)) {
            Some(i) => d.notes[i] = under_note,
            None => d.notes.insert(0, under_note),
        }
    }
    d.notes.insert(0, toggle_note);
}

/// The note for rank decisions at the file's configuration that came within
/// [`NEAR_FACTOR`](crate::structure::rank::NEAR_FACTOR) of their threshold (`kept`, `dropped`:
/// the closest ratios to it), as `rigid --method geometric` warns of its own ("ill-conditioned"):
/// the answer may turn with more digits or a slightly different pose. `precision`: the numbers'
/// written precision.
pub(super) fn near_threshold_note(precision: Option<f64>, (kept, dropped): (f64, f64)) -> String {
    let numbers = match precision {
        Some(p) if p > 0.0 => format!("the numbers known to ±{p:.0e}"),
        _ => "the numbers taken as exact".to_string(),
    };
    let mut closest = Vec::new();
    if kept.is_finite() && kept < crate::structure::rank::NEAR_FACTOR {
        closest.push(format!("a value kept at {kept:.2} times its threshold"));
    }
    if dropped * crate::structure::rank::NEAR_FACTOR > 1.0 {
        closest.push(format!("one set aside at {dropped:.2} times it"));
    }
    format!(
        "ill-conditioned: with {numbers}, a rank decision at the file's configuration lies within \
         a factor {} of its threshold ({}); the configuration may be near a singular one, or the \
         precision too coarse to decide it: the answer may change with more digits \
         (`--tolerance` sets the precision)",
        crate::structure::rank::NEAR_FACTOR,
        closest.join(", ")
    )
}
