//! Joint models over GF(p) at a random realization: the exact counterpart of
//! [`crate::motion::realize`], for rank decisions that do not depend on size or conditioning.
//!
//! Each joint gets random field elements for its features (drawn per (seed, joint index))
//! and the twists of its kind ([`kinds::allowed`], the definition the floating-point models
//! use); directions need no normalization (twist spaces are spans). Its constraint rows are
//! an exact basis of the annihilator of the twists left once its driven DOF are fixed.
//! Count-only kinds get `B − k` random rows (generic contact lines in general position); a
//! driven DOF of theirs, or of SPSP, keeps `k − driven` random combinations of the allowed
//! twists (their echelon basis has no named DOF, as in [`crate::motion`]). With p = 2^61 − 1
//! a random realization has the generic rank except with probability below (degree)/p.

use super::kinds::{self, Allowed, Features, V3};
use crate::budget::BudgetExceeded;
use crate::exact::dense::{complement_rows, rank};
use crate::exact::field::Fp;
use crate::exact::sparse::{Factor, Limits, Rows, SparseMatrix, SparseRow};
use crate::joint::JointType;
use crate::mechanism::{Mechanism, Space};
use crate::rng::SplitMix64;
use crate::rng::indexed_seed;
use nalgebra::DMatrix;

fn rand3(rng: &mut SplitMix64) -> V3<Fp> {
    [
        Fp::random_nonzero(rng),
        Fp::random_nonzero(rng),
        Fp::random_nonzero(rng),
    ]
}

/// Random features for a joint of `kind`: point `p`, directions `u`, `v`, `n` (in this order
/// from `rng`), then the pitch of a spatial H or the second centre of a spatial SPSP (drawn
/// only where the kind has a model, as the rows that replace it draw from the same stream). `v` is the second axis of
/// U and the start of every perpendicular pair; PC's axis is the random direction `n × v` of
/// the plane and CR's slot normal is `−v` (only its part across the axis counts).
fn random_features(kind: JointType, space: Space, rng: &mut SplitMix64) -> Features<Fp> {
    let (p, u, v, n) = (rand3(rng), rand3(rng), rand3(rng), rand3(rng));
    let mut f = Features {
        origin: p,
        origin2: p,
        axis: u,
        axis2: v,
        normal: n,
        pitch: Fp::ZERO,
        hint: v,
    };
    if space != Space::Spatial {
        return f;
    }
    match kind {
        JointType::H => f.pitch = Fp::random_nonzero(rng),
        JointType::SPSP => f.origin2 = rand3(rng),
        JointType::PC => f.axis = kinds::cross(&n, &v),
        JointType::CR => f.normal = v.map(|x| -x),
        _ => {}
    }
    f
}

/// The allowed twists of `kind` in driven-DOF order (B coordinates each), or `None` for a
/// kind without a model (it gets random constraint rows).
fn twists(kind: JointType, space: Space, rng: &mut SplitMix64) -> Option<Vec<Vec<Fp>>> {
    let b = space.b() as usize;
    let f = random_features(kind, space, rng);
    match kinds::allowed(kind, space, &f)? {
        Allowed::Listed(list, n) => Some(list[..n].iter().map(|t| t[..b].to_vec()).collect()),
        Allowed::AnnihilatorOf(line) => {
            let row = DMatrix::from_row_slice(1, 6, &line);
            let t = complement_rows(&row.transpose());
            Some(
                (0..t.nrows())
                    .map(|i| t.row(i).iter().copied().collect())
                    .collect(),
            )
        }
    }
}

/// The constraint rows (B − k + driven) × B of joint `index` of `m` with `driven` DOF fixed, at
/// the random realization `seed`.
pub fn joint_rows(m: &Mechanism, index: usize, seed: u64, driven: u32) -> DMatrix<Fp> {
    let j = &m.joints[index];
    let b = m.b() as usize;
    let k = (j.kind.grade() as usize).min(b);
    let d = (driven as usize).min(k);
    // Its own stream, distinct from the floating-point realization's.
    let mut rng = SplitMix64::new(indexed_seed(seed ^ 0xE4AC_7F1E_1D00_0000, index));
    // Whether the twists have named DOF (format.md): a driven DOF of a kind without them is a
    // generic direction.
    let (all, named): (Vec<Vec<Fp>>, bool) = match twists(j.kind, m.space, &mut rng) {
        Some(t) if t.len() == k => (t, j.kind != JointType::SPSP),
        _ => {
            // Generic contact lines: B − k random rows; the allowed motions are their
            // annihilator.
            let rows = DMatrix::from_fn(b - k, b, |_, _| Fp::random_nonzero(&mut rng));
            let t = complement_rows(&rows.transpose());
            let t = (0..t.nrows())
                .map(|i| t.row(i).iter().copied().collect())
                .collect();
            (t, false)
        }
    };
    let tw = if named || d == 0 {
        let kept = &all[d.min(all.len())..];
        DMatrix::from_fn(b, kept.len(), |r, c| kept[c][r])
    } else {
        mixed(&all, d, b, &mut rng)
    };
    complement_rows(&tw)
}

/// `all.len() − d` random combinations of the twists `all` (columns, B rows): `all` mixed by a
/// random invertible matrix with its first `d` combinations dropped, a generic subspace of the
/// allowed motions. The echelon basis [`complement_rows`] gives has zeros in the free
/// coordinates, so dropping its first vectors kept a subspace fixed by the construction (the
/// floating-point model had the same flaw: `motion::kept_twists`). Dependent combinations
/// (probability about k/p) are drawn again; the fixed convention is the last resort.
fn mixed(all: &[Vec<Fp>], d: usize, b: usize, rng: &mut SplitMix64) -> DMatrix<Fp> {
    let k = all.len();
    let n = k.saturating_sub(d);
    for _ in 0..4 {
        let c = DMatrix::from_fn(k, n, |_, _| Fp::random(rng));
        let tw = DMatrix::from_fn(b, n, |r, col| {
            (0..k).map(|i| all[i][r] * c[(i, col)]).sum::<Fp>()
        });
        if rank(&tw) == n {
            return tw;
        }
    }
    let kept = &all[d.min(k)..];
    DMatrix::from_fn(b, kept.len(), |r, c| kept[c][r])
}

/// The exact rank of the constraint Jacobian of `m` (every binary pair hub→other of every
/// joint, frame fixed, B columns per movable body) at the random realization `seed`, with its
/// number of rows and columns.
pub fn jacobian_rank(m: &Mechanism, seed: u64) -> (usize, usize, usize) {
    let b = m.b() as usize;
    let nb = m.bodies.len();
    let mut col = vec![usize::MAX; nb];
    let mut ncols = 0;
    for (x, c) in col.iter_mut().enumerate() {
        if x != m.frame {
            *c = ncols;
            ncols += b;
        }
    }
    let mut a = SparseMatrix::with_groups(vec![b; nb.saturating_sub(1)]);
    for (ji, j) in m.joints.iter().enumerate() {
        let rows = joint_rows(m, ji, seed, j.driven);
        let Some((&hub, others)) = j.bodies.split_first() else {
            continue;
        };
        for &o in others {
            for r in 0..rows.nrows() {
                let mut entries: Vec<(u32, Fp)> = Vec::with_capacity(2 * b);
                for (x, sign) in [(hub, true), (o, false)] {
                    if col[x] == usize::MAX {
                        continue;
                    }
                    for k in 0..b {
                        let v = rows[(r, k)];
                        entries.push((
                            (col[x] + k) as u32,
                            if sign { Fp::from_u64(0) - v } else { v },
                        ));
                    }
                }
                a.push_row(entries);
            }
        }
    }
    let rows = a.nrows();
    let rank = Factor::new(&a).rank();
    (rank, rows, ncols)
}

/// The exact rank of the rows of some pairs `(joint, hub, other)` (`rows[joint]` acting on the
/// twist of `other` minus that of `hub`), with B columns for each body `group` numbers
/// (`0..ngroups`) and none for the others (held fixed).
pub fn pairs_rank(
    b: usize,
    ngroups: usize,
    rows: &[DMatrix<Fp>],
    pairs: impl Iterator<Item = (usize, usize, usize)>,
    group: impl Fn(usize) -> Option<usize>,
) -> usize {
    let a = pairs_matrix(b, ngroups, rows, pairs, group);
    if a.nrows() == 0 {
        0
    } else {
        Factor::new(&a).rank()
    }
}

/// The rows of some pairs as in [`pairs_rank`]: B columns per group, one row per row of each
/// pair's joint.
pub fn pairs_matrix(
    b: usize,
    ngroups: usize,
    rows: &[DMatrix<Fp>],
    pairs: impl Iterator<Item = (usize, usize, usize)>,
    group: impl Fn(usize) -> Option<usize>,
) -> SparseMatrix {
    let mut a = SparseMatrix::with_groups(vec![b; ngroups]);
    for (joint, hub, other) in pairs {
        let r = &rows[joint];
        let (gh, go) = (group(hub), group(other));
        if hub == other || (gh.is_none() && go.is_none()) {
            continue;
        }
        for i in 0..r.nrows() {
            let mut entries: Vec<(u32, Fp)> = Vec::with_capacity(2 * b);
            for (g, sign) in [(gh, true), (go, false)] {
                let Some(g) = g else { continue };
                for k in 0..b {
                    let v = r[(i, k)];
                    entries.push(((g * b + k) as u32, if sign { -v } else { v }));
                }
            }
            a.push_row(entries);
        }
    }
    a
}

/// The exact factorization behind [`pairs_rank`] (`None` when the pairs give no row), within
/// `limits`: its rank, and random vectors of its null space (the motions, B columns per group
/// in group order) through [`Factor::random_null_vectors`]. With `track`, it also keeps what
/// [`pairs_stress_support_from`] needs (the self-stresses from the same factorization).
pub fn pairs_factor(
    b: usize,
    ngroups: usize,
    rows: &[DMatrix<Fp>],
    pairs: impl Iterator<Item = (usize, usize, usize)>,
    group: impl Fn(usize) -> Option<usize>,
    track: bool,
    limits: &mut Limits<'_>,
) -> Result<Option<Factor>, BudgetExceeded> {
    let pairs: Vec<(usize, usize, usize)> = pairs.collect();
    if let Some(p) = PairRows::new(b, ngroups, rows, &pairs, &group) {
        if p.nrows() == 0 {
            return Ok(None);
        }
        return Factor::from_rows_within(&p, track, limits).map(Some);
    }
    let a = pairs_matrix(b, ngroups, rows, pairs.into_iter(), group);
    if a.nrows() == 0 {
        return Ok(None);
    }
    Factor::from_matrix_within(a, track, limits).map(Some)
}

/// The rows of [`pairs_matrix`] made one at a time from the pairs and their joints' rows
/// (16 bytes a pair and 4 a row instead of a vector a row): the same rows, in the same
/// order, with the same entries.
struct PairRows<'a> {
    b: usize,
    ngroups: usize,
    rows: &'a [DMatrix<Fp>],
    /// Per pair giving rows: its joint, the hub's and the other body's groups ([`NO_GROUP`]
    /// for none), and its first row.
    pairs: Vec<[u32; 4]>,
    /// The pair (index into `pairs`) of each row.
    owner: Vec<u32>,
}

/// A body without a column group (held fixed) in [`PairRows`].
const NO_GROUP: u32 = u32::MAX;

impl<'a> PairRows<'a> {
    /// `None` where the compact form does not fit (indices beyond `u32`, a group out of
    /// range: [`pairs_matrix`]'s own check then reports it).
    fn new(
        b: usize,
        ngroups: usize,
        rows: &'a [DMatrix<Fp>],
        pairs: &[(usize, usize, usize)],
        group: &impl Fn(usize) -> Option<usize>,
    ) -> Option<PairRows<'a>> {
        let small = |x: usize| u32::try_from(x).ok().filter(|&x| x != NO_GROUP);
        small(ngroups.checked_mul(b)?)?;
        let mut kept = Vec::new();
        let mut nrows = 0usize;
        for &(joint, hub, other) in pairs {
            let (gh, go) = (group(hub), group(other));
            if hub == other || (gh.is_none() && go.is_none()) {
                continue;
            }
            let g = |x: Option<usize>| match x {
                None => Some(NO_GROUP),
                Some(x) if x < ngroups => small(x),
                Some(_) => None,
            };
            let r = rows.get(joint)?;
            if r.nrows() > 0 && r.ncols() < b {
                return None;
            }
            kept.push([small(joint)?, g(gh)?, g(go)?, small(nrows)?]);
            nrows += r.nrows();
        }
        small(nrows)?;
        let mut owner = Vec::with_capacity(nrows);
        for (k, p) in kept.iter().enumerate() {
            owner.extend(std::iter::repeat_n(k as u32, rows[p[0] as usize].nrows()));
        }
        Some(PairRows {
            b,
            ngroups,
            rows,
            pairs: kept,
            owner,
        })
    }
}

impl Rows for PairRows<'_> {
    fn ncols(&self) -> usize {
        self.ngroups * self.b
    }
    fn nrows(&self) -> usize {
        self.owner.len()
    }
    fn group_sizes(&self) -> Vec<usize> {
        vec![self.b; self.ngroups]
    }
    /// As `push_row` leaves the row [`pairs_matrix`] pushes: the hub's entries negated,
    /// the two groups' columns in increasing order, zeros dropped; on one group twice the
    /// two entries of each column cancel.
    fn row<'b>(&'b self, i: usize, buf: &'b mut SparseRow) -> &'b [(u32, Fp)] {
        buf.clear();
        let [joint, gh, go, first] = self.pairs[self.owner[i] as usize];
        if gh == go {
            return buf;
        }
        let r = &self.rows[joint as usize];
        let ri = i - first as usize;
        let mut sides = [(gh, true), (go, false)];
        if go < gh {
            sides.swap(0, 1);
        }
        for (g, hub) in sides {
            if g == NO_GROUP {
                continue;
            }
            for k in 0..self.b {
                let v = r[(ri, k)];
                let v = if hub { -v } else { v };
                if !v.is_zero() {
                    buf.push((g * self.b as u32 + k as u32, v));
                }
            }
        }
        buf
    }
}

/// The pairs carrying the self-stresses (the left null space) of the rows of some pairs, from
/// their tracked factorization `f` ([`pairs_factor`] with `track`; `None` for no rows): a
/// flag per pair, set when a random self-stress is nonzero on one of its rows (every
/// self-stress has its support within these pairs; a random one reaches all of them except
/// with probability at most (rows)/p). A pair that gives the matrix no row (its bodies both
/// held fixed, or one body twice) constrains nothing that moves: each of its rows is a
/// self-stress of its own. Cost: one pass over the factorization's trace
/// ([`Factor::random_left_null_vector`]), charged to `meter`; the transpose is never factored.
///
/// `None` when `f` was not tracked.
#[allow(clippy::too_many_arguments)]
pub fn pairs_stress_support_from(
    f: Option<&Factor>,
    rows: &[DMatrix<Fp>],
    pairs: &[(usize, usize, usize)],
    group: impl Fn(usize) -> Option<usize>,
    seed: u64,
    meter: &mut crate::budget::Meter,
) -> Result<Option<Vec<bool>>, BudgetExceeded> {
    let mut rng = crate::rng::SplitMix64::new(seed);
    let y = match f {
        Some(f) => {
            meter.charge(f.trace_len() as u64)?;
            match f.random_left_null_vector(&mut rng) {
                Some(y) => y,
                None => return Ok(None),
            }
        }
        None => Vec::new(),
    };
    // The rows of each pair in the matrix, in the order `pairs_matrix` pushes them.
    let mut at = 0usize;
    let out = pairs
        .iter()
        .map(|&(joint, hub, other)| {
            let n = rows[joint].nrows();
            if hub == other || (group(hub).is_none() && group(other).is_none()) {
                return n > 0;
            }
            let s = y
                .get(at..at + n)
                .is_some_and(|s| s.iter().any(|v| !v.is_zero()));
            at += n;
            s
        })
        .collect();
    Ok(Some(out))
}

/// The same flags as [`pairs_stress_support_from`] by the factorization of the transpose
/// (the pairs' rows as unknowns, grouped by pair; one equation per body column), within
/// `limits`: the reference the tests compare with. Not used by the analysis: the transpose
/// is over-determined (a body's B equations against the fewer rows of its pairs), so its
/// block triangular order is one tier and the greedy order fills in (10^5 random spatial
/// bodies: minutes, several GB).
pub fn pairs_stress_support(
    b: usize,
    rows: &[DMatrix<Fp>],
    pairs: &[(usize, usize, usize)],
    group: impl Fn(usize) -> Option<usize>,
    ngroups: usize,
    seed: u64,
    limits: &mut Limits<'_>,
) -> Result<Vec<bool>, BudgetExceeded> {
    let sizes: Vec<usize> = pairs.iter().map(|&(j, _, _)| rows[j].nrows()).collect();
    let mut off = Vec::with_capacity(sizes.len());
    let mut acc = 0u32;
    for &s in &sizes {
        off.push(acc);
        acc += s as u32;
    }
    // Column (g, k) of the Jacobian: the entries of every row touching it.
    let mut cols: Vec<Vec<(u32, Fp)>> = vec![Vec::new(); ngroups * b];
    for (pi, &(joint, hub, other)) in pairs.iter().enumerate() {
        if hub == other {
            continue;
        }
        let r = &rows[joint];
        for (x, sign) in [(hub, true), (other, false)] {
            let Some(g) = group(x) else { continue };
            for i in 0..r.nrows() {
                for k in 0..b {
                    let v = r[(i, k)];
                    if !v.is_zero() {
                        cols[g * b + k].push((off[pi] + i as u32, if sign { -v } else { v }));
                    }
                }
            }
        }
    }
    let mut t = SparseMatrix::with_groups(sizes.clone());
    for c in cols {
        let mut c = c;
        c.sort_unstable_by_key(|e| e.0);
        t.push_row(c);
    }
    let f = Factor::new_within(&t, limits)?;
    if f.nullity() == 0 {
        return Ok(vec![false; pairs.len()]);
    }
    let mut rng = crate::rng::SplitMix64::new(seed);
    limits
        .meter
        .charge(f.stats().factor_entries as u64 + f.ncols() as u64)?;
    let y = f.random_null_vectors(1, &mut rng).pop().unwrap_or_default();
    Ok((0..pairs.len())
        .map(|pi| {
            let o = off[pi] as usize;
            y.get(o..o + sizes[pi])
                .is_some_and(|s| s.iter().any(|v| !v.is_zero()))
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanism::{BodyId, JointSpec};

    #[test]
    fn every_kind_has_its_number_of_rows() {
        for space in [Space::Spatial, Space::Planar, Space::Spherical] {
            let b = space.b() as usize;
            for kind in JointType::all() {
                if kind.grade() as usize > b {
                    continue;
                }
                let m = Mechanism::from_parts(
                    "t",
                    space,
                    BodyId::Int(1),
                    vec![],
                    vec![JointSpec::new(kind, 1, 2, 0)],
                );
                let r = joint_rows(&m, 0, 7, 0);
                assert_eq!(r.nrows(), b - kind.grade() as usize, "{kind:?} {space:?}");
            }
        }
    }

    /// A driven DOF of a kind without named DOF keeps a generic direction: Formerly
    /// the echelon null basis lost its first vector, so the twist kept had a zero in a free
    /// coordinate at every draw (a planar contact joint driven once: never a turn about the
    /// origin, or never a slide along x). Nothing driven gives the rows as before.
    #[test]
    fn driven_dof_without_a_name_is_generic() {
        for (kind, space) in [
            (JointType::EO, Space::Planar),
            (JointType::RP, Space::Planar),
            (JointType::SPSP, Space::Spatial),
            (JointType::CTEP, Space::Spatial),
        ] {
            let b = space.b() as usize;
            let k = kind.grade() as usize;
            let m = Mechanism::from_parts(
                "t",
                space,
                BodyId::Int(1),
                vec![],
                vec![JointSpec::new(kind, 1, 2, 0)],
            );
            for seed in 0..20 {
                let free = joint_rows(&m, 0, seed, 0);
                assert_eq!(free.nrows(), b - k);
                for d in 1..=k as u32 {
                    let rows = joint_rows(&m, 0, seed, d);
                    assert_eq!(rows.nrows(), b - k + d as usize, "{kind:?}");
                    assert_eq!(rows, joint_rows(&m, 0, seed, d), "deterministic");
                    // The driven model keeps the free rows' constraints.
                    let both = DMatrix::from_fn(rows.nrows() + free.nrows(), b, |i, c| {
                        if i < rows.nrows() {
                            rows[(i, c)]
                        } else {
                            free[(i - rows.nrows(), c)]
                        }
                    });
                    assert_eq!(rank(&both), rows.nrows(), "{kind:?}");
                }
                // One DOF left: the twist kept (the null space of the rows) has no zero
                // coordinate.
                let rows = joint_rows(&m, 0, seed, k as u32 - 1);
                let t = complement_rows(&rows.transpose());
                assert_eq!(t.nrows(), 1);
                assert!(
                    t.iter().all(|x| !x.is_zero()),
                    "{kind:?} seed {seed}: {t:?}"
                );
            }
        }
    }

    /// A random mechanism's joint rows at realization `rseed`, its pairs `(joint, hub,
    /// other)`, and a group per body with the frame and body `frame + 1` held fixed (as a
    /// part's root is): `(mechanism, rows, pairs, group of each body, groups)`.
    #[allow(clippy::type_complexity)]
    fn random_pairs(
        n: u64,
        planar: bool,
        seed: u64,
        rseed: u64,
    ) -> (
        Mechanism,
        Vec<DMatrix<Fp>>,
        Vec<(usize, usize, usize)>,
        Vec<Option<usize>>,
        usize,
    ) {
        let (m, _) = crate::generate::random(n, planar, seed).expect("generates");
        let rows: Vec<DMatrix<Fp>> = (0..m.joints.len())
            .map(|ji| joint_rows(&m, ji, rseed, m.joints[ji].driven))
            .collect();
        let mut pairs = Vec::new();
        for (ji, j) in m.joints.iter().enumerate() {
            if let Some((&hub, others)) = j.bodies.split_first() {
                pairs.extend(others.iter().map(|&o| (ji, hub, o)));
            }
        }
        let fixed = (m.frame + 1) % m.bodies.len();
        let mut local = vec![None; m.bodies.len()];
        let mut ng = 0;
        for (x, l) in local.iter_mut().enumerate() {
            if x != m.frame && x != fixed {
                *l = Some(ng);
                ng += 1;
            }
        }
        (m, rows, pairs, local, ng)
    }

    /// [`pairs_factor`] of `pairs` with `track` (what both the stress support and the
    /// comparison with [`pairs_matrix`] need), within `limits`, which the tests size to fit.
    fn tracked_factor(
        b: usize,
        ng: usize,
        rows: &[DMatrix<Fp>],
        pairs: &[(usize, usize, usize)],
        group: impl Fn(usize) -> Option<usize>,
        limits: &mut Limits<'_>,
    ) -> Option<Factor> {
        pairs_factor(b, ng, rows, pairs.iter().copied(), group, true, limits).expect("fits")
    }

    /// The rows [`PairRows`] makes one at a time are those [`pairs_matrix`] stores, row for
    /// row, and the factorization from them is the one from the matrix (rank, random null
    /// vectors drawn alike, which solve the matrix): on random mechanisms with a body held
    /// fixed, a pair on one body twice and two bodies sharing a group (rows that cancel).
    #[test]
    fn pair_rows_made_on_demand_are_the_matrix_rows() {
        let budget = crate::budget::Budget::UNLIMITED;
        let what = || "test".to_string();
        for (n, planar, seed) in [(40, false, 1), (90, true, 2), (200, false, 3)] {
            let (m, rows, mut pairs, local, ng) = random_pairs(n, planar, seed, 7);
            let b = m.b() as usize;
            pairs.insert(0, (0, 1, 1));
            for shared in [false, true] {
                let group = |x: usize| {
                    if shared && x == m.bodies.len() - 1 {
                        Some(0)
                    } else {
                        local[x]
                    }
                };
                let a = pairs_matrix(b, ng, &rows, pairs.iter().copied(), group);
                let p = PairRows::new(b, ng, &rows, &pairs, &group).expect("fits");
                assert_eq!((p.nrows(), p.ncols()), (a.nrows(), a.ncols));
                assert_eq!(p.group_sizes(), a.groups());
                let mut buf = Vec::new();
                for (i, r) in a.rows.iter().enumerate() {
                    assert_eq!(p.row(i, &mut buf), &r[..], "{n} {seed} row {i}");
                }
                let mut meter = budget.meter("test");
                let mut limits = Limits {
                    budget: &budget,
                    meter: &mut meter,
                    what: &what,
                };
                let f = tracked_factor(b, ng, &rows, &pairs, group, &mut limits).expect("rows");
                let g = Factor::from_matrix_within(a.clone(), true, &mut limits).expect("fits");
                assert_eq!((f.rank(), f.nullity()), (g.rank(), g.nullity()));
                let mut r1 = SplitMix64::new(seed);
                let mut r2 = SplitMix64::new(seed);
                let v = f.random_null_vectors(3, &mut r1);
                assert_eq!(v, g.random_null_vectors(3, &mut r2));
                for x in &v {
                    assert!(a.mul_dense(x).iter().all(|e| e.is_zero()));
                }
            }
        }
    }

    /// The self-stress support from the tracked Jacobian factorization equals the one from
    /// the transpose's factorization, on random mechanisms (spatial and planar) with a
    /// fixed body besides the frame (as a part's root is).
    #[test]
    fn stress_support_from_the_factorization_matches_the_transpose() {
        let budget = crate::budget::Budget::UNLIMITED;
        let what = || "test".to_string();
        let mut nonempty = 0;
        for (n, planar, seed) in [
            (60, false, 1),
            (120, false, 2),
            (150, true, 3),
            (300, false, 4),
        ] {
            let (m, rows, pairs, local, ng) = random_pairs(n, planar, seed, 9);
            let b = m.b() as usize;
            let group = |x: usize| local[x];
            let mut meter = budget.meter("test");
            let mut limits = Limits {
                budget: &budget,
                meter: &mut meter,
                what: &what,
            };
            let reference =
                pairs_stress_support(b, &rows, &pairs, group, ng, 5, &mut limits).expect("fits");
            let f = tracked_factor(b, ng, &rows, &pairs, group, &mut limits);
            let got = pairs_stress_support_from(f.as_ref(), &rows, &pairs, group, 6, &mut meter)
                .expect("fits")
                .expect("tracked");
            assert_eq!(got, reference, "{n} {planar} {seed}");
            nonempty += got.iter().filter(|&&s| s).count();
        }
        assert!(
            nonempty > 0,
            "no self-stress at all: the test shows nothing"
        );
    }

    #[test]
    fn planar_four_bar_in_space_has_generic_redundancy() {
        let j = |a, b| JointSpec::new(JointType::R, a, b, 0);
        let m = Mechanism::from_parts(
            "4R",
            Space::Spatial,
            BodyId::Int(1),
            vec![],
            vec![j(1, 2), j(2, 3), j(3, 4), j(4, 1)],
        );
        // Generic spatial 4R: 20 rows, 18 unknowns, rank 18.
        assert_eq!(jacobian_rank(&m, 3), (18, 20, 18));
    }

    /// The rank of the floating-point constraint Jacobian of `m` at its random realization
    /// `seed` ([`crate::motion::realize`]), by SVD: every binary pair hub→other, frame fixed.
    fn float_rank(m: &Mechanism, seed: u64) -> usize {
        let b = m.b() as usize;
        let models = crate::motion::realize(m, seed);
        let col = |x: usize| (x != m.frame).then(|| if x < m.frame { x } else { x - 1 } * b);
        let mut rows: Vec<Vec<f64>> = Vec::new();
        for (j, model) in m.joints.iter().zip(&models) {
            let Some((&hub, others)) = j.bodies.split_first() else {
                continue;
            };
            for &o in others {
                for r in 0..model.rows.nrows() {
                    let mut row = vec![0.0; b * (m.bodies.len() - 1)];
                    for (x, sign) in [(hub, -1.0), (o, 1.0)] {
                        if let Some(c) = col(x) {
                            (0..b).for_each(|k| row[c + k] += sign * model.rows[(r, k)]);
                        }
                    }
                    rows.push(row);
                }
            }
        }
        let a = DMatrix::from_fn(rows.len(), b * (m.bodies.len() - 1), |i, c| rows[i][c]);
        if a.nrows() == 0 { 0 } else { a.rank(1e-8) }
    }

    /// The exact models and the floating-point ones describe the same joints: at random
    /// geometry their Jacobians have the same rank, for closed loops of three joints of
    /// every kind in every space (driven or not) and for random mechanisms.
    #[test]
    fn exact_rank_is_the_floating_point_rank() {
        let mut compared = 0;
        for space in [Space::Spatial, Space::Planar, Space::Spherical] {
            let b = space.b() as usize;
            for kind in JointType::all() {
                if kind.grade() as usize > b || !kind.valid_in(space) {
                    continue;
                }
                for driven in [0, 1] {
                    let j = |a, c| JointSpec::new(kind, a, c, driven);
                    let m = Mechanism::from_parts(
                        "loop",
                        space,
                        BodyId::Int(1),
                        vec![],
                        vec![j(1, 2), j(2, 3), j(3, 1)],
                    );
                    for seed in 0..3 {
                        let (exact, _, _) = jacobian_rank(&m, seed);
                        assert_eq!(exact, float_rank(&m, seed), "{kind:?} {space:?} {driven}");
                        compared += 1;
                    }
                }
            }
        }
        for (n, planar, seed) in [(12, false, 1), (15, true, 2), (20, false, 3)] {
            let (m, _) = crate::generate::random(n, planar, seed).expect("generates");
            assert_eq!(jacobian_rank(&m, 5).0, float_rank(&m, 5), "{n} {planar}");
            compared += 1;
        }
        assert!(compared > 100, "{compared}");
    }
}
