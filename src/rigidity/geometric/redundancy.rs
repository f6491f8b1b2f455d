//! Redundant constraints: the self-stresses (left null space) of each part, the joints'
//! weights they give, and why some were not computed.

use super::analysis::{Analysis, Tally};
use super::dense::orthonormalize;
use super::jacobian::{Complements, Pair, Part, eliminate, pair_block};
use super::report::JointWeight;
use crate::budget::{Budget, BudgetExceeded, Limit, Meter};
use crate::elimination::Block;
use crate::motion::JointModel;
use nalgebra::{DMatrix, DVector};
use std::collections::{BTreeMap, BTreeSet};

/// Largest residual ‖yᵀA‖ / σ_max of a unit floating-point self-stress y whose weights are
/// printed without a note. Where every pivot the transposed elimination drops is rounding,
/// the residual is rounding too (under 10^-15 on the bundled mechanisms at a random
/// realization); pivots dropped just under the analysis's threshold (1e-9 · rows · σ_max), or
/// at a threshold raised to reach the exact rank, leave up to that much (10^-8 to 10^-4 on
/// random spatial mechanisms of 400 to 2,000 bodies with their inputs).
pub const STRESS_RESIDUAL: f64 = 1e-9;

/// A part's self-stress step: done as the part was analysed (its additions to the weights,
/// in order), or deferred (an exactly analysed part: optional beside its exact count).
pub(super) enum StressStep {
    Done(Vec<(usize, f64)>),
    Exact(Deferred),
}

/// The float self-stresses of an exactly analysed part, left for the end: the pairs of its
/// exact support (with their bodies), their groups, the exact rank to reach, and how many
/// self-stresses over how many rows.
pub(super) struct Deferred {
    pub(super) sub: Part,
    pub(super) sgroup: BTreeMap<usize, usize>,
    pub(super) target: usize,
    pub(super) stresses: usize,
    pub(super) rows: usize,
}

/// Why some rigid blocks' floating-point self-stresses were given up (the first limit met):
/// the amount they needed at least, the limit, and how many self-stresses over how many
/// constraint rows went without weights.
pub(super) struct Unweighted {
    pub(super) limit: Limit,
    /// Work: the units of their share, all spent; memory: the bytes needed at least.
    pub(super) needed: u64,
    /// The budget's limit (work units or bytes).
    pub(super) allowed: u64,
    pub(super) stresses: usize,
    pub(super) rows: usize,
}

impl Unweighted {
    /// The note for `weights_note` (`joints`: how many are listed without weights;
    /// `weighted`: whether other blocks' joints are listed with theirs).
    fn note(&self, joints: usize, weighted: bool) -> String {
        let need = match self.limit {
            Limit::Work => format!(
                "need more than the {} work units the rest of the analysis left of the work \
                 limit of {} work units",
                crate::budget::count_in_words(self.needed),
                crate::budget::count_in_words(self.allowed)
            ),
            _ => format!(
                "need at least {}, over the memory limit of {}",
                crate::budget::bytes_in_words(self.needed),
                crate::budget::bytes_in_words(self.allowed)
            ),
        };
        // The weights of the other blocks are theirs (the self-stresses of separate blocks
        // are independent), but printed relative to the largest computed.
        let relative = if weighted {
            "; the weights shown (other rigid blocks) are relative to the largest of them, not \
             to the joints without one"
        } else {
            ""
        };
        format!(
            "the weights of the {joints} joints listed without one were not computed: the \
             floating-point self-stresses they come from ({} over {} constraint rows) {need}; \
             those joints carry the exact self-stresses (over GF(2^61 - 1) at this \
             realization) and the count of redundant constraints is exact{relative}; to \
             compute the weights, raise the limit with `{} N` or scale every limit with \
             `--budget X`",
            self.stresses,
            self.rows,
            self.limit.flag()
        )
    }
}

/// The self-stresses of a part (the left null space of its rows, by the elimination on the
/// transpose with the pairs as unknowns, orthonormalized), each joint's share of them pushed
/// onto `w` as (joint, share), pair by pair, once nothing more can fail. With `retry`, the
/// threshold moves (as for the motions) until the elimination's rank is that number, the rank
/// decided exactly. Returns the largest ‖yᵀA‖ of the unit
/// self-stresses found (the weights' check: not small where the float rank was reached only
/// by dropping pivots that are not rounding).
#[allow(clippy::too_many_arguments)]
pub(super) fn self_stresses(
    part: &Part,
    pairs: &[Pair],
    models: &[JointModel],
    comp: &Complements,
    lgroup: &BTreeMap<usize, usize>,
    ngroups: usize,
    rank: usize,
    abs_tol: f64,
    retry: Option<usize>,
    budget: &Budget,
    meter: &mut Meter,
    w: &mut Vec<(usize, f64)>,
) -> Result<f64, BudgetExceeded> {
    let prow: usize = part
        .pairs
        .iter()
        .map(|&pi| models[pairs[pi].joint].rows.nrows())
        .sum();
    if prow <= rank {
        return Ok(0.0);
    }
    let psizes: Vec<usize> = part
        .pairs
        .iter()
        .map(|&pi| models[pairs[pi].joint].rows.nrows())
        .collect();
    let mut poff = Vec::new();
    let mut acc = 0;
    for &s in &psizes {
        poff.push(acc);
        acc += s;
    }
    let tblocks = transposed_blocks(part, pairs, models, comp, lgroup, ngroups, &psizes);
    let nv = part.bodies.len() as u64;
    let mut telim = eliminate(&psizes, tblocks.clone(), abs_tol, budget, nv, meter)?;
    if let Some(target) = retry {
        let mut tries = 0;
        while telim.rank != target && tries < 16 {
            tries += 1;
            // Steered by this run's pivot norms to the exact rank (one run usually reaches
            // it); else one decision at a time, as before.
            let t = telim
                .steered_threshold(target)
                .unwrap_or(if telim.rank > target {
                    telim.kept_min * (1.0 + 1e-9)
                } else {
                    telim.dropped_max * (1.0 - 1e-9)
                });
            telim = eliminate(&psizes, tblocks.clone(), t, budget, nv, meter)?;
        }
    }
    let e = prow.saturating_sub(telim.rank) as u64;
    budget.check_memory(e.saturating_mul(prow as u64).saturating_mul(16), || {
        format!(
            "the geometric rigidity analysis ({e} self-stresses over {prow} constraint rows in \
             one rigid block)"
        )
    })?;
    meter.charge(e.saturating_mul(e).saturating_mul(prow as u64))?;
    let stresses = orthonormalize(telim.null_space());
    // The check that they are self-stresses: ‖yᵀA‖ per vector, body by body (a body's
    // transposed block holds its columns of A over its pairs' rows).
    let entries: u64 = tblocks.iter().map(|t| t.mat.len() as u64).sum();
    meter.charge(
        entries
            .saturating_mul(2)
            .saturating_mul(stresses.len() as u64),
    )?;
    let worst = residual(&stresses, &tblocks, &psizes, &poff);
    for y in &stresses {
        for (lp, &pi) in part.pairs.iter().enumerate() {
            let s = y.rows(poff[lp], psizes[lp]).norm_squared();
            w.push((pairs[pi].joint, s));
        }
    }
    Ok(worst)
}

/// The part's rows transposed, as blocks over the pairs: one per group (body) of `lgroup`,
/// its columns of the rows of its pairs (`psizes` rows each), in the pairs' order.
fn transposed_blocks(
    part: &Part,
    pairs: &[Pair],
    models: &[JointModel],
    comp: &Complements,
    lgroup: &BTreeMap<usize, usize>,
    ngroups: usize,
    psizes: &[usize],
) -> Vec<Block> {
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
    let mut tblocks = Vec::new();
    let mut gbodies: Vec<(usize, usize)> = lgroup.iter().map(|(&x, &g)| (g, x)).collect();
    gbodies.sort_unstable();
    for &(g, body) in &gbodies {
        let s = comp[body].ncols();
        let ps = std::mem::take(&mut linc[g]);
        let width: usize = ps.iter().map(|&lp| psizes[lp]).sum();
        let mut mat = DMatrix::zeros(s, width);
        let mut c = 0;
        for &lp in &ps {
            let blk = pair_block(pairs, models, comp, part.pairs[lp], body).transpose();
            mat.view_mut((0, c), (s, blk.ncols())).copy_from(&blk);
            c += blk.ncols();
        }
        tblocks.push(Block { groups: ps, mat });
    }
    tblocks
}

/// The largest ‖yᵀA‖ of the unit self-stresses y, body by body (a body's transposed block
/// holds its columns of A over its pairs' rows, at `poff`).
fn residual(stresses: &[DVector<f64>], tblocks: &[Block], psizes: &[usize], poff: &[usize]) -> f64 {
    let mut worst: f64 = 0.0;
    for y in stresses {
        let mut s2 = 0.0;
        for t in tblocks {
            let mut yl = DVector::zeros(t.mat.ncols());
            let mut c = 0;
            for &lp in &t.groups {
                yl.rows_mut(c, psizes[lp])
                    .copy_from(&y.rows(poff[lp], psizes[lp]));
                c += psizes[lp];
            }
            s2 += (&t.mat * yl).norm_squared();
        }
        worst = worst.max(s2.sqrt());
    }
    worst
}

impl Analysis<'_> {
    /// The deferred self-stress step of an exactly analysed part whose `prow` rows have rank
    /// `rank`: the self-stresses live on the pairs a random exact self-stress reaches
    /// (`support`), so the floating-point ones (for the joints' weights) come from those rows
    /// alone, whose left null space is the whole one's.
    pub(super) fn deferred(
        &self,
        part: &Part,
        support: &[bool],
        groups: &[usize],
        prow: usize,
        rank: usize,
    ) -> Deferred {
        let (pairs, models) = (&self.pairs, self.models);
        let sub = Part {
            root: part.root,
            pairs: part
                .pairs
                .iter()
                .zip(support)
                .filter(|(_, s)| **s)
                .map(|(&pi, _)| pi)
                .collect(),
            bodies: Vec::new(),
        };
        let srows: usize = sub
            .pairs
            .iter()
            .map(|&pi| models[pairs[pi].joint].rows.nrows())
            .sum();
        let mut sbodies: Vec<usize> = sub
            .pairs
            .iter()
            .flat_map(|&pi| [pairs[pi].hub, pairs[pi].other])
            .collect();
        sbodies.sort_unstable();
        sbodies.dedup();
        let mut lgroup: BTreeMap<usize, usize> = BTreeMap::new();
        for (g, &x) in groups.iter().enumerate() {
            lgroup.insert(x, g);
        }
        let mut sgroup: BTreeMap<usize, usize> = BTreeMap::new();
        for &x in &sbodies {
            if lgroup.contains_key(&x) {
                let g = sgroup.len();
                sgroup.insert(x, g);
            }
        }
        let sub = Part {
            bodies: sbodies,
            ..sub
        };
        let target = srows.saturating_sub(prow - rank);
        // Optional beside the exact count: run once every other part is done, on what is
        // left of the budget, and given up past it.
        Deferred {
            sub,
            sgroup,
            target,
            stresses: prow - rank,
            rows: srows,
        }
    }

    /// The joints' weights, in the parts' order (the same additions in the same order as when
    /// each part added its own as it went: the same sums bit for bit). An exactly analysed
    /// part's float self-stresses come last, on the units every other step left (nothing
    /// after this charges the meter): wherever the whole analysis fits the budget they are
    /// computed as before; where they do not fit (the work or memory limit), they are given
    /// up and the joints carrying the exact self-stresses are returned, with why.
    pub(super) fn weigh(
        &self,
        steps: Vec<StressStep>,
        base_abs: f64,
        meter: &mut Meter,
        t: &mut Tally,
    ) -> Result<(BTreeSet<usize>, Option<Unweighted>), BudgetExceeded> {
        let (pairs, budget) = (&self.pairs, self.budget);
        let mut unweighted: BTreeSet<usize> = BTreeSet::new();
        let mut unweighted_why: Option<Unweighted> = None;
        for step in steps {
            let log = match step {
                StressStep::Done(log) => log,
                StressStep::Exact(d) => {
                    let mut rest = meter.share(1, 1);
                    let units = rest.allowed() - meter.used();
                    let mut log = Vec::new();
                    let res = self_stresses(
                        &d.sub,
                        pairs,
                        self.models,
                        &self.comp,
                        &d.sgroup,
                        d.sgroup.len(),
                        d.target,
                        base_abs,
                        Some(d.target),
                        budget,
                        &mut rest,
                        &mut log,
                    );
                    meter.settle(&rest);
                    match res {
                        Ok(res) => {
                            t.stress_residual = t.stress_residual.max(res);
                            log
                        }
                        Err(e) if e.limit == Limit::Work || e.limit == Limit::Memory => {
                            unweighted.extend(d.sub.pairs.iter().map(|&pi| pairs[pi].joint));
                            let (needed, allowed) = match e.limit {
                                Limit::Work => (units, budget.max_work),
                                _ => (e.needed, budget.max_memory_bytes),
                            };
                            let u = unweighted_why.get_or_insert(Unweighted {
                                limit: e.limit,
                                needed,
                                allowed,
                                stresses: 0,
                                rows: 0,
                            });
                            u.stresses += d.stresses;
                            u.rows += d.rows;
                            Vec::new()
                        }
                        Err(e) => return Err(e),
                    }
                }
            };
            for (j, s) in log {
                *t.w.entry(j).or_insert(0.0) += s;
            }
        }
        Ok((unweighted, unweighted_why))
    }

    /// The joints taking part in the redundant constraints, by weight (the square root of
    /// their share relative to the largest).
    pub(super) fn ranked_joints(&self, w: BTreeMap<usize, f64>) -> Vec<JointWeight> {
        let m = self.m;
        let mut redundant_joints = Vec::new();
        let wmax = w.values().cloned().fold(0.0, f64::max);
        if wmax > 0.0 {
            // Ordered by the weight as reported (rounded to 1e-6), then in joint order: equal
            // weights (the four joints of a Bennett linkage) are not ordered by rounding
            // noise.
            let mut list: Vec<(usize, f64)> = w
                .into_iter()
                .map(|(j, v)| (j, (v / wmax).sqrt()))
                .filter(|(_, v)| *v > 1e-6)
                .map(|(j, v)| (j, (v * 1e6).round() / 1e6))
                .collect();
            list.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            redundant_joints = list
                .into_iter()
                .map(|(j, v)| JointWeight {
                    joint: m.joints[j].id.clone(),
                    weight: v,
                })
                .collect();
        }
        redundant_joints
    }

    /// The note on the weights: why some were not computed (`unweighted`: how many joints are
    /// listed without one; `weighted`: whether others are listed with theirs), and whether the
    /// self-stresses they come from leave more than rounding (at the file's geometry its
    /// rounded numbers allow residuals up to the precision they carry, as for the rank
    /// decisions).
    pub(super) fn weights_note(
        &self,
        smax: f64,
        stress_residual: f64,
        why: Option<Unweighted>,
        unweighted: usize,
        weighted: bool,
    ) -> Option<String> {
        let approximate = {
            let floor = STRESS_RESIDUAL * smax;
            let limit =
                crate::geometry::file_threshold(self.m, &self.used).map_or(floor, |t| t.max(floor));
            let per = |x: f64| x / smax.max(f64::MIN_POSITIVE);
            (stress_residual > limit).then(|| {
                format!(
                    "the joints' weights are approximate: the floating-point self-stresses y \
                     they come from leave |y^T A| up to {:.1e} sigma_max (accepted: {:.1e}); \
                     the count of redundant constraints is exact",
                    per(stress_residual),
                    per(limit)
                )
            })
        };
        match (why.map(|u| u.note(unweighted, weighted)), approximate) {
            (Some(a), Some(b)) => Some(format!("{a}. {b}")),
            (a, b) => a.or(b),
        }
    }
}
