//! Steps 1 and 2 of the rule ([`super`]): the tree of the rule's order, then exchanges that
//! make dependent closures independent.

use super::rank::{self, Ranks, Threshold};
use super::tree::{self, Force, Plan, Step};
use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::mechanism::Mechanism;
use crate::motion::JointModel;

/// What every evaluation needs.
pub(super) struct Ctx<'a> {
    pub(super) m: &'a Mechanism,
    /// The joint models, driven inputs released.
    pub(super) models: &'a [JointModel],
    pub(super) threshold: Threshold,
    pub(super) budget: &'a Budget,
    /// The mechanism has no redundant constraint (the geometric analysis of the whole
    /// Jacobian says so): every closure is independent, no rank to take.
    pub(super) independent: bool,
}

/// A tree with its loops and ranks.
#[derive(Clone, Debug)]
pub(super) struct Eval {
    pub(super) plan: Plan,
    /// Per cut: the loop's bodies.
    pub(super) loop_bodies: Vec<Vec<usize>>,
    /// Per cut: the loop's tree steps.
    pub(super) loops: Vec<Vec<Step>>,
    /// Per cut: its ranks.
    pub(super) ranks: Vec<Ranks>,
}

impl Eval {
    /// Cuts whose closure has a redundant row.
    fn dependent(&self) -> usize {
        self.ranks.iter().filter(|r| r.redundant() > 0).count()
    }

    /// The tree coordinates: the tree pairs' freedoms, B for each root but the frame.
    pub(super) fn coordinates(&self, m: &Mechanism, models: &[JointModel]) -> usize {
        let tree: usize = self
            .plan
            .links
            .iter()
            .flatten()
            .map(|l| models[self.plan.pairs[l.pair].joint].twists.ncols())
            .sum();
        tree + (self.plan.roots.len() - 1) * m.b() as usize
    }
}

/// The chosen tree, and what the exchanges did.
pub(super) struct Chosen {
    pub(super) eval: Eval,
    force: Force,
    /// Why the exchange step stopped early.
    pub(super) note: Option<String>,
}

impl Chosen {
    /// The step of the rule that made pair `p` a cut.
    pub(super) fn why(&self, m: &Mechanism, p: usize) -> &'static str {
        if self.force.cut.contains(&p) {
            "independent"
        } else if tree::class(m, self.eval.plan.pairs[p].joint) == 2 {
            "spherical"
        } else {
            "order"
        }
    }
}

/// The tree of `force`, its loops and their ranks.
fn evaluate(ctx: &Ctx, force: &Force, meter: &mut Meter) -> Result<Eval, BudgetExceeded> {
    let plan = tree::plan(ctx.m, force, meter)?;
    let mut loop_bodies = Vec::with_capacity(plan.cuts.len());
    let mut loops = Vec::with_capacity(plan.cuts.len());
    for &c in &plan.cuts {
        let (bodies, steps) = tree::closed_loop(&plan, c, meter)?;
        loop_bodies.push(bodies);
        loops.push(steps);
    }
    let ranks = if ctx.independent {
        let rows = |c: usize| ctx.models[plan.pairs[c].joint].rows.nrows();
        plan.cuts
            .iter()
            .map(|&c| Ranks {
                rows: rows(c),
                rank: rows(c),
                alone: rows(c),
            })
            .collect()
    } else {
        rank::ranks(&plan, ctx.models, &loops, ctx.threshold, ctx.budget, meter)?
    };
    Ok(Eval {
        plan,
        loop_bodies,
        loops,
        ranks,
    })
}

/// Step 1, then step 2 within half the work left (stopped there with a note).
pub(super) fn choose(ctx: &Ctx, meter: &mut Meter) -> Result<Chosen, BudgetExceeded> {
    let mut chosen = Chosen {
        eval: evaluate(ctx, &Force::default(), meter)?,
        force: Force::default(),
        note: None,
    };
    let mut sub = meter.share(1, 2);
    let result = exchange(ctx, &mut chosen, &mut sub);
    meter.settle(&sub);
    if let Err(e) = result {
        chosen.note = Some(format!(
            "the exchanges for independent closures stopped at the work limit ({e}); the cuts \
             are those found so far"
        ));
    }
    Ok(chosen)
}

/// Step 2: until no exchange helps, the first exchange (cuts in order, then the joints of
/// the cut's loop in order) that lowers the number of dependent closures.
fn exchange(ctx: &Ctx, chosen: &mut Chosen, meter: &mut Meter) -> Result<(), BudgetExceeded> {
    'search: loop {
        let now = chosen.eval.dependent();
        for (k, &c) in chosen.eval.plan.cuts.iter().enumerate() {
            let r = chosen.eval.ranks[k];
            // Only a closure dependent on other loops' closures can become independent.
            if r.redundant() == 0 || r.alone < r.rows {
                continue;
            }
            let class = tree::class(ctx.m, chosen.eval.plan.pairs[c].joint);
            let mut candidates: Vec<usize> = chosen.eval.loops[k]
                .iter()
                .map(|s| s.pair)
                .filter(|&t| tree::class(ctx.m, chosen.eval.plan.pairs[t].joint) == class)
                .collect();
            candidates.sort_unstable();
            for t in candidates {
                let mut force = chosen.force.clone();
                force.cut.remove(&c);
                force.keep.insert(c);
                force.keep.remove(&t);
                force.cut.insert(t);
                let eval = evaluate(ctx, &force, meter)?;
                if eval.dependent() < now {
                    chosen.eval = eval;
                    chosen.force = force;
                    continue 'search;
                }
            }
        }
        return Ok(());
    }
}
