//! Peak memory of `rigid --method geometric` on a planar Assur linkage at a random realization
//! (3.1 GB at 10^6 bodies, over the 2 GB target). A counting allocator
//! around the system one records the peak of the bytes held (the tests of this binary run one
//! at a time: none counts another's allocations).

use crate::peak_alloc;
use mbsa::generate::{Variant, assur};
use mbsa::rigidity::geometric::{GeometricOptions, analyze};

/// The planar Assur linkage of 5,002 bodies (the benchmark family, one rigid block analysed
/// exactly): the analysis holds at most 2,000 bytes a body at its peak above the mechanism
/// itself (1,710 now). Before the floating-point blocks of an exactly analysed block were
/// dropped after σ_max, the exact elimination's input matrix before its elimination, the full
/// twists built only when the loops are listed and the elimination's queue kept one entry per
/// group, it held 2,752.
#[test]
fn the_planar_assur_linkage_is_analysed_within_a_bounded_memory_per_body() {
    let _serial = crate::serial();
    let m = assur(2, 1250, 364, Variant::A).expect("an Assur linkage");
    let bodies = m.bodies.len();
    let base = peak_alloc::reset_peak();
    let r = analyze(&m, &GeometricOptions::default()).expect("random geometry");
    let peak = peak_alloc::peak() - base;
    assert_eq!(r.redundant, 0);
    let per_body = peak / bodies;
    eprintln!("peak {peak} bytes above the mechanism, {per_body} a body");
    assert!(per_body < 2_000, "{peak} bytes at peak, {per_body} a body");
}
