//! Reading a large TOML file allocates about once per joint (its id string), not once per
//! joint table, array and id (issue 16: reading was a quarter of `analyze` at 10^6 bodies,
//! much of it allocations and frees). A counting allocator around the system one; one test in
//! this binary, so that no other test's allocations are counted.

use mbsa::format::{Format, load};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The system allocator, counting allocations (a `realloc` counts as one).
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is forwarded unchanged to the system allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller's guarantees for `layout` are the system allocator's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from the system allocator with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: as for `alloc` and `dealloc`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// A random spatial mechanism (about 2.5 joints a body, 5 % of them with an explicit id, no
/// geometry: the shape of the 10^6-body benchmark files) reads with fewer than 1.25
/// allocations a joint. The reader before this bound built a vector for every joint table
/// and every `bodies` array: over 3 a joint.
#[test]
fn a_large_toml_file_reads_with_about_one_allocation_per_joint() {
    let (m, _) = mbsa::generate::random(20_000, false, 1).expect("a random mechanism");
    let text = mbsa::generate::to_toml(&m);
    drop(m);
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let m = load("random.toml", &text, Format::Toml).expect("the file reads");
    let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
    let joints = m.joints.len();
    assert!(joints > 40_000, "{joints} joints");
    assert!(
        allocations < joints + joints / 4,
        "{allocations} allocations to read {joints} joints"
    );
}
