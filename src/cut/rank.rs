//! The closure rows of the cuts in tree coordinates and their ranks: cut pair `c` with
//! constraint rows `R_c` closes `R_c · Σ sign · T_e q̇_e = 0` over the tree pairs `e` of its
//! loop. Cuts whose loops share no tree pair are independent blocks; within a block the rows
//! are taken cut by cut (Gram–Schmidt twice), so each cut's rank is what its rows add to the
//! closures before it.

use super::tree::{Plan, Step};
use crate::budget::{Budget, BudgetExceeded, Meter};
use crate::motion::JointModel;
use nalgebra::DVector;

/// The ranks of one cut's closure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ranks {
    /// Its rows (the constraint rows of the cut joint's pair).
    pub rows: usize,
    /// The rank its rows add to the closures before it (in cut order).
    pub rank: usize,
    /// The rank of its rows alone (its loop as the only one).
    pub alone: usize,
}

impl Ranks {
    /// Rows implied by the rows before them.
    pub fn redundant(&self) -> usize {
        self.rows - self.rank
    }
}

/// The rank decisions: a row is independent when what is left of it after the rows before
/// it exceeds `max(1e-9 · max(rows, columns) · s, file)`, `s` the largest row norm of its
/// block and `file` the threshold the file's rounding allows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Threshold {
    /// The file's rounding threshold (`None` at a random realization).
    pub file: Option<f64>,
}

/// The ranks of every cut of `plan` (in `plan.cuts` order), each loop given as its steps.
pub fn ranks(
    plan: &Plan,
    models: &[JointModel],
    loops: &[Vec<Step>],
    threshold: Threshold,
    budget: &Budget,
    meter: &mut Meter,
) -> Result<Vec<Ranks>, BudgetExceeded> {
    let mut out = vec![Ranks::default(); plan.cuts.len()];
    for block in blocks(plan, loops) {
        let rows = block_rows(plan, models, loops, &block, budget, meter)?;
        let tol = tolerance(&rows, threshold);
        let mut basis: Vec<DVector<f64>> = Vec::new();
        for (&k, cut_rows) in block.cuts.iter().zip(&rows.per_cut) {
            let before = basis.len();
            let mut alone: Vec<DVector<f64>> = Vec::new();
            for r in cut_rows {
                add(&mut basis, r.clone(), tol, meter)?;
                add(&mut alone, r.clone(), tol, meter)?;
            }
            out[k] = Ranks {
                rows: cut_rows.len(),
                rank: basis.len() - before,
                alone: alone.len(),
            };
        }
    }
    Ok(out)
}

/// Cuts whose loops share tree pairs, with the tree pairs they use (sorted).
struct Block {
    /// Indices into `plan.cuts`, increasing.
    cuts: Vec<usize>,
    /// The tree pairs, increasing.
    columns: Vec<usize>,
}

fn find(uf: &mut [usize], mut x: usize) -> usize {
    while uf[x] != x {
        uf[x] = uf[uf[x]];
        x = uf[x];
    }
    x
}

/// The blocks of cuts (cuts joined when their loops share a tree pair), in order of their
/// first cut.
fn blocks(plan: &Plan, loops: &[Vec<Step>]) -> Vec<Block> {
    let mut uf: Vec<usize> = (0..loops.len()).collect();
    let mut first_user: Vec<Option<usize>> = vec![None; plan.pairs.len()];
    for (k, steps) in loops.iter().enumerate() {
        for s in steps {
            match first_user[s.pair] {
                None => first_user[s.pair] = Some(k),
                Some(o) => {
                    let (a, b) = (find(&mut uf, o), find(&mut uf, k));
                    if a != b {
                        uf[a.max(b)] = a.min(b);
                    }
                }
            }
        }
    }
    let mut index: Vec<Option<usize>> = vec![None; loops.len()];
    let mut out: Vec<Block> = Vec::new();
    for (k, steps) in loops.iter().enumerate() {
        let r = find(&mut uf, k);
        let bi = *index[r].get_or_insert_with(|| {
            out.push(Block {
                cuts: Vec::new(),
                columns: Vec::new(),
            });
            out.len() - 1
        });
        out[bi].cuts.push(k);
        out[bi].columns.extend(steps.iter().map(|s| s.pair));
    }
    for b in &mut out {
        b.columns.sort_unstable();
        b.columns.dedup();
    }
    out
}

/// The closure rows of a block's cuts over its columns.
struct BlockRows {
    per_cut: Vec<Vec<DVector<f64>>>,
    columns: usize,
}

fn block_rows(
    plan: &Plan,
    models: &[JointModel],
    loops: &[Vec<Step>],
    block: &Block,
    budget: &Budget,
    meter: &mut Meter,
) -> Result<BlockRows, BudgetExceeded> {
    let twists = |pair: usize| &models[plan.pairs[pair].joint].twists;
    let mut offset = vec![0usize; block.columns.len() + 1];
    for (i, &e) in block.columns.iter().enumerate() {
        offset[i + 1] = offset[i] + twists(e).ncols();
    }
    let ncols = offset[block.columns.len()];
    let nrows: usize = block
        .cuts
        .iter()
        .map(|&k| models[plan.pairs[plan.cuts[k]].joint].rows.nrows())
        .sum();
    let bytes = (nrows as u64)
        .saturating_mul(ncols as u64)
        .saturating_mul(16);
    budget.check_memory(bytes, || {
        format!("the closure rows of {nrows} constraints over {ncols} tree coordinates")
    })?;
    let mut per_cut = Vec::with_capacity(block.cuts.len());
    for &k in &block.cuts {
        let r = &models[plan.pairs[plan.cuts[k]].joint].rows;
        let mut m = nalgebra::DMatrix::<f64>::zeros(r.nrows(), ncols);
        for s in &loops[k] {
            let i = block.columns.binary_search(&s.pair).unwrap_or(0);
            let t = twists(s.pair);
            meter.charge((r.nrows() * t.nrows() * t.ncols()) as u64 + 1)?;
            let part = r * t * s.sign;
            let mut view = m.columns_mut(offset[i], t.ncols());
            view += part;
        }
        per_cut.push(m.row_iter().map(|row| row.transpose()).collect());
    }
    Ok(BlockRows {
        per_cut,
        columns: ncols,
    })
}

/// The absolute threshold of a block's rank decisions ([`Threshold`]).
fn tolerance(rows: &BlockRows, threshold: Threshold) -> f64 {
    let all = rows.per_cut.iter().flatten();
    let n = rows
        .per_cut
        .iter()
        .map(Vec::len)
        .sum::<usize>()
        .max(rows.columns);
    let s = all.map(|r| r.norm()).fold(0.0f64, f64::max);
    let rel = 1e-9 * n.max(1) as f64 * s.max(f64::MIN_POSITIVE);
    threshold.file.map_or(rel, |f| rel.max(f))
}

/// Add `v` to the orthonormal `basis` when what is left of it exceeds `tol`.
fn add(
    basis: &mut Vec<DVector<f64>>,
    mut v: DVector<f64>,
    tol: f64,
    meter: &mut Meter,
) -> Result<(), BudgetExceeded> {
    meter.charge((2 * basis.len() * v.len()) as u64 + 1)?;
    for _ in 0..2 {
        for q in basis.iter() {
            let d = q.dot(&v);
            v.axpy(-d, q, 1.0);
        }
    }
    let n = v.norm();
    if n > tol {
        basis.push(v / n);
    }
    Ok(())
}
