//! The search's test of a partial placement at the file's geometry: the inputs placed so far
//! must be independent on the mechanism's motions there, or no placement that keeps them is
//! determined.
//!
//! The count sees every joint as generic. At the file's geometry a mechanism can have
//! motions the count does not see (a bar between two spherical joints spins; equations are
//! set aside), and there the count-valid placements and the determined ones part ways: the
//! search meets, in its order, long runs of placements whose first inputs already drive one
//! motion twice (Gepetto's `digit_like` leg: none of its first 500 count-valid placements is
//! determined). With `N` the motions (the null space of the constraint rows `J`), a placement
//! `P` is determined only if its inputs' rows on `N` are independent (`M_P = [J; R_P]` needs
//! full row rank), and a dependent subset stays dependent in every placement that holds it:
//! the search cuts the branch where the units it has fixed become dependent, so every
//! placement it reaches passes this test, which the rank check then confirms.

use crate::budget::{BudgetExceeded, Meter};
use crate::geometry::{GeometrySource, file_threshold, geometries};
use crate::mechanism::{Geometry, Mechanism};
use nalgebra::DMatrix;
use std::collections::HashMap;

/// The least threshold of a motion (a file whose numbers give no precision: rounding only).
const LEAST_THRESHOLD: f64 = 1e-8;

/// Branches a search with `--limit L` may cut, per placement of the limit (the Digit-like
/// leg cuts about 55 per placement it reaches).
const CUTS_PER_PLACEMENT: u64 = 4_096;

/// Columns (movable bodies × B) up to which the motions are computed (a dense SVD).
const MAX_COLUMNS: usize = 600;

/// The motions at the file's geometry and the rows of the placed units on them.
pub(super) struct Pruner {
    m_b: usize,
    /// The motions of each movable body, `B × k` (`None`: the frame).
    motion: Vec<Option<DMatrix<f64>>>,
    /// The isolated freedoms: (body, its twist, `B` numbers).
    spins: Vec<(usize, Vec<f64>)>,
    geoms: Vec<Geometry>,
    bodies: Vec<[usize; 2]>,
    /// A unit is dependent when its row keeps less than this norm once the rows of the units
    /// placed before it are taken out.
    tol: f64,
    /// Each (pair, unit)'s row on the motions, as the search asks for them.
    rows: HashMap<(usize, u32), Unit>,
    /// The units tested so far, in order, and the basis their rows span after each.
    placed: Vec<((usize, u32), usize)>,
    basis: Vec<Vec<f64>>,
    /// A unit whose row reads a spin by more than this moves it.
    spin_tol: f64,
    /// Branches cut so far.
    pub(super) cut: u64,
}

/// A [`Pruner`] made at the search's first choice, so that a search without one (a single
/// placement) never pays for the motions. What it cuts depends on the mechanism alone, not on
/// the analyses: shards, and parts placed apart, cut as the whole does.
pub(super) struct LazyPruner<'a> {
    m: &'a Mechanism,
    source: GeometrySource,
    precision: Option<f64>,
    unknowns: &'a [u32],
    state: Option<Option<Pruner>>,
    /// The work of making the motions (its own meter: the search holds its own).
    meter: Meter,
    /// The most branches cut before the search stops (`--limit` bounds the placements
    /// examined; a cut branch is not one, so this bounds the work between them).
    max_cuts: u64,
}

impl<'a> LazyPruner<'a> {
    pub(super) fn new(
        m: &'a Mechanism,
        source: GeometrySource,
        precision: Option<f64>,
        unknowns: &'a [u32],
        meter: Meter,
        limit: Option<usize>,
    ) -> LazyPruner<'a> {
        LazyPruner {
            m,
            source,
            precision,
            unknowns,
            state: None,
            meter,
            max_cuts: limit.map_or(u64::MAX, |l| {
                (l as u64).max(1).saturating_mul(CUTS_PER_PLACEMENT)
            }),
        }
    }

    /// The pruner, made at the first call; `None` when it does not apply (past its work budget
    /// too: the search then goes on uncut).
    pub(super) fn get(&mut self) -> Option<&mut Pruner> {
        if self.state.is_none() {
            let made = Pruner::of(
                self.m,
                self.source,
                self.precision,
                self.unknowns,
                &mut self.meter,
            );
            self.state = Some(made.ok().flatten());
        }
        self.state.as_mut().and_then(Option::as_mut)
    }

    /// Whether the search has cut as many branches as its limit allows: it stops there.
    pub(super) fn exhausted(&self) -> bool {
        self.cut() >= self.max_cuts
    }

    /// Branches cut so far.
    pub(super) fn cut(&self) -> u64 {
        self.state
            .as_ref()
            .and_then(Option::as_ref)
            .map_or(0, |p| p.cut)
    }

    /// The mechanism the pruner reads.
    pub(super) fn mechanism(&self) -> &'a Mechanism {
        self.m
    }
}

impl Pruner {
    /// The pruner of `m` (an expansion: binary pairs) at the geometry the rank check uses
    /// (`source`, `precision`) when it is the file's, or `None` when it does not apply (a
    /// random realization, a multiple joint, more than [`MAX_COLUMNS`] unknowns, no motion).
    /// The bodies with fewer `unknowns` than B are those whose isolated freedoms it reads.
    pub(super) fn of(
        m: &Mechanism,
        source: GeometrySource,
        precision: Option<f64>,
        unknowns: &[u32],
        meter: &mut Meter,
    ) -> Result<Option<Pruner>, BudgetExceeded> {
        let b = m.b() as usize;
        let reduced: Vec<usize> = (0..unknowns.len().min(m.bodies.len()))
            .filter(|&x| x != m.frame && (unknowns[x] as usize) < b)
            .collect();
        let ncols = m.bodies.len().saturating_sub(1) * b;
        if ncols == 0 || ncols > MAX_COLUMNS || m.joints.iter().any(|j| j.bodies.len() != 2) {
            return Ok(None);
        }
        let Ok((geoms, used)) = geometries(m, source, precision) else {
            return Ok(None);
        };
        // At a random realization the exact rank decides each placement at once (`Oracle`),
        // and the parts placed apart are analysed there: the search stays as it is.
        if used.seed.is_some() {
            return Ok(None);
        }
        // The rank check's threshold at the file's geometry, at least a dependence to
        // rounding.
        let thr = file_threshold(m, &used)
            .unwrap_or(LEAST_THRESHOLD)
            .max(LEAST_THRESHOLD);
        let bodies: Vec<[usize; 2]> = m
            .joints
            .iter()
            .map(|j| [j.bodies[0], j.bodies[1]])
            .collect();
        // A dense factorization of n unknowns costs n^3, as the rank check counts it.
        meter.charge((ncols * ncols * ncols) as u64)?;
        let Some(motion) = motions(m, &geoms, &bodies, thr) else {
            return Ok(None);
        };
        Ok(Some(Pruner {
            m_b: b,
            motion,
            spins: spins(m, &geoms, &bodies, &reduced, thr),
            geoms,
            bodies,
            // Far below the rank check's threshold: only a dependence it also finds cuts.
            tol: thr * 1e-2,
            rows: HashMap::new(),
            placed: Vec::new(),
            basis: Vec::new(),
            cut: 0,
            spin_tol: thr * 10.0,
        }))
    }

    /// Whether the units `units` (pair, units on it; each pair once, in the search's order)
    /// have independent rows on the motions. The units of the longest prefix tested before
    /// are not tested again.
    pub(super) fn independent(&mut self, m: &Mechanism, units: &[(usize, u32)]) -> bool {
        // The longest prefix of `units` already tested: its basis is kept.
        let mut keep = 0;
        let mut i = 0;
        while i < units.len() && keep < self.placed.len() {
            let (q, n) = units[i];
            // Pair `q`'s units were tested one at a time: `n` of them is `n` entries.
            let run = (1..=n).all(|d| {
                self.placed
                    .get(keep + d as usize - 1)
                    .is_some_and(|&(u, _)| u == (q, d))
            });
            if !run {
                break;
            }
            keep += n as usize;
            i += 1;
        }
        let len = if keep == 0 {
            0
        } else {
            self.placed[keep - 1].1
        };
        self.placed.truncate(keep);
        self.basis.truncate(len);
        for &(q, n) in &units[i..] {
            for d in 1..=n {
                if !self.add(m, q, d) {
                    self.cut += 1;
                    return false;
                }
            }
        }
        true
    }

    /// Add the `d`-th unit of pair `q`: its row on the motions, less the basis. `false`
    /// (nothing kept) when it adds no direction.
    fn add(&mut self, m: &Mechanism, q: usize, d: u32) -> bool {
        let mut v = match self.row_of(m, q, d) {
            Unit::Row(v) => v,
            Unit::Spin => return false,
            Unit::Unknown => {
                self.placed.push(((q, d), self.basis.len()));
                return true;
            }
        };
        for e in &self.basis {
            let s: f64 = v.iter().zip(e).map(|(a, b)| a * b).sum();
            v.iter_mut().zip(e).for_each(|(a, b)| *a -= s * b);
        }
        let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt();
        if norm <= self.tol {
            return false;
        }
        v.iter_mut().for_each(|a| *a /= norm);
        self.basis.push(v);
        self.placed.push(((q, d), self.basis.len()));
        true
    }

    /// The row of the `d`-th unit of pair `q` on the motions (`k` numbers): the one row its
    /// model with `d` units fixed has beyond its model with `d − 1` (the models the rank
    /// check builds), read on the relative motion of the pair's two bodies.
    fn row_of(&mut self, m: &Mechanism, q: usize, d: u32) -> Unit {
        if let Some(r) = self.rows.get(&(q, d)) {
            return r.clone();
        }
        let [x, y] = self.bodies[q];
        let with = crate::motion::pair_model(m, q, &self.geoms[q], d).rows;
        let before = crate::motion::pair_model(m, q, &self.geoms[q], d - 1).rows;
        // Both models' rows are orthonormal: the new one is the row of `with` that keeps the
        // most once the rows of `before` are taken out.
        let mut best: Option<(f64, Vec<f64>)> = None;
        for r in 0..with.nrows() {
            let mut u: Vec<f64> = with.row(r).iter().copied().collect();
            for p in 0..before.nrows() {
                let s: f64 = (0..u.len()).map(|k| u[k] * before[(p, k)]).sum();
                (0..u.len()).for_each(|k| u[k] -= s * before[(p, k)]);
            }
            let n = u.iter().map(|a| a * a).sum::<f64>().sqrt();
            if best.as_ref().is_none_or(|(bn, _)| n > *bn) {
                best = Some((n, u));
            }
        }
        let k = self.motion.iter().flatten().next().map_or(0, |t| t.ncols());
        let row = match best {
            Some((n, u))
                if n > 0.5
                    && self.spins.iter().any(|(z, t)| {
                        [x, y].contains(z)
                            && (0..self.m_b).map(|c| u[c] / n * t[c]).sum::<f64>().abs()
                                > self.spin_tol
                    }) =>
            {
                Unit::Spin
            }
            Some((n, u)) if n > 0.5 => Unit::Row(
                (0..k)
                    .map(|l| {
                        (0..self.m_b)
                            .map(|c| {
                                let at =
                                    |z: usize| self.motion[z].as_ref().map_or(0.0, |t| t[(c, l)]);
                                u[c] / n * (at(y) - at(x))
                            })
                            .sum()
                    })
                    .collect(),
            ),
            // No new row (a model that cannot take the unit): nothing is cut.
            _ => Unit::Unknown,
        };
        self.rows.insert((q, d), row.clone());
        row
    }
}

/// What one unit (pair, DOF) reads on the motions.
#[derive(Clone)]
enum Unit {
    /// Its row on the motions (`k` numbers).
    Row(Vec<f64>),
    /// It moves an isolated freedom: a placement that drives it is not determined.
    Spin,
    /// Its model gives no row of its own: never cut.
    Unknown,
}

/// Each movable body's motions (`B × k`; `None`: the frame): a basis of the null space of the
/// constraint rows of every pair (the frame fixed), the directions whose singular value is at
/// most `thr` (the rank check's threshold: the motions here hold every motion it sees).
/// `None` when there is none.
fn motions(
    m: &Mechanism,
    geoms: &[Geometry],
    bodies: &[[usize; 2]],
    thr: f64,
) -> Option<Vec<Option<DMatrix<f64>>>> {
    let b = m.b() as usize;
    let (col, ncols) = super::null_space::body_columns(m);
    let mut rows: Vec<Vec<f64>> = Vec::new();
    for (q, &[x, y]) in bodies.iter().enumerate().filter(|(_, p)| p[0] != p[1]) {
        let model = crate::motion::pair_model(m, q, &geoms[q], 0);
        for r in 0..model.rows.nrows() {
            let mut row = vec![0.0; ncols];
            for k in 0..b {
                let v = model.rows[(r, k)];
                if col[x] != usize::MAX {
                    row[col[x] + k] -= v;
                }
                if col[y] != usize::MAX {
                    row[col[y] + k] += v;
                }
            }
            rows.push(row);
        }
    }
    // Padded to square: the thin SVD of a wide matrix gives no basis of its null space.
    let n = rows.len().max(ncols);
    let j = DMatrix::from_fn(n, ncols, |i, k| rows.get(i).map_or(0.0, |r| r[k]));
    let svd = j.svd(false, true);
    let vt = svd.v_t?;
    let null: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] <= thr)
        .collect();
    if null.is_empty() {
        return None;
    }
    Some(
        col.iter()
            .map(|&c| {
                (c != usize::MAX)
                    .then(|| DMatrix::from_fn(b, null.len(), |k, l| vt[(null[l], c + k)]))
            })
            .collect(),
    )
}

/// The isolated freedoms of the `reduced` bodies (those the search gives fewer unknowns):
/// the motions of a body's pairs' rows with its neighbours held (a bar's spin between two
/// spherical joints), as (body, twist). The count leaves them out, so a unit that moves one
/// is spent on it.
fn spins(
    m: &Mechanism,
    geoms: &[Geometry],
    bodies: &[[usize; 2]],
    reduced: &[usize],
    thr: f64,
) -> Vec<(usize, Vec<f64>)> {
    let b = m.b() as usize;
    let mut out = Vec::new();
    for &x in reduced {
        let stacked: Vec<Vec<f64>> = (0..bodies.len())
            .filter(|&q| bodies[q].contains(&x) && bodies[q][0] != bodies[q][1])
            .flat_map(|q| {
                let r = crate::motion::pair_model(m, q, &geoms[q], 0).rows;
                (0..r.nrows())
                    .map(|i| r.row(i).iter().copied().collect::<Vec<f64>>())
                    .collect::<Vec<_>>()
            })
            .collect();
        let n = stacked.len().max(b);
        let a = DMatrix::from_fn(n, b, |i, k| stacked.get(i).map_or(0.0, |r| r[k]));
        let svd = a.svd(false, true);
        let Some(vt) = svd.v_t else {
            continue;
        };
        for i in (0..svd.singular_values.len()).filter(|&i| svd.singular_values[i] <= thr) {
            out.push((x, (0..b).map(|k| vt[(i, k)]).collect()));
        }
    }
    out
}
