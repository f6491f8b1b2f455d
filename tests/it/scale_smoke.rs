//! CI-sized scale smoke test: every command on a generated 10^5-body
//! mechanism under a memory cap (`ulimit -v`) and a time cap. A command must answer (exit 0
//! or exit 1) or stop with a clear message (exit 2); a timeout, a signal (failed allocation,
//! abort) or a panic fails the test.
//!
//! Release only (`.ci/run`): `cargo test --release --test it -- --ignored scale_smoke::`.

use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

/// Virtual memory cap in KiB (`ulimit -v`).
const MEMORY_KIB: u64 = 4_000_000;
/// Time cap per command: catches hangs, with room for a 2-core machine shared with other
/// builds (the slowest command, `analyze` on random spatial, took 85 s there; 6 s when quiet).
const SECONDS: u64 = 240;

const COMMANDS: &[&[&str]] = &[
    &["mobility"],
    &["check"],
    &["analyze"],
    &["analyze", "--count-only"],
    &["analyze", "--format", "json"],
    &["rigid", "--method", "counting"],
    &["dot"],
    &["dot", "--view", "topology"],
    // `rigid` alone runs both methods, each already run above.
    &["rigid", "--method", "geometric"],
    &["dot", "--view", "structure"],
    &["dot", "--view", "rigid"],
    &["transform", "--limit", "1", "--format", "jsonl"],
];

fn bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_mbsa"))
}

fn sh_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

/// Run `mbsa args` under the caps; returns (exit code or None when killed, seconds, stderr tail).
fn capped(args: &[String]) -> (Option<i32>, f64, String) {
    let cmd = format!(
        "ulimit -v {MEMORY_KIB}; exec timeout -s KILL {SECONDS} {} {} > /dev/null",
        sh_quote(bin().to_str().expect("UTF-8 path")),
        args.iter()
            .map(|a| sh_quote(a))
            .collect::<Vec<_>>()
            .join(" ")
    );
    let start = Instant::now();
    let out = Command::new("sh")
        .arg("-c")
        .arg(cmd)
        .env("NO_COLOR", "1")
        .output()
        .expect("sh runs");
    let secs = start.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&out.stderr);
    let tail: String = err
        .chars()
        .rev()
        .take(400)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    (out.status.code(), secs, tail)
}

fn generated(name: &str, args: &[&str]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scale_smoke");
    std::fs::create_dir_all(&dir).expect("writable");
    let path = dir.join(name);
    if !path.exists() {
        let out = Command::new(bin())
            .arg("generate")
            .args(args)
            .output()
            .expect("generate runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::write(&path, out.stdout).expect("writable");
    }
    path
}

#[test]
#[ignore = "release only: cargo test --release --test it -- --ignored scale_smoke::"]
fn every_command_on_a_hundred_thousand_bodies() {
    let files = [
        generated(
            "random-spatial-1e5.toml",
            &["random", "--bodies", "100000", "--seed", "1"],
        ),
        generated(
            "assur-planar-1e5.toml",
            &["assur", "--class", "1", "--groups", "25000"],
        ),
    ];
    let mut failures = Vec::new();
    for file in &files {
        for args in COMMANDS {
            let mut full: Vec<String> = args.iter().map(|s| s.to_string()).collect();
            full.insert(1, file.to_str().expect("UTF-8").to_string());
            let (code, secs, tail) = capped(&full);
            eprintln!(
                "{:<50} exit {code:?} in {secs:.1} s",
                format!(
                    "{} {}",
                    args.join(" "),
                    file.file_name().unwrap().to_string_lossy()
                )
            );
            let ok = matches!(code, Some(0..=2)) && !tail.contains("panicked");
            if !ok {
                failures.push(format!("{full:?}: exit {code:?} after {secs:.1} s\n{tail}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
