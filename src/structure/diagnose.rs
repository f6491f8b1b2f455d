//! The diagnosis of an analysis: the over- and under-determined parts in words and lists, the
//! joints that could take one more input, and the redundancies found by the rank check.

use super::count::{Decomposition, Equations, Part};
use super::{
    Diagnosis, Excess, Isolated, Missing, NOTE_JOINTS, OverPart, Redundancy, UnderPart, capped,
};
use crate::mechanism::Mechanism;

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
    if let Some((part, note)) = under_part(m, eqs, dec, isolated) {
        d.notes.push(note);
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
    let note = format!(
        "{missing} DOF not fixed by any input: bodies {{{}}} can move; one more input on \
         one of the joints {} would fix one DOF{caveat}",
        capped(&bodies),
        capped(&input_candidates)
    );
    let part = UnderPart {
        missing,
        short,
        bodies,
        input_candidates,
    };
    Some((part, note))
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
