//! `mbsa check --format json|jsonl` and `--files-from`: one record per file (expectations,
//! mismatches, read errors with their location), the exit codes of the text format, and
//! standard input read once at most.

use assert_cmd::Command;
use serde_json::Value;
use std::path::PathBuf;

/// Run `mbsa args...` with `stdin`: exit code, standard output, standard error.
fn run(args: &[&str], stdin: &str) -> (i32, String, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the binary is built")
        .env("NO_COLOR", "1")
        .args(args)
        .write_stdin(stdin)
        .output()
        .expect("the binary runs");
    let text = |b: Vec<u8>| String::from_utf8(b).expect("UTF-8");
    let code = out.status.code().expect("exited normally");
    (code, text(out.stdout), text(out.stderr))
}

/// Write `text` to a fresh file `name` of this module's scratch directory.
fn scratch(name: &str, text: &str) -> String {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_check");
    std::fs::create_dir_all(&dir).expect("the target directory is writable");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("writable");
    path.to_string_lossy().into_owned()
}

const WRONG: &str = "space = \"planar\"\nframe = 1\n\
[[joint]]\ntype = \"R\"\nbodies = [1, 2]\ndriven = 1\n\
[[joint]]\ntype = \"R\"\nbodies = [2, 3]\n\
[[joint]]\ntype = \"R\"\nbodies = [3, 4]\n\
[[joint]]\ntype = \"R\"\nbodies = [4, 1]\n\
[expect]\nmobility = 5\ngroups = 2\n";

#[test]
fn json_has_a_record_per_file_with_its_mismatches() {
    let wrong = scratch("wrong.toml", WRONG);
    let (code, out, _) = run(&["check", "@four-bar", &wrong, "--format", "json"], "");
    assert_eq!(code, 1, "a failed expectation exits 1");
    let v: Value = serde_json::from_str(&out).expect("one JSON document");
    assert_eq!(v["format_version"], 1);
    assert_eq!(v["ok"], false);
    assert_eq!(
        (v["checked"].as_u64(), v["failed"].as_u64()),
        (Some(2), Some(1))
    );
    assert_eq!(v["unreadable"], 0);
    let files = v["files"].as_array().expect("files");
    assert_eq!(files[0]["file"], "@four-bar");
    assert_eq!(files[0]["ok"], true);
    assert_eq!(files[0]["mismatches"].as_array().map(Vec::len), Some(0));
    assert_eq!(files[1]["ok"], false);
    let m = &files[1]["mismatches"];
    assert_eq!(m.as_array().map(Vec::len), Some(1), "{m}");
    assert_eq!(
        (&m[0]["key"], &m[0]["expected"], &m[0]["found"]),
        (&"mobility".into(), &"5".into(), &"1".into())
    );
    assert_eq!(files[1]["checks"].as_array().map(Vec::len), Some(2));
    assert!(files[1]["error"].is_null());
}

#[test]
fn jsonl_gives_read_errors_their_line_and_column() {
    let bad = scratch("bad.toml", "name = \"x\"\n[bodies\n");
    let (code, out, err) = run(&["check", &bad, "@rotor", "--format", "jsonl"], "");
    assert_eq!(code, 2, "an unreadable file exits 2");
    assert!(
        err.contains("unclosed table"),
        "the diagnostic stays on stderr: {err}"
    );
    let lines: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    assert_eq!(lines.len(), 2);
    assert!(lines.iter().all(|l| l["format_version"] == 1));
    let e = &lines[0]["error"];
    assert_eq!(
        (e["file"].as_str(), e["line"].as_u64(), e["col"].as_u64()),
        (Some(bad.as_str()), Some(2), Some(8))
    );
    assert!(
        e["message"]
            .as_str()
            .is_some_and(|m| m.contains("unclosed table")),
        "{e}"
    );
    assert_eq!(lines[0]["ok"], false);
    assert_eq!(lines[1]["ok"], true);
    // A file that cannot be opened has no location.
    let (code, out, _) = run(&["check", "/nonexistent/x.toml", "--format", "jsonl"], "");
    assert_eq!(code, 2);
    let v: Value = serde_json::from_str(out.trim()).expect("a JSON line");
    assert!(v["error"]["line"].is_null());
    assert!(
        v["error"]["message"]
            .as_str()
            .is_some_and(|m| m.starts_with("cannot read")),
        "{v}"
    );
}

#[test]
fn files_from_reads_a_list_from_a_file_or_standard_input() {
    let list = scratch("list.txt", "@four-bar\n\n@rotor\r\n");
    let (code, out, _) = run(&["check", "--files-from", &list], "");
    assert_eq!(code, 0);
    assert_eq!(out.lines().count(), 2, "{out}");
    assert!(
        out.starts_with("ok      @four-bar:") && out.contains("ok      @rotor:"),
        "{out}"
    );
    let (code, piped, _) = run(&["check", "--files-from", "-"], "@four-bar\n@rotor\n");
    assert_eq!((code, piped), (0, out));
    let (code, _, err) = run(&["check", "--files-from", "-"], "\n\n");
    assert_eq!(code, 2, "an empty list checks nothing: {err}");
}

#[test]
fn standard_input_given_twice_is_refused() {
    let four_bar = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/mechanisms/four-bar.toml"
    ))
    .expect("bundled file");
    assert_eq!(run(&["check", "-"], &four_bar).0, 0);
    for args in [
        &["check", "-", "-"][..],
        &["check", "--files-from", "-", "-"],
    ] {
        let (code, out, err) = run(args, &four_bar);
        assert_eq!(code, 2, "{args:?}");
        assert!(
            out.is_empty() && err.contains("more than once"),
            "{args:?}: {err}"
        );
    }
    let (code, _, err) = run(&["check", "--files-from", "-"], "-\n-\n");
    assert_eq!(code, 2);
    assert!(err.contains("more than once"), "{err}");
}

/// A CI gate that checks nothing must say so: non-finite `[expect]` values are refused at
/// their location in every format (they were dropped, and `check` said "valid (no [expect]
/// table)", exit 0), and an empty table is called empty.
#[test]
fn non_finite_and_empty_expect_tables_are_not_a_silent_pass() {
    let body = "space = \"planar\"\nframe = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n\
                driven = 1\n";
    let toml = scratch("nan.toml", &format!("{body}[expect]\nmobility = nan\n"));
    let json = scratch(
        "inf.json",
        "{\"space\": \"planar\", \"frame\": 1, \"joint\": [{\"type\": \"R\", \"bodies\": [1, 2], \
         \"driven\": 1}], \"expect\": {\"mobility\": 1e999}}",
    );
    let yaml = scratch(
        "nan.yaml",
        "space: planar\nframe: 1\njoint:\n  - type: R\n    bodies: [1, 2]\n    driven: 1\n\
         expect:\n  mobility: .nan\n",
    );
    for f in [&toml, &json, &yaml] {
        let (code, out, err) = run(&["check", f], "");
        assert_eq!(code, 2, "{f}: {out}{err}");
        assert!(err.contains("is not a finite number"), "{f}: {err}");
        assert!(err.contains(&format!("{f}:")), "{f}: located: {err}");
    }
    let empty = scratch("empty.toml", &format!("{body}[expect]\n"));
    let (code, out, err) = run(&["check", &empty], "");
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("valid (empty [expect] table: nothing checked)"),
        "{out}"
    );
}
