//! Sparse Gauss–Newton on many bodies at once: the global reference solve at scale.
//!
//! The Jacobian of a mechanism is block sparse: a pair's equations touch its two bodies only.
//! Each step is the basic least-squares solution of `J δ = −e` by a multifrontal QR
//! ([`crate::elimination`]) of `J`'s columns scaled to unit norm, one group a body (`B` = 3
//! or 6 unknowns), in a minimum-degree elimination order of the body graph, with `e` carried
//! as a last column. A column whose residual against the columns before it is under
//! [`QR_TOLERANCE`] (a redundant equation, as in a planar loop written in space; an isolated
//! spin; a singular configuration) gets no step, so free unknowns do not move. QR works on
//! `J` itself: the normal equations `JᵀJ` square its conditioning, which on a long chain of
//! loops (a strip of 10^4 dyads) grows past what their Cholesky factor can resolve. A step
//! that does not lower `‖e‖` is halved (up to 30 times), as in [`super::newton`].
//!
//! The elimination order is computed once per solve from the body graph
//! ([`super::block_chol::symbolic`]); its factor structure bounds the memory checked against
//! the budget before anything is allocated, and every ordering step, evaluation and
//! factorization is charged to a work [`Meter`]. Above [`DENSE_REPORT_COLUMNS`] the report's
//! singular values are estimated from the block Cholesky pivots of `JᵀJ + μI` at the final
//! point.

use super::block_chol::{Normal, Symbolic, symbolic};
use super::newton::{NewtonOptions, NewtonOutcome, System, Targets};
use super::pose::{Configuration, Pose};
use super::residual::PositionModel;
use crate::budget::{BudgetExceeded, Meter};
use crate::elimination::{Block, Elimination, Stop};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Largest system (columns) whose final Jacobian gets a dense SVD for the report's nullity
/// and conditioning; above it they are estimated from the Cholesky pivots.
pub const DENSE_REPORT_COLUMNS: usize = 600;

/// Where each pair's blocks go: elimination indices of its unknown sides and the
/// off-diagonal block joining them.
#[derive(Clone, Copy)]
struct Slot {
    a: Option<u32>,
    b: Option<u32>,
    off: Option<usize>,
}

/// The pairs' Jacobians at one point: pair `p`'s rows are `start[p]..start[p + 1]`, each
/// row its `2B` entries (the first body's columns, then the second's).
#[derive(Default)]
struct Jacobian {
    start: Vec<usize>,
    vals: Vec<f64>,
}

/// Residual norm (of a column scaled to unit norm) under which the QR of a step takes the
/// column for dependent on those before it.
const QR_TOLERANCE: f64 = 1e-12;

/// Pairs evaluated at once (bounds the memory of one parallel batch).
const CHUNK: usize = 4096;

/// The sparse global solver: [`System::solve_local`] for systems of any size.
pub struct Sparse<'a> {
    sys: &'a System,
    model: &'a PositionModel,
    targets: &'a Targets,
    sym: Symbolic,
    slots: Vec<Slot>,
    col: Vec<u32>,
}

impl<'a> Sparse<'a> {
    /// Order the unknowns and allocate nothing yet; errors when the ordering or the factor
    /// would pass the budget.
    pub fn new(
        sys: &'a System,
        model: &'a PositionModel,
        targets: &'a Targets,
        opts: &NewtonOptions,
        meter: &mut Meter,
    ) -> Result<Sparse<'a>, BudgetExceeded> {
        let b = model.b();
        let mut col = vec![u32::MAX; model.bodies];
        for (i, &x) in sys.bodies.iter().enumerate() {
            col[x] = i as u32;
        }
        let known = |x: usize| col.get(x).copied().filter(|&c| c != u32::MAX);
        let mut edges = Vec::new();
        for &p in &sys.pairs {
            let pair = &model.pairs[p];
            if let (Some(u), Some(v)) = (known(pair.a), known(pair.b))
                && u != v
            {
                edges.push((u, v));
            }
        }
        let n = sys.bodies.len();
        let max = opts.budget.max_memory_bytes;
        let sym = symbolic(n, b, &edges, meter, max)?;
        // The normal equations and the QR factor (each about the factor's size), and per pair
        // its slot, its Jacobian (at most `B` rows of `2B`) and that Jacobian's copy as a
        // block of the QR.
        let per_pair = 24 + 2 * (b * 2 * b * 8) as u64;
        opts.budget.check_memory(
            sym.factor_bytes()
                .saturating_mul(2)
                .saturating_add((sys.pairs.len() as u64).saturating_mul(per_pair)),
            || "the sparse factorization of the global solve".into(),
        )?;
        let slots = sys
            .pairs
            .iter()
            .map(|&p| {
                let pair = &model.pairs[p];
                let a = known(pair.a).map(|c| sym.pos[c as usize]);
                let bb = if pair.a == pair.b {
                    None
                } else {
                    known(pair.b).map(|c| sym.pos[c as usize])
                };
                let off = match (a, bb) {
                    (Some(x), Some(y)) if x != y => sym.find(x.min(y) as usize, x.max(y)),
                    _ => None,
                };
                Slot { a, b: bb, off }
            })
            .collect();
        Ok(Sparse {
            sys,
            model,
            targets,
            sym,
            slots,
            col,
        })
    }

    /// The factor's structure.
    pub fn symbolic(&self) -> &Symbolic {
        &self.sym
    }

    /// Residuals (all pairs, in order), per-pair maxima, the normal equations into `ne` and
    /// the pairs' Jacobians into `jac`.
    fn evaluate(
        &self,
        config: &Configuration,
        local: &[Pose],
        ne: &mut Normal,
        jac: &mut Jacobian,
        meter: &mut Meter,
    ) -> Result<(Vec<f64>, Vec<f64>), BudgetExceeded> {
        let b = self.model.b();
        let bb = b * b;
        let pose = |body: usize| match self.col.get(body).copied() {
            Some(c) if c != u32::MAX => local[c as usize],
            _ => config.poses[body],
        };
        ne.clear();
        jac.vals.clear();
        jac.start.clear();
        jac.start.push(0);
        let mut r = Vec::new();
        let mut per_pair = Vec::with_capacity(self.sys.pairs.len());
        for (chunk, slots) in self.sys.pairs.chunks(CHUNK).zip(self.slots.chunks(CHUNK)) {
            meter.charge(chunk.len() as u64 * 200)?;
            let eqs: Vec<_> = chunk
                .par_iter()
                .map(|&p| {
                    let pair = &self.model.pairs[p];
                    self.model.pair_equations(
                        p,
                        &pose(pair.a),
                        &pose(pair.b),
                        self.targets.get(p).map(Vec::as_slice).unwrap_or(&[]),
                    )
                })
                .collect();
            for (e, slot) in eqs.iter().zip(slots) {
                let rows = e.residual.len();
                per_pair.push(e.residual.iter().fold(0.0f64, |m, x| m.max(x.abs())));
                r.extend_from_slice(&e.residual);
                let j = &e.jacobian;
                for i in 0..rows {
                    jac.vals.extend((0..2 * b).map(|c| j[(i, c)]));
                }
                jac.start.push(r.len());
                let sides = [(slot.a, 0usize), (slot.b, 1usize)];
                for &(s, side) in &sides {
                    let Some(k) = s else { continue };
                    let k = k as usize;
                    let d = &mut ne.diag[k * bb..(k + 1) * bb];
                    for c1 in 0..b {
                        for c2 in 0..b {
                            let mut v = 0.0;
                            for i in 0..rows {
                                v += j[(i, side * b + c1)] * j[(i, side * b + c2)];
                            }
                            d[c1 * b + c2] += v;
                        }
                    }
                }
                if let (Some(x), Some(y), Some(at)) = (slot.a, slot.b, slot.off) {
                    // Block (row max, column min): J_rowᵀ J_col.
                    let (sr, sc) = if x > y { (0, 1) } else { (1, 0) };
                    let o = &mut ne.off[at * bb..(at + 1) * bb];
                    for c1 in 0..b {
                        for c2 in 0..b {
                            let mut v = 0.0;
                            for i in 0..rows {
                                v += j[(i, sr * b + c1)] * j[(i, sc * b + c2)];
                            }
                            o[c1 * b + c2] += v;
                        }
                    }
                }
            }
        }
        Ok((r, per_pair))
    }

    /// The Gauss–Newton step: the basic least-squares solution of `J δ = −e` by the
    /// multifrontal QR of [`crate::elimination`] on the columns scaled to unit norm, the
    /// groups (bodies) in the factor's elimination order, `e` a last column carried through.
    /// The normal equations' factor would square `J`'s conditioning: on a long strip of dyads
    /// (10^4 bodies) its steps stopped Newton short of convergence. Columns whose residual
    /// falls under [`QR_TOLERANCE`] (redundant equations, an isolated spin, a singular
    /// configuration) do not move. `diag` holds each unknown's `‖J column‖²`, in elimination
    /// order.
    fn step(
        &self,
        jac: &Jacobian,
        e: &[f64],
        diag: &[f64],
        opts: &NewtonOptions,
        meter: &mut Meter,
    ) -> Result<Vec<f64>, BudgetExceeded> {
        let b = self.sym.b;
        let n = self.sym.pos.len();
        let scale: Vec<f64> = diag
            .iter()
            .map(|&d| if d > 0.0 { 1.0 / d.sqrt() } else { 0.0 })
            .collect();
        let mut sizes = vec![b; n];
        sizes.push(1);
        let mut blocks = Vec::with_capacity(self.slots.len());
        for (p, slot) in self.slots.iter().enumerate() {
            let (lo, hi) = (jac.start[p], jac.start[p + 1]);
            let sides: Vec<(usize, u32)> = [(0, slot.a), (1, slot.b)]
                .into_iter()
                .filter_map(|(side, k)| k.map(|k| (side, k)))
                .collect();
            if sides.is_empty() || hi == lo {
                continue;
            }
            let cols = sides.len() * b + 1;
            let mat = DMatrix::from_fn(hi - lo, cols, |i, c| {
                let row = lo + i;
                match sides.get(c / b) {
                    Some(&(side, k)) => {
                        jac.vals[row * 2 * b + side * b + c % b] * scale[k as usize * b + c % b]
                    }
                    None => e[row],
                }
            });
            let mut groups: Vec<usize> = sides.iter().map(|&(_, k)| k as usize).collect();
            groups.push(n);
            blocks.push(Block { groups, mat });
        }
        let order: Vec<usize> = (0..n).collect();
        let max = opts.budget.max_memory_bytes;
        let elim =
            Elimination::run_in_order_metered(&sizes, blocks, QR_TOLERANCE, max, &order, meter)
                .map_err(|stop| match stop {
                    Stop::Work(e) => e,
                    Stop::Memory(needed) => BudgetExceeded {
                        limit: crate::budget::Limit::Memory,
                        what: "the sparse QR factorization of the global solve".into(),
                        needed,
                        at_least: true,
                        allowed: max,
                    },
                })?;
        let mut x = DVector::zeros(n * b + 1);
        x[n * b] = 1.0;
        elim.back_substitute(&mut x);
        Ok((0..n * b).map(|i| x[i] * scale[i]).collect())
    }

    /// Gauss–Newton from `config`; returns the outcome and the unknowns' new poses.
    pub fn solve(
        &self,
        config: &Configuration,
        opts: &NewtonOptions,
        meter: &mut Meter,
    ) -> Result<(NewtonOutcome, Vec<Pose>), BudgetExceeded> {
        let b = self.model.b();
        let n = self.sys.bodies.len();
        let inf = |r: &[f64]| {
            if r.iter().all(|x| x.is_finite()) {
                r.iter().fold(0.0f64, |m, x| m.max(x.abs()))
            } else {
                f64::INFINITY
            }
        };
        let norm = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut local: Vec<Pose> = self.sys.bodies.iter().map(|&x| config.poses[x]).collect();
        let mut ne = Normal::zeros(&self.sym);
        let mut jac = Jacobian::default();
        let (mut r, mut per_pair) = self.evaluate(config, &local, &mut ne, &mut jac, meter)?;
        let mut iterations = 0;
        loop {
            let finite = ne.diag.iter().chain(&ne.off).all(|x| x.is_finite());
            if n == 0 || r.is_empty() || !finite {
                break;
            }
            if inf(&r) <= opts.tolerance || iterations >= opts.max_iterations {
                break;
            }
            let diag: Vec<f64> = (0..n * b)
                .map(|i| ne.diag[(i / b) * b * b + (i % b) * (b + 1)])
                .collect();
            let step = self.step(&jac, &r, &diag, opts, meter)?;
            if !step.iter().all(|x| x.is_finite()) {
                break;
            }
            iterations += 1;
            let base = local.clone();
            let norm0 = norm(&r);
            let mut t = 1.0;
            let mut accepted = false;
            for _ in 0..30 {
                for (c, p) in local.iter_mut().enumerate() {
                    let k = self.sym.pos[c] as usize;
                    let tw: Vec<f64> = (0..b).map(|i| t * step[k * b + i]).collect();
                    *p = base[c].moved_by(self.model.space, &tw);
                }
                let (r2, p2) = self.evaluate(config, &local, &mut ne, &mut jac, meter)?;
                if norm(&r2) < norm0 || inf(&r2) <= opts.tolerance {
                    (r, per_pair) = (r2, p2);
                    accepted = true;
                    break;
                }
                t *= 0.5;
            }
            if !accepted {
                local = base;
                self.evaluate(config, &local, &mut ne, &mut jac, meter)?;
                break;
            }
        }
        let columns = n * b;
        let singular_values = if columns <= DENSE_REPORT_COLUMNS {
            let mut cfg = config.clone();
            for (&x, p) in self.sys.bodies.iter().zip(&local) {
                cfg.poses[x] = *p;
            }
            let (_, j, _) = self.sys.evaluate(self.model, self.targets, &cfg);
            let mut s: Vec<f64> = if j.nrows() == 0 || j.ncols() == 0 {
                Vec::new()
            } else {
                nalgebra::SVD::try_new(j, false, false, f64::EPSILON, 10_000)
                    .map(|d| d.singular_values.iter().copied().collect())
                    .unwrap_or_default()
            };
            s.sort_by(|a, b| b.total_cmp(a));
            s
        } else {
            // Estimates: square roots of the pivots of `JᵀJ + μI` less the damping (zero when
            // a pivot is no more than twice the damping).
            let top = (0..columns)
                .map(|i| ne.diag[(i / b) * b * b + (i % b) * (b + 1)])
                .fold(0.0f64, f64::max);
            let mu = 1e-12 * top.max(1e-300);
            let finite = ne.diag.iter().chain(&ne.off).all(|x| x.is_finite());
            let pivots = if r.is_empty() || !finite {
                Vec::new()
            } else {
                meter.charge(self.sym.factor_work())?;
                ne.factor(&self.sym, mu)
            };
            let mut s: Vec<f64> = pivots
                .iter()
                .map(|&p| if p <= 2.0 * mu { 0.0 } else { (p - mu).sqrt() })
                .collect();
            s.sort_by(|a, b| b.total_cmp(a));
            s
        };
        let out = NewtonOutcome {
            converged: inf(&r) <= opts.tolerance,
            iterations,
            residual: inf(&r),
            singular_values,
            unknowns: columns,
            equations: r.len(),
            pair_residuals: per_pair,
        };
        Ok((out, local))
    }
}
