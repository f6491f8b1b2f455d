//! Reading a large TOML file allocates about once per joint (its id string), not once per
//! joint table, array and id (issue 16: reading was a quarter of `analyze` at 10^6 bodies,
//! much of it allocations and frees). A counting allocator around the system one; one test in
//! this binary, so that no other test's allocations are counted.

use mbsa::format::{Format, load};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The system allocator, counting allocations (a `realloc` counts as one) and the bytes they
/// ask for (a `realloc` its new size).
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
static BYTES: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is forwarded unchanged to the system allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        BYTES.fetch_add(layout.size(), Ordering::Relaxed);
        // SAFETY: the caller's guarantees for `layout` are the system allocator's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from the system allocator with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        BYTES.fetch_add(new_size, Ordering::Relaxed);
        // SAFETY: as for `alloc` and `dealloc`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Bytes a joint the read may allocate: 163 now; with the 32-byte natural-order keys, or the
/// 16-byte spans, back, over 180.
const BYTES_PER_JOINT: usize = 180;

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// A random spatial mechanism (about 2.5 joints a body, 5 % of them with an explicit id, no
/// geometry: the shape of the 10^6-body benchmark files) reads with fewer than 1.25
/// allocations a joint. The reader before this bound built a vector for every joint table
/// and every `bodies` array: over 3 a joint.
///
/// And with at most BYTES_PER_JOINT bytes allocated a joint (session 13): the joint itself
/// (64 bytes), its id (24), the body-list sort of the defaults and its order (about 21), the
/// explicit ids' map. Before, a 32-byte natural-order key a joint (the ids parsed back into
/// numbers and sorted, where the default ids are in natural order already) and a 16-byte
/// span a joint kept for an error the fast reader throws away.
///
/// Also at 30,000 bodies (about 77,000 joints), above the count from which the joint tables
/// are read on a second thread (session 18): its batches of table nodes, handed back and
/// forth, are allocated once, not per table.
#[test]
fn a_large_toml_file_reads_with_about_one_allocation_per_joint() {
    for bodies in [20_000, 30_000] {
        let (m, _) = mbsa::generate::random(bodies, false, 1).expect("a random mechanism");
        let text = mbsa::generate::to_toml(&m);
        drop(m);
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        let bytes_before = BYTES.load(Ordering::Relaxed);
        let m = load("random.toml", &text, Format::Toml).expect("the file reads");
        let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
        let bytes = BYTES.load(Ordering::Relaxed) - bytes_before;
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
