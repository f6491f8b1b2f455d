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
//! ([`crate::structure::analyze_cached`], with its rank check unless `count_only`), in
//! parallel, and the ones the rank check rejects are excluded and counted. The analyses of one
//! expansion share the rank check's factorizations (a placement re-factorizes only the bodies
//! and blocks whose rows its inputs change) and start their maximum flow from the search's own
//! matching, so a placement costs about one pass over the mechanism plus its new groups.
//! `docs/algorithms.md` has details.

use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::joint::JointType;
use crate::mechanism::{InputSpec, InputSpecError, Joint, Mechanism, resolve_ref};
use crate::structure::{self, Analysis, Library, Status, TypeCount};
use rayon::prelude::*;
use serde::Serialize;
use std::cmp::Ordering;
use std::collections::{BTreeMap, HashMap};
use std::sync::{Arc, OnceLock};

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
    /// `--limit`: how many count-valid placements to examine at most (per part); the search
    /// stops there (it only looks on for one more, to say whether any were left out).
    pub limit: Option<usize>,
    /// Caps on the work of the search and the analyses (`--max-work`, `--budget`).
    pub budget: Budget,
    /// Place the independent parts one by one (default). `false` places the whole mechanism
    /// as one: the same placements, counts and scores, at the cost of the product (tests).
    pub split: bool,
    /// Analyse every placement in full (tests: the former path). By default a placement the
    /// exact rank certifies is analysed from the search's own flow (the same groups, types
    /// and scores), and every placement of a mechanism whose constraint equations are
    /// dependent is rejected by one exact rank (the same verdicts).
    pub full_analyses: bool,
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
            budget: Budget::DEFAULT,
            split: true,
            full_analyses: false,
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
    /// The work of the search or of the analyses passed the budget.
    #[error(transparent)]
    Budget(#[from] BudgetExceeded),
    /// The groups of a listed placement could not be made again for output (never expected:
    /// they were made once during the search, from the same placement).
    #[error("internal error: the groups of the placement ranked {rank} could not be made again")]
    Regenerate {
        /// Rank of the placement.
        rank: usize,
    },
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
    pub partition: Partition,
    /// Enumeration order (deterministic), the final tie-break.
    #[serde(skip)]
    seq: usize,
    /// Index of the expansion (0 = every multiple joint as a star on its hub).
    #[serde(skip)]
    exp: usize,
    /// Index (in the mechanism's joints) of the joint of each input.
    #[serde(skip)]
    inputs_at: Vec<usize>,
    /// Level and smallest body (index) of each group of `partition`.
    #[serde(skip)]
    groups_at: Vec<(usize, usize)>,
    /// SG type of each group of `partition` (its index in `types`).
    #[serde(skip)]
    kinds: Vec<u32>,
    /// Whether the library covers each group of `partition`.
    #[serde(skip)]
    in_lib: Vec<bool>,
    /// The placement (units per pair of the expansion, sparse) when its groups came from the
    /// search's flow ([`Lean`]) of a mechanism placed whole: [`ranked`] drops the partition
    /// and makes it again from this when it is written.
    #[serde(skip)]
    lean: Option<Vec<(usize, u32)>>,
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
}

/// The groups' bodies of a placement, in canonical order, kept as body indices into the
/// mechanism's body ids (shared by every placement): four bytes a body instead of a string
/// each. A listed placement of a 10^5-body linkage held 10^5 strings (about 6 MB; 100 of them
/// and their families' copies were 2.3 GB of `transform --limit 100`). It serializes as the
/// list of lists of body ids it stands for.
#[derive(Clone, Debug)]
pub struct Partition(Repr);

#[derive(Clone, Debug)]
enum Repr {
    /// Group `g` is `bodies[ends[g - 1]..ends[g]]`, each an index into `ids`.
    Indexed {
        ids: Arc<Vec<String>>,
        bodies: Vec<u32>,
        ends: Vec<u32>,
    },
    /// The ids themselves: an analysis named a body the id table lacks (never expected).
    Text(Vec<Vec<String>>),
}

impl Partition {
    /// Groups of bodies given as indices into `ids`.
    fn indexed(ids: &Arc<Vec<String>>, groups: impl Iterator<Item = Vec<u32>>) -> Partition {
        let mut bodies = Vec::new();
        let mut ends = Vec::new();
        for g in groups {
            bodies.extend_from_slice(&g);
            ends.push(bodies.len() as u32);
        }
        bodies.shrink_to_fit();
        ends.shrink_to_fit();
        Partition(Repr::Indexed {
            ids: Arc::clone(ids),
            bodies,
            ends,
        })
    }

    /// Number of groups.
    pub fn len(&self) -> usize {
        match &self.0 {
            Repr::Indexed { ends, .. } => ends.len(),
            Repr::Text(v) => v.len(),
        }
    }

    /// Whether there are no groups.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn range(ends: &[u32], g: usize) -> std::ops::Range<usize> {
        let start = if g == 0 { 0 } else { ends[g - 1] as usize };
        start..ends[g] as usize
    }

    /// Body ids of group `g` (empty past the last group).
    pub fn group(&self, g: usize) -> Vec<&str> {
        match &self.0 {
            Repr::Indexed { ids, bodies, ends } if g < ends.len() => bodies[Self::range(ends, g)]
                .iter()
                .map(|&x| ids.get(x as usize).map_or("", String::as_str))
                .collect(),
            Repr::Text(v) => v
                .get(g)
                .map(|grp| grp.iter().map(String::as_str).collect())
                .unwrap_or_default(),
            _ => Vec::new(),
        }
    }

    /// Number of bodies of group `g`.
    fn group_len(&self, g: usize) -> usize {
        match &self.0 {
            Repr::Indexed { ends, .. } if g < ends.len() => Self::range(ends, g).len(),
            Repr::Text(v) => v.get(g).map_or(0, Vec::len),
            _ => 0,
        }
    }

    /// Every group's body ids.
    pub fn to_vec(&self) -> Vec<Vec<String>> {
        (0..self.len())
            .map(|g| self.group(g).into_iter().map(str::to_string).collect())
            .collect()
    }

    /// An order-independent fingerprint of the groups (the number of groups and two 64-bit
    /// sums of a SipHash of each group's bodies in order): equal partitions (the same groups,
    /// each with its bodies in the same order, in any group order) have equal fingerprints,
    /// and different ones equal fingerprints with probability about 2^-128. Families are
    /// made by it, so a listed placement's partition need not be held.
    fn fingerprint(&self) -> Fingerprint {
        use std::hash::{DefaultHasher, Hash, Hasher};
        let mut sums = [0u64; 2];
        for g in 0..self.len() {
            for (lane, sum) in sums.iter_mut().enumerate() {
                let mut h = DefaultHasher::new();
                (lane as u8).hash(&mut h);
                match &self.0 {
                    Repr::Indexed { bodies, ends, .. } => {
                        0u8.hash(&mut h);
                        bodies[Self::range(ends, g)].hash(&mut h);
                    }
                    Repr::Text(v) => {
                        1u8.hash(&mut h);
                        v[g].hash(&mut h);
                    }
                }
                *sum = sum.wrapping_add(h.finish());
            }
        }
        (self.len(), sums[0], sums[1])
    }
}

/// [`Partition::fingerprint`].
type Fingerprint = (usize, u64, u64);

impl PartialEq for Partition {
    fn eq(&self, other: &Partition) -> bool {
        self.len() == other.len() && (0..self.len()).all(|g| self.group(g) == other.group(g))
    }
}

impl Eq for Partition {}

impl Serialize for Partition {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        /// One group's body ids, written without collecting them.
        struct Group<'a>(&'a Partition, usize);
        impl Serialize for Group<'_> {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                match &self.0.0 {
                    Repr::Indexed { ids, bodies, ends } if self.1 < ends.len() => s.collect_seq(
                        bodies[Partition::range(ends, self.1)]
                            .iter()
                            .map(|&x| ids.get(x as usize).map_or("", String::as_str)),
                    ),
                    _ => s.collect_seq(self.0.group(self.1)),
                }
            }
        }
        let mut seq = s.serialize_seq(Some(self.len()))?;
        for g in 0..self.len() {
            seq.serialize_element(&Group(self, g))?;
        }
        seq.end()
    }
}

/// The body ids of a mechanism as the analysis writes them, shared by its placements'
/// partitions, and (made on first use, by the full analyses only) the index of each.
struct BodyNames {
    ids: Arc<Vec<String>>,
    index: OnceLock<HashMap<String, u32>>,
}

impl BodyNames {
    fn of(m: &Mechanism) -> BodyNames {
        BodyNames {
            ids: Arc::new(m.bodies.iter().map(|b| b.id.to_string()).collect()),
            index: OnceLock::new(),
        }
    }

    /// The partition of groups given by their body ids.
    fn partition(&self, groups: &[&[String]]) -> Partition {
        let index = self.index.get_or_init(|| {
            let mut h = HashMap::with_capacity(self.ids.len());
            for (i, id) in self.ids.iter().enumerate() {
                h.entry(id.clone()).or_insert(i as u32);
            }
            h
        });
        let mut out: Vec<Vec<u32>> = Vec::with_capacity(groups.len());
        for g in groups {
            let mut v = Vec::with_capacity(g.len());
            for id in g.iter() {
                match index.get(id) {
                    Some(&x) => v.push(x),
                    None => {
                        return Partition(Repr::Text(groups.iter().map(|g| g.to_vec()).collect()));
                    }
                }
            }
            out.push(v);
        }
        Partition::indexed(&self.ids, out.into_iter())
    }
}

/// Placements with the same partition into groups.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Family {
    /// 1-based, in order of the best member's rank.
    pub id: usize,
    /// The groups' bodies (as in the best member).
    pub partition: Partition,
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
    /// Independent parts: the mechanism's bodies form this many connected pieces once the
    /// frame is removed. Each is placed on its own; the counts are products over the parts.
    pub parts: usize,
    /// Binary expansions of the multiple joints explored (a product over the parts).
    pub expansions: usize,
    /// Binary expansions there are (saturating: `u64::MAX` means more than 10^19, and the
    /// notes say so in words).
    pub expansions_total: u64,
    /// Count-valid placements examined by the full analysis (with several parts: the product
    /// of the parts' counts). A count too large to hold (`u128::MAX`) is written in words,
    /// "more than 10^38".
    #[serde(serialize_with = "ser_count")]
    pub count_valid: u128,
    /// Count-valid placements the rank check rejected (not determined).
    #[serde(serialize_with = "ser_count")]
    pub excluded_by_rank: u128,
    /// Determined placements (exact unless `truncated`).
    #[serde(serialize_with = "ser_count")]
    pub determined: u128,
    /// Determined placements listed (the best ones; at most 100,000, fewer for large
    /// mechanisms, and at most `--limit`).
    pub listed: usize,
    /// The `--limit` used, if any.
    pub limit: Option<usize>,
    /// Whether the search left placements out: `--limit` was reached and at least one more
    /// count-valid placement exists.
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

/// The most placements a result lists (and keeps in memory): 100,000, fewer for large
/// mechanisms (about 256 MB of listed placements). Counts are never cut by it.
fn list_cap(m: &Mechanism, limit: Option<usize>) -> usize {
    let per = 64 * (m.bodies.len() + m.joints.len()) + 512;
    let cap = (LIST_MEMORY / per).clamp(1_000, 100_000);
    limit.map_or(cap, |l| l.min(cap))
}

/// Bytes of listed placements a result may hold ([`list_cap`]).
const LIST_MEMORY: usize = 256 << 20;

/// Placements analysed per parallel batch (and between progress reports).
const BATCH: usize = 512;

/// Bytes of the search's flows a batch may hold (warm starts of the analyses).
const BATCH_FLOW_BYTES: usize = 64 << 20;

/// The search's callback: a placement (units per pair) and its flow (units of each pair into
/// its two bodies); `false` stops the search.
type LeafFn<'a> = &'a mut dyn FnMut(&[u32], &[[u32; 2]]) -> bool;

/// A placement waiting for its analysis: expansion, driven pairs, and the search's flow
/// (units of each pair into its two bodies).
type Leaf = (usize, Vec<(usize, u32)>, Vec<[u8; 2]>);

/// Enumerate the determined placements and stream them to `sink`, calling `progress` between
/// batches. Returns the counts.
///
/// A mechanism in one part (its bodies connected without the frame) streams in enumeration
/// order (deterministic, unranked) from the first placement found. A mechanism of several
/// independent parts ([`Summary::parts`]) is placed part by part and the parts combined; its
/// placements stream best first, at most [`list_cap`] of them, while the counts are exact.
pub fn enumerate(
    m: &Mechanism,
    opts: &TransformOptions,
    lib: &Library,
    progress: Option<ProgressFn<'_>>,
    sink: &mut dyn FnMut(Placement),
) -> Result<Summary, TransformError> {
    enumerate_kept(m, opts, lib, progress, sink, None)
}

/// [`enumerate`]; with `keep`, a mechanism placed whole in one expansion keeps its problem
/// there, and the placements analysed from the search's flow carry their inputs to make
/// their groups again ([`Placement::lean`]).
fn enumerate_kept(
    m: &Mechanism,
    opts: &TransformOptions,
    lib: &Library,
    progress: Option<ProgressFn<'_>>,
    sink: &mut dyn FnMut(Placement),
    keep: Option<&mut Option<Problem>>,
) -> Result<Summary, TransformError> {
    let mut rules = Rules::of(m, opts)?;
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
    rules.random = geometry.as_ref().is_none_or(|g| g.seed.is_some());
    let mob = crate::mobility::mobility(m);
    let mut meter = opts.budget.meter("the transform search");
    let parts = if opts.split { part_sets(m) } else { Vec::new() };
    let mut summary = Summary {
        name: m.name.clone(),
        count: mob.mobility.count,
        isolated: 0,
        set_aside: 0,
        geometry,
        f: 0,
        drivable: 0,
        parts: parts.len().max(1),
        expansions: 1,
        expansions_total: 1,
        count_valid: 0,
        excluded_by_rank: 0,
        determined: 0,
        listed: 0,
        limit: opts.limit,
        truncated: false,
        notes: rules.notes.clone(),
    };
    if parts.len() <= 1 {
        let r = place(
            m,
            &rules,
            opts,
            lib,
            &mut meter,
            progress,
            &mut |p| {
                sink(p);
                true
            },
            keep,
        )?;
        summary.absorb(&r);
        summary.count_valid = r.count_valid as u128;
        summary.excluded_by_rank = r.excluded as u128;
        summary.determined = r.determined as u128;
        summary.listed = r.determined;
        summary.truncated = r.cut;
        summary.notes.extend(r.notes);
        finish_notes(&mut summary, opts);
        return Ok(summary);
    }
    combine_parts(
        m,
        &parts,
        &rules,
        opts,
        lib,
        &mut meter,
        progress,
        &mut summary,
        sink,
    )?;
    finish_notes(&mut summary, opts);
    Ok(summary)
}

/// The notes every run ends with: truncation, rank-check exclusions, a partial listing.
fn finish_notes(s: &mut Summary, opts: &TransformOptions) {
    if s.expansions_total > s.expansions as u64 {
        s.notes.push(format!(
            "explored {} of {} binary expansions of the multiple joints (raise --max-expansions)",
            s.expansions,
            crate::budget::count_in_words(s.expansions_total)
        ));
    }
    // Zero placements always get a reason: the specific ones (too few drivable DOF, the
    // joints over-determining the bodies) say "no placement"; otherwise the count itself.
    if s.count_valid == 0
        && s.f > 0
        && !s.truncated
        && !s.notes.iter().any(|n| n.contains("no placement"))
    {
        s.notes.push(format!(
            "no placement of the {} input(s) on the {} joint(s) that may be driven passes the \
             count: each one leaves some bodies with freedoms no input fixes while others get \
             more inputs than freedoms",
            s.f, s.drivable
        ));
    }
    if s.truncated {
        s.notes.push(format!(
            "the search stopped at --limit {}: more placements exist and are not ranked here{}",
            opts.limit.unwrap_or(0),
            if s.parts > 1 {
                " (the counts are lower bounds)"
            } else {
                ""
            }
        ));
        if s.determined == 0 && s.count_valid > 0 {
            // A Delta robot at --limit 20: every placement examined drove a rod's spin.
            s.notes.push(format!(
                "none of the {} placement(s) examined is determined: raise --limit, or narrow the \
                 search with --on, --grounded or --exclude",
                count_words(s.count_valid)
            ));
        }
    }
    if s.excluded_by_rank > 0 {
        s.notes.push(format!(
            "{} of {} count-valid placements are not determined (the rank check finds redundant \
             equations or uncontrolled freedoms) and are excluded",
            count_words(s.excluded_by_rank),
            count_words(s.count_valid)
        ));
    }
    if (s.listed as u128) < s.determined {
        s.notes.push(format!(
            "{} determined placements: the best {} are listed",
            count_words(s.determined),
            s.listed
        ));
    }
}

/// A count for messages; a saturated `u128::MAX` says "more than 10^38".
pub fn count_words(n: u128) -> String {
    if n == u128::MAX {
        "more than 10^38".to_string()
    } else {
        n.to_string()
    }
}

/// Serialize a count as a number, or as words when it saturated.
fn ser_count<S: serde::Serializer>(n: &u128, s: S) -> Result<S::Ok, S::Error> {
    if *n == u128::MAX {
        s.serialize_str(&count_words(*n))
    } else {
        s.serialize_u128(*n)
    }
}

/// What placing one mechanism (or one part) found.
#[derive(Default)]
struct Placed {
    isolated: u32,
    set_aside: u32,
    f: i64,
    drivable: usize,
    expansions: usize,
    expansions_total: u64,
    count_valid: usize,
    excluded: usize,
    determined: usize,
    cut: bool,
    notes: Vec<String>,
}

impl Summary {
    fn absorb(&mut self, r: &Placed) {
        self.isolated += r.isolated;
        self.set_aside += r.set_aside;
        self.f += r.f;
        self.drivable += r.drivable;
        self.expansions = self.expansions.saturating_mul(r.expansions);
        self.expansions_total = self.expansions_total.saturating_mul(r.expansions_total);
    }
}

/// Work units charged for one structural analysis of `m` (a placement's, or the first one
/// before the search): an estimate proportional to its size, made before it runs.
fn analysis_work(m: &Mechanism) -> u64 {
    (m.bodies.len() + m.joints.len()) as u64 * 50 + 100
}

/// Enumerate and analyse the placements of `m` (one part), streaming each determined one to
/// `sink` in enumeration order (`sink` returns `false` to stop early). `--limit` bounds the
/// count-valid placements examined; the search goes on only to learn whether one more
/// exists (`cut`).
#[allow(clippy::too_many_arguments)]
fn place(
    m: &Mechanism,
    rules: &Rules,
    opts: &TransformOptions,
    lib: &Library,
    meter: &mut Meter,
    progress: Option<ProgressFn<'_>>,
    sink: &mut dyn FnMut(Placement) -> bool,
    mut keep: Option<&mut Option<Problem>>,
) -> Result<Placed, TransformError> {
    let exps = Expansions::of(m, opts.max_expansions);
    // With `keep` and one expansion, a placement analysed from the search's flow carries its
    // inputs (`Placement::lean`), and the expansion's problem is kept to make its groups again.
    let defer = keep.is_some() && exps.len == 1;
    let mut r = Placed {
        expansions: exps.len,
        expansions_total: exps.total,
        f: crate::mobility::mobility(m).mobility.count,
        ..Placed::default()
    };
    let limit = opts.limit.unwrap_or(usize::MAX);
    let per_eval = analysis_work(m);
    // The body ids every placement's partition indexes (an expansion keeps the bodies).
    let names = BodyNames::of(m);
    // (expansion, placement, the search's flow for a warm start of the analysis)
    let mut batch: Vec<Leaf> = Vec::new();
    let mut stopped = false;
    // Analyse a batch in parallel and stream its determined placements in order.
    let flush = |e: &Expansion,
                 cache: &structure::AnalysisCache,
                 oracle: &Oracle,
                 lean: Option<&Lean>,
                 batch: &mut Vec<Leaf>,
                 r: &mut Placed,
                 meter: &mut Meter,
                 stopped: &mut bool,
                 sink: &mut dyn FnMut(Placement) -> bool|
     -> Result<(), BudgetExceeded> {
        if batch.is_empty() || *stopped {
            batch.clear();
            return Ok(());
        }
        // One unit a placement first; what each then spends (the exact decision of its
        // inputs, a lean analysis, a full one and the rank decisions inside it) after the
        // batch.
        meter.charge(batch.len() as u64)?;
        let results: Vec<(Option<Placement>, u64)> = batch
            .par_iter()
            .map_init(
                // A copy of the expansion only for the placements analysed in full.
                || None::<Mechanism>,
                |mech, (x, w, flow)| {
                    let decided = oracle.work(w);
                    let certified = match oracle.decide(&e.mech, w) {
                        Some(false) => return (None, decided),
                        Some(true) => true,
                        None => false,
                    };
                    if certified && let Some(l) = lean {
                        let g = l.groups(&e.mech, flow, lib);
                        let mut p = placement_of(&e.mech, e, *x, w, g);
                        if defer {
                            p.lean = Some(w.clone());
                        }
                        return (Some(p), decided.saturating_add(l.work));
                    }
                    let mech = mech.get_or_insert_with(|| e.mech.as_ref().clone());
                    let (a, work) = evaluate(mech, w, flow, &opts.analysis, lib, cache, certified);
                    (
                        a.map(|a| placement(mech, e, *x, &a, w, &names)),
                        work.saturating_add(per_eval).saturating_add(decided),
                    )
                },
            )
            .collect();
        // The analyses' work: a full analysis its estimate and its rank decisions (dense
        // factorizations of growing groups above all), a lean one its pass over the arrays.
        meter.charge(results.iter().map(|r| r.1).fold(0u64, u64::saturating_add))?;
        let results = results.into_iter().map(|r| r.0);
        let done = r.count_valid;
        for (i, p) in results.enumerate() {
            r.count_valid += 1;
            match p {
                Some(mut p) => {
                    p.seq = done + i;
                    r.determined += 1;
                    if !*stopped && !sink(p) {
                        *stopped = true;
                    }
                }
                None => r.excluded += 1,
            }
        }
        batch.clear();
        if let Some(cb) = progress {
            cb(Progress {
                examined: r.count_valid,
                total: r.count_valid,
                determined: r.determined,
            });
        }
        Ok(())
    };
    // The analyses charge their own meter (the search holds `meter`): each may spend the
    // work budget.
    let mut eval_meter = opts.budget.meter("the analysis of the placements");
    let mut found = 0usize;
    let mut batch_size = 1usize;
    // A batch holds each placement's flow (two bytes a pair): at most about 64 MB of them.
    let max_batch = (BATCH_FLOW_BYTES / (2 * m.joints.len().max(1))).clamp(1, BATCH);
    let mut by_parts = ExpansionParts::applies(&exps, rules, opts).then(ExpansionParts::default);
    for x in 0..exps.len {
        if let Some(parts) = &mut by_parts
            && let Some(got) =
                parts.place(&exps.skeleton(x), x, rules, opts, lib, &names.ids, meter)?
        {
            if x == 0 {
                r.isolated = got.isolated;
                r.set_aside = got.set_aside;
                r.f = got.f;
                r.drivable = got.drivable;
            }
            if let Some(p) = got.placement {
                // As the search and `flush` count a placement of the whole expansion.
                if found >= limit {
                    r.cut = true;
                    break;
                }
                found += 1;
                let seq = r.count_valid;
                r.count_valid += 1;
                match p {
                    Some(mut p) => {
                        p.seq = seq;
                        r.determined += 1;
                        if !stopped && !sink(p) {
                            stopped = true;
                        }
                    }
                    None => r.excluded += 1,
                }
                if let Some(cb) = progress {
                    cb(Progress {
                        examined: r.count_valid,
                        total: r.count_valid,
                        determined: r.determined,
                    });
                }
            }
            if stopped {
                break;
            }
            continue;
        }
        let e = &exps.get(x);
        // The rank check's factorizations, shared by every analysis of this expansion: a
        // placement re-factorizes only the blocks and bodies whose rows its inputs changed.
        let cache = structure::AnalysisCache::default();
        let p = Problem::of(e, m, rules, opts, &cache, &names.ids, meter)?;
        if x == 0 {
            r.isolated = p.isolated;
            r.set_aside = p.set_aside;
            r.f = p.f;
            r.drivable = p.drivable();
            if let Some(n) = &p.note {
                r.notes.push(n.clone());
            }
        }
        let mut err: Option<BudgetExceeded> = None;
        // `Oracle::Later`: decided once a placement of this expansion is rejected.
        let mut late: Option<Oracle> = None;
        let excluded_before = r.excluded;
        p.search(meter, &mut |w, flow| {
            if found >= limit {
                r.cut = true;
                return false;
            }
            found += 1;
            batch.push((
                x,
                (0..w.len())
                    .filter(|&q| w[q] > 0)
                    .map(|q| (q, w[q]))
                    .collect(),
                flow.iter()
                    .map(|f| [f[0].min(255) as u8, f[1].min(255) as u8])
                    .collect(),
            ));
            if batch.len() >= batch_size {
                // Batches grow from one placement: the first ones stream at once.
                batch_size = (batch_size * 2).min(max_batch);
                // Only with more placements to analyse: a rejected single one (each
                // expansion of a shared joint) pays nothing.
                if late.is_none()
                    && r.excluded > excluded_before
                    && matches!(p.oracle, Oracle::Later { .. })
                {
                    late = Some(p.oracle.dependent(&e.mech, &opts.budget, &mut eval_meter));
                }
                if let Err(b) = flush(
                    e,
                    &cache,
                    late.as_ref().unwrap_or(&p.oracle),
                    p.lean.as_ref(),
                    &mut batch,
                    &mut r,
                    &mut eval_meter,
                    &mut stopped,
                    &mut *sink,
                ) {
                    err = Some(b);
                    return false;
                }

                if stopped {
                    return false;
                }
            }
            true
        })?;
        if let Some(b) = err {
            return Err(b.into());
        }
        // The rest of the batch belongs to this expansion: analysed before the next is built.
        if late.is_none()
            && !batch.is_empty()
            && r.excluded > excluded_before
            && matches!(p.oracle, Oracle::Later { .. })
        {
            late = Some(p.oracle.dependent(&e.mech, &opts.budget, &mut eval_meter));
        }
        flush(
            e,
            &cache,
            late.as_ref().unwrap_or(&p.oracle),
            p.lean.as_ref(),
            &mut batch,
            &mut r,
            &mut eval_meter,
            &mut stopped,
            &mut *sink,
        )?;
        if defer
            && x == 0
            && p.lean.is_some()
            && let Some(k) = keep.as_deref_mut()
        {
            // Only what making the groups again needs: the exact oracle's null vectors go.
            let mut p = p;
            p.oracle = Oracle::Undecided;
            *k = Some(p);
        }
        if r.cut || stopped {
            break;
        }
    }
    Ok(r)
}

/// What one expansion placed part by part ([`ExpansionParts::place`]).
struct ByParts {
    isolated: u32,
    set_aside: u32,
    f: i64,
    drivable: usize,
    /// `None`: no count-valid placement; else the expansion's one count-valid placement,
    /// with its analysis when it is determined.
    placement: Option<Option<Placement>>,
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
struct ExpansionParts {
    index: HashMap<Vec<u32>, usize>,
    results: Vec<PartResult>,
}

impl ExpansionParts {
    /// Whether the expansions of `m` may be placed part by part under `rules`: random
    /// geometry (or none), and no kept input on a multiple joint (a minimum over all its
    /// pairs, which span the parts).
    fn applies(exps: &Expansions<'_>, rules: &Rules, opts: &TransformOptions) -> bool {
        opts.split
            && rules.random
            && !exps.multi.is_empty()
            && exps.multi.iter().all(|&j| rules.keep[j] == 0)
    }

    /// Place expansion `e` (number `x`) part by part; `None` when it is in one piece or a
    /// part has several placements or a note (then the whole expansion is placed).
    #[allow(clippy::too_many_arguments)]
    fn place(
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
        for (joints, bodies) in &sets {
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
}

/// The random realization a geometry source falls back to (the file's geometry is never
/// used where this is asked: the whole is analysed at a random realization).
fn random_source(g: crate::motion::GeometrySource) -> crate::motion::GeometrySource {
    use crate::motion::GeometrySource;
    match g {
        GeometrySource::Auto { seed } => GeometrySource::Random { seed },
        other => other,
    }
}

/// The placement of a whole from one placement per part, each in its part's own indices
/// (`sets[i]`: the part's joints and bodies in the whole's indices), as the analysis of the
/// whole gives it: inputs in the order of the whole's joints (`origin`: the original joint
/// of each joint of an expansion, then the pair), groups in canonical order (level, size,
/// smallest body), types in order of first appearance. A member with `rebuild[i]` was placed
/// on another part of the same structure: its inputs are named by `names` (joint `q`'s id and
/// bodies' label; the part's joints are binary). `None` if a member names a joint or body the part lacks (never
/// expected).
#[allow(clippy::too_many_arguments)]
fn join_parts(
    names: &dyn Fn(usize) -> Option<(String, String)>,
    origin: Option<&[usize]>,
    sets: &[(Vec<usize>, Vec<usize>)],
    members: &[&Placement],
    rebuild: &[bool],
    ids: &Arc<Vec<String>>,
    expansion: Option<String>,
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
    let mut types: Vec<TypeCount> = Vec::new();
    let mut kinds = Vec::with_capacity(groups.len());
    let mut in_lib = Vec::with_capacity(groups.len());
    for &(_, _, _, pi, gi) in &groups {
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
    let partition = if indexed {
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
    };
    Some(Placement {
        rank: None,
        family: None,
        scores: key?.scores(),
        inputs_at: inputs.iter().map(|i| i.0).collect(),
        inputs: inputs.into_iter().map(|i| i.3).collect(),
        expansion,
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

/// Enumerate, rank and group the determined placements (at most [`list_cap`] listed, the best
/// ones; the counts cover them all). [`ranked`] with every partition made.
pub fn transform(
    m: &Mechanism,
    opts: &TransformOptions,
    lib: &Library,
    progress: Option<ProgressFn<'_>>,
) -> Result<Transform, TransformError> {
    ranked(m, opts, lib, progress)?.into_transform()
}

/// The ranked result of [`ranked`]: [`Transform`] without the partitions the search's flow
/// gave, each made again when it is written (it serializes as [`Transform`] does, byte for
/// byte, streaming). A listed placement of a 10^6-body linkage held its partition (about
/// 10 MB with its bookkeeping), and each family a copy: 100 of them were over 1 GB of
/// `transform --limit 100`; held now is O(bodies) for the search's problem plus each
/// placement's inputs and scores.
#[derive(Debug)]
pub struct Ranked {
    /// Counts and notes.
    pub summary: Summary,
    /// The ranking criteria used.
    pub criteria: Vec<Criterion>,
    /// Rank of the file's own placement among the determined ones, if it is one of them.
    pub original_rank: Option<usize>,
    /// Every listed placement, best first; one whose groups came from the search's flow has
    /// an empty partition here ([`Ranked::partition`] makes it).
    pub placements: Vec<Placement>,
    /// Each family's members (ranks, best first), best family first (family `i + 1`).
    pub families: Vec<Vec<usize>>,
    /// The fingerprint of each placement's partition (a check on the ones made again).
    fingerprints: Vec<Fingerprint>,
    /// The search's problem, to make the partitions again.
    problem: Option<Problem>,
}

impl std::fmt::Debug for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Problem")
            .field("pairs", &self.a.len())
            .finish_non_exhaustive()
    }
}

/// Enumerate, rank and group the determined placements as [`transform`] does, holding each
/// listed placement's partition only where it cannot be made again ([`Ranked`]).
pub fn ranked(
    m: &Mechanism,
    opts: &TransformOptions,
    lib: &Library,
    progress: Option<ProgressFn<'_>>,
) -> Result<Ranked, TransformError> {
    let criteria = if opts.rank.is_empty() {
        Criterion::DEFAULT.to_vec()
    } else {
        opts.rank.clone()
    };
    let cap = list_cap(m, None);
    let order = |a: &(Placement, Fingerprint), b: &(Placement, Fingerprint)| {
        compare_scores(&a.0.scores, &b.0.scores, &criteria).then(a.0.seq.cmp(&b.0.seq))
    };
    let mut placements: Vec<(Placement, Fingerprint)> = Vec::new();
    let mut problem: Option<Problem> = None;
    let mut summary = enumerate_kept(
        m,
        opts,
        lib,
        progress,
        &mut |mut p| {
            let fp = p.partition.fingerprint();
            if p.lean.is_some() {
                p.partition = Partition(Repr::Text(Vec::new()));
            }
            // Bookkeeping only the joining of parts reads (a whole's placement is never a
            // part's): one record a group.
            p.groups_at = Vec::new();
            p.kinds = Vec::new();
            p.in_lib = Vec::new();
            placements.push((p, fp));
            // Keep the best `cap` only: memory stays bounded however many there are.
            if placements.len() >= 2 * cap {
                placements.sort_by(order);
                placements.truncate(cap);
            }
        },
        Some(&mut problem),
    )?;
    placements.sort_by(order);
    if placements.len() > cap {
        placements.truncate(cap);
    }
    if summary.listed != placements.len() {
        summary.notes.retain(|n| !n.contains("are listed"));
        summary.listed = placements.len();
        finish_listing_note(&mut summary);
    }
    let mut index: HashMap<Fingerprint, usize> = HashMap::new();
    let mut families: Vec<Vec<usize>> = Vec::new();
    for (i, (p, fp)) in placements.iter_mut().enumerate() {
        p.rank = Some(i + 1);
        let f = *index.entry(*fp).or_insert_with(|| {
            families.push(Vec::new());
            families.len()
        });
        families[f - 1].push(i + 1);
        p.family = Some(f);
    }
    let own = exps_default_inputs(m, opts.max_expansions);
    let original_rank = placements
        .iter()
        .find(|(p, _)| p.exp == 0 && p.inputs == own)
        .and_then(|(p, _)| p.rank);
    let (placements, fingerprints) = placements.into_iter().unzip();
    Ok(Ranked {
        summary,
        criteria,
        original_rank,
        placements,
        families,
        fingerprints,
        problem,
    })
}

impl Ranked {
    /// The partition of the placement at index `i` (rank `i + 1`): held, or made again from
    /// its inputs and the search's problem (checked against the fingerprint taken when it
    /// was first made).
    pub fn partition(&self, i: usize) -> Result<std::borrow::Cow<'_, Partition>, TransformError> {
        use std::borrow::Cow;
        let failed = TransformError::Regenerate { rank: i + 1 };
        let p = self.placements.get(i).ok_or(failed.clone())?;
        let Some(w) = &p.lean else {
            return Ok(Cow::Borrowed(&p.partition));
        };
        let made = self.problem.as_ref().and_then(|pr| {
            let l = pr.lean.as_ref()?;
            let flow = pr.flow_of(w)?;
            Some(Partition::indexed(
                &l.ids,
                l.raw(&flow)
                    .into_iter()
                    .map(|(_, g)| g.into_iter().map(|x| x as u32).collect()),
            ))
        });
        match made {
            Some(part) if Some(&part.fingerprint()) == self.fingerprints.get(i) => {
                Ok(Cow::Owned(part))
            }
            _ => Err(failed),
        }
    }

    /// The placement at index `i` with its partition, as [`Transform`] lists it.
    fn full(&self, i: usize) -> Result<std::borrow::Cow<'_, Placement>, TransformError> {
        use std::borrow::Cow;
        let failed = TransformError::Regenerate { rank: i + 1 };
        let p = self.placements.get(i).ok_or(failed)?;
        Ok(match self.partition(i)? {
            Cow::Borrowed(_) => Cow::Borrowed(p),
            Cow::Owned(part) => {
                let mut q = p.clone();
                q.partition = part;
                q.lean = None;
                Cow::Owned(q)
            }
        })
    }

    /// Every partition made: the [`Transform`].
    pub fn into_transform(self) -> Result<Transform, TransformError> {
        let mut placements = Vec::with_capacity(self.placements.len());
        for i in 0..self.placements.len() {
            placements.push(self.full(i)?.into_owned());
        }
        let mut families = Vec::with_capacity(self.families.len());
        for (f, members) in self.families.iter().enumerate() {
            let best = members.first().and_then(|&r| placements.get(r - 1));
            let Some(best) = best else {
                return Err(TransformError::Regenerate { rank: 0 });
            };
            families.push(Family {
                id: f + 1,
                partition: best.partition.clone(),
                placements: members.clone(),
            });
        }
        Ok(Transform {
            summary: self.summary,
            criteria: self.criteria,
            original_rank: self.original_rank,
            placements,
            families,
        })
    }
}

impl Serialize for Ranked {
    /// As [`Transform`] serializes, each partition made when it is written.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::{Error, SerializeSeq, SerializeStruct};
        struct Placements<'a>(&'a Ranked);
        impl Serialize for Placements<'_> {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                let mut seq = s.serialize_seq(Some(self.0.placements.len()))?;
                for i in 0..self.0.placements.len() {
                    let p = self.0.full(i).map_err(S::Error::custom)?;
                    seq.serialize_element(&*p)?;
                }
                seq.end()
            }
        }
        /// A family as [`Family`] serializes.
        #[derive(Serialize)]
        struct FamilyRef<'a> {
            id: usize,
            partition: &'a Partition,
            placements: &'a [usize],
        }
        struct Families<'a>(&'a Ranked);
        impl Serialize for Families<'_> {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                let r = self.0;
                let mut seq = s.serialize_seq(Some(r.families.len()))?;
                for (f, members) in r.families.iter().enumerate() {
                    let best = members.first().map_or(0, |&r| r - 1);
                    let part = r.partition(best).map_err(S::Error::custom)?;
                    seq.serialize_element(&FamilyRef {
                        id: f + 1,
                        partition: &part,
                        placements: members,
                    })?;
                }
                seq.end()
            }
        }
        let mut st = s.serialize_struct("Transform", 5)?;
        st.serialize_field("summary", &self.summary)?;
        st.serialize_field("criteria", &self.criteria)?;
        st.serialize_field("original_rank", &self.original_rank)?;
        st.serialize_field("placements", &Placements(self))?;
        st.serialize_field("families", &Families(self))?;
        st.end()
    }
}

fn finish_listing_note(s: &mut Summary) {
    if (s.listed as u128) < s.determined {
        s.notes.push(format!(
            "{} determined placements: the best {} are listed",
            count_words(s.determined),
            s.listed
        ));
    }
}

// ---------------------------------------------------------------------------------------------
// Independent parts

/// The independent parts of `m`, as index sets: each part is the frame with one connected
/// component of the other bodies (joined by joints that do not pass through the frame) and
/// the joints touching it, in order of their first joint; a mechanism in one piece gives none.
/// Every joint belongs to exactly one part: the frame's equations only ever fix the frame, so
/// the constraint Jacobian (frame fixed) is block diagonal over the parts, and so are the
/// matching, the groups and the rank check. Each part's joints (ascending) and bodies
/// (ascending, the frame included); [`part_mechanism`] builds one part's mechanism.
fn part_sets(m: &Mechanism) -> Vec<(Vec<usize>, Vec<usize>)> {
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
    let mut parent: Vec<usize> = (0..nb).collect();
    fn root(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
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

/// The mechanism of one part of `m` (its `joints` and sorted `bodies`, the frame among them).
/// `local` is a table of every body of `m`, all `usize::MAX`, used and cleared here (one
/// table for every part: a table per part was quadratic, 10^5 parts of a 10^5-body star
/// cleared 80 GB).
fn part_mechanism(
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
fn part_key<'a>(
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
fn combine_parts(
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
    let mut memo: Vec<PartKeys> = Vec::new();
    let mut index: HashMap<Vec<u32>, usize> = HashMap::new();
    // The entry of `memo` of each part.
    let mut per: Vec<usize> = Vec::with_capacity(sets.len());
    let (mut count_valid, mut determined) = (1u128, 1u128);
    summary.expansions = 1;
    summary.expansions_total = 1;
    let mut examined = 0usize;
    let whole_ids: Arc<Vec<String>> = Arc::new(m.bodies.iter().map(|b| b.id.to_string()).collect());
    let mut local = vec![usize::MAX; m.bodies.len()];
    let mut key: Vec<u32> = Vec::new();
    for (pi, (joints, bodies)) in sets.iter().enumerate() {
        // A part alone takes the file's geometry (when the whole lacks some) if all its
        // joints have theirs: placed alone then, as before.
        let shared = rules.random
            && joints.iter().all(|&j| m.joints[j].bodies.len() == 2)
            && (opts.analysis.count_only
                || matches!(
                    opts.analysis.geometry,
                    crate::motion::GeometrySource::Random { .. }
                )
                || joints.iter().all(|&j| m.joints[j].geometry.is_empty()));
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
                let mut by: BTreeMap<Key, (u128, Vec<Placement>)> = BTreeMap::new();
                let placed = place(
                    &mech,
                    &prules,
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
                memo.push(PartKeys {
                    placed,
                    keys: by.into_iter().map(|(k, (n, v))| (k, n, v)).collect(),
                    shared,
                });
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
    if determined == 0 {
        return Ok(());
    }
    // The keys of the whole, part by part: layer i holds the keys of parts 0..=i combined.
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
    let n = per.len();
    let rebuild: Vec<bool> = per.iter().map(|&at| memo[at].shared).collect();
    let mut listed = 0usize;
    'keys: for target in whole {
        // Every choice of one key per part that joins to `target`, the last part first.
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
                    break;
                }
                i += 1;
                continue;
            }
            if i > 0 {
                i -= 1;
                cursor[i] = 0;
                continue;
            }
            // A full choice: the product of the parts' listed placements, the last part
            // varying fastest.
            let lists: Vec<&Vec<Placement>> =
                (0..n).map(|p| &memo[per[p]].keys[chosen[p]].2).collect();
            let mut digit = vec![0usize; n];
            'prod: loop {
                meter.charge(n as u64)?;
                let members: Vec<&Placement> = (0..n).map(|p| &lists[p][digit[p]]).collect();
                let labels: Vec<String> =
                    members.iter().filter_map(|p| p.expansion.clone()).collect();
                let names = |q: usize| {
                    let j = m.joints.get(q)?;
                    Some((j.id.clone(), m.joint_bodies_label(j)))
                };
                let Some(mut p) = join_parts(
                    &names,
                    None,
                    sets,
                    &members,
                    &rebuild,
                    &whole_ids,
                    (!labels.is_empty()).then(|| labels.join("; ")),
                    members.iter().map(|p| p.exp).max().unwrap_or(0),
                ) else {
                    break 'keys;
                };
                p.seq = listed;
                sink(p);
                listed += 1;
                if listed >= cap {
                    break 'keys;
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
        }
    }
    summary.listed = listed;
    Ok(())
}

/// `bodies 2-5` style label of a part (its `bodies`) for notes: its movable bodies' ids,
/// shortened.
fn part_label(m: &Mechanism, bodies: &[usize]) -> String {
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
    /// Whether the analyses use no geometry or a random realization (drawn joint by joint):
    /// then the independent parts of an expansion may be analysed apart ([`ExpansionParts`]).
    /// The file's geometry is made dimensionless by the whole mechanism's scale, so a part
    /// alone would not be analysed at the same configuration.
    random: bool,
}

impl Rules {
    /// The rules of one part, whose joints are `joints` of the whole.
    fn restrict(&self, joints: &[usize]) -> Rules {
        Rules {
            allowed: joints.iter().map(|&j| self.allowed[j]).collect(),
            grounded: self.grounded,
            keep: joints.iter().map(|&j| self.keep[j]).collect(),
            notes: Vec::new(),
            random: self.random,
        }
    }

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
            random: false,
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Binary expansions of multiple joints

/// The mechanism with every joint binary: a multiple joint of n bodies becomes the n − 1 pairs
/// of one spanning tree of its bodies. The first pair takes the joint's place (so the other
/// joints keep their index, and their random geometry in the rank check); the rest are
/// appended after the last joint.
struct Expansion<'a> {
    label: Option<String>,
    /// The file's mechanism itself when it has no multiple joint and no driven joint: a
    /// 10^6-body mechanism was held three times (the file's, a copy without inputs, and the
    /// expansion's copy of that).
    mech: std::borrow::Cow<'a, Mechanism>,
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
    // The smallest leaf at each step, in linear time: `ptr` only moves up; a vertex below it
    // that becomes a leaf is taken at once (it is then the smallest). Was a scan from 0 at
    // each step, quadratic: 40 % of `transform` on a 10^4-body shared joint.
    let mut ptr = (0..n).find(|&v| degree[v] == 1).unwrap_or(0);
    let mut leaf = ptr;
    for &s in &seq {
        edges.push((leaf.min(s), leaf.max(s)));
        degree[leaf] = 0;
        degree[s] -= 1;
        if degree[s] == 1 && s < ptr {
            leaf = s;
        } else {
            ptr += 1;
            while ptr < n && degree[ptr] != 1 {
                ptr += 1;
            }
            leaf = ptr.min(n - 1);
        }
    }
    let last: Vec<usize> = (0..n).filter(|&v| degree[v] == 1).collect();
    if let [a, b] = last[..] {
        edges.push((a, b));
    }
    edges.sort_unstable();
    edges
}

/// The binary expansions of `m`'s multiple joints, built one at a time ([`Expansions::get`]):
/// only one expansion's mechanism is held at once.
struct Expansions<'a> {
    m: &'a Mechanism,
    /// Multiple joints, and their spanning trees.
    multi: Vec<usize>,
    counts: Vec<u64>,
    /// Expansions to explore (at least one).
    len: usize,
    /// Expansions there are (saturating).
    total: u64,
}

impl<'a> Expansions<'a> {
    /// Up to `max` expansions (at least one) and how many there are.
    fn of(m: &'a Mechanism, max: usize) -> Expansions<'a> {
        let multi: Vec<usize> = (0..m.joints.len())
            .filter(|&j| m.joints[j].bodies.len() > 2)
            .collect();
        let counts: Vec<u64> = multi
            .iter()
            .map(|&j| trees(m.joints[j].bodies.len()))
            .collect();
        let total = counts.iter().fold(1u64, |t, &c| t.saturating_mul(c));
        let len = (max.max(1) as u64).min(total) as usize;
        Expansions {
            m,
            multi,
            counts,
            len,
            total,
        }
    }

    /// The pairs of expansion `k` ([`Skeleton`]): [`Expansions::get`] without the mechanism.
    fn skeleton(&self, k: usize) -> Skeleton<'a> {
        let m = self.m;
        let nj = m.joints.len();
        let mut ends: Vec<[usize; 2]> = m
            .joints
            .iter()
            .map(|j| [j.bodies[0], j.bodies[j.bodies.len() - 1]])
            .collect();
        let mut origin: Vec<usize> = (0..nj).collect();
        let mut multi = Vec::with_capacity(self.multi.len());
        for (&j, &d) in self.multi.iter().zip(&self.digits(k)) {
            let joint = &m.joints[j];
            let edges = prufer_tree(joint.bodies.len(), d);
            let mut pairs = Vec::with_capacity(edges.len());
            for (i, &(a, b)) in edges.iter().enumerate() {
                let e = [joint.bodies[a], joint.bodies[b]];
                if i == 0 {
                    ends[j] = e;
                    pairs.push(j);
                } else {
                    pairs.push(ends.len());
                    ends.push(e);
                    origin.push(j);
                }
            }
            multi.push((j, pairs));
        }
        Skeleton {
            m,
            ends,
            origin,
            multi,
        }
    }

    /// The tree of each multiple joint in expansion `k` (mixed radix, the last varying
    /// fastest).
    fn digits(&self, k: usize) -> Vec<u64> {
        let mut rest = k as u64;
        let mut digits = vec![0u64; self.multi.len()];
        for (d, &c) in digits.iter_mut().zip(&self.counts).rev() {
            *d = rest % c.max(1);
            rest /= c.max(1);
        }
        digits
    }

    /// Expansion `k` (mixed radix over the multiple joints' trees, the last varying fastest).
    fn get(&self, k: usize) -> Expansion<'a> {
        let m = self.m;
        if self.multi.is_empty() && m.joints.iter().all(|j| j.driven == 0) {
            return Expansion {
                label: None,
                mech: std::borrow::Cow::Borrowed(m),
                origin: (0..m.joints.len()).collect(),
            };
        }
        // `m` with no joint driven.
        let mut mech = m.clone();
        for j in &mut mech.joints {
            j.driven = 0;
        }
        if self.multi.is_empty() {
            return Expansion {
                label: None,
                mech: std::borrow::Cow::Owned(mech),
                origin: (0..m.joints.len()).collect(),
            };
        }
        let digits = self.digits(k);
        let mut origin: Vec<usize> = (0..m.joints.len()).collect();
        let mut labels = Vec::new();
        let mut appended: Vec<Joint> = Vec::new();
        for (&j, &d) in self.multi.iter().zip(&digits) {
            let joint = &m.joints[j];
            let edges = prufer_tree(joint.bodies.len(), d);
            let mut pairs = Vec::new();
            for (i, &(a, b)) in edges.iter().enumerate() {
                let (ba, bb) = (joint.bodies[a], joint.bodies[b]);
                let label = format!("{}-{}", m.body_id(ba), m.body_id(bb));
                let pj = Joint {
                    id: format!("{}[{label}]", joint.id),
                    kind: joint.kind,
                    bodies: [ba, bb].into(),
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
        Expansion {
            label: Some(labels.join("; ")),
            mech: std::borrow::Cow::Owned(mech),
            origin,
        }
    }
}

/// The pairs of one expansion without its mechanism ([`Expansions::skeleton`]): each pair's
/// two bodies and original joint, numbered as [`Expansions::get`] numbers them; ids, labels
/// and joints are made only for what is asked (building every expansion's mechanism, two
/// strings a pair, was 60 % of placing a 10^5-body shared joint part by part).
struct Skeleton<'a> {
    m: &'a Mechanism,
    ends: Vec<[usize; 2]>,
    origin: Vec<usize>,
    /// Each multiple joint and its pairs in the order of its tree's edges.
    multi: Vec<(usize, Vec<usize>)>,
}

impl Skeleton<'_> {
    fn is_pair(&self, q: usize) -> bool {
        self.m.joints[self.origin[q]].bodies.len() > 2
    }

    /// Pair `q`'s bodies as a label, `a-b`.
    fn label(&self, q: usize) -> String {
        let [a, b] = self.ends[q];
        format!("{}-{}", self.m.body_id(a), self.m.body_id(b))
    }

    /// Joint `q` of the expansion, as [`Expansions::get`] builds it.
    fn joint(&self, q: usize) -> Joint {
        let o = &self.m.joints[self.origin[q]];
        if !self.is_pair(q) {
            let mut j = o.clone();
            j.driven = 0;
            return j;
        }
        Joint {
            id: format!("{}[{}]", o.id, self.label(q)),
            kind: o.kind,
            bodies: self.ends[q].into(),
            driven: 0,
            geometry: o.geometry.clone(),
        }
    }

    /// Joint `q`'s id and its bodies' label.
    fn names(&self, q: usize) -> (String, String) {
        let o = &self.m.joints[self.origin[q]];
        if self.is_pair(q) {
            let label = self.label(q);
            (format!("{}[{label}]", o.id), label)
        } else {
            (o.id.clone(), self.m.joint_bodies_label(o))
        }
    }

    /// The expansion's label, as [`Expansions::get`] writes it.
    fn expansion_label(&self) -> Option<String> {
        if self.multi.is_empty() {
            return None;
        }
        let labels: Vec<String> = self
            .multi
            .iter()
            .map(|(j, pairs)| {
                let pairs: Vec<String> = pairs.iter().map(|&q| self.label(q)).collect();
                format!("{}: {}", self.m.joints[*j].id, pairs.join(", "))
            })
            .collect();
        Some(labels.join("; "))
    }
}

/// The file's own placement on the default expansion, as the analysis distributes a multiple
/// joint's driven DOF: its pairs in order, at most k each, the last taking the rest.
fn exps_default_inputs(m: &Mechanism, max: usize) -> Vec<Input> {
    let e = &Expansions::of(m, max.min(1)).get(0);
    let mut w: Vec<(usize, u32)> = Vec::new();
    // The pairs of each joint, in pair order (one pass: was a scan of every pair per joint,
    // quadratic: 88 % of `transform --limit 3` on a 10^5-body linkage).
    let mut pairs_of: Vec<Vec<usize>> = vec![Vec::new(); m.joints.len()];
    for (q, &o) in e.origin.iter().enumerate() {
        if let Some(v) = pairs_of.get_mut(o) {
            v.push(q);
        }
    }
    for (j, joint) in m.joints.iter().enumerate() {
        let pairs = &pairs_of[j];
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
    /// The exact decision of each placement, where one is made before its analysis.
    oracle: Oracle,
    /// A placement the oracle certifies is analysed from the search's own flow
    /// ([`Lean`]): random geometry, binary joints, the flow method, and an input-free
    /// analysis with no isolated freedom, no redundancy and nothing set aside.
    lean: Option<Lean>,
}

impl Problem {
    fn of(
        e: &Expansion,
        orig: &Mechanism,
        rules: &Rules,
        opts: &TransformOptions,
        cache: &structure::AnalysisCache,
        ids: &Arc<Vec<String>>,
        meter: &mut Meter,
    ) -> Result<Problem, BudgetExceeded> {
        let m = &e.mech;
        let nb = m.bodies.len();
        let b = m.b();
        let mut u = vec![b; nb];
        u[m.frame] = 0;
        let mut isolated = 0u32;
        let mut oracle = Oracle::Undecided;
        let mut lean = None;
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
            // The geometry was checked before the enumeration: this analysis cannot fail. It
            // is charged like the analysis of one placement.
            meter.charge(analysis_work(m))?;
            let a =
                structure::analyze_cached(m, &opts.analysis, &Library::empty(), Some(cache), None)
                    .ok();
            let a = a.as_ref();
            if let Some(a) = a {
                for (q, &n) in a.set_aside.iter().enumerate() {
                    set_aside[q] = n;
                }
                oracle = Oracle::of(m, a, opts.full_analyses, meter)?;
                if matches!(oracle, Oracle::Motions { .. })
                    && !opts.full_analyses
                    && opts.analysis.method == structure::Method::Flow
                    && a.isolated.is_empty()
                    && a.redundant.is_empty()
                    && a.set_aside.iter().all(|&n| n == 0)
                {
                    lean = Some(Lean::of(m, ids));
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
            oracle,
            lean,
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
            return Ok(p);
        }
        if kept > p.f {
            p.note = Some(format!(
                "the kept inputs ({kept}) are more than the {} the mechanism takes",
                p.f
            ));
            return Ok(p);
        }
        p.need = (p.f - kept) as usize;
        // Without this the search finds nothing and the user reads "0 placements" with no
        // reason (a Stewart platform with --on P: 6 pistons for 11 inputs).
        let capacity: i64 =
            p.hi.iter()
                .zip(&p.lo)
                .map(|(&h, &l)| i64::from(h.saturating_sub(l)))
                .sum();
        if capacity < p.need as i64 {
            p.note = Some(format!(
                "the joints that may be driven carry {capacity} DOF in all, fewer than the {} \
                 input(s) to place: no placement exists",
                p.need
            ));
            return Ok(p);
        }
        let mut s = State {
            flow: vec![[0; 2]; nq],
            used: vec![0; nb],
        };
        let mut scratch = p.scratch();
        for (q, &n) in cons.iter().enumerate() {
            for _ in 0..n {
                let r = p.augment(&mut s, &[q], &mut scratch);
                meter.charge(scratch.queue.len() as u64 + 1)?;
                if r.is_none() {
                    p.note = Some(format!(
                        "the joints' own equations over-determine the bodies near joint {} (by \
                         count): no placement of inputs can determine the mechanism",
                        m.joints[q].id
                    ));
                    return Ok(p);
                }
            }
        }
        for q in 0..nq {
            for _ in 0..p.lo[q] {
                let r = p.augment(&mut s, &[q], &mut scratch);
                meter.charge(scratch.queue.len() as u64 + 1)?;
                if r.is_none() {
                    p.note = Some(format!(
                        "the kept input on joint {} over-determines the bodies it joins: no \
                         placement keeping it is determined",
                        m.joints[q].id
                    ));
                    return Ok(p);
                }
            }
        }
        p.root = Some(s);
        Ok(p)
    }

    /// A flow routing the equations and the inputs of placement `w` (units per pair, sparse,
    /// kept units included), clipped to a byte as the search's flows are: the root's, then
    /// each input unit beyond the kept ones augmented. Any such flow gives the same groups
    /// ([`Lean`]). `None` if a unit does not fit (never expected: `w` is a count-valid
    /// placement of this problem, so a flow with all its units exists and every partial one
    /// has an augmenting path from the pair of a missing unit).
    fn flow_of(&self, w: &[(usize, u32)]) -> Option<Vec<[u8; 2]>> {
        let mut s = self.root.clone()?;
        let mut sc = self.scratch();
        for &(q, n) in w {
            for _ in *self.lo.get(q)?..n {
                self.augment(&mut s, &[q], &mut sc)?;
            }
        }
        Some(
            s.flow
                .iter()
                .map(|f| [f[0].min(255) as u8, f[1].min(255) as u8])
                .collect(),
        )
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
        self.augment_marked(s, sources, sc, None)
    }

    /// [`Problem::augment`]; with `dead`, bodies from which an earlier call found no spare
    /// unknown are skipped, and a failed call marks every body it reached. Sound while only
    /// augmentations happen in between: an augmenting path changes flows between bodies that
    /// all reach a spare unknown, so a body that reached none still reaches none (and spare
    /// unknowns only get used up). A run of failures then costs one pass, not one each.
    fn augment_marked(
        &self,
        s: &mut State,
        sources: &[usize],
        sc: &mut Scratch,
        dead: Option<&mut [bool]>,
    ) -> Option<usize> {
        let alive = |dead: &Option<&mut [bool]>, x: usize| dead.as_ref().is_none_or(|d| !d[x]);
        sc.stamp = sc.stamp.wrapping_add(1);
        if sc.stamp == 0 {
            sc.seen.iter_mut().for_each(|v| *v = 0);
            sc.stamp = 1;
        }
        sc.queue.clear();
        for &q in sources {
            for x in [self.a[q], self.c[q]] {
                if x != self.frame && sc.seen[x] != sc.stamp && alive(&dead, x) {
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
                if y != self.frame && y != x && sc.seen[y] != sc.stamp && alive(&dead, y) {
                    sc.seen[y] = sc.stamp;
                    sc.prev[y] = (q as u32, x as u32);
                    sc.queue.push(y);
                }
            }
        }
        if let Some(d) = dead {
            for &x in &sc.queue {
                d[x] = true;
            }
        }
        None
    }

    /// Visit every count-valid placement (sparse `(pair, driven)`, pair order) in
    /// lexicographic order of its units' candidate positions (the most units on the earliest
    /// candidate first), calling `leaf` on each; `leaf` returns `false` to stop. Charges
    /// `meter` one unit per search step and per body an exchange visits.
    ///
    /// The search is a binary partition of the bases of the placement matroid: a node holds
    /// one complete placement (a perfect matching of equations and inputs to unknowns) and
    /// bounds `lo ≤ w ≤ hi` per pair; it decides the first candidate still open, first "one
    /// more unit here" (same placement, or one exchange), then "no more units here" (each
    /// unit removed is refilled by an augmenting path). A branch whose bounds admit no
    /// placement is cut at once by a failed exchange, so there are no dead ends: the first
    /// placement comes after one greedy pass, and each further one after at most one
    /// exchange per candidate. Changes are undone from a trail, so memory stays linear. A
    /// failed exchange marks the bodies it reached (no free unit from there) until units move
    /// back, so a run of candidates that take no unit costs one pass over the bodies, not one
    /// each (with `--limit`, the work grows with the placements found, not with candidates ×
    /// bodies).
    fn search(&self, meter: &mut Meter, leaf: LeafFn<'_>) -> Result<(), BudgetExceeded> {
        let Some(root) = &self.root else {
            return Ok(());
        };
        let mut t = Search {
            s: root.clone(),
            w: self.lo.clone(),
            lo: self.lo.clone(),
            hi: self.hi.clone(),
            trail: Vec::new(),
            sc: self.scratch(),
            dead: vec![0; self.u.len()],
            version: 1,
            free: 0,
        };
        // The greedy first placement: as many units as fit on each candidate in order.
        let mut placed = 0usize;
        let mut full = vec![false; self.u.len()];
        for &q in &self.cand {
            while placed < self.need && t.w[q] < t.hi[q] {
                // Bodies whose spare unknowns no unit reaches are marked `full` once, so a
                // run of candidates that take no unit costs one pass (charged: bodies seen).
                let r = self.augment_marked(&mut t.s, &[q], &mut t.sc, Some(&mut full));
                meter.charge(t.sc.queue.len() as u64 + 1)?;
                if r.is_none() {
                    break;
                }
                t.w[q] += 1;
                placed += 1;
            }
        }
        if placed < self.need {
            return Ok(());
        }
        // Units every placement needs (matroid coloops) are fixed at once: a unit is needed
        // unless some slot outside the placement reaches it by an alternating path (one BFS
        // from all such slots). A tree (star, serial chain) is then decided in linear time.
        {
            let Search { s, w, hi, sc, .. } = &mut t;
            sc.next_stamp();
            for &q in &self.cand {
                if w[q] < hi[q] {
                    for x in [self.a[q], self.c[q]] {
                        if x != self.frame && sc.seen[x] != sc.stamp {
                            sc.seen[x] = sc.stamp;
                            sc.queue.push(x);
                        }
                    }
                }
            }
            let mut reached = vec![false; self.a.len()];
            let mut qi = 0;
            while qi < sc.queue.len() {
                let x = sc.queue[qi];
                qi += 1;
                meter.charge(1 + self.touching[x].len() as u64)?;
                for &r in &self.touching[x] {
                    if s.flow[r][self.side(r, x)] == 0 {
                        continue;
                    }
                    reached[r] = true;
                    let y = self.other(r, x);
                    if y != self.frame && y != x && sc.seen[y] != sc.stamp {
                        sc.seen[y] = sc.stamp;
                        sc.queue.push(y);
                    }
                }
            }
            for &q in &self.cand {
                if !reached[q] {
                    t.lo[q] = t.lo[q].max(t.w[q]);
                }
            }
        }
        t.trail.clear();
        t.free = (0..t.w.len()).map(|q| t.free_of(q)).sum();
        // Choice points: (trail mark, candidate position) whose "no more units" branch is
        // still to be explored.
        let mut choices: Vec<(usize, usize)> = Vec::new();
        let mut cur = 0usize;
        loop {
            meter.charge(1)?;
            while cur < self.cand.len() && t.lo[self.cand[cur]] >= t.hi[self.cand[cur]] {
                cur += 1;
            }
            let mut go_back = false;
            if cur == self.cand.len() {
                let ok = self
                    .kept_groups
                    .iter()
                    .all(|(qs, min)| qs.iter().map(|&q| t.w[q]).sum::<u32>() >= *min);
                if ok && !leaf(&t.w, &t.s.flow) {
                    return Ok(());
                }
                go_back = true;
            } else {
                let q = self.cand[cur];
                let mark = t.trail.len();
                if t.w[q] > t.lo[q] || self.exchange_in(&mut t, q, meter)? {
                    choices.push((mark, cur));
                    t.set_lo(q, t.lo[q] + 1);
                } else if !self.cap(&mut t, q, meter)? {
                    go_back = true;
                }
            }
            if go_back {
                // The "no more units" branch of the latest choice point that admits one.
                loop {
                    let Some((mark, c)) = choices.pop() else {
                        return Ok(());
                    };
                    t.undo(mark);
                    cur = c;
                    if self.cap(&mut t, self.cand[c], meter)? {
                        break;
                    }
                }
            }
        }
    }

    /// "One more unit on `q`" when the placement has none spare there: add a unit of `q` and
    /// drop a free unit (above its lower bound) of another pair, along an alternating path.
    fn exchange_in(
        &self,
        t: &mut Search,
        q: usize,
        meter: &mut Meter,
    ) -> Result<bool, BudgetExceeded> {
        // No unit above its lower bound on another pair: nothing to drop (the search below
        // would visit every body it reaches to find none, once a placement: the place of the
        // only input of an Assur linkage is then fixed).
        if t.free == t.free_of(q) {
            return Ok(false);
        }
        let found = {
            let Search {
                s,
                w,
                lo,
                sc,
                dead,
                version,
                ..
            } = &mut *t;
            sc.next_stamp();
            for x in [self.a[q], self.c[q]] {
                if x != self.frame && sc.seen[x] != sc.stamp && dead[x] != *version {
                    sc.seen[x] = sc.stamp;
                    sc.prev[x] = (q as u32, NONE);
                    sc.queue.push(x);
                }
            }
            let mut found = None;
            let mut qi = 0;
            'bfs: while qi < sc.queue.len() {
                let x = sc.queue[qi];
                qi += 1;
                meter.charge(1 + self.touching[x].len() as u64)?;
                for &r in &self.touching[x] {
                    if s.flow[r][self.side(r, x)] == 0 {
                        continue;
                    }
                    if r != q && w[r] > lo[r] {
                        found = Some((x, r));
                        break 'bfs;
                    }
                    let y = self.other(r, x);
                    if y != self.frame && y != x && sc.seen[y] != sc.stamp && dead[y] != *version {
                        sc.seen[y] = sc.stamp;
                        sc.prev[y] = (r as u32, x as u32);
                        sc.queue.push(y);
                    }
                }
            }
            if found.is_none() {
                // No free unit is reachable from any body this search reached: while the
                // placement (flows, units, lower bounds) stays as it is, later exchanges skip
                // them (a run of failed exchanges costs one pass over the bodies, not one each).
                for &x in &sc.queue {
                    dead[x] = *version;
                }
            }
            found
        };
        let Some((x, r)) = found else {
            return Ok(false);
        };
        // Drop a unit of r at x, then push the new unit of q along the path into x.
        t.flow_add(r, self.side(r, x), -1);
        t.w_add(r, -1);
        let mut y = x;
        loop {
            let (pq, from) = t.sc.prev[y];
            let pq = pq as usize;
            t.flow_add(pq, self.side(pq, y), 1);
            if from == NONE {
                t.w_add(pq, 1);
                return Ok(true);
            }
            let from = from as usize;
            t.flow_add(pq, self.side(pq, from), -1);
            y = from;
        }
    }

    /// "No more units on `q`": its upper bound drops to its lower one; each unit above is
    /// removed and the body it held refilled from a pair with spare capacity, along an
    /// alternating path. `false` when some unit cannot be refilled (the branch is empty).
    fn cap(&self, t: &mut Search, q: usize, meter: &mut Meter) -> Result<bool, BudgetExceeded> {
        t.set_hi(q, t.lo[q]);
        while t.w[q] > t.hi[q] {
            // Units move back to pairs below their upper bound: free units may appear.
            t.version += 1;
            let side = usize::from(t.s.flow[q][0] == 0);
            let x = if side == 0 { self.a[q] } else { self.c[q] };
            t.flow_add(q, side, -1);
            t.w_add(q, -1);
            if !self.refill(t, x, meter)? {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Give body `x`, one unit short, a unit from a pair below its upper bound, moving units
    /// between the two bodies of pairs along the way.
    fn refill(&self, t: &mut Search, x: usize, meter: &mut Meter) -> Result<bool, BudgetExceeded> {
        let found = {
            let Search { s, w, hi, sc, .. } = &mut *t;
            sc.next_stamp();
            sc.seen[x] = sc.stamp;
            sc.prev[x] = (NONE, NONE);
            sc.queue.push(x);
            let mut found = None;
            let mut qi = 0;
            'bfs: while qi < sc.queue.len() {
                let z = sc.queue[qi];
                qi += 1;
                meter.charge(1 + self.touching[z].len() as u64)?;
                for &r in &self.touching[z] {
                    if w[r] < hi[r] {
                        found = Some((z, r));
                        break 'bfs;
                    }
                    let y = self.other(r, z);
                    if y == self.frame || y == z || sc.seen[y] == sc.stamp {
                        continue;
                    }
                    if s.flow[r][self.side(r, y)] > 0 {
                        sc.seen[y] = sc.stamp;
                        sc.prev[y] = (r as u32, z as u32);
                        sc.queue.push(y);
                    }
                }
            }
            found
        };
        let Some((z, r)) = found else {
            return Ok(false);
        };
        t.flow_add(r, self.side(r, z), 1);
        t.w_add(r, 1);
        let mut y = z;
        while y != x {
            let (pq, to) = t.sc.prev[y];
            let (pq, to) = (pq as usize, to as usize);
            t.flow_add(pq, self.side(pq, y), -1);
            t.flow_add(pq, self.side(pq, to), 1);
            y = to;
        }
        Ok(true)
    }
}

impl Scratch {
    /// A fresh BFS: a new stamp (clearing on wrap-around) and an empty queue.
    fn next_stamp(&mut self) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.seen.iter_mut().for_each(|v| *v = 0);
            self.stamp = 1;
        }
        self.queue.clear();
    }
}

/// The mutable state of [`Problem::search`], with a trail of old values to undo.
struct Search {
    s: State,
    w: Vec<u32>,
    lo: Vec<u32>,
    hi: Vec<u32>,
    trail: Vec<(u8, u32, u32)>,
    sc: Scratch,
    /// Bodies from which [`Problem::exchange_in`] found no free unit, valid while `dead[x] ==
    /// version`. A successful exchange keeps them valid (it is an augmenting path towards a
    /// free unit: it changes flows only between bodies that all reach one, so a body that
    /// reached none still reaches none), and so does raising a lower bound (fewer free units);
    /// removing units ([`Problem::cap`]) and undoing bump `version`.
    dead: Vec<u64>,
    version: u64,
    /// Units above their lower bound, summed over the pairs (`Σ w − lo` where positive):
    /// with none but on the pair itself, an exchange has none to drop and fails at once.
    free: u64,
}

impl Search {
    /// Units of `q` above its lower bound.
    fn free_of(&self, q: usize) -> u64 {
        u64::from(self.w[q].saturating_sub(self.lo[q]))
    }
    fn flow_add(&mut self, q: usize, side: usize, d: i32) {
        let old = self.s.flow[q][side];
        self.trail.push((side as u8, q as u32, old));
        self.s.flow[q][side] = old.wrapping_add_signed(d);
    }
    fn w_add(&mut self, q: usize, d: i32) {
        let old = self.w[q];
        self.trail.push((2, q as u32, old));
        self.free -= self.free_of(q);
        self.w[q] = old.wrapping_add_signed(d);
        self.free += self.free_of(q);
    }
    fn set_lo(&mut self, q: usize, v: u32) {
        self.trail.push((3, q as u32, self.lo[q]));
        self.free -= self.free_of(q);
        self.lo[q] = v;
        self.free += self.free_of(q);
    }
    fn set_hi(&mut self, q: usize, v: u32) {
        self.trail.push((4, q as u32, self.hi[q]));
        self.hi[q] = v;
    }
    fn undo(&mut self, mark: usize) {
        while self.trail.len() > mark {
            let Some((k, q, old)) = self.trail.pop() else {
                break;
            };
            let q = q as usize;
            if k < 4 {
                self.version += 1;
            }
            match k {
                0 | 1 => self.s.flow[q][k as usize] = old,
                2 | 3 => {
                    self.free -= self.free_of(q);
                    if k == 2 {
                        self.w[q] = old;
                    } else {
                        self.lo[q] = old;
                    }
                    self.free += self.free_of(q);
                }
                _ => self.hi[q] = old,
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Full analysis of a placement

/// Analyse `mech` with the placement `w`; the analysis if it is determined, and the work
/// units of the rank decisions it made.
fn evaluate(
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

fn placement(
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
struct Groups {
    scores: Scores,
    types: Vec<TypeCount>,
    partition: Partition,
    groups_at: Vec<(usize, usize)>,
    kinds: Vec<u32>,
    in_lib: Vec<bool>,
}

fn placement_of(
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
struct Lean {
    /// Pairs touching each body (`touch[start[x]..start[x + 1]]`), a pair of a body with
    /// itself once, in pair order (as `structure::build` lists them).
    start: Vec<usize>,
    touch: Vec<u32>,
    /// Body ids as the analysis writes them (shared with the placements' partitions).
    ids: Arc<Vec<String>>,
    /// Each pair's two bodies and joint type (read from the joints, hundreds of bytes apart,
    /// each was a cache miss).
    ends: Vec<[u32; 2]>,
    kind: Vec<JointType>,
    /// The frame's index.
    frame: usize,
    /// Work units of one lean analysis: a few passes over the bodies and pairs.
    work: u64,
}

impl Lean {
    fn of(m: &Mechanism, ids: &Arc<Vec<String>>) -> Lean {
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
    fn raw(&self, flow: &[[u8; 2]]) -> Vec<(usize, Vec<usize>)> {
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
    fn groups(&self, m: &Mechanism, flow: &[[u8; 2]], lib: &Library) -> Groups {
        let nb = m.bodies.len();
        let ends = |q: usize| {
            let [a, c] = self.ends[q];
            (a as usize, c as usize)
        };
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
            kinds.clear();
            for &x in &grp.1 {
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
            for (k, n) in &kinds {
                let _ = std::fmt::Write::write_fmt(&mut kind, format_args!("{n}{}", k.code()));
            }
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

// ---------------------------------------------------------------------------------------------
// The exact rank of a placement's whole system

/// Null vectors of the constraint system an [`Oracle`] keeps at most (its per-placement test is
/// a dense rank of about `6 f` rows by this many columns).
const ORACLE_NULLITY: usize = 64;

/// What the exact rank at the analysis's random realization (over GF(p), as the rank check's
/// large blocks and the geometric rigidity use it) decides for every placement of one
/// expansion, before its analysis. A placement `P` is determined exactly when its square
/// system `M_P` (every pair's constraint rows and its inputs' rows, frame fixed) is
/// nonsingular on the reduced unknowns; that needs `M_P` of full row rank (reducing the
/// unknowns of a body by its isolated freedom keeps the rank). With `J` the constraint rows
/// alone: `rank M_P = rank J + rank` of the inputs' rows on the null space of `J`.
/// - `J` has dependent rows: no placement is determined (each `M_P` has them too).
/// - `J` has full row rank and a small null space (`mbsa` keeps `N ≤` [`ORACLE_NULLITY`]
///   random null vectors, which span it except with probability `N / p`): a placement is
///   rejected when its inputs' rows on those vectors have rank below `f`, and otherwise
///   certified: its analysis skips the rank check's factorizations
///   ([`structure::analyze_placement`]).
/// - Otherwise the analysis decides alone, as before.
///
/// Each decision is the generic rank (probability of error at most rows / p), which the
/// floating-point rank check also finds except on a block so badly conditioned that its
/// tolerance takes it for singular.
enum Oracle {
    Undecided,
    Reject,
    /// A large null space: undecided, until a placement is rejected; then the exact rank of
    /// `J` ([`Oracle::dependent`]) may reject every other one at once.
    Later {
        seed: u64,
    },
    Motions {
        seed: u64,
        /// Column of each body's first unknown (`usize::MAX`: the frame).
        col: Vec<usize>,
        /// Random null vectors of `J`.
        v: Vec<Vec<crate::exact::Fp>>,
    },
}

impl Oracle {
    /// The oracle of `m` (an expansion, binary joints, no inputs) given its first analysis `a`
    /// (no inputs either). `cols_minus_rows` is the count's nullity of `J`.
    fn of(
        m: &Mechanism,
        a: &Analysis,
        full_analyses: bool,
        meter: &mut Meter,
    ) -> Result<Oracle, BudgetExceeded> {
        use crate::exact::{Factor, models};
        let Some(seed) = a.geometry.as_ref().and_then(|g| g.seed) else {
            return Ok(Oracle::Undecided);
        };
        let b = m.b() as usize;
        let pair = |q: usize| match m.joints[q].bodies[..] {
            [x, y] => Some((x, y)),
            _ => None,
        };
        if m.joints.iter().any(|j| j.bodies.len() != 2) {
            return Ok(Oracle::Undecided);
        }
        // A dependency the analysis named among the constraint rows alone: the rows of the
        // named joints, exactly.
        for r in a.redundant.iter().filter(|r| !r.configuration) {
            let named: std::collections::HashSet<&str> =
                r.joints.iter().map(String::as_str).collect();
            let qs: Vec<usize> = (0..m.joints.len())
                .filter(|&q| named.contains(m.joints[q].id.as_str()))
                .collect();
            meter.charge(m.joints.len() as u64 / 8 + 1)?;
            let mut bodies: Vec<usize> = qs
                .iter()
                .filter_map(|&q| pair(q))
                .flat_map(|(x, y)| [x, y])
                .filter(|&x| x != m.frame)
                .collect();
            bodies.sort_unstable();
            bodies.dedup();
            let rows: Vec<_> = qs
                .iter()
                .map(|&q| models::joint_rows(m, q, seed, 0))
                .collect();
            let total: usize = rows.iter().map(|r| r.nrows()).sum();
            let rank = models::pairs_rank(
                b,
                bodies.len(),
                &rows,
                qs.iter().enumerate().filter_map(|(i, &q)| {
                    let (x, y) = pair(q)?;
                    Some((i, x, y))
                }),
                |x| bodies.binary_search(&x).ok(),
            );
            if rank < total {
                return Ok(Oracle::Reject);
            }
        }
        // The count's nullity of J: unknowns less constraint rows.
        let movable = m.bodies.len().saturating_sub(1);
        let cons: usize = m
            .joints
            .iter()
            .map(|j| b.saturating_sub(j.grade() as usize))
            .sum();
        let ncols = movable * b;
        if cons > ncols {
            return Ok(Oracle::Undecided);
        }
        // A large null space: no per-placement test, but dependent rows of `J` still reject
        // every placement; that is decided once a placement is rejected ([`Oracle::Later`],
        // [`Oracle::dependent`]), so a mechanism with one placement (a serial chain, each
        // expansion of a shared joint) never pays for it.
        if ncols - cons > ORACLE_NULLITY {
            return Ok(if full_analyses {
                Oracle::Undecided
            } else {
                Oracle::Later { seed }
            });
        }
        meter.charge(50 * (m.bodies.len() + m.joints.len()) as u64)?;
        // A basis of the null space by back-substitution along the routing's blocks, when
        // they are nonsingular (then `J` has full row rank); else the whole factorization.
        // Either basis gives the same decisions: [`Oracle::decide`] uses only the rank of
        // the inputs' rows on the vectors, the same for any basis of the null space.
        if let Some((col, v)) = block_null_vectors(m, seed) {
            return Ok(Oracle::Motions { seed, col, v });
        }
        let (j, col) = jacobian(m, seed);
        let nrows = j.nrows();
        let f = Factor::new(&j);
        if f.rank() < nrows {
            return Ok(Oracle::Reject);
        }
        let n = f.nullity();
        if n > ORACLE_NULLITY {
            return Ok(Oracle::Undecided);
        }
        let mut rng = crate::rng::SplitMix64::new(seed ^ 0x7A4E_5F0B_0C1E_0000);
        let v = f.random_null_vectors(n, &mut rng);
        Ok(Oracle::Motions { seed, col, v })
    }

    /// For [`Oracle::Later`], once a placement was rejected: [`Oracle::Reject`] when the
    /// constraint rows `J` of `m` are dependent (then no placement is determined: the
    /// random families, whose redundancy among the constraints the input-free analysis
    /// cannot see, its under-determined block being too large to check), else
    /// [`Oracle::Undecided`]. The exact rank runs within a work and memory cap of its own;
    /// past it the analyses decide, as before. Its work is charged to `meter`.
    fn dependent(&self, m: &Mechanism, budget: &Budget, meter: &mut Meter) -> Oracle {
        let Oracle::Later { seed } = self else {
            return Oracle::Undecided;
        };
        let b = m.b() as usize;
        let units = 50 * (m.bodies.len() + m.joints.len()) as u64;
        if meter.charge(units).is_err() {
            return Oracle::Undecided;
        }
        // The rows made one at a time as the factorization reads them (the same rows as
        // `jacobian`'s, so the same factorization), unless their indices outgrow `u32`.
        let rows = JacobianRows::of(m, *seed);
        let j = match rows {
            Some(_) => None,
            None => Some(jacobian(m, *seed).0),
        };
        let nrows = match (&rows, &j) {
            (Some(r), _) => crate::exact::sparse::Rows::nrows(r),
            (_, Some(j)) => j.nrows(),
            _ => 0,
        };
        let entries = (nrows * 2 * b + m.bodies.len() * b) as u64;
        let cap = Budget {
            max_work: budget.max_work.min(400 * entries + 1_000_000),
            max_memory_bytes: budget.max_memory_bytes.min(1 << 30),
            ..*budget
        };
        let mut own = cap.meter("the exact rank of the constraints");
        let what = || "the exact rank of the constraints".to_string();
        let mut limits = crate::exact::sparse::Limits {
            budget: &cap,
            meter: &mut own,
            what: &what,
        };
        // Only the rank is read: the factor's records (its null space) are not kept.
        let r = match (rows, j) {
            (Some(r), _) => crate::exact::Factor::rank_of_rows_within(r, &mut limits),
            (_, Some(j)) => crate::exact::Factor::rank_of_rows_within(j, &mut limits),
            _ => return Oracle::Undecided,
        };
        if meter.charge(own.used()).is_err() {
            return Oracle::Undecided;
        }
        match r {
            Ok(rank) if rank < nrows => Oracle::Reject,
            _ => Oracle::Undecided,
        }
    }

    /// Work units of [`Oracle::decide`] on placement `w`: its inputs' rows on the null
    /// vectors (`f × N` numbers and their rank).
    fn work(&self, w: &[(usize, u32)]) -> u64 {
        match self {
            Oracle::Motions { v, .. } => {
                let f: u64 = w.iter().map(|&(_, n)| u64::from(n)).sum();
                f.saturating_mul(v.len() as u64).saturating_mul(8) + 1
            }
            _ => 1,
        }
    }

    /// `Some(false)`: placement `w` (units per pair of `m`) is not determined; `Some(true)`:
    /// its whole system has full row rank; `None`: the analysis decides.
    fn decide(&self, m: &Mechanism, w: &[(usize, u32)]) -> Option<bool> {
        use crate::exact::{Fp, dense, models};
        match self {
            Oracle::Undecided | Oracle::Later { .. } => None,
            Oracle::Reject => Some(false),
            Oracle::Motions { seed, col, v } => {
                let b = m.b() as usize;
                let f: usize = w.iter().map(|&(_, n)| n as usize).sum();
                if f > v.len() {
                    return Some(false);
                }
                let mut stacked: Vec<Vec<Fp>> = Vec::new();
                for &(q, d) in w {
                    let [x, y] = m.joints[q].bodies[..] else {
                        return None;
                    };
                    let rows = models::joint_rows(m, q, *seed, d);
                    for r in 0..rows.nrows() {
                        let line: Vec<Fp> = v
                            .iter()
                            .map(|vl| {
                                let mut s = Fp::ZERO;
                                for k in 0..b {
                                    let ty = if col[y] == usize::MAX {
                                        Fp::ZERO
                                    } else {
                                        vl[col[y] + k]
                                    };
                                    let tx = if col[x] == usize::MAX {
                                        Fp::ZERO
                                    } else {
                                        vl[col[x] + k]
                                    };
                                    s += rows[(r, k)] * (ty - tx);
                                }
                                s
                            })
                            .collect();
                        stacked.push(line);
                    }
                }
                if stacked.is_empty() {
                    return Some(f == 0);
                }
                let a = nalgebra::DMatrix::from_fn(stacked.len(), v.len(), |i, l| stacked[i][l]);
                Some(dense::rank(&a) == f)
            }
        }
    }
}

/// Unknowns of one block at most in [`block_null_vectors`] (a dense solve of about `d³`
/// steps); a larger block falls back to the whole factorization.
const BLOCK_MAX: usize = 384;

/// A basis of the null space of `J` (the constraint rows of `m` at realization `seed`,
/// exactly as [`jacobian`] builds them) without factorizing `J`, and each body's first
/// column as [`jacobian`] gives it. The rows of `J` are routed into the bodies' unknowns (a
/// matching of row units to body units, `b` a body, by augmenting paths); `J` is completed
/// to a square system `M = [J; E]` by one random row `E` on the unknowns of a body for each
/// unit the routing leaves free there. `M` is block triangular along the strongly connected
/// components of the routing (a row routed to body `z` touches `z` and one other body), so
/// `M x = [0; e_l]`, for each unit vector `e_l`, is solved component by component with small
/// dense exact solves: linear in the size of `m`. When every block is nonsingular, so is `M`:
/// `J` has full row rank and the `x` are a basis of its null space (its nullity is the
/// number of free units).
///
/// `None` (the caller factorizes `J`, the same decision) when a joint is not binary or joins
/// a body to itself, a joint's rows are not `b − grade`, a row finds no unit, the routing's
/// search exceeds its linear cap, the nullity exceeds [`ORACLE_NULLITY`], or a block is
/// singular (at this `E` or because `J` has dependent rows) or larger than [`BLOCK_MAX`].
fn block_null_vectors(
    m: &Mechanism,
    seed: u64,
) -> Option<(Vec<usize>, Vec<Vec<crate::exact::Fp>>)> {
    use crate::exact::Fp;
    use crate::exact::field::axpy_sub;
    use crate::exact::models;
    const NIL: u32 = u32::MAX;
    let b = m.b() as usize;
    let nb = m.bodies.len();
    let nq = m.joints.len();
    let frame = m.frame;
    if b == 0 || nb == 0 {
        return None;
    }
    let mut col = vec![usize::MAX; nb];
    let mut c = 0;
    for (x, slot) in col.iter_mut().enumerate() {
        if x != frame {
            *slot = c;
            c += b;
        }
    }
    let ncols = c;
    // Each pair's two bodies and its rows.
    let mut ends: Vec<[u32; 2]> = Vec::with_capacity(nq);
    let mut rows_of: Vec<u8> = Vec::with_capacity(nq);
    let mut deg = vec![0u32; nb + 1];
    for j in &m.joints {
        let [x, y] = j.bodies[..] else {
            return None;
        };
        if x == y || x >= nb || y >= nb {
            return None;
        }
        ends.push([x as u32, y as u32]);
        rows_of.push((b - (j.grade() as usize).min(b)) as u8);
        for z in [x, y] {
            if z != frame {
                deg[z + 1] += 1;
            }
        }
    }
    // The pairs at each body (frame excluded), compressed.
    for z in 0..nb {
        deg[z + 1] += deg[z];
    }
    let start = deg;
    let mut fill: Vec<u32> = start[..nb].to_vec();
    let mut touching = vec![0u32; start[nb] as usize];
    for (q, e) in ends.iter().enumerate() {
        for &z in e {
            let z = z as usize;
            if z != frame {
                touching[fill[z] as usize] = q as u32;
                fill[z] += 1;
            }
        }
    }
    drop(fill);
    let side = |q: usize, z: usize| usize::from(ends[q][0] as usize != z);
    // Each body's distance from the frame along the pairs: a row goes to the farther of its
    // two bodies when both have room, so the free units (the random rows) stay near the
    // frame, where the inputs of a linkage built outwards from its cranks sit and the blocks
    // are small; a free unit far out would tie every group between it and the frame into
    // one block.
    let mut dist = vec![NIL; nb];
    let mut queue: Vec<u32> = Vec::new();
    dist[frame] = 0;
    for e in &ends {
        for s in 0..2 {
            let (z, w) = (e[s] as usize, e[1 - s] as usize);
            if z == frame && dist[w] == NIL {
                dist[w] = 1;
                queue.push(w as u32);
            }
        }
    }
    let mut head = 0;
    while head < queue.len() {
        let z = queue[head] as usize;
        head += 1;
        for &q in &touching[start[z] as usize..start[z + 1] as usize] {
            let w = ends[q as usize][1 - side(q as usize, z)] as usize;
            if dist[w] == NIL {
                dist[w] = dist[z] + 1;
                queue.push(w as u32);
            }
        }
    }
    // The routing: `flow[q][s]` rows of pair `q` on its body `ends[q][s]`.
    let mut flow = vec![[0u8; 2]; nq];
    let mut used = vec![0u8; nb];
    let mut seen = vec![0u32; nb];
    let mut prev: Vec<(u32, u32)> = vec![(NIL, NIL); nb];
    let mut stamp = 0u32;
    let mut work: u64 = 0;
    let cap_work = 64 * (nb + nq) as u64 + 100_000;
    for q in 0..nq {
        for _ in 0..rows_of[q] {
            stamp = stamp.checked_add(1)?;
            queue.clear();
            let [x, y] = ends[q];
            // Unreached bodies (`NIL`) count as farthest.
            let order = if dist[y as usize] > dist[x as usize] {
                [y, x]
            } else {
                [x, y]
            };
            for z in order {
                let z = z as usize;
                if z != frame && seen[z] != stamp {
                    seen[z] = stamp;
                    prev[z] = (NIL, q as u32);
                    queue.push(z as u32);
                }
            }
            let mut head = 0;
            let mut found = None;
            while head < queue.len() {
                let z = queue[head] as usize;
                head += 1;
                if (used[z] as usize) < b {
                    found = Some(z);
                    break;
                }
                for &q2 in &touching[start[z] as usize..start[z + 1] as usize] {
                    let q2 = q2 as usize;
                    work += 1;
                    if flow[q2][side(q2, z)] == 0 {
                        continue;
                    }
                    let w = ends[q2][1 - side(q2, z)] as usize;
                    if w == frame || seen[w] == stamp {
                        continue;
                    }
                    seen[w] = stamp;
                    prev[w] = (z as u32, q2 as u32);
                    queue.push(w as u32);
                }
            }
            work += head as u64;
            if work > cap_work {
                return None;
            }
            // One more row on the free body; each pair on the path moves one of its rows
            // from the body before it to the body after it.
            let mut w = found?;
            used[w] += 1;
            loop {
                let (z, q2) = prev[w];
                let q2 = q2 as usize;
                flow[q2][side(q2, w)] += 1;
                if z == NIL {
                    break;
                }
                let z = z as usize;
                flow[q2][side(q2, z)] -= 1;
                w = z;
            }
        }
    }
    drop((seen, prev, queue, dist));
    let nrows: usize = rows_of.iter().map(|&r| r as usize).sum();
    let n = ncols.checked_sub(nrows)?;
    if n > ORACLE_NULLITY {
        return None;
    }
    let mut v: Vec<Vec<Fp>> = vec![vec![Fp::ZERO; ncols]; n];
    let mut rng = crate::rng::SplitMix64::new(seed ^ 0xB10C_5B57_0000_0001);
    // Tarjan's components of "a row routed to `z` touches `w`" (frame excluded), emitted
    // sinks first: each block's rows touch only its own unknowns and those of blocks
    // already solved. The arcs of each body in `touching` order, so the components come out
    // as a walk of `touching` itself would find them.
    let mut arc_start = vec![0usize; nb + 1];
    let mut arcs: Vec<u32> = Vec::with_capacity(nrows);
    for z in 0..nb {
        for &q in &touching[start[z] as usize..start[z + 1] as usize] {
            let q = q as usize;
            if flow[q][side(q, z)] != 0 {
                arcs.push(ends[q][1 - side(q, z)]);
            }
        }
        arc_start[z + 1] = arcs.len();
    }
    let mut active = vec![true; nb];
    active[frame] = false;
    let (members, bounds) = crate::structure::tarjan_flat(&arc_start, &arcs, &active);
    drop((arc_start, arcs, active));
    let mut done = vec![false; nq];
    let mut loc = vec![NIL; nb];
    let mut unit = 0usize;
    let mut a: Vec<Fp> = Vec::new();
    let mut comp: Vec<usize> = Vec::new();
    for span in bounds.windows(2) {
        // `tarjan_flat` lists a component from the top of its stack down; the block takes it
        // bottom up (its root first), the order of its unknowns, rows and random rows.
        comp.clear();
        comp.extend(members[span[0]..span[1]].iter().rev().map(|&x| x as usize));
        let d = b * comp.len();
        if d > BLOCK_MAX {
            return None;
        }
        for (i, &x) in comp.iter().enumerate() {
            loc[x] = i as u32;
        }
        // [A | R] row-major: the block's rows on its unknowns, the right-hand sides.
        let w_all = d + n;
        a.clear();
        a.resize(d * w_all, Fp::ZERO);
        let mut r = 0usize;
        for &x in &comp {
            for &q in &touching[start[x] as usize..start[x + 1] as usize] {
                let q = q as usize;
                if done[q] || flow[q][side(q, x)] == 0 {
                    continue;
                }
                done[q] = true;
                let rows = models::joint_rows(m, q, seed, 0);
                if rows.nrows() != rows_of[q] as usize || rows.ncols() != b {
                    return None;
                }
                for i in 0..rows.nrows() {
                    if r >= d {
                        return None;
                    }
                    let line = &mut a[r * w_all..(r + 1) * w_all];
                    for (s, &u) in ends[q].iter().enumerate() {
                        let u = u as usize;
                        if u == frame {
                            continue;
                        }
                        for k in 0..b {
                            let e = if s == 0 { -rows[(i, k)] } else { rows[(i, k)] };
                            if loc[u] != NIL {
                                line[loc[u] as usize * b + k] += e;
                            } else {
                                // A body of a block solved before.
                                for (l, vl) in v.iter().enumerate() {
                                    line[d + l] -= e * vl[col[u] + k];
                                }
                            }
                        }
                    }
                    r += 1;
                }
            }
        }
        for &x in &comp {
            for _ in used[x] as usize..b {
                if r >= d || unit >= n {
                    return None;
                }
                let line = &mut a[r * w_all..(r + 1) * w_all];
                for k in 0..b {
                    line[loc[x] as usize * b + k] = Fp::random_nonzero(&mut rng);
                }
                line[d + unit] = Fp::ONE;
                unit += 1;
                r += 1;
            }
        }
        if r != d {
            return None;
        }
        // Gauss-Jordan: a singular block gives up.
        for cc in 0..d {
            let p = (cc..d).find(|&i| !a[i * w_all + cc].is_zero())?;
            if p != cc {
                for t in 0..w_all {
                    a.swap(p * w_all + t, cc * w_all + t);
                }
            }
            let inv = a[cc * w_all + cc].inv();
            for t in cc..w_all {
                a[cc * w_all + t] *= inv;
            }
            for i in 0..d {
                if i == cc {
                    continue;
                }
                let f = a[i * w_all + cc];
                if f.is_zero() {
                    continue;
                }
                let (lo, hi) = a.split_at_mut(i.max(cc) * w_all);
                let (dst, src) = if i < cc {
                    (&mut lo[i * w_all..(i + 1) * w_all], &hi[..w_all])
                } else {
                    (&mut hi[..w_all], &lo[cc * w_all..(cc + 1) * w_all])
                };
                axpy_sub(&mut dst[cc..], f, &src[cc..]);
            }
        }
        for &x in &comp {
            let i0 = loc[x] as usize * b;
            for k in 0..b {
                for (l, vl) in v.iter_mut().enumerate() {
                    vl[col[x] + k] = a[(i0 + k) * w_all + d + l];
                }
            }
            loc[x] = NIL;
        }
    }
    (unit == n).then_some((col, v))
}

/// The constraint rows `J` of `m` (binary joints, no inputs) over GF(p) at the random
/// realization `seed`, one column group per movable body, and each body's first column
/// (`usize::MAX`: the frame).
fn jacobian(m: &Mechanism, seed: u64) -> (crate::exact::SparseMatrix, Vec<usize>) {
    use crate::exact::{Fp, SparseMatrix, models};
    let b = m.b() as usize;
    let mut col = vec![usize::MAX; m.bodies.len()];
    let mut c = 0;
    for (x, slot) in col.iter_mut().enumerate() {
        if x != m.frame {
            *slot = c;
            c += b;
        }
    }
    let mut j = SparseMatrix::with_groups(vec![b; m.bodies.len().saturating_sub(1)]);
    for q in 0..m.joints.len() {
        let [x, y] = m.joints[q].bodies[..] else {
            continue;
        };
        let rows = models::joint_rows(m, q, seed, 0);
        for r in 0..rows.nrows() {
            let mut entries: Vec<(u32, Fp)> = Vec::with_capacity(2 * b);
            for (z, negate) in [(x, true), (y, false)] {
                if x == y || col[z] == usize::MAX {
                    continue;
                }
                for k in 0..b {
                    let v = rows[(r, k)];
                    entries.push(((col[z] + k) as u32, if negate { -v } else { v }));
                }
            }
            j.push_row(entries);
        }
    }
    (j, col)
}

/// The rows of [`jacobian`] made one at a time when the exact factorization reads them:
/// each row's B values and its joint (8 bytes a value, 4 a row, 8 a joint) instead of a
/// vector a row (about 230 bytes a spatial row, with its allocation), which were the peak
/// of `transform` on the random families (rs5: 132 MB of 378).
struct JacobianRows {
    b: usize,
    ngroups: usize,
    /// Row `i`'s values in `vals[i * b..(i + 1) * b]`: its joint's row as
    /// `models::joint_rows` gives it.
    vals: Vec<crate::exact::Fp>,
    /// The joint (index into `sides`) of each row.
    owner: Vec<u32>,
    /// Per binary joint: the column groups of its two bodies (the first one's entries
    /// negated), [`NO_GROUP`] for the frame; both [`NO_GROUP`] for a joint on one body
    /// twice, whose rows are empty in [`jacobian`].
    sides: Vec<[u32; 2]>,
}

/// A body without columns (the frame) in [`JacobianRows`].
const NO_GROUP: u32 = u32::MAX;

impl JacobianRows {
    /// [`jacobian`]'s rows of `m` at `seed`; `None` where its indices (columns, rows,
    /// joints) do not fit in `u32`, or a joint's rows are narrower than B.
    fn of(m: &Mechanism, seed: u64) -> Option<JacobianRows> {
        use crate::exact::models;
        let b = m.b() as usize;
        let ngroups = m.bodies.len().saturating_sub(1);
        let small = |x: usize| u32::try_from(x).ok().filter(|&x| x != NO_GROUP);
        small(ngroups.checked_mul(b)?)?;
        // Body `z`'s group: its columns are `col[z]..col[z] + b` in `jacobian`.
        let group = |z: usize| match z.cmp(&m.frame) {
            Ordering::Less => small(z),
            Ordering::Equal => Some(NO_GROUP),
            Ordering::Greater => small(z - 1),
        };
        // Reserved at the count's rows (B − k a binary joint, what `joint_rows` gives), so
        // that the largest array is not grown by doubling.
        let binary = m.joints.iter().filter(|j| j.bodies.len() == 2);
        let nrows: usize = binary
            .clone()
            .map(|j| b.saturating_sub(j.grade() as usize))
            .sum();
        let mut vals = Vec::with_capacity(nrows.saturating_mul(b));
        let mut owner = Vec::with_capacity(nrows);
        let mut sides = Vec::with_capacity(binary.count());
        for q in 0..m.joints.len() {
            let [x, y] = m.joints[q].bodies[..] else {
                continue;
            };
            let rows = models::joint_rows(m, q, seed, 0);
            if rows.nrows() > 0 && rows.ncols() < b {
                return None;
            }
            let k = small(sides.len())?;
            sides.push(if x == y {
                [NO_GROUP, NO_GROUP]
            } else {
                [group(x)?, group(y)?]
            });
            for r in 0..rows.nrows() {
                owner.push(k);
                vals.extend((0..b).map(|c| rows[(r, c)]));
            }
        }
        small(owner.len())?;
        Some(JacobianRows {
            b,
            ngroups,
            vals,
            owner,
            sides,
        })
    }
}

impl crate::exact::sparse::Rows for JacobianRows {
    fn ncols(&self) -> usize {
        self.ngroups * self.b
    }
    fn nrows(&self) -> usize {
        self.owner.len()
    }
    fn group_sizes(&self) -> Vec<usize> {
        vec![self.b; self.ngroups]
    }
    /// As `push_row` leaves the row [`jacobian`] pushes: the first body's entries negated,
    /// the two groups' columns in increasing order (the bodies' groups differ), zeros
    /// dropped; empty for a joint on one body twice.
    fn row<'a>(
        &'a self,
        i: usize,
        buf: &'a mut crate::exact::sparse::SparseRow,
    ) -> &'a [(u32, crate::exact::Fp)] {
        buf.clear();
        let [gx, gy] = self.sides[self.owner[i] as usize];
        if gx == gy {
            return buf;
        }
        let vals = &self.vals[i * self.b..(i + 1) * self.b];
        let mut sides = [(gx, true), (gy, false)];
        if gy < gx {
            sides.swap(0, 1);
        }
        for (g, negate) in sides {
            if g == NO_GROUP {
                continue;
            }
            for (k, &v) in vals.iter().enumerate() {
                let v = if negate { -v } else { v };
                if !v.is_zero() {
                    buf.push((g * self.b as u32 + k as u32, v));
                }
            }
        }
        buf
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mechanism with only binary joints and none driven is its own one expansion,
    /// borrowed (not copied); with a driven joint the expansion is a copy without inputs.
    #[test]
    fn expansion_borrows_an_undriven_binary_mechanism() {
        let text = "space = \"planar\"\nframe = 1\n\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n\n[[joint]]\ntype = \"R\"\nbodies = [2, 3]\n\n[[joint]]\ntype = \"R\"\nbodies = [3, 1]\n";
        let mut m = crate::format::load("t", text, crate::format::Format::Toml).expect("loads");
        let exps = Expansions::of(&m, 8);
        assert_eq!(exps.len, 1);
        let e = exps.get(0);
        assert!(matches!(e.mech, std::borrow::Cow::Borrowed(_)));
        assert!(std::ptr::eq(e.mech.as_ref(), &m));
        assert_eq!(e.origin, vec![0, 1, 2]);
        m.joints[0].driven = 1;
        let exps = Expansions::of(&m, 8);
        let e = exps.get(0);
        assert!(matches!(e.mech, std::borrow::Cow::Owned(_)));
        assert!(e.mech.joints.iter().all(|j| j.driven == 0));
        assert_eq!(e.mech.joints.len(), 3);
    }

    /// `J v` for the null vectors `v` of [`block_null_vectors`], through [`jacobian`]'s rows.
    fn j_times(m: &Mechanism, seed: u64, v: &[crate::exact::Fp]) -> Vec<crate::exact::Fp> {
        use crate::exact::{Fp, models};
        let (_, col) = jacobian(m, seed);
        let b = m.b() as usize;
        let mut out = Vec::new();
        for q in 0..m.joints.len() {
            let [x, y] = m.joints[q].bodies[..] else {
                continue;
            };
            let rows = models::joint_rows(m, q, seed, 0);
            for i in 0..rows.nrows() {
                let mut s = Fp::ZERO;
                for k in 0..b {
                    if col[y] != usize::MAX {
                        s += rows[(i, k)] * v[col[y] + k];
                    }
                    if col[x] != usize::MAX {
                        s -= rows[(i, k)] * v[col[x] + k];
                    }
                }
                out.push(s);
            }
        }
        out
    }

    /// [`JacobianRows`] makes [`jacobian`]'s rows, row for row (entries, order, empty
    /// rows), with its columns and groups: bundled mechanisms with binary joints, random
    /// linkages planar and spatial, and a file whose frame is not its first body and with
    /// a joint on one body twice and joints to the frame on either side.
    #[test]
    fn jacobian_rows_made_one_at_a_time_are_the_jacobian() {
        use crate::exact::sparse::Rows;
        use crate::generate::random;
        let mut mechs: Vec<Mechanism> = Vec::new();
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/mechanisms");
        for f in std::fs::read_dir(dir).expect("mechanisms") {
            let f = f.expect("entry").path();
            let text = std::fs::read_to_string(&f).expect("reads");
            if let Ok(m) = crate::format::load("m", &text, crate::format::Format::Toml) {
                mechs.push(m);
            }
        }
        for seed in 0..4 {
            for planar in [true, false] {
                mechs.push(random(15, planar, seed).expect("random").0);
            }
        }
        let text = "space = \"spatial\"\nframe = 2\n\n[[joint]]\ntype = \"S\"\nbodies = [1, 2]\n\n\
                    [[joint]]\ntype = \"R\"\nbodies = [1, 3]\n\n[[joint]]\ntype = \"U\"\n\
                    bodies = [2, 3]\n\n[[joint]]\ntype = \"P\"\nbodies = [3, 1]\n\n\
                    [[joint]]\ntype = \"S\"\nbodies = [1, 2, 3]\n";
        let mut m = crate::format::load("t", text, crate::format::Format::Toml).expect("loads");
        // A joint on one body twice (the reader refuses one; `jacobian` gives it empty rows).
        let x = m.joints[1].bodies[1];
        m.joints[1].bodies = vec![x, x].into();
        mechs.push(m);
        let (mut rows_seen, mut empty) = (0, 0);
        for m in &mechs {
            for seed in [1u64, 0x5EED_0000_1234] {
                let (j, _) = jacobian(m, seed);
                let r = JacobianRows::of(m, seed).expect("fits");
                assert_eq!(r.ncols(), j.ncols);
                assert_eq!(r.group_sizes(), j.groups());
                assert_eq!(Rows::nrows(&r), j.nrows());
                let mut buf = Vec::new();
                for (i, want) in j.rows.iter().enumerate() {
                    assert_eq!(r.row(i, &mut buf), &want[..], "row {i}");
                    empty += usize::from(want.is_empty());
                }
                rows_seen += j.nrows();
            }
        }
        assert!(
            rows_seen > 1000 && empty > 0,
            "{rows_seen} rows, {empty} empty"
        );
    }

    /// The back-substituted null vectors are null vectors of `J`, as many as its nullity,
    /// and span the factorization's null space (bundled mechanisms with binary joints, Assur
    /// linkages planar and spatial of every class, random linkages); where `J` has dependent
    /// rows there is none (the caller factorizes).
    #[test]
    fn block_null_vectors_span_the_null_space() {
        use crate::exact::{Factor, dense};
        use crate::generate::{Variant, assur, assur_spatial, random};
        let mut mechs: Vec<(String, Mechanism)> = Vec::new();
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/mechanisms");
        let mut files: Vec<_> = std::fs::read_dir(dir)
            .expect("mechanisms")
            .map(|e| e.expect("entry").path())
            .collect();
        files.sort();
        for f in files {
            let text = std::fs::read_to_string(&f).expect("reads");
            let name = f.display().to_string();
            if let Ok(m) = crate::format::load(&name, &text, crate::format::Format::Toml) {
                mechs.push((name, m));
            }
        }
        for class in 1..=3 {
            for seed in 0..3 {
                for variant in [Variant::A, Variant::B] {
                    let m = assur(class, 6, seed, variant).expect("assur");
                    mechs.push((format!("assur {class} {seed}"), m));
                    let m = assur_spatial(class, 6, seed, variant).expect("assur");
                    mechs.push((format!("spatial assur {class} {seed}"), m));
                }
            }
        }
        for seed in 0..6 {
            for planar in [true, false] {
                let (m, _) = random(12, planar, seed).expect("random");
                mechs.push((format!("random {planar} {seed}"), m));
            }
        }
        let (mut solved, mut dependent) = (0, 0);
        for (name, m) in &mechs {
            if m.joints.iter().any(|j| j.bodies.len() != 2) {
                continue;
            }
            for seed in [1u64, 0x5EED_0000_1234] {
                let (j, col) = jacobian(m, seed);
                let f = Factor::new(&j);
                let got = block_null_vectors(m, seed);
                if f.rank() < j.nrows() {
                    assert!(got.is_none(), "{name}: J is dependent");
                    dependent += 1;
                    continue;
                }
                let Some((col2, v)) = got else {
                    continue;
                };
                assert_eq!(col, col2, "{name}");
                let n = f.nullity();
                assert_eq!(v.len(), n, "{name}");
                for vl in &v {
                    assert!(j_times(m, seed, vl).iter().all(|x| x.is_zero()), "{name}");
                }
                let w = f.random_null_vectors(n, &mut crate::rng::SplitMix64::new(seed));
                let ncols = (m.bodies.len() - 1) * m.b() as usize;
                let ours = nalgebra::DMatrix::from_fn(ncols, n, |i, l| v[l][i]);
                let both = nalgebra::DMatrix::from_fn(ncols, 2 * n, |i, l| {
                    if l < n { v[l][i] } else { w[l - n][i] }
                });
                assert_eq!(dense::rank(&ours), n, "{name}: independent");
                assert_eq!(dense::rank(&both), n, "{name}: the same space");
                solved += 1;
            }
        }
        assert!(solved >= 40, "{solved} solved");
        assert!(dependent >= 1, "{dependent} dependent");
    }

    /// A singular block gives up (the caller factorizes): a body held to the frame by two
    /// spherical joints has six rows of rank five on its six unknowns.
    #[test]
    fn block_null_vectors_give_up_on_a_singular_block() {
        let text = "name = \"two S\"\nspace = \"spatial\"\nframe = 1\n\n[[joint]]\nid = \"a\"\n\
                    type = \"S\"\nbodies = [1, 2]\n\n[[joint]]\nid = \"b\"\ntype = \"S\"\n\
                    bodies = [1, 2]\n";
        let m = crate::format::load("two-s", text, crate::format::Format::Toml).expect("loads");
        let (j, _) = jacobian(&m, 3);
        assert!(crate::exact::Factor::new(&j).rank() < j.nrows());
        assert!(block_null_vectors(&m, 3).is_none());
        // One S: three rows, nullity three, one block of six unknowns with three random rows.
        let one = "name = \"one S\"\nspace = \"spatial\"\nframe = 1\n\n[[joint]]\nid = \"a\"\n\
                   type = \"S\"\nbodies = [1, 2]\n";
        let m = crate::format::load("one-s", one, crate::format::Format::Toml).expect("loads");
        let (_, v) = block_null_vectors(&m, 3).expect("solved");
        assert_eq!(v.len(), 3);
    }

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

    /// The linear decoding takes the smallest leaf at each step, as the scan from 0 did.
    #[test]
    fn prufer_decoding_takes_the_smallest_leaf() {
        fn reference(n: usize, mut index: u64) -> Vec<(usize, usize)> {
            let mut seq = vec![0usize; n - 2];
            for s in seq.iter_mut().rev() {
                *s = (index % n as u64) as usize;
                index /= n as u64;
            }
            let mut degree = vec![1usize; n];
            for &s in &seq {
                degree[s] += 1;
            }
            let mut edges = Vec::new();
            for &s in &seq {
                let leaf = (0..n).find(|&v| degree[v] == 1).unwrap();
                edges.push((leaf.min(s), leaf.max(s)));
                degree[leaf] = 0;
                degree[s] -= 1;
            }
            let last: Vec<usize> = (0..n).filter(|&v| degree[v] == 1).collect();
            edges.push((last[0], last[1]));
            edges.sort_unstable();
            edges
        }
        let mut rng = crate::rng::SplitMix64::new(3);
        for n in 3..=9 {
            for i in 0..trees(n).min(2000) {
                assert_eq!(prufer_tree(n, i), reference(n, i), "tree {i} of K{n}");
            }
        }
        for n in [10, 17, 40, 200] {
            for _ in 0..300 {
                let i = rng.next_u64() % trees(n);
                assert_eq!(prufer_tree(n, i), reference(n, i), "tree {i} of K{n}");
            }
        }
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
