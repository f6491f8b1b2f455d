//! The reference cases of `docs/cases.md` (the MBSSA3D paper's examples), built in code, and
//! a few cases where counting is fooled.

use mbsa::joint::JointType::{self, *};
use mbsa::mechanism::{BodyId, JointSpec, Mechanism, Space};
use mbsa::structure::{Analysis, Library, Method, Options, Status, analyze};

fn mech(name: &str, space: Space, joints: &[(JointType, i64, i64, u32)]) -> Mechanism {
    Mechanism::from_parts(
        name,
        space,
        BodyId::Int(1),
        vec![],
        joints
            .iter()
            .map(|&(k, a, b, d)| JointSpec::new(k, a, b, d))
            .collect(),
    )
}

fn count_only() -> Options {
    Options {
        count_only: true,
        ..Options::default()
    }
}

/// Groups as `L<level> {bodies} type` lines.
fn summary(a: &Analysis) -> String {
    a.groups
        .iter()
        .map(|g| format!("L{} {{{}}} {}", g.level, g.bodies.join(","), g.kind))
        .collect::<Vec<_>>()
        .join("\n")
}

fn snap(name: &str, value: String) {
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!(name, value);
    });
}

fn both_methods_agree(m: &Mechanism, opts: Options) -> Analysis {
    let lib = Library::builtin();
    let a = analyze(m, &opts, &lib).unwrap();
    let b = analyze(
        m,
        &Options {
            method: Method::Exhaustive,
            ..opts
        },
        &lib,
    )
    .unwrap();
    assert_eq!(summary(&a), summary(&b), "flow and exhaustive differ");
    a
}

pub fn four_bar() -> Mechanism {
    mech(
        "four-bar-rscp",
        Space::Spatial,
        &[(R, 1, 2, 1), (S, 2, 3, 0), (C, 3, 4, 0), (P, 1, 4, 0)],
    )
}

pub fn nine_bar() -> Mechanism {
    mech(
        "nine-bar",
        Space::Planar,
        &[
            (R, 1, 2, 1),
            (R, 2, 3, 1),
            (R, 3, 4, 1),
            (R, 4, 5, 0),
            (R, 5, 6, 0),
            (R, 6, 1, 0),
            (R, 5, 7, 0),
            (R, 7, 8, 0),
            (R, 8, 9, 0),
            (R, 9, 1, 1),
        ],
    )
}

pub fn rotor(set: u32) -> Mechanism {
    let d = |a: i64, b: i64| -> u32 {
        let one = match set {
            1 => [(13, 9), (13, 15), (11, 14)].contains(&(a, b)),
            _ => [(1, 2), (1, 13), (13, 15)].contains(&(a, b)),
        };
        one as u32
    };
    let pairs: [(JointType, i64, i64); 21] = [
        (P, 1, 2),
        (P, 1, 3),
        (P, 1, 4),
        (P, 1, 13),
        (R, 8, 9),
        (R, 11, 9),
        (R, 13, 9),
        (R, 13, 15),
        (R, 15, 16),
        (U, 2, 5),
        (U, 3, 6),
        (U, 4, 7),
        (U, 1, 10),
        (U, 8, 12),
        (U, 11, 14),
        (S, 5, 8),
        (S, 6, 9),
        (S, 7, 11),
        (S, 10, 9),
        (S, 12, 16),
        (S, 14, 16),
    ];
    let joints: Vec<(JointType, i64, i64, u32)> =
        pairs.iter().map(|&(k, a, b)| (k, a, b, d(a, b))).collect();
    mech(&format!("rotor-set{set}"), Space::Spatial, &joints)
}

pub fn micro() -> Mechanism {
    let mut j: Vec<(JointType, i64, i64, u32)> = Vec::new();
    for b in [4, 2, 15, 8, 13, 16] {
        j.push((ER, 1, b, 0));
    }
    for (a, b) in [
        (1, 7),
        (5, 6),
        (6, 7),
        (1, 12),
        (10, 11),
        (11, 12),
        (1, 20),
        (18, 19),
        (19, 20),
    ] {
        j.push((R, a, b, 0));
    }
    for (a, b) in [(4, 5), (2, 3), (10, 15), (8, 9), (13, 14), (16, 17)] {
        j.push((C, a, b, 1));
    }
    for (a, b) in [
        (3, 5),
        (5, 21),
        (10, 21),
        (9, 10),
        (10, 14),
        (18, 21),
        (17, 18),
    ] {
        j.push((S, a, b, 0));
    }
    mech("micro-manipulator", Space::Spatial, &j)
}

pub fn stewart(ik: bool) -> Mechanism {
    let mut j: Vec<(JointType, i64, i64, u32)> = Vec::new();
    for i in 1..=6 {
        let (a, b) = (2 * i, 2 * i + 1);
        j.push((U, 1, a, 0));
        j.push((P, a, b, (!ik) as u32));
        j.push((S, b, 14, 0));
    }
    j.push((F, 1, 14, if ik { 6 } else { 0 }));
    mech(
        if ik { "stewart-ik" } else { "stewart" },
        Space::Spatial,
        &j,
    )
}

/// 6-RSS hexapod: crank 2i (R on the frame, driven), rod 2i+1 (S-S), platform 14.
pub fn hexapod() -> Mechanism {
    let mut j: Vec<(JointType, i64, i64, u32)> = Vec::new();
    for i in 1..=6 {
        let (a, b) = (2 * i, 2 * i + 1);
        j.push((R, 1, a, 1));
        j.push((S, a, b, 0));
        j.push((S, b, 14, 0));
    }
    mech("hexapod-6rss", Space::Spatial, &j)
}

#[test]
fn four_bar_groups() {
    let a = both_methods_agree(&four_bar(), count_only());
    assert_eq!(summary(&a), "L1 {2} 1R3D\nL2 {3,4} 1P1C1S3D");
    assert_eq!(a.status, Status::Determined);
    let a = analyze(&four_bar(), &Options::default(), &Library::builtin()).unwrap();
    assert_eq!(a.status, Status::Determined);
    snap("structure_four_bar", mbsa::report::structure::table(&a));
}

#[test]
fn nine_bar_groups() {
    let a = both_methods_agree(&nine_bar(), count_only());
    assert_eq!(
        summary(&a),
        "L1 {2} 1R2D\nL1 {9} 1R2D\nL2 {3} 1R2D\nL3 {4} 1R2D\nL4 {5,6} 3R2D\nL5 {7,8} 3R2D"
    );
    let a = analyze(&nine_bar(), &Options::default(), &Library::builtin()).unwrap();
    assert_eq!(a.status, Status::Determined);
    assert!(a.redundant.is_empty() && a.isolated.is_empty());
    snap("structure_nine_bar", mbsa::report::structure::table(&a));
}

#[test]
fn rotor_set_1() {
    let a = both_methods_agree(&rotor(1), count_only());
    assert_eq!(
        summary(&a),
        "L1 {9,10,13} 1R1P1U1S3D\nL2 {15} 1R3D\nL2 {3,6} 1P1U1S3D\nL3 {11,14,16} 2R1U1S3D\n\
         L4 {4,7} 1P1U1S3D\nL4 {8,12} 1R1U1S3D\nL5 {2,5} 1P1U1S3D"
    );
    let g = &a.groups[0];
    assert_eq!(g.from, "10&1U.13&1P.");
    assert_eq!(g.internal, "9&10S.9&13R.");
    assert_eq!(g.to, "9&6S.9&8R.9&11R.13&15R.");
    let uncovered: Vec<&str> = a
        .types
        .iter()
        .filter(|t| !t.in_library)
        .map(|t| t.kind.as_str())
        .collect();
    assert_eq!(uncovered, ["1R1P1U1S3D", "2R1U1S3D"]);
    let full = analyze(&rotor(1), &Options::default(), &Library::builtin()).unwrap();
    assert_eq!(summary(&full), summary(&a));
    assert_eq!(full.status, Status::Determined);
    snap(
        "structure_rotor_set1",
        mbsa::report::structure::table(&full),
    );
    snap("structure_rotor_set1_json", mbsa::report::json(&full));
}

#[test]
fn rotor_set_2() {
    let a = both_methods_agree(&rotor(2), count_only());
    assert_eq!(
        summary(&a),
        "L1 {2} 1P3D\nL1 {13} 1P3D\nL2 {15} 1R3D\nL2 {9,10} 1R1U1S3D\nL3 {3,6} 1P1U1S3D\n\
         L3 {5,8} 1R1U1S3D\nL4 {12,16} 1R1U1S3D\nL5 {11,14} 1R1U1S3D\nL6 {4,7} 1P1U1S3D"
    );
    assert!(a.types.iter().all(|t| t.in_library));
    let full = analyze(&rotor(2), &Options::default(), &Library::builtin()).unwrap();
    assert_eq!(full.status, Status::Determined);
    snap(
        "structure_rotor_set2",
        mbsa::report::structure::table(&full),
    );
}

#[test]
fn micro_manipulator_count_only() {
    let a = both_methods_agree(&micro(), count_only());
    assert_eq!(
        summary(&a),
        "L1 {4,5,6,7} 3R1C1ER3D\nL1 {10,11,12,15} 3R1C1ER3D\nL2 {21} 2S3D\nL2 {2,3} 1C1ER1S3D\n\
         L2 {8,9} 1C1ER1S3D\nL2 {13,14} 1C1ER1S3D\nL3 {18,19,20} 3R1S3D\nL4 {16,17} 1C1ER1S3D"
    );
    assert_eq!(a.status, Status::Determined);
    snap(
        "structure_micro_count_only",
        mbsa::report::structure::table(&a),
    );
}

#[test]
fn micro_manipulator_rank_check() {
    let a = analyze(&micro(), &Options::default(), &Library::builtin()).unwrap();
    assert_ne!(a.status, Status::Determined);
    assert_eq!(a.redundant.len(), 1);
    let r = &a.redundant[0];
    assert_eq!(r.bodies, ["21"]);
    assert_eq!(r.joints, ["5-21", "10-21"]);
    assert_eq!(r.count, 1);
    let d = a.diagnosis.as_ref().expect("not determined");
    let under = d.underdetermined.as_ref().expect("a freedom appears");
    assert_eq!(under.missing, 1);
    assert!(under.input_candidates.iter().any(|j| j == "18-19"));
    snap("structure_micro", mbsa::report::structure::table(&a));
}

#[test]
fn stewart_original_and_ik() {
    let a = both_methods_agree(&stewart(false), count_only());
    assert_eq!(
        summary(&a),
        "L1 {2,3,4,5,6,7,8,9,10,11,12,13,14} 6P6U6S1F3D"
    );
    let a = both_methods_agree(&stewart(true), count_only());
    assert_eq!(
        summary(&a),
        "L1 {14} 1F3D\nL2 {2,3} 1P1U1S3D\nL2 {4,5} 1P1U1S3D\nL2 {6,7} 1P1U1S3D\n\
         L2 {8,9} 1P1U1S3D\nL2 {10,11} 1P1U1S3D\nL2 {12,13} 1P1U1S3D"
    );
    for ik in [false, true] {
        let full = analyze(&stewart(ik), &Options::default(), &Library::builtin()).unwrap();
        assert_eq!(full.status, Status::Determined, "ik = {ik}");
        let name = if ik {
            "structure_stewart_ik"
        } else {
            "structure_stewart"
        };
        snap(name, mbsa::report::structure::table(&full));
    }
}

#[test]
fn hexapod_rod_spins_are_isolated() {
    let a = analyze(&hexapod(), &Options::default(), &Library::builtin()).unwrap();
    assert_eq!(a.status, Status::Determined);
    assert_eq!(a.isolated.len(), 6);
    assert!(a.redundant.is_empty());
    assert_eq!(
        summary(&a),
        "L1 {2} 1R3D\nL1 {4} 1R3D\nL1 {6} 1R3D\nL1 {8} 1R3D\nL1 {10} 1R3D\nL1 {12} 1R3D\n\
         L2 {3,5,7,9,11,13,14} 12S3D"
    );
    // Counting alone sees six undriven DOF.
    let c = analyze(&hexapod(), &count_only(), &Library::builtin()).unwrap();
    assert_eq!(c.status, Status::Underdetermined);
    snap("structure_hexapod", mbsa::report::structure::table(&a));
}

#[test]
fn badly_placed_inputs_are_mixed() {
    // A planar four-bar (mobility 1) and a five-bar (mobility 2) on one frame: three inputs,
    // as many as the count, but two on the four-bar and one on the five-bar.
    let m = mech(
        "four-bar-and-five-bar-misplaced",
        Space::Planar,
        &[
            (R, 1, 2, 1),
            (R, 2, 3, 0),
            (R, 3, 4, 1),
            (R, 4, 1, 0),
            (R, 1, 5, 1),
            (R, 5, 6, 0),
            (R, 6, 7, 0),
            (R, 7, 8, 0),
            (R, 8, 1, 0),
        ],
    );
    let a = analyze(&m, &count_only(), &Library::builtin()).unwrap();
    assert_eq!(a.mobility.count, 3);
    assert_eq!(a.mobility.inputs, 3);
    assert_eq!(a.status, Status::Mixed);
    let d = a.diagnosis.as_ref().expect("not determined");
    assert_eq!(d.overdetermined.as_ref().map(|o| o.excess), Some(1));
    assert_eq!(d.underdetermined.as_ref().map(|u| u.missing), Some(1));
    assert_eq!(summary(&a), "L1 {5} 1R2D");
    let full = analyze(&m, &Options::default(), &Library::builtin()).unwrap();
    assert_eq!(full.status, Status::Mixed);
    snap(
        "structure_misplaced_inputs",
        mbsa::report::structure::table(&full),
    );
}

/// A declared body that no joint names moves freely, with one meaning in every analysis: the
/// count (3·4 - 8 = 4 for a driven four-bar plus a lone planar body), the structural analysis
/// (under-determined, the lone body's 3 DOF uncontrolled) and the pebble game (4 DOF).
#[test]
fn a_body_no_joint_names_is_a_free_body_everywhere() {
    let text = r#"
name = "four-bar and a lone body"
space = "planar"
frame = 1
body = [{ id = 1 }, { id = 2 }, { id = 3 }, { id = 4 }, { id = 9 }]
joint = [
  { type = "R", bodies = [1, 2], driven = 1 },
  { type = "R", bodies = [2, 3] },
  { type = "R", bodies = [3, 4] },
  { type = "R", bodies = [1, 4] },
]
"#;
    let m = mbsa::format::load("lone.toml", text, mbsa::format::Format::Toml).unwrap();
    assert_eq!(mbsa::mobility::mobility(&m).mobility.count, 4);
    let a = analyze(&m, &Options::default(), &Library::builtin()).unwrap();
    assert_eq!(a.status, Status::Underdetermined);
    assert_eq!(a.uncontrolled, 3);
    assert_eq!(a.disconnected, vec!["9".to_string()]);
    let diagnosis = a.diagnosis.as_ref().expect("a diagnosis");
    let under = diagnosis
        .underdetermined
        .as_ref()
        .expect("an uncontrolled part");
    assert!(under.bodies.contains(&"9".to_string()), "{under:?}");
    let pebble = mbsa::rigidity::pebble::analyze(&m, &Default::default());
    assert_eq!(pebble.dof, 4);
}
