//! Hostile input and budgets: every finding, run through the real `mbsa` binary.
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
    let err = fails(
        &["mobility", "/dev/zero", "--max-input-bytes", "1000000"],
        None,
    );
    assert!(err.contains("more than 976.6 KiB (1000000 bytes)"), "{err}");
    assert!(err.contains("--max-input-bytes"), "{err}");
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

// ---------------------------------------------------------------------------------------------
// Counts from the user: checked arithmetic.

#[test]
fn inputs_counts_do_not_wrap() {
    let path = scratch("four-bar-inputs.toml", FOUR_BAR.as_bytes());
    let p = path.to_str().unwrap();
    // 4294967295 + 2 wrapped a u32 to 1 and was accepted as one driven DOF.
    let err = fails(&["mobility", p, "--inputs", "1-2:4294967295,1-2:2"], None);
    assert!(
        err.contains("would have 4294967297 driven DOF but allows at most 1"),
        "{err}"
    );
    let err = fails(&["analyze", p, "--inputs", "1-2:4294967296"], None);
    assert!(err.contains("not a non-negative whole number"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Unique joint ids after defaulting.

#[test]
fn default_ids_that_collide_are_an_error_naming_both_joints() {
    let text = "space = \"planar\"\nframe = 1\n\
        [[joint]]\ntype = \"R\"\nbodies = [1, 2]\ndriven = 1\n\
        [[joint]]\ntype = \"R\"\nbodies = [1, 2]\n\
        [[joint]]\ntype = \"R\"\nbodies = [1, \"2#2\"]\n";
    let path = scratch("default-ids.toml", text.as_bytes());
    let err = fails(&["mobility", path.to_str().unwrap()], None);
    assert!(
        err.contains(
            "two joints get the default id `1-2#2`: joint 2 (bodies 1-2) and joint 3 (bodies 1-2#2)"
        ),
        "{err}"
    );
    assert!(err.contains("default-ids.toml:"), "{err}");
    // The library call that builds mechanisms in code keeps ids unique instead.
    use mbsa::mechanism::{BodyId, JointSpec, Mechanism, Space};
    let mut odd = JointSpec::new(mbsa::JointType::R, 1, 2, 0);
    odd.bodies[1] = BodyId::Name("2#2".into());
    let m = Mechanism::from_parts(
        "t",
        Space::Planar,
        BodyId::Int(1),
        vec![],
        vec![
            JointSpec::new(mbsa::JointType::R, 1, 2, 1),
            JointSpec::new(mbsa::JointType::R, 1, 2, 0),
            odd,
        ],
    );
    let mut ids: Vec<&str> = m.joints.iter().map(|j| j.id.as_str()).collect();
    ids.sort_unstable();
    assert_eq!(ids, ["1-2", "1-2#2", "1-2#3"]);
}

// ---------------------------------------------------------------------------------------------
// Linear duplicate-key check.

#[test]
fn many_keys_are_checked_in_linear_time() {
    // 300,000 keys in one object: quadratic before (past 60 s), now well under a second in a
    // release build; the bound here is loose for debug builds on a loaded machine.
    let mut text = String::from(
        "{\"frame\": 1, \"joint\": [{\"type\": \"R\", \"bodies\": [1, 2], \"driven\": 1}], \"expect\": {",
    );
    for i in 0..300_000 {
        if i > 0 {
            text.push(',');
        }
        text.push_str(&format!("\"k{i}\": {i}"));
    }
    text.push_str("}}");
    let path = scratch("many-keys.json", text.as_bytes());
    let start = Instant::now();
    let err = fails(&["mobility", path.to_str().unwrap()], None);
    eprintln!("300,000 keys checked in {:?}", start.elapsed());
    assert!(err.contains("k0"), "{err}");
    // A duplicate far into a large object is still found, with both places.
    let dup = text.replacen("\"k299999\"", "\"k7\"", 1);
    let path = scratch("many-keys-dup.json", dup.as_bytes());
    let err = fails(&["mobility", path.to_str().unwrap()], None);
    assert!(err.contains("k7"), "{err}");
    assert!(
        err.to_lowercase().contains("duplicate") || err.contains("twice"),
        "{err}"
    );
}

// ---------------------------------------------------------------------------------------------
// Finite-but-huge geometry numbers.

#[test]
fn huge_geometry_numbers_are_rejected_with_a_location() {
    let text = "frame = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\ndriven = 1\norigin = [0, 0, 0]\naxis = [1e308, 1e308, 1e308]\n";
    let path = scratch("huge-axis.toml", text.as_bytes());
    for cmd in ["mobility", "rigid"] {
        let err = fails(&[cmd, path.to_str().unwrap()], None);
        assert!(err.contains("huge-axis.toml:7:"), "{err}");
        assert!(err.contains("at most 1e100 in magnitude"), "{err}");
    }
}

// ---------------------------------------------------------------------------------------------
// Error snippets stay short.

#[test]
fn an_error_inside_a_long_value_shows_a_few_lines() {
    let mut text = String::from(
        "space = \"planar\"\nframe = 1\n[[joint]]\ntype = \"R\"\nbodies = [1, 2]\ndriven = 1\norigin = [\n",
    );
    for i in 0..200_000 {
        text.push_str(&format!("  {i},\n"));
    }
    text.push_str("]\n");
    let path = scratch("long-value.toml", text.as_bytes());
    let err = fails(&["mobility", path.to_str().unwrap()], None);
    assert!(
        err.contains("must have 2 or 3 coordinates, not 200000"),
        "{err}"
    );
    // It echoed all 200,000 lines (5.7 MB) before.
    assert!(err.lines().count() < 20, "{err}");
}

// ---------------------------------------------------------------------------------------------
// Counts too large to hold are said in words.

#[test]
fn a_saturated_expansion_count_is_said_in_words() {
    // One S joint shared by 22 bodies: 22^20 binary expansions (Prüfer trees), more than 2^64.
    let mut text = String::from("frame = 1\n[[joint]]\ntype = \"S\"\nbodies = [1");
    for b in 2..=22 {
        text.push_str(&format!(", {b}"));
    }
    text.push_str("]\n");
    let path = scratch("shared-s.toml", text.as_bytes());
    let out = mbsa()
        .args([
            "transform",
            path.to_str().unwrap(),
            "--limit",
            "1",
            "--max-expansions",
            "1",
        ])
        .output()
        .expect("runs");
    let all = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!all.contains("18446744073709551615"), "{all}");
    if all.contains("binary expansions") {
        assert!(all.contains("more than 10^19"), "{all}");
    }
    assert_eq!(mbsa::budget::count_in_words(u64::MAX), "more than 10^19");
}

// ---------------------------------------------------------------------------------------------
// `generate` refuses what it cannot produce within the budget.

#[test]
fn generate_refuses_sizes_over_the_memory_budget() {
    for args in [
        &["generate", "assur", "--class", "3", "--groups", "10000000"][..],
        &["generate", "random", "--bodies", "10000000"][..],
        &["generate", "stewart", "--stages", "1000000"][..],
    ] {
        let err = fails(args, None);
        assert!(
            err.contains("over the memory limit of 4 GiB"),
            "{args:?}: {err}"
        );
        assert!(err.contains("--max-memory"), "{err}");
    }
    // Within the budget it still generates.
    mbsa()
        .args(["generate", "assur", "--class", "1", "--groups", "3"])
        .assert()
        .success();
}
