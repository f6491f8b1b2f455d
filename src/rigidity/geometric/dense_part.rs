//! The floating-point analysis of one part with dense motions: its elimination (at the rank
//! decided exactly when the realization is random), its motions as dense orthonormal
//! vectors, its self-stresses, its locked DOF and its rigid clusters.

use super::analysis::{Analysis, Tally, ZERO_TOL};
use super::clusters::{Local, union_min};
use super::dense::{orthonormalize, small_rank};
use super::jacobian::{Built, Part, eliminate};
use super::redundancy::{StressStep, self_stresses};
use crate::budget::{BudgetExceeded, Meter};
use crate::elimination::{Block, Elimination};
use crate::exact::Fp;
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeMap;

/// Each body's twist over the part's motions (B × d, zero for a fixed body), in the order of
/// the part's bodies, the part's groups by body, and d.
struct Twists {
    tw: Vec<DMatrix<f64>>,
    lgroup: BTreeMap<usize, usize>,
    d: usize,
}

impl Analysis<'_> {
    /// A part analysed by the floating-point elimination and its dense motions.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn dense_part(
        &self,
        part: &Part,
        bp: Built,
        smax: f64,
        base_abs: f64,
        one_part: bool,
        meter: &mut Meter,
        t: &mut Tally,
    ) -> Result<(), BudgetExceeded> {
        let Built {
            groups: lbody,
            sizes: lsizes,
            offsets: loffsets,
            blocks,
            smax: _,
        } = bp;
        let lcols: usize = lsizes.iter().sum();
        self.check_dense_room(part, &blocks, lcols)?;
        let (elim, abs_tol, target) =
            self.eliminate_part(part, &lsizes, &blocks, base_abs, meter)?;
        if target.is_some() && one_part {
            t.tol = abs_tol / smax.max(f64::MIN_POSITIVE);
        }
        t.rank += target.unwrap_or(elim.rank);
        t.float_rank += elim.rank;
        t.kept_min = t.kept_min.min(elim.kept_min);
        t.dropped_max = t.dropped_max.max(elim.dropped_max);

        let tws = self.part_twists(part, &elim, &lbody, &lsizes, &loffsets, lcols, meter)?;

        // Left null space (self-stresses) by the same elimination on the transpose.
        let rank_here = target.unwrap_or(elim.rank);
        let mut log = Vec::new();
        let res = self_stresses(
            part,
            &self.pairs,
            self.models,
            &self.comp,
            &tws.lgroup,
            lbody.len(),
            rank_here,
            abs_tol,
            None,
            self.budget,
            meter,
            &mut log,
        )?;
        t.stress_residual = t.stress_residual.max(res);
        if t.stress_steps.is_empty() {
            // Nothing deferred before it (always so at the file's geometry, where the sparse
            // parts add to `w` as they go): added now, as before.
            for (j, s) in log {
                *t.w.entry(j).or_insert(0.0) += s;
            }
        } else {
            t.stress_steps.push(StressStep::Done(log));
        }
        self.locked_in_part(part, &tws, meter, &mut t.locked_by_joint)?;
        self.clusters_in_part(part, &tws, meter, &mut t.uf)
    }

    /// Before any elimination: the part has at least `lcols − rows` motions, each a dense
    /// vector over its unknowns, orthonormalized (d² · lcols) and compared body by body.
    fn check_dense_room(
        &self,
        part: &Part,
        blocks: &[Block],
        lcols: usize,
    ) -> Result<(), BudgetExceeded> {
        let (budget, b) = (self.budget, self.b);
        let prows: usize = blocks.iter().map(|x| x.mat.nrows()).sum();
        let dmin = lcols.saturating_sub(prows) as u64;
        let nv = part.bodies.len() as u64;
        budget.check_memory(
            dmin.saturating_mul(lcols as u64 + nv * b as u64)
                .saturating_mul(16),
            || {
                format!(
                    "the geometric rigidity analysis (at least {dmin} motions over {lcols} \
                     unknowns in one rigid block of {nv} bodies)"
                )
            },
        )?;
        budget.check_work(
            dmin.saturating_mul(dmin).saturating_mul(lcols as u64),
            || {
                format!(
                    "the geometric rigidity analysis (at least {dmin} motions over {lcols} \
                     unknowns in one rigid block of {nv} bodies)"
                )
            },
        )
    }

    /// The part's elimination, its threshold and, at a random realization, its exact rank.
    /// At a random realization the rank is decided exactly, over GF(2^61 − 1): floating point
    /// cannot tell a large, badly conditioned full-rank system from a deficient one at every
    /// size and seed. The pivoted elimination (which gives the motions and self-stresses) is
    /// then run at a threshold that keeps exactly that many pivots.
    fn eliminate_part(
        &self,
        part: &Part,
        lsizes: &[usize],
        blocks: &[Block],
        base_abs: f64,
        meter: &mut Meter,
    ) -> Result<(Elimination, f64, Option<usize>), BudgetExceeded> {
        let (budget, nv) = (self.budget, part.bodies.len() as u64);
        let mut abs_tol = base_abs;
        let mut elim = eliminate(lsizes, blocks.to_vec(), abs_tol, budget, nv, meter)?;
        let target = match self.exact {
            Some(rows) => Some(self.exact_rank(part, rows, meter)?),
            None => None,
        };
        if let Some(target) = target {
            let mut tries = 0;
            while elim.rank != target && tries < 16 {
                tries += 1;
                abs_tol = if elim.rank > target {
                    elim.kept_min * (1.0 + 1e-9)
                } else {
                    elim.dropped_max * (1.0 - 1e-9)
                };
                elim = eliminate(lsizes, blocks.to_vec(), abs_tol, budget, nv, meter)?;
            }
        }
        Ok((elim, abs_tol, target))
    }

    /// The rank of the part's rows over GF(2^61 − 1) (the part's root and the frame fixed).
    fn exact_rank(
        &self,
        part: &Part,
        rows: &[DMatrix<Fp>],
        meter: &mut Meter,
    ) -> Result<usize, BudgetExceeded> {
        let (b, pairs) = (self.b, &self.pairs);
        let fixed = |x: usize| x == self.frame || x == part.root;
        let mut ng = 0;
        let mut local = BTreeMap::new();
        for &x in &part.bodies {
            if !fixed(x) {
                local.insert(x, ng);
                ng += 1;
            }
        }
        let r = crate::motion::exact::pairs_rank(
            b,
            ng,
            rows,
            part.pairs
                .iter()
                .map(|&pi| (pairs[pi].joint, pairs[pi].hub, pairs[pi].other)),
            |x| local.get(&x).copied(),
        );
        meter.charge((part.pairs.len() * b * b * 8) as u64)?;
        Ok(r)
    }

    /// The part's motions (null space, orthonormal), then each body's twist over them.
    #[allow(clippy::too_many_arguments)]
    fn part_twists(
        &self,
        part: &Part,
        elim: &Elimination,
        lbody: &[usize],
        lsizes: &[usize],
        loffsets: &[usize],
        lcols: usize,
        meter: &mut Meter,
    ) -> Result<Twists, BudgetExceeded> {
        let b = self.b;
        let d = lcols.saturating_sub(elim.rank);
        let nv = part.bodies.len() as u64;
        self.budget.check_memory(
            ((d as u64).saturating_mul(lcols as u64 + nv * b as u64)).saturating_mul(16),
            || {
                format!(
                    "the geometric rigidity analysis ({d} motions over {lcols} unknowns in one \
                     rigid block of {nv} bodies)"
                )
            },
        )?;
        meter.charge(
            (d as u64)
                .saturating_mul(d as u64)
                .saturating_mul(lcols as u64)
                .saturating_add((d as u64).saturating_mul(lcols as u64 * 8)),
        )?;
        let null_red: Vec<DVector<f64>> = orthonormalize(elim.null_space());
        let d = null_red.len();
        let mut lgroup: BTreeMap<usize, usize> = BTreeMap::new();
        for (g, &x) in lbody.iter().enumerate() {
            lgroup.insert(x, g);
        }
        let tw: Vec<DMatrix<f64>> = part
            .bodies
            .iter()
            .map(|&body| {
                let mut t = DMatrix::zeros(b, d);
                if let Some(&g) = lgroup.get(&body) {
                    for (k, x) in null_red.iter().enumerate() {
                        t.set_column(k, &(&self.comp[body] * x.rows(loffsets[g], lsizes[g])));
                    }
                }
                t
            })
            .collect();
        Ok(Twists { tw, lgroup, d })
    }

    /// Locked DOF per joint: allowed dimension minus the rank used over all motions.
    fn locked_in_part(
        &self,
        part: &Part,
        tws: &Twists,
        meter: &mut Meter,
        locked_by_joint: &mut BTreeMap<usize, usize>,
    ) -> Result<(), BudgetExceeded> {
        let (b, d, tw, iso) = (self.b, tws.d, &tws.tw, &self.iso);
        let lidx = |x: usize| part.bodies.binary_search(&x).unwrap_or(0);
        meter.charge((part.pairs.len() as u64).saturating_mul((b * b * (d + 2 * b)) as u64))?;
        for &pi in &part.pairs {
            let p = self.pairs[pi];
            let (th, to) = (&tw[lidx(p.hub)], &tw[lidx(p.other)]);
            let mut cols: Vec<DVector<f64>> = Vec::new();
            for k in 0..d {
                cols.push(to.column(k) - th.column(k));
            }
            for body in [p.hub, p.other] {
                for c in iso[body].column_iter() {
                    cols.push(c.into_owned());
                }
            }
            let used = if cols.is_empty() {
                0
            } else {
                small_rank(&DMatrix::from_columns(&cols), ZERO_TOL)
            };
            let allowed = self.models[p.joint].twists.ncols();
            *locked_by_joint.entry(p.joint).or_insert(0) += allowed.saturating_sub(used);
        }
        Ok(())
    }

    /// Rigid clusters over the part's motions: bodies whose twists agree (modulo their own
    /// isolated motions), joined across parts at their shared cut bodies.
    fn clusters_in_part(
        &self,
        part: &Part,
        tws: &Twists,
        meter: &mut Meter,
        uf: &mut [usize],
    ) -> Result<(), BudgetExceeded> {
        let (b, d, tw, iso) = (self.b, tws.d, &tws.tw, &self.iso);
        let lidx = |x: usize| part.bodies.binary_search(&x).unwrap_or(0);
        let nl = part.bodies.len();
        let mut cl = Local::new(part.bodies.iter().map(|&x| iso[x].ncols()).collect());
        let same = |x: usize, y: usize| {
            let diff = &tw[x] - &tw[y];
            let cols: Vec<DVector<f64>> = iso[part.bodies[x]]
                .column_iter()
                .chain(iso[part.bodies[y]].column_iter())
                .map(|c| c.into_owned())
                .collect();
            let q = orthonormalize(cols);
            let mut res = diff;
            for qv in &q {
                let proj = qv * (qv.transpose() * &res);
                res -= proj;
            }
            res.norm() <= ZERO_TOL
        };
        for &pi in &part.pairs {
            let p = self.pairs[pi];
            cl.join_if(lidx(p.hub), lidx(p.other), &same);
        }
        let reps: Vec<usize> = (0..nl).filter(|&x| cl.root(x) == x).collect();
        meter.charge(
            (reps.len() as u64)
                .saturating_mul(reps.len() as u64)
                .saturating_mul((b * (d + 2 * b) + 16) as u64)
                / 2,
        )?;
        for i in 0..reps.len() {
            for j in 0..i {
                cl.join_if(reps[j], reps[i], &same);
            }
        }
        for x in 0..nl {
            let r = cl.root(x);
            if r != x {
                union_min(uf, part.bodies[r], part.bodies[x]);
            }
        }
        Ok(())
    }
}
