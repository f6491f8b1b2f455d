//! Scale check of the pebble game: planar Laman frameworks (Henneberg steps,
//! each bar a body, each point a multiple revolute), random planar bar-joint frameworks around
//! the rigidity threshold, the generated Assur families, random mechanisms, serial chains and
//! stars. The default test runs them at 10^4 and checks the answers that the construction
//! knows (a Laman framework is minimally rigid: dof 0, redundant 0, one component of every
//! bar); timings are printed, never asserted. The ignored test runs 10^3 to 10^5
//! (`cargo test --release --test it -- --ignored --nocapture pebble_perf::`); with
//! `MBSA_PEBBLE_WRITE=DIR` it also writes the inputs as TOML files for `/usr/bin/time -v mbsa
//! rigid` (docs/benchmarks.md).

use mbsa::generate::{self, Variant};
use mbsa::joint::JointType;
use mbsa::rigidity::pebble::{PebbleOptions, PebbleReport, analyze};
use mbsa::{BodyId, JointSpec, Mechanism, Space};
use std::time::Instant;

use crate::common;
use common::laman;

/// An open serial chain of `n` bodies after the frame on revolutes (planar or spatial).
fn chain(n: i64, space: Space) -> Mechanism {
    let joints = (1..=n)
        .map(|i| JointSpec::new(JointType::R, i, i + 1, 0))
        .collect();
    Mechanism::from_parts("chain", space, BodyId::Int(1), vec![], joints)
}

/// A star: `n` bodies each on a revolute to the frame (binary joints), or all sharing one
/// spherical joint with the frame (one multiple joint).
fn star(n: i64, shared: bool) -> Mechanism {
    let joints = if shared {
        let mut j = JointSpec::new(JointType::S, 1, 2, 0);
        j.bodies = (1..=n + 1).map(BodyId::Int).collect();
        vec![j]
    } else {
        (2..=n + 1)
            .map(|i| JointSpec::new(JointType::R, 1, i, 0))
            .collect()
    };
    Mechanism::from_parts("star", Space::Spatial, BodyId::Int(1), vec![], joints)
}

fn timed(label: &str, m: &Mechanism) -> PebbleReport {
    let t = Instant::now();
    let r = analyze(m, &PebbleOptions::default());
    let s = t.elapsed().as_secs_f64();
    let largest = r.rigid.iter().map(Vec::len).max().unwrap_or(0);
    eprintln!(
        "{label}: {} bodies, {} bars: {s:.3} s; dof {}, redundant {}, {} rigid components (largest {largest}), {} overconstrained regions, degenerate {}",
        r.bodies,
        r.bars,
        r.dof,
        r.redundant,
        r.rigid.len(),
        r.overconstrained.len(),
        r.degenerate
    );
    assert_eq!(r.dof, r.count + r.redundant as i64);
    if let Ok(dir) = std::env::var("MBSA_PEBBLE_WRITE") {
        let file = format!("{dir}/{}.toml", label.replace([' ', '/', '^'], "-"));
        std::fs::write(&file, generate::to_toml(m)).expect("writable");
    }
    r
}

/// Every family at `n` bodies or points; the answers the constructions know are asserted.
fn families(n: usize) {
    for local in [false, true] {
        let r = timed(
            &format!(
                "laman {n} points {}",
                if local { "local" } else { "uniform" }
            ),
            &laman(n, local, 7),
        );
        assert_eq!((r.dof, r.redundant), (0, 0));
        assert_eq!(r.rigid.len(), 1);
        assert_eq!(r.rigid[0].len(), 2 * n - 3);
    }
    // Mean point degree 3 (flexible), 4 (threshold) and 6 (over-braced).
    // MBSA_PEBBLE_SKIP_OVERBRACED=1 leaves out degrees 4 and 6 (their overconstrained regions
    // still take a search per redundant bar: quadratic).
    let skip = std::env::var("MBSA_PEBBLE_SKIP_OVERBRACED").is_ok();
    for (deg, label) in [(3, "degree 3"), (4, "degree 4"), (6, "degree 6")] {
        if skip && deg > 3 {
            continue;
        }
        timed(
            &format!("framework {n} bars {label}"),
            &generate::planar_framework((2 * n / deg) as u64, n, 42),
        );
    }
    for class in 1..=3u32 {
        let groups = (n as u64).div_ceil(2 * class as u64);
        for spatial in [false, true] {
            let m = if spatial {
                generate::assur_spatial(class, groups, 364, Variant::A)
            } else {
                generate::assur(class, groups, 364, Variant::A)
            }
            .expect("valid parameters");
            let r = timed(
                &format!(
                    "assur class {class} {} {n}",
                    if spatial { "spatial" } else { "planar" }
                ),
                &m,
            );
            assert_eq!(r.redundant, 0, "Assur linkages are not overconstrained");
        }
    }
    for planar in [true, false] {
        let (m, _) = generate::random(n as u64, planar, 1).expect("valid parameters");
        timed(
            &format!("random {} {n}", if planar { "planar" } else { "spatial" }),
            &m,
        );
    }
    for space in [Space::Planar, Space::Spatial] {
        let r = timed(
            &format!("chain {} {n}", space.name()),
            &chain(n as i64, space),
        );
        assert_eq!(r.dof, n as i64);
        assert_eq!(r.rigid, [["1"]]);
    }
    for shared in [false, true] {
        let r = timed(
            &format!("star {} {n}", if shared { "shared S" } else { "R" }),
            &star(n as i64, shared),
        );
        assert_eq!(r.redundant, 0);
        assert_eq!(r.dof, if shared { 3 * n as i64 } else { n as i64 });
    }
}

#[test]
fn ten_thousand() {
    families(10_000);
}

#[test]
#[ignore = "minutes in debug; run in release with --ignored --nocapture"]
fn scale_1e3_to_1e5() {
    // MBSA_PEBBLE_SIZES=1000,10000 picks the sizes.
    let sizes: Vec<usize> = std::env::var("MBSA_PEBBLE_SIZES")
        .map(|s| {
            s.split(',')
                .map(|x| x.trim().parse().expect("a size"))
                .collect()
        })
        .unwrap_or_else(|_| vec![1_000, 10_000, 30_000, 100_000]);
    for n in sizes {
        families(n);
    }
}

#[test]
#[ignore = "profiling aid: MBSA_PEBBLE_LAMAN=points"]
fn laman_only() {
    let n: usize = std::env::var("MBSA_PEBBLE_LAMAN")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000);
    timed(&format!("laman {n} points uniform"), &laman(n, false, 7));
}
