//! Restrictions, limits, streaming and multiple-joint expansions of `mbsa transform`.

use mbsa::format::{Format, load};
use mbsa::structure::Library;
use mbsa::transform::{
    BaseMode, Placement, Progress, TransformError, TransformOptions, enumerate, transform,
};
use mbsa::{BodyId, InputSpec, JointSpec, JointType, Mechanism, Space};
use std::sync::atomic::{AtomicUsize, Ordering};

fn rotor() -> Mechanism {
    let (file, text) = mbsa::examples::find("rotor").expect("bundled example");
    load(file, text, Format::Toml).expect("bundled example loads")
}

/// Count-only keeps these tests fast; restrictions do not depend on the rank check.
fn opts() -> TransformOptions {
    let mut o = TransformOptions::default();
    o.analysis.count_only = true;
    o
}

fn specs(ps: &[Placement]) -> Vec<String> {
    let mut v: Vec<String> = ps.iter().map(|p| p.spec()).collect();
    v.sort();
    v
}

/// A restriction is exactly a filter on the unrestricted placements.
fn check_filter(restricted: &TransformOptions, keep: impl Fn(&Placement) -> bool) -> usize {
    let m = rotor();
    let lib = Library::builtin();
    let all = transform(&m, &opts(), &lib, None).unwrap();
    let some = transform(&m, restricted, &lib, None).unwrap();
    let expected: Vec<Placement> = all.placements.iter().filter(|p| keep(p)).cloned().collect();
    assert!(!expected.is_empty());
    assert!(expected.len() < all.placements.len());
    assert_eq!(specs(&some.placements), specs(&expected));
    assert!(!some.summary.notes.is_empty());
    expected.len()
}

fn kind_of(m: &Mechanism, joint: &str) -> JointType {
    m.joints.iter().find(|j| j.id == joint).unwrap().kind
}

#[test]
fn on_restricts_joint_types() {
    let m = rotor();
    let mut o = opts();
    o.on = Some(TransformOptions::parse_on("R,P").unwrap());
    check_filter(&o, |p| {
        p.inputs
            .iter()
            .all(|i| matches!(kind_of(&m, &i.joint), JointType::R | JointType::P))
    });
}

#[test]
fn grounded_restricts_to_frame_joints() {
    let mut o = opts();
    o.grounded = true;
    check_filter(&o, |p| p.inputs.iter().all(|i| i.pair.starts_with("1-")));
}

#[test]
fn keep_holds_inputs() {
    let mut o = opts();
    o.keep = Some(InputSpec::parse("13-15,1-13").unwrap());
    let n = check_filter(&o, |p| {
        p.inputs.iter().any(|i| i.joint == "13-15") && p.inputs.iter().any(|i| i.joint == "1-13")
    });
    assert!(n >= 1);
}

#[test]
fn exclude_forbids_joints() {
    let mut o = opts();
    o.exclude = Some(InputSpec::parse("13-15,11-14").unwrap());
    check_filter(&o, |p| {
        p.inputs
            .iter()
            .all(|i| i.joint != "13-15" && i.joint != "11-14")
    });
}

#[test]
fn bad_restrictions_are_errors() {
    let m = rotor();
    let lib = Library::builtin();
    let mut o = opts();
    o.keep = Some(InputSpec::parse("13-15").unwrap());
    o.exclude = Some(InputSpec::parse("13-15").unwrap());
    assert!(matches!(
        transform(&m, &o, &lib, None),
        Err(TransformError::KeepExcluded { .. })
    ));
    let mut o = opts();
    o.keep = Some(InputSpec::parse("13-15:2").unwrap());
    assert!(matches!(
        transform(&m, &o, &lib, None),
        Err(TransformError::Spec(_))
    ));
    let mut o = opts();
    o.exclude = Some(InputSpec::parse("99-100").unwrap());
    assert!(transform(&m, &o, &lib, None).is_err());
}

#[test]
fn limit_cuts_the_search_with_a_note() {
    let m = rotor();
    let mut o = opts();
    o.limit = Some(10);
    let t = transform(&m, &o, &Library::builtin(), None).unwrap();
    assert!(t.summary.truncated);
    assert_eq!(t.summary.count_valid, 10);
    assert!(t.summary.notes.iter().any(|n| n.contains("--limit 10")));
    let text = mbsa::report::transform::table(&t, 3);
    assert!(text.contains("--limit 10"));
}

#[test]
fn streaming_matches_ranking_and_reports_progress() {
    let m = rotor();
    let lib = Library::builtin();
    let calls = AtomicUsize::new(0);
    let last = AtomicUsize::new(0);
    let progress = |p: Progress| {
        calls.fetch_add(1, Ordering::Relaxed);
        assert!(p.examined <= p.total);
        last.store(p.examined, Ordering::Relaxed);
    };
    let mut lines = Vec::new();
    let s = enumerate(&m, &opts(), &lib, Some(&progress), &mut |p| {
        lines.push(mbsa::report::transform::jsonl(&p));
    })
    .unwrap();
    assert_eq!(lines.len() as u128, s.determined);
    assert!(
        lines
            .iter()
            .all(|l| l.ends_with('\n') && !l[..l.len() - 1].contains('\n'))
    );
    assert!(calls.load(Ordering::Relaxed) >= 1);
    assert_eq!(last.load(Ordering::Relaxed) as u128, s.count_valid);
    let t = transform(&m, &opts(), &lib, None).unwrap();
    assert_eq!(t.placements.len(), lines.len());
    let json: serde_json::Value = serde_json::from_str(&mbsa::report::json(&t)).unwrap();
    assert_eq!(
        json["placements"].as_array().unwrap().len() as u128,
        s.determined
    );
}

/// Planar: bodies 2 and 3 pinned to the frame and joined with 4 by one ternary pin.
fn ternary() -> Mechanism {
    let mut j = JointSpec::new(JointType::R, 2, 3, 0);
    j.id = Some("C".into());
    j.bodies.push(BodyId::Int(4));
    Mechanism::from_parts(
        "ternary",
        Space::Planar,
        BodyId::Int(1),
        vec![],
        vec![
            JointSpec::new(JointType::R, 1, 2, 0),
            JointSpec::new(JointType::R, 1, 3, 0),
            j,
        ],
    )
}

#[test]
fn multiple_joints_are_expanded_into_spanning_trees() {
    let m = ternary();
    let lib = Library::builtin();
    let t = transform(&m, &TransformOptions::default(), &lib, None).unwrap();
    assert_eq!(t.summary.f, 1);
    assert_eq!(t.summary.expansions, 3);
    assert_eq!(t.summary.expansions_total, 3);
    let got: Vec<(String, String)> = t
        .placements
        .iter()
        .map(|p| (p.spec(), p.expansion.clone().unwrap()))
        .collect();
    // Star on 2 (the default): a triangle 1-2-3 and body 4 on pair 2-4, driven there; star
    // on 3: likewise with 3-4; star on 4: a four-bar 1-2-4-3, driven at any of its joints
    // (one group of three bodies, so ranked last).
    let s = |a: &str, b: &str| (a.to_string(), b.to_string());
    assert_eq!(
        got,
        vec![
            s("C[2-4]", "C: 2-3, 2-4"),
            s("C[3-4]", "C: 2-3, 3-4"),
            s("1-2", "C: 2-4, 3-4"),
            s("1-3", "C: 2-4, 3-4"),
            s("C[2-4]", "C: 2-4, 3-4"),
            s("C[3-4]", "C: 2-4, 3-4"),
        ]
    );
    let o = TransformOptions {
        max_expansions: 1,
        ..TransformOptions::default()
    };
    let t = transform(&m, &o, &lib, None).unwrap();
    assert_eq!(t.placements.len(), 1);
    assert!(
        t.summary
            .notes
            .iter()
            .any(|n| n.contains("--max-expansions"))
    );
    let text = mbsa::report::transform::table(&t, 10);
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!("transform_ternary_table", text);
    });
}

/// Zero placements always come with a reason. Too few drivable DOF (no S joint in the slider
/// crank for `--on S`, at the file's geometry and by count alone): the note says how many DOF
/// the allowed joints carry against the inputs to place.
#[test]
fn no_placement_for_want_of_drivable_dof_says_so() {
    let (file, text) = mbsa::examples::find("slider-crank-geometry").expect("bundled example");
    let m = load(file, text, Format::Toml).expect("bundled example loads");
    let lib = Library::builtin();
    for count_only in [false, true] {
        let mut o = TransformOptions::default();
        o.analysis.count_only = count_only;
        o.analysis.geometry = mbsa::geometry::GeometrySource::File;
        o.on = Some(TransformOptions::parse_on("S").unwrap());
        let r = transform(&m, &o, &lib, None).unwrap();
        assert_eq!((r.summary.count_valid, r.summary.determined), (0, 0));
        assert!(
            r.summary.notes.iter().any(|n| n.contains("no placement")),
            "count_only {count_only}: {:?}",
            r.summary.notes
        );
        if !count_only {
            assert!(
                r.summary
                    .notes
                    .iter()
                    .any(|n| n.contains("carry 0 DOF in all, fewer than the 1 input(s)")),
                "{:?}",
                r.summary.notes
            );
        }
    }
}

/// Enough drivable DOF, yet every placement fails the count: a planar four-bar (A, C, D, E)
/// with a pendant bar on B, and B excluded. Two inputs are needed, and the only joints left are
/// in the four-bar's loop, which takes one: the note says nothing passes the count.
#[test]
fn no_placement_by_count_says_so() {
    let text = r#"
name = "four-bar with a pendant bar"
space = "planar"
frame = 0
"#
    .to_string()
        + &[
            ("A", 0, 1),
            ("B", 1, 2),
            ("C", 1, 3),
            ("D", 3, 4),
            ("E", 4, 0),
        ]
        .iter()
        .map(|(id, a, b)| format!("[[joint]]\nid = \"{id}\"\ntype = \"R\"\nbodies = [{a}, {b}]\n"))
        .collect::<String>();
    let m = load("pendant.toml", &text, Format::Toml).expect("valid");
    let lib = Library::builtin();
    let mut o = opts();
    o.exclude = Some(InputSpec::parse("B").unwrap());
    let r = transform(&m, &o, &lib, None).unwrap();
    assert_eq!((r.summary.f, r.summary.count_valid), (2, 0));
    let why: Vec<&String> = r
        .summary
        .notes
        .iter()
        .filter(|n| n.contains("no placement"))
        .collect();
    assert_eq!(why.len(), 1, "{:?}", r.summary.notes);
    assert!(
        why[0].contains("no placement of the 2 input(s) on the 4 joint(s)"),
        "{}",
        why[0]
    );
    // Without the exclusion there are placements and no such note.
    let r = transform(&m, &opts(), &lib, None).unwrap();
    assert!(r.summary.determined > 0);
    assert!(r.summary.notes.iter().all(|n| !n.contains("no placement")));
}

/// `--limit` reached before any determined placement: besides "more placements exist" the note
/// says none examined is determined and how to go on (a Delta robot at `--limit 20`: every
/// placement examined drove a rod's spin). Here: the micro-manipulator at `--limit 1`, whose
/// first placement the rank check excludes.
#[test]
fn a_limit_reached_with_nothing_determined_says_how_to_go_on() {
    let (file, text) = mbsa::examples::find("micro-manipulator").expect("bundled example");
    let m = load(file, text, Format::Toml).expect("bundled example loads");
    let lib = Library::builtin();
    let mut o = TransformOptions {
        limit: Some(1),
        ..Default::default()
    };
    let r = transform(&m, &o, &lib, None).unwrap();
    assert!(
        r.summary.truncated && r.summary.determined == 0,
        "{:?}",
        r.summary
    );
    assert!(
        r.summary
            .notes
            .iter()
            .any(|n| n.starts_with("none of the 1 placement(s) examined is determined")),
        "{:?}",
        r.summary.notes
    );
    // With room to find one, no such note.
    o.limit = Some(100_000);
    let r = transform(&m, &o, &lib, None).unwrap();
    assert!(r.summary.determined > 0);
    assert!(
        r.summary
            .notes
            .iter()
            .all(|n| !n.starts_with("none of the"))
    );
}

/// An imported model, read as `mbsa transform FILE` reads it.
fn imported(name: &str) -> Mechanism {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/import")
        .join(name);
    mbsa::import::import_file(&path, &mbsa::import::ImportOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .mechanism
}

fn with_base(base: BaseMode, limit: Option<usize>) -> TransformOptions {
    TransformOptions {
        base,
        limit,
        ..TransformOptions::default()
    }
}

/// A Delta robot imported from Gazebo floats: its base's free joint (`base_link:free`) is its
/// only joint to the world. Its pose is taken as given, so `--limit 50` finds the arms'
/// placements at once (it used to examine 50 placements driving the base or the rods' spins
/// and find none); the note and the JSON name the joint.
#[test]
fn a_floating_base_is_driven_in_full_and_named() {
    let m = imported("delta_robot.sdf");
    let lib = Library::builtin();
    let t = transform(&m, &with_base(BaseMode::Auto, Some(50)), &lib, None).unwrap();
    assert_eq!(t.summary.f, 9);
    assert_eq!(t.summary.fixed_base, vec!["base_link:free".to_string()]);
    assert!(t.summary.determined > 0, "{:?}", t.summary);
    assert!(t.placements.iter().all(|p| {
        p.inputs
            .iter()
            .any(|i| i.joint == "base_link:free" && i.driven == 6)
    }));
    assert!(
        t.summary
            .notes
            .iter()
            .any(|n| n.starts_with("floating base taken as driven in full")
                && n.contains("base_link:free (6 DOF)")),
        "{:?}",
        t.summary.notes
    );
    let best = &t.placements[0];
    assert_eq!(
        best.spec(),
        "base_link:free:6,proximal_link_1_joint,proximal_link_3_joint,proximal_link_5_joint"
    );
    let json: serde_json::Value = serde_json::from_str(&mbsa::report::json(&t)).unwrap();
    assert_eq!(
        json["summary"]["fixed_base"],
        serde_json::json!(["base_link:free"])
    );
    let text = mbsa::report::transform::table(&t, 3);
    assert!(text.contains("note: floating base taken as driven in full"));
    // The same run twice: the same bytes.
    let again = transform(&m, &with_base(BaseMode::Auto, Some(50)), &lib, None).unwrap();
    assert_eq!(mbsa::report::json(&again), mbsa::report::json(&t));
    // Without a floating base, no key.
    let r = transform(&rotor(), &opts(), &lib, None).unwrap();
    let json: serde_json::Value = serde_json::from_str(&mbsa::report::json(&r)).unwrap();
    assert!(json["summary"].get("fixed_base").is_none());
}

/// Nothing is lost: every determined placement of a floating mechanism drives its free base
/// in full, so searching with the base free finds the same ones (@floating-base, with its leg;
/// the Delta with inputs on its R and F joints only, as the whole search with the base free
/// takes minutes).
#[test]
fn fixing_a_floating_base_keeps_every_determined_placement() {
    let lib = Library::builtin();
    let (file, text) = mbsa::examples::find("floating-base").expect("bundled example");
    let leg = load(file, text, Format::Toml).expect("bundled example loads");
    for (m, on) in [(imported("delta_robot.sdf"), Some("R,F")), (leg, None)] {
        let mut o = with_base(BaseMode::Auto, None);
        o.on = on.map(|t| TransformOptions::parse_on(t).unwrap());
        let fixed = transform(&m, &o, &lib, None).unwrap();
        o.base = BaseMode::Free;
        let free = transform(&m, &o, &lib, None).unwrap();
        assert!(free.summary.fixed_base.is_empty());
        assert!(fixed.summary.determined > 0);
        assert_eq!(
            specs(&fixed.placements),
            specs(&free.placements),
            "{}",
            m.name
        );
        assert!(free.summary.count_valid >= fixed.summary.count_valid);
    }
}

/// A free joint that is not its part's only joint to the frame (the fictitious pair 1-14 of
/// @stewart, which carries the platform's pose) is placed like any other, unless `--fix-base`
/// says otherwise; then it is driven in full, and `--exclude` of it is an error.
#[test]
fn fix_base_drives_every_free_joint_to_the_frame() {
    let (file, text) = mbsa::examples::find("stewart").expect("bundled example");
    let m = load(file, text, Format::Toml).expect("bundled example loads");
    let lib = Library::builtin();
    let mut o = opts();
    o.limit = Some(20);
    let auto = transform(&m, &o, &lib, None).unwrap();
    assert!(auto.summary.fixed_base.is_empty());
    assert!(auto.placements.iter().any(|p| p.spec() != "1-14:6"));
    o.limit = None;
    o.base = BaseMode::Fixed;
    let fixed = transform(&m, &o, &lib, None).unwrap();
    assert_eq!(fixed.summary.fixed_base, vec!["1-14".to_string()]);
    assert_eq!(specs(&fixed.placements), vec!["1-14:6".to_string()]);
    assert!(fixed.summary.notes.iter().any(|n| n.contains("--fix-base")));
    o.exclude = Some(InputSpec::parse("1-14").unwrap());
    assert!(matches!(
        transform(&m, &o, &lib, None),
        Err(TransformError::KeepExcluded { .. })
    ));
}

/// The Cassie at its file's configuration: each foot's four-bar is planar and closed by a
/// ball, so 2 constraint equations are redundant there (set aside) and two rods spin alone.
/// Every one of the first 50 count-valid placements drove a spin or one motion twice: nothing
/// was determined, and the first note said why redundant constraints can do that and pointed
/// to `mbsa repair`. The search now cuts those branches: its first 50 placements are all
/// determined, and the note is gone. The former path (every count-valid placement analysed in
/// full) still meets only excluded ones and still says so first.
#[test]
fn redundant_constraints_are_said_first_with_the_way_to_repair() {
    let m = imported("cassie.xml");
    let lib = Library::builtin();
    let t = transform(&m, &with_base(BaseMode::Auto, Some(50)), &lib, None).unwrap();
    assert_eq!(t.summary.fixed_base, vec!["cassie-pelvis:free".to_string()]);
    assert_eq!(t.summary.set_aside, 2);
    assert_eq!((t.summary.determined, t.summary.excluded_by_rank), (50, 0));
    assert!(
        t.summary.notes.iter().all(|n| !n.contains("mbsa repair")),
        "{:?}",
        t.summary.notes
    );
    let former = TransformOptions {
        full_analyses: true,
        ..with_base(BaseMode::Auto, Some(50))
    };
    let t = transform(&m, &former, &lib, None).unwrap();
    assert_eq!((t.summary.determined, t.summary.set_aside), (0, 2));
    let first = &t.summary.notes[0];
    assert!(
        first.starts_with("none of the 50 placement(s) examined is determined, and 2 constraint")
            && first.contains("`mbsa repair`"),
        "{:?}",
        t.summary.notes
    );
    // A mechanism whose redundancy the set-aside equations absorb (a planar four-bar written
    // in space) has placements and no such note.
    let four = imported("four_bar.sdf");
    let t = transform(&four, &TransformOptions::default(), &lib, None).unwrap();
    assert!(t.summary.set_aside > 0 && t.summary.determined > 0);
    assert!(t.summary.notes.iter().all(|n| !n.contains("mbsa repair")));
}

#[test]
fn an_over_constrained_count_places_no_input_rather_than_a_negative_number() {
    let (code, out, _) = crate::common::mbsa(&[
        "transform",
        "mechanisms/four-bar-3d-driven.toml",
        "--geometry",
        "random",
    ]);
    assert_eq!(code, 0, "{out}");
    let head = out.lines().next().unwrap();
    assert!(
        head.contains("count -2: no input to place (2 DOF over-constrained by count)"),
        "{head}"
    );
    assert!(!out.contains("-2 input(s)"), "{out}");
}

/// A whole search past the work budget names the search's own bounds beside the budget's
/// flags (a 24-body leg ran 120 s to the work limit, where `--limit 20` answers at once);
/// with `--limit` given, only the budget's.
#[test]
fn a_search_over_the_budget_names_limit_and_keep() {
    let (code, out, err) =
        crate::common::mbsa(&["--max-work", "100000", "transform", "@hexapod-rss"]);
    assert_eq!(code, 2, "{out}{err}");
    assert!(err.contains("--max-work"), "{err}");
    assert!(
        err.contains("help: or bound the search: `--limit N` examines the first N placements"),
        "{err}"
    );
    let (code, _, err) = crate::common::mbsa(&[
        "--max-work",
        "100000",
        "transform",
        "@hexapod-rss",
        "--limit",
        "1000",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(!err.contains("bound the search"), "{err}");
}
