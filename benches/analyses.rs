//! Benchmarks of the other analyses (divan): `cargo bench --bench analyses`.
//!
//! - `transform`: every input placement of the rotor and the micro-manipulator, analysed in
//!   full (rank check) and by counting only (targets: rotor < 1 s, micro-manipulator < 10 s).
//! - `pebble`: the (B, B) pebble game on random planar bar-joint frameworks of 10^4 bars at
//!   mean point degree 3, 4 (the rigidity threshold) and 6, and on a 10^4-body mechanism.
//! - `geometric`: the double banana at its file geometry (target < 10 ms) and a Henneberg-built
//!   spatial framework of 996 bars (target < 2 s).
//!
//! Inputs are built outside the timed closures. See docs/benchmarks.md for the results.

use divan::{Bencher, black_box};
use mbsa::format::{Format, load};
use mbsa::generate;
use mbsa::mechanism::Mechanism;
use mbsa::rigidity::geometric::{self, GeometricOptions, GeometrySource};
use mbsa::rigidity::pebble::{self, PebbleOptions};
use mbsa::structure::Library;
use mbsa::transform::{TransformOptions, transform};

fn main() {
    divan::main();
}

fn example(name: &str) -> Mechanism {
    let (file, text) = mbsa::examples::find(name).expect("bundled example");
    load(file, text, Format::Toml).expect("bundled examples load")
}

/// Every input placement, ranked (the work of `mbsa transform FILE`).
#[divan::bench_group(sample_size = 1, sample_count = 3)]
mod transform_all {
    use super::*;

    fn run(bencher: Bencher, name: &str, count_only: bool) {
        let m = example(name);
        let lib = Library::builtin();
        let mut opts = TransformOptions::default();
        opts.analysis.count_only = count_only;
        bencher.bench_local(|| transform(black_box(&m), &opts, &lib, None).expect("enumerates"));
    }

    #[divan::bench(args = ["rotor", "micro-manipulator"])]
    fn default(bencher: Bencher, name: &str) {
        run(bencher, name, false);
    }

    #[divan::bench(args = ["rotor", "micro-manipulator"])]
    fn count_only(bencher: Bencher, name: &str) {
        run(bencher, name, true);
    }
}

/// The pebble game (generic rigidity by counting).
#[divan::bench_group(sample_size = 1, sample_count = 5)]
mod pebble_game {
    use super::*;

    /// (points, label): 10^4 bars at mean point degree 2·bars/points.
    const FRAMEWORKS: [(u64, &str); 3] = [(6667, "degree3"), (5000, "degree4"), (3334, "degree6")];

    #[divan::bench(args = FRAMEWORKS.map(|f| f.1))]
    fn framework_10k_bars(bencher: Bencher, label: &str) {
        let points = FRAMEWORKS
            .iter()
            .find(|f| f.1 == label)
            .map_or(5000, |f| f.0);
        let m = generate::planar_framework(points, 10_000, 42);
        bencher.bench_local(|| pebble::analyze(black_box(&m), &PebbleOptions::default()));
    }

    #[divan::bench]
    fn random_planar_10k_bodies(bencher: Bencher) {
        let (m, _) = generate::random(10_000, true, 1).expect("valid parameters");
        bencher.bench_local(|| pebble::analyze(black_box(&m), &PebbleOptions::default()));
    }
}

/// The geometric analysis (true mobility, redundancy, isolated DOF, clusters, loops).
#[divan::bench_group(sample_count = 10)]
mod geometric_rigidity {
    use super::*;

    const FILE: GeometricOptions = GeometricOptions {
        geometry: GeometrySource::File,
        check_finite: false,
        precision: None,
    };

    #[divan::bench]
    fn double_banana(bencher: Bencher) {
        let m = example("rig-double-banana");
        bencher.bench_local(|| geometric::analyze(black_box(&m), &FILE).expect("geometry given"));
    }

    #[divan::bench(sample_size = 1, sample_count = 5)]
    fn framework_996_bars(bencher: Bencher) {
        let m = generate::henneberg_framework(334, 3);
        bencher.bench_local(|| geometric::analyze(black_box(&m), &FILE).expect("geometry given"));
    }
}
