//! Every example that a `--help` page shows runs and succeeds: the pages are read from the
//! binary (the commands found by walking each page's `Commands:` list), each `mbsa ...` line
//! under `Example:`/`Examples:` is run by the shell in a scratch folder that holds the files
//! the examples name (copies of fixtures and bundled mechanisms), and must exit 0. A pipe into
//! another program (`| dot -Tsvg`) is left out: only mbsa's part is run.

use assert_cmd::cargo::cargo_bin;
use std::path::{Path, PathBuf};
use std::process::Command;

fn help(words: &[String]) -> String {
    let out = Command::new(cargo_bin("mbsa"))
        .args(words)
        .arg("--help")
        .output()
        .expect("mbsa runs");
    assert!(out.status.success(), "{words:?} --help");
    String::from_utf8(out.stdout).expect("help is UTF-8")
}

/// The indented lines of the section that starts with one of `headings`.
fn section<'a>(page: &'a str, headings: &[&str]) -> Vec<&'a str> {
    let mut lines = page
        .lines()
        .skip_while(|l| !headings.contains(&l.trim_end()));
    lines.next();
    lines.take_while(|l| l.starts_with("  ")).collect()
}

/// Every command path (`[]`, `["analyze"]`, `["generate", "star"]`, ...) and its examples.
fn examples() -> Vec<(Vec<String>, Vec<String>)> {
    let mut todo = vec![Vec::<String>::new()];
    let mut all = Vec::new();
    while let Some(path) = todo.pop() {
        let page = help(&path);
        for line in section(&page, &["Commands:"]) {
            let name = line.split_whitespace().next().unwrap_or("");
            // A description wrapped onto the next line is indented further.
            if line.starts_with("  ") && !line.starts_with("   ") && name != "help" {
                let mut sub = path.clone();
                sub.push(name.to_string());
                todo.push(sub);
            }
        }
        let ex: Vec<String> = section(&page, &["Example:", "Examples:"])
            .into_iter()
            .map(|l| l.trim().to_string())
            .filter(|l| l.starts_with("mbsa "))
            .collect();
        all.push((path, ex));
    }
    all
}

/// The scratch folder (new): the files the examples name.
fn scratch() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("mbsa-help-examples-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    let d = dir.as_path();
    let fixture = |name: &str| root.join("tests/fixtures/import").join(name);
    let bundled = |name: &str| root.join("mechanisms").join(name);
    for (from, to) in [
        (fixture("cassie.xml"), "cassie.xml"),
        (fixture("four_bar.sdf"), "four_bar.sdf"),
        (fixture("ur5.urdf"), "model.txt"),
        (fixture("robotiq_2f85.xml"), "gripper.xml"),
        (bundled("rig-double-banana.toml"), "frame.toml"),
        (bundled("four-bar.toml"), "my-linkage.toml"),
        (bundled("slider-crank-geometry.toml"), "robot.toml"),
    ] {
        std::fs::copy(&from, d.join(to)).unwrap_or_else(|e| panic!("{}: {e}", from.display()));
    }
    std::fs::create_dir(d.join("mechanisms")).expect("mkdir");
    for e in std::fs::read_dir(root.join("mechanisms")).expect("mechanisms/") {
        let p = e.expect("entry").path();
        std::fs::copy(&p, d.join("mechanisms").join(p.file_name().expect("name"))).expect("copy");
    }
    // The YAML of docs/format.md.
    std::fs::write(
        d.join("my-robot.yaml"),
        "name: Spatial four-bar RSCP\nframe: 1\njoints:\n  - {id: A, type: R, bodies: [1, 2], driven: 1}\n  - {id: B, type: S, bodies: [2, 3]}\n  - {id: C, type: C, bodies: [3, 4]}\n  - {id: D, type: P, bodies: [1, 4]}\n",
    )
    .expect("write");
    // Poses as `mbsa solve --format json` writes them, for `assemble --poses`.
    let poses = Command::new(cargo_bin("mbsa"))
        .args(["solve", "robot.toml", "--format", "json"])
        .current_dir(d)
        .output()
        .expect("mbsa runs");
    assert!(poses.status.success());
    std::fs::write(d.join("keyframe.json"), poses.stdout).expect("write");
    dir
}

#[test]
fn every_help_example_runs() {
    let dir = scratch();
    let bin = cargo_bin("mbsa");
    let path = format!(
        "{}:{}",
        bin.parent().expect("bin dir").display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut ran = 0;
    let mut failures = Vec::new();
    for (cmd, examples) in examples() {
        for ex in examples {
            let own = ex.split(" | ").next().expect("a command");
            let out = Command::new("sh")
                .args(["-c", &format!("{own} > /dev/null")])
                .current_dir(&dir)
                .env("PATH", &path)
                .output()
                .expect("sh runs");
            ran += 1;
            if !out.status.success() {
                failures.push(format!(
                    "`mbsa {} --help`: `{ex}` exited {:?}: {}",
                    cmd.join(" "),
                    out.status.code(),
                    String::from_utf8_lossy(&out.stderr)
                ));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(ran >= 30, "only {ran} examples found");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
