//! The sparse floating-point path for large parts at the file's geometry.
//!
//! The dense path keeps every motion of a part as a dense orthonormal vector: `d` motions over
//! `n` unknowns cost `d² · n` to orthonormalize and `d · n` memory, then every two clusters are
//! compared over all motions. On a part with more than [`SPARSE_COLUMNS`] unknowns this path
//! instead:
//! 1. writes each body's twist about its own reference point (the mean of its joints' origins)
//!    instead of the world origin: `t_O = M(c) · t_c`, an invertible change of coordinates per
//!    body, so ranks, null spaces and self-stresses are the same, but the Jacobian's
//!    conditioning no longer grows with the square of the mechanism's size in bar lengths (a
//!    rotation about a pin 10^3 lengths from the origin is a velocity of 10^3 at the origin);
//! 2. factors the part's rows by the same block-sparse rank-revealing QR
//!    ([`Elimination`], greedy minimum-front order, column pivoting within each body) with
//!    the same threshold rule ([`threshold`]) applied to the re-expressed rows, except that
//!    the relative threshold's size factor is that of the largest front (at least
//!    [`SPARSE_COLUMNS`]), not the block's size: the rounding of a front's QR grows with the
//!    front, and a row of windows has singular values down to about `1/N` (a difference
//!    operator along the row), which `1e-9 · 6N` would cut at `N ≈ 10^4`;
//! 3. takes `B + 2` random motions (one back substitution each: every free column random)
//!    instead of the whole null space, and decides locked DOF and rigid clusters from them:
//!    each decision is about a linear map from the motions to one body's or one pair's twist,
//!    of rank at most `B`, which keeps its rank on `B` random vectors of its domain (almost
//!    surely); equal twists are found by sorting the bodies on a random projection of their
//!    sampled twists (no comparison of every two clusters);
//! 4. takes up to 8 random self-stresses (the same elimination on the transpose) for the
//!    joints' weights: the joints taking part are the same, the weights are estimates.
//!
//! Cost: the factorization (linear in the part for chains of windows, bounded by the fill of
//! the minimum-front order in general) plus `B + 2` back substitutions, then linear in the
//! part's pairs and bodies (sorting aside).

use super::analysis::ZERO_TOL;
use super::clusters::{Local, merge_across_joints, union_min};
use super::dense::{orthonormalize, small_null, small_rank};
use super::jacobian::{Complements, Pair, Part, eliminate, pair_block};
use super::threshold;
use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::elimination::{Block, Elimination, sigma_max};
use crate::geometry::GeometryUsed;
use crate::mechanism::Mechanism;
use crate::motion::{self, JointModel, Scale};
use nalgebra::{DMatrix, DVector};
use std::cell::Cell;
use std::collections::BTreeMap;

/// Parts with more unknowns than this are analysed by the sparse path at the file's geometry.
pub(super) const SPARSE_COLUMNS: usize = 1200;

/// File geometry with a joint origin farther than this from the centre, in characteristic
/// lengths ([`crate::motion::lever`] at the dimensionless geometry), takes the sparse path at
/// any size: its body-local twists keep the rank decisions that centre-based twists lose as
/// the lever arm grows (a long row of windows, in any unit). A compact linkage (a four-bar in
/// millimetres far from the world origin: lever 0.8) stays on the dense path, which the
/// dimensionless geometry keeps well conditioned.
pub(super) const FAR_LEVER: f64 = 10.0;

thread_local! {
    static SPARSE_FROM: Cell<usize> = const { Cell::new(SPARSE_COLUMNS) };
}

/// The part size (unknowns) above which the sparse path runs, on this thread.
pub(super) fn sparse_from() -> usize {
    SPARSE_FROM.with(|c| c.get())
}

/// Run `f` with the sparse path taken for parts of more than `columns` unknowns (0: every
/// part), on this thread; for tests comparing it with the dense path.
#[doc(hidden)]
pub fn with_sparse_from<R>(columns: usize, f: impl FnOnce() -> R) -> R {
    let old = SPARSE_FROM.with(|c| c.replace(columns));
    let out = f();
    SPARSE_FROM.with(|c| c.set(old));
    out
}

/// How many random motions beyond `B`.
const EXTRA_SAMPLES: usize = 2;
/// How many random self-stresses at most.
const STRESS_SAMPLES: usize = 8;

/// The reference point of a body: the mean of the origins of `joints` (none without one), at
/// the dimensionless geometry `scale` gives (the joint models' coordinates).
fn reference(
    m: &Mechanism,
    scale: &Scale,
    joints: impl Iterator<Item = usize>,
) -> Option<[f64; 3]> {
    let mut c = [0.0; 3];
    let mut n = 0.0;
    for j in joints {
        if let Some(o) = m.joints[j].geometry.origin.map(|p| scale.point(p)) {
            for i in 0..3 {
                c[i] += o[i];
            }
            n += 1.0;
        }
    }
    (n > 0.0).then(|| c.map(|x| x / n))
}

/// A body's fully isolated motions (orthonormal, world twists) from the stacked rows `a` of
/// its pairs ([`small_null`] at `rel`), checked about the body's own reference point: far
/// from the world origin, the rows of two pins of one bar differ by about 1/distance² and
/// [`small_null`] takes the bar's rotation about both pins for an isolated motion (the
/// N-four-bar from about 4,000 windows). When the count about the reference point (each
/// row scaled to unit norm) differs, that one is used, mapped back to world twists; else the
/// world one (unchanged reports).
pub(super) fn isolated(
    m: &Mechanism,
    scale: &Scale,
    a: &DMatrix<f64>,
    rel: f64,
    joints: impl Iterator<Item = usize>,
) -> DMatrix<f64> {
    let world = small_null(a, rel);
    let Some(s) = reference(m, scale, joints).and_then(|c| motion::twist_shift(m.space, c)) else {
        return world;
    };
    let mut local = a * &s;
    for mut row in local.row_iter_mut() {
        let n = row.norm();
        if n > 0.0 {
            row.unscale_mut(n);
        }
    }
    let near = small_null(&local, rel);
    if near.ncols() == world.ncols() {
        return world;
    }
    let cols = orthonormalize((&s * &near).column_iter().map(|c| c.into_owned()).collect());
    if cols.is_empty() {
        DMatrix::zeros(a.ncols(), 0)
    } else {
        DMatrix::from_columns(&cols)
    }
}

/// One part for the sparse path (the fields mirror the dense path's locals).
pub(super) struct SparsePart<'a> {
    pub m: &'a Mechanism,
    pub part: &'a Part,
    pub pairs: &'a [Pair],
    pub models: &'a [JointModel],
    pub comp: &'a Complements,
    pub iso: &'a [DMatrix<f64>],
    pub b: usize,
    pub used: &'a GeometryUsed,
    /// The size entering the relative tolerance (max(rows, unknowns) of the mechanism).
    pub ntol: usize,
    /// σ_max of the mechanism in world coordinates (the report's scale).
    pub smax: f64,
    /// The part's groups (bodies with unknowns), their sizes and offsets.
    pub groups: &'a [usize],
    pub sizes: &'a [usize],
}

/// What the part adds to the report.
pub(super) struct SparseOut {
    pub rank: usize,
    /// Smallest pivot kept and largest dropped, on the report's scale (× σ_max / σ_max,local).
    pub kept_min: f64,
    pub dropped_max: f64,
    /// Largest ‖yᵀA‖ of the unit self-stresses y the weights come from, on the report's scale
    /// (as the pivots): 0 without self-stresses.
    pub stress_residual: f64,
}

impl SparsePart<'_> {
    /// The shift of `body`'s twist when it has every DOF as unknowns (no isolated motion).
    fn body_shift(&self, body: usize, incident: &[usize]) -> Option<DMatrix<f64>> {
        if self.iso[body].ncols() > 0 || self.comp[body].ncols() != self.b {
            return None;
        }
        let scale = self.used.scale.unwrap_or(Scale::IDENTITY);
        let c = reference(
            self.m,
            &scale,
            incident.iter().map(|&pi| self.pairs[pi].joint),
        )?;
        motion::twist_shift(self.m.space, c)
    }

    /// The analysis of the part: its rank; locked DOF added to `locked`, self-stress weights
    /// to `w`, rigid clusters merged into `uf`.
    pub(super) fn run(
        &self,
        budget: &Budget,
        meter: &mut Meter,
        w: &mut BTreeMap<usize, f64>,
        locked: &mut BTreeMap<usize, usize>,
        uf: &mut [usize],
    ) -> Result<SparseOut, BudgetExceeded> {
        let (part, b) = (self.part, self.b);
        let mut lgroup: BTreeMap<usize, usize> = BTreeMap::new();
        for (g, &x) in self.groups.iter().enumerate() {
            lgroup.insert(x, g);
        }
        let shifts = self.shifts();
        // The block of pair `pi` on `body`, in the body's local coordinates.
        let local_block = |pi: usize, body: usize| {
            let blk = pair_block(self.pairs, self.models, self.comp, pi, body);
            match lgroup.get(&body).and_then(|&g| shifts[g].as_ref()) {
                Some(s) => blk * s,
                None => blk,
            }
        };
        meter.charge((part.pairs.len() * b * b * 8) as u64)?;
        let (blocks, rownorm) = self.scaled_blocks(&lgroup, &local_block);
        let mut offsets = Vec::with_capacity(self.sizes.len());
        let mut acc = 0;
        for &s in self.sizes {
            offsets.push(acc);
            acc += s;
        }
        let lcols = acc;
        let smax_l = sigma_max(self.sizes, &offsets, &blocks);
        let (elim, abs_tol) = self.factor(blocks, smax_l, budget, meter)?;
        let rank = elim.rank;
        let (kept, dropped) = (elim.kept_min, elim.dropped_max);
        let scale = if smax_l > 0.0 {
            self.smax / smax_l
        } else {
            1.0
        };
        let (tw, k) =
            self.sampled_twists(elim, &lgroup, &shifts, &offsets, lcols, budget, meter)?;

        let scaled_block = |pi: usize, body: usize| {
            let mut blk = local_block(pi, body);
            if let Some(norms) = rownorm.get(&pi) {
                for (i, &n) in norms.iter().enumerate() {
                    blk.row_mut(i).unscale_mut(n);
                }
            }
            blk
        };
        let unscale = |pi: usize, i: usize| rownorm.get(&pi).map_or(1.0, |v| v[i]);
        let stress_residual = self.stresses(
            &lgroup,
            &scaled_block,
            &unscale,
            abs_tol,
            rank,
            budget,
            meter,
            w,
        )?;
        self.locked_sampled(&tw, k, meter, locked)?;
        self.clusters_sampled(&tw, k, meter, uf)?;
        Ok(SparseOut {
            rank,
            kept_min: kept * scale,
            dropped_max: dropped * scale,
            stress_residual: stress_residual * scale,
        })
    }

    /// The part's index of each body.
    fn lidx(&self, x: usize) -> usize {
        self.part.bodies.binary_search(&x).unwrap_or(0)
    }

    /// Each group's shift to its body's local coordinates (from the pairs of each of the
    /// part's bodies).
    fn shifts(&self) -> Vec<Option<DMatrix<f64>>> {
        let (part, pairs) = (self.part, self.pairs);
        let mut inc: Vec<Vec<usize>> = vec![Vec::new(); part.bodies.len()];
        for &pi in &part.pairs {
            let p = pairs[pi];
            inc[self.lidx(p.hub)].push(pi);
            if p.other != p.hub {
                inc[self.lidx(p.other)].push(pi);
            }
        }
        self.groups
            .iter()
            .map(|&x| self.body_shift(x, &inc[self.lidx(x)]))
            .collect()
    }

    /// The part's row blocks in local coordinates, each row scaled to unit norm over the
    /// pair's columns (a rotation's rows about a far pin shrink to about 1/distance once
    /// written about a near point): same rank and null space; a self-stress y of the scaled
    /// rows is D·y' of the original ones. With each pair's row norms.
    #[allow(clippy::type_complexity)]
    fn scaled_blocks(
        &self,
        lgroup: &BTreeMap<usize, usize>,
        local_block: &dyn Fn(usize, usize) -> DMatrix<f64>,
    ) -> (Vec<Block>, BTreeMap<usize, Vec<f64>>) {
        let mut rownorm: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
        let mut blocks = Vec::new();
        for &pi in &self.part.pairs {
            let p = self.pairs[pi];
            let mut bodies: Vec<usize> = [p.hub, p.other]
                .into_iter()
                .filter(|x| lgroup.contains_key(x))
                .collect();
            bodies.sort_by_key(|x| lgroup.get(x).copied());
            bodies.dedup();
            let r = self.models[p.joint].rows.nrows();
            if bodies.is_empty() || r == 0 {
                continue;
            }
            let width: usize = bodies.iter().map(|&x| self.comp[x].ncols()).sum();
            let mut mat = DMatrix::zeros(r, width);
            let mut c = 0;
            for &x in &bodies {
                let blk = local_block(pi, x);
                mat.view_mut((0, c), (r, blk.ncols())).copy_from(&blk);
                c += blk.ncols();
            }
            let norms: Vec<f64> = (0..r)
                .map(|i| {
                    let n = mat.row(i).norm();
                    if n > 0.0 { n } else { 1.0 }
                })
                .collect();
            for (i, &n) in norms.iter().enumerate() {
                mat.row_mut(i).unscale_mut(n);
            }
            rownorm.insert(pi, norms);
            blocks.push(Block {
                groups: bodies
                    .iter()
                    .filter_map(|x| lgroup.get(x).copied())
                    .collect(),
                mat,
            });
        }
        (blocks, rownorm)
    }

    /// The part's elimination and its threshold. The relative threshold's size factor: that
    /// of the largest dense factorization done (a front), at least the dense path's largest
    /// whole Jacobian (SPARSE_COLUMNS), not the block's whole size (module docs).
    fn factor(
        &self,
        blocks: Vec<Block>,
        smax_l: f64,
        budget: &Budget,
        meter: &mut Meter,
    ) -> Result<(Elimination, f64), BudgetExceeded> {
        let mut ntol = self.ntol.min(SPARSE_COLUMNS);
        let (_, mut abs_tol) = threshold(self.m, self.used, smax_l, ntol);
        let nv = self.part.bodies.len() as u64;
        let mut elim = eliminate(self.sizes, blocks.clone(), abs_tol, budget, nv, meter)?;
        let front = elim.max_front();
        if front > ntol && ntol < self.ntol {
            ntol = front.min(self.ntol);
            abs_tol = threshold(self.m, self.used, smax_l, ntol).1;
            elim = eliminate(self.sizes, blocks, abs_tol, budget, nv, meter)?;
        }
        Ok((elim, abs_tol))
    }

    /// Random motions and each body's twist (world coordinates) over them, each motion
    /// scaled to unit norm over the part's unknowns; and their number.
    #[allow(clippy::too_many_arguments)]
    fn sampled_twists(
        &self,
        elim: Elimination,
        lgroup: &BTreeMap<usize, usize>,
        shifts: &[Option<DMatrix<f64>>],
        offsets: &[usize],
        lcols: usize,
        budget: &Budget,
        meter: &mut Meter,
    ) -> Result<(Vec<DMatrix<f64>>, usize), BudgetExceeded> {
        let (part, b) = (self.part, self.b);
        let nl = part.bodies.len();
        let nv = nl as u64;
        let d = lcols.saturating_sub(elim.rank);
        let k = d.min(b + EXTRA_SAMPLES);
        budget.check_memory(
            ((lcols + nl * b) as u64)
                .saturating_mul(k as u64)
                .saturating_mul(8),
            || {
                format!(
                    "the geometric rigidity analysis ({k} sampled motions over {lcols} unknowns \
                     in one rigid block of {nv} bodies)"
                )
            },
        )?;
        meter.charge(elim.factor_entries().saturating_mul(k as u64 + 1))?;
        let seed = part.pairs.first().copied().unwrap_or(0) as u64;
        let x = elim.random_null_vectors(k, 0x7370_6172_7365 ^ seed);
        drop(elim);
        let mut tw: Vec<DMatrix<f64>> = vec![DMatrix::zeros(b, k); nl];
        for (li, &body) in part.bodies.iter().enumerate() {
            if let Some(&g) = lgroup.get(&body) {
                let xg = x.rows(offsets[g], self.sizes[g]);
                tw[li] = match &shifts[g] {
                    Some(s) => s * xg,
                    None => &self.comp[body] * xg,
                };
            }
        }
        drop(x);
        for j in 0..k {
            let n2: f64 = tw.iter().map(|t| t.column(j).norm_squared()).sum();
            if n2 > 0.0 {
                let n = n2.sqrt();
                for t in &mut tw {
                    t.column_mut(j).unscale_mut(n);
                }
            }
        }
        Ok((tw, k))
    }

    /// Locked DOF per joint: allowed dimension minus the rank of the relative twist over the
    /// `k` sampled motions, with both bodies' own isolated motions.
    fn locked_sampled(
        &self,
        tw: &[DMatrix<f64>],
        k: usize,
        meter: &mut Meter,
        locked: &mut BTreeMap<usize, usize>,
    ) -> Result<(), BudgetExceeded> {
        let (part, pairs, b) = (self.part, self.pairs, self.b);
        meter.charge((part.pairs.len() as u64).saturating_mul((b * b * (k + 2 * b)) as u64))?;
        for &pi in &part.pairs {
            let p = pairs[pi];
            let (th, to) = (&tw[self.lidx(p.hub)], &tw[self.lidx(p.other)]);
            let mut cols: Vec<DVector<f64>> = (0..k).map(|j| to.column(j) - th.column(j)).collect();
            for body in [p.hub, p.other] {
                for c in self.iso[body].column_iter() {
                    cols.push(c.into_owned());
                }
            }
            let used = if cols.is_empty() {
                0
            } else {
                small_rank(&DMatrix::from_columns(&cols), ZERO_TOL)
            };
            let allowed = self.models[p.joint].twists.ncols();
            *locked.entry(p.joint).or_insert(0) += allowed.saturating_sub(used);
        }
        Ok(())
    }

    /// Rigid clusters: bodies whose twists agree (modulo their own isolated motions) on
    /// every sampled motion: within ZERO_TOL · sqrt(k) over the k unit samples (a difference
    /// within ZERO_TOL over an orthonormal basis of the motions, the dense rule, is within
    /// that on any k unit motions). Merged into `uf`.
    fn clusters_sampled(
        &self,
        tw: &[DMatrix<f64>],
        k: usize,
        meter: &mut Meter,
        uf: &mut [usize],
    ) -> Result<(), BudgetExceeded> {
        let (part, pairs, b) = (self.part, self.pairs, self.b);
        let nl = part.bodies.len();
        let lidx = |x: usize| self.lidx(x);
        let same_tol = ZERO_TOL * (k.max(1) as f64).sqrt();
        let iso_of = |li: usize| &self.iso[part.bodies[li]];
        let same = |x: usize, y: usize| {
            let diff = &tw[x] - &tw[y];
            let cols: Vec<DVector<f64>> = iso_of(x)
                .column_iter()
                .chain(iso_of(y).column_iter())
                .map(|c| c.into_owned())
                .collect();
            let mut res = diff;
            for qv in &orthonormalize(cols) {
                let proj = qv * (qv.transpose() * &res);
                res -= proj;
            }
            res.norm() <= same_tol
        };
        let mut cl = Local::new((0..nl).map(|x| iso_of(x).ncols()).collect());
        meter.charge((part.pairs.len() as u64).saturating_mul((b * b * k + 64) as u64))?;
        for &pi in &part.pairs {
            let p = pairs[pi];
            cl.join_if(lidx(p.hub), lidx(p.other), &same);
        }
        let reps: Vec<usize> = (0..nl).filter(|&x| cl.root(x) == x).collect();
        self.merge_plain(&reps, tw, k, same_tol, &same, &mut cl, meter)?;
        // Representatives with isolated motions: compared with the clusters sharing a joint
        // with them (as the exact path does), until nothing changes.
        if reps.iter().any(|&x| cl.has_iso(x)) {
            merge_across_joints(part, self.pairs, &lidx, &mut cl, same, meter)?;
        }
        for x in 0..nl {
            let r = cl.root(x);
            if r != x {
                union_min(uf, part.bodies[r], part.bodies[x]);
            }
        }
        Ok(())
    }

    /// Representatives `reps` without isolated motions of their own: sorted on a random
    /// projection of their sampled twists; equal twists project within `same_tol`, and those
    /// `same` says move alike are joined in `luf`.
    #[allow(clippy::too_many_arguments)]
    fn merge_plain(
        &self,
        reps: &[usize],
        tw: &[DMatrix<f64>],
        k: usize,
        same_tol: f64,
        same: &dyn Fn(usize, usize) -> bool,
        cl: &mut Local,
        meter: &mut Meter,
    ) -> Result<(), BudgetExceeded> {
        let b = self.b;
        let seed = self.part.pairs.first().copied().unwrap_or(0) as u64;
        let mut rng = crate::rng::SplitMix64::new(0x0063_6c75_7374_6572 ^ seed);
        let mut dir: Vec<f64> = (0..b * k).map(|_| rng.next_signed()).collect();
        let dn = dir
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt()
            .max(f64::MIN_POSITIVE);
        for v in &mut dir {
            *v /= dn;
        }
        let proj = |li: usize| -> f64 { tw[li].iter().zip(&dir).map(|(a, c)| a * c).sum() };
        // Each cluster by its representative's twists.
        let mut plain: Vec<(f64, usize)> = reps
            .iter()
            .map(|&r| cl.rep(r))
            .filter(|&x| self.iso[self.part.bodies[x]].ncols() == 0)
            .map(|x| (proj(x), x))
            .collect();
        plain.sort_by(|a, c| a.0.total_cmp(&c.0).then(a.1.cmp(&c.1)));
        let mut compared: u64 = 0;
        for i in 0..plain.len() {
            for j in i + 1..plain.len() {
                if plain[j].0 - plain[i].0 > same_tol {
                    break;
                }
                compared += 1;
                if compared.is_multiple_of(4096) {
                    meter.charge(4096 * (b * k * 4) as u64)?;
                }
                let (a, c) = (plain[i].1, plain[j].1);
                if cl.root(a) != cl.root(c) && same(a, c) {
                    cl.join(a, c);
                }
            }
        }
        Ok(())
    }

    /// Random self-stresses of the part (the elimination on the transpose, with the pairs as
    /// unknowns), each joint's share added to `w`: the sum over `s` unit random stresses,
    /// times `e / s` (`e` stresses in all) so that it estimates the dense path's share over an
    /// orthonormal basis (exact when `s = e` and the stresses are orthogonal).
    ///
    /// Returns the largest residual ‖y'ᵀA'‖ of the sampled stresses y' of the scaled rows A'
    /// (each y' of unit norm; 0 when there are none), on the part's own scale: a stress of the
    /// scaled rows is one of the original rows (y = D·y' gives yᵀA = y'ᵀA'), and the caller
    /// puts the residual on the report's scale, as it does the pivots.
    #[allow(clippy::too_many_arguments)]
    fn stresses(
        &self,
        lgroup: &BTreeMap<usize, usize>,
        local_block: &dyn Fn(usize, usize) -> DMatrix<f64>,
        row_norm: &dyn Fn(usize, usize) -> f64,
        abs_tol: f64,
        rank: usize,
        budget: &Budget,
        meter: &mut Meter,
        w: &mut BTreeMap<usize, f64>,
    ) -> Result<f64, BudgetExceeded> {
        let (part, pairs) = (self.part, self.pairs);
        let psizes: Vec<usize> = part
            .pairs
            .iter()
            .map(|&pi| self.models[pairs[pi].joint].rows.nrows())
            .collect();
        let prow: usize = psizes.iter().sum();
        if prow <= rank {
            return Ok(0.0);
        }
        let mut poff = Vec::with_capacity(psizes.len());
        let mut acc = 0;
        for &s in &psizes {
            poff.push(acc);
            acc += s;
        }
        let (tblocks, linc, tentries) = self.transposed_blocks(lgroup, local_block, &psizes);
        let nv = part.bodies.len() as u64;
        let telim = eliminate(&psizes, tblocks, abs_tol, budget, nv, meter)?;
        let e = prow.saturating_sub(telim.rank);
        let s = e.min(STRESS_SAMPLES);
        if s == 0 {
            return Ok(0.0);
        }
        budget.check_memory((prow as u64).saturating_mul(s as u64 * 8), || {
            format!(
                "the geometric rigidity analysis ({s} sampled self-stresses over {prow} \
                 constraint rows in one rigid block)"
            )
        })?;
        meter.charge(telim.factor_entries().saturating_mul(s as u64 + 1))?;
        let seed = part.pairs.first().copied().unwrap_or(0) as u64;
        let mut y = telim.random_null_vectors(s, 0x7374_7265_7373 ^ seed);
        drop(telim);
        // Each stress's residual, group by group: the blocks again, transposed, times y'
        // (the elimination's own blocks are gone; rebuilding them costs what building did).
        meter.charge(tentries.saturating_mul(s as u64 + 1))?;
        let residual = self.residual(&y, &linc, local_block, &psizes, &poff);
        // Back to the original rows' stresses: y = D·y', D = 1 / row norms.
        for (lp, &pi) in part.pairs.iter().enumerate() {
            for i in 0..psizes[lp] {
                let n = row_norm(pi, i);
                y.row_mut(poff[lp] + i).unscale_mut(n);
            }
        }
        let factor = e as f64 / s as f64;
        for j in 0..s {
            let n2 = y.column(j).norm_squared();
            if n2 == 0.0 {
                continue;
            }
            for (lp, &pi) in part.pairs.iter().enumerate() {
                let v = y.view((poff[lp], j), (psizes[lp], 1)).norm_squared() / n2;
                *w.entry(pairs[pi].joint).or_insert(0.0) += v * factor;
            }
        }
        Ok(residual)
    }

    /// The part's scaled rows transposed, as blocks over the pairs: one per group, its
    /// columns of the rows of its pairs (`psizes` rows each), in the pairs' order; with each
    /// group's pairs (local indices) and the blocks' entries.
    #[allow(clippy::type_complexity)]
    fn transposed_blocks(
        &self,
        lgroup: &BTreeMap<usize, usize>,
        local_block: &dyn Fn(usize, usize) -> DMatrix<f64>,
        psizes: &[usize],
    ) -> (Vec<Block>, Vec<Vec<usize>>, u64) {
        let (part, pairs) = (self.part, self.pairs);
        let ngroups = self.groups.len();
        let mut linc: Vec<Vec<usize>> = vec![Vec::new(); ngroups];
        for (lp, &pi) in part.pairs.iter().enumerate() {
            for x in [pairs[pi].hub, pairs[pi].other] {
                if let Some(&g) = lgroup.get(&x)
                    && linc[g].last() != Some(&lp)
                {
                    linc[g].push(lp);
                }
            }
        }
        let mut tblocks = Vec::with_capacity(ngroups);
        let mut tentries = 0u64;
        for (g, &body) in self.groups.iter().enumerate() {
            let s = self.sizes[g];
            // Kept for the residual check (`residual`).
            let ps = linc[g].clone();
            let width: usize = ps.iter().map(|&lp| psizes[lp]).sum();
            tentries = tentries.saturating_add((s * width) as u64);
            let mut mat = DMatrix::zeros(s, width);
            let mut c = 0;
            for &lp in &ps {
                let blk = local_block(part.pairs[lp], body).transpose();
                mat.view_mut((0, c), (s, blk.ncols())).copy_from(&blk);
                c += blk.ncols();
            }
            tblocks.push(Block { groups: ps, mat });
        }
        (tblocks, linc, tentries)
    }

    /// The largest residual ‖y'ᵀA'‖ / ‖y'‖ of the sampled stresses (the columns of `y`),
    /// group by group over its pairs `linc`.
    fn residual(
        &self,
        y: &DMatrix<f64>,
        linc: &[Vec<usize>],
        local_block: &dyn Fn(usize, usize) -> DMatrix<f64>,
        psizes: &[usize],
        poff: &[usize],
    ) -> f64 {
        let (part, s) = (self.part, y.ncols());
        let mut res2 = vec![0.0f64; s];
        for (g, &body) in self.groups.iter().enumerate() {
            let mut acc = DMatrix::<f64>::zeros(self.sizes[g], s);
            for &lp in &linc[g] {
                let blk = local_block(part.pairs[lp], body);
                let yl = y.rows(poff[lp], psizes[lp]);
                acc += blk.transpose() * yl;
            }
            for (j, r) in res2.iter_mut().enumerate() {
                *r += acc.column(j).norm_squared();
            }
        }
        res2.iter()
            .enumerate()
            .map(|(j, &r)| {
                let n = y.column(j).norm();
                if n > 0.0 { r.sqrt() / n } else { 0.0 }
            })
            .fold(0.0, f64::max)
    }
}
