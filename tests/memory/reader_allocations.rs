//! Reading a large TOML file allocates about once per joint (its id string), not once per
//! joint table, array and id (reading was a quarter of `analyze` at 10^6 bodies,
//! much of it allocations and frees). A counting allocator around the system one (the tests of
//! this binary run one at a time: none counts another's allocations).

use crate::peak_alloc;
use mbsa::format::{Format, load};

/// Bytes a joint the read may allocate: 163 now; with the 32-byte natural-order keys, or the
/// 16-byte spans, back, over 180.
const BYTES_PER_JOINT: usize = 180;

/// A random spatial mechanism (about 2.5 joints a body, 5 % of them with an explicit id, no
/// geometry: the shape of the 10^6-body benchmark files) reads with fewer than 1.25
/// allocations a joint. The reader before this bound built a vector for every joint table
/// and every `bodies` array: over 3 a joint.
///
/// And with at most BYTES_PER_JOINT bytes allocated a joint: the joint itself
/// (64 bytes), its id (24), the body-list sort of the defaults and its order (about 21), the
/// explicit ids' map. Before, a 32-byte natural-order key a joint (the ids parsed back into
/// numbers and sorted, where the default ids are in natural order already) and a 16-byte
/// span a joint kept for an error the fast reader throws away.
///
/// Also at 30,000 bodies (about 77,000 joints), above the count from which the joint tables
/// are read on a second thread: its batches of table nodes, handed back and
/// forth, are allocated once, not per table.
#[test]
fn a_large_toml_file_reads_with_about_one_allocation_per_joint() {
    let _serial = crate::serial();
    for bodies in [20_000, 30_000] {
        let (m, _) = mbsa::generate::random(bodies, false, 1).expect("a random mechanism");
        let text = mbsa::generate::to_toml(&m);
        drop(m);
        let before = peak_alloc::allocations();
        let bytes_before = peak_alloc::asked();
        let m = load("random.toml", &text, Format::Toml).expect("the file reads");
        let allocations = peak_alloc::allocations() - before;
        let bytes = peak_alloc::asked() - bytes_before;
        let joints = m.joints.len();
        eprintln!(
            "{joints} joints: {allocations} allocations, {bytes} bytes ({:.1} a joint)",
            bytes as f64 / joints as f64
        );
        assert!(joints > 40_000, "{joints} joints");
        assert!(
            allocations < joints + joints / 4,
            "{allocations} allocations to read {joints} joints"
        );
        assert!(
            bytes < BYTES_PER_JOINT * joints,
            "{bytes} bytes allocated to read {joints} joints"
        );
    }
}
