//! A deficient block explained: rows of a redundant pair dropped while the block keeps its
//! rank, and the freedom the redundancy hides put in words.

use super::attempt::Attempt;
use super::blocks::block_matrix;
use super::cache::matrix_digest;
use super::float::{Svd, Tol, cube, rank_of};
use super::rows::PairRows;
use crate::joint::JointType;
use crate::mechanism::Mechanism;
use crate::structure::Redundancy;
use crate::structure::count::Equations;
use nalgebra::DMatrix;

impl Attempt<'_> {
    /// A deficient block (`rank`, `deficit` rows short) explained and lowered: the pairs with
    /// weight in its left null space are named, and the one that carries most of the
    /// dependency (ties: the later pair) loses rows while the block keeps its rank; its count
    /// before goes to `lowerings`. Whether a pair lost rows.
    pub(super) fn lower_deficient(
        &mut self,
        eqs: &mut Equations,
        block_eqs: &[usize],
        bodies: &[usize],
        rank: usize,
        deficit: usize,
        lowerings: &mut Vec<(usize, u32)>,
    ) -> bool {
        let b = self.b;
        let a = block_matrix(b, block_eqs, bodies, eqs, &self.rows, &self.q);
        // Large blocks at the file's geometry are lowered at once, from the left basis alone.
        let at_once = self.used.seed.is_none() && a.nrows().max(a.ncols()) > MAX_ROW_BY_ROW;
        let svd = if at_once {
            Svd::left(&a, &self.tol)
        } else {
            Svd::of(&a, &self.tol)
        };
        self.work = self.work.saturating_add(cube(a.nrows().max(a.ncols())));
        debug_assert_eq!(
            svd.rank(),
            rank,
            "same singular values with or without vectors"
        );
        let named = null_weights(&self.rows, block_eqs, &svd);
        if at_once {
            return self.lower_at_once(
                eqs, block_eqs, bodies, &svd, rank, deficit, &named, lowerings,
            );
        }
        // Lower the pair that carries most of the dependency (ties: the later pair).
        let mut order = named.clone();
        order.sort_by(|a, b| b.1.total_cmp(&a.1).then(b.0.cmp(&a.0)));
        let mut lowered = usize::MAX;
        let mut removed = 0;
        for &(e, _) in &order {
            let (rows, q) = (&mut self.rows, &self.q);
            let tries;
            (removed, tries) = drop_rows(
                b, e, deficit, block_eqs, bodies, eqs, rows, q, rank, &self.tol,
            );
            let n = a.nrows().max(a.ncols());
            self.work = self.work.saturating_add(cube(n).saturating_mul(tries));
            if removed > 0 {
                lowered = e;
                break;
            }
        }
        if removed == 0 {
            return false;
        }
        self.record_lowering(eqs, bodies, &named, &[lowered], removed, lowerings);
        true
    }

    /// The pairs `lowered` lost `removed` rows in all: their counts before go to `lowerings`,
    /// the count's capacities and the cache digests follow the rows, and the redundancy (the
    /// pairs `named` carry it) is reported.
    fn record_lowering(
        &mut self,
        eqs: &mut Equations,
        bodies: &[usize],
        named: &[(usize, f64)],
        lowered: &[usize],
        removed: usize,
        lowerings: &mut Vec<(usize, u32)>,
    ) {
        let m = self.m;
        for &e in lowered {
            lowerings.push((e, eqs.cap[e]));
            eqs.cap[e] = self.rows.nrows(e) as u32;
            if let Some(d) = self.rd.get_mut(e) {
                *d = matrix_digest(&self.rows.get(e));
            }
        }
        let mut joints: Vec<usize> = named.iter().map(|&(e, _)| eqs.joint[e]).collect();
        joints.sort_unstable();
        joints.dedup();
        let mut lowered_joints: Vec<usize> = lowered.iter().map(|&e| eqs.joint[e]).collect();
        lowered_joints.sort_unstable();
        lowered_joints.dedup();
        let ids: Vec<&str> = lowered_joints
            .iter()
            .map(|&j| m.joints[j].id.as_str())
            .collect();
        self.redundant.push(Redundancy {
            bodies: body_names(m, eqs, bodies),
            freedom: describe(m, eqs, bodies, &joints, removed),
            joints: joints.iter().map(|&j| m.joints[j].id.clone()).collect(),
            count: removed as u32,
            lowered: ids.join(", "),
            configuration: false,
        });
    }

    /// [`lower_deficient`](Self::lower_deficient) on a block of more than [`MAX_ROW_BY_ROW`]
    /// unknowns at the file's geometry: every dependent row goes in one step, from the one
    /// SVD already made. Row by row, each lowering cost an SVD per row tried and a new
    /// decomposition of the whole mechanism, and the deficit of a long chain of loops at a
    /// coarse written precision grows with its length (an N-four-bar of 400 bodies: 20 s,
    /// 1,000 bodies: minutes). The rows are chosen by a pivoted Gram-Schmidt on the rows of
    /// the left null space (the row with the most weight, ties the later row, then the next
    /// one on what is left): a set of rows on which the null space has full rank can go while
    /// the block keeps its rank, which one more rank decision confirms (else the first half
    /// of them is tried, down to one row; nothing is lowered when no row can go).
    #[allow(clippy::too_many_arguments)]
    fn lower_at_once(
        &mut self,
        eqs: &mut Equations,
        block_eqs: &[usize],
        bodies: &[usize],
        svd: &Svd,
        rank: usize,
        deficit: usize,
        named: &[(usize, f64)],
        lowerings: &mut Vec<(usize, u32)>,
    ) -> bool {
        let b = self.b;
        let mut picked = null_space_pivots(&self.rows, block_eqs, svd, deficit);
        // Near the threshold a set can cost the block a singular value: then the first half
        // of the pivots (the rows with most weight), and so on down to one row.
        loop {
            if picked.is_empty() {
                return false;
            }
            let mut take = picked.clone();
            take.sort_unstable();
            let mut touched: Vec<usize> = take.iter().map(|&(e, _)| e).collect();
            touched.dedup();
            let saved: Vec<(usize, DMatrix<f64>)> = touched
                .iter()
                .map(|&e| (e, self.rows.get(e).into_owned()))
                .collect();
            // Within a pair, the later rows first, so that the earlier indices still hold.
            for &(e, r) in take.iter().rev() {
                self.rows.remove_row(e, r);
            }
            let a = block_matrix(b, block_eqs, bodies, eqs, &self.rows, &self.q);
            self.work = self.work.saturating_add(cube(a.nrows().max(a.ncols())));
            if rank_of(&a, &self.tol) == rank {
                self.record_lowering(eqs, bodies, named, &touched, take.len(), lowerings);
                return true;
            }
            for (e, r) in &saved {
                self.rows.set(*e, r);
            }
            picked.truncate(picked.len() / 2);
        }
    }
}

/// Blocks (unknowns or equations) above this size at the file's geometry are lowered at once
/// ([`Attempt::lower_at_once`]) rather than a row at a time; the blocks lowered by the bundled
/// mechanisms and import fixtures have at most 136.
const MAX_ROW_BY_ROW: usize = 160;

/// Up to `count` rows of the block (pair, row within the pair), in pivot order, on which the
/// left null space of `svd` has full rank: a Gram-Schmidt on the null space's rows, pivoting
/// on the largest remaining norm (ties: the later row), stopping below 1e-6 of the first.
fn null_space_pivots(
    rows: &PairRows,
    block_eqs: &[usize],
    svd: &Svd,
    count: usize,
) -> Vec<(usize, usize)> {
    let null: Vec<usize> = (0..svd.sv.len())
        .filter(|&i| svd.sv[i] <= svd.tol)
        .collect();
    let owner: Vec<(usize, usize)> = block_eqs
        .iter()
        .flat_map(|&e| (0..rows.nrows(e)).map(move |i| (e, i)))
        .collect();
    let mut left: Vec<Vec<f64>> = (0..owner.len())
        .map(|r| null.iter().map(|&k| svd.u[(r, k)]).collect())
        .collect();
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut picked: Vec<usize> = Vec::new();
    let mut first = 0.0;
    while picked.len() < count {
        let best = (0..left.len())
            .filter(|r| !picked.contains(r))
            .map(|r| (norm(&left[r]), r))
            .max_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let Some((n, r)) = best else {
            break;
        };
        if picked.is_empty() {
            first = n;
        }
        if n.is_nan() || n <= 1e-6 * first || n == 0.0 {
            break;
        }
        let v: Vec<f64> = left[r].iter().map(|x| x / n).collect();
        for row in &mut left {
            let d: f64 = row.iter().zip(&v).map(|(a, c)| a * c).sum();
            for (x, vk) in row.iter_mut().zip(&v) {
                *x -= d * vk;
            }
        }
        picked.push(r);
    }
    picked.into_iter().map(|r| owner[r]).collect()
}

/// Each pair of the block with its weight in the left null space (the left singular vectors
/// of the singular values at most the threshold), those above 1e-6, in block order.
fn null_weights(rows: &PairRows, block_eqs: &[usize], svd: &Svd) -> Vec<(usize, f64)> {
    let null: Vec<usize> = (0..svd.sv.len())
        .filter(|&i| svd.sv[i] <= svd.tol)
        .collect();
    let mut named: Vec<(usize, f64)> = Vec::new();
    let mut r0 = 0;
    for &e in block_eqs {
        let n = rows.nrows(e);
        let w: f64 = (r0..r0 + n)
            .map(|r| null.iter().map(|&k| svd.u[(r, k)].powi(2)).sum::<f64>())
            .sum();
        if w > 1e-6 {
            named.push((e, w));
        }
        r0 += n;
    }
    named
}

/// Remove up to `count` rows of pair `e` that the block can lose without losing rank; the rows
/// removed and the rank decisions made (each a dense factorization of the block).
#[allow(clippy::too_many_arguments)]
pub(super) fn drop_rows(
    b: usize,
    e: usize,
    count: usize,
    block_eqs: &[usize],
    bodies: &[usize],
    eqs: &Equations,
    rows: &mut PairRows,
    q: &[Option<DMatrix<f64>>],
    rank: usize,
    t: &Tol,
) -> (usize, u64) {
    let mut removed = 0;
    let mut tries = 0;
    let mut r = rows.nrows(e);
    while r > 0 && removed < count {
        r -= 1;
        let saved = rows.get(e).into_owned();
        rows.remove_row(e, r);
        let a = block_matrix(b, block_eqs, bodies, eqs, rows, q);
        tries += 1;
        if rank_of(&a, t) == rank {
            removed += 1;
        } else {
            rows.set(e, &saved);
        }
    }
    (removed, tries)
}

/// The ids of the bodies among `nodes` (element nodes left out).
pub(super) fn body_names(m: &Mechanism, eqs: &Equations, nodes: &[usize]) -> Vec<String> {
    nodes
        .iter()
        .filter(|&&x| !eqs.is_element(x))
        .map(|&x| m.body_id(x).to_string())
        .collect()
}

/// The freedom a redundancy hides, in words.
pub(super) fn describe(
    m: &Mechanism,
    eqs: &Equations,
    bodies: &[usize],
    joints: &[usize],
    count: usize,
) -> String {
    let ids = body_names(m, eqs, bodies);
    let all_s = joints.iter().all(|&j| m.joints[j].kind == JointType::S);
    if ids.len() == 1 && bodies.len() == 1 && joints.len() == 2 && all_s {
        return format!(
            "body {} turns about the line through the centres of the spherical joints {} and {}, \
             a freedom no input controls",
            ids[0], m.joints[joints[0]].id, m.joints[joints[1]].id
        );
    }
    format!(
        "bodies {{{}}} keep {count} freedom(s) that no input controls",
        crate::structure::capped(&ids)
    )
}

#[cfg(test)]
mod tests {
    use super::MAX_ROW_BY_ROW;
    use crate::geometry::{GeometrySource, geometries};
    use crate::structure::count::Equations;
    use crate::structure::rank::{Shortcut, check};
    use std::fmt::Write as _;

    /// The IFToMM N-four-bar of `n` windows (as the bundled `n-four-bar-40-driven`, first crank
    /// driven) with its numbers known to ±0.5 only (half its link length): at that precision a
    /// long row of windows is rank deficient by a number of equations that grows with its
    /// length (at ±0.05 it is not: `rigid` keeps every equation, its smallest singular value
    /// 0.2).
    fn coarse_windows(n: usize) -> String {
        let mut s = String::from("space = \"planar\"\nframe = 1\nprecision = 0.5\n");
        let mut joint = |id: String, a: usize, b: usize, x: f64, y: f64, driven: bool| {
            let _ = write!(
                s,
                "\n[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [{a}, {b}]\norigin = [{x}, {y}]\n{}",
                if driven { "driven = 1\n" } else { "" }
            );
        };
        joint("A0".into(), 1, 2, 0.0, 0.0, true);
        for k in 1..=n {
            let kf = k as f64;
            joint(
                format!("VB{}", k - 1),
                2 * k,
                2 * k + 1,
                kf - 0.4,
                0.8,
                false,
            );
            joint(format!("B{k}"), 2 * k + 1, 2 * k + 2, kf + 0.6, 0.8, false);
            joint(format!("P{k}"), 1, 2 * k + 2, kf, 0.0, false);
        }
        s
    }

    /// A deficient block of a few hundred unknowns at the file's geometry loses its dependent
    /// rows in one step: row by row it took a round (a decomposition of the whole mechanism
    /// and an SVD of the block) per row, and an SVD per row tried (5 rounds and about 30 SVDs
    /// of 171 unknowns at 60 windows, 10 rounds and 312 SVDs of 308 at 120: minutes at
    /// 500 windows). The work units (`n^3` per dense decision, now counting every row tried)
    /// stay within a few SVDs of the block.
    #[test]
    fn a_long_deficient_block_is_lowered_in_few_rounds() {
        for n in [60, 120] {
            let text = coarse_windows(n);
            let m = crate::format::load("w.toml", &text, crate::format::Format::Toml)
                .expect("generated file loads");
            let mut eqs = Equations::of(&m);
            let mut u = eqs.unknowns(&m);
            let (geoms, used) = geometries(&m, GeometrySource::File, None).expect("file geometry");
            let r = check(&m, &geoms, &used, &mut eqs, &mut u, None, Shortcut::None);
            let lowered = r.redundant.iter().filter(|x| !x.configuration).count();
            // The under-determined block: its unknowns bound every dense decision's size.
            let size = 3 * (2 * n + 1);
            assert!(
                size > MAX_ROW_BY_ROW,
                "{n} windows: a block lowered at once"
            );
            let svds = r.work / super::cube(size).max(1);
            assert!(lowered >= 1, "{n} windows: a deficit lowered");
            assert!(
                r.rounds <= 3 && svds <= 16,
                "{n} windows: {} rounds, {lowered} lowerings, work {} (~{svds} SVDs)",
                r.rounds,
                r.work
            );
        }
    }
}
