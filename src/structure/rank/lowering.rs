//! A deficient block explained: rows of a redundant pair dropped while the block keeps its
//! rank, and the freedom the redundancy hides put in words.

use super::blocks::block_matrix;
use super::float::{Tol, rank_of};
use super::rows::PairRows;
use crate::joint::JointType;
use crate::mechanism::Mechanism;
use crate::structure::count::Equations;
use nalgebra::DMatrix;

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
        ids.join(", ")
    )
}
