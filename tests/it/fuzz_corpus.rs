//! The committed fuzz corpus through the fuzz targets' own checks (`fuzz/fuzz_targets/checks/`,
//! the same code the libFuzzer binaries run): every input the fuzzer kept stays a regression
//! test of `cargo test`, without the instrumented build. Finding new inputs is the fuzzer's
//! job (`scripts/fuzz-ci.sh`, docs/reliability.md).

#[path = "../../fuzz/fuzz_targets/common.rs"]
mod common;

#[path = "../../fuzz/fuzz_targets/checks/analyze.rs"]
mod analyze;
#[path = "../../fuzz/fuzz_targets/checks/import.rs"]
mod import;
#[path = "../../fuzz/fuzz_targets/checks/load.rs"]
mod load;
#[path = "../../fuzz/fuzz_targets/checks/rigid.rs"]
mod rigid;
#[path = "../../fuzz/fuzz_targets/checks/transform.rs"]
mod transform;

use std::panic::{AssertUnwindSafe, catch_unwind};

/// Runs `check` on every file of `fuzz/corpus/<target>/`; fails naming each input that panics.
fn replay(target: &str, check: fn(&[u8])) {
    let dir = format!("{}/fuzz/corpus/{target}", env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("the fuzz corpus is committed")
        .map(|e| e.expect("readable").path())
        .collect();
    files.sort();
    assert!(files.len() >= 10, "{dir}: {} inputs", files.len());
    let failed: Vec<String> = files
        .iter()
        .filter(|p| {
            let data = std::fs::read(p).expect("readable");
            catch_unwind(AssertUnwindSafe(|| check(&data))).is_err()
        })
        .map(|p| p.display().to_string())
        .collect();
    assert!(failed.is_empty(), "inputs that panic: {failed:?}");
}

#[test]
fn load_corpus() {
    replay("load", load::run);
}

#[test]
fn analyze_corpus() {
    replay("analyze", analyze::run);
}

#[test]
fn rigid_corpus() {
    replay("rigid", rigid::run);
}

#[test]
fn transform_corpus() {
    replay("transform", transform::run);
}

#[test]
fn import_corpus() {
    replay("import", import::run);
}

/// The trees the import target writes import in every format with one mobility count (the sum
/// of their joints' freedoms): the renaming and reordering property compares real imports, not
/// two errors.
#[test]
fn generated_trees_import_in_every_format() {
    // Hinges, sliders and balls, some on the root, some on other bodies.
    let bytes = [0u8, 0, 5, 0, 1, 6, 1, 2, 9, 2, 0, 1, 3, 1, 4, 1, 2, 0];
    // URDF has no ball joint: the tree writes a `floating` one (6 DOF).
    let dof = |ball: i64| -> i64 {
        bytes
            .chunks(3)
            .map(|c| [1, 1, ball][c[1] as usize % 3])
            .sum()
    };
    let formats = [("MJCF", 3), ("SDFormat", 3), ("URDF", 6), ("OpenSim", 3)];
    for ((format, ball), got) in formats.iter().zip(import::tree_mobility(&bytes)) {
        assert_eq!(got, Ok(dof(*ball)), "{format}");
    }
}
