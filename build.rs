//! Embeds every mechanism file of `mechanisms/` in the binary, for `@name` and `mbsa examples`.
use std::{env, fs, path::Path};

fn main() {
    println!("cargo:rerun-if-changed=mechanisms");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("mechanisms");
    let mut files: Vec<_> = fs::read_dir(&dir)
        .map(|rd| rd.filter_map(Result::ok).map(|e| e.path()).collect())
        .unwrap_or_default();
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
