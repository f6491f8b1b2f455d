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

mod combine;
mod compare;
mod expansion;
mod groups;
mod null_space;
mod oracle;
mod partition;
mod parts;
mod place;
mod problem;
mod prune;
mod ranked;
mod rules;
mod search;
pub mod shard;

pub use compare::{Changes, Comparison, Evaluation, GroupBrief, compare};
pub use partition::Partition;
pub use ranked::{Ranked, compare_scores, ranked, scores};

use crate::budget::{Budget, BudgetExceeded};
use crate::joint::JointType;
use crate::mechanism::{InputSpec, InputSpecError, Mechanism};
use crate::structure::{self, Library, TypeCount};
use combine::combine_parts;
use parts::part_sets;
use place::place;
use problem::Problem;
use rules::Rules;
use serde::{Deserialize, Serialize};

/// A ranking criterion (`--rank`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
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

/// What [`transform`] does with a free joint to the frame (F; FP in a planar or spherical
/// mechanism): a floating base, whose pose the analysis of a fixed-base robot takes as given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BaseMode {
    /// Drive in full each free joint to the frame that is the only joint between its part and
    /// the frame (a floating base). Nothing is lost: inputs on the other joints move bodies
    /// relative to one another, so only the free joint's own inputs fix the part's pose, and
    /// every determined placement drives it in full. The search only gets shorter.
    #[default]
    Auto,
    /// `--fix-base`: drive in full every free joint to the frame, also where other joints
    /// join its part to the frame (a fictitious free pair carrying a platform's pose).
    Fixed,
    /// `--keep-free-base`: place inputs on free joints to the frame as on any other joint.
    Free,
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
    /// `--fix-base`, `--keep-free-base`: free joints to the frame taken as driven in full.
    pub base: BaseMode,
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
    /// Analyse only the placements of this shard ([`shard::run_shard`] sets it; the counts
    /// of determined and excluded placements are then the shard's).
    pub shard: Option<shard::ShardSpec>,
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
            base: BaseMode::Auto,
            max_expansions: 64,
            limit: None,
            budget: Budget::DEFAULT,
            split: true,
            full_analyses: false,
            analysis: structure::Options::default(),
            shard: None,
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
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Input {
    /// Joint id (for a pair of an expanded multiple joint: `id[a-b]`).
    pub joint: String,
    /// Its bodies, `a-b`.
    pub pair: String,
    /// Driven DOF.
    pub driven: u32,
}

/// The structural scores of one placement.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
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
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
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
    /// `expansion` with each multiple joint's pairs cut to a few and counted, when a joint has
    /// more (the table's; JSON lists them all).
    #[serde(skip)]
    brief: Option<String>,
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
    /// The expansion's label for the table: each multiple joint's first pairs and a count of
    /// the rest, so that a joint of many bodies keeps the table's width bounded.
    pub fn expansion_brief(&self) -> Option<&str> {
        self.brief.as_deref().or(self.expansion.as_deref())
    }

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

    /// The bytes the placement holds (its own and on the heap, each allocation as an
    /// allocator rounds it: a short name takes 32 bytes), as [`ranked::Listing`] counts them
    /// to bound a listing's memory.
    pub(super) fn bytes(&self) -> usize {
        use std::mem::size_of;
        let heap = |n: usize| {
            if n == 0 {
                0
            } else {
                (n + 8).next_multiple_of(16).max(32)
            }
        };
        let text = |s: &Option<String>| s.as_ref().map_or(0, |s| heap(s.capacity()));
        let inputs: usize = heap(self.inputs.capacity() * size_of::<Input>())
            + self
                .inputs
                .iter()
                .map(|i| heap(i.joint.capacity()) + heap(i.pair.capacity()))
                .sum::<usize>();
        let types: usize = heap(self.types.capacity() * size_of::<TypeCount>())
            + self
                .types
                .iter()
                .map(|t| heap(t.kind.capacity()))
                .sum::<usize>();
        size_of::<Placement>()
            + inputs
            + types
            + text(&self.expansion)
            + text(&self.brief)
            + self.partition.bytes()
            + self.inputs_at.capacity() * size_of::<usize>()
            + self.groups_at.capacity() * size_of::<(usize, usize)>()
            + self.kinds.capacity() * size_of::<u32>()
            + self.in_lib.capacity()
            + self
                .lean
                .as_ref()
                .map_or(0, |l| l.capacity() * size_of::<(usize, u32)>())
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "shard::geometry_read"
    )]
    pub geometry: Option<crate::geometry::GeometryUsed>,
    /// Inputs each placement has: the count plus the equations set aside, minus the isolated
    /// DOF (the true mobility less the isolated DOF).
    pub f: i64,
    /// Joints (binary pairs) that may be driven under the restrictions.
    pub drivable: usize,
    /// Free joints to the frame taken as driven in full, the base's pose given
    /// ([`BaseMode`]): every placement drives them in full (absent when none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fixed_base: Vec<String>,
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
    #[serde(serialize_with = "ser_count", skip_deserializing)]
    pub count_valid: u128,
    /// Count-valid placements the rank check rejected (not determined).
    #[serde(serialize_with = "ser_count", skip_deserializing)]
    pub excluded_by_rank: u128,
    /// Determined placements (exact unless `truncated`).
    #[serde(serialize_with = "ser_count", skip_deserializing)]
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

/// The most placements a result lists: 100,000, fewer for large mechanisms. Counts are never
/// cut by it. A ranked listing also keeps at most [`LIST_MEMORY`] bytes of placements.
fn list_cap(m: &Mechanism, limit: Option<usize>) -> usize {
    let per = 64 * (m.bodies.len() + m.joints.len()) + 512;
    let cap = (LIST_MEMORY / per).clamp(1_000, 100_000);
    limit.map_or(cap, |l| l.min(cap))
}

/// Bytes of listed placements a result may hold ([`list_cap`], [`ranked::Listing`]).
const LIST_MEMORY: usize = 256 << 20;

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

/// [`enumerate`] of a shard (`opts.shard`): without the notes made from the counts when the
/// counts are the shard's own (a mechanism in one part), which the merge makes from the run's.
pub(crate) fn enumerate_shard(
    m: &Mechanism,
    opts: &TransformOptions,
    lib: &Library,
    sink: &mut dyn FnMut(Placement),
) -> Result<Summary, TransformError> {
    enumerate_kept(m, opts, lib, None, sink, None)
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
        Some(crate::geometry::choose(
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
        fixed_base: rules.fixed_base.clone(),
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
        if opts.shard.is_none() {
            finish_notes(&mut summary);
        }
        return Ok(summary);
    }
    // The parts are placed whole: a shard keeps its own of the combined placements.
    let whole = TransformOptions {
        shard: None,
        ..opts.clone()
    };
    combine_parts(
        m,
        &parts,
        &rules,
        &whole,
        lib,
        &mut meter,
        progress,
        &mut summary,
        sink,
    )?;
    finish_notes(&mut summary);
    Ok(summary)
}

/// The notes every run ends with: truncation, rank-check exclusions, a partial listing.
pub(crate) fn finish_notes(s: &mut Summary) {
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
            s.limit.unwrap_or(0),
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
                 search with --keep (inputs every placement keeps, e.g. the file's own), --on, \
                 --grounded or --exclude",
                count_words(s.count_valid)
            ));
        }
    }
    if let Some(n) = redundancy_note(s) {
        s.notes.insert(0, n);
    }
    if s.excluded_by_rank > 0 {
        s.notes.push(format!(
            "{} of {} count-valid placements are not determined (the rank check finds redundant \
             equations or uncontrolled freedoms) and are excluded",
            count_words(s.excluded_by_rank),
            count_words(s.count_valid)
        ));
    }
    push_listing_note(s);
}

/// The note when fewer placements are listed than are determined ([`list_cap`]).
fn push_listing_note(s: &mut Summary) {
    if (s.listed as u128) < s.determined {
        s.notes.push(format!(
            "{} determined placements: the best {} are listed (the listing is capped to bound \
             memory; the counts are exact)",
            count_words(s.determined),
            s.listed
        ));
    }
}

/// Nothing determined while constraint equations are dependent at the file's configuration:
/// the first note says so and where to go (a Cassie leg's foot loop, planar, closed by a
/// ball joint: each placement keeps a redundant equation and a freedom no input controls).
fn redundancy_note(s: &Summary) -> Option<String> {
    if s.determined > 0 || s.excluded_by_rank == 0 || s.set_aside == 0 {
        return None;
    }
    let found = if s.truncated {
        format!(
            "none of the {} placement(s) examined is determined",
            count_words(s.count_valid)
        )
    } else {
        "no placement is determined".to_string()
    };
    Some(format!(
        "{found}, and {} constraint equation(s) are redundant at the file's configuration \
         (parallel or concurrent axes, a planar or spherical loop written in space): redundant \
         constraints can leave every placement with a freedom no input controls; `mbsa repair` \
         finds joint changes that remove them and keep the motion, and `--geometry random` \
         gives the answer at generic geometry",
        s.set_aside
    ))
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

#[cfg(test)]
mod tests {
    use super::*;

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
