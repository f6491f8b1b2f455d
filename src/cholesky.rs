//! Block-sparse Cholesky factorization of normal equations `(JᵀJ + μI) δ = −Jᵀe` whose
//! unknowns come in blocks of `B` (one block a body): a minimum-degree elimination order of
//! the blocks' graph and the factor's structure ([`symbolic`]), then the numeric factor, its
//! solve and Jacobi scaling ([`Normal`]). Numbers only: the position solver
//! (`position::sparse`) fills the blocks. The factor's memory is checked against the budget
//! before it is allocated and the ordering is charged to a work [`Meter`].

use crate::budget::{BudgetExceeded, Meter};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Bytes of factor storage per entry of the elimination structure, beside the blocks.
const STRUCT_BYTES: u64 = 16;

/// The structure of the block Cholesky factor: columns in elimination order.
#[derive(Clone, Debug)]
pub struct Symbolic {
    /// Block size.
    pub(crate) b: usize,
    /// `pos[c]`: elimination index of unknown block `c`.
    pub(crate) pos: Vec<u32>,
    /// Column `k`'s rows (elimination indices above `k`, ascending) are
    /// `rows[start[k]..start[k + 1]]`.
    pub(crate) start: Vec<usize>,
    pub(crate) rows: Vec<u32>,
}

impl Symbolic {
    /// Number of off-diagonal blocks of the factor.
    pub fn off_blocks(&self) -> usize {
        self.rows.len()
    }

    /// Most off-diagonal blocks in one column of the factor.
    pub fn widest_column(&self) -> usize {
        self.start
            .windows(2)
            .map(|w| w[1] - w[0])
            .max()
            .unwrap_or(0)
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
    pub(crate) fn find(&self, k: usize, i: u32) -> Option<usize> {
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

/// The normal equations at one point, in the factor's storage, in each body's local
/// twists (see [`Sparse`]).
pub(crate) struct Normal {
    pub(crate) diag: Vec<f64>,
    pub(crate) off: Vec<f64>,
    pub(crate) grad: Vec<f64>,
    /// Column scales of the last [`Normal::equilibrate`] (elimination order).
    pub(crate) scale: Vec<f64>,
}

impl Normal {
    pub(crate) fn zeros(s: &Symbolic) -> Normal {
        let bb = s.b * s.b;
        Normal {
            diag: vec![0.0; s.pos.len() * bb],
            off: vec![0.0; s.rows.len() * bb],
            grad: vec![0.0; s.pos.len() * s.b],
            scale: vec![1.0; s.pos.len() * s.b],
        }
    }

    /// Scale every unknown to a unit diagonal (`D (JᵀJ) D`, `D g`; Jacobi scaling, which
    /// Cholesky's accuracy does not depend on, but which makes `μ` damp each unknown relative
    /// to its own column); a column below `10⁻²⁴` of the largest keeps the largest's scale.
    pub(crate) fn equilibrate(&mut self, s: &Symbolic) {
        let b = s.b;
        let bb = b * b;
        let n = s.pos.len();
        let top = (0..n * b)
            .map(|i| self.diag[(i / b) * bb + (i % b) * (b + 1)])
            .filter(|x| x.is_finite())
            .fold(0.0f64, f64::max);
        if top <= 0.0 {
            self.scale.fill(1.0);
            return;
        }
        for i in 0..n * b {
            let d = self.diag[(i / b) * bb + (i % b) * (b + 1)];
            self.scale[i] = 1.0 / if d > 1e-24 * top { d } else { top }.sqrt();
        }
        let scale_block = |blk: &mut [f64], r: &[f64], c: &[f64]| {
            for i in 0..b {
                for j in 0..b {
                    blk[i * b + j] *= r[i] * c[j];
                }
            }
        };
        for k in 0..n {
            let sk = &self.scale[k * b..(k + 1) * b];
            scale_block(&mut self.diag[k * bb..(k + 1) * bb], sk, sk);
            for idx in s.start[k]..s.start[k + 1] {
                let w = s.rows[idx] as usize;
                let sw = &self.scale[w * b..(w + 1) * b];
                scale_block(&mut self.off[idx * bb..(idx + 1) * bb], sw, sk);
            }
        }
        for (g, d) in self.grad.iter_mut().zip(&self.scale) {
            *g *= d;
        }
    }

    /// The diagonal entries, in elimination order.
    pub(crate) fn diagonal(&self, s: &Symbolic) -> Vec<f64> {
        let b = s.b;
        (0..s.pos.len() * b)
            .map(|i| self.diag[(i / b) * b * b + (i % b) * (b + 1)])
            .collect()
    }

    pub(crate) fn clear(&mut self) {
        self.diag.fill(0.0);
        self.off.fill(0.0);
        self.grad.fill(0.0);
    }

    /// Factor `self + μI` in place; the squared pivots, in elimination order.
    pub(crate) fn factor(&mut self, s: &Symbolic, mu: f64) -> Vec<f64> {
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
    pub(crate) fn solve(&self, s: &Symbolic, rhs: &mut [f64]) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::budget::Budget;
    use nalgebra::{DMatrix, DVector};
    use std::ops::AddAssign;

    /// `(Σ JᵀJ + I) x = g` on a ring with a chord (the ordering fills in) matches a dense
    /// solve, for blocks of 2 and of 3.
    #[test]
    fn factor_and_solve_match_a_dense_solve() {
        for b in [2usize, 3] {
            let n = 7;
            let mut edges: Vec<(u32, u32)> =
                (0..n as u32).map(|u| (u, (u + 1) % n as u32)).collect();
            edges.push((1, 4));
            let mut meter = Budget::DEFAULT.meter("test");
            let s = symbolic(n, b, &edges, &mut meter, u64::MAX).unwrap();
            let (bb, nb) = (b * b, n * b);
            let mut ne = Normal::zeros(&s);
            let mut dense = DMatrix::<f64>::identity(nb, nb);
            for (e, &(u, v)) in edges.iter().enumerate() {
                let j = DMatrix::from_fn(b + 1, 2 * b, |i, c| {
                    ((e * 5 + i * 3 + c * 7) % 11) as f64 / 4.0 - 1.2
                });
                let (ku, kv) = (s.pos[u as usize] as usize, s.pos[v as usize] as usize);
                let a = j.transpose() * &j;
                for (x, kx) in [(0, ku), (1, kv)] {
                    for (y, ky) in [(0, ku), (1, kv)] {
                        let blk = a.view((x * b, y * b), (b, b));
                        dense.view_mut((kx * b, ky * b), (b, b)).add_assign(&blk);
                        if kx == ky && x == y {
                            for r in 0..b {
                                for c in 0..b {
                                    ne.diag[kx * bb + r * b + c] += blk[(r, c)];
                                }
                            }
                        } else if kx > ky {
                            let at = s.find(ky, kx as u32).unwrap();
                            for r in 0..b {
                                for c in 0..b {
                                    ne.off[at * bb + r * b + c] += blk[(r, c)];
                                }
                            }
                        }
                    }
                }
            }
            let g: Vec<f64> = (0..nb).map(|i| (i as f64 * 0.37).sin()).collect();
            let want = dense.lu().solve(&DVector::from_column_slice(&g)).unwrap();
            ne.factor(&s, 1.0);
            let mut x = g.clone();
            ne.solve(&s, &mut x);
            let err = (DVector::from_vec(x) - want).norm();
            assert!(err < 1e-10, "b = {b}: {err}");
        }
    }
}
