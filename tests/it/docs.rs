//! The command examples of the documentation are run and their output checked.
//!
//! Every ```console block of README.md and docs/*.md is a transcript (trycmd): each `$ mbsa ...`
//! line is run with this crate's binary from the repository root (so `mechanisms/...`, `@rotor`
//! and `tests/fixtures/...` resolve), and its output, standard output and error together, must
//! match the lines below it. `...` alone on a line skips lines, `[..]` skips within a line, a
//! `? 2` or `? failed` line after the command states the exit code (success otherwise), and an
//! output that ends with a newline is followed by a blank line before the next `$` or the
//! closing fence. Blocks shown but not run use another fence (```sh, ```text).
//! `TRYCMD=overwrite cargo test --test it docs::` rewrites the expected outputs from the binary
//! (check the diff: it may also rewrite lines around a `...`).

#[test]
fn console_blocks_of_readme_and_docs() {
    trycmd::TestCases::new()
        .register_bin("mbsa", trycmd::cargo::cargo_bin!("mbsa"))
        .case("README.md")
        .case("docs/*.md");
}

/// The ```bash-recipe blocks of docs/*.md (shell recipes: loops, redirections, GNU
/// parallel) run with bash in a scratch directory, `mbsa` on the PATH: the output of their
/// `$` lines must be the lines shown. A block that calls `parallel` is skipped where GNU
/// parallel is not installed.
#[test]
fn bash_recipe_blocks_of_docs() {
    let bin = std::path::PathBuf::from(trycmd::cargo::cargo_bin!("mbsa"));
    let path = format!(
        "{}:{}",
        bin.parent()
            .expect("the binary is in a directory")
            .display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let has_parallel = std::process::Command::new("parallel")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    let mut ran = 0;
    for entry in std::fs::read_dir("docs").expect("docs/ is readable") {
        let file = entry.expect("readable").path();
        if file.extension().is_none_or(|e| e != "md") {
            continue;
        }
        let text = std::fs::read_to_string(&file).expect("UTF-8");
        for (k, block) in text.split("```bash-recipe\n").skip(1).enumerate() {
            let block = block.split("```").next().unwrap_or_default();
            let commands: Vec<&str> = block.lines().filter_map(|l| l.strip_prefix("$ ")).collect();
            let shown: String = block
                .lines()
                .filter(|l| !l.starts_with("$ "))
                .map(|l| format!("{l}\n"))
                .collect();
            if !has_parallel && commands.iter().any(|c| c.starts_with("parallel ")) {
                continue;
            }
            let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
                .join("bash-recipe")
                .join(format!("{}-{k}", file.display()).replace('/', "_"));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).expect("writable");
            let out = std::process::Command::new("bash")
                .args(["-euo", "pipefail", "-c", &commands.join("\n")])
                .current_dir(&dir)
                .env("PATH", &path)
                .env("NO_COLOR", "1")
                .output()
                .expect("bash runs");
            assert!(out.status.success(), "{}: block {k} failed", file.display());
            let got = String::from_utf8(out.stdout).expect("UTF-8");
            assert_eq!(got, shown, "{}: block {k}", file.display());
            ran += 1;
        }
    }
    assert!(ran > 0, "no bash-recipe block ran");
}
