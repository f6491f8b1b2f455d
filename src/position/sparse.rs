//! Sparse Gauss–Newton on many bodies at once: the global reference solve at scale.
//!
//! The Jacobian of a mechanism is block sparse: a pair's equations touch its two bodies only.
//! Each step solves the normal equations `(JᵀJ + μI) δ = −Jᵀe` by a block Cholesky
//! factorization (one `B × B` block per body, `B` = 3 or 6) in a minimum-degree elimination
//! order of the body graph. `μ = 10⁻¹²·max diag(JᵀJ)` keeps the factorization defined when the
//! equations are redundant (a planar loop written in space) or leave unknowns free (an
//! isolated spin); since `Jᵀe` lies in the row space of `J`, the step then stays (to rounding)
//! in that row space, as the dense solver's minimum-norm step does, so free unknowns do not
//! move. Components of the step along singular values below about `10⁻⁶·σ_max` are damped (a
//! Levenberg–Marquardt step): near a singular configuration Newton slows but does not jump.
//! A step that does not lower `‖e‖` is halved (up to 30 times), as in [`super::newton`].
//!
//! The elimination order is computed once per solve from the body graph (the elimination
//! graph gives the factor's structure as it goes); the memory the factor needs is checked
//! against the budget before it is allocated, and every ordering step, evaluation and
//! factorization is charged to a work [`Meter`].

use super::newton::{NewtonOptions, NewtonOutcome, System, Targets};
use super::pose::{Configuration, Pose};
use super::residual::PositionModel;
use crate::budget::{BudgetExceeded, Meter};
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Largest system (columns) whose final Jacobian gets a dense SVD for the report's nullity
/// and conditioning; above it they are estimated from the Cholesky pivots.
pub const DENSE_REPORT_COLUMNS: usize = 600;

/// Bytes of factor storage per entry of the elimination structure, beside the blocks.
const STRUCT_BYTES: u64 = 16;

/// The structure of the block Cholesky factor: columns in elimination order.
#[derive(Clone, Debug)]
pub struct Symbolic {
    /// Block size.
    b: usize,
    /// `pos[c]`: elimination index of local unknown `c` (index in `System::bodies`).
    pos: Vec<u32>,
    /// Column `k`'s rows (elimination indices above `k`, ascending) are
    /// `rows[start[k]..start[k + 1]]`.
    start: Vec<usize>,
    rows: Vec<u32>,
}

impl Symbolic {
    /// Number of off-diagonal blocks of the factor.
    pub fn off_blocks(&self) -> usize {
        self.rows.len()
    }

    /// Bytes of the numeric factor.
    pub fn factor_bytes(&self) -> u64 {
        let blocks = (self.pos.len() + self.rows.len()) as u64;
        blocks
            .saturating_mul((self.b * self.b * 8) as u64)
            .saturating_add(self.rows.len() as u64 * STRUCT_BYTES)
    }

    /// Work units of one numeric factorization (block multiply-adds times `B³`).
    pub fn factor_work(&self) -> u64 {
        let b3 = (self.b * self.b * self.b) as u64;
        (0..self.pos.len())
            .map(|k| {
                let l = (self.start[k + 1] - self.start[k]) as u64;
                (l * (l + 1) / 2 + l + 1) * b3
            })
            .fold(0u64, u64::saturating_add)
    }

    /// Index (into the off-diagonal blocks) of block (row `i`, column `k`), `i > k`.
    fn find(&self, k: usize, i: u32) -> Option<usize> {
        let r = &self.rows[self.start[k]..self.start[k + 1]];
        r.binary_search(&i).ok().map(|x| self.start[k] + x)
    }
}

/// Sorted union of `a` without `skip_a` and `b` without `skip_b`.
fn merge(a: &[u32], b: &[u32], skip: u32, skip2: u32) -> Vec<u32> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        let x = match (a.get(i), b.get(j)) {
            (Some(&x), Some(&y)) if x == y => {
                i += 1;
                j += 1;
                x
            }
            (Some(&x), Some(&y)) if x < y => {
                i += 1;
                x
            }
            (Some(_), Some(&y)) => {
                j += 1;
                y
            }
            (Some(&x), None) => {
                i += 1;
                x
            }
            (None, Some(&y)) => {
                j += 1;
                y
            }
            (None, None) => break,
        };
        if x != skip && x != skip2 {
            out.push(x);
        }
    }
    out
}

/// Minimum-degree elimination of the graph of `n` unknowns with `edges`: the elimination
/// order and the factor structure. Ties go to the lowest index (deterministic). The
/// elimination graph's size is checked against `max_bytes` as it grows.
pub fn symbolic(
    n: usize,
    b: usize,
    edges: &[(u32, u32)],
    meter: &mut Meter,
    max_bytes: u64,
) -> Result<Symbolic, BudgetExceeded> {
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n];
    for &(u, v) in edges {
        if u != v {
            adj[u as usize].push(v);
            adj[v as usize].push(u);
        }
    }
    for a in &mut adj {
        a.sort_unstable();
        a.dedup();
    }
    meter.charge(edges.len() as u64 * 4 + n as u64)?;
    let mut alive = vec![true; n];
    let mut heap: BinaryHeap<Reverse<(usize, u32)>> = (0..n as u32)
        .map(|v| Reverse((adj[v as usize].len(), v)))
        .collect();
    let mut order: Vec<u32> = Vec::with_capacity(n);
    let mut structure: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut stored: u64 = adj.iter().map(|a| a.len() as u64).sum();
    let block = (b * b * 8) as u64 + STRUCT_BYTES;
    let mut fill: u64 = 0;
    while let Some(Reverse((d, v))) = heap.pop() {
        let vi = v as usize;
        if !alive[vi] || adj[vi].len() != d {
            continue;
        }
        alive[vi] = false;
        order.push(v);
        let nb = std::mem::take(&mut adj[vi]);
        for &u in &nb {
            let ui = u as usize;
            let merged = merge(&adj[ui], &nb, v, u);
            meter.charge((adj[ui].len() + nb.len()) as u64 + 1)?;
            stored = stored + merged.len() as u64 - adj[ui].len() as u64;
            adj[ui] = merged;
            heap.push(Reverse((adj[ui].len(), u)));
        }
        stored = stored.saturating_sub(nb.len() as u64);
        // The factor holds every structure so far, the elimination graph the rest.
        fill += nb.len() as u64;
        structure[vi] = nb;
        let estimate = stored
            .saturating_mul(4)
            .saturating_add((order.len() as u64 + fill).saturating_mul(block));
        if estimate > max_bytes {
            return Err(BudgetExceeded {
                limit: crate::budget::Limit::Memory,
                what: "the sparse factorization of the global solve".into(),
                needed: estimate,
                at_least: true,
                allowed: max_bytes,
            });
        }
    }
    let mut pos = vec![0u32; n];
    for (i, &v) in order.iter().enumerate() {
        pos[v as usize] = i as u32;
    }
    let mut start = Vec::with_capacity(n + 1);
    let mut rows = Vec::new();
    start.push(0);
    for &v in &order {
        let mut r: Vec<u32> = structure[v as usize]
            .iter()
            .map(|&u| pos[u as usize])
            .collect();
        r.sort_unstable();
        rows.extend_from_slice(&r);
        start.push(rows.len());
    }
    Ok(Symbolic {
        b,
        pos,
        start,
        rows,
    })
}

/// Dense lower Cholesky of the `b × b` row-major block `a` in place (upper part zeroed);
/// pivots below `floor` are raised to it. Returns the squared pivots.
fn chol(a: &mut [f64], b: usize, floor: f64, pivots: &mut [f64]) {
    for j in 0..b {
        let mut d = a[j * b + j];
        for k in 0..j {
            d -= a[j * b + k] * a[j * b + k];
        }
        let d = if d.is_finite() && d > floor { d } else { floor };
        pivots[j] = d;
        let l = d.sqrt();
        a[j * b + j] = l;
        for i in j + 1..b {
            let mut s = a[i * b + j];
            for k in 0..j {
                s -= a[i * b + k] * a[j * b + k];
            }
            a[i * b + j] = s / l;
        }
        for i in 0..j {
            a[i * b + j] = 0.0;
        }
    }
}

/// `x ← x L⁻ᵀ` for the row-major block `x` (each row solved against lower `l`).
fn right_solve_lt(x: &mut [f64], l: &[f64], b: usize) {
    for r in 0..b {
        let row = &mut x[r * b..(r + 1) * b];
        for j in 0..b {
            let mut s = row[j];
            for k in 0..j {
                s -= row[k] * l[j * b + k];
            }
            row[j] = s / l[j * b + j];
        }
    }
}

/// `c ← c − x yᵀ` for row-major blocks.
fn sub_xyt(c: &mut [f64], x: &[f64], y: &[f64], b: usize) {
    for i in 0..b {
        for j in 0..b {
            let mut s = 0.0;
            for k in 0..b {
                s += x[i * b + k] * y[j * b + k];
            }
            c[i * b + j] -= s;
        }
    }
}

/// The normal equations at one point, in the factor's storage.
struct Normal {
    diag: Vec<f64>,
    off: Vec<f64>,
    grad: Vec<f64>,
}

impl Normal {
    fn zeros(s: &Symbolic) -> Normal {
        let bb = s.b * s.b;
        Normal {
            diag: vec![0.0; s.pos.len() * bb],
            off: vec![0.0; s.rows.len() * bb],
            grad: vec![0.0; s.pos.len() * s.b],
        }
    }

    fn clear(&mut self) {
        self.diag.fill(0.0);
        self.off.fill(0.0);
        self.grad.fill(0.0);
    }

    /// Factor `self + μI` in place; the squared pivots, in elimination order.
    fn factor(&mut self, s: &Symbolic, mu: f64) -> Vec<f64> {
        let b = s.b;
        let bb = b * b;
        let n = s.pos.len();
        let mut pivots = vec![0.0; n * b];
        let floor = mu.max(f64::MIN_POSITIVE);
        for k in 0..n {
            let dk = &mut self.diag[k * bb..(k + 1) * bb];
            for i in 0..b {
                dk[i * b + i] += mu;
            }
            chol(dk, b, floor, &mut pivots[k * b..(k + 1) * b]);
            let lkk: Vec<f64> = dk.to_vec();
            let (lo, hi) = (s.start[k], s.start[k + 1]);
            let (left, right) = self.off.split_at_mut(hi * bb);
            let col = &mut left[lo * bb..];
            for blk in col.chunks_exact_mut(bb) {
                right_solve_lt(blk, &lkk, b);
            }
            for a in 0..hi - lo {
                let u = s.rows[lo + a] as usize;
                let lu = &col[a * bb..(a + 1) * bb];
                sub_xyt(&mut self.diag[u * bb..(u + 1) * bb], lu, lu, b);
                let mut from = s.start[u];
                for c in a + 1..hi - lo {
                    let w = s.rows[lo + c];
                    let lw = &col[c * bb..(c + 1) * bb];
                    let r = &s.rows[from..s.start[u + 1]];
                    let Ok(x) = r.binary_search(&w) else { continue };
                    let at = from + x - hi;
                    from += x + 1;
                    sub_xyt(&mut right[at * bb..(at + 1) * bb], lw, lu, b);
                }
            }
        }
        pivots
    }

    /// Solve `L Lᵀ x = rhs` with the factor in place (elimination order).
    fn solve(&self, s: &Symbolic, rhs: &mut [f64]) {
        let b = s.b;
        let bb = b * b;
        let n = s.pos.len();
        for k in 0..n {
            let l = &self.diag[k * bb..(k + 1) * bb];
            let (head, tail) = rhs.split_at_mut((k + 1) * b);
            let y = &mut head[k * b..];
            for i in 0..b {
                let mut v = y[i];
                for j in 0..i {
                    v -= l[i * b + j] * y[j];
                }
                y[i] = v / l[i * b + i];
            }
            for idx in s.start[k]..s.start[k + 1] {
                let w = s.rows[idx] as usize;
                let blk = &self.off[idx * bb..(idx + 1) * bb];
                let t = &mut tail[(w - k - 1) * b..(w - k) * b];
                for i in 0..b {
                    let mut v = 0.0;
                    for j in 0..b {
                        v += blk[i * b + j] * y[j];
                    }
                    t[i] -= v;
                }
            }
        }
        for k in (0..n).rev() {
            let (head, tail) = rhs.split_at_mut((k + 1) * b);
            let x = &mut head[k * b..];
            for idx in s.start[k]..s.start[k + 1] {
                let w = s.rows[idx] as usize;
                let blk = &self.off[idx * bb..(idx + 1) * bb];
                let t = &tail[(w - k - 1) * b..(w - k) * b];
                for j in 0..b {
                    let mut v = 0.0;
                    for i in 0..b {
                        v += blk[i * b + j] * t[i];
                    }
                    x[j] -= v;
                }
            }
            let l = &self.diag[k * bb..(k + 1) * bb];
            for i in (0..b).rev() {
                let mut v = x[i];
                for j in i + 1..b {
                    v -= l[j * b + i] * x[j];
                }
                x[i] = v / l[i * b + i];
            }
        }
    }
}

/// Where each pair's blocks go: elimination indices of its unknown sides and the
/// off-diagonal block joining them.
#[derive(Clone, Copy)]
struct Slot {
    a: Option<u32>,
    b: Option<u32>,
    off: Option<usize>,
}

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

    /// Residuals (all pairs, in order), per-pair maxima, and the normal equations into `ne`.
    fn evaluate(
        &self,
        config: &Configuration,
        local: &[Pose],
        ne: &mut Normal,
        meter: &mut Meter,
    ) -> Result<(Vec<f64>, Vec<f64>), BudgetExceeded> {
        let b = self.model.b();
        let bb = b * b;
        let pose = |body: usize| match self.col.get(body).copied() {
            Some(c) if c != u32::MAX => local[c as usize],
            _ => config.poses[body],
        };
        ne.clear();
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
        let (mut r, mut per_pair) = self.evaluate(config, &local, &mut ne, meter)?;
        let mut iterations = 0;
        let mut pivots: Vec<f64> = Vec::new();
        let mut mu = 0.0;
        let work = self.sym.factor_work();
        loop {
            let finite = ne.diag.iter().chain(&ne.off).all(|x| x.is_finite());
            if n == 0 || r.is_empty() || !finite {
                break;
            }
            let top = (0..n * b)
                .map(|i| ne.diag[(i / b) * b * b + (i % b) * (b + 1)])
                .fold(0.0f64, f64::max);
            mu = 1e-12 * top.max(1e-300);
            let mut rhs: Vec<f64> = ne.grad.iter().map(|g| -g).collect();
            meter.charge(work)?;
            pivots = ne.factor(&self.sym, mu);
            if inf(&r) <= opts.tolerance || iterations >= opts.max_iterations {
                break;
            }
            ne.solve(&self.sym, &mut rhs);
            if !rhs.iter().all(|x| x.is_finite()) {
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
                    let tw: Vec<f64> = (0..b).map(|i| t * rhs[k * b + i]).collect();
                    *p = base[c].moved_by(self.model.space, &tw);
                }
                let (r2, p2) = self.evaluate(config, &local, &mut ne, meter)?;
                if norm(&r2) < norm0 || inf(&r2) <= opts.tolerance {
                    (r, per_pair) = (r2, p2);
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
        let columns = n * b;
        let singular_values = if columns <= DENSE_REPORT_COLUMNS {
            let mut cfg = config.clone();
            for (&x, p) in self.sys.bodies.iter().zip(&local) {
                cfg.poses[x] = *p;
            }
            let (_, j, _) = self.sys.evaluate(self.model, self.targets, &cfg);
            super::newton::singular_values(j)
        } else {
            // Estimates: square roots of the pivots less the damping (zero when a pivot is
            // no more than twice the damping).
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
