//! The `import` target: the checks of `checks/import.rs` on each input (docs/reliability.md).

#![no_main]

#[path = "checks/import.rs"]
mod check;

libfuzzer_sys::fuzz_target!(|data: &[u8]| check::run(data));
