//! Large and hostile inputs through the real binary: analysed or refused cleanly (exit 2, a
//! short message with the location), never a crash. docs/reliability.md has the measurements;
//! the 10^6-joint run is `cargo test --release --test it -- --ignored reliability_large::`.

use assert_cmd::Command;
use std::path::PathBuf;

/// Write `bytes` to `name` in this test binary's scratch directory.
fn scratch(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("reliability_large");
    std::fs::create_dir_all(&dir).expect("the target directory is writable");
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("writable");
    path
}

/// Run `mbsa args... file`: (exit code, stdout, stderr), with no panic allowed.
fn run(args: &[&str], file: &PathBuf) -> (i32, String, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the binary is built")
        .args(args)
        .arg(file)
        .env("NO_COLOR", "1")
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    let code = out
        .status
        .code()
        .expect("exited normally, not killed by a signal");
    (
        code,
        String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr,
    )
}

/// A refusal: exit 2, a short message naming `location`.
fn refused(args: &[&str], file: &PathBuf, location: &str) {
    let (code, stdout, stderr) = run(args, file);
    assert_eq!(code, 2, "{args:?} {}: {stderr}", file.display());
    assert!(stdout.is_empty());
    assert!(stderr.contains(location), "`{location}` not in:\n{stderr}");
    assert!(
        stderr.len() < 4000,
        "a short message, not the input: {} bytes",
        stderr.len()
    );
}

/// About 10^5 joints (40 000 bodies): counted, decomposed by counting and pebble-counted.
#[test]
fn a_hundred_thousand_joints_are_analysed() {
    let (m, _) = mbsa::generate::random(40_000, false, 1).expect("a valid size");
    assert!(m.joints.len() > 100_000, "{} joints", m.joints.len());
    let file = scratch("big.toml", mbsa::generate::to_toml(&m).as_bytes());
    let (code, stdout, _) = run(&["mobility", "--format", "json"], &file);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    assert_eq!(v["joints"], m.joints.len());
    assert_eq!(v["mobility"]["verdict"], "equal");
    let (code, stdout, _) = run(&["analyze", "--format", "json", "--count-only"], &file);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    assert_eq!(v["status"], "determined");
    let (code, _, _) = run(
        &["rigid", "--method", "counting", "--format", "json"],
        &file,
    );
    assert_eq!(code, 0);
}

/// 10^6 joints. Release build: ~6 s and 2.5 GB max RSS to count (docs/reliability.md).
#[test]
#[ignore = "slow: about 10^6 joints; run with --release"]
fn a_million_joints_are_counted() {
    let (m, _) = mbsa::generate::random(392_000, false, 1).expect("a valid size");
    assert!(m.joints.len() >= 1_000_000);
    let file = scratch("huge.toml", mbsa::generate::to_toml(&m).as_bytes());
    let (code, _, _) = run(&["mobility", "--format", "json"], &file);
    assert_eq!(code, 0);
    let (code, _, _) = run(&["analyze", "--count-only", "--format", "json"], &file);
    assert_eq!(code, 0);
}

#[test]
fn deep_nesting_is_refused_in_every_format() {
    let n = 100_000;
    let (open, close) = ("[".repeat(n), "]".repeat(n));
    let json = scratch(
        "deep.json",
        format!("{{\"frame\": 1, \"joints\": {open}{close}}}").as_bytes(),
    );
    refused(&["mobility"], &json, "deep.json:1:");
    let yaml = scratch(
        "deep.yaml",
        format!("frame: 1\njoints: {open}{close}\n").as_bytes(),
    );
    refused(&["mobility"], &yaml, "deep.yaml:2:");
    let toml = scratch(
        "deep.toml",
        format!("frame = 1\njoint = {open}{close}\n").as_bytes(),
    );
    refused(&["mobility"], &toml, "deep.toml:2:");
    let tables = "{a = ".repeat(n) + "1" + &"}".repeat(n);
    let inline = scratch(
        "inline.toml",
        format!("frame = 1\njoint = {tables}\n").as_bytes(),
    );
    refused(&["mobility"], &inline, "inline.toml:2:");
    let mut block = String::from("frame: 1\njoints:\n");
    for i in 0..2_000 {
        block.push_str(&" ".repeat(i));
        block.push_str("-\n");
    }
    let block = scratch("block.yaml", block.as_bytes());
    refused(&["mobility"], &block, "block.yaml:");
}

/// Regression: an error far along a long line (minified JSON) made miette panic (a format
/// width past 65535) and would have printed the whole line.
#[test]
fn an_error_on_a_long_line_is_reported_briefly() {
    let joints: Vec<String> = (1..20_000)
        .map(|i| format!("{{\"type\": \"R\", \"bodies\": [{i}, {}]}}", i + 1))
        .collect();
    let text = format!(
        "{{\"frame\": 1, \"joints\": [{}, {{\"type\": \"Q\", \"bodies\": [1, 2]}}]}}",
        joints.join(", ")
    );
    let file = scratch("minified.json", text.as_bytes());
    let col = text.find("\"Q\"").expect("present") + 1;
    refused(&["mobility"], &file, &format!("minified.json:1:{col}"));
    // Near the start of the long line too.
    let file = scratch(
        "minified2.json",
        text.replacen("\"frame\"", "\"frme\"", 1).as_bytes(),
    );
    refused(&["mobility"], &file, "minified2.json:1:2");
}

#[test]
fn a_huge_string_is_loaded_or_refused_briefly() {
    let text = format!(
        "frame = 1\nname = \"{}\"\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\nlabel = 1\n",
        "x".repeat(5_000_000)
    );
    let file = scratch("long-name.toml", text.as_bytes());
    refused(&["mobility"], &file, "long-name.toml:6:1");
}

#[test]
fn many_keys_and_yaml_alias_bombs_are_refused() {
    // A billion-laughs document: aliases are refused before anything expands.
    let mut bomb = String::from("a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n");
    for i in 1..10 {
        let refs = vec![format!("*a{}", i - 1); 10].join(", ");
        bomb.push_str(&format!("a{i}: &a{i} [{refs}]\n"));
    }
    bomb.push_str("frame: 1\njoints: *a9\n");
    let file = scratch("bomb.yaml", bomb.as_bytes());
    refused(&["mobility"], &file, "bomb.yaml:2:");
    // 10^5 unknown keys: the first one is reported.
    let keys: String = (0..100_000).map(|i| format!("k{i} = {i}\n")).collect();
    let file = scratch("keys.toml", format!("frame = 1\n{keys}").as_bytes());
    refused(&["mobility"], &file, "keys.toml:2:1");
}
