//! Timings of the structural transformations (run with `--release -- --ignored --nocapture`;
//! benchmarks, never timed assertions).

use mbsa::format::{Format, load};
use mbsa::structure::Library;
use mbsa::transform::{TransformOptions, transform};

fn time(name: &str, count_only: bool) {
    let (file, text) = mbsa::examples::find(name).expect("bundled example");
    let m = load(file, text, Format::Toml).expect("loads");
    let mut opts = TransformOptions::default();
    opts.analysis.count_only = count_only;
    let t0 = std::time::Instant::now();
    let t = transform(&m, &opts, &Library::builtin(), None).unwrap();
    eprintln!(
        "{name} (count_only {count_only}): {} count-valid, {} excluded, {} determined, {} families in {:.3} s",
        t.summary.count_valid,
        t.summary.excluded_by_rank,
        t.summary.determined,
        t.families.len(),
        t0.elapsed().as_secs_f64()
    );
}

#[test]
#[ignore]
fn timings() {
    for name in ["rotor", "stewart", "micro-manipulator"] {
        time(name, true);
        time(name, false);
    }
}
