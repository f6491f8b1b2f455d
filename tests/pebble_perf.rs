//! Scale check of the pebble game: random planar bar-joint frameworks of 10^4 bars (each bar a
//! body, each point a multiple revolute), at, above and below the rigidity threshold (mean
//! point degree 4), and a 10^4-body generated mechanism. Timings are printed, never asserted
//! (`cargo test --release --test pebble_perf -- --nocapture`; `cargo bench --bench analyses`
//! measures them).

use mbsa::Mechanism;
use mbsa::generate::planar_framework;
use mbsa::rigidity::pebble::{PebbleOptions, analyze};
use std::time::Instant;

fn timed(label: &str, m: &Mechanism) {
    let t = Instant::now();
    let r = analyze(m, &PebbleOptions::default());
    let s = t.elapsed().as_secs_f64();
    let largest = r.rigid.iter().map(Vec::len).max().unwrap_or(0);
    eprintln!(
        "{label}: {} bodies, {} bars: {s:.3} s; dof {}, redundant {}, {} rigid components (largest {largest}), {} overconstrained regions",
        r.bodies,
        r.bars,
        r.dof,
        r.redundant,
        r.rigid.len(),
        r.overconstrained.len()
    );
    assert_eq!(r.dof, r.count + r.redundant as i64);
}

#[test]
fn ten_thousand_bodies_under_a_second() {
    // Mean point degree 2·bars/points: 3 (flexible), 4 (threshold), 5 and 6 (over-braced).
    for (points, label) in [
        (6667, "degree 3"),
        (5000, "degree 4"),
        (4000, "degree 5"),
        (3334, "degree 6"),
    ] {
        timed(label, &planar_framework(points, 10_000, 42));
    }
    let (m, _) = mbsa::generate::random(10_000, true, 1).expect("valid parameters");
    timed("generate::random planar", &m);
}
