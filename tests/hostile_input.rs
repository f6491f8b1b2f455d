//! Issue 16, hostile input and budgets: every finding, run through the real `mbsa` binary.
//! Each must exit with code 2 and a clear message, quickly and without a panic or an abort
//! (docs/reliability.md lists the findings with these tests).

use assert_cmd::Command;
use std::path::PathBuf;
use std::time::{Duration, Instant};

fn mbsa() -> Command {
    let mut c = Command::cargo_bin("mbsa").expect("the binary is built");
    c.env("NO_COLOR", "1").timeout(Duration::from_secs(60));
    c
}

fn scratch(name: &str, content: &[u8]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("hostile_input");
    std::fs::create_dir_all(&dir).expect("the target directory is writable");
    let path = dir.join(name);
    std::fs::write(&path, content).expect("writable");
    path
}

/// Run, expect exit 2, return stderr.
fn fails(args: &[&str], stdin: Option<Vec<u8>>) -> String {
    let mut c = mbsa();
    c.args(args);
    if let Some(s) = stdin {
        c.write_stdin(s);
    }
    let out = c.output().expect("runs");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "args {args:?}\nstderr:\n{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

const FOUR_BAR: &str = "space = \"planar\"\nframe = 1\n\
[[joint]]\ntype = \"R\"\nbodies = [1, 2]\ndriven = 1\n\
[[joint]]\ntype = \"R\"\nbodies = [2, 3]\n\
[[joint]]\ntype = \"R\"\nbodies = [3, 4]\n\
[[joint]]\ntype = \"R\"\nbodies = [4, 1]\n";

// ---------------------------------------------------------------------------------------------
// Budgets: reading stops at the input limit as it reads.

#[test]
fn dev_zero_stops_at_the_input_limit() {
    let start = Instant::now();
    let err = fails(
        &["mobility", "/dev/zero", "--max-input-bytes", "1000000"],
        None,
    );
    assert!(err.contains("more than 976.6 KiB (1000000 bytes)"), "{err}");
    assert!(err.contains("--max-input-bytes"), "{err}");
    assert!(start.elapsed() < Duration::from_secs(20));
}

#[test]
fn dev_zero_with_the_default_limit_costs_the_limit_only() {
    // 256 MiB of zeros: read, refused, never more (the kernel killed it at 24 GB before).
    let err = fails(&["mobility", "/dev/zero"], None);
    assert!(err.contains("input size limit of 256 MiB"), "{err}");
}

#[test]
fn standard_input_stops_at_the_input_limit() {
    let err = fails(
        &["mobility", "-", "--max-input-bytes", "100"],
        Some(vec![b'#'; 5000]),
    );
    assert!(
        err.contains("reading standard input needs more than 100 bytes"),
        "{err}"
    );
    assert!(
        err.contains("help: raise it with `--max-input-bytes N`"),
        "{err}"
    );
}

#[test]
fn a_file_over_the_limit_is_refused_from_its_size() {
    let padded = format!("{FOUR_BAR}{}\n", "#".repeat(900 - FOUR_BAR.len() - 1));
    let path = scratch("big.toml", padded.as_bytes());
    let err = fails(
        &[
            "mobility",
            path.to_str().unwrap(),
            "--max-input-bytes",
            "100",
        ],
        None,
    );
    assert!(
        err.contains("needs 900 bytes, over the input size limit of 100 bytes"),
        "{err}"
    );
    // The budget flags raise the limit.
    for raise in [["--max-input-bytes", "900"], ["--budget", "1"]] {
        mbsa()
            .args(["mobility", path.to_str().unwrap()])
            .args(raise)
            .assert()
            .success();
    }
}

#[cfg(unix)]
#[test]
fn an_endless_fifo_stops_at_the_input_limit() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("hostile_input");
    std::fs::create_dir_all(&dir).unwrap();
    let fifo = dir.join("endless.fifo");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    if !made {
        return; // no mkfifo on this system
    }
    // A writer that never ends (like `yes > fifo`), killed when the reader is done.
    let mut writer = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("yes > '{}'", fifo.display()))
        .spawn()
        .expect("sh runs");
    let err = fails(
        &[
            "mobility",
            fifo.to_str().unwrap(),
            "--max-input-bytes",
            "1000000",
        ],
        None,
    );
    let _ = writer.kill();
    let _ = writer.wait();
    assert!(err.contains("--max-input-bytes"), "{err}");
}

#[test]
fn the_library_is_read_within_the_limit_and_its_errors_are_located() {
    let four_bar = scratch("four-bar.toml", FOUR_BAR.as_bytes());
    let lib = scratch("lib.toml", b"types = [\n  \"1R3D\",\n  \"nonsense\",\n]\n");
    let err = fails(
        &[
            "analyze",
            four_bar.to_str().unwrap(),
            "--library",
            lib.to_str().unwrap(),
        ],
        None,
    );
    assert!(err.contains("line 3, column 3: `nonsense`"), "{err}");
    let err = fails(
        &[
            "analyze",
            four_bar.to_str().unwrap(),
            "--library",
            "/dev/zero",
            "--max-input-bytes",
            "1000",
        ],
        None,
    );
    assert!(
        err.contains("reading library `/dev/zero`") || err.contains("`/dev/zero`"),
        "{err}"
    );
    assert!(err.contains("--max-input-bytes"), "{err}");
}

#[test]
fn budget_flags_are_validated() {
    let err = fails(&["mobility", "@rotor", "--budget=-1"], None);
    assert!(err.contains("not a positive number"), "{err}");
}
