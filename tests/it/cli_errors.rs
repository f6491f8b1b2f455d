//! The error catalogue: malformed inputs run through the real `mbsa` binary. Each must exit
//! with code 2, print no panic, name the location (`file:line:col` where the input has one,
//! else the file or the flag) and keep a reviewed snapshot of its standard error.

use assert_cmd::Command;
use std::path::PathBuf;

/// One malformed input.
struct Case {
    /// Snapshot name (`cli_error__<name>`).
    name: &'static str,
    /// File name written in the case's directory (`None`: no file is written).
    file: Option<&'static str>,
    /// File content.
    content: &'static [u8],
    /// Arguments; `{}` stands for the file name.
    args: &'static [&'static str],
    /// Standard input, if any.
    stdin: Option<&'static [u8]>,
    /// Text that stderr must contain: the location.
    location: &'static str,
}

impl Case {
    /// A file run through `mbsa mobility FILE`.
    const fn file(
        name: &'static str,
        file: &'static str,
        content: &'static str,
        location: &'static str,
    ) -> Case {
        Case {
            name,
            file: Some(file),
            content: content.as_bytes(),
            args: &["mobility", "{}"],
            stdin: None,
            location,
        }
    }
}

/// A fresh directory for one case (file names in diagnostics stay relative and stable).
fn case_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("cli_errors")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("the target directory is writable");
    dir
}

/// Run `case`: exit code 2, no panic, the location named, stderr snapshotted.
fn run(case: &Case) {
    let dir = case_dir(case.name);
    let file = case.file.unwrap_or("missing.toml");
    if case.file.is_some() {
        std::fs::write(dir.join(file), case.content).expect("writable");
    }
    let args: Vec<&str> = case
        .args
        .iter()
        .map(|a| if *a == "{}" { file } else { a })
        .collect();
    let mut cmd = Command::cargo_bin("mbsa").expect("the binary is built");
    cmd.current_dir(&dir).args(&args).env("NO_COLOR", "1");
    if let Some(input) = case.stdin {
        cmd.write_stdin(input);
    }
    let out = cmd.output().expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}: exit code; stderr:\n{stderr}",
        case.name
    );
    assert!(out.stdout.is_empty(), "{}: nothing on stdout", case.name);
    assert!(
        !stderr.contains("panicked"),
        "{}: panic:\n{stderr}",
        case.name
    );
    assert!(
        stderr.contains(case.location),
        "{}: stderr does not name `{}`:\n{stderr}",
        case.name,
        case.location
    );
    insta::with_settings!({snapshot_path => "../../snapshots", prepend_module_to_snapshot => false}, {
        insta::assert_snapshot!(format!("cli_error__{}", case.name), stderr);
    });
}

/// Defines one test per case.
macro_rules! cases {
    ($($name:ident => $case:expr;)*) => {
        $(
            #[test]
            fn $name() {
                run(&$case);
            }
        )*
    };
}

cases! {
    // --- syntax, one or more per format
    toml_unclosed_string => Case::file("toml_unclosed_string", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\nbodies = [1, 2]\n", "bad.toml:3:");
    toml_missing_value => Case::file("toml_missing_value", "bad.toml",
        "frame =\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n", "bad.toml:1:");
    toml_duplicate_key => Case::file("toml_duplicate_key", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\ntype = \"P\"\nbodies = [1, 2]\n", "bad.toml:4:1");
    toml_duplicate_table => Case::file("toml_duplicate_table", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n[expect]\nmobility = 1\n[expect]\ninputs = 1\n", "bad.toml:7:");
    yaml_unclosed_flow => Case::file("yaml_unclosed_flow", "bad.yaml",
        "frame: 1\njoints:\n  - {type: R, bodies: [1, 2]\n  - {type: R, bodies: [2, 3]}\n", "bad.yaml:4:");
    yaml_bad_indentation => Case::file("yaml_bad_indentation", "bad.yaml",
        "frame: 1\njoints:\n  - type: R\n     bodies: [1, 2]\n", "bad.yaml:4:");
    yaml_tab_indentation => Case::file("yaml_tab_indentation", "bad.yaml",
        "frame: 1\njoints:\n\t- {type: R, bodies: [1, 2]}\n", "bad.yaml:3:2");
    yaml_alias => Case::file("yaml_alias", "bad.yaml",
        "frame: 1\njoints:\n  - &a {type: R, bodies: [1, 2]}\n  - *a\n", "bad.yaml:4:5");
    yaml_two_documents => Case::file("yaml_two_documents", "bad.yaml",
        "frame: 1\njoints:\n  - {type: R, bodies: [1, 2]}\n---\nframe: 2\n", "bad.yaml:4:1");
    yaml_duplicate_key => Case::file("yaml_duplicate_key", "bad.yaml",
        "frame: 1\nframe: 2\njoints:\n  - {type: R, bodies: [1, 2]}\n", "bad.yaml:2:1");
    json_missing_comma => Case::file("json_missing_comma", "bad.json",
        "{\n  \"frame\": 1,\n  \"joints\": [\n    {\"type\": \"R\" \"bodies\": [1, 2]}\n  ]\n}\n", "bad.json:4:18");
    json_trailing_comma => Case::file("json_trailing_comma", "bad.json",
        "{\n  \"frame\": 1,\n  \"joints\": [{\"type\": \"R\", \"bodies\": [1, 2]},]\n}\n", "bad.json:3:");
    json_unclosed => Case::file("json_unclosed", "bad.json",
        "{\n  \"frame\": 1,\n  \"joints\": [{\"type\": \"R\", \"bodies\": [1, 2]}\n", "bad.json:");
    json_duplicate_key => Case::file("json_duplicate_key", "bad.json",
        "{\"frame\": 1,\n \"frame\": 1,\n \"joints\": [{\"type\": \"R\", \"bodies\": [1, 2]}]}\n", "bad.json:2:2");
    // --- types
    frame_is_a_list => Case::file("frame_is_a_list", "bad.toml",
        "frame = [1]\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n", "bad.toml:1:9");
    bodies_is_a_string => Case::file("bodies_is_a_string", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = \"1-2\"\n", "bad.toml:4:10");
    driven_is_a_string => Case::file("driven_is_a_string", "bad.yaml",
        "frame: 1\njoints:\n  - {type: R, bodies: [1, 2], driven: yes}\n", "bad.yaml:3:");
    joints_is_a_table => Case::file("joints_is_a_table", "bad.json",
        "{\"frame\": 1, \"joints\": {\"type\": \"R\", \"bodies\": [1, 2]}}\n", "bad.json:1:");
    // --- ranges and numbers
    driven_above_grade => Case::file("driven_above_grade", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\ndriven = 2\n", "bad.toml:5:10");
    driven_negative => Case::file("driven_negative", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\ndriven = -1\n", "bad.toml:5:10");
    huge_integer_toml => Case::file("huge_integer_toml", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 123456789012345678901234567890]\n", "bad.toml:4:");
    huge_integer_json => Case::file("huge_integer_json", "bad.json",
        "{\"frame\": 1, \"joints\": [{\"type\": \"R\", \"bodies\": [1, 2], \"driven\": 99999999999999999999999}]}\n", "bad.json:1:");
    huge_float_geometry => Case::file("huge_float_geometry", "bad.json",
        "{\"frame\": 1, \"joints\": [{\"type\": \"R\", \"bodies\": [1, 2], \"axis\": [1e999, 0, 0]}]}\n", "bad.json:1:");
    nan_geometry => Case::file("nan_geometry", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\norigin = [0.0, nan, 0.0]\n", "bad.toml:5:");
    // --- references and required keys
    missing_frame => Case::file("missing_frame", "bad.toml",
        "[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n", "bad.toml:1:3");
    no_joints => Case::file("no_joints", "bad.toml", "frame = 1\nname = \"nothing\"\n", "bad.toml:1:1");
    missing_type => Case::file("missing_type", "bad.toml",
        "frame = 1\n[[joint]]\nbodies = [1, 2]\n", "bad.toml:3:1");
    unknown_joint_type => Case::file("unknown_joint_type", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"revolut\"\nbodies = [1, 2]\n", "bad.toml:3:8");
    unknown_key_typo => Case::file("unknown_key_typo", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbody = [1, 2]\n", "bad.toml:4:1");
    unknown_top_key => Case::file("unknown_top_key", "bad.yaml",
        "frame: 1\nspaces: planar\njoints:\n  - {type: R, bodies: [1, 2]}\n", "bad.yaml:2:1");
    undeclared_body => Case::file("undeclared_body", "bad.toml",
        "frame = 1\n[[body]]\nid = 1\n[[body]]\nid = 2\n[[joint]]\ntype = \"R\"\nbodies = [1, 3]\n", "bad.toml:8:");
    frame_not_in_joint => Case::file("frame_not_in_joint", "bad.toml",
        "frame = 9\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n", "bad.toml:1:9");
    invalid_space => Case::file("invalid_space", "bad.toml",
        "space = \"plane\"\nframe = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n", "bad.toml:1:9");
    // --- duplicates
    duplicate_joint_id => Case::file("duplicate_joint_id", "bad.toml",
        "frame = 1\n[[joint]]\nid = \"A\"\ntype = \"R\"\nbodies = [1, 2]\n[[joint]]\nid = \"A\"\ntype = \"R\"\nbodies = [2, 3]\n", "bad.toml:7:");
    duplicate_body_id => Case::file("duplicate_body_id", "bad.yaml",
        "frame: 1\nbodies:\n  - {id: 1}\n  - {id: 2}\n  - {id: 1}\njoints:\n  - {type: R, bodies: [1, 2]}\n", "bad.yaml:5:");
    repeated_body => Case::file("repeated_body", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 1]\n", "bad.toml:4:");
    too_few_bodies => Case::file("too_few_bodies", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1]\n", "bad.toml:4:");
    both_aliases => Case::file("both_aliases", "bad.yaml",
        "frame: 1\njoint:\n  - {type: R, bodies: [1, 2]}\njoints:\n  - {type: R, bodies: [2, 3]}\n", "bad.yaml:4:1");
    // --- geometry
    axis_wrong_length => Case::file("axis_wrong_length", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\naxis = [0.0, 1.0]\n", "bad.toml:5:8");
    zero_axis => Case::file("zero_axis", "bad.toml",
        "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\naxis = [0, 0, 0]\n", "bad.toml:5:8");
    spatial_joint_in_planar => Case::file("spatial_joint_in_planar", "bad.toml",
        "space = \"planar\"\nframe = 1\n[[joint]]\ntype = \"S\"\nbodies = [1, 2]\n", "bad.toml:4:8");
    // --- whole-file problems
    empty_file => Case::file("empty_file", "empty.toml", "", "empty.toml");
    comments_only => Case::file("comments_only", "empty.yaml", "# to do\n\n", "empty.yaml");
    binary_garbage => Case {
        name: "binary_garbage",
        file: Some("garbage.toml"),
        content: b"frame = 1\n\x00\xff\xfe\x80garbage\x01\x02",
        args: &["mobility", "{}"],
        stdin: None,
        location: "garbage.toml:2:",
    };
    deep_nesting_json => Case::file("deep_nesting_json", "deep.json",
        concat!("{\"frame\": 1, \"joints\": ",
            "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[",
            "]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]}\n"),
        "deep.json:1:");
    deep_nesting_yaml => Case::file("deep_nesting_yaml", "deep.yaml",
        concat!("frame: 1\njoints: ",
            "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[",
            "]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]\n"),
        "deep.yaml:2:");
    deep_nesting_toml => Case::file("deep_nesting_toml", "deep.toml",
        concat!("frame = 1\njoint = ",
            "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[",
            "]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]\n"),
        "deep.toml:2:");
    crlf_line_endings => Case::file("crlf_line_endings", "crlf.toml",
        "frame = 1\r\n[[joint]]\r\ntype = \"R\"\r\nbodies = [1, 2]\r\ndriven = 7\r\n", "crlf.toml:5:10");
    byte_order_mark => Case::file("byte_order_mark", "bom.toml",
        "\u{feff}frame = 1\n[[joint]]\ntype = \"Rx\"\nbodies = [1, 2]\n", "bom.toml:3:8");
    // --- files and command-line specs
    missing_file => Case {
        name: "missing_file",
        file: None,
        content: b"",
        args: &["mobility", "does-not-exist.toml"],
        stdin: None,
        location: "does-not-exist.toml",
    };
    directory_as_file => Case {
        name: "directory_as_file",
        file: None,
        content: b"",
        args: &["mobility", "."],
        stdin: None,
        location: "`.`",
    };
    unknown_example => Case {
        name: "unknown_example",
        file: None,
        content: b"",
        args: &["mobility", "@rotr"],
        stdin: None,
        location: "`rotr`",
    };
    inputs_no_match => Case {
        name: "inputs_no_match",
        file: None,
        content: b"",
        args: &["mobility", "@four-bar", "--inputs", "Z"],
        stdin: None,
        location: "--inputs",
    };
    inputs_bad_count => Case {
        name: "inputs_bad_count",
        file: None,
        content: b"",
        args: &["mobility", "@four-bar", "--inputs", "A:x"],
        stdin: None,
        location: "--inputs",
    };
    inputs_empty => Case {
        name: "inputs_empty",
        file: None,
        content: b"",
        args: &["mobility", "@four-bar", "--inputs", ","],
        stdin: None,
        location: "--inputs",
    };
    inputs_pair_no_joint => Case {
        name: "inputs_pair_no_joint",
        file: None,
        content: b"",
        args: &["mobility", "@four-bar", "--inputs", "1-3"],
        stdin: None,
        location: "--inputs",
    };
    inputs_above_grade => Case {
        name: "inputs_above_grade",
        file: None,
        content: b"",
        args: &["mobility", "@four-bar", "--inputs", "A:5"],
        stdin: None,
        location: "--inputs",
    };
    stdin_bad_yaml => Case {
        name: "stdin_bad_yaml",
        file: None,
        content: b"",
        args: &["mobility", "-"],
        stdin: Some(b"frame: 1\njoints:\n  - {type: R, bodies: [1, 2], drivn: 1}\n"),
        location: "<stdin>:3:",
    };
    stdin_wrong_declared_format => Case {
        name: "stdin_wrong_declared_format",
        file: None,
        content: b"",
        args: &["mobility", "-", "--input-format", "json"],
        stdin: Some(b"frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n"),
        location: "<stdin>:1:",
    };
    check_broken_file => Case {
        name: "check_broken_file",
        file: Some("broken.toml"),
        content: b"frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\nexpect = 3\n",
        args: &["check", "{}"],
        stdin: None,
        location: "broken.toml:5:",
    };
}
