//! Gauss–Newton least squares on a set of joint equations over a set of unknown bodies.
//!
//! Each step is the minimum-norm least-squares solution of `J δ = −e` (SVD, singular values
//! below `1e-10·σ_max` dropped), so redundant equations (a planar loop written in 3D) and
//! unknowns the equations leave free are both fine: free unknowns do not move (least change).
//! A step that does not lower `‖e‖` is halved (up to 30 times).

use super::pose::{Configuration, Pose};
use super::residual::PositionModel;
use crate::budget::{BudgetExceeded, Meter};
use nalgebra::{DMatrix, DVector};

/// A system: some pairs' equations, some bodies unknown (the others held at their poses).
#[derive(Clone, Debug)]
pub struct System {
    /// Pair indices (into `PositionModel::pairs`).
    pub pairs: Vec<usize>,
    /// Unknown bodies, in column order.
    pub bodies: Vec<usize>,
}

/// Options of [`System::solve`].
#[derive(Clone, Copy, Debug)]
pub struct NewtonOptions {
    /// Converged when every residual is at most this (model units).
    pub tolerance: f64,
    /// Iteration limit.
    pub max_iterations: usize,
    /// Work and memory limits: every iteration charges its evaluations and factorizations
    /// to a work meter ([`crate::budget::Meter`]); the sparse global solve checks its factor's
    /// memory before allocating it.
    pub budget: crate::budget::Budget,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            tolerance: 1e-11,
            max_iterations: 60,
            budget: crate::budget::Budget::DEFAULT,
        }
    }
}

/// The outcome of a solve.
#[derive(Clone, Debug, PartialEq)]
pub struct NewtonOutcome {
    /// Whether the residual reached the tolerance.
    pub converged: bool,
    /// Iterations done.
    pub iterations: usize,
    /// Largest residual at the end (model units).
    pub residual: f64,
    /// Singular values of the final Jacobian, descending.
    pub singular_values: Vec<f64>,
    /// Unknowns (columns).
    pub unknowns: usize,
    /// Equations (rows).
    pub equations: usize,
    /// Largest residual per pair at the end, in `System::pairs` order.
    pub pair_residuals: Vec<f64>,
    /// The steps stopped lowering the residual at their pace before the iteration limit (the
    /// sparse solver's slow-step rules), which says nothing of whether a solution exists.
    pub stalled: bool,
}

impl NewtonOutcome {
    /// Nullity of the Jacobian (columns less rank, relative threshold `rel`).
    pub fn nullity(&self, rel: f64) -> usize {
        let top = self
            .singular_values
            .first()
            .copied()
            .unwrap_or(0.0)
            .max(1.0);
        let rank = self
            .singular_values
            .iter()
            .filter(|&&s| s > rel * top)
            .count();
        self.unknowns - rank
    }

    /// Smallest singular value above `1e-9 ×` the largest, relative to the largest (at
    /// least 1): how close the equations are to losing one more rank (1 when there are none).
    pub fn conditioning(&self) -> f64 {
        let top = self
            .singular_values
            .first()
            .copied()
            .unwrap_or(0.0)
            .max(1.0);
        self.singular_values
            .iter()
            .copied()
            .filter(|&s| s > 1e-9 * top)
            .fold(top, f64::min)
            / top
    }
}

/// Driven targets per pair (model units; empty = not driven).
pub type Targets = Vec<Vec<f64>>;

/// The unknown bodies of a system and their places in it, sorted by body: a dense system has
/// at most a hundred, where a search costs less than hashing.
struct Columns(Vec<(usize, usize)>);

impl Columns {
    fn get(&self, body: usize) -> Option<usize> {
        self.0
            .binary_search_by_key(&body, |&(b, _)| b)
            .ok()
            .map(|k| self.0[k].1)
    }
}

impl System {
    /// Residual vector, Jacobian and per-pair maximum residual at `config`.
    pub fn evaluate(
        &self,
        model: &PositionModel,
        targets: &Targets,
        config: &Configuration,
    ) -> (DVector<f64>, DMatrix<f64>, Vec<f64>) {
        let local: Vec<Pose> = self.bodies.iter().map(|&b| config.poses[b]).collect();
        self.evaluate_local(model, targets, config, &local, &self.columns())
    }

    /// Column block of each unknown body.
    fn columns(&self) -> Columns {
        let mut c: Vec<(usize, usize)> = self
            .bodies
            .iter()
            .enumerate()
            .map(|(i, &b)| (b, i))
            .collect();
        c.sort_unstable();
        Columns(c)
    }

    /// [`System::evaluate`] with the unknown bodies at `local` (in `bodies` order) and the
    /// others at `config`.
    fn evaluate_local(
        &self,
        model: &PositionModel,
        targets: &Targets,
        config: &Configuration,
        local: &[Pose],
        col: &Columns,
    ) -> (DVector<f64>, DMatrix<f64>, Vec<f64>) {
        let b = model.b();
        let pose = |body: usize| match col.get(body) {
            Some(i) => local[i],
            None => config.poses[body],
        };
        let blocks: Vec<_> = self
            .pairs
            .iter()
            .map(|&p| {
                let pair = &model.pairs[p];
                model.pair_equations(
                    p,
                    &pose(pair.a),
                    &pose(pair.b),
                    targets.get(p).map(Vec::as_slice).unwrap_or(&[]),
                )
            })
            .collect();
        let rows: usize = blocks.iter().map(|e| e.residual.len()).sum();
        let mut r = DVector::zeros(rows);
        let mut j = DMatrix::zeros(rows, self.bodies.len() * b);
        let mut per_pair = Vec::with_capacity(blocks.len());
        let mut at = 0;
        for (e, &p) in blocks.iter().zip(&self.pairs) {
            let pair = &model.pairs[p];
            let n = e.residual.len();
            let mut worst: f64 = 0.0;
            for i in 0..n {
                r[at + i] = e.residual[i];
                worst = worst.max(e.residual[i].abs());
            }
            per_pair.push(worst);
            for (side, body) in [(0, pair.a), (1, pair.b)] {
                let Some(c) = col.get(body) else { continue };
                if side == 1 && pair.a == pair.b {
                    continue;
                }
                for i in 0..n {
                    for k in 0..b {
                        j[(at + i, c * b + k)] += e.jacobian[(i, side * b + k)];
                    }
                }
            }
            at += n;
        }
        (r, j, per_pair)
    }

    /// Solve in place from `config` (only the unknown bodies move).
    pub fn solve(
        &self,
        model: &PositionModel,
        targets: &Targets,
        config: &mut Configuration,
        opts: &NewtonOptions,
    ) -> NewtonOutcome {
        let (out, poses) = self.solve_local(model, targets, config, opts);
        for (&b, p) in self.bodies.iter().zip(poses) {
            config.poses[b] = p;
        }
        out
    }

    /// Solve from `config` without changing it: the outcome and the unknown bodies' new poses
    /// (in `bodies` order). Reads only the poses the system's pairs touch.
    pub fn solve_local(
        &self,
        model: &PositionModel,
        targets: &Targets,
        config: &Configuration,
        opts: &NewtonOptions,
    ) -> (NewtonOutcome, Vec<Pose>) {
        let mut meter = opts.budget.meter("the position solve");
        match self.solve_metered(model, targets, config, opts, &mut meter) {
            Ok(x) => x,
            // Out of budget: unchanged poses, not converged.
            Err(_) => {
                let (r, j, per_pair) = self.evaluate(model, targets, config);
                let residual = r.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                let out = NewtonOutcome {
                    converged: false,
                    iterations: 0,
                    residual,
                    singular_values: Vec::new(),
                    unknowns: j.ncols(),
                    equations: j.nrows(),
                    pair_residuals: per_pair,
                    stalled: false,
                };
                (out, self.bodies.iter().map(|&x| config.poses[x]).collect())
            }
        }
    }

    /// Memory (bytes) the dense solve of this system needs: the Jacobian and the SVD's
    /// factors.
    pub fn dense_bytes(&self, model: &PositionModel) -> u64 {
        let b = model.b() as u64;
        let cols = self.bodies.len() as u64 * b;
        let rows = self.pairs.len() as u64 * b;
        let big = rows.max(cols);
        big.saturating_mul(big).saturating_mul(8 * 3)
    }

    /// [`System::solve_local`], charging `meter` (each evaluation and each SVD) and checking
    /// the dense memory against `opts.budget` first.
    pub fn solve_metered(
        &self,
        model: &PositionModel,
        targets: &Targets,
        config: &Configuration,
        opts: &NewtonOptions,
        meter: &mut Meter,
    ) -> Result<(NewtonOutcome, Vec<Pose>), BudgetExceeded> {
        opts.budget.check_memory(self.dense_bytes(model), || {
            format!(
                "the dense solve of {} bodies and {} joint pairs",
                self.bodies.len(),
                self.pairs.len()
            )
        })?;
        let eval_work = self.pairs.len() as u64 * 200;
        let b = model.b();
        let col = self.columns();
        let inf = |r: &DVector<f64>| {
            if r.iter().all(|x| x.is_finite()) {
                r.iter().fold(0.0f64, |m, x| m.max(x.abs()))
            } else {
                f64::INFINITY
            }
        };
        let mut local: Vec<Pose> = self.bodies.iter().map(|&x| config.poses[x]).collect();
        meter.charge(eval_work)?;
        let (mut r, mut j, mut per_pair) =
            self.evaluate_local(model, targets, config, &local, &col);
        let mut iterations = 0;
        // The singular values of the last `j`, once they are known.
        let mut svd_values: Option<Vec<f64>>;
        loop {
            if j.nrows() == 0 || j.ncols() == 0 || !j.iter().chain(r.iter()).all(|x| x.is_finite())
            {
                svd_values = Some(Vec::new());
                break;
            }
            // Bounded iterations: never loop on a pathological matrix.
            let (rows, cols) = (j.nrows() as u64, j.ncols() as u64);
            meter.charge(
                rows.max(cols)
                    .saturating_mul(cols)
                    .saturating_mul(cols.min(rows))
                    / 4,
            )?;
            let last = inf(&r) <= opts.tolerance
                || iterations >= opts.max_iterations
                || !r.iter().all(|x| x.is_finite());
            let step = match next_step(&j, &r, last) {
                Next::Stop(values) => {
                    svd_values = Some(values);
                    break;
                }
                Next::Step(step, values) => {
                    svd_values = values;
                    step
                }
            };
            iterations += 1;
            let base = local.clone();
            let norm0 = r.norm();
            let mut t = 1.0;
            let mut accepted = false;
            for _ in 0..30 {
                for (i, p) in local.iter_mut().enumerate() {
                    let tw: Vec<f64> = (0..b).map(|k| t * step[i * b + k]).collect();
                    *p = base[i].moved_by(model.space, &tw);
                }
                meter.charge(eval_work)?;
                let (r2, j2, p2) = self.evaluate_local(model, targets, config, &local, &col);
                if r2.norm() < norm0 || inf(&r2) <= opts.tolerance {
                    (r, j, per_pair) = (r2, j2, p2);
                    accepted = true;
                    break;
                }
                t *= 0.5;
            }
            if !accepted {
                local = base;
                break;
            }
        }
        // A failed line search after an LU step: the values at the point kept.
        let svd_values = match svd_values {
            Some(mut v) => {
                v.sort_by(|a, b| b.total_cmp(a));
                v
            }
            None => singular_values(j.clone()),
        };
        let out = NewtonOutcome {
            converged: inf(&r) <= opts.tolerance,
            iterations,
            residual: inf(&r),
            singular_values: svd_values,
            unknowns: j.ncols(),
            equations: j.nrows(),
            pair_residuals: per_pair,
            stalled: false,
        };
        Ok((out, local))
    }
}

/// What a Newton iteration does at a point.
enum Next {
    /// Take the step; the singular values when an SVD gave it.
    Step(DVector<f64>, Option<Vec<f64>>),
    /// Stop, with the singular values at the point.
    Stop(Vec<f64>),
}

/// The step at `j`, `r`: the LU step of a square, well conditioned system, else the SVD's
/// damped minimum-norm one; at the `last` point only the singular values.
fn next_step(j: &DMatrix<f64>, r: &DVector<f64>, last: bool) -> Next {
    if let Some(step) = (!last).then(|| square_step(j, r)).flatten() {
        return Next::Step(step, None);
    }
    let Some(svd) = nalgebra::SVD::try_new(j.clone(), !last, !last, f64::EPSILON, 10_000) else {
        return Next::Stop(Vec::new());
    };
    let values: Vec<f64> = svd.singular_values.iter().copied().collect();
    if last {
        return Next::Stop(values);
    }
    let top = values.iter().copied().fold(0.0, f64::max);
    match svd.solve(&(-r), 1e-10 * top.max(1e-300)) {
        Ok(step) => Next::Step(step, Some(values)),
        Err(_) => Next::Stop(values),
    }
}

/// Smallest ratio of the smallest to the largest pivot of a square system's LU (full
/// pivoting) for which its solution is taken as the Newton step; below it the SVD's damped
/// minimum-norm step is taken.
const SQUARE_PIVOT_RATIO: f64 = 1e-6;

/// The step `J⁻¹(−r)` of a square `J` whose LU pivots stay within [`SQUARE_PIVOT_RATIO`]
/// of each other (far from a singular configuration), else `None`. A group of a solve is
/// usually square; its LU costs a small part of an SVD with singular vectors.
fn square_step(j: &DMatrix<f64>, r: &DVector<f64>) -> Option<DVector<f64>> {
    if j.nrows() != j.ncols() {
        return None;
    }
    let lu = j.clone().full_piv_lu();
    let d = lu.u().diagonal();
    let (lo, hi) = d.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
        (lo.min(x.abs()), hi.max(x.abs()))
    });
    // NaN pivots fail this comparison too.
    if lo.partial_cmp(&(SQUARE_PIVOT_RATIO * hi)) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    lu.solve(&(-r)).filter(|s| s.iter().all(|x| x.is_finite()))
}

/// The singular values of `j`, largest first (none for an empty matrix or an SVD that does not
/// converge).
pub(super) fn singular_values(j: DMatrix<f64>) -> Vec<f64> {
    if j.nrows() == 0 || j.ncols() == 0 {
        return Vec::new();
    }
    let mut s: Vec<f64> = nalgebra::SVD::try_new(j, false, false, f64::EPSILON, 10_000)
        .map(|d| d.singular_values.iter().copied().collect())
        .unwrap_or_default();
    s.sort_by(|a, b| b.total_cmp(a));
    s
}
