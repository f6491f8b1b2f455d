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
