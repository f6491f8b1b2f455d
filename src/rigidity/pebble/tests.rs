//! Unit tests of the pebble game on small frameworks.

use super::*;
use crate::joint::JointType::{self, *};
use crate::mechanism::{BodyId, JointSpec, Space};

fn j(kind: JointType, bodies: &[i64]) -> JointSpec {
    let mut s = JointSpec::new(kind, bodies[0], bodies[1], 0);
    s.bodies = bodies.iter().map(|&b| BodyId::Int(b)).collect();
    s
}

fn run(space: Space, joints: Vec<JointSpec>) -> PebbleReport {
    let m = Mechanism::from_parts("t", space, BodyId::Int(1), vec![], joints);
    analyze(&m, &PebbleOptions::default())
}

fn ids(r: &PebbleReport) -> Vec<Vec<&str>> {
    r.rigid
        .iter()
        .map(|c| c.iter().map(String::as_str).collect())
        .collect()
}

/// Planar four-bar 1-2-3-4 with revolutes at the points A (1,2), B (2,3), C (3,4),
/// D (4,1); `diagonals` adds bar 5 (A-C) and then bar 6 (B-D), pinned at those points.
fn four_bar(diagonals: usize) -> Vec<JointSpec> {
    let mut a = vec![1, 2];
    let mut b = vec![2, 3];
    let mut c = vec![3, 4];
    let mut d = vec![4, 1];
    if diagonals >= 1 {
        a.push(5);
        c.push(5);
    }
    if diagonals >= 2 {
        b.push(6);
        d.push(6);
    }
    [a, b, c, d].iter().map(|p| j(R, p)).collect()
}

#[test]
fn triangle_is_rigid() {
    let r = run(
        Space::Planar,
        vec![j(R, &[1, 2]), j(R, &[2, 3]), j(R, &[3, 1])],
    );
    assert_eq!((r.count, r.dof, r.dof_free, r.redundant), (0, 0, 3, 0));
    assert_eq!(ids(&r), [["1", "2", "3"]]);
    assert_eq!(r.immobile, ["2", "3"]);
    assert!(r.overconstrained.is_empty());
    assert!(!r.degenerate, "no proper sub-chain of a triangle is rigid");
}

#[test]
fn four_bar_has_one_dof() {
    let r = run(Space::Planar, four_bar(0));
    assert_eq!((r.count, r.dof, r.redundant), (1, 1, 0));
    assert_eq!(ids(&r), [["1"]]);
    assert!(!r.degenerate);
}

#[test]
fn one_diagonal_makes_it_rigid() {
    let r = run(Space::Planar, four_bar(1));
    assert_eq!((r.count, r.dof, r.redundant), (0, 0, 0));
    assert_eq!(ids(&r), [["1", "2", "3", "4", "5"]]);
    // The triangle 1-4-5 (points A, D, C) is a proper rigid sub-chain.
    assert!(r.degenerate);
}

#[test]
fn both_diagonals_are_one_redundant_bar() {
    let r = run(Space::Planar, four_bar(2));
    assert_eq!((r.count, r.dof, r.redundant), (-1, 0, 1));
    assert_eq!(ids(&r), [["1", "2", "3", "4", "5", "6"]]);
    assert_eq!(r.overconstrained.len(), 1);
    let region = &r.overconstrained[0];
    assert_eq!(region.redundant, 1);
    assert_eq!(region.bodies.len(), 6);
    assert_eq!(region.joints, ["1-2-5", "2-3-6", "3-4-5", "4-1-6"]);
    assert!(r.degenerate);
}

#[test]
fn two_triangles_sharing_a_vertex() {
    // Bars 1-3 and 4-6 form two triangles pinned together at one point P.
    let r = run(
        Space::Planar,
        vec![
            j(R, &[1, 2, 4, 5]),
            j(R, &[2, 3]),
            j(R, &[3, 1]),
            j(R, &[5, 6]),
            j(R, &[6, 4]),
        ],
    );
    assert_eq!(ids(&r), [vec!["1", "2", "3"], vec!["4", "5", "6"]]);
    assert_eq!((r.dof, r.redundant), (1, 0));
    assert!(r.degenerate);
}

#[test]
fn stacked_four_bars() {
    // Lower four-bar on points p1..p4 with both diagonals (bars 1..6, frame 1 = p1p2),
    // upper four-bar p3-p6-p5-p4 on the lower top bar 3 (bars 7, 8, 9).
    let r = run(
        Space::Planar,
        vec![
            j(R, &[1, 4, 5]),
            j(R, &[1, 2, 6]),
            j(R, &[2, 3, 5, 7]),
            j(R, &[3, 4, 6, 9]),
            j(R, &[8, 9]),
            j(R, &[7, 8]),
        ],
    );
    assert_eq!((r.dof, r.redundant), (1, 1));
    assert_eq!(ids(&r), [["1", "2", "3", "4", "5", "6"]]);
    assert_eq!(r.overconstrained.len(), 1);
    assert_eq!(r.overconstrained[0].bodies, ["1", "2", "3", "4", "5", "6"]);
    assert_eq!(r.overconstrained[0].redundant, 1);
    assert!(r.degenerate);
}

#[test]
fn spatial_rssr_counts_the_bar_spin() {
    // Body-bar counting sees the spin of the S-S bar as a DOF: generic DOF 2.
    let r = run(
        Space::Spatial,
        vec![j(R, &[1, 2]), j(S, &[2, 3]), j(S, &[3, 4]), j(R, &[4, 1])],
    );
    assert_eq!((r.count, r.dof, r.redundant), (2, 2, 0));
    assert_eq!(ids(&r), [["1"]]);
}

#[test]
fn two_spherical_joints_look_rigid_to_counting() {
    // Two S joints between the same bodies: 6 bars, a rigid pair by counting, although
    // the bodies can turn about the line through the centres (a limit of counting).
    let r = run(Space::Spatial, vec![j(S, &[1, 2]), j(S, &[1, 2])]);
    assert_eq!((r.dof, r.redundant), (0, 0));
    assert_eq!(ids(&r), [["1", "2"]]);
}

#[test]
fn tetrahedron_of_ss_bars() {
    // Six bars (bodies 1..6) on four points, three bars at each point: spins counted.
    let r = run(
        Space::Spatial,
        vec![
            j(S, &[1, 2, 3]),
            j(S, &[1, 4, 5]),
            j(S, &[2, 4, 6]),
            j(S, &[3, 5, 6]),
        ],
    );
    assert_eq!((r.count, r.dof, r.redundant), (6, 6, 0));
}

#[test]
fn multiple_joint_with_redundancy() {
    // Crank 2 and links 3, 4 from the ground share one pin: 4 repeats the dyad 2-3.
    let r = run(
        Space::Planar,
        vec![
            j(R, &[1, 2]),
            j(R, &[2, 3, 4]),
            j(R, &[3, 1]),
            j(R, &[4, 1]),
        ],
    );
    assert_eq!((r.count, r.dof, r.redundant), (-1, 0, 1));
    assert_eq!(ids(&r), [["1", "2", "3", "4"]]);
}

#[test]
fn inputs_count_as_bars_on_request() {
    let mut joints = four_bar(0);
    joints[0].driven = 1;
    let m = Mechanism::from_parts("t", Space::Planar, BodyId::Int(1), vec![], joints);
    let off = analyze(&m, &PebbleOptions::default());
    let on = analyze(&m, &PebbleOptions { with_inputs: true });
    assert_eq!((off.dof, on.dof), (1, 0));
    assert_eq!(on.rigid, [["1", "2", "3", "4"]]);
    assert_eq!(on.count, off.count);
}

#[test]
fn disconnected_and_bad_input_do_not_panic() {
    let r = run(Space::Planar, vec![j(R, &[1, 1]), j(R, &[2, 3])]);
    assert_eq!(r.redundant, 2);
    assert_eq!(r.dof, 3 * 2 - 2);
}
