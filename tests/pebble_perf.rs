//! Scale check of the pebble game: random planar bar-joint frameworks of 10^4 bars (each bar a
//! body, each point a multiple revolute), at, above and below the rigidity threshold (mean
//! point degree 4), and a 10^4-body generated mechanism. The time limit (1 s each) is
//! asserted in release builds only: `cargo test --release --test pebble_perf -- --nocapture`.

use mbsa::joint::JointType;
use mbsa::rigidity::pebble::{PebbleOptions, analyze};
use mbsa::rng::SplitMix64;
use mbsa::{BodyId, Geometry, JointSpec, Mechanism, Space};
use std::time::Instant;

/// `bars` random bars on `points` points (no repeated pair, no loop), bar 1 the frame.
fn framework(points: u64, bars: usize, seed: u64) -> Mechanism {
    let mut rng = SplitMix64::new(seed);
    let mut seen = std::collections::BTreeSet::new();
    let mut at: Vec<Vec<i64>> = vec![Vec::new(); points as usize];
    while seen.len() < bars {
        let (a, b) = (rng.below(points), rng.below(points));
        if a == b || !seen.insert((a.min(b), a.max(b))) {
            continue;
        }
        let id = seen.len() as i64;
        at[a as usize].push(id);
        at[b as usize].push(id);
    }
    let joints = at
        .into_iter()
        .enumerate()
        .filter(|(_, bs)| bs.len() >= 2)
        .map(|(p, bs)| JointSpec {
            id: Some(format!("p{p}")),
            kind: JointType::R,
            bodies: bs.into_iter().map(BodyId::Int).collect(),
            driven: 0,
            geometry: Geometry::default(),
        })
        .collect();
    Mechanism::from_parts(
        "random framework",
        Space::Planar,
        BodyId::Int(1),
        vec![],
        joints,
    )
}

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
    if !cfg!(debug_assertions) {
        assert!(s < 1.0, "{label} took {s:.3} s");
    }
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
        timed(label, &framework(points, 10_000, 42));
    }
    let (m, _) = mbsa::generate::random(10_000, true, 1).expect("valid parameters");
    timed("generate::random planar", &m);
}
