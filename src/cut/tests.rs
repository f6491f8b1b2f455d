use super::*;
use crate::format::{Format, load};

fn bundled(name: &str) -> Mechanism {
    let (file, text) = crate::examples::find(name).expect("bundled");
    load(file, text, Format::Toml).expect("valid")
}

fn cut(name: &str) -> CutReport {
    analyze(&bundled(name), &CutOptions::default()).expect("cuts")
}

fn ids(r: &CutReport) -> Vec<&str> {
    r.cuts.iter().map(|c| c.joint.as_str()).collect()
}

#[test]
fn a_planar_four_bar_is_cut_at_its_last_joint_and_keeps_the_driven_crank() {
    let r = cut("four-bar");
    assert_eq!(ids(&r), ["D"]);
    let c = &r.cuts[0];
    assert_eq!((c.rows, c.rank, c.redundant, c.why), (2, 2, 0, "order"));
    assert_eq!(c.loop_bodies, ["4", "3", "2", "1"]);
    assert_eq!(c.loop_joints, ["C", "B", "A", "D"]);
    let tree: Vec<(&str, &str, &str)> = r
        .tree
        .iter()
        .map(|t| (t.joint.as_str(), t.parent.as_str(), t.child.as_str()))
        .collect();
    assert_eq!(tree, [("A", "1", "2"), ("B", "2", "3"), ("C", "3", "4")]);
    assert_eq!((r.coordinates, r.rank, r.mobility), (3, 2, 1));
}

#[test]
fn a_planar_loop_written_in_space_carries_its_three_redundant_rows() {
    let r = cut("rig-planar-four-bar-3d");
    assert_eq!(ids(&r), ["D"]);
    assert_eq!((r.rows, r.rank, r.redundant, r.mobility), (5, 2, 3, 1));
    assert!(!r.cuts[0].independent);
}

#[test]
fn the_bricard_linkage_has_one_redundant_closure_row() {
    let r = cut("bricard");
    assert_eq!(ids(&r), ["Pin_6"]);
    assert_eq!((r.rows, r.rank, r.redundant, r.mobility), (5, 4, 1, 1));
    assert!(r.geometry_used.is_file());
}

#[test]
fn a_stewart_platform_is_cut_at_its_six_spherical_joints() {
    let r = cut("stewart");
    assert_eq!(r.loops, 6);
    assert!(r.cuts.iter().all(|c| c.kind == "S" && c.why == "spherical"));
    assert!(r.cuts.iter().all(|c| c.independent && c.rows == 3));
    // Random geometry (the file has none); with the actuators released the platform keeps its
    // 6 DOF (a U-P-S leg has no spin of its own).
    assert_eq!(r.geometry_used.mode, "random");
    assert_eq!(r.mobility, 6);
}

#[test]
fn the_same_input_gives_the_same_cuts() {
    let a = cut("rotor");
    let b = cut("rotor");
    assert_eq!(a, b);
}

#[test]
fn a_tiny_budget_stops_the_cuts() {
    let m = bundled("n-four-bar-40");
    let budget = Budget {
        max_work: 100,
        ..Budget::UNLIMITED
    };
    assert!(matches!(
        analyze_within(&m, &CutOptions::default(), &budget),
        Err(CutError::Budget(_))
    ));
}

#[test]
fn the_exchange_preferences_move_the_cut_within_its_loop() {
    let m = bundled("rig-planar-four-bar-3d");
    let mut meter = Budget::UNLIMITED.meter("test");
    let plain = tree::plan(&m, &tree::Force::default(), &mut meter).expect("plan");
    let joint = |p: usize| m.joints[plain.pairs[p].joint].id.as_str();
    assert_eq!(
        plain.cuts.iter().map(|&p| joint(p)).collect::<Vec<_>>(),
        ["D"]
    );
    // Keeping D and cutting B (as an exchange does) cuts B, and D joins the tree.
    let force = tree::Force {
        keep: [3].into(),
        cut: [1].into(),
    };
    let moved = tree::plan(&m, &force, &mut meter).expect("plan");
    assert_eq!(
        moved.cuts.iter().map(|&p| joint(p)).collect::<Vec<_>>(),
        ["B"]
    );
    let (bodies, steps) = tree::closed_loop(&moved, moved.cuts[0], &mut meter).expect("loop");
    assert_eq!(bodies.len(), 4);
    // Its closure carries the loop's 3 redundant rows as D's did: a planar loop written in
    // space is overconstrained wherever it is cut.
    let real = crate::geometry::realization(&m, GeometrySource::default(), None).expect("models");
    let threshold = rank::Threshold { file: None };
    let budget = Budget::UNLIMITED;
    let ranks = rank::ranks(
        &moved,
        &real.models,
        &[steps],
        threshold,
        &budget,
        &mut meter,
    );
    let r = ranks.expect("ranks")[0];
    assert_eq!((r.rows, r.rank, r.alone), (5, 2, 2));
}
