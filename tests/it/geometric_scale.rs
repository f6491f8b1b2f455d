//! Scale and timing of the geometric rigidity analysis (timings printed, not asserted).

use mbsa::generate::henneberg_framework;
use mbsa::rigidity::geometric::{GeometricOptions, GeometrySource, analyze};
use std::time::Instant;

#[test]
fn random_framework_is_rigid_with_spins() {
    for points in [20, 120] {
        let m = henneberg_framework(points, 3);
        let bars = m.bodies.len();
        let t = Instant::now();
        let r = analyze(
            &m,
            &GeometricOptions {
                geometry: GeometrySource::File,
                check_finite: false,
                precision: None,
            },
        )
        .expect("geometry given");
        let dt = t.elapsed();
        assert_eq!(r.redundant, 0);
        assert_eq!(r.mobility, bars, "{bars} bars: spins (frame's included)");
        assert_eq!(r.isolated, bars);
        assert_eq!(r.rigid.len(), 1);
        assert_eq!(r.rigid[0].bodies.len(), bars);
        eprintln!("{bars} bars: {dt:?}");
    }
}

/// `cargo test --release --test it -- --ignored --nocapture geometric_scale::`
#[test]
#[ignore]
fn timing_thousand_bars() {
    let m = henneberg_framework(334, 3);
    let t = Instant::now();
    let r = analyze(
        &m,
        &GeometricOptions {
            geometry: GeometrySource::File,
            check_finite: false,
            precision: None,
        },
    )
    .expect("geometry given");
    eprintln!(
        "{} bars: {:?} (mobility {}, redundant {}, rigid clusters {})",
        m.bodies.len(),
        t.elapsed(),
        r.mobility,
        r.redundant,
        r.rigid.len()
    );
    eprintln!("{:?}", r.numeric);
}
