//! Embeds every mechanism file of `mechanisms/` in the binary, for `@name` and `mbsa examples`,
//! and the commit the binary was built from, for `mbsa --version`.
use std::{env, fs, path::Path, process::Command};

fn main() {
    version();
    println!("cargo:rerun-if-changed=mechanisms");
    // The manifest directory when the script runs, not when it was compiled (`env!`): one
    // compiled script is reused by every checkout sharing a target directory, and a stale path
    // embedded nothing once that checkout was gone.
    let manifest = env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let dir = Path::new(&manifest).join("mechanisms");
    let mut files: Vec<_> = fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()))
        .filter_map(Result::ok)
        .map(|e| e.path())
        .collect();
    files.retain(|p| p.extension().is_some_and(|e| e == "toml"));
    files.sort();
    let mut out = String::from(
        "/// Bundled mechanisms: (name, file name, TOML text), sorted by name.\npub static EXAMPLES: &[(&str, &str, &str)] = &[\n",
    );
    for p in &files {
        println!("cargo:rerun-if-changed={}", p.display());
        let stem = p.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
        let file = p.file_name().and_then(|s| s.to_str()).unwrap_or_default();
        out.push_str(&format!(
            "    ({stem:?}, {file:?}, include_str!({:?})),\n",
            p.display().to_string()
        ));
    }
    out.push_str("];\n");
    let dest = Path::new(&env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("examples.rs");
    fs::write(dest, out).expect("OUT_DIR is writable");
}

/// `MBSA_VERSION`: the package version, with the commit and its date when built from a git
/// checkout (`0.1.0 (1a2b3c4 2026-12-05)`), the version alone otherwise (a crates.io
/// download, no git). The commit date, not the build date: the same commit gives the same
/// bytes.
fn version() {
    let manifest = env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .current_dir(&manifest)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .and_then(|o| String::from_utf8(o.stdout).ok())
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
    };
    let mut version = env::var("CARGO_PKG_VERSION").expect("cargo sets CARGO_PKG_VERSION");
    // Only a checkout of this package: not a parent repository the sources were unpacked in.
    let top = git(&["rev-parse", "--show-toplevel"]);
    let ours = top.is_some_and(|t| {
        Path::new(&t).join("Cargo.toml") == Path::new(&manifest).join("Cargo.toml")
    });
    if ours
        && let (Some(commit), Some(date)) = (
            git(&["rev-parse", "--short", "HEAD"]),
            git(&["log", "-1", "--format=%cs"]),
        )
    {
        version.push_str(&format!(" ({commit} {date})"));
        // Rerun when HEAD moves: HEAD itself (a checkout), the branch it names (a commit),
        // packed refs. Paths through `--git-path` also hold in a worktree.
        let mut watched = vec!["HEAD".to_string(), "packed-refs".to_string()];
        if let Some(branch) = git(&["symbolic-ref", "-q", "HEAD"]) {
            watched.push(branch);
        }
        for w in watched {
            if let Some(p) = git(&["rev-parse", "--git-path", &w]) {
                let p = Path::new(&manifest).join(p);
                if p.exists() {
                    println!("cargo:rerun-if-changed={}", p.display());
                }
            }
        }
    }
    println!("cargo:rustc-env=MBSA_VERSION={version}");
}
