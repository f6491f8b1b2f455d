//! The `mbsa` command-line tool: a thin layer over the `mbsa` library.

mod cli;

fn main() -> std::process::ExitCode {
    keep_freed_memory();
    cli::main()
}

/// Keeps memory the analysis frees for its own later allocations.
///
/// glibc serves every block above its mmap threshold (at most 32 MB) with a fresh mapping and
/// unmaps it on `free`, so each large array allocated after another was freed is faulted in
/// and zeroed by the kernel again: at 10^6 bodies that was about half of `analyze`'s page faults
/// and most of its system time (random spatial: 554,000 faults, 1.7-2.6 s system; with the
/// heap kept, 294,000 and 0.7-1.2 s, for a peak 3 % higher). A command runs once and exits, so
/// returning memory to the kernel early gains nothing. The library does not do this: the
/// process that embeds it chooses its allocator.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
fn keep_freed_memory() {
    // SAFETY: `mallopt` only sets two of the allocator's parameters; it is called before any
    // other thread exists and its result (0 when a value is refused) leaves the defaults.
    unsafe {
        libc::mallopt(libc::M_MMAP_MAX, 0);
        libc::mallopt(libc::M_TRIM_THRESHOLD, libc::c_int::MAX);
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn keep_freed_memory() {}
