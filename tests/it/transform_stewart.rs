//! Structural transformations of the Stewart platform (paper Figs. 16-17).

use mbsa::Mechanism;
use mbsa::format::{Format, load};
use mbsa::structure::Library;
use mbsa::transform::{TransformOptions, transform};

fn example(name: &str) -> Mechanism {
    let (file, text) = mbsa::examples::find(name).expect("bundled example");
    load(file, text, Format::Toml).expect("bundled example loads")
}

/// All 85,151 count-valid placements, each analysed in full: seconds in release, minutes in a
/// debug build, so it runs with `cargo test --release` only.
#[test]
#[cfg_attr(debug_assertions, ignore = "slow in debug builds; run with --release")]
fn inverse_kinematics_placement_is_found_and_rank_rejects_are_counted() {
    let m = example("stewart");
    let t = transform(&m, &TransformOptions::default(), &Library::builtin(), None).unwrap();
    assert_eq!(t.summary.f, 6);
    let ik = t
        .placements
        .iter()
        .find(|p| p.inputs.len() == 1 && p.inputs[0].pair == "1-14" && p.inputs[0].driven == 6)
        .expect("the inverse-kinematics placement 1-14:6 is determined");
    assert_eq!(ik.scores.groups, 7);
    assert_eq!(ik.scores.covered, 7);
    assert!(ik.scores.all_covered);
    assert_eq!(ik.scores.levels, 2);
    assert!(t.summary.excluded_by_rank > 0);
    assert_eq!(
        t.summary.count_valid,
        t.summary.determined + t.summary.excluded_by_rank
    );
    assert_eq!(t.placements.len() as u128, t.summary.determined);
    assert!(t.summary.notes.iter().any(|n| n.contains("rank check")));
    // The original inputs (the six legs) are determined too.
    assert!(t.original_rank.is_some());
}

/// The same question on the legs' actuators and the free pair only (fast in any build).
#[test]
fn inverse_kinematics_among_actuator_and_pose_inputs() {
    let m = example("stewart");
    let o = TransformOptions {
        on: Some(TransformOptions::parse_on("P,F").unwrap()),
        ..TransformOptions::default()
    };
    let t = transform(&m, &o, &Library::builtin(), None).unwrap();
    let top = &t.placements[0];
    assert_eq!(top.spec(), "1-14:6");
    assert_eq!(top.scores.groups, 7);
    assert!(top.scores.all_covered);
    let text = mbsa::report::transform::table(&t, 5);
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!("transform_stewart_pf", text);
    });
}
