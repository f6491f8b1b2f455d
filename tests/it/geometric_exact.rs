//! At a random realization the geometric analysis decides ranks exactly (over GF(2^61 − 1)):
//! the answer must not depend on size or seed. A planar Laman framework of 1,000 points
//! (1,997 bars, 5,988 unknowns) built by Henneberg steps is minimally rigid at every seed;
//! with floating point and a size-scaled tolerance it came out with mobility 1 and one
//! redundant bar at some seeds.

use crate::common;

use mbsa::mechanism::Mechanism;
use mbsa::rigidity::geometric::{GeometricOptions, GeometrySource, analyze};
use mbsa::rng::SplitMix64;

/// Henneberg type-I steps in the plane: each new point joined by two bars to two earlier
/// points. Bars are bodies, points multiple revolute joints (no geometry: random realization).
fn laman(points: usize, seed: u64) -> Mechanism {
    let mut rng = SplitMix64::new(seed);
    let mut bars = vec![(0, 1)];
    for p in 2..points {
        let a = rng.below(p as u64) as usize;
        let mut b = rng.below(p as u64 - 1) as usize;
        if b >= a {
            b += 1;
        }
        bars.push((p, a));
        bars.push((p, b));
    }
    common::bar_framework("laman", points, &bars)
}

#[test]
fn thousand_point_laman_framework_is_minimally_rigid_at_every_seed() {
    let m = laman(1000, 11);
    assert_eq!(m.bodies.len(), 1997);
    for seed in 0..3 {
        let r = analyze(
            &m,
            &GeometricOptions {
                geometry: GeometrySource::Random { seed },
                check_finite: false,
                precision: None,
            },
        )
        .expect("random geometry always works");
        assert_eq!((r.mobility, r.redundant), (0, 0), "seed {seed}");
        assert!(r.numeric.exact.is_some());
    }
}

/// The structural rank check decides blocks too large for its dense SVD exactly at a random
/// realization: the 1,257-body group of a planar Assur II-B linkage (3,771 unknowns) was left
/// `unchecked` before.
#[test]
fn giant_group_is_checked_exactly() {
    use mbsa::generate::{Variant, assur};
    use mbsa::structure::{Library, Options, Status, analyze};
    let m = assur(2, 2000, 364, Variant::B).expect("valid sizes");
    let a = analyze(&m, &Options::default(), &Library::builtin()).expect("no geometry needed");
    assert_eq!(a.status, Status::Determined);
    assert!(a.groups.iter().any(|g| g.nm == 1257));
    assert!(a.unchecked.is_empty(), "{:?}", a.unchecked);
}
