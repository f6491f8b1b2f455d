//! `mbsa analyze` (rank check included) holds less at its peak (10^6 bodies in
//! under 2 GB; the binary keeps freed memory, so every byte of the peak is a page faulted in
//! and zeroed). The peak is in the count's decomposition inside the rank check, with the
//! pairs' rows, the bodies' reduced unknowns and the maximum-flow network all live: the parts'
//! lists were made before the network was dropped, the flow was read back in eight bytes a
//! pair, the search queue held eight bytes a node, the sound blocks' signatures eight bytes a
//! word, the pairs' first row counts eight bytes a pair, and the network held the source's
//! edges explicitly (two 12-byte slots a pair; implicit now, 8 bytes). Also: `mbsa dot`
//! writes its diagram as it makes it ([`mbsa::report::dot::write_diagram`]), the same text.
//! A counting allocator around the system one records the peak of live bytes
//! (the tests of this binary run one at a time: none counts another's allocations).

use crate::digest::Digest;
use crate::peak_alloc;

/// A 50,000-body random spatial mechanism: the analysis with its rank check peaks at under
/// 800 bytes a body above the mechanism (776 now; 817 with the flow network's source edges
/// explicit, 899 with the earlier flow network), and its structural diagram
/// written as it is made is byte for byte the text `diagram` returns.
#[test]
fn analyze_peak_and_streamed_diagram() {
    let _serial = crate::serial();
    let (m, _) = mbsa::generate::random(50_000, false, 1).expect("a random mechanism");
    let bodies = m.bodies.len();
    let lib = mbsa::structure::Library::builtin();
    let opts = mbsa::structure::Options::default();

    let base = peak_alloc::reset_peak();
    let a = mbsa::structure::analyze(&m, &opts, &lib).expect("analysis");
    let peak = peak_alloc::peak() - base;
    assert!(
        peak < 800 * bodies,
        "{peak} bytes at the peak of the analysis of {bodies} bodies ({} a body)",
        peak / bodies
    );

    let mut streamed = Digest::default();
    mbsa::report::dot::write_diagram(&a, &mut streamed).expect("written");
    let whole = mbsa::report::dot::diagram(&a);
    let mut want = Digest::default();
    std::fmt::Write::write_str(&mut want, &whole).expect("digested");
    assert_eq!((streamed.len, streamed.hash), (want.len, want.hash));
    assert!(whole.len() > 100_000, "{} bytes of diagram", whole.len());
}
