//! The block Cholesky factorization of the sparse global solve's normal equations: a
//! minimum-degree elimination order of the body graph ([`symbolic`]), the factor's structure
//! ([`Symbolic`]), and the numeric factor ([`Normal`]), one `B × B` block per body (`B` = 3
//! or 6), whose pivots estimate the singular values of a large system's Jacobian.

use crate::budget::{BudgetExceeded, Meter};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
/// Bytes of factor storage per entry of the elimination structure, beside the blocks.
const STRUCT_BYTES: u64 = 16;

/// The structure of the block Cholesky factor: columns in elimination order.
#[derive(Clone, Debug)]
pub struct Symbolic {
    /// Block size.
    pub(super) b: usize,
    /// `pos[c]`: elimination index of local unknown `c` (index in `System::bodies`).
    pub(super) pos: Vec<u32>,
    /// Column `k`'s rows (elimination indices above `k`, ascending) are
    /// `rows[start[k]..start[k + 1]]`.
    pub(super) start: Vec<usize>,
    pub(super) rows: Vec<u32>,
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
    pub(super) fn find(&self, k: usize, i: u32) -> Option<usize> {
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
pub(super) struct Normal {
    pub(super) diag: Vec<f64>,
    pub(super) off: Vec<f64>,
}

impl Normal {
    pub(super) fn zeros(s: &Symbolic) -> Normal {
        let bb = s.b * s.b;
        Normal {
            diag: vec![0.0; s.pos.len() * bb],
            off: vec![0.0; s.rows.len() * bb],
        }
    }

    pub(super) fn clear(&mut self) {
        self.diag.fill(0.0);
        self.off.fill(0.0);
    }

    /// Factor `self + μI` in place; the squared pivots, in elimination order.
    pub(super) fn factor(&mut self, s: &Symbolic, mu: f64) -> Vec<f64> {
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
}
