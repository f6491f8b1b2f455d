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
mod flow;
pub mod library;
mod rank;

pub use library::{Library, LibraryError};

use crate::joint::JointType;
use crate::mechanism::Mechanism;
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
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Options {
    /// Skip the rank check: pure counting, as the paper does.
    pub count_only: bool,
    /// Decomposition algorithm.
    pub method: Method,
    /// Seed of the random joint geometry used by the rank check.
    pub seed: u64,
}

/// Whether the inputs determine the mechanism.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Every body is solved, every equation used.
    Determined,
    /// Some equations are too many (inputs or constraints fight), nothing is missing.
    Overdetermined,
    /// Some body DOF are not fixed by any input, nothing is too many.
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

/// A freedom of one body that no input can drive (like a bar's spin between two S joints).
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
    /// The joint whose equation count was lowered to go on.
    pub lowered: String,
    /// What the redundancy means, in words.
    pub freedom: String,
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
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
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
}

/// Analyse the structure of `m`.
pub fn analyze(m: &Mechanism, opts: &Options, lib: &Library) -> Analysis {
    let b = m.b();
    let mut eqs = Equations::of(m);
    let mut u: Vec<u32> = vec![b; m.bodies.len()];
    if let Some(f) = u.get_mut(m.frame) {
        *f = 0;
    }
    let mut isolated = Vec::new();
    let mut redundant = Vec::new();
    let mut unchecked = Vec::new();
    let mut dec = if opts.count_only {
        count::decompose(m, &eqs, &u)
    } else {
        let r = rank::check(m, opts.seed, &mut eqs, &mut u);
        isolated = r.isolated;
        redundant = r.redundant;
        unchecked = r.unchecked;
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
        m, &eqs, &dec, groups, unsolved, isolated, redundant, opts, lib,
    );
    a.unchecked = unchecked;
    a
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
) -> Analysis {
    let nb = m.bodies.len();
    let id = |b: usize| m.body_id(b).to_string();
    // Solve-order key of every body: frame and over-determined part are known first, groups in
    // canonical order, the under-determined part (or unsolved bodies) last.
    let mut key = vec![i64::MAX; nb];
    for (b, k) in key.iter_mut().enumerate() {
        *k = match dec.body_part[b] {
            Part::Frame => -2,
            Part::Over => -1,
            _ => i64::MAX,
        };
    }
    for (g, grp) in raw.iter().enumerate() {
        for &b in &grp.bodies {
            key[b] = g as i64;
        }
    }
    if let Some(k) = key.get_mut(m.frame) {
        *k = -2;
    }
    // Pairs touching each body, compressed (`touch[start[x]..start[x + 1]]`), in pair order.
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
    let mut touch = vec![0usize; start[nb]];
    for e in 0..eqs.len() {
        let [a, c] = eqs.bodies(e);
        touch[fill[a]] = e;
        fill[a] += 1;
        if c != a {
            touch[fill[c]] = e;
            fill[c] += 1;
        }
    }
    drop(fill);
    let code = |e: usize| m.joints[eqs.joint[e]].kind.code();
    // Each group's pair lists, type and inputs on its own (in parallel: they read shared
    // data only); then the types are numbered in order of first appearance.
    let rendered: Vec<(String, String, String, String, u32)> = crate::par::map(raw.len(), |g| {
        let grp = &raw[g];
        let gk = g as i64;
        let mut from: Vec<(usize, usize, usize)> = Vec::new();
        let mut internal: Vec<(usize, usize, usize)> = Vec::new();
        let mut to: Vec<(usize, usize, usize)> = Vec::new();
        let mut kinds: Vec<(JointType, usize)> = Vec::new();
        let mut inputs = 0u32;
        for &x in &grp.bodies {
            for &e in &touch[start[x]..start[x + 1]] {
                let [a, c] = eqs.bodies(e);
                let y = if a == x { c } else { a };
                let active = if key[y] == gk {
                    // Count an internal pair once, from its hub's side.
                    if x != a {
                        continue;
                    }
                    internal.push((x.min(y), x.max(y), e));
                    true
                } else if key[y] < gk {
                    from.push((x, y, e));
                    true
                } else {
                    to.push((x, y, e));
                    false
                };
                if active {
                    let jt = m.joints[eqs.joint[e]].kind;
                    match kinds.iter_mut().find(|(k, _)| *k == jt) {
                        Some((_, n)) => *n += 1,
                        None => kinds.push((jt, 1)),
                    }
                    inputs += eqs.driven[e];
                }
            }
        }
        let render = |list: &mut Vec<(usize, usize, usize)>| {
            list.sort_unstable();
            let mut s = String::with_capacity(list.len() * 8);
            for &(i, j, e) in list.iter() {
                // Writing into a String cannot fail.
                let _ = write!(s, "{}&{}{}.", m.body_id(i), m.body_id(j), code(e));
            }
            s
        };
        // Joint types in catalogue order, as the BTreeMap over `JointType` gave them.
        kinds.sort_unstable_by_key(|&(k, _)| k);
        let mut kind = String::new();
        for (k, n) in &kinds {
            let _ = write!(kind, "{n}{}", k.code());
        }
        kind.push_str(m.space.suffix());
        (
            kind,
            render(&mut from),
            render(&mut internal),
            render(&mut to),
            inputs,
        )
    });
    let mut groups = Vec::with_capacity(raw.len());
    // Types in order of first appearance, with their counts and library membership.
    let mut type_order: Vec<(String, usize, bool)> = Vec::new();
    let mut type_index: BTreeMap<String, usize> = BTreeMap::new();
    for (g, (grp, (kind, from, internal, to, inputs))) in raw.iter().zip(rendered).enumerate() {
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
        groups.push(Group {
            name: format!("SG-{}", roman(g + 1)),
            bodies: grp.bodies.iter().map(|&b| id(b)).collect(),
            nm: grp.bodies.len(),
            level: grp.level,
            inputs,
            in_library: type_order[t].2,
            kind,
            depends_on: grp.deps.clone(),
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

    let diag = diagnose(m, eqs, dec, unsolved, &redundant);
    let over = diag.overdetermined.is_some();
    let under = diag.underdetermined.is_some();
    let status = match (over, under) {
        (false, false) => Status::Determined,
        (true, false) => Status::Overdetermined,
        (false, true) => Status::Underdetermined,
        (true, true) => Status::Mixed,
    };
    let mob = crate::mobility::mobility(m);
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
        levels: raw.iter().map(|g| g.level).max().unwrap_or(0),
        groups,
        types,
        library: lib.name.clone(),
        isolated,
        redundant,
        unchecked: Vec::new(),
        diagnosis: (status != Status::Determined || !diag.unsolved.is_empty()).then_some(diag),
    }
}

/// The over- and under-determined parts in words and lists.
fn diagnose(
    m: &Mechanism,
    eqs: &Equations,
    dec: &Decomposition,
    unsolved: Vec<usize>,
    redundant: &[Redundancy],
) -> Diagnosis {
    let id = |b: usize| m.body_id(b).to_string();
    let pair_label = |e: usize| {
        let [a, c] = eqs.bodies(e);
        format!("{}-{}", id(a), id(c))
    };
    let joint_ids = |mut js: Vec<usize>| {
        js.sort_unstable();
        js.dedup();
        js.into_iter()
            .map(|j| m.joints[j].id.clone())
            .collect::<Vec<_>>()
    };
    let mut d = Diagnosis {
        unsolved: unsolved.iter().map(|&b| id(b)).collect(),
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
        d.notes.push(format!(
            "{excess} equation(s) too many: {} {} more than the bodies {{{}}} can satisfy; \
             remove an input there or free a joint",
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
    let short: Vec<Missing> = (0..m.bodies.len())
        .filter(|&b| b != m.frame && dec.body_missing[b] > 0)
        .map(|b| Missing {
            body: id(b),
            missing: dec.body_missing[b],
        })
        .collect();
    if !short.is_empty() {
        let missing: u64 = short.iter().map(|s| s.missing as u64).sum();
        let in_part: Vec<bool> = (0..m.bodies.len())
            .map(|b| dec.body_part[b] == Part::Under)
            .collect();
        let bodies: Vec<String> = (0..m.bodies.len())
            .filter(|&b| in_part[b])
            .map(id)
            .collect();
        let mut cands: Vec<usize> = Vec::new();
        for (ji, j) in m.joints.iter().enumerate() {
            let spare = j.driven < j.grade() * j.pairs();
            if spare && j.bodies.iter().any(|&b| in_part[b]) {
                cands.push(ji);
            }
        }
        let input_candidates = joint_ids(cands);
        d.notes.push(format!(
            "{missing} DOF not fixed by any input: bodies {{{}}} can move; one more input on \
             one of the joints {} would fix one DOF",
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
        d.notes.push(format!(
            "group {{{}}}: joints {} carry {} redundant equation(s); {}",
            r.bodies.join(", "),
            r.joints.join(", "),
            r.count,
            r.freedom
        ));
    }
    d
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
