//! `--merge-pins`: coincident coaxial revolute joints that share a body merged into multiple
//! joints.

use super::JointRec;
use super::pose::unit;
use crate::joint::JointType;
use crate::mechanism::Geometry;
use nalgebra::Vector3;
use std::collections::{HashMap, HashSet};

/// Merge coincident coaxial revolute joints sharing exactly one body into multiple joints;
/// returns how many joints were merged into others.
pub(super) fn merge_pins(joints: &mut Vec<JointRec>) -> usize {
    let mut merged = 0;
    let mut alive = vec![true; joints.len()];
    // The joints on each body (only pairs sharing a body can merge).
    let mut on: HashMap<usize, Vec<usize>> = HashMap::new();
    for (k, j) in joints.iter().enumerate() {
        if j.kind == JointType::R {
            for &b in &j.bodies {
                on.entry(b).or_default().push(k);
            }
        }
    }
    loop {
        let mut changed = false;
        for i in 0..joints.len() {
            if !alive[i] || joints[i].kind != JointType::R {
                continue;
            }
            let n = merge_into(joints, i, &mut on, &mut alive);
            merged += n;
            changed |= n > 0;
        }
        if !changed {
            break;
        }
    }
    retain_alive(joints, &alive);
    merged
}

/// Keep the joints `alive` marks (the others were merged into them).
pub(super) fn retain_alive(joints: &mut Vec<JointRec>, alive: &[bool]) {
    let mut idx = 0;
    joints.retain(|_| {
        let keep = alive[idx];
        idx += 1;
        keep
    });
}

/// Whether two joints are coaxial revolute pins at one place: parallel axes on one line.
fn coaxial(a: &Geometry, b: &Geometry) -> bool {
    let (Some(oa), Some(aa), Some(ob), Some(ab)) = (a.origin, a.axis, b.origin, b.axis) else {
        return false;
    };
    let (oa, ob) = (Vector3::from(oa), Vector3::from(ob));
    let (Some(ua), Some(ub)) = (unit(&aa), unit(&ab)) else {
        return false;
    };
    let scale = 1.0 + oa.norm().max(ob.norm());
    let tol = 1e-6 * scale;
    ua.cross(&ub).norm() < 1e-6 && (ob - oa).cross(&ua).norm() < tol
}

/// Merge into joint `i` every live joint coaxial with it that shares exactly one of its bodies,
/// then those on the bodies that merging brings in; returns how many were merged.
fn merge_into(
    joints: &mut [JointRec],
    i: usize,
    on: &mut HashMap<usize, Vec<usize>>,
    alive: &mut [bool],
) -> usize {
    let mut merged = 0;
    let mut candidates: Vec<usize> = joints[i]
        .bodies
        .iter()
        .flat_map(|b| on.get(b).map(Vec::as_slice).unwrap_or(&[]))
        .copied()
        .filter(|&k| k != i && alive[k])
        .collect();
    candidates.sort_unstable();
    candidates.dedup();
    let mut members: HashSet<usize> = joints[i].bodies.iter().copied().collect();
    // A worklist: joints on bodies that merging brings in are candidates too.
    let mut queue = candidates;
    while let Some(k) = queue.pop() {
        if k == i || !alive[k] {
            continue;
        }
        let shared = joints[k]
            .bodies
            .iter()
            .filter(|b| members.contains(b))
            .count();
        if shared != 1 || !coaxial(&joints[i].geometry, &joints[k].geometry) {
            continue;
        }
        let extra: Vec<usize> = joints[k]
            .bodies
            .iter()
            .copied()
            .filter(|b| !members.contains(b))
            .collect();
        for &b in &extra {
            queue.extend(on.get(&b).map(Vec::as_slice).unwrap_or(&[]).iter().copied());
            on.entry(b).or_default().push(i);
            members.insert(b);
        }
        let other = joints[k].clone();
        let j = &mut joints[i];
        j.bodies.extend(extra);
        j.driven += other.driven;
        j.id = format!("{}+{}", j.id, other.id);
        j.comments.extend(other.comments);
        alive[k] = false;
        merged += 1;
    }
    merged
}
