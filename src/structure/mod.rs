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

mod ball_parts;
mod build;
mod count;
mod diagnose;
pub mod exhaustive;
pub mod library;
mod rank;

pub(crate) use crate::graph::scc::tarjan;
/// The count decomposition's components and canonical order, for `mbsa transform`'s analysis
/// of certified placements from its search's flow.
pub(crate) use count::canonical;
pub use diagnose::Spin;
pub use library::{Library, LibraryError};

use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::geometry::{GeometrySource, GeometryUsed};
use crate::joint::JointType;
use crate::mechanism::Mechanism;
use crate::motion::{self, MotionError};
use build::build;
use count::{Equations, RawGroup};
use serde::Serialize;

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
#[derive(Clone, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
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
    /// The part's independent pieces (no joint between two of them), when there are several
    /// (the two fingers of a gripper): each one's unfixed DOF, bodies and input candidates.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pieces: Vec<UnderPiece>,
}

/// One independent piece of the under-determined part.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct UnderPiece {
    /// Its unfixed DOF.
    pub missing: u64,
    /// Its bodies.
    pub bodies: Vec<String>,
    /// Joints where one more input would fix one of its DOF.
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
    /// Rigid parts' own spins, set aside like isolated freedoms (`mbsa rigid`'s structurally
    /// isolated motions).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub spins: Vec<Spin>,
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

pub(crate) use crate::words::capped;

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
    let toggle = diagnose::toggle_suspect(m, a);
    if a.count_only || !(exact_file && set_aside || toggle) || m.bodies.len() > FINITE_CHECK_BODIES
    {
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
    if toggle {
        diagnose::name_toggle(m, a, &f);
    }
    if !(exact_file && set_aside) || f.assembled || f.finite >= f.first_order {
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

/// Why [`analyze_within`] gave no analysis.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AnalyzeError {
    /// As [`analyze`].
    #[error(transparent)]
    Motion(#[from] MotionError),
    /// The exhaustive search ([`Method::Exhaustive`]) ran out of the work budget.
    #[error(transparent)]
    Budget(#[from] BudgetExceeded),
}

/// [`analyze`] with the exhaustive search ([`Method::Exhaustive`], exponential) charged to
/// `budget`'s work limit: past it, [`AnalyzeError::Budget`]. The flow method's answer is
/// [`analyze`]'s.
pub fn analyze_within(
    m: &Mechanism,
    opts: &Options,
    lib: &Library,
    budget: &Budget,
) -> Result<Analysis, AnalyzeError> {
    let mut meter = budget.meter("the exhaustive search");
    let spend = &mut Spend {
        rank: 0,
        search: &mut meter,
    };
    analyze_at(m, opts, lib, None, None, rank::Shortcut::None, spend)?.ok_or(AnalyzeError::Motion(
        MotionError::Degenerate {
            kind: "any",
            reason: "the rank check stopped early",
        },
    ))
}

/// The work one analysis spends: the rank decisions' units (counted, for `mbsa transform`)
/// and the exhaustive search's meter (which stops it).
struct Spend<'a> {
    rank: u64,
    search: &'a mut Meter,
}

/// An error of an analysis with an unlimited search meter, which cannot run out.
fn unlimited(e: AnalyzeError) -> MotionError {
    match e {
        AnalyzeError::Motion(e) => e,
        AnalyzeError::Budget(_) => MotionError::Degenerate {
            kind: "any",
            reason: "the exhaustive search ran out of work units",
        },
    }
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
    let mut meter = Budget::UNLIMITED.meter("the exhaustive search");
    let spend = &mut Spend {
        rank: 0,
        search: &mut meter,
    };
    // The plain check always answers (`None` comes only from `Shortcut::Determined`).
    analyze_at(m, opts, lib, cache, flow, rank::Shortcut::None, spend)
        .map_err(unlimited)?
        .ok_or(MotionError::Degenerate {
            kind: "any",
            reason: "the rank check stopped early",
        })
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
/// nothing) and of the exhaustive search ([`Method::Exhaustive`]), for `mbsa transform`'s work
/// budget.
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
    let mut meter = Budget::UNLIMITED.meter("the exhaustive search");
    let mut spend = Spend {
        rank: 0,
        search: &mut meter,
    };
    let a = analyze_at(m, opts, lib, cache, flow, shortcut, &mut spend).map_err(unlimited)?;
    let work = spend.rank.saturating_add(meter.used());
    Ok((a, work))
}

fn analyze_at(
    m: &Mechanism,
    opts: &Options,
    lib: &Library,
    cache: Option<&AnalysisCache>,
    flow: Option<&[[u8; 2]]>,
    shortcut: rank::Shortcut,
    spend: &mut Spend<'_>,
) -> Result<Option<Analysis>, AnalyzeError> {
    let Some(mut a) = analyze_once(m, opts, lib, cache, flow, shortcut, spend)? else {
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
        let Some(g) = analyze_once(m, &generic, lib, cache, flow, rank::Shortcut::None, spend)?
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
                "the file's geometry is special (axes parallel, concurrent or coaxial by design, or a \
                 singular pose)"
                    .to_string()
            } else {
                let n: u32 = special.iter().map(|r| r.count).sum();
                let joints: Vec<&str> = special
                    .iter()
                    .flat_map(|r| r.joints.iter().map(String::as_str))
                    .collect();
                format!(
                    "at the file's configuration joints {} carry {n} redundant constraint(s) that \
                     generic geometry would not have",
                    capped(&joints)
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
    spend: &mut Spend<'_>,
) -> Result<Option<Analysis>, AnalyzeError> {
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
    let mut spins = diagnose::Spins::default();
    let mut near = None;
    // Joint motions at the file's configuration, for the spatiality of group types.
    let mut twists: Option<Vec<nalgebra::DMatrix<f64>>> = None;
    let mut dec = if opts.count_only {
        count::decompose(m, &eqs, &u)
    } else {
        // A random realization is drawn joint by joint where it is used.
        let used = crate::geometry::choose(m, opts.geometry, opts.precision)?;
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
        spend.rank = spend.rank.saturating_add(r.work);
        if r.deficient {
            return Ok(None);
        }
        near = r
            .near
            .map(|n| diagnose::near_threshold_note(used.precision, n));
        geometry = Some(used);
        isolated = r.isolated;
        redundant = r.redundant;
        unchecked = r.unchecked;
        set_aside = r.set_aside;
        let mut dec = r.decomposition;
        spins = diagnose::set_aside_spins(m, opts, &eqs, &mut dec, &mut u, &mut redundant);
        dec
    };
    let mut unsolved = Vec::new();
    let groups: Vec<RawGroup> = match opts.method {
        // `build` reads the parts only, so the groups can move out.
        Method::Flow => std::mem::take(&mut dec.groups),
        Method::Exhaustive => {
            let s = exhaustive::search(m, &eqs, &u, spend.search)?;
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
    diagnose::spin_notes(&mut a, spins);
    if let Some(n) = near {
        match a.diagnosis.as_mut() {
            Some(d) => d.notes.push(n),
            None => a.notes.push(n),
        }
    }
    a.unchecked = unchecked;
    a.geometry = geometry;
    a.set_aside = set_aside;
    Ok(Some(a))
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
    /// redundancy (5 or more here, 38 on the same family at 10^5 bodies): quadratic.
    #[test]
    fn rank_check_rounds_do_not_grow_with_redundancies() {
        let (m, _) = crate::generate::random(5_000, false, 3).expect("valid parameters");
        let mut eqs = super::Equations::of(&m);
        let mut u = eqs.unknowns(&m);
        let (geoms, used) = crate::geometry::geometries(
            &m,
            crate::geometry::GeometrySource::Random { seed: 0 },
            None,
        )
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
