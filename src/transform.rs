//! Structural transformations: every placement of the driven inputs that determines the
//! mechanism, ranked by the kinematic structure it gives.
//!
//! A placement gives each joint `w_j` driven DOF (`0 ≤ w_j ≤ k_j`, `Σ w_j = f`). Think of each
//! joint as `B − k_j` constraint equations plus up to `k_j` identical input slots, and of each
//! movable body as `B` unknowns (fewer when it has an isolated spin). Determined placements (by
//! count) are exactly the bases of the transversal matroid of that bipartite graph contracted
//! by the constraint equations. They are enumerated as multisets of slots, depth first, with an
//! incremental matching: a new slot is kept only if an augmenting path exists (otherwise it is
//! dependent and the partial placement over-determines some part), and a branch is cut as soon
//! as the joints still to come cannot complete it (a matroid rank test by augmenting paths).
//! Every leaf is thus a count-valid placement; each is then analysed in full
//! ([`crate::structure::analyze`], with its rank check unless `count_only`), in parallel, and
//! the ones the rank check rejects are excluded and counted. `docs/algorithms.md` has details.

use crate::joint::JointType;
use crate::mechanism::{InputSpec, InputSpecError, Joint, Mechanism, resolve_ref};
use crate::structure::{self, Analysis, Library, Status, TypeCount};
use rayon::prelude::*;
use serde::Serialize;
use std::cmp::Ordering;
use std::collections::BTreeMap;

/// A ranking criterion (`--rank`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Criterion {
    /// More structural groups first (smaller, simpler groups).
    Groups,
    /// Every group covered by the library first, then more covered groups.
    Library,
    /// Smaller largest group first.
    MaxSize,
    /// Fewer solve levels first.
    Levels,
}

impl Criterion {
    /// The default order: `groups,library,max-size,levels`.
    pub const DEFAULT: [Criterion; 4] = [
        Criterion::Groups,
        Criterion::Library,
        Criterion::MaxSize,
        Criterion::Levels,
    ];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Criterion::Groups => "groups",
            Criterion::Library => "library",
            Criterion::MaxSize => "max-size",
            Criterion::Levels => "levels",
        }
    }

    /// Parse one criterion name.
    pub fn parse(text: &str) -> Result<Criterion, TransformError> {
        let t = text.trim().to_ascii_lowercase().replace('_', "-");
        [
            Criterion::Groups,
            Criterion::Library,
            Criterion::MaxSize,
            Criterion::Levels,
        ]
        .into_iter()
        .find(|c| c.name() == t)
        .ok_or_else(|| TransformError::UnknownCriterion {
            text: text.trim().to_string(),
        })
    }

    /// Parse a comma-separated list (`groups,library`); repeated names count once.
    pub fn parse_list(text: &str) -> Result<Vec<Criterion>, TransformError> {
        let mut out: Vec<Criterion> = Vec::new();
        for part in text.split(',').filter(|p| !p.trim().is_empty()) {
            let c = Criterion::parse(part)?;
            if !out.contains(&c) {
                out.push(c);
            }
        }
        Ok(out)
    }
}

/// Options of `mbsa transform`, one field per command-line flag.
#[derive(Clone, Debug, PartialEq)]
pub struct TransformOptions {
    /// `--rank`: ranking criteria, most important first.
    pub rank: Vec<Criterion>,
    /// `--top`: how many families of placements the table shows (default 10).
    pub top: usize,
    /// `--on R,P`: only joints of these types may be driven (`None`: any).
    pub on: Option<Vec<JointType>>,
    /// `--grounded`: only joints to the frame may be driven.
    pub grounded: bool,
    /// `--keep SPEC`: inputs that must stay (each named joint keeps at least that many DOF).
    /// Kept inputs are placed even on joints that `on`, `grounded` would rule out.
    pub keep: Option<InputSpec>,
    /// `--exclude SPEC`: joints that may not be driven (counts are ignored).
    pub exclude: Option<InputSpec>,
    /// `--inputs SPEC`: evaluate this one placement beside the file's own ([`compare`]).
    pub inputs: Option<InputSpec>,
    /// `--max-expansions`: how many binary expansions of the multiple joints to explore.
    pub max_expansions: usize,
    /// `--limit`: how many count-valid placements to examine at most.
    pub limit: Option<usize>,
    /// Structural analysis options (`--count-only`, `--seed`, method).
    pub analysis: structure::Options,
}

impl Default for TransformOptions {
    fn default() -> TransformOptions {
        TransformOptions {
            rank: Criterion::DEFAULT.to_vec(),
            top: 10,
            on: None,
            grounded: false,
            keep: None,
            exclude: None,
            inputs: None,
            max_expansions: 64,
            limit: None,
            analysis: structure::Options::default(),
        }
    }
}

impl TransformOptions {
    /// Parse the `--on` list: joint codes or names, comma-separated (`R,P`, `revolute`).
    pub fn parse_on(text: &str) -> Result<Vec<JointType>, TransformError> {
        let mut out = Vec::new();
        for part in text.split(',').filter(|p| !p.trim().is_empty()) {
            let k = JointType::parse(part).ok_or_else(|| TransformError::UnknownType {
                text: part.trim().to_string(),
                hint: JointType::suggest(part).map(str::to_string),
            })?;
            if !out.contains(&k) {
                out.push(k);
            }
        }
        Ok(out)
    }
}

/// Errors of the transformation options.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TransformError {
    /// An `--inputs`, `--keep` or `--exclude` spec that does not fit the mechanism.
    #[error(transparent)]
    Spec(#[from] InputSpecError),
    /// An unknown joint type in `--on`.
    #[error("unknown joint type `{text}` in --on{}", hint.as_ref().map(|h| format!(" (did you mean `{h}`?)")).unwrap_or_default())]
    UnknownType {
        /// The entry.
        text: String,
        /// Nearest known code.
        hint: Option<String>,
    },
    /// An unknown ranking criterion.
    #[error("unknown ranking criterion `{text}`; expected groups, library, max-size or levels")]
    UnknownCriterion {
        /// The entry.
        text: String,
    },
    /// The joint geometry asked for cannot be used.
    #[error(transparent)]
    Geometry(#[from] crate::motion::MotionError),
    /// A joint both kept and excluded.
    #[error("joint `{joint}` is both kept (--keep) and excluded (--exclude)")]
    KeepExcluded {
        /// Joint id.
        joint: String,
    },
}

/// One driven joint of a placement.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Input {
    /// Joint id (for a pair of an expanded multiple joint: `id[a-b]`).
    pub joint: String,
    /// Its bodies, `a-b`.
    pub pair: String,
    /// Driven DOF.
    pub driven: u32,
}

/// The structural scores of one placement.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Scores {
    /// Number of structural groups.
    pub groups: usize,
    /// Bodies in the largest group.
    pub largest: usize,
    /// Number of solve levels.
    pub levels: usize,
    /// Groups whose type the library covers.
    pub covered: usize,
    /// Whether the library covers every group.
    pub all_covered: bool,
}

/// A determined placement and the structure it gives.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Placement {
    /// Rank (1 = best) once ranked; absent when streamed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rank: Option<usize>,
    /// Family (1-based): placements with the same partition into groups share it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub family: Option<usize>,
    /// The driven joints, in joint order.
    pub inputs: Vec<Input>,
    /// The binary expansion of the multiple joints (absent when there are none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub expansion: Option<String>,
    /// The scores.
    #[serde(flatten)]
    pub scores: Scores,
    /// Group types with counts and coverage, in order of first appearance.
    pub types: Vec<TypeCount>,
    /// The groups' bodies in canonical order (level, size, smallest body).
    pub partition: Vec<Vec<String>>,
    /// Enumeration order (deterministic), the final tie-break.
    #[serde(skip)]
    seq: usize,
    /// Index of the expansion (0 = every multiple joint as a star on its hub).
    #[serde(skip)]
    exp: usize,
}

impl Placement {
    /// The placement as an `--inputs` spec (`1-2,1-13,13-15`, `:n` for n > 1).
    pub fn spec(&self) -> String {
        self.inputs
            .iter()
            .map(|i| {
                if i.driven == 1 {
                    i.joint.clone()
                } else {
                    format!("{}:{}", i.joint, i.driven)
                }
            })
            .collect::<Vec<_>>()
            .join(",")
    }

    /// The partition as an order-independent key.
    fn partition_key(&self) -> Vec<Vec<String>> {
        let mut k = self.partition.clone();
        k.sort();
        k
    }
}

/// Placements with the same partition into groups.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Family {
    /// 1-based, in order of the best member's rank.
    pub id: usize,
    /// The groups' bodies (as in the best member).
    pub partition: Vec<Vec<String>>,
    /// Ranks of the members, best first.
    pub placements: Vec<usize>,
}

/// Counts and notes of one run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Mechanism name.
    pub name: String,
    /// The mobility count.
    pub count: i64,
    /// Isolated DOF (spins no input can drive), from the rank check.
    pub isolated: u32,
    /// Constraint equations dependent at the file's configuration (they fix nothing, so the
    /// mechanism takes that many more inputs than its count says).
    pub set_aside: u32,
    /// The joint geometry of the analyses (absent with `count_only`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub geometry: Option<crate::motion::GeometryUsed>,
    /// Inputs each placement has: the count plus the equations set aside, minus the isolated
    /// DOF (the true mobility less the isolated DOF).
    pub f: i64,
    /// Joints (binary pairs) that may be driven under the restrictions.
    pub drivable: usize,
    /// Binary expansions of the multiple joints explored.
    pub expansions: usize,
    /// Binary expansions there are (saturating: `u64::MAX` means more than 10^19, and the
    /// notes say so in words).
    pub expansions_total: u64,
    /// Count-valid placements examined by the full analysis.
    pub count_valid: usize,
    /// Count-valid placements the rank check rejected (not determined).
    pub excluded_by_rank: usize,
    /// Determined placements.
    pub determined: usize,
    /// The `--limit` used, if any.
    pub limit: Option<usize>,
    /// Whether the limit cut the search (more placements exist).
    pub truncated: bool,
    /// Plain-language notes (restrictions, truncation, why nothing was found).
    pub notes: Vec<String>,
}

/// The ranked result of [`transform`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Transform {
    /// Counts and notes.
    pub summary: Summary,
    /// The ranking criteria used.
    pub criteria: Vec<Criterion>,
    /// Rank of the file's own placement among the determined ones, if it is one of them.
    pub original_rank: Option<usize>,
    /// Every determined placement, best first.
    pub placements: Vec<Placement>,
    /// Placements grouped by partition, best family first.
    pub families: Vec<Family>,
}

/// Progress of the full analysis of the count-valid placements.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// Placements analysed so far.
    pub examined: usize,
    /// Placements to analyse in all.
    pub total: usize,
    /// Determined placements so far.
    pub determined: usize,
}

/// A progress callback (called from the thread that called the library, between batches).
pub type ProgressFn<'a> = &'a (dyn Fn(Progress) + Sync);

/// Enumerate the determined placements and stream them to `sink` in enumeration order
/// (deterministic, unranked), calling `progress` between batches. Returns the counts.
pub fn enumerate(
    m: &Mechanism,
    opts: &TransformOptions,
    lib: &Library,
    progress: Option<ProgressFn<'_>>,
    sink: &mut dyn FnMut(Placement),
) -> Result<Summary, TransformError> {
    let rules = Rules::of(m, opts)?;
    // A geometry that cannot be used is the user's error, said once, before any work.
    let geometry = if opts.analysis.count_only {
        None
    } else {
        Some(crate::motion::choose(
            m,
            opts.analysis.geometry,
            opts.analysis.precision,
        )?)
    };
    let (exps, total_exps) = expansions(m, opts.max_expansions);
    let mob = crate::mobility::mobility(m);
    let mut summary = Summary {
        name: m.name.clone(),
        count: mob.mobility.count,
        isolated: 0,
        set_aside: 0,
        geometry,
        f: mob.mobility.count,
        drivable: 0,
        expansions: exps.len(),
        expansions_total: total_exps,
        count_valid: 0,
        excluded_by_rank: 0,
        determined: 0,
        limit: opts.limit,
        truncated: false,
        notes: rules.notes.clone(),
    };
    if total_exps > exps.len() as u64 {
        summary.notes.push(format!(
            "explored {} of {} binary expansions of the multiple joints (raise --max-expansions)",
            exps.len(),
            crate::budget::count_in_words(total_exps)
        ));
    }

    // Enumerate the count-valid placements of every expansion first (cheap), so the
    // expensive analysis knows its total and runs in parallel batches.
    let mut cands: Vec<(usize, Vec<(usize, u32)>)> = Vec::new();
    let mut limit_left = opts.limit.unwrap_or(usize::MAX);
    for (x, e) in exps.iter().enumerate() {
        let p = Problem::of(e, m, &rules, opts);
        if x == 0 {
            summary.isolated = p.isolated;
            summary.set_aside = p.set_aside;
            summary.f = p.f;
            summary.drivable = p.drivable();
            if let Some(n) = &p.note {
                summary.notes.push(n.clone());
            }
        }
        let mut found = Vec::new();
        let cut = p.enumerate(limit_left, &mut found);
        limit_left -= found.len();
        cands.extend(found.into_iter().map(|w| (x, w)));
        if cut {
            summary.truncated = true;
            break;
        }
    }
    if summary.truncated {
        summary.notes.push(format!(
            "the search stopped at --limit {}: more placements exist and are not ranked here",
            opts.limit.unwrap_or(0)
        ));
    }

    let total = cands.len();
    const BATCH: usize = 512;
    let mut done = 0;
    for batch in cands.chunks(BATCH) {
        let results: Vec<Option<Placement>> = batch
            .par_iter()
            .map_init(
                || exps.iter().map(|e| e.mech.clone()).collect::<Vec<_>>(),
                |mechs, (x, w)| {
                    let e = &exps[*x];
                    let mech = &mut mechs[*x];
                    let a = evaluate(mech, w, &opts.analysis, lib)?;
                    Some(placement(mech, e, *x, &a, w))
                },
            )
            .collect();
        for (i, r) in results.into_iter().enumerate() {
            match r {
                Some(mut p) => {
                    p.seq = done + i;
                    summary.determined += 1;
                    sink(p);
                }
                None => summary.excluded_by_rank += 1,
            }
        }
        done += batch.len();
        if let Some(cb) = progress {
            cb(Progress {
                examined: done,
                total,
                determined: summary.determined,
            });
        }
    }
    summary.count_valid = total;
    if summary.excluded_by_rank > 0 {
        summary.notes.push(format!(
            "{} of {} count-valid placements are not determined (the rank check finds redundant \
             equations or uncontrolled freedoms) and are excluded",
            summary.excluded_by_rank, total
        ));
    }
    Ok(summary)
}

/// Enumerate, rank and group every determined placement.
pub fn transform(
    m: &Mechanism,
    opts: &TransformOptions,
    lib: &Library,
    progress: Option<ProgressFn<'_>>,
) -> Result<Transform, TransformError> {
    let mut placements = Vec::new();
    let summary = enumerate(m, opts, lib, progress, &mut |p| placements.push(p))?;
    let criteria = if opts.rank.is_empty() {
        Criterion::DEFAULT.to_vec()
    } else {
        opts.rank.clone()
    };
    placements
        .sort_by(|a, b| compare_scores(&a.scores, &b.scores, &criteria).then(a.seq.cmp(&b.seq)));
    let mut index: BTreeMap<Vec<Vec<String>>, usize> = BTreeMap::new();
    let mut families: Vec<Family> = Vec::new();
    for (i, p) in placements.iter_mut().enumerate() {
        p.rank = Some(i + 1);
        let key = p.partition_key();
        let f = *index.entry(key).or_insert_with(|| {
            families.push(Family {
                id: families.len() + 1,
                partition: p.partition.clone(),
                placements: Vec::new(),
            });
            families.len()
        });
        families[f - 1].placements.push(i + 1);
        p.family = Some(f);
    }
    let own = exps_default_inputs(m, opts.max_expansions);
    let original_rank = placements
        .iter()
        .find(|p| p.exp == 0 && p.inputs == own)
        .and_then(|p| p.rank);
    Ok(Transform {
        summary,
        criteria,
        original_rank,
        placements,
        families,
    })
}

/// Order two score sets by `criteria` (`Less`: `a` ranks before `b`).
pub fn compare_scores(a: &Scores, b: &Scores, criteria: &[Criterion]) -> Ordering {
    for c in criteria {
        let o = match c {
            Criterion::Groups => b.groups.cmp(&a.groups),
            Criterion::Library => b
                .all_covered
                .cmp(&a.all_covered)
                .then(b.covered.cmp(&a.covered)),
            Criterion::MaxSize => a.largest.cmp(&b.largest),
            Criterion::Levels => a.levels.cmp(&b.levels),
        };
        if o != Ordering::Equal {
            return o;
        }
    }
    Ordering::Equal
}

/// The scores of an analysis.
pub fn scores(a: &Analysis) -> Scores {
    let covered = a.groups.iter().filter(|g| g.in_library).count();
    Scores {
        groups: a.groups.len(),
        largest: a.groups.iter().map(|g| g.nm).max().unwrap_or(0),
        levels: a.levels,
        covered,
        all_covered: covered == a.groups.len(),
    }
}

// ---------------------------------------------------------------------------------------------
// Restrictions

/// The restrictions resolved on the original joints.
struct Rules {
    /// May joint j be driven (type, exclusion)? `grounded` is checked per binary pair.
    allowed: Vec<bool>,
    grounded: bool,
    /// Driven DOF joint j must keep at least.
    keep: Vec<u32>,
    notes: Vec<String>,
}

impl Rules {
    fn of(m: &Mechanism, opts: &TransformOptions) -> Result<Rules, TransformError> {
        let n = m.joints.len();
        let mut allowed = vec![true; n];
        let mut notes = Vec::new();
        if let Some(on) = &opts.on {
            for (a, j) in allowed.iter_mut().zip(&m.joints) {
                *a &= on.contains(&j.kind);
            }
            let codes: Vec<&str> = on.iter().map(|k| k.code()).collect();
            notes.push(format!(
                "only joints of type {} may be driven",
                codes.join(", ")
            ));
        }
        if opts.grounded {
            notes.push("only joints to the frame may be driven".into());
        }
        let mut excluded = vec![false; n];
        if let Some(spec) = &opts.exclude {
            for r in &spec.refs {
                excluded[resolve_ref(m, &r.text)?] = true;
            }
            let ids: Vec<&str> = (0..n)
                .filter(|&j| excluded[j])
                .map(|j| m.joints[j].id.as_str())
                .collect();
            if !ids.is_empty() {
                notes.push(format!("never driven: {}", ids.join(", ")));
            }
        }
        let mut keep = vec![0u32; n];
        if let Some(spec) = &opts.keep {
            for (j, c) in spec.resolve(m)? {
                keep[j] = keep[j].saturating_add(c);
            }
            for (j, joint) in m.joints.iter().enumerate() {
                let max = joint.grade() * joint.pairs();
                if keep[j] > max {
                    return Err(InputSpecError::AboveGrade {
                        joint: joint.id.clone(),
                        driven: u64::from(keep[j]),
                        grade: max,
                    }
                    .into());
                }
                if keep[j] > 0 && excluded[j] {
                    return Err(TransformError::KeepExcluded {
                        joint: joint.id.clone(),
                    });
                }
            }
            let kept: Vec<String> = (0..n)
                .filter(|&j| keep[j] > 0)
                .map(|j| format!("{}:{}", m.joints[j].id, keep[j]))
                .collect();
            if !kept.is_empty() {
                notes.push(format!("kept inputs: {}", kept.join(", ")));
            }
        }
        for (a, x) in allowed.iter_mut().zip(&excluded) {
            *a &= !x;
        }
        Ok(Rules {
            allowed,
            grounded: opts.grounded,
            keep,
            notes,
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Binary expansions of multiple joints

/// The mechanism with every joint binary: a multiple joint of n bodies becomes the n − 1 pairs
/// of one spanning tree of its bodies. The first pair takes the joint's place (so the other
/// joints keep their index, and their random geometry in the rank check); the rest are
/// appended after the last joint.
struct Expansion {
    label: Option<String>,
    mech: Mechanism,
    /// Original joint of each joint of `mech`.
    origin: Vec<usize>,
}

/// `n^(n−2)`, saturating.
fn trees(n: usize) -> u64 {
    if n < 3 {
        return 1;
    }
    let mut t: u64 = 1;
    for _ in 0..n - 2 {
        t = t.saturating_mul(n as u64);
    }
    t
}

/// The spanning tree with Prüfer sequence number `index` (base-n digits, most significant
/// first), as sorted edges `(a, b)`, `a < b`, over local vertices `0..n`. Index 0 is the star on
/// vertex 0.
fn prufer_tree(n: usize, mut index: u64) -> Vec<(usize, usize)> {
    if n < 2 {
        return Vec::new();
    }
    if n == 2 {
        return vec![(0, 1)];
    }
    let mut seq = vec![0usize; n - 2];
    for s in seq.iter_mut().rev() {
        *s = (index % n as u64) as usize;
        index /= n as u64;
    }
    let mut degree = vec![1usize; n];
    for &s in &seq {
        degree[s] += 1;
    }
    let mut edges = Vec::with_capacity(n - 1);
    for &s in &seq {
        let leaf = (0..n)
            .find(|&v| degree[v] == 1)
            .expect("a tree with at least two vertices left has a leaf");
        edges.push((leaf.min(s), leaf.max(s)));
        degree[leaf] = 0;
        degree[s] -= 1;
    }
    let last: Vec<usize> = (0..n).filter(|&v| degree[v] == 1).collect();
    if let [a, b] = last[..] {
        edges.push((a, b));
    }
    edges.sort_unstable();
    edges
}

/// Up to `max` expansions (at least one) and how many there are.
fn expansions(m: &Mechanism, max: usize) -> (Vec<Expansion>, u64) {
    let mut base = m.clone();
    for j in &mut base.joints {
        j.driven = 0;
    }
    let multi: Vec<usize> = (0..m.joints.len())
        .filter(|&j| m.joints[j].bodies.len() > 2)
        .collect();
    if multi.is_empty() {
        let origin = (0..m.joints.len()).collect();
        let e = Expansion {
            label: None,
            mech: base,
            origin,
        };
        return (vec![e], 1);
    }
    let counts: Vec<u64> = multi
        .iter()
        .map(|&j| trees(m.joints[j].bodies.len()))
        .collect();
    let total = counts.iter().fold(1u64, |t, &c| t.saturating_mul(c));
    let n = (max.max(1) as u64).min(total) as usize;
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        // Mixed radix, the last multiple joint varying fastest.
        let mut rest = k as u64;
        let mut digits = vec![0u64; multi.len()];
        for (d, &c) in digits.iter_mut().zip(&counts).rev() {
            *d = rest % c.max(1);
            rest /= c.max(1);
        }
        let mut mech = base.clone();
        let mut origin: Vec<usize> = (0..m.joints.len()).collect();
        let mut labels = Vec::new();
        let mut appended: Vec<Joint> = Vec::new();
        for (&j, &d) in multi.iter().zip(&digits) {
            let joint = &m.joints[j];
            let edges = prufer_tree(joint.bodies.len(), d);
            let mut pairs = Vec::new();
            for (i, &(a, b)) in edges.iter().enumerate() {
                let (ba, bb) = (joint.bodies[a], joint.bodies[b]);
                let label = format!("{}-{}", m.body_id(ba), m.body_id(bb));
                let pj = Joint {
                    id: format!("{}[{label}]", joint.id),
                    kind: joint.kind,
                    bodies: vec![ba, bb],
                    driven: 0,
                    geometry: joint.geometry.clone(),
                };
                pairs.push(label);
                if i == 0 {
                    mech.joints[j] = pj;
                } else {
                    appended.push(pj);
                    origin.push(j);
                }
            }
            labels.push(format!("{}: {}", joint.id, pairs.join(", ")));
        }
        mech.joints.extend(appended);
        out.push(Expansion {
            label: Some(labels.join("; ")),
            mech,
            origin,
        });
    }
    (out, total)
}

/// The file's own placement on the default expansion, as the analysis distributes a multiple
/// joint's driven DOF: its pairs in order, at most k each, the last taking the rest.
fn exps_default_inputs(m: &Mechanism, max: usize) -> Vec<Input> {
    let (exps, _) = expansions(m, max.min(1));
    let Some(e) = exps.first() else {
        return Vec::new();
    };
    let mut w: Vec<(usize, u32)> = Vec::new();
    for (j, joint) in m.joints.iter().enumerate() {
        let pairs: Vec<usize> = (0..e.origin.len()).filter(|&q| e.origin[q] == j).collect();
        let mut left = joint.driven;
        for (p, &q) in pairs.iter().enumerate() {
            let share = if p + 1 == pairs.len() {
                left
            } else {
                left.min(joint.grade())
            };
            left -= share;
            if share > 0 {
                w.push((q, share));
            }
        }
    }
    inputs_of(&e.mech, e, &w)
}

/// The driven joints of a placement, in original joint order.
fn inputs_of(mech: &Mechanism, e: &Expansion, w: &[(usize, u32)]) -> Vec<Input> {
    let mut w: Vec<(usize, u32)> = w.iter().copied().filter(|&(_, n)| n > 0).collect();
    w.sort_by_key(|&(q, _)| (e.origin[q], q));
    w.iter()
        .map(|&(q, n)| Input {
            joint: mech.joints[q].id.clone(),
            pair: mech.joint_bodies_label(&mech.joints[q]),
            driven: n,
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Count enumeration: matroid bases by incremental matching

/// Flow of every pair into its two bodies, and the units each body has received.
#[derive(Clone, Debug)]
struct State {
    flow: Vec<[u32; 2]>,
    used: Vec<u32>,
}

/// BFS buffers reused across augmentations.
struct Scratch {
    seen: Vec<u32>,
    stamp: u32,
    prev: Vec<(u32, u32)>,
    queue: Vec<usize>,
}

const NONE: u32 = u32::MAX;

/// One expansion as a bipartite matching problem.
struct Problem {
    frame: usize,
    u: Vec<u32>,
    a: Vec<usize>,
    c: Vec<usize>,
    touching: Vec<Vec<usize>>,
    lo: Vec<u32>,
    hi: Vec<u32>,
    /// Multiple joints with a kept minimum: their pairs and the minimum of their sum.
    kept_groups: Vec<(Vec<usize>, u32)>,
    /// Pairs that may receive inputs beyond the kept ones, in joint order.
    cand: Vec<usize>,
    isolated: u32,
    set_aside: u32,
    f: i64,
    /// Units the search places beyond the kept ones.
    need: usize,
    /// The matching of the constraint equations and the kept inputs; `None` when no
    /// placement can exist.
    root: Option<State>,
    note: Option<String>,
}

impl Problem {
    fn of(e: &Expansion, orig: &Mechanism, rules: &Rules, opts: &TransformOptions) -> Problem {
        let m = &e.mech;
        let nb = m.bodies.len();
        let b = m.b();
        let mut u = vec![b; nb];
        u[m.frame] = 0;
        let mut isolated = 0u32;
        // Constraint equations dependent at the file's configuration fix nothing: inputs take
        // their place (a planar four-bar written in space takes one input, not none).
        let mut set_aside = vec![0u32; m.joints.len()];
        if !opts.analysis.count_only {
            // Spins no input can drive (a bar between two spherical joints): the rank check's
            // isolated freedoms with no input at all, on bodies held by two pairs or more. A
            // body hanging on a single joint also moves with its neighbours held, but that is
            // the joint's own freedom, which an input on it drives.
            let mut pairs = vec![0usize; nb];
            for j in &m.joints {
                for &x in &j.bodies {
                    pairs[x] += 1;
                }
            }
            // The geometry was checked before the enumeration: this analysis cannot fail.
            let a = structure::analyze(m, &opts.analysis, &Library::empty()).ok();
            let a = a.as_ref();
            if let Some(a) = a {
                for (q, &n) in a.set_aside.iter().enumerate() {
                    set_aside[q] = n;
                }
            }
            for iso in a.map(|a| &a.isolated[..]).unwrap_or(&[]) {
                let id = crate::mechanism::BodyId::from_text(&iso.body);
                if let Some(x) = m.body_index(&id)
                    && pairs[x] >= 2
                {
                    u[x] = u[x].saturating_sub(iso.dimension);
                    isolated += iso.dimension;
                }
            }
        }
        let nq = m.joints.len();
        let mut p = Problem {
            frame: m.frame,
            u,
            a: Vec::with_capacity(nq),
            c: Vec::with_capacity(nq),
            touching: vec![Vec::new(); nb],
            lo: vec![0; nq],
            hi: vec![0; nq],
            kept_groups: Vec::new(),
            cand: Vec::new(),
            isolated,
            set_aside: set_aside.iter().sum(),
            f: 0,
            need: 0,
            root: None,
            note: None,
        };
        let mut cons = vec![0u32; nq];
        let mut group_pairs: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
        for (q, j) in m.joints.iter().enumerate() {
            let (x, y) = match j.bodies[..] {
                [x, y] => (x, y),
                // Every joint of an expansion is binary; anything else would have no pair.
                _ => (m.frame, m.frame),
            };
            p.a.push(x);
            p.c.push(y);
            for z in [x, y] {
                if z != m.frame && !p.touching[z].contains(&q) {
                    p.touching[z].push(q);
                }
            }
            cons[q] = b.saturating_sub(j.grade()).saturating_sub(set_aside[q]);
            let o = e.origin[q];
            let k = j.grade();
            let ok = rules.allowed[o] && (!rules.grounded || x == m.frame || y == m.frame);
            let kept = rules.keep[o];
            if orig.joints[o].bodies.len() > 2 {
                p.hi[q] = if ok || kept > 0 { k } else { 0 };
                if kept > 0 {
                    group_pairs.entry(o).or_default().push(q);
                }
            } else {
                p.lo[q] = kept.min(k);
                p.hi[q] = if ok { k } else { p.lo[q] };
            }
        }
        p.kept_groups = group_pairs
            .into_iter()
            .map(|(o, qs)| (qs, rules.keep[o]))
            .collect();
        p.cand = (0..nq).filter(|&q| p.hi[q] > p.lo[q]).collect();
        let total_u: i64 = p.u.iter().map(|&x| x as i64).sum();
        let total_c: i64 = cons.iter().map(|&x| x as i64).sum();
        p.f = total_u - total_c;
        let kept: i64 = p.lo.iter().map(|&x| x as i64).sum();
        if p.f < 0 {
            p.note = Some(format!(
                "the joints remove {} DOF more than the bodies have: no placement of inputs \
                 can determine the mechanism",
                -p.f
            ));
            return p;
        }
        if kept > p.f {
            p.note = Some(format!(
                "the kept inputs ({kept}) are more than the {} the mechanism takes",
                p.f
            ));
            return p;
        }
        p.need = (p.f - kept) as usize;
        let mut s = State {
            flow: vec![[0; 2]; nq],
            used: vec![0; nb],
        };
        let mut scratch = p.scratch();
        for (q, &n) in cons.iter().enumerate() {
            for _ in 0..n {
                if p.augment(&mut s, &[q], &mut scratch).is_none() {
                    p.note = Some(format!(
                        "the joints' own equations over-determine the bodies near joint {} (by \
                         count): no placement of inputs can determine the mechanism",
                        m.joints[q].id
                    ));
                    return p;
                }
            }
        }
        for q in 0..nq {
            for _ in 0..p.lo[q] {
                if p.augment(&mut s, &[q], &mut scratch).is_none() {
                    p.note = Some(format!(
                        "the kept input on joint {} over-determines the bodies it joins: no \
                         placement keeping it is determined",
                        m.joints[q].id
                    ));
                    return p;
                }
            }
        }
        p.root = Some(s);
        p
    }

    /// Pairs that may be driven (including kept ones).
    fn drivable(&self) -> usize {
        self.hi.iter().filter(|&&h| h > 0).count()
    }

    fn scratch(&self) -> Scratch {
        let nb = self.u.len();
        Scratch {
            seen: vec![0; nb],
            stamp: 0,
            prev: vec![(NONE, NONE); nb],
            queue: Vec::with_capacity(nb),
        }
    }

    fn side(&self, q: usize, x: usize) -> usize {
        usize::from(self.a[q] != x)
    }

    fn other(&self, q: usize, x: usize) -> usize {
        if self.a[q] == x { self.c[q] } else { self.a[q] }
    }

    /// Route one more equation unit from one of `sources` to a body with spare unknowns,
    /// rerouting earlier units along an augmenting path. Returns the source used.
    fn augment(&self, s: &mut State, sources: &[usize], sc: &mut Scratch) -> Option<usize> {
        sc.stamp = sc.stamp.wrapping_add(1);
        if sc.stamp == 0 {
            sc.seen.iter_mut().for_each(|v| *v = 0);
            sc.stamp = 1;
        }
        sc.queue.clear();
        for &q in sources {
            for x in [self.a[q], self.c[q]] {
                if x != self.frame && sc.seen[x] != sc.stamp {
                    sc.seen[x] = sc.stamp;
                    sc.prev[x] = (q as u32, NONE);
                    sc.queue.push(x);
                }
            }
        }
        let mut qi = 0;
        while qi < sc.queue.len() {
            let x = sc.queue[qi];
            qi += 1;
            if s.used[x] < self.u[x] {
                s.used[x] += 1;
                let mut t = x;
                loop {
                    let (q, from) = sc.prev[t];
                    let q = q as usize;
                    s.flow[q][self.side(q, t)] += 1;
                    if from == NONE {
                        return Some(q);
                    }
                    let from = from as usize;
                    s.flow[q][self.side(q, from)] -= 1;
                    t = from;
                }
            }
            for &q in &self.touching[x] {
                if s.flow[q][self.side(q, x)] == 0 {
                    continue;
                }
                let y = self.other(q, x);
                if y != self.frame && y != x && sc.seen[y] != sc.stamp {
                    sc.seen[y] = sc.stamp;
                    sc.prev[y] = (q as u32, x as u32);
                    sc.queue.push(y);
                }
            }
        }
        None
    }

    /// Whether `need` more units fit using the candidates from position `from` on.
    fn extends(&self, s: &State, w: &[u32], from: usize, need: usize, sc: &mut Scratch) -> bool {
        if need == 0 {
            return true;
        }
        let mut extra: Vec<(usize, u32)> = self.cand[from.min(self.cand.len())..]
            .iter()
            .map(|&q| (q, self.hi[q] - w[q]))
            .filter(|&(_, x)| x > 0)
            .collect();
        let spare: u64 = extra.iter().map(|&(_, x)| x as u64).sum();
        if spare < need as u64 {
            return false;
        }
        let mut s = s.clone();
        let mut sources: Vec<usize> = extra.iter().map(|&(q, _)| q).collect();
        for _ in 0..need {
            let Some(q) = self.augment(&mut s, &sources, sc) else {
                return false;
            };
            if let Some(pos) = extra.iter().position(|&(r, _)| r == q) {
                extra[pos].1 -= 1;
                if extra[pos].1 == 0 {
                    extra.remove(pos);
                    sources = extra.iter().map(|&(r, _)| r).collect();
                }
            }
        }
        true
    }

    /// The first candidate position from which `need` units no longer fit (monotone, so a
    /// binary search), at least `from`.
    fn reach(&self, s: &State, w: &[u32], from: usize, need: usize, sc: &mut Scratch) -> usize {
        if !self.extends(s, w, from, need, sc) {
            return from;
        }
        // extends(lo) holds, extends(hi) fails.
        let (mut lo, mut hi) = (from, self.cand.len());
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if self.extends(s, w, mid, need, sc) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    }

    /// Push every count-valid placement (sparse `(pair, driven)`, pair order) into `out`, at
    /// most `limit`. Returns whether the limit cut the search.
    fn enumerate(&self, limit: usize, out: &mut Vec<Vec<(usize, u32)>>) -> bool {
        let Some(root) = &self.root else {
            return false;
        };
        let mut sc = self.scratch();
        let mut w = self.lo.clone();
        let emit = |w: &[u32], out: &mut Vec<Vec<(usize, u32)>>| -> bool {
            let ok = self
                .kept_groups
                .iter()
                .all(|(qs, min)| qs.iter().map(|&q| w[q]).sum::<u32>() >= *min);
            if ok {
                out.push(
                    (0..w.len())
                        .filter(|&q| w[q] > 0)
                        .map(|q| (q, w[q]))
                        .collect(),
                );
            }
            ok
        };
        if limit == 0 {
            return true;
        }
        if self.need == 0 {
            emit(&w, out);
            return false;
        }
        // Depth-first over multisets of candidate positions (non-decreasing), one unit per
        // level, so the depth is at most `need`; explicit stack, no recursion.
        struct Node {
            state: State,
            next: usize,
            end: usize,
        }
        let end = self.reach(root, &w, 0, self.need, &mut sc);
        let mut stack = vec![Node {
            state: root.clone(),
            next: 0,
            end,
        }];
        let mut path: Vec<usize> = Vec::new();
        while let Some(top) = stack.last_mut() {
            if top.next >= top.end {
                stack.pop();
                if let Some(ci) = path.pop() {
                    w[self.cand[ci]] -= 1;
                }
                continue;
            }
            let ci = top.next;
            top.next += 1;
            let q = self.cand[ci];
            if w[q] >= self.hi[q] {
                continue;
            }
            let mut s = top.state.clone();
            if self.augment(&mut s, &[q], &mut sc).is_none() {
                // Dependent: this slot over-determines some part; so would every larger set.
                continue;
            }
            w[q] += 1;
            let left = self.need - path.len() - 1;
            if left == 0 {
                emit(&w, out);
                w[q] -= 1;
                if out.len() >= limit {
                    return true;
                }
                continue;
            }
            path.push(ci);
            let end = self.reach(&s, &w, ci, left, &mut sc);
            stack.push(Node {
                state: s,
                next: ci,
                end,
            });
        }
        false
    }
}

// ---------------------------------------------------------------------------------------------
// Full analysis of a placement

/// Analyse `mech` with the placement `w`; the analysis if it is determined.
fn evaluate(
    mech: &mut Mechanism,
    w: &[(usize, u32)],
    opts: &structure::Options,
    lib: &Library,
) -> Option<Analysis> {
    for j in &mut mech.joints {
        j.driven = 0;
    }
    for &(q, n) in w {
        mech.joints[q].driven = n;
    }
    // The geometry was checked before the enumeration: this analysis cannot fail.
    structure::analyze(mech, opts, lib)
        .ok()
        .filter(|a| a.status == Status::Determined)
}

fn placement(
    mech: &Mechanism,
    e: &Expansion,
    x: usize,
    a: &Analysis,
    w: &[(usize, u32)],
) -> Placement {
    Placement {
        rank: None,
        family: None,
        inputs: inputs_of(mech, e, w),
        expansion: e.label.clone(),
        scores: scores(a),
        types: a.types.clone(),
        partition: a.groups.iter().map(|g| g.bodies.clone()).collect(),
        seq: 0,
        exp: x,
    }
}

// ---------------------------------------------------------------------------------------------
// One given placement beside the file's own

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
    /// The groups in canonical order.
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prufer_trees_are_spanning_and_distinct() {
        for n in 2..=5 {
            let mut seen = std::collections::BTreeSet::new();
            for i in 0..trees(n) {
                let t = prufer_tree(n, i);
                assert_eq!(t.len(), n - 1);
                // Connected: union-find over the edges.
                let mut p: Vec<usize> = (0..n).collect();
                fn root(p: &mut [usize], mut x: usize) -> usize {
                    while p[x] != x {
                        x = p[x];
                    }
                    x
                }
                for &(a, b) in &t {
                    let (ra, rb) = (root(&mut p, a), root(&mut p, b));
                    assert_ne!(ra, rb, "cycle in tree {i} of K{n}");
                    p[ra] = rb;
                }
                assert!(seen.insert(t));
            }
            assert_eq!(seen.len() as u64, trees(n));
        }
        // Index 0 is the star on the hub.
        assert_eq!(prufer_tree(4, 0), vec![(0, 1), (0, 2), (0, 3)]);
    }

    #[test]
    fn parses_criteria_and_types() {
        assert_eq!(
            Criterion::parse_list("groups,library,max-size,levels").unwrap(),
            Criterion::DEFAULT.to_vec()
        );
        assert_eq!(
            Criterion::parse_list("levels, groups,levels").unwrap(),
            vec![Criterion::Levels, Criterion::Groups]
        );
        assert!(matches!(
            Criterion::parse("size"),
            Err(TransformError::UnknownCriterion { .. })
        ));
        assert_eq!(
            TransformOptions::parse_on("R,P").unwrap(),
            vec![JointType::R, JointType::P]
        );
        assert!(matches!(
            TransformOptions::parse_on("R,Q"),
            Err(TransformError::UnknownType { .. })
        ));
    }
}
