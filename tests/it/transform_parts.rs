//! Independent parts placed once per structure: the binary
//! expansions of a shared joint placed part by part, with each part's placements kept across
//! expansions, and the parts of a star placed once for every part of the same structure. The
//! results equal placing the whole (`split: false`, the former path) field for field; the
//! work units (deterministic) show the work no longer grows with the expansions times the
//! bodies, nor with the parts times an analysis each.

use mbsa::budget::Budget;
use mbsa::generate;
use mbsa::structure::Library;
use mbsa::transform::{Transform, TransformError, TransformOptions, transform};
use mbsa::{BodyId, JointSpec, JointType, Mechanism, Space};

fn json(t: &Transform) -> String {
    serde_json::to_string_pretty(t).unwrap()
}

/// `transform` with and without placing parts apart. One part (a shared joint's expansions
/// placed part by part): the same output, byte for byte. The file's own parts: the same
/// counts and the same placements (inputs by name, scores, groups, types); their listing
/// order is the parts' ranking, not the whole's enumeration order.
fn parts_equal_whole(m: &Mechanism, limit: Option<usize>, count_only: bool) -> Transform {
    let lib = Library::builtin();
    let mut o = TransformOptions {
        limit,
        ..TransformOptions::default()
    };
    o.analysis.count_only = count_only;
    let split = transform(m, &o, &lib, None).unwrap();
    let whole = transform(
        m,
        &TransformOptions {
            split: false,
            ..o.clone()
        },
        &lib,
        None,
    )
    .unwrap();
    if split.summary.parts == 1 {
        assert_eq!(json(&split), json(&whole), "{}", m.name);
        return split;
    }
    let s = (&split.summary, &whole.summary);
    assert_eq!(s.0.count_valid, s.1.count_valid, "{}", m.name);
    assert_eq!(s.0.determined, s.1.determined, "{}", m.name);
    assert_eq!(s.0.f, s.1.f, "{}", m.name);
    assert_eq!(s.0.drivable, s.1.drivable, "{}", m.name);
    let set = |t: &Transform| {
        let mut v: Vec<String> = t
            .placements
            .iter()
            .map(|p| {
                let mut p = p.clone();
                p.rank = None;
                p.family = None;
                serde_json::to_string(&p).unwrap()
            })
            .collect();
        v.sort();
        v
    };
    assert_eq!(set(&split), set(&whole), "{}", m.name);
    split
}

fn mech(name: &str, space: Space, joints: Vec<JointSpec>) -> Mechanism {
    Mechanism::from_parts(name, space, BodyId::Int(1), vec![], joints)
}

#[test]
fn expansions_of_a_shared_s_joint_placed_part_by_part_equal_the_whole() {
    for n in [3, 4, 12, 40] {
        let m = generate::star(n, JointType::S, false, true, false).unwrap();
        for count_only in [false, true] {
            // Some trees have paths of three bodies, whose parts have several placements
            // (placed whole); the others are placed part by part.
            let t = parts_equal_whole(&m, Some(100), count_only);
            assert!(t.summary.count_valid > 0, "{n}");
        }
    }
    // A planar shared R joint (every expansion's parts: one body, or two in series).
    let m = generate::star(30, JointType::R, true, true, false).unwrap();
    parts_equal_whole(&m, None, false);
}

/// A part of an expansion with several placements (a loop through the frame: bodies 2 and 3
/// also joined by an R joint) is placed with its whole expansion, as before; the others are
/// still placed part by part.
#[test]
fn an_expansion_with_a_part_of_several_placements_is_placed_whole() {
    let mut joints = vec![JointSpec::new(JointType::S, 1, 2, 0)];
    joints[0].bodies = (1..=6).map(BodyId::Int).collect();
    joints[0].id = Some("hub".into());
    joints.push(JointSpec::new(JointType::R, 2, 3, 0));
    let m = mech("hub with a loop", Space::Spatial, joints);
    for count_only in [false, true] {
        let t = parts_equal_whole(&m, None, count_only);
        assert!(t.summary.count_valid > 64, "{:?}", t.summary);
    }
}

/// Parts the same up to renaming share one placing: stars of R and S joints on the frame,
/// and two legs of different shapes, each twice (bodies named apart).
#[test]
fn parts_of_the_same_structure_placed_once_equal_the_whole() {
    let star = generate::star(25, JointType::R, false, false, false).unwrap();
    parts_equal_whole(&star, None, false);
    let star = generate::star(25, JointType::S, false, false, false).unwrap();
    parts_equal_whole(&star, None, false);
    // Two planar four-bars and two slider four-bars on one frame, interleaved ids.
    use JointType::{P, R};
    let j = |k, a, b| JointSpec::new(k, a, b, 0);
    let joints = vec![
        j(R, 1, 2),
        j(R, 2, 3),
        j(R, 3, 4),
        j(R, 4, 1),
        j(R, 1, 10),
        j(P, 10, 11),
        j(R, 11, 12),
        j(R, 12, 1),
        j(R, 1, 5),
        j(R, 5, 6),
        j(R, 6, 7),
        j(R, 7, 1),
        j(R, 1, 20),
        j(P, 20, 21),
        j(R, 21, 22),
        j(R, 22, 1),
    ];
    let m = mech("two shapes twice", Space::Planar, joints);
    let t = parts_equal_whole(&m, None, false);
    assert_eq!(t.summary.parts, 4);
    assert!(t.summary.determined > 1);
}

/// A shared S joint of 3,001 bodies, `--limit 100`: 64 expansions, each analysed twice in
/// full before (without inputs, then its one placement: 50 units a body or pair each, about
/// 3.8·10^7 units), now a pass over each expansion's parts (an eighth of a unit a body or
/// pair) and three small parts placed once. It fits 2·10^6 units; the whole does not. Every
/// expansion is determined: one that chains two balls of the one centre through a body has
/// that body's turn driven too (the input beyond it drags it).
#[test]
fn a_shared_s_joint_fits_a_budget_the_whole_expansions_overrun() {
    let m = generate::star(3_001, JointType::S, false, true, false).unwrap();
    let lib = Library::builtin();
    let o = TransformOptions {
        limit: Some(100),
        budget: Budget {
            max_work: 2_000_000,
            ..Budget::DEFAULT
        },
        ..TransformOptions::default()
    };
    let t = transform(&m, &o, &lib, None).unwrap();
    assert_eq!(t.summary.count_valid, 64);
    assert_eq!(t.summary.determined, 64);
    assert_eq!(t.placements[0].inputs.len(), 3_000);
    let whole = TransformOptions { split: false, ..o };
    match transform(&m, &whole, &lib, None) {
        Err(TransformError::Budget(e)) => assert!(e.help().contains("--max-work"), "{e}"),
        other => panic!("{:?}", other.map(|t| t.summary)),
    }
}

/// A star of 20,000 spatial R joints on the frame: 20,000 parts of one structure, placed once
/// (each was placed alone before: about 500 units a part, 10^7 in all). It fits 10^6 units.
#[test]
fn a_star_of_20000_parts_is_placed_once() {
    let m = generate::star(20_001, JointType::R, false, false, false).unwrap();
    let lib = Library::builtin();
    let o = TransformOptions {
        limit: Some(100),
        budget: Budget {
            max_work: 1_000_000,
            ..Budget::DEFAULT
        },
        ..TransformOptions::default()
    };
    let t = transform(&m, &o, &lib, None).unwrap();
    assert_eq!(t.summary.parts, 20_000);
    assert_eq!(t.summary.determined, 1);
    assert_eq!(t.placements[0].inputs.len(), 20_000);
    assert_eq!(t.placements[0].inputs[19_999].pair, "1-20001");
}
