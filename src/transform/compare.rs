//! One given placement beside the file's own (`mbsa transform --inputs`).

use super::ranked::{compare_scores, scores};
use super::{Criterion, Input, Scores, TransformError, TransformOptions};
use crate::mechanism::{InputSpec, Mechanism};
use crate::structure::{self, Analysis, Library, Status, TypeCount};
use serde::Serialize;
use std::cmp::Ordering;

/// A group in a comparison.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct GroupBrief {
    /// Body ids.
    pub bodies: Vec<String>,
    /// Solve level.
    pub level: usize,
    /// SG type.
    #[serde(rename = "type")]
    pub kind: String,
    /// Whether the library covers it.
    pub in_library: bool,
}

/// One placement analysed.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Evaluation {
    /// The driven joints.
    pub inputs: Vec<Input>,
    /// The verdict of the analysis.
    pub status: Status,
    /// The scores (of the well-determined part when not determined).
    #[serde(flatten)]
    pub scores: Scores,
    /// Group types.
    pub types: Vec<TypeCount>,
    /// The groups in canonical order (`group_list` in JSON: `groups` is the scores' count).
    #[serde(rename = "group_list")]
    pub groups: Vec<GroupBrief>,
}

impl Evaluation {
    fn of(m: &Mechanism, a: &Analysis) -> Evaluation {
        Evaluation {
            inputs: m
                .joints
                .iter()
                .filter(|j| j.driven > 0)
                .map(|j| Input {
                    joint: j.id.clone(),
                    pair: m.joint_bodies_label(j),
                    driven: j.driven,
                })
                .collect(),
            status: a.status,
            scores: scores(a),
            types: a.types.clone(),
            groups: a
                .groups
                .iter()
                .map(|g| GroupBrief {
                    bodies: g.bodies.clone(),
                    level: g.level,
                    kind: g.kind.clone(),
                    in_library: g.in_library,
                })
                .collect(),
        }
    }
}

/// What changed from the file's placement to the given one.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Changes {
    /// Groups: given − file.
    pub groups: i64,
    /// Largest group: given − file.
    pub largest: i64,
    /// Levels: given − file.
    pub levels: i64,
    /// Covered groups: given − file.
    pub covered: i64,
    /// Whether both give the same partition into groups.
    pub same_partition: bool,
    /// Groups (by body set) both have.
    pub common: usize,
    /// Groups only the file's placement has.
    pub only_file: Vec<GroupBrief>,
    /// Groups only the given placement has.
    pub only_given: Vec<GroupBrief>,
    /// `better`, `worse` or `same` by the ranking criteria when both are determined;
    /// otherwise `not comparable`.
    pub verdict: &'static str,
}

/// `mbsa transform --inputs`: the file's placement and the given one side by side.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Comparison {
    /// Mechanism name.
    pub name: String,
    /// Ranking criteria used for the verdict.
    pub criteria: Vec<Criterion>,
    /// The file's own placement.
    pub file: Evaluation,
    /// The given placement.
    pub given: Evaluation,
    /// The differences.
    pub changes: Changes,
}

/// Analyse the placement `spec` and compare it with the file's own.
pub fn compare(
    m: &Mechanism,
    spec: &InputSpec,
    opts: &TransformOptions,
    lib: &Library,
) -> Result<Comparison, TransformError> {
    let mut given_m = m.clone();
    given_m.apply_inputs(spec)?;
    let fa = structure::analyze(m, &opts.analysis, lib)?;
    let ga = structure::analyze(&given_m, &opts.analysis, lib)?;
    let file = Evaluation::of(m, &fa);
    let given = Evaluation::of(&given_m, &ga);
    let criteria = if opts.rank.is_empty() {
        Criterion::DEFAULT.to_vec()
    } else {
        opts.rank.clone()
    };
    let set = |e: &Evaluation| {
        e.groups
            .iter()
            .map(|g| g.bodies.clone())
            .collect::<std::collections::BTreeSet<_>>()
    };
    let (fs, gs) = (set(&file), set(&given));
    let diff = |a: &Evaluation, other: &std::collections::BTreeSet<Vec<String>>| {
        a.groups
            .iter()
            .filter(|g| !other.contains(&g.bodies))
            .cloned()
            .collect::<Vec<_>>()
    };
    let both = file.status == Status::Determined && given.status == Status::Determined;
    let verdict = if !both {
        "not comparable"
    } else {
        match compare_scores(&given.scores, &file.scores, &criteria) {
            Ordering::Less => "better",
            Ordering::Greater => "worse",
            Ordering::Equal => "same",
        }
    };
    let d = |a: usize, b: usize| a as i64 - b as i64;
    let changes = Changes {
        groups: d(given.scores.groups, file.scores.groups),
        largest: d(given.scores.largest, file.scores.largest),
        levels: d(given.scores.levels, file.scores.levels),
        covered: d(given.scores.covered, file.scores.covered),
        same_partition: fs == gs,
        common: fs.intersection(&gs).count(),
        only_file: diff(&file, &gs),
        only_given: diff(&given, &fs),
        verdict,
    };
    Ok(Comparison {
        name: m.name.clone(),
        criteria,
        file,
        given,
        changes,
    })
}
