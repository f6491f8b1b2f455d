//! One snapshot per error kind of the mechanism reader: the rendered diagnostic (no colour),
//! so that location, label and hint are reviewed together. Plus: no input makes `load` panic.

use mbsa::format::{ErrorKind, Format, load, load_bytes};
use proptest::prelude::*;

/// Load `text` as `file` (format from the extension), expect an error of `kind`, and snapshot
/// its rendering under `name`.
fn check(name: &str, file: &str, text: &str, kind: ErrorKind) {
    let format = Format::from_path(std::path::Path::new(file)).expect("test files have extensions");
    let err = match load(file, text, format) {
        Ok(m) => panic!("{name}: expected {kind:?}, loaded {m:?}"),
        Err(e) => e,
    };
    assert_eq!(err.kind(), kind, "{name}: {err}");
    let shown = mbsa::diagnostic::render(&err, false);
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!(format!("format_error__{name}"), shown);
    });
}

const HEAD: &str = "frame = 1\n\n";

fn joint(body: &str) -> String {
    format!("{HEAD}[[joint]]\n{body}")
}

#[test]
fn syntax_toml() {
    check(
        "syntax_toml",
        "four-bar.toml",
        "frame = 1\n[[joint]]\ntype = \"R\nbodies = [1, 2]\n",
        ErrorKind::Syntax,
    );
}

#[test]
fn syntax_yaml() {
    check(
        "syntax_yaml",
        "four-bar.yaml",
        "frame: 1\njoints:\n  - {type: R, bodies: [1, 2]\n  - {type: R, bodies: [2, 3]}\n",
        ErrorKind::Syntax,
    );
}

#[test]
fn syntax_json() {
    check(
        "syntax_json",
        "four-bar.json",
        "{\n  \"frame\": 1,\n  \"joints\": [\n    {\"type\": \"R\" \"bodies\": [1, 2]}\n  ]\n}\n",
        ErrorKind::Syntax,
    );
}

#[test]
fn empty() {
    check(
        "empty",
        "four-bar.toml",
        "# nothing yet\n",
        ErrorKind::Empty,
    );
}

#[test]
fn empty_yaml() {
    check("empty_yaml", "four-bar.yaml", "\n", ErrorKind::Empty);
}

#[test]
fn not_utf8() {
    let err = load_bytes(
        "four-bar.toml",
        b"frame = 1\nname = \"caf\xe9\"\n",
        Format::Toml,
    )
    .unwrap_err();
    assert_eq!(err.kind(), ErrorKind::NotUtf8);
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!("format_error__not_utf8", mbsa::diagnostic::render(&err, false));
    });
}

#[test]
fn too_deep() {
    let text = format!(
        "{{\"frame\": 1, \"joints\": {}{}}}\n",
        "[".repeat(70),
        "]".repeat(70)
    );
    check("too_deep", "four-bar.json", &text, ErrorKind::TooDeep);
}

#[test]
fn unsupported_yaml_alias() {
    check(
        "unsupported_alias",
        "four-bar.yaml",
        "frame: 1\njoints:\n  - &a {type: R, bodies: [1, 2]}\n  - *a\n",
        ErrorKind::Unsupported,
    );
}

#[test]
fn duplicate_key() {
    check(
        "duplicate_key",
        "four-bar.yaml",
        "frame: 1\njoints:\n  - type: R\n    bodies: [1, 2]\n    type: P\n",
        ErrorKind::DuplicateKey,
    );
}

#[test]
fn unknown_key_top() {
    check(
        "unknown_key_top",
        "four-bar.toml",
        "frame = 1\nspce = \"planar\"\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n",
        ErrorKind::UnknownKey,
    );
}

#[test]
fn unknown_key_joint() {
    check(
        "unknown_key_joint",
        "four-bar.toml",
        &joint("type = \"R\"\nbodies = [1, 2]\ndrivn = 1\n"),
        ErrorKind::UnknownKey,
    );
}

#[test]
fn unknown_key_body() {
    check(
        "unknown_key_body",
        "four-bar.yaml",
        "frame: 1\nbodies:\n  - {id: 1, lable: ground}\njoints:\n  - {type: R, bodies: [1, 2]}\n",
        ErrorKind::UnknownKey,
    );
}

#[test]
fn unknown_key_expect() {
    check(
        "unknown_key_expect",
        "four-bar.toml",
        &format!(
            "{}\n[expect]\nmobilty = 1\n",
            joint("type = \"R\"\nbodies = [1, 2]\n")
        ),
        ErrorKind::UnknownKey,
    );
}

#[test]
fn missing_frame() {
    check(
        "missing_frame",
        "four-bar.toml",
        "name = \"four-bar\"\n\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n",
        ErrorKind::MissingFrame,
    );
}

#[test]
fn no_joints() {
    check(
        "no_joints",
        "four-bar.toml",
        "name = \"four-bar\"\nframe = 1\n",
        ErrorKind::NoJoints,
    );
}

#[test]
fn empty_joint_list() {
    check(
        "empty_joint_list",
        "four-bar.yaml",
        "frame: 1\njoints: []\n",
        ErrorKind::NoJoints,
    );
}

#[test]
fn missing_field() {
    check(
        "missing_field",
        "four-bar.toml",
        &joint("id = \"A\"\nbodies = [1, 2]\n"),
        ErrorKind::MissingField,
    );
}

#[test]
fn wrong_type_bodies() {
    check(
        "wrong_type_bodies",
        "four-bar.toml",
        &joint("type = \"R\"\nbodies = \"1-2\"\n"),
        ErrorKind::WrongType,
    );
}

#[test]
fn wrong_type_driven() {
    check(
        "wrong_type_driven",
        "four-bar.yaml",
        "frame: 1\njoints:\n  - {type: R, bodies: [1, 2], driven: \"1\"}\n",
        ErrorKind::WrongType,
    );
}

#[test]
fn wrong_type_expect() {
    check(
        "wrong_type_expect",
        "four-bar.toml",
        &format!(
            "{}\n[expect]\ngroups = -1\n",
            joint("type = \"R\"\nbodies = [1, 2]\n")
        ),
        ErrorKind::WrongType,
    );
}

#[test]
fn number_out_of_range() {
    check(
        "number_out_of_range",
        "four-bar.toml",
        &joint("type = \"R\"\nbodies = [1, 99999999999999999999]\n"),
        ErrorKind::NumberOutOfRange,
    );
}

#[test]
fn empty_id() {
    check(
        "empty_id",
        "four-bar.toml",
        &joint("type = \"R\"\nbodies = [1, \"\"]\n"),
        ErrorKind::EmptyId,
    );
}

#[test]
fn invalid_space() {
    check(
        "invalid_space",
        "four-bar.toml",
        "space = \"planr\"\nframe = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n",
        ErrorKind::InvalidSpace,
    );
}

#[test]
fn both_aliases() {
    check(
        "both_aliases",
        "four-bar.yaml",
        "frame: 1\njoint:\n  - {type: R, bodies: [1, 2]}\njoints:\n  - {type: R, bodies: [2, 3]}\n",
        ErrorKind::BothAliases,
    );
}

#[test]
fn unknown_joint_type() {
    check(
        "unknown_joint_type",
        "four-bar.toml",
        &joint("type = \"revolut\"\nbodies = [1, 2]\n"),
        ErrorKind::UnknownJointType,
    );
}

#[test]
fn too_few_bodies() {
    check(
        "too_few_bodies",
        "four-bar.toml",
        &joint("type = \"R\"\nbodies = [1]\n"),
        ErrorKind::TooFewBodies,
    );
}

#[test]
fn repeated_body() {
    check(
        "repeated_body",
        "four-bar.toml",
        &joint("type = \"R\"\nbodies = [1, 2, 1]\n"),
        ErrorKind::RepeatedBody,
    );
}

#[test]
fn driven_above_grade() {
    check(
        "driven_above_grade",
        "four-bar.toml",
        &joint("type = \"C\"\nbodies = [1, 2]\ndriven = 3\n"),
        ErrorKind::DrivenOutOfRange,
    );
}

#[test]
fn driven_negative() {
    check(
        "driven_negative",
        "four-bar.yaml",
        "frame: 1\njoints:\n  - {type: R, bodies: [1, 2], driven: -1}\n",
        ErrorKind::DrivenOutOfRange,
    );
}

#[test]
fn undeclared_body() {
    check(
        "undeclared_body",
        "four-bar.toml",
        "frame = \"ground\"\n\n[[body]]\nid = \"ground\"\n[[body]]\nid = \"crank\"\n\n[[joint]]\ntype = \"R\"\nbodies = [\"ground\", \"crnk\"]\n",
        ErrorKind::UndeclaredBody,
    );
}

#[test]
fn duplicate_joint_id() {
    check(
        "duplicate_joint_id",
        "four-bar.toml",
        "frame = 1\n\n[[joint]]\nid = \"A\"\ntype = \"R\"\nbodies = [1, 2]\n\n[[joint]]\nid = \"A\"\ntype = \"R\"\nbodies = [2, 3]\n",
        ErrorKind::DuplicateJointId,
    );
}

#[test]
fn duplicate_body_id() {
    check(
        "duplicate_body_id",
        "four-bar.yaml",
        "frame: 1\nbodies:\n  - {id: 1}\n  - {id: 2}\n  - {id: 1, label: again}\njoints:\n  - {type: R, bodies: [1, 2]}\n",
        ErrorKind::DuplicateBodyId,
    );
}

#[test]
fn frame_not_in_joint() {
    check(
        "frame_not_in_joint",
        "four-bar.toml",
        "frame = 0\n\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n",
        ErrorKind::FrameNotInJoint,
    );
}

#[test]
fn joint_not_valid_in_space() {
    check(
        "joint_not_valid_in_space",
        "four-bar.toml",
        "space = \"planar\"\nframe = 1\n\n[[joint]]\ntype = \"S\"\nbodies = [1, 2]\n",
        ErrorKind::JointNotValidInSpace,
    );
}

#[test]
fn geometry_length() {
    check(
        "geometry_length",
        "four-bar.toml",
        &joint("type = \"R\"\nbodies = [1, 2]\norigin = [0, 1]\n"),
        ErrorKind::GeometryLength,
    );
}

#[test]
fn zero_axis() {
    check(
        "zero_axis",
        "four-bar.toml",
        &joint("type = \"R\"\nbodies = [1, 2]\naxis = [0, 0, 0]\n"),
        ErrorKind::ZeroAxis,
    );
}

#[test]
fn non_finite() {
    check(
        "non_finite",
        "four-bar.toml",
        &joint("type = \"R\"\nbodies = [1, 2]\norigin = [0, nan, 0]\n"),
        ErrorKind::NonFinite,
    );
}

#[test]
fn mixed_framework() {
    check(
        "mixed_framework",
        "truss.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n[[bar]]\npoints = [1, 2]\n",
        ErrorKind::MixedFramework,
    );
}

const TRUSS: &str = "space = \"planar\"\nframe = \"ab\"\n\n[[point]]\nid = \"a\"\n[[point]]\nid = \"b\"\n[[point]]\nid = \"c\"\n\n[[bar]]\nid = \"ab\"\npoints = [\"a\", \"b\"]\n";

#[test]
fn unknown_point() {
    check(
        "unknown_point",
        "truss.toml",
        &format!("{TRUSS}[[bar]]\npoints = [\"b\", \"d\"]\n"),
        ErrorKind::UnknownPoint,
    );
}

#[test]
fn bar_points() {
    check(
        "bar_points",
        "truss.toml",
        &format!("{TRUSS}[[bar]]\npoints = [\"c\", \"c\"]\n"),
        ErrorKind::BarPoints,
    );
}

#[test]
fn duplicate_point_id() {
    check(
        "duplicate_point_id",
        "truss.toml",
        &format!("{TRUSS}[[point]]\nid = \"a\"\n"),
        ErrorKind::DuplicatePointId,
    );
}

fn valid_files() -> Vec<(&'static str, Format)> {
    vec![
        (
            "name = \"x\"\nspace = \"planar\"\nframe = 1\n[[body]]\nid = 1\n[[body]]\nid = 2\n[[joint]]\nid = \"A\"\ntype = \"R\"\nbodies = [1, 2]\ndriven = 1\norigin = [0, 1]\n[expect]\nmobility = 1\n",
            Format::Toml,
        ),
        (
            "frame: 1\njoints:\n  - {id: A, type: R, bodies: [1, 2], driven: 1, axis: [0, 0, 1]}\n  - {type: S, bodies: [2, 3], origin: [1, 2, 3]}\nexpect: {groups: 2}\n",
            Format::Yaml,
        ),
        (
            "{\"frame\": 1, \"joints\": [{\"type\": \"U\", \"bodies\": [1, 2], \"axis\": [1, 0, 0], \"axis2\": [0, 1, 0]}]}",
            Format::Json,
        ),
        (
            "frame = \"g\"\n[[point]]\nid = 1\nat = [0, 0, 0]\n[[point]]\nid = 2\n[[bar]]\nid = \"g\"\npoints = [1, 2]\n[[bar]]\npoints = [2, 1]\n",
            Format::Toml,
        ),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,200}", f in 0..3usize) {
        let format = [Format::Toml, Format::Yaml, Format::Json][f];
        let _ = load("any", &text, format);
        let _ = Format::sniff(&text);
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..200), f in 0..3usize) {
        let format = [Format::Toml, Format::Yaml, Format::Json][f];
        if let Err(e) = load_bytes("any", &bytes, format) {
            let _ = mbsa::diagnostic::render(&e, false);
        }
    }

    #[test]
    fn mutated_valid_files_never_panic(
        which in 0..4usize,
        edits in proptest::collection::vec((any::<prop::sample::Index>(), 0..4u8, "[\\[\\]{}:,=\"'#\\-0-9a-z \\n.]{0,3}"), 1..6),
    ) {
        let (text, format) = valid_files()[which];
        let mut s = text.to_string();
        for (at, op, ins) in edits {
            if s.is_empty() { break; }
            let mut i = at.index(s.len());
            while !s.is_char_boundary(i) { i -= 1; }
            match op {
                0 => { s.insert_str(i, &ins); }
                1 => { let j = (i + ins.len().max(1)).min(s.len()); let mut j = j; while !s.is_char_boundary(j) { j -= 1; } s.replace_range(i..j, ""); }
                2 => { let mut j = (i + 1).min(s.len()); while !s.is_char_boundary(j) { j += 1; } s.replace_range(i..j, &ins); }
                _ => { s.truncate(i); }
            }
        }
        if let Err(e) = load("mutated", &s, format) {
            let shown = mbsa::diagnostic::render(&e, false);
            prop_assert!(!shown.is_empty());
        }
    }
}
