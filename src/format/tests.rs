use super::*;
use crate::joint::JointType;
use crate::mechanism::{BodyId, Space};

const TOML_EXAMPLE: &str = r#"name = "Spatial four-bar RSCP"
space = "spatial"
frame = 1

[[joint]]
id = "A"
type = "R"
bodies = [1, 2]
driven = 1

[[joint]]
id = "B"
type = "S"
bodies = [2, 3]

[[joint]]
id = "C"
type = "C"
bodies = [3, 4]

[[joint]]
id = "D"
type = "P"
bodies = [1, 4]
"#;

const YAML_EXAMPLE: &str = "name: Spatial four-bar RSCP
frame: 1
joints:
  - {id: A, type: R, bodies: [1, 2], driven: 1}
  - {id: B, type: S, bodies: [2, 3]}
  - {id: C, type: C, bodies: [3, 4]}
  - {id: D, type: P, bodies: [1, 4]}
";

const JSON_EXAMPLE: &str = r#"{
  "name": "Spatial four-bar RSCP",
  "frame": 1,
  "joints": [
    {"id": "A", "type": "R", "bodies": [1, 2], "driven": 1},
    {"id": "B", "type": "S", "bodies": [2, 3]},
    {"id": "C", "type": "C", "bodies": [3, 4]},
    {"id": "D", "type": "P", "bodies": [1, 4]}
  ]
}"#;

#[test]
fn the_three_examples_give_the_same_mechanism() {
    let t = load("rscp.toml", TOML_EXAMPLE, Format::Toml).unwrap();
    let y = load("rscp.yaml", YAML_EXAMPLE, Format::Yaml).unwrap();
    let j = load("rscp.json", JSON_EXAMPLE, Format::Json).unwrap();
    assert_eq!(t, y);
    assert_eq!(t, j);
    assert_eq!(t.name, "Spatial four-bar RSCP");
    assert_eq!(t.space, Space::Spatial);
    assert_eq!(t.bodies.len(), 4);
    assert_eq!(t.body_id(t.frame), &BodyId::Int(1));
    let kinds: Vec<JointType> = t.joints.iter().map(|j| j.kind).collect();
    assert_eq!(
        kinds,
        [JointType::R, JointType::S, JointType::C, JointType::P]
    );
    assert_eq!(t.inputs(), 1);
}

#[test]
fn sniffs_formats() {
    assert_eq!(Format::sniff(TOML_EXAMPLE), Format::Toml);
    assert_eq!(Format::sniff(YAML_EXAMPLE), Format::Yaml);
    assert_eq!(Format::sniff(JSON_EXAMPLE), Format::Json);
    assert_eq!(Format::sniff("# c\n{frame: 1}"), Format::Yaml);
    assert_eq!(Format::sniff("frame = 1\n[[joint]\n"), Format::Toml);
    assert_eq!(Format::sniff("{\"frame\": 1,"), Format::Json);
    assert_eq!(Format::sniff("# c\n{\n  \"frame\": 1,\n"), Format::Json);
    assert_eq!(Format::sniff(""), Format::Yaml);
    assert_eq!(Format::from_path(Path::new("a/b.YML")), Some(Format::Yaml));
    assert_eq!(Format::from_path(Path::new("b.txt")), None);
}

#[test]
fn defaults_and_long_names() {
    let m = load(
        "dir/thing.toml",
        "frame = 1\n[[joint]]\ntype = \"Revolute\"\nbodies = [1, 2]\n[[joint]]\ntype = \"hinge\"\nbodies = [1, 2]\n[[joint]]\ntype = \"pin\"\nbodies = [1, 2]\n",
        Format::Toml,
    )
    .unwrap();
    assert_eq!(m.name, "thing");
    let ids: Vec<&str> = m.joints.iter().map(|j| j.id.as_str()).collect();
    assert_eq!(ids, ["1-2", "1-2#2", "1-2#3"]);
    assert!(m.joints.iter().all(|j| j.kind == JointType::R));
}

#[test]
fn default_ids_avoid_explicit_ones() {
    let m = load(
        "x.yaml",
        "frame: 1\njoints:\n  - {type: R, bodies: [1, 2]}\n  - {id: 1-2, type: R, bodies: [2, 3]}\n",
        Format::Yaml,
    )
    .unwrap();
    // Joints are kept in natural id order; the unnamed one gets the suffix.
    let ids: Vec<(&str, usize)> = m
        .joints
        .iter()
        .map(|j| (j.id.as_str(), j.bodies[1]))
        .collect();
    let three = m.body_index(&BodyId::Int(3)).unwrap();
    let two = m.body_index(&BodyId::Int(2)).unwrap();
    assert_eq!(ids, [("1-2", three), ("1-2#2", two)]);
}

#[test]
fn string_ids_and_declared_bodies() {
    let text = r#"
frame = "ground"
space = "planar"
[[body]]
id = "ground"
label = "the frame"
[[body]]
id = "crank"
[[body]]
id = "7"
[[joint]]
type = "R"
bodies = ["ground", "crank"]
origin = [0, 0.5]
axis = [0, 0, 1]
[[joint]]
type = "R"
bodies = ["crank", 7]
"#;
    let m = load("s.toml", text, Format::Toml).unwrap();
    assert_eq!(m.bodies.len(), 3);
    assert_eq!(m.bodies[0].id, BodyId::Int(7));
    let ground = m.body_index(&BodyId::Name("ground".into())).unwrap();
    assert_eq!(m.bodies[ground].label.as_deref(), Some("the frame"));
    let pin = m.joints.iter().find(|j| j.id == "ground-crank").unwrap();
    assert_eq!(pin.geometry.origin, Some([0.0, 0.5, 0.0]));
    assert!(m.joints.iter().any(|j| j.id == "crank-7"));
}

#[test]
fn multiple_joints_and_driven_limit() {
    let ok =
        "space = \"planar\"\nframe = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2, 3]\ndriven = 2\n";
    let m = load("m.toml", ok, Format::Toml).unwrap();
    assert_eq!(m.joints[0].id, "1-2-3");
    assert_eq!(m.joints[0].driven, 2);
    let bad = ok.replace("driven = 2", "driven = 3");
    let e = load("m.toml", &bad, Format::Toml).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::DrivenOutOfRange);
    assert_eq!(e.line_col(), Some((6, 10)));
}

#[test]
fn expect_is_read() {
    let text = "frame: 1\njoints: [{type: R, bodies: [1, 2], driven: 1}]\nexpect: {mobility: 1, determined: true}\n";
    let m = load("e.yaml", text, Format::Yaml).unwrap();
    assert_eq!(m.expect.mobility, Some(1));
    assert_eq!(m.expect.determined, Some(true));
    let e = load("e.yaml", &text.replace("mobility", "mobilty"), Format::Yaml).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::UnknownKey);
    assert!(e.hint().unwrap().contains("`mobility`"));
    let e = load("e.yaml", &text.replace("true", "3"), Format::Yaml).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::WrongType);
}

/// A non-finite or null expectation is refused where it is written: dropping it would let
/// `mbsa check` pass a file that checks nothing.
#[test]
fn expect_values_must_be_written_values() {
    let cases: [(&str, String, Format); 5] = [
        ("t.toml", "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n[expect]\nmobility = nan\n".into(), Format::Toml),
        ("t.toml", "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n[expect]\nredundant = -inf\n".into(), Format::Toml),
        ("j.json", r#"{"frame": 1, "joints": [{"type": "R", "bodies": [1, 2]}], "expect": {"mobility": 1e999}}"#.into(), Format::Json),
        ("y.yaml", "frame: 1\njoints: [{type: R, bodies: [1, 2]}]\nexpect:\n  mobility: .nan\n".into(), Format::Yaml),
        ("y.yaml", "frame: 1\njoints: [{type: R, bodies: [1, 2]}]\nexpect:\n  determined: ~\n".into(), Format::Yaml),
    ];
    for (name, text, format) in cases {
        let e = load(name, &text, format).expect_err(&text);
        assert_eq!(e.kind(), ErrorKind::WrongType, "{text}");
        assert!(e.message().starts_with("`expect."), "{}", e.message());
        let (line, _) = e.line_col().expect("located");
        let key_line = text
            .lines()
            .position(|l| {
                l.contains("nan") || l.contains("inf") || l.contains("1e999") || l.contains('~')
            })
            .unwrap()
            + 1;
        assert_eq!(line, key_line, "{text}");
    }
    // An empty table is read as written, so that `check` can say it checks nothing.
    let empty = load(
        "e.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n[expect]\n",
        Format::Toml,
    )
    .unwrap();
    assert!(empty.expect.written);
    assert_eq!(empty.expect.mobility, None);
    let none = load(
        "n.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n",
        Format::Toml,
    )
    .unwrap();
    assert!(!none.expect.written);
}

#[test]
fn frameworks() {
    let text = r#"
space = "planar"
frame = "g"
[[point]]
id = "a"
at = [0, 0]
[[point]]
id = "b"
at = [1, 0]
[[point]]
id = "c"
at = [0, 1]
[[bar]]
id = "g"
points = ["a", "b"]
[[bar]]
points = ["b", "c"]
[[bar]]
points = ["c", "a"]
"#;
    let m = load("tri.toml", text, Format::Toml).unwrap();
    assert_eq!(m.bodies.len(), 3);
    let ids: Vec<&str> = m.joints.iter().map(|j| j.id.as_str()).collect();
    assert_eq!(ids, ["a", "b", "c"]);
    assert!(m.joints.iter().all(|j| j.kind == JointType::R));
    assert_eq!(m.joints[1].geometry.origin, Some([1.0, 0.0, 0.0]));
    assert_eq!(m.joint_bodies_label(&m.joints[1]), "g-b-c");
    let spatial = load(
        "tri.toml",
        &text
            .replace("planar", "spatial")
            .replace("[0, 0]", "[0, 0, 0]")
            .replace("[1, 0]", "[1, 0, 0]")
            .replace("[0, 1]", "[0, 1, 0]"),
        Format::Toml,
    )
    .unwrap();
    assert!(spatial.joints.iter().all(|j| j.kind == JointType::S));
}

#[test]
fn bundled_examples_load() {
    for name in crate::examples::names() {
        let (file, text) = crate::examples::find(name).unwrap();
        if let Err(e) = load(file, text, Format::Toml) {
            panic!("{name}: {}", crate::diagnostic::render(&e, false));
        }
    }
}

#[test]
fn bytes_entry_point() {
    let e = load_bytes("b.toml", b"frame = 1\n\xff\xfe", Format::Toml).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::NotUtf8);
    assert_eq!(e.line_col(), Some((2, 1)));
    let m = load_bytes(
        "b.yaml",
        format!("\u{FEFF}{YAML_EXAMPLE}").as_bytes(),
        Format::Yaml,
    );
    assert!(m.is_ok());
}

#[test]
fn absurd_numbers_are_clean_errors() {
    for (text, kind) in [
        (
            "frame = 99999999999999999999999\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n",
            ErrorKind::NumberOutOfRange,
        ),
        (
            "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\ndriven = 1000000000000000000000000000000\n",
            ErrorKind::DrivenOutOfRange,
        ),
        (
            "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\ndriven = -9223372036854775808\n",
            ErrorKind::DrivenOutOfRange,
        ),
        (
            "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\norigin = [1e400, 0, 0]\n",
            ErrorKind::NonFinite,
        ),
        (
            "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\norigin = [-nan, 0, 0]\n",
            ErrorKind::NonFinite,
        ),
    ] {
        match load("n.toml", text, Format::Toml) {
            Err(e) => assert_eq!(e.kind(), kind, "{text}: {e}"),
            Ok(m) => panic!("{text} loaded: {m:?}"),
        }
    }
}

#[test]
fn deep_nesting_is_refused() {
    let deep = format!("frame: 1\nx: {}{}\n", "[".repeat(200), "]".repeat(200));
    let e = load("d.yaml", &deep, Format::Yaml).unwrap_err();
    assert!(
        matches!(e.kind(), ErrorKind::TooDeep | ErrorKind::Syntax),
        "{e}"
    );
    let deep = format!("{{\"frame\": {}{}}}", "[".repeat(100), "]".repeat(100));
    let e = load("d.json", &deep, Format::Json).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::TooDeep);
    let deep = format!("frame = 1\nx = {}{}\n", "[".repeat(100), "]".repeat(100));
    let e = load("d.toml", &deep, Format::Toml).unwrap_err();
    assert!(
        matches!(e.kind(), ErrorKind::TooDeep | ErrorKind::Syntax),
        "{e}"
    );
}

#[test]
fn schema_lists_the_keys() {
    let s = schema();
    let props = s["properties"].as_object().unwrap();
    for k in [
        "name",
        "frame",
        "joint",
        "joints",
        "body",
        "expect",
        "point",
        "bar",
        "space",
        "precision",
    ] {
        assert!(props.contains_key(k), "{k}");
    }
    let text = serde_json::to_string(&s).unwrap();
    assert!(text.contains("\"revolute\""));
    assert!(text.contains("generic_dof"));
    assert!(text.contains("2020-12"));
}

/// The one-joint-at-a-time YAML reads (the list last: one read; elsewhere: two reads) give
/// what the whole-tree read gives, results and errors alike.
#[test]
fn yaml_lazy_reads_equal_the_whole_read() {
    let texts = [
        "name: y\nspace: planar\nframe: 1\njoints:\n  - {type: R, bodies: [1, 2], driven: 1}\n  - type: R\n    bodies: [2, 3]\n  - {type: R, bodies: [3, 1]}\n",
        "frame: 1\njoint:\n  - {type: R, bodies: [1, 2]}\nexpect:\n  mobility: 1\n",
        "joints:\n  - {type: R, bodies: [1, 2]}\nframe: 1\nspace: spherical\n",
        "---\nframe: 1\njoints:\n- {type: S, bodies: [1, 2], origin: [0, 0, 1]}\n...\n",
        // Errors: in a joint, after the list, an alias in a joint, two documents, both lists.
        "frame: 1\njoints:\n  - {type: Q, bodies: [1, 2]}\n",
        "frame: 1\njoints:\n  - {type: R, bodies: [1, 2]}\nspace: plnar\n",
        "space: plnar\nframe: 1\njoints:\n  - {type: R, bodies: [1, 2], x: *a}\n",
        "frame: 1\njoints:\n  - {type: R, bodies: [1, 2]}\n---\nframe: 2\n",
        "frame: 1\njoints:\n  - {type: R, bodies: [1, 2]}\njoint:\n  - {type: R, bodies: [1, 2]}\n",
        "frame: 1\njoints: []\n",
        "frame: 1\njoints:\n  - {type: R, bodies: [1, 2]\n",
    ];
    for text in texts {
        let lazy = load("t.yaml", text, Format::Yaml).map_err(|e| e.to_string());
        let whole = yaml_whole(text, "t").map_err(|e| e.with_source("t.yaml", text).to_string());
        assert_eq!(lazy, whole, "{text}");
    }
    // One read where the list comes last; a key after it sends the text to the other reads.
    let one_read: Vec<bool> = texts[..4]
        .iter()
        .map(|t| {
            read::parse_yaml_resume(t)
                .is_some_and(|(root, lazy)| model::build(root, "t", lazy).is_ok())
        })
        .collect();
    assert_eq!(one_read, [true, false, false, true]);
}

/// Integer bodies with explicit ids: the k-th default of a body list takes the k-th suffix no
/// explicit id holds (the set-free path), as with named bodies (the general path).
#[test]
fn default_ids_skip_explicit_suffixes_in_order() {
    let joints = |b: &str| {
        format!(
            "frame: 1\njoints:\n  - {{id: 1-{b}, type: R, bodies: [1, {b}]}}\n  - {{type: R, bodies: [1, {b}]}}\n  - {{id: 1-{b}#3, type: R, bodies: [1, {b}]}}\n  - {{type: R, bodies: [1, {b}]}}\n  - {{type: R, bodies: [1, {b}]}}\n  - {{id: 9-9, type: R, bodies: [{b}, 3]}}\n  - {{type: R, bodies: [3, {b}]}}\n"
        )
    };
    for (b, named) in [("2", false), ("x", true)] {
        let m = load("t.yaml", &joints(b), Format::Yaml).unwrap();
        let mut ids: Vec<String> = m.joints.iter().map(|j| j.id.clone()).collect();
        ids.sort();
        let mut expected: Vec<String> = ["1-B", "1-B#2", "1-B#3", "1-B#4", "1-B#5", "9-9", "3-B"]
            .iter()
            .map(|s| s.replace('B', b))
            .collect();
        expected.sort();
        assert_eq!(ids, expected, "named {named}");
    }
}

/// The reader's body numbering (dense integer ids as their own indices, left for the general
/// table at the first other id, possibly in the middle of a long joint) and its shortcut to
/// the natural order of default ids give the mechanism `Mechanism::from_parts` builds from
/// the same joints: random files with small, sparse, large, negative and named ids, repeated
/// pairs, multiple joints, and repeated bodies after the switch still found.
#[test]
fn body_numbering_equals_from_parts() {
    use crate::mechanism::{JointSpec, Mechanism};
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move |n: u64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state % n
    };
    let write = |b: &BodyId| match b {
        BodyId::Int(i) => i.to_string(),
        BodyId::Name(s) => format!("\"{s}\""),
    };
    for case in 0..240u64 {
        let n_joints = 1 + next(60) as usize;
        let odd = case % 6; // 0: dense, 1: sparse, 2: one large id, 3: negative, 4: names, 5: long joints
        let pick = |next: &mut dyn FnMut(u64) -> u64| -> BodyId {
            match odd {
                1 => BodyId::Int(7 * next(40) as i64 + 3),
                2 if next(30) == 0 => BodyId::Int(1_000_000_007 + next(3) as i64),
                3 if next(5) == 0 => BodyId::Int(-(next(4) as i64) - 1),
                4 if next(5) == 0 => BodyId::Name(format!("b{}", next(6))),
                5 => BodyId::Int(next(60) as i64),
                _ => BodyId::Int(next(25) as i64),
            }
        };
        let frame = if odd == 4 && case % 12 == 4 {
            BodyId::Name("b0".into())
        } else {
            BodyId::Int(0)
        };
        let mut specs: Vec<JointSpec> = Vec::new();
        for k in 0..n_joints {
            let len = if odd == 5 && next(4) == 0 {
                17 + next(20) as usize
            } else if next(8) == 0 {
                3
            } else {
                2
            };
            let mut bodies: Vec<BodyId> = if k == 0 { vec![frame.clone()] } else { vec![] };
            while bodies.len() < len {
                let b = pick(&mut next);
                if !bodies.contains(&b) {
                    bodies.push(b);
                }
            }
            specs.push(JointSpec {
                id: None,
                kind: JointType::R,
                bodies,
                driven: 0,
                geometry: Default::default(),
            });
        }
        // A repeated pair or two.
        for _ in 0..next(3) {
            let k = next(specs.len() as u64) as usize;
            specs.push(specs[k].clone());
        }
        let mut toml = format!("name = \"t\"\nframe = {}\n", write(&frame));
        let mut json = format!(
            "{{\"name\": \"t\", \"frame\": {}, \"joints\": [",
            write(&frame)
        );
        for (k, j) in specs.iter().enumerate() {
            let list: Vec<String> = j.bodies.iter().map(write).collect();
            let list = list.join(", ");
            toml.push_str(&format!("\n[[joint]]\ntype = \"R\"\nbodies = [{list}]\n"));
            let sep = if k > 0 { ", " } else { "" };
            json.push_str(&format!("{sep}{{\"type\": \"R\", \"bodies\": [{list}]}}"));
        }
        json.push_str("]}");
        let expected = Mechanism::from_parts("t", Space::Spatial, frame.clone(), vec![], specs);
        for (text, format) in [(&toml, Format::Toml), (&json, Format::Json)] {
            let m = load("t", text, format).unwrap_or_else(|e| panic!("{e:?}\n{text}"));
            assert_eq!(m, expected, "case {case} {format:?}\n{text}");
        }
        // A body repeated in a long joint, after the numbering switched: still found.
        if odd == 2 || odd == 5 {
            let list: Vec<String> = (1..=20)
                .map(|i| i.to_string())
                .chain(["1000000009".into(), "\"x\"".into(), "7".into()])
                .collect();
            let text = format!(
                "{toml}\n[[joint]]\ntype = \"R\"\nbodies = [{}]\n",
                list.join(", ")
            );
            let e = load("t", &text, Format::Toml).unwrap_err();
            assert_eq!(e.kind(), ErrorKind::RepeatedBody, "{text}");
        }
    }
}

/// Integer bodies with explicit ids: the reader's natural order (defaults merged with the
/// explicit ids when they are short numeric ids) is the order `Mechanism::from_indexed` sorts
/// the same joints into. Explicit ids that are defaults of other lists, suffixed defaults,
/// single numbers, long numeric ids (`1-2-3-4`, not packed) and names.
#[test]
fn explicit_ids_merge_into_the_natural_order() {
    use crate::mechanism::Mechanism;
    let mut rng = crate::rng::SplitMix64::new(0x2545_F491_4F6C_DD1D);
    let mut next = move |n: u64| rng.below(n);
    for case in 0..300u64 {
        let n_joints = 1 + next(50) as usize;
        let mut used = std::collections::HashSet::new();
        let mut toml = String::from("frame = 0\n");
        for k in 0..n_joints {
            let spread = if case % 3 == 0 { 40 } else { 6 };
            let a = if k == 0 { 0 } else { next(spread) };
            let mut b = next(spread);
            while b == a {
                b = next(spread);
            }
            let third = (case % 5 == 4 && next(6) == 0).then(|| next(spread) + spread);
            let id = match next(10) {
                0 => Some(format!("{a}-{b}")),
                1 => Some(format!("{}-{}#{}", next(spread), next(spread), 2 + next(3))),
                2 => Some(format!("{}", next(60))),
                3 if case % 4 == 0 => Some(format!("{}-{}-{}-{}", a, b, next(9), next(9))),
                4 if case % 7 == 0 => Some(format!("j{}", next(9))),
                5 => Some(format!("{}-{}", next(spread), next(spread))),
                _ => None,
            }
            .filter(|id| used.insert(id.clone()));
            toml.push_str("\n[[joint]]\n");
            if let Some(id) = id {
                toml.push_str(&format!("id = \"{id}\"\n"));
            }
            match third {
                Some(c) if c != a && c != b => {
                    toml.push_str(&format!("type = \"S\"\nbodies = [{a}, {b}, {c}]\n"));
                }
                _ => toml.push_str(&format!("type = \"S\"\nbodies = [{a}, {b}]\n")),
            }
        }
        let m = load("t", &toml, Format::Toml).unwrap_or_else(|e| panic!("{e:?}\n{toml}"));
        let mut joints = m.joints.clone();
        joints.reverse();
        let sorted =
            Mechanism::from_indexed(m.name.clone(), m.space, m.frame, m.bodies.clone(), joints);
        assert_eq!(m, sorted, "case {case}\n{toml}");
    }
}

/// The top-level `precision` key: read in all three formats into [`Mechanism::precision`]
/// (absent: `None`, the digits decide), rejected with its location when negative, NaN,
/// infinite or not a number.
#[test]
fn precision_key_is_read_and_checked() {
    let toml = "frame = 1\nprecision = 5e-7\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n";
    let m = load("p.toml", toml, Format::Toml).unwrap();
    assert_eq!(m.precision, Some(5e-7));
    let yaml = "frame: 1\nprecision: 0\njoints: [{type: R, bodies: [1, 2]}]\n";
    assert_eq!(
        load("p.yaml", yaml, Format::Yaml).unwrap().precision,
        Some(0.0)
    );
    let json = r#"{"frame": 1, "precision": 2.5e-5, "joints": [{"type": "R", "bodies": [1, 2]}]}"#;
    assert_eq!(
        load("p.json", json, Format::Json).unwrap().precision,
        Some(2.5e-5)
    );
    let none = toml.replace("precision = 5e-7\n", "");
    assert_eq!(load("p.toml", &none, Format::Toml).unwrap().precision, None);
    let keyed = "frame = 1\nprecision = 1e-9\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n";
    let m = load("p.toml", keyed, Format::Toml).unwrap();
    // Written back (`mbsa assemble`, `generate`) as read.
    let again = load("q.toml", &crate::generate::to_toml(&m), Format::Toml).unwrap();
    assert_eq!(again.precision, Some(1e-9));
    for (value, kind) in [
        ("-1e-6", ErrorKind::NumberOutOfRange),
        ("nan", ErrorKind::NonFinite),
        ("inf", ErrorKind::NonFinite),
        ("1e300", ErrorKind::NumberOutOfRange),
        ("\"tight\"", ErrorKind::WrongType),
    ] {
        let bad = toml.replace("5e-7", value);
        let e = load("p.toml", &bad, Format::Toml).unwrap_err();
        assert_eq!(e.kind(), kind, "{value}: {e}");
        assert_eq!(e.line_col(), Some((2, 13)), "{value}");
    }
    let e = load(
        "p.yaml",
        &yaml.replace("precision: 0", "precision: .nan"),
        Format::Yaml,
    )
    .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::NonFinite);
    assert_eq!(e.line_col(), Some((2, 12)));
    let e = load("p.json", &json.replace("2.5e-5", "-1"), Format::Json).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::NumberOutOfRange);
    // Unknown top-level keys stay errors (a typo of the new key included).
    let typo = toml.replace("precision", "precison");
    let e = load("p.toml", &typo, Format::Toml).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::UnknownKey);
}
