//! Exit codes (0 success, 1 a check failed, 2 usage or input error) and quiet ends on a
//! closed standard output (`mbsa examples | head -1`).

use assert_cmd::Command;
use std::io::Read;
use std::path::PathBuf;
use std::process::Stdio;

fn mbsa() -> Command {
    let mut cmd = Command::cargo_bin("mbsa").expect("the binary is built");
    cmd.env("NO_COLOR", "1");
    cmd
}

/// Write `text` to a fresh file `name` of this test binary's scratch directory.
fn scratch(name: &str, text: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_exit_codes");
    std::fs::create_dir_all(&dir).expect("the target directory is writable");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("writable");
    path
}

/// The exit code of `mbsa args...`, with its stderr checked for panics.
fn code(args: &[&str]) -> i32 {
    let out = mbsa().args(args).output().expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    out.status.code().expect("exited normally")
}

const FOUR_BAR: &str = "space = \"planar\"\nframe = 1\n\
[[joint]]\nid = \"A\"\ntype = \"R\"\nbodies = [1, 2]\ndriven = 1\n\
[[joint]]\ntype = \"R\"\nbodies = [2, 3]\n\
[[joint]]\ntype = \"R\"\nbodies = [3, 4]\n\
[[joint]]\ntype = \"R\"\nbodies = [4, 1]\n";

#[test]
fn success_is_0() {
    for args in [
        &["--help"][..],
        &["--version"],
        &["help"],
        &["mobility", "--help"],
        &["examples"],
        &["joints"],
        &["schema"],
        &["mobility", "@rotor"],
        &["mobility", "--format", "json", "@four-bar"],
        &["check", "@all"],
    ] {
        assert_eq!(code(args), 0, "{args:?}");
    }
}

#[test]
fn analyses_succeed_with_0() {
    for args in [
        &["analyze", "@four-bar"][..],
        &["analyze", "--format", "json", "@rotor"],
        &["dot", "@four-bar"],
        &["rigid", "@rig-bennett"],
        &["transform", "@four-bar"],
        &["generate", "random", "--help"],
    ] {
        assert_eq!(code(args), 0, "{args:?}");
    }
}

#[test]
fn a_failed_expectation_is_1() {
    let wrong = scratch(
        "wrong.toml",
        &format!("{FOUR_BAR}\n[expect]\nmobility = 2\n"),
    );
    let right = scratch(
        "right.toml",
        &format!("{FOUR_BAR}\n[expect]\nmobility = 1\n"),
    );
    let out = mbsa().arg("check").arg(&wrong).output().expect("runs");
    assert_eq!(out.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("MISMATCH") && stdout.contains("expected 2, got 1"),
        "{stdout}"
    );
    assert!(out.stderr.is_empty(), "a failed check is not an error");
    // A right file beside it does not hide the failure.
    let out = mbsa()
        .arg("check")
        .arg(&right)
        .arg(&wrong)
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        mbsa()
            .arg("check")
            .arg(&right)
            .output()
            .expect("runs")
            .status
            .code(),
        Some(0)
    );
}

#[test]
fn an_unreadable_file_beats_a_failed_check() {
    // Input errors (2) take precedence over failed expectations (1).
    let wrong = scratch(
        "wrong2.toml",
        &format!("{FOUR_BAR}\n[expect]\nmobility = 2\n"),
    );
    let out = mbsa()
        .arg("check")
        .arg(&wrong)
        .arg("no-such-file.toml")
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn usage_errors_are_2() {
    for args in [
        &["--bogus"][..],
        &[],
        &["frobnicate"],
        &["mobility"],
        &["mobility", "@rotor", "--format", "xml"],
        &["mobility", "@rotor", "extra"],
        &["check"],
        &["mobility", "@rotor", "--input-format", "ini"],
        &["mobility", "@nope"],
        &["analyze", "@rotor", "--method", "magic"],
        &["analyze", "@rotor", "--seed", "-1"],
        &["rigid", "@rotor", "--geometry", "maybe"],
        &["dot", "@rotor", "--view", "side"],
    ] {
        assert_eq!(code(args), 2, "{args:?}");
    }
}

/// Run `args`, read `keep` bytes of stdout and close the pipe: the program must end without
/// a panic message (Rust ignores SIGPIPE, so writes fail with EPIPE instead).
fn closed_pipe(args: &[&str], keep: usize) {
    let bin = assert_cmd::cargo::cargo_bin("mbsa");
    let mut child = std::process::Command::new(bin)
        .args(args)
        .env("NO_COLOR", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let mut stdout = child.stdout.take().expect("piped");
    let mut buf = vec![0u8; keep];
    stdout.read_exact(&mut buf).expect("some output");
    drop(stdout);
    let out = child.wait_with_output().expect("the binary ends");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.is_empty(),
        "{args:?}: stderr after a closed pipe:\n{stderr}"
    );
    assert!(
        matches!(out.status.code(), Some(0)),
        "{args:?}: exit {:?}",
        out.status
    );
}

#[test]
fn a_closed_pipe_ends_quietly() {
    closed_pipe(&["examples"], 1);
    closed_pipe(&["mobility", "--format", "json", "@rotor"], 10);
    closed_pipe(&["joints"], 10);
    closed_pipe(&["schema"], 10);
    closed_pipe(&["check", "@all"], 10);
    closed_pipe(&["analyze", "@rotor"], 10);
    closed_pipe(&["dot", "@rotor"], 10);
    closed_pipe(&["rigid", "@rig-bennett"], 10);
    closed_pipe(&["transform", "@four-bar"], 10);
}

/// Run `args` with a standard output whose reading end is already closed: the very first
/// write fails (EPIPE), deterministically, whatever the output size.
fn pipe_closed_from_the_start(args: &[&str]) {
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    let out = std::process::Command::new(assert_cmd::cargo::cargo_bin("mbsa"))
        .args(args)
        .env("NO_COLOR", "1")
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.is_empty(),
        "{args:?}: stderr after a closed pipe:\n{stderr}"
    );
    assert_eq!(out.status.code(), Some(0), "{args:?}");
}

#[test]
fn a_pipe_closed_before_the_first_write_ends_quietly() {
    for args in [
        &["examples"][..],
        &["joints"],
        &["schema"],
        &["mobility", "@rotor"],
        &["mobility", "--format", "json", "@rotor"],
        &["check", "@four-bar"],
        &["analyze", "@rotor"],
        &["analyze", "--format", "json", "@rotor"],
        &["dot", "@rotor"],
        &["rigid", "@rig-bennett"],
        &["transform", "@four-bar"],
        &["generate", "random", "--bodies", "50"],
        &["--help"],
    ] {
        pipe_closed_from_the_start(args);
    }
}

#[test]
fn a_pipe_closed_mid_stream_ends_quietly() {
    // Larger than a pipe buffer (64 KiB), so the writer meets the closed pipe mid-way.
    closed_pipe(
        &["generate", "random", "--bodies", "20000", "--seed", "3"],
        100,
    );
}

/// Regression: miette panicked on a label past column 65,535 (minified JSON keeps a whole
/// file on one line). The message must keep its location and the program must not panic.
#[test]
fn an_error_far_along_one_long_line_is_located_without_a_panic() {
    let joints: Vec<String> = (2..3000)
        .map(|i| format!("{{\"type\":\"R\",\"bodies\":[{},{i}]}}", i - 1))
        .collect();
    let text = format!(
        "{{\"frame\":1,\"joints\":[{},{{\"type\":\"R\",\"bodies\":[1,2],\"drivn\":1}}]}}",
        joints.join(",")
    );
    assert!(text.len() > 70_000);
    let path = scratch("minified.json", &text);
    let p = path.to_string_lossy().into_owned();
    let out = mbsa()
        .args(["mobility", &p])
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("minified.json:1:"), "{stderr}");
    assert!(stderr.contains("drivn"), "{stderr}");
}

#[test]
fn version_names_the_commit_of_a_git_checkout() {
    let out = mbsa().arg("--version").output().expect("runs");
    let text = String::from_utf8(out.stdout).expect("UTF-8");
    let version = concat!("mbsa ", env!("CARGO_PKG_VERSION"));
    let rest = text
        .strip_prefix(version)
        .unwrap_or_else(|| panic!("{text:?} starts with {version:?}"));
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match (
        git(&["rev-parse", "--short", "HEAD"]),
        git(&["log", "-1", "--format=%cs"]),
    ) {
        (Some(commit), Some(date)) => assert_eq!(rest, format!(" ({commit} {date})\n")),
        // Not a checkout (a packaged crate) or no git: the version alone.
        _ => assert_eq!(rest, "\n"),
    }
}
