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
        let (m, b) = (self.m, self.b);
        let a = block_matrix(b, block_eqs, bodies, eqs, &self.rows, &self.q);
        let svd = Svd::of(&a, &self.tol);
        self.work = self.work.saturating_add(cube(a.nrows().max(a.ncols())));
        debug_assert_eq!(
            svd.rank(),
            rank,
            "same singular values with or without vectors"
        );
        let named = null_weights(&self.rows, block_eqs, &svd);
        // Lower the pair that carries most of the dependency (ties: the later pair).
        let mut order = named.clone();
        order.sort_by(|a, b| b.1.total_cmp(&a.1).then(b.0.cmp(&a.0)));
        let mut lowered = usize::MAX;
        let mut removed = 0;
        for &(e, _) in &order {
            let (rows, q) = (&mut self.rows, &self.q);
            removed = drop_rows(
                b, e, deficit, block_eqs, bodies, eqs, rows, q, rank, &self.tol,
            );
            if removed > 0 {
                lowered = e;
                break;
            }
        }
        if removed == 0 {
            return false;
        }
        let named: Vec<usize> = named.iter().map(|&(e, _)| e).collect();
        lowerings.push((lowered, eqs.cap[lowered]));
        eqs.cap[lowered] = self.rows.nrows(lowered) as u32;
        if let Some(d) = self.rd.get_mut(lowered) {
            *d = matrix_digest(&self.rows.get(lowered));
        }
        let mut joints: Vec<usize> = named.iter().map(|&e| eqs.joint[e]).collect();
        joints.sort_unstable();
        joints.dedup();
        self.redundant.push(Redundancy {
            bodies: body_names(m, eqs, bodies),
            freedom: describe(m, eqs, bodies, &joints, removed),
            joints: joints.iter().map(|&j| m.joints[j].id.clone()).collect(),
            count: removed as u32,
            lowered: m.joints[eqs.joint[lowered]].id.clone(),
            configuration: false,
        });
        true
    }
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

/// Remove up to `count` rows of pair `e` that the block can lose without losing rank.
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
) -> usize {
    let mut removed = 0;
    let mut r = rows.nrows(e);
    while r > 0 && removed < count {
        r -= 1;
        let saved = rows.get(e).into_owned();
        rows.remove_row(e, r);
        let a = block_matrix(b, block_eqs, bodies, eqs, rows, q);
        if rank_of(&a, t) == rank {
            removed += 1;
        } else {
            rows.set(e, &saved);
        }
    }
    removed
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
