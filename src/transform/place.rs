//! Placing one mechanism (or one part): each expansion's count-valid placements, found by the
//! search and analysed in parallel batches, streamed in enumeration order.

use super::expansion::{Expansion, Expansions};
use super::groups::{Lean, evaluate, placement, placement_of};
use super::oracle::Oracle;
use super::partition::BodyNames;
use super::parts::{ByParts, ExpansionParts};
use super::problem::Problem;
use super::prune::LazyPruner;
use super::rules::Rules;
use super::{
    Placed, Placement, Progress, ProgressFn, TransformError, TransformOptions, analysis_work,
};
use crate::budget::{BudgetExceeded, Meter};
use crate::mechanism::Mechanism;
use crate::structure::{self, Library};
use rayon::prelude::*;

/// Placements analysed per parallel batch (and between progress reports).
const BATCH: usize = 512;

/// Bytes of the search's flows a batch may hold (warm starts of the analyses).
const BATCH_FLOW_BYTES: usize = 64 << 20;

/// A placement waiting for its analysis: expansion, driven pairs, the search's flow (units
/// of each pair into its two bodies) and its number among the count-valid placements.
type Leaf = (usize, Vec<(usize, u32)>, Vec<[u8; 2]>, usize);

/// Enumerate and analyse the placements of `m` (one part), streaming each determined one to
/// `sink` in enumeration order (`sink` returns `false` to stop early). `--limit` bounds the
/// count-valid placements examined; the search goes on only to learn whether one more
/// exists (`cut`).
#[allow(clippy::too_many_arguments)]
pub(super) fn place(
    m: &Mechanism,
    rules: &Rules,
    opts: &TransformOptions,
    lib: &Library,
    meter: &mut Meter,
    progress: Option<ProgressFn<'_>>,
    sink: &mut dyn FnMut(Placement) -> bool,
    mut keep: Option<&mut Option<Problem>>,
) -> Result<Placed, TransformError> {
    let exps = Expansions::of(m, opts.max_expansions);
    let mut st = Placing::new(m, &exps, opts, lib, progress, keep.is_some());
    let mut by_parts = ExpansionParts::applies(&exps, rules, opts).then(ExpansionParts::default);
    for x in 0..exps.len {
        if let Some(parts) = &mut by_parts
            && let Some(got) = parts.place(
                &exps.skeleton(x),
                x,
                rules,
                opts,
                lib,
                &st.cx.names.ids,
                meter,
            )?
        {
            if st.take_by_parts(x, got, sink) {
                break;
            }
            continue;
        }
        let e = &exps.get(x);
        // The rank check's factorizations, shared by every analysis of this expansion: a
        // placement re-factorizes only the blocks and bodies whose rows its inputs changed.
        let cache = structure::AnalysisCache::default();
        let p = Problem::of(e, m, rules, opts, &cache, &st.cx.names.ids, meter)?;
        if x == 0 {
            st.r.isolated = p.isolated;
            st.r.set_aside = p.set_aside;
            st.r.f = p.f;
            st.r.drivable = p.drivable();
            if let Some(n) = &p.note {
                st.r.notes.push(n.clone());
            }
        }
        st.search_expansion(x, e, &p, &cache, meter, sink)?;
        if st.cx.defer
            && x == 0
            && p.lean.is_some()
            && let Some(k) = keep.as_deref_mut()
        {
            // Only what making the groups again needs: the exact oracle's null vectors go.
            let mut p = p;
            p.oracle = Oracle::Undecided;
            *k = Some(p);
        }
        if st.r.cut || st.stopped {
            break;
        }
    }
    if st.cut > 0 {
        let note = if st.r.count_valid == 0 {
            format!(
                "no placement is determined: each one the count allows drives one motion twice \
                 or a body's isolated spin at this geometry (the search cut all {} branch(es))",
                st.cut
            )
        } else {
            format!(
                "the search cut {} branch(es) whose inputs drive one motion twice or a body's \
                 isolated spin at this geometry: their placements are not determined and are not \
                 counted among the count-valid ones",
                st.cut
            )
        };
        st.r.notes.push(note);
    }
    Ok(st.r)
}

/// Add `note` to `notes` unless it is there.
fn add_note(notes: &mut Vec<String>, note: String) {
    if !notes.contains(&note) {
        notes.push(note);
    }
}

/// What every analysis of one mechanism's placements reads.
struct Analyses<'a> {
    opts: &'a TransformOptions,
    lib: &'a Library,
    progress: Option<ProgressFn<'a>>,
    names: BodyNames,
    /// Work units charged for a full analysis.
    per_eval: u64,
    /// Whether a placement analysed from the search's flow keeps its inputs.
    defer: bool,
}

/// The state of [`place`]: what it found, and the placements waiting for their analysis.
struct Placing<'a> {
    cx: Analyses<'a>,
    r: Placed,
    limit: usize,
    /// Count-valid placements found (at most `limit`).
    found: usize,
    /// Whether the sink asked to stop.
    stopped: bool,
    /// Count-valid placements of other shards found since the last batch (not analysed).
    skipped: usize,
    /// (expansion, placement, the search's flow for a warm start of the analysis)
    batch: Vec<Leaf>,
    batch_size: usize,
    max_batch: usize,
    eval_meter: Meter,
    /// Branches the search cut at a dependent or spin-driving unit ([`LazyPruner`]).
    cut: u64,
}

impl<'a> Placing<'a> {
    /// The state before the first expansion; with `keep`, a mechanism of one expansion
    /// keeps its inputs on the placements analysed from the search's flow.
    fn new(
        m: &Mechanism,
        exps: &Expansions<'_>,
        opts: &'a TransformOptions,
        lib: &'a Library,
        progress: Option<ProgressFn<'a>>,
        keep: bool,
    ) -> Placing<'a> {
        Placing {
            cx: Analyses {
                opts,
                lib,
                progress,
                // The body ids every placement's partition indexes (an expansion keeps the bodies).
                names: BodyNames::of(m),
                per_eval: analysis_work(m),
                // With `keep` and one expansion, a placement analysed from the search's flow
                // carries its inputs (`Placement::lean`), and the expansion's problem is kept to
                // make its groups again.
                defer: keep && exps.len == 1,
            },
            r: Placed {
                expansions: exps.len,
                expansions_total: exps.total,
                f: crate::mobility::mobility(m).mobility.count,
                ..Placed::default()
            },
            limit: opts.limit.unwrap_or(usize::MAX),
            found: 0,
            stopped: false,
            skipped: 0,
            batch: Vec::new(),
            batch_size: 1,
            // A batch holds each placement's flow (two bytes a pair): at most about 64 MB of them.
            max_batch: (BATCH_FLOW_BYTES / (2 * m.joints.len().max(1))).clamp(1, BATCH),
            // The analyses charge their own meter (the search holds `meter`): each may spend the
            // work budget.
            eval_meter: opts.budget.meter("the analysis of the placements"),
            cut: 0,
        }
    }
}

impl Placing<'_> {
    /// Stream the one placement an expansion placed part by part gave, if any; `true` when
    /// the placing stops here.
    fn take_by_parts(
        &mut self,
        x: usize,
        got: ByParts,
        sink: &mut dyn FnMut(Placement) -> bool,
    ) -> bool {
        let r = &mut self.r;
        if x == 0 {
            r.isolated = got.isolated;
            r.set_aside = got.set_aside;
            r.f = got.f;
            r.drivable = got.drivable;
        }
        if let Some(p) = got.placement {
            // As the search and `flush` count a placement of the whole expansion.
            if self.found >= self.limit {
                r.cut = true;
                return true;
            }
            let seq = self.found;
            self.found += 1;
            r.count_valid += 1;
            // A shard counts its own: a determined placement by its key, an excluded one
            // (no key made) by its number.
            if let Some(spec) = self.cx.opts.shard {
                let hash = p.as_ref().map_or(0, super::shard::placement_hash);
                let spec = match p {
                    Some(_) => spec,
                    None => super::shard::ShardSpec {
                        kind: super::shard::ShardKind::Slice,
                        ..spec
                    },
                };
                if !spec.keeps(hash, seq as u64) {
                    return false;
                }
            }
            match p {
                Some(mut p) => {
                    p.seq = seq;
                    r.determined += 1;
                    if !self.stopped && !sink(p) {
                        self.stopped = true;
                    }
                }
                None => r.excluded += 1,
            }
            self.report();
        }
        self.stopped
    }

    /// Search expansion `e` (number `x`, problem `p`) and analyse its placements in batches
    /// that grow from one placement, so that the first ones stream at once.
    fn search_expansion(
        &mut self,
        x: usize,
        e: &Expansion,
        p: &Problem,
        cache: &structure::AnalysisCache,
        meter: &mut Meter,
        sink: &mut dyn FnMut(Placement) -> bool,
    ) -> Result<(), TransformError> {
        let mut err: Option<BudgetExceeded> = None;
        // `Oracle::Later`: decided once a placement of this expansion is rejected.
        let mut late: Option<Oracle> = None;
        let excluded_before = self.r.excluded;
        let mut dependent = false;
        // At the file's geometry, where the count may not see every motion, the search cuts
        // the branches whose inputs drive one twice or a spin (the former path analyses them
        // all).
        let mut pruner = (!self.cx.opts.full_analyses).then(|| {
            LazyPruner::new(
                &e.mech,
                self.cx.opts.analysis.geometry,
                self.cx.opts.analysis.precision,
                &p.u,
                self.cx
                    .opts
                    .budget
                    .meter("the motions the search is cut by"),
                self.cx.opts.limit,
            )
        });
        p.search(
            meter,
            &mut |w, flow| {
                if self.found >= self.limit {
                    self.r.cut = true;
                    return false;
                }
                let seq = self.found;
                self.found += 1;
                let driven: Vec<(usize, u32)> = (0..w.len())
                    .filter(|&q| w[q] > 0)
                    .map(|q| (q, w[q]))
                    .collect();
                if let Some(spec) = self.cx.opts.shard {
                    let key = super::shard::key_hash(
                        &super::expansion::inputs_of(&e.mech, e, &driven),
                        e.label.as_deref(),
                    );
                    if !spec.keeps(key, seq as u64) {
                        // Another shard's: counted, not analysed.
                        self.skipped += 1;
                        return true;
                    }
                }
                self.batch.push((
                    x,
                    driven,
                    flow.iter()
                        .map(|f| [f[0].min(255) as u8, f[1].min(255) as u8])
                        .collect(),
                    seq,
                ));
                if self.batch.len() >= self.batch_size {
                    // Batches grow from one placement: the first ones stream at once.
                    self.batch_size = (self.batch_size * 2).min(self.max_batch);
                    // Only with more placements to analyse: a rejected single one (each
                    // expansion of a shared joint) pays nothing.
                    if late.is_none()
                        && self.r.excluded > excluded_before
                        && matches!(p.oracle, Oracle::Later { .. })
                    {
                        late = Some(p.oracle.dependent(
                            &e.mech,
                            &self.cx.opts.budget,
                            &mut self.eval_meter,
                        ));
                    }
                    let oracle = late.as_ref().unwrap_or(&p.oracle);
                    if let Err(b) = self.flush(e, cache, oracle, p.lean.as_ref(), &mut *sink) {
                        err = Some(b);
                        return false;
                    }

                    if self.stopped {
                        return false;
                    }
                    // Dependent constraint equations reject every placement of this expansion:
                    // the search stops at the first ones instead of rejecting them all.
                    if matches!(oracle, Oracle::Reject) && self.r.excluded > excluded_before {
                        dependent = true;
                        return false;
                    }
                }
                true
            },
            pruner.as_mut(),
        )?;
        if let Some(b) = err {
            return Err(b.into());
        }
        // The rest of the batch belongs to this expansion: analysed before the next is built.
        if late.is_none()
            && !self.batch.is_empty()
            && self.r.excluded > excluded_before
            && matches!(p.oracle, Oracle::Later { .. })
        {
            late = Some(
                p.oracle
                    .dependent(&e.mech, &self.cx.opts.budget, &mut self.eval_meter),
            );
        }
        let oracle = late.as_ref().unwrap_or(&p.oracle);
        self.flush(e, cache, oracle, p.lean.as_ref(), sink)?;
        self.cut += pruner.as_ref().map_or(0, LazyPruner::cut);
        if pruner.as_ref().is_some_and(LazyPruner::exhausted) {
            // Stopped by the cuts' bound: more placements may exist, as at `--limit`.
            self.r.cut = true;
        }
        if dependent || (matches!(oracle, Oracle::Reject) && self.r.excluded > excluded_before) {
            let note = format!(
                "the constraint equations are dependent at this geometry: every placement of the \
                 {} input(s) keeps a freedom no input controls (the mechanism moves more than \
                 the count says), so the search stopped at the first rejected one(s); \
                 `mbsa rigid` names the redundant joints",
                p.f
            );
            add_note(&mut self.r.notes, note);
        }
        Ok(())
    }

    /// Analyse the batch in parallel and stream its determined placements in order.
    fn flush(
        &mut self,
        e: &Expansion,
        cache: &structure::AnalysisCache,
        oracle: &Oracle,
        lean: Option<&Lean>,
        sink: &mut dyn FnMut(Placement) -> bool,
    ) -> Result<(), BudgetExceeded> {
        // Another shard's placements are counted, not analysed.
        self.r.count_valid += std::mem::take(&mut self.skipped);
        if self.batch.is_empty() || self.stopped {
            self.batch.clear();
            return Ok(());
        }
        // One unit a placement first; what each then spends (the exact decision of its
        // inputs, a lean analysis, a full one and the rank decisions inside it) after the
        // batch.
        self.eval_meter.charge(self.batch.len() as u64)?;
        let results = self.cx.analyse(&self.batch, e, cache, oracle, lean);
        // The analyses' work: a full analysis its estimate and its rank decisions (dense
        // factorizations of growing groups above all), a lean one its pass over the arrays.
        self.eval_meter
            .charge(results.iter().map(|r| r.1).fold(0u64, u64::saturating_add))?;
        let results = results.into_iter().map(|r| r.0);
        let r = &mut self.r;
        for (p, leaf) in results.zip(&self.batch) {
            r.count_valid += 1;
            match p {
                Some(mut p) => {
                    p.seq = leaf.3;
                    r.determined += 1;
                    if !self.stopped && !sink(p) {
                        self.stopped = true;
                    }
                }
                None => r.excluded += 1,
            }
        }
        self.batch.clear();
        self.report();
        Ok(())
    }

    /// Report the progress so far.
    fn report(&self) {
        if let Some(cb) = self.cx.progress {
            cb(Progress {
                examined: self.r.count_valid,
                total: self.r.count_valid,
                determined: self.r.determined,
            });
        }
    }
}

impl Analyses<'_> {
    /// Each placement of `batch` analysed (in parallel): its placement if it is determined,
    /// and the work it spent.
    fn analyse(
        &self,
        batch: &[Leaf],
        e: &Expansion,
        cache: &structure::AnalysisCache,
        oracle: &Oracle,
        lean: Option<&Lean>,
    ) -> Vec<(Option<Placement>, u64)> {
        let Analyses {
            opts,
            lib,
            names,
            per_eval,
            defer,
            ..
        } = self;
        batch
            .par_iter()
            .map_init(
                // A copy of the expansion only for the placements analysed in full.
                || None::<Mechanism>,
                |mech, (x, w, flow, _)| {
                    let decided = oracle.work(w);
                    let certified = match oracle.decide(&e.mech, w) {
                        Some(false) => return (None, decided),
                        Some(true) => true,
                        None => false,
                    };
                    if certified && let Some(l) = lean {
                        let g = l.groups(&e.mech, flow, lib);
                        let mut p = placement_of(&e.mech, e, *x, w, g);
                        if *defer {
                            p.lean = Some(w.clone());
                        }
                        return (Some(p), decided.saturating_add(l.work));
                    }
                    let mech = mech.get_or_insert_with(|| e.mech.as_ref().clone());
                    let (a, work) = evaluate(mech, w, flow, &opts.analysis, lib, cache, certified);
                    (
                        a.map(|a| placement(mech, e, *x, &a, w, names)),
                        work.saturating_add(*per_eval).saturating_add(decided),
                    )
                },
            )
            .collect()
    }
}
