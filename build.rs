//! Embeds every mechanism file of `mechanisms/` in the binary, for `@name` and `mbsa examples`.
use std::{env, fs, path::Path};

fn main() {
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
