//! The tests that bound allocations: the bytes live at a peak, the allocations a read makes.
//! One binary with one counting global allocator ([`peak_alloc::Peak`]); every test holds
//! [`serial`] while it runs, so that no test's allocations are counted in another's.

mod digest;
mod peak_alloc;

mod analyze_memory;
mod georigid_memory;
mod reader_allocations;
mod table_streaming;
mod transform_memory;

#[global_allocator]
static ALLOCATOR: peak_alloc::Peak = peak_alloc::Peak;

static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Held by every test for its whole run: the tests run one at a time. A failed test's
/// poisoning is ignored (its failure is reported on its own).
fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}
