//! Structural analysis: the decomposition of a mechanism into ordered structural groups.
//!
//! The default method ([`Method::Flow`]) is a maximum flow from joint equations to body
//! unknowns followed by the strongly connected components of the dependency graph (a
//! Dulmage–Mendelsohn / block-triangular decomposition): near-linear, and it also splits a
//! mechanism that is not determined into its over-, well- and under-determined parts. The
//! paper's exhaustive smallest-first search ([`Method::Exhaustive`], [`exhaustive`]) is kept as
//! a reference. Unless [`Options::count_only`] is set, a rank check at random generic joint
//! geometry then removes isolated freedoms and redundant equations that the count cannot see.
//! `docs/algorithms.md` explains the method.

mod count;
pub mod exhaustive;
pub(crate) mod flow;
pub mod library;
mod rank;

/// The count decomposition's components and canonical order, for `mbsa transform`'s analysis
/// of certified placements from its search's flow.
pub(crate) use count::{canonical, tarjan, tarjan_flat};
pub use library::{Library, LibraryError};

use crate::joint::JointType;
use crate::mechanism::Mechanism;
use crate::motion::{self, GeometrySource, GeometryUsed, MotionError};
use count::{Decomposition, Equations, Part, RawGroup};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Which decomposition algorithm to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Maximum flow + strongly connected components (near-linear).
    #[default]
    Flow,
    /// The paper's smallest-first search over connected chains (exponential; reference only).
    Exhaustive,
}

/// Analysis options.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Options {
    /// Skip the rank check: pure counting, as the paper does.
    pub count_only: bool,
    /// Decomposition algorithm.
    pub method: Method,
    /// The joint geometry of the rank check: the file's configuration or a seeded random
    /// realization ([`GeometrySource`]).
    pub geometry: GeometrySource,
    /// File geometry: how precisely its numbers are known (default: from the digits written).
    pub precision: Option<f64>,
}

/// Whether the inputs determine the mechanism.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Every body is solved, every equation used.
    Determined,
    /// Some equations are too many (inputs or constraints fight), nothing is missing.
    Overdetermined,
    /// Some body DOF are not fixed by any input, no equation fights (redundant constraints
    /// consistent at the configuration, or with no input driven, may be set aside).
    Underdetermined,
    /// Both: as in inputs that add up to the count but are badly placed.
    Mixed,
}

/// The mobility count as the structural analysis sees it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct CountSummary {
    /// `B·Nm − Σ pairs·(B − k)`.
    pub count: i64,
    /// Total driven DOF.
    pub inputs: u64,
}

/// One structural group, as in the paper's Table 8.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Group {
    /// `SG-I`, `SG-II`, ... in canonical order.
    pub name: String,
    /// Body ids, ascending.
    pub bodies: Vec<String>,
    /// Number of bodies.
    pub nm: usize,
    /// Solve level (1 = depends on the frame only).
    pub level: usize,
    /// Driven DOF on the group's active pairs.
    pub inputs: u32,
    /// SG type string (`1R1P1U1S3D`).
    #[serde(rename = "type")]
    pub kind: String,
    /// Whether the library solves this type.
    pub in_library: bool,
    /// Indices (0-based, into `groups`) of the groups it depends on.
    pub depends_on: Vec<usize>,
    /// Active external pairs `i&jT.` (i in the group).
    pub from: String,
    /// Internal pairs.
    pub internal: String,
    /// Pairs that hand DOF to bodies solved later.
    pub to: String,
}

/// One row of the type table (paper Tables 9, 11, 15).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct TypeCount {
    /// SG type string.
    #[serde(rename = "type")]
    pub kind: String,
    /// Number of groups of this type.
    pub count: usize,
    /// Whether the library solves it.
    pub in_library: bool,
}

/// A freedom of one body that moves no other body (like a bar's spin between two S joints).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Isolated {
    /// The body.
    pub body: String,
    /// Dimension of the freedom.
    pub dimension: u32,
}

/// Redundant equations found by the rank check.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Redundancy {
    /// Bodies of the group whose system lost rank.
    pub bodies: Vec<String>,
    /// Joints whose equations take part in the dependency.
    pub joints: Vec<String>,
    /// Number of redundant equations.
    pub count: u32,
    /// The joint(s) whose equation count was lowered to go on.
    pub lowered: String,
    /// What the redundancy means, in words.
    pub freedom: String,
    /// True for constraints dependent at the file's configuration (consistent there: they fix
    /// nothing and are set aside before the decomposition); false for a deficit the rank check
    /// found in a group (equations too many for the freedom they hide).
    pub configuration: bool,
}

/// A pair with more equations than the flow could use.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Excess {
    /// Joint id.
    pub joint: String,
    /// The binary pair `a-b`.
    pub pair: String,
    /// Unused equations.
    pub excess: u32,
}

/// A body with DOF no equation fixes.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Missing {
    /// Body id.
    pub body: String,
    /// Unfixed DOF.
    pub missing: u32,
}

/// The over-determined part.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct OverPart {
    /// Surplus equations in total.
    pub excess: u64,
    /// The pairs with unused equations.
    pub unsaturated: Vec<Excess>,
    /// All joints of the part (ids).
    pub joints: Vec<String>,
    /// Its bodies.
    pub bodies: Vec<String>,
}

/// The under-determined part.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct UnderPart {
    /// Unfixed DOF in total.
    pub missing: u64,
    /// Bodies with unfixed DOF.
    pub short: Vec<Missing>,
    /// All bodies of the part.
    pub bodies: Vec<String>,
    /// Joints where one more input would fix a DOF (touching the part, spare grade).
    pub input_candidates: Vec<String>,
}

/// Why the mechanism is not determined.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Diagnosis {
    /// Too many equations, if any.
    pub overdetermined: Option<OverPart>,
    /// Too few, if any.
    pub underdetermined: Option<UnderPart>,
    /// Bodies the exhaustive search could not place (exhaustive method only).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unsolved: Vec<String>,
    /// Plain-language findings.
    pub notes: Vec<String>,
}

/// A block the rank check left to the count because it is too large to factorize densely.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub struct Unchecked {
    /// Number of bodies in the block.
    pub bodies: usize,
    /// Its unknowns (body DOF less isolated freedoms).
    pub unknowns: usize,
    /// Its equations.
    pub equations: usize,
}

/// The full structural analysis.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Analysis {
    /// Mechanism name.
    pub name: String,
    /// Motion space name.
    pub space: &'static str,
    /// DOF of a free body.
    pub b: u32,
    /// Algorithm used.
    pub method: Method,
    /// Whether the rank check was skipped.
    pub count_only: bool,
    /// The mobility count and inputs.
    pub mobility: CountSummary,
    /// The verdict.
    pub status: Status,
    /// The joint geometry of the rank check (absent with `count_only`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub geometry: Option<GeometryUsed>,
    /// DOF the inputs leave free (missing DOF of the under-determined part); 0 when determined.
    pub uncontrolled: u64,
    /// Bodies that no joint names (not part of the mechanism; never a group).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub disconnected: Vec<String>,
    /// Number of solve levels.
    pub levels: usize,
    /// Structural groups in canonical order.
    pub groups: Vec<Group>,
    /// Library coverage per type, in order of first appearance.
    pub types: Vec<TypeCount>,
    /// Name of the library used.
    pub library: String,
    /// Isolated freedoms (rank check).
    pub isolated: Vec<Isolated>,
    /// Redundant equations (rank check).
    pub redundant: Vec<Redundancy>,
    /// Blocks too large for the rank check (their verdict is the count's); empty when every
    /// block was checked.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unchecked: Vec<Unchecked>,
    /// Present unless the mechanism is determined.
    pub diagnosis: Option<Diagnosis>,
    /// At the file's configuration: what generic geometry gives, when it differs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub generic: Option<GenericAnswer>,
    /// Findings worth saying when the mechanism is determined (redundant constraints set
    /// aside, the comparison with generic geometry).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// Constraint equations set aside at the file's configuration, per joint index (for the
    /// transformations: they fix nothing, so inputs take their place).
    #[serde(skip)]
    pub set_aside: Vec<u32>,
    /// Set by [`check_finite`] when the file's configuration is singular (fewer finite than
    /// first-order freedoms): the verdict and the groups are first-order answers there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub finite: Option<FiniteCaveat>,
}

/// The file's configuration is singular: fewer finite than first-order freedoms
/// ([`check_finite`]). The numbers are those of `mbsa rigid --finite`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct FiniteCaveat {
    /// First-order mobility: the nullity of the constraint Jacobian at the file's
    /// configuration (frame fixed, inputs not counted).
    pub first_order: usize,
    /// Finite mobility: the local dimension of the set of configurations there.
    pub finite: usize,
    /// First-order freedoms that do not extend to a finite motion.
    pub instantaneous_only: usize,
    /// Joints that move in those freedoms.
    pub singular_joints: Vec<String>,
    /// The note added to the analysis's notes.
    pub note: String,
}

/// Largest mechanism (bodies) [`check_finite`] tests: the test is dense (an SVD of the whole
/// constraint Jacobian per trial point), seconds at 160 bodies.
pub const FINITE_CHECK_BODIES: usize = 64;

/// Work cap of [`check_finite`] (the units of [`crate::budget::Budget::max_work`], about the
/// dense flops): a mechanism that needs more is not tested (the verdict stays the first-order
/// one, as before, and nothing is said). Measured (release, `docs/benchmarks.md`): a run that
/// stops at the cap costs 0.04-0.08 s of CPU; a flat parallelogram needs under 10^7 units,
/// `@rig-double-banana` (19 first-order freedoms, one slicing level each) more than the cap
/// and is not tested, a flat N-four-bar of 31 windows (64 bodies) about 2·10^9.
pub const FINITE_CHECK_WORK: u64 = 200_000_000;

/// Joints the note of [`check_finite`] names at most (the JSON lists them all).
const NOTE_JOINTS: usize = 8;

/// Whether the first-order verdict of `a` (an analysis of `m`) holds for finite motion at the
/// file's configuration, and a note (and [`Analysis::finite`]) when it does not.
///
/// Runs only where the verdict can fail: at the file's geometry, when the analysis set aside
/// constraints dependent at the configuration (a [`Redundancy`] with `configuration: true`).
/// Otherwise the constraint Jacobian has full row rank there, the constraints are a
/// submersion, and the configurations near it form a manifold of the first-order dimension
/// (implicit function theorem): every first-order freedom extends to a motion and the verdict
/// holds. Also only for at most [`FINITE_CHECK_BODIES`] bodies and within
/// [`FINITE_CHECK_WORK`] work units (or `max_work`, when lower); past either, and on any
/// error of the test, nothing is said. It runs the finite-mobility test of `mbsa rigid
/// --finite` ([`crate::position::finite::finite_mobility_of_file`], seeded: deterministic) and
/// speaks only when that finds fewer finite than first-order freedoms (a singular
/// configuration: a flat or folded loop, a Stewart platform's singular leg). A redundancy by
/// design (a planar loop written in space, a Bennett linkage) keeps its freedoms along the
/// motion and says nothing.
///
/// The test takes the numbers as exact (it tracks curves of solutions to a residual of
/// 1e-14), while the analysis takes rounded numbers as known to their precision: rounding
/// alone can make a linkage that moves by design rigid at that scale (`@bennett-rounded-8`:
/// first order 1, finite 0 as written). So a file whose numbers are rounded (a nonzero
/// [`GeometryUsed::precision`]) is not tested unless `--tolerance 0` declares them exact, and a
/// file that misses closure (tested at an assembled configuration, not the file's) says
/// nothing. `precision` is `--tolerance`, `max_work` the caller's work limit.
pub fn check_finite(m: &Mechanism, a: &mut Analysis, precision: Option<f64>, max_work: u64) {
    use crate::position::finite::{FiniteOptions, finite_mobility_of_file};
    // File geometry whose numbers are exact as written (or `--tolerance 0`).
    let exact_file = a
        .geometry
        .as_ref()
        .is_some_and(|g| g.is_file() && g.precision.unwrap_or(0.0) == 0.0);
    let set_aside = a.redundant.iter().any(|r| r.configuration);
    if a.count_only || !exact_file || !set_aside || m.bodies.len() > FINITE_CHECK_BODIES {
        return;
    }
    let opts = FiniteOptions {
        budget: crate::budget::Budget {
            max_work: FINITE_CHECK_WORK.min(max_work),
            ..crate::budget::Budget::DEFAULT
        },
        ..FiniteOptions::default()
    };
    // The closure tolerance `mbsa rigid --finite` takes from `--tolerance`.
    let tolerance = precision.map(|p| {
        crate::position::closure::tolerance_for(crate::position::residual::model_size(m), p)
    });
    let Ok(f) = finite_mobility_of_file(m, tolerance, &opts) else {
        return;
    };
    if f.assembled || f.finite >= f.first_order {
        return;
    }
    let inputs = a.mobility.inputs;
    let consequence = if a.status == Status::Determined {
        format!(
            "its {inputs} input(s) fix every first-order freedom, but near this configuration \
             they cannot all be set independently: \"determined\" holds to first order only"
        )
    } else {
        "the verdict and the groups count first-order freedoms: they hold to first order only"
            .to_string()
    };
    let joints = match f.singular_joints.len() {
        0 => String::new(),
        n if n <= NOTE_JOINTS => format!(", at joint(s) {}", f.singular_joints.join(", ")),
        n => format!(
            ", at joint(s) {} and {} more",
            f.singular_joints[..NOTE_JOINTS].join(", "),
            n - NOTE_JOINTS
        ),
    };
    let note = format!(
        "singular configuration: at the file's configuration the joints allow {} DOF to first \
         order (inputs not counted) but only {} for finite motion ({} first-order freedom(s) \
         do not extend to a motion{joints}): {consequence}; `mbsa rigid --finite` gives the \
         details",
        f.first_order, f.finite, f.instantaneous_only
    );
    if let Some(d) = a.diagnosis.as_mut() {
        d.notes.push(note.clone());
    } else {
        a.notes.push(note.clone());
    }
    a.finite = Some(FiniteCaveat {
        first_order: f.first_order,
        finite: f.finite,
        instantaneous_only: f.instantaneous_only,
        singular_joints: f.singular_joints,
        note,
    });
}

/// The structural answer at generic (random) geometry, when it differs from the answer at the
/// file's configuration.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct GenericAnswer {
    /// The verdict at generic geometry.
    pub status: Status,
    /// Its number of groups.
    pub groups: usize,
    /// Its uncontrolled DOF.
    pub uncontrolled: u64,
    /// Why the two differ.
    pub why: String,
}

/// Analyse the structure of `m`. Errors: the file geometry asked for (`--geometry file`) is
/// missing or unusable (a joint model cannot be built).
pub fn analyze(m: &Mechanism, opts: &Options, lib: &Library) -> Result<Analysis, MotionError> {
    analyze_cached(m, opts, lib, None, None)
}

/// What [`analyze_cached`] keeps between analyses of one mechanism under different inputs.
pub type AnalysisCache = rank::Cache;

/// [`analyze`], reusing the rank check's factorizations from earlier analyses of the same
/// mechanism (other inputs) kept in `cache`, and starting the maximum flow from `flow` (per
/// joint, the units of its equations and inputs routed into its first and its second body,
/// as `mbsa transform`'s search has them; binary joints only). The groups, levels, types and
/// the verdict are the same as without them (the decomposition does not depend on which
/// maximum flow is found); only the lists of unsaturated pairs and short bodies of a mechanism
/// that is not determined name one maximum flow's choice. Used by `mbsa transform`, which
/// analyses many placements of one mechanism.
pub fn analyze_cached(
    m: &Mechanism,
    opts: &Options,
    lib: &Library,
    cache: Option<&AnalysisCache>,
    flow: Option<&[[u8; 2]]>,
) -> Result<Analysis, MotionError> {
    // The plain check always answers (`None` comes only from `Shortcut::Determined`).
    analyze_at(m, opts, lib, cache, flow, rank::Shortcut::None, &mut 0)?.ok_or(
        MotionError::Degenerate {
            kind: "any",
            reason: "the rank check stopped early",
        },
    )
}

/// [`analyze_cached`] for `mbsa transform`, which keeps a placement only when it is
/// determined: `None` when it is surely not (a group the count finds well-determined is rank
/// deficient), found without explaining the deficit or factorizing the other groups; else
/// the analysis [`analyze_cached`] gives.
///
/// `certified`: the caller has proved the placement's whole constraint system (every pair's
/// rows with its inputs, frame fixed) of full row rank at the random realization (`mbsa
/// transform` decides it over GF(p), see `docs/algorithms.md`). Then every group block is
/// nonsingular and the under-determined block has full row rank: when the count has no
/// over-determined part, the rank check skips the blocks' factorizations (the reduced
/// unknowns are still computed). The answer is the one the rank check would give unless a
/// block is numerically rank deficient at the floating-point realization while generically of
/// full rank (the exact rank is the generic one). Ignored at the file's geometry.
///
/// Also returns the work units of the rank decisions made (a dense factorization of `n`
/// unknowns costs `n^3`, an exact sparse one its factor's entries; cached and certified blocks
/// nothing), for `mbsa transform`'s work budget.
pub fn analyze_placement(
    m: &Mechanism,
    opts: &Options,
    lib: &Library,
    cache: Option<&AnalysisCache>,
    flow: Option<&[[u8; 2]]>,
    certified: bool,
) -> Result<(Option<Analysis>, u64), MotionError> {
    let shortcut = if certified {
        rank::Shortcut::Certified
    } else {
        rank::Shortcut::Determined
    };
    let mut work = 0;
    let a = analyze_at(m, opts, lib, cache, flow, shortcut, &mut work)?;
    Ok((a, work))
}

fn analyze_at(
    m: &Mechanism,
    opts: &Options,
    lib: &Library,
    cache: Option<&AnalysisCache>,
    flow: Option<&[[u8; 2]]>,
    shortcut: rank::Shortcut,
    work: &mut u64,
) -> Result<Option<Analysis>, MotionError> {
    let Some(mut a) = analyze_once(m, opts, lib, cache, flow, shortcut, work)? else {
        return Ok(None);
    };
    // At the file's configuration, say what generic geometry would give when it differs.
    if let Some(used) = &a.geometry
        && used.is_file()
        && m.bodies.len() <= GENERIC_COMPARISON_BODIES
    {
        let generic = Options {
            geometry: GeometrySource::Random { seed: 0 },
            ..*opts
        };
        let Some(g) = analyze_once(m, &generic, lib, cache, flow, rank::Shortcut::None, work)?
        else {
            return Ok(Some(a));
        };
        let differs = g.status != a.status
            || g.groups.len() != a.groups.len()
            || g.uncontrolled != a.uncontrolled;
        if differs {
            let special: Vec<&Redundancy> =
                a.redundant.iter().filter(|r| r.configuration).collect();
            let why = if special.is_empty() {
                "the file's configuration is special (a singular or degenerate pose)".to_string()
            } else {
                let n: u32 = special.iter().map(|r| r.count).sum();
                let joints: Vec<&str> = special
                    .iter()
                    .flat_map(|r| r.joints.iter().map(String::as_str))
                    .collect();
                format!(
                    "at the file's configuration joints {} carry {n} redundant constraint(s) that \
                     generic geometry would not have",
                    joints.join(", ")
                )
            };
            a.generic = Some(GenericAnswer {
                status: g.status,
                groups: g.groups.len(),
                uncontrolled: g.uncontrolled,
                why: why.clone(),
            });
            if let Some(d) = a.diagnosis.as_mut() {
                d.notes.push(generic_note(&g, &why));
            } else {
                a.notes.push(generic_note(&g, &why));
            }
        }
    }
    Ok(Some(a))
}

/// Mechanisms up to this size also get the comparison with generic geometry.
const GENERIC_COMPARISON_BODIES: usize = 10_000;

fn generic_note(g: &Analysis, why: &str) -> String {
    format!(
        "at generic (random) geometry the answer would differ: {} with {} group(s){}; {why}",
        status_word(g.status),
        g.groups.len(),
        if g.uncontrolled > 0 {
            format!(", {} DOF not fixed by the inputs", g.uncontrolled)
        } else {
            String::new()
        }
    )
}

fn status_word(s: Status) -> &'static str {
    match s {
        Status::Determined => "determined",
        Status::Overdetermined => "over-determined",
        Status::Underdetermined => "under-determined",
        Status::Mixed => "mixed (over- and under-determined)",
    }
}

fn analyze_once(
    m: &Mechanism,
    opts: &Options,
    lib: &Library,
    cache: Option<&AnalysisCache>,
    flow: Option<&[[u8; 2]]>,
    shortcut: rank::Shortcut,
    work: &mut u64,
) -> Result<Option<Analysis>, MotionError> {
    let mut eqs = Equations::of(m);
    if let Some(f) = flow {
        eqs.hint = (0..eqs.len())
            .map(|e| {
                let j = eqs.joint[e];
                let binary = m.joints.get(j).is_some_and(|j| j.bodies.len() == 2);
                match f.get(j) {
                    Some(&[a, c]) if binary && !eqs.input_only[e] => [u32::from(a), u32::from(c)],
                    _ => [0, 0],
                }
            })
            .collect();
    }
    let mut u = eqs.unknowns(m);
    let mut isolated = Vec::new();
    let mut redundant = Vec::new();
    let mut unchecked = Vec::new();
    let mut geometry = None;
    let mut set_aside = vec![0; m.joints.len()];
    // Joint motions at the file's configuration, for the spatiality of group types.
    let mut twists: Option<Vec<nalgebra::DMatrix<f64>>> = None;
    let mut dec = if opts.count_only {
        count::decompose(m, &eqs, &u)
    } else {
        // A random realization is drawn joint by joint where it is used.
        let used = motion::choose(m, opts.geometry, opts.precision)?;
        let geoms = match used.seed {
            Some(_) => Vec::new(),
            None => motion::file_geometries(m),
        };
        if used.is_file() && m.space == crate::mechanism::Space::Spatial {
            twists = Some(
                (0..m.joints.len())
                    .map(|j| motion::pair_model(m, j, &geoms[j], 0).twists)
                    .collect(),
            );
        }
        let shortcut = match shortcut {
            rank::Shortcut::Certified if used.seed.is_none() => rank::Shortcut::None,
            s => s,
        };
        let r = rank::check(m, &geoms, &used, &mut eqs, &mut u, cache, shortcut);
        *work = work.saturating_add(r.work);
        if r.deficient {
            return Ok(None);
        }
        geometry = Some(used);
        isolated = r.isolated;
        redundant = r.redundant;
        unchecked = r.unchecked;
        set_aside = r.set_aside;
        r.decomposition
    };
    let mut unsolved = Vec::new();
    let groups: Vec<RawGroup> = match opts.method {
        // `build` reads the parts only, so the groups can move out.
        Method::Flow => std::mem::take(&mut dec.groups),
        Method::Exhaustive => {
            let s = exhaustive::search(m, &eqs, &u);
            unsolved = s.unsolved;
            s.groups
        }
    };
    let mut a = build(
        m,
        &eqs,
        &dec,
        groups,
        unsolved,
        isolated,
        redundant,
        opts,
        lib,
        twists.as_deref(),
    );
    a.unchecked = unchecked;
    a.geometry = geometry;
    a.set_aside = set_aside;
    Ok(Some(a))
}

#[allow(clippy::too_many_arguments)]
fn build(
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
    let nb = eqs.nodes;
    // Every body id written once, in body order; the group lists copy them from here (read
    // from the bodies, 48 bytes apart, each id was a cache miss at 10^6 bodies).
    let mut id_text = String::with_capacity(8 * m.bodies.len());
    let mut id_at = Vec::with_capacity(m.bodies.len() + 1);
    id_at.push(0);
    for body in &m.bodies {
        push_id(&mut id_text, &body.id);
        id_at.push(id_text.len());
    }
    let id_of = |b: usize| &id_text[id_at[b]..id_at[b + 1]];
    let id = |b: usize| id_of(b).to_string();
    // Integer ids that are their body's index plus one constant (every generated file) are
    // written from the index: the group lists name bodies at random, and each read of the id
    // table was two cache misses at 10^6 bodies.
    let int_base = match m.bodies.first().map(|b| &b.id) {
        Some(crate::mechanism::BodyId::Int(first)) => {
            let follows = m.bodies.iter().enumerate().all(|(k, b)| {
                matches!(b.id, crate::mechanism::BodyId::Int(i)
                    if i64::try_from(k).ok().and_then(|k| k.checked_add(*first)) == Some(i))
            });
            follows.then_some(*first)
        }
        _ => None,
    };
    let put_id = |s: &mut String, b: usize| match int_base {
        Some(c) => crate::format::push_int(s, b as i64 + c),
        None => s.push_str(id_of(b)),
    };
    // Solve-order key of every body: frame (0) and over-determined part (1) are known first,
    // groups in canonical order (group g is g + 2), the under-determined part (or unsolved
    // bodies) last. Four bytes a node: the group lists read it at random.
    let mut key = vec![u32::MAX; nb];
    for (b, k) in key.iter_mut().enumerate() {
        *k = match dec.body_part[b] {
            Part::Frame => 0,
            Part::Over => 1,
            _ => u32::MAX,
        };
    }
    let group_key = |g: usize| u32::try_from(g + 2).unwrap_or(u32::MAX - 1);
    for (g, grp) in raw.iter().enumerate() {
        for &b in &grp.bodies {
            key[b] = group_key(g);
        }
    }
    if let Some(k) = key.get_mut(m.frame) {
        *k = 0;
    }
    // Pairs touching each node, compressed (`near[start[x]..start[x + 1]]`), in pair order,
    // each with what the group lists need of it: reading the pair's fields from `eqs` and the
    // joint's kind from the joint was five cache misses a pair at 10^6 bodies.
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
    drop(fill);
    // Each group's pair lists, type and inputs on its own (in parallel: they read shared
    // data only); then the types are numbered in order of first appearance.
    let rendered: Vec<(String, String, String, String, u32)> = crate::par::map(raw.len(), |g| {
        let grp = &raw[g];
        let gk = group_key(g);
        // (first body, second body, pair, its joint's kind).
        let mut from: Vec<(u32, u32, u32, JointType)> = Vec::new();
        let mut internal: Vec<(u32, u32, u32, JointType)> = Vec::new();
        let mut to: Vec<(u32, u32, u32, JointType)> = Vec::new();
        let mut kinds: Vec<(JointType, usize)> = Vec::new();
        let mut inputs = 0u32;
        let mut active_joints: Vec<usize> = Vec::new();
        // (joint, its kind, pairs counted), to retype a joint that acts as a planar one.
        let mut counted: Vec<(usize, JointType, usize)> = Vec::new();
        let mut add_kind = |ji: usize, jt: JointType, n: usize| {
            if n == 0 {
                return;
            }
            active_joints.push(ji);
            counted.push((ji, jt, n));
            match kinds.iter_mut().find(|(k, _)| *k == jt) {
                Some((_, c)) => *c += n,
                None => kinds.push((jt, n)),
            }
        };
        // Element nodes of multiple joints met by this group (rendered per joint below).
        let mut elements: Vec<usize> = Vec::new();
        for &x in &grp.bodies {
            if eqs.is_element(x) {
                elements.push(x);
                continue;
            }
            let xi = x as u32;
            for p in &near[start[x]..start[x + 1]] {
                let y = p.y as usize;
                if eqs.is_element(y) {
                    elements.push(y);
                    continue;
                }
                let ky = key[y];
                if p.input_only {
                    // A multiple joint's inputs: counted, not listed (its pairs are below).
                    if ky < gk || (ky == gk && p.hub) {
                        inputs += p.driven;
                    }
                    continue;
                }
                let active = if ky == gk {
                    // Count an internal pair once, from its hub's side.
                    if !p.hub {
                        continue;
                    }
                    internal.push((xi.min(p.y), xi.max(p.y), p.e, p.kind));
                    true
                } else if ky < gk {
                    from.push((xi, p.y, p.e, p.kind));
                    true
                } else {
                    to.push((xi, p.y, p.e, p.kind));
                    false
                };
                if active {
                    add_kind(p.joint as usize, p.kind, 1);
                    inputs += p.driven;
                }
            }
        }
        // A multiple joint as the binary pairs it stands for: with its element in the group,
        // one body of the joint in the group is its hub; with the element solved before, each
        // body of the group hangs on a body solved before that holds the element.
        elements.sort_unstable();
        elements.dedup();
        for v in elements {
            let jt = eqs.element_joint(v);
            let jk = m.joints[jt].kind;
            let mut inside: Vec<(u32, u32)> = Vec::new();
            let mut before: Vec<(u32, u32)> = Vec::new();
            let mut after: Vec<(u32, u32)> = Vec::new();
            for p in &near[start[v]..start[v + 1]] {
                match key[p.y as usize].cmp(&gk) {
                    std::cmp::Ordering::Equal => inside.push((p.y, p.e)),
                    std::cmp::Ordering::Less => before.push((p.y, p.e)),
                    std::cmp::Ordering::Greater => after.push((p.y, p.e)),
                }
            }
            if key[v] == gk {
                let Some(&(hub, _)) = inside.first() else {
                    continue;
                };
                for &(y, e) in &inside[1..] {
                    internal.push((hub, y, e, jk));
                }
                for &(y, e) in &before {
                    from.push((hub, y, e, jk));
                }
                for &(y, e) in &after {
                    to.push((hub, y, e, jk));
                }
                add_kind(jt, jk, inside.len() - 1 + before.len());
            } else if key[v] < gk {
                let holder = before.first().map_or(m.frame as u32, |&(y, _)| y);
                for &(x, e) in &inside {
                    from.push((x, holder, e, jk));
                }
                add_kind(jt, jk, inside.len());
            } else if let Some(&(holder, _)) = after.first() {
                for &(x, e) in &inside {
                    to.push((x, holder, e, jk));
                }
            }
        }
        let render = |list: &mut Vec<(u32, u32, u32, JointType)>| {
            list.sort_unstable();
            let mut s = String::with_capacity(list.len() * 8);
            for &(i, j, _, k) in list.iter() {
                put_id(&mut s, i as usize);
                s.push('&');
                put_id(&mut s, j as usize);
                s.push_str(k.code());
                s.push('.');
            }
            s
        };

        // A spatial group that closes a loop whose joints move in a space of 3 dimensions at
        // the file's configuration (a planar or spherical loop written in space) is typed by
        // the spatiality it really has.
        let pairs: usize = kinds.iter().map(|&(_, n)| n).sum();
        let real = grp.bodies.iter().filter(|&&x| !eqs.is_element(x)).count();
        let mut planar_here = false;
        if let Some(tw) = twists
            && pairs > real
        {
            active_joints.sort_unstable();
            active_joints.dedup();
            planar_here = spatiality(active_joints.iter().map(|&j| &tw[j])) <= 3;
            // The freedoms of a ball (or another joint of several) that the group's
            // single-freedom joints keep out of their plane are locked: the joint acts as
            // the planar joint it is inside the plane (the S of a planar loop as its pin).
            if !planar_here && let Some(acts) = locked_planar(tw, &active_joints) {
                planar_here = true;
                kinds.clear();
                for &(ji, jt, n) in &counted {
                    let k = acts.iter().find(|&&(j, _)| j == ji).map_or(jt, |&(_, k)| k);
                    match kinds.iter_mut().find(|(x, _)| *x == k) {
                        Some((_, c)) => *c += n,
                        None => kinds.push((k, n)),
                    }
                }
            }
        }
        // Joint types in catalogue order, as the BTreeMap over `JointType` gave them.
        kinds.sort_unstable_by_key(|&(k, _)| k);
        let mut kind = String::new();
        for (k, n) in &kinds {
            let _ = write!(kind, "{n}{}", k.code());
        }
        kind.push_str(if planar_here { "2D" } else { m.space.suffix() });
        (
            kind,
            render(&mut from),
            render(&mut internal),
            render(&mut to),
            inputs,
        )
    });
    // The pair lists are written: their inputs (115 MB at 10^6 bodies) are freed before the
    // groups are made, not held with them.
    drop(near);
    drop(start);
    drop(key);
    let mut groups = Vec::with_capacity(raw.len());
    // Types in order of first appearance, with their counts and library membership.
    let mut type_order: Vec<(String, usize, bool)> = Vec::new();
    let mut type_index: BTreeMap<String, usize> = BTreeMap::new();
    // Groups of element nodes only (a shared pin fixed by one solved body) are not shown:
    // shown groups are numbered in order, and a dependency on a hidden group is one on what
    // that group depends on.
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
    for grp in &raw {
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
            .map(|&b| id(b))
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

    let mut diag = diagnose(m, eqs, dec, unsolved, &redundant, &isolated);
    let over = diag.overdetermined.is_some();
    let under = diag.underdetermined.is_some();
    // Mixed whenever equations that can fight (too many by count, or a group's deficit the
    // rank check found, whose right-hand side the inputs move) and uncontrolled DOF coexist.
    // Constraints dependent at the file's configuration are consistent there and set aside
    // before the decomposition, and with no input driven every right-hand side is zero: such
    // redundancy fights nothing, so it makes a mechanism neither over-determined nor mixed
    // (as it leaves a determined one determined); the notes list it.
    let driven = m.joints.iter().any(|j| j.driven > 0);
    let redundant_eqs = over || (driven && redundant.iter().any(|r| !r.configuration));
    let status = if under && redundant_eqs {
        Status::Mixed
    } else if under {
        Status::Underdetermined
    } else if over {
        Status::Overdetermined
    } else {
        Status::Determined
    };
    let mob = crate::mobility::mobility(m);
    let uncontrolled = diag.underdetermined.as_ref().map_or(0, |u| u.missing);
    let mut touched = vec![false; m.bodies.len()];
    for j in &m.joints {
        for &x in &j.bodies {
            touched[x] = true;
        }
    }
    let disconnected: Vec<String> = (0..m.bodies.len())
        .filter(|&x| !touched[x] && x != m.frame)
        .map(id)
        .collect();
    if !disconnected.is_empty() {
        diag.notes.push(format!(
            "bodies {{{}}} are named by no joint: not part of the mechanism",
            disconnected.join(", ")
        ));
    }
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
        levels: raw
            .iter()
            .filter(|g| g.bodies.iter().any(|&x| !eqs.is_element(x)))
            .map(|g| g.level)
            .max()
            .unwrap_or(0),
        groups,
        types,
        library: lib.name.clone(),
        isolated,
        redundant,
        unchecked: Vec::new(),
        diagnosis: (status != Status::Determined || !diag.unsolved.is_empty()).then_some(diag),
        generic: None,
        notes,
        set_aside: vec![0; m.joints.len()],
        finite: None,
    }
}

/// A pair seen from one of its nodes (see `build`).
#[derive(Clone, Copy)]
struct Near {
    /// The other node.
    y: u32,
    /// The pair.
    e: u32,
    driven: u32,
    joint: u32,
    kind: JointType,
    /// Whether this node is the pair's hub.
    hub: bool,
    input_only: bool,
}

/// The dimension of the span of joint motions (columns of `twists`, normalized), at a relative
/// tolerance of 1e-6: 3 for a planar or spherical loop, 6 for a general spatial one.
fn spatiality<'a>(twists: impl Iterator<Item = &'a nalgebra::DMatrix<f64>>) -> usize {
    let cols: Vec<nalgebra::DVector<f64>> = twists
        .flat_map(|t| t.column_iter().map(|c| c.normalize()).collect::<Vec<_>>())
        .collect();
    if cols.is_empty() {
        return 0;
    }
    nalgebra::DMatrix::from_columns(&cols).rank(1e-6)
}

/// Whether the single-freedom joints among `joints` (twists `tw`, 6 × freedoms, angular part
/// first) move in a plane or about a point, and every joint of several freedoms keeps at least
/// one inside that motion space: then the group is solved as a planar (spherical) one, its
/// other freedoms locked by the single-freedom joints, which fix the bodies' turns out of the
/// plane. Returns each such joint with the kind it acts as when one freedom is left (a turn
/// about the plane's normal: R; a slide: P); `None` otherwise.
fn locked_planar(
    tw: &[nalgebra::DMatrix<f64>],
    joints: &[usize],
) -> Option<Vec<(usize, JointType)>> {
    use nalgebra::{DMatrix, DVector, Vector3};
    const TOL: f64 = 1e-6;
    let rank = |cols: &[DVector<f64>]| {
        if cols.is_empty() {
            0
        } else {
            DMatrix::from_columns(cols).rank(TOL)
        }
    };
    let single: Vec<usize> = joints
        .iter()
        .copied()
        .filter(|&j| tw[j].ncols() == 1)
        .collect();
    let multi: Vec<usize> = joints
        .iter()
        .copied()
        .filter(|&j| tw[j].ncols() > 1)
        .collect();
    if single.is_empty() || multi.is_empty() {
        return None;
    }
    // The motion algebra the single-freedom joints generate: their twists closed under the
    // Lie bracket [(w1, v1), (w2, v2)] = (w1 × w2, w1 × v2 − w2 × v1).
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let add = |basis: &mut Vec<DVector<f64>>, v: DVector<f64>| {
        let n = v.norm();
        if n > TOL {
            let v = v / n;
            basis.push(v);
            if rank(basis) < basis.len() {
                basis.pop();
            }
        }
    };
    for &j in &single {
        add(&mut basis, tw[j].column(0).into_owned());
    }
    let part = |v: &DVector<f64>, at: usize| Vector3::new(v[at], v[at + 1], v[at + 2]);
    let mut grew = true;
    while grew && basis.len() <= 3 {
        grew = false;
        let n = basis.len();
        for a in 0..n {
            for b in a + 1..n {
                let (w1, v1) = (part(&basis[a], 0), part(&basis[a], 3));
                let (w2, v2) = (part(&basis[b], 0), part(&basis[b], 3));
                let w = w1.cross(&w2);
                let v = w1.cross(&v2) - w2.cross(&v1);
                let before = basis.len();
                add(
                    &mut basis,
                    DVector::from_vec(vec![w.x, w.y, w.z, v.x, v.y, v.z]),
                );
                grew |= basis.len() > before;
            }
        }
    }
    if basis.len() != 3 {
        return None;
    }
    let mut acts = Vec::new();
    for &j in &multi {
        let t: Vec<DVector<f64>> = tw[j]
            .column_iter()
            .map(|c| c.into_owned().normalize())
            .collect();
        let mut both = t.clone();
        both.extend(basis.iter().cloned());
        // dim(T ∩ L) = dim T + dim L − dim(T + L).
        let inside = (rank(&t) + 3).saturating_sub(rank(&both));
        if inside == 0 {
            return None;
        }
        if inside == 1 {
            // The one freedom inside: a null vector of [T, −L] gives T·a in both.
            let k = t.len();
            let mut m = DMatrix::zeros(6, k + 3);
            for (c, v) in t.iter().enumerate() {
                m.set_column(c, v);
            }
            for (c, v) in basis.iter().enumerate() {
                m.set_column(k + c, &(-v));
            }
            // The eigenvector of the smallest eigenvalue of MᵀM (square: M may be wide).
            let eig = (m.transpose() * &m).symmetric_eigen();
            let last = eig
                .eigenvalues
                .iter()
                .enumerate()
                .min_by(|x, y| x.1.total_cmp(y.1))
                .map(|(i, _)| i)?;
            let a = eig.eigenvectors.column(last);
            let mut w = DVector::zeros(6);
            for (c, v) in t.iter().enumerate() {
                w += v * a[c];
            }
            let (ang, lin) = (part(&w, 0), part(&w, 3));
            let kind = if ang.norm() <= TOL * lin.norm().max(1.0) {
                JointType::P
            } else if ang.dot(&lin).abs() <= TOL * ang.norm() * lin.norm().max(1.0) {
                JointType::R
            } else {
                continue;
            };
            acts.push((j, kind));
        }
    }
    Some(acts)
}

/// The over- and under-determined parts in words and lists.
fn diagnose(
    m: &Mechanism,
    eqs: &Equations,
    dec: &Decomposition,
    unsolved: Vec<usize>,
    redundant: &[Redundancy],
    isolated: &[Isolated],
) -> Diagnosis {
    let id = |b: usize| m.body_id(b).to_string();
    let pair_label = |e: usize| {
        let [a, c] = eqs.bodies(e);
        format!("{}-{}", eqs.node_name(m, a), eqs.node_name(m, c))
    };
    let joint_ids = |mut js: Vec<usize>| {
        js.sort_unstable();
        js.dedup();
        js.into_iter()
            .map(|j| m.joints[j].id.clone())
            .collect::<Vec<_>>()
    };
    let mut d = Diagnosis {
        unsolved: unsolved.iter().map(|&b| eqs.node_name(m, b)).collect(),
        ..Diagnosis::default()
    };
    let over_eqs: Vec<usize> = (0..eqs.len()).filter(|&e| dec.eq_excess[e] > 0).collect();
    if !over_eqs.is_empty() {
        let excess: u64 = over_eqs.iter().map(|&e| dec.eq_excess[e] as u64).sum();
        let part_eqs: Vec<usize> = (0..eqs.len())
            .filter(|&e| dec.eq_part[e] == Part::Over)
            .collect();
        let bodies: Vec<String> = (0..m.bodies.len())
            .filter(|&b| dec.body_part[b] == Part::Over)
            .map(id)
            .collect();
        let unsaturated: Vec<Excess> = over_eqs
            .iter()
            .map(|&e| Excess {
                joint: m.joints[eqs.joint[e]].id.clone(),
                pair: pair_label(e),
                excess: dec.eq_excess[e],
            })
            .collect();
        let with_inputs = over_eqs.iter().any(|&e| eqs.driven[e] > 0)
            || part_eqs.iter().any(|&e| eqs.driven[e] > 0);
        let remedy = if with_inputs {
            "remove an input there or free a joint"
        } else {
            "the joints over-constrain these bodies for generic dimensions: free a joint"
        };
        d.notes.push(format!(
            "{excess} equation(s) too many: {} {} more than the bodies {{{}}} can satisfy; \
             {remedy}",
            if unsaturated.len() == 1 {
                "joint"
            } else {
                "joints"
            },
            unsaturated
                .iter()
                .map(|x| format!("{} (+{})", x.joint, x.excess))
                .collect::<Vec<_>>()
                .join(", "),
            bodies.join(", ")
        ));
        d.overdetermined = Some(OverPart {
            excess,
            unsaturated,
            joints: joint_ids(part_eqs.iter().map(|&e| eqs.joint[e]).collect()),
            bodies,
        });
    }
    // Element nodes (`<J>`: the shared pin of multiple joint J) can miss DOF too.
    let short: Vec<Missing> = (0..eqs.nodes)
        .filter(|&b| b != m.frame && dec.body_missing[b] > 0)
        .map(|b| Missing {
            body: eqs.node_name(m, b),
            missing: dec.body_missing[b],
        })
        .collect();
    if !short.is_empty() {
        let missing: u64 = short.iter().map(|s| s.missing as u64).sum();
        let in_part: Vec<bool> = (0..eqs.nodes)
            .map(|b| dec.body_part[b] == Part::Under)
            .collect();
        let bodies: Vec<String> = (0..m.bodies.len())
            .filter(|&b| in_part[b])
            .map(id)
            .collect();
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
        // The candidates are found by count. A body with an isolated freedom (a bar spinning
        // between two balls) can take an input that only turns that freedom and fixes nothing
        // else (a Delta robot's rods): such candidates are named, with how to test one.
        let spinning: std::collections::HashSet<&str> =
            isolated.iter().map(|i| i.body.as_str()).collect();
        let doubtful: Vec<String> = if spinning.is_empty() {
            Vec::new()
        } else {
            joint_ids(
                cands
                    .iter()
                    .copied()
                    .filter(|&ji| {
                        m.joints[ji]
                            .bodies
                            .iter()
                            .any(|&b| spinning.contains(id(b).as_str()))
                    })
                    .collect(),
            )
        };
        let caveat = match doubtful.len() {
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
        };
        let input_candidates = joint_ids(cands);
        d.notes.push(format!(
            "{missing} DOF not fixed by any input: bodies {{{}}} can move; one more input on \
             one of the joints {} would fix one DOF{caveat}",
            bodies.join(", "),
            input_candidates.join(", ")
        ));
        d.underdetermined = Some(UnderPart {
            missing,
            short,
            bodies,
            input_candidates,
        });
    }
    for r in redundant {
        d.notes.push(if r.configuration {
            format!(
                "bodies {{{}}}: {} redundant constraint(s) set aside (lowered on {}); {}",
                r.bodies.join(", "),
                r.count,
                r.lowered,
                r.freedom
            )
        } else {
            format!(
                "group {{{}}}: joints {} carry {} redundant equation(s); {}",
                r.bodies.join(", "),
                r.joints.join(", "),
                r.count,
                r.freedom
            )
        });
    }
    d
}

/// Append a body id as `Display` writes it, without the formatting machinery (the group
/// lists of a 10^6-body mechanism write millions of ids).
fn push_id(s: &mut String, id: &crate::mechanism::BodyId) {
    match id {
        crate::mechanism::BodyId::Int(i) => crate::format::push_int(s, *i),
        crate::mechanism::BodyId::Name(n) => s.push_str(n),
    }
}

/// Upper-case Roman numeral (1 → `I`); plain digits beyond 3999.
fn roman(mut n: usize) -> String {
    if n == 0 || n > 3999 {
        return n.to_string();
    }
    const TABLE: [(usize, &str); 13] = [
        (1000, "M"),
        (900, "CM"),
        (500, "D"),
        (400, "CD"),
        (100, "C"),
        (90, "XC"),
        (50, "L"),
        (40, "XL"),
        (10, "X"),
        (9, "IX"),
        (5, "V"),
        (4, "IV"),
        (1, "I"),
    ];
    let mut s = String::new();
    for &(v, r) in &TABLE {
        while n >= v {
            s.push_str(r);
            n -= v;
        }
    }
    s
}

impl crate::position::SolveOrder for Analysis {
    fn groups(&self) -> Vec<crate::position::OrderedGroup<'_>> {
        self.groups
            .iter()
            .map(|g| crate::position::OrderedGroup {
                name: &g.name,
                level: g.level,
                bodies: &g.bodies,
            })
            .collect()
    }

    fn overdetermined(&self) -> Option<&[String]> {
        self.diagnosis
            .as_ref()
            .and_then(|d| d.overdetermined.as_ref())
            .map(|o| o.bodies.as_slice())
    }
}

#[cfg(test)]
mod tests {
    /// Scale regression: the rank check decomposes the whole mechanism once per round, and a
    /// round lowers every deficient group it meets. The check before ran one round per
    /// redundancy (9 here, 38 on the same family at 10^5 bodies): quadratic.
    #[test]
    fn rank_check_rounds_do_not_grow_with_redundancies() {
        let (m, _) = crate::generate::random(20_000, false, 3).expect("valid parameters");
        let mut eqs = super::Equations::of(&m);
        let mut u = eqs.unknowns(&m);
        let (geoms, used) =
            super::motion::geometries(&m, super::GeometrySource::Random { seed: 0 }, None)
                .expect("random geometry");
        let r = super::rank::check(
            &m,
            &geoms,
            &used,
            &mut eqs,
            &mut u,
            None,
            super::rank::Shortcut::None,
        );
        assert!(r.redundant.len() >= 5, "{} redundancies", r.redundant.len());
        assert!(
            r.rounds <= 3,
            "{} rounds for {} redundancies",
            r.rounds,
            r.redundant.len()
        );
    }

    #[test]
    fn push_id_writes_what_display_writes() {
        use crate::mechanism::BodyId;
        for id in [
            BodyId::Int(0),
            BodyId::Int(7),
            BodyId::Int(-13),
            BodyId::Int(1_000_000),
            BodyId::Int(i64::MAX),
            BodyId::Int(i64::MIN),
            BodyId::Name("crank".into()),
            BodyId::Name(String::new()),
        ] {
            let mut s = String::from("x");
            super::push_id(&mut s, &id);
            assert_eq!(s, format!("x{id}"));
        }
    }

    /// A rotation about `axis` through `p`, as the joint models write it.
    fn turn(axis: [f64; 3], p: [f64; 3]) -> nalgebra::DVector<f64> {
        let u = nalgebra::Vector3::from(axis);
        let m = nalgebra::Vector3::from(p).cross(&u);
        nalgebra::DVector::from_vec(vec![u.x, u.y, u.z, m.x, m.y, m.z])
    }

    fn twists(cols: &[nalgebra::DVector<f64>]) -> nalgebra::DMatrix<f64> {
        nalgebra::DMatrix::from_columns(cols)
    }

    #[test]
    fn a_ball_between_pins_on_parallel_axes_acts_as_a_pin() {
        use crate::joint::JointType;
        let x = [1.0, 0.0, 0.0];
        let ball = [0.0, 0.3, 0.2];
        let tw = vec![
            twists(&[turn(x, [0.0, 0.0, 0.0])]),
            twists(&[turn(x, [0.0, 1.0, 0.1])]),
            twists(&[
                turn(x, ball),
                turn([0.0, 1.0, 0.0], ball),
                turn([0.0, 0.0, 1.0], ball),
            ]),
        ];
        // Two parallel pins generate the plane's motions (turns about x, slides in y and z);
        // the ball keeps only its turn about x: a pin.
        assert_eq!(
            super::locked_planar(&tw, &[0, 1, 2]),
            Some(vec![(2, JointType::R)])
        );
        // All the ball's turns count when the pins are not parallel: spatial.
        let mut skew = tw.clone();
        skew[1] = twists(&[turn([0.0, 1.0, 0.0], [0.0, 1.0, 0.1])]);
        assert_eq!(super::locked_planar(&skew, &[0, 1, 2]), None);
        // Without a joint of several freedoms nothing is retyped.
        assert_eq!(super::locked_planar(&tw, &[0, 1]), None);
    }

    /// A planar four-bar loop through the pins `pins` (A: frame-crank, B, C, D: rocker-frame),
    /// with the joints in `driven` driven.
    fn four_bar(space: &str, pins: [[f64; 2]; 4], driven: &[&str]) -> crate::Mechanism {
        let mut text = format!("name = \"four-bar\"\nspace = \"{space}\"\nframe = 1\n");
        let bodies = [[1, 2], [2, 3], [3, 4], [4, 1]];
        for (k, id) in ["A", "B", "C", "D"].iter().enumerate() {
            let [x, y] = pins[k];
            let [a, b] = bodies[k];
            text += &format!("[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [{a}, {b}]\n");
            if space == "planar" {
                text += &format!("origin = [{x}, {y}]\n");
            } else {
                text += &format!("origin = [{x}, {y}, 0]\naxis = [0, 0, 1]\n");
            }
            if driven.contains(id) {
                text += "driven = 1\n";
            }
        }
        crate::format::load("four-bar", &text, crate::format::Format::Toml).expect("valid")
    }

    fn checked(m: &crate::Mechanism) -> super::Analysis {
        let lib = super::Library::builtin();
        let mut a = super::analyze(m, &super::Options::default(), &lib).expect("analyses");
        super::check_finite(m, &mut a, None, u64::MAX);
        a
    }

    /// A parallelogram four-bar written flat (every pin on one line) is at a singular
    /// configuration: the parallelogram and the anti-parallelogram branches cross there, 2
    /// first-order freedoms but 1 finite one. Its two inputs fix the first-order freedoms
    /// ("determined" at the file's geometry), but they cannot be set independently: the note
    /// says so, in the plane and written in space.
    #[test]
    fn a_flat_parallelogram_is_determined_to_first_order_only() {
        let flat = [[0.0, 0.0], [1.0, 0.0], [3.0, 0.0], [2.0, 0.0]];
        for space in ["planar", "spatial"] {
            let a = checked(&four_bar(space, flat, &["A", "D"]));
            assert_eq!(a.status, super::Status::Determined, "{space}");
            let f = a.finite.as_ref().expect("singular: a caveat");
            assert_eq!((f.first_order, f.finite, f.instantaneous_only), (2, 1, 1));
            assert!(f.note.starts_with("singular configuration"), "{}", f.note);
            assert!(f.note.contains("holds to first order only"), "{}", f.note);
            assert!(a.notes.contains(&f.note), "{space}: {:?}", a.notes);
            // Deterministic: the same note again.
            assert_eq!(
                checked(&four_bar(space, flat, &["A", "D"])).finite,
                a.finite
            );
        }
        // One input: under-determined to first order; the note is in the diagnosis.
        let a = checked(&four_bar("planar", flat, &["A"]));
        assert_eq!(a.status, super::Status::Underdetermined);
        let f = a.finite.as_ref().expect("singular: a caveat");
        let d = a.diagnosis.as_ref().expect("a diagnosis");
        assert!(d.notes.contains(&f.note), "{:?}", d.notes);
    }

    /// The same loop at a generic pose, in the plane (full row rank: not even tested) and
    /// written in space (3 constraints set aside by design, every freedom finite), and a Bennett
    /// linkage (redundant by design, it moves): no caveat.
    #[test]
    fn redundancy_by_design_keeps_the_first_order_verdict() {
        let generic = [[0.0, 0.0], [0.13, 0.97], [1.41, 1.22], [1.93, -0.08]];
        for space in ["planar", "spatial"] {
            let a = checked(&four_bar(space, generic, &["A"]));
            assert_eq!(a.status, super::Status::Determined, "{space}");
            assert_eq!(a.finite, None, "{space}");
            assert!(a.notes.iter().all(|n| !n.contains("singular")), "{space}");
        }
        let (file, text) = crate::examples::find("rig-bennett").expect("bundled");
        let m = crate::format::load(file, text, crate::format::Format::Toml).expect("valid");
        let a = checked(&m);
        assert!(
            a.redundant.iter().any(|r| r.configuration),
            "{:?}",
            a.redundant
        );
        assert_eq!(a.finite, None);
    }
}
