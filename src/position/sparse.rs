//! Sparse Gauss–Newton on many bodies at once: the global reference solve at scale.
//!
//! The Jacobian of a mechanism is block sparse: a pair's equations touch its two bodies only.
//! Each step solves the normal equations `(JᵀJ + μI) δ = −Jᵀe` by the block Cholesky of
//! [`crate::cholesky`] (one `B × B` block per body, `B` = 3 or 6) in a minimum-degree
//! elimination order of the body graph. Each body's unknowns are a twist about its reference
//! point (the mean of its joint points), so that a rotation does not carry the body's distance
//! from the origin (far bodies' columns would be nearly parallel); the normal equations are
//! scaled to a unit diagonal and `μ = 10⁻¹²` of it keeps the factorization defined when the
//! equations are redundant (a planar loop written in space) or leave unknowns free (an
//! isolated spin); since `Jᵀe` lies in the row space of `J`, the step then stays (to rounding)
//! in that row space, as the dense solver's minimum-norm step does, so free unknowns do not
//! move. Components of the step along singular values below about `10⁻⁶·σ_max` are damped (a
//! Levenberg–Marquardt step): near a singular configuration Newton slows but does not jump.
//! A full step that leaves over half the residual lowers `μ` a hundredfold (down to `10⁻¹⁶`);
//! a step that does not lower `‖e‖` is halved (up to 30 times), as in [`super::newton`]. When
//! the normal equations (which square the conditioning) do not converge on a system with
//! little fill, the solve runs again with the QR steps of [`super::sparse_qr`].
//!
//! The elimination order is computed once per solve from the body graph (the elimination
//! graph gives the factor's structure as it goes); the memory the factor needs is checked
//! against the budget before it is allocated, and every ordering step, evaluation and
//! factorization is charged to a work [`Meter`].

use super::newton::{NewtonOptions, NewtonOutcome, System, Targets};
use super::pose::{Configuration, Pose};
use super::residual::PositionModel;
use super::sparse_qr::Jacobian;
use crate::budget::{BudgetExceeded, Meter};
use crate::cholesky::{Normal, Symbolic, symbolic};
use crate::motion::twist_shift;
use nalgebra::{DMatrix, DVector, Vector3};
use rayon::prelude::*;

/// Largest system (columns) whose final Jacobian gets a dense SVD for the report's nullity
/// and conditioning; above it they are estimated from the Cholesky pivots.
pub const DENSE_REPORT_COLUMNS: usize = 600;

/// Damping `μ` relative to the largest diagonal of the scaled normal equations: steps along
/// singular values below about `10⁻⁶·σ_max` are damped.
const DAMPING: f64 = 1e-12;

/// Least damping (about the rounding of the unit diagonal): singular values down to about
/// `10⁻⁸·σ_max` resolved.
const MIN_DAMPING: f64 = 1e-16;

/// A full step that leaves more than this fraction of `‖e‖` converges only linearly: the
/// damping, not the equations, sets its pace, and it is lowered a hundredfold.
const SLOW: f64 = 0.5;

/// A step that leaves more than this fraction of `‖e‖` made no real progress: [`STALLS`] of
/// them in a row end the QR steps (a target out of reach, where the residual's least-squares
/// minimum is not zero).
const FLAT: f64 = 0.99;

/// Halved or slow steps after which the normal equations give way to the QR steps (where
/// those are affordable): they are limited by the conditioning, not the damping.
const STALLS: usize = 4;

/// Where each pair's blocks go: elimination indices of its unknown sides and the
/// off-diagonal block joining them.
#[derive(Clone, Copy)]
pub(super) struct Slot {
    pub(super) a: Option<u32>,
    pub(super) b: Option<u32>,
    off: Option<usize>,
}

/// The first piece of a continuation, as a fraction of the input's move.
const INITIAL_PIECE: f64 = 0.25;

/// The smallest piece a continuation cuts the move into.
const MIN_PIECE: f64 = 1.0 / 16.0;

/// The targets a fraction `f` of the way: the goal itself at 1 (and where a value has no start).
fn partial(goal: &Targets, moves: &[Vec<(f64, f64)>], f: f64) -> Targets {
    if f >= 1.0 {
        return goal.clone();
    }
    goal.iter()
        .zip(moves)
        .map(|(t, m)| {
            if m.len() != t.len() {
                return t.clone();
            }
            m.iter().map(|&(v, d)| v + f * d).collect()
        })
        .collect()
}

/// Pairs evaluated at once (bounds the memory of one parallel batch).
const CHUNK: usize = 4096;

/// The sparse global solver: [`System::solve_local`] for systems of any size.
pub struct Sparse<'a> {
    sys: &'a System,
    model: &'a PositionModel,
    targets: Targets,
    sym: Symbolic,
    pub(super) slots: Vec<Slot>,
    col: Vec<u32>,
    /// Per elimination index: the local unknown (index in `System::bodies`) and its reference
    /// point (the mean of its joint points, in its reference coordinates).
    body: Vec<u32>,
    centre: Vec<Vector3<f64>>,
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
        opts.budget.check_memory(
            sym.factor_bytes()
                .saturating_add((sys.pairs.len() as u64).saturating_mul(24)),
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
        let mut sum = vec![(Vector3::zeros(), 0u32); n];
        for &p in &sys.pairs {
            let pair = &model.pairs[p];
            let (xa, xb) = pair.anchors();
            for (body, x) in [(pair.a, xa), (pair.b, xb)] {
                if let Some(c) = known(body) {
                    let e = &mut sum[c as usize];
                    e.0 += x;
                    e.1 += 1;
                }
            }
        }
        let mut body = vec![0u32; n];
        let mut centre = vec![Vector3::zeros(); n];
        for (c, &(x, m)) in sum.iter().enumerate() {
            let k = sym.pos[c] as usize;
            body[k] = c as u32;
            centre[k] = if m > 0 && x.iter().all(|v| v.is_finite()) {
                x / m as f64
            } else {
                Vector3::zeros()
            };
        }
        Ok(Sparse {
            sys,
            model,
            targets: targets.clone(),
            sym,
            slots,
            col,
            body,
            centre,
        })
    }

    /// Solve for other driven targets with the same ordering (a continuation's steps).
    pub(super) fn set_targets(&mut self, targets: Targets) {
        self.targets = targets;
    }

    /// The factor's structure.
    pub fn symbolic(&self) -> &Symbolic {
        &self.sym
    }

    /// Twist size B.
    pub(super) fn model_b(&self) -> usize {
        self.model.b()
    }

    /// Where each unknown's reference point is at `local` (elimination order).
    fn points(&self, local: &[Pose]) -> Vec<Vector3<f64>> {
        self.body
            .iter()
            .zip(&self.centre)
            .map(|(&c, x)| local[c as usize].point(x))
            .collect()
    }

    /// Per unknown (elimination order), [`twist_shift`] at its reference point at `local`:
    /// its twist about that point to the twist about the origin (`None` in a spherical
    /// mechanism). About a point on the body a rotation no longer carries the body's distance
    /// from the origin, which made the Jacobian columns of far bodies nearly parallel.
    fn shifts(&self, local: &[Pose]) -> Vec<Option<DMatrix<f64>>> {
        let space = self.model.space;
        self.points(local)
            .iter()
            .map(|p| twist_shift(space, [p.x, p.y, p.z]))
            .collect()
    }

    /// Residuals (all pairs, in order), per-pair maxima, and the normal equations into `ne`.
    fn evaluate(
        &self,
        config: &Configuration,
        local: &[Pose],
        ne: &mut Normal,
        mut jac: Option<&mut Jacobian>,
        meter: &mut Meter,
    ) -> Result<(Vec<f64>, Vec<f64>), BudgetExceeded> {
        let b = self.model.b();
        let bb = b * b;
        if let Some(j) = jac.as_deref_mut() {
            j.clear();
        }
        let pose = |body: usize| match self.col.get(body).copied() {
            Some(c) if c != u32::MAX => local[c as usize],
            _ => config.poses[body],
        };
        ne.clear();
        let shifts = self.shifts(local);
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
            for (mut e, slot) in eqs.into_iter().zip(slots) {
                let rows = e.residual.len();
                per_pair.push(e.residual.iter().fold(0.0f64, |m, x| m.max(x.abs())));
                r.extend_from_slice(&e.residual);
                // Columns in twists about each unknown's point: `J_O M(p)`.
                for (s, side) in [(slot.a, 0), (slot.b, 1)] {
                    if let Some(shift) = s.and_then(|k| shifts[k as usize].as_ref()) {
                        let cols = e.jacobian.columns(side * b, b) * shift;
                        e.jacobian.columns_mut(side * b, b).copy_from(&cols);
                    }
                }
                let j = &e.jacobian;
                if let Some(store) = jac.as_deref_mut() {
                    store.push(j);
                }
                let sides = [(slot.a, 0usize), (slot.b, 1usize)];
                for &(s, side) in &sides {
                    let Some(k) = s else { continue };
                    let k = k as usize;
                    let g = &mut ne.grad[k * b..(k + 1) * b];
                    for c in 0..b {
                        let mut v = 0.0;
                        for i in 0..rows {
                            v += j[(i, side * b + c)] * e.residual[i];
                        }
                        g[c] += v;
                    }
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

    /// Gauss–Newton from `config`; returns the outcome and the unknowns' new poses. The steps
    /// come from the normal equations; when they do not converge on a system whose factor has
    /// little fill (chains of loops), the solve runs again from `config` with the steps of the
    /// sparse QR ([`super::sparse_qr`]), which does not square the conditioning (from where
    /// the normal equations stalled, the QR steps fared worse: those had drifted along the
    /// near-null directions), and the better of the two ends is kept.
    pub fn solve(
        &self,
        config: &Configuration,
        opts: &NewtonOptions,
        meter: &mut Meter,
    ) -> Result<(NewtonOutcome, Vec<Pose>), BudgetExceeded> {
        let first = self.run(config, opts, meter, false)?;
        if first.0.converged || !self.qr_affordable() {
            return Ok(first);
        }
        let second = self.run(config, opts, meter, true)?;
        Ok(if second.0.residual < first.0.residual {
            second
        } else {
            first
        })
    }

    /// [`Sparse::solve`], and where it does not converge (the iteration limit, or steps that
    /// stalled: no proof that no solution exists), a continuation: the driven values are moved
    /// from `config`'s to the targets in pieces, each solved from the last (a large input move
    /// takes Newton outside its basin on a long chain of loops; a piece stays inside). A piece
    /// that does not converge is cut in half, down to [`MIN_PIECE`] of the move; then the first
    /// outcome stands.
    pub fn solve_continued(
        &mut self,
        config: &Configuration,
        opts: &NewtonOptions,
        meter: &mut Meter,
    ) -> Result<(NewtonOutcome, Vec<Pose>), BudgetExceeded> {
        let first = self.solve(config, opts, meter)?;
        let open = |o: &NewtonOutcome| o.iterations >= opts.max_iterations || o.stalled;
        if first.0.converged || !open(&first.0) {
            return Ok(first);
        }
        let goal = std::mem::take(&mut self.targets);
        let moves = self.driven_moves(config, &goal);
        let mut at = config.clone();
        let (mut done, mut piece) = (0.0f64, INITIAL_PIECE);
        let (mut last, mut iterations) = (None, first.0.iterations);
        while done < 1.0 {
            let next = (done + piece).min(1.0);
            self.set_targets(partial(&goal, &moves, next));
            let (out, poses) = self.solve(&at, opts, meter)?;
            iterations += out.iterations;
            if out.converged {
                for (&b, p) in self.sys.bodies.iter().zip(&poses) {
                    at.poses[b] = *p;
                }
                done = next;
                last = Some((out, poses));
            } else if piece / 2.0 >= MIN_PIECE {
                piece /= 2.0;
            } else {
                self.set_targets(goal);
                return Ok(first);
            }
        }
        self.set_targets(goal);
        Ok(match last {
            Some((out, poses)) => (NewtonOutcome { iterations, ..out }, poses),
            None => first,
        })
    }

    /// Each driven value's start (at `config`) and its move to `goal` (angles the short way
    /// round), per pair of the model.
    fn driven_moves(&self, config: &Configuration, goal: &Targets) -> Vec<Vec<(f64, f64)>> {
        goal.iter()
            .enumerate()
            .map(|(p, t)| {
                if t.is_empty() {
                    return Vec::new();
                }
                let pair = &self.model.pairs[p];
                let now = self
                    .model
                    .pair_values(p, &config.poses[pair.a], &config.poses[pair.b]);
                t.iter()
                    .zip(now)
                    .map(|(&t, (v, angle))| {
                        let d = t - v;
                        let d = if angle {
                            d - std::f64::consts::TAU * (d / std::f64::consts::TAU).round()
                        } else {
                            d
                        };
                        (v, d)
                    })
                    .collect()
            })
            .collect()
    }

    /// Scale `ne` to a unit diagonal and factor it, damped by `damping` of that diagonal's
    /// largest entry: the damping `μ` and the squared pivots.
    fn damped_factor(
        &self,
        ne: &mut Normal,
        damping: f64,
        meter: &mut Meter,
    ) -> Result<(f64, Vec<f64>), BudgetExceeded> {
        ne.equilibrate(&self.sym);
        let top = ne.diagonal(&self.sym).into_iter().fold(0.0f64, f64::max);
        let mu = damping * top.max(1e-300);
        meter.charge(self.sym.factor_work())?;
        Ok((mu, ne.factor(&self.sym, mu)))
    }

    /// The report's singular values at `local`: of the dense Jacobian up to
    /// [`DENSE_REPORT_COLUMNS`] columns, above that estimated from the factor's `pivots`
    /// (square roots of the pivots less the damping `mu`; zero when a pivot is no more than
    /// twice the damping).
    fn singular_values(
        &self,
        config: &Configuration,
        local: &[Pose],
        pivots: &[f64],
        mu: f64,
    ) -> Vec<f64> {
        if self.sys.bodies.len() * self.model.b() <= DENSE_REPORT_COLUMNS {
            let mut cfg = config.clone();
            for (&x, p) in self.sys.bodies.iter().zip(local) {
                cfg.poses[x] = *p;
            }
            let (_, j, _) = self.sys.evaluate(self.model, &self.targets, &cfg);
            return super::newton::singular_values(j);
        }
        let mut s: Vec<f64> = pivots
            .iter()
            .map(|&p| if p <= 2.0 * mu { 0.0 } else { (p - mu).sqrt() })
            .collect();
        s.sort_by(|a, b| b.total_cmp(a));
        s
    }

    /// Gauss–Newton from `config` with the normal equations' steps, or the QR's (`qr`).
    /// Longer than most: the step, the line search and the report share the loop's state.
    fn run(
        &self,
        config: &Configuration,
        opts: &NewtonOptions,
        meter: &mut Meter,
        qr: bool,
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
        fn store(qr: bool, j: &mut Jacobian) -> Option<&mut Jacobian> {
            if qr { Some(j) } else { None }
        }
        let (mut r, mut per_pair) =
            self.evaluate(config, &local, &mut ne, store(qr, &mut jac), meter)?;
        let mut iterations = 0;
        let mut pivots: Option<Vec<f64>> = None;
        let mut mu = 0.0;
        let mut damping = DAMPING;
        let mut stalls = 0;
        let mut flat = 0;
        let mut stalled = false;
        loop {
            let finite = ne.diag.iter().chain(&ne.off).all(|x| x.is_finite());
            if n == 0 || r.is_empty() || !finite {
                break;
            }
            let done = inf(&r) <= opts.tolerance || iterations >= opts.max_iterations;
            let mut step = if qr {
                if done {
                    break;
                }
                self.qr_step(&jac, &r, &ne.diagonal(&self.sym), opts, meter)?
            } else {
                let (m, p) = self.damped_factor(&mut ne, damping, meter)?;
                (mu, pivots) = (m, Some(p));
                if done {
                    break;
                }
                let mut rhs: Vec<f64> = ne.grad.iter().map(|g| -g).collect();
                ne.solve(&self.sym, &mut rhs);
                for (x, d) in rhs.iter_mut().zip(&ne.scale) {
                    *x *= d;
                }
                rhs
            };
            if !step.iter().all(|x| x.is_finite()) {
                break;
            }
            for (t, shift) in step.chunks_exact_mut(b).zip(self.shifts(&local)) {
                if let Some(shift) = shift {
                    let about_origin = shift * DVector::from_column_slice(t);
                    t.copy_from_slice(about_origin.as_slice());
                }
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
                let (r2, p2) =
                    self.evaluate(config, &local, &mut ne, store(qr, &mut jac), meter)?;
                if norm(&r2) < norm0 || inf(&r2) <= opts.tolerance {
                    (r, per_pair) = (r2, p2);
                    accepted = true;
                    break;
                }
                t *= 0.5;
            }
            if !accepted {
                local = base;
                if pivots.is_none() {
                    self.evaluate(config, &local, &mut ne, None, meter)?;
                }
                break;
            }
            let slow = t < 1.0 || norm(&r) > SLOW * norm0;
            stalls += usize::from(slow);
            flat = if norm(&r) > FLAT * norm0 { flat + 1 } else { 0 };
            if (stalls >= STALLS && !qr && self.qr_affordable()) || (qr && flat >= STALLS) {
                stalled = true;
                break;
            }
            damping = if t < 1.0 {
                DAMPING
            } else if norm(&r) > SLOW * norm0 {
                (damping * 1e-2).max(MIN_DAMPING)
            } else {
                damping
            };
        }
        let columns = n * b;
        if columns > DENSE_REPORT_COLUMNS && pivots.is_none() {
            let finite = ne.diag.iter().chain(&ne.off).all(|x| x.is_finite());
            if !r.is_empty() && finite {
                let (m, p) = self.damped_factor(&mut ne, DAMPING, meter)?;
                (mu, pivots) = (m, Some(p));
            }
        }
        let singular_values = self.singular_values(config, &local, &pivots.unwrap_or_default(), mu);
        let out = NewtonOutcome {
            converged: inf(&r) <= opts.tolerance,
            iterations,
            residual: inf(&r),
            singular_values,
            unknowns: columns,
            equations: r.len(),
            pair_residuals: per_pair,
            stalled,
        };
        Ok((out, local))
    }
}
