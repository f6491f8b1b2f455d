//! Snapshots of the pebble-game report: the stacked four-bars of docs (lower four-bar with both
//! diagonals, upper four-bar on its top bar), as a table and as JSON.

use mbsa::joint::JointType;
use mbsa::rigidity::pebble::{PebbleOptions, analyze};
use mbsa::{BodyId, Geometry, JointSpec, Mechanism, Space};

fn stacked_four_bars() -> Mechanism {
    // Points p1..p6; bars 1 (frame, p1p2), 2 p2p3, 3 p3p4, 4 p4p1, 5 p1p3, 6 p2p4 (lower
    // four-bar and its diagonals), 7 p3p6, 8 p6p5, 9 p5p4 (upper four-bar on bar 3).
    let points: [(&str, &[i64]); 6] = [
        ("p1", &[1, 4, 5]),
        ("p2", &[1, 2, 6]),
        ("p3", &[2, 3, 5, 7]),
        ("p4", &[3, 4, 6, 9]),
        ("p5", &[8, 9]),
        ("p6", &[7, 8]),
    ];
    let joints = points
        .iter()
        .map(|(id, bars)| JointSpec {
            id: Some(id.to_string()),
            kind: JointType::R,
            bodies: bars.iter().map(|&b| BodyId::Int(b)).collect(),
            driven: 0,
            geometry: Geometry::default(),
        })
        .collect();
    Mechanism::from_parts(
        "stacked four-bars",
        Space::Planar,
        BodyId::Int(1),
        vec![],
        joints,
    )
}

#[test]
fn stacked_four_bars_report() {
    let r = analyze(&stacked_four_bars(), &PebbleOptions::default());
    assert_eq!((r.dof, r.redundant, r.count), (1, 1, 0));
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!("pebble_stacked_four_bars_table", mbsa::report::rigid_pebble::table(&r));
        insta::assert_snapshot!("pebble_stacked_four_bars_json", mbsa::report::json(&r));
    });
}
